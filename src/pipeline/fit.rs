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
//! `T_1`); `fit.yaml` names the frame. A study of several frames is fitted over its distinct
//! frames (floor 1, the roof and every floor of one storey are one building) with the building's
//! features (`N`, `z_stack`: [`BuildingFeatures`]), each case's `T_rigid`
//! its frame's `T_1,rigid`; then per frame the recommended form's metrics beside those of the
//! one-storey equation (every form fitted to the study's one-storey frame, if it has one, the
//! best recommended as for a one-storey study) and the paper's: where the one-storey equations
//! hold and where the higher modes make them fail (docs/fit.md, "A study over buildings").
//!
//! Fingerprint: T_new's, the forms, the number of folds and the box.

use super::{PipelineError, Session, StageId, StageOutcome};
use crate::fit::extrapolation::{BOX_MARGIN, BOX_POINTS};
use crate::fit::{
    BuildingFeatures, DesignBox, FitError, Form, Metrics, Sample, check_box, cross_validate,
    feature_names, fit, metrics, paper_equation, uncertainty,
};
use crate::grid::Grid;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::{FitReport, FormFit, FrameFit, NotFitted, ZoneFit, write_fit};
use crate::study::building::{Frame, fit_features, repeats};
use crate::study::tnew::{building_samples, samples};
use rayon::prelude::*;
use std::collections::HashMap;
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

/// The fraction a designer counts, `max(λ, 0)`, of every stored `λ`: the fraction form is
/// fitted to it (docs/fit.md). A `λ` below 0 says that the sliding stack lowers the base shear
/// below the bare building's, and `tnew.h5` keeps it whole; a code counts no less than none of
/// the live load.
fn design_fractions(lambda: &ndarray::ArrayD<f64>) -> Vec<f64> {
    lambda
        .iter()
        .map(|&l| if l.is_nan() { l } else { l.max(0.0) })
        .collect()
}

/// The fingerprint `fit.h5` and `fit.yaml` must carry (`building`: of a building study, which
/// also fits `λ`).
pub fn fingerprint(tnew_fingerprint: &str, building: bool) -> String {
    let forms: Vec<&str> = Form::FOR_T_NEW.iter().map(|f| f.name()).collect();
    let mut parts = vec![
        tnew_fingerprint.to_string(),
        format!("folds={FOLDS}"),
        format!("forms={}", forms.join(",")),
        format!("box={BOX_MARGIN},{BOX_POINTS}"),
    ];
    if building {
        parts.push(format!("lambda={}", Form::Fraction.name()));
    }
    let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
    StageId::Fit.fingerprint(&hash_parts(&parts))
}

/// The least number of cases any form can be fitted to and [`FOLDS`]-fold cross-validated
/// on, with `features` features: the whole fit and every fold's training cases need three
/// per parameter ([`crate::fit`]).
pub fn cases_needed(features: usize) -> usize {
    let least = |m: usize| {
        (1..)
            .find(|&n: &usize| n - n.div_ceil(FOLDS) >= 3 * m)
            .expect("the training cases grow with n")
    };
    (Form::FOR_T_NEW.iter())
        .map(|f| least(f.parameter_count(features)))
        .min()
        .expect("there are forms")
}

