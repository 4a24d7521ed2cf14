//! The fit stage's files: `fit.yaml` (the numbers, for people and scripts) and `fit.h5` (the same
//! numbers for HDF5 readers), written with the same fingerprint. Both are written checked and
//! atomically with a checksum sidecar; the stage is up to date only when both verify and agree.
//!
//! ```text
//! fit.h5:  /  attrs: contents, slidestack_version, fingerprint, features
//!          /zone_<name>                       attrs: recommended_form, recommendation
//!          /zone_<name>/<form>                attrs: equation, r2, r, rmse_s, mse_s2, mae_s, n,
//!                                                     relative_rmse, max_relative_error,
//!                                                     cv_r2, cv_r, …, solver, converged,
//!                                                     iterations, relative_offset,
//!                                                     objective, residual_std,
//!                                                     condition_number,
//!                                                     box_passed, box_points,
//!                                                     box_min_t_new_over_t_p,
//!                                                     box_max_t_new_over_t_rigid
//!          /zone_<name>/<form>/coefficients   attrs: names     [parameter]
//!          /zone_<name>/<form>/standard_errors attrs: names     [parameter]
//!          /zone_<name>/<form>/parameter      the coefficients' names (dimension scale)
//!          /zone_<name>/published             attrs: r2, r, rmse_s, mse_s2, mae_s, n
//!          /zone_<name>/lambda                (a building study) the fraction form for λ, as a
//!                                             form's group (its "T_new" is λ)
//!          /zone_<name>/frame_<i>             (a building study of several frames, frame i of
//!                                             fit.yaml's `frames`) attrs: frame, the
//!                                             recommended form's metrics on its cases (r2, …),
//!                                             one_storey_r2, …, published_r2, …,
//!                                             lambda_r2, …
//! ```

use super::h5::{
    attach_scale, attr_f64, attr_str, set_scale, write_1d, write_stage_file, write_strings,
};
use super::{StoreError, checksum};
use crate::fit::{
    BoxCheck, BuildingFeatures, Fitted, Form, HEIGHT_FEATURE, Method, Metrics, STOREYS_FEATURE,
    SolverReport, feature_names,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One fitted form of one zone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FormFit {
    pub form: Form,
    /// Parameter names and values.
    pub coefficients: Vec<(String, f64)>,
    /// Standard error of each coefficient, same order: `√diag(s²·(JᵀJ)⁻¹)` from the Jacobian
    /// at the optimum, `s² = SSE/(n − p)`; NaN where `JᵀJ` is singular.
    pub standard_errors: Vec<f64>,
    pub all_cases: Metrics,
    pub cross_validated: Metrics,
    /// The equation, for people ([`Form::equation`]).
    #[serde(default)]
    pub equation: String,
    /// What the least squares minimise ([`Form::objective`]).
    #[serde(default)]
    pub objective: String,
    /// `s = √(SSE/(n − p))` of the residuals the fit minimised: s, or a fraction of `T_p` for a
    /// form fitted to `T_new/T_p`.
    #[serde(default)]
    pub residual_std: f64,
    /// Condition number of the column-scaled Jacobian at the optimum (standard errors are NaN
    /// above [`crate::fit::metrics::SINGULAR_CONDITION`]).
    #[serde(default)]
    pub condition_number: f64,
    /// How the solver went on all cases.
    #[serde(default)]
    pub solver: SolverReport,
    /// How it went on each cross-validation fold.
    #[serde(default)]
    pub cv_solvers: Vec<SolverReport>,
    /// Whether the fitted form stays finite and inside `[½·T_p, 1.5·T_rigid]` on the box
    /// beyond the grid.
    #[serde(default)]
    pub box_check: BoxCheck,
}

impl FormFit {
    /// The fitted form as a function of the features.
    pub fn fitted(&self) -> Fitted {
        Fitted {
            form: self.form,
            params: self.coefficients.iter().map(|c| c.1).collect(),
        }
    }
}

/// A form the stage did not fit, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NotFitted {
    pub form: Form,
    pub reason: String,
}

/// How the design equations do on one frame of a building study of several frames: where the
/// one-storey equations still hold and where they fail.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameFit {
    /// `3 storeys, stack on the roof`.
    pub frame: String,
    /// Cases of the frame with a `T_new`.
    pub cases: usize,
    /// The zone's recommended form, fitted with the building's features, on this frame's cases.
    pub building: Metrics,
    /// The recommended one-storey equation (fitted to the study's one-storey frame with the
    /// one-storey features, `T_p = T_1`) on this frame's cases; `None` without a one-storey
    /// frame.
    pub one_storey: Option<Metrics>,
    /// The paper's published equation (`T_p = T_1`) on this frame's cases, when it applies.
    pub published: Option<Metrics>,
    /// The zone's fitted `λ` ([`ZoneFit::lambda`]) on this frame's cases.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<Metrics>,
}

