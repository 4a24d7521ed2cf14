//! The building's floors within one contact and yield state (docs/model.md, "A multi-storey
//! building"): a linear system `M·ü + C·u̇ + K_t·u = −M·1·a_g(t) − d − f_top` with constant `M`
//! (each floor's mass plus the blocks stuck to it), `C`, `K_t` (each storey's branch
//! stiffness) and loads, linear in time within a piece.
//!
//! Its state `z = (u, u̇)` (floor displacements and velocities relative to the ground) obeys
//! `ż = A·z + (0, p₀ + p₁·τ)` with `p = −1·a_g − M⁻¹(d + f_top)`. In the eigenvector basis of `A`
//! (`A = V·Λ·V⁻¹`) every mode is a scalar equation `ẏ_r = λ_r·y_r + β₀ + β₁·τ` with the exact
//! solution `y_r(τ) = e^{λτ}·y₀ + τφ₁(λτ)·β₀ + τ²φ₂(λτ)·β₁` (Hochbruck & Ostermann 2010), stable
//! for every `λ`, zero included (an elastic–perfectly plastic storey). Any linear function of the
//! state (a floor's displacement or absolute acceleration, a storey's drift, a relative velocity)
//! is `Σ_r w_r·Re(c_r·y_r(τ))` plus a polynomial, and its `k`-th derivative (`k ≥ 2`) is bounded by
//! `Σ_r w_r·|c_r|·|λ^k·y₀ + λ^{k−1}·β₀ + λ^{k−2}·β₁|·e^{Re λ·τ}`: the bounds the certified searches
//! need ([`super::super::search`]). A complex pair is kept once with weight 2.
//!
//! The eigenvectors: `A` is written in the undamped modes `Φ` of `(K_t, M)` (mass-normalised) and
//! balanced, `B = [[0, S], [−Ω²S⁻¹, −Φᵀ·C·Φ]]` on `(S·q, q̇)` with `S = diag(ω_r)`, so every entry
//! is of the size of a frequency; its eigenvalues come from `nalgebra`'s real Schur form and each
//! eigenvector from two steps of inverse iteration (complex LU at a shift `1e-10·‖B‖` off the
//! eigenvalue), orthogonalised within a cluster of repeated eigenvalues. `V⁻¹` is an LU solve;
//! a basis whose eigenvectors are too close to dependent (a defective or nearly defective state
//! matrix, near critical damping of a mode) is refused with [`ModalError::Defective`].

use super::model::modes;
use crate::numeric::Cx;
use nalgebra::{Complex, DMatrix, DVector, Schur};
use thiserror::Error;

/// Eigenvectors whose matrix has a condition number above this lose more than about 8 digits;
/// such a state is refused rather than run.
pub const MAX_MODAL_CONDITION: f64 = 1e8;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModalError {
    #[error(
        "the building's state matrix in this contact and yield state has (nearly) coinciding \
         modes (eigenvector condition number {condition:.1e} > {MAX_MODAL_CONDITION:.0e}, e.g. a \
         mode at critical damping); this state is not supported: change the damping slightly"
    )]
    Defective { condition: f64 },
    #[error("the eigenvalues of the building's state matrix did not converge")]
    NoConvergence,
}

/// The eigenvector basis of one contact and yield state.
#[derive(Debug, Clone)]
pub struct StateModes {
    /// Floors `N`.
    pub n: usize,
    /// Kept eigenvalues (one of each complex pair, and the real ones), rad/s.
    pub lambda: Vec<Cx>,
    /// 2 for a kept complex pair, 1 for a real mode.
    pub weight: Vec<f64>,
    /// `V`: `2N × m` row-major, `z_i = Σ_r w_r·Re(v[i][r]·y_r)`.
    v: Vec<Cx>,
    /// Rows of `V⁻¹` for the kept modes, `y = uz·z` and `β = up·p`, stored column by column
    /// (`uz[i·m + r]`, `2N × m`; `up[j·m + r]`, `N × m`) for [`Self::piece`]'s pass over the
    /// modes.
    uz: Vec<Cx>,
    up: Vec<Cx>,
    /// `up·1` (`β₁ = −ȧ_g·up_ones`).
    up_ones: Vec<Cx>,
    /// `|λ_r|`.
    abs_lambda: Vec<f64>,
    /// This basis among those of the process (a clone keeps it: the same eigenvalues): what
    /// a piece keeps for its modes is kept under it ([`Kept`]).
    id: u64,
}

/// The next [`StateModes::id`].
static NEXT_BASIS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

impl StateModes {
    /// The basis of `M = diag(masses)`, storey stiffnesses `k_t` (N/m, `≥ 0`) and damping
    /// `c` (row-major `N × N`).
    pub fn new(masses: &[f64], k_t: &[f64], c: &[f64]) -> Result<Self, ModalError> {
        let n = masses.len();
        let (omega2, phi) = modes(masses, k_t);
        let omega: Vec<f64> = omega2.iter().map(|w| w.max(0.0).sqrt()).collect();
        let top = omega.iter().copied().fold(0.0, f64::max);
        let cm = DMatrix::from_row_slice(n, n, c);
        let c_modal = phi.transpose() * &cm * &phi;
        let top = top.max(c_modal.amax()).max(1e-300);
        // Balancing (any positive scale is exact): a mode of little or no stiffness takes a
        // scale near the largest frequency, so that no entry is a round-off ratio.
        let s: Vec<f64> = omega.iter().map(|&w| w.max(1e-4 * top)).collect();
        let dim = 2 * n;
        let b = DMatrix::from_fn(dim, dim, |r, col| match (r < n, col < n) {
            (true, true) => 0.0,
            (true, false) => {
                if col - n == r {
                    s[r]
                } else {
                    0.0
                }
            }
            (false, true) => {
                if r - n == col {
                    -omega2[col].max(0.0) / s[col]
                } else {
                    0.0
                }
            }
            (false, false) => -c_modal[(r - n, col - n)],
        });
        let (lambda, weight, vb) = eigenvectors(&b)?;
        let m = lambda.len();
        // Full V_B (conjugate partners as columns) and its inverse.
        let mut full = DMatrix::<Complex<f64>>::zeros(dim, dim);
        let mut col = 0;
        for r in 0..m {
            for i in 0..dim {
                full[(i, col)] = vb[(i, r)];
            }
            col += 1;
            if weight[r] == 2.0 {
                for i in 0..dim {
                    full[(i, col)] = vb[(i, r)].conj();
                }
                col += 1;
            }
        }
        let norm1 = |a: &DMatrix<Complex<f64>>| {
            (0..a.ncols())
                .map(|j| (0..a.nrows()).map(|i| a[(i, j)].norm()).sum::<f64>())
                .fold(0.0, f64::max)
        };
        let inv = full
            .clone()
            .lu()
            .try_inverse()
            .ok_or(ModalError::Defective {
                condition: f64::INFINITY,
            })?;
        let condition = norm1(&full) * norm1(&inv);
        if condition.is_nan() || condition > MAX_MODAL_CONDITION {
            return Err(ModalError::Defective { condition });
        }
        // Back to physical coordinates: u = Φ·S⁻¹·w₁, u̇ = Φ·w₂; w₁ = S·ΦᵀM·u, w₂ = ΦᵀM·u̇.
        let mut v = vec![Cx(0.0, 0.0); dim * m];
        for r in 0..m {
            for j in 0..n {
                let (mut du, mut dv) = (Complex::new(0.0, 0.0), Complex::new(0.0, 0.0));
                for q in 0..n {
                    du += vb[(q, r)] * (phi[(j, q)] / s[q]);
                    dv += vb[(n + q, r)] * phi[(j, q)];
                }
                v[j * m + r] = Cx(du.re, du.im);
                v[(n + j) * m + r] = Cx(dv.re, dv.im);
            }
        }
        // Rows of the inverse for the kept modes: the kept column order of `full`.
        let mut kept_rows = Vec::with_capacity(m);
        let mut col = 0;
        for &w in &weight {
            kept_rows.push(col);
            col += if w == 2.0 { 2 } else { 1 };
        }
        let mut uz = vec![Cx(0.0, 0.0); m * dim];
        let mut up = vec![Cx(0.0, 0.0); m * n];
        for (r, &row) in kept_rows.iter().enumerate() {
            for j in 0..n {
                let (mut gu, mut gv) = (Complex::new(0.0, 0.0), Complex::new(0.0, 0.0));
                for q in 0..n {
                    let pm = phi[(j, q)] * masses[j];
                    gu += inv[(row, q)] * (s[q] * pm);
                    gv += inv[(row, n + q)] * pm;
                }
                uz[j * m + r] = Cx(gu.re, gu.im);
                uz[(n + j) * m + r] = Cx(gv.re, gv.im);
                up[j * m + r] = Cx(gv.re, gv.im);
            }
        }
        let up_ones = (0..m)
            .map(|r| (0..n).map(|j| up[j * m + r]).fold(Cx(0.0, 0.0), Cx::add))
            .collect();
        let lambda: Vec<Cx> = lambda.iter().map(|l| Cx(l.re, l.im)).collect();
        let abs_lambda = lambda.iter().map(|l| l.abs()).collect();
        Ok(Self {
            n,
            lambda,
            weight,
            v,
            uz,
            up,
            up_ones,
            abs_lambda,
            id: NEXT_BASIS.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        })
    }

