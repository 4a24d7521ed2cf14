//! `ida.h5`, the incremental dynamic analysis stage's file.
//!
//! ```text
//! /                  attrs: contents, slidestack_version, fingerprint, motions_fingerprint,
//!                           config_sha256, + the writer's settings (tracing, structure, fit)
//! /zone_<name>/      attrs: target
//!     system, record, demand, limit_state (strings), case, block, run, Sa (g), fractile
//!                                                    coordinates (dimension scales)
//!     case_T_p (s) [case]; case_alpha, case_mu [case, block]; c_y [case]
//!     limit_state_definition [limit_state]
//!     record_Sa (g) [record, case]: Sa(T_p, 5 %) of the unscaled motion
//!     run_Sa (g) [system, record, case, run]; run_demand [system, record, case, run, demand];
//!     run_collapsed, run_slip_exceeded (CF flags) [system, record, case, run]
//!     collapse_Sa (g) [system, record, case]: lowest collapsing intensity (NaN: none)
//!     curve [system, record, case, Sa, demand]
//!     fractile_curve [system, case, fractile, Sa, demand]
//!     exceed_fraction, fragility_curve [system, case, limit_state, Sa]
//!     theta (g), beta, theta_ci_low, theta_ci_high (g), beta_ci_low, beta_ci_high,
//!     fit_status (CF flags) [system, case, limit_state]
//! ```
//! In a building study (docs/model.md, "Incremental dynamic analysis", "In a building") every
//! variable over `case` is over `case, storeys, stack_floor` instead (the frames, dimension
//! scales as in `sweep.h5`; `c_y`, the base-shear coefficient, stays over `case`), and
//! ```text
//!     storey (number, 1 = the lowest) coordinate
//!     storey_c_y [case, storeys, storey]: C_y,i of each storey (NaN above the building)
//! ```
//! In memory ([`IdaVars`]) the frames are folded into the case axis, case-major
//! (`case·frames + frame`, frames as [`BuildingAxes::frame`] orders them).
//!
//! Runs a trace did not make are NaN (255 for the flags). Variables are chunked per system,
//! deflate+shuffle compressed, Fletcher32-checksummed, written in a fixed order with object
//! times not tracked, so the same inputs give the same bytes.

use super::StoreError;
use super::h5::{
    Attr, GroupReader, attach_scale, attr_str, coordinate, string_coordinate, write_attrs,
    write_flags, write_stage_file, write_strings, write_var,
};
use super::sweep::{building_coordinates, read_building_coordinates};
use crate::grid::BuildingAxes;
use ndarray::{ArrayD, IxDyn};
use std::path::Path;

/// The axes every zone shares.
#[derive(Debug, Clone, PartialEq)]
pub struct IdaAxes {
    pub systems: Vec<String>,
    pub case_period_s: Vec<f64>,
    /// `[case][block]`.
    pub case_alpha: Vec<Vec<f64>>,
    pub case_mu: Vec<Vec<f64>>,
    pub runs: usize,
    pub sa_grid_g: Vec<f64>,
    pub demands: Vec<String>,
    pub limit_states: Vec<String>,
    pub limit_state_definitions: Vec<String>,
    pub fractiles: Vec<f64>,
    /// The frames of a building study.
    pub building: Option<BuildingAxes>,
}

impl IdaAxes {
    /// Frames per case (1 on one storey).
    pub fn frame_count(&self) -> usize {
        self.building.as_ref().map_or(1, BuildingAxes::frame_count)
    }

    /// The largest storey count (the length of `storey`).
    pub fn max_storeys(&self) -> usize {
        (self.building.as_ref()).map_or(1, |b| b.storeys.iter().copied().max().unwrap_or(1))
    }
}

