//! The IDA stage: every case of the `ida:` section under every matched motion, on a yielding
//! structure, traced by hunt & fill → `ida.h5` (layout in [`crate::store::ida`]; the numerics of
//! one unit in [`crate::study::ida`], the kernels in [`crate::ida`]).
//!
//! Work units (one zone, one motion, one case; both systems) run in parallel, each stored as a
//! unit file in [`UNITS_DIR`] as it ends (identity and checksum, written atomically: the sweep's
//! format, [`crate::store::units`]), so a run killed at any point resumes where it stopped, and
//! `--shard K/N` traces only the units `i` with `i mod N = K − 1` beside the other shards. The
//! unsharded stage traces what no unit file holds, reads every unit back in its fixed order and
//! writes `ida.h5` once, atomically; its bytes depend neither on the thread count nor on the
//! shards. The unit files go once `ida.h5` is written and verified.
//!
//! In a building study a unit is one zone, one motion, one case and one frame (`storeys`,
//! `stack_floor`; docs/model.md, "Incremental dynamic analysis", "In a building").
//!
//! Fingerprint: the `zones` section, the physics of the grid, the `ida` section and the
//! motions' fingerprint; in a building study also the `building` section and
//! `grid.stack_floor`.

use super::{PipelineError, Session, StageId, StageOutcome, Study};
use crate::ground_motion::Record;
use crate::ida::fragility::FIT_STATUS_FLAGS;
use crate::ida::trace::{Run, Trace};
use crate::spectrum::TargetSpectrum;
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::h5::Attr;
use crate::store::ida::{IdaMeta, write_ida};
use crate::store::units::{Columns, Stored, UnitId, read_unit, write_unit};
use crate::study::case_units::{CaseUnit, UnitPlan};
use crate::study::config::StudyConfig;
use crate::study::ida::{IdaConfig, RunDemand, SYSTEMS};
use crate::study::ida_zone::{UnitTraces, axes_of, trace_unit, zone_ida};
use crate::study::physics::Physics;
use rayon::prelude::*;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum IdaStageError {
    #[error("{}: the `ida` stage needs an `ida` section", config.display())]
    NoSection { config: PathBuf },
    #[error("zone {zone}, motion {motion}, case {case}{frame} ({system}): {why}")]
    Simulation {
        zone: String,
        motion: String,
        case: usize,
        /// `, 3 storeys, stack on the roof` in a building study, else empty.
        frame: String,
        system: &'static str,
        why: String,
    },
}

/// The fingerprint `ida.h5` must carry, `None` without an `ida` section.
pub fn fingerprint(cfg: &StudyConfig, motions_fingerprint: &str) -> Option<String> {
    let ida = cfg.ida.as_ref()?;
    let p = cfg.physics();
    let mut section = serde_json::json!({
        "zones": cfg.zones, "ida": ida, "solver": "exact",
        "physics": { "damping": p.damping, "basis": p.basis, "mu_static_ratio": p.mu_static_ratio },
    });
    if let Some(b) = &cfg.building {
        section["building"] = serde_json::json!(b);
        let floors = cfg.grid.as_ref().and_then(|g| g.stack_floor.as_ref());
        section["stack_floor"] = serde_json::json!(floors);
    }
    Some(StageId::Ida.fingerprint(&hash_parts(&[&section.to_string(), motions_fingerprint])))
}

