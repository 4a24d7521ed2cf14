//! The linear building (docs/model.md, "The linear building kernel"): a shear building without
//! stacks and with elastic storeys, whose peak responses to a record are computed from one
//! complex modal basis, without the event-driven machinery of [`super::exact`].
//!
//! Such a building is one linear system `M·ü + C·u̇ + K·u = −M·1·a_g(t)` for the whole record
//! (the rigidly loaded and bare systems of a study, the building of `λ`; `C` need not be
//! classical for `M`). In the eigenvectors of its state matrix (`StateModes`, computed once)
//! every mode obeys `ẏ_r = λ_r·y_r + β₀ + β₁·τ` over a sample interval, with `β = −g_r·a_g`
//! (`g_r` the modal share of a unit load on every floor), so the exact step from sample to sample
//! is the complex Nigam–Jennings recurrence
//!
//! `y_r(k+1) = e^{λh}·y_r(k) + F_r·a_g,k + G_r·a_g,k+1`,
//! `F_r = −g_r·(hφ₁(λh) − hφ₂(λh))`, `G_r = −g_r·hφ₂(λh)`,
//!
//! its coefficients computed once per record step `h`. Every output is a fixed real linear
//! function of the modal state, `f(t) = Σ_r w_r·Re(c_r·y_r(t))` (per floor the displacement and
//! the absolute acceleration, per storey the drift and the storey shear, the overturning moment at
//! the base), so one pass over the samples costs `O(modes × outputs)` multiply-adds per sample,
//! with no allocation, division or square root: a matrix–vector product over outputs grouped by
//! eight (compiled for AVX-512 and AVX2 where the processor has them, the same bits either way).
//!
//! Peaks are exact between samples. The first pass takes every output's largest sampled `|f|`
//! and keeps, per block of `BLOCK` (32) intervals, the modal state at its start, each output's
//! largest sampled `|f|` in it and per mode the largest `|y_r''|` bound over its intervals
//! (`y_r''(τ) = e^{λτ}·q_r`, `q_r = λ²y₀ + λβ₀ + β₁`, bounded by `|Re q_r| + |Im q_r|`). Over an
//! interval `max|f| ≤ max(|f(0)|, |f(h)|) + max|f''|·h²/8`, with `|f''| ≤ Σ_r w_r·|c_r|·|q_r|`
//! (times `e^{Re λ·h}` where round-off leaves a mode growing): the second pass revisits only the
//! blocks where this bound reaches an output's sampled peak, repeats their recurrence from the
//! stored state (the same bits), tests each interval the same way, and searches the survivors by
//! the certified peak search of `dynamics::search` on the closed form (the searches of
//! the building's integrator, on the same functions).

use super::super::search::{self, Node, SearchError};
use super::super::{Ground, SimError};
use super::modal::{ModalError, ModalFn, Piece, StateModes, mode_terms};
use super::model::Building;
use crate::numeric::Cx;
use std::borrow::Cow;
use thiserror::Error;

/// Sample intervals per block of the first pass: the second pass repeats a block's recurrence
/// when one of its outputs may hold a peak above the sampled one; the blocks' stored states and
/// maxima take `(3·modes + outputs)/BLOCK` numbers per sample.
const BLOCK: usize = 32;

/// Relative slack on the derivative bounds against the rounding of their sums (as
/// `ModalFn::bound`).
const BOUND_SLACK: f64 = 1.0 + 1e-12;

/// A building the kernel cannot take, or a record it cannot run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LinearBuildingError {
    #[error(
        "the linear building kernel takes a building without stacks (attach them first, \
         Building::with_stacks_attached_fraction); this one carries {0} block(s)"
    )]
    Stacks(usize),
    #[error(
        "the linear building kernel takes elastic storeys; this building's storeys yield (run \
         simulate_building)"
    )]
    Yielding,
    #[error(transparent)]
    Modal(#[from] ModalError),
    #[error(transparent)]
    Ground(#[from] SimError),
    #[error("the linear building's response is not finite")]
    NotFinite,
}

/// The peaks over a whole record of a linear building's responses, exact between samples
/// (docs/model.md, "The linear building kernel").
#[derive(Debug, Clone, PartialEq)]
pub struct LinearPeaks {
    /// Peak `|u_j|` of each floor relative to the ground, m, floor 1 first.
    pub floor_peak_displacement_m: Vec<f64>,
    /// Peak `|ü_j + a_g|`, each floor's absolute acceleration, m/s².
    pub floor_peak_abs_accel_mps2: Vec<f64>,
    /// Peak `|δ_i|`, `δ_i = u_i − u_{i−1}`, m, storey 1 first.
    pub storey_peak_drift_m: Vec<f64>,
    /// Peak `|V_i|`, N, of the storey shear `V_i = k_i·δ_i + Σ_{j≥i} (C·u̇)_j`
    /// `= −Σ_{j≥i} m_j·a_abs,j`; storey 1's is the base shear
    /// (`BuildingResponse::peak_base_shear_n`).
    pub storey_peak_shear_n: Vec<f64>,
    /// Peak `|M|`, N·m, of the overturning moment at the base `M = Σ_i h_i·V_i`
    /// `= −Σ_j z_j·m_j·a_abs,j` (`h_i` storey `i`'s height, `z_j` floor `j`'s elevation).
    pub peak_overturning_moment_nm: f64,
}

impl LinearPeaks {
    /// Peak `|V|` of the base shear `V = k_1·u_1 + 1ᵀ·C·u̇`, N (storey 1's shear).
    pub fn peak_base_shear_n(&self) -> f64 {
        self.storey_peak_shear_n[0]
    }
}

/// A linear building ready to run records: its modal basis and output rows, computed once.
#[derive(Debug, Clone)]
pub struct LinearBuilding {
    n: usize,
    modes: StateModes,
    heights_m: Vec<f64>,
    /// Every output's coefficient `c_r` of every kept mode (`(4N + 1) × modes`): floor
    /// displacements, floor absolute accelerations, storey drifts, storey shears, the
    /// overturning moment. Tabled for the samples' products by [`Self::run`] and
    /// [`Self::select`] (a search of `λ` takes one of them).
    rows: Vec<Cx>,
}

/// One peak response of a linear building ([`LinearBuilding::select`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearOutput {
    /// Floor `j`'s displacement relative to the ground (0 the lowest floor), m.
    FloorDisplacement(usize),
    /// Floor `j`'s absolute acceleration, m/s².
    FloorAbsAccel(usize),
    /// Storey `i`'s drift (0 the ground storey), m.
    StoreyDrift(usize),
    /// Storey `i`'s shear (0 the base shear), N.
    StoreyShear(usize),
    /// The overturning moment at the base, N·m.
    OverturningMoment,
}

/// Some of a linear building's outputs, prepared for [`LinearBuilding::peaks_of`]: each output's
/// peak is the bits [`LinearBuilding::run`] gives for it (the same row, sums and searches), at
/// the cost of the outputs chosen.
#[derive(Debug, Clone)]
pub struct Selection(Outputs);

