//! The T_new stage: per zone and case, the mean peak displacements over the motions, `T_rigid`,
//! `T_new` read off the zone's mean 5 %-damped displacement spectrum (paper Section 7.1; the
//! rule for several crossings in [`crate::study::tnew`]), whether anything slid, `DRR_1` and
//! `DRR_2` → `tnew.h5` (layout in [`crate::store::tnew`]).
//!
//! The numbers are [`crate::study::tnew::zone`]'s (in a building study also the attached
//! fractions, [`crate::study::attached`]); the stage reads the motions and the sweep, calls it
//! per zone, reports and writes.
//!
//! Fingerprint: the sweep's, the step of the spectrum's period grid, the methods' versions.

use super::{PipelineError, Session, StageId, StageOutcome};
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::tnew::{TnewMeta, write_tnew};
use crate::study::attached::FRACTION_FLAGS;
use crate::study::tnew::{self, BAND_FLAGS, SD_STEP_S, TNEW_FLAG_CODES, ZoneInputs};

/// The fingerprint `tnew.h5` must carry (`λ`'s definition and search are the `lambda` method's
/// version).
pub fn fingerprint(sweep_fingerprint: &str) -> String {
    let step = format!("sd_step_s={SD_STEP_S}");
    StageId::Tnew.fingerprint(&hash_parts(&[sweep_fingerprint, &step]))
}

/// Builds `tnew.h5`: per zone, reads the sweep, computes ([`tnew::zone`]) and reports.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Tnew;
    let grid = study.grid(me)?;
    let motions = super::files::motions(study)?;
    let physics = study.physics();
    let building = study.building();
    let frames = study.frames();
    let keep_going = || !s.reporter.cancelled();
    let mut zones = Vec::new();
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let sw = super::files::sweep_zone(study, &zc.name, Some(&motions[z]))?;
        let out = tnew::zone(&ZoneInputs {
            name: &zc.name,
            target: &zc.target,
            grid,
            physics: &physics,
            building,
            frames: &frames,
            motions: &motions[z],
            sweep: &sw.vars,
            keep_going: &keep_going,
        })
        .map_err(|e| match e.is_stopped() {
            true => PipelineError::Cancelled(me),
            false => e.into(),
        })?;
        if let Some(f) = &out.fractions {
            let line = format!(
                "zone {}: effective live-load fraction λ {}",
                zc.name,
                f.summary()
            );
            s.reporter.info(me, &line);
        }
        let line = format!(
            "zone {}: {} cases; {}",
            zc.name,
            out.cases,
            out.bands.summary()
        );
        s.reporter.info(me, &line);
        zones.push(out.tnew);
        s.pass("tnew.zone", me)?;
    }
    let building_json = study.building_attr();
    let mut settings = super::physics_attrs(&physics).to_vec();
    if let Some(b) = &building_json {
        settings.push(("building", crate::store::h5::Attr::Str(b)));
    }
    let meta = TnewMeta {
        fingerprint: study.fingerprint(me)?,
        sweep_fingerprint: study.fingerprint(StageId::Sweep)?,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        flag_codes: TNEW_FLAG_CODES,
        band_flags: BAND_FLAGS,
        lambda_flags: FRACTION_FLAGS,
        mu_static_ratio: physics.mu_static_ratio,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_tnew(&path, &meta, grid, building, &zones)?;
    Ok(StageOutcome::Wrote(vec![path]))
}
