//! The IDA stage's numerics (docs/model.md, "Incremental dynamic analysis"): the `ida:` section
//! of a study, the two systems of a case on a yielding structure, and one work unit (one motion,
//! one case) traced by hunt & fill ([`crate::ida::trace`]).
//!
//! Per case two systems share the structure (its `k`, `c` and yield force `F_y`): the sliding
//! stack, and the same load rigidly attached (a bilinear SDOF of mass `m_p(1+α)`, so its
//! strength ratio on the total mass is `C_y/(1+α)`, docs/model.md "Yielding structure"). Both
//! are traced in `Sa(T_p, 5 %)` of the record, `T_p` the bare structure's period, so their
//! curves share one intensity axis. No skip rule is used: a stack that never slides is the
//! rigid system only while the structure stays elastic.
//!
//! In a building study (docs/model.md, "Incremental dynamic analysis", "In a building") every
//! case is traced in every frame of the study (`building.storeys` × `grid.stack_floor`): the
//! storeys yield with the strengths [`storey_strength_ratios`] gives the base-shear coefficient
//! `C_y`, `T_p` is the bare building's first-mode period `T_1`, the rigid system is the frame
//! with its stacks attached to their floors (same springs), and collapse is a peak interstorey
//! drift ratio of `collapse_drift_ratio`. A building of one storey runs as the one-storey model.

use super::building::Frame;
use super::physics::{Physics, SystemKind};
use super::storey_strength::storey_strength_ratios;
use crate::case::Case;
use crate::dynamics::building::{
    Building, BuildingError, BuildingResponse, StoreyYielding, simulate_building,
};
use crate::dynamics::{
    ExactOptions, G, Ground, ModelError, SimError, System, Yielding, simulate_exact,
};
use crate::grid::Grid;
use crate::ida::trace::{HuntFill, Trace, hunt_fill};
use crate::limits::{
    MAX_IDA_CASES, MAX_IDA_GRID_POINTS, MAX_IDA_PAD_S, MAX_IDA_TRACE_RUNS, MAX_TARGET_DUCTILITY,
    STRENGTH_RATIO_RANGE,
};
use crate::spectrum::TargetSpectrum;
use crate::spectrum::target::ZoneScaling;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The `ida:` section of a study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IdaConfig {
    pub structure: StructureConfig,
    /// The cases traced, each under every motion of every zone (static friction =
    /// `grid.mu_static_ratio` × kinetic): a list, or `grid` for every case of the study's grid.
    pub cases: IdaCases,
    /// Hunt & fill (Vamvatsikos & Cornell 2002), intensities `Sa(T_p, 5 %)` in g.
    pub tracing: HuntFill,
    /// The common intensity grid: `grid_points` equal steps from 0 to `tracing.cap_sa_g`
    /// (zero excluded).
    pub grid_points: usize,
    /// A run with a ductility at or above this counts as collapse (the model has no negative
    /// stiffness, so no dynamic instability ends a curve by itself); one storey only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collapse_ductility: Option<f64>,
    /// In a building study: a run whose peak interstorey drift ratio reaches this counts as
    /// collapse (the usual proxy, e.g. 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collapse_drift_ratio: Option<f64>,
    /// A block "falls off" when its peak slip relative to what it sits on reaches this, m.
    pub slip_limit_m: f64,
    pub limit_states: Vec<LimitState>,
    /// Zeros appended to every record so the residual drift is read near rest, s.
    #[serde(default)]
    pub pad_s: f64,
}

/// `ida.cases`: the cases as a list. A file may write `grid` instead: every case of the study's
/// grid, in its stored order ([`Grid::case`]), put in the list when the config is read
/// ([`IdaCases::expand`]), so the stage, its file and its fingerprint see the same list as a
/// file that writes those cases out (it serialises as the list).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct IdaCases {
    pub list: Vec<Case>,
    /// The file wrote `grid`.
    pub from_grid: bool,
}

/// The word a file writes for every case of the grid.
pub const GRID_CASES: &str = "grid";

