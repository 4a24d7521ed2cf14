//! The sweep stage: every case of the grid under every motion → `sweep.h5` (layout in
//! [`crate::store::sweep`]; the numerics of one work unit in [`crate::study::sweep`]).
//!
//! Work units (one zone, one motion, one `T_p`) are computed in parallel, each stored as its own
//! file under `OUT/sweep.units/` the moment it is done ([`crate::store::units`]): a rerun after
//! an interruption computes only the rest. With a shard `K/N` only the units `i` with
//! `i mod N = K−1` are computed and nothing is assembled (`merge` does that when every shard is
//! done). Assembling reads every unit back (checksum and identity checked), writes `sweep.h5`,
//! reads it back and compares it with what was meant, and only then removes the units.
//!
//! In a building study a unit is one zone, one motion, one frame (`storeys`, `stack_floor`) and
//! one `T_p`; a frame that repeats an earlier frame's building (on one storey floor 1, the roof
//! and every floor) has no units of its own, and `sweep.h5` stores its first frame's results.
//!
//! Fingerprint: the `zones` and `grid` sections (and `building`, when given), the solver, and
//! the motions' fingerprint.

use super::{PipelineError, Session, StageId, StageOutcome, Study};
use crate::dynamics::Ground;
use crate::grid::{BuildingAxes, Grid};
use crate::ground_motion::Record;
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::h5::Attr;
use crate::store::sweep::{
    BuildingVars, SweepMeta, SweepVars, ZoneSweep, read_zone_sweep, write_sweep,
};
use crate::store::units::{Columns, Stored, UnitId, read_unit, write_unit};
use crate::store::vars;
use crate::study::building::{distinct_frames, first_of_building};
use crate::study::config::StudyConfig;
use crate::study::physics::{CaseError, SystemKind};
use crate::study::sweep::{SKIP_RULE_CODES, SKIP_RULE_FLAGS, UnitOptions, UnitResult, run_unit};
use ndarray::{ArrayD, IxDyn};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use thiserror::Error;

/// Directory of the unit files inside the output directory.
pub const UNITS_DIR: &str = "sweep.units";

#[derive(Debug, Error)]
pub enum SweepStageError {
    #[error("zone {zone}, motion {motion}: {source}")]
    Simulation {
        zone: String,
        motion: String,
        source: Box<CaseError>,
    },
    #[error(
        "{missing} of {total} units are missing from {}: run the remaining shards (or the sweep unsharded)",
        dir.display()
    )]
    MissingUnits {
        missing: usize,
        total: usize,
        dir: PathBuf,
    },
    #[error(
        "{} of the units in {} are damaged or misplaced, first: {first}; rerun the shards that made \
         them (or the sweep unsharded), which recompute them",
        count, dir.display()
    )]
    BadUnits {
        count: usize,
        dir: PathBuf,
        first: String,
    },
    #[error("{}: read back, it differs from what was written in {what}", file.display())]
    Verify { file: PathBuf, what: String },
}

/// What a building study's `sweep.h5` stores, part of its fingerprint: a file written before
/// the per-floor peaks and the base shear were (the first building sweeps) is out of date, not
/// read as if it held them. Change it when the stored building variables change.
const BUILDING_OUTPUTS: &str = "roof peaks, per-floor accelerations, per-storey drift ratios, \
     base shear, per-storey shears, overturning moment, stuck mass share";

/// The fingerprint `sweep.h5` must carry.
pub fn fingerprint(cfg: &StudyConfig, motions_fingerprint: &str) -> String {
    let mut section = serde_json::json!({
        "zones": cfg.zones, "grid": cfg.grid, "solver": "exact",
    });
    // Only when given, so that a one-storey study keeps its fingerprint.
    if let Some(b) = &cfg.building {
        section["building"] = serde_json::json!(b);
        section["building_outputs"] = serde_json::json!(BUILDING_OUTPUTS);
    }
    StageId::Sweep.fingerprint(&hash_parts(&[&section.to_string(), motions_fingerprint]))
}

