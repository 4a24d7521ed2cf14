//! One case under one ground motion, as `slidestack simulate` runs it: its [`Settings`] (from
//! flags, a YAML file or both) checked and resolved into a [`Simulation`] (the system and the
//! record), the run, and the [`Summary`] its `--json` prints.
//!
//! The physics of the case comes from [`Physics`], as for the study's stages; the yielding model
//! is docs/model.md, "Yielding structure".

pub mod batch;
pub mod building;
pub mod edp;
pub mod floor_spectra;

use crate::dynamics::building::Building;
use crate::dynamics::{
    Energy, ExactOptions, G, Ground, History, Response, RockingOnset, SimError, System, SystemSpec,
    Unwatched, Watch, Yielding, simulate_exact_watched, simulate_rk4_watched,
};
use crate::ground_motion::{self, Record, RecordError};
use crate::limits::MAX_PEAK_ACCEL_G;
use crate::study::config::{ConfigError, read_yaml_text, yaml_problem};
use crate::study::physics::{DampingBasis, Physics};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Seconds per record sample and body of the one-storey exact integrator; per sample of a
/// building's, times `N^4.5` (with a two-block stack on every floor: 20, 30 and 60 storeys took
/// 0.58, 3.6 and 83 ms per sample); per sub-step and body of RK4 (one storey at 1,000 sub-steps
/// 9.5e-8 s, 20 storeys at 100 sub-steps 6.6e-8 s) ([`Simulation::cost_estimate_s`]; measured
/// on this project's 2-core machine, docs/faults.md).
const COST_ONE_STOREY_S: f64 = 1e-6;
const COST_BUILDING_S: f64 = 8.3e-10;
const COST_RK4_S: f64 = 1e-7;

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

