//! Spectral matching in the time domain by wavelet adjustment (Al Atik & Abrahamson 2010,
//! "An improved method for nonstationary spectral matching", Earthquake Spectra 26(3)).
//!
//! Each iteration finds, for every control period `T_i`, the peak pseudo-acceleration `R_i` of
//! the 5 %-damped oscillator and its time `t_i` (exact, [`crate::spectrum::response`]), and the
//! misfit `δR_i = (Q_i − |R_i|)·sign(R_i)` against the target `Q_i`. It adds
//! `Σ_j b_j·f_j(t)`, where `f_j` is the improved tapered cosine of the paper (its Eq. 10),
//! `f_j(t) = cos(ω'_j·τ)·exp(−(τ/γ_j)²)`, `τ = t − t_j + Δt_j`,
//! `γ_j = 1.178·f_j^−0.93` (f in Hz), `Δt_j = atan(√(1−β²)/β)/ω'_j`, `ω'_j = ω_j√(1−β²)`,
//! which is centred so that oscillator `j` answers it at `t_j` and integrates to velocity and
//! displacement that vanish after it (no drift). The amplitudes solve the linearised system
//! `C·b = δR`, `C_ij` = the response of oscillator `i` at `t_i` to `f_j`, with Tikhonov
//! regularisation `(CᵀC + μ·I)·b = Cᵀ·δR`, `μ = reg·mean(diag CᵀC)`, and a relaxation gain.
//! Passes use an increasing number of log-spaced control periods so that the spectrum between
//! control periods is matched too; the result is accepted only when a dense check grid is within
//! the bounds.
//!
//! Units: accelerations and spectral values in g. Nothing here reads files.

use super::process::{BaselineCorrection, PreparedBaseline, ProcessError};
use crate::limits::{MAX_PERIODS, PERIOD_RANGE_S};
use crate::sdof::{self, free_displacement};
pub use crate::spectrum::log_space;
use crate::spectrum::response::{
    Peak, response_spectrum, response_spectrum_while, validate_record,
};
use crate::spectrum::{SpectrumError, TARGET_DAMPING, TargetError, TargetSpectrum};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use thiserror::Error;

/// Matching settings. Defaults: the acceptance of the study (every period of 200 log-spaced
/// check periods in 0.05–4 s within ±10 % of the target).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MatchSettings {
    /// Damping ratio of the spectra.
    pub damping: f64,
    /// Period range checked for acceptance, s.
    pub check_range_s: (f64, f64),
    /// Number of log-spaced check periods.
    pub check_periods: usize,
    /// Accepted band of spectrum/target on the check grid.
    pub lower: f64,
    pub upper: f64,
    /// The matched period range is the checked one widened by this factor at each end (≥ 1),
    /// at the check grid's log spacing and within the target's periods: the spectrum just
    /// outside the checked range is matched too, so that the edges of the checked range are not
    /// left to the tails of wavelets aimed inside it.
    pub range_margin: f64,
    /// Control periods per pass: the check grid is cut into this many bands and the worst
    /// period of each band is controlled.
    pub passes: Vec<usize>,
    /// Iterations per pass at most.
    pub max_iterations: usize,
    /// When the best motion's worst misfit on the check grid stays above this, the record is
    /// matched again by the fallback strategies (see `match_record`), the best result kept.
    pub retry_misfit: f64,
    /// Whether the fallback strategies may run.
    pub fallback: bool,
    /// Matching stops when every check period is within this relative misfit.
    pub tolerance: f64,
    /// Relaxation gain on each adjustment (0 < gain ≤ 1).
    pub gain: f64,
    /// Tikhonov weight relative to the mean of diag(CᵀC).
    pub regularisation: f64,
    /// Other response peaks of a controlled oscillator that exceed its target by more than half
    /// the tolerance are held down in the same step, at most this many per oscillator (0: only
    /// the largest peak, the classic method). Without them, lowering the largest peak lets the
    /// next one take over and the iteration stalls.
    pub secondary_peaks: usize,
    /// Scale the record first so that its spectrum's geometric mean over the check range equals
    /// the target's.
    pub prescale: bool,
    /// Baseline correction applied to every trial motion (`none`, `poly:N`, `highpass:F[:N]`):
    /// wavelets cut by the ends of a record leave velocity and displacement drift, and correcting
    /// each trial lets the iterations match the corrected motion itself.
    #[serde(with = "as_text")]
    pub baseline: BaselineCorrection,
    /// After the baseline correction, subtract the linear acceleration `α + β·t` that brings the
    /// ground exactly to rest at the end (zero final velocity and displacement).
    pub end_at_rest: bool,
}

/// Serde through the text form of [`BaselineCorrection`].
mod as_text {
    use super::BaselineCorrection;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(b: &BaselineCorrection, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&b.to_string())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<BaselineCorrection, D::Error> {
        String::deserialize(d)?
            .parse()
            .map_err(serde::de::Error::custom)
    }
}

impl Default for MatchSettings {
    fn default() -> Self {
        Self {
            damping: TARGET_DAMPING,
            check_range_s: (0.05, 4.0),
            check_periods: 200,
            lower: 0.9,
            upper: 1.1,
            range_margin: 1.25,
            passes: vec![50, 100, 200],
            max_iterations: 10,
            retry_misfit: 0.09,
            fallback: true,
            tolerance: 0.08,
            gain: 1.0,
            regularisation: 1e-3,
            secondary_peaks: 0,
            prescale: true,
            baseline: BaselineCorrection::Polynomial { order: 3 },
            end_at_rest: true,
        }
    }
}

