//! The forms of the design equation for `T_new` (s): their predictions, their analytic
//! derivatives with respect to the parameters, and where the solver starts them.
//!
//! Features of a case: `x = (T_p, μ_1 … μ_n, α_1 … α_n)` (the paper's order for `n = 2`:
//! `T_p, μ_1, μ_2, α_1, α_2`), `T_p` in s; `T_rigid = T_p·√(1 + Σα)` (paper Eqs. 10–13).
//! `σ(z) = 1/(1 + e^{−z})` is the logistic function.
//!
//! * [`Form::Paper`]: the shape of the paper's Eqs. 16–17, `T_new = a·x + b·e^{c·x + d} + e`.
//!   Only `b·e^d` is identifiable (docs/model.md, "The design equations"), so it is fitted as `T_new = a·x + B·e^{c·x} + e`.
//!   Nothing keeps it between the physical limits.
//! * [`Form::Bounded`]: `T_new = T_p + (T_rigid − T_p)·σ(w·x + w₀)`: always between the bare
//!   period and the rigidly attached one (the limits `μ → 0` and `μ → ∞`), so it cannot
//!   represent `T_new < T_p`, which friction damping produces (2,940 of the 7,156 sliding cases
//!   of Zone V on the paper grid).
//! * [`Form::Damped`]: `T_new = T_p·(1 − ½·σ(v·z + v₀)) + (T_rigid − T_p)·σ(w·z + w₀)` with
//!   regressors `z = (ln x, (ln T_p)²)`: the bounded form on the logarithms of the features,
//!   less a friction-damping term that can take up to half of `T_p` away; the square of
//!   `ln T_p` lets either term rise and fall with the period (the damping is strongest near the
//!   spectrum's corner period). For every input and any parameters `½·T_p ≤ T_new ≤ T_rigid`
//!   (strictly inside in exact arithmetic): bounded by construction. It is fitted to the
//!   elongation ratio `T_new/T_p` (least squares weighted by `1/T_p`, [`Form::weight`]), so a
//!   short-period structure counts as much as a long-period one.
//!
//! * [`Form::Fraction`]: not a form of `T_new` but of a fraction in `[0, 1]`, a building's
//!   effective live-load fraction `λ` (docs/model.md, "A study over buildings"):
//!   `λ = σ(w·z + w₀)`, `z = (ln x, (ln T_p)²)` as for the damped form; in `[0, 1]` by
//!   construction. Its "`T_new`" in a [`Sample`] is the fraction, and `T_p`, `T_rigid` are not
//!   used. Not in [`Form::FOR_T_NEW`].
//!
//! `docs/fit.md` tells why this form, these features and this objective, with the numbers
//! measured on the paper grid.

use super::Sample;
use serde::{Deserialize, Serialize};

/// A form of the design equation for `T_new`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Form {
    Paper,
    Bounded,
    Damped,
    Fraction,
}

/// Largest fraction of `T_p` the friction-damping term of [`Form::Damped`] can take away.
pub const DAMPING_DEPTH: f64 = 0.5;

