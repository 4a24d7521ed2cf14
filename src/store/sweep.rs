//! `sweep.h5`: the peak responses of every case of the grid under every motion, per zone.
//!
//! ```text
//! /                     attrs: contents, slidestack_version, fingerprint, config_sha256,
//!                              motions_fingerprint, skip_rule_codes, + the writer's extra attrs
//! /zone_<name>/         attrs: target
//!     motion, T_p, alpha_1 … alpha_n, mu_1 … mu_n, interface, block    coordinates
//!     u_stack, u_single, u_rigid (m), a_stack (g), friction_energy (J/kg),
//!     skip_rule, single_rule                       [motion, T_p, alpha_1 … alpha_n, mu_1 … mu_n]
//!     slip_peak, slip_residual (m)                 [… , interface]
//!     block_accel_stack (g), block_velocity_stack (m s-1)           [… , block]
//!     rocks_stack                                  [motion, T_p, …] (with grid.aspect only)
//! ```
//! A building study (docs/model.md, "A study over buildings") has two more coordinates,
//! `storeys` (numbers) and `stack_floor` (strings: a floor number, `roof`, `mid`, `all`), as dimensions
//! after `motion`: `[motion, storeys, stack_floor, T_p, …]`; the structure's peaks are then the
//! roof's. It also stores, with and without sliding (`_stack`, `_rigid`: the stack rigidly
//! attached), each floor's and storey's peaks over the coordinates `floor` and `storey`
//! (`1 … N_max`, the largest `storeys`; a building of fewer storeys is NaN above its roof,
//! the variables' fill value), and the peak base shear:
//! ```text
//!     floor_accel_stack, floor_accel_rigid (g)     [motion, storeys, stack_floor, T_p, …, floor]
//!     drift_ratio_stack, drift_ratio_rigid (1)     [… , storey]
//!     storey_shear_stack, storey_shear_rigid (1)   [… , storey]
//!     base_shear_stack, base_shear_rigid (1),
//!     overturning_stack, overturning_rigid (1),
//!     stuck_share_stack (1)                        [motion, storeys, stack_floor, T_p, …]
//!     floor_velocity_stack, floor_velocity_rigid (m s-1)           [… , floor]
//!     residual_drift_ratio_stack, residual_drift_ratio_rigid (1)   [… , storey]
//! ```
//! One padded array per variable rather than one per storey count keeps every variable on the
//! grid's dimensions (xarray selects `storeys=3` and gets floors 1 … 3 and NaN above).
//!
//! Variables are chunked by work unit (one motion, one `T_p`), deflate+shuffle compressed,
//! Fletcher32-checksummed, with NaN (255 for the codes) as fill value. Objects are written in a
//! fixed order with their times not tracked, so the same inputs give the same bytes.

use super::StoreError;
use super::h5::{
    Attr, GroupReader, attr_str, coordinate, string_coordinate, write_attrs, write_stage_file,
};
use super::vars::{Codes, Data, Target, Trailing, Var, read_optional, write_declared};
use crate::grid::{BuildingAxes, Grid, StackFloor};
use ndarray::ArrayD;
use std::path::Path;

/// Provenance written on `sweep.h5`.
#[derive(Debug, Clone)]
pub struct SweepMeta<'a> {
    pub fingerprint: &'a str,
    pub config_sha256: &'a str,
    pub motions_fingerprint: &'a str,
    /// Long description of the `skip_rule` codes (file attribute `skip_rule_codes`).
    pub skip_rule_codes: &'a str,
    /// `(code, word)` pairs for the CF `flag_values`/`flag_meanings` of `skip_rule`.
    pub skip_rule_flags: &'a [(u8, &'a str)],
    /// Static friction = this × kinetic (in the `mu_i` coordinates' description).
    pub mu_static_ratio: f64,
    /// Physics settings that are not coordinates (`damping`, …), as scalar file attributes.
    pub settings: &'a [(&'a str, Attr<'a>)],
}

