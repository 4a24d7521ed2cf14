//! A building case's FEMA P-58 demands under a set of motions, in pelicun's demand-sample format
//! (docs/building.md, "FEMA P-58 demands through pelicun"): per motion, each floor's peak
//! absolute acceleration (PFA, the ground as floor 0) and velocity (PFV), each storey's peak and
//! residual drift ratio (PID, RID), with the stacks sliding or rigidly attached.

use super::{Model, Settings, Simulation, SimulationError};
use crate::dynamics::{G, Unwatched, Watch};
use crate::ground_motion::{Record, peak_ground_velocity_mps};
use std::io::Write;
use std::path::Path;

/// Why a case without `building` has no FEMA P-58 demands.
const NOT_A_BUILDING: &str = "FEMA P-58 demands are a building's: the case needs the key \
                              `building` (one storey is `building: {storeys: 1, …}`)";

/// `export edp` (the command and Python's `export_edp`): the building case of the file `config`
/// under each of `records`, its demand sample written to `out` (CSV). Bad input (`out` not a
/// CSV file that can be made, a case that is not a building) is refused before any run.
pub fn export(
    config: &Path,
    records: &[Record],
    stacks: Stacks,
    out: &Path,
) -> Result<Vec<Demands>, SimulationError> {
    check_sample_path(out)?;
    if records.is_empty() {
        return Err(SimulationError::Setting {
            key: "records".into(),
            message: "a demand sample needs at least one record (one row per record)".into(),
        });
    }
    let sim = Settings::read(config)?.resolve()?;
    if !matches!(sim.model, Model::Building { .. }) {
        return Err(SimulationError::Key {
            file: config.display().to_string(),
            message: NOT_A_BUILDING.into(),
        });
    }
    let rows = demands(&sim, records, stacks, &Unwatched)?;
    write_sample(&rows, out)?;
    Ok(rows)
}

/// `Err` unless a demand sample (CSV) can be written at `out`, checked before any work.
pub fn check_sample_path(out: &Path) -> Result<(), crate::store::atomic::OutputPathError> {
    crate::store::atomic::check_output_extension(out, "a demand sample", &["csv"])
}

/// Writes `rows` to `out` as the demand sample ([`write_csv`]): the whole file or, failing,
/// none of it ([`crate::store::atomic::write_bytes`]).
pub fn write_sample(rows: &[Demands], out: &Path) -> Result<(), crate::store::StoreError> {
    let mut bytes = Vec::new();
    write_csv(rows, &mut bytes).expect("a CSV written to memory");
    crate::store::atomic::write_bytes(out, &bytes)
}

/// Whether the stacks slide on their floors (the case as stated) or are rigidly attached
/// ([`crate::dynamics::building::Building::with_stacks_attached`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stacks {
    Sliding,
    Attached,
}

/// One motion's demands: floors `0 ..= N` (0 the ground), storeys `1 ..= N`.
#[derive(Debug, Clone, PartialEq)]
pub struct Demands {
    pub motion: String,
    /// Peak floor acceleration, g.
    pub pfa_g: Vec<f64>,
    /// Peak floor velocity, m/s.
    pub pfv_mps: Vec<f64>,
    /// Peak interstorey drift over the storey's height.
    pub pid_rad: Vec<f64>,
    /// `|drift|` at the record's end over the storey's height.
    pub rid_rad: Vec<f64>,
}

/// The demands of `sim` (a building case) under each of `records` (the case's `scale` applied to
/// each), in order.
pub fn demands(
    sim: &Simulation,
    records: &[Record],
    stacks: Stacks,
    watch: &dyn Watch,
) -> Result<Vec<Demands>, SimulationError> {
    let Model::Building { building, settings } = &sim.model else {
        return Err(SimulationError::Invalid(NOT_A_BUILDING.into()));
    };
    let heights = settings
        .storey_heights()
        .map_err(SimulationError::Invalid)?;
    let building = match stacks {
        Stacks::Sliding => (**building).clone(),
        Stacks::Attached => building.with_stacks_attached(),
    };
    records
        .iter()
        .map(|record| {
            let case = sim.with_record(record.clone())?;
            let accel = case.accel_mps2();
            let r = case.run_building(&building, &accel, false, watch)?;
            let pga_g = accel.iter().fold(0.0f64, |p, a| p.max(a.abs())) / G;
            let pgv = peak_ground_velocity_mps(&accel, record.dt_s);
            let ratios = |drifts: &[f64]| -> Vec<f64> {
                drifts
                    .iter()
                    .zip(&heights)
                    .map(|(d, h)| d.abs() / h)
                    .collect()
            };
            Ok(Demands {
                motion: record.name.clone(),
                pfa_g: std::iter::once(pga_g)
                    .chain(r.floor_peak_abs_accel_mps2.iter().map(|a| a / G))
                    .collect(),
                pfv_mps: std::iter::once(pgv)
                    .chain(r.floor_peak_abs_velocity_mps.iter().copied())
                    .collect(),
                pid_rad: ratios(&r.storey_peak_drift_m),
                rid_rad: ratios(&r.storey_residual_drift_m),
            })
        })
        .collect()
}

/// pelicun's column kinds in the order written, with their units row entry.
const KINDS: [(&str, &str); 4] = [("PFA", "g"), ("PFV", "mps"), ("PID", "rad"), ("RID", "rad")];

/// Writes `rows` as pelicun's demand sample (`Assessment.demand.load_sample`): a header of
/// `EVENT-TYPE-LOCATION-DIRECTION` labels (event 1, direction 1; PFA and PFV at floors
/// `0 ..= N`, PID and RID at storeys `1 ..= N`), a `Units` row, then one row per motion
/// labelled by its name.
pub fn write_csv(rows: &[Demands], out: impl Write) -> csv::Result<()> {
    let storeys = rows.first().map_or(0, |r| r.pid_rad.len());
    let levels = |kind: &str| -> std::ops::RangeInclusive<usize> {
        if kind.starts_with("PF") {
            0..=storeys
        } else {
            1..=storeys
        }
    };
    let mut w = csv::Writer::from_writer(out);
    let mut header = vec![String::new()];
    let mut units = vec!["Units".to_string()];
    for (kind, unit) in KINDS {
        for at in levels(kind) {
            header.push(format!("1-{kind}-{at}-1"));
            units.push(unit.to_string());
        }
    }
    w.write_record(&header)?;
    w.write_record(&units)?;
    for r in rows {
        let mut line = vec![r.motion.clone()];
        for values in [&r.pfa_g, &r.pfv_mps, &r.pid_rad, &r.rid_rad] {
            line.extend(values.iter().map(|v| format!("{v:e}")));
        }
        w.write_record(&line)?;
    }
    w.flush()?;
    Ok(())
}
