//! `motions.h5`, the ground-motion stage's file.
//!
//! ```text
//! /                      attrs: contents, slidestack_version, fingerprint, config_sha256, inputs
//! /seeds/seed_NN         seed motion NN (g); attrs name, dt_s, units, long_name
//! /zone_<name>/          attrs: target (SPEC), target_label, fingerprint, set_scale,
//!                               mean_ratio_min, set_mean_min, set_mean_ok, asce7_ok,
//!                               all_within_band
//!     period             check grid, s                                  [period]
//!     target_psa_g, mean_psa_g                                          [period]
//!     target_table_period (s), target_table_sa_g (g): the rows of a `table:FILE` target, the
//!                        spectrum the study used (absent for the codes' spectra, which the
//!                        SPEC string states whole)                      [target_row]
//!     motion             names of the kept (matched and accepted) motions [motion]
//!     psa_g              5 %-damped PSA of each kept motion, g          [motion, period]
//!     seed               names of all seeds                             [seed]
//!     kept, converged, iterations, worst_misfit, scale, pga_before_g, pga_after_g,
//!     final_velocity_mps, final_displacement_m, arias_ratio             [seed]
//!     accel/motion_NN    kept motion NN (g); attrs name, dt_s, units
//! ```

use super::h5::{
    GroupReader, attr_f64, attr_str, open, read_attr_f64, read_attr_str, write_1d, write_small,
    write_stage_file, write_strings,
};
use super::vars::{Codes, Trailing, Var};
use super::{H5Context, StoreError};
use crate::ground_motion::Record;
use crate::ground_motion::matching::MatchReport;
use crate::ground_motion::set::ZoneMotions;
use crate::spectrum::{TargetError, TargetSpectrum};
use std::path::Path;

/// Provenance written on the file.
#[derive(Debug, Clone, PartialEq)]
pub struct StageMeta {
    pub fingerprint: String,
    pub config_sha256: String,
    /// JSON list of the input files and their SHA-256.
    pub inputs: String,
}

fn write_record(g: &hdf5::Group, key: &str, r: &Record, long: &str) -> hdf5::Result<()> {
    let ds = write_1d(g, key, &r.accel_g, "g", long)?;
    attr_str(&ds, "name", &r.name)?;
    attr_f64(&ds, "dt_s", r.dt_s)
}

/// The record `key` of `g`: one-dimensional, with its name and step.
fn read_record(g: &GroupReader, key: &str) -> Result<Record, StoreError> {
    let accel_g = g.vector(key)?;
    let ds = g.group().dataset(key).at(g.file())?;
    Ok(Record {
        name: read_attr_str(&ds, "name").unwrap_or_else(|| key.to_string()),
        dt_s: read_attr_f64(&ds, "dt_s").at(g.file())?,
        accel_g,
    })
}

/// Writes `motions.h5` at `path` (checked and atomic, [`write_stage_file`]).
pub fn write_motions(
    path: &Path,
    meta: &StageMeta,
    seeds: &[Record],
    zones: &[(ZoneMotions, String)],
) -> Result<(), StoreError> {
    write_stage_file(
        path,
        "slidestack motions stage: seed motions, motions matched per zone, their spectra",
        &meta.fingerprint,
        |f| {
            attr_str(f, "config_sha256", &meta.config_sha256)?;
            attr_str(f, "inputs", &meta.inputs)?;
            let g = f.create_group("seeds")?;
            for (i, s) in seeds.iter().enumerate() {
                write_record(&g, &format!("seed_{i:02}"), s, "seed ground acceleration")?;
            }
            for (z, fp) in zones {
                write_zone(f, z, fp)?;
            }
            Ok(())
        },
    )
}

fn write_zone(f: &hdf5::File, z: &ZoneMotions, fingerprint: &str) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", &z.target.to_string())?;
    attr_str(&g, "target_label", &z.target.label())?;
    attr_str(&g, "fingerprint", fingerprint)?;
    attr_f64(&g, "set_scale", z.set_scale)?;
    attr_f64(&g, "mean_ratio_min", z.mean_ratio_min)?;
    for (k, v) in [
        ("set_mean_ok", z.set_mean_ok),
        ("asce7_ok", z.asce7_ok),
        ("all_within_band", z.all_within_band),
    ] {
        attr_f64(&g, k, if v { 1.0 } else { 0.0 })?;
    }
    if let TargetSpectrum::Table {
        periods_s, sa_g, ..
    } = &z.target
    {
        for (var, values) in TARGET_TABLE.iter().zip([periods_s, sa_g]) {
            let ds = write_1d(&g, var.name, values, var.units, var.long_name)?;
            attr_str(&ds, "dims", "target_row")?;
        }
    }
    write_spectra(&g, z)?;
    write_seed_report(&g, z)?;
    let acc = g.create_group("accel")?;
    for (i, m) in z.motions.iter().enumerate() {
        write_record(
            &acc,
            &format!("motion_{i:02}"),
            m,
            "matched ground acceleration",
        )?;
    }
    Ok(())
}

