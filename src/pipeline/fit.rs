//! The fit stage: per zone, the design equation for `T_new` in every form of
//! [`crate::fit::Form`] (the paper's Eqs. 16–17 shape, the bounded logistic form, and the
//! damped form that can go below `T_p`). Every case with a finite `T_new` enters. For each form:
//! coefficients with standard errors; R², R, RMSE, MSE, MAE on all cases and
//! [`FOLDS`]-fold cross-validated; which solver converged; and the box check (finite and inside
//! `[½·T_p, 1.5·T_rigid]` on a box [`BOX_MARGIN`] beyond the grid). The recommended form is the
//! best cross-validated R² among the forms that pass the box check. Also the paper's own
//! published Eqs. 16–17 on our `T_new` (zones named III and V, two blocks) → `fit.h5` and
//! `fit.yaml` (layout in [`crate::store::fit`]). `docs/fit.md` explains the forms.
//!
//! Forms and folds are fitted in parallel, each fit sequentially: the results do not depend on
//! the thread count.
//!
//! A building study of one frame (one storey count, one `stack_floor`) is fitted as a one-storey
//! study, `T_p` being its bare first-mode period `T_1` (its `T_new`, the first mode's, over
//! `T_1`); `fit.yaml` names the frame. A study of several frames needs the building's own
//! features (issue 23, item 2) and is refused.
//!
//! Fingerprint: T_new's, the forms, the number of folds and the box.

use super::{Outcome, PipelineError, Session, StageId};
use crate::fit::extrapolation::{BOX_MARGIN, BOX_POINTS};
use crate::fit::{
    DesignBox, FitError, Form, Sample, check_box, cross_validate, feature_names, fit, metrics,
    paper_equation, uncertainty,
};
use crate::grid::Grid;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::{FitReport, FormFit, NotFitted, ZoneFit, write_fit};
use crate::study::tnew::samples;
use rayon::prelude::*;
use thiserror::Error;

/// Folds of the cross-validation.
pub const FOLDS: usize = 5;

#[derive(Debug, Error)]
pub enum FitStageError {
    #[error("zone {zone}: {form} form: {source}")]
    Fit {
        zone: String,
        form: &'static str,
        source: FitError,
    },
    #[error("zone {zone}: no form could be fitted ({reasons})")]
    NoForm { zone: String, reasons: String },
}

/// The fingerprint `fit.h5` and `fit.yaml` must carry.
pub fn fingerprint(tnew_fingerprint: &str) -> String {
    let forms: Vec<&str> = Form::ALL.iter().map(|f| f.name()).collect();
    hash_parts(&[
        tnew_fingerprint,
        &format!("folds={FOLDS}"),
        &format!("forms={}", forms.join(",")),
        &format!("box={BOX_MARGIN},{BOX_POINTS}"),
    ])
}

/// Names of a form's parameters, in [`crate::fit::Fitted::params`] order.
pub fn parameter_names(form: Form, features: &[String]) -> Vec<String> {
    form.parameter_names(features)
}

/// One form on one zone's data: fitted, cross-validated, its uncertainty and its box check;
/// `Ok(Err(_))` when the form does not apply to the data.
fn assess(
    form: Form,
    data: &[Sample],
    features: &[String],
    bx: &DesignBox,
) -> Result<Result<FormFit, NotFitted>, FitError> {
    let (all, cv) = rayon::join(|| fit(form, data), || cross_validate(form, data, FOLDS));
    let (all, cv) = match (all, cv) {
        (Err(e @ (FitError::NotApplicable { .. } | FitError::TooFew { .. })), _) => {
            return Ok(Err(NotFitted {
                form,
                reason: e.to_string(),
            }));
        }
        (all, cv) => (all?, cv?),
    };
    let observed: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
    let predicted: Vec<f64> = data.iter().map(|s| all.fitted.predict(s)).collect();
    let u = uncertainty(&all.fitted, data)?;
    let box_check = check_box(&all.fitted, bx, BOX_POINTS, BOX_MARGIN);
    Ok(Ok(FormFit {
        form,
        coefficients: form
            .parameter_names(features)
            .into_iter()
            .zip(all.fitted.params.iter().copied())
            .collect(),
        standard_errors: u.standard_errors,
        all_cases: metrics(&observed, &predicted),
        cross_validated: cv.metrics,
        equation: form.equation().to_string(),
        objective: form.objective().to_string(),
        residual_std: u.residual_std,
        condition_number: u.condition_number,
        solver: all.solver,
        cv_solvers: cv.solvers,
        box_check,
    }))
}

