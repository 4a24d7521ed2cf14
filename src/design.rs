//! `slidestack design`'s entry point: a finished study's files read and checked (each verified,
//! `fit.yaml` made from that `tnew.h5`, that `tnew.h5` from that `motions.h5`), then the
//! designer's arithmetic ([`crate::study::design`]) on the zone's (or frame's) data. Above the
//! pipeline: it checks the fit's fingerprint as the fit stage computes it.

use crate::store::fit::read_fit;
use crate::store::h5::stored_fingerprint;
use crate::store::motions::read_zone_target;
use crate::store::tnew::{
    is_building, read_motions_fingerprint, read_zone_tnew_in, zones_and_blocks,
};
use crate::study::design::{
    Answer, DesignError, Query, ZoneDesign, answer, check_counts, check_frames, check_values,
    frame_index,
};
use std::path::Path;

/// Answers `q` from the finished study in `dir`.
pub fn design(dir: &Path, q: &Query) -> Result<Answer, DesignError> {
    check_values(q)?;
    let tnew = dir.join("tnew.h5");
    let fit_yaml = dir.join("fit.yaml");
    let motions = dir.join("motions.h5");
    let missing = |file| DesignError::Missing {
        dir: dir.to_path_buf(),
        file,
    };
    let tnew_fp = stored_fingerprint(&tnew)?.ok_or_else(|| missing("tnew.h5"))?;
    let building = is_building(&tnew)?;
    match (building, q.building) {
        (true, None) => return Err(DesignError::Building { file: tnew }),
        (false, Some(_)) => return Err(DesignError::NotBuilding { file: tnew }),
        _ => {}
    }
    let motions_fp = stored_fingerprint(&motions)?.ok_or_else(|| missing("motions.h5"))?;
    match read_motions_fingerprint(&tnew)? {
        Some(fp) if fp == motions_fp => {}
        Some(_) => {
            return Err(DesignError::OtherMotions {
                file: motions,
                why: "tnew.h5 was made from another motions.h5: rerun the study",
            });
        }
        None => {
            return Err(DesignError::OtherMotions {
                file: tnew,
                why: "made by an earlier slidestack, it does not record its motions.h5: rebuild it \
                      (the tnew stage, forced)",
            });
        }
    }
    let fit = read_fit(&fit_yaml)?.ok_or_else(|| missing("fit.yaml"))?;
    if fit.fingerprint != crate::pipeline::fit::fingerprint(&tnew_fp, building) {
        return Err(DesignError::Mismatch { file: fit_yaml });
    }
    let (zones, blocks) = zones_and_blocks(&tnew)?;
    fit.check_blocks(&fit_yaml, blocks)?;
    if !zones.contains(&q.zone) {
        return Err(DesignError::UnknownZone {
            zone: q.zone.clone(),
            known: zones.join(", "),
        });
    }
    check_counts(q, blocks)?;
    let (grid, axes, t) = read_zone_tnew_in(&tnew, &q.zone, blocks, building)?;
    let target = read_zone_target(&motions, &q.zone)?;
    let data = match (q.building, axes) {
        (Some((storeys, floor)), Some(axes)) => {
            check_frames(&fit, &axes, &fit_yaml)?;
            let f = frame_index(&fit, &axes, storeys, floor)?;
            ZoneDesign::of_frame(&q.zone, target, grid, &t, &fit, f)
        }
        _ => {
            let zone_fit = fit.zones.iter().find(|z| z.zone == q.zone);
            ZoneDesign::of_zone(&q.zone, target, grid, &t, zone_fit)
        }
    };
    answer(&data, q)
}
