//! The floors stage: the floor response spectra of the `floor_spectra:` section's cases, each
//! on every frame, under every matched motion, sliding and attached → `floors.h5` (layout in
//! [`crate::store::floors`]; one unit's numerics in [`crate::study::floors`]).
//!
//! Units (one zone, one motion, one case, one frame) run in parallel and are collected in their
//! fixed order, so the file's bytes do not depend on the thread count; a frame that is an
//! earlier one's building takes that frame's spectra. The file is written once, atomically, at
//! the end (a run killed before leaves nothing; the rerun computes everything again).
//!
//! Fingerprint: the `zones` and `floor_spectra` sections, the grid's physics, in a building
//! study the `building` section and `grid.stack_floor`, and the motions' fingerprint.

use super::{PipelineError, Session, StageId, StageOutcome, Study};
use crate::ground_motion::Record;
use crate::spectrum::floor::{FloorSpectraSpec, REFINEMENT};
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::floors::{FloorsAxes, FloorsMeta, Offsets, ZoneFloors, write_floors};
use crate::store::h5::Attr;
use crate::study::building::Frame;
use crate::study::case_units::{CaseUnit, UnitPlan};
use crate::study::config::StudyConfig;
use crate::study::floors::{FloorUnit, FloorsConfig, FloorsError, floor_unit};
use crate::study::physics::Physics;
use ndarray::{ArrayD, IxDyn};
use rayon::prelude::*;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum FloorsStageError {
    #[error("{}: the `floors` stage needs a `floor_spectra` section", config.display())]
    NoSection { config: PathBuf },
    #[error("zone {zone}, motion {motion}: {why}")]
    Record {
        zone: String,
        motion: String,
        why: String,
    },
    #[error("zone {zone}, motion {motion}, case {case}{frame}: {source}")]
    Unit {
        zone: String,
        motion: String,
        case: usize,
        /// `, 3 storeys, stack on the roof` in a building study, else empty.
        frame: String,
        source: Box<FloorsError>,
    },
}

/// The fingerprint `floors.h5` must carry, `None` without a `floor_spectra` section.
pub fn fingerprint(cfg: &StudyConfig, motions_fingerprint: &str) -> Option<String> {
    let floors = cfg.floor_spectra.as_ref()?;
    let p = cfg.physics();
    let mut section = serde_json::json!({
        "zones": cfg.zones, "floor_spectra": floors, "refinement": REFINEMENT,
        "physics": { "damping": p.damping, "basis": p.basis, "mu_static_ratio": p.mu_static_ratio },
    });
    if let Some(b) = &cfg.building {
        section["building"] = serde_json::json!(b);
        let floors = cfg.grid.as_ref().and_then(|g| g.stack_floor.as_ref());
        section["stack_floor"] = serde_json::json!(floors);
    }
    Some(StageId::Floors.fingerprint(&hash_parts(&[&section.to_string(), motions_fingerprint])))
}

/// Builds `floors.h5`: checks every record, runs the units (`run_units`: a repeated
/// building's taken from its first frame), assembles each zone (`zone_floors`) and writes.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Floors;
    let cfg = study.floors_config()?;
    let fp = study.fingerprint(me)?;
    let axes = super::files::floors_axes(study)?;
    let spec = FloorSpectraSpec {
        periods_s: axes.periods_s.clone(),
        damping: axes.damping.clone(),
    };
    let motions = super::files::motions(study)?;
    check_records(study, &motions)?;
    let physics = study.physics();
    let frames = study.frames();
    let counts: Vec<usize> = motions.iter().map(Vec::len).collect();
    let plan = UnitPlan::new(&counts, cfg.cases.len(), frames);
    let inp = UnitInputs {
        physics: &physics,
        cfg,
        frames,
        motions: &motions,
        spec: &spec,
    };
    let outs = run_units(s, &inp, &plan.run)?;
    let done: std::collections::BTreeMap<CaseUnit, &FloorUnit> =
        plan.run.iter().copied().zip(&outs).collect();
    let mut zones = Vec::new();
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let ms = &motions[z];
        let unit = |motion: usize, case: usize, frame: usize| {
            done[&plan.source(CaseUnit {
                zone: z,
                motion,
                case,
                frame,
            })]
        };
        zones.push(zone_floors(
            &axes,
            ms.len(),
            frames.len(),
            unit,
            ZoneNames {
                name: zc.name.clone(),
                target: zc.target.clone(),
                motions: ms.iter().map(|r| r.name.clone()).collect(),
                pga_g: ms.iter().map(|r| r.pga_g()).collect(),
            },
        ));
    }
    let physics_attrs = super::physics_attrs(&physics);
    let building_json = study.building_attr();
    let mut settings: Vec<(&str, Attr)> = physics_attrs.to_vec();
    settings.push(("refinement", Attr::F64(REFINEMENT as f64)));
    if let Some(b) = &building_json {
        settings.push(("building", Attr::Str(b)));
    }
    let meta = FloorsMeta {
        fingerprint: fp,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        config_sha256: &study.config_sha256,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_floors(&path, &meta, &axes, &zones)?;
    s.reporter.info(me, &format!("verified {}", path.display()));
    Ok(StageOutcome::Wrote(vec![path]))
}