    /// Kept modes `m`.
    pub fn modes(&self) -> usize {
        self.lambda.len()
    }

    /// Row `i` of `V` (state component `i`: `u_j` for `i = j`, `u̇_j` for `i = N + j`).
    pub fn row(&self, i: usize) -> &[Cx] {
        let m = self.modes();
        &self.v[i * m..(i + 1) * m]
    }

    /// `V⁻¹` applied to a unit load on every floor, per kept mode: under `p(τ) = −a(τ)·1` (the
    /// ground's acceleration alone, no force offsets) the modal loads are `β = −a·load_row()`.
    pub fn load_row(&self) -> &[Cx] {
        &self.up_ones
    }

    /// The largest `|λ|`, rad/s.
    pub fn fastest(&self) -> f64 {
        self.abs_lambda.iter().copied().fold(0.0, f64::max)
    }

    /// The piece from state `z` (`2N`) under `p(τ) = p₀ + p₁·1·τ` (`p₀` per floor, m/s²), its
    /// loads projected as they are (the integrator splits them: [`Self::piece_in_mode`]).
    #[cfg(test)]
    pub fn piece(&self, z: &[f64], p0: &[f64], p1: f64, out: &mut Piece) {
        out.resize(self.modes());
        self.project(&self.uz, z, &mut out.y0);
        self.project(&self.up, p0, &mut out.b0);
        self.finish_piece(p1, out);
    }

    /// `y = V⁻¹·z` of a state `z` (`2N`), per kept mode.
    pub fn modal_state(&self, z: &[f64], y: &mut Vec<Cx>) {
        y.resize(self.modes(), Cx(0.0, 0.0));
        self.project(&self.uz, z, y);
    }

    /// The modal loads `β = up·p` of constant floor loads `p` (m/s²), per kept mode.
    pub fn modal_loads(&self, p: &[f64], beta: &mut Vec<Cx>) {
        beta.resize(self.modes(), Cx(0.0, 0.0));
        self.project(&self.up, p, beta);
    }

    /// The piece from modal state `y0` under `p(τ) = p_c − a·1 + p₁·1·τ`, `load` being
    /// [`Self::modal_loads`] of the constant `p_c`: `β₀ = load − a·up·1`. Within one mode the
    /// modal state carries from piece to piece, with no pass over the floors.
    pub fn piece_in_mode(&self, y0: &[Cx], load: &[Cx], a: f64, p1: f64, out: &mut Piece) {
        out.resize(self.modes());
        out.y0.copy_from_slice(y0);
        for ((b0, l), u) in out.b0.iter_mut().zip(load).zip(&self.up_ones) {
            *b0 = l.sub(u.scale(a));
        }
        self.finish_piece(p1, out);
    }

    /// `sum_r = Σ_i columns[i·m + r]·x_i`, each mode's terms added in column order from zero:
    /// mode by mode for a few modes, else one column at a time over every mode.
    fn project(&self, columns: &[Cx], x: &[f64], sum: &mut [Cx]) {
        let m = self.modes();
        if m <= FEW_MODES {
            for (r, s) in sum.iter_mut().enumerate() {
                let terms = x
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| columns[i * m + r].scale(x));
                *s = terms.fold(Cx(0.0, 0.0), Cx::add);
            }
            return;
        }
        sum.fill(Cx(0.0, 0.0));
        for (col, &x) in columns.chunks_exact(m).zip(x) {
            for (s, c) in sum.iter_mut().zip(col) {
                *s = s.add(c.scale(x));
            }
        }
    }

    /// A piece's `β₁`, `q₂` and bounds, from its `y₀` and `β₀`.
    fn finish_piece(&self, p1: f64, out: &mut Piece) {
        for r in 0..self.modes() {
            let (y0, b0) = (out.y0[r], out.b0[r]);
            let b1 = self.up_ones[r].scale(p1);
            let l = self.lambda[r];
            let q2 = l.mul(l).mul(y0).add(l.mul(b0)).add(b1);
            out.b1[r] = b1;
            out.q2[r] = q2;
            let a = q2.norm_sqr().sqrt();
            let al = self.abs_lambda[r];
            out.mag[r] = [a, al * a, al * al * a];
        }
    }
}

/// Eigenvalues (one per complex pair, Im > 0, then real ones in Schur order), weights and
/// unit eigenvectors (columns) of the real matrix `b`.
#[allow(clippy::type_complexity)]
fn eigenvectors(
    b: &DMatrix<f64>,
) -> Result<(Vec<Complex<f64>>, Vec<f64>, DMatrix<Complex<f64>>), ModalError> {
    let dim = b.nrows();
    let schur = Schur::try_new(b.clone(), f64::EPSILON, 10_000).ok_or(ModalError::NoConvergence)?;
    let all = schur.complex_eigenvalues();
    let scale = b.amax().max(1e-300);
    let mut lambda = Vec::new();
    let mut weight = Vec::new();
    for l in all.iter() {
        if l.im > 0.0 {
            lambda.push(*l);
            weight.push(2.0);
        } else if l.im == 0.0 {
            lambda.push(*l);
            weight.push(1.0);
        }
    }
    let bc = b.map(|x| Complex::new(x, 0.0));
    let mut vecs = DMatrix::<Complex<f64>>::zeros(dim, lambda.len());
    let cluster = 1e-6 * scale;
    for r in 0..lambda.len() {
        let l = lambda[r];
        // Earlier eigenvectors of (nearly) the same eigenvalue: the new one is kept apart from
        // them.
        let same: Vec<usize> = (0..r)
            .filter(|&q| (lambda[q] - l).norm() < cluster)
            .collect();
        let shift = l + Complex::new(1e-10 * scale, 0.0);
        let mut a = bc.clone();
        for i in 0..dim {
            a[(i, i)] -= shift;
        }
        let lu = a.lu();
        let mut x = DVector::from_fn(dim, |i, _| {
            Complex::new(1.0 + (i as f64 + 1.0) * 0.618_033_988_749_895 % 1.0, 0.0)
        });
        for _ in 0..3 {
            for &q in &same {
                let col = vecs.column(q).clone_owned();
                let d = col.dotc(&x);
                x -= col * d;
            }
            x = lu.solve(&x).ok_or(ModalError::Defective {
                condition: f64::INFINITY,
            })?;
            let norm = x.norm();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(ModalError::Defective {
                    condition: f64::INFINITY,
                });
            }
            x /= Complex::new(norm, 0.0);
        }
        if weight[r] == 1.0 {
            // A real eigenvalue's eigenvector, made real: rotate by the phase of its largest entry.
            let (imax, _) = x.iter().enumerate().fold((0, 0.0), |best, (i, c)| {
                if c.norm() > best.1 {
                    (i, c.norm())
                } else {
                    best
                }
            });
            let phase = x[imax] / Complex::new(x[imax].norm(), 0.0);
            x = x.map(|c| Complex::new((c / phase).re, 0.0));
            let norm = x.norm();
            x /= Complex::new(norm, 0.0);
        }
        vecs.set_column(r, &x);
    }
    Ok((lambda, weight, vecs))
}

