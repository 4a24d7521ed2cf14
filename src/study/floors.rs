//! The floor response spectra of a study (`floor_spectra:`; docs/model.md, "Floor response
//! spectra", "In a study"): listed cases, each on every frame, under every motion of every
//! zone, with the stacks sliding and with them rigidly attached. One unit is one case on one
//! frame under one motion; the stage ([`crate::pipeline::floors`]) runs the units and stores
//! them.

use super::building::Frame;
use super::physics::{CaseError, Physics, SystemKind};
use crate::case::Case;
use crate::dynamics::building::BuildingResponse;
use crate::dynamics::{ExactOptions, G, Ground};
use crate::ground_motion::Record;
use crate::limits::MAX_FLOOR_SPECTRA_CASES;
use crate::spectrum::floor::{
    FloorSpectraSettings, FloorSpectraSpec, Periods, REFINEMENT, floor_psa_g,
};
use serde::{Deserialize, Serialize};

/// The `floor_spectra:` section of a study config.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FloorsConfig {
    /// Oscillator periods, s: the `--periods` syntax or a list [default: 0.05:4:0.01].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periods: Option<Periods>,
    /// Oscillator damping ratios [default: [0.05]].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<Vec<f64>>,
    /// The cases (a building's `period_s` is its bare first-mode period `T_1`), each on every
    /// frame of a building study (static friction = `grid.mu_static_ratio` × kinetic).
    pub cases: Vec<Case>,
}

/// The two systems of every unit, in stored order: the stack sliding, then rigidly attached.
pub const SYSTEMS: [SystemKind; 2] = [SystemKind::Stack, SystemKind::Rigid];

impl FloorsConfig {
    /// The periods and damping ratios, checked; the key under `floor_spectra.` and why
    /// otherwise.
    pub fn spec(&self) -> Result<FloorSpectraSpec, (&'static str, String)> {
        FloorSpectraSettings {
            periods: self.periods.clone(),
            damping: self.damping.clone(),
        }
        .checked()
    }

    /// The section checked before any work: its spectra and cases (each as the physics and
    /// every frame can build it); the key under `floor_spectra.` and why otherwise.
    pub fn validate(
        &self,
        physics: &Physics,
        frames: Option<&[Frame]>,
    ) -> Result<(), (String, String)> {
        let err = |k: &str, w: String| Err((format!("floor_spectra.{k}"), w));
        if let Err((key, why)) = self.spec() {
            return err(key, why);
        }
        if self.cases.is_empty() || self.cases.len() > MAX_FLOOR_SPECTRA_CASES {
            return err(
                "cases",
                format!(
                    "{} cases; needs 1 to {MAX_FLOOR_SPECTRA_CASES}",
                    self.cases.len()
                ),
            );
        }
        let blocks = self.cases[0].alpha.len();
        for (i, c) in self.cases.iter().enumerate() {
            let key = |k: &str| format!("cases[{i}].{k}");
            c.check(blocks).or_else(|(k, why)| err(&key(k), why))?;
            physics
                .check(c.alpha_total())
                .or_else(|why| err(&key("alpha"), why))?;
            for frame in frames.unwrap_or_default() {
                physics.building(SystemKind::Stack, c, frame).map_err(|e| {
                    (
                        format!("floor_spectra.{}", key("alpha")),
                        format!("{frame}: {e}"),
                    )
                })?;
            }
        }
        Ok(())
    }
}

/// What one unit stores: per system ([`SYSTEMS`]), each floor's spectra `[damping][floor]
/// [period]` (g) and peak absolute acceleration (g), floor 1 first.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorUnit {
    pub psa_g: [Vec<Vec<Vec<f64>>>; 2],
    pub pfa_g: [Vec<f64>; 2],
}

/// One system's run on the refined record, its history kept.
fn run(
    physics: &Physics,
    kind: SystemKind,
    case: &Case,
    frame: &Frame,
    ground: &Ground,
) -> Result<BuildingResponse, CaseError> {
    let opts = ExactOptions {
        history: true,
        energy_balance: false,
        abs_velocity: false,
        floor_displacements: false,
        ..ExactOptions::default()
    };
    physics.simulate_building(kind, case, frame, ground, &opts, None)
}

/// `case` on `frame` (one storey: [`Frame::one_storey`]) under `record`: each floor's spectra as `spec` asks,
/// from its history on the record refined [`REFINEMENT`] times, with the stack sliding and
/// rigidly attached.
pub fn floor_unit(
    physics: &Physics,
    case: &Case,
    frame: &Frame,
    record: &Record,
    spec: &FloorSpectraSpec,
) -> Result<FloorUnit, FloorsError> {
    let fine = record.refined(REFINEMENT);
    let accel = fine.accel_mps2(1.0);
    let ground = Ground::new(fine.dt_s, &accel);
    let floors = frame.storeys();
    let mut psa_g: [Vec<Vec<Vec<f64>>>; 2] = Default::default();
    let mut pfa_g: [Vec<f64>; 2] = Default::default();
    for (s, kind) in SYSTEMS.into_iter().enumerate() {
        let r = run(physics, kind, case, frame, &ground)?;
        let h = r
            .history
            .as_ref()
            .expect("a run asked for its history keeps it");
        psa_g[s] = floor_psa_g(h, floors, fine.dt_s, spec)?;
        pfa_g[s] = (r.floor_peak_abs_accel_mps2.iter())
            .map(|a| a / G)
            .collect();
    }
    Ok(FloorUnit { psa_g, pfa_g })
}