#[derive(Debug, Error)]
pub enum MatchError {
    #[error("matching setting `{key}` = {value}: {why}")]
    Setting {
        key: &'static str,
        value: String,
        why: &'static str,
    },
    #[error(transparent)]
    Target(#[from] TargetError),
    #[error(transparent)]
    Spectrum(#[from] SpectrumError),
    #[error("baseline correction: {0}")]
    Baseline(#[from] ProcessError),
}

impl MatchSettings {
    pub fn validate(&self) -> Result<(), MatchError> {
        let bad = |key, value: String, why| Err(MatchError::Setting { key, value, why });
        if !(self.damping.is_finite() && (0.0..1.0).contains(&self.damping)) {
            return bad("damping", self.damping.to_string(), "must be in [0, 1)");
        }
        let (lo, hi) = self.check_range_s;
        if !(lo >= PERIOD_RANGE_S.0 && hi <= PERIOD_RANGE_S.1 && hi > lo) {
            return bad(
                "check_range_s",
                format!("[{lo}, {hi}]"),
                "needs 0.001 s ≤ low < high ≤ 10⁴ s",
            );
        }
        if !(2..=MAX_PERIODS).contains(&self.check_periods) {
            return bad(
                "check_periods",
                self.check_periods.to_string(),
                "must be 2 … 100000",
            );
        }
        if self.max_iterations > 10_000 {
            return bad(
                "max_iterations",
                self.max_iterations.to_string(),
                "must be ≤ 10000",
            );
        }
        if self.passes.iter().any(|&n| n > MAX_PERIODS) {
            return bad(
                "passes",
                format!("{:?}", self.passes),
                "a pass controls at most 100000 periods",
            );
        }
        if !(self.lower > 0.0 && self.lower <= 1.0) {
            return bad("lower", self.lower.to_string(), "must be in (0, 1]");
        }
        if !(self.upper >= 1.0 && self.upper.is_finite()) {
            return bad("upper", self.upper.to_string(), "must be ≥ 1");
        }
        if !(self.range_margin >= 1.0 && self.range_margin <= 4.0) {
            return bad(
                "range_margin",
                self.range_margin.to_string(),
                "must be in [1, 4]",
            );
        }
        if self.passes.is_empty() || self.passes.iter().any(|&n| n < 2) {
            return bad(
                "passes",
                format!("{:?}", self.passes),
                "needs at least one pass of ≥ 2 control periods",
            );
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "0".into(), "must be ≥ 1");
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad("tolerance", self.tolerance.to_string(), "must be in (0, 1)");
        }
        if !(self.retry_misfit > 0.0 && self.retry_misfit.is_finite()) {
            return bad("retry_misfit", self.retry_misfit.to_string(), "must be > 0");
        }
        if !(self.gain > 0.0 && self.gain <= 1.0) {
            return bad("gain", self.gain.to_string(), "must be in (0, 1]");
        }
        if !(self.regularisation >= 0.0 && self.regularisation.is_finite()) {
            return bad(
                "regularisation",
                self.regularisation.to_string(),
                "must be ≥ 0",
            );
        }
        Ok(())
    }

    /// The dense check grid, s.
    pub fn check_grid_s(&self) -> Vec<f64> {
        log_space(
            self.check_range_s.0,
            self.check_range_s.1,
            self.check_periods,
        )
    }
}

/// What matching did to one record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MatchReport {
    /// Every check period within `[lower, upper]` of the target.
    pub converged: bool,
    pub iterations: usize,
    /// Strategies tried (1 + fallbacks run).
    pub attempts: usize,
    /// Steps that lowered nothing even at an eighth of the gain, each ending its pass.
    pub stalls: usize,
    /// Largest |spectrum/target − 1| on the check grid.
    pub worst_misfit: f64,
    /// Check period of the largest misfit, s, and spectrum/target there.
    pub worst_period_s: f64,
    pub worst_ratio: f64,
    /// Pre-scale factor applied before the wavelets.
    pub scale: f64,
    /// The motion was matched to this factor times the target (1 unless matched again for a
    /// set scale, see `study::motions`).
    pub target_factor: f64,
    pub pga_before_g: f64,
    pub pga_after_g: f64,
    /// Velocity and displacement at the end of the matched record, m/s and m (drift).
    pub final_velocity_mps: f64,
    pub final_displacement_m: f64,
    /// Arias intensity after / before (before = the unscaled record).
    pub arias_ratio: f64,
}

/// A matched motion and its report.
#[derive(Debug, Clone)]
pub struct Matched {
    pub accel_g: Vec<f64>,
    /// Pseudo-spectral acceleration on the check grid, g.
    pub check_psa_g: Vec<f64>,
    pub report: MatchReport,
}

/// Pseudo-acceleration peaks (g, signed) and their times (s) at `periods`.
fn signed_psa(
    accel_g: &[f64],
    dt_s: f64,
    periods: &[f64],
    damping: f64,
) -> Result<Vec<(f64, f64)>, SpectrumError> {
    let spec = response_spectrum(accel_g, dt_s, periods, damping)?;
    Ok(periods
        .iter()
        .zip(&spec.peaks)
        .map(|(t, p)| ((TAU / t).powi(2) * p.u_m, p.time_s))
        .collect())
}

/// The improved tapered cosine of oscillator `j` (period `period_s`) with its response peak at
/// `peak_s`, sampled at `k·dt` over its support (±4γ about its centre, where it is below e⁻¹⁶);
/// returns the first index and the samples, with a zero sample added at each end so the
/// piecewise-linear motion returns to zero outside.
fn wavelet(period_s: f64, damping: f64, peak_s: f64, dt_s: f64, n: usize) -> (usize, Vec<f64>) {
    let f_hz = 1.0 / period_s;
    let wd = TAU * f_hz * (1.0 - damping * damping).sqrt();
    let gamma = 1.178 * f_hz.powf(-0.93);
    let shift = ((1.0 - damping * damping).sqrt() / damping.max(1e-12)).atan() / wd;
    let centre = peak_s - shift;
    let first = (((centre - 4.0 * gamma) / dt_s).floor().max(1.0) as usize - 1).min(n - 1);
    let last = (((centre + 4.0 * gamma) / dt_s).ceil() as usize + 1).min(n - 1);
    let mut samples = vec![0.0; last + 1 - first];
    // cos(ω'τ) by rotation and the Gaussian by its ratio recurrence
    // (g_{k+1}/g_k = e^{−(2τ_k·dt + dt²)/γ²}, that ratio itself falling by e^{−2dt²/γ²}),
    // restarted exactly every 64 samples so round-off cannot build up (≤ 1e-14 relative).
    let (sd, cd) = (wd * dt_s).sin_cos();
    let q = (-2.0 * (dt_s / gamma).powi(2)).exp();
    let inner = first + 1..last;
    for block in inner.clone().step_by(64) {
        let end = (block + 64).min(last);
        let tau = block as f64 * dt_s - centre;
        let (mut sn, mut cs) = (wd * tau).sin_cos();
        let mut g = (-(tau / gamma).powi(2)).exp();
        let mut r = (-(2.0 * tau * dt_s + dt_s * dt_s) / (gamma * gamma)).exp();
        for x in &mut samples[block - first..end - first] {
            *x = cs * g;
            (cs, sn) = (cs * cd - sn * sd, sn * cd + cs * sd);
            g *= r;
            r *= q;
        }
    }
    (first, samples)
}

/// Response (pseudo-acceleration, same units as the input) of the oscillator with step
/// coefficients `step`, circular frequency `omega`, at time `at_s`, to the input that is
/// `samples` from index `first` and zero elsewhere. The scalar reference of
/// [`system_matrix`].
#[cfg(test)]
fn response_at(
    step: &sdof::Step,
    omega: f64,
    damping: f64,
    dt_s: f64,
    first: usize,
    samples: &[f64],
    at_s: f64,
) -> f64 {
    let start = first as f64 * dt_s;
    if at_s <= start {
        return 0.0;
    }
    let (mut u, mut v) = (0.0, 0.0);
    let mut k = 0;
    while k + 1 < samples.len() && (first + k + 1) as f64 * dt_s <= at_s {
        (u, v) = step.step(u, v, samples[k], samples[k + 1]);
        k += 1;
    }
    let t_k = (first + k) as f64 * dt_s;
    let rest = at_s - t_k;
    if rest > 0.0 {
        let (a0, a1) = if k + 1 < samples.len() {
            let frac = rest / dt_s;
            (
                samples[k],
                samples[k] + (samples[k + 1] - samples[k]) * frac,
            )
        } else {
            (0.0, 0.0)
        };
        (u, _) = sdof::Step::new(omega, damping, rest).step(u, v, a0, a1);
    }
    omega * omega * u
}

/// Where a constraint's time falls on the record: the oscillator, the last sample at or before
/// the time, and the step over the rest of that interval (s).
struct Probe {
    grid: usize,
    k: usize,
    rest_s: f64,
    partial: sdof::Step,
}

impl Probe {
    fn new(grid: &MatchGrid, c: &Constraint, n: usize) -> Self {
        let k = ((c.time_s / grid.dt_s).floor().max(0.0) as usize).min(n - 1);
        let rest_s = (c.time_s - k as f64 * grid.dt_s).max(0.0);
        Self {
            grid: c.grid,
            k,
            rest_s,
            partial: sdof::Step::new(grid.omega[c.grid], grid.zeta, rest_s.max(f64::MIN_POSITIVE)),
        }
    }
}

/// Probes whose weights are computed together: two AVX2 registers per quantity.
const PROBE_LANES: usize = 8;

/// The matrix of the linearised system, row-major, a row per probe and a column per wave: entry
/// `(r, j)` is the pseudo-acceleration of probe `r`'s oscillator at its time in response to
/// wave `j` (first sample and samples, zero elsewhere), for `probes` in time order. Equal to
/// [`response_at`] entry by entry up to round-off.
///
/// The response at a probe is a linear form in the record's samples, `u(t_r) = Σ_s w_s·a_s`:
/// with the step `x_{s+1} = A·x_s + b₀·a_s + b₁·a_{s+1}` from rest, the adjoint state
/// `λ_s = Aᵀ·λ_{s+1}` from `λ_k` = the first row of the partial step from the probe's sample `k`
/// to its time gives `w_s = λ_{s+1}·b₀ + λ_s·b₁` below `k`, and the partial step's own load
/// terms at `k` and `k + 1`. Eight probes' weights run back together once, and every entry is a
/// dot product of a wave with them: the cost of one pass per eight probes plus the waves'
/// lengths, where stepping every oscillator through every wave costs a pass per wave.
fn system_matrix(
    grid: &MatchGrid,
    probes: &[Probe],
    waves: &[(usize, Vec<f64>)],
    n: usize,
    weights: &mut Vec<[f64; PROBE_LANES]>,
) -> Vec<f64> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { system_matrix_avx2(grid, probes, waves, n, weights) };
        }
    }
    system_matrix_generic(grid, probes, waves, n, weights)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn system_matrix_avx2(
    grid: &MatchGrid,
    probes: &[Probe],
    waves: &[(usize, Vec<f64>)],
    n: usize,
    weights: &mut Vec<[f64; PROBE_LANES]>,
) -> Vec<f64> {
    system_matrix_generic(grid, probes, waves, n, weights)
}

