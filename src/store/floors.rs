//! `floors.h5`: the floor response spectra of a study's listed cases, per zone (the floors
//! stage, [`crate::pipeline::floors`]).
//!
//! ```text
//! /                     attrs: contents, slidestack_version, fingerprint, config_sha256,
//!                              motions_fingerprint, refinement, + the physics' attrs
//! /zone_<name>/         attrs: target
//!     motion, case, [storeys, stack_floor,] damping, floor, period     coordinates
//!     case_period_s (s) [case], case_alpha, case_mu [case, block]      the cases
//!     pga (g)                                               [motion]
//!     pfa_stack, pfa_rigid (g)                              [motion, case, (storeys, stack_floor,) floor]
//!     psa_stack, psa_rigid (g)                              [… , damping, floor, period]
//! ```
//! `_stack`: the stacks sliding; `_rigid`: rigidly attached. `floor` runs `1 … N_max` (the
//! largest `storeys`); a building of fewer storeys is NaN above its roof (the fill value). On one
//! storey the floor is the structure and there are no `storeys`, `stack_floor` dimensions.

use super::StoreError;
use super::h5::{
    Attr, GroupReader, attach_all, attr_str, coordinate, string_coordinate, write_attrs,
    write_stage_file, write_var,
};
use super::sweep::{building_coordinates, read_building_coordinates};
use super::vars::{Codes, Trailing, Var};
use crate::grid::BuildingAxes;
use ndarray::ArrayD;
use std::path::Path;

/// One zone's variables, in the layout of the module doc (the frame dimensions present in a
/// building study only).
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneFloors {
    pub name: String,
    pub target: String,
    pub motions: Vec<String>,
    /// Each motion's peak ground acceleration, g.
    pub pga_g: Vec<f64>,
    pub pfa_stack: ArrayD<f64>,
    pub pfa_rigid: ArrayD<f64>,
    pub psa_stack: ArrayD<f64>,
    pub psa_rigid: ArrayD<f64>,
}

/// What every zone shares: the cases, the spectra's axes and the frames.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorsAxes {
    /// `T_p` (a building's `T_1`), s, `α` and `μ` of each case.
    pub case_period_s: Vec<f64>,
    pub case_alpha: Vec<Vec<f64>>,
    pub case_mu: Vec<Vec<f64>>,
    pub damping: Vec<f64>,
    pub periods_s: Vec<f64>,
    /// `floor` runs `1 … floors`.
    pub floors: usize,
    pub building: Option<BuildingAxes>,
}

/// The file's attributes.
pub struct FloorsMeta<'a> {
    pub fingerprint: &'a str,
    pub motions_fingerprint: &'a str,
    pub config_sha256: &'a str,
    pub settings: &'a [(&'a str, Attr<'a>)],
}

/// Writes `floors.h5` (checked and atomic).
pub fn write_floors(
    path: &Path,
    meta: &FloorsMeta,
    axes: &FloorsAxes,
    zones: &[ZoneFloors],
) -> Result<(), StoreError> {
    write_stage_file(
        path,
        "slidestack floors stage: floor response spectra (pseudo-acceleration of each floor's \
         absolute acceleration) of the listed cases, sliding and with the stacks attached",
        meta.fingerprint,
        |f| {
            attr_str(f, "motions_fingerprint", meta.motions_fingerprint)?;
            attr_str(f, "config_sha256", meta.config_sha256)?;
            write_attrs(f, meta.settings)?;
            for z in zones {
                write_zone(f, axes, z)?;
            }
            Ok(())
        },
    )
}

/// Each motion's peaks, `[motion, case, (storeys, stack_floor,) floor]`.
pub const PEAKS: [Var; 2] = [
    floor_var(
        "pfa_stack",
        Trailing::Floor,
        "peak absolute acceleration of the floor, stacks sliding",
    ),
    floor_var(
        "pfa_rigid",
        Trailing::Floor,
        "peak absolute acceleration of the floor, stacks rigidly attached",
    ),
];

