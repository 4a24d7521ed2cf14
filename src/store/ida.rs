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
//!     record_Sa, run_Sa, run_demand, …, fit_status: declared once in [`IdaVars`] (each one's
//!     axes before and after the case, units and long name; docs/variables.md)
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
    write_stage_file, write_strings, write_var,
};
use super::sweep::{building_coordinates, read_building_coordinates};
use super::vars::{Codes, Data, Element, long_name_in, write_data};
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

/// An axis a variable of `ida.h5` has before or after its case dimensions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdaAxis {
    System,
    Record,
    Run,
    Demand,
    Sa,
    Fractile,
    LimitState,
}

impl IdaAxis {
    /// The coordinate's name.
    pub fn name(self) -> &'static str {
        match self {
            IdaAxis::System => "system",
            IdaAxis::Record => "record",
            IdaAxis::Run => "run",
            IdaAxis::Demand => "demand",
            IdaAxis::Sa => "Sa",
            IdaAxis::Fractile => "fractile",
            IdaAxis::LimitState => "limit_state",
        }
    }
}

/// One declared variable of `ida.h5`: over `before`, the case dimensions (`case`, or `case,
/// storeys, stack_floor` in a building study), then `after`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IdaVar {
    pub name: &'static str,
    pub before: &'static [IdaAxis],
    pub after: &'static [IdaAxis],
    /// CF units (`""` for a code variable).
    pub units: &'static str,
    pub long_name: &'static str,
    /// The long name in a building study's file, where it differs.
    pub building_long_name: Option<&'static str>,
    pub codes: Codes,
}

