//! The sweep's files: one small file per finished work unit, and `sweep.h5` assembled from them.
//!
//! A unit file is written to a temporary name and renamed, so it is either whole or absent: a run
//! killed at any moment leaves only whole units, and a rerun computes the rest. Each carries the
//! sweep's fingerprint; a unit made from other inputs is never read. `sweep.h5` is assembled from
//! the units in a fixed order, with object times not tracked, so the same inputs give the same
//! bytes whatever the thread count, shard split or interruptions.
//!
//! ```text
//! /                     attrs: contents, slidestack_version, fingerprint, config_sha256,
//!                              motions_fingerprint, skip_rule_codes
//! /zone_<name>/         attrs: target
//!     motion, T_p, alpha_1 … alpha_n, mu_1 … mu_n, interface    coordinates (dimension scales)
//!     u_stack, u_single, u_rigid (m), a_stack (g), friction_energy (J/kg),
//!     skip_rule, single_rule                       [motion, T_p, alpha_1 … alpha_n, mu_1 … mu_n]
//!     slip_peak (m)                                [… , interface]
//! ```
//! Variables are chunked by work unit (one motion, one `T_p`), deflate+shuffle compressed, with
//! NaN (255 for the rule codes) as fill value.

use super::h5::{
    attach_scale, attr_str, coordinate, scalar_var, set_scale, write_stage_file, write_strings,
};
use crate::study::sweep::{Grid, SKIP_RULE_CODES, UnitResult};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"SLSWEEP1";
const TRAILER: &[u8; 4] = b"END!";

/// File name of unit (zone, motion, period) inside the units directory.
pub fn unit_path(dir: &Path, zone: &str, motion: usize, period: usize) -> PathBuf {
    dir.join(format!("{zone}_{motion:03}_{period:03}.unit"))
}

/// Writes a unit atomically (temporary file, fsync, rename).
pub fn write_unit(path: &Path, fingerprint: &str, r: &UnitResult) -> std::io::Result<()> {
    let mut buf = Vec::new();
    buf.extend_from_slice(MAGIC);
    buf.extend_from_slice(&(fingerprint.len() as u32).to_le_bytes());
    buf.extend_from_slice(fingerprint.as_bytes());
    let cases = r.u_stack.len();
    buf.extend_from_slice(&(cases as u64).to_le_bytes());
    buf.extend_from_slice(&(r.slip_peak.len() as u64).to_le_bytes());
    for v in [
        &r.u_stack,
        &r.u_single,
        &r.u_rigid,
        &r.a_stack,
        &r.friction_energy,
        &r.slip_peak,
    ] {
        for x in v.iter() {
            buf.extend_from_slice(&x.to_le_bytes());
        }
    }
    buf.extend_from_slice(&r.skip_rule);
    buf.extend_from_slice(&r.single_rule);
    buf.extend_from_slice(TRAILER);
    let tmp = path.with_extension("unit.tmp");
    {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&buf)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}

/// Reads a unit if it is whole and was made with `fingerprint`; `None` otherwise.
pub fn read_unit(path: &Path, fingerprint: &str) -> Option<UnitResult> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .read_to_end(&mut bytes)
        .ok()?;
    let mut at = 0;
    let mut take = |n: usize| -> Option<&[u8]> {
        let s = bytes.get(at..at + n)?;
        at += n;
        Some(s)
    };
    if take(8)? != MAGIC {
        return None;
    }
    let fl = u32::from_le_bytes(take(4)?.try_into().ok()?) as usize;
    if take(fl)? != fingerprint.as_bytes() {
        return None;
    }
    let cases = u64::from_le_bytes(take(8)?.try_into().ok()?) as usize;
    let slips = u64::from_le_bytes(take(8)?.try_into().ok()?) as usize;
    let mut f64s = |n: usize| -> Option<Vec<f64>> {
        Some(
            take(n * 8)?
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        )
    };
    let mut r = UnitResult {
        u_stack: f64s(cases)?,
        u_single: f64s(cases)?,
        u_rigid: f64s(cases)?,
        a_stack: f64s(cases)?,
        friction_energy: f64s(cases)?,
        slip_peak: f64s(slips)?,
        ..UnitResult::default()
    };
    r.skip_rule = take(cases)?.to_vec();
    r.single_rule = take(cases)?.to_vec();
    (take(4)? == TRAILER && at == bytes.len()).then_some(r)
}

