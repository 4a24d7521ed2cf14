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

use super::process::{BaselineCorrection, ProcessError};
use crate::limits::{MAX_PERIODS, PERIOD_RANGE_S};
pub use crate::spectrum::log_space;
use crate::spectrum::response::{NjStep, response_spectrum, validate_record};
use crate::spectrum::{SpectrumError, TargetError, TargetSpectrum};
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
    /// Control periods per pass: the check grid is cut into this many bands and the worst
    /// period of each band is controlled.
    pub passes: Vec<usize>,
    /// Iterations per pass at most.
    pub max_iterations: usize,
    /// Matching stops when every check period is within this relative misfit.
    pub tolerance: f64,
    /// Relaxation gain on each adjustment (0 < gain ≤ 1).
    pub gain: f64,
    /// Tikhonov weight relative to the mean of diag(CᵀC).
    pub regularisation: f64,
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
            damping: 0.05,
            check_range_s: (0.05, 4.0),
            check_periods: 200,
            lower: 0.9,
            upper: 1.1,
            passes: vec![10, 25, 50],
            max_iterations: 10,
            tolerance: 0.05,
            gain: 1.0,
            regularisation: 1e-3,
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
    /// Largest |spectrum/target − 1| on the check grid.
    pub worst_misfit: f64,
    /// Pre-scale factor applied before the wavelets.
    pub scale: f64,
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
    let samples = (first..=last)
        .map(|k| {
            if k == first || k == last {
                return 0.0;
            }
            let tau = k as f64 * dt_s - centre;
            (wd * tau).cos() * (-(tau / gamma).powi(2)).exp()
        })
        .collect();
    (first, samples)
}

/// Response (pseudo-acceleration, same units as the input) of the oscillator with step
/// coefficients `step`, circular frequency `omega`, at time `at_s`, to the input that is
/// `samples` from index `first` and zero elsewhere.
fn response_at(
    step: &NjStep,
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
        (u, _) = NjStep::new(omega, damping, rest).step(u, v, a0, a1);
    }
    omega * omega * u
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

/// Solves `(CᵀC + μI)·b = Cᵀ·d` by Cholesky (`c` row-major `n×n`).
fn regularised_solve(c: &[f64], d: &[f64], reg: f64) -> Vec<f64> {
    let n = d.len();
    let mut a = vec![0.0; n * n];
    let mut rhs = vec![0.0; n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..n).map(|k| c[k * n + i] * c[k * n + j]).sum();
            a[i * n + j] = s;
            a[j * n + i] = s;
        }
        rhs[i] = (0..n).map(|k| c[k * n + i] * d[k]).sum();
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

fn worst(ratio: &[f64]) -> f64 {
    ratio.iter().fold(0.0f64, |m, r| m.max((r - 1.0).abs()))
}

/// The spectrum of a trial motion on the check grid: signed peaks with times, ratios to the
/// target, and the worst misfit.
#[derive(Clone)]
struct Evaluation {
    psa: Vec<(f64, f64)>,
    ratio: Vec<f64>,
    worst: f64,
    /// `Σ (ln ratio)²`: the smooth objective the line search lowers.
    sum_sq: f64,
}

fn evaluate(
    accel: &[f64],
    dt_s: f64,
    grid: &[f64],
    target: &[f64],
    zeta: f64,
) -> Result<Evaluation, SpectrumError> {
    let psa = signed_psa(accel, dt_s, grid, zeta)?;
    let ratio = ratios(&psa, target);
    let worst = worst(&ratio);
    let sum_sq = ratio.iter().map(|r| r.ln().powi(2)).sum();
    Ok(Evaluation {
        psa,
        ratio,
        worst,
        sum_sq,
    })
}

/// Control periods of a pass with `count` of them: the check grid cut into `count` contiguous
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

