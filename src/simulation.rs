//! One case under one ground motion, as `slidestack simulate` runs it: the case's settings (from
//! flags, a YAML file or both) checked and resolved into a [`System`], the simulation, and the
//! [`Summary`] its `--json` prints.
//!
//! The physics of the case comes from [`Physics`], as for the study's stages; the yielding model
//! is docs/model.md, "Yielding structure".

use crate::dynamics::{
    Energy, ExactOptions, G, Ground, History, Response, SimError, System, SystemSpec, Yielding,
    simulate_exact, simulate_rk4,
};
use crate::motion::{self, Record, RecordError};
use crate::study::config::{ConfigError, read_yaml_text};
use crate::study::sweep::{DampingBasis, Physics};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Largest factor on the record a case may ask for.
pub const MAX_SCALE: f64 = 1e6;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Event-driven closed-form integrator (exact for piecewise-linear ground motion).
    Exact,
    /// The paper's fixed-step RK4 with its top-down cluster rule.
    Rk4,
}

/// The structure's restoring force (docs/model.md, "Yielding structure").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum StructureKind {
    /// Linear, the paper's structure.
    Elastic,
    /// Elastic–perfectly plastic (needs a yield strength ratio).
    Epp,
    /// Bilinear with kinematic hardening (needs a yield strength ratio and a post-yield ratio).
    Bilinear,
}

impl StructureKind {
    pub fn name(self) -> &'static str {
        match self {
            StructureKind::Elastic => "elastic",
            StructureKind::Epp => "epp",
            StructureKind::Bilinear => "bilinear",
        }
    }
}

/// The case as flags or a YAML file state it: every setting optional (a default applies), unknown
/// YAML keys refused.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseSettings {
    /// Ground-motion file; the built-in record when absent.
    pub record: Option<PathBuf>,
    /// Period of the bare structure `T_p`, s (default 1.0).
    pub period: Option<f64>,
    /// Mass ratios `α_i = m_i/m_p`, bottom block first (default 0.5, 0.5).
    pub alpha: Option<Vec<f64>>,
    /// Kinetic friction coefficients, interface 1 (structure–block 1) first (default 0.2, 0.1).
    pub mu: Option<Vec<f64>>,
    /// Static friction coefficients (default equal to `mu`).
    pub mu_static: Option<Vec<f64>>,
    /// Viscous damping ratio of the system `damping_basis` names (default 0.05).
    pub damping: Option<f64>,
    pub damping_basis: Option<DampingBasis>,
    /// Factor on the record (default 1.0).
    pub scale: Option<f64>,
    pub integrator: Option<Integrator>,
    /// RK4 sub-steps per record interval (default 10).
    pub rk4_substeps: Option<usize>,
    /// Time-history file, `.h5` or `.csv`.
    pub history: Option<PathBuf>,
    pub structure: Option<StructureKind>,
    /// `C_y = F_y/(m_p·g)`, `m_p` the bare structure's mass.
    pub yield_strength_ratio: Option<f64>,
    /// Post-yield stiffness over elastic stiffness `r`, `0 ≤ r < 1`.
    pub post_yield_ratio: Option<f64>,
}

#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("{file}: {message}")]
    Yaml { file: String, message: String },
    #[error("invalid case: {0}")]
    Invalid(String),
    #[error(transparent)]
    Record(#[from] RecordError),
    #[error("simulation of {record} failed")]
    Simulation {
        record: String,
        #[source]
        source: SimError,
    },
}

impl CaseError {
    /// Whether the input was at fault (rather than the run).
    pub fn is_bad_input(&self) -> bool {
        match self {
            CaseError::Simulation { source, .. } => source.is_bad_input(),
            _ => true,
        }
    }
}

impl CaseSettings {
    /// Reads a case file (the keys of [`CaseSettings`]).
    pub fn read(path: &Path) -> Result<Self, CaseError> {
        let text = read_yaml_text(path)?;
        serde_yaml::from_str(&text).map_err(|e| CaseError::Yaml {
            file: path.display().to_string(),
            message: crate::limits::excerpt_message(&e.to_string()),
        })
    }