stored_vars! {
    /// One zone's variables, each shaped `[motion, T_p, alpha…, mu…]` (in a building study
    /// `[motion, storeys, stack_floor, T_p, …]`), some with a trailing `interface` or `block`
    /// axis.
    #[derive(Debug, Clone, PartialEq)]
    pub struct SweepVars {
        u_stack: f64 => "u_stack", Case, "m",
            "peak structure displacement with the sliding stack",
            building "peak structure displacement with the sliding stack (a building: its roof's)";
        u_single: f64 => "u_single", Case, "m",
            "peak structure displacement with the stack as one sliding block on interface 1",
            building "peak structure displacement with the stack as one sliding block on \
                      interface 1 (a building: its roof's)";
        u_rigid: f64 => "u_rigid", Case, "m",
            "peak structure displacement with the stack rigidly attached",
            building "peak structure displacement with the stack rigidly attached (a building: \
                      its roof's)";
        a_stack: f64 => "a_stack", Case, "g",
            "peak absolute structure acceleration with the sliding stack",
            building "peak absolute structure acceleration with the sliding stack (a building: \
                      its roof's)";
        friction_energy: f64 => "friction_energy", Case, "J/kg",
            "energy dissipated by friction in the stack, per kg of structure mass",
            building "energy dissipated by friction in the stack, per kg of structure mass (a \
                      building: of every stack, per kg of all its floors)";
        slip_peak: f64 => "slip_peak", Interface, "m",
            "peak slip of each interface",
            building "peak slip of each interface (with a stack on every floor: the largest over \
                      them)";
        /// Slip of each interface at the record's end, m (signed; a building with a stack on
        /// several floors: the one of the largest magnitude).
        slip_residual: f64 => "slip_residual", Interface, "m",
            "slip of each interface at the record's end, signed",
            building "slip of each interface at the record's end, signed (with a stack on every \
                      floor: the one of the largest magnitude)";
        /// The goods' own demands: each block's peak absolute acceleration, g, and velocity, m/s
        /// (a building with a stack on several floors: the largest over them).
        block_accel_stack: f64 => "block_accel_stack", Block, "g",
            "peak absolute acceleration of each block",
            building "peak absolute acceleration of each block (with a stack on every floor: the \
                      largest over them)";
        block_velocity_stack: f64 => "block_velocity_stack", Block, "m s-1",
            "peak absolute velocity of each block",
            building "peak absolute velocity of each block (with a stack on every floor: the \
                      largest over them)";
        /// The rule that gave each case's stack result (codes: the study's skip rules).
        skip_rule: u8 => "skip_rule", Case, "",
            "rule that gave the stack result (file attribute skip_rule_codes)";
        single_rule: u8 => "single_rule", Case, "",
            "1 when the single block cannot slip and equals the rigid system",
            codes &[(0, "simulated"), (1, "equals_rigid")];
    }
}

/// With `grid.aspect`: 1 where the stack would start to rock (docs/model.md, "Rocking: when a
/// case leaves the model"), `[motion, …]` as [`SweepVars`]' case variables.
pub const ROCKS_STACK: Var = Var {
    name: "rocks_stack",
    trailing: Trailing::Case,
    units: "",
    long_name: "1 when the stack (in a building, any of its stacks) would start to rock: the \
                sliding-only model does not hold (blocks' width over height: file attribute aspect)",
    building_long_name: None,
    codes: Codes::Fixed(&[(0, "slides_only"), (1, "rocks")]),
};