/// One work unit: zone, motion, frame (0 on one storey) and period indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Unit {
    zone: usize,
    motion: usize,
    frame: usize,
    period: usize,
}

/// Every unit in the fixed order shards count in (the order of the stored axes). A frame that
/// repeats an earlier frame's building (not in [`distinct_frames`]: on one storey the roof and
/// every floor repeat floor 1) has no units: its results are its first frame's, to the bit.
fn all_units(study: &Study, grid: &Grid, motions: &[Vec<Record>]) -> Vec<Unit> {
    let frames = distinct_frames(study.frames());
    let mut v = Vec::new();
    for (zone, ms) in motions.iter().enumerate() {
        for motion in 0..ms.len() {
            for &frame in &frames {
                for period in 0..grid.periods_s.len() {
                    v.push(Unit {
                        zone,
                        motion,
                        frame,
                        period,
                    });
                }
            }
        }
    }
    v
}

struct Units<'a> {
    study: &'a Study,
    grid: &'a Grid,
    motions: &'a [Vec<Record>],
    fingerprint: &'a str,
}

impl Units<'_> {
    fn place(&self, u: Unit) -> (PathBuf, UnitId) {
        super::files::unit_place(
            self.study,
            (UNITS_DIR, self.fingerprint),
            self.motions,
            (u.zone, u.motion, u.frame),
            (u.period, self.grid.periods_s[u.period]),
        )
    }

    /// The unit's file, refused (as damaged) unless its columns have the lengths the grid
    /// gives ([`column_lengths`]).
    fn read(&self, u: Unit) -> Result<Stored, StoreError> {
        let (path, id) = self.place(u);
        let stored = read_unit(&path, &id)?;
        if let Stored::Valid(c) = &stored {
            let found: Vec<usize> = (c.f64s.iter().map(Vec::len))
                .chain(c.u8s.iter().map(Vec::len))
                .collect();
            let nmax = self.study.building().map(BuildingAxes::max_storeys);
            let rocks = self.study.aspect().is_some();
            let want = column_lengths(self.grid.cases_per_unit(), self.grid.blocks(), nmax, rocks);
            if found != want || c.u8s.len() != 2 + usize::from(rocks) {
                return Err(StoreError::shape(&path, "columns", &found, &want));
            }
        }
        Ok(stored)
    }
}

/// The lengths of the columns [`to_columns`] writes for a unit of `cases` cases of `blocks`
/// blocks: six `f64` columns (the slip, per interface, last), in a building study whose largest
/// building has `nmax` storeys fifteen more (four per floor or storey, padded to `nmax`, the two
/// base shears, the two storey shears, padded, the two overturning moments, the stuck share,
/// and four more per floor or storey: the velocities and the residual drifts), then three per
/// interface or block (the residual slips, the blocks' accelerations and velocities), then two
/// code columns, and with `rocks` (the blocks' ratios given) a third, the rocking flags.
fn column_lengths(cases: usize, blocks: usize, nmax: Option<usize>, rocks: bool) -> Vec<usize> {
    let mut v = vec![cases, cases, cases, cases, cases, cases * blocks];
    if let Some(n) = nmax {
        v.extend([cases * n; 4]);
        v.extend([cases; 2]);
        v.extend([cases * n; 2]);
        v.extend([cases; 3]);
        v.extend([cases * n; 4]);
    }
    v.extend([cases * blocks; 3]);
    v.extend([cases; 2]);
    if rocks {
        v.push(cases);
    }
    v
}

/// `[case][level]` rows of `n` values each, padded with NaN to `nmax` per case.
fn padded(rows: &[f64], n: usize, nmax: usize) -> Vec<f64> {
    (rows.chunks(n.max(1)))
        .flat_map(|r| {
            r.iter()
                .copied()
                .chain(std::iter::repeat_n(f64::NAN, nmax - r.len()))
        })
        .collect()
}