/// Builds `ida.h5`, or with `shard = Some((K, N))` only that shard's unit files: reads the
/// unit files there are, traces the rest (each stored as it ends) and, unsharded, assembles
/// and writes `ida.h5`.
pub fn build(s: &Session, shard: Option<(usize, usize)>) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Ida;
    let cfg = study.ida_config()?;
    let motions = super::files::motions(study)?;
    let targets = super::files::targets(study)?;
    let frames = study.frames();
    let counts: Vec<usize> = motions.iter().map(Vec::len).collect();
    let plan = UnitPlan::new(&counts, cfg.cases.len(), frames);
    let units = plan.run.len();
    let in_shard = super::shard_filter(me, shard, units)?;
    let store = CaseUnits {
        study,
        cfg,
        motions: &motions,
        fingerprint: study.fingerprint(me)?,
    };
    s.reporter
        .info(me, &plan_line(study, cfg, &counts, &plan, frames.len()));
    let mine: Vec<CaseUnit> = (plan.run.iter().enumerate())
        .filter(|&(i, _)| in_shard(i))
        .map(|(_, u)| *u)
        .collect();
    let dir = study.path(UNITS_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| StoreError::io(&dir, "cannot create", e))?;
    // Each unit file read once: a shard only asks whether a unit is done; the whole stage
    // keeps the traces for the assembly.
    let (mut held, todo) = store.scan(s, &mine, shard.is_none());
    let inputs = TraceInputs {
        physics: study.physics(),
        targets: &targets,
    };
    for (i, traced) in trace_units(s, &store, &inputs, &todo)? {
        held[i] = Some(traced);
    }
    if let Some((k, n)) = shard {
        return Ok(StageOutcome::ShardDone { k, n });
    }
    s.pass("ida.assemble", me)?;
    let held: Vec<UnitTraces> = (held.into_iter())
        .map(|t| t.expect("read or traced"))
        .collect();
    let path = write_stage_file(study, &store, &inputs, &plan.expand(&held))?;
    remove_units(study)?;
    s.reporter.info(me, &format!("verified {}", path.display()));
    Ok(StageOutcome::Wrote(vec![path]))
}

/// The stage's first line: the traces, what they run over, and the runs a trace may take.
fn plan_line(
    study: &Study,
    cfg: &IdaConfig,
    motions: &[usize],
    plan: &UnitPlan,
    nf: usize,
) -> String {
    let traced = plan.run.len();
    format!(
        "{} traces ({} motions over {} zones × {} cases{} × {} systems{}), at most {} runs each",
        traced * SYSTEMS.len(),
        motions.iter().sum::<usize>(),
        motions.len(),
        cfg.cases.len(),
        if nf > 1 || study.building().is_some() {
            format!(" × {nf} frames")
        } else {
            String::new()
        },
        SYSTEMS.len(),
        match plan.all.len() - traced {
            0 => String::new(),
            n => format!("; {n} units of frames that repeat a building take its traces"),
        },
        cfg.tracing.max_runs()
    )
}

/// What tracing a unit needs besides the config and its record.
struct TraceInputs<'a> {
    physics: Physics,
    /// Each zone's target spectrum (as `motions.h5` stores it).
    targets: &'a [TargetSpectrum],
}

/// Traces the units `todo` (`(index, unit)`) in parallel, each stored as it ends, and reports
/// the rate; `(index, traces)` in `todo`'s order.
fn trace_units(
    s: &Session,
    store: &CaseUnits,
    inp: &TraceInputs,
    todo: &[(usize, CaseUnit)],
) -> Result<Vec<(usize, UnitTraces)>, PipelineError> {
    let (me, cfg, study) = (StageId::Ida, store.cfg, store.study);
    let start = std::time::Instant::now();
    let bar = s.reporter.progress(me, todo.len() as u64);
    let trace = |u: CaseUnit| -> Result<UnitTraces, IdaStageError> {
        let record = &store.motions[u.zone][u.motion];
        let of = (
            &cfg.cases[u.case],
            &study.frames()[u.frame],
            study.shape.is_building(),
        );
        (trace_unit(cfg, &inp.physics, &inp.targets[u.zone], of, record)).map_err(|f| {
            IdaStageError::Simulation {
                zone: study.cfg.zones[u.zone].name.clone(),
                motion: record.name.clone(),
                case: u.case,
                frame: study.shape.label_suffix(u.frame),
                system: f.system,
                why: f.why,
            }
        })
    };
    let done = todo
        .par_iter()
        .map(|&(i, u)| -> Result<(usize, UnitTraces), PipelineError> {
            s.check_cancelled(me)?;
            let traced = trace(u)?;
            store.write(u, &traced)?;
            bar.inc();
            s.pass("ida.trace", me)?;
            Ok((i, traced))
        })
        .collect::<Result<Vec<_>, _>>()?;
    bar.finish();
    if !done.is_empty() {
        let runs: usize = (done.iter())
            .flat_map(|(_, t)| &t.traces)
            .map(|t| t.runs.len())
            .sum();
        let samples: usize = done.iter().map(|(_, t)| t.samples).sum();
        let secs = start.elapsed().as_secs_f64();
        let threads = rayon::current_num_threads();
        s.reporter.info(
            me,
            &format!(
                "{runs} runs in {secs:.1} s ({:.0} runs/s); {:.0} ns per simulated record sample \
                 per thread ({threads} threads)",
                runs as f64 / secs.max(1e-9),
                secs * 1e9 * threads as f64 / samples.max(1) as f64
            ),
        );
    }
    Ok(done)
}

