//! The study's design equations (the fit stage's numerics): per zone, every form of
//! [`crate::fit::Form`] fitted to the cases' `T_new` (the paper's Eqs. 16–17 shape, the bounded
//! logistic form, and the damped form that can go below `T_p`); every case with a finite
//! `T_new` enters. For each form: coefficients with standard errors; R², R, RMSE, MSE, MAE on
//! all cases and [`FOLDS`]-fold cross-validated; which solver converged; and the box check
//! (finite and inside `[½·T_p, 1.5·T_rigid]` on a box [`BOX_MARGIN`] beyond the grid). The
//! recommended form is the best cross-validated R² among the forms that pass the box check.
//! Also the paper's own published Eqs. 16–17 on our `T_new` (zones named III and V, two
//! blocks). `docs/fit.md` explains the forms.
//!
//! Forms and folds are fitted in parallel, each fit sequentially, each result kept under its
//! job (zone, form, frame): the results do not depend on the thread count.
//!
//! A building study of one frame (one storey count, one `stack_floor`) is fitted as a one-storey
//! study, `T_p` being its bare first-mode period `T_1` (its `T_new`, the first mode's, over
//! `T_1`). A study of several frames is fitted over its distinct frames (floor 1, the roof and
//! every floor of one storey are one building) with the building's features (`N`, `z_stack`:
//! [`BuildingFeatures`]), each case's `T_rigid` its frame's `T_1,rigid`; then per frame the
//! recommended form's metrics beside those of the one-storey equation (every form fitted to the
//! study's one-storey frame, if it has one, the best recommended as for a one-storey study) and
//! the paper's: where the one-storey equations hold and where the higher modes make them fail
//! (docs/fit.md, "A study over buildings"). A building study also fits its effective live-load
//! fraction `λ` ([`Form::Fraction`]).

use crate::fit::extrapolation::{BOX_MARGIN, BOX_POINTS};
use crate::fit::{
    BuildingFeatures, DesignBox, FitError, Form, Metrics, Sample, check_box, cross_validate,
    feature_names, fit, metrics, paper_equation, uncertainty,
};
use crate::grid::Grid;
use crate::store::fit::{FormFit, FrameFit, NotFitted, ZoneFit};
use crate::store::tnew::ZoneTnew;
use crate::study::building::{Frame, distinct_frames, fit_features, repeats};
use crate::study::tnew::{building_samples, samples};
use rayon::prelude::*;
use std::collections::HashMap;

/// Folds of the cross-validation.
pub const FOLDS: usize = 5;

#[derive(Debug, thiserror::Error)]
pub enum EquationError {
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
    let distinct = distinct_frames(frames).len().max(1);
    (grid.cases() * distinct, cases_needed(features.len()))
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

/// One fit: a form on a zone's cases, or on its one-storey frame's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct FitJob {
    zone: usize,
    form: Form,
    one_storey: bool,
}

/// What one [`FitJob`] gave.
type JobResult = Result<Result<FormFit, NotFitted>, EquationError>;

/// A zone's fit and what else the stage reports of it.
pub struct ZoneFitted {
    pub fit: ZoneFit,
    /// A building study's one-storey frame: every form fitted to its cases (the fit keeps the
    /// recommended one) and the forms that do not apply.
    pub one_storey_forms: Vec<FormFit>,
    pub one_storey_not_fitted: Vec<NotFitted>,
    /// The cases `λ` was fitted to, and why it could not be.
    pub lambda_cases: usize,
    pub lambda_not_fitted: Option<NotFitted>,
}

/// A study's design equations: the features they are written in and every zone's fit.
pub struct StudyFit {
    pub features: Vec<String>,
    pub zones: Vec<ZoneFitted>,
}