/// The case of a simulation, every setting optional (a default applies): the keys of a YAML
/// case file (unknown keys refused) and, field by field, the flags of `slidestack simulate`
/// (`period` is `--period`), which override the file's ([`Settings::over`]). A new setting is a
/// new field here and nowhere else: a flag unless marked `#[arg(skip)]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, clap::Args)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    /// Ground-motion record: PEER .AT2 or two-column time/acceleration text, values in g [default:
    /// the built-in record].
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Period of the bare structure T_p, s [default: 1.0].
    #[arg(long)]
    pub period: Option<f64>,
    /// Block mass ratios α_i = m_i/m_p, bottom block first [default: 0.5,0.5].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub alpha: Option<Vec<f64>>,
    /// Kinetic friction coefficients μ_i, interface 1 (structure–block 1) first [default:
    /// 0.2,0.1].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub mu: Option<Vec<f64>>,
    /// Static friction coefficients (≥ kinetic) [default: equal to mu].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub mu_static: Option<Vec<f64>>,
    /// Viscous damping ratio, of the system damping_basis names [default: 0.05].
    #[arg(long)]
    pub damping: Option<f64>,
    /// `rigid`: the damping ratio is that of the structure with its whole stack rigidly attached
    /// (the study's default); `structure`: of the bare structure [default: rigid].
    #[arg(long)]
    pub damping_basis: Option<DampingBasis>,
    /// Factor applied to the record [default: 1.0].
    #[arg(long)]
    pub scale: Option<f64>,
    /// Integrator: exact or rk4 [default: exact].
    #[arg(long)]
    pub integrator: Option<Integrator>,
    /// RK4 sub-steps per record interval [default: 10].
    #[arg(long)]
    pub rk4_substeps: Option<usize>,
    /// Restoring force of the structure: elastic, epp or bilinear [default: elastic].
    #[arg(long)]
    pub structure: Option<StructureKind>,
    /// Yield strength ratio C_y = F_y/(m_p·g) of an epp or bilinear structure (m_p the bare
    /// structure's mass).
    #[arg(long)]
    pub yield_strength_ratio: Option<f64>,
    /// Post-yield stiffness over elastic stiffness r (0 ≤ r < 1) of a bilinear structure.
    #[arg(long)]
    pub post_yield_ratio: Option<f64>,
    /// Width over height of each block, bottom first: reports when the stack would start to
    /// rock (docs/model.md, "Rocking: when a case leaves the model") [default: not checked].
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub aspect: Option<Vec<f64>>,
    /// Write the time history to this .h5 or .csv file.
    #[arg(long)]
    pub history: Option<PathBuf>,
    /// A shear building of several storeys (case files only; docs/model.md, "A multi-storey
    /// building"). With it the stacks are given under `stacks`, and the one-storey keys
    /// (`period`, `alpha`, `mu`, `mu_static`, `structure`, `yield_strength_ratio`,
    /// `post_yield_ratio`) do not apply.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub building: Option<building::BuildingSettings>,
    /// The stacks on a building's floors (case files only).
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stacks: Option<Vec<building::StackSettings>>,
    /// Each floor's response spectra (case files only; docs/model.md, "Floor response
    /// spectra"): `periods` (the `--periods` syntax or a list, s) and `damping` (a list).
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_spectra: Option<floor_spectra::FloorSpectraSettings>,
    /// The case file these settings were read from, for messages.
    #[arg(skip)]
    #[serde(skip)]
    pub file: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum SimulationError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A case file that is not valid YAML or has keys of the wrong kind
    /// ([`crate::study::config::yaml_problem`]): the message names the file's keys as it
    /// writes them, not a command's flags.
    #[error("{file}: {problem}")]
    Yaml {
        file: String,
        problem: crate::study::config::YamlProblem,
    },
    #[error("invalid case: {0}")]
    Invalid(String),
    /// A setting of a call (a Python keyword) of the wrong kind, or unknown.
    #[error("invalid case: `{key}`: {message}")]
    Setting { key: String, message: String },
    /// A key of a case file, named with the file.
    #[error("{file}: {message}")]
    Key { file: String, message: String },
    #[error(transparent)]
    Record(#[from] RecordError),
    /// A file to write (`history`) that cannot be made where it is asked for.
    #[error(transparent)]
    Output(#[from] crate::store::atomic::OutputPathError),
    /// A file (`export edp`'s) that could not be written.
    #[error(transparent)]
    Store(#[from] crate::store::StoreError),
    #[error("simulation of {record} failed")]
    Simulation {
        record: String,
        #[source]
        source: SimError,
    },
}

impl Settings {
    /// Reads a case file (the keys of [`Settings`]).
    pub fn read(path: &Path) -> Result<Self, SimulationError> {
        let text = read_yaml_text(path)?;
        let mut settings: Settings =
            serde_yaml::from_str(&text).map_err(|e| SimulationError::Yaml {
                file: path.display().to_string(),
                problem: yaml_problem(&text, &e),
            })?;
        settings.file = Some(path.to_path_buf());
        Ok(settings)
    }

    /// Settings from a call's keywords as a mapping; a key of the wrong kind, or unknown, is
    /// named (the first in the mapping's order).
    pub fn from_mapping(mapping: serde_yaml::Mapping) -> Result<Settings, SimulationError> {
        use serde_yaml::{Mapping, Value};
        serde_yaml::from_value(Value::Mapping(mapping.clone())).map_err(|e| {
            for (key, value) in mapping {
                let one = Mapping::from_iter([(key.clone(), value)]);
                if let Err(e) = serde_yaml::from_value::<Settings>(Value::Mapping(one)) {
                    let key = key
                        .as_str()
                        .map_or_else(|| format!("{key:?}"), str::to_string);
                    return SimulationError::Setting {
                        key,
                        message: e.to_string(),
                    };
                }
            }
            SimulationError::Invalid(e.to_string())
        })
    }

    /// These settings where given, `base`'s elsewhere: the one place settings from two sources
    /// meet, key by key, whatever the keys.
    pub fn over(self, base: Settings) -> Result<Settings, SimulationError> {
        let mapping = |s: &Settings| match serde_yaml::to_value(s) {
            Ok(serde_yaml::Value::Mapping(m)) => Ok(m),
            Ok(_) => unreachable!("a struct serialises to a mapping"),
            Err(e) => Err(SimulationError::Invalid(e.to_string())),
        };
        let mut merged = mapping(&base)?;
        for (key, value) in mapping(&self)? {
            if !value.is_null() {
                merged.insert(key, value);
            }
        }
        let file = self.file.or(base.file);
        let mut merged: Settings = serde_yaml::from_value(serde_yaml::Value::Mapping(merged))
            .map_err(|e| SimulationError::Invalid(e.to_string()))?;
        merged.file = file;
        Ok(merged)
    }

    /// The simulation with its defaults, checked: the system built, the record read, the history
    /// format known, all before any simulation.
    pub fn resolve(self) -> Result<Simulation, SimulationError> {
        self.resolve_reading(|path| match path {
            Some(path) => ground_motion::read_record(path),
            None => Ok(ground_motion::builtin()),
        })
    }

    /// [`Settings::resolve`] under `record` (read once by the caller for many cases) in place of
    /// the settings' own.
    pub fn resolve_with(self, record: Record) -> Result<Simulation, SimulationError> {
        self.resolve_reading(|_| Ok(record))
    }

    /// [`Settings::resolve`] with the record from `read` (given the settings' `record`), which
    /// is asked only once every other setting has passed its checks.
    fn resolve_reading(
        self,
        read: impl FnOnce(Option<&Path>) -> Result<Record, RecordError>,
    ) -> Result<Simulation, SimulationError> {
        let physics = Physics {
            damping: self.damping.unwrap_or(Physics::DEFAULT.damping),
            basis: self.damping_basis.unwrap_or(Physics::DEFAULT.basis),
            ..Physics::DEFAULT
        };
        let model = match &self.building {
            Some(b) => self.building_model(b, &physics)?,
            None => self.one_storey_model(&physics)?,
        };
        let scale = self.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0 && scale <= MAX_SCALE) {
            return Err(self.key_error(format!(
                "`scale` must be finite, > 0 and ≤ {MAX_SCALE:e}, got {scale}"
            )));
        }
        if let Some(p) = &self.history {
            crate::store::HistoryFormat::from_path(p).map_err(|e| self.key_error(e.to_string()))?;
            crate::store::atomic::check_output_file(p)?;
        }
        let floor_spectra = (self.floor_spectra.as_ref())
            .map(floor_spectra::FloorSpectraSettings::resolve)
            .transpose()
            .map_err(|m| self.key_error(m))?;
        let record = read(self.record.as_deref())?;
        let label = (self.record.as_ref()).map_or(record.name.clone(), |p| p.display().to_string());
        check_peak(&label, &record, scale).map_err(|m| self.key_error(m))?;
        if floor_spectra.is_some() {
            record
                .check_refinable(floor_spectra::REFINEMENT)
                .map_err(|m| self.key_error(m))?;
        }
        Ok(Simulation {
            record,
            scale,
            physics,
            model,
            integrator: self.integrator.unwrap_or(Integrator::Exact),
            rk4_substeps: self.rk4_substeps.unwrap_or(10),
            history: self.history,
            floor_spectra,
        })
    }

    /// The one-storey system of these settings.
    fn one_storey_model(&self, physics: &Physics) -> Result<Model, SimulationError> {
        if self.stacks.is_some() {
            return Err(self.key_error("`stacks` needs `building` (the floors they stand on)"));
        }
        let alpha = self.alpha.clone().unwrap_or_else(|| vec![0.5, 0.5]);
        let total: f64 = alpha.iter().sum();
        if total.is_finite() && total <= crate::limits::MAX_ALPHA {
            physics.check(total).map_err(SimulationError::Invalid)?;
        }
        let spec = SystemSpec {
            period_s: self.period.unwrap_or(1.0),
            damping_ratio: physics.structure_damping(total),
            mass_kg: 1.0,
            alpha,
            mu: self.mu.clone().unwrap_or_else(|| vec![0.2, 0.1]),
            mu_static: self.mu_static.clone(),
        };
        let structure = self.structure.unwrap_or(StructureKind::Elastic);
        let yielding = yielding(structure, self.yield_strength_ratio, self.post_yield_ratio)?;
        let mut system = System::new(&spec).map_err(|e| SimulationError::Invalid(e.to_string()))?;
        if let Some(y) = yielding {
            system = system
                .with_yielding(y)
                .map_err(|e| SimulationError::Invalid(e.to_string()))?;
        }
        if let Some(a) = &self.aspect {
            system = system
                .with_aspect(a)
                .map_err(|e| SimulationError::Invalid(e.to_string()))?;
        }
        Ok(Model::OneStorey { system, structure })
    }

    /// A message about the case file's keys, with the file's name when they came from one.
    fn key_error(&self, message: impl Into<String>) -> SimulationError {
        let message = message.into();
        match &self.file {
            Some(f) => SimulationError::Key {
                file: f.display().to_string(),
                message,
            },
            None => SimulationError::Invalid(message),
        }
    }

    /// The building of these settings (`building` given).
    fn building_model(
        &self,
        settings: &building::BuildingSettings,
        physics: &Physics,
    ) -> Result<Model, SimulationError> {
        let one_storey_keys = [
            ("period", self.period.is_some()),
            ("alpha", self.alpha.is_some()),
            ("mu", self.mu.is_some()),
            ("mu_static", self.mu_static.is_some()),
            ("structure", self.structure.is_some()),
            ("yield_strength_ratio", self.yield_strength_ratio.is_some()),
            ("post_yield_ratio", self.post_yield_ratio.is_some()),
            ("aspect", self.aspect.is_some()),
        ];
        if let Some((key, _)) = one_storey_keys.iter().find(|(_, given)| *given) {
            return Err(self.key_error(format!(
                "{key} (a key or flag of a one-storey case) does not apply to a case with \
                 `building` (the building's keys go under `building`, each stack's under `stacks`)"
            )));
        }
        let stacks = self.stacks.clone().unwrap_or_default();
        let spec = building::building_spec(settings, &stacks, physics.damping, physics.basis)
            .map_err(|m| self.key_error(m))?;
        let b = Building::new(&spec).map_err(|e| self.key_error(e.to_string()))?;
        Ok(Model::Building {
            building: Box::new(b),
            settings: settings.clone(),
        })
    }
}

/// Refuses a record (`label` in the message) whose peak times `scale` is beyond what a simulation
/// takes ([`MAX_PEAK_ACCEL_G`]).
fn check_peak(label: &str, record: &Record, scale: f64) -> Result<(), String> {
    let peak_g = record.pga_g() * scale;
    if peak_g > MAX_PEAK_ACCEL_G {
        return Err(format!(
            "`record` {label} peaks at {:.3e} g, times `scale` {scale} that is {peak_g:.3e} g, \
             beyond the {MAX_PEAK_ACCEL_G:e} g a simulation takes (its results would be round-off; \
             a unit or scale mistake?)",
            record.pga_g(),
        ));
    }
    Ok(())
}

/// The yielding model the settings ask for; `None` for the elastic structure. Each setting is
/// refused where it does not apply, and required where it does.
fn yielding(
    structure: StructureKind,
    strength: Option<f64>,
    r: Option<f64>,
) -> Result<Option<Yielding>, SimulationError> {
    let bad = |s: String| Err(SimulationError::Invalid(s));
    match (structure, strength, r) {
        (StructureKind::Elastic, None, None) => Ok(None),
        (StructureKind::Elastic, _, _) => bad(
            "`yield_strength_ratio` and `post_yield_ratio` apply only to `structure: epp` or \
             `structure: bilinear`"
                .into(),
        ),
        (_, None, _) => bad(format!(
            "`structure: {}` needs `yield_strength_ratio` (C_y = F_y/(m_p·g))",
            structure.name()
        )),
        (StructureKind::Epp, Some(c), None) => Ok(Some(Yielding::epp(c))),
        (StructureKind::Epp, Some(_), Some(r)) => bad(format!(
            "`structure: epp` has no post-yield stiffness (r = 0), got `post_yield_ratio: {r}`; \
             use `structure: bilinear`"
        )),
        (StructureKind::Bilinear, Some(_), None) => {
            bad("`structure: bilinear` needs `post_yield_ratio` (r, 0 ≤ r < 1)".into())
        }
        (StructureKind::Bilinear, Some(c), Some(r)) => Ok(Some(Yielding::bilinear(c, r))),
    }
}

/// What a simulation runs.
#[derive(Debug, Clone)]
pub enum Model {
    /// One storey (the paper's structure) with its stack.
    OneStorey {
        system: System,
        structure: StructureKind,
    },
    /// A building with stacks on its floors.
    Building {
        building: Box<Building>,
        settings: building::BuildingSettings,
    },
}

/// What a simulation gives: the one `--json` object of one storey or of a building.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Outcome {
    OneStorey(Box<Summary>),
    Building(Box<building::BuildingSummary>),
}