/// Writes `ida.h5` from every unit's traces (`outs`, over every zone, motion, case and frame in
/// stored order), zone by zone ([`zone_ida`]); its path.
fn write_stage_file(
    study: &Study,
    store: &CaseUnits,
    inp: &TraceInputs,
    outs: &[UnitTraces],
) -> Result<PathBuf, PipelineError> {
    let cfg = store.cfg;
    let axes = axes_of(cfg, study.building());
    let mut zones = Vec::new();
    let mut at = 0;
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let motions = &store.motions[z];
        let count = motions.len() * cfg.cases.len() * study.frames().len();
        let names = motions.iter().map(|m| m.name.clone()).collect();
        let (zone, target) = ((zc.name.as_str(), zc.target.as_str()), &inp.targets[z]);
        let building = study.cfg.building.as_ref();
        let units = &outs[at..at + count];
        zones.push(zone_ida(cfg, &axes, building, zone, target, names, units));
        at += count;
    }
    let c_y_rule = c_y_rule(cfg, study.building().is_some());
    let building_json = study.building_attr();
    let settings = settings_attrs(cfg, &inp.physics, &c_y_rule, building_json.as_deref());
    let meta = IdaMeta {
        fingerprint: store.fingerprint,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        config_sha256: &study.config_sha256,
        fit_flags: FIT_STATUS_FLAGS,
        settings: &settings,
    };
    let path = study.path(StageId::Ida.output());
    write_ida(&path, &meta, &axes, &zones)?;
    Ok(path)
}

/// `(units the IDA traces, units stored for the current IDA)`; before the motions stage ran
/// the motion counts come from the config ([`Study::motions_per_zone`]) and none is
/// stored.
pub fn unit_status(study: &Study) -> Result<(usize, usize), PipelineError> {
    let cfg = study.ida_config()?;
    let frames = study.frames();
    if study.state(StageId::Motions)? != super::StageState::UpToDate {
        let counts = study.motions_per_zone();
        let plan = UnitPlan::new(&counts, cfg.cases.len(), frames);
        return Ok((plan.run.len(), 0));
    }
    let motions = super::files::motions(study)?;
    let counts: Vec<usize> = motions.iter().map(Vec::len).collect();
    let plan = UnitPlan::new(&counts, cfg.cases.len(), frames);
    let done = if study.state(StageId::Ida)? == super::StageState::UpToDate {
        plan.run.len()
    } else {
        let store = CaseUnits {
            study,
            cfg,
            motions: &motions,
            fingerprint: study.fingerprint(StageId::Ida)?,
        };
        (plan.run.iter())
            .filter(|&&u| matches!(store.read(u), Ok(Some(_))))
            .count()
    };
    Ok((plan.run.len(), done))
}

/// The directory of the IDA's unit files.
pub const UNITS_DIR: &str = "ida.units";

/// Removes the IDA's unit files (after `ida.h5` was verified, or left over from an interrupted
/// cleanup).
pub fn remove_units(study: &Study) -> Result<(), StoreError> {
    crate::store::units::remove_units(&study.path(UNITS_DIR))
}