/// Every zone's design equations from its `T_new` (`zones`, in the config's order), on `grid`
/// over `frames` (the study's building frames in stored order; empty on one storey).
pub fn fit_study(
    grid: &Grid,
    frames: &[Frame],
    zones: &[ZoneTnew],
) -> Result<StudyFit, EquationError> {
    let n = grid.blocks();
    let building = fit_features(n, frames);
    let features = building.map_or_else(|| feature_names(n), BuildingFeatures::names);
    let one_storey_features = feature_names(n);
    let bx = design_box(grid, building.map(|f| (f, frames)));
    let one_storey_bx = design_box(grid, None);
    let zone_data: Vec<ZoneData> = (zones.iter())
        .map(|t| ZoneData::of(grid, frames, building, t))
        .collect();
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
            let d = &zone_data[job.zone];
            let run = if job.one_storey {
                assess(
                    job.form,
                    &d.one_storey,
                    &one_storey_features,
                    &one_storey_bx,
                )
            } else {
                assess(job.form, &d.data, &features, &bx)
            };
            let result = run.map_err(|source| EquationError::Fit {
                zone: d.zone.clone(),
                form: job.form.name(),
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
                    EquationError::Fit {
                        zone: d.zone.clone(),
                        form: Form::Fraction.name(),
                        source,
                    }
                })
            })
        })
        .collect();
    let mut fitted = Vec::new();
    for ((zi, z), lambda) in zone_data.iter().enumerate().zip(lambda_fits) {
        let (forms, not_fitted) = collect_forms((zi, &z.zone), false, &mut results)?;
        let (one_storey_forms, one_storey_not_fitted) = if z.one_storey.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            collect_forms((zi, &z.zone), true, &mut results)?
        };
        let one_storey = (!one_storey_forms.is_empty()).then(|| {
            let (best, _) = recommend(&one_storey_forms);
            one_storey_forms.iter().find(|f| f.form == best).cloned()
        });
        let observed: Vec<f64> = z.data.iter().map(|s| s.t_new_s).collect();
        let published: Option<Vec<f64>> = (z.data.iter())
            .map(|s| paper_equation(&z.zone, &s.x[..1 + 2 * n]))
            .collect();
        let (recommended, recommendation) = recommend(&forms);
        let (lambda, lambda_not_fitted) = match lambda.transpose()? {
            Some(Ok(f)) => (Some(f), None),
            Some(Err(nf)) => (None, Some(nf)),
            None => (None, None),
        };
        let best = forms.iter().find(|f| f.form == recommended);
        let one_storey = one_storey.flatten();
        let frames = match (building, best) {
            (Some(_), Some(best)) => {
                frame_fits(z, frames, n, best, one_storey.as_ref(), lambda.as_ref())
            }
            _ => Vec::new(),
        };
        fitted.push(ZoneFitted {
            fit: ZoneFit {
                zone: z.zone.clone(),
                cases: z.data.len(),
                forms,
                recommended,
                published: published.map(|p| metrics(&observed, &p)),
                recommendation,
                not_fitted,
                frames,
                one_storey,
                lambda,
            },
            one_storey_forms,
            one_storey_not_fitted,
            lambda_cases: z.lambda.len(),
            lambda_not_fitted,
        });
    }
    Ok(StudyFit {
        features,
        zones: fitted,
    })
}

/// Zone `z`'s forms (on its one-storey frame's cases with `one_storey`) from `results`, in
/// [`Form::FOR_T_NEW`] order: the fitted ones and the ones that do not apply; an error when
/// none could be fitted.
fn collect_forms(
    (z, zone): (usize, &str),
    one_storey: bool,
    results: &mut HashMap<FitJob, JobResult>,
) -> Result<(Vec<FormFit>, Vec<NotFitted>), EquationError> {
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
    if forms.is_empty() {
        return Err(EquationError::NoForm {
            zone: zone.to_string(),
            reasons: (not_fitted.iter())
                .map(|n| n.reason.as_str())
                .collect::<Vec<_>>()
                .join("; "),
        });
    }
    Ok((forms, not_fitted))
}

impl ZoneData {
    /// Zone `t`'s samples (`building`: the features of a study of several frames).
    fn of(grid: &Grid, frames: &[Frame], building: Option<BuildingFeatures>, t: &ZoneTnew) -> Self {
        let t_rigid: Vec<f64> = t.vars.t_rigid.iter().copied().collect();
        let t_new: Vec<f64> = t.vars.t_new.iter().copied().collect();
        let zone = t.name.clone();
        let Some(f) = building else {
            // A one-storey study has no λ; a building study of one frame fits it with the
            // one-storey features.
            let lambda: Vec<Sample> = (t.lambda.as_ref()).map_or_else(Vec::new, |l| {
                let lambda = design_fractions(&l.lambda);
                samples(grid, &vec![1.0; lambda.len()], &lambda)
            });
            return Self {
                zone,
                data: samples(grid, &t_rigid, &t_new),
                every: Vec::new(),
                one_storey: Vec::new(),
                lambda_every: lambda.iter().map(|s| (0, s.clone())).collect(),
                lambda,
            };
        };
        // The cases of the distinct frames, the ones fitted.
        let repeats = repeats(frames);
        let distinct = |every: &[(usize, Sample)]| -> Vec<Sample> {
            (every.iter())
                .filter(|(f, _)| !repeats[*f])
                .map(|(_, s)| s.clone())
                .collect()
        };
        let every = building_samples(grid, frames, f, &t_rigid, &t_new);
        // The one-storey frame, where the one-storey equation is fitted (its stack floors are
        // all the same building).
        let per = grid.cases();
        let one_storey =
            (frames.iter().position(|f| f.storeys() == 1)).map_or_else(Vec::new, |o| {
                let cases = o * per..(o + 1) * per;
                samples(grid, &t_rigid[cases.clone()], &t_new[cases])
            });
        // λ where it is finite, as the fraction form's "T_new"; the features as T_new's.
        let lambda_every: Vec<(usize, Sample)> = match &t.lambda {
            Some(l) => {
                let lambda = design_fractions(&l.lambda);
                let ones = vec![1.0; lambda.len()];
                building_samples(grid, frames, f, &ones, &lambda)
            }
            None => Vec::new(),
        };
        Self {
            zone,
            data: distinct(&every),
            every,
            one_storey,
            lambda: distinct(&lambda_every),
            lambda_every,
        }
    }
}