/// A checked simulation: one case under one record, ready to run.
#[derive(Debug, Clone)]
pub struct Simulation {
    pub record: Record,
    pub scale: f64,
    pub physics: Physics,
    pub model: Model,
    pub integrator: Integrator,
    pub rk4_substeps: usize,
    /// Where the time history goes, if asked for.
    pub history: Option<PathBuf>,
    /// The floor response spectra asked for.
    pub floor_spectra: Option<floor_spectra::FloorSpectraSpec>,
}

impl Simulation {
    /// The one-storey system; `None` for a building.
    pub fn system(&self) -> Option<&System> {
        match &self.model {
            Model::OneStorey { system, .. } => Some(system),
            Model::Building { .. } => None,
        }
    }

    /// This case under `record` instead of its own, the record's peak checked as
    /// [`Settings::resolve`] checks it.
    pub fn with_record(&self, record: Record) -> Result<Simulation, SimulationError> {
        check_peak(&record.name, &record, self.scale).map_err(SimulationError::Invalid)?;
        Ok(Simulation {
            record,
            scale: self.scale,
            physics: self.physics,
            model: self.model.clone(),
            integrator: self.integrator,
            rk4_substeps: self.rk4_substeps,
            history: self.history.clone(),
            floor_spectra: self.floor_spectra.clone(),
        })
    }