impl IdaCases {
    /// The list of `grid`'s cases when the file wrote `grid`; refused above [`MAX_IDA_CASES`].
    pub fn expand(&mut self, grid: &Grid) -> Result<(), String> {
        if self.from_grid {
            if grid.cases() > MAX_IDA_CASES {
                return Err(format!(
                    "`{GRID_CASES}`: the grid has {} cases; an IDA takes at most {MAX_IDA_CASES}",
                    grid.cases()
                ));
            }
            self.list = (0..grid.cases()).map(|i| grid.case(i)).collect();
        }
        Ok(())
    }
}

impl std::ops::Deref for IdaCases {
    type Target = Vec<Case>;
    fn deref(&self) -> &Vec<Case> {
        &self.list
    }
}

impl Serialize for IdaCases {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.list.serialize(s)
    }
}

impl<'de> Deserialize<'de> for IdaCases {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match serde_yaml::Value::deserialize(d)? {
            serde_yaml::Value::String(w) if w == GRID_CASES => Ok(IdaCases {
                list: Vec::new(),
                from_grid: true,
            }),
            serde_yaml::Value::String(w) => Err(D::Error::custom(format!(
                "`{w}`: give a list of cases or `{GRID_CASES}` (every case of the grid)"
            ))),
            v => Ok(IdaCases {
                list: serde_yaml::from_value(v).map_err(D::Error::custom)?,
                from_grid: false,
            }),
        }
    }
}

/// The yielding structure: a strength stated directly or from the IS 1893 design force.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureConfig {
    /// Yield strength ratio `C_y = F_y/(m_p·g)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c_y: Option<f64>,
    /// `C_y = (Z/2)·(I/R)·(Sa/g)(T_p)` of the zone's IS 1893 target (Clause 6.4.2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design: Option<DesignStrength>,
    /// Post-yield stiffness ratio `r`.
    pub post_yield_ratio: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignStrength {
    /// Importance factor `I` (IS 1893 Table 8).
    pub importance: f64,
    /// Response reduction factor `R` (IS 1893 Table 9).
    pub response_reduction: f64,
}

/// A limit state for the fragility fits: exactly one of the two thresholds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LimitState {
    pub name: String,
    /// Exceeded when the ductility reaches this (or the run collapses).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ductility: Option<f64>,
    /// Exceeded when some interface's peak slip reaches this, m (or the run collapses).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slip_m: Option<f64>,
    /// In a building study: exceeded when the peak interstorey drift ratio reaches this (or
    /// the run collapses).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drift_ratio: Option<f64>,
}

impl LimitState {
    /// `ductility >= 2`, `peak slip >= 0.3 m` or `peak drift ratio >= 0.02`.
    pub fn definition(&self) -> String {
        match (self.ductility, self.slip_m, self.drift_ratio) {
            (Some(d), _, _) => format!("ductility >= {d}"),
            (None, Some(s), _) => format!("peak slip >= {s} m"),
            (None, None, Some(r)) => format!("peak drift ratio >= {r}"),
            (None, None, None) => String::new(),
        }
    }

    /// The threshold, whichever it is.
    pub fn threshold(&self) -> f64 {
        (self.ductility.or(self.slip_m).or(self.drift_ratio)).unwrap_or(f64::INFINITY)
    }
}

/// Where each demand sits among a run's demands ([`IdaConfig::demand_names`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DemandLayout {
    /// In a building study: the drift ratios and floor accelerations come first.
    pub building: bool,
    pub blocks: usize,
}

impl DemandLayout {
    /// The demand the curves are drawn in and collapse is judged on: the ductility on one
    /// storey, the peak interstorey drift ratio in a building.
    pub const PRIMARY: usize = 0;

    pub fn ductility(&self) -> usize {
        if self.building { 3 } else { 0 }
    }

    /// The peak slip of block 0 (the others follow).
    pub fn first_slip(&self) -> usize {
        if self.building { 4 } else { 2 }
    }

    /// The demand `limit` is judged on, and whether it is the largest peak slip of the blocks.
    pub fn of_limit(&self, limit: &LimitState) -> (usize, bool) {
        match (limit.ductility, limit.slip_m) {
            (Some(_), _) => (self.ductility(), false),
            (None, Some(_)) => (self.first_slip(), true),
            (None, None) => (Self::PRIMARY, false),
        }
    }

