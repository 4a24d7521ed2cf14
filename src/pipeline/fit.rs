//! The fit stage: reads every zone's `T_new`, fits the study's design equations
//! ([`crate::study::equations`]: every form, cross-validated and box-checked, the recommended
//! one, the paper's published equations on our `T_new`, a building study's `λ` and its frames),
//! reports them and writes `fit.h5` and `fit.yaml` (layout in [`crate::store::fit`]). A building
//! study of one frame is fitted as a one-storey study and `fit.yaml` names the frame.
//!
//! Fingerprint: T_new's, the forms, the number of folds and the box.

use super::{PipelineError, Session, StageId, StageOutcome};
use crate::fit::extrapolation::{BOX_MARGIN, BOX_POINTS};
use crate::fit::{Form, Metrics};
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::{FitReport, FormFit, NotFitted, write_fit};
use crate::study::building::Frame;
use crate::study::equations::{FOLDS, ZoneFitted, fit_study};

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

/// Every line the stage prints of zone `z`'s fit: each form (and the one-storey frame's), the
/// forms that do not apply, the published equations, the recommendation, `λ` and each frame.
fn report_zone(s: &Session, z: &ZoneFitted) {
    let me = StageId::Fit;
    let (zone, f) = (&z.fit.zone, &z.fit);
    let forms = |what: &str, forms: &[FormFit], not_fitted: &[NotFitted]| {
        for form in forms {
            s.reporter
                .info(me, &format!("zone {zone}{what}: {}", describe(form)));
        }
        for nf in not_fitted {
            let line = format!("zone {zone}{what}: {} form: {}", nf.form.name(), nf.reason);
            s.reporter.warn(me, &line);
        }
    };
    forms("", &f.forms, &f.not_fitted);
    forms(
        ", one storey",
        &z.one_storey_forms,
        &z.one_storey_not_fitted,
    );
    if let Some(m) = &f.published {
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
    s.reporter.info(
        me,
        &format!(
            "zone {zone}: recommended {}: {}",
            f.recommended.name(),
            f.recommendation
        ),
    );
    if let Some(l) = &f.lambda {
        let (m, cv, b) = (&l.all_cases, &l.cross_validated, &l.box_check);
        s.reporter.info(
            me,
            &format!(
                "zone {zone}: λ ({} cases) R² {:.4}  RMSE {:.4}  ({FOLDS}-fold CV: R² {:.4}, \
                 RMSE {:.4})  solver {}  λ in [{:.3}, {:.3}] on the box",
                z.lambda_cases,
                m.r2,
                m.rmse,
                cv.r2,
                cv.rmse,
                if l.solver.converged {
                    "converged"
                } else {
                    "NOT converged"
                },
                b.min_t_new_over_t_p,
                b.max_t_new_over_t_rigid
            ),
        );
    }
    if let Some(nf) = &z.lambda_not_fitted {
        s.reporter
            .warn(me, &format!("zone {zone}: λ not fitted: {}", nf.reason));
    }
    for fr in &f.frames {
        let r2 = |m: &Option<Metrics>| m.map_or("–".to_string(), |m| format!("{:.4}", m.r2));
        s.reporter.info(
            me,
            &format!(
                "zone {zone}, {}: {} cases, R² {:.4} (one-storey equation {}, published {}); \
                 λ R² {}",
                fr.frame,
                fr.cases,
                fr.building.r2,
                r2(&fr.one_storey),
                r2(&fr.published),
                r2(&fr.lambda)
            ),
        );
    }
}

/// Builds `fit.h5` and `fit.yaml`.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let start = std::time::Instant::now();
    let study = &s.study;
    let me = StageId::Fit;
    let grid = study.grid(me)?;
    let tnew = (study.cfg.zones.iter())
        .map(|zc| super::files::tnew_zone(study, &zc.name))
        .collect::<Result<Vec<_>, _>>()?;
    let fitted = fit_study(grid, study.frames(), &tnew)?;
    for z in &fitted.zones {
        report_zone(s, z);
    }
    let report = FitReport {
        slidestack_version: env!("CARGO_PKG_VERSION").to_string(),
        fingerprint: study.fingerprint(me)?.to_string(),
        features: fitted.features,
        folds: FOLDS,
        building: (study.frames().len() == 1)
            .then(|| study.shape.label(0))
            .flatten(),
        frames: (study.shape.building_frames().iter())
            .map(Frame::spec)
            .collect(),
        zones: fitted.zones.into_iter().map(|z| z.fit).collect(),
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