    /// These settings where given, `base`'s elsewhere.
    pub fn over(self, base: CaseSettings) -> CaseSettings {
        CaseSettings {
            record: self.record.or(base.record),
            period: self.period.or(base.period),
            alpha: self.alpha.or(base.alpha),
            mu: self.mu.or(base.mu),
            mu_static: self.mu_static.or(base.mu_static),
            damping: self.damping.or(base.damping),
            damping_basis: self.damping_basis.or(base.damping_basis),
            scale: self.scale.or(base.scale),
            integrator: self.integrator.or(base.integrator),
            rk4_substeps: self.rk4_substeps.or(base.rk4_substeps),
            history: self.history.or(base.history),
            structure: self.structure.or(base.structure),
            yield_strength_ratio: self.yield_strength_ratio.or(base.yield_strength_ratio),
            post_yield_ratio: self.post_yield_ratio.or(base.post_yield_ratio),
        }
    }

    /// The case with its defaults, checked: the system built, the record read, the history
    /// format known, all before any simulation.
    pub fn resolve(self) -> Result<Case, CaseError> {
        let alpha = self.alpha.unwrap_or_else(|| vec![0.5, 0.5]);
        let physics = Physics {
            damping: self.damping.unwrap_or(0.05),
            basis: self.damping_basis.unwrap_or_default(),
            mu_static_ratio: 1.0,
        };
        let total: f64 = alpha.iter().sum();
        if total.is_finite() && total <= crate::limits::MAX_ALPHA {
            physics.check(total).map_err(CaseError::Invalid)?;
        }
        let spec = SystemSpec {
            period_s: self.period.unwrap_or(1.0),
            damping_ratio: physics.structure_damping(total),
            mass_kg: 1.0,
            alpha,
            mu: self.mu.unwrap_or_else(|| vec![0.2, 0.1]),
            mu_static: self.mu_static,
        };
        let scale = self.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0 && scale <= MAX_SCALE) {
            return Err(CaseError::Invalid(format!(
                "scale must be finite, > 0 and ≤ {MAX_SCALE:e}, got {scale}"
            )));
        }
        if let Some(p) = &self.history {
            crate::store::HistoryFormat::from_path(p)
                .map_err(|e| CaseError::Invalid(e.to_string()))?;
        }
        let structure = self.structure.unwrap_or(StructureKind::Elastic);
        let yielding = yielding(structure, self.yield_strength_ratio, self.post_yield_ratio)?;
        let mut system = System::new(&spec).map_err(|e| CaseError::Invalid(e.to_string()))?;
        if let Some(y) = yielding {
            system = system
                .with_yielding(y)
                .map_err(|e| CaseError::Invalid(e.to_string()))?;
        }
        let record = match &self.record {
            Some(path) => motion::read_record(path)?,
            None => motion::builtin(),
        };
        Ok(Case {
            record,
            scale,
            physics,
            system,
            structure,
            integrator: self.integrator.unwrap_or(Integrator::Exact),
            rk4_substeps: self.rk4_substeps.unwrap_or(10),
            history: self.history,
        })
    }
}

/// The yielding model the settings ask for; `None` for the elastic structure. Each setting is
/// refused where it does not apply, and required where it does.
fn yielding(
    structure: StructureKind,
    strength: Option<f64>,
    r: Option<f64>,
) -> Result<Option<Yielding>, CaseError> {
    let bad = |s: String| Err(CaseError::Invalid(s));
    match (structure, strength, r) {
        (StructureKind::Elastic, None, None) => Ok(None),
        (StructureKind::Elastic, _, _) => bad(
            "--yield-strength-ratio and --post-yield-ratio apply only to --structure epp or \
             bilinear"
                .into(),
        ),
        (_, None, _) => bad(format!(
            "--structure {} needs --yield-strength-ratio (C_y = F_y/(m_p·g))",
            structure.name()
        )),
        (StructureKind::Epp, Some(c), None) => Ok(Some(Yielding::epp(c))),
        (StructureKind::Epp, Some(_), Some(r)) => bad(format!(
            "--structure epp has no post-yield stiffness (r = 0), got --post-yield-ratio {r}; \
             use --structure bilinear"
        )),
        (StructureKind::Bilinear, Some(_), None) => {
            bad("--structure bilinear needs --post-yield-ratio (r, 0 ≤ r < 1)".into())
        }
        (StructureKind::Bilinear, Some(c), Some(r)) => Ok(Some(Yielding::bilinear(c, r))),
    }
}

