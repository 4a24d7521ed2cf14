//! Processing of acceleration records: refinement onto a finer step, baseline correction, and
//! integral measures (final velocity and displacement, Arias intensity).
//!
//! Pure functions over slices and [`Record`]s; nothing here reads or writes files.
//!
//! # The ground motion between samples
//!
//! As in the integrators of [`crate::dynamics`], the ground acceleration is linear in time between
//! samples. Every integral here is exact for that piecewise-linear function (up to roundoff):
//!
//! * velocity: `v_{k+1} = v_k + dt·(a_k + a_{k+1})/2` (trapezoid);
//! * displacement: `d_{k+1} = d_k + v_k·dt + dt²·(2a_k + a_{k+1})/6` (the velocity is piecewise
//!   quadratic, the displacement piecewise cubic);
//! * `∫a² dt` over a step: `dt·(a_k² + a_k·a_{k+1} + a_{k+1}²)/3`.
//!
//! Integration starts at rest: `v_0 = d_0 = 0`.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;
use thiserror::Error;

use super::record::Record;
use crate::dynamics::G;

/// Highest polynomial order [`BaselineCorrection::Polynomial`] accepts. Baseline corrections in
/// practice use orders 0 to 6; higher orders start fitting the motion itself.
pub const MAX_POLY_ORDER: usize = 10;

/// Butterworth order used by `highpass:<corner_hz>` when no order is given.
pub const DEFAULT_HIGHPASS_ORDER: usize = 4;

/// Most zero-padding samples [`BaselineCorrection::HighPass`] adds at each end (80 MB of `f64`);
/// a corner so low that it needs more is refused.
pub const MAX_PAD_SAMPLES: usize = 10_000_000;

/// Relative tolerance on `record.dt / dt` being a whole number in [`resample_to_dt`].
const RATIO_REL_TOL: f64 = 1e-9;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ProcessError {
    #[error("the record is empty")]
    Empty,
    #[error("a record needs at least 2 samples, got {0}")]
    TooShort(usize),
    #[error("time step must be finite and > 0, got {0} s")]
    TimeStep(f64),
    #[error("acceleration sample {index} is not finite ({value})")]
    NonFinite { index: usize, value: f64 },
    #[error(
        "target step {target_s} s is longer than the record's step {record_s} s: only refinement \
         is supported (a coarser step needs an anti-alias filter)"
    )]
    Coarser { target_s: f64, record_s: f64 },
    #[error(
        "target step {target_s} s does not divide the record's step {record_s} s into a whole \
         number of sub-steps (ratio {ratio}; an integer within 1e-9 relative is needed)"
    )]
    NotSubmultiple {
        target_s: f64,
        record_s: f64,
        ratio: f64,
    },
    #[error("polynomial baseline order {order} is above the maximum {max}")]
    PolyOrder { order: usize, max: usize },
    #[error("a polynomial baseline of order {order} needs at least {needed} samples, got {found}")]
    TooShortForOrder {
        order: usize,
        needed: usize,
        found: usize,
    },
    #[error("high-pass filter order must be >= 1, got 0")]
    FilterOrder,
    #[error("high-pass corner frequency must be finite and > 0 Hz, got {0} Hz")]
    Corner(f64),
    #[error(
        "high-pass corner {corner_hz} Hz is at or above the Nyquist frequency {nyquist_hz} Hz \
         (dt = {dt_s} s)"
    )]
    AboveNyquist {
        corner_hz: f64,
        nyquist_hz: f64,
        dt_s: f64,
    },
    #[error(
        "high-pass corner {corner_hz} Hz of order {order} needs {pad} samples of zero padding at \
         each end (1.5·order/corner seconds), more than the limit {limit}; use a higher corner"
    )]
    Padding {
        corner_hz: f64,
        order: usize,
        pad: f64,
        limit: usize,
    },
    #[error(
        "invalid baseline correction `{input}`: {reason}; expected `none`, `poly:<order>`, \
         `highpass:<corner_hz>` or `highpass:<corner_hz>:<order>`"
    )]
    Parse { input: String, reason: String },
}

/// Checks a series: at least 2 finite samples and a finite step > 0.
fn check_series(accel: &[f64], dt_s: f64) -> Result<(), ProcessError> {
    match accel.len() {
        0 => return Err(ProcessError::Empty),
        1 => return Err(ProcessError::TooShort(1)),
        _ => {}
    }
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(ProcessError::TimeStep(dt_s));
    }
    if let Some((index, &value)) = accel.iter().enumerate().find(|(_, a)| !a.is_finite()) {
        return Err(ProcessError::NonFinite { index, value });
    }
    Ok(())
}

/// The record on the step `dt/factor`, by linear interpolation between its samples.
///
/// The ground motion is linear between samples, so the refined record describes the same function
/// of time: the original samples are kept exactly, the new ones lie on the lines between them, and
/// every integral of this module gives the same value up to roundoff. The result has
/// `(n − 1)·factor + 1` samples (the same duration) and `dt_s = record.dt_s / factor`.
///
/// # Panics
///
/// If `factor` is 0.
pub fn refine(record: &Record, factor: usize) -> Record {
    assert!(factor >= 1, "refinement factor must be >= 1, got 0");
    let a = &record.accel_g;
    let mut out = Vec::with_capacity(a.len().saturating_sub(1) * factor + 1);
    for w in a.windows(2) {
        let (a0, a1) = (w[0], w[1]);
        out.push(a0);
        for j in 1..factor {
            out.push(a0 + (a1 - a0) * (j as f64 / factor as f64));
        }
    }
    out.extend(a.last());
    Record {
        name: record.name.clone(),
        dt_s: record.dt_s / factor as f64,
        accel_g: out,
    }
}

