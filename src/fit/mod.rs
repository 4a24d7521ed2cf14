//! The design equation for `T_new` (paper Eqs. 16–17 and forms that improve on them):
//!
//! * [`forms`]: the physics, each form's prediction and analytic Jacobian;
//! * `problem`: one form against one data set as nonlinear least squares;
//! * [`solver`]: the machinery, argmin's trust region on the Gauss–Newton model from several
//!   starts, Nelder–Mead as a fallback;
//! * [`mod@metrics`]: goodness of fit and the parameters' standard errors;
//! * [`extrapolation`]: the check that a fitted form stays physical beyond the grid;
//! * [`published`]: the paper's own Eqs. 16–17.
//!
//! `docs/fit.md` explains the forms and why the recommended one is chosen.

pub mod extrapolation;
pub mod forms;
pub mod metrics;
mod problem;
pub mod published;
pub mod solver;

pub use extrapolation::{BoxCheck, DesignBox, check_box};
pub use forms::Form;
pub use metrics::{Metrics, Uncertainty, metrics, uncertainty};
pub use published::{PaperEquation, paper_equation};
pub use solver::{Method, SolverReport};

use rayon::prelude::*;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum FitError {
    #[error("too few cases to fit: {cases} (the form needs at least {needed})")]
    TooFew { cases: usize, needed: usize },
    #[error("a case has {got} features, the others {expected}")]
    Features { expected: usize, got: usize },
    #[error("the {form} form does not apply: {reason}")]
    NotApplicable { form: &'static str, reason: String },
    #[error("optimiser: {0}")]
    Solver(String),
}

/// The names of the features of a stack of `blocks` blocks, in [`features`] order.
pub fn feature_names(blocks: usize) -> Vec<String> {
    let mut names = vec!["T_p".to_string()];
    names.extend((1..=blocks).map(|i| format!("mu_{i}")));
    names.extend((1..=blocks).map(|i| format!("alpha_{i}")));
    names
}

/// The features of a structure of period `period_s` (s) and its stack: `(T_p, μ_1 … μ_n,
/// α_1 … α_n)`.
pub fn features(period_s: f64, alpha: &[f64], mu: &[f64]) -> Vec<f64> {
    let mut x = vec![period_s];
    x.extend(mu);
    x.extend(alpha);
    x
}

/// The feature of a building study of several frames giving its storey count `N`.
pub const STOREYS_FEATURE: &str = "N";
/// The feature giving the relative height `z = h/H` of the floor carrying the stack
/// ([`crate::study::building::Frame::stack_height_ratio`]).
pub const HEIGHT_FEATURE: &str = "z_stack";

/// The features of a building study of several frames (docs/fit.md, "A study over buildings"):
/// the stack's, `T_p` being the bare building's first-mode period `T_1`, then `N` when the
/// study has several storey counts and `z_stack` when the stack's relative height varies
/// over the frames. A feature that is one value for every case is left out: it would only
/// repeat the intercept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct BuildingFeatures {
    pub blocks: usize,
    pub storeys: bool,
    pub height: bool,
}

impl BuildingFeatures {
    /// The names, in [`Self::features`] order; the first is `T_1`.
    pub fn names(self) -> Vec<String> {
        let mut names = feature_names(self.blocks);
        names[0] = "T_1".into();
        if self.storeys {
            names.push(STOREYS_FEATURE.into());
        }
        if self.height {
            names.push(HEIGHT_FEATURE.into());
        }
        names
    }

    /// The features named `names` for stacks of `blocks` blocks, if they are a building
    /// study's.
    pub fn of_names(names: &[String], blocks: usize) -> Option<Self> {
        [(false, false), (true, false), (false, true), (true, true)]
            .into_iter()
            .map(|(storeys, height)| Self {
                blocks,
                storeys,
                height,
            })
            .find(|f| f.names() == names)
    }

    /// `(T_1, μ_1 … μ_n, α_1 … α_n[, N][, z_stack])`, `T_1` in s.
    pub fn features(
        self,
        period_s: f64,
        alpha: &[f64],
        mu: &[f64],
        storeys: usize,
        z_stack: f64,
    ) -> Vec<f64> {
        let mut x = features(period_s, alpha, mu);
        if self.storeys {
            x.push(storeys as f64);
        }
        if self.height {
            x.push(z_stack);
        }
        x
    }
}

/// One case: features, its two physical limits and the computed `T_new`.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// `(T_p, μ_1 … μ_n, α_1 … α_n)`, `T_p` in s.
    pub x: Vec<f64>,
    pub t_rigid_s: f64,
    pub t_new_s: f64,
}

impl Sample {
    pub fn t_p_s(&self) -> f64 {
        self.x[0]
    }
}

/// A fitted form.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Fitted {
    pub form: Form,
    /// In the order of [`Form::parameter_names`].
    pub params: Vec<f64>,
}

impl Fitted {
    /// `T_new`, s.
    pub fn predict(&self, s: &Sample) -> f64 {
        self.form.predict(&self.params, s)
    }
}

/// A least-squares fit and how the solver went.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    pub fitted: Fitted,
    pub solver: SolverReport,
}

/// Fits `form` to `data` by least squares (`solver` module doc).
pub fn fit(form: Form, data: &[Sample]) -> Result<Solution, FitError> {
    let problem = problem::Problem::new(form, data)?;
    let (params, solver) = solver::solve(&problem, &form.starts(problem.k))?;
    Ok(Solution {
        fitted: Fitted { form, params },
        solver,
    })
}

/// Cross-validated metrics and how the solver went on each fold.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossValidation {
    pub metrics: Metrics,
    pub solvers: Vec<SolverReport>,
}

/// `k`-fold cross-validated metrics: case `i` is in fold `i mod k`; each fold is predicted by
/// the form fitted (the same way as [`fit`]) to the others.
pub fn cross_validate(form: Form, data: &[Sample], k: usize) -> Result<CrossValidation, FitError> {
    // Folds are independent fits, each sequential: in parallel, the result does not depend on
    // the thread count.
    let fitted = (0..k)
        .into_par_iter()
        .map(|fold| {
            let train: Vec<Sample> = data
                .iter()
                .enumerate()
                .filter(|(i, _)| i % k != fold)
                .map(|(_, s)| s.clone())
                .collect();
            fit(form, &train)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let predicted: Vec<f64> = data
        .iter()
        .enumerate()
        .map(|(i, s)| fitted[i % k].fitted.predict(s))
        .collect();
    let observed: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
    Ok(CrossValidation {
        metrics: metrics(&observed, &predicted),
        solvers: fitted.into_iter().map(|f| f.solver).collect(),
    })
}