/// A unit's columns; `frame`: `(N, N_max)` of a building study's unit.
fn to_columns(r: &UnitResult, frame: Option<(usize, usize)>) -> Columns {
    let mut f64s = vec![
        r.u_stack.clone(),
        r.u_single.clone(),
        r.u_rigid.clone(),
        r.a_stack.clone(),
        r.friction_energy.clone(),
        r.slip_peak.clone(),
    ];
    if let Some((n, nmax)) = frame {
        for rows in [
            &r.floor_accel_stack,
            &r.floor_accel_rigid,
            &r.drift_ratio_stack,
            &r.drift_ratio_rigid,
        ] {
            f64s.push(padded(rows, n, nmax));
        }
        f64s.push(r.base_shear_stack.clone());
        f64s.push(r.base_shear_rigid.clone());
        f64s.push(padded(&r.storey_shear_stack, n, nmax));
        f64s.push(padded(&r.storey_shear_rigid, n, nmax));
        f64s.push(r.overturning_stack.clone());
        f64s.push(r.overturning_rigid.clone());
        f64s.push(r.stuck_share_stack.clone());
        for rows in [
            &r.floor_velocity_stack,
            &r.floor_velocity_rigid,
            &r.residual_drift_ratio_stack,
            &r.residual_drift_ratio_rigid,
        ] {
            f64s.push(padded(rows, n, nmax));
        }
    }
    f64s.push(r.slip_residual.clone());
    f64s.push(r.block_accel_stack.clone());
    f64s.push(r.block_velocity_stack.clone());
    let mut u8s = vec![r.skip_rule.clone(), r.single_rule.clone()];
    if !r.rocks_stack.is_empty() {
        u8s.push(r.rocks_stack.clone());
    }
    Columns { f64s, u8s }
}

/// Builds `sweep.h5`, or with `shard = Some((K, N))` only that shard's units.
pub fn build(s: &Session, shard: Option<(usize, usize)>) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Sweep;
    let grid = study.grid(me)?;
    let fp = study.fingerprint(me)?;
    let motions = super::files::motions(study)?;
    let units = Units {
        study,
        grid,
        motions: &motions,
        fingerprint: fp,
    };
    let all = all_units(study, grid, &motions);
    let in_shard = super::shard_filter(me, shard, all.len())?;
    let mine: Vec<Unit> = all
        .iter()
        .enumerate()
        .filter(|&(i, _)| in_shard(i))
        .map(|(_, u)| *u)
        .collect();
    let dir = study.path(UNITS_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| StoreError::io(&dir, "cannot create", e))?;
    let todo = todo_units(s, &units, &mine);
    compute_units(s, &units, &todo)?;
    if let Some((k, n)) = shard {
        return Ok(StageOutcome::ShardDone { k, n });
    }
    s.pass("sweep.assemble", me)?;
    assemble(s, &units, &all)
}

/// Of `mine`, the units no valid unit file holds (a damaged one with a warning), and a line
/// saying how many.
fn todo_units(s: &Session, units: &Units, mine: &[Unit]) -> Vec<Unit> {
    let me = StageId::Sweep;
    let valid = |u| {
        units
            .read(u)
            .map(|r| matches!(r, Stored::Valid(_)).then_some(()))
    };
    let (_, todo) = super::scan_units(s, me, mine, false, valid);
    let todo: Vec<Unit> = todo.into_iter().map(|(_, u)| u).collect();
    let cases = todo.len() * units.grid.cases_per_unit();
    s.reporter.info(
        me,
        &format!(
            "{} of {} units to compute ({} cases; {} already done)",
            todo.len(),
            mine.len(),
            cases,
            mine.len() - todo.len()
        ),
    );
    todo
}