    /// Names in stored order (units in the names).
    pub fn names(&self) -> Vec<String> {
        let n = self.blocks;
        let mut v: Vec<String> = if self.building {
            [
                "peak_drift_ratio",
                "residual_drift_ratio",
                "peak_floor_accel_g",
                "ductility",
            ]
            .map(String::from)
            .to_vec()
        } else {
            vec!["ductility".to_string(), "residual_drift_m".to_string()]
        };
        v.extend((1..=n).map(|i| format!("peak_slip_{i}_m")));
        v.extend((1..=n).map(|i| format!("residual_slip_{i}_m")));
        v
    }
}

/// A system as traced: the one-storey model, or a building of several storeys.
#[derive(Debug, Clone)]
pub enum Traced {
    One(System),
    Building(Box<Building>),
}

/// A system of an IDA case that cannot be built.
#[derive(Debug, Error)]
pub enum IdaSystemError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Building(#[from] BuildingError),
}

/// The two systems of a case (module doc), in stored order.
pub const SYSTEMS: [SystemKind; 2] = [SystemKind::Stack, SystemKind::Rigid];

impl IdaConfig {
    /// The common intensity grid, g.
    pub fn grid_sa_g(&self) -> Vec<f64> {
        let n = self.grid_points;
        (1..=n)
            .map(|k| self.tracing.cap_sa_g * k as f64 / n as f64)
            .collect()
    }

    /// Blocks per case (validated equal for every case).
    pub fn blocks(&self) -> usize {
        self.cases.first().map_or(0, |c| c.alpha.len())
    }

    /// Where each demand of a run sits, in a building study or not.
    pub fn layout(&self, building: bool) -> DemandLayout {
        DemandLayout {
            building,
            blocks: self.blocks(),
        }
    }

    /// Names of the demands of every run, in stored order.
    pub fn demand_names(&self, building: bool) -> Vec<String> {
        self.layout(building).names()
    }

    /// `C_y` of `case` in the zone with target `target` (validated: IS 1893 when `design`).
    pub fn strength_ratio(&self, target: &TargetSpectrum, case: &Case) -> f64 {
        match (&self.structure.c_y, &self.structure.design, target) {
            (Some(c), _, _) => *c,
            (None, Some(d), TargetSpectrum::Is1893 { zone, soil, .. }) => TargetSpectrum::Is1893 {
                zone: *zone,
                soil: *soil,
                scaling: ZoneScaling::HalfZ,
                importance: d.importance,
                response_reduction: d.response_reduction,
            }
            .sa_g(case.period_s),
            _ => f64::NAN,
        }
    }

    /// The systems of [`SYSTEMS`] of `case` on the bilinear structure of strength ratio `c_y`
    /// in `frame`: the building whose storeys have [`storey_strength_ratios`] of the base shear
    /// coefficient `c_y`; one storey is the one-storey model.
    pub fn systems(
        &self,
        physics: &Physics,
        case: &Case,
        c_y: f64,
        frame: &Frame,
    ) -> Result<Vec<Traced>, IdaSystemError> {
        let r = self.structure.post_yield_ratio;
        if frame.storeys() == 1 {
            let yielding = Yielding::bilinear(c_y, r);
            return (SYSTEMS.iter())
                .map(|&kind| Ok(Traced::One(physics.system(kind, case, Some(yielding))?)))
                .collect();
        }
        let yielding = StoreyYielding {
            strength_ratios: storey_strength_ratios(
                c_y,
                &frame.floor_masses,
                &frame.storey_heights_m,
            ),
            post_yield_ratio: r,
        };
        (SYSTEMS.iter())
            .map(|&kind| {
                let b = physics.yielding_building(kind, case, frame, Some(yielding.clone()))?;
                Ok(Traced::Building(Box::new(b)))
            })
            .collect()
    }