/// Why a unit could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FloorsError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error("the floor spectrum: {0}")]
    Spectrum(#[from] crate::spectrum::SpectrumError),
}

/// ASCE 7-16 Table 13.5-1's footnote: a component whose period is at most 0.06 s is rigid
/// (`a_p = 1`), a longer one flexible (`a_p = 2.5`), s.
pub const RIGID_COMPONENT_PERIOD_S: f64 = 0.06;

/// The height factor of ASCE 7-16 Eq. 13.3-1, `1 + 2·z/h`: the floor's acceleration over the
/// ground's at height `z` of a building `h` tall.
pub fn asce7_16_height_factor(z_over_h: f64) -> f64 {
    1.0 + 2.0 * z_over_h
}

/// ASCE 7-22's `H_f` (Eq. 13.3-4), the floor's acceleration over the ground's at height `z` of
/// a building `h` tall whose approximate fundamental period is `t_a_s`:
/// `1 + a_1·(z/h) + a_2·(z/h)^10`, `a_1 = min(1/T_a, 2.5)`, `a_2 = max(1 − (0.4/T_a)², 0)`.
pub fn asce7_22_h_f(z_over_h: f64, t_a_s: f64) -> f64 {
    let a1 = (1.0 / t_a_s).min(2.5);
    let a2 = (1.0 - (0.4 / t_a_s).powi(2)).max(0.0);
    1.0 + a1 * z_over_h + a2 * z_over_h.powi(10)
}

/// ASCE 7-22's component resonance ductility factor `C_AR` (Tables 13.5-1 and 13.6-1) of a
/// component supported above grade whose period is near the building's (the value most of the
/// tables' flexible rows take; a rigid component takes 1, and "other" equipment support
/// structures 2.8). Read from the tables as public `F_p` calculators transcribe them
/// (FpCalcApp's `data/mech.json`), not from the standard itself.
pub const ASCE7_22_C_AR_RESONANT: f64 = 2.2;

/// ASCE 7-22's structure ductility reduction factor `R_μ = (1.1·R/(I_e·Ω_0))^½ ≥ 1.3` of a
/// building with response modification `r`, importance `i_e` and overstrength `omega_0`; an
/// elastic frame (`R = Ω_0 = I_e = 1`) takes the floor, 1.3.
pub fn asce7_22_r_mu(r: f64, i_e: f64, omega_0: f64) -> f64 {
    (1.1 * r / (i_e * omega_0)).sqrt().max(1.3)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The code's factors at their ends: the ground (1), the roof (ASCE 7-16: 3); ASCE 7-22 at
    /// `T_a = 0.4 s` has `a_1 = 2.5`, `a_2 = 0`; at `T_a = 1 s`, `a_1 = 1`, `a_2 = 0.84`.
    #[test]
    fn the_code_factors_at_their_ends() {
        assert_eq!(asce7_16_height_factor(0.0), 1.0);
        assert_eq!(asce7_16_height_factor(1.0), 3.0);
        assert_eq!(asce7_22_h_f(0.0, 1.0), 1.0);
        assert!((asce7_22_h_f(1.0, 0.4) - 3.5).abs() < 1e-15);
        assert!((asce7_22_h_f(1.0, 1.0) - 2.84).abs() < 1e-15);
        assert!((asce7_22_h_f(0.5, 1.0) - (1.5 + 0.84 * 0.5f64.powi(10))).abs() < 1e-15);
        // Short periods: a_1 capped at 2.5, a_2 at 0.
        assert!((asce7_22_h_f(1.0, 0.1) - 3.5).abs() < 1e-15);
    }

    /// `R_μ` at its floor (an elastic frame: `√1.1` is below 1.3) and above it, against a
    /// published worked example (a frame with `R = 6.5`, `Ω_0 = 3`, `I_e = 1`: 1.544, to the
    /// example's three decimals).
    #[test]
    fn the_ductility_factor_at_its_floor_and_above() {
        assert_eq!(asce7_22_r_mu(1.0, 1.0, 1.0), 1.3);
        assert_eq!(asce7_22_r_mu(1.5, 1.0, 1.0), 1.3);
        assert!((asce7_22_r_mu(6.5, 1.0, 3.0) - 1.544).abs() < 5e-4);
    }
}