stored_vars! {
    /// A building study's per-floor and per-storey peaks (a trailing `floor` or `storey` axis of
    /// length `N_max`, NaN above a building's roof) and base shear, with the stack (`_stack`) and
    /// with it rigidly attached (`_rigid`); docs/model.md, "Base shear, drift ratio, floor
    /// acceleration".
    #[derive(Debug, Clone, PartialEq)]
    pub struct BuildingVars {
        /// Peak absolute acceleration of each floor, g.
        floor_accel_stack: f64 => "floor_accel_stack", Floor, "g",
            "peak absolute acceleration of each floor with the sliding stack";
        floor_accel_rigid: f64 => "floor_accel_rigid", Floor, "g",
            "peak absolute acceleration of each floor with the stack rigidly attached";
        /// Peak interstorey drift over the storey's height, per storey.
        drift_ratio_stack: f64 => "drift_ratio_stack", Storey, "1",
            "peak interstorey drift over the storey height, with the sliding stack";
        drift_ratio_rigid: f64 => "drift_ratio_rigid", Storey, "1",
            "peak interstorey drift over the storey height, with the stack rigidly attached";
        /// Peak base shear over the bare building's weight (NaN in a building of one storey).
        base_shear_stack: f64 => "base_shear_stack", Case, "1",
            "peak base shear over the bare building's weight, with the sliding stack (NaN on one \
             storey: its integrator does not give it)";
        base_shear_rigid: f64 => "base_shear_rigid", Case, "1",
            "peak base shear over the bare building's weight, with the stack rigidly attached \
             (NaN on one storey: its integrator does not give it)";
        /// Peak shear of each storey over the bare building's weight (storey 1's is the base
        /// shear; NaN in a building of one storey).
        storey_shear_stack: f64 => "storey_shear_stack", Storey, "1",
            "peak shear of each storey over the bare building's weight, with the sliding stack \
             (NaN on one storey)";
        storey_shear_rigid: f64 => "storey_shear_rigid", Storey, "1",
            "peak shear of each storey over the bare building's weight, with the stack rigidly \
             attached (NaN on one storey)";
        /// Peak overturning moment at the base over the bare building's weight times its height
        /// (NaN in a building of one storey).
        overturning_stack: f64 => "overturning_stack", Case, "1",
            "peak overturning moment at the base over the bare building's weight times its \
             height, with the sliding stack (NaN on one storey)";
        overturning_rigid: f64 => "overturning_rigid", Case, "1",
            "peak overturning moment at the base over the bare building's weight times its \
             height, with the stack rigidly attached (NaN on one storey)";
        /// The stack's stuck mass share: the time average of its mass moving with its floor, over
        /// its mass (NaN in a building of one storey).
        stuck_share_stack: f64 => "stuck_share_stack", Case, "1",
            "time average of the stack's mass moving with its floor over its mass (1: it never \
             slid; NaN on one storey)";
        /// Peak absolute velocity of each floor, m/s (FEMA P-58's PFV).
        floor_velocity_stack: f64 => "floor_velocity_stack", Floor, "m s-1",
            "peak absolute velocity of each floor with the sliding stack";
        floor_velocity_rigid: f64 => "floor_velocity_rigid", Floor, "m s-1",
            "peak absolute velocity of each floor with the stack rigidly attached";
        /// Each storey's drift at the record's end over its height, signed.
        residual_drift_ratio_stack: f64 => "residual_drift_ratio_stack", Storey, "1",
            "interstorey drift at the record's end over the storey height, signed, with the \
             sliding stack";
        residual_drift_ratio_rigid: f64 => "residual_drift_ratio_rigid", Storey, "1",
            "interstorey drift at the record's end over the storey height, signed, with the \
             stack rigidly attached";
    }
}

/// One zone of `sweep.h5`.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneSweep {
    pub name: String,
    pub target: String,
    pub motions: Vec<String>,
    pub vars: SweepVars,
    /// With `grid.aspect`: [`ROCKS_STACK`]; `None` when not checked.
    pub rocks_stack: Option<ArrayD<u8>>,
    /// A building study's per-floor peaks and base shear (`None` on one storey).
    pub building: Option<BuildingVars>,
}