/// A checked case, ready to simulate.
#[derive(Debug, Clone)]
pub struct Case {
    pub record: Record,
    pub scale: f64,
    pub physics: Physics,
    pub system: System,
    pub structure: StructureKind,
    pub integrator: Integrator,
    pub rk4_substeps: usize,
    /// Where the time history goes, if asked for.
    pub history: Option<PathBuf>,
}

impl Case {
    /// The record scaled, in m/s².
    pub fn accel_mps2(&self) -> Vec<f64> {
        self.record.accel_mps2(self.scale)
    }

    /// What the integrator says of the system against this record's step before it runs
    /// (`dynamics::accuracy_warnings`).
    pub fn warnings(&self, accel_mps2: &[f64]) -> Vec<String> {
        crate::dynamics::accuracy_warnings(&self.system, &self.ground(accel_mps2))
    }

    fn ground<'a>(&self, accel_mps2: &'a [f64]) -> Ground<'a> {
        Ground {
            dt_s: self.record.dt_s,
            accel_mps2,
        }
    }

    /// Runs the case on `accel_mps2` (from [`Case::accel_mps2`]); the time history is kept when
    /// the case names a history file.
    pub fn simulate(&self, accel_mps2: &[f64]) -> Result<(Summary, Option<History>), CaseError> {
        let ground = self.ground(accel_mps2);
        let history = self.history.is_some();
        let response = match self.integrator {
            Integrator::Exact => simulate_exact(
                &self.system,
                &ground,
                &ExactOptions {
                    history,
                    ..ExactOptions::default()
                },
            ),
            Integrator::Rk4 => simulate_rk4(&self.system, &ground, self.rk4_substeps, history),
        }
        .map_err(|source| CaseError::Simulation {
            record: self.record.name.clone(),
            source,
        })?;
        let summary = self.summary(&response);
        Ok((summary, response.history))
    }

    fn summary(&self, r: &Response) -> Summary {
        let sys = &self.system;
        let e = &r.energy;
        let hyst = sys.hysteresis();
        Summary {
            record: self.record.name.clone(),
            dt_s: self.record.dt_s,
            npts: self.record.accel_g.len(),
            scale: self.scale,
            period_s: sys.period_s(),
            period_rigid_s: sys.period_rigid_s(),
            damping: self.physics.damping,
            damping_basis: self.physics.basis,
            structure_damping: sys.damping_ratio(),
            alpha: sys.masses()[1..]
                .iter()
                .map(|m| m / sys.mass_kg())
                .collect(),
            mu: sys.mu_kinetic().to_vec(),
            mu_static: sys.mu_static().to_vec(),
            integrator: self.integrator,
            rk4_substeps: (self.integrator == Integrator::Rk4).then_some(self.rk4_substeps),
            structure: self.structure,
            yield_strength_ratio: hyst.map(|h| h.strength_ratio),
            post_yield_ratio: hyst.map(|h| h.post_yield_ratio),
            yield_displacement_m: hyst.map(|h| h.yield_displacement_m),
            peak_displacement_m: r.peak_displacement_m,
            peak_displacement_time_s: r.peak_displacement_time_s,
            peak_abs_accel_g: r.peak_abs_accel_mps2.iter().map(|a| a / G).collect(),
            peak_slip_m: r.peak_slip_m.clone(),
            residual_slip_m: r.residual_slip_m.clone(),
            slip_time_s: r.slip_time_s.clone(),
            switches: r.switches,
            ductility: r.ductility,
            residual_displacement_m: r.residual_displacement_m,
            yield_events: r.yield_events,
            energy: e.clone(),
            energy_balance_error: e.balance_error(),
            energy_balance_error_max: r.energy_balance_error_max,
        }
    }
}