/// One piece's modal coefficients (reused buffers).
#[derive(Debug, Clone, Default)]
pub struct Piece {
    pub y0: Vec<Cx>,
    pub b0: Vec<Cx>,
    pub b1: Vec<Cx>,
    /// `λ²·y₀ + λ·β₀ + β₁`: `y''(τ) = e^{λτ}·q₂`.
    pub q2: Vec<Cx>,
    /// `|q₂|·|λ|^{k−2}` for `k = 2, 3, 4`.
    pub mag: Vec<[f64; 3]>,
    /// Per mode the largest `e^{Re λ_r·τ}` over an interval `[lo, t1]`: a search asks for the
    /// bounds of several orders over one interval, and every function of a piece (and the next
    /// piece, at the next sample) over the same intervals, each the same exponentials.
    envelopes: Kept<f64>,
    /// Per mode [`value_terms`] at a time `τ`: the searches split their intervals at the same
    /// points.
    terms: Kept<[Cx; 3]>,
}

/// Slots of a [`Kept`].
const KEPT: usize = 4;

/// Bases of at most this many modes compute the numbers of a [`Kept`] afresh at each call, and
/// a piece's coefficients mode by mode ([`StateModes::piece`]): for so few, keeping them and
/// summing column by column cost more than they save (`cargo bench --bench integrator` with
/// both everywhere: 1 and 3 storeys 10 % and 6 % slower, 20 storeys 15 % faster).
const FEW_MODES: usize = 6;

/// A key (the basis' identity and two times' bits) and its numbers, one per mode.
type Slot<T> = (Option<[u64; 3]>, Vec<T>);

/// Per-mode numbers for the last [`KEPT`] keys they were asked for: a key is a basis
/// ([`StateModes::id`]) and the bits of one or two times, on which alone the numbers depend, so
/// a piece keeps them from one piece to the next (from one sample to the next) and gives the
/// bits it would compute. A new key takes the oldest slot.
#[derive(Debug, Clone)]
struct Kept<T> {
    slots: std::cell::RefCell<[Slot<T>; KEPT]>,
    oldest: std::cell::Cell<usize>,
}

impl<T> Default for Kept<T> {
    fn default() -> Self {
        Self {
            slots: std::cell::RefCell::new(std::array::from_fn(|_| (None, Vec::new()))),
            oldest: std::cell::Cell::new(0),
        }
    }
}

impl<T> Kept<T> {
    /// `visit(r, number)` for each mode `r` of `modes` in order, the numbers at times `key`:
    /// kept, or computed by `value` (and kept, where the basis has more than [`FEW_MODES`]).
    fn each(
        &self,
        modes: &StateModes,
        key: (f64, f64),
        value: impl Fn(usize) -> T,
        mut visit: impl FnMut(usize, &T),
    ) {
        if modes.modes() <= FEW_MODES {
            for r in 0..modes.modes() {
                visit(r, &value(r));
            }
            return;
        }
        self.kept(
            modes,
            key,
            |v| v.extend((0..modes.modes()).map(value)),
            visit,
        );
    }

    /// [`Self::each`] in a basis of more than [`FEW_MODES`] modes, the numbers at times `key`
    /// kept, or appended by `fill` in the modes' order (and kept).
    fn kept(
        &self,
        modes: &StateModes,
        key: (f64, f64),
        fill: impl FnOnce(&mut Vec<T>),
        mut visit: impl FnMut(usize, &T),
    ) {
        let key = Some([modes.id, key.0.to_bits(), key.1.to_bits()]);
        let mut slots = self.slots.borrow_mut();
        let at = match slots.iter().position(|(k, _)| *k == key) {
            Some(at) => at,
            None => {
                let at = self.oldest.get();
                self.oldest.set((at + 1) % KEPT);
                let (k, values) = &mut slots[at];
                values.clear();
                fill(values);
                *k = key;
                at
            }
        };
        for (r, v) in slots[at].1.iter().enumerate() {
            visit(r, v);
        }
    }
}

impl Piece {
    /// `y_r(τ)` from the mode terms `[e^{λτ}, τφ₁, τ²φ₂]` at `τ`.
    #[inline]
    fn y(&self, r: usize, e: Cx, p1: Cx, p2: Cx) -> Cx {
        e.mul(self.y0[r])
            .add(p1.mul(self.b0[r]))
            .add(p2.mul(self.b1[r]))
    }

    /// `y_r'(τ)` of mode `r` (eigenvalue `l`) from the mode terms `[e^{λτ}, τφ₁]` at `τ`.
    #[inline]
    fn dy(&self, r: usize, l: Cx, e: Cx, p1: Cx) -> Cx {
        l.mul(e)
            .mul(self.y0[r])
            .add(e.mul(self.b0[r]))
            .add(p1.mul(self.b1[r]))
    }

    /// `from`'s coefficients, in this piece's buffers (its kept numbers depend on the basis and
    /// times alone, so they stay).
    pub fn copy_coefficients(&mut self, from: &Piece) {
        self.y0.clone_from(&from.y0);
        self.b0.clone_from(&from.b0);
        self.b1.clone_from(&from.b1);
        self.q2.clone_from(&from.q2);
        self.mag.clone_from(&from.mag);
    }

    fn resize(&mut self, m: usize) {
        for v in [&mut self.y0, &mut self.b0, &mut self.b1, &mut self.q2] {
            v.resize(m, Cx(0.0, 0.0));
        }
        self.mag.resize(m, [0.0; 3]);
    }
}

/// The modal state at one instant of a piece: `y(τ)`, `y'(τ)`, and `∫₀^τ y` per kept mode
/// where `integrals` asks for it (the energy balance alone reads it).
#[derive(Debug, Clone, Default)]
pub struct ModalPoint {
    pub tau: f64,
    pub y: Vec<Cx>,
    pub dy: Vec<Cx>,
    pub iy: Vec<Cx>,
    pub integrals: bool,
}

impl ModalPoint {
    /// The point at `tau` (the modes' terms [`TERM_LANES`] at a time, each mode's bits).
    pub fn at(&mut self, modes: &StateModes, piece: &Piece, tau: f64) {
        self.resize(modes.modes(), tau);
        each_in_lanes(&modes.lambda, tau, mode_terms_in_lanes, |r, terms| {
            self.set(modes, piece, r, terms)
        });
    }

    /// The point at `tau` with the mode terms given (cached for a whole sample interval).
    pub fn at_terms(&mut self, modes: &StateModes, piece: &Piece, tau: f64, terms: &[[Cx; 4]]) {
        self.fill(modes, piece, tau, |r| terms[r]);
    }

    /// The piece's start: `y(0) = y₀`, `y'(0) = λ·y₀ + β₀`, no exponential needed.
    pub fn start(&mut self, modes: &StateModes, piece: &Piece) {
        let zero = Cx(0.0, 0.0);
        self.fill(modes, piece, 0.0, |_| [Cx(1.0, 0.0), zero, zero, zero]);
    }

    fn fill(
        &mut self,
        modes: &StateModes,
        piece: &Piece,
        tau: f64,
        terms: impl Fn(usize) -> [Cx; 4],
    ) {
        self.resize(modes.modes(), tau);
        for r in 0..modes.modes() {
            self.set(modes, piece, r, terms(r));
        }
    }

    /// `from`'s time, values and slopes (not its integrals), in this point's buffers.
    pub fn copy_values(&mut self, from: &ModalPoint) {
        self.tau = from.tau;
        self.y.clone_from(&from.y);
        self.dy.clone_from(&from.dy);
    }

    fn resize(&mut self, m: usize, tau: f64) {
        self.tau = tau;
        self.y.resize(m, Cx(0.0, 0.0));
        self.dy.resize(m, Cx(0.0, 0.0));
        self.iy.resize(m, Cx(0.0, 0.0));
    }