    /// Every check that needs no record; `Err((key, why))` with keys under `ida.`.
    /// `targets` are the zones' target spectra (the design strength needs IS 1893 ones);
    /// `frames` the frames of a building study (`None`: one storey).
    pub fn validate(
        &self,
        physics: &Physics,
        targets: &[(String, TargetSpectrum)],
        frames: Option<&[Frame]>,
    ) -> Result<(), (String, String)> {
        self.validate_structure(targets)?;
        self.validate_cases(physics, targets, frames)?;
        self.validate_tracing()?;
        self.validate_curves(frames.is_some())?;
        self.validate_limit_states(frames.is_some())
    }

    /// `structure`: one strength, by `c_y` or by design (IS 1893 targets only), and `r`.
    fn validate_structure(
        &self,
        targets: &[(String, TargetSpectrum)],
    ) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((format!("ida.{k}"), w));
        let s = &self.structure;
        match (s.c_y, &s.design) {
            (Some(_), Some(_)) | (None, None) => {
                return err("structure", "give exactly one of `c_y` and `design`".into());
            }
            (Some(c), None) if !(STRENGTH_RATIO_RANGE.0..=STRENGTH_RATIO_RANGE.1).contains(&c) => {
                return err(
                    "structure.c_y",
                    format!(
                        "{c} must be in [{:e}, {:e}]",
                        STRENGTH_RATIO_RANGE.0, STRENGTH_RATIO_RANGE.1
                    ),
                );
            }
            (None, Some(d)) => {
                for (k, v) in [
                    ("importance", d.importance),
                    ("response_reduction", d.response_reduction),
                ] {
                    if !(v.is_finite() && v > 0.0 && v <= 100.0) {
                        return err(
                            &format!("structure.design.{k}"),
                            format!("{v} must be in (0, 100]"),
                        );
                    }
                }
                if let Some((name, _)) = targets
                    .iter()
                    .find(|(_, t)| !matches!(t, TargetSpectrum::Is1893 { .. }))
                {
                    return err(
                        "structure.design",
                        format!("zone {name}: its target is not an IS 1893 spectrum; give `c_y`"),
                    );
                }
            }
            _ => {}
        }
        let r = s.post_yield_ratio;
        if !(r.is_finite() && (0.0..1.0).contains(&r)) {
            return err(
                "structure.post_yield_ratio",
                format!("{r} must be in [0, 1)"),
            );
        }
        Ok(())
    }

    /// `cases`: how many, and each one's period, stack and systems.
    fn validate_cases(
        &self,
        physics: &Physics,
        targets: &[(String, TargetSpectrum)],
        frames: Option<&[Frame]>,
    ) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((format!("ida.{k}"), w));
        if self.cases.is_empty() || self.cases.len() > MAX_IDA_CASES {
            return err(
                "cases",
                format!("{} cases; needs 1 to {MAX_IDA_CASES}", self.cases.len()),
            );
        }
        let n = self.blocks();
        for (i, c) in self.cases.iter().enumerate() {
            let key = |k: &str| format!("cases[{i}].{k}");
            c.check(n).or_else(|(k, why)| err(&key(k), why))?;
            let total = c.alpha_total();
            physics
                .check(total)
                .map_err(|why| (format!("ida.{}", key("alpha")), why))?;
            let one = [Frame::one_storey()];
            for (zone, t) in targets {
                let c_y = self.strength_ratio(t, c);
                for frame in frames.unwrap_or(&one) {
                    self.systems(physics, c, c_y, frame).map_err(|e| {
                        let at = frames.map_or(String::new(), |_| format!(" ({frame})"));
                        (
                            "ida.structure".to_string(),
                            format!("zone {zone}, case {i}{at}: {e}"),
                        )
                    })?;
                }
            }
        }
        Ok(())
    }

    /// `tracing`: its intensities, and the runs a trace may take.
    fn validate_tracing(&self) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((format!("ida.{k}"), w));
        let t = &self.tracing;
        if !(t.first_sa_g.is_finite() && t.first_sa_g > 0.0) {
            return err(
                "tracing.first_sa_g",
                format!("{} must be > 0", t.first_sa_g),
            );
        }
        if !(t.step_increment_sa_g.is_finite() && t.step_increment_sa_g >= 0.0) {
            return err(
                "tracing.step_increment_sa_g",
                format!("{} must be ≥ 0", t.step_increment_sa_g),
            );
        }
        if !(t.cap_sa_g.is_finite() && t.cap_sa_g >= t.first_sa_g) {
            return err(
                "tracing.cap_sa_g",
                format!("{} must be ≥ first_sa_g", t.cap_sa_g),
            );
        }
        // Bounded before the hunt is counted: its steps are at least `first_sa_g`.
        let hunt_bound = (t.cap_sa_g / t.first_sa_g).ceil() + 1.0;
        let extra = t.bracket_runs.saturating_add(t.fill_runs);
        let runs = if hunt_bound > MAX_IDA_TRACE_RUNS as f64 {
            usize::MAX
        } else {
            t.max_hunt_runs().saturating_add(extra)
        };
        if runs > MAX_IDA_TRACE_RUNS {
            return err(
                "tracing",
                format!(
                    "{} runs per trace (hunt up to cap_sa_g, brackets, fills); at most \
                     {MAX_IDA_TRACE_RUNS}",
                    if runs == usize::MAX {
                        "too many".to_string()
                    } else {
                        runs.to_string()
                    }
                ),
            );
        }
        Ok(())
    }

    /// The curves and their end: `grid_points`, `collapse_ductility` (one storey) or
    /// `collapse_drift_ratio` (a building), `slip_limit_m`, `pad_s`.
    fn validate_curves(&self, building: bool) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((format!("ida.{k}"), w));
        if self.grid_points < 2 || self.grid_points > MAX_IDA_GRID_POINTS {
            return err(
                "grid_points",
                format!("{} must be 2 to {MAX_IDA_GRID_POINTS}", self.grid_points),
            );
        }
        match (building, self.collapse_ductility, self.collapse_drift_ratio) {
            (false, Some(d), None) => {
                if !(d.is_finite() && d > 1.0 && d <= MAX_TARGET_DUCTILITY) {
                    return err(
                        "collapse_ductility",
                        format!("{d} must be > 1 and ≤ {MAX_TARGET_DUCTILITY}"),
                    );
                }
            }
            (false, _, Some(_)) => {
                return err(
                    "collapse_drift_ratio",
                    "is for a building study; one storey collapses at `collapse_ductility`".into(),
                );
            }
            (false, None, None) => return err("collapse_ductility", "is missing".into()),
            (true, None, Some(r)) => {
                if !(r.is_finite() && r > 0.0 && r <= 1.0) {
                    return err("collapse_drift_ratio", format!("{r} must be in (0, 1]"));
                }
            }
            (true, Some(_), _) => {
                return err(
                    "collapse_ductility",
                    "a building study's collapse is its peak interstorey drift ratio: give \
                     `collapse_drift_ratio` instead (e.g. 0.1)"
                        .into(),
                );
            }
            (true, None, None) => {
                return err(
                    "collapse_drift_ratio",
                    "is missing: a building study's collapse is its peak interstorey drift \
                     ratio (e.g. 0.1)"
                        .into(),
                );
            }
        }
        let sl = self.slip_limit_m;
        if !(sl.is_finite() && sl > 0.0) {
            return err("slip_limit_m", format!("{sl} must be > 0"));
        }
        if !(self.pad_s.is_finite() && (0.0..=MAX_IDA_PAD_S).contains(&self.pad_s)) {
            return err(
                "pad_s",
                format!("{} must be in [0, {MAX_IDA_PAD_S}]", self.pad_s),
            );
        }
        Ok(())
    }

    /// `limit_states`: at least one, named once each, with one finite threshold (a drift ratio
    /// only in a building study).
    fn validate_limit_states(&self, building: bool) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((format!("ida.{k}"), w));
        if self.limit_states.is_empty() {
            return err("limit_states", "needs at least one limit state".into());
        }
        for (i, l) in self.limit_states.iter().enumerate() {
            let key = format!("limit_states[{i}]");
            let earlier = self.limit_states[..i].iter().map(|o| o.name.as_str());
            crate::limits::check_name(&l.name, earlier)
                .map_err(|why| (format!("ida.{key}.name"), why))?;
            if l.drift_ratio.is_some() && !building {
                return err(
                    &format!("{key}.drift_ratio"),
                    "is for a building study (a `building:` section)".into(),
                );
            }
            let given = [l.ductility, l.slip_m, l.drift_ratio];
            match given.iter().flatten().collect::<Vec<_>>()[..] {
                [v] if v.is_finite() && *v > 0.0 => {}
                [_] => return err(&key, "the threshold must be finite and > 0".into()),
                _ if building => {
                    return err(
                        &key,
                        "give exactly one of `ductility`, `slip_m` and `drift_ratio`".into(),
                    );
                }
                _ => return err(&key, "give exactly one of `ductility` and `slip_m`".into()),
            }
        }
        Ok(())
    }
}