/// Computes `todo` in parallel, each unit's file written as it ends, and reports the rate.
fn compute_units(s: &Session, units: &Units, todo: &[Unit]) -> Result<(), PipelineError> {
    let (me, study, grid) = (StageId::Sweep, units.study, units.grid);
    let cases = todo.len() * grid.cases_per_unit();
    let bar = s.reporter.progress(me, todo.len() as u64);
    let start = std::time::Instant::now();
    let sims = AtomicUsize::new(0);
    // Record samples crossed by all simulations together.
    let samples = AtomicUsize::new(0);
    let physics = study.physics();
    todo.par_iter()
        .try_for_each(|&u| -> Result<(), PipelineError> {
            s.check_cancelled(me)?;
            let rec = &units.motions[u.zone][u.motion];
            let accel = rec.accel_mps2(1.0);
            let ground = Ground::new(rec.dt_s, &accel);
            let r = run_unit(
                grid,
                &physics,
                &study.frames()[u.frame],
                &ground,
                u.period,
                UnitOptions {
                    skip: true,
                    aspect: study.aspect(),
                },
            )
            .map_err(|source| SweepStageError::Simulation {
                zone: study.cfg.zones[u.zone].name.clone(),
                motion: rec.name.clone(),
                source: Box::new(source),
            })?;
            sims.fetch_add(r.simulations, Ordering::Relaxed);
            samples.fetch_add(r.simulations * accel.len(), Ordering::Relaxed);
            let sizes = (study.building()).map(|b| (b.frame(u.frame).0, b.max_storeys()));
            let (path, id) = units.place(u);
            write_unit(&path, &id, &to_columns(&r, sizes))?;
            bar.inc();
            s.pass("sweep.unit", me)
        })?;
    bar.finish();
    let secs = start.elapsed().as_secs_f64();
    if !todo.is_empty() {
        let sims = sims.into_inner();
        let threads = rayon::current_num_threads();
        s.reporter.info(
            me,
            &format!(
                "{cases} cases in {secs:.1} s ({:.0} cases/s); {sims} simulations ({:.0}/s; the \
                 skip rules saved {:.0} %); {:.0} ns per simulated record sample per thread \
                 ({threads} threads)",
                cases as f64 / secs.max(1e-9),
                sims as f64 / secs.max(1e-9),
                100.0 * (1.0 - sims as f64 / (SystemKind::ALL.len() * cases) as f64),
                secs * 1e9 * threads as f64 / samples.into_inner().max(1) as f64
            ),
        );
    }
    Ok(())
}

/// Assembles `sweep.h5` from the stored units of every shard (`merge`).
pub fn merge(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Sweep;
    study.require(StageId::Motions)?;
    if study.state(me)? == super::StageState::UpToDate {
        remove_units(study)?;
        return Ok(StageOutcome::UpToDate(study.path(me.output())));
    }
    let grid = study.grid(me)?;
    let motions = super::files::motions(study)?;
    let units = Units {
        study,
        grid,
        motions: &motions,
        fingerprint: study.fingerprint(me)?,
    };
    let all = all_units(study, grid, &motions);
    assemble(s, &units, &all)
}

/// `sweep.h5` from the unit files of `all` (every unit of the grid): read, per zone its
/// variables, written and verified; then the units go.
fn assemble(s: &Session, units: &Units, all: &[Unit]) -> Result<StageOutcome, PipelineError> {
    let study = units.study;
    let read = units.read_all(all)?;
    let by_unit: std::collections::HashMap<Unit, &Columns> =
        all.iter().copied().zip(&read).collect();
    // Every frame's units in stored order, a repeated building's its first frame's.
    let first = first_of_building(study.frames());
    let mut zones = Vec::new();
    for z in 0..study.cfg.zones.len() {
        let mut cols = Vec::new();
        for motion in 0..units.motions[z].len() {
            for &frame in &first {
                for period in 0..units.grid.periods_s.len() {
                    let u = Unit {
                        zone: z,
                        motion,
                        frame,
                        period,
                    };
                    cols.push(by_unit[&u]);
                }
            }
        }
        zones.push(units.zone_of(z, &cols)?);
    }
    let path = write_verified(study, units.grid, &zones)?;
    remove_units(study)?;
    s.reporter
        .info(StageId::Sweep, &format!("verified {}", path.display()));
    Ok(StageOutcome::Wrote(vec![path]))
}