    /// About how long the run takes on a machine like the project's own (docs/faults.md,
    /// "Costs a user can see"), s: the record's samples times a cost per sample fitted to runs
    /// on this project's machine (RK4: per sub-step and body; the exact integrator of a
    /// building: as `N^4.5` for a two-block stack on every floor, the contact states it meets
    /// growing with the floors, each with its own modal basis). Measured, not bounded: how much
    /// a case slides can make it several times shorter or longer.
    pub fn cost_estimate_s(&self) -> f64 {
        let samples = self.record.accel_g.len() as f64;
        let substeps = self.rk4_substeps as f64;
        let per_sample_s = match &self.model {
            Model::OneStorey { system, .. } => {
                let bodies = 1.0 + system.blocks() as f64;
                match self.integrator {
                    Integrator::Exact => COST_ONE_STOREY_S * bodies,
                    Integrator::Rk4 => COST_RK4_S * substeps * bodies,
                }
            }
            Model::Building { building, .. } => {
                let n = building.storeys() as f64;
                let bodies = n + building.blocks() as f64;
                match self.integrator {
                    Integrator::Exact => COST_BUILDING_S * n.powf(4.5) * bodies / (3.0 * n),
                    Integrator::Rk4 => COST_RK4_S * substeps * bodies,
                }
            }
        };
        // Floor spectra: the case again on its record refined REFINEMENT times.
        let runs = match self.floor_spectra {
            Some(_) => 1.0 + floor_spectra::REFINEMENT as f64,
            None => 1.0,
        };
        runs * samples * per_sample_s
    }