/// What one run leaves: the demands in the order of [`IdaConfig::demand_names`], and the flags.
#[derive(Debug, Clone, PartialEq)]
pub struct RunDemand {
    pub values: Vec<f64>,
    pub slip_exceeded: bool,
}

/// `Sa(T_p, 5 %)` of a record, g (exact peak between samples, `spectrum::response`), damped as
/// the target spectra are.
pub fn sa_g(
    accel_mps2: &[f64],
    dt_s: f64,
    period_s: f64,
) -> Result<f64, crate::spectrum::SpectrumError> {
    let peak = crate::spectrum::response::peak_response(
        accel_mps2,
        dt_s,
        period_s,
        crate::spectrum::TARGET_DAMPING,
    )?;
    let omega = std::f64::consts::TAU / period_s;
    Ok(omega * omega * peak.sd_m / G)
}

/// Traces one system under one record: `padded_mps2` is the record followed by the pad of zeros,
/// `record_sa_g` the unscaled record's `Sa(T_p, 5 %)`; every run scales the whole record.
/// `storey_heights_m`: the frame's, in a building study (its demands are then drift ratios).
pub fn trace_system(
    cfg: &IdaConfig,
    sys: &Traced,
    storey_heights_m: Option<&[f64]>,
    padded_mps2: &[f64],
    dt_s: f64,
    record_sa_g: f64,
) -> Result<Trace<RunDemand>, SimError> {
    // What `run_demand` reads: no energies, velocities or floor displacements.
    let opts = ExactOptions {
        energy_balance: false,
        abs_velocity: false,
        floor_displacements: false,
        ..ExactOptions::default()
    };
    let mut accel = Vec::with_capacity(padded_mps2.len());
    hunt_fill(&cfg.tracing, |sa| {
        let lambda = sa / record_sa_g;
        accel.clear();
        accel.extend(padded_mps2.iter().map(|a| lambda * a));
        let ground = Ground {
            dt_s,
            accel_mps2: &accel,
        };
        let r = match sys {
            Traced::One(s) => BuildingResponse::from_one_storey(simulate_exact(s, &ground, &opts)?),
            Traced::Building(b) => simulate_building(b, &ground, &opts)?,
        };
        Ok(run_demand(cfg, &r, storey_heights_m))
    })
}