#[inline(always)]
fn system_matrix_generic(
    grid: &MatchGrid,
    probes: &[Probe],
    waves: &[(usize, Vec<f64>)],
    n: usize,
    weights: &mut Vec<[f64; PROBE_LANES]>,
) -> Vec<f64> {
    const L: usize = PROBE_LANES;
    let m = waves.len();
    let mut c = vec![0.0; probes.len() * m];
    let Some(lo) = waves.iter().map(|w| w.0).min() else {
        return c;
    };
    for (base, chunk) in probes.chunks(L).enumerate().map(|(i, ch)| (i * L, ch)) {
        let lanes = chunk.len();
        // The last sample of the record that any probe of the chunk depends on.
        let hi = chunk
            .iter()
            .map(|p| (p.k + 1).min(n - 1))
            .max()
            .unwrap_or(0);
        if hi < lo {
            continue;
        }
        let s = |f: fn(&sdof::Step) -> f64| -> [f64; L] {
            std::array::from_fn(|l| chunk.get(l).map_or(0.0, |p| f(&grid.steps[p.grid])))
        };
        let (uu, uv, ug0, ug1) = (s(|s| s.uu), s(|s| s.uv), s(|s| s.ug0), s(|s| s.ug1));
        let (vu, vv, vg0, vg1) = (s(|s| s.vu), s(|s| s.vv), s(|s| s.vg0), s(|s| s.vg1));
        // Each lane's λ at its sample `k` and the partial step's load weights at `k`, `k + 1`.
        let mut start = [(0.0, 0.0, 0.0, 0.0); L];
        for (l, p) in chunk.iter().enumerate() {
            start[l] = if p.rest_s <= 0.0 {
                (1.0, 0.0, 0.0, 0.0)
            } else if p.k + 1 < n {
                let (q, r) = (&p.partial, p.rest_s / grid.dt_s);
                (q.uu, q.uv, q.ug0 + q.ug1 * (1.0 - r), q.ug1 * r)
            } else {
                // Past the last sample: free vibration (the record is zero after its end).
                let omega = grid.omega[p.grid];
                let free = |x| free_displacement(omega, grid.zeta, x, p.rest_s);
                (free((1.0, 0.0)), free((0.0, 1.0)), 0.0, 0.0)
            };
        }
        let mut by_k: [usize; L] = std::array::from_fn(|l| l);
        by_k[..lanes].sort_by_key(|&l| std::cmp::Reverse(chunk[l].k));
        weights.clear();
        weights.resize(hi + 1 - lo, [0.0; L]);
        let (mut lu, mut lv) = ([0.0f64; L], [0.0f64; L]);
        let mut next = 0;
        for (s, w) in (lo..=hi).rev().zip(weights.iter_mut().rev()) {
            let (pu, pv) = (lu, lv);
            for l in 0..L {
                lu[l] = uu[l] * pu[l] + vu[l] * pv[l];
                lv[l] = uv[l] * pu[l] + vv[l] * pv[l];
            }
            while next < lanes && chunk[by_k[next]].k == s {
                let l = by_k[next];
                (lu[l], lv[l]) = (start[l].0, start[l].1);
                next += 1;
            }
            // The state at sample 0 is rest, whatever the load there.
            let b1 = if s > 0 { 1.0 } else { 0.0 };
            for l in 0..L {
                w[l] = pu[l] * ug0[l] + pv[l] * vg0[l] + b1 * (lu[l] * ug1[l] + lv[l] * vg1[l]);
            }
        }
        for (l, p) in chunk.iter().enumerate() {
            if (lo..=hi).contains(&p.k) {
                weights[p.k - lo][l] += start[l].2;
            }
            if (lo..=hi).contains(&(p.k + 1)) {
                weights[p.k + 1 - lo][l] += start[l].3;
            }
        }
        let w2: [f64; L] =
            std::array::from_fn(|l| chunk.get(l).map_or(0.0, |p| grid.omega[p.grid].powi(2)));
        for (j, (first, samples)) in waves.iter().enumerate() {
            let (a, b) = (*first, (first + samples.len() - 1).min(hi));
            if b < a {
                continue;
            }
            let mut acc = [0.0f64; L];
            for (w, x) in weights[a - lo..=b - lo].iter().zip(samples) {
                for l in 0..L {
                    acc[l] += w[l] * x;
                }
            }
            for l in 0..lanes {
                c[(base + l) * m + j] = w2[l] * acc[l];
            }
        }
    }
    c
}