/// The coordinates of the case dimensions `T_p, alpha_1 … alpha_n, mu_1 … mu_n` of `grid` in
/// group `g`, as dimension scales in that order (shared by `sweep.h5` and `tnew.h5`); static
/// friction is `mu_static_ratio` × kinetic.
pub fn case_coordinates(
    g: &hdf5::Group,
    grid: &Grid,
    mu_static_ratio: f64,
) -> hdf5::Result<Vec<hdf5::Dataset>> {
    let mut scales = vec![coordinate(
        g,
        "T_p",
        &grid.periods_s,
        "s",
        "period of the bare structure",
    )?];
    for (i, a) in grid.alpha.iter().enumerate() {
        let long = format!("mass ratio m_{}/m_p of block {} (bottom = 1)", i + 1, i + 1);
        scales.push(coordinate(g, &format!("alpha_{}", i + 1), a, "1", &long)?);
    }
    for (i, mu) in grid.mu.iter().enumerate() {
        let long = format!(
            "kinetic friction coefficient of interface {} (static = {} × kinetic)",
            i + 1,
            mu_static_ratio
        );
        scales.push(coordinate(g, &format!("mu_{}", i + 1), mu, "1", &long)?);
    }
    Ok(scales)
}

/// The grid axes `T_p, alpha_1 … alpha_n, mu_1 … mu_n` stored in a group, each one-dimensional.
pub fn read_case_coordinates(g: &GroupReader, blocks: usize) -> Result<Grid, StoreError> {
    Ok(Grid {
        periods_s: g.vector("T_p")?,
        alpha: (1..=blocks)
            .map(|i| g.vector(&format!("alpha_{i}")))
            .collect::<Result<_, _>>()?,
        mu: (1..=blocks)
            .map(|i| g.vector(&format!("mu_{i}")))
            .collect::<Result<_, _>>()?,
    })
}

/// The coordinates `storeys` and `stack_floor` of a building study in group `g`, as dimension
/// scales in that order (shared by `sweep.h5` and `tnew.h5`).
pub fn building_coordinates(
    g: &hdf5::Group,
    axes: &BuildingAxes,
) -> hdf5::Result<Vec<hdf5::Dataset>> {
    let storeys: Vec<f64> = axes.storeys.iter().map(|&n| n as f64).collect();
    let s = coordinate(g, "storeys", &storeys, "1", "storeys N of the building")?;
    let floors: Vec<String> = axes.stack_floor.iter().map(|f| f.to_string()).collect();
    let f = string_coordinate(
        g,
        "stack_floor",
        &floors,
        "floor carrying the stack (1 the lowest; roof: floor N; all: a stack on every floor)",
    )?;
    Ok(vec![s, f])
}

/// The building axes stored in a group by [`building_coordinates`].
pub fn read_building_coordinates(g: &GroupReader) -> Result<BuildingAxes, StoreError> {
    let bad = |why: String| StoreError::corrupt(g.file(), why);
    let storeys = (g.vector("storeys")?.into_iter())
        .map(|n| {
            (n >= 1.0 && n.fract() == 0.0 && n <= u32::MAX as f64)
                .then_some(n as usize)
                .ok_or_else(|| bad(format!("storeys: {n} is not a storey count")))
        })
        .collect::<Result<_, _>>()?;
    let stack_floor = (g.strings("stack_floor")?.iter())
        .map(|s| {
            s.parse::<StackFloor>()
                .map_err(|why| bad(format!("stack_floor: {why}")))
        })
        .collect::<Result<_, _>>()?;
    Ok(BuildingAxes {
        storeys,
        stack_floor,
    })
}

/// Writes `sweep.h5` at `path` (checked and atomic, [`write_stage_file`]); `building` the
/// building axes of a building study.
pub fn write_sweep(
    path: &Path,
    meta: &SweepMeta,
    grid: &Grid,
    building: Option<&BuildingAxes>,
    zones: &[ZoneSweep],
) -> Result<(), StoreError> {
    write_stage_file(
        path,
        "slidestack sweep stage: peak responses over the grid, per zone",
        meta.fingerprint,
        |f| {
            attr_str(f, "config_sha256", meta.config_sha256)?;
            attr_str(f, "motions_fingerprint", meta.motions_fingerprint)?;
            attr_str(f, "skip_rule_codes", meta.skip_rule_codes)?;
            write_attrs(f, meta.settings)?;
            for z in zones {
                write_zone(f, grid, building, z, meta)?;
            }
            Ok(())
        },
    )
}