    /// The record scaled, in m/s².
    pub fn accel_mps2(&self) -> Vec<f64> {
        self.record.accel_mps2(self.scale)
    }

    /// What the integrator says of the system against this record's step before it runs
    /// (`dynamics::accuracy_warnings`).
    pub fn warnings(&self, accel_mps2: &[f64]) -> Vec<String> {
        match &self.model {
            Model::OneStorey { system, .. } => {
                crate::dynamics::accuracy_warnings(system, &self.ground(accel_mps2))
            }
            Model::Building { .. } => Vec::new(),
        }
    }

    fn ground<'a>(&self, accel_mps2: &'a [f64]) -> Ground<'a> {
        Ground {
            dt_s: self.record.dt_s,
            accel_mps2,
        }
    }

    /// Runs the case on `accel_mps2` (from [`Simulation::accel_mps2`]); the time history is kept
    /// when the settings name a history file.
    pub fn run(&self, accel_mps2: &[f64]) -> Result<(Outcome, Option<History>), SimulationError> {
        self.run_keeping(accel_mps2, self.history.is_some())
    }

    /// [`Simulation::run`], keeping the time history when `history` (whatever the settings say:
    /// the Python module returns it as arrays rather than writing a file).
    pub fn run_keeping(
        &self,
        accel_mps2: &[f64],
        history: bool,
    ) -> Result<(Outcome, Option<History>), SimulationError> {
        self.run_watched(accel_mps2, history, &Unwatched)
    }

    /// [`Simulation::run_keeping`] under `watch` (a progress bar, Ctrl-C:
    /// [`crate::dynamics::Watch`]).
    pub fn run_watched(
        &self,
        accel_mps2: &[f64],
        history: bool,
        watch: &dyn Watch,
    ) -> Result<(Outcome, Option<History>), SimulationError> {
        let failed = |source| SimulationError::Simulation {
            record: self.record.name.clone(),
            source,
        };
        match &self.model {
            Model::OneStorey { system, structure } => {
                let ground = self.ground(accel_mps2);
                let response = match self.integrator {
                    Integrator::Exact => simulate_exact_watched(
                        system,
                        &ground,
                        &ExactOptions {
                            history,
                            ..ExactOptions::default()
                        },
                        watch,
                    ),
                    Integrator::Rk4 => {
                        simulate_rk4_watched(system, &ground, self.rk4_substeps, history, watch)
                    }
                }
                .map_err(failed)?;
                let mut summary = self.summary(system, *structure, &response);
                summary.floor_spectra = self.floor_spectra_of(watch)?;
                Ok((Outcome::OneStorey(Box::new(summary)), response.history))
            }
            Model::Building { building, settings } => {
                let mut r = self.run_building(building, accel_mps2, history, watch)?;
                let mut summary = building::building_summary(
                    building,
                    settings,
                    (
                        &self.record.name,
                        self.record.dt_s,
                        self.record.accel_g.len(),
                        self.scale,
                    ),
                    (self.physics.damping, self.physics.basis),
                    (self.integrator, self.rk4_substeps),
                    &r,
                );
                summary.floor_spectra = self.floor_spectra_of(watch)?;
                Ok((Outcome::Building(Box::new(summary)), r.history.take()))
            }
        }
    }

    /// The figure of a building case (`simulate --figure`): its stacks sliding against them
    /// rigidly attached ([`Building::with_stacks_attached`]), both run with their histories
    /// ([`building::building_figure`]). `None` for a one-storey case.
    pub fn building_figure(
        &self,
        accel_mps2: &[f64],
        watch: &dyn Watch,
    ) -> Result<Option<crate::render::chart::Figure>, SimulationError> {
        let Model::Building { building: b, .. } = &self.model else {
            return Ok(None);
        };
        let sliding = self.run_building(b, accel_mps2, true, watch)?;
        let attached = self.run_building(&b.with_stacks_attached(), accel_mps2, true, watch)?;
        let title = format!(
            "{} storeys, T_1 = {} s, under {} × {}",
            b.storeys(),
            b.spec().period_s,
            self.record.name,
            self.scale
        );
        Ok(Some(building::building_figure(
            b, &sliding, &attached, &title,
        )))
    }

    /// A building on `accel_mps2` with this simulation's integrator (the one-storey ones where
    /// the building is one storey with at most one stack).
    pub fn run_building(
        &self,
        b: &Building,
        accel_mps2: &[f64],
        history: bool,
        watch: &dyn Watch,
    ) -> Result<crate::dynamics::building::BuildingResponse, SimulationError> {
        building::run_building(
            b,
            self.record.dt_s,
            accel_mps2,
            self.integrator,
            self.rk4_substeps,
            history,
            watch,
        )
        .map_err(|source| SimulationError::Simulation {
            record: self.record.name.clone(),
            source,
        })
    }

    /// The floor response spectra, when the case asks for them.
    fn floor_spectra_of(
        &self,
        watch: &dyn Watch,
    ) -> Result<Option<floor_spectra::FloorSpectra>, SimulationError> {
        (self.floor_spectra.as_ref())
            .map(|spec| floor_spectra::floor_spectra(self, spec, floor_spectra::REFINEMENT, watch))
            .transpose()
    }

    fn summary(&self, sys: &System, structure: StructureKind, r: &Response) -> Summary {
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
            structure,
            yield_strength_ratio: hyst.map(|h| h.strength_ratio),
            post_yield_ratio: hyst.map(|h| h.post_yield_ratio),
            yield_displacement_m: hyst.map(|h| h.yield_displacement_m),
            peak_displacement_m: r.peak_displacement_m,
            peak_displacement_time_s: r.peak_displacement_time_s,
            peak_abs_accel_g: r.peak_abs_accel_mps2.iter().map(|a| a / G).collect(),
            peak_abs_velocity_mps: r.peak_abs_velocity_mps.clone(),
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
            aspect: sys.rocking().map(|r| r.aspect().to_vec()),
            rocking_onset: sys.rocking().map(|_| r.rocking_onset),
            floor_spectra: None,
        }
    }
}