impl Units<'_> {
    /// Every unit of `all` in order, refused naming the directory unless each is stored whole
    /// for the current sweep.
    fn read_all(&self, all: &[Unit]) -> Result<Vec<Columns>, PipelineError> {
        let dir = self.study.path(UNITS_DIR);
        let mut missing = 0;
        let mut bad = Vec::new();
        let mut read: Vec<Columns> = Vec::with_capacity(all.len());
        for &u in all {
            match self.read(u) {
                Ok(Stored::Valid(c)) => read.push(c),
                Ok(Stored::Missing | Stored::Stale) => missing += 1,
                Err(e) => bad.push(e.to_string()),
            }
        }
        if !bad.is_empty() {
            return Err(SweepStageError::BadUnits {
                count: bad.len(),
                dir,
                first: bad.swap_remove(0),
            }
            .into());
        }
        if missing > 0 {
            return Err(SweepStageError::MissingUnits {
                missing,
                total: all.len(),
                dir,
            }
            .into());
        }
        Ok(read)
    }

    /// Zone `z`'s variables from its units' columns `cols` (motion, frame, `T_p` in stored
    /// order; the columns' layout is `column_lengths`').
    fn zone_of(&self, z: usize, cols: &[&Columns]) -> Result<ZoneSweep, PipelineError> {
        let (study, grid) = (self.study, self.grid);
        let dir = study.path(UNITS_DIR);
        let building = study.building();
        let mut shape = vec![self.motions[z].len()];
        shape.extend(building.iter().flat_map(|b| b.shape()));
        shape.extend(grid.shape());
        let mut shape_i = shape.clone();
        shape_i.push(grid.blocks());
        let f = |i: usize, shape: &[usize]| -> Result<ArrayD<f64>, PipelineError> {
            let flat: Vec<f64> = cols
                .iter()
                .flat_map(|c| c.f64s[i].iter().copied())
                .collect();
            array(flat, shape, &dir)
        };
        let building_vars = match building {
            None => None,
            Some(b) => {
                let mut per_floor = shape.clone();
                per_floor.push(b.max_storeys());
                Some(BuildingVars {
                    floor_accel_stack: f(6, &per_floor)?,
                    floor_accel_rigid: f(7, &per_floor)?,
                    drift_ratio_stack: f(8, &per_floor)?,
                    drift_ratio_rigid: f(9, &per_floor)?,
                    base_shear_stack: f(10, &shape)?,
                    base_shear_rigid: f(11, &shape)?,
                    storey_shear_stack: f(12, &per_floor)?,
                    storey_shear_rigid: f(13, &per_floor)?,
                    overturning_stack: f(14, &shape)?,
                    overturning_rigid: f(15, &shape)?,
                    stuck_share_stack: f(16, &shape)?,
                    floor_velocity_stack: f(17, &per_floor)?,
                    floor_velocity_rigid: f(18, &per_floor)?,
                    residual_drift_ratio_stack: f(19, &per_floor)?,
                    residual_drift_ratio_rigid: f(20, &per_floor)?,
                })
            }
        };
        // The goods' columns follow the building's (`column_lengths`).
        let goods = if building.is_some() { 21 } else { 6 };
        let codes = |i: usize| -> Result<ArrayD<u8>, PipelineError> {
            let flat: Vec<u8> = cols.iter().flat_map(|c| c.u8s[i].iter().copied()).collect();
            array(flat, &shape, &dir)
        };
        let zc = &study.cfg.zones[z];
        Ok(ZoneSweep {
            name: zc.name.clone(),
            target: zc.target.clone(),
            motions: self.motions[z].iter().map(|m| m.name.clone()).collect(),
            vars: SweepVars {
                u_stack: f(0, &shape)?,
                u_single: f(1, &shape)?,
                u_rigid: f(2, &shape)?,
                a_stack: f(3, &shape)?,
                friction_energy: f(4, &shape)?,
                slip_peak: f(5, &shape_i)?,
                slip_residual: f(goods, &shape_i)?,
                block_accel_stack: f(goods + 1, &shape_i)?,
                block_velocity_stack: f(goods + 2, &shape_i)?,
                skip_rule: codes(0)?,
                single_rule: codes(1)?,
            },
            rocks_stack: study.aspect().map(|_| codes(2)).transpose()?,
            building: building_vars,
        })
    }
}