/// Subtracts from `accel` (any units) the linear acceleration `α + β·t` whose removal leaves the
/// final velocity and displacement exactly zero: with `T` the duration, `v_T` and `d_T` the final
/// velocity and displacement (exact for a piecewise-linear record), `α·T + β·T²/2 = v_T` and
/// `α·T²/2 + β·T³/6 = d_T`. A correction of the record's own length barely touches periods up to a
/// few seconds.
pub fn bring_to_rest(accel: &mut [f64], dt_s: f64) {
    let (mut v, mut d) = (0.0, 0.0);
    for w in accel.windows(2) {
        d += v * dt_s + dt_s * dt_s * (2.0 * w[0] + w[1]) / 6.0;
        v += 0.5 * dt_s * (w[0] + w[1]);
    }
    let t = (accel.len() - 1) as f64 * dt_s;
    // [T, T²/2; T²/2, T³/6]·(α, β) = (v, d); determinant −T⁴/12.
    let det = -t.powi(4) / 12.0;
    let alpha = (v * t.powi(3) / 6.0 - d * t * t / 2.0) / det;
    let beta = (t * d - t * t / 2.0 * v) / det;
    for (k, a) in accel.iter_mut().enumerate() {
        *a -= alpha + beta * k as f64 * dt_s;
    }
}

/// Solves `(CᵀC + μI)·b = Cᵀ·d` by Cholesky (`c` row-major `n×n`), `μ = reg·mean(diag CᵀC)`.
fn regularised_solve(c: &[f64], d: &[f64], reg: f64) -> Vec<f64> {
    let n = d.len();
    // CᵀC as a sum of the outer products of C's rows (contiguous inner loops).
    let mut a = vec![0.0; n * n];
    let mut rhs = vec![0.0; n];
    for (row, dk) in c.chunks(n).zip(d) {
        for (i, &ci) in row.iter().enumerate() {
            rhs[i] += ci * dk;
            for (a, &cj) in a[i * n + i..i * n + n].iter_mut().zip(&row[i..]) {
                *a += ci * cj;
            }
        }
    }
    for i in 0..n {
        for j in 0..i {
            a[i * n + j] = a[j * n + i];
        }
    }
    let mean_diag = (0..n).map(|i| a[i * n + i]).sum::<f64>() / n as f64;
    let mu = reg * mean_diag + f64::MIN_POSITIVE;
    for i in 0..n {
        a[i * n + i] += mu;
    }
    crate::numeric::cholesky_solve(&mut a, &mut rhs, n, mu);
    rhs
}

/// Ratio spectrum/target on `periods`.
fn ratios(psa: &[(f64, f64)], target: &[f64]) -> Vec<f64> {
    psa.iter().zip(target).map(|(r, q)| r.0.abs() / q).collect()
}

/// Index and value of the largest `|ratio − 1|`.
fn worst_of(ratio: &[f64]) -> (usize, f64) {
    ratio
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |(wi, w), (i, r)| {
            let m = (r - 1.0).abs();
            if m > w { (i, m) } else { (wi, w) }
        })
}

/// The spectrum of a trial motion on the match grid: signed peaks with times, ratios to the
/// target, the worst misfit on the check grid (a contiguous part of the match grid) and the
/// objective.
#[derive(Clone)]
struct Evaluation {
    psa: Vec<(f64, f64)>,
    ratio: Vec<f64>,
    /// Largest `|ratio − 1|` on the check grid and its index there.
    worst: f64,
    worst_at: usize,
    /// `Σ (ln ratio)²` over the match grid: the smooth objective the line search lowers.
    sum_sq: f64,
}