/// The IDA's unit files: a unit's traces as columns (the record's `Sa` first, then per system
/// its runs' `Sa` and demands, `f64`; its runs' collapse and slip flags, `u8`), under an
/// identity whose `period_index` and `period_s` are the `ida:` section's case and its `T_p`.
struct CaseUnits<'a> {
    study: &'a Study,
    cfg: &'a IdaConfig,
    motions: &'a [Vec<Record>],
    fingerprint: &'a str,
}

impl CaseUnits<'_> {
    fn place(&self, u: CaseUnit) -> (PathBuf, UnitId) {
        super::files::unit_place(
            self.study,
            (UNITS_DIR, self.fingerprint),
            self.motions,
            (u.zone, u.motion, u.frame),
            (u.case, self.cfg.cases[u.case].period_s),
        )
    }

    /// Reads each of `units` (in order): what a unit file holds when `keep` (else nothing),
    /// and `(index, unit)` of those to trace, a damaged file among them with a warning.
    fn scan(
        &self,
        s: &Session,
        units: &[CaseUnit],
        keep: bool,
    ) -> (Vec<Option<UnitTraces>>, Vec<(usize, CaseUnit)>) {
        let me = StageId::Ida;
        let (held, todo) = super::scan_units(s, me, units, keep, |u| self.read(u));
        if todo.len() < units.len() {
            let line = format!(
                "{} of {} units to trace ({} already done)",
                todo.len(),
                units.len(),
                units.len() - todo.len()
            );
            s.reporter.info(me, &line);
        }
        (held, todo)
    }

    fn write(&self, u: CaseUnit, t: &UnitTraces) -> Result<(), StoreError> {
        let mut c = Columns {
            f64s: vec![vec![t.record_sa_g]],
            u8s: Vec::new(),
        };
        for trace in &t.traces {
            c.f64s.push(trace.runs.iter().map(|r| r.sa_g).collect());
            (c.f64s).push(
                trace
                    .runs
                    .iter()
                    .flat_map(|r| r.demand.values.clone())
                    .collect(),
            );
            c.u8s
                .push(trace.runs.iter().map(|r| u8::from(r.collapsed)).collect());
            (c.u8s).push(
                (trace.runs.iter())
                    .map(|r| u8::from(r.demand.slip_exceeded))
                    .collect(),
            );
        }
        let (path, id) = self.place(u);
        write_unit(&path, &id, &c)
    }

    /// The unit's traces, `None` when no file holds them for this IDA (missing, or made with
    /// other inputs); a file of the wrong shape is refused as damaged.
    fn read(&self, u: CaseUnit) -> Result<Option<UnitTraces>, StoreError> {
        let (path, id) = self.place(u);
        let c = match read_unit(&path, &id)? {
            Stored::Valid(c) => c,
            Stored::Missing | Stored::Stale => return Ok(None),
        };
        let demands = self.cfg.demand_names(self.study.building().is_some()).len();
        let max_runs = self.cfg.tracing.max_runs();
        let shape_ok = c.f64s.len() == 1 + 2 * SYSTEMS.len()
            && c.u8s.len() == 2 * SYSTEMS.len()
            && c.f64s[0].len() == 1
            && (0..SYSTEMS.len()).all(|k| {
                let runs = c.f64s[1 + 2 * k].len();
                runs <= max_runs
                    && c.f64s[2 + 2 * k].len() == runs * demands
                    && c.u8s[2 * k].len() == runs
                    && c.u8s[2 * k + 1].len() == runs
            });
        if !shape_ok {
            let found: Vec<usize> = (c.f64s.iter().map(Vec::len))
                .chain(c.u8s.iter().map(Vec::len))
                .collect();
            let why = format!(
                "holds columns of lengths {found:?}, not one unit of {} systems' runs of {demands} \
                 demands",
                SYSTEMS.len()
            );
            return Err(StoreError::corrupt(&path, why));
        }
        let traces = (0..SYSTEMS.len())
            .map(|k| {
                let (sa, values) = (&c.f64s[1 + 2 * k], &c.f64s[2 + 2 * k]);
                let (collapsed, slip) = (&c.u8s[2 * k], &c.u8s[2 * k + 1]);
                let runs = (0..sa.len())
                    .map(|r| Run {
                        sa_g: sa[r],
                        demand: RunDemand {
                            values: values[r * demands..(r + 1) * demands].to_vec(),
                            slip_exceeded: slip[r] != 0,
                        },
                        collapsed: collapsed[r] != 0,
                    })
                    .collect();
                Trace { runs }
            })
            .collect();
        Ok(Some(UnitTraces {
            record_sa_g: c.f64s[0][0],
            traces,
            samples: 0,
        }))
    }
}