/// What one simulation gives: the `simulate --json` contract (docs/simulate.md); field names are
/// relied on by users and checks.
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
    /// Structure, then blocks bottom-up: relative to the ground plus the ground's, m/s.
    pub peak_abs_velocity_mps: Vec<f64>,
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
    /// Width over height per block, as given (absent: rocking not checked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aspect: Option<Vec<f64>>,
    /// With `aspect`: `null`, or the block (1 = bottom) whose base the stack would first rock
    /// on, and when (docs/model.md, "Rocking: when a case leaves the model").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rocking_onset: Option<Option<RockingOnset>>,
    /// The structure's response spectra (`floor_spectra:` asked for them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor_spectra: Option<floor_spectra::FloorSpectra>,
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
    use crate::dynamics::simulate_exact;

    #[test]
    fn flags_override_the_file_and_defaults_fill_the_rest() {
        let file = Settings {
            period: Some(2.0),
            mu: Some(vec![0.3]),
            alpha: Some(vec![1.0]),
            ..Settings::default()
        };
        let flags = Settings {
            period: Some(0.5),
            ..Settings::default()
        };
        let case = flags.over(file).unwrap().resolve().unwrap();
        assert_eq!(case.system().unwrap().period_s(), 0.5);
        assert_eq!(case.system().unwrap().mu_kinetic(), &[0.3]);
        assert_eq!(case.scale, 1.0);
        assert_eq!(case.integrator, Integrator::Exact);
        assert_eq!(case.physics.basis, DampingBasis::Rigid);
    }

    #[test]
    fn every_key_of_the_file_survives_the_merge_and_every_flag_wins() {
        let yaml = "record: r.AT2\nperiod: 2.0\nalpha: [1.0]\nmu: [0.3]\nmu_static: [0.4]\n\
                    damping: 0.02\ndamping_basis: structure\nscale: 2.0\nintegrator: rk4\n\
                    rk4_substeps: 20\nstructure: bilinear\nyield_strength_ratio: 0.3\n\
                    post_yield_ratio: 0.05\naspect: [0.4]\nhistory: h.csv\n\
                    building: {storeys: 2, period: 0.5}\n\
                    stacks: [{floor: roof, alpha: [1.0], mu: [0.2]}]\n";
        let file: Settings = serde_yaml::from_str(yaml).unwrap();
        let value = |s: &Settings| serde_yaml::to_value(s).unwrap();
        // The file sets every key (a new one must be added here too).
        let keys = value(&file);
        assert!(keys.as_mapping().unwrap().values().all(|v| !v.is_null()));
        let nothing = Settings::default();
        assert_eq!(value(&nothing.clone().over(file.clone()).unwrap()), keys);
        assert_eq!(value(&file.clone().over(nothing).unwrap()), keys);
    }

    #[test]
    fn a_bad_setting_is_refused_before_the_record_is_read() {
        for (settings, expect) in [
            (
                Settings {
                    scale: Some(-1.0),
                    ..Settings::default()
                },
                "`scale` must be finite",
            ),
            (
                Settings {
                    yield_strength_ratio: Some(0.1),
                    ..Settings::default()
                },
                "apply only to `structure: epp` or `structure: bilinear`",
            ),
            (
                Settings {
                    history: Some("out.txt".into()),
                    ..Settings::default()
                },
                "out.txt",
            ),
        ] {
            let settings = Settings {
                record: Some("/nonexistent/record.AT2".into()),
                ..settings
            };
            let e = settings.resolve().unwrap_err();
            assert!(
                matches!(&e, SimulationError::Invalid(m) if m.contains(expect))
                    && crate::fault::classify(&e).kind == crate::fault::FaultKind::BadInput,
                "{e}"
            );
        }
    }

    #[test]
    fn the_summary_is_the_simulation_of_the_system() {
        let case = Settings::default().resolve().unwrap();
        let accel = case.accel_mps2();
        let (outcome, history) = case.run(&accel).unwrap();
        let Outcome::OneStorey(summary) = outcome else {
            panic!("a one-storey case")
        };
        let direct = simulate_exact(
            case.system().unwrap(),
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
