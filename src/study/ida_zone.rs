//! One zone of the IDA (the `ida` stage's numerics): a work unit traced (one motion, one case
//! of the `ida:` section, on a building study's frame; both systems, [`SYSTEMS`]), then the
//! zone's curves on the intensity grid, their fractiles and each limit state's stripes and
//! lognormal fragility, as `ida.h5` stores them ([`crate::store::ida`]). The kernels are in
//! [`crate::ida`]; the systems and one trace in [`super::ida`].

use super::building::{BuildingSection, Frame};
use super::ida::{IdaConfig, SYSTEMS, padded, sa_g, trace_system};
use super::physics::Physics;
use super::storey_strength::storey_strength_ratios;
use crate::case::Case;
use crate::grid::BuildingAxes;
use crate::ground_motion::Record;
use crate::ida::curve::{fractile, on_grid};
use crate::ida::fragility::{FitStatus, fit_lognormal};
use crate::ida::trace::Trace;
use crate::spectrum::TargetSpectrum;
use crate::store::ida::{IdaAxes, IdaVars, ZoneIda};
use crate::study::ida::RunDemand;
use ndarray::{ArrayD, IxDyn};
use rayon::prelude::*;

/// The fractiles of the summary curves (Vamvatsikos & Cornell 2002, Section 6).
pub const FRACTILES: [f64; 3] = [0.16, 0.5, 0.84];

/// One zone of `ida.h5` from its units' traces (`units`: record-major, then case, then frame):
/// the strengths of its cases from its `target` and, in a building study (`building`), each
/// storey's.
pub fn zone_ida(
    cfg: &IdaConfig,
    axes: &IdaAxes,
    building: Option<&BuildingSection>,
    (name, target_name): (&str, &str),
    target: &TargetSpectrum,
    records: Vec<String>,
    units: &[UnitTraces],
) -> ZoneIda {
    let c_y: Vec<f64> = (cfg.cases.iter())
        .map(|c| cfg.strength_ratio(target, c))
        .collect();
    ZoneIda {
        name: name.to_string(),
        target: target_name.to_string(),
        storey_c_y: storey_c_y(building, axes, &c_y),
        vars: zone_vars(cfg, axes, records.len(), units),
        c_y: ArrayD::from_shape_vec(IxDyn(&[c_y.len()]), c_y).expect("one per case"),
        records,
    }
}

/// What a unit gave: the record's `Sa(T_p, 5 %)`, g, each system's trace, and the record
/// samples its runs simulated (for the stage's rate).
#[derive(Clone)]
pub struct UnitTraces {
    pub record_sa_g: f64,
    pub traces: Vec<Trace<RunDemand>>,
    pub samples: usize,
}

/// Why a unit could not be traced: the system ([`crate::study::physics::SystemKind::key`])
/// and the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitFailure {
    pub system: &'static str,
    pub why: String,
}