/// A table of outputs, each a linear function of the modal state.
#[derive(Debug, Clone)]
struct Outputs {
    count: usize,
    /// Per output the coefficient `c_r` of every kept mode (`count × modes`).
    rows: Vec<Cx>,
    /// `w_r·|c_r|` (`outputs × modes`).
    rows_abs: Vec<f64>,
    /// The rows weighted by state component, `f_o = Σ_c wrows[o][c]·y_c` over the state
    /// `y = (Re y_r, Im y_r)`: `wrows[o][r] = w_r·Re c_r`, `wrows[o][m + r] = −w_r·Im c_r`
    /// (`outputs × 2·modes`).
    wrows: Vec<f64>,
    /// The same numbers for the samples' matrix–vector product, [`LANE`] outputs at a time:
    /// `cols[g·2m + c][i] = wrows[g·LANE + i][c]` (zero past the last output), so that a group's
    /// sums stay in registers. Each output is summed in the same order either way.
    cols: Vec<[f64; LANE]>,
}

impl Outputs {
    /// The table of `rows` (`count × modes`) in `modes`' basis.
    fn new(modes: &StateModes, rows: Vec<Cx>) -> Self {
        let m = modes.modes();
        let count = rows.len() / m;
        let rows_abs = rows
            .iter()
            .enumerate()
            .map(|(i, c)| modes.weight[i % m] * c.abs())
            .collect();
        let mut wrows = vec![0.0; count * 2 * m];
        for o in 0..count {
            for r in 0..m {
                let (cr, w) = (rows[o * m + r], modes.weight[r]);
                wrows[o * 2 * m + r] = w * cr.0;
                wrows[o * 2 * m + m + r] = -w * cr.1;
            }
        }
        let mut cols = vec![[0.0; LANE]; count.div_ceil(LANE) * 2 * m];
        for o in 0..count {
            for c in 0..2 * m {
                cols[(o / LANE) * 2 * m + c][o % LANE] = wrows[o * 2 * m + c];
            }
        }
        Self {
            count,
            rows,
            rows_abs,
            wrows,
            cols,
        }
    }

    /// Every output at modal state `y`, [`LANE`] at a time.
    #[inline(always)]
    fn eval_all(&self, y: &[f64], f: &mut [[f64; LANE]]) {
        for (out, group) in f.iter_mut().zip(self.cols.chunks_exact(y.len())) {
            let mut acc = [0.0; LANE];
            for (col, &s) in group.iter().zip(y) {
                for i in 0..LANE {
                    acc[i] += col[i] * s;
                }
            }
            *out = acc;
        }
    }

    /// [`Self::eval_all`] in every lane of `y` (`2·modes` components of `L` lanes): each lane's
    /// sums in the same order, the same bits.
    #[inline(always)]
    fn lane_eval_all<const L: usize>(&self, y: &[[f64; L]], f: &mut [[[f64; LANE]; L]]) {
        for (out, group) in f.iter_mut().zip(self.cols.chunks_exact(y.len())) {
            let mut acc = [[0.0; LANE]; L];
            for (col, s) in group.iter().zip(y) {
                for l in 0..L {
                    for i in 0..LANE {
                        acc[l][i] += col[i] * s[l];
                    }
                }
            }
            *out = acc;
        }
    }

    /// Output `o` at modal state `y`: the same sum as [`Self::eval_all`]'s, the same bits.
    fn eval_one(&self, o: usize, y: &[f64]) -> f64 {
        let row = &self.wrows[o * y.len()..(o + 1) * y.len()];
        row.iter().zip(y).fold(0.0, |acc, (c, s)| acc + c * s)
    }
}

/// Outputs summed together in the samples' matrix–vector product (two AVX2 registers).
const LANE: usize = 8;

/// What the first pass keeps: per block its start state (`2·modes`), each output's largest
/// sampled `|f|` (grouped by [`LANE`]) and per mode the largest `|y''|` bound; each output's
/// largest sampled `|f|`.
struct FirstPass {
    starts: Vec<f64>,
    block_max: Vec<[f64; LANE]>,
    block_q: Vec<f64>,
    best: Vec<[f64; LANE]>,
}

impl FirstPass {
    /// Room for `intervals` sample intervals of `out` in `modes` modes.
    fn new(out: &Outputs, modes: usize, intervals: usize) -> Self {
        let (groups, blocks) = (out.count.div_ceil(LANE), intervals.div_ceil(BLOCK));
        Self {
            starts: vec![0.0; blocks * 2 * modes],
            block_max: vec![[0.0; LANE]; blocks * groups],
            block_q: vec![0.0; blocks * modes],
            best: vec![[0.0; LANE]; groups],
        }
    }
}

/// The first pass's state between blocks: the modal state and each output's `|f|` at the
/// latest sample (a block's maxima start from its first sample's).
struct Carry {
    y: Vec<f64>,
    f_abs: Vec<[f64; LANE]>,
}

impl Carry {
    /// At rest.
    fn new(out: &Outputs, modes: usize) -> Self {
        Self {
            y: vec![0.0; 2 * modes],
            f_abs: vec![[0.0; LANE]; out.count.div_ceil(LANE)],
        }
    }
}

/// The copies of the first pass, each compiled for an instruction set: the same operations in
/// the same order (no multiply–add contracted), so the same bits. AVX-512 (with VL) runs the
/// AVX2 copy's 256-bit operations with 32 vector registers instead of 16, so that more of the
/// modes' coefficients stay in registers (`tnew` of `configs/mdof.yaml`, two pairs: 40.4 → 38.8 s
/// and 40.4 → 39.1 s; docs/performance.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Simd {
    Baseline,
    Avx2,
    Avx512,
}

impl Simd {
    /// The most this processor runs.
    fn available() -> Simd {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            if has!("avx2") && has!("avx512f") && has!("avx512vl") {
                return Simd::Avx512;
            }
            if has!("avx2") {
                return Simd::Avx2;
            }
        }
        Simd::Baseline
    }
}

/// Lane `l` of a state held lane by lane (`[component][lane]`) into `out`, component by
/// component.
#[inline(always)]
fn lane_of<const L: usize>(lanes: &[[f64; L]], l: usize, out: &mut [f64]) {
    for (o, v) in out.iter_mut().zip(lanes) {
        *o = v[l];
    }
}

/// Records whose first passes run side by side, one per lane of four `f64` (one AVX2
/// register).
const MOTIONS: usize = 4;