    /// Mode `r` of the point from its terms `[e^{λτ}, τφ₁, τ²φ₂, τ³φ₃]`.
    #[inline]
    fn set(&mut self, modes: &StateModes, piece: &Piece, r: usize, [e, p1, p2, p3]: [Cx; 4]) {
        self.y[r] = piece.y(r, e, p1, p2);
        self.dy[r] = piece.dy(r, modes.lambda[r], e, p1);
        if self.integrals {
            self.iy[r] = p1
                .mul(piece.y0[r])
                .add(p2.mul(piece.b0[r]))
                .add(p3.mul(piece.b1[r]));
        }
    }

    /// `Σ_r w_r·Re(c_r·x_r)` of a row `c` over one of this point's vectors.
    pub fn dot(modes: &StateModes, c: &[Cx], x: &[Cx]) -> f64 {
        c.iter()
            .zip(x)
            .zip(&modes.weight)
            .map(|((c, x), w)| w * c.mul(*x).0)
            .sum()
    }
}

/// Rows from which [`RowsByMode`]'s passes take their AVX2 copy: below it the call costs more
/// than the wider operations save (`cargo bench --bench integrator`, one storey).
const WIDE_ROWS: usize = 16;

/// A table of rows stored mode by mode: row `i`'s coefficient of mode `r` at `r·stride + i`,
/// real and imaginary parts apart, and `w_r·|c|` of each.
#[derive(Debug, Clone, Default)]
pub struct RowsByMode {
    /// Rows per mode.
    stride: usize,
    re: Vec<f64>,
    im: Vec<f64>,
    abs: Vec<f64>,
}

impl RowsByMode {
    /// The table of `rows` (`rows.len() / m` rows of `m` coefficients each, row-major) and
    /// their weighted magnitudes `rows_abs` (the same layout).
    pub fn new(rows: &[Cx], rows_abs: &[f64], m: usize) -> Self {
        let stride = rows.len() / m.max(1);
        let mut re = vec![0.0; rows.len()];
        let mut im = re.clone();
        let mut abs = re.clone();
        for i in 0..stride {
            for r in 0..m {
                re[r * stride + i] = rows[i * m + r].0;
                im[r * stride + i] = rows[i * m + r].1;
                abs[r * stride + i] = rows_abs[i * m + r];
            }
        }
        Self {
            stride,
            re,
            im,
            abs,
        }
    }

