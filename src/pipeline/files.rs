//! The stage files as the later stages and the report read them: one reader per file kind, each
//! refusing as damaged a file whose axes are not the config's, so that no stage reads another
//! stage's file with checks of its own. It imports no stage. (The store layer, [`crate::store`], reads a file by its
//! path; this layer knows the study it must belong to.)

use super::{PipelineError, StageId, Study};
use crate::ground_motion::Record;
use crate::spectrum::TargetSpectrum;
use crate::store::StoreError;
use crate::store::fit::{FitReport, read_fit};
use crate::store::floors::{FloorsAxes, ZoneFloors, read_zone_floors};
use crate::store::ida::{IdaAxes, ZoneIda, read_zone_ida};
use crate::store::motions::{read_zone_motions, read_zone_target};
use crate::store::sweep::{ZoneSweep, read_zone_sweep};
use crate::store::tnew::{ZoneTnew, read_zone_tnew_in};
use crate::store::units::{UnitId, unit_path};
use crate::study::ida_zone::axes_of as ida_axes_of;
use crate::study::tnew::spectrum_periods_s;
use std::path::Path;

/// What `read` gives for each zone of the config, in order, from `motions.h5`.
fn each_zone<T>(
    study: &Study,
    read: impl Fn(&Path, &str) -> Result<T, StoreError>,
) -> Result<Vec<T>, StoreError> {
    let path = study.path(StageId::Motions.output());
    (study.cfg.zones.iter())
        .map(|z| read(&path, &z.name))
        .collect()
}

/// The kept motions of every zone, from `motions.h5`.
pub fn motions(study: &Study) -> Result<Vec<Vec<Record>>, StoreError> {
    each_zone(study, read_zone_motions)
}

/// Every zone's target spectrum as `motions.h5` stores it: the one its motions were matched to.
pub fn targets(study: &Study) -> Result<Vec<TargetSpectrum>, StoreError> {
    each_zone(study, read_zone_target)
}

/// Zone `zone` of `sweep.h5`, refused unless its grid (and a building study's frames) are the
/// config's and, when `motions` are given, its motions are those (of `motions.h5`).
pub fn sweep_zone(
    study: &Study,
    zone: &str,
    motions: Option<&[Record]>,
) -> Result<ZoneSweep, PipelineError> {
    let grid = study.grid(StageId::Sweep)?;
    let path = study.path(StageId::Sweep.output());
    let building = study.building();
    let (axes, frames, sw) = read_zone_sweep(&path, zone, grid.blocks(), building.is_some())?;
    let same_motions = |m: &[Record]| sw.motions.iter().eq(m.iter().map(|r| &r.name));
    let why = if axes != *grid || frames.as_ref() != building {
        "its grid differs from the config's"
    } else if motions.is_some_and(|m| !same_motions(m)) {
        "its motions are not those of motions.h5"
    } else {
        return Ok(sw);
    };
    Err(StoreError::corrupt(&path, format!("zone_{zone}: {why}")).into())
}

/// Zone `zone` of `tnew.h5`, refused unless its grid and its spectrum's periods are the ones
/// the config gives.
pub fn tnew_zone(study: &Study, zone: &str) -> Result<ZoneTnew, PipelineError> {
    let grid = study.grid(StageId::Tnew)?;
    let path = study.path(StageId::Tnew.output());
    let building = study.building();
    let (axes, frames, t) = read_zone_tnew_in(&path, zone, grid.blocks(), building.is_some())?;
    let why = if axes != *grid || frames.as_ref() != building {
        "its grid differs from the config's"
    } else if t.period_sd_s != spectrum_periods_s(grid) {
        "its spectrum's periods differ from the config's grid"
    } else {
        return Ok(t);
    };
    Err(StoreError::corrupt(&path, format!("zone_{zone}: {why}")).into())
}