/// A frame of a building study, all `design` needs to evaluate the fitted forms there: its
/// `T_1,rigid` and features (`crate::study::building::Frame::spec` and `Frame::of_spec` convert).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameSpec {
    pub storeys: usize,
    /// `3`, `roof`, `mid` or `all`.
    pub stack_floor: String,
    /// Relative floor masses, floor 1 first.
    pub floor_masses: Vec<f64>,
    /// Relative storey stiffnesses, storey 1 first.
    pub storey_stiffnesses: Vec<f64>,
    /// Storey heights, m, storey 1 first.
    pub storey_heights_m: Vec<f64>,
    /// The stack's relative height `z_stack`.
    pub z_stack: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneFit {
    pub zone: String,
    pub cases: usize,
    pub forms: Vec<FormFit>,
    /// The form a designer should use for this zone: the best cross-validated R² among the
    /// forms that pass the box check, else the best overall (see `recommendation`).
    pub recommended: Form,
    /// The paper's published equation for this zone on our T_new, when it applies.
    pub published: Option<Metrics>,
    /// Why `recommended` was chosen.
    #[serde(default)]
    pub recommendation: String,
    /// Forms that could not be fitted to this zone's data.
    #[serde(default)]
    pub not_fitted: Vec<NotFitted>,
    /// A building study of several frames: the recommended equation frame by frame, beside the
    /// one-storey ones.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<FrameFit>,
    /// The recommended one-storey equation of `frames` (its form and coefficients), fitted to
    /// the study's one-storey frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub one_storey: Option<FormFit>,
    /// A building study's design equation for the effective live-load fraction `λ`
    /// ([`Form::Fraction`], the same features as `T_new`'s), fitted to every case of its
    /// distinct frames with a `λ`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<FormFit>,
}

impl ZoneFit {
    /// The recommended form's fit.
    pub fn recommended_fit(&self) -> Option<&FormFit> {
        self.forms.iter().find(|f| f.form == self.recommended)
    }
}

/// Everything the fit stage stores.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    pub slidestack_version: String,
    pub fingerprint: String,
    pub features: Vec<String>,
    /// Folds of the cross-validation.
    #[serde(default)]
    pub folds: usize,
    /// A building study's one frame (`3 storeys, stack on the roof`): `T_p` is then the bare
    /// building's first-mode period `T_1` and `T_new` the first mode's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub building: Option<String>,
    /// A building study's frames, in `tnew.h5`'s order (`T_p` is then `T_1`; with several
    /// frames the features end with the building's: [`crate::fit::BuildingFeatures`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<FrameSpec>,
    pub zones: Vec<ZoneFit>,
}

fn write_metrics(g: &hdf5::Location, prefix: &str, m: &Metrics) -> hdf5::Result<()> {
    for (k, v) in [
        ("r2", m.r2),
        ("r", m.r),
        ("rmse_s", m.rmse),
        ("mse_s2", m.mse),
        ("mae_s", m.mae),
        ("n", m.n as f64),
        ("relative_rmse", m.relative_rmse),
        ("max_relative_error", m.max_relative_error),
    ] {
        attr_f64(g, &format!("{prefix}{k}"), v)?;
    }
    Ok(())
}

/// One fitted form as group `name` of `g`.
fn write_form(g: &hdf5::Group, name: &str, fr: &FormFit) -> hdf5::Result<()> {
    let sub = g.create_group(name)?;
    attr_str(&sub, "equation", &fr.equation)?;
    attr_str(&sub, "objective", &fr.objective)?;
    attr_str(
        &sub,
        "solver",
        match fr.solver.method {
            Method::TrustRegion => "trust-region",
            Method::NelderMead => "nelder-mead",
            Method::ProjectedNelderMead => "nelder-mead-projected",
        },
    )?;
    let b = &fr.box_check;
    for (k, v) in [
        ("converged", f64::from(u8::from(fr.solver.converged))),
        ("iterations", fr.solver.iterations as f64),
        ("relative_offset", fr.solver.relative_offset),
        ("residual_std", fr.residual_std),
        ("condition_number", fr.condition_number),
        ("box_passed", f64::from(u8::from(b.passed))),
        ("box_points", b.points as f64),
        ("box_min_t_new_over_t_p", b.min_t_new_over_t_p),
        ("box_max_t_new_over_t_rigid", b.max_t_new_over_t_rigid),
    ] {
        attr_f64(&sub, k, v)?;
    }
    let values: Vec<f64> = fr.coefficients.iter().map(|c| c.1).collect();
    let names: Vec<String> = fr.coefficients.iter().map(|c| c.0.clone()).collect();
    let ds = write_1d(
        &sub,
        "coefficients",
        &values,
        "mixed (s, s per unit feature)",
        "fitted coefficients",
    )?;
    attr_str(&ds, "names", &names.join(", "))?;
    // The coefficients' names as their dimension's scale, so xarray labels them.
    let parameter = write_strings(&sub, "parameter", &names, "the coefficient's name")?;
    set_scale(&parameter, "parameter")?;
    attach_scale(&ds, &parameter, 0)?;
    let se = write_1d(
        &sub,
        "standard_errors",
        &fr.standard_errors,
        "mixed (as the coefficients)",
        "standard error of each coefficient, from the Jacobian at the optimum",
    )?;
    attr_str(&se, "names", &names.join(", "))?;
    attach_scale(&se, &parameter, 0)?;
    write_metrics(&sub, "", &fr.all_cases)?;
    write_metrics(&sub, "cv_", &fr.cross_validated)?;
    Ok(())
}