/// The rows of a `table:FILE` target, `[target_row]`.
pub const TARGET_TABLE: [Var; 2] = [
    value(TABLE_PERIOD, "s", "period of a row of the target table"),
    value(
        TABLE_SA,
        "g",
        "target pseudo-spectral acceleration of a row",
    ),
];

/// The spectra over the check periods, `[period]` (`psa_g`: `[motion, period]`).
pub const SPECTRA: [Var; 4] = [
    value("period", "s", "oscillator period"),
    value("target_psa_g", "g", "target pseudo-spectral acceleration"),
    value(
        "mean_psa_g",
        "g",
        "mean PSA of the kept motions (5 % damping)",
    ),
    value(
        "psa_g",
        "g",
        "pseudo-spectral acceleration of each kept motion (5 % damping)",
    ),
];

/// The matching report of every seed, `[seed]`: whether it was kept, then each column of its
/// [`MatchReport`] (`SEED_REPORT_OF` in the same order).
pub const SEED_REPORT: [Var; 10] = [
    value(
        "kept",
        "1",
        "1 when the motion is one of the zone's motions",
    ),
    value(
        "converged",
        "1",
        "1 when every check period is within the band",
    ),
    value("iterations", "1", "matching iterations"),
    value(
        "worst_misfit",
        "1",
        "largest |PSA/target − 1| on the check grid",
    ),
    value("scale", "1", "pre-scale factor before matching"),
    value("pga_before_g", "g", "peak ground acceleration of the seed"),
    value(
        "pga_after_g",
        "g",
        "peak ground acceleration after matching",
    ),
    value(
        "final_velocity_mps",
        "m/s",
        "ground velocity at the end (drift)",
    ),
    value(
        "final_displacement_m",
        "m",
        "ground displacement at the end (drift)",
    ),
    value(
        "arias_ratio",
        "1",
        "Arias intensity after / before matching",
    ),
];

/// The columns of [`SEED_REPORT`] after `kept`, from a seed's report.
const SEED_REPORT_OF: [fn(&MatchReport) -> f64; 9] = [
    |r| f64::from(u8::from(r.converged)),
    |r| r.iterations as f64,
    |r| r.worst_misfit,
    |r| r.scale,
    |r| r.pga_before_g,
    |r| r.pga_after_g,
    |r| r.final_velocity_mps,
    |r| r.final_displacement_m,
    |r| r.arias_ratio,
];

const fn value(name: &'static str, units: &'static str, long_name: &'static str) -> Var {
    Var {
        name,
        trailing: Trailing::Case,
        units,
        long_name,
        building_long_name: None,
        codes: Codes::Value,
    }
}

/// The check periods, the target and mean spectra and each kept motion's ([`SPECTRA`]) and the
/// kept motions' names.
fn write_spectra(g: &hdf5::Group, z: &ZoneMotions) -> hdf5::Result<()> {
    let [period, target, mean, psa_var] = &SPECTRA;
    for (var, values) in [
        (period, &z.periods_s),
        (target, &z.target_psa_g),
        (mean, &z.mean_psa_g),
    ] {
        write_1d(g, var.name, values, var.units, var.long_name)?;
    }
    let names: Vec<String> = z.motions.iter().map(|m| m.name.clone()).collect();
    write_strings(g, "motion", &names, "kept (matched and accepted) motions")?;
    let flat: Vec<f64> = z.psa_g.iter().flatten().copied().collect();
    let psa = ndarray::Array2::from_shape_vec((z.psa_g.len(), z.periods_s.len()), flat)
        .map_err(|e| hdf5::Error::from(e.to_string()))?;
    let ds = write_small(
        g,
        psa_var.name,
        psa.view().into_dyn(),
        psa_var.units,
        psa_var.long_name,
    )?;
    attr_str(&ds, "dims", "motion, period")
}