/// How the structure's strength is set, in words (in a building: the base-shear coefficient
/// and its distribution over the height).
fn c_y_rule(cfg: &IdaConfig, building: bool) -> String {
    let base = match (&cfg.structure.c_y, &cfg.structure.design) {
        (Some(c), _) => format!("C_y = {c}"),
        (None, Some(d)) => format!(
            "C_y = (Z/2)(I/R)(Sa/g)(T_p) of the zone's IS 1893 target, I = {}, R = {}",
            d.importance, d.response_reduction
        ),
        (None, None) => String::new(),
    };
    if !building {
        return base;
    }
    format!(
        "{base}, the base-shear coefficient on the bare floors' weight (T_p = T_1, the bare \
         building's first-mode period); storey strengths F_y,i = V_i = sum_(j>=i) Q_j with \
         Q_j = V_B m_j h_j^2 / sum_k m_k h_k^2 (IS 1893 (Part 1):2016 Clause 7.6.3), h_j the \
         height of floor j"
    )
}

/// The settings `ida.h5` states as file attributes.
fn settings_attrs<'a>(
    cfg: &IdaConfig,
    physics: &Physics,
    c_y_rule: &'a str,
    building_json: Option<&'a str>,
) -> Vec<(&'static str, Attr<'a>)> {
    let t = &cfg.tracing;
    let mut settings: Vec<(&str, Attr)> = super::physics_attrs(physics).to_vec();
    settings.extend([
        ("mu_static_ratio", Attr::F64(physics.mu_static_ratio)),
        ("c_y_rule", Attr::Str(c_y_rule)),
        (
            "post_yield_ratio",
            Attr::F64(cfg.structure.post_yield_ratio),
        ),
    ]);
    match (
        building_json,
        cfg.collapse_ductility,
        cfg.collapse_drift_ratio,
    ) {
        (Some(b), _, Some(r)) => settings.extend([
            ("building", Attr::Str(b)),
            ("collapse_drift_ratio", Attr::F64(r)),
        ]),
        (_, Some(d), _) => settings.push(("collapse_ductility", Attr::F64(d))),
        _ => {}
    }
    settings.extend([
        ("slip_limit_m", Attr::F64(cfg.slip_limit_m)),
        ("pad_s", Attr::F64(cfg.pad_s)),
        ("first_sa_g", Attr::F64(t.first_sa_g)),
        ("step_increment_sa_g", Attr::F64(t.step_increment_sa_g)),
        ("bracket_runs", Attr::F64(t.bracket_runs as f64)),
        ("fill_runs", Attr::F64(t.fill_runs as f64)),
        ("cap_sa_g", Attr::F64(t.cap_sa_g)),
        (
            "intensity_measure",
            Attr::Str(if building_json.is_some() {
                "Sa(T_1, 5 %) of the scaled motion, T_1 the bare building's first-mode period, g"
            } else {
                "Sa(T_p, 5 %) of the scaled motion, T_p the bare structure's period, g"
            }),
        ),
        (
            "fragility_method",
            Attr::Str(
                "lognormal, maximum likelihood on multiple stripes (Baker 2015) read off the IDA \
                 curves at every grid intensity; 95 % Wald intervals from the observed \
                 information (stripes treated as independent)",
            ),
        ),
    ]);
    settings
}
