//! Work-precision measures: how far a method's structure-displacement history is from a
//! reference, the convergence order it shows as its step shrinks, and the finest setting it needs
//! to reach a tolerance. Plain functions over slices; `slidestack-verify accuracy` runs the
//! integrators, times them and composes these.

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum AccuracyError {
    #[error("history has {got} samples, the reference {want}")]
    Length { got: usize, want: usize },
    #[error("the reference history has no non-zero value: relative errors are undefined")]
    ZeroReference,
}

/// Errors of a history `û` against a reference `u`, both sampled at the record samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Errors {
    /// `(max_k|û_k| − max_k|u_k|) / max_k|u_k|`: signed, > 0 when the method overshoots.
    pub peak_signed: f64,
    /// `max_k|û_k − u_k| / max_k|u_k|`.
    pub history: f64,
}

impl Errors {
    pub fn peak(&self) -> f64 {
        self.peak_signed.abs()
    }
}

/// Peak and history errors of `u` against `reference`, relative to the reference's peak over the
/// same samples (so a method that samples its peak is compared with a sampled reference).
pub fn errors(u: &[f64], reference: &[f64]) -> Result<Errors, AccuracyError> {
    if u.len() != reference.len() {
        return Err(AccuracyError::Length {
            got: u.len(),
            want: reference.len(),
        });
    }
    let peak = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let scale = peak(reference);
    if scale == 0.0 || !scale.is_finite() {
        return Err(AccuracyError::ZeroReference);
    }
    let history = u
        .iter()
        .zip(reference)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    Ok(Errors {
        peak_signed: (peak(u) - scale) / scale,
        history: history / scale,
    })
}

/// Least-squares slope of `log err` against `log h` (with `h ∝ 1/steps`) over the points
/// `(steps, err)` with `steps ≥ min_steps` and `err > 0`: the observed order of convergence.
/// `None` with fewer than two such points.
pub fn observed_order(points: &[(usize, f64)], min_steps: usize) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(s, e)| *s >= min_steps && *e > 0.0 && e.is_finite())
        .map(|(s, e)| (-(*s as f64).ln(), e.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Where a method meets a tolerance, given `(steps, err)` in increasing `steps`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Needed {
    /// Index of the smallest step count from which the error stays `≤ tol` at every finer count.
    pub index: usize,
    /// A coarser count already met the tolerance before the error rose above it again.
    pub touched_earlier: bool,
}

/// The setting needed for `err ≤ tol` (see [`Needed`]); `None` if the finest count misses it.
pub fn needed_for(points: &[(usize, f64)], tol: f64) -> Option<Needed> {
    let meets = |e: f64| e <= tol;
    let first = points.iter().position(|(_, e)| meets(*e))?;
    let stays = points
        .iter()
        .rposition(|(_, e)| !meets(*e))
        .map_or(0, |i| i + 1);
    (stays < points.len()).then_some(Needed {
        index: stays,
        touched_earlier: first < stays,
    })
}

/// Geometric mean of the positive finite values, with values below `floor` raised to it (an
/// error of exactly zero would otherwise send the mean to zero); `None` if there are none.
pub fn geometric_mean(values: impl IntoIterator<Item = f64>, floor: f64) -> Option<f64> {
    let (sum, n) = values
        .into_iter()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .fold((0.0, 0usize), |(s, n), v| (s + v.max(floor).ln(), n + 1));
    (n > 0).then(|| (sum / n as f64).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_relative_to_the_reference_peak() {
        let reference = [0.0, 1.0, -2.0, 0.5];
        let u = [0.0, 1.1, -1.9, 0.5];
        let e = errors(&u, &reference).unwrap();
        assert!((e.peak_signed - (-0.05)).abs() < 1e-15);
        assert!((e.history - 0.05).abs() < 1e-15);
        assert_eq!(
            errors(&u[..3], &reference),
            Err(AccuracyError::Length { got: 3, want: 4 })
        );
        assert_eq!(
            errors(&[0.0; 2], &[0.0; 2]),
            Err(AccuracyError::ZeroReference)
        );
    }

    #[test]
    fn observed_order_recovers_a_power_law() {
        // err = 3·h^p with h = 1/steps: the slope is p exactly (up to rounding).
        for p in [1.0, 2.0, 4.0] {
            let pts: Vec<(usize, f64)> = [1usize, 2, 5, 10, 20, 50]
                .iter()
                .map(|&s| (s, 3.0 * (1.0 / s as f64).powf(p)))
                .collect();
            let got = observed_order(&pts, 2).unwrap();
            assert!((got - p).abs() < 1e-12, "{got} vs {p}");
        }
        assert_eq!(observed_order(&[(10, 1e-3), (20, 0.0)], 1), None);
    }

    #[test]
    fn needed_for_takes_the_count_from_which_the_error_stays_below() {
        let pts = [(1, 1e-1), (2, 5e-4), (5, 2e-3), (10, 1e-4), (20, 1e-7)];
        assert_eq!(
            needed_for(&pts, 1e-3),
            Some(Needed {
                index: 3,
                touched_earlier: true
            })
        );
        assert_eq!(
            needed_for(&pts, 1e-6),
            Some(Needed {
                index: 4,
                touched_earlier: false
            })
        );
        assert_eq!(needed_for(&pts, 1e-9), None);
        // A NaN error never counts as meeting the tolerance.
        assert_eq!(needed_for(&[(1, 1e-9), (2, f64::NAN)], 1e-3), None);
    }

    #[test]
    fn geometric_mean_floors_zeros() {
        let m = geometric_mean([1e-2, 1e-4], 1e-16).unwrap();
        assert!((m - 1e-3).abs() < 1e-15);
        let z = geometric_mean([0.0, 1e-16], 1e-16).unwrap();
        assert!((z - 1e-16).abs() < 1e-30);
        assert_eq!(geometric_mean([f64::NAN], 1e-16), None);
    }
}