/// Each motion's floor spectra, `[motion, case, (storeys, stack_floor,) damping, floor, period]`
/// (their trailing axes `damping, floor, period` written by this module, not by
/// [`super::vars::write_declared`]: `Case` here).
pub const SPECTRA: [Var; 2] = [
    floor_var(
        "psa_stack",
        Trailing::Case,
        "floor response spectrum (pseudo-acceleration of an oscillator on the floor), stacks \
         sliding",
    ),
    floor_var(
        "psa_rigid",
        Trailing::Case,
        "floor response spectrum (pseudo-acceleration of an oscillator on the floor), stacks \
         rigidly attached",
    ),
];

const fn floor_var(name: &'static str, trailing: Trailing, long_name: &'static str) -> Var {
    Var {
        name,
        trailing,
        units: "g",
        long_name,
        building_long_name: None,
        codes: Codes::Value,
    }
}

/// The listed cases: each one's period `[case]` and its mass ratios and friction coefficients
/// `[case, block]`.
fn write_cases(
    g: &hdf5::Group,
    axes: &FloorsAxes,
    case: &hdf5::Dataset,
    block: &hdf5::Dataset,
) -> hdf5::Result<()> {
    let cases = axes.case_period_s.len();
    let blocks = axes.case_alpha.first().map_or(0, Vec::len);
    let ds = write_var(
        g,
        "case_period_s",
        ndarray::arr1(&axes.case_period_s).into_dyn().view(),
        &[cases],
        "s",
        "the case's bare period T_p (a building: its first-mode period T_1)",
    )?;
    attach_all(&ds, std::slice::from_ref(case))?;
    for (name, values, long) in [
        (
            "case_alpha",
            &axes.case_alpha,
            "the case's mass ratios, block 1 first",
        ),
        (
            "case_mu",
            &axes.case_mu,
            "the case's kinetic friction coefficients, interface 1 first",
        ),
    ] {
        let flat: Vec<f64> = values.iter().flatten().copied().collect();
        let a = ArrayD::from_shape_vec(vec![cases, blocks], flat).expect("one per block");
        let ds = write_var(g, name, a.view(), &[cases, blocks], "1", long)?;
        attach_all(&ds, &[case.clone(), block.clone()])?;
    }
    Ok(())
}

fn write_zone(f: &hdf5::File, axes: &FloorsAxes, z: &ZoneFloors) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", &z.target)?;
    let motion = string_coordinate(&g, "motion", &z.motions, "ground motion (see motions.h5)")?;
    let count = |n: usize| (1..=n).map(|i| i as f64).collect::<Vec<_>>();
    let cases = axes.case_period_s.len();
    let case = coordinate(
        &g,
        "case",
        &count(cases),
        "1",
        "case of floor_spectra.cases",
    )?;
    let blocks = axes.case_alpha.first().map_or(0, Vec::len);
    let block = coordinate(&g, "block", &count(blocks), "1", "block (1 the lowest)")?;
    let frames = match &axes.building {
        Some(b) => building_coordinates(&g, b)?,
        None => Vec::new(),
    };
    let damping = coordinate(
        &g,
        "damping",
        &axes.damping,
        "1",
        "oscillator damping ratio",
    )?;
    let floor = coordinate(
        &g,
        "floor",
        &count(axes.floors),
        "1",
        "floor (1 the lowest; one storey: the structure)",
    )?;
    let period = coordinate(&g, "period", &axes.periods_s, "s", "oscillator period")?;
    write_cases(&g, axes, &case, &block)?;
    let ds = write_var(
        &g,
        "pga",
        ndarray::arr1(&z.pga_g).into_dyn().view(),
        &[z.pga_g.len()],
        "g",
        "peak ground acceleration of the motion",
    )?;
    attach_all(&ds, std::slice::from_ref(&motion))?;
    let mut head = vec![motion.clone(), case.clone()];
    head.extend(frames);
    let with = |tail: &[&hdf5::Dataset]| {
        let mut v = head.clone();
        v.extend(tail.iter().map(|d| (*d).clone()));
        v
    };
    for (var, data) in PEAKS.iter().zip([&z.pfa_stack, &z.pfa_rigid]) {
        let mut chunk = vec![1; data.ndim()];
        chunk[data.ndim() - 1] = axes.floors;
        let ds = write_var(&g, var.name, data.view(), &chunk, var.units, var.long_name)?;
        attach_all(&ds, &with(&[&floor]))?;
    }
    for (var, data) in SPECTRA.iter().zip([&z.psa_stack, &z.psa_rigid]) {
        let n = data.ndim();
        let mut chunk = vec![1; n];
        chunk[n - 1] = axes.periods_s.len();
        chunk[n - 2] = axes.floors;
        let ds = write_var(&g, var.name, data.view(), &chunk, var.units, var.long_name)?;
        attach_all(&ds, &with(&[&damping, &floor, &period]))?;
    }
    Ok(())
}