/// The record on the finer step `dt_s` (same function of time, see [`refine`]).
///
/// `dt_s` must be ≤ the record's step and divide it into a whole number `m` of sub-steps (within
/// `1e-9` relative). The result's step is `record.dt_s / m`, which agrees with `dt_s` to that
/// tolerance and keeps the duration exact.
pub fn resample_to_dt(record: &Record, dt_s: f64) -> Result<Record, ProcessError> {
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(ProcessError::TimeStep(dt_s));
    }
    if !(record.dt_s.is_finite() && record.dt_s > 0.0) {
        return Err(ProcessError::TimeStep(record.dt_s));
    }
    let ratio = record.dt_s / dt_s;
    let m = ratio.round();
    if m < 1.0 {
        return Err(ProcessError::Coarser {
            target_s: dt_s,
            record_s: record.dt_s,
        });
    }
    if (ratio - m).abs() > RATIO_REL_TOL * ratio {
        if ratio < 1.0 {
            return Err(ProcessError::Coarser {
                target_s: dt_s,
                record_s: record.dt_s,
            });
        }
        return Err(ProcessError::NotSubmultiple {
            target_s: dt_s,
            record_s: record.dt_s,
            ratio,
        });
    }
    Ok(refine(record, m as usize))
}

/// One step of the exact piecewise-linear integration: `(v, d)` at the end of the step from
/// `(v, d)` at its start and the accelerations at both ends.
#[inline]
fn step(v: f64, d: f64, a0: f64, a1: f64, dt: f64) -> (f64, f64) {
    (
        v + dt * (a0 + a1) / 2.0,
        d + v * dt + dt * dt * (2.0 * a0 + a1) / 6.0,
    )
}

/// Displacement at every sample, from rest, in the units of `accel`·s².
fn displacement(accel: &[f64], dt: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(accel.len());
    let (mut v, mut d) = (0.0, 0.0);
    out.extend(accel.first().map(|_| 0.0));
    for w in accel.windows(2) {
        (v, d) = step(v, d, w[0], w[1], dt);
        out.push(d);
    }
    out
}

/// Final ground velocity (m/s) and displacement (m) of a record in g, from rest, exact for
/// piecewise-linear acceleration (module docs). `(0, 0)` for fewer than 2 samples.
pub fn drift(accel_g: &[f64], dt_s: f64) -> (f64, f64) {
    let (mut v, mut d) = (0.0, 0.0);
    for w in accel_g.windows(2) {
        (v, d) = step(v, d, w[0], w[1], dt_s);
    }
    (v * G, d * G)
}

/// Arias intensity `Ia = π/(2g)·∫a² dt`, m/s, of a record in g (`a` taken in m/s²), exact for
/// piecewise-linear acceleration: `∫a²` over a step is `dt·(a_k² + a_k·a_{k+1} + a_{k+1}²)/3`.
pub fn arias_intensity_mps(accel_g: &[f64], dt_s: f64) -> f64 {
    let sum: f64 = accel_g
        .windows(2)
        .map(|w| w[0] * w[0] + w[0] * w[1] + w[1] * w[1])
        .sum();
    // π/(2g)·g²·∫a_g² = (π·g/2)·∫a_g².
    PI * G / 2.0 * (sum * dt_s / 3.0)
}

/// Time at which the fraction `p` of a record's Arias intensity has accrued (cumulative
/// `Σ a_k²·dt`, linear between samples), s.
pub fn arias_time_s(accel_g: &[f64], dt_s: f64, p: f64) -> f64 {
    let total: f64 = accel_g.iter().map(|a| a * a).sum();
    let target = p * total;
    let mut cum = 0.0;
    for (k, a) in accel_g.iter().enumerate() {
        let next = cum + a * a;
        if next >= target && a * a > 0.0 {
            // Sample k's energy accrues over (t_{k−1}, t_k].
            let frac = (target - cum) / (a * a);
            return ((k as f64 - 1.0) + frac).max(0.0) * dt_s;
        }
        cum = next;
    }
    accel_g.len().saturating_sub(1) as f64 * dt_s
}

/// Baseline correction of an acceleration record.
///
/// Textual form ([`FromStr`], [`Display`](fmt::Display)): `none`, `poly:<order>`,
/// `highpass:<corner_hz>` (order [`DEFAULT_HIGHPASS_ORDER`]) or `highpass:<corner_hz>:<order>`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BaselineCorrection {
    /// Leave the record as it is.
    None,
    /// Subtract from the acceleration a polynomial in time of degree `order`, fitted through the
    /// displacement.
    ///
    /// The acceleration is integrated twice from rest (module docs) and the displacement `d(t)` is
    /// fitted by least squares, equal weight per sample, with `p(t) = τ²·q(τ)`, `τ = t/T` on
    /// `[0, 1]` (`T` the duration) and `q` of degree `order`: the terms `t², …, t^(order+2)`, no
    /// constant or linear term, so the fitted baseline starts at rest like the record. `p''(t)`, a
    /// polynomial of degree `order`, is subtracted from the acceleration. (Boore-style; `order = 0`
    /// removes the best constant acceleration offset, i.e. a quadratic displacement drift.)
    ///
    /// `q` is written in Legendre polynomials of `2τ − 1`, which keeps the least-squares problem
    /// (`numeric::linalg::least_squares`, an SVD) well conditioned up to [`MAX_POLY_ORDER`].
    ///
    /// The fit does not force the corrected record to end at rest: its final velocity and
    /// displacement are small but not zero.
    ///
    /// The corrected record's displacement is `d − p` exactly when `order ≤ 1` (then `p''` is
    /// linear and so exactly represented between samples); for higher orders it differs from
    /// `d − p` by the interpolation error of `p''`, which is negligible at usual steps.
    Polynomial { order: usize },
    /// Zero-phase Butterworth high-pass filter.
    ///
    /// A Butterworth of `order` poles, from the analog prototype by the bilinear transform with the
    /// corner prewarped (so the digital gain at `corner_hz` is exactly the analog one), run as
    /// cascaded second-order sections (one first-order section when `order` is odd), forward then
    /// backward. The two passes cancel the phase and square the gain: the effective roll-off is
    /// that of order `2·order`, and the gain at the corner is `1/2` (−6 dB), not `1/√2`.
    ///
    /// Before filtering the record is padded with zeros at both ends, each pad
    /// `⌈1.5·order/corner_hz/dt⌉` samples long (the filter transient length of Boore & Bommer
    /// 2005); the pads are removed afterwards, so the output has the input's length.
    ///
    /// The filtered motion is not at rest where the pads are cut off, so integrating the output
    /// from rest at its first sample (as [`drift`] does) can show velocity and displacement drift
    /// that the padded filtered record does not have (Boore 2005): on processed records, final
    /// displacements of the order of the peak.
    HighPass { corner_hz: f64, order: usize },
}