/// The cases a fit of a study of `grid` over `frames` (empty on one storey) has at most (the
/// distinct frames' cases; those whose `T_new` is not finite are left out later) and the least
/// it needs ([`cases_needed`]), from the config alone.
pub fn case_count(grid: &Grid, frames: &[Frame]) -> (usize, usize) {
    let n = grid.blocks();
    let features = fit_features(n, frames).map_or_else(|| feature_names(n), |b| b.names());
    let distinct = repeats(frames).iter().filter(|r| !**r).count().max(1);
    (grid.cases() * distinct, cases_needed(features.len()))
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

/// The box of the box check: [`BOX_MARGIN`] beyond the grid's range of every feature; for a
/// building study of several frames also beyond its range of `N` and `z_stack`, but no lower
/// than one storey and no higher than the roof.
fn design_box(grid: &Grid, building: Option<(BuildingFeatures, &[Frame])>) -> DesignBox {
    let range = |v: &mut dyn Iterator<Item = f64>| {
        v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
    };
    let mut ranges = vec![range(&mut grid.periods_s.iter().copied())];
    ranges.extend(grid.mu.iter().map(|v| range(&mut v.iter().copied())));
    ranges.extend(grid.alpha.iter().map(|v| range(&mut v.iter().copied())));
    let k = ranges.len();
    let Some((features, frames)) = building else {
        return DesignBox::beyond(&ranges, BOX_MARGIN);
    };
    if features.storeys {
        ranges.push(range(&mut frames.iter().map(|f| f.storeys() as f64)));
    }
    if features.height {
        ranges.push(range(&mut frames.iter().map(Frame::stack_height_ratio)));
    }
    let mut bx = DesignBox::beyond(&ranges, BOX_MARGIN);
    bx.building = ranges.len() - k;
    let mut j = k;
    if features.storeys {
        bx.lower[j] = bx.lower[j].max(1.0);
        j += 1;
    }
    if features.height {
        bx.upper[j] = bx.upper[j].min(1.0);
    }
    bx
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

/// One zone's samples: the cases fitted, every case with a `T_new` (for a building study of
/// several frames, of its distinct frames, with the building's features); a building study's
/// every case with its frame's index; and its one-storey frame's cases with the one-storey
/// features.
struct ZoneData {
    zone: String,
    data: Vec<Sample>,
    every: Vec<(usize, Sample)>,
    one_storey: Vec<Sample>,
    /// A building study's `λ` as the samples' "`T_new`": the cases fitted, and every case
    /// with its frame's index.
    lambda: Vec<Sample>,
    lambda_every: Vec<(usize, Sample)>,
}

/// The first `1 + 2n` features of a building sample: the one-storey equation's (`T_p = T_1`).
fn stack_sample(s: &Sample, blocks: usize) -> Sample {
    Sample {
        x: s.x[..1 + 2 * blocks].to_vec(),
        ..s.clone()
    }
}

/// The recommended building equation, the one-storey equation and the paper's on each frame's
/// cases.
fn frame_fits(
    z: &ZoneData,
    frames: &[Frame],
    blocks: usize,
    building: &FormFit,
    one_storey: Option<&FormFit>,
    lambda: Option<&FormFit>,
) -> Vec<FrameFit> {
    let (building, one_storey) = (building.fitted(), one_storey.map(FormFit::fitted));
    let lambda = lambda.map(FormFit::fitted);
    (frames.iter().enumerate())
        .map(|(f, frame)| {
            let cases: Vec<&Sample> = (z.every.iter())
                .filter(|(g, _)| *g == f)
                .map(|(_, s)| s)
                .collect();
            let observed: Vec<f64> = cases.iter().map(|s| s.t_new_s).collect();
            let of = |p: &dyn Fn(&Sample) -> Option<f64>| -> Option<Metrics> {
                let predicted: Option<Vec<f64>> = cases.iter().map(|s| p(s)).collect();
                predicted.map(|p| metrics(&observed, &p))
            };
            FrameFit {
                frame: frame.to_string(),
                cases: cases.len(),
                building: of(&|s| Some(building.predict(s))).expect("every case predicted"),
                one_storey: (one_storey.as_ref())
                    .and_then(|o| of(&|s| Some(o.predict(&stack_sample(s, blocks))))),
                published: of(&|s| paper_equation(&z.zone, &s.x[..1 + 2 * blocks])),
                lambda: lambda.as_ref().map(|l| {
                    let (observed, predicted): (Vec<f64>, Vec<f64>) = (z.lambda_every.iter())
                        .filter(|(g, _)| *g == f)
                        .map(|(_, s)| (s.t_new_s, l.predict(s)))
                        .unzip();
                    metrics(&observed, &predicted)
                }),
            }
        })
        .collect()
}

/// One fit of the stage: a form on a zone's cases, or on its one-storey frame's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct FitJob {
    zone: usize,
    form: Form,
    one_storey: bool,
}

/// What one [`FitJob`] gave.
type JobResult = Result<Result<FormFit, NotFitted>, FitStageError>;

/// Zone `z`'s forms (on its one-storey frame's cases with `one_storey`) from the stage's
/// `results`, in [`Form::FOR_T_NEW`] order: the fitted ones (each described through
/// `reporter`) and the ones that do not apply.
fn collect_forms(
    s: &Session,
    (z, zone): (usize, &str),
    one_storey: bool,
    results: &mut HashMap<FitJob, JobResult>,
) -> Result<(Vec<FormFit>, Vec<NotFitted>), PipelineError> {
    let me = StageId::Fit;
    let what = if one_storey { ", one storey" } else { "" };
    let mut forms = Vec::new();
    let mut not_fitted = Vec::new();
    for form in Form::FOR_T_NEW {
        let job = FitJob {
            zone: z,
            form,
            one_storey,
        };
        match results.remove(&job).expect("one result per job")? {
            Ok(f) => forms.push(f),
            Err(nf) => not_fitted.push(nf),
        }
    }
    for f in &forms {
        s.reporter
            .info(me, &format!("zone {zone}{what}: {}", describe(f)));
    }
    for nf in &not_fitted {
        s.reporter.warn(
            me,
            &format!("zone {zone}{what}: {} form: {}", nf.form.name(), nf.reason),
        );
    }
    if forms.is_empty() {
        return Err(FitStageError::NoForm {
            zone: zone.to_string(),
            reasons: not_fitted
                .iter()
                .map(|n| n.reason.as_str())
                .collect::<Vec<_>>()
                .join("; "),
        }
        .into());
    }
    Ok((forms, not_fitted))
}

/// Builds `fit.h5` and `fit.yaml`.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let start = std::time::Instant::now();
    let study = &s.study;
    let me = StageId::Fit;
    let grid = study.grid(me)?;
    let n = grid.blocks();
    let frames: Vec<Frame> = study.frames().into_iter().flatten().collect();
    let building = fit_features(n, &frames);
    let features = building.map_or_else(|| feature_names(n), BuildingFeatures::names);
    let one_storey_features = feature_names(n);
    let bx = design_box(grid, building.map(|f| (f, frames.as_slice())));
    let one_storey_bx = design_box(grid, None);
    // A building study's one-storey frame, where the one-storey equation is fitted (its
    // stack floors are all the same building).
    let one_storey_frame = building.and(frames.iter().position(|f| f.storeys() == 1));
    let repeats = repeats(&frames);
    let mut zone_data = Vec::new();
    for zc in &study.cfg.zones {
        let t = super::files::tnew_zone(study, &zc.name)?;
        let t_rigid: Vec<f64> = t.vars.t_rigid.iter().copied().collect();
        let t_new: Vec<f64> = t.vars.t_new.iter().copied().collect();
        let z = match building {
            None => {
                // A one-storey study has no λ; a building study of one frame fits it with the
                // one-storey features.
                let lambda: Vec<Sample> = (t.lambda.as_ref()).map_or_else(Vec::new, |l| {
                    let lambda = design_fractions(&l.lambda);
                    samples(grid, &vec![1.0; lambda.len()], &lambda)
                });
                ZoneData {
                    zone: zc.name.clone(),
                    data: samples(grid, &t_rigid, &t_new),
                    every: Vec::new(),
                    one_storey: Vec::new(),
                    lambda_every: lambda.iter().map(|s| (0, s.clone())).collect(),
                    lambda,
                }
            }
            Some(f) => {
                // The cases of the distinct frames, the ones fitted.
                let distinct = |every: &[(usize, Sample)]| -> Vec<Sample> {
                    (every.iter())
                        .filter(|(f, _)| !repeats[*f])
                        .map(|(_, s)| s.clone())
                        .collect()
                };
                let every = building_samples(grid, &frames, f, &t_rigid, &t_new);
                let data = distinct(&every);
                let per = grid.cases();
                let one_storey = one_storey_frame.map_or_else(Vec::new, |o| {
                    let cases = o * per..(o + 1) * per;
                    samples(grid, &t_rigid[cases.clone()], &t_new[cases])
                });
                // λ where it is finite, as the fraction form's "T_new"; the features as T_new's.
                let lambda_every: Vec<(usize, Sample)> = match &t.lambda {
                    Some(l) => {
                        let lambda = design_fractions(&l.lambda);
                        let ones = vec![1.0; lambda.len()];
                        building_samples(grid, &frames, f, &ones, &lambda)
                    }
                    None => Vec::new(),
                };
                let lambda = distinct(&lambda_every);
                ZoneData {
                    zone: zc.name.clone(),
                    data,
                    every,
                    one_storey,
                    lambda,
                    lambda_every,
                }
            }
        };
        zone_data.push(z);
    }
    // Per zone every form on its data, then (a building study with a one-storey frame) every
    // form on the one-storey frame's cases.
    let jobs: Vec<FitJob> = (0..zone_data.len())
        .flat_map(|zone| {
            let has_one_storey = !zone_data[zone].one_storey.is_empty();
            [false, true]
                .into_iter()
                .filter(move |&one| !one || has_one_storey)
                .flat_map(move |one_storey| {
                    Form::FOR_T_NEW.map(|form| FitJob {
                        zone,
                        form,
                        one_storey,
                    })
                })
        })
        .collect();
    let mut results: HashMap<FitJob, JobResult> = jobs
        .par_iter()
        .map(|&job| {
            let FitJob {
                zone: z,
                form,
                one_storey: one,
            } = job;
            let d = &zone_data[z];
            let run = if one {
                assess(form, &d.one_storey, &one_storey_features, &one_storey_bx)
            } else {
                assess(form, &d.data, &features, &bx)
            };
            let result = run.map_err(|source| FitStageError::Fit {
                zone: d.zone.clone(),
                form: form.name(),
                source,
            });
            (job, result)
        })
        .collect();
    let lambda_fits: Vec<_> = zone_data
        .par_iter()
        .map(|d| {
            (!d.lambda.is_empty()).then(|| {
                assess(Form::Fraction, &d.lambda, &features, &bx).map_err(|source| {
                    FitStageError::Fit {
                        zone: d.zone.clone(),
                        form: Form::Fraction.name(),
                        source,
                    }
                })
            })
        })
        .collect();
    let mut lambda_fits = lambda_fits.into_iter();
    let mut zones = Vec::new();
    for (zi, z) in zone_data.iter().enumerate() {
        let (zone, data) = (&z.zone, &z.data);
        let (forms, not_fitted) = collect_forms(s, (zi, zone), false, &mut results)?;
        let one_storey = if z.one_storey.is_empty() {
            None
        } else {
            let (forms, _) = collect_forms(s, (zi, zone), true, &mut results)?;
            let (best, _) = recommend(&forms);
            forms.into_iter().find(|f| f.form == best)
        };
        let observed: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
        let published: Option<Vec<f64>> = (data.iter())
            .map(|s| paper_equation(zone, &s.x[..1 + 2 * n]))
            .collect();
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
        let lambda = match lambda_fits.next().expect("one per zone").transpose()? {
            Some(Ok(f)) => {
                let (m, cv, b) = (&f.all_cases, &f.cross_validated, &f.box_check);
                s.reporter.info(
                    me,
                    &format!(
                        "zone {zone}: λ ({} cases) R² {:.4}  RMSE {:.4}  ({FOLDS}-fold CV: R² \
                         {:.4}, RMSE {:.4})  solver {}  λ in [{:.3}, {:.3}] on the box",
                        z.lambda.len(),
                        m.r2,
                        m.rmse,
                        cv.r2,
                        cv.rmse,
                        if f.solver.converged {
                            "converged"
                        } else {
                            "NOT converged"
                        },
                        b.min_t_new_over_t_p,
                        b.max_t_new_over_t_rigid
                    ),
                );
                Some(f)
            }
            Some(Err(nf)) => {
                s.reporter
                    .warn(me, &format!("zone {zone}: λ not fitted: {}", nf.reason));
                None
            }
            None => None,
        };
        let best = forms.iter().find(|f| f.form == recommended);
        let frame_fits = match (building, best) {
            (Some(_), Some(best)) => {
                frame_fits(z, &frames, n, best, one_storey.as_ref(), lambda.as_ref())
            }
            _ => Vec::new(),
        };
        for f in &frame_fits {
            let r2 = |m: &Option<Metrics>| m.map_or("–".to_string(), |m| format!("{:.4}", m.r2));
            s.reporter.info(
                me,
                &format!(
                    "zone {zone}, {}: {} cases, R² {:.4} (one-storey equation {}, published {}); \
                     λ R² {}",
                    f.frame,
                    f.cases,
                    f.building.r2,
                    r2(&f.one_storey),
                    r2(&f.published),
                    r2(&f.lambda)
                ),
            );
        }
        zones.push(ZoneFit {
            zone: zone.clone(),
            cases: data.len(),
            forms,
            recommended,
            published,
            recommendation,
            not_fitted,
            frames: frame_fits,
            one_storey,
            lambda,
        });
    }
    let report = FitReport {
        slidestack_version: env!("CARGO_PKG_VERSION").to_string(),
        fingerprint: study.fingerprint(me)?.to_string(),
        features,
        folds: FOLDS,
        building: (frames.len() == 1).then(|| frames[0].to_string()),
        frames: frames.iter().map(Frame::spec).collect(),
        zones,
    };
    let (h5, yaml) = (study.path(me.output()), study.path("fit.yaml"));
    write_fit(&h5, &yaml, &report)?;
    s.reporter.info(
        me,
        &format!(
            "{} zones × {} forms, {FOLDS}-fold cross-validated, in {:.1} s",
            report.zones.len(),
            Form::FOR_T_NEW.len(),
            start.elapsed().as_secs_f64()
        ),
    );
    Ok(StageOutcome::Wrote(vec![h5, yaml]))
}