    /// `out[i] = Σ_r w_r·Re(c_{r,first+i}·x_r)` for the rows `first …` (as many as `out`
    /// holds), in one pass over the modes: [`ModalPoint::dot`] of each row, the same terms
    /// added in the same order (from the same start as `f64`'s `Sum`), so the same bits.
    ///
    /// Compiled twice, as [`Self::curvatures`]: for AVX2 (chosen at run time where the
    /// processor has it: four rows per operation instead of two) and for the baseline. Neither
    /// contracts a multiply and an add, so both give the same bits.
    pub fn dots(&self, weight: &[f64], x: &[Cx], first: usize, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        {
            if out.len() >= WIDE_ROWS && std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2 (checked just above).
                return unsafe { self.dots_avx2(weight, x, first, out) };
            }
        }
        self.dots_generic(weight, x, first, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn dots_avx2(&self, weight: &[f64], x: &[Cx], first: usize, out: &mut [f64]) {
        self.dots_generic(weight, x, first, out)
    }

    #[inline(always)]
    fn dots_generic(&self, weight: &[f64], x: &[Cx], first: usize, out: &mut [f64]) {
        let rows = out.len();
        out.fill(std::iter::empty::<f64>().sum());
        for (r, (&w, xr)) in weight.iter().zip(x).enumerate() {
            let at = r * self.stride + first;
            let (cr, ci) = (&self.re[at..at + rows], &self.im[at..at + rows]);
            for ((o, &a), &b) in out.iter_mut().zip(cr).zip(ci) {
                *o += w * (a * xr.0 - b * xr.1);
            }
        }
    }

    /// `out[i] = Σ_r w_r·|c_{r,i}|·mag_r[0]` for the first rows (as many as `out` holds): each
    /// row's modal curvature bound over a piece (what [`ModalFn`]'s bound of `k = 2` sums from
    /// a decaying start), the terms in mode order.
    ///
    /// Compiled twice: for AVX2 (chosen at run time where the processor has it) and for the
    /// baseline, the same bits.
    pub fn curvatures(&self, mag: &[[f64; 3]], out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        {
            if out.len() >= WIDE_ROWS && std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2 (checked just above).
                return unsafe { self.curvatures_avx2(mag, out) };
            }
        }
        self.curvatures_generic(mag, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn curvatures_avx2(&self, mag: &[[f64; 3]], out: &mut [f64]) {
        self.curvatures_generic(mag, out)
    }

    #[inline(always)]
    fn curvatures_generic(&self, mag: &[[f64; 3]], out: &mut [f64]) {
        out.fill(std::iter::empty::<f64>().sum());
        for (r, m) in mag.iter().enumerate() {
            let a = &self.abs[r * self.stride..r * self.stride + out.len()];
            for (o, &a) in out.iter_mut().zip(a) {
                *o += a * m[0];
            }
        }
    }
}

/// `[e^{λτ}, τφ₁(λτ), τ²φ₂(λτ), τ³φ₃(λτ)]`.
#[inline]
pub fn mode_terms(lambda: Cx, tau: f64) -> [Cx; 4] {
    let x = lambda.scale(tau);
    let [e, p1, p2, p3] = if x.norm_sqr() < 1.0 {
        // φ₃ by its Taylor series (Horner, 17 terms: the next is below 1e-17 for |x| < 1), the
        // others by φ_{k−1}(x) = 1/(k−1)! + x·φ_k(x): no cancellation for |x| < 1.
        let p3 = horner(x, &INV_FACTORIAL[3..20]);
        let p2 = Cx(0.5, 0.0).add(x.mul(p3));
        let p1 = Cx(1.0, 0.0).add(x.mul(p2));
        [Cx(1.0, 0.0).add(x.mul(p1)), p1, p2, p3]
    } else {
        // Each φ_{k−1} − 1/(k−1)! is at least of the size of x/k!: a few ulps lost at most.
        let e = x.exp();
        let p1 = Cx(e.0 - 1.0, e.1).div(x);
        let p2 = p1.sub(Cx(1.0, 0.0)).div(x);
        let p3 = p2.sub(Cx(0.5, 0.0)).div(x);
        [e, p1, p2, p3]
    };
    let t2 = tau * tau;
    [e, p1.scale(tau), p2.scale(t2), p3.scale(t2 * tau)]
}

/// `[e^{λτ}, τφ₁(λτ), τ²φ₂(λτ)]`, what a value and a slope need: the closed forms from
/// `|λτ| = 1/2` on (each `φ_{k−1} − 1/(k−1)!` is at least `|x|/k!`, a few ulps lost), below it
/// the Taylor series of `φ₂` (13 terms: the next is below 1e-16 of it for `|x| < 1/2`) and the
/// recurrence. Agrees with [`mode_terms`] to a few ulps (tested).
#[inline]
pub fn value_terms(lambda: Cx, tau: f64) -> [Cx; 3] {
    let [e, p1, p2] = phi_terms::<true>(lambda.scale(tau));
    [e, p1.scale(tau), p2.scale(tau * tau)]
}

/// Modes whose terms ([`value_terms`], [`mode_terms`]) are computed side by side.
const TERM_LANES: usize = 4;

/// [`horner`] in each lane, the lanes' steps interleaved: each lane's bits, its chain of
/// dependent multiply–adds overlapping the others' instead of following them.
#[inline(always)]
fn horner_in_lanes(x: &[Cx; TERM_LANES], c: &[f64]) -> [Cx; TERM_LANES] {
    let (mut re, mut im) = ([0.0; TERM_LANES], [0.0; TERM_LANES]);
    for &ck in c.iter().rev() {
        for l in 0..TERM_LANES {
            let (r, i) = (
                re[l] * x[l].0 - im[l] * x[l].1,
                re[l] * x[l].1 + im[l] * x[l].0,
            );
            re[l] = r + ck;
            im[l] = i + 0.0;
        }
    }
    std::array::from_fn(|l| Cx(re[l], im[l]))
}

/// Terms of up to [`TERM_LANES`] modes at one `τ` (`lambda.len()` of them): `series` of the
/// lanes' `λτ` where every `|λτ|²` is below `limit` (every mode takes the Taylor series; the
/// lanes past `lambda.len()` repeat its first mode and are not to be read), else `one` of each
/// mode, as for a mode alone.
#[inline(always)]
fn terms_in_lanes<T: Copy>(
    lambda: &[Cx],
    tau: f64,
    limit: f64,
    one: impl Fn(Cx, f64) -> T,
    series: impl FnOnce(&[Cx; TERM_LANES]) -> [T; TERM_LANES],
) -> [T; TERM_LANES] {
    if lambda.len() == 1 {
        return [one(lambda[0], tau); TERM_LANES];
    }
    let mode = |l: usize| *lambda.get(l).unwrap_or(&lambda[0]);
    let x: [Cx; TERM_LANES] = std::array::from_fn(|l| mode(l).scale(tau));
    if !x.iter().all(|x| x.norm_sqr() < limit) {
        return std::array::from_fn(|l| one(mode(l), tau));
    }
    series(&x)
}

/// [`value_terms`] of up to [`TERM_LANES`] modes at one `τ`: each mode's bits, the same
/// operations in the same order, their Taylor series side by side where every mode takes it
/// ([`horner_in_lanes`]; a refinement's evaluation waits on them).
#[inline(always)]
fn value_terms_in_lanes(lambda: &[Cx], tau: f64) -> [[Cx; 3]; TERM_LANES] {
    terms_in_lanes(lambda, tau, 0.25, value_terms, |x| {
        let p2 = horner_in_lanes(x, &INV_FACTORIAL[2..15]);
        let t2 = tau * tau;
        std::array::from_fn(|l| {
            let p1 = Cx(1.0, 0.0).add(x[l].mul(p2[l]));
            let e = Cx(1.0, 0.0).add(x[l].mul(p1));
            [e, p1.scale(tau), p2[l].scale(t2)]
        })
    })
}

/// [`mode_terms`] of up to [`TERM_LANES`] modes at one `τ`, as [`value_terms_in_lanes`].
#[inline(always)]
fn mode_terms_in_lanes(lambda: &[Cx], tau: f64) -> [[Cx; 4]; TERM_LANES] {
    terms_in_lanes(lambda, tau, 1.0, mode_terms, |x| {
        let p3 = horner_in_lanes(x, &INV_FACTORIAL[3..20]);
        let (t2, t3) = (tau * tau, tau * tau * tau);
        std::array::from_fn(|l| {
            let p2 = Cx(0.5, 0.0).add(x[l].mul(p3[l]));
            let p1 = Cx(1.0, 0.0).add(x[l].mul(p2));
            let e = Cx(1.0, 0.0).add(x[l].mul(p1));
            [e, p1.scale(tau), p2.scale(t2), p3[l].scale(t3)]
        })
    })
}

/// `visit(r, terms)` for every mode `r` of `lambda` in order, the terms computed by `lanes`
/// ([`value_terms_in_lanes`], [`mode_terms_in_lanes`]) [`TERM_LANES`] modes at a time.
#[inline(always)]
fn each_in_lanes<T>(
    lambda: &[Cx],
    tau: f64,
    lanes: impl Fn(&[Cx], f64) -> [T; TERM_LANES],
    mut visit: impl FnMut(usize, T),
) {
    for (first, modes) in (0..).step_by(TERM_LANES).zip(lambda.chunks(TERM_LANES)) {
        for (r, terms) in (first..first + modes.len()).zip(lanes(modes, tau)) {
            visit(r, terms);
        }
    }
}

/// `visit(r, value_terms(lambda[r], tau))` for every mode `r` in order ([`each_in_lanes`]).
#[inline(always)]
fn each_value_terms(lambda: &[Cx], tau: f64, visit: impl FnMut(usize, [Cx; 3])) {
    each_in_lanes(lambda, tau, value_terms_in_lanes, visit);
}

/// `[e^{λτ}, τφ₁(λτ)]`, what a slope needs: [`value_terms`]' first two, the same bits, without
/// `φ₂`'s division where the closed form does not need it.
#[inline]
pub fn slope_terms(lambda: Cx, tau: f64) -> [Cx; 2] {
    let [e, p1, _] = phi_terms::<false>(lambda.scale(tau));
    [e, p1.scale(tau)]
}

/// `[e^x, φ₁(x), φ₂(x)]` as [`value_terms`] states them; `φ₂` zero where `!P2` and the closed
/// form would spend a division on it.
#[inline(always)]
fn phi_terms<const P2: bool>(x: Cx) -> [Cx; 3] {
    if x.norm_sqr() < 0.25 {
        let p2 = horner(x, &INV_FACTORIAL[2..15]);
        let p1 = Cx(1.0, 0.0).add(x.mul(p2));
        [Cx(1.0, 0.0).add(x.mul(p1)), p1, p2]
    } else {
        let e = x.exp();
        let p1 = Cx(e.0 - 1.0, e.1).div(x);
        let p2 = if P2 {
            p1.sub(Cx(1.0, 0.0)).div(x)
        } else {
            Cx(0.0, 0.0)
        };
        [e, p1, p2]
    }
}

/// `1/k!` for `k = 0 … 19`.
const INV_FACTORIAL: [f64; 20] = {
    let mut out = [1.0; 20];
    let mut k = 1;
    while k < 20 {
        out[k] = out[k - 1] / k as f64;
        k += 1;
    }
    out
};

/// `Σ_k c_k·x^k` by Horner's rule.
#[inline]
fn horner(x: Cx, c: &[f64]) -> Cx {
    c.iter()
        .rev()
        .fold(Cx(0.0, 0.0), |acc, &ck| acc.mul(x).add(Cx(ck, 0.0)))
}

/// `q₀ + q₁τ + q₂τ² + q₃τ³` by Horner's rule (a function's polynomial part).
#[inline]
pub(super) fn cubic(q: &[f64; 4], t: f64) -> f64 {
    q[0] + t * (q[1] + t * (q[2] + t * q[3]))
}

/// The slope of [`cubic`] at `τ`.
#[inline]
pub(super) fn cubic_slope(q: &[f64; 4], t: f64) -> f64 {
    q[1] + t * (2.0 * q[2] + 3.0 * t * q[3])
}

/// A linear function of the floors' state plus a cubic in `τ`:
/// `f(τ) = scale·Σ_r w_r·Re(c_r·y_r(τ)) + poly(τ)`, over one piece.
#[derive(Clone, Copy)]
pub struct ModalFn<'a> {
    pub modes: &'a StateModes,
    pub piece: &'a Piece,
    /// Coefficients per kept mode (empty: the polynomial alone), times `scale`, and their
    /// magnitudes `w_r·|c_r|`.
    pub c: &'a [Cx],
    pub c_abs: &'a [f64],
    pub scale: f64,
    /// `poly(τ) = p[0] + p[1]·τ + p[2]·τ² + p[3]·τ³`.
    pub poly: [f64; 4],
}

impl ModalFn<'_> {
    fn poly_eval(&self, t: f64) -> (f64, f64, f64) {
        let p = &self.poly;
        (cubic(p, t), cubic_slope(p, t), 2.0 * p[2] + 6.0 * t * p[3])
    }
}

