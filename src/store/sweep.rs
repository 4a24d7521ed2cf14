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
    Attr, GroupReader, attach_all, attach_scale, attr_str, coordinate, string_coordinate,
    write_attrs, write_flags, write_stage_file, write_var,
};
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

/// One zone's variables, each shaped `[motion, T_p, alpha…, mu…]` (`slip_peak` with a trailing
/// interface axis).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepVars {
    pub u_stack: ArrayD<f64>,
    pub u_single: ArrayD<f64>,
    pub u_rigid: ArrayD<f64>,
    pub a_stack: ArrayD<f64>,
    pub friction_energy: ArrayD<f64>,
    pub slip_peak: ArrayD<f64>,
    /// Slip of each interface at the record's end, m (signed; a building with a stack on
    /// several floors: the one of the largest magnitude).
    pub slip_residual: ArrayD<f64>,
    /// The goods' own demands: each block's peak absolute acceleration, g, and velocity, m/s
    /// (a building with a stack on several floors: the largest over them).
    pub block_accel_stack: ArrayD<f64>,
    pub block_velocity_stack: ArrayD<f64>,
    pub skip_rule: ArrayD<u8>,
    pub single_rule: ArrayD<u8>,
    /// With `grid.aspect`: 1 where the stack would start to rock (docs/model.md, "Rocking:
    /// when a case leaves the model"); `None` when not checked.
    pub rocks_stack: Option<ArrayD<u8>>,
    /// A building study's per-floor peaks and base shear (`None` on one storey).
    pub building: Option<BuildingVars>,
}

/// A building study's per-floor and per-storey peaks (a trailing `floor` or `storey` axis of
/// length `N_max`, NaN above a building's roof) and base shear, with the stack (`_stack`) and
/// with it rigidly attached (`_rigid`); docs/model.md, "Base shear, drift ratio, floor
/// acceleration".
#[derive(Debug, Clone, PartialEq)]
pub struct BuildingVars {
    /// Peak absolute acceleration of each floor, g.
    pub floor_accel_stack: ArrayD<f64>,
    pub floor_accel_rigid: ArrayD<f64>,
    /// Peak interstorey drift over the storey's height, per storey.
    pub drift_ratio_stack: ArrayD<f64>,
    pub drift_ratio_rigid: ArrayD<f64>,
    /// Peak base shear over the bare building's weight (NaN in a building of one storey).
    pub base_shear_stack: ArrayD<f64>,
    pub base_shear_rigid: ArrayD<f64>,
    /// Peak shear of each storey over the bare building's weight (storey 1's is the base
    /// shear; NaN in a building of one storey).
    pub storey_shear_stack: ArrayD<f64>,
    pub storey_shear_rigid: ArrayD<f64>,
    /// Peak overturning moment at the base over the bare building's weight times its height
    /// (NaN in a building of one storey).
    pub overturning_stack: ArrayD<f64>,
    pub overturning_rigid: ArrayD<f64>,
    /// The stack's stuck mass share: the time average of its mass moving with its floor, over
    /// its mass (NaN in a building of one storey).
    pub stuck_share_stack: ArrayD<f64>,
    /// Peak absolute velocity of each floor, m/s (FEMA P-58's PFV).
    pub floor_velocity_stack: ArrayD<f64>,
    pub floor_velocity_rigid: ArrayD<f64>,
    /// Each storey's drift at the record's end over its height, signed.
    pub residual_drift_ratio_stack: ArrayD<f64>,
    pub residual_drift_ratio_rigid: ArrayD<f64>,
}

/// The trailing level axis of a building variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// None: the case dimensions alone.
    Case,
    Floor,
    Storey,
}