/// Declares [`IdaVars`]: one `ArrayD` field per variable, its cases and frames folded into one
/// axis (module doc), and derives `VARS`, `data` and `read` from it, as `stored_vars!` does for
/// the files whose variables have one trailing axis.
macro_rules! ida_vars {
    (@building) => { None };
    (@building $b:literal) => { Some($b) };
    (@codes $t:ty) => { <$t as Element>::CODES };
    (@codes $t:ty, $c:expr) => { Codes::Fixed($c) };
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[$fmeta:meta])*
                $field:ident : $t:ty => $var:literal, [$($before:ident),*] [$($after:ident),*],
                    $units:literal, $long:literal $(, building $blong:literal)? $(, codes $codes:expr)? ;
            )*
        }
    ) => {
        $(#[$meta])*
        $vis struct $name {
            $( $(#[$fmeta])* pub $field: ArrayD<$t>, )*
        }

        impl $name {
            /// The declarations, in field order: the order they are written and read.
            pub const VARS: &'static [IdaVar] = &[
                $(
                    IdaVar {
                        name: $var,
                        before: &[$(IdaAxis::$before),*],
                        after: &[$(IdaAxis::$after),*],
                        units: $units,
                        long_name: $long,
                        building_long_name: ida_vars!(@building $($blong)?),
                        codes: ida_vars!(@codes $t $(, $codes)?),
                    },
                )*
            ];

            /// Each variable's declaration with its array, in field order.
            pub fn data(&self) -> Vec<(&'static IdaVar, Data<'_>)> {
                Self::VARS
                    .iter()
                    .zip([$(<$t as Element>::data(&self.$field)),*])
                    .collect()
            }

            /// Every variable of group `g`, each refused unless its stored shape is
            /// `shape(var)`, its frames folded into the case axis.
            fn read(
                g: &GroupReader,
                shape: impl Fn(&IdaVar) -> Vec<usize>,
                frames: Option<[usize; 2]>,
            ) -> Result<Self, StoreError> {
                let mut vars = Self::VARS.iter();
                Ok(Self {
                    $( $field: {
                        let v = vars.next().expect("one declaration per field");
                        fold(g.array(v.name, &shape(v))?, v.before.len(), frames)
                    }, )*
                })
            }
        }
    };
}

ida_vars! {
    /// One zone's traces, curves and fits (in memory the frames folded into the case axis,
    /// case-major).
    #[derive(Debug, Clone, PartialEq)]
    pub struct IdaVars {
        record_sa_g: f64 => "record_Sa", [Record] [], "g",
            "Sa(T_p, 5 %) of the unscaled motion",
            building "Sa(T_1, 5 %) of the unscaled motion (T_1 the bare building's first-mode period)";
        run_sa_g: f64 => "run_Sa", [System, Record] [Run], "g", "intensity of each traced run";
        run_demand: f64 => "run_demand", [System, Record] [Run, Demand], "demand",
            "demands of each traced run (units in the demand names)";
        run_collapsed: u8 => "run_collapsed", [System, Record] [Run], "",
            "the run reached the collapse ductility",
            building "the run reached the collapse drift ratio", codes &YES_NO;
        run_slip_exceeded: u8 => "run_slip_exceeded", [System, Record] [Run], "",
            "some block's peak slip reached slip_limit_m", codes &YES_NO;
        collapse_sa_g: f64 => "collapse_Sa", [System, Record] [], "g",
            "lowest collapsing intensity of the trace (NaN: no collapse up to the cap)";
        curve: f64 => "curve", [System, Record] [Sa, Demand], "demand",
            "IDA curve on the common grid (linear between runs; +inf from the collapse on; NaN above the last run)";
        fractile_curve: f64 => "fractile_curve", [System] [Fractile, Sa, Demand], "demand",
            "fractiles of the curves over the records (type 7; collapsed records count as +inf)";
        exceed_fraction: f64 => "exceed_fraction", [System] [LimitState, Sa], "1",
            "fraction of the records whose curve exceeds the limit state (the stripe data of the fit)";
        fragility_curve: f64 => "fragility_curve", [System] [LimitState, Sa], "1",
            "fitted lognormal fragility Phi(ln(Sa/theta)/beta)";
        theta_sa_g: f64 => "theta", [System] [LimitState], "g",
            "median capacity theta (maximum likelihood, multiple stripes, Baker 2015)";
        beta: f64 => "beta", [System] [LimitState], "1", "logarithmic standard deviation beta";
        theta_ci_low_sa_g: f64 => "theta_ci_low", [System] [LimitState], "g",
            "95 % Wald interval of theta, observed information, lower end";
        theta_ci_high_sa_g: f64 => "theta_ci_high", [System] [LimitState], "g",
            "95 % Wald interval of theta, upper end";
        beta_ci_low: f64 => "beta_ci_low", [System] [LimitState], "1",
            "95 % Wald interval of beta (on ln beta), lower end";
        beta_ci_high: f64 => "beta_ci_high", [System] [LimitState], "1",
            "95 % Wald interval of beta, upper end";
        fit_status: u8 => "fit_status", [System] [LimitState], "", "how the fragility fit ended";
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ZoneIda {
    pub name: String,
    pub target: String,
    pub records: Vec<String>,
    /// `[case]`: the structure's yield strength ratio (a building's base-shear coefficient).
    pub c_y: ArrayD<f64>,
    /// `[case, storeys, storey]`, in a building study.
    pub storey_c_y: Option<ArrayD<f64>>,
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

/// The Markdown table of [`IdaVars::VARS`] (`docs/variables.md`), `case` standing for the case
/// dimensions.
pub fn variables_table() -> String {
    let mut s = String::from(super::vars::TABLE_HEAD);
    for v in IdaVars::VARS {
        let names = |a: &[IdaAxis]| a.iter().map(|a| a.name()).collect::<Vec<_>>();
        let dims = [names(v.before), vec!["case"], names(v.after)].concat();
        s.push_str(&super::vars::table_row(
            v.name,
            &dims.join(", "),
            (v.units, v.codes),
            (v.long_name, v.building_long_name),
        ));
    }
    s
}

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
    fn axis(&self, a: IdaAxis) -> &hdf5::Dataset {
        match a {
            IdaAxis::System => &self.system,
            IdaAxis::Record => &self.record,
            IdaAxis::Run => &self.run,
            IdaAxis::Demand => &self.demand,
            IdaAxis::Sa => &self.sa,
            IdaAxis::Fractile => &self.fractile,
            IdaAxis::LimitState => &self.limit,
        }
    }

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
    write_cases(&g, axes, z, &dims)?;
    write_vars(&g, &z.vars, &dims, meta, frames)
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

/// The cases and their strengths.
fn write_cases(g: &hdf5::Group, axes: &IdaAxes, z: &ZoneIda, d: &Coordinates) -> hdf5::Result<()> {
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
        &z.c_y,
        &[&d.case],
        "1",
        if d.building.is_some() {
            "base-shear coefficient V_B/(g sum_j m_j) of the bare building (the strength of storey 1)"
        } else {
            "yield strength ratio F_y/(m_p g) of the structure"
        },
    )?;
    if let (Some(c), Some([n, _, storey])) = (&z.storey_c_y, &d.building) {
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
    Ok(())
}

/// The declared variables ([`IdaVars::VARS`]), each over its coordinates with its frames split
/// out of the case axis, chunked by [`chunk_of`]; `fit_status` with the writer's codes.
fn write_vars(
    g: &hdf5::Group,
    v: &IdaVars,
    d: &Coordinates,
    meta: &IdaMeta,
    frames: Option<[usize; 2]>,
) -> hdf5::Result<()> {
    for (var, data) in v.data() {
        let axes = |a: &[IdaAxis]| a.iter().map(|&a| d.axis(a)).collect::<Vec<_>>();
        let dims = d.around(&axes(var.before), &axes(var.after));
        let long = long_name_in((var.long_name, var.building_long_name), frames.is_some());
        // The frames split out of the case axis.
        let at = var.before.len();
        let (values, codes);
        let data = match data {
            Data::Values(a) => {
                values = split(a, at, frames);
                Data::Values(&values)
            }
            Data::Codes(a) => {
                codes = split(a, at, frames);
                Data::Codes(&codes)
            }
        };
        let ds = write_data(
            g,
            (var.name, data),
            &chunk_of(data.shape()),
            (var.units, long),
            var.codes,
            || meta.fit_flags,
        )?;
        for (i, s) in dims.iter().enumerate() {
            attach_scale(&ds, s, i)?;
        }
    }
    Ok(())
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
    let size = |a: &IdaAxis| match a {
        IdaAxis::System => axes.systems.len(),
        IdaAxis::Record => records.len(),
        IdaAxis::Run => axes.runs,
        IdaAxis::Demand => axes.demands.len(),
        IdaAxis::Sa => axes.sa_grid_g.len(),
        IdaAxis::Fractile => axes.fractiles.len(),
        IdaAxis::LimitState => axes.limit_states.len(),
    };
    // Each variable over `[before.., case(, storeys, stack_floor), after..]` as stored.
    let shape = |v: &IdaVar| -> Vec<usize> {
        let mut s: Vec<usize> = v.before.iter().map(size).collect();
        s.push(cases);
        s.extend(frames.into_iter().flatten());
        s.extend(v.after.iter().map(size));
        s
    };
    let storey_c_y = match &axes.building {
        None => None,
        Some(b) => Some(g.array("storey_c_y", &[cases, b.storeys.len(), axes.max_storeys()])?),
    };
    let z = ZoneIda {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        c_y: g.array("c_y", &[cases])?,
        storey_c_y,
        vars: IdaVars::read(&g, shape, frames)?,
        records,
    };
    Ok((axes, z))
}