/// `σ(z)` and `σ'(z) = σ(z)·(1 − σ(z))`, without overflow for any `z`.
fn logistic(z: f64) -> (f64, f64) {
    let e = (-z.abs()).exp();
    let (s, one_minus) = if z >= 0.0 {
        (1.0 / (1.0 + e), e / (1.0 + e))
    } else {
        (e / (1.0 + e), 1.0 / (1.0 + e))
    };
    (s, s * one_minus)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Form {
    /// The forms fitted to `T_new`, in the order the fit stage reports them ([`Form::Fraction`]
    /// is `λ`'s).
    pub const FOR_T_NEW: [Form; 3] = [Form::Paper, Form::Bounded, Form::Damped];

    pub fn name(self) -> &'static str {
        match self {
            Form::Paper => "paper",
            Form::Bounded => "bounded",
            Form::Damped => "damped",
            Form::Fraction => "fraction",
        }
    }

    /// The equation, for people.
    pub fn equation(self) -> &'static str {
        match self {
            Form::Paper => "T_new = a·x + B·exp(c·x) + e  (paper Eqs. 16–17 with B = b·e^d)",
            Form::Bounded => "T_new = T_p + (T_rigid − T_p)·σ(w·x + w_0)",
            Form::Damped => {
                "T_new = T_p·(1 − σ(v·z + v_0)/2) + (T_rigid − T_p)·σ(w·z + w_0), \
                 z = (ln x, (ln T_p)²)"
            }
            Form::Fraction => "λ = σ(w·z + w_0), z = (ln x, (ln T_p)²)",
        }
    }

    /// Whether every input gives a `T_new` inside `[½·T_p, T_rigid]` (for `T_rigid ≥ T_p`),
    /// whatever the finite parameters.
    pub fn bounded_by_construction(self) -> bool {
        matches!(self, Form::Bounded | Form::Damped | Form::Fraction)
    }

    /// What the least squares minimise, for people.
    pub fn objective(self) -> &'static str {
        match self {
            Form::Paper | Form::Bounded => "sum of squared errors of T_new (s²)",
            Form::Damped => "sum of squared errors of T_new/T_p (weights 1/T_p)",
            Form::Fraction => "sum of squared errors of λ",
        }
    }

    /// The weight of a case of bare period `t_p_s` in the least squares: 1, or `1/T_p` for
    /// [`Form::Damped`] (errors of `T_new/T_p`).
    pub fn weight(self, t_p_s: f64) -> f64 {
        match self {
            Form::Paper | Form::Bounded | Form::Fraction => 1.0,
            Form::Damped => 1.0 / t_p_s,
        }
    }

    /// Parameters for `k` features.
    pub fn parameter_count(self, k: usize) -> usize {
        match self {
            Form::Paper => 2 * k + 2,
            Form::Bounded => k + 1,
            Form::Damped => 2 * k + 4,
            Form::Fraction => k + 2,
        }
    }

    /// Names of the parameters, in [`crate::fit::Fitted::params`] order: paper
    /// `a_1 … a_k, c_1 … c_k, B, e`; bounded `w_1 … w_k, w_0`; damped
    /// `w_ln_1 … w_ln_k, w_ln_T_p_sq, w_0, v_ln_1 … v_ln_k, v_ln_T_p_sq, v_0` (weights of `ln x`
    /// and of `(ln T_p)²`).
    pub fn parameter_names(self, features: &[String]) -> Vec<String> {
        let each = |prefix: &str, log: bool| -> Vec<String> {
            features
                .iter()
                .map(|f| {
                    if log {
                        format!("{prefix}_ln_{f}")
                    } else {
                        format!("{prefix}_{f}")
                    }
                })
                .collect()
        };
        match self {
            Form::Paper => {
                let mut v = each("a", false);
                v.extend(each("c", false));
                v.extend(["B (= b·e^d)".to_string(), "e".to_string()]);
                v
            }
            Form::Bounded => {
                let mut v = each("w", false);
                v.push("w_0".into());
                v
            }
            Form::Damped => {
                let square = format!("ln_{}_sq", features.first().map_or("T_p", |f| f));
                let mut v = each("w", true);
                v.extend([format!("w_{square}"), "w_0".into()]);
                v.extend(each("v", true));
                v.extend([format!("v_{square}"), "v_0".into()]);
                v
            }
            Form::Fraction => {
                let square = format!("ln_{}_sq", features.first().map_or("T_p", |f| f));
                let mut v = each("w", true);
                v.extend([format!("w_{square}"), "w_0".into()]);
                v
            }
        }
    }

    /// The regressors of the linear predictors for features `x`: `x` itself, or
    /// `(ln x, (ln T_p)²)` for [`Form::Damped`] (NaN or −∞ where a feature is not positive).
    pub fn regressors(self, x: &[f64]) -> Vec<f64> {
        match self {
            Form::Paper | Form::Bounded => x.to_vec(),
            Form::Damped | Form::Fraction => {
                let mut z: Vec<f64> = x.iter().map(|v| v.ln()).collect();
                z.push(z[0] * z[0]);
                z
            }
        }
    }

    /// `T_new` (s) with parameters `p` at regressors `z` ([`Form::regressors`]) of a case with
    /// periods `t_p_s` and `t_rigid_s`; when `grad` is given, it receives `∂T_new/∂p` (s per
    /// unit parameter), the case's row of the Jacobian.
    pub fn evaluate(
        self,
        p: &[f64],
        z: &[f64],
        t_p_s: f64,
        t_rigid_s: f64,
        grad: Option<&mut [f64]>,
    ) -> f64 {
        let k = z.len();
        match self {
            Form::Paper => {
                let (a, rest) = p.split_at(k);
                let (c, be) = rest.split_at(k);
                let ex = dot(c, z).exp();
                if let Some(g) = grad {
                    g[..k].copy_from_slice(z);
                    for j in 0..k {
                        g[k + j] = be[0] * z[j] * ex;
                    }
                    g[2 * k] = ex;
                    g[2 * k + 1] = 1.0;
                }
                dot(a, z) + be[0] * ex + be[1]
            }
            Form::Bounded => {
                let span = t_rigid_s - t_p_s;
                let (s, ds) = logistic(dot(&p[..k], z) + p[k]);
                if let Some(g) = grad {
                    for j in 0..k {
                        g[j] = span * ds * z[j];
                    }
                    g[k] = span * ds;
                }
                t_p_s + span * s
            }
            Form::Damped => {
                let span = t_rigid_s - t_p_s;
                let (w, v) = p.split_at(k + 1);
                let (s1, ds1) = logistic(dot(&w[..k], z) + w[k]);
                let (s2, ds2) = logistic(dot(&v[..k], z) + v[k]);
                if let Some(g) = grad {
                    let damp = -DAMPING_DEPTH * t_p_s * ds2;
                    for j in 0..k {
                        g[j] = span * ds1 * z[j];
                        g[k + 1 + j] = damp * z[j];
                    }
                    g[k] = span * ds1;
                    g[2 * k + 1] = damp;
                }
                t_p_s * (1.0 - DAMPING_DEPTH * s2) + span * s1
            }
            Form::Fraction => {
                let (s, ds) = logistic(dot(&p[..k], z) + p[k]);
                if let Some(g) = grad {
                    for j in 0..k {
                        g[j] = ds * z[j];
                    }
                    g[k] = ds;
                }
                s
            }
        }
    }

    /// `T_new` (s) of case `s` with parameters `p` (layout in [`Form::parameter_names`]).
    pub fn predict(self, p: &[f64], s: &Sample) -> f64 {
        self.evaluate(p, &self.regressors(&s.x), s.t_p_s(), s.t_rigid_s, None)
    }

    /// Where the solver starts, for `k` features (each start is probed, the best run to
    /// convergence; see `docs/fit.md`). The paper form's linear parameters are then filled in
    /// by least squares.
    pub fn starts(self, k: usize) -> Vec<Vec<f64>> {
        match self {
            // Exponent weights only (`c`, all features alike); the rest is filled in.
            Form::Paper => [-0.5, 0.5]
                .iter()
                .map(|&c| {
                    let mut p = vec![0.0; 2 * k + 2];
                    p[k..2 * k].fill(c);
                    p
                })
                .collect(),
            // Halfway between the limits.
            Form::Bounded => vec![vec![0.0; k + 1]],
            // Flat predictors (every weight zero) at six points of (w_0, v_0): the two
            // logistic terms can trade roles, which gives the sum of squares several local
            // minima (docs/fit.md). Most start near the rigid limit with little damping
            // (σ(4) = 0.98, σ(−2) = 0.12), as most cases of a study barely slide.
            Form::Damped => [
                (4.0, -2.0),
                (4.0, 0.0),
                (2.0, 0.0),
                (0.0, -4.0),
                (-2.0, -2.0),
                (2.0, 2.0),
            ]
            .iter()
            .map(|&(w0, v0)| {
                let mut p = vec![0.0; 2 * k + 4];
                p[k + 1] = w0;
                p[2 * k + 3] = v0;
                p
            })
            .collect(),
            // Flat at λ = σ(w_0): 0.88, 0.5, 0.12.
            Form::Fraction => [2.0, 0.0, -2.0]
                .iter()
                .map(|&w0| {
                    let mut p = vec![0.0; k + 2];
                    p[k + 1] = w0;
                    p
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logistic_is_stable_and_matches_its_definition() {
        for z in [-800.0, -30.0, -1.5, 0.0, 0.3, 12.0, 800.0] {
            let (s, ds) = logistic(z);
            assert!(s.is_finite() && ds.is_finite() && (0.0..=1.0).contains(&s));
            if f64::abs(z) < 30.0 {
                // Direct formula where it does not overflow: agreement to a few ulps.
                let direct = 1.0 / (1.0 + (-z).exp());
                assert!((s - direct).abs() < 1e-15, "{z}");
                assert!((ds - direct * (1.0 - direct)).abs() < 1e-15, "{z}");
            }
        }
        assert_eq!(logistic(800.0).0, 1.0);
        assert_eq!(logistic(-800.0).0, 0.0);
    }

    #[test]
    fn names_match_counts() {
        let f: Vec<String> = ["T_p", "mu_1", "alpha_1"].map(String::from).to_vec();
        for form in Form::FOR_T_NEW.into_iter().chain([Form::Fraction]) {
            assert_eq!(form.parameter_names(&f).len(), form.parameter_count(3));
            for s in form.starts(3) {
                assert_eq!(s.len(), form.parameter_count(3));
            }
        }
    }
}