/// The recommended form and why: the best cross-validated R² among the forms that pass the box
/// check, else the best overall.
fn recommend(forms: &[FormFit]) -> (Form, String) {
    fn best<'a>(it: impl Iterator<Item = &'a FormFit>) -> Option<&'a FormFit> {
        it.max_by(|a, b| a.cross_validated.r2.total_cmp(&b.cross_validated.r2))
    }
    let passing = forms.iter().filter(|f| f.box_check.passed).count();
    if let Some(f) = best(forms.iter().filter(|f| f.box_check.passed)) {
        (
            f.form,
            format!(
                "best cross-validated R² ({:.4}) of the {passing} of {} forms that stay finite \
                 and inside [0.5·T_p, 1.5·T_rigid] on the box {:.0} % beyond the grid",
                f.cross_validated.r2,
                forms.len(),
                100.0 * BOX_MARGIN
            ),
        )
    } else {
        let f = best(forms.iter()).expect("at least one form");
        (
            f.form,
            format!(
                "no form stays finite and inside [0.5·T_p, 1.5·T_rigid] on the box {:.0} % \
                 beyond the grid; this is the best cross-validated R² ({:.4}) overall: do not \
                 use it outside the grid",
                100.0 * BOX_MARGIN,
                f.cross_validated.r2
            ),
        )
    }
}

/// The box of the box check: [`BOX_MARGIN`] beyond the grid's range of every feature.
fn design_box(grid: &Grid) -> DesignBox {
    let range = |v: &[f64]| {
        v.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(*x), hi.max(*x))
            })
    };
    let mut ranges = vec![range(&grid.periods_s)];
    ranges.extend(grid.mu.iter().map(|v| range(v)));
    ranges.extend(grid.alpha.iter().map(|v| range(v)));
    DesignBox::beyond(&ranges, BOX_MARGIN)
}

/// One line on a fitted form: its metrics, cross-validated ones, solver and box check.
fn describe(f: &FormFit) -> String {
    let (m, cv, b) = (&f.all_cases, &f.cross_validated, &f.box_check);
    format!(
        "{:<7} R² {:.4}  R {:.4}  RMSE {:.4} s  MAE {:.4} s  relative RMS {:.3}, max {:.2}   \
         ({FOLDS}-fold CV: R² {:.4}, RMSE {:.4} s)   {} {}   box {}",
        f.form.name(),
        m.r2,
        m.r,
        m.rmse,
        m.mae,
        m.relative_rmse,
        m.max_relative_error,
        cv.r2,
        cv.rmse,
        match f.solver.method {
            crate::fit::Method::TrustRegion => "trust region",
            crate::fit::Method::NelderMead => "Nelder–Mead fallback",
            crate::fit::Method::ProjectedNelderMead => "Nelder–Mead (projected) fallback",
        },
        if f.solver.converged {
            "converged"
        } else {
            "NOT converged"
        },
        if b.passed {
            format!(
                "passed (T_new/T_p ≥ {:.3}, T_new/T_rigid ≤ {:.3})",
                b.min_t_new_over_t_p, b.max_t_new_over_t_rigid
            )
        } else {
            format!(
                "FAILED at {} of {} points ({} not finite)",
                b.outside + b.non_finite,
                b.points,
                b.non_finite
            )
        }
    )
}