/// What one simulation gives: the `simulate --json` contract (README); field names are relied
/// on by users and checks.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub record: String,
    pub dt_s: f64,
    pub npts: usize,
    pub scale: f64,
    pub period_s: f64,
    pub period_rigid_s: f64,
    /// The damping ratio as given, of the system `damping_basis` names.
    pub damping: f64,
    pub damping_basis: DampingBasis,
    /// The bare structure's damping ratio that gives the same damper.
    pub structure_damping: f64,
    pub alpha: Vec<f64>,
    pub mu: Vec<f64>,
    pub mu_static: Vec<f64>,
    pub integrator: Integrator,
    pub rk4_substeps: Option<usize>,
    pub structure: StructureKind,
    pub yield_strength_ratio: Option<f64>,
    pub post_yield_ratio: Option<f64>,
    pub yield_displacement_m: Option<f64>,
    pub peak_displacement_m: f64,
    pub peak_displacement_time_s: f64,
    /// Structure, then blocks bottom-up.
    pub peak_abs_accel_g: Vec<f64>,
    pub peak_slip_m: Vec<f64>,
    pub residual_slip_m: Vec<f64>,
    pub slip_time_s: Vec<f64>,
    pub switches: u64,
    /// Peak displacement over the yield displacement; null when elastic.
    pub ductility: Option<f64>,
    /// Structure displacement at the end of the record, m.
    pub residual_displacement_m: f64,
    /// Yield and unloading events (or, with rk4, changes of branch between sub-steps).
    pub yield_events: u64,
    /// Energy terms per unit structure mass, J/kg, at the end of the record.
    pub energy: Energy,
    pub energy_balance_error: f64,
    pub energy_balance_error_max: f64,
}

impl std::str::FromStr for Integrator {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "exact" => Ok(Integrator::Exact),
            "rk4" => Ok(Integrator::Rk4),
            other => Err(format!("integrator `{other}`: expected `exact` or `rk4`")),
        }
    }
}

impl std::str::FromStr for StructureKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "elastic" => Ok(StructureKind::Elastic),
            "epp" => Ok(StructureKind::Epp),
            "bilinear" => Ok(StructureKind::Bilinear),
            other => Err(format!(
                "structure `{other}`: expected `elastic`, `epp` or `bilinear`"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_override_the_file_and_defaults_fill_the_rest() {
        let file = CaseSettings {
            period: Some(2.0),
            mu: Some(vec![0.3]),
            alpha: Some(vec![1.0]),
            ..CaseSettings::default()
        };
        let flags = CaseSettings {
            period: Some(0.5),
            ..CaseSettings::default()
        };
        let case = flags.over(file).resolve().unwrap();
        assert_eq!(case.system.period_s(), 0.5);
        assert_eq!(case.system.mu_kinetic(), &[0.3]);
        assert_eq!(case.scale, 1.0);
        assert_eq!(case.integrator, Integrator::Exact);
        assert_eq!(case.physics.basis, DampingBasis::Rigid);
    }

    #[test]
    fn a_bad_setting_is_refused_before_the_record_is_read() {
        for (settings, expect) in [
            (
                CaseSettings {
                    scale: Some(-1.0),
                    ..CaseSettings::default()
                },
                "scale must be finite",
            ),
            (
                CaseSettings {
                    yield_strength_ratio: Some(0.1),
                    ..CaseSettings::default()
                },
                "apply only to --structure epp or bilinear",
            ),
            (
                CaseSettings {
                    history: Some("out.txt".into()),
                    ..CaseSettings::default()
                },
                "out.txt",
            ),
        ] {
            let settings = CaseSettings {
                record: Some("/nonexistent/record.AT2".into()),
                ..settings
            };
            let e = settings.resolve().unwrap_err();
            assert!(
                matches!(&e, CaseError::Invalid(m) if m.contains(expect)) && e.is_bad_input(),
                "{e}"
            );
        }
    }

    #[test]
    fn the_summary_is_the_simulation_of_the_system() {
        let case = CaseSettings::default().resolve().unwrap();
        let accel = case.accel_mps2();
        let (summary, history) = case.simulate(&accel).unwrap();
        let direct = simulate_exact(
            &case.system,
            &Ground {
                dt_s: case.record.dt_s,
                accel_mps2: &accel,
            },
            &ExactOptions::default(),
        )
        .unwrap();
        assert!(history.is_none());
        assert_eq!(summary.peak_displacement_m, direct.peak_displacement_m);
        assert_eq!(summary.peak_slip_m, direct.peak_slip_m);
        assert_eq!(summary.alpha, vec![0.5, 0.5]);
    }
}