/// Provenance written on `sweep.h5`.
#[derive(Debug, Clone)]
pub struct SweepMeta {
    pub fingerprint: String,
    pub config_sha256: String,
    pub motions_fingerprint: String,
}

/// One zone's units, `units[motion][period]`.
pub struct ZoneUnits<'a> {
    pub name: &'a str,
    pub target: &'a str,
    pub motions: &'a [String],
    pub units: Vec<Vec<UnitResult>>,
}

fn code_var(
    g: &hdf5::Group,
    name: &str,
    shape: &[usize],
    chunk: &[usize],
    data: &[u8],
    long: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = g
        .new_dataset::<u8>()
        .shape(shape.to_vec())
        .chunk(chunk.to_vec())
        .shuffle()
        .deflate(4)
        .fill_value(255u8)
        .obj_track_times(false)
        .create(name)?;
    ds.write_raw(data)?;
    attr_str(&ds, "long_name", long)?;
    Ok(ds)
}

/// The coordinates of the case dimensions `T_p, alpha_1 … alpha_n, mu_1 … mu_n` of `grid` in
/// group `g`, as dimension scales in that order (shared by `sweep.h5` and `tnew.h5`).
pub fn case_coordinates(g: &hdf5::Group, grid: &Grid) -> hdf5::Result<Vec<hdf5::Dataset>> {
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
            grid.mu_static_ratio
        );
        scales.push(coordinate(g, &format!("mu_{}", i + 1), mu, "1", &long)?);
    }
    Ok(scales)
}

/// Assembles `sweep.h5` at `path` (through a temporary file renamed at the end).
pub fn write_sweep(
    path: &Path,
    meta: &SweepMeta,
    grid: &Grid,
    zones: &[ZoneUnits],
) -> hdf5::Result<()> {
    write_stage_file(
        path,
        "slidestack sweep stage: peak responses over the grid, per zone",
        &meta.fingerprint,
        |f| {
            attr_str(f, "config_sha256", &meta.config_sha256)?;
            attr_str(f, "motions_fingerprint", &meta.motions_fingerprint)?;
            attr_str(f, "skip_rule_codes", SKIP_RULE_CODES)?;
            for z in zones {
                write_zone(f, grid, z)?;
            }
            Ok(())
        },
    )
}