/// One zone's variables (shapes in the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct IdaVars {
    pub c_y: ArrayD<f64>,
    /// `[case, storeys, storey]`, in a building study.
    pub storey_c_y: Option<ArrayD<f64>>,
    pub record_sa_g: ArrayD<f64>,
    pub run_sa_g: ArrayD<f64>,
    pub run_demand: ArrayD<f64>,
    pub run_collapsed: ArrayD<u8>,
    pub run_slip_exceeded: ArrayD<u8>,
    pub collapse_sa_g: ArrayD<f64>,
    pub curve: ArrayD<f64>,
    pub fractile_curve: ArrayD<f64>,
    pub exceed_fraction: ArrayD<f64>,
    pub fragility_curve: ArrayD<f64>,
    pub theta_sa_g: ArrayD<f64>,
    pub beta: ArrayD<f64>,
    pub theta_ci_low_sa_g: ArrayD<f64>,
    pub theta_ci_high_sa_g: ArrayD<f64>,
    pub beta_ci_low: ArrayD<f64>,
    pub beta_ci_high: ArrayD<f64>,
    pub fit_status: ArrayD<u8>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ZoneIda {
    pub name: String,
    pub target: String,
    pub records: Vec<String>,
    pub vars: IdaVars,
}

/// Provenance written on `ida.h5`.
#[derive(Debug, Clone)]
pub struct IdaMeta<'a> {
    pub fingerprint: &'a str,
    pub motions_fingerprint: &'a str,
    pub config_sha256: &'a str,
    /// `(code, word)` pairs of `fit_status`.
    pub fit_flags: &'a [(u8, &'a str)],
    pub settings: &'a [(&'a str, Attr<'a>)],
}

const YES_NO: [(u8, &str); 2] = [(0, "no"), (1, "yes")];

/// Writes `ida.h5` (checked and atomic).
pub fn write_ida(
    path: &Path,
    meta: &IdaMeta,
    axes: &IdaAxes,
    zones: &[ZoneIda],
) -> Result<(), StoreError> {
    write_stage_file(
        path,
        "slidestack ida stage: incremental dynamic analysis of a yielding structure with its \
         stack, IDA curves, fractiles and fragility functions",
        meta.fingerprint,
        |f| {
            attr_str(f, "motions_fingerprint", meta.motions_fingerprint)?;
            attr_str(f, "config_sha256", meta.config_sha256)?;
            write_attrs(f, meta.settings)?;
            for z in zones {
                write_zone(f, axes, z, meta)?;
            }
            Ok(())
        },
    )
}

fn indices(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64).collect()
}

/// One chunk per leading index (per system where there is one).
fn chunk_of(shape: &[usize]) -> Vec<usize> {
    let mut c = shape.to_vec();
    if c.len() > 1 {
        c[0] = 1;
    }
    c
}

/// The coordinates of one zone's group, each a dimension scale.
struct Coordinates {
    system: hdf5::Dataset,
    record: hdf5::Dataset,
    case: hdf5::Dataset,
    block: hdf5::Dataset,
    run: hdf5::Dataset,
    sa: hdf5::Dataset,
    demand: hdf5::Dataset,
    limit: hdf5::Dataset,
    fractile: hdf5::Dataset,
    /// `storeys`, `stack_floor` and `storey`, in a building study.
    building: Option<[hdf5::Dataset; 3]>,
}

impl Coordinates {
    /// `before`, then the case's dimensions (`case`, or `case, storeys, stack_floor` in a
    /// building study), then `after`.
    fn around<'a>(
        &'a self,
        before: &[&'a hdf5::Dataset],
        after: &[&'a hdf5::Dataset],
    ) -> Vec<&'a hdf5::Dataset> {
        let mut v = before.to_vec();
        v.push(&self.case);
        if let Some([n, f, _]) = &self.building {
            v.extend([n, f]);
        }
        v.extend_from_slice(after);
        v
    }
}

/// `a` with its axis `at` of `cases × frames` split into `[cases, storeys, stack_floor]`
/// (`frames` the latter two; `None`: `a` itself).
fn split<T: Clone>(a: &ArrayD<T>, at: usize, frames: Option<[usize; 2]>) -> ArrayD<T> {
    let Some([n, f]) = frames else {
        return a.clone();
    };
    let mut shape = a.shape().to_vec();
    let cases = shape[at] / (n * f);
    shape.splice(at..=at, [cases, n, f]);
    a.as_standard_layout()
        .into_owned()
        .into_shape_with_order(IxDyn(&shape))
        .expect("cases × frames")
}