/// Zone `zone` of `floors.h5` with the axes stored with it; `blocks` blocks per case, a
/// building study's frame axes when `building`. Every variable is checked against the shape
/// its coordinates give.
pub fn read_zone_floors(
    path: &Path,
    zone: &str,
    building: bool,
) -> Result<(FloorsAxes, ZoneFloors), StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let motions = g.strings("motion")?;
    let case_period_s = g.vector("case_period_s")?;
    let cases = case_period_s.len();
    let blocks = g.vector("block")?.len();
    let rows = |name: &str| -> Result<Vec<Vec<f64>>, StoreError> {
        let a: ArrayD<f64> = g.array(name, &[cases, blocks])?;
        Ok(a.outer_iter()
            .map(|r| r.iter().copied().collect())
            .collect())
    };
    let building = building
        .then(|| read_building_coordinates(&g))
        .transpose()?;
    let axes = FloorsAxes {
        case_alpha: rows("case_alpha")?,
        case_mu: rows("case_mu")?,
        case_period_s,
        damping: g.vector("damping")?,
        periods_s: g.vector("period")?,
        floors: g.vector("floor")?.len(),
        building,
    };
    let mut head = vec![motions.len(), cases];
    head.extend(axes.building.iter().flat_map(BuildingAxes::shape));
    let mut per_floor = head.clone();
    per_floor.push(axes.floors);
    let mut spectra = head;
    spectra.extend([axes.damping.len(), axes.floors, axes.periods_s.len()]);
    let zone = ZoneFloors {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        pga_g: g
            .array::<f64>("pga", &[motions.len()])?
            .iter()
            .copied()
            .collect(),
        pfa_stack: g.array(PEAKS[0].name, &per_floor)?,
        pfa_rigid: g.array(PEAKS[1].name, &per_floor)?,
        psa_stack: g.array(SPECTRA[0].name, &spectra)?,
        psa_rigid: g.array(SPECTRA[1].name, &spectra)?,
        motions,
    };
    Ok((axes, zone))
}

/// Where a value of a zone's variables lies in their flat row-major arrays
/// (this module's layout: `[motion, case, frame, …]`, the frame axis `storeys ×
/// stack_floor` folded into one).
pub struct Offsets {
    pub cases: usize,
    pub frames: usize,
    pub damping: usize,
    pub floors: usize,
    pub periods: usize,
}

impl Offsets {
    pub fn of(axes: &FloorsAxes, frames: usize) -> Self {
        Self {
            cases: axes.case_period_s.len(),
            frames,
            damping: axes.damping.len(),
            floors: axes.floors,
            periods: axes.periods_s.len(),
        }
    }

    pub fn unit(&self, m: usize, c: usize, f: usize) -> usize {
        (m * self.cases + c) * self.frames + f
    }

    /// Floor `j`'s peak of `pfa_*`.
    pub fn pfa(&self, m: usize, c: usize, f: usize, j: usize) -> usize {
        self.unit(m, c, f) * self.floors + j
    }

    /// The first period of floor `j`'s spectrum at damping ratio `d` in `psa_*`.
    pub fn psa(&self, m: usize, c: usize, f: usize, d: usize, j: usize) -> usize {
        ((self.unit(m, c, f) * self.damping + d) * self.floors + j) * self.periods
    }
}