/// The demands of one run (in the order of [`IdaConfig::demand_names`]) and whether it counts
/// as collapse. Each block's slip is the largest over the stacks (one per loaded floor; the
/// same blocks on each), in absolute value.
pub fn run_demand(
    cfg: &IdaConfig,
    r: &BuildingResponse,
    storey_heights_m: Option<&[f64]>,
) -> (RunDemand, bool) {
    let n = cfg.blocks();
    let ductility = r.storey_ductility.as_ref().map_or(f64::NAN, |d| {
        d.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    });
    let slips = |v: &[f64]| -> Vec<f64> {
        let mut s = vec![0.0f64; n];
        for (k, x) in v.iter().enumerate() {
            s[k % n] = s[k % n].max(x.abs());
        }
        s
    };
    let peak = slips(&r.peak_slip_m);
    let slip_exceeded = peak.iter().any(|&s| s >= cfg.slip_limit_m);
    let (mut values, collapsed) = match storey_heights_m {
        None => (
            vec![ductility, r.storey_residual_drift_m[0].abs()],
            ductility >= cfg.collapse_ductility.unwrap_or(f64::INFINITY),
        ),
        Some(h) => {
            let ratio = |d: &[f64]| -> f64 {
                d.iter()
                    .zip(h)
                    .map(|(d, h)| d.abs() / h)
                    .fold(0.0, f64::max)
            };
            let drift = ratio(&r.storey_peak_drift_m);
            let accel = r
                .floor_peak_abs_accel_mps2
                .iter()
                .copied()
                .fold(0.0, f64::max)
                / G;
            let values = vec![drift, ratio(&r.storey_residual_drift_m), accel, ductility];
            (
                values,
                drift >= cfg.collapse_drift_ratio.unwrap_or(f64::INFINITY),
            )
        }
    };
    values.extend(peak);
    values.extend(slips(&r.residual_slip_m));
    (
        RunDemand {
            values,
            slip_exceeded,
        },
        collapsed,
    )
}