/// The seeds' names and their matching report ([`SEED_REPORT`]).
fn write_seed_report(g: &hdf5::Group, z: &ZoneMotions) -> hdf5::Result<()> {
    write_strings(g, "seed", &z.seeds, "all seed motions")?;
    let kept: Vec<f64> = (0..z.seeds.len())
        .map(|i| f64::from(u8::from(z.kept.contains(&i))))
        .collect();
    let columns = std::iter::once(kept).chain(
        SEED_REPORT_OF
            .iter()
            .map(|of| z.reports.iter().map(of).collect()),
    );
    for (var, data) in SEED_REPORT.iter().zip(columns) {
        let ds = write_1d(g, var.name, &data, var.units, var.long_name)?;
        attr_str(&ds, "dims", "seed")?;
    }
    Ok(())
}

/// The zone names of a motions file, in file order.
pub fn zone_names(path: &Path) -> Result<Vec<String>, StoreError> {
    let f = open(path)?;
    Ok(f.member_names()
        .at(path)?
        .into_iter()
        .filter_map(|n| n.strip_prefix("zone_").map(str::to_string))
        .collect())
}

const TABLE_PERIOD: &str = "target_table_period";
const TABLE_SA: &str = "target_table_sa_g";

/// The target spectrum zone `zone` was matched to: a table from its stored rows (never from its
/// file, which may have changed since), a code's spectrum from its SPEC string.
pub fn read_zone_target(path: &Path, zone: &str) -> Result<TargetSpectrum, StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let corrupt = |why: String| StoreError::corrupt(path, format!("zone_{zone}: {why}"));
    let spec = g
        .attr_str("target")
        .ok_or_else(|| corrupt("no target attribute".into()))?;
    let Some(source) = TargetSpectrum::table_file(&spec) else {
        return spec
            .parse()
            .map_err(|e: TargetError| corrupt(format!("target `{spec}`: {e}")));
    };
    let periods_s = g.vector(TABLE_PERIOD)?;
    let sa_g: Vec<f64> = g.array(TABLE_SA, &[periods_s.len()])?.into_iter().collect();
    let rows_ok = periods_s.len() >= 2
        && periods_s.iter().all(|t| t.is_finite() && *t >= 0.0)
        && periods_s.windows(2).all(|w| w[1] > w[0])
        && sa_g.iter().all(|s| s.is_finite() && *s > 0.0);
    if !rows_ok {
        return Err(corrupt(format!(
            "the rows of target `{spec}` are not a target table (2 rows or more, periods ≥ 0 \
             increasing, Sa > 0)"
        )));
    }
    Ok(TargetSpectrum::Table {
        source: source.to_string(),
        periods_s,
        sa_g,
    })
}

/// The kept motions of one zone, in order: one per name in its `motion` list.
pub fn read_zone_motions(path: &Path, zone: &str) -> Result<Vec<Record>, StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let names = g.strings("motion")?;
    let acc = GroupReader::open(path, &format!("zone_{zone}/accel"))?;
    let mut keys = acc.members()?;
    keys.sort();
    g.expect("accel", &[keys.len()], &[names.len()])?;
    keys.iter().map(|k| read_record(&acc, k)).collect()
}

/// One zone's spectra: the check periods, the target and the set mean (PSA, g), and every kept
/// motion's PSA (`[motion][period]`, g).
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneSpectra {
    pub periods_s: Vec<f64>,
    pub target_psa_g: Vec<f64>,
    pub mean_psa_g: Vec<f64>,
    pub psa_g: ndarray::Array2<f64>,
}

/// One zone's spectra, each of the shape its `period` and `motion` lists give.
pub fn read_zone_spectra(path: &Path, zone: &str) -> Result<ZoneSpectra, StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let periods_s = g.vector("period")?;
    let n = periods_s.len();
    let motions = g.strings("motion")?.len();
    let list = |var: &Var| -> Result<Vec<f64>, StoreError> {
        Ok(g.array(var.name, &[n])?.into_iter().collect())
    };
    let [_, target, mean, psa] = &SPECTRA;
    let psa_g = g.array::<f64>(psa.name, &[motions, n])?;
    Ok(ZoneSpectra {
        target_psa_g: list(target)?,
        mean_psa_g: list(mean)?,
        psa_g: psa_g
            .into_dimensionality()
            .map_err(|e| StoreError::corrupt(path, e.to_string()))?,
        periods_s,
    })
}

/// The seed names of one zone's report and whether each was kept.
pub fn read_zone_report(path: &Path, zone: &str) -> Result<Vec<(String, bool)>, StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let names = g.strings("seed")?;
    let converged = g.array::<f64>("converged", &[names.len()])?;
    Ok(names
        .into_iter()
        .zip(converged.into_iter().map(|c| c == 1.0))
        .collect())
}