/// The inverse of [`split`].
fn fold<T: Clone>(a: ArrayD<T>, at: usize, frames: Option<[usize; 2]>) -> ArrayD<T> {
    if frames.is_none() {
        return a;
    }
    let mut shape = a.shape().to_vec();
    let merged: usize = shape[at..at + 3].iter().product();
    shape.splice(at..at + 3, [merged]);
    a.as_standard_layout()
        .into_owned()
        .into_shape_with_order(IxDyn(&shape))
        .expect("cases × frames")
}

fn write_zone(f: &hdf5::File, axes: &IdaAxes, z: &ZoneIda, meta: &IdaMeta) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", &z.target)?;
    let dims = write_coordinates(&g, axes, z)?;
    let frames = axes.building.as_ref().map(BuildingAxes::shape);
    write_cases(&g, axes, &z.vars, &dims, frames)?;
    write_runs(&g, &z.vars, &dims, frames)?;
    write_fits(&g, &z.vars, &dims, meta, frames)
}

/// A variable over the coordinates `dims`, chunked by [`chunk_of`].
fn put(
    g: &hdf5::Group,
    name: &str,
    data: &ArrayD<f64>,
    dims: &[&hdf5::Dataset],
    units: &str,
    long: &str,
) -> hdf5::Result<()> {
    let ds = write_var(g, name, data.view(), &chunk_of(data.shape()), units, long)?;
    for (i, d) in dims.iter().enumerate() {
        attach_scale(&ds, d, i)?;
    }
    Ok(())
}

/// A CF flag variable over the coordinates `dims`.
fn put_flags(
    g: &hdf5::Group,
    name: &str,
    data: &ArrayD<u8>,
    dims: &[&hdf5::Dataset],
    long: &str,
    flags: &[(u8, &str)],
) -> hdf5::Result<()> {
    let ds = write_flags(g, name, data.view(), &chunk_of(data.shape()), long, flags)?;
    for (i, d) in dims.iter().enumerate() {
        attach_scale(&ds, d, i)?;
    }
    Ok(())
}

fn write_coordinates(g: &hdf5::Group, axes: &IdaAxes, z: &ZoneIda) -> hdf5::Result<Coordinates> {
    let system = string_coordinate(
        g,
        "system",
        &axes.systems,
        "stack: the sliding stack; rigid: the same load rigidly attached",
    )?;
    let record = string_coordinate(
        g,
        "record",
        &z.records,
        "ground motion (matched, see motions.h5)",
    )?;
    let case = coordinate(
        g,
        "case",
        &indices(axes.case_period_s.len()),
        "1",
        "case index (ida.cases of the config)",
    )?;
    let block = coordinate(
        g,
        "block",
        &indices(axes.case_alpha.first().map_or(0, Vec::len)),
        "1",
        "block (0 = bottom) or interface under it",
    )?;
    let run = coordinate(
        g,
        "run",
        &indices(axes.runs),
        "1",
        "run of a trace, in the order made (hunt, bracket, fill)",
    )?;
    let sa = coordinate(
        g,
        "Sa",
        &axes.sa_grid_g,
        "g",
        if axes.building.is_some() {
            "Sa(T_1, 5 %) of the scaled motion (T_1 the bare building's first-mode period): the \
             common intensity grid"
        } else {
            "Sa(T_p, 5 %) of the scaled motion: the common intensity grid"
        },
    )?;
    let demand = string_coordinate(
        g,
        "demand",
        &axes.demands,
        "engineering demand (units in the name; ductility = u_m/u_y)",
    )?;
    let limit = string_coordinate(
        g,
        "limit_state",
        &axes.limit_states,
        "limit state of the fragility fits",
    )?;
    let fractile = coordinate(
        g,
        "fractile",
        &axes.fractiles,
        "1",
        "fractile over the records",
    )?;
    let ds = write_strings(
        g,
        "limit_state_definition",
        &axes.limit_state_definitions,
        "exceeded when (a collapse exceeds every limit state)",
    )?;
    attach_scale(&ds, &limit, 0)?;
    let building = match &axes.building {
        None => None,
        Some(b) => {
            let [n, f] = <[hdf5::Dataset; 2]>::try_from(building_coordinates(g, b)?)
                .expect("storeys and stack_floor");
            let storeys: Vec<f64> = (1..=axes.max_storeys()).map(|i| i as f64).collect();
            let storey = coordinate(g, "storey", &storeys, "1", "storey (1 = the lowest)")?;
            Some([n, f, storey])
        }
    };
    Ok(Coordinates {
        system,
        record,
        case,
        block,
        run,
        sa,
        demand,
        limit,
        fractile,
        building,
    })
}