/// `fit.yaml`, refused when missing or made for another number of blocks.
pub fn fit(study: &Study) -> Result<FitReport, PipelineError> {
    let path = study.path("fit.yaml");
    let fit = read_fit(&path)?.ok_or_else(|| StoreError::corrupt(&path, "is missing"))?;
    fit.check_blocks(&path, study.grid(StageId::Fit)?.blocks())?;
    Ok(fit)
}

/// Where a unit of a stage that stores its work units (the sweep, the IDA) lives in `dir`, and
/// the identity its file must hold: zone `zone`'s motion `motion` of `motions`, a building
/// study's frame `frame`, and index `index` along the stage's own axis with its `period_s` (the
/// sweep's `T_p`, the IDA's case).
pub fn unit_place(
    study: &Study,
    (dir, fingerprint): (&str, &str),
    motions: &[Vec<Record>],
    (zone, motion, frame): (usize, usize, usize),
    (index, period_s): (usize, f64),
) -> (std::path::PathBuf, UnitId) {
    let zone_name = &study.cfg.zones[zone].name;
    let building = study.building();
    let path = unit_path(
        &study.path(dir),
        zone_name,
        motion,
        building.map(|_| frame),
        index,
    );
    let frame = frame_label(study, frame);
    let id = UnitId {
        frame,
        fingerprint: fingerprint.to_string(),
        zone: zone_name.clone(),
        motion_index: Some(motion),
        motion: Some(motions[zone][motion].name.clone()),
        period_index: index,
        period_s,
        alpha_total: None,
    };
    (path, id)
}

/// A building study's frame `frame` as a unit file names it: its index and `storeys`/
/// `stack_floor` (`None` on one storey).
pub fn frame_label(study: &Study, frame: usize) -> Option<(usize, String)> {
    study.building().map(|b| {
        let (n, floor) = b.frame(frame);
        (frame, format!("storeys {n}, stack_floor {floor}"))
    })
}

/// Zone `zone` of `ida.h5` (the caller has required it up to date), refused unless its axes
/// are the ones the config's `ida:` section gives.
pub fn ida_zone(study: &Study, zone: &str) -> Result<(IdaAxes, ZoneIda), PipelineError> {
    let path = study.path(StageId::Ida.output());
    let (axes, z) = read_zone_ida(&path, zone)?;
    if axes != ida_axes_of(study.ida_config()?, study.building()) {
        let why = format!("zone_{zone}: its axes differ from the config's `ida:` section");
        return Err(StoreError::corrupt(&path, why).into());
    }
    Ok((axes, z))
}

/// The axes the config gives every zone of `floors.h5`.
pub fn floors_axes(study: &Study) -> Result<FloorsAxes, PipelineError> {
    let cfg = study.floors_config()?;
    let spec = cfg.spec().map_err(|(key, why)| PipelineError::BadInput {
        file: study.config_path.clone(),
        why: format!("`floor_spectra.{key}`: {why}"),
    })?;
    Ok(FloorsAxes {
        case_period_s: cfg.cases.iter().map(|c| c.period_s).collect(),
        case_alpha: cfg.cases.iter().map(|c| c.alpha.clone()).collect(),
        case_mu: cfg.cases.iter().map(|c| c.mu.clone()).collect(),
        damping: spec.damping,
        periods_s: spec.periods_s,
        floors: study.building().map_or(1, |b| b.max_storeys()),
        building: study.building().cloned(),
    })
}

/// Zone `zone` of `floors.h5` (the caller has required it up to date), refused unless its
/// axes are the ones the config's `floor_spectra:` section gives.
pub fn floors_zone(study: &Study, zone: &str) -> Result<(FloorsAxes, ZoneFloors), PipelineError> {
    let path = study.path(StageId::Floors.output());
    let (axes, z) = read_zone_floors(&path, zone, study.building().is_some())?;
    if axes != floors_axes(study)? {
        let why =
            format!("zone_{zone}: its axes differ from the config's `floor_spectra:` section");
        return Err(StoreError::corrupt(&path, why).into());
    }
    Ok((axes, z))
}
