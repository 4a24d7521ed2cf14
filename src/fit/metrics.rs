//! Goodness of fit (the paper's Table 3: R², R, RMSE, MSE, MAE) and the parameters' standard
//! errors.

use super::problem::Problem;
use super::{FitError, Fitted, Sample};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Goodness of fit (paper Table 3). `rmse`, `mae` in s, `mse` in s²; the relative errors are
/// fractions of the computed `T_new` (not in Table 3: they show how a form does at short
/// periods, where errors of a few hundredths of a second are large).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    pub r2: f64,
    pub r: f64,
    pub rmse: f64,
    pub mse: f64,
    pub mae: f64,
    pub n: usize,
    /// Root mean square of `(predicted − observed)/observed`.
    #[serde(default = "nan")]
    pub relative_rmse: f64,
    /// Largest `|predicted − observed|/observed`.
    #[serde(default = "nan")]
    pub max_relative_error: f64,
}

fn nan() -> f64 {
    f64::NAN
}

impl Default for Metrics {
    fn default() -> Self {
        Self {
            r2: f64::NAN,
            r: f64::NAN,
            rmse: f64::NAN,
            mse: f64::NAN,
            mae: f64::NAN,
            n: 0,
            relative_rmse: f64::NAN,
            max_relative_error: f64::NAN,
        }
    }
}

/// Metrics of `predicted` against `observed`: `R² = 1 − SS_res/SS_tot`, `R` Pearson's
/// correlation of the two.
pub fn metrics(observed: &[f64], predicted: &[f64]) -> Metrics {
    let n = observed.len() as f64;
    let mo = observed.iter().sum::<f64>() / n;
    let mp = predicted.iter().sum::<f64>() / n;
    let (mut ss_res, mut ss_tot, mut abs, mut cov, mut vp) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut ss_rel, mut max_rel) = (0.0, 0.0f64);
    for (o, p) in observed.iter().zip(predicted) {
        let rel = (p - o) / o;
        ss_rel += rel * rel;
        max_rel = max_rel.max(rel.abs());
        ss_res += (o - p).powi(2);
        ss_tot += (o - mo).powi(2);
        abs += (o - p).abs();
        cov += (o - mo) * (p - mp);
        vp += (p - mp).powi(2);
    }
    let mse = ss_res / n;
    Metrics {
        r2: 1.0 - ss_res / ss_tot,
        r: cov / (ss_tot * vp).sqrt(),
        rmse: mse.sqrt(),
        mse,
        mae: abs / n,
        n: observed.len(),
        relative_rmse: (ss_rel / n).sqrt(),
        max_relative_error: max_rel,
    }
}

/// Above this condition number of the column-scaled Jacobian, `JᵀJ` counts as singular and
/// the standard errors are NaN: the Jacobian's entries carry round-off of about 1e-16 of their
/// size, which moves its smallest singular value by about 1e-16 of the largest, so at 1e10 the
/// smallest is known to about 1e-6 of itself and beyond that the errors lose their meaning fast.
pub const SINGULAR_CONDITION: f64 = 1e10;

/// The parameters' uncertainty at a least-squares optimum.
#[derive(Debug, Clone, PartialEq)]
pub struct Uncertainty {
    /// `√diag(s²·(JᵀJ)⁻¹)`, same units as the parameters; NaN where `JᵀJ` is singular.
    pub standard_errors: Vec<f64>,
    /// `s = √(SSE/(n − p))` of the (weighted) residuals: s, or a fraction of `T_p` for a form
    /// fitted to `T_new/T_p`.
    pub residual_std: f64,
    /// Condition number of the Jacobian with its columns scaled to unit norm (∞ when a column
    /// is zero).
    pub condition_number: f64,
}

/// Standard errors `√diag(s²·(JᵀJ)⁻¹)` from a Jacobian `j` (`n × p`) and the sum of squared
/// residuals `sse`, `s² = SSE/(n − p)`. Through the SVD of the column-scaled Jacobian
/// `J·D⁻¹ = U·Σ·Vᵀ`: `(JᵀJ)⁻¹ = D⁻¹·V·Σ⁻²·Vᵀ·D⁻¹`, which never forms `JᵀJ` (that would square
/// the condition number).
pub fn standard_errors(j: &DMatrix<f64>, sse: f64) -> Uncertainty {
    let (n, p) = j.shape();
    let dof = n.saturating_sub(p);
    let s2 = if dof > 0 { sse / dof as f64 } else { f64::NAN };
    let norms: Vec<f64> = (0..p).map(|c| j.column(c).norm()).collect();
    let nan = |cond: f64| Uncertainty {
        standard_errors: vec![f64::NAN; p],
        residual_std: s2.sqrt(),
        condition_number: cond,
    };
    if norms.iter().any(|v| !(v.is_finite() && *v > 0.0)) || dof == 0 {
        return nan(f64::INFINITY);
    }
    let mut scaled = j.clone();
    for (c, nrm) in norms.iter().enumerate() {
        scaled.column_mut(c).scale_mut(1.0 / nrm);
    }
    let svd = scaled.svd(false, true);
    let sv = &svd.singular_values;
    let (max, min) = (sv.max(), sv.min());
    let cond = if min > 0.0 { max / min } else { f64::INFINITY };
    if cond.is_nan() || cond > SINGULAR_CONDITION {
        return nan(cond);
    }
    let vt = svd.v_t.expect("asked for Vᵀ");
    let standard_errors = (0..p)
        .map(|a| {
            let var: f64 = (0..sv.len()).map(|i| (vt[(i, a)] / sv[i]).powi(2)).sum();
            (s2 * var).sqrt() / norms[a]
        })
        .collect();
    Uncertainty {
        standard_errors,
        residual_std: s2.sqrt(),
        condition_number: cond,
    }
}