/// The cases and their strengths, and each record's intensity.
fn write_cases(
    g: &hdf5::Group,
    axes: &IdaAxes,
    v: &IdaVars,
    d: &Coordinates,
    frames: Option<[usize; 2]>,
) -> hdf5::Result<()> {
    let shape = (
        axes.case_alpha.len(),
        axes.case_alpha.first().map_or(0, Vec::len),
    );
    let alpha = ndarray::Array2::from_shape_fn(shape, |(c, b)| axes.case_alpha[c][b]).into_dyn();
    let mu = ndarray::Array2::from_shape_fn(shape, |(c, b)| axes.case_mu[c][b]).into_dyn();
    let periods = ndarray::Array1::from(axes.case_period_s.clone()).into_dyn();
    put(
        g,
        "case_T_p",
        &periods,
        &[&d.case],
        "s",
        "period of the bare structure",
    )?;
    put(
        g,
        "case_alpha",
        &alpha,
        &[&d.case, &d.block],
        "1",
        "mass ratio m_i/m_p of each block",
    )?;
    put(
        g,
        "case_mu",
        &mu,
        &[&d.case, &d.block],
        "1",
        "kinetic friction coefficient of the interface under each block",
    )?;
    put(
        g,
        "c_y",
        &v.c_y,
        &[&d.case],
        "1",
        if d.building.is_some() {
            "base-shear coefficient V_B/(g sum_j m_j) of the bare building (the strength of storey 1)"
        } else {
            "yield strength ratio F_y/(m_p g) of the structure"
        },
    )?;
    if let (Some(c), Some([n, _, storey])) = (&v.storey_c_y, &d.building) {
        put(
            g,
            "storey_c_y",
            c,
            &[&d.case, n, storey],
            "1",
            "storey strength ratio F_y,i/(g sum_{j>=i} m_j) from c_y by IS 1893 (Part 1):2016 \
             Clause 7.6.3 (NaN above the building)",
        )?;
    }
    put(
        g,
        "record_Sa",
        &split(&v.record_sa_g, 1, frames),
        &d.around(&[&d.record], &[]),
        "g",
        if d.building.is_some() {
            "Sa(T_1, 5 %) of the unscaled motion (T_1 the bare building's first-mode period)"
        } else {
            "Sa(T_p, 5 %) of the unscaled motion"
        },
    )
}