/// The periods matched and checked, their targets and oscillators.
struct MatchGrid {
    /// Match grid, s: the check grid with as many points of the same log spacing added below
    /// and above as `range_margin` asks (and the target covers).
    periods_s: Vec<f64>,
    /// The check grid is `periods_s[check.0..check.1]`.
    check: (usize, usize),
    target_g: Vec<f64>,
    omega: Vec<f64>,
    steps: Vec<sdof::Step>,
    zeta: f64,
    dt_s: f64,
}

impl MatchGrid {
    fn new(
        settings: &MatchSettings,
        target: &TargetSpectrum,
        dt_s: f64,
    ) -> Result<Self, MatchError> {
        let check = settings.check_grid_s();
        let n = check.len();
        let (lo, hi) = settings.check_range_s;
        let spacing = (hi / lo).ln() / (n - 1) as f64;
        let (from, to) = target.period_range_s();
        let extra = (settings.range_margin.ln() / spacing).round() as usize;
        let below = (1..=extra)
            .map(|k| lo * (-spacing * k as f64).exp())
            .take_while(|&t| t >= from)
            .count();
        let above = (1..=extra)
            .map(|k| hi * (spacing * k as f64).exp())
            .take_while(|&t| t <= to)
            .count();
        let mut periods_s: Vec<f64> = (1..=below)
            .rev()
            .map(|k| lo * (-spacing * k as f64).exp())
            .collect();
        periods_s.extend_from_slice(&check);
        periods_s.extend((1..=above).map(|k| hi * (spacing * k as f64).exp()));
        let zeta = settings.damping;
        let omega: Vec<f64> = periods_s.iter().map(|t| TAU / t).collect();
        Ok(Self {
            target_g: periods_s.iter().map(|&t| target.sa_g(t)).collect(),
            steps: omega
                .iter()
                .map(|&w| sdof::Step::new(w, zeta, dt_s))
                .collect(),
            omega,
            periods_s,
            check: (below, below + n),
            zeta,
            dt_s,
        })
    }

    fn evaluate(&self, accel: &[f64]) -> Result<Evaluation, SpectrumError> {
        Ok(self
            .evaluate_below(accel, None)?
            .expect("an evaluation without a limit is never dropped"))
    }

    /// [`MatchGrid::evaluate`] when its objective is below `limit` (if any), else `None`: the
    /// spectrum is taken eight periods at a time and dropped as soon as the objective's partial sum (of
    /// non-negative terms, in the same order, so never above the whole) reaches `limit`. A
    /// trial that a line search refuses thus costs only the periods up to where it fails.
    fn evaluate_below(
        &self,
        accel: &[f64],
        limit: Option<f64>,
    ) -> Result<Option<Evaluation>, SpectrumError> {
        let mut sum_sq = 0.0;
        let target = &self.target_g;
        let periods = &self.periods_s;
        let to_psa = |i: usize, p: &Peak| (TAU / periods[i]).powi(2) * p.u_m;
        let Some(spec) =
            response_spectrum_while(accel, self.dt_s, periods, self.zeta, |at, group| {
                for (i, p) in (at..).zip(group) {
                    sum_sq += (to_psa(i, p).abs() / target[i]).ln().powi(2);
                }
                limit.is_none_or(|l| sum_sq < l)
            })?
        else {
            return Ok(None);
        };
        let psa: Vec<(f64, f64)> = spec
            .peaks
            .iter()
            .enumerate()
            .map(|(i, p)| (to_psa(i, p), p.time_s))
            .collect();
        let ratio = ratios(&psa, target);
        let (i, worst) = worst_of(&ratio[self.check.0..self.check.1]);
        Ok(Some(Evaluation {
            psa,
            ratio,
            worst,
            worst_at: i,
            sum_sq,
        }))
    }

    /// Secondary response peaks of oscillator `i` in `accel` that the next step must not let
    /// take over: local extrema of the sampled displacement, at least a quarter period from the
    /// main peak at `main_s` and from each other, whose pseudo-acceleration exceeds the target
    /// by more than `above` (relative). At most `count`, the largest first; `(time s, signed
    /// pseudo-acceleration g)`.
    fn secondary_peaks(
        &self,
        accel: &[f64],
        i: usize,
        main_s: f64,
        above: f64,
        count: usize,
    ) -> Vec<(f64, f64)> {
        if count == 0 {
            return Vec::new();
        }
        let step = &self.steps[i];
        let w2 = self.omega[i] * self.omega[i];
        let level = self.target_g[i] * (1.0 + above) / w2;
        let (mut u, mut v) = (0.0, 0.0);
        let mut prev = 0.0f64;
        let mut rising = false;
        let mut found: Vec<(f64, f64)> = Vec::new();
        for (k, w) in accel.windows(2).enumerate() {
            (u, v) = step.step(u, v, w[0], w[1]);
            let grows = u.abs() > prev.abs() && u * prev >= 0.0;
            if rising && !grows && prev.abs() > level {
                found.push((k as f64 * self.dt_s, prev));
            }
            rising = grows;
            prev = u;
        }
        found.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        let apart = 0.25 * self.periods_s[i];
        let mut kept: Vec<(f64, f64)> = Vec::new();
        for (t, u) in found {
            if kept.len() == count {
                break;
            }
            if (t - main_s).abs() > apart && kept.iter().all(|k| (t - k.0).abs() > apart) {
                kept.push((t, w2 * u));
            }
        }
        kept
    }
}

/// One condition of a step: oscillator `grid` (index into the match grid) shall respond with
/// pseudo-acceleration changed by `misfit` (g, signed) at `time_s`.
struct Constraint {
    grid: usize,
    time_s: f64,
    misfit: f64,
}

/// Control periods of a pass with `count` of them: the match grid cut into `count` contiguous
/// bands, and in each band the period with the largest misfit now. Controlling the locally worst
/// period, rather than a fixed one, is what matches the spectrum between control periods.
fn control_indices(ratio: &[f64], count: usize) -> Vec<usize> {
    let n = ratio.len();
    let count = count.min(n);
    (0..count)
        .map(|b| {
            let (lo, hi) = (b * n / count, (b + 1) * n / count);
            (lo..hi)
                .max_by(|&x, &y| (ratio[x] - 1.0).abs().total_cmp(&(ratio[y] - 1.0).abs()))
                .unwrap_or(lo)
        })
        .collect()
}