impl fmt::Display for BaselineCorrection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BaselineCorrection::None => f.write_str("none"),
            BaselineCorrection::Polynomial { order } => write!(f, "poly:{order}"),
            BaselineCorrection::HighPass { corner_hz, order } => {
                write!(f, "highpass:{corner_hz}:{order}")
            }
        }
    }
}

impl FromStr for BaselineCorrection {
    type Err = ProcessError;

    /// `none`, `poly:<order>`, `highpass:<corner_hz>` or `highpass:<corner_hz>:<order>`
    /// (case-insensitive); checks what can be checked without the record (order limits, corner
    /// finite and > 0).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let fail = |reason: String| ProcessError::Parse {
            input: s.to_string(),
            reason,
        };
        let lower = s.trim().to_ascii_lowercase();
        let mut parts = lower.split(':').map(str::trim);
        let kind = parts.next().unwrap_or("");
        let args: Vec<&str> = parts.collect();
        let order = |tok: &str| {
            tok.parse::<usize>()
                .map_err(|_| fail(format!("order `{tok}` is not a whole number")))
        };
        let parsed = match (kind, args.as_slice()) {
            ("none", []) => BaselineCorrection::None,
            ("poly", [o]) => BaselineCorrection::Polynomial { order: order(o)? },
            ("highpass", [c]) | ("highpass", [c, _]) => {
                let corner_hz: f64 = c
                    .parse()
                    .map_err(|_| fail(format!("corner `{c}` is not a number")))?;
                let order = match args.get(1) {
                    Some(o) => order(o)?,
                    None => DEFAULT_HIGHPASS_ORDER,
                };
                BaselineCorrection::HighPass { corner_hz, order }
            }
            ("none" | "poly" | "highpass", _) => {
                return Err(fail(format!("wrong number of `:` fields for `{kind}`")));
            }
            _ => return Err(fail(format!("unknown kind `{kind}`"))),
        };
        parsed.check().map_err(|e| fail(e.to_string()))?;
        Ok(parsed)
    }
}

impl BaselineCorrection {
    /// The checks that do not depend on the record.
    fn check(&self) -> Result<(), ProcessError> {
        match *self {
            BaselineCorrection::None => Ok(()),
            BaselineCorrection::Polynomial { order } if order > MAX_POLY_ORDER => {
                Err(ProcessError::PolyOrder {
                    order,
                    max: MAX_POLY_ORDER,
                })
            }
            BaselineCorrection::Polynomial { .. } => Ok(()),
            BaselineCorrection::HighPass { order: 0, .. } => Err(ProcessError::FilterOrder),
            BaselineCorrection::HighPass { corner_hz, .. }
                if !(corner_hz.is_finite() && corner_hz > 0.0) =>
            {
                Err(ProcessError::Corner(corner_hz))
            }
            BaselineCorrection::HighPass { .. } => Ok(()),
        }
    }

    /// This correction prepared for records of `n` samples at step `dt_s`, to be applied to
    /// many of them ([`PreparedBaseline`]); the same checks as [`BaselineCorrection::apply`]
    /// that do not need the values.
    pub fn prepare(&self, n: usize, dt_s: f64) -> Result<PreparedBaseline, ProcessError> {
        self.check()?;
        match n {
            0 => return Err(ProcessError::Empty),
            1 => return Err(ProcessError::TooShort(1)),
            _ => {}
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(ProcessError::TimeStep(dt_s));
        }
        let poly = match *self {
            BaselineCorrection::Polynomial { order } => Some(PolynomialFit::new(n, dt_s, order)?),
            _ => None,
        };
        Ok(PreparedBaseline {
            correction: *self,
            n,
            dt_s,
            poly,
        })
    }

    /// The corrected acceleration, in the units of `accel` (any: the corrections are linear),
    /// sampled at `dt_s` seconds. Needs at least 2 finite samples.
    pub fn apply(&self, accel: &[f64], dt_s: f64) -> Result<Vec<f64>, ProcessError> {
        self.check()?;
        check_series(accel, dt_s)?;
        match *self {
            BaselineCorrection::None => Ok(accel.to_vec()),
            BaselineCorrection::Polynomial { order } => polynomial(accel, dt_s, order),
            BaselineCorrection::HighPass { corner_hz, order } => {
                high_pass(accel, dt_s, corner_hz, order)
            }
        }
    }
}