/// The uncertainty of `fitted` on `data` (the Jacobian of the weighted residuals at its
/// parameters: for weights `1/T_p` the covariance of a fit whose errors scale with `T_p`).
pub fn uncertainty(fitted: &Fitted, data: &[Sample]) -> Result<Uncertainty, FitError> {
    let problem = Problem::new(fitted.form, data)?;
    let j = problem.jacobian(&fitted.params);
    Ok(standard_errors(&j, problem.sse(&fitted.params)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_by_hand() {
        // observed 1,2,3; predicted 1,2,4: SSres 1, SStot 2 → R² 0.5; MSE 1/3; MAE 1/3.
        let m = metrics(&[1.0, 2.0, 3.0], &[1.0, 2.0, 4.0]);
        assert!((m.r2 - 0.5).abs() < 1e-15);
        assert!((m.mse - 1.0 / 3.0).abs() < 1e-15 && (m.mae - 1.0 / 3.0).abs() < 1e-15);
        // Pearson r of (1,2,3) and (1,2,4): Σ products of deviations 3, sums of squares 2 and
        // 14/3 → 3/sqrt(2·14/3).
        assert!((m.r - 3.0 / (2.0f64 * 14.0 / 3.0).sqrt()).abs() < 1e-15);
        // Relative errors 0, 0, 1/3.
        assert!((m.max_relative_error - 1.0 / 3.0).abs() < 1e-15);
        assert!((m.relative_rmse - (1.0f64 / 27.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn standard_errors_of_a_straight_line() {
        // y = a + b·x by least squares: the textbook closed forms
        // SE(b) = s/√Sxx, SE(a) = s·√(1/n + x̄²/Sxx), s² = SSE/(n − 2); the Jacobian of the
        // residuals is the design matrix [1, x]. Agreement to 1e-12 relative (the SVD route
        // and the closed form round differently, both backward stable).
        let x: Vec<f64> = (0..12).map(|i| 0.3 + 0.17 * i as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, x)| 1.5 - 0.8 * x + 0.05 * ((i * 7 % 5) as f64 - 2.0))
            .collect();
        let n = x.len() as f64;
        let xm = x.iter().sum::<f64>() / n;
        let ym = y.iter().sum::<f64>() / n;
        let sxx: f64 = x.iter().map(|v| (v - xm).powi(2)).sum();
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - xm) * (b - ym)).sum();
        let b = sxy / sxx;
        let a = ym - b * xm;
        let sse: f64 = x.iter().zip(&y).map(|(u, v)| (v - a - b * u).powi(2)).sum();
        let s = (sse / (n - 2.0)).sqrt();
        let j = DMatrix::from_fn(x.len(), 2, |i, c| if c == 0 { 1.0 } else { x[i] });
        let u = standard_errors(&j, sse);
        let se_a = s * (1.0 / n + xm * xm / sxx).sqrt();
        let se_b = s / sxx.sqrt();
        assert!((u.standard_errors[0] / se_a - 1.0).abs() < 1e-12, "{u:?}");
        assert!((u.standard_errors[1] / se_b - 1.0).abs() < 1e-12, "{u:?}");
        assert!((u.residual_std / s - 1.0).abs() < 1e-14);
    }

    #[test]
    fn singular_jacobian_gives_nan() {
        // Two equal columns: JᵀJ singular.
        let j = DMatrix::from_fn(10, 3, |i, c| if c == 2 { i as f64 } else { 1.0 + i as f64 });
        let u = standard_errors(&j, 1.0);
        assert!(u.standard_errors.iter().all(|v| v.is_nan()), "{u:?}");
        assert!(u.condition_number > SINGULAR_CONDITION);
        // A zero column.
        let j = DMatrix::from_fn(10, 2, |i, c| if c == 1 { 0.0 } else { i as f64 });
        assert!(standard_errors(&j, 1.0).standard_errors[0].is_nan());
    }
}