/// The traced runs, the curves on the common grid and their fractiles.
fn write_runs(
    g: &hdf5::Group,
    v: &IdaVars,
    d: &Coordinates,
    frames: Option<[usize; 2]>,
) -> hdf5::Result<()> {
    let sys_run = d.around(&[&d.system, &d.record], &[&d.run]);
    let at = |a: &ArrayD<f64>| split(a, 2, frames);
    let at_flags = |a: &ArrayD<u8>| split(a, 2, frames);
    put(
        g,
        "run_Sa",
        &at(&v.run_sa_g),
        &sys_run,
        "g",
        "intensity of each traced run",
    )?;
    put(
        g,
        "run_demand",
        &at(&v.run_demand),
        &d.around(&[&d.system, &d.record], &[&d.run, &d.demand]),
        "demand",
        "demands of each traced run (units in the demand names)",
    )?;
    put_flags(
        g,
        "run_collapsed",
        &at_flags(&v.run_collapsed),
        &sys_run,
        if frames.is_some() {
            "the run reached the collapse drift ratio"
        } else {
            "the run reached the collapse ductility"
        },
        &YES_NO,
    )?;
    put_flags(
        g,
        "run_slip_exceeded",
        &at_flags(&v.run_slip_exceeded),
        &sys_run,
        "some block's peak slip reached slip_limit_m",
        &YES_NO,
    )?;
    put(
        g,
        "collapse_Sa",
        &at(&v.collapse_sa_g),
        &d.around(&[&d.system, &d.record], &[]),
        "g",
        "lowest collapsing intensity of the trace (NaN: no collapse up to the cap)",
    )?;
    put(
        g,
        "curve",
        &at(&v.curve),
        &d.around(&[&d.system, &d.record], &[&d.sa, &d.demand]),
        "demand",
        "IDA curve on the common grid (linear between runs; +inf from the collapse on; NaN above the last run)",
    )?;
    put(
        g,
        "fractile_curve",
        &split(&v.fractile_curve, 1, frames),
        &d.around(&[&d.system], &[&d.fractile, &d.sa, &d.demand]),
        "demand",
        "fractiles of the curves over the records (type 7; collapsed records count as +inf)",
    )
}

/// The stripes, the fragility fits and their intervals.
fn write_fits(
    g: &hdf5::Group,
    v: &IdaVars,
    d: &Coordinates,
    meta: &IdaMeta,
    frames: Option<[usize; 2]>,
) -> hdf5::Result<()> {
    let fr = d.around(&[&d.system], &[&d.limit, &d.sa]);
    put(
        g,
        "exceed_fraction",
        &split(&v.exceed_fraction, 1, frames),
        &fr,
        "1",
        "fraction of the records whose curve exceeds the limit state (the stripe data of the fit)",
    )?;
    put(
        g,
        "fragility_curve",
        &split(&v.fragility_curve, 1, frames),
        &fr,
        "1",
        "fitted lognormal fragility Phi(ln(Sa/theta)/beta)",
    )?;
    let fit = d.around(&[&d.system], &[&d.limit]);
    for (name, data, units, long) in [
        (
            "theta",
            &v.theta_sa_g,
            "g",
            "median capacity theta (maximum likelihood, multiple stripes, Baker 2015)",
        ),
        ("beta", &v.beta, "1", "logarithmic standard deviation beta"),
        (
            "theta_ci_low",
            &v.theta_ci_low_sa_g,
            "g",
            "95 % Wald interval of theta, observed information, lower end",
        ),
        (
            "theta_ci_high",
            &v.theta_ci_high_sa_g,
            "g",
            "95 % Wald interval of theta, upper end",
        ),
        (
            "beta_ci_low",
            &v.beta_ci_low,
            "1",
            "95 % Wald interval of beta (on ln beta), lower end",
        ),
        (
            "beta_ci_high",
            &v.beta_ci_high,
            "1",
            "95 % Wald interval of beta, upper end",
        ),
    ] {
        put(g, name, &split(data, 1, frames), &fit, units, long)?;
    }
    put_flags(
        g,
        "fit_status",
        &split(&v.fit_status, 1, frames),
        &fit,
        "how the fragility fit ended",
        meta.fit_flags,
    )
}