/// Fills `p`, `dp`, `d2p` with the Legendre polynomials `P_j(x)` and their first and second
/// derivatives with respect to `x`, `j = 0..p.len()`.
fn legendre(x: f64, p: &mut [f64], dp: &mut [f64], d2p: &mut [f64]) {
    let m = p.len();
    for j in 0..m {
        (p[j], dp[j], d2p[j]) = match j {
            0 => (1.0, 0.0, 0.0),
            1 => (x, 1.0, 0.0),
            _ => {
                let k = (j - 1) as f64;
                (
                    ((2.0 * k + 1.0) * x * p[j - 1] - k * p[j - 2]) / (k + 1.0),
                    dp[j - 2] + (2.0 * k + 1.0) * p[j - 1],
                    d2p[j - 2] + (2.0 * k + 1.0) * dp[j - 1],
                )
            }
        };
    }
}

fn polynomial(accel: &[f64], dt: f64, order: usize) -> Result<Vec<f64>, ProcessError> {
    Ok(PolynomialFit::new(accel.len(), dt, order)?.correct(accel))
}

/// The polynomial baseline of [`BaselineCorrection::Polynomial`] for records of one length and
/// step: the basis at every sample and the least-squares factorisation computed once, so that
/// [`PolynomialFit::correct`] costs two passes over the record and gives the same bits as
/// [`BaselineCorrection::apply`].
struct PolynomialFit {
    dt: f64,
    duration: f64,
    /// `τ` at every sample.
    tau: Vec<f64>,
    /// Legendre values and first and second derivatives at `2τ − 1`, sample by sample
    /// (`order + 1` each).
    p: Vec<f64>,
    dp: Vec<f64>,
    d2p: Vec<f64>,
    fit: crate::numeric::linalg::LeastSquares,
    m: usize,
}

impl PolynomialFit {
    fn new(n: usize, dt: f64, order: usize) -> Result<Self, ProcessError> {
        let m = order + 1;
        // The sample at t = 0 carries no information (every basis term is 0 there).
        if n < m + 1 {
            return Err(ProcessError::TooShortForOrder {
                order,
                needed: m + 1,
                found: n,
            });
        }
        let duration = (n - 1) as f64 * dt;
        let tau: Vec<f64> = (0..n).map(|k| k as f64 / (n - 1) as f64).collect();
        let (mut p, mut dp, mut d2p) = (vec![0.0; m * n], vec![0.0; m * n], vec![0.0; m * n]);
        let mut cols = vec![vec![0.0; n]; m];
        for (k, &t) in tau.iter().enumerate() {
            let at = k * m..(k + 1) * m;
            legendre(
                2.0 * t - 1.0,
                &mut p[at.clone()],
                &mut dp[at.clone()],
                &mut d2p[at.clone()],
            );
            for (col, pj) in cols.iter_mut().zip(&p[at]) {
                col[k] = t * t * pj;
            }
        }
        Ok(Self {
            dt,
            duration,
            tau,
            p,
            dp,
            d2p,
            fit: crate::numeric::linalg::LeastSquares::new(&cols),
            m,
        })
    }

    /// `accel` (of the length prepared) less `p''(t)`.
    fn correct(&self, accel: &[f64]) -> Vec<f64> {
        let m = self.m;
        let c = self.fit.solve(&displacement(accel, self.dt));
        // p(t) = τ²·q(τ): p''(t) = (2q + 4τ·q' + τ²·q'')/T², with d/dτ = 2·d/dx.
        let t2 = self.duration * self.duration;
        accel
            .iter()
            .zip(&self.tau)
            .enumerate()
            .map(|(k, (&a, &t))| {
                let at = k * m..(k + 1) * m;
                let (mut q, mut dq, mut d2q) = (0.0, 0.0, 0.0);
                for (((cj, p), dp), d2p) in c
                    .iter()
                    .zip(&self.p[at.clone()])
                    .zip(&self.dp[at.clone()])
                    .zip(&self.d2p[at])
                {
                    q += cj * p;
                    dq += 2.0 * cj * dp;
                    d2q += 4.0 * cj * d2p;
                }
                a - (2.0 * q + 4.0 * t * dq + t * t * d2q) / t2
            })
            .collect()
    }
}

/// A [`BaselineCorrection`] prepared for records of one length and step
/// ([`BaselineCorrection::prepare`]): what does not depend on the values is computed once. Its
/// [`PreparedBaseline::apply`] gives the same bits as [`BaselineCorrection::apply`].
pub struct PreparedBaseline {
    correction: BaselineCorrection,
    n: usize,
    dt_s: f64,
    poly: Option<PolynomialFit>,
}

impl PreparedBaseline {
    /// [`BaselineCorrection::apply`] on `accel`, which must have the length prepared for.
    pub fn apply(&self, accel: &[f64]) -> Result<Vec<f64>, ProcessError> {
        assert_eq!(
            accel.len(),
            self.n,
            "record of another length than prepared"
        );
        match &self.poly {
            Some(fit) => {
                check_series(accel, self.dt_s)?;
                Ok(fit.correct(accel))
            }
            None => self.correction.apply(accel, self.dt_s),
        }
    }
}