/// Writes `sweep.h5` of `zones` and reads it back: its fingerprint and every zone bit for bit
/// what was meant, before the units go; its path.
fn write_verified(
    study: &Study,
    grid: &Grid,
    zones: &[ZoneSweep],
) -> Result<PathBuf, PipelineError> {
    let me = StageId::Sweep;
    let fp = study.fingerprint(me)?;
    let physics = study.physics();
    let building = study.building();
    let building_json = study.building_attr();
    let mut settings = super::physics_attrs(&physics).to_vec();
    if let Some(b) = &building_json {
        settings.push(("building", Attr::Str(b)));
    }
    let aspect_json = study.aspect().map(|a| serde_json::json!(a).to_string());
    if let Some(a) = &aspect_json {
        settings.push(("aspect", Attr::Str(a)));
    }
    let meta = SweepMeta {
        fingerprint: fp,
        config_sha256: &study.config_sha256,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        skip_rule_codes: SKIP_RULE_CODES,
        skip_rule_flags: SKIP_RULE_FLAGS,
        mu_static_ratio: physics.mu_static_ratio,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_sweep(&path, &meta, grid, building, zones)?;
    if study.stored(me)?.as_deref() != Some(fp) {
        return Err(SweepStageError::Verify {
            file: path,
            what: "its fingerprint".into(),
        }
        .into());
    }
    for z in zones {
        let (_, _, back) = read_zone_sweep(&path, &z.name, grid.blocks(), building.is_some())?;
        if !same_bits(&back, z) {
            return Err(SweepStageError::Verify {
                file: path,
                what: format!("zone_{}", z.name),
            }
            .into());
        }
    }
    Ok(path)
}

fn array<T>(
    flat: Vec<T>,
    shape: &[usize],
    dir: &std::path::Path,
) -> Result<ArrayD<T>, PipelineError> {
    ArrayD::from_shape_vec(IxDyn(shape), flat).map_err(|_| {
        SweepStageError::BadUnits {
            count: 1,
            dir: dir.to_path_buf(),
            first: "a unit holds the wrong number of cases".into(),
        }
        .into()
    })
}

/// Equal to the bit (NaN fill included).
fn same_bits(a: &ZoneSweep, b: &ZoneSweep) -> bool {
    a.motions == b.motions
        && vars::same_bits(&a.vars.data(), &b.vars.data())
        && a.rocks_stack == b.rocks_stack
        && match (&a.building, &b.building) {
            (None, None) => true,
            (Some(x), Some(y)) => vars::same_bits(&x.data(), &y.data()),
            _ => false,
        }
}

/// Removes the unit files (after `sweep.h5` was verified, or left over from an interrupted
/// cleanup).
pub fn remove_units(study: &Study) -> Result<(), StoreError> {
    crate::store::units::remove_units(&study.path(UNITS_DIR))
}

/// `(work units, units stored for the current sweep, record samples per motion)`; before the
/// motions stage ran the motion counts come from the config and the samples are 0.
pub fn unit_status(study: &Study) -> Result<(usize, usize, usize), PipelineError> {
    let grid = study.grid(StageId::Sweep)?;
    if study.state(StageId::Motions)? != super::StageState::UpToDate {
        let motions: usize = study.motions_per_zone().iter().sum();
        let frames = distinct_frames(study.frames()).len();
        return Ok((motions * frames * grid.periods_s.len(), 0, 0));
    }
    let motions = super::files::motions(study)?;
    let units = Units {
        study,
        grid,
        motions: &motions,
        fingerprint: study.fingerprint(StageId::Sweep)?,
    };
    let all = all_units(study, grid, &motions);
    let done = if study.state(StageId::Sweep)? == super::StageState::UpToDate {
        all.len()
    } else {
        all.iter()
            .filter(|&&u| matches!(units.read(u), Ok(Stored::Valid(_))))
            .count()
    };
    let (count, samples) = motions
        .iter()
        .flatten()
        .fold((0, 0), |(c, n), m| (c + 1, n + m.accel_g.len()));
    Ok((all.len(), done, samples / count.max(1)))
}