/// Zone `zone` of `ida.h5` with the axes stored with it; every variable has the shape its
/// coordinates give (module doc).
pub fn read_zone_ida(path: &Path, zone: &str) -> Result<(IdaAxes, ZoneIda), StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let (systems, records) = (g.strings("system")?, g.strings("record")?);
    let (cases, blocks) = (g.vector("case")?.len(), g.vector("block")?.len());
    let rows = |name: &str| -> Result<Vec<Vec<f64>>, StoreError> {
        let a = g.array::<f64>(name, &[cases, blocks])?;
        Ok(a.outer_iter()
            .map(|r| r.iter().copied().collect())
            .collect())
    };
    let limit_states = g.strings("limit_state")?;
    let limit_state_definitions = g.strings("limit_state_definition")?;
    g.expect(
        "limit_state_definition",
        &[limit_state_definitions.len()],
        &[limit_states.len()],
    )?;
    let axes = IdaAxes {
        systems,
        case_period_s: g.array("case_T_p", &[cases])?.iter().copied().collect(),
        case_alpha: rows("case_alpha")?,
        case_mu: rows("case_mu")?,
        runs: g.vector("run")?.len(),
        sa_grid_g: g.vector("Sa")?,
        demands: g.strings("demand")?,
        limit_states,
        limit_state_definitions,
        fractiles: g.vector("fractile")?,
        building: if g.group().link_exists("storeys") {
            Some(read_building_coordinates(&g)?)
        } else {
            None
        },
    };
    let frames = axes.building.as_ref().map(BuildingAxes::shape);
    let (s, r, c, n) = (axes.systems.len(), records.len(), cases, axes.runs);
    let (d, sa, l, q) = (
        axes.demands.len(),
        axes.sa_grid_g.len(),
        axes.limit_states.len(),
        axes.fractiles.len(),
    );
    // Each variable over `[before.., case, after..]` as stored, folded back to one case axis.
    let shape = |before: &[usize], after: &[usize]| -> Vec<usize> {
        let mut v = before.to_vec();
        v.push(c);
        v.extend(frames.into_iter().flatten());
        v.extend_from_slice(after);
        v
    };
    let f64s = |name: &str, before: &[usize], after: &[usize]| -> Result<ArrayD<f64>, StoreError> {
        Ok(fold(
            g.array(name, &shape(before, after))?,
            before.len(),
            frames,
        ))
    };
    let flags = |name: &str, before: &[usize], after: &[usize]| -> Result<ArrayD<u8>, StoreError> {
        Ok(fold(
            g.array(name, &shape(before, after))?,
            before.len(),
            frames,
        ))
    };
    let storey_c_y = match &axes.building {
        None => None,
        Some(b) => Some(g.array("storey_c_y", &[c, b.storeys.len(), axes.max_storeys()])?),
    };
    let vars = IdaVars {
        c_y: g.array("c_y", &[c])?,
        storey_c_y,
        record_sa_g: f64s("record_Sa", &[r], &[])?,
        run_sa_g: f64s("run_Sa", &[s, r], &[n])?,
        run_demand: f64s("run_demand", &[s, r], &[n, d])?,
        run_collapsed: flags("run_collapsed", &[s, r], &[n])?,
        run_slip_exceeded: flags("run_slip_exceeded", &[s, r], &[n])?,
        collapse_sa_g: f64s("collapse_Sa", &[s, r], &[])?,
        curve: f64s("curve", &[s, r], &[sa, d])?,
        fractile_curve: f64s("fractile_curve", &[s], &[q, sa, d])?,
        exceed_fraction: f64s("exceed_fraction", &[s], &[l, sa])?,
        fragility_curve: f64s("fragility_curve", &[s], &[l, sa])?,
        theta_sa_g: f64s("theta", &[s], &[l])?,
        beta: f64s("beta", &[s], &[l])?,
        theta_ci_low_sa_g: f64s("theta_ci_low", &[s], &[l])?,
        theta_ci_high_sa_g: f64s("theta_ci_high", &[s], &[l])?,
        beta_ci_low: f64s("beta_ci_low", &[s], &[l])?,
        beta_ci_high: f64s("beta_ci_high", &[s], &[l])?,
        fit_status: flags("fit_status", &[s], &[l])?,
    };
    let z = ZoneIda {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        records,
        vars,
    };
    Ok((axes, z))
}