/// `LinearBuilding::lane_step` of [`MOTIONS`] lanes in AVX2 registers: the same operations in
/// the same order (no multiply–add contracted), so the same bits. Written with intrinsics
/// because the compiler vectorises the portable version's loop over the modes as well, four
/// modes at a time through transposes and spills, which made ten or more modes in lanes no
/// faster than each record alone (`cargo bench --bench linear`, `records/20`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn lane_step_avx2<const SUM: bool>(
    steps: &[ModeStep],
    y: &mut [[f64; MOTIONS]],
    q_max: &mut [[f64; MOTIONS]],
    (a0, a1): ([f64; MOTIONS], [f64; MOTIONS]),
    inv_h: f64,
    row: &[f64],
    f: &mut [[f64; MOTIONS]; 2],
) {
    use std::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_andnot_pd, _mm256_loadu_pd, _mm256_max_pd, _mm256_mul_pd,
        _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
    };
    // SAFETY (every load and store): a `[f64; MOTIONS]` is four contiguous `f64`.
    let load = |v: &[f64; MOTIONS]| unsafe { _mm256_loadu_pd(v.as_ptr()) };
    let store = |v: &mut [f64; MOTIONS], x: __m256d| unsafe { _mm256_storeu_pd(v.as_mut_ptr(), x) };
    let (mul, add, sub, splat) = (_mm256_mul_pd, _mm256_add_pd, _mm256_sub_pd, _mm256_set1_pd);
    let m = steps.len();
    let (re, im) = y.split_at_mut(m);
    let (a0, a1) = (load(&a0), load(&a1));
    let slope = mul(sub(a1, a0), splat(inv_h));
    let sign = splat(-0.0);
    let (w_re, w_im) = if SUM { row.split_at(m) } else { (row, row) };
    if SUM {
        assert_eq!(w_im.len(), m, "one output's row: 2·modes weights");
    }
    let (mut f0, mut f1) = (load(&f[0]), splat(0.0));
    for (r, (((s, yr), yi), q_max)) in steps.iter().zip(re).zip(im).zip(q_max).enumerate() {
        let (y0r, y0i) = (load(yr), load(yi));
        if SUM {
            f0 = add(f0, mul(splat(w_im[r]), y0i));
        }
        let qr = add(
            add(
                sub(mul(splat(s.l2.0), y0r), mul(splat(s.l2.1), y0i)),
                mul(splat(s.lg.0), a0),
            ),
            mul(splat(s.ng.0), slope),
        );
        let qi = add(
            add(
                add(mul(splat(s.l2.0), y0i), mul(splat(s.l2.1), y0r)),
                mul(splat(s.lg.1), a0),
            ),
            mul(splat(s.ng.1), slope),
        );
        let qa = add(_mm256_andnot_pd(sign, qr), _mm256_andnot_pd(sign, qi));
        // `q_max` is never NaN (from 0, raised by `f64::max`), and `maxpd` gives its second
        // operand where either is NaN: `f64::max(q_max, qa)`.
        store(q_max, _mm256_max_pd(qa, load(q_max)));
        let y1r = add(
            add(
                sub(mul(splat(s.e.0), y0r), mul(splat(s.e.1), y0i)),
                mul(splat(s.fa0.0), a0),
            ),
            mul(splat(s.fa1.0), a1),
        );
        store(yr, y1r);
        store(
            yi,
            add(
                add(
                    add(mul(splat(s.e.0), y0i), mul(splat(s.e.1), y0r)),
                    mul(splat(s.fa0.1), a0),
                ),
                mul(splat(s.fa1.1), a1),
            ),
        );
        if SUM {
            f1 = add(f1, mul(splat(w_re[r]), y1r));
        }
    }
    if SUM {
        store(&mut f[0], f0);
        store(&mut f[1], f1);
    }
}

/// One mode's coefficients over a sample interval of `h`.
#[derive(Debug, Clone, Copy)]
struct ModeStep {
    /// `e^{λh}`.
    e: Cx,
    /// `F_r`, `G_r` (module doc): the end state's coefficients on `a_g,k` and `a_g,k+1`, s.
    fa0: Cx,
    fa1: Cx,
    /// `λ²`, `−λ·g`, `−g`: `q = λ²·y₀ + (−λg)·a_g,k + (−g)·ȧ_g`.
    l2: Cx,
    lg: Cx,
    ng: Cx,
}

impl LinearBuilding {
    /// The kernel of `building` (no stacks, elastic storeys; its storey heights enter only the
    /// overturning moment). Computes the modal basis of `(M, C, K)` and the output rows once.
    pub fn new(building: &Building) -> Result<Self, LinearBuildingError> {
        if building.blocks() > 0 {
            return Err(LinearBuildingError::Stacks(building.blocks()));
        }
        if building.springs().is_some() {
            return Err(LinearBuildingError::Yielding);
        }
        let n = building.storeys();
        let storey_heights_m = building.storey_heights_m();
        let masses = &building.masses()[..n];
        let (k, c) = (building.stiffness(), building.damping());
        let modes = StateModes::new(masses, k, c)?;
        let m = modes.modes();
        let outputs = 4 * n + 1;

        // Storey i's shear, V_i = k_i·(u_i − u_{i−1}) + Σ_{j≥i} Σ_l C_jl·u̇_l, as coefficients on
        // the floors' displacements (N/m) and velocities (N·s/m); the moment Σ_i h_i·V_i the
        // same way.
        let shear = |i: usize| {
            let mut su = vec![0.0; n];
            su[i] = k[i];
            if i > 0 {
                su[i - 1] = -k[i];
            }
            let sv: Vec<f64> = (0..n).map(|l| (i..n).map(|j| c[j * n + l]).sum()).collect();
            (su, sv)
        };
        let (mut mu, mut mv) = (vec![0.0; n], vec![0.0; n]);
        for (i, &h) in storey_heights_m.iter().enumerate() {
            let (su, sv) = shear(i);
            for j in 0..n {
                mu[j] += h * su[j];
                mv[j] += h * sv[j];
            }
        }
        // A real combination of displacement and velocity rows, summed floor by floor (for
        // storey 1 the same operations as the integrator's `Row::Shear`).
        let combine = |su: &[f64], sv: &[f64], r: usize| {
            (0..n).fold(Cx(0.0, 0.0), |s, j| {
                s.add(modes.row(j)[r].scale(su[j]))
                    .add(modes.row(n + j)[r].scale(sv[j]))
            })
        };
        let mut rows = vec![Cx(0.0, 0.0); outputs * m];
        for j in 0..n {
            let (su, sv) = shear(j);
            for r in 0..m {
                let u = modes.row(j)[r];
                let u_prev = if j > 0 {
                    modes.row(j - 1)[r]
                } else {
                    Cx(0.0, 0.0)
                };
                rows[Self::disp(j) * m + r] = u;
                rows[Self::accel(n, j) * m + r] = modes.lambda[r].mul(modes.row(n + j)[r]);
                rows[Self::drift(n, j) * m + r] = u.sub(u_prev);
                rows[Self::shear(n, j) * m + r] = combine(&su, &sv, r);
            }
        }
        for r in 0..m {
            rows[Self::moment(n) * m + r] = combine(&mu, &mv, r);
        }
        Ok(Self {
            n,
            modes,
            heights_m: storey_heights_m.to_vec(),
            rows,
        })
    }

    /// The outputs `which`, in that order (an index beyond the storeys panics).
    pub fn select(&self, which: &[LinearOutput]) -> Selection {
        let (n, m) = (self.n, self.modes());
        let rows = (which.iter())
            .flat_map(|&o| {
                let at = match o {
                    LinearOutput::FloorDisplacement(j) => Self::disp(j),
                    LinearOutput::FloorAbsAccel(j) => Self::accel(n, j),
                    LinearOutput::StoreyDrift(i) => Self::drift(n, i),
                    LinearOutput::StoreyShear(i) => Self::shear(n, i),
                    LinearOutput::OverturningMoment => Self::moment(n),
                };
                let within = match o {
                    LinearOutput::OverturningMoment => 0,
                    LinearOutput::FloorDisplacement(j)
                    | LinearOutput::FloorAbsAccel(j)
                    | LinearOutput::StoreyDrift(j)
                    | LinearOutput::StoreyShear(j) => j,
                };
                assert!(within < n, "{o:?} of a building of {n} storeys");
                self.rows[at * m..(at + 1) * m].iter().copied()
            })
            .collect();
        Selection(Outputs::new(&self.modes, rows))
    }