/// The record followed by `pad_s` of zeros, m/s².
pub fn padded(accel_mps2: &[f64], dt_s: f64, pad_s: f64) -> Vec<f64> {
    let extra = (pad_s / dt_s).ceil() as usize;
    let mut v = Vec::with_capacity(accel_mps2.len() + extra);
    v.extend_from_slice(accel_mps2);
    v.resize(accel_mps2.len() + extra, 0.0);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_s_indices_name_their_demands() {
        for building in [false, true] {
            let l = DemandLayout {
                building,
                blocks: 3,
            };
            let names = l.names();
            assert_eq!(names.len(), if building { 4 } else { 2 } + 2 * 3);
            assert_eq!(names[l.ductility()], "ductility");
            assert_eq!(names[l.first_slip()], "peak_slip_1_m");
            assert_eq!(names[l.first_slip() + 3], "residual_slip_1_m");
            let primary = if building {
                "peak_drift_ratio"
            } else {
                "ductility"
            };
            assert_eq!(names[DemandLayout::PRIMARY], primary);
        }
    }

    /// A building's demands from a response set by hand: two storeys of 3 m and 4 m, two stacks
    /// of two blocks (a stack on each floor).
    #[test]
    fn a_building_s_demands_are_its_largest_ratios_and_slips() {
        let cfg: IdaConfig = serde_yaml::from_str(
            "structure: { c_y: 0.3, post_yield_ratio: 0.05 }\n\
             cases: [{ period_s: 1.0, alpha: [0.5, 0.5], mu: [0.2, 0.1] }]\n\
             tracing: { first_sa_g: 0.1, step_increment_sa_g: 0.1, bracket_runs: 1, \
             fill_runs: 1, cap_sa_g: 1.0 }\n\
             grid_points: 10\n\
             collapse_drift_ratio: 0.02\n\
             slip_limit_m: 0.3\n\
             limit_states: [{ name: LS, drift_ratio: 0.01 }]\n",
        )
        .unwrap();
        let mut r = BuildingResponse::zeroed(2, 4, 1);
        r.storey_peak_drift_m = vec![0.066, 0.04]; // 0.022 and 0.01 of the heights
        r.storey_residual_drift_m = vec![-0.003, 0.008]; // 0.001 and 0.002
        r.floor_peak_abs_accel_mps2 = vec![G, 2.5 * G];
        r.storey_ductility = Some(vec![3.0, 1.5]);
        r.peak_slip_m = vec![0.1, -0.05, 0.2, 0.01];
        r.residual_slip_m = vec![-0.04, 0.0, 0.02, -0.03];
        let (d, collapsed) = run_demand(&cfg, &r, Some(&[3.0, 4.0]));
        let want = [0.022, 0.002, 2.5, 3.0, 0.2, 0.05, 0.04, 0.03];
        for (got, want) in d.values.iter().zip(want) {
            assert!((got - want).abs() <= 1e-15, "{:?}", d.values);
        }
        assert_eq!(d.values.len(), want.len());
        assert!(collapsed && !d.slip_exceeded);
        r.storey_peak_drift_m[0] = 0.059; // 0.0197: below the cap 0.02
        r.peak_slip_m[3] = -0.3;
        let (d, collapsed) = run_demand(&cfg, &r, Some(&[3.0, 4.0]));
        assert!(!collapsed && d.slip_exceeded);
    }
}