/// The wavelets of a step (first sample and samples, see [`wavelet`]) and their amplitudes
/// from the regularised linearised system.
struct Step {
    waves: Vec<(usize, Vec<f64>)>,
    amplitudes: Vec<f64>,
}

/// The constraints of a step: for each control period (see [`control_indices`]) its peak, and
/// with `secondary_peaks` the other peaks that must not take over.
fn constraints(
    grid: &MatchGrid,
    accel: &[f64],
    now: &Evaluation,
    count: usize,
    secondary_peaks: usize,
    settings: &MatchSettings,
) -> Vec<Constraint> {
    let mut cons: Vec<Constraint> = Vec::new();
    for i in control_indices(&now.ratio, count) {
        let (r, t) = now.psa[i];
        cons.push(Constraint {
            grid: i,
            time_s: t,
            misfit: (grid.target_g[i] - r.abs()) * r.signum(),
        });
        for (ts, rs) in grid.secondary_peaks(accel, i, t, 0.5 * settings.tolerance, secondary_peaks)
        {
            cons.push(Constraint {
                grid: i,
                time_s: ts,
                misfit: (grid.target_g[i] - rs.abs()) * rs.signum(),
            });
        }
    }
    cons
}

fn build_step(grid: &MatchGrid, n: usize, cons: &[Constraint], settings: &MatchSettings) -> Step {
    let waves: Vec<(usize, Vec<f64>)> = cons
        .iter()
        .map(|c| wavelet(grid.periods_s[c.grid], grid.zeta, c.time_s, grid.dt_s, n))
        .collect();
    let m = cons.len();
    // Probes in time order, so that the eight whose weights run back together end near the
    // same sample.
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| cons[a].time_s.total_cmp(&cons[b].time_s));
    let probes: Vec<Probe> = order
        .iter()
        .map(|&r| Probe::new(grid, &cons[r], n))
        .collect();
    let sorted = system_matrix(grid, &probes, &waves, n, &mut Vec::new());
    let mut c = vec![0.0; m * m];
    for (&r, row) in order.iter().zip(sorted.chunks(m)) {
        c[r * m..(r + 1) * m].copy_from_slice(row);
    }
    let misfit: Vec<f64> = cons.iter().map(|c| c.misfit).collect();
    Step {
        amplitudes: regularised_solve(&c, &misfit, settings.regularisation),
        waves,
    }
}

/// `accel + gain·Σ b_j·f_j`, baseline-corrected (`baseline`, the settings' correction prepared
/// for the record) and brought to rest as the settings ask.
fn trial(
    accel: &[f64],
    step: &Step,
    gain: f64,
    baseline: &PreparedBaseline,
    settings: &MatchSettings,
    dt_s: f64,
) -> Result<Vec<f64>, MatchError> {
    let mut trial = accel.to_vec();
    for ((first, samples), bj) in step.waves.iter().zip(&step.amplitudes) {
        for (a, w) in trial[*first..].iter_mut().zip(samples) {
            *a += gain * bj * w;
        }
    }
    let mut trial = baseline.apply(&trial)?;
    if settings.end_at_rest {
        bring_to_rest(&mut trial, dt_s);
    }
    Ok(trial)
}

/// How one attempt iterates: control periods per pass, iterations per pass, secondary peaks
/// held down per controlled oscillator, and whether the gain adapts between iterations.
#[derive(Debug, Clone, PartialEq)]
struct Strategy {
    passes: Vec<usize>,
    max_iterations: usize,
    secondary_peaks: usize,
    adaptive_gain: bool,
}

impl Strategy {
    /// The attempts, first the one the settings describe, then (with `fallback`) the two that
    /// the FEMA P695 sets showed to fail on other records than it and each other: many short
    /// passes from coarse to every band with secondary peaks held down and a fresh gain every
    /// iteration, and many passes at every band.
    fn ladder(settings: &MatchSettings) -> Vec<Strategy> {
        let mut out = vec![Strategy {
            passes: settings.passes.clone(),
            max_iterations: settings.max_iterations,
            secondary_peaks: settings.secondary_peaks,
            adaptive_gain: true,
        }];
        if settings.fallback {
            let every = settings.check_periods;
            out.push(Strategy {
                passes: vec![10, 25, 50, every / 2, every],
                max_iterations: 10,
                secondary_peaks: settings.secondary_peaks.max(2),
                adaptive_gain: false,
            });
            out.push(Strategy {
                passes: vec![every / 8, every / 4, every / 2, every, every, every],
                max_iterations: 8,
                secondary_peaks: 0,
                adaptive_gain: true,
            });
        }
        out
    }
}

/// The best motion of one attempt and what it cost.
struct Attempt {
    accel: Vec<f64>,
    eval: Evaluation,
    iterations: usize,
    stalls: usize,
}

/// One attempt from the pre-scaled record `start` (its evaluation `start_eval`): passes of damped Newton steps. When the full
/// step does not lower `Σ (ln spectrum/target)²` over the match grid, the gain is halved (at
/// most three times); a step that lowers nothing even then is a stall and ends its pass, the
/// next (denser) pass starting afresh at full gain. The motion kept is the one with the
/// smallest worst misfit on the check grid seen.
fn attempt(
    grid: &MatchGrid,
    baseline: &PreparedBaseline,
    (start, start_eval): (&[f64], &Evaluation),
    settings: &MatchSettings,
    strategy: &Strategy,
) -> Result<Attempt, MatchError> {
    let mut accel = start.to_vec();
    let mut now = start_eval.clone();
    let mut best = (accel.clone(), now.clone());
    let (mut iterations, mut stalls) = (0, 0);
    // With `adaptive_gain`, the gain of the last accepted step, doubled (up to `settings.gain`)
    // after a full one: a record whose steps overshoot keeps the smaller gain instead of paying
    // for the same failed trials every iteration.
    let mut gain_now = settings.gain;
    for &count in &strategy.passes {
        for _ in 0..strategy.max_iterations {
            if now.worst < settings.tolerance {
                break;
            }
            let cons = constraints(
                grid,
                &accel,
                &now,
                count,
                strategy.secondary_peaks,
                settings,
            );
            let step = build_step(grid, accel.len(), &cons, settings);
            iterations += 1;
            let mut gain = gain_now;
            let mut accepted = false;
            for tried in 0..4 {
                let trial = trial(&accel, &step, gain, baseline, settings, grid.dt_s)?;
                if let Some(eval) = grid.evaluate_below(&trial, Some(now.sum_sq))? {
                    if eval.worst < best.1.worst {
                        best = (trial.clone(), eval.clone());
                    }
                    accel = trial;
                    now = eval;
                    accepted = true;
                    if strategy.adaptive_gain {
                        gain_now = if tried == 0 {
                            (2.0 * gain).min(settings.gain)
                        } else {
                            gain
                        };
                    }
                    break;
                }
                gain *= 0.5;
            }
            if !accepted {
                stalls += 1;
                gain_now = settings.gain;
                break;
            }
        }
    }
    Ok(Attempt {
        accel: best.0,
        eval: best.1,
        iterations,
        stalls,
    })
}