    /// The peak `|f|` over `ground` of every output of `selection` (from
    /// [`Self::select`] of this building), in its order.
    pub fn peaks_of(
        &self,
        selection: &Selection,
        ground: &Ground,
    ) -> Result<Vec<f64>, LinearBuildingError> {
        self.peaks(&selection.0, ground)
    }

    /// [`Self::peaks_of`] of each of `grounds`, in their order, to the bit; records of one
    /// sample interval run side by side, four at a time.
    pub fn peaks_of_records(
        &self,
        selection: &Selection,
        grounds: &[Ground],
    ) -> Result<Vec<Vec<f64>>, LinearBuildingError> {
        self.peaks_of_records_in(&selection.0, grounds)
    }

    fn disp(j: usize) -> usize {
        j
    }
    fn accel(n: usize, j: usize) -> usize {
        n + j
    }
    fn drift(n: usize, i: usize) -> usize {
        2 * n + i
    }
    fn shear(n: usize, i: usize) -> usize {
        3 * n + i
    }
    fn moment(n: usize) -> usize {
        4 * n
    }

    /// Storeys (and floors) `N`.
    pub fn storeys(&self) -> usize {
        self.n
    }

    /// Storey heights, m, storey 1 first.
    pub fn storey_heights_m(&self) -> &[f64] {
        &self.heights_m
    }

    /// Kept modes of the state matrix (one per complex pair, one per real eigenvalue).
    pub fn modes(&self) -> usize {
        self.modes.modes()
    }

    /// The modes' coefficients over a sample interval of `h` s.
    fn mode_steps(&self, h: f64) -> Vec<ModeStep> {
        let g = self.modes.load_row();
        let inv_h = 1.0 / h;
        self.modes
            .lambda
            .iter()
            .zip(g)
            .map(|(&l, &g)| {
                let [e, p1, p2, _] = mode_terms(l, h);
                let ng = Cx(-g.0, -g.1);
                let p2h = p2.scale(inv_h);
                ModeStep {
                    e,
                    fa0: ng.mul(p1.sub(p2h)),
                    fa1: ng.mul(p2h),
                    l2: l.mul(l),
                    lg: l.mul(ng),
                    ng,
                }
            })
            .collect()
    }

    /// One sample interval: raises `q_max[r]` to the interval's bound of `|y_r''|`
    /// (`|Re q| + |Im q| ≥ |q|`) and moves `y` (`Re y_r` then `Im y_r`) to its end.
    #[inline(always)]
    fn step(steps: &[ModeStep], y: &mut [f64], q_max: &mut [f64], a0: f64, a1: f64, inv_h: f64) {
        let m = steps.len();
        let (re, im) = y.split_at_mut(m);
        let slope = (a1 - a0) * inv_h;
        // Written out rather than through `Cx` so that it is compiled into the AVX2 copy of the
        // first pass whatever the inliner decides (the same operations in the same order).
        for (((s, yr), yi), q_max) in steps.iter().zip(re).zip(im).zip(q_max) {
            let (y0r, y0i) = (*yr, *yi);
            let qr = s.l2.0 * y0r - s.l2.1 * y0i + s.lg.0 * a0 + s.ng.0 * slope;
            let qi = s.l2.0 * y0i + s.l2.1 * y0r + s.lg.1 * a0 + s.ng.1 * slope;
            let qa = qr.abs() + qi.abs();
            *q_max = if qa > *q_max { qa } else { *q_max };
            *yr = s.e.0 * y0r - s.e.1 * y0i + s.fa0.0 * a0 + s.fa1.0 * a1;
            *yi = s.e.0 * y0i + s.e.1 * y0r + s.fa0.1 * a0 + s.fa1.1 * a1;
        }
    }

