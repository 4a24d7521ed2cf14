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
//! Runs a trace did not make are NaN (255 for the flags). Variables are chunked per system,
//! deflate+shuffle compressed, Fletcher32-checksummed, written in a fixed order with object
//! times not tracked, so the same inputs give the same bytes.

use super::StoreError;
use super::h5::{
    Attr, GroupReader, attach_scale, attr_str, coordinate, set_scale, write_attrs, write_flags,
    write_stage_file, write_strings, write_var,
};
use ndarray::ArrayD;
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
}

/// One zone's variables (shapes in the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct IdaVars {
    pub c_y: ArrayD<f64>,
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

fn strings_scale(
    g: &hdf5::Group,
    name: &str,
    v: &[String],
    long: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = write_strings(g, name, v, long)?;
    set_scale(&ds, name)?;
    Ok(ds)
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
}

fn write_zone(f: &hdf5::File, axes: &IdaAxes, z: &ZoneIda, meta: &IdaMeta) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", &z.target)?;
    let dims = write_coordinates(&g, axes, z)?;
    write_cases(&g, axes, &z.vars, &dims)?;
    write_runs(&g, &z.vars, &dims)?;
    write_fits(&g, &z.vars, &dims, meta)
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
    let system = strings_scale(
        g,
        "system",
        &axes.systems,
        "stack: the sliding stack; rigid: the same load rigidly attached",
    )?;
    let record = strings_scale(
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
        "Sa(T_p, 5 %) of the scaled motion: the common intensity grid",
    )?;
    let demand = strings_scale(
        g,
        "demand",
        &axes.demands,
        "engineering demand (units in the name; ductility = u_m/u_y)",
    )?;
    let limit = strings_scale(
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
    })
}

/// The cases and their strengths, and each record's intensity.
fn write_cases(g: &hdf5::Group, axes: &IdaAxes, v: &IdaVars, d: &Coordinates) -> hdf5::Result<()> {
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
        "yield strength ratio F_y/(m_p g) of the structure",
    )?;
    put(
        g,
        "record_Sa",
        &v.record_sa_g,
        &[&d.record, &d.case],
        "g",
        "Sa(T_p, 5 %) of the unscaled motion",
    )
}

/// The traced runs, the curves on the common grid and their fractiles.
fn write_runs(g: &hdf5::Group, v: &IdaVars, d: &Coordinates) -> hdf5::Result<()> {
    let sys_run = [&d.system, &d.record, &d.case, &d.run];
    put(
        g,
        "run_Sa",
        &v.run_sa_g,
        &sys_run,
        "g",
        "intensity of each traced run",
    )?;
    put(
        g,
        "run_demand",
        &v.run_demand,
        &[&d.system, &d.record, &d.case, &d.run, &d.demand],
        "demand",
        "demands of each traced run (units in the demand names)",
    )?;
    put_flags(
        g,
        "run_collapsed",
        &v.run_collapsed,
        &sys_run,
        "the run reached the collapse ductility",
        &YES_NO,
    )?;
    put_flags(
        g,
        "run_slip_exceeded",
        &v.run_slip_exceeded,
        &sys_run,
        "some block's peak slip reached slip_limit_m",
        &YES_NO,
    )?;
    put(
        g,
        "collapse_Sa",
        &v.collapse_sa_g,
        &[&d.system, &d.record, &d.case],
        "g",
        "lowest collapsing intensity of the trace (NaN: no collapse up to the cap)",
    )?;
    put(
        g,
        "curve",
        &v.curve,
        &[&d.system, &d.record, &d.case, &d.sa, &d.demand],
        "demand",
        "IDA curve on the common grid (linear between runs; +inf from the collapse on; NaN above the last run)",
    )?;
    put(
        g,
        "fractile_curve",
        &v.fractile_curve,
        &[&d.system, &d.case, &d.fractile, &d.sa, &d.demand],
        "demand",
        "fractiles of the curves over the records (type 7; collapsed records count as +inf)",
    )
}

/// The stripes, the fragility fits and their intervals.
fn write_fits(g: &hdf5::Group, v: &IdaVars, d: &Coordinates, meta: &IdaMeta) -> hdf5::Result<()> {
    let fr = [&d.system, &d.case, &d.limit, &d.sa];
    put(
        g,
        "exceed_fraction",
        &v.exceed_fraction,
        &fr,
        "1",
        "fraction of the records whose curve exceeds the limit state (the stripe data of the fit)",
    )?;
    put(
        g,
        "fragility_curve",
        &v.fragility_curve,
        &fr,
        "1",
        "fitted lognormal fragility Phi(ln(Sa/theta)/beta)",
    )?;
    let fit = [&d.system, &d.case, &d.limit];
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
        put(g, name, data, &fit, units, long)?;
    }
    put_flags(
        g,
        "fit_status",
        &v.fit_status,
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
    };
    let (s, r, c, n) = (axes.systems.len(), records.len(), cases, axes.runs);
    let (d, sa, l, q) = (
        axes.demands.len(),
        axes.sa_grid_g.len(),
        axes.limit_states.len(),
        axes.fractiles.len(),
    );
    let fit = [s, c, l];
    let vars = IdaVars {
        c_y: g.array("c_y", &[c])?,
        record_sa_g: g.array("record_Sa", &[r, c])?,
        run_sa_g: g.array("run_Sa", &[s, r, c, n])?,
        run_demand: g.array("run_demand", &[s, r, c, n, d])?,
        run_collapsed: g.array("run_collapsed", &[s, r, c, n])?,
        run_slip_exceeded: g.array("run_slip_exceeded", &[s, r, c, n])?,
        collapse_sa_g: g.array("collapse_Sa", &[s, r, c])?,
        curve: g.array("curve", &[s, r, c, sa, d])?,
        fractile_curve: g.array("fractile_curve", &[s, c, q, sa, d])?,
        exceed_fraction: g.array("exceed_fraction", &[s, c, l, sa])?,
        fragility_curve: g.array("fragility_curve", &[s, c, l, sa])?,
        theta_sa_g: g.array("theta", &fit)?,
        beta: g.array("beta", &fit)?,
        theta_ci_low_sa_g: g.array("theta_ci_low", &fit)?,
        theta_ci_high_sa_g: g.array("theta_ci_high", &fit)?,
        beta_ci_low: g.array("beta_ci_low", &fit)?,
        beta_ci_high: g.array("beta_ci_high", &fit)?,
        fit_status: g.array("fit_status", &fit)?,
    };
    let z = ZoneIda {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        records,
        vars,
    };
    Ok((axes, z))
}