/// `Err` naming the first record whose history the floor spectra cannot refine: every record
/// is checked before any run.
fn check_records(study: &Study, motions: &[Vec<Record>]) -> Result<(), FloorsStageError> {
    for (z, ms) in motions.iter().enumerate() {
        for m in ms {
            m.check_refinable(REFINEMENT)
                .map_err(|why| FloorsStageError::Record {
                    zone: study.cfg.zones[z].name.clone(),
                    motion: m.name.clone(),
                    why,
                })?;
        }
    }
    Ok(())
}

/// What running a unit needs besides the unit.
struct UnitInputs<'a> {
    physics: &'a Physics,
    cfg: &'a FloorsConfig,
    frames: &'a [Frame],
    motions: &'a [Vec<Record>],
    spec: &'a FloorSpectraSpec,
}

/// Runs `units` in parallel, reporting what they are and a bar; their results in order.
fn run_units(
    s: &Session,
    inp: &UnitInputs,
    units: &[CaseUnit],
) -> Result<Vec<FloorUnit>, PipelineError> {
    let (me, study) = (StageId::Floors, &s.study);
    s.reporter.info(
        me,
        &format!(
            "{} units (motions × cases{}), each two runs on the record refined {REFINEMENT} \
             times and {} spectra of {} periods per floor",
            units.len(),
            if study.building().is_some() {
                " × distinct buildings"
            } else {
                ""
            },
            inp.spec.damping.len(),
            inp.spec.periods_s.len()
        ),
    );
    let bar = s.reporter.progress(me, units.len() as u64);
    let outs = units
        .par_iter()
        .map(|&u| -> Result<FloorUnit, PipelineError> {
            s.check_cancelled(me)?;
            let rec = &inp.motions[u.zone][u.motion];
            let frame = &inp.frames[u.frame];
            let case = &inp.cfg.cases[u.case];
            let unit = floor_unit(inp.physics, case, frame, rec, inp.spec).map_err(|source| {
                FloorsStageError::Unit {
                    zone: study.cfg.zones[u.zone].name.clone(),
                    motion: rec.name.clone(),
                    case: u.case,
                    frame: study.shape.label_suffix(u.frame),
                    source: Box::new(source),
                }
            })?;
            bar.inc();
            Ok(unit)
        })
        .collect::<Result<_, _>>()?;
    bar.finish();
    Ok(outs)
}

/// A zone's names, and its motions' peak ground accelerations, g.
struct ZoneNames {
    name: String,
    target: String,
    motions: Vec<String>,
    pga_g: Vec<f64>,
}

/// One zone's variables from its units: `unit(m, c, f)` of motion `m`, case `c`, frame `f`,
/// padded with NaN above each building's roof.
fn zone_floors<'u>(
    axes: &FloorsAxes,
    motions: usize,
    frames: usize,
    unit: impl Fn(usize, usize, usize) -> &'u FloorUnit,
    names: ZoneNames,
) -> ZoneFloors {
    let o = Offsets::of(axes, frames);
    let mut head = vec![motions, o.cases];
    head.extend(axes.building.iter().flat_map(|b| b.shape()));
    let nan = |tail: &[usize]| {
        let mut shape = head.clone();
        shape.extend_from_slice(tail);
        ArrayD::from_elem(IxDyn(&shape), f64::NAN)
    };
    let mut pfa = [nan(&[o.floors]), nan(&[o.floors])];
    let per_floor = [o.damping, o.floors, o.periods];
    let mut psa = [nan(&per_floor), nan(&per_floor)];
    for m in 0..motions {
        for c in 0..o.cases {
            for f in 0..frames {
                let u = unit(m, c, f);
                for s in 0..2 {
                    let at = o.pfa(m, c, f, 0);
                    let rows = pfa[s].as_slice_mut().expect("standard layout");
                    rows[at..at + u.pfa_g[s].len()].copy_from_slice(&u.pfa_g[s]);
                    let rows = psa[s].as_slice_mut().expect("standard layout");
                    for (d, floors) in u.psa_g[s].iter().enumerate() {
                        for (j, spectrum) in floors.iter().enumerate() {
                            let at = o.psa(m, c, f, d, j);
                            rows[at..at + o.periods].copy_from_slice(spectrum);
                        }
                    }
                }
            }
        }
    }
    let [pfa_stack, pfa_rigid] = pfa;
    let [psa_stack, psa_rigid] = psa;
    ZoneFloors {
        name: names.name,
        target: names.target,
        pga_g: names.pga_g,
        motions: names.motions,
        pfa_stack,
        pfa_rigid,
        psa_stack,
        psa_rigid,
    }
}