    /// The first pass over the samples (module doc) of up to [`MOTIONS`] records of one sample
    /// interval: side by side, one per SIMD lane, over the longest record's whole blocks (a
    /// shorter record's lane runs on over zeros, its pass and state kept as they stood at its
    /// own last whole block), then each record's partial last block alone (one record: alone
    /// throughout). Every lane does the scalar pass's operations in its order, so each record's
    /// pass has the same bits as its own. Compiled for AVX-512, AVX2 (each chosen at run time
    /// where the processor has it) and the baseline ([`Simd`]); none contracts a multiply and
    /// an add, so all give the same bits.
    fn first_passes(
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]],
        inv_h: f64,
    ) -> Vec<FirstPass> {
        Self::first_passes_in(Simd::Avx512, out, steps, accels, inv_h)
    }

    /// [`Self::first_passes`] by the copies of `simd`, or of the most below it that the
    /// processor runs.
    fn first_passes_in(
        simd: Simd,
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]],
        inv_h: f64,
    ) -> Vec<FirstPass> {
        match simd.min(Simd::available()) {
            // SAFETY: a copy only as far as the processor runs it (`Simd::available`).
            #[cfg(target_arch = "x86_64")]
            Simd::Avx512 => unsafe { Self::first_passes_avx512(out, steps, accels, inv_h) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 => unsafe { Self::first_passes_avx2(out, steps, accels, inv_h) },
            _ => Self::first_passes_with::<false>(out, steps, accels, inv_h),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn first_passes_avx2(
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]],
        inv_h: f64,
    ) -> Vec<FirstPass> {
        Self::first_passes_with::<true>(out, steps, accels, inv_h)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl")]
    unsafe fn first_passes_avx512(
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]],
        inv_h: f64,
    ) -> Vec<FirstPass> {
        Self::first_passes_with::<true>(out, steps, accels, inv_h)
    }

    /// [`Self::first_passes`], compiled into each copy: `AVX2` only in
    /// [`Self::first_passes_avx2`] and [`Self::first_passes_avx512`], whose lane steps are then
    /// [`lane_step_avx2`]'s.
    #[inline(always)]
    fn first_passes_with<const AVX2: bool>(
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]],
        inv_h: f64,
    ) -> Vec<FirstPass> {
        let m = steps.len();
        let mut passes: Vec<FirstPass> = (accels.iter())
            .map(|a| FirstPass::new(out, m, a.len() - 1))
            .collect();
        let mut carries: Vec<Carry> = accels.iter().map(|_| Carry::new(out, m)).collect();
        // Each record's whole blocks, and the most of them.
        let whole: Vec<usize> = accels.iter().map(|a| (a.len() - 1) / BLOCK).collect();
        let most = whole.iter().copied().max().unwrap_or(0);
        let mut from = vec![0; accels.len()];
        if accels.len() > 1 && most > 0 {
            // A record shorter than the longest's whole blocks, padded with zeros to them.
            let samples = most * BLOCK + 1;
            let padded: Vec<Cow<[f64]>> = (accels.iter())
                .map(|&a| {
                    if a.len() < samples {
                        Cow::Owned([a, &vec![0.0; samples - a.len()]].concat())
                    } else {
                        Cow::Borrowed(a)
                    }
                })
                .collect();
            // Fewer records than lanes: the first fills the rest, its copies' passes dropped.
            let record = |l: usize| if l < accels.len() { l } else { 0 };
            let lanes: [&[f64]; MOTIONS] = std::array::from_fn(|l| &*padded[record(l)]);
            let ends: [usize; MOTIONS] = std::array::from_fn(|l| whole[record(l)]);
            for _ in accels.len()..MOTIONS {
                passes.push(FirstPass::new(out, m, accels[0].len() - 1));
                carries.push(Carry::new(out, m));
            }
            let (p, c) = (&mut passes, &mut carries);
            Self::lane_blocks::<AVX2>(out, steps, &lanes, inv_h, p, c, ends);
            from = whole;
        }
        passes.truncate(accels.len());
        for (((pass, carry), accel), from) in
            passes.iter_mut().zip(&mut carries).zip(accels).zip(from)
        {
            Self::blocks(out, steps, accel, inv_h, pass, carry, from);
        }
        passes
    }

    /// The first pass's blocks from `from` to the record's end, from the state `carry` holds
    /// at block `from`'s start.
    #[inline(always)]
    fn blocks(
        out: &Outputs,
        steps: &[ModeStep],
        accel: &[f64],
        inv_h: f64,
        pass: &mut FirstPass,
        carry: &mut Carry,
        from: usize,
    ) {
        let m = steps.len();
        let groups = out.count.div_ceil(LANE);
        let intervals = accel.len() - 1;
        let Carry { y, f_abs } = carry;
        let mut f = vec![[0.0; LANE]; groups];
        for b in from..intervals.div_ceil(BLOCK) {
            pass.starts[b * 2 * m..(b + 1) * 2 * m].copy_from_slice(y);
            let bm = &mut pass.block_max[b * groups..(b + 1) * groups];
            bm.copy_from_slice(f_abs);
            let bq = &mut pass.block_q[b * m..(b + 1) * m];
            for k in b * BLOCK..((b + 1) * BLOCK).min(intervals) {
                Self::step(steps, y, bq, accel[k], accel[k + 1], inv_h);
                if out.count == 1 {
                    f[0][0] = out.eval_one(0, y);
                } else {
                    out.eval_all(y, &mut f);
                }
                for ((bm, fa), fo) in bm.iter_mut().zip(f_abs.iter_mut()).zip(&f) {
                    for i in 0..LANE {
                        let a = fo[i].abs();
                        fa[i] = a;
                        // `max` without its NaN case: one instruction.
                        bm[i] = if a > bm[i] { a } else { bm[i] };
                    }
                }
            }
            for (best, bm) in pass.best.iter_mut().zip(bm.iter()) {
                for i in 0..LANE {
                    best[i] = if bm[i] > best[i] { bm[i] } else { best[i] };
                }
            }
        }
    }

    /// [`Self::blocks`] over [`MOTIONS`] records at once, one per lane (each lane the scalar
    /// operations in their order), lane `l` kept for its first `ends[l]` blocks: its pass
    /// written over them and its state after them left in its `carries`. The lanes run the
    /// most blocks of any (`accels[l]` holds at least `BLOCK·max(ends) + 1` samples). `AVX2`:
    /// compiled into [`Self::first_passes_avx2`] and [`Self::first_passes_avx512`] alone, its
    /// steps by [`lane_step_avx2`] (inlined there, so compiled for each).
    #[inline(always)]
    fn lane_blocks<const AVX2: bool>(
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]; MOTIONS],
        inv_h: f64,
        passes: &mut [FirstPass],
        carries: &mut [Carry],
        ends: [usize; MOTIONS],
    ) {
        if out.count == 1 {
            return Self::lane_blocks_one::<AVX2>(out, steps, accels, inv_h, passes, carries, ends);
        }
        const L: usize = MOTIONS;
        let m = steps.len();
        let groups = out.count.div_ceil(LANE);
        let mut y = vec![[0.0; L]; 2 * m];
        let mut q = vec![[0.0; L]; m];
        let mut f = vec![[[0.0; LANE]; L]; groups];
        let mut f_abs = vec![[[0.0; LANE]; L]; groups];
        let mut bm = vec![[[0.0; LANE]; L]; groups];
        let mut sums = [[0.0; L]; 2];
        let blocks = ends.iter().copied().max().unwrap_or(0);
        for b in 0..blocks {
            for (l, pass) in passes.iter_mut().enumerate().filter(|(l, _)| b < ends[*l]) {
                lane_of(&y, l, &mut pass.starts[b * 2 * m..(b + 1) * 2 * m]);
            }
            bm.copy_from_slice(&f_abs);
            q.fill([0.0; L]);
            for k in b * BLOCK..(b + 1) * BLOCK {
                let a0: [f64; L] = std::array::from_fn(|l| accels[l][k]);
                let a1: [f64; L] = std::array::from_fn(|l| accels[l][k + 1]);
                Self::lane_step_in::<AVX2, false>(
                    steps,
                    &mut y,
                    &mut q,
                    (a0, a1),
                    inv_h,
                    &[],
                    &mut sums,
                );
                out.lane_eval_all(&y, &mut f);
                for ((bm, fa), fo) in bm.iter_mut().zip(f_abs.iter_mut()).zip(&f) {
                    for l in 0..L {
                        for i in 0..LANE {
                            let a = fo[l][i].abs();
                            fa[l][i] = a;
                            bm[l][i] = if a > bm[l][i] { a } else { bm[l][i] };
                        }
                    }
                }
            }
            for (l, pass) in passes.iter_mut().enumerate().filter(|(l, _)| b < ends[*l]) {
                lane_of(&q, l, &mut pass.block_q[b * m..(b + 1) * m]);
                for (g, bm) in bm.iter().enumerate() {
                    pass.block_max[b * groups + g] = bm[l];
                    let best = &mut pass.best[g];
                    for i in 0..LANE {
                        best[i] = if bm[l][i] > best[i] {
                            bm[l][i]
                        } else {
                            best[i]
                        };
                    }
                }
            }
            for (l, carry) in carries
                .iter_mut()
                .enumerate()
                .filter(|(l, _)| b + 1 == ends[*l])
            {
                lane_of(&y, l, &mut carry.y);
                for (g, fa) in f_abs.iter().enumerate() {
                    carry.f_abs[g] = fa[l];
                }
            }
        }
    }

    /// [`Self::lane_blocks`] of a table of one output (a search of one attached fraction): its
    /// `|f|` kept per lane alone, not in a group of [`LANE`] whose other seven are zero, and
    /// summed as [`Self::lane_eval_all`] sums it; the same values in `passes` and `carries`.
    #[inline(always)]
    fn lane_blocks_one<const AVX2: bool>(
        out: &Outputs,
        steps: &[ModeStep],
        accels: &[&[f64]; MOTIONS],
        inv_h: f64,
        passes: &mut [FirstPass],
        carries: &mut [Carry],
        ends: [usize; MOTIONS],
    ) {
        const L: usize = MOTIONS;
        let m = steps.len();
        let row = &out.wrows[..2 * m];
        let mut y = vec![[0.0; L]; 2 * m];
        let mut q = vec![[0.0; L]; m];
        let mut f_abs = [0.0; L];
        let mut f = [[0.0; L]; 2];
        let blocks = ends.iter().copied().max().unwrap_or(0);
        for b in 0..blocks {
            for (l, pass) in passes.iter_mut().enumerate().filter(|(l, _)| b < ends[*l]) {
                lane_of(&y, l, &mut pass.starts[b * 2 * m..(b + 1) * 2 * m]);
            }
            let mut bm = f_abs;
            q.fill([0.0; L]);
            let mut keep = |f: [f64; L]| {
                for l in 0..L {
                    let a = f[l].abs();
                    f_abs[l] = a;
                    bm[l] = if a > bm[l] { a } else { bm[l] };
                }
            };
            // Each step completes the output of the sample before it (`lane_step`'s `SUM`):
            // the first step's is discarded (the last block's was completed below).
            for (j, k) in (b * BLOCK..(b + 1) * BLOCK).enumerate() {
                let a0: [f64; L] = std::array::from_fn(|l| accels[l][k]);
                let a1: [f64; L] = std::array::from_fn(|l| accels[l][k + 1]);
                Self::lane_step_in::<AVX2, true>(
                    steps,
                    &mut y,
                    &mut q,
                    (a0, a1),
                    inv_h,
                    row,
                    &mut f,
                );
                if j > 0 {
                    keep(f[0]);
                }
                f[0] = f[1];
            }
            for (w, s) in row[m..].iter().zip(&y[m..]) {
                for l in 0..L {
                    f[0][l] += w * s[l];
                }
            }
            keep(f[0]);
            for (l, pass) in passes.iter_mut().enumerate().filter(|(l, _)| b < ends[*l]) {
                lane_of(&q, l, &mut pass.block_q[b * m..(b + 1) * m]);
                pass.block_max[b][0] = bm[l];
                let best = &mut pass.best[0][0];
                *best = if bm[l] > *best { bm[l] } else { *best };
            }
            for (l, carry) in carries
                .iter_mut()
                .enumerate()
                .filter(|(l, _)| b + 1 == ends[*l])
            {
                lane_of(&y, l, &mut carry.y);
                carry.f_abs[0][0] = f_abs[l];
            }
        }
    }

    /// [`Self::lane_step`] of [`MOTIONS`] lanes, by [`lane_step_avx2`] where `AVX2` (the
    /// same bits).
    #[inline(always)]
    fn lane_step_in<const AVX2: bool, const SUM: bool>(
        steps: &[ModeStep],
        y: &mut [[f64; MOTIONS]],
        q_max: &mut [[f64; MOTIONS]],
        a: ([f64; MOTIONS], [f64; MOTIONS]),
        inv_h: f64,
        row: &[f64],
        f: &mut [[f64; MOTIONS]; 2],
    ) {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is true only inside `first_passes_avx2` and
            // `first_passes_avx512`, called where the processor has AVX2.
            return unsafe { lane_step_avx2::<SUM>(steps, y, q_max, a, inv_h, row, f) };
        }
        Self::lane_step::<MOTIONS, SUM>(steps, y, q_max, a, inv_h, row, f)
    }

    /// [`Self::step`] in every lane. `SUM` (one output, its row `row`, [`Self::eval_one`]'s
    /// terms in its order, spread over two steps so that the sum's chain of additions overlaps
    /// the steps' arithmetic): `f[0]`, the previous state's output with its real parts' terms
    /// summed, gains the imaginary parts' terms (so holds that output, the same bits), and
    /// `f[1]` becomes the new state's real parts' terms summed from 0.
    #[inline(always)]
    fn lane_step<const L: usize, const SUM: bool>(
        steps: &[ModeStep],
        y: &mut [[f64; L]],
        q_max: &mut [[f64; L]],
        (a0, a1): ([f64; L], [f64; L]),
        inv_h: f64,
        row: &[f64],
        f: &mut [[f64; L]; 2],
    ) {
        let m = steps.len();
        let (re, im) = y.split_at_mut(m);
        let slope: [f64; L] = std::array::from_fn(|l| (a1[l] - a0[l]) * inv_h);
        let (w_re, w_im) = if SUM { row.split_at(m) } else { (row, row) };
        if SUM {
            assert_eq!(w_im.len(), m, "one output's row: 2·modes weights");
            f[1] = [0.0; L];
        }
        for (r, (((s, yr), yi), q_max)) in steps.iter().zip(re).zip(im).zip(q_max).enumerate() {
            let (y0r, y0i) = (*yr, *yi);
            if SUM {
                f[0] = std::array::from_fn(|l| f[0][l] + w_im[r] * y0i[l]);
            }
            let qr: [f64; L] = std::array::from_fn(|l| {
                s.l2.0 * y0r[l] - s.l2.1 * y0i[l] + s.lg.0 * a0[l] + s.ng.0 * slope[l]
            });
            let qi: [f64; L] = std::array::from_fn(|l| {
                s.l2.0 * y0i[l] + s.l2.1 * y0r[l] + s.lg.1 * a0[l] + s.ng.1 * slope[l]
            });
            let qa: [f64; L] = std::array::from_fn(|l| qr[l].abs() + qi[l].abs());
            // `f64::max` rather than a select, which the compiler makes a masked store (a
            // store-forwarding stall on the next sample): the same value, `qa` never NaN-free
            // below a NaN `q_max` (both start at 0 and `qa ≥ 0`).
            *q_max = std::array::from_fn(|l| q_max[l].max(qa[l]));
            *yr = std::array::from_fn(|l| {
                s.e.0 * y0r[l] - s.e.1 * y0i[l] + s.fa0.0 * a0[l] + s.fa1.0 * a1[l]
            });
            *yi = std::array::from_fn(|l| {
                s.e.0 * y0i[l] + s.e.1 * y0r[l] + s.fa0.1 * a0[l] + s.fa1.1 * a1[l]
            });
            if SUM {
                f[1] = std::array::from_fn(|l| f[1][l] + w_re[r] * yr[l]);
            }
        }
    }

    /// The peaks of every output over `ground` (from rest at its first sample, over its
    /// duration), exact for a ground acceleration linear between samples.
    pub fn run(&self, ground: &Ground) -> Result<LinearPeaks, LinearBuildingError> {
        let best = self.peaks(&Outputs::new(&self.modes, self.rows.clone()), ground)?;
        let n = self.n;
        let take = |at: fn(usize, usize) -> usize| (0..n).map(|j| best[at(n, j)]).collect();
        Ok(LinearPeaks {
            floor_peak_displacement_m: take(|_, j| Self::disp(j)),
            floor_peak_abs_accel_mps2: take(Self::accel),
            storey_peak_drift_m: take(Self::drift),
            storey_peak_shear_n: take(Self::shear),
            peak_overturning_moment_nm: best[Self::moment(n)],
        })
    }

    /// The peak `|V|` of the base shear over `ground`, N: [`Self::run`]'s
    /// [`LinearPeaks::peak_base_shear_n`] to the bit (the same row, sums and searches), at the
    /// cost of one output instead of `4N + 1`.
    pub fn peak_base_shear_n(&self, ground: &Ground) -> Result<f64, LinearBuildingError> {
        let base = self.select(&[LinearOutput::StoreyShear(0)]);
        Ok(self.peaks_of(&base, ground)?[0])
    }

    /// The peak `|f|` of every output of `out` over `ground` (module doc).
    fn peaks(&self, out: &Outputs, ground: &Ground) -> Result<Vec<f64>, LinearBuildingError> {
        ground.validate()?;
        let steps = self.mode_steps(ground.dt_s);
        let first = Self::first_passes(out, &steps, &[ground.accel_mps2], 1.0 / ground.dt_s)
            .pop()
            .expect("one record, one pass");
        self.second_pass(out, &steps, ground, first)
    }

    /// [`Self::peaks`] of each of `grounds`, in their order: the records of one sample interval
    /// run their first passes [`MOTIONS`] at a time ([`Self::first_passes`]), the same bits.
    fn peaks_of_records_in(
        &self,
        out: &Outputs,
        grounds: &[Ground],
    ) -> Result<Vec<Vec<f64>>, LinearBuildingError> {
        for g in grounds {
            g.validate()?;
        }
        let mut by_step: Vec<(u64, Vec<usize>)> = Vec::new();
        for (i, g) in grounds.iter().enumerate() {
            let key = g.dt_s.to_bits();
            match by_step.iter_mut().find(|(k, _)| *k == key) {
                Some((_, v)) => v.push(i),
                None => by_step.push((key, vec![i])),
            }
        }
        let mut peaks = vec![Vec::new(); grounds.len()];
        for (_, records) in by_step {
            let h = grounds[records[0]].dt_s;
            let steps = self.mode_steps(h);
            for batch in records.chunks(MOTIONS) {
                let accels: Vec<&[f64]> = batch.iter().map(|&i| grounds[i].accel_mps2).collect();
                let firsts = Self::first_passes(out, &steps, &accels, 1.0 / h);
                for (&i, first) in batch.iter().zip(firsts) {
                    peaks[i] = self.second_pass(out, &steps, &grounds[i], first)?;
                }
            }
        }
        Ok(peaks)
    }

    /// The peaks from a record's first pass `first` (module doc: the second pass).
    fn second_pass(
        &self,
        out: &Outputs,
        steps: &[ModeStep],
        ground: &Ground,
        first: FirstPass,
    ) -> Result<Vec<f64>, LinearBuildingError> {
        let accel = ground.accel_mps2;
        let h = ground.dt_s;
        let inv_h = 1.0 / h;
        let (m, outputs) = (self.modes(), out.count);
        // Curvature rows: h²/8 · w_r·|c_r| · max(1, e^{Re λ·h}), with the slack.
        let growth: Vec<f64> = (self.modes.lambda.iter())
            .map(|l| (l.0 * h).exp().max(1.0) * h * h / 8.0 * BOUND_SLACK)
            .collect();
        let curv: Vec<f64> = (out.rows_abs.chunks_exact(m))
            .flat_map(|row| row.iter().zip(&growth).map(|(a, g)| a * g))
            .collect();

        // First pass: sampled peaks, and per block its start state, sampled maxima and `|y''|`
        // bounds.
        let FirstPass {
            starts,
            block_max,
            block_q,
            best,
        } = first;
        let mut best: Vec<f64> = best.as_flattened()[..outputs].to_vec();
        if !best.iter().all(|x| x.is_finite()) {
            return Err(LinearBuildingError::NotFinite);
        }
        let block_max = block_max.as_flattened();
        let stride = outputs.div_ceil(LANE) * LANE;

        // Second pass: the blocks and intervals whose bound reaches an output's peak so far.
        let intervals = accel.len() - 1;
        let mut candidates = Vec::with_capacity(outputs);
        // Each candidate's value at the interval's start and end.
        let (mut f0, mut f1) = (Vec::with_capacity(outputs), Vec::with_capacity(outputs));
        let mut q = vec![0.0; m];
        let mut y = vec![0.0; 2 * m];
        let mut y1 = vec![0.0; 2 * m];
        let mut piece = Piece::default();
        for b in 0..intervals.div_ceil(BLOCK) {
            let bq = &block_q[b * m..(b + 1) * m];
            candidates.clear();
            for o in 0..outputs {
                let slack: f64 = curv[o * m..(o + 1) * m]
                    .iter()
                    .zip(bq)
                    .map(|(c, q)| c * q)
                    .sum();
                if block_max[b * stride + o] + slack > best[o] {
                    candidates.push(o);
                }
            }
            if candidates.is_empty() {
                continue;
            }
            y.copy_from_slice(&starts[b * 2 * m..(b + 1) * 2 * m]);
            f0.clear();
            f0.extend(candidates.iter().map(|&o| out.eval_one(o, &y)));
            for k in b * BLOCK..((b + 1) * BLOCK).min(intervals) {
                let (a0, a1) = (accel[k], accel[k + 1]);
                q.fill(0.0);
                y1.copy_from_slice(&y);
                Self::step(steps, &mut y1, &mut q, a0, a1, inv_h);
                f1.clear();
                f1.extend(candidates.iter().map(|&o| out.eval_one(o, &y1)));
                let mut built = false;
                for (i, &o) in candidates.iter().enumerate() {
                    let slack: f64 = curv[o * m..(o + 1) * m]
                        .iter()
                        .zip(&q)
                        .map(|(c, q)| c * q)
                        .sum();
                    if f0[i].abs().max(f1[i].abs()) + slack <= best[o] {
                        continue;
                    }
                    if !built {
                        self.piece(&y, a0, (a1 - a0) * inv_h, &mut piece);
                        built = true;
                    }
                    let ends = (f0[i], f1[i]);
                    best[o] = self
                        .search(out, o, &piece, (&y, &y1), ends, h, best[o])
                        .map_err(|source| {
                            LinearBuildingError::Ground(SimError::Search {
                                time_s: k as f64 * h,
                                source,
                            })
                        })?;
                }
                std::mem::swap(&mut y, &mut y1);
                std::mem::swap(&mut f0, &mut f1);
            }
        }

        Ok(best)
    }

    /// The modal coefficients of the interval starting at state `y` under
    /// `a_g(τ) = a0 + slope·τ`: `y₀`, `β₀ = −g·a0`, `β₁ = −g·slope`, `q = λ²y₀ + λβ₀ + β₁` and
    /// `|q|·|λ|^{k−2}` (as [`StateModes::piece_in_mode`] under the ground's load alone, `y` the
    /// modal state in real and imaginary halves).
    fn piece(&self, y: &[f64], a0: f64, slope: f64, out: &mut Piece) {
        let m = self.modes();
        let g = self.modes.load_row();
        for v in [&mut out.y0, &mut out.b0, &mut out.b1, &mut out.q2] {
            v.clear();
        }
        out.mag.clear();
        for r in 0..m {
            let l = self.modes.lambda[r];
            let y0 = Cx(y[r], y[m + r]);
            let b0 = g[r].scale(-a0);
            let b1 = g[r].scale(-slope);
            let q2 = l.mul(l).mul(y0).add(l.mul(b0)).add(b1);
            let (a, al) = (q2.abs(), l.abs());
            out.y0.push(y0);
            out.b0.push(b0);
            out.b1.push(b1);
            out.q2.push(q2);
            out.mag.push([a, al * a, al * al * a]);
        }
    }

    /// The peak `|f_o|` over one interval (`y`, `f` at its ends) if above `best`, else `best`:
    /// the certified search on the closed form.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        out: &Outputs,
        o: usize,
        piece: &Piece,
        (y0, y1): (&[f64], &[f64]),
        (f0, f1): (f64, f64),
        h: f64,
        best: f64,
    ) -> Result<f64, SearchError> {
        let m = self.modes();
        let c = &out.rows[o * m..(o + 1) * m];
        let func = ModalFn {
            modes: &self.modes,
            piece,
            c,
            c_abs: &out.rows_abs[o * m..(o + 1) * m],
            scale: 1.0,
            poly: [0.0; 4],
        };
        // Slopes at the ends: y' = λ·y + β₀ + β₁·τ.
        let (mut d0, mut d1) = (0.0, 0.0);
        for r in 0..m {
            let (l, w) = (self.modes.lambda[r], self.modes.weight[r]);
            let (b0, b1) = (piece.b0[r], piece.b1[r]);
            let s0 = l.mul(Cx(y0[r], y0[m + r])).add(b0);
            let s1 = l.mul(Cx(y1[r], y1[m + r])).add(b0).add(b1.scale(h));
            d0 += w * c[r].mul(s0).0;
            d1 += w * c[r].mul(s1).0;
        }
        let n0 = Node {
            at: 0.0,
            f: f0,
            df: d0,
        };
        let n1 = Node {
            at: h,
            f: f1,
            df: d1,
        };
        Ok(search::peak_abs(&func, &n0, &n1, best, h)?.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::model::{BuildingSpec, StackSpec, StoreyYielding};
    use super::*;

    fn spec() -> BuildingSpec {
        let mut s = BuildingSpec::uniform(3, 0.6);
        s.floor_masses = vec![1.2, 1.0, 0.7];
        s.storey_stiffnesses = vec![3.0, 2.0, 1.0];
        s
    }

    /// Stacks and yielding storeys are refused with the reason; the attached
    /// building of the same stacks is taken.
    #[test]
    fn refuses_what_is_not_a_linear_building() {
        let mut s = spec();
        s.stacks = vec![StackSpec::new(2, &[0.5, 0.5], &[0.2, 0.1])];
        let b = Building::new(&s).unwrap();
        let e = LinearBuilding::new(&b).unwrap_err();
        assert_eq!(e, LinearBuildingError::Stacks(2));
        assert!(e.to_string().contains("without stacks"), "{e}");
        assert!(LinearBuilding::new(&b.with_stacks_attached_fraction(0.3)).is_ok());
        let mut y = spec();
        y.yielding = Some(StoreyYielding {
            strength_ratios: vec![0.2; 3],
            post_yield_ratio: 0.05,
        });
        let b = Building::new(&y).unwrap();
        assert_eq!(
            LinearBuilding::new(&b).unwrap_err(),
            LinearBuildingError::Yielding
        );
        let b = Building::new(&spec()).unwrap();
        let lin = LinearBuilding::new(&b).unwrap();
        let e = lin.run(&Ground::new(0.01, &[0.0])).unwrap_err();
        assert_eq!(e, LinearBuildingError::Ground(SimError::TooShort(1)));
    }

    /// The first passes of records side by side and each alone, by the AVX-512 and AVX2 copies
    /// (where the processor has them) and by the baseline's, against each record's pass alone by
    /// the baseline's: every stored number the same bits, for one output (its sum spread over
    /// two steps) and several, with records shorter than the longest's whole blocks, one shorter
    /// than a block and a batch short of lanes. `tests/building_linear.rs` checks the peaks;
    /// this reaches the copies a processor with more never runs there.
    #[test]
    fn lanes_give_each_records_first_pass_on_either_instruction_set() {
        let lin = LinearBuilding::new(&Building::new(&spec()).unwrap()).unwrap();
        let steps = lin.mode_steps(0.01);
        let wave = |n: usize, w: f64| -> Vec<f64> {
            (0..n)
                .map(|k| 3.0 * (k as f64 * w).sin() * (-(k as f64) / 500.0).exp())
                .collect()
        };
        let records: Vec<Vec<f64>> = [700, 1001, 333, 20, 961]
            .iter()
            .enumerate()
            .map(|(i, &n)| wave(n, 0.05 + 0.02 * i as f64))
            .collect();
        let one = lin.select(&[LinearOutput::StoreyShear(0)]);
        let several = lin.select(&[
            LinearOutput::FloorDisplacement(2),
            LinearOutput::OverturningMoment,
            LinearOutput::FloorAbsAccel(0),
        ]);
        let bits = |p: &FirstPass| -> Vec<u64> {
            (p.starts.iter().chain(&p.block_q))
                .chain(p.block_max.as_flattened())
                .chain(p.best.as_flattened())
                .map(|x| x.to_bits())
                .collect()
        };
        for out in [&one.0, &several.0] {
            for batch in [&records[..4], &records[..2], &records[2..]] {
                let accels: Vec<&[f64]> = batch.iter().map(|a| &a[..]).collect();
                let alone: Vec<Vec<u64>> = (accels.iter())
                    .map(|a| {
                        let pass = LinearBuilding::first_passes_in(
                            Simd::Baseline,
                            out,
                            &steps,
                            &[a],
                            100.0,
                        );
                        bits(&pass[0])
                    })
                    .collect();
                // A copy the processor does not run gives way to the most below it that it
                // runs (`Simd::available`).
                for simd in [Simd::Baseline, Simd::Avx2, Simd::Avx512] {
                    let lanes = LinearBuilding::first_passes_in(simd, out, &steps, &accels, 100.0);
                    let got: Vec<Vec<u64>> = lanes.iter().map(bits).collect();
                    assert_eq!(
                        got,
                        alone,
                        "{simd:?}, {} outputs, {} records",
                        out.count,
                        batch.len()
                    );
                    // Each record alone by this copy too (its partial last block).
                    for (a, want) in accels.iter().zip(&alone) {
                        let pass = LinearBuilding::first_passes_in(simd, out, &steps, &[a], 100.0);
                        assert_eq!(&bits(&pass[0]), want, "{simd:?} alone");
                    }
                }
            }
        }
    }

    /// The recurrence's coefficients against the closed form of one interval: a state and a
    /// linear load stepped by `ModeStep` equal `e^{λh}y₀ + hφ₁β₀ + h²φ₂β₁` (the piece's own
    /// evaluation, `ModalPoint`) to a few ulps.
    #[test]
    fn the_recurrence_is_the_closed_form_of_an_interval() {
        use super::super::modal::ModalPoint;
        let b = Building::new(&spec()).unwrap();
        let lin = LinearBuilding::new(&b).unwrap();
        let m = lin.modes();
        let h = 0.013;
        let steps = lin.mode_steps(h);
        let y0: Vec<f64> = (0..2 * m).map(|i| 0.01 * (i as f64 + 1.0).sin()).collect();
        let (a0, a1) = (1.7, -0.4);
        let mut y = y0.clone();
        let mut q = vec![0.0; m];
        LinearBuilding::step(&steps, &mut y, &mut q, a0, a1, 1.0 / h);
        let mut piece = Piece::default();
        lin.piece(&y0, a0, (a1 - a0) / h, &mut piece);
        let mut p = ModalPoint::default();
        p.at(&lin.modes, &piece, h);
        for r in 0..m {
            let want = p.y[r];
            let err = Cx(y[r], y[m + r]).sub(want).abs();
            assert!(err < 1e-14 * want.abs().max(1e-3), "mode {r}: {err:e}");
            // The curvature bound covers the modulus of y''(0) = q.
            assert!(q[r] >= piece.q2[r].abs() && q[r] <= 1.5 * piece.q2[r].abs());
        }
    }
}