fn high_pass(
    accel: &[f64],
    dt: f64,
    corner_hz: f64,
    order: usize,
) -> Result<Vec<f64>, ProcessError> {
    let nyquist_hz = 0.5 / dt;
    if corner_hz >= nyquist_hz {
        return Err(ProcessError::AboveNyquist {
            corner_hz,
            nyquist_hz,
            dt_s: dt,
        });
    }
    let pad_f = (1.5 * order as f64 / corner_hz / dt).ceil();
    if pad_f > MAX_PAD_SAMPLES as f64 {
        return Err(ProcessError::Padding {
            corner_hz,
            order,
            pad: pad_f,
            limit: MAX_PAD_SAMPLES,
        });
    }
    let pad = pad_f as usize;
    let n = accel.len();
    let mut x = vec![0.0; n + 2 * pad];
    x[pad..pad + n].copy_from_slice(accel);
    let sections = crate::numeric::filter::butterworth_high_pass(corner_hz, order, dt);
    for s in &sections {
        s.run(&mut x);
    }
    x.reverse();
    for s in &sections {
        s.run(&mut x);
    }
    x.reverse();
    x.truncate(pad + n);
    x.drain(..pad);
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64*, for reproducible random records.
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn signed(&mut self) -> f64 {
            2.0 * self.unit() - 1.0
        }
    }

    fn record(accel_g: Vec<f64>, dt_s: f64) -> Record {
        Record {
            name: "test".into(),
            dt_s,
            accel_g,
        }
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    fn max_abs(x: &[f64]) -> f64 {
        x.iter().fold(0.0, |m, v| m.max(v.abs()))
    }

    fn sine(n: usize, dt: f64, f_hz: f64) -> Vec<f64> {
        (0..n)
            .map(|k| (2.0 * PI * f_hz * k as f64 * dt).sin())
            .collect()
    }

    /// Amplitude of the best fit `A·sin(ωt) + B·cos(ωt)` to `y` over `range` (2×2 least squares).
    fn amplitude(y: &[f64], dt: f64, f_hz: f64, range: std::ops::Range<usize>) -> f64 {
        let (mut ss, mut sc, mut cc, mut ys, mut yc) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in range {
            let w = 2.0 * PI * f_hz * k as f64 * dt;
            let (s, c) = w.sin_cos();
            ss += s * s;
            sc += s * c;
            cc += c * c;
            ys += y[k] * s;
            yc += y[k] * c;
        }
        let det = ss * cc - sc * sc;
        let a = (ys * cc - yc * sc) / det;
        let b = (yc * ss - ys * sc) / det;
        a.hypot(b)
    }

    #[test]
    fn refine_keeps_samples_and_interpolates_linearly() {
        let r = refine(&record(vec![0.0, 1.0, -1.0], 0.02), 4);
        assert_eq!(r.dt_s, 0.005);
        assert_eq!(
            r.accel_g,
            vec![0.0, 0.25, 0.5, 0.75, 1.0, 0.5, 0.0, -0.5, -1.0]
        );
        assert_eq!(r.duration_s(), 0.04);
        let same = refine(&record(vec![0.3, 0.1], 0.01), 1);
        assert_eq!(same.accel_g, vec![0.3, 0.1]);
        assert_eq!(refine(&record(vec![], 0.01), 3).accel_g, Vec::<f64>::new());
        assert_eq!(refine(&record(vec![0.2], 0.01), 3).accel_g, vec![0.2]);
    }

    /// Tolerance 1e-12 relative: the refined record is the same piecewise-linear function, so the
    /// exact integrals agree mathematically; what differs is roundoff accumulated over up to
    /// (n−1)·factor = 2·10⁴ steps (observed ≤ 5e-15).
    #[test]
    fn refine_preserves_drift_and_arias() {
        let mut rng = Rng(0x1234_5678);
        // A nonzero mean gives a large final velocity and displacement to compare against.
        let a: Vec<f64> = (0..2001).map(|_| 0.05 + 0.3 * rng.signed()).collect();
        let r = record(a, 0.01);
        let (v0, d0) = drift(&r.accel_g, r.dt_s);
        let ia0 = arias_intensity_mps(&r.accel_g, r.dt_s);
        for factor in [2, 3, 10] {
            let f = refine(&r, factor);
            let (v, d) = drift(&f.accel_g, f.dt_s);
            assert!(rel(v, v0) < 1e-12, "factor {factor}: v {v} vs {v0}");
            assert!(rel(d, d0) < 1e-12, "factor {factor}: d {d} vs {d0}");
            let ia = arias_intensity_mps(&f.accel_g, f.dt_s);
            assert!(rel(ia, ia0) < 1e-12, "factor {factor}: Ia {ia} vs {ia0}");
        }
    }

    #[test]
    fn resample_to_whole_submultiples_only() {
        let r = record(vec![0.0, 1.0, 0.0], 0.01);
        let f = resample_to_dt(&r, 0.0025).unwrap();
        assert_eq!(f.accel_g.len(), 9);
        assert_eq!(f.dt_s, 0.01 / 4.0);
        assert_eq!(resample_to_dt(&r, 0.01).unwrap().accel_g, r.accel_g);
        assert_eq!(
            resample_to_dt(&r, 0.003).unwrap_err().to_string(),
            "target step 0.003 s does not divide the record's step 0.01 s into a whole number of \
             sub-steps (ratio 3.3333333333333335; an integer within 1e-9 relative is needed)"
        );
        assert_eq!(
            resample_to_dt(&r, 0.02).unwrap_err().to_string(),
            "target step 0.02 s is longer than the record's step 0.01 s: only refinement is \
             supported (a coarser step needs an anti-alias filter)"
        );
        assert_eq!(
            resample_to_dt(&r, 0.011).unwrap_err(),
            ProcessError::Coarser {
                target_s: 0.011,
                record_s: 0.01
            }
        );
        assert_eq!(
            resample_to_dt(&r, 0.0).unwrap_err().to_string(),
            "time step must be finite and > 0, got 0 s"
        );
    }

    #[test]
    fn baseline_text_forms() {
        let cases = [
            ("none", BaselineCorrection::None, "none"),
            (
                "poly:2",
                BaselineCorrection::Polynomial { order: 2 },
                "poly:2",
            ),
            (
                " HighPass:0.1 ",
                BaselineCorrection::HighPass {
                    corner_hz: 0.1,
                    order: 4,
                },
                "highpass:0.1:4",
            ),
            (
                "highpass:0.05:2",
                BaselineCorrection::HighPass {
                    corner_hz: 0.05,
                    order: 2,
                },
                "highpass:0.05:2",
            ),
        ];
        for (text, value, shown) in cases {
            let parsed: BaselineCorrection = text.parse().unwrap();
            assert_eq!(parsed, value, "{text}");
            assert_eq!(parsed.to_string(), shown);
            assert_eq!(shown.parse::<BaselineCorrection>().unwrap(), value);
        }
        let err = |s: &str| s.parse::<BaselineCorrection>().unwrap_err().to_string();
        let tail = "; expected `none`, `poly:<order>`, `highpass:<corner_hz>` or \
                    `highpass:<corner_hz>:<order>`";
        assert_eq!(
            err("poly"),
            format!(
                "invalid baseline correction `poly`: wrong number of `:` fields for `poly`{tail}"
            )
        );
        assert_eq!(
            err("poly:x"),
            format!("invalid baseline correction `poly:x`: order `x` is not a whole number{tail}")
        );
        assert_eq!(
            err("poly:11"),
            format!(
                "invalid baseline correction `poly:11`: polynomial baseline order 11 is above \
                 the maximum 10{tail}"
            )
        );
        assert_eq!(
            err("highpass:0.1:0"),
            format!(
                "invalid baseline correction `highpass:0.1:0`: high-pass filter order must be >= \
                 1, got 0{tail}"
            )
        );
        assert_eq!(
            err("highpass:-1"),
            format!(
                "invalid baseline correction `highpass:-1`: high-pass corner frequency must be \
                 finite and > 0 Hz, got -1 Hz{tail}"
            )
        );
        assert_eq!(
            err("lowpass:3"),
            format!("invalid baseline correction `lowpass:3`: unknown kind `lowpass`{tail}")
        );
    }

    #[test]
    fn apply_refuses_bad_input() {
        let hp = BaselineCorrection::HighPass {
            corner_hz: 0.1,
            order: 4,
        };
        let poly = BaselineCorrection::Polynomial { order: 2 };
        let msg =
            |b: &BaselineCorrection, a: &[f64], dt: f64| b.apply(a, dt).unwrap_err().to_string();
        assert_eq!(msg(&hp, &[], 0.01), "the record is empty");
        assert_eq!(
            msg(&BaselineCorrection::None, &[], 0.01),
            "the record is empty"
        );
        assert_eq!(
            msg(&poly, &[0.1], 0.01),
            "a record needs at least 2 samples, got 1"
        );
        assert_eq!(
            msg(&poly, &[0.1, f64::NAN], 0.01),
            "acceleration sample 1 is not finite (NaN)"
        );
        assert_eq!(
            msg(&hp, &[0.1, 0.2], -0.01),
            "time step must be finite and > 0, got -0.01 s"
        );
        assert_eq!(
            msg(&poly, &[0.1, 0.2, 0.3], 0.01),
            "a polynomial baseline of order 2 needs at least 4 samples, got 3"
        );
        assert_eq!(
            msg(
                &BaselineCorrection::Polynomial { order: 11 },
                &[0.0; 100],
                0.01
            ),
            "polynomial baseline order 11 is above the maximum 10"
        );
        assert_eq!(
            msg(
                &BaselineCorrection::HighPass {
                    corner_hz: 50.0,
                    order: 4
                },
                &[0.0; 100],
                0.01
            ),
            "high-pass corner 50 Hz is at or above the Nyquist frequency 50 Hz (dt = 0.01 s)"
        );
        assert_eq!(
            msg(
                &BaselineCorrection::HighPass {
                    corner_hz: 0.1,
                    order: 0
                },
                &[0.0; 100],
                0.01
            ),
            "high-pass filter order must be >= 1, got 0"
        );
        assert_eq!(
            msg(
                &BaselineCorrection::HighPass {
                    corner_hz: 0.0,
                    order: 4
                },
                &[0.0; 100],
                0.01
            ),
            "high-pass corner frequency must be finite and > 0 Hz, got 0 Hz"
        );
        assert_eq!(
            msg(
                &BaselineCorrection::HighPass {
                    corner_hz: 1e-6,
                    order: 4
                },
                &[0.0; 100],
                0.01
            ),
            "high-pass corner 0.000001 Hz of order 4 needs 600000000 samples of zero padding \
             at each end (1.5·order/corner seconds), more than the limit 10000000; use a higher \
             corner"
        );
        let a = [0.1, -0.2, 0.3];
        assert_eq!(
            BaselineCorrection::None.apply(&a, 0.01).unwrap(),
            a.to_vec()
        );
    }

    /// Constant and linear accelerations start at rest with displacements `c·t²/2` and `c·t³/6`:
    /// exactly representable as `τ²·q(τ)` with `q` of degree 0 and 1, and `p''` is then exactly
    /// linear between samples. So the correction removes them to roundoff: the displacement
    /// recursion over 2000 steps and the QR solve leave ~1e-15 relative in the fit, amplified by
    /// the second derivative's Legendre factors (≤ order⁴); observed ≤ 3e-13 of `c` for the
    /// residual, tolerance 1e-11 (of `c` for the residual, of the uncorrected values for the final
    /// velocity and displacement).
    #[test]
    fn polynomial_removes_offset_and_ramp() {
        let (n, dt, c) = (2001, 0.01, 0.02);
        let offset = vec![c; n];
        let ramp: Vec<f64> = (0..n).map(|k| c * k as f64 * dt).collect();
        let mut cases = vec![];
        for order in 0..=3 {
            cases.push(("offset", order, &offset));
        }
        for order in 1..=3 {
            cases.push(("ramp", order, &ramp));
        }
        for (what, order, a) in cases {
            let out = BaselineCorrection::Polynomial { order }
                .apply(a, dt)
                .unwrap();
            let (v_before, d_before) = drift(a, dt);
            let (v, d) = drift(&out, dt);
            assert!(
                max_abs(&out) < 1e-11 * c,
                "{what} order {order}: residual {}",
                max_abs(&out)
            );
            assert!(
                v.abs() < 1e-11 * v_before.abs(),
                "{what} order {order}: v {v}"
            );
            assert!(
                d.abs() < 1e-11 * d_before.abs(),
                "{what} order {order}: d {d}"
            );
        }
    }

    /// The correction is linear, so a record plus an offset is corrected back to the corrected
    /// record; same roundoff budget as above (observed ≤ 2e-13, tolerance 1e-11 of the offset).
    #[test]
    fn polynomial_corrects_record_plus_offset_back() {
        let mut rng = Rng(99);
        let (n, dt, c) = (1501, 0.02, 0.05);
        let base: Vec<f64> = (0..n)
            .map(|k| 0.2 * (0.7 * k as f64 * dt).sin() * rng.unit())
            .collect();
        for order in [0, 1, 2, 4] {
            let b = BaselineCorrection::Polynomial { order };
            let clean = b.apply(&base, dt).unwrap();
            let shifted: Vec<f64> = base.iter().map(|a| a + c).collect();
            let out = b.apply(&shifted, dt).unwrap();
            let diff = out
                .iter()
                .zip(&clean)
                .fold(0.0, |m: f64, (x, y)| m.max((x - y).abs()));
            assert!(diff < 1e-11 * c, "order {order}: {diff}");
        }
    }

    /// A correction prepared once and applied to several records of its length gives the same
    /// bits as applying it to each (the prepared basis and factorisation are only read), and
    /// refuses at preparation what `apply` refuses without the values.
    #[test]
    fn prepared_correction_equals_apply_bit_for_bit() {
        let mut rng = Rng(7);
        let (n, dt) = (2001, 0.01);
        let records: Vec<Vec<f64>> = (0..3)
            .map(|r| {
                (0..n)
                    .map(|k| 0.3 * ((0.3 + r as f64) * k as f64 * dt).sin() + 0.05 * rng.unit())
                    .collect()
            })
            .collect();
        for b in [
            BaselineCorrection::None,
            BaselineCorrection::Polynomial { order: 3 },
            BaselineCorrection::Polynomial { order: 6 },
            BaselineCorrection::HighPass {
                corner_hz: 0.1,
                order: 4,
            },
        ] {
            let prepared = b.prepare(n, dt).unwrap();
            for rec in &records {
                let want = b.apply(rec, dt).unwrap();
                let got = prepared.apply(rec).unwrap();
                assert!(
                    got.iter()
                        .zip(&want)
                        .all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{b}"
                );
            }
        }
        let short = BaselineCorrection::Polynomial { order: 3 }.prepare(4, dt);
        assert!(matches!(short, Err(ProcessError::TooShortForOrder { .. })));
        assert!(matches!(
            BaselineCorrection::None.prepare(10, -1.0),
            Err(ProcessError::TimeStep(_))
        ));
    }

    /// A forward-backward pass squares the gain: exactly 1/2 at the prewarped corner. A steady sine
    /// at the corner, measured between 20 s and 40 s of a 60 s record (filter transients from the
    /// padded ends decay by e^(−ζωt), ζω ≥ 0.38·2π·1 Hz, below 1e-9 after 20 s), gives 1/2 to
    /// 1e-6 (observed 4e-15).
    #[test]
    fn high_pass_gain_at_corner_is_one_half() {
        let (dt, fc) = (0.005, 1.0);
        let n = 12_001;
        let x = sine(n, dt, fc);
        for order in [1, 2, 3, 4, 6] {
            let y = BaselineCorrection::HighPass {
                corner_hz: fc,
                order,
            }
            .apply(&x, dt)
            .unwrap();
            let gain = amplitude(&y, dt, fc, 4000..8000) / amplitude(&x, dt, fc, 4000..8000);
            assert!((gain - 0.5).abs() < 1e-6, "order {order}: gain {gain}");
        }
    }

    /// 5 Hz is 50× the 0.1 Hz corner: the forward-backward gain `1/(1 + (fc/f)^(2n))`, n = 4,
    /// differs from 1 by 4e-14. Pointwise error below 1 % of the amplitude more than 10 s from the
    /// ends (observed 2.4e-4: the small transient the sine's start and end excite).
    #[test]
    fn high_pass_passes_5_hz() {
        let (dt, n) = (0.005, 16_001);
        let x = sine(n, dt, 5.0);
        let y = BaselineCorrection::HighPass {
            corner_hz: 0.1,
            order: 4,
        }
        .apply(&x, dt)
        .unwrap();
        let err = (2000..n - 2000).fold(0.0, |m: f64, k| m.max((y[k] - x[k]).abs()));
        assert!(err < 0.01, "max error {err}");
    }

    /// A constant is removed: the DC gain is exactly zero (each section's numerator sums to 0), and
    /// what is left is the transient of the two steps the zero padding creates at the ends, which
    /// decays like e^(−0.38·2π·0.1 t). At least 60 s from the ends (14 time constants) the output
    /// and its mean are below 1e-6 of the offset (observed 1.3e-7). Over the whole 200 s record
    /// the end transients, of area ~1/(2π·fc) s each, leave a mean below 1 % of the offset
    /// (observed 0.52 %).
    #[test]
    fn high_pass_removes_offset() {
        let (dt, n, c) = (0.01, 20_001, 0.05);
        let y = BaselineCorrection::HighPass {
            corner_hz: 0.1,
            order: 4,
        }
        .apply(&vec![c; n], dt)
        .unwrap();
        let middle = &y[6000..n - 6000];
        let interior = max_abs(middle);
        assert!(interior < 1e-6 * c, "interior {interior}");
        let interior_mean = middle.iter().sum::<f64>() / middle.len() as f64;
        assert!(
            interior_mean.abs() < 1e-6 * c,
            "interior mean {interior_mean}"
        );
        let mean = y.iter().sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01 * c, "mean {mean}");
    }

    /// Zero phase: the impulse response of the forward-backward filter is symmetric about the
    /// impulse (to roundoff, 1e-12 of its peak), and a 1 Hz wavelet through a 0.5 Hz corner (where
    /// a single causal pass would shift it by a large fraction of a period) comes out with its
    /// cross-correlation peak at lag 0.
    #[test]
    fn high_pass_is_zero_phase() {
        let (dt, n) = (0.01, 8001);
        let hp = BaselineCorrection::HighPass {
            corner_hz: 0.5,
            order: 4,
        };
        let mut impulse = vec![0.0; n];
        let mid = n / 2;
        impulse[mid] = 1.0;
        let h = hp.apply(&impulse, dt).unwrap();
        let peak = h[mid].abs();
        for k in 1..2000 {
            assert!(
                (h[mid + k] - h[mid - k]).abs() < 1e-12 * peak,
                "lag {k}: {} vs {}",
                h[mid + k],
                h[mid - k]
            );
        }
        let t0 = mid as f64 * dt;
        let x: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 * dt - t0;
                (-(t / 1.5).powi(2)).exp() * (2.0 * PI * t).cos()
            })
            .collect();
        let y = hp.apply(&x, dt).unwrap();
        let xcorr = |lag: isize| -> f64 {
            (1000..n - 1000)
                .map(|k| x[k] * y[(k as isize + lag) as usize])
                .sum()
        };
        let best = (-50..=50)
            .max_by(|&a, &b| xcorr(a).total_cmp(&xcorr(b)))
            .unwrap();
        assert_eq!(best, 0);
        // The single causal pass does shift it, so the check above has teeth.
        let mut causal = x.clone();
        for s in &crate::numeric::filter::butterworth_high_pass(0.5, 4, dt) {
            s.run(&mut causal);
        }
        let xcorr_causal = |lag: isize| -> f64 {
            (1000..n - 1000)
                .map(|k| x[k] * causal[(k as isize + lag) as usize])
                .sum()
        };
        let best_causal = (-50..=50)
            .max_by(|&a, &b| xcorr_causal(a).total_cmp(&xcorr_causal(b)))
            .unwrap();
        assert_ne!(best_causal, 0);
    }

    #[test]
    fn drift_is_exact_for_constant_and_ramp() {
        // Constant 0.1 g for 2 s: v = 0.1·g·2, d = 0.1·g·4/2. Tolerance 1e-13: 200 steps of
        // roundoff in the sums.
        let (v, d) = drift(&[0.1; 201], 0.01);
        assert!(rel(v, 0.2 * G) < 1e-13, "{v}");
        assert!(rel(d, 0.2 * G) < 1e-13, "{d}");
        // Ramp a = 0.1·t g: v = 0.05·t²·g, d = 0.1·t³/6·g; one step is exact in one rounding.
        let (v, d) = drift(&[0.0, 0.1], 1.0);
        assert_eq!(v, 0.05 * G);
        assert!(rel(d, 0.1 / 6.0 * G) < 1e-15);
        let ramp: Vec<f64> = (0..=300).map(|k| 0.1 * k as f64 * 0.01).collect();
        let (v, d) = drift(&ramp, 0.01);
        assert!(rel(v, 0.05 * 9.0 * G) < 1e-13, "{v}");
        assert!(rel(d, 0.1 * 27.0 / 6.0 * G) < 1e-13, "{d}");
        assert_eq!(drift(&[0.3], 0.01), (0.0, 0.0));
    }

    #[test]
    fn arias_intensity_hand_values() {
        // 1 g for 1 s: Ia = π/(2g)·g²·1 s = π·g/2, exactly (the sum is 3·1/3 = 1 exactly).
        assert_eq!(arias_intensity_mps(&[1.0, 1.0], 1.0), PI * G / 2.0);
        // Same on a fine step: 100 equal terms, tolerance 1e-14 for the summation.
        let ia = arias_intensity_mps(&[1.0; 101], 0.01);
        assert!(rel(ia, PI * G / 2.0) < 1e-14, "{ia}");
        // Triangle 0 → A → 0 over T: ∫a² = A²·T/3 (each half A²·(T/2)/3), exact on any grid that
        // has the apex as a sample. A = 0.4 g, T = 6 s: Ia = π·g/2·0.16·2.
        let hand = PI * G / 2.0 * 0.16 * 6.0 / 3.0;
        assert!(rel(arias_intensity_mps(&[0.0, 0.4, 0.0], 3.0), hand) < 1e-15);
        let fine: Vec<f64> = (0..=600)
            .map(|k| 0.4 * (1.0 - (k as f64 - 300.0).abs() / 300.0))
            .collect();
        let ia = arias_intensity_mps(&fine, 0.01);
        assert!(rel(ia, hand) < 1e-13, "{ia} vs {hand}");
    }
}
