//! The fit stage: per zone, the design equation for `T_new` in two forms ([`crate::fit`]): the
//! paper's (Eqs. 16–17, `b·e^d` reparameterised) and a bounded logistic form between `T_p` and
//! `T_rigid`. Every case with a finite `T_new` enters. For each form: coefficients and R², R,
//! RMSE, MSE, MAE on all cases and 5-fold cross-validated; and the paper's own published
//! Eqs. 16–17 on our `T_new` (zones named III and V, two blocks) → `fit.h5` and `fit.yaml`
//! (layout in [`crate::store::fit`]).
//!
//! Fingerprint: T_new's, and the number of folds.

use super::{Outcome, PipelineError, Session, StageId};
use crate::fit::{FitError, Form, cross_validate, fit, metrics, paper_equation};
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::{FitReport, FormFit, ZoneFit, write_fit};
use crate::store::tnew::read_zone_tnew;
use crate::study::tnew::samples;
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
}

/// The fingerprint `fit.h5` and `fit.yaml` must carry.
pub fn fingerprint(tnew_fingerprint: &str) -> String {
    hash_parts(&[tnew_fingerprint, &format!("folds={FOLDS}")])
}

/// Names of a form's parameters, in [`crate::fit::Fitted::params`] order.
pub fn parameter_names(form: Form, features: &[String]) -> Vec<String> {
    match form {
        Form::Paper => features
            .iter()
            .map(|f| format!("a_{f}"))
            .chain(features.iter().map(|f| format!("c_{f}")))
            .chain(["B (= b·e^d)".to_string(), "e".to_string()])
            .collect(),
        Form::Bounded => features
            .iter()
            .map(|f| format!("w_{f}"))
            .chain(["w_0".to_string()])
            .collect(),
    }
}

/// Builds `fit.h5` and `fit.yaml`.
pub fn build(s: &Session) -> Result<Outcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Fit;
    let grid = study.grid(me)?;
    let tnew_path = study.path(StageId::Tnew.output());
    let n = grid.blocks();
    let mut features = vec!["T_p".to_string()];
    features.extend((1..=n).map(|i| format!("mu_{i}")));
    features.extend((1..=n).map(|i| format!("alpha_{i}")));
    let mut zones = Vec::new();
    for zc in &study.cfg.zones {
        let (_, t) = read_zone_tnew(&tnew_path, &zc.name, n)?;
        let t_rigid: Vec<f64> = t.vars.t_rigid.iter().copied().collect();
        let t_new: Vec<f64> = t.vars.t_new.iter().copied().collect();
        let data = samples(grid, &t_rigid, &t_new);
        let observed: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
        let mut forms = Vec::new();
        for form in [Form::Paper, Form::Bounded] {
            let err = |source| FitStageError::Fit {
                zone: zc.name.clone(),
                form: form.name(),
                source,
            };
            let f = fit(form, &data).map_err(err)?;
            let pred: Vec<f64> = data.iter().map(|s| f.predict(s)).collect();
            let cv = cross_validate(form, &data, FOLDS).map_err(err)?;
            let m = metrics(&observed, &pred);
            s.reporter.info(
                me,
                &format!(
                    "zone {}: {:<7} R² {:.3}  R {:.3}  RMSE {:.3} s  MAE {:.3} s   ({FOLDS}-fold CV: \
                     R² {:.3}, RMSE {:.3} s)",
                    zc.name,
                    form.name(),
                    m.r2,
                    m.r,
                    m.rmse,
                    m.mae,
                    cv.r2,
                    cv.rmse
                ),
            );
            let n = f.params.len();
            forms.push(FormFit {
                form,
                coefficients: parameter_names(form, &features)
                    .into_iter()
                    .zip(f.params)
                    .collect(),
                standard_errors: vec![f64::NAN; n],
                all_cases: m,
                cross_validated: cv,
            });
        }
        let published: Option<Vec<f64>> = data
            .iter()
            .map(|s| paper_equation(&zc.name, &s.x))
            .collect();
        let published = published.map(|p| metrics(&observed, &p));
        if let Some(m) = &published {
            s.reporter.info(
                me,
                &format!(
                    "zone {}: published Eq. {} on our T_new: R² {:.3}  RMSE {:.3} s",
                    zc.name,
                    if zc.name == "III" { 16 } else { 17 },
                    m.r2,
                    m.rmse
                ),
            );
        }
        let recommended = forms
            .iter()
            .max_by(|a, b| a.cross_validated.r2.total_cmp(&b.cross_validated.r2))
            .map(|f| f.form)
            .expect("at least one form");
        zones.push(ZoneFit {
            zone: zc.name.clone(),
            cases: data.len(),
            forms,
            recommended,
            published,
        });
    }
    let report = FitReport {
        slidestack_version: env!("CARGO_PKG_VERSION").to_string(),
        fingerprint: study.fingerprint(me)?.to_string(),
        features,
        zones,
    };
    let (h5, yaml) = (study.path(me.output()), study.path("fit.yaml"));
    write_fit(&h5, &yaml, &report)?;
    Ok(Outcome::Wrote(vec![h5, yaml]))
}