/// Matches `accel_g` (step `dt_s`) to `target`. Returns the best motion found (smallest worst
/// misfit on the check grid) whether or not it met the acceptance; `report.converged` says
/// which, and callers must leave out a record that did not.
///
/// The first attempt follows the settings; while the best motion's worst misfit on the check
/// grid exceeds `retry_misfit` (and `fallback` is on), the record is matched again from its
/// pre-scaled start by the next strategy of `Strategy::ladder`, and the best of all attempts
/// is kept.
pub fn match_record(
    accel_g: &[f64],
    dt_s: f64,
    target: &TargetSpectrum,
    settings: &MatchSettings,
) -> Result<Matched, MatchError> {
    match_record_scaled(accel_g, dt_s, target, 1.0, settings)
}

/// [`match_record`] to `target_factor` times `target` (the band, the check and the report all
/// relative to the scaled target).
pub fn match_record_scaled(
    accel_g: &[f64],
    dt_s: f64,
    target: &TargetSpectrum,
    target_factor: f64,
    settings: &MatchSettings,
) -> Result<Matched, MatchError> {
    settings.validate()?;
    validate_record(accel_g, dt_s)?;
    if !(target_factor.is_finite() && target_factor > 0.0) {
        return Err(MatchError::Setting {
            key: "target_factor",
            value: target_factor.to_string(),
            why: "must be finite and > 0",
        });
    }
    let (lo, hi) = settings.check_range_s;
    target.check_covers(lo, hi)?;
    let mut grid = MatchGrid::new(settings, target, dt_s)?;
    let baseline = settings.baseline.prepare(accel_g.len(), dt_s)?;
    grid.target_g.iter_mut().for_each(|q| *q *= target_factor);

    let mut start = accel_g.to_vec();
    let mut scale = 1.0;
    if settings.prescale {
        let psa = signed_psa(&start, dt_s, &grid.periods_s, grid.zeta)?;
        let ratio = ratios(&psa, &grid.target_g);
        let check = &ratio[grid.check.0..grid.check.1];
        let mean_log = check.iter().map(|r| r.ln()).sum::<f64>() / check.len() as f64;
        scale = (-mean_log).exp();
        start.iter_mut().for_each(|a| *a *= scale);
    }
    let start_eval = grid.evaluate(&start)?;
    let mut best: Option<Attempt> = None;
    let (mut iterations, mut stalls, mut attempts) = (0, 0, 0);
    for strategy in Strategy::ladder(settings) {
        if best
            .as_ref()
            .is_some_and(|b| b.eval.worst <= settings.retry_misfit)
        {
            break;
        }
        let a = attempt(&grid, &baseline, (&start, &start_eval), settings, &strategy)?;
        attempts += 1;
        iterations += a.iterations;
        stalls += a.stalls;
        if best.as_ref().is_none_or(|b| a.eval.worst < b.eval.worst) {
            best = Some(a);
        }
    }
    let Attempt {
        accel, eval: now, ..
    } = best.expect("the ladder has at least one strategy");
    let check = &now.ratio[grid.check.0..grid.check.1];
    let converged = check
        .iter()
        .all(|&r| r >= settings.lower && r <= settings.upper);
    let (final_velocity_mps, final_displacement_m) = super::process::drift(&accel, dt_s);
    let pga = |a: &[f64]| a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let report = MatchReport {
        converged,
        iterations,
        attempts,
        stalls,
        worst_misfit: now.worst,
        worst_period_s: grid.periods_s[grid.check.0 + now.worst_at],
        worst_ratio: check[now.worst_at],
        scale,
        target_factor,
        pga_before_g: pga(accel_g),
        pga_after_g: pga(&accel),
        final_velocity_mps,
        final_displacement_m,
        arias_ratio: super::process::arias_intensity_mps(&accel, dt_s)
            / super::process::arias_intensity_mps(accel_g, dt_s),
    };
    Ok(Matched {
        check_psa_g: now.psa[grid.check.0..grid.check.1]
            .iter()
            .map(|p| p.0.abs())
            .collect(),
        accel_g: accel,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regularised_solve_solves_a_well_posed_system() {
        let c = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.1, 0.3, 2.0];
        let x = [1.0, -2.0, 0.5];
        let d: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|k| c[i * 3 + k] * x[k]).sum())
            .collect();
        let b = regularised_solve(&c, &d, 0.0);
        for k in 0..3 {
            assert!((b[k] - x[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn bring_to_rest_zeroes_the_final_velocity_and_displacement() {
        // A record with an offset and a trend ends at rest after the correction, to round-off
        // of the sums (1e-12 of the uncorrected values).
        let dt = 0.01;
        let mut a: Vec<f64> = (0..3000)
            .map(|k| 0.3 * (0.05 * k as f64).sin() + 0.01 + 2e-6 * k as f64)
            .collect();
        let (v0, d0) = crate::ground_motion::process::drift(&a, dt);
        bring_to_rest(&mut a, dt);
        let (v, d) = crate::ground_motion::process::drift(&a, dt);
        assert!(
            v.abs() < 1e-12 * v0.abs() && d.abs() < 1e-12 * d0.abs(),
            "{v} {d}"
        );
    }

    #[test]
    fn wavelet_leaves_no_drift() {
        // ∫f dt and ∫∫f dt² of the improved tapered cosine nearly vanish: the design property of
        // Al Atik & Abrahamson's wavelet. ∫f dt = γ√π·e^{−(ωγ/2)²}·cos(…), largest at long
        // periods (e^{−(ωγ/2)²} ≈ 7e-6 at T = 4 s, 2e-5 of ∫|f| measured): bound 5e-5.
        for &t in &[0.05, 0.3, 1.0, 4.0] {
            let dt = 0.005;
            let (first, w) = wavelet(t, 0.05, 40.0, dt, 20_000);
            let (mut v, mut d, mut mag) = (0.0, 0.0, 0.0);
            for s in w.windows(2) {
                d += v * dt + dt * dt * (2.0 * s[0] + s[1]) / 6.0;
                v += 0.5 * dt * (s[0] + s[1]);
                mag += 0.5 * dt * (s[0].abs() + s[1].abs());
            }
            let dur = (w.len() - 1) as f64 * dt;
            assert!(first > 0);
            assert!(v.abs() < 5e-5 * mag, "T={t}: v {v} vs {mag}");
            assert!(d.abs() < 5e-5 * mag * dur, "T={t}: d {d}");
        }
    }

    #[test]
    fn wavelet_recurrence_equals_the_formula() {
        // Rotation and ratio recurrences, restarted every 64 samples, against cos·exp at every
        // sample: 1e-13 of the peak (round-off of ≤ 64 products).
        for &(t, dt) in &[(0.05, 0.02), (0.3, 0.005), (4.0, 0.0025)] {
            let (first, w) = wavelet(t, 0.05, 30.0, dt, 100_000);
            let f_hz: f64 = 1.0 / t;
            let wd = TAU * f_hz * (1.0f64 - 0.0025).sqrt();
            let gamma = 1.178 * f_hz.powf(-0.93);
            let centre = 30.0 - ((1.0f64 - 0.0025).sqrt() / 0.05).atan() / wd;
            for (i, &x) in w.iter().enumerate().skip(1).take(w.len() - 2) {
                let tau = (first + i) as f64 * dt - centre;
                let want = (wd * tau).cos() * (-(tau / gamma).powi(2)).exp();
                assert!((x - want).abs() < 1e-13, "T={t} i={i}: {x} vs {want}");
            }
        }
    }

    #[test]
    fn system_matrix_equals_the_scalar_responses() {
        // The adjoint weights of eight probes at a time, dotted with each wave, equal
        // `response_at` (stepping each oscillator through the wave) to 1e-10 of the largest
        // entry: probes before, inside and after the waves, at and between samples and past
        // the last sample; waves from the record's first sample and cut by its end.
        let settings = MatchSettings::default();
        let target: TargetSpectrum = "is1893:zone=III,soil=I".parse().unwrap();
        let dt = 0.01;
        let n = 4000;
        let grid = MatchGrid::new(&settings, &target, dt).unwrap();
        let mut cons: Vec<Constraint> = (0..grid.periods_s.len())
            .step_by(7)
            .enumerate()
            .map(|(k, g)| Constraint {
                grid: g,
                time_s: 5.0 + 0.731 * k as f64 + if k % 3 == 0 { 0.0 } else { 0.0037 },
                misfit: 0.0,
            })
            .collect();
        for (g, t) in [(3, 0.004), (40, 39.99), (90, 39.995)] {
            cons.push(Constraint {
                grid: g,
                time_s: t,
                misfit: 0.0,
            });
        }
        cons.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let probes: Vec<Probe> = cons.iter().map(|c| Probe::new(&grid, c, n)).collect();
        assert!(probes.iter().any(|p| p.k == n - 1 && p.rest_s > 0.0));
        let waves: Vec<(usize, Vec<f64>)> = [
            (0.1, 9.0),
            (1.0, 14.0),
            (3.0, 20.0),
            (0.5, 0.3),
            (3.0, 38.0),
        ]
        .iter()
        .map(|&(t, at)| wavelet(t, 0.05, at, dt, n))
        .collect();
        assert!(waves.iter().any(|w| w.0 == 0) && waves.iter().any(|w| w.0 + w.1.len() == n));
        let c = system_matrix(&grid, &probes, &waves, n, &mut Vec::new());
        let m = waves.len();
        for (j, (first, w)) in waves.iter().enumerate() {
            let want: Vec<f64> = cons
                .iter()
                .map(|c| {
                    response_at(
                        &grid.steps[c.grid],
                        grid.omega[c.grid],
                        grid.zeta,
                        dt,
                        *first,
                        w,
                        c.time_s,
                    )
                })
                .collect();
            let scale = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (r, x) in want.iter().enumerate() {
                let g = c[r * m + j];
                assert!(
                    (g - x).abs() < 1e-10 * scale,
                    "wave {j}, probe {r}: {g} vs {x}"
                );
            }
        }
    }

    #[test]
    fn response_to_a_wavelet_equals_the_full_record_response() {
        // C_ij computed on the wavelet's support plus free vibration equals the response of the
        // oscillator to the whole record that holds the wavelet (both exact).
        let dt = 0.01;
        let n = 3000;
        let (first, w) = wavelet(0.5, 0.05, 12.0, dt, n);
        let mut rec = vec![0.0; n];
        rec[first..first + w.len()].copy_from_slice(&w);
        for &(t, at) in &[(0.5, 12.0), (0.2, 11.03), (2.0, 25.0), (1.0, 11.6)] {
            let omega = TAU / t;
            let step = sdof::Step::new(omega, 0.05, dt);
            let got = response_at(&step, omega, 0.05, dt, first, &w, at);
            let k = (at / dt).floor() as usize;
            let (mut u, mut v) = (0.0, 0.0);
            for s in rec[..=k].windows(2) {
                (u, v) = step.step(u, v, s[0], s[1]);
            }
            let rest = at - k as f64 * dt;
            if rest > 0.0 {
                let a1 = rec[k] + (rec[k + 1] - rec[k]) * rest / dt;
                (u, _) = sdof::Step::new(omega, 0.05, rest).step(u, v, rec[k], a1);
            }
            let want = omega * omega * u;
            assert!(
                (got - want).abs() < 1e-12 * want.abs().max(1e-3),
                "{t}: {got} vs {want}"
            );
        }
    }
}