/// Builds `fit.h5` and `fit.yaml`.
pub fn build(s: &Session) -> Result<Outcome, PipelineError> {
    let start = std::time::Instant::now();
    let study = &s.study;
    let me = StageId::Fit;
    let grid = study.grid(me)?;
    let n = grid.blocks();
    let features = feature_names(n);
    let bx = design_box(grid);
    let mut zone_data = Vec::new();
    for zc in &study.cfg.zones {
        let t = super::tnew::read_zone(study, &zc.name)?;
        let t_rigid: Vec<f64> = t.vars.t_rigid.iter().copied().collect();
        let t_new: Vec<f64> = t.vars.t_new.iter().copied().collect();
        zone_data.push((zc.name.clone(), samples(grid, &t_rigid, &t_new)));
    }
    let jobs: Vec<(usize, Form)> = (0..zone_data.len())
        .flat_map(|z| Form::ALL.map(|f| (z, f)))
        .collect();
    let results: Vec<_> = jobs
        .par_iter()
        .map(|&(z, form)| {
            assess(form, &zone_data[z].1, &features, &bx).map_err(|source| FitStageError::Fit {
                zone: zone_data[z].0.clone(),
                form: form.name(),
                source,
            })
        })
        .collect();
    let mut results = results.into_iter();
    let mut zones = Vec::new();
    for (zone, data) in &zone_data {
        let mut forms = Vec::new();
        let mut not_fitted = Vec::new();
        for _ in Form::ALL {
            match results.next().expect("one result per job")? {
                Ok(f) => forms.push(f),
                Err(nf) => not_fitted.push(nf),
            }
        }
        for f in &forms {
            s.reporter
                .info(me, &format!("zone {zone}: {}", describe(f)));
        }
        for nf in &not_fitted {
            s.reporter.warn(
                me,
                &format!("zone {zone}: {} form: {}", nf.form.name(), nf.reason),
            );
        }
        if forms.is_empty() {
            return Err(FitStageError::NoForm {
                zone: zone.clone(),
                reasons: not_fitted
                    .iter()
                    .map(|n| n.reason.as_str())
                    .collect::<Vec<_>>()
                    .join("; "),
            }
            .into());
        }
        let observed: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
        let published: Option<Vec<f64>> = data.iter().map(|s| paper_equation(zone, &s.x)).collect();
        let published = published.map(|p| metrics(&observed, &p));
        if let Some(m) = &published {
            s.reporter.info(
                me,
                &format!(
                    "zone {zone}: published Eq. {} on our T_new: R² {:.4}  RMSE {:.4} s",
                    if zone == "III" { 16 } else { 17 },
                    m.r2,
                    m.rmse
                ),
            );
        }
        let (recommended, recommendation) = recommend(&forms);
        s.reporter.info(
            me,
            &format!(
                "zone {zone}: recommended {}: {recommendation}",
                recommended.name()
            ),
        );
        zones.push(ZoneFit {
            zone: zone.clone(),
            cases: data.len(),
            forms,
            recommended,
            published,
            recommendation,
            not_fitted,
        });
    }
    let report = FitReport {
        slidestack_version: env!("CARGO_PKG_VERSION").to_string(),
        fingerprint: study.fingerprint(me)?.to_string(),
        features,
        folds: FOLDS,
        building: (study.building())
            .and_then(|b| study.cfg.frame(b, 0))
            .map(|f| f.to_string()),
        zones,
    };
    let (h5, yaml) = (study.path(me.output()), study.path("fit.yaml"));
    write_fit(&h5, &yaml, &report)?;
    s.reporter.info(
        me,
        &format!(
            "{} zones × {} forms, {FOLDS}-fold cross-validated, in {:.1} s",
            report.zones.len(),
            Form::ALL.len(),
            start.elapsed().as_secs_f64()
        ),
    );
    Ok(Outcome::Wrote(vec![h5, yaml]))
}