impl super::super::search::Smooth for ModalFn<'_> {
    type At = f64;

    fn at(&self, tau: f64) -> f64 {
        tau
    }

    fn tau(at: &f64) -> f64 {
        *at
    }

    fn eval(&self, &t: &f64) -> (f64, f64) {
        let (mut f, mut df, _) = self.poly_eval(t);
        if self.c.is_empty() {
            return (f, df);
        }
        let lambda = &self.modes.lambda;
        let mut add = |r: usize, [e, p1, p2]: [Cx; 3]| {
            let (c, w) = (self.c[r], self.scale * self.modes.weight[r]);
            f += w * c.mul(self.piece.y(r, e, p1, p2)).0;
            df += w * c.mul(self.piece.dy(r, lambda[r], e, p1)).0;
        };
        if self.modes.modes() <= FEW_MODES {
            each_value_terms(lambda, t, add);
        } else {
            let fill = |v: &mut Vec<[Cx; 3]>| each_value_terms(lambda, t, |_, terms| v.push(terms));
            (self.piece.terms).kept(self.modes, (t, 0.0), fill, |r, &t| add(r, t));
        }
        (f, df)
    }

    /// `eval`'s value and slope, the same bits, and the curvature from the same mode terms
    /// (`e^{λτ}·q2`, no second exponential). A Newton step's time is asked once: its terms are
    /// not kept (`Kept` holds the searches' points).
    fn eval_second(&self, &t: &f64) -> (f64, f64, f64) {
        let (mut f, mut df, mut d2) = self.poly_eval(t);
        let lambda = &self.modes.lambda[..self.c.len()];
        each_value_terms(lambda, t, |r, [e, p1, p2]| {
            let (c, w) = (self.c[r], self.scale * self.modes.weight[r]);
            f += w * c.mul(self.piece.y(r, e, p1, p2)).0;
            df += w * c.mul(self.piece.dy(r, lambda[r], e, p1)).0;
            d2 += w * c.mul(e.mul(self.piece.q2[r])).0;
        });
        (f, df, d2)
    }

    /// `eval`'s value alone, the same bits (a root's refinement needs no slope).
    fn value(&self, &t: &f64) -> f64 {
        let (mut f, _, _) = self.poly_eval(t);
        each_value_terms(&self.modes.lambda[..self.c.len()], t, |r, [e, p1, p2]| {
            let w = self.scale * self.modes.weight[r];
            f += w * self.c[r].mul(self.piece.y(r, e, p1, p2)).0;
        });
        f
    }

    /// `eval`'s slope alone, the same bits (an extremum's refinement, where its Newton steps do
    /// not converge, refines the slope's root, which needs no value).
    fn slope(&self, &t: &f64) -> f64 {
        let (_, mut df, _) = self.poly_eval(t);
        for (r, c) in self.c.iter().enumerate() {
            let l = self.modes.lambda[r];
            let [e, p1] = slope_terms(l, t);
            let w = self.scale * self.modes.weight[r];
            df += w * c.mul(self.piece.dy(r, l, e, p1)).0;
        }
        df
    }

    fn second(&self, &t: &f64) -> f64 {
        let (_, _, mut d2) = self.poly_eval(t);
        for (r, c) in self.c.iter().enumerate() {
            let e = self.modes.lambda[r].scale(t).exp();
            d2 += self.scale * self.modes.weight[r] * c.mul(e.mul(self.piece.q2[r])).0;
        }
        d2
    }

    fn bound(&self, k: usize, &lo: &f64, t1: f64) -> f64 {
        let p = &self.poly;
        let t = lo.abs().max(t1.abs());
        let poly = match k {
            2 => 2.0 * p[2].abs() + 6.0 * t * p[3].abs(),
            3 => 6.0 * p[3].abs(),
            _ => 0.0,
        };
        // The modal terms times each mode's envelope over the interval (none for the
        // polynomial alone).
        let lambda = &self.modes.lambda;
        let envelope = |r: usize| {
            let re = lambda[r].0;
            if lo == 0.0 && re <= 0.0 {
                1.0
            } else {
                (re * lo).max(re * t1).exp()
            }
        };
        let mut modal = 0.0;
        if !self.c_abs.is_empty() {
            (self.piece.envelopes).each(self.modes, (lo, t1), envelope, |r, e| {
                modal += self.c_abs[r] * self.piece.mag[r][k - 2] * e;
            });
        }
        // A few ulps of slack for the rounding of the terms above.
        (poly + self.scale.abs() * modal) * (1.0 + 1e-12)
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    /// The mode terms against the φ-functions of `numeric` (series and closed forms, an
    /// independent evaluation) on both sides of the switch at `|λτ| = 1`: within 4 ulps of the
    /// largest term.
    #[test]
    fn mode_terms_match_the_phi_functions() {
        // Both sides of each switch: |x| = 1/2 (value terms) and 1 (mode terms).
        use crate::numeric::{phi1, phi2, phi3};
        for (re, im) in [
            (-0.3, 0.9),
            (-0.01, 0.2),
            (-1e-9, 0.0),
            (0.0, 0.0),
            (-0.999, 0.04),
            (-1.001, 0.0),
            (-0.05, 1.2),
            (-0.49, 0.05),
            (-0.3, -0.41),
            (-3.0, 25.0),
            (-40.0, 0.0),
        ] {
            let x = Cx(re, im);
            let [e, p1, p2, p3] = mode_terms(x, 1.0);
            let want = [x.exp(), phi1(x), phi2(x), phi3(x)];
            for (got, want) in [e, p1, p2, p3].iter().zip(want) {
                let err = got.sub(want).abs();
                assert!(
                    err <= 4.0 * f64::EPSILON * want.abs().max(1e-300),
                    "{x:?}: {got:?} vs {want:?}"
                );
            }
            let [e, p1, p2] = value_terms(x, 1.0);
            for (got, want) in [e, p1, p2].iter().zip(&want[..3]) {
                let err = got.sub(*want).abs();
                assert!(
                    err <= 8.0 * f64::EPSILON * want.abs().max(1e-300),
                    "{x:?}: value terms {got:?} vs {want:?}"
                );
            }
        }
    }

    /// The modes' terms side by side (`value_terms_in_lanes`, `mode_terms_in_lanes`) are each
    /// mode's own, bit for bit: every mode on the series (the lanes' interleaved Horner
    /// steps), one mode past it (every lane by its own terms), fewer modes than lanes, more
    /// than one group of lanes, signed zeros; and `each_value_terms` visits every mode once, in
    /// order, with those bits.
    #[test]
    fn value_terms_in_lanes_are_each_modes_own_bits() {
        let bits = |t: &[Cx; 3]| t.map(|c| (c.0.to_bits(), c.1.to_bits()));
        let sets: [&[Cx]; 7] = [
            &[Cx(-0.3, 40.0), Cx(-3.0, 150.0), Cx(-1.0, 15.0)],
            &[
                Cx(-0.3, 40.0),
                Cx(-1.0, 15.0),
                Cx(-0.01, 2.0),
                Cx(-5.0, 0.0),
            ],
            &[
                Cx(-0.3, 40.0),
                Cx(-1.0, 15.0),
                Cx(-9.0, 70.0),
                Cx(-5.0, 0.0),
            ],
            &[Cx(-0.3, 40.0), Cx(-1.0, -15.0)],
            &[Cx(0.0, -0.0), Cx(-0.0, 3.0), Cx(-2.0, 0.0)],
            &[Cx(-49.0, 0.0)],
            &[
                Cx(-0.2, 5.0),
                Cx(-0.4, 9.0),
                Cx(-0.6, 13.0),
                Cx(-0.8, 17.0),
                Cx(-1.0, 21.0),
            ],
        ];
        for lambda in sets {
            for tau in [0.0, 1e-9, 3.7e-3, 0.01, -0.004] {
                for (first, lanes) in (0..).step_by(TERM_LANES).zip(lambda.chunks(TERM_LANES)) {
                    let got = value_terms_in_lanes(lanes, tau);
                    let got4 = mode_terms_in_lanes(lanes, tau);
                    for (l, &x) in lanes.iter().enumerate() {
                        let r = first + l;
                        let want = value_terms(x, tau);
                        assert_eq!(
                            bits(&got[l]),
                            bits(&want),
                            "mode {r} of {lambda:?} at {tau}"
                        );
                        let (got4, want4) = (got4[l], mode_terms(x, tau));
                        assert_eq!(
                            got4.map(|c| (c.0.to_bits(), c.1.to_bits())),
                            want4.map(|c| (c.0.to_bits(), c.1.to_bits())),
                            "mode terms of mode {r} of {lambda:?} at {tau}"
                        );
                    }
                }
                let mut seen = Vec::new();
                each_value_terms(lambda, tau, |r, t| seen.push((r, bits(&t))));
                let want: Vec<_> = (lambda.iter().enumerate())
                    .map(|(r, &x)| (r, bits(&value_terms(x, tau))))
                    .collect();
                assert_eq!(seen, want, "{lambda:?} at {tau}");
            }
        }
    }

    use super::super::model::{Building, BuildingSpec, StackSpec, stiffness_matrix};
    use super::*;

    /// The state matrix `A` of `(M, K_t, C)` in physical coordinates.
    fn state_matrix(m: &[f64], k: &[f64], c: &[f64]) -> DMatrix<f64> {
        let n = m.len();
        let kk = stiffness_matrix(k);
        DMatrix::from_fn(2 * n, 2 * n, |r, col| match (r < n, col < n) {
            (true, true) => 0.0,
            (true, false) => f64::from(u8::from(col - n == r)),
            (false, true) => -kk[(r - n, col)] / m[r - n],
            (false, false) => -c[(r - n) * n + col - n] / m[r - n],
        })
    }

    fn building() -> Building {
        let mut s = BuildingSpec::uniform(3, 0.6);
        s.storey_stiffnesses = vec![3.0, 2.0, 1.0];
        s.stacks = vec![StackSpec::new(2, &[2.0], &[0.2])];
        Building::new(&s).unwrap()
    }

    /// `A·V = V·Λ` and `V⁻¹·V = I` in physical coordinates, for a non-classical state (the
    /// stack slides, so `C` is not proportional in the current modes) and one with a storey
    /// without stiffness.
    #[test]
    fn the_eigenvectors_diagonalise_the_state_matrix() {
        let b = building();
        let bare = &b.masses()[..3];
        for k_t in [
            b.stiffness().to_vec(),
            vec![0.0, b.stiffness()[1], 0.05 * b.stiffness()[2]],
        ] {
            let sm = StateModes::new(bare, &k_t, b.damping()).unwrap();
            let a = state_matrix(bare, &k_t, b.damping());
            let dim = 6;
            let scale = a.amax();
            for r in 0..sm.modes() {
                let l = sm.lambda[r];
                for i in 0..dim {
                    let av = (0..dim).fold(Cx(0.0, 0.0), |s, j| {
                        s.add(sm.v[j * sm.modes() + r].scale(a[(i, j)]))
                    });
                    let lv = l.mul(sm.v[i * sm.modes() + r]);
                    assert!(av.sub(lv).abs() < 1e-11 * scale, "mode {r} row {i}");
                }
            }
            // y = V⁻¹z then z = Σ w·Re(V·y): the identity on a test state.
            let z = [0.01, -0.02, 0.03, 0.4, 0.1, -0.3];
            let mut piece = Piece::default();
            sm.piece(&z, &[0.0; 3], 0.0, &mut piece);
            for i in 0..dim {
                let back = ModalPoint::dot(&sm, sm.row(i), &piece.y0);
                assert!((back - z[i]).abs() < 1e-13, "{i}: {back} vs {}", z[i]);
            }
        }
    }

    /// A mode at critical damping makes the state matrix defective (a double eigenvalue with one
    /// eigenvector): refused with the reason, not run. Overdamped and nearly critical modes are
    /// represented (real eigenvalues) and reproduce the state.
    #[test]
    fn a_critically_damped_mode_is_refused_and_overdamped_ones_run() {
        use super::super::model::modal_damping;
        let m = [1.0, 1.0];
        let k = [800.0, 400.0];
        let c = modal_damping(&m, &k, 1.0);
        let e = StateModes::new(&m, &k, &c).unwrap_err();
        assert!(
            matches!(e, ModalError::Defective { .. }) && e.to_string().contains("critical"),
            "{e}"
        );
        for zeta in [0.999, 1.001, 1.5] {
            let c = modal_damping(&m, &k, zeta);
            let sm = StateModes::new(&m, &k, &c).unwrap();
            let z = [0.01, -0.02, 0.3, 0.1];
            let mut piece = Piece::default();
            sm.piece(&z, &[0.0; 2], 0.0, &mut piece);
            for i in 0..4 {
                let back = ModalPoint::dot(&sm, sm.row(i), &piece.y0);
                assert!(
                    (back - z[i]).abs() < 1e-12,
                    "ζ {zeta}, {i}: {back} vs {}",
                    z[i]
                );
            }
        }
    }

    /// A building's piece and functions of it for the tests below: the stack sliding (a
    /// non-classical state), a ramp in the load, an eigenvalue scale that puts `|λτ|` on both
    /// sides of the series' switch within a sample interval.
    fn a_piece() -> (StateModes, Piece) {
        let b = building();
        let sm = StateModes::new(&[1.0, 3.0, 1.0], b.stiffness(), b.damping()).unwrap();
        let mut piece = Piece::default();
        sm.piece(
            &[0.01, -0.02, 0.03, 0.4, 0.1, -0.3],
            &[-1.0, 2.0, 0.5],
            -3.0,
            &mut piece,
        );
        (sm, piece)
    }

    /// The value and the slope alone are `eval`'s, bit for bit: the searches refine roots with
    /// the value (and an extremum, where Newton's steps fail, with the slope), and the stored
    /// switch times must not move.
    #[test]
    fn value_and_slope_alone_have_the_bits_of_eval() {
        use super::super::super::search::Smooth;
        let (sm, piece) = a_piece();
        let fastest = sm.fastest();
        for i in 0..6 {
            let c: Vec<Cx> = sm.row(i).to_vec();
            let c_abs: Vec<f64> = c.iter().zip(&sm.weight).map(|(c, w)| w * c.abs()).collect();
            let f = ModalFn {
                modes: &sm,
                piece: &piece,
                c: &c,
                c_abs: &c_abs,
                scale: -1.5,
                poly: [0.3, -0.2, 0.1, 0.05],
            };
            // |λ|τ from 0 through 0.5 (the switch of the value terms) to 3.
            for k in 0..=60 {
                let t = k as f64 * 0.05 / fastest;
                let (v, d) = f.eval(&t);
                assert_eq!(f.value(&t).to_bits(), v.to_bits(), "row {i}, τ {t}");
                assert_eq!(f.slope(&t).to_bits(), d.to_bits(), "row {i}, τ {t}");
            }
        }
    }

    /// A piece's values, slopes and bounds with the numbers it keeps for times and intervals
    /// ([`Kept`]) have the bits of a fresh piece's, whichever rows asked before, after its buffer
    /// served other modes at the same times, and after more times than it keeps.
    #[test]
    fn kept_numbers_follow_the_times_and_the_modes() {
        use super::super::super::search::Smooth;
        // Eight storeys: more modes than a piece computes afresh each time (`FEW_MODES`).
        let b = Building::new(&BuildingSpec::uniform(8, 0.8)).unwrap();
        let masses = |k: f64| -> Vec<f64> { (0..8).map(|j| 1.0 + k * j as f64).collect() };
        let bases = [
            StateModes::new(&masses(0.25), b.stiffness(), b.damping()).unwrap(),
            StateModes::new(&masses(-0.1), b.stiffness(), b.damping()).unwrap(),
        ];
        assert_eq!(bases[0].modes(), bases[1].modes());
        assert!(bases[0].modes() > FEW_MODES);
        let z: Vec<f64> = (0..16).map(|i| 0.01 * (i as f64 - 7.0)).collect();
        let p0: Vec<f64> = (0..8).map(|j| 0.5 - 0.2 * j as f64).collect();
        let h = 0.9 / bases[0].fastest();
        let mut kept = Piece::default();
        // Times and intervals, more than a piece keeps, one after another: every row asks at
        // each (the later rows find the numbers kept), and the next modes start where the last
        // left off (the other way round).
        let asked = [
            (0.5, 0.25),
            (0.8, 0.5),
            (0.3, 0.1),
            (0.6, 0.3),
            (0.9, 0.6),
            (0.2, 0.0),
        ];
        assert!(asked.len() > KEPT);
        for (round, sm) in [&bases[0], &bases[1], &bases[0]].into_iter().enumerate() {
            sm.piece(&z, &p0, -3.0, &mut kept);
            let at = |piece: &Piece, i: usize, (t, lo): (f64, f64)| {
                let c = sm.row(i).to_vec();
                let c_abs: Vec<f64> = c.iter().zip(&sm.weight).map(|(c, w)| w * c.abs()).collect();
                let f = ModalFn {
                    modes: sm,
                    piece,
                    c: &c,
                    c_abs: &c_abs,
                    scale: -1.5,
                    poly: [0.3, -0.2, 0.1, 0.05],
                };
                let (t, lo) = (t * h, lo * h);
                (f.eval(&t), [2, 3, 4].map(|k| f.bound(k, &lo, t)))
            };
            let mut order = asked;
            if round % 2 == 1 {
                order.reverse();
            }
            for point in order {
                for i in 0..16 {
                    // From a piece that has kept nothing yet.
                    let mut fresh = Piece::default();
                    sm.piece(&z, &p0, -3.0, &mut fresh);
                    let want = at(&fresh, i, point);
                    let got = at(&kept, i, point);
                    assert_eq!(
                        format!("{got:?}"),
                        format!("{want:?}"),
                        "row {i} at {point:?}"
                    );
                }
            }
        }
    }

    /// Every row at once mode by mode has the bits of each row's [`ModalPoint::dot`], for a
    /// range of rows starting anywhere, as many as [`WIDE_ROWS`] or more (the AVX2 copy where
    /// the processor has it) and fewer (the baseline); the curvatures those of the sum over the
    /// modes.
    #[test]
    fn rows_by_mode_have_each_rows_bits() {
        let (sm, piece) = a_piece();
        let m = sm.modes();
        let count = WIDE_ROWS + 11;
        // The basis' six rows over and over, each copy scaled apart.
        let rows: Vec<Cx> = (0..count)
            .flat_map(|i| {
                sm.row(i % 6)
                    .iter()
                    .map(move |c| c.scale(1.0 + 0.37 * i as f64))
            })
            .collect();
        let rows_abs: Vec<f64> = (0..rows.len())
            .map(|i| sm.weight[i % m] * rows[i].abs())
            .collect();
        let table = RowsByMode::new(&rows, &rows_abs, m);
        let mut pt = ModalPoint::default();
        pt.at(&sm, &piece, 0.7 / sm.fastest());
        for first in [0, 2, 5, 11, 20] {
            let mut out = vec![f64::NAN; count - first];
            table.dots(&sm.weight, &pt.y, first, &mut out);
            for (k, got) in out.iter().enumerate() {
                let i = first + k;
                let want = ModalPoint::dot(&sm, &rows[i * m..(i + 1) * m], &pt.y);
                assert_eq!(got.to_bits(), want.to_bits(), "row {i} from {first}");
            }
        }
        for len in [6, count] {
            let mut curv = vec![f64::NAN; len];
            table.curvatures(&piece.mag, &mut curv);
            for (i, got) in curv.iter().enumerate() {
                let want: f64 = (0..m).map(|r| rows_abs[i * m + r] * piece.mag[r][0]).sum();
                assert_eq!(got.to_bits(), want.to_bits(), "row {i} of {len}");
            }
        }
    }

    /// The fine-step tests' building: three floors of masses 1, 3 and 1 (its basis and state
    /// matrix), a start state and constant floor loads (m/s²).
    fn three_floors() -> (StateModes, DMatrix<f64>, [f64; 6], [f64; 3]) {
        let b = building();
        let m = [1.0, 3.0, 1.0];
        let sm = StateModes::new(&m, b.stiffness(), b.damping()).unwrap();
        let a = state_matrix(&m, b.stiffness(), b.damping());
        (sm, a, [0.01, -0.02, 0.03, 0.4, 0.1, -0.3], [-1.0, 2.0, 0.5])
    }

    /// `z` (three floors' state) moved over `[0, h]` under `ż = A·z + (0, p(t))` by RK4 at `steps`
    /// steps: the fine-step reference of the tests below (error ~(h/steps)⁴).
    fn rk4(a: &DMatrix<f64>, z: &mut [f64; 6], p: impl Fn(f64) -> [f64; 3], h: f64, steps: usize) {
        let rhs = |t: f64, z: &[f64; 6]| {
            let load = p(t);
            let mut d = [0.0; 6];
            for i in 0..6 {
                d[i] = (0..6).map(|j| a[(i, j)] * z[j]).sum::<f64>();
                if i >= 3 {
                    d[i] += load[i - 3];
                }
            }
            d
        };
        let add = |z: &[f64; 6], k: &[f64; 6], f: f64| {
            let mut o = *z;
            for i in 0..6 {
                o[i] += f * k[i];
            }
            o
        };
        let dt = h / steps as f64;
        for s in 0..steps {
            let t = s as f64 * dt;
            let k1 = rhs(t, z);
            let k2 = rhs(t + 0.5 * dt, &add(z, &k1, 0.5 * dt));
            let k3 = rhs(t + 0.5 * dt, &add(z, &k2, 0.5 * dt));
            let k4 = rhs(t + dt, &add(z, &k3, dt));
            for i in 0..6 {
                z[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
    }

    /// Pieces carried from one sample interval to the next in the modal state (what the
    /// integrator does within a mode: [`StateModes::piece_in_mode`] from the last piece's end,
    /// the constant loads projected once) against an independent integration over forty
    /// intervals of a piecewise-linear ground acceleration: RK4 at a very small step (error
    /// ~h⁴). The tolerance, `1e-11` of the state's size, allows the round-off of forty pieces.
    #[test]
    fn pieces_carried_in_the_modal_state_match_a_fine_step_integration() {
        let (sm, a, z0, p_c) = three_floors();
        let accel: Vec<f64> = (0..=40).map(|k| 3.0 * (0.7 * k as f64).sin()).collect();
        let h = 0.01;
        let mut load = Vec::new();
        sm.modal_loads(&p_c, &mut load);
        let mut y = Vec::new();
        sm.modal_state(&z0, &mut y);
        let (mut piece, mut end) = (Piece::default(), ModalPoint::default());
        for k in 0..40 {
            let slope = (accel[k + 1] - accel[k]) / h;
            sm.piece_in_mode(&y, &load, accel[k], -slope, &mut piece);
            end.at(&sm, &piece, h);
            y.clone_from(&end.y);
        }
        let mut z = z0;
        for k in 0..40 {
            let slope = (accel[k + 1] - accel[k]) / h;
            rk4(
                &a,
                &mut z,
                |t| p_c.map(|p| p - accel[k] - slope * t),
                h,
                2_000,
            );
        }
        let size = z.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for i in 0..6 {
            let carried = ModalPoint::dot(&sm, sm.row(i), &y);
            assert!(
                (carried - z[i]).abs() < 1e-11 * size,
                "{i}: {carried} vs {}",
                z[i]
            );
        }
    }

    /// A piece against an independent integration of `ż = A·z + (0, p₀ + p₁τ)`: RK4 at a very
    /// small step (error ~h⁴, far below the tolerance).
    #[test]
    fn a_piece_matches_a_fine_step_integration() {
        let (sm, a, z0, p0) = three_floors();
        let p1 = -3.0;
        let mut piece = Piece::default();
        sm.piece(&z0, &p0, p1, &mut piece);
        let h = 0.02;
        let mut z = z0;
        rk4(&a, &mut z, |t| p0.map(|p| p + p1 * t), h, 20_000);
        let mut pt = ModalPoint::default();
        pt.at(&sm, &piece, h);
        for i in 0..6 {
            let exact = ModalPoint::dot(&sm, sm.row(i), &pt.y);
            assert!((exact - z[i]).abs() < 1e-12, "{i}: {exact} vs {}", z[i]);
        }
        // The derivative of the displacement rows is the velocity rows.
        for j in 0..3 {
            let du = ModalPoint::dot(&sm, sm.row(j), &pt.dy);
            let v = ModalPoint::dot(&sm, sm.row(3 + j), &pt.y);
            assert!((du - v).abs() < 1e-12);
        }
    }
}