/// Traces `case` under `record` on `frame` ([`Frame::one_storey`] on one storey), both systems,
/// the strength from the zone's `target`; `building`: a building study's, whose demands are
/// drift ratios of the frame's storey heights ([`run_demand`](super::ida::run_demand)).
pub fn trace_unit(
    cfg: &IdaConfig,
    physics: &Physics,
    target: &TargetSpectrum,
    (case, frame, building): (&Case, &Frame, bool),
    record: &Record,
) -> Result<UnitTraces, UnitFailure> {
    let fail = |system: &'static str, why: String| UnitFailure { system, why };
    let accel = record.accel_mps2(1.0);
    let record_sa_g = sa_g(&accel, record.dt_s, case.period_s)
        .map_err(|e| fail(SYSTEMS[0].key(), e.to_string()))?;
    let padded = padded(&accel, record.dt_s, cfg.pad_s);
    let c_y = cfg.strength_ratio(target, case);
    let systems = (cfg.systems(physics, case, c_y, frame))
        .map_err(|e| fail(SYSTEMS[0].key(), e.to_string()))?;
    let heights = building.then_some(frame.storey_heights_m.as_slice());
    let traces = (systems.iter().zip(SYSTEMS))
        .map(|(sys, kind)| {
            trace_system(cfg, sys, heights, &padded, record.dt_s, record_sa_g)
                .map_err(|e| fail(kind.key(), e.to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let runs: usize = traces.iter().map(|t| t.runs.len()).sum();
    Ok(UnitTraces {
        record_sa_g,
        traces,
        samples: runs * padded.len(),
    })
}

/// The axes `ida.h5` has for the `ida:` section `cfg` (in a building study of `building`).
pub fn axes_of(cfg: &IdaConfig, building: Option<&BuildingAxes>) -> IdaAxes {
    IdaAxes {
        systems: SYSTEMS.iter().map(|s| s.key().to_string()).collect(),
        case_period_s: cfg.cases.iter().map(|c| c.period_s).collect(),
        case_alpha: cfg.cases.iter().map(|c| c.alpha.clone()).collect(),
        case_mu: cfg.cases.iter().map(|c| c.mu.clone()).collect(),
        runs: cfg.tracing.max_runs(),
        sa_grid_g: cfg.grid_sa_g(),
        demands: cfg.demand_names(building.is_some()),
        limit_states: cfg.limit_states.iter().map(|l| l.name.clone()).collect(),
        limit_state_definitions: cfg.limit_states.iter().map(|l| l.definition()).collect(),
        fractiles: FRACTILES.to_vec(),
        building: building.cloned(),
    }
}

/// `storey_c_y` `[case, storeys, storey]` of a building study (NaN above each building).
fn storey_c_y(
    section: Option<&BuildingSection>,
    axes: &IdaAxes,
    c_y: &[f64],
) -> Option<ArrayD<f64>> {
    let b = axes.building.as_ref()?;
    let section = section?;
    let mut a = array(&[c_y.len(), b.storeys.len(), axes.max_storeys()], f64::NAN);
    for (c, &cy) in c_y.iter().enumerate() {
        for (k, &n) in b.storeys.iter().enumerate() {
            let f = section.frame(n, crate::grid::StackFloor::Roof);
            let ratios = storey_strength_ratios(cy, &f.floor_masses, &f.storey_heights_m);
            for (i, r) in ratios.into_iter().enumerate() {
                a[[c, k, i]] = r;
            }
        }
    }
    Some(a)
}

fn array<T: Clone>(shape: &[usize], fill: T) -> ArrayD<T> {
    ArrayD::from_elem(IxDyn(shape), fill)
}

/// One zone's variables from its units (record-major, then case).
fn zone_vars(cfg: &IdaConfig, axes: &IdaAxes, records: usize, units: &[UnitTraces]) -> IdaVars {
    // Cases and frames folded into one axis, case-major (crate::store::ida).
    let (ns, nc, nr) = (
        SYSTEMS.len(),
        cfg.cases.len() * axes.frame_count(),
        axes.runs,
    );
    let layout = cfg.layout(axes.building.is_some());
    let (nd, ng, nl) = (
        axes.demands.len(),
        axes.sa_grid_g.len(),
        cfg.limit_states.len(),
    );
    let grid = &axes.sa_grid_g;
    let mut v = IdaVars {
        record_sa_g: array(&[records, nc], f64::NAN),
        run_sa_g: array(&[ns, records, nc, nr], f64::NAN),
        run_demand: array(&[ns, records, nc, nr, nd], f64::NAN),
        run_collapsed: array(&[ns, records, nc, nr], 255u8),
        run_slip_exceeded: array(&[ns, records, nc, nr], 255u8),
        collapse_sa_g: array(&[ns, records, nc], f64::NAN),
        curve: array(&[ns, records, nc, ng, nd], f64::NAN),
        fractile_curve: array(&[ns, nc, FRACTILES.len(), ng, nd], f64::NAN),
        exceed_fraction: array(&[ns, nc, nl, ng], f64::NAN),
        fragility_curve: array(&[ns, nc, nl, ng], f64::NAN),
        theta_sa_g: array(&[ns, nc, nl], f64::NAN),
        beta: array(&[ns, nc, nl], f64::NAN),
        theta_ci_low_sa_g: array(&[ns, nc, nl], f64::NAN),
        theta_ci_high_sa_g: array(&[ns, nc, nl], f64::NAN),
        beta_ci_low: array(&[ns, nc, nl], f64::NAN),
        beta_ci_high: array(&[ns, nc, nl], f64::NAN),
        fit_status: array(&[ns, nc, nl], 255u8),
    };
    for (u, out) in units.iter().enumerate() {
        let (r, c) = (u / nc, u % nc);
        v.record_sa_g[[r, c]] = out.record_sa_g;
        for (s, t) in out.traces.iter().enumerate() {
            for (k, run) in t.runs.iter().enumerate() {
                v.run_sa_g[[s, r, c, k]] = run.sa_g;
                v.run_collapsed[[s, r, c, k]] = u8::from(run.collapsed);
                v.run_slip_exceeded[[s, r, c, k]] = u8::from(run.demand.slip_exceeded);
                for (d, x) in run.demand.values.iter().enumerate() {
                    v.run_demand[[s, r, c, k, d]] = *x;
                }
            }
            if let Some((_, hi)) = t.capacity_sa_g() {
                v.collapse_sa_g[[s, r, c]] = hi;
            }
            let sa: Vec<f64> = t.runs.iter().map(|x| x.sa_g).collect();
            let collapsed: Vec<bool> = t.runs.iter().map(|x| x.collapsed).collect();
            for d in 0..nd {
                let demand: Vec<f64> = t.runs.iter().map(|x| x.demand.values[d]).collect();
                for (j, y) in on_grid(&sa, &demand, &collapsed, grid)
                    .into_iter()
                    .enumerate()
                {
                    v.curve[[s, r, c, j, d]] = y;
                }
            }
        }
    }
    let n = cfg.blocks();
    // Each limit state's stripes (`[system, case, limit state]`, intensities, runs, exceedances).
    let mut stripes = Vec::new();
    for s in 0..ns {
        for c in 0..nc {
            for j in 0..ng {
                for d in 0..nd {
                    let vals: Vec<f64> = (0..records).map(|r| v.curve[[s, r, c, j, d]]).collect();
                    for (q, &p) in FRACTILES.iter().enumerate() {
                        v.fractile_curve[[s, c, q, j, d]] = fractile(&vals, p);
                    }
                }
            }
            for (l, ls) in cfg.limit_states.iter().enumerate() {
                let (mut x, mut trials, mut exceed) = (Vec::new(), Vec::new(), Vec::new());
                for (j, &sa) in grid.iter().enumerate() {
                    let (mut nj, mut zj) = (0u32, 0u32);
                    let (d0, over_blocks) = layout.of_limit(ls);
                    for r in 0..records {
                        let value = if over_blocks {
                            (0..n)
                                .map(|i| v.curve[[s, r, c, j, d0 + i]])
                                .fold(f64::NEG_INFINITY, f64::max)
                        } else {
                            v.curve[[s, r, c, j, d0]]
                        };
                        if value.is_nan() {
                            continue;
                        }
                        let threshold = ls.threshold();
                        nj += 1;
                        zj += u32::from(value >= threshold);
                    }
                    if nj > 0 {
                        v.exceed_fraction[[s, c, l, j]] = zj as f64 / nj as f64;
                        x.push(sa);
                        trials.push(nj);
                        exceed.push(zj);
                    }
                }
                stripes.push(([s, c, l], x, trials, exceed));
            }
        }
    }
    // The fits are independent, each sequential: in parallel, the same bits on any thread count.
    let fits: Vec<_> = stripes
        .par_iter()
        .map(|(_, x, trials, exceed)| fit_lognormal(x, trials, exceed))
        .collect();
    for ((at, ..), f) in stripes.iter().zip(fits) {
        let [s, c, l] = *at;
        v.theta_sa_g[*at] = f.theta_sa_g;
        v.beta[*at] = f.beta;
        v.theta_ci_low_sa_g[*at] = f.theta_ci_sa_g.0;
        v.theta_ci_high_sa_g[*at] = f.theta_ci_sa_g.1;
        v.beta_ci_low[*at] = f.beta_ci.0;
        v.beta_ci_high[*at] = f.beta_ci.1;
        v.fit_status[*at] = f.status as u8;
        if matches!(f.status, FitStatus::Fitted | FitStatus::Degenerate) {
            for (j, &sa) in grid.iter().enumerate() {
                v.fragility_curve[[s, c, l, j]] = f.probability(sa);
            }
        }
    }
    v
}