/// Matches `accel_g` (step `dt_s`) to `target`. Returns the best motion found (smallest worst
/// misfit on the check grid) whether or not it met the acceptance; `report.converged` says
/// which, and callers must leave out a record that did not.
///
/// Each iteration is a damped Newton step on the linearised system: when the full step does not
/// lower `Σ (ln spectrum/target)²` over the check grid, the gain is halved (at most three times)
/// before the pass gives up. The motion kept is the one with the smallest worst misfit seen.
pub fn match_record(
    accel_g: &[f64],
    dt_s: f64,
    target: &TargetSpectrum,
    settings: &MatchSettings,
) -> Result<Matched, MatchError> {
    settings.validate()?;
    validate_record(accel_g, dt_s)?;
    let (lo, hi) = settings.check_range_s;
    target.check_covers(lo, hi)?;
    let zeta = settings.damping;
    let n = accel_g.len();
    let grid = settings.check_grid_s();
    let q: Vec<f64> = grid.iter().map(|&t| target.sa_g(t)).collect();
    let omega: Vec<f64> = grid.iter().map(|t| TAU / t).collect();
    let steps: Vec<NjStep> = omega.iter().map(|&w| NjStep::new(w, zeta, dt_s)).collect();

    let mut accel = accel_g.to_vec();
    let mut scale = 1.0;
    if settings.prescale {
        let ratio = ratios(&signed_psa(&accel, dt_s, &grid, zeta)?, &q);
        let mean_log = ratio.iter().map(|r| r.ln()).sum::<f64>() / grid.len() as f64;
        scale = (-mean_log).exp();
        accel.iter_mut().for_each(|a| *a *= scale);
    }
    let mut now = evaluate(&accel, dt_s, &grid, &q, zeta)?;
    let mut best = (accel.clone(), now.clone());
    let mut iterations = 0;
    for &count in &settings.passes {
        for _ in 0..settings.max_iterations {
            if now.worst < settings.tolerance {
                break;
            }
            let control = control_indices(&now.ratio, count);
            let misfit: Vec<f64> = control
                .iter()
                .map(|&i| (q[i] - now.psa[i].0.abs()) * now.psa[i].0.signum())
                .collect();
            let waves: Vec<(usize, Vec<f64>)> = control
                .iter()
                .map(|&i| wavelet(grid[i], zeta, now.psa[i].1, dt_s, n))
                .collect();
            let m = control.len();
            let mut c = vec![0.0; m * m];
            for (j, (first, samples)) in waves.iter().enumerate() {
                for (r, &i) in control.iter().enumerate() {
                    c[r * m + j] = response_at(
                        &steps[i],
                        omega[i],
                        zeta,
                        dt_s,
                        *first,
                        samples,
                        now.psa[i].1,
                    );
                }
            }
            let b = regularised_solve(&c, &misfit, settings.regularisation);
            iterations += 1;
            let mut gain = settings.gain;
            let mut accepted = false;
            for _ in 0..4 {
                let mut trial = accel.clone();
                for ((first, samples), bj) in waves.iter().zip(&b) {
                    for (a, w) in trial[*first..].iter_mut().zip(samples) {
                        *a += gain * bj * w;
                    }
                }
                let mut trial = settings.baseline.apply(&trial, dt_s)?;
                if settings.end_at_rest {
                    bring_to_rest(&mut trial, dt_s);
                }
                let eval = evaluate(&trial, dt_s, &grid, &q, zeta)?;
                if eval.sum_sq < now.sum_sq {
                    if eval.worst < best.1.worst {
                        best = (trial.clone(), eval.clone());
                    }
                    accel = trial;
                    now = eval;
                    accepted = true;
                    break;
                }
                gain *= 0.5;
            }
            if !accepted {
                break;
            }
        }
    }

    let (accel, now) = best;
    let converged = now
        .ratio
        .iter()
        .all(|&r| r >= settings.lower && r <= settings.upper);
    let (final_velocity_mps, final_displacement_m) = super::process::drift(&accel, dt_s);
    let pga = |a: &[f64]| a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let report = MatchReport {
        converged,
        iterations,
        worst_misfit: now.worst,
        scale,
        pga_before_g: pga(accel_g),
        pga_after_g: pga(&accel),
        final_velocity_mps,
        final_displacement_m,
        arias_ratio: super::process::arias_intensity_mps(&accel, dt_s)
            / super::process::arias_intensity_mps(accel_g, dt_s),
    };
    Ok(Matched {
        check_psa_g: now.psa.iter().map(|p| p.0.abs()).collect(),
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
        let (v0, d0) = crate::motion::process::drift(&a, dt);
        bring_to_rest(&mut a, dt);
        let (v, d) = crate::motion::process::drift(&a, dt);
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
            let step = NjStep::new(omega, 0.05, dt);
            let got = response_at(&step, omega, 0.05, dt, first, &w, at);
            let k = (at / dt).floor() as usize;
            let (mut u, mut v) = (0.0, 0.0);
            for s in rec[..=k].windows(2) {
                (u, v) = step.step(u, v, s[0], s[1]);
            }
            let rest = at - k as f64 * dt;
            if rest > 0.0 {
                let a1 = rec[k] + (rec[k + 1] - rec[k]) * rest / dt;
                (u, _) = NjStep::new(omega, 0.05, rest).step(u, v, rec[k], a1);
            }
            let want = omega * omega * u;
            assert!(
                (got - want).abs() < 1e-12 * want.abs().max(1e-3),
                "{t}: {got} vs {want}"
            );
        }
    }
}