fn write_zone(f: &hdf5::File, grid: &Grid, z: &ZoneUnits) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", z.target)?;
    let n = grid.blocks();
    let mut scales = Vec::new();
    let m = write_strings(
        &g,
        "motion",
        z.motions,
        "ground motion (matched, see motions.h5)",
    )?;
    set_scale(&m, "motion")?;
    scales.push(m);
    scales.extend(case_coordinates(&g, grid)?);
    let iface: Vec<f64> = (1..=n).map(|i| i as f64).collect();
    let iface = coordinate(
        &g,
        "interface",
        &iface,
        "1",
        "interface (1 = structure–block 1)",
    )?;

    let mut shape = vec![z.motions.len(), grid.periods_s.len()];
    shape.extend(grid.case_shape());
    let mut chunk = vec![1, 1];
    chunk.extend(grid.case_shape());
    let flat = |f: &dyn Fn(&UnitResult) -> &Vec<f64>| -> Vec<f64> {
        z.units
            .iter()
            .flatten()
            .flat_map(|u| f(u).iter().copied())
            .collect()
    };
    let attach = |ds: &hdf5::Dataset, with_interface: bool| -> hdf5::Result<()> {
        for (d, s) in scales.iter().enumerate() {
            attach_scale(ds, s, d)?;
        }
        if with_interface {
            attach_scale(ds, &iface, scales.len())?;
        }
        Ok(())
    };
    let vars: [(&str, Vec<f64>, &str, &str); 5] = [
        (
            "u_stack",
            flat(&|u| &u.u_stack),
            "m",
            "peak structure displacement with the sliding stack",
        ),
        (
            "u_single",
            flat(&|u| &u.u_single),
            "m",
            "peak structure displacement with the stack as one sliding block on interface 1",
        ),
        (
            "u_rigid",
            flat(&|u| &u.u_rigid),
            "m",
            "peak structure displacement with the stack rigidly attached",
        ),
        (
            "a_stack",
            flat(&|u| &u.a_stack),
            "g",
            "peak absolute structure acceleration with the sliding stack",
        ),
        (
            "friction_energy",
            flat(&|u| &u.friction_energy),
            "J/kg",
            "energy dissipated by friction in the stack, per kg of structure mass",
        ),
    ];
    for (name, data, units, long) in &vars {
        let ds = scalar_var(&g, name, &shape, &chunk, data, units, long)?;
        attach(&ds, false)?;
    }
    let mut shape_i = shape.clone();
    shape_i.push(n);
    let mut chunk_i = chunk.clone();
    chunk_i.push(n);
    let slips = flat(&|u| &u.slip_peak);
    let ds = scalar_var(
        &g,
        "slip_peak",
        &shape_i,
        &chunk_i,
        &slips,
        "m",
        "peak slip of each interface",
    )?;
    attach(&ds, true)?;
    let codes = |f: &dyn Fn(&UnitResult) -> &Vec<u8>| -> Vec<u8> {
        z.units
            .iter()
            .flatten()
            .flat_map(|u| f(u).iter().copied())
            .collect()
    };
    let ds = code_var(
        &g,
        "skip_rule",
        &shape,
        &chunk,
        &codes(&|u| &u.skip_rule),
        "rule that gave the stack result (file attribute skip_rule_codes)",
    )?;
    attr_str(&ds, "flag_meanings", SKIP_RULE_CODES)?;
    attach(&ds, false)?;
    let ds = code_var(
        &g,
        "single_rule",
        &shape,
        &chunk,
        &codes(&|u| &u.single_rule),
        "1 when the single block cannot slip and equals the rigid system",
    )?;
    attach(&ds, false)?;
    Ok(())
}

/// The stage fingerprint stored in an existing `sweep.h5`.
pub fn read_fingerprint(path: &Path) -> Option<String> {
    let f = hdf5::File::open(path).ok()?;
    super::h5::read_attr_str(&f, "fingerprint")
}

/// One zone of `sweep.h5`, read back: the coordinates and the variables `tnew` needs, flat in
/// the file's order (`[motion][T_p][alpha…][mu…]`, `slip_peak` with a trailing interface).
#[derive(Debug, Clone)]
pub struct ZoneSweep {
    pub motions: Vec<String>,
    pub grid: Grid,
    pub u_stack: Vec<f64>,
    pub u_single: Vec<f64>,
    pub u_rigid: Vec<f64>,
    pub slip_peak: Vec<f64>,
}

/// Reads zone `zone` of `sweep.h5`; the grid's static ratio and damping come from `grid`
/// (they are not coordinates).
pub fn read_zone_sweep(path: &Path, zone: &str, like: &Grid) -> hdf5::Result<ZoneSweep> {
    let f = hdf5::File::open(path)?;
    let g = f.group(&format!("zone_{zone}"))?;
    let read = |n: &str| g.dataset(n)?.read_raw::<f64>();
    let n = like.blocks();
    let grid = Grid {
        periods_s: read("T_p")?,
        alpha: (1..=n)
            .map(|i| read(&format!("alpha_{i}")))
            .collect::<hdf5::Result<_>>()?,
        mu: (1..=n)
            .map(|i| read(&format!("mu_{i}")))
            .collect::<hdf5::Result<_>>()?,
        mu_static_ratio: like.mu_static_ratio,
        damping: like.damping,
    };
    Ok(ZoneSweep {
        motions: super::h5::read_strings(&g, "motion")?,
        grid,
        u_stack: read("u_stack")?,
        u_single: read("u_single")?,
        u_rigid: read("u_rigid")?,
        slip_peak: read("slip_peak")?,
    })
}