fn write_zone(
    f: &hdf5::File,
    grid: &Grid,
    building: Option<&BuildingAxes>,
    z: &ZoneSweep,
    meta: &SweepMeta,
) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", &z.target)?;
    let n = grid.blocks();
    let m = string_coordinate(
        &g,
        "motion",
        &z.motions,
        "ground motion (matched, see motions.h5)",
    )?;
    let mut scales = vec![m];
    if let Some(b) = building {
        scales.extend(building_coordinates(&g, b)?);
    }
    scales.extend(case_coordinates(&g, grid, meta.mu_static_ratio)?);
    let blocks: Vec<f64> = (1..=n).map(|i| i as f64).collect();
    let interface = coordinate(
        &g,
        "interface",
        &blocks,
        "1",
        "interface (1 = structure–block 1)",
    )?;
    let block = coordinate(
        &g,
        "block",
        &blocks,
        "1",
        "block (1 = the lowest, resting on interface 1)",
    )?;
    let levels: Vec<f64> = (1..=building.map_or(0, |b| b.max_storeys()))
        .map(|j| j as f64)
        .collect();
    let (floor, storey) = match building {
        Some(_) => (
            Some(coordinate(
                &g,
                "floor",
                &levels,
                "1",
                "floor (1 the lowest)",
            )?),
            Some(coordinate(
                &g,
                "storey",
                &levels,
                "1",
                "storey (1 the lowest: between the ground and floor 1)",
            )?),
        ),
        None => (None, None),
    };
    // One chunk per work unit: one motion (one frame), one T_p.
    let mut chunk = vec![1; if building.is_some() { 4 } else { 2 }];
    chunk.extend(grid.case_shape());
    let trailing = |t: Trailing| match t {
        Trailing::Case => None,
        Trailing::Interface => Some(&interface),
        Trailing::Block => Some(&block),
        Trailing::Floor => floor.as_ref(),
        Trailing::Storey => storey.as_ref(),
    };
    let given = |_: &str| meta.skip_rule_flags;
    let to = Target {
        group: &g,
        building: building.is_some(),
        chunk: &chunk,
        scales: &scales,
        trailing: &trailing,
        given: &given,
    };
    write_declared(&to, &z.vars.data())?;
    if let Some(rocks) = &z.rocks_stack {
        write_declared(&to, &[(&ROCKS_STACK, Data::Codes(rocks))])?;
    }
    if let Some(bv) = &z.building {
        write_declared(&to, &bv.data())?;
    }
    Ok(())
}

/// Zone `zone` of `sweep.h5` (`blocks` blocks; `building`: of a building study) and the axes
/// stored with it; every variable has the shape its coordinates give.
pub fn read_zone_sweep(
    path: &Path,
    zone: &str,
    blocks: usize,
    building: bool,
) -> Result<(Grid, Option<BuildingAxes>, ZoneSweep), StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let grid = read_case_coordinates(&g, blocks)?;
    let axes = building
        .then(|| read_building_coordinates(&g))
        .transpose()?;
    let motions = g.strings("motion")?;
    let mut shape = vec![motions.len()];
    shape.extend(axes.iter().flat_map(BuildingAxes::shape));
    shape.extend(grid.shape());
    let levels = axes.as_ref().map_or(0, BuildingAxes::max_storeys);
    let shape_of = |t: Trailing| {
        let mut s = shape.clone();
        match t {
            Trailing::Case => {}
            Trailing::Interface | Trailing::Block => s.push(blocks),
            Trailing::Floor | Trailing::Storey => s.push(levels),
        }
        s
    };
    let zone = ZoneSweep {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        motions,
        vars: SweepVars::read(&g, shape_of)?,
        rocks_stack: read_optional(&g, ROCKS_STACK.name, &shape)?,
        building: axes
            .is_some()
            .then(|| BuildingVars::read(&g, shape_of))
            .transpose()?,
    };
    Ok((grid, axes, zone))
}