impl BuildingVars {
    /// `(name, data, units, long name, level axis)` of every variable, in the order they are
    /// written and read.
    pub fn vars(
        &self,
    ) -> [(
        &'static str,
        &ArrayD<f64>,
        &'static str,
        &'static str,
        Level,
    ); 15] {
        [
            (
                "floor_accel_stack",
                &self.floor_accel_stack,
                "g",
                "peak absolute acceleration of each floor with the sliding stack",
                Level::Floor,
            ),
            (
                "floor_accel_rigid",
                &self.floor_accel_rigid,
                "g",
                "peak absolute acceleration of each floor with the stack rigidly attached",
                Level::Floor,
            ),
            (
                "drift_ratio_stack",
                &self.drift_ratio_stack,
                "1",
                "peak interstorey drift over the storey height, with the sliding stack",
                Level::Storey,
            ),
            (
                "drift_ratio_rigid",
                &self.drift_ratio_rigid,
                "1",
                "peak interstorey drift over the storey height, with the stack rigidly attached",
                Level::Storey,
            ),
            (
                "base_shear_stack",
                &self.base_shear_stack,
                "1",
                "peak base shear over the bare building's weight, with the sliding stack \
                 (NaN on one storey: its integrator does not give it)",
                Level::Case,
            ),
            (
                "base_shear_rigid",
                &self.base_shear_rigid,
                "1",
                "peak base shear over the bare building's weight, with the stack rigidly \
                 attached (NaN on one storey: its integrator does not give it)",
                Level::Case,
            ),
            (
                "storey_shear_stack",
                &self.storey_shear_stack,
                "1",
                "peak shear of each storey over the bare building's weight, with the sliding \
                 stack (NaN on one storey)",
                Level::Storey,
            ),
            (
                "storey_shear_rigid",
                &self.storey_shear_rigid,
                "1",
                "peak shear of each storey over the bare building's weight, with the stack \
                 rigidly attached (NaN on one storey)",
                Level::Storey,
            ),
            (
                "overturning_stack",
                &self.overturning_stack,
                "1",
                "peak overturning moment at the base over the bare building's weight times its \
                 height, with the sliding stack (NaN on one storey)",
                Level::Case,
            ),
            (
                "overturning_rigid",
                &self.overturning_rigid,
                "1",
                "peak overturning moment at the base over the bare building's weight times its \
                 height, with the stack rigidly attached (NaN on one storey)",
                Level::Case,
            ),
            (
                "stuck_share_stack",
                &self.stuck_share_stack,
                "1",
                "time average of the stack's mass moving with its floor over its mass (1: it \
                 never slid; NaN on one storey)",
                Level::Case,
            ),
            (
                "floor_velocity_stack",
                &self.floor_velocity_stack,
                "m s-1",
                "peak absolute velocity of each floor with the sliding stack",
                Level::Floor,
            ),
            (
                "floor_velocity_rigid",
                &self.floor_velocity_rigid,
                "m s-1",
                "peak absolute velocity of each floor with the stack rigidly attached",
                Level::Floor,
            ),
            (
                "residual_drift_ratio_stack",
                &self.residual_drift_ratio_stack,
                "1",
                "interstorey drift at the record's end over the storey height, signed, with \
                 the sliding stack",
                Level::Storey,
            ),
            (
                "residual_drift_ratio_rigid",
                &self.residual_drift_ratio_rigid,
                "1",
                "interstorey drift at the record's end over the storey height, signed, with \
                 the stack rigidly attached",
                Level::Storey,
            ),
        ]
    }
}

