//! `slidestack export edp --study`'s entry point: one case of a finished building study, its
//! FEMA P-58 demands under each of its zone's motions, read from `sweep.h5` (checked, and made
//! from that `motions.h5`) and written as pelicun's demand sample
//! ([`crate::one_case::edp::write_sample`]); docs/building.md, "FEMA P-58 demands through
//! pelicun".

use crate::grid::StackFloor;
use crate::one_case::edp::{Demands, Stacks, check_sample_path, write_sample};
use crate::store::StoreError;
use crate::store::h5::stored_fingerprint;
use crate::store::motions::read_zone_motions;
use crate::store::sweep::read_zone_sweep;
use crate::store::tnew::{is_building, read_motions_fingerprint, zones_and_blocks};
use ndarray::ArrayD;
use std::path::{Path, PathBuf};

/// One case of a building study: its zone, frame (`storeys`, `stack_floor`) and grid values.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameQuery {
    pub zone: String,
    pub storeys: usize,
    pub stack_floor: StackFloor,
    /// The bare building's first-mode period `T_p`, s.
    pub period_s: f64,
    pub alpha: Vec<f64>,
    pub mu: Vec<f64>,
}

#[derive(Debug, thiserror::Error)]
pub enum FrameEdpError {
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error(transparent)]
    Output(#[from] crate::store::atomic::OutputPathError),
    #[error("{dir}: no finished {file} (run the study's sweep)")]
    Missing { dir: PathBuf, file: &'static str },
    #[error("{file}: a one-storey study; FEMA P-58 demands are a building study's")]
    NotBuilding { file: PathBuf },
    #[error("{file}: made from another motions.h5: rerun the study")]
    OtherMotions { file: PathBuf },
    /// A list of another length than the study's stacks have blocks.
    #[error("{file}: `{key}` lists {given} values; the study's stacks have {blocks} blocks")]
    Blocks {
        file: PathBuf,
        key: String,
        given: usize,
        blocks: usize,
    },
    /// A value the study does not hold, named by its key, with the values it holds.
    #[error("{file}: `{key}` {given} is not in the study (it holds {held})")]
    NotHeld {
        file: PathBuf,
        key: String,
        given: String,
        held: String,
    },
}

/// The demands of the case `q` of the finished building study in `dir`, one row per motion of
/// its zone, with the stacks sliding or rigidly attached; the ground row is the motion's PGA and
/// exact PGV.
pub fn frame_demands(
    dir: &Path,
    q: &FrameQuery,
    stacks: Stacks,
) -> Result<Vec<Demands>, FrameEdpError> {
    let sweep = dir.join("sweep.h5");
    let motions = dir.join("motions.h5");
    let missing = |file| FrameEdpError::Missing {
        dir: dir.to_path_buf(),
        file,
    };
    stored_fingerprint(&sweep)?.ok_or_else(|| missing("sweep.h5"))?;
    let motions_fp = stored_fingerprint(&motions)?.ok_or_else(|| missing("motions.h5"))?;
    if read_motions_fingerprint(&sweep)?.as_deref() != Some(motions_fp.as_str()) {
        return Err(FrameEdpError::OtherMotions { file: sweep });
    }
    if !is_building(&sweep)? {
        return Err(FrameEdpError::NotBuilding { file: sweep });
    }
    let (zones, blocks) = zones_and_blocks(&sweep)?;
    let not_held = |key: &str, given: String, held: String| FrameEdpError::NotHeld {
        file: sweep.clone(),
        key: key.to_string(),
        given,
        held,
    };
    if !zones.contains(&q.zone) {
        return Err(not_held("zone", q.zone.clone(), zones.join(", ")));
    }
    let (grid, axes, zone) = read_zone_sweep(&sweep, &q.zone, blocks, true)?;
    let axes = axes.expect("a building study's zone has its frame axes");
    for (key, values) in [("alpha", &q.alpha), ("mu", &q.mu)] {
        if values.len() != blocks {
            return Err(FrameEdpError::Blocks {
                file: sweep.clone(),
                key: key.to_string(),
                given: values.len(),
                blocks,
            });
        }
    }
    let list = |v: &[String]| v.join(", ");
    let position = |key: &str, given: f64, held: &[f64]| {
        held.iter()
            .position(|&h| (h - given).abs() <= 1e-9 * h.abs().max(given.abs()))
            .ok_or_else(|| {
                let held: Vec<String> = held.iter().map(f64::to_string).collect();
                not_held(key, given.to_string(), list(&held))
            })
    };
    let s = (axes.storeys.iter().position(|&n| n == q.storeys)).ok_or_else(|| {
        let held: Vec<String> = axes.storeys.iter().map(usize::to_string).collect();
        not_held("storeys", q.storeys.to_string(), list(&held))
    })?;
    let f = (axes.stack_floor.iter().position(|&x| x == q.stack_floor)).ok_or_else(|| {
        let held: Vec<String> = axes.stack_floor.iter().map(StackFloor::to_string).collect();
        not_held("stack_floor", q.stack_floor.to_string(), list(&held))
    })?;
    let mut case = vec![s, f, position("period", q.period_s, &grid.periods_s)?];
    for (i, a) in q.alpha.iter().enumerate() {
        case.push(position(&format!("alpha[{i}]"), *a, &grid.alpha[i])?);
    }
    for (i, m) in q.mu.iter().enumerate() {
        case.push(position(&format!("mu[{i}]"), *m, &grid.mu[i])?);
    }
    let records = read_zone_motions(&motions, &q.zone)?;
    let names: Vec<&str> = records.iter().map(|r| r.name.as_str()).collect();
    if names != zone.motions.iter().map(String::as_str).collect::<Vec<_>>() {
        return Err(FrameEdpError::OtherMotions { file: sweep });
    }
    let b = zone
        .building
        .expect("a building study's zone has its building variables");
    let (accel, velocity, drift, residual) = match stacks {
        Stacks::Sliding => (
            &b.floor_accel_stack,
            &b.floor_velocity_stack,
            &b.drift_ratio_stack,
            &b.residual_drift_ratio_stack,
        ),
        Stacks::Attached => (
            &b.floor_accel_rigid,
            &b.floor_velocity_rigid,
            &b.drift_ratio_rigid,
            &b.residual_drift_ratio_rigid,
        ),
    };
    // Levels 1 … N of the case under motion `m`, from a variable `[motion, case…, level]`.
    let levels = |v: &ArrayD<f64>, m: usize| -> Vec<f64> {
        (0..q.storeys)
            .map(|level| {
                let mut at = vec![m];
                at.extend(&case);
                at.push(level);
                v[at.as_slice()]
            })
            .collect()
    };
    Ok(records
        .iter()
        .enumerate()
        .map(|(m, r)| Demands {
            motion: r.name.clone(),
            pfa_g: std::iter::once(r.pga_g()).chain(levels(accel, m)).collect(),
            pfv_mps: std::iter::once(r.pgv_mps(1.0))
                .chain(levels(velocity, m))
                .collect(),
            pid_rad: levels(drift, m),
            rid_rad: levels(residual, m).iter().map(|d| d.abs()).collect(),
        })
        .collect())
}

/// [`frame_demands`] written to `out` (CSV), refused before any work when `out` cannot be one.
pub fn export_frame(
    dir: &Path,
    q: &FrameQuery,
    stacks: Stacks,
    out: &Path,
) -> Result<Vec<Demands>, FrameEdpError> {
    check_sample_path(out)?;
    let rows = frame_demands(dir, q, stacks)?;
    write_sample(&rows, out)?;
    Ok(rows)
}