/// Writes `fit.h5` at `h5` and `fit.yaml` at `yaml`.
pub fn write_fit(h5: &Path, yaml: &Path, r: &FitReport) -> Result<(), StoreError> {
    write_stage_file(
        h5,
        "slidestack fit stage: design equations for T_new (see fit.yaml)",
        &r.fingerprint,
        |f| {
            attr_str(f, "features", &r.features.join(", "))?;
            if let Some(b) = &r.building {
                attr_str(f, "building", b)?;
            }
            for z in &r.zones {
                let g = f.create_group(&format!("zone_{}", z.zone))?;
                attr_str(&g, "recommended_form", z.recommended.name())?;
                attr_str(&g, "recommendation", &z.recommendation)?;
                for fr in &z.forms {
                    write_form(&g, fr.form.name(), fr)?;
                }
                if let Some(fr) = &z.lambda {
                    write_form(&g, "lambda", fr)?;
                }
                if let Some(m) = &z.published {
                    let sub = g.create_group("published")?;
                    write_metrics(&sub, "", m)?;
                }
                for (i, fr) in z.frames.iter().enumerate() {
                    let sub = g.create_group(&format!("frame_{i}"))?;
                    attr_str(&sub, "frame", &fr.frame)?;
                    write_metrics(&sub, "", &fr.building)?;
                    if let Some(m) = &fr.one_storey {
                        write_metrics(&sub, "one_storey_", m)?;
                    }
                    if let Some(m) = &fr.published {
                        write_metrics(&sub, "published_", m)?;
                    }
                    if let Some(m) = &fr.lambda {
                        write_metrics(&sub, "lambda_", m)?;
                    }
                }
            }
            Ok(())
        },
    )?;
    let text = serde_yaml::to_string(r).expect("the fit report serialises");
    checksum::write_with_sidecar(yaml, text.as_bytes())
}

impl FitReport {
    /// Refuses a report (read from `yaml`) whose features are not those of a stack of `blocks`
    /// blocks, the stack its forms are evaluated on.
    pub fn check_blocks(&self, yaml: &Path, blocks: usize) -> Result<(), StoreError> {
        let building = BuildingFeatures::of_names(&self.features, blocks);
        if self.features == feature_names(blocks) || !self.frames.is_empty() && building.is_some() {
            return Ok(());
        }
        Err(StoreError::corrupt(
            yaml,
            format!(
                "its features ({}) are not those of the study's {blocks}-block stacks",
                self.features.join(", ")
            ),
        ))
    }
}

/// `fit.yaml`, verified against its sidecar; every form has one coefficient and one standard
/// error per parameter its features give.
pub fn read_fit(yaml: &Path) -> Result<Option<FitReport>, StoreError> {
    if !checksum::verify(yaml)? {
        return Ok(None);
    }
    let text = std::fs::read_to_string(yaml).map_err(|e| StoreError::io(yaml, "cannot read", e))?;
    let report: FitReport = serde_yaml::from_str(&text)
        .map_err(|e| StoreError::corrupt(yaml, format!("is not a slidestack fit report: {e}")))?;
    let k = report.features.len();
    let building = (report.features.iter())
        .filter(|f| [STOREYS_FEATURE, HEIGHT_FEATURE].contains(&f.as_str()))
        .count();
    for z in &report.zones {
        let forms = z.forms.iter().map(|f| (f, k));
        let one_storey = z.one_storey.iter().map(|f| (f, k - building));
        for (f, k) in forms
            .chain(one_storey)
            .chain(z.lambda.iter().map(|f| (f, k)))
        {
            let want = [f.form.parameter_count(k)];
            for (what, found) in [
                ("coefficients", f.coefficients.len()),
                ("standard_errors", f.standard_errors.len()),
            ] {
                if [found] != want {
                    let variable = format!("zone {}, {} form: {what}", z.zone, f.form.name());
                    return Err(StoreError::shape(yaml, variable, &[found], &want));
                }
            }
        }
    }
    Ok(Some(report))
}

/// The fingerprint of the fit stage's files: `None` when either is missing; an error when either
/// fails its checksum or they disagree.
pub fn stored_fingerprint(h5: &Path, yaml: &Path) -> Result<Option<String>, StoreError> {
    let Some(fp) = super::h5::stored_fingerprint(h5)? else {
        return Ok(None);
    };
    let Some(report) = read_fit(yaml)? else {
        return Ok(None);
    };
    if report.fingerprint != fp {
        return Err(StoreError::corrupt(
            yaml,
            format!("belongs to another fit than {}", h5.display()),
        ));
    }
    Ok(Some(fp))
}