/// One zone of `sweep.h5`.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneSweep {
    pub name: String,
    pub target: String,
    pub motions: Vec<String>,
    pub vars: SweepVars,
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
    let iface: Vec<f64> = (1..=n).map(|i| i as f64).collect();
    let iface = coordinate(
        &g,
        "interface",
        &iface,
        "1",
        "interface (1 = structure–block 1)",
    )?;
    // One chunk per work unit: one motion (one frame), one T_p.
    let mut chunk = vec![1; if building.is_some() { 4 } else { 2 }];
    chunk.extend(grid.case_shape());
    let v = &z.vars;
    let vars: [(&str, &ArrayD<f64>, &str, &str); 5] = [
        (
            "u_stack",
            &v.u_stack,
            "m",
            "peak structure displacement with the sliding stack",
        ),
        (
            "u_single",
            &v.u_single,
            "m",
            "peak structure displacement with the stack as one sliding block on interface 1",
        ),
        (
            "u_rigid",
            &v.u_rigid,
            "m",
            "peak structure displacement with the stack rigidly attached",
        ),
        (
            "a_stack",
            &v.a_stack,
            "g",
            "peak absolute structure acceleration with the sliding stack",
        ),
        (
            "friction_energy",
            &v.friction_energy,
            "J/kg",
            "energy dissipated by friction in the stack, per kg of structure mass",
        ),
    ];
    for (name, data, units, long) in vars {
        // In a building the structure's peaks are the roof's.
        let long = match name {
            "u_stack" | "u_single" | "u_rigid" | "a_stack" if building.is_some() => {
                format!("{long} (a building: its roof's)")
            }
            "friction_energy" if building.is_some() => {
                format!("{long} (a building: of every stack, per kg of all its floors)")
            }
            _ => long.to_string(),
        };
        let ds = write_var(&g, name, data.view(), &chunk, units, &long)?;
        attach_all(&ds, &scales)?;
    }
    let mut chunk_i = chunk.clone();
    chunk_i.push(n);
    let ds = write_var(
        &g,
        "slip_peak",
        v.slip_peak.view(),
        &chunk_i,
        "m",
        if building.is_some() {
            "peak slip of each interface (with a stack on every floor: the largest over them)"
        } else {
            "peak slip of each interface"
        },
    )?;
    attach_all(&ds, &scales)?;
    attach_scale(&ds, &iface, scales.len())?;
    let several = building.is_some();
    let ds = write_var(
        &g,
        "slip_residual",
        v.slip_residual.view(),
        &chunk_i,
        "m",
        if several {
            "slip of each interface at the record's end, signed (with a stack on every floor: \
             the one of the largest magnitude)"
        } else {
            "slip of each interface at the record's end, signed"
        },
    )?;
    attach_all(&ds, &scales)?;
    attach_scale(&ds, &iface, scales.len())?;
    let block: Vec<f64> = (1..=n).map(|i| i as f64).collect();
    let block = coordinate(
        &g,
        "block",
        &block,
        "1",
        "block (1 = the lowest, resting on interface 1)",
    )?;
    for (name, data, units, long) in [
        (
            "block_accel_stack",
            &v.block_accel_stack,
            "g",
            "peak absolute acceleration of each block",
        ),
        (
            "block_velocity_stack",
            &v.block_velocity_stack,
            "m s-1",
            "peak absolute velocity of each block",
        ),
    ] {
        let long = if several {
            format!("{long} (with a stack on every floor: the largest over them)")
        } else {
            long.to_string()
        };
        let ds = write_var(&g, name, data.view(), &chunk_i, units, &long)?;
        attach_all(&ds, &scales)?;
        attach_scale(&ds, &block, scales.len())?;
    }
    let ds = write_flags(
        &g,
        "skip_rule",
        v.skip_rule.view(),
        &chunk,
        "rule that gave the stack result (file attribute skip_rule_codes)",
        meta.skip_rule_flags,
    )?;
    attach_all(&ds, &scales)?;
    let ds = write_flags(
        &g,
        "single_rule",
        v.single_rule.view(),
        &chunk,
        "1 when the single block cannot slip and equals the rigid system",
        &[(0, "simulated"), (1, "equals_rigid")],
    )?;
    attach_all(&ds, &scales)?;
    if let Some(rocks) = &v.rocks_stack {
        let ds = write_flags(
            &g,
            "rocks_stack",
            rocks.view(),
            &chunk,
            "1 when the stack (in a building, any of its stacks) would start to rock: the \
             sliding-only model does not hold (blocks' width over height: file attribute aspect)",
            &[(0, "slides_only"), (1, "rocks")],
        )?;
        attach_all(&ds, &scales)?;
    }
    if let (Some(b), Some(bv)) = (building, &v.building) {
        let levels: Vec<f64> = (1..=b.max_storeys()).map(|j| j as f64).collect();
        let floor = coordinate(&g, "floor", &levels, "1", "floor (1 the lowest)")?;
        let storey = coordinate(
            &g,
            "storey",
            &levels,
            "1",
            "storey (1 the lowest: between the ground and floor 1)",
        )?;
        let mut chunk_f = chunk.clone();
        chunk_f.push(levels.len());
        for (name, data, units, long, level) in bv.vars() {
            let per = match level {
                Level::Floor => Some(&floor),
                Level::Storey => Some(&storey),
                Level::Case => None,
            };
            let ds = write_var(
                &g,
                name,
                data.view(),
                if per.is_some() { &chunk_f } else { &chunk },
                units,
                long,
            )?;
            attach_all(&ds, &scales)?;
            if let Some(p) = per {
                attach_scale(&ds, p, scales.len())?;
            }
        }
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
    let mut per_interface = shape.clone();
    per_interface.push(blocks);
    let building_vars = match &axes {
        None => None,
        Some(a) => {
            let mut per_floor = shape.clone();
            per_floor.push(a.max_storeys());
            Some(BuildingVars {
                floor_accel_stack: g.array("floor_accel_stack", &per_floor)?,
                floor_accel_rigid: g.array("floor_accel_rigid", &per_floor)?,
                drift_ratio_stack: g.array("drift_ratio_stack", &per_floor)?,
                drift_ratio_rigid: g.array("drift_ratio_rigid", &per_floor)?,
                base_shear_stack: g.array("base_shear_stack", &shape)?,
                base_shear_rigid: g.array("base_shear_rigid", &shape)?,
                storey_shear_stack: g.array("storey_shear_stack", &per_floor)?,
                storey_shear_rigid: g.array("storey_shear_rigid", &per_floor)?,
                overturning_stack: g.array("overturning_stack", &shape)?,
                overturning_rigid: g.array("overturning_rigid", &shape)?,
                stuck_share_stack: g.array("stuck_share_stack", &shape)?,
                floor_velocity_stack: g.array("floor_velocity_stack", &per_floor)?,
                floor_velocity_rigid: g.array("floor_velocity_rigid", &per_floor)?,
                residual_drift_ratio_stack: g.array("residual_drift_ratio_stack", &per_floor)?,
                residual_drift_ratio_rigid: g.array("residual_drift_ratio_rigid", &per_floor)?,
            })
        }
    };
    let vars = SweepVars {
        building: building_vars,
        u_stack: g.array("u_stack", &shape)?,
        u_single: g.array("u_single", &shape)?,
        u_rigid: g.array("u_rigid", &shape)?,
        a_stack: g.array("a_stack", &shape)?,
        friction_energy: g.array("friction_energy", &shape)?,
        slip_peak: g.array("slip_peak", &per_interface)?,
        slip_residual: g.array("slip_residual", &per_interface)?,
        block_accel_stack: g.array("block_accel_stack", &per_interface)?,
        block_velocity_stack: g.array("block_velocity_stack", &per_interface)?,
        skip_rule: g.array("skip_rule", &shape)?,
        single_rule: g.array("single_rule", &shape)?,
        rocks_stack: (g.has("rocks_stack"))
            .then(|| g.array("rocks_stack", &shape))
            .transpose()?,
    };
    let zone = ZoneSweep {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        motions,
        vars,
    };
    Ok((grid, axes, zone))
}
