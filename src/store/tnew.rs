//! `tnew.h5`, the T_new stage's file.
//!
//! ```text
//! /                  attrs: contents, slidestack_version, fingerprint, sweep_fingerprint,
//!                           T_new_flag_codes
//! /zone_<name>/      attrs: target
//!     T_p, alpha_1 … alpha_n, mu_1 … mu_n                 coordinates (dimension scales)
//!     u_stack_mean, u_single_mean, u_rigid_mean (m), T_rigid, T_new (s), DRR_1, DRR_2,
//!     slides (0/1), T_new_flag                            [T_p, alpha_1 … alpha_n, mu_1 … mu_n]
//!     period_sd (s), sd_mean (m): the zone's mean 5 %-damped displacement spectrum
//! ```

use super::h5::{attach_scale, attr_str, coordinate, scalar_var, write_stage_file};
use crate::study::sweep::Grid;
use crate::study::tnew::TNEW_FLAG_CODES;
use std::path::Path;

/// One zone's derived quantities, flat over the case dimensions `[T_p][alpha…][mu…]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ZoneTnew {
    pub name: String,
    pub target: String,
    pub u_stack_mean: Vec<f64>,
    pub u_single_mean: Vec<f64>,
    pub u_rigid_mean: Vec<f64>,
    pub t_rigid: Vec<f64>,
    pub t_new: Vec<f64>,
    pub drr_1: Vec<f64>,
    pub drr_2: Vec<f64>,
    pub slides: Vec<f64>,
    pub flag: Vec<f64>,
    pub period_sd_s: Vec<f64>,
    pub sd_mean_m: Vec<f64>,
}

/// Writes `tnew.h5` (through a temporary file renamed at the end).
pub fn write_tnew(
    path: &Path,
    fingerprint: &str,
    sweep_fingerprint: &str,
    grid: &Grid,
    zones: &[ZoneTnew],
) -> hdf5::Result<()> {
    write_stage_file(
        path,
        "slidestack tnew stage: T_new and displacement response ratios",
        fingerprint,
        |f| {
            attr_str(f, "sweep_fingerprint", sweep_fingerprint)?;
            attr_str(f, "T_new_flag_codes", TNEW_FLAG_CODES)?;
            for z in zones {
                let g = f.create_group(&format!("zone_{}", z.name))?;
                attr_str(&g, "target", &z.target)?;
                let scales = super::sweep::case_coordinates(&g, grid)?;
                let mut shape = vec![grid.periods_s.len()];
                shape.extend(grid.case_shape());
                let mut chunk = vec![1];
                chunk.extend(grid.case_shape());
                let vars: [(&str, &Vec<f64>, &str, &str); 9] = [
                    (
                        "u_stack_mean",
                        &z.u_stack_mean,
                        "m",
                        "mean over the motions of the peak structure displacement with the sliding stack",
                    ),
                    (
                        "u_single_mean",
                        &z.u_single_mean,
                        "m",
                        "mean peak structure displacement with the stack as one block",
                    ),
                    (
                        "u_rigid_mean",
                        &z.u_rigid_mean,
                        "m",
                        "mean peak structure displacement with the stack rigidly attached",
                    ),
                    (
                        "T_rigid",
                        &z.t_rigid,
                        "s",
                        "period with the stack rigidly attached, T_p·sqrt(1+α)",
                    ),
                    (
                        "T_new",
                        &z.t_new,
                        "s",
                        "period whose mean 5 %-damped spectral displacement equals u_stack_mean (Section 7.1)",
                    ),
                    (
                        "DRR_1",
                        &z.drr_1,
                        "1",
                        "u_stack_mean / u_rigid_mean (Eq. 7)",
                    ),
                    (
                        "DRR_2",
                        &z.drr_2,
                        "1",
                        "u_single_mean / u_rigid_mean (Eq. 8)",
                    ),
                    (
                        "slides",
                        &z.slides,
                        "1",
                        "1 when some interface slips under some motion",
                    ),
                    (
                        "T_new_flag",
                        &z.flag,
                        "1",
                        "how T_new was found (file attribute T_new_flag_codes)",
                    ),
                ];
                for (name, data, units, long) in vars {
                    let ds = scalar_var(&g, name, &shape, &chunk, data, units, long)?;
                    for (d, s) in scales.iter().enumerate() {
                        attach_scale(&ds, s, d)?;
                    }
                }
                let p = coordinate(
                    &g,
                    "period_sd",
                    &z.period_sd_s,
                    "s",
                    "period of the mean displacement spectrum",
                )?;
                let ds = g
                    .new_dataset::<f64>()
                    .shape(z.sd_mean_m.len())
                    .obj_track_times(false)
                    .create("sd_mean")?;
                ds.write_raw(&z.sd_mean_m)?;
                attr_str(&ds, "units", "m")?;
                attr_str(
                    &ds,
                    "long_name",
                    "mean 5 %-damped displacement spectrum of the zone's motions",
                )?;
                attach_scale(&ds, &p, 0)?;
            }
            Ok(())
        },
    )
}

/// The stage fingerprint stored in an existing `tnew.h5`.
pub fn read_fingerprint(path: &Path) -> Option<String> {
    let f = hdf5::File::open(path).ok()?;
    super::h5::read_attr_str(&f, "fingerprint")
}

/// What the fit stage reads from one zone of `tnew.h5`: the case coordinates and, flat over
/// `[T_p][alpha…][mu…]`, `T_rigid`, `T_new` and its flag.
#[derive(Debug, Clone)]
pub struct ZoneTnewRead {
    pub periods_s: Vec<f64>,
    pub alpha: Vec<Vec<f64>>,
    pub mu: Vec<Vec<f64>>,
    pub t_rigid: Vec<f64>,
    pub t_new: Vec<f64>,
    pub flag: Vec<f64>,
}

pub fn read_zone_tnew(path: &Path, zone: &str, blocks: usize) -> hdf5::Result<ZoneTnewRead> {
    let f = hdf5::File::open(path)?;
    let g = f.group(&format!("zone_{zone}"))?;
    let read = |n: &str| g.dataset(n)?.read_raw::<f64>();
    Ok(ZoneTnewRead {
        periods_s: read("T_p")?,
        alpha: (1..=blocks)
            .map(|i| read(&format!("alpha_{i}")))
            .collect::<hdf5::Result<_>>()?,
        mu: (1..=blocks)
            .map(|i| read(&format!("mu_{i}")))
            .collect::<hdf5::Result<_>>()?,
        t_rigid: read("T_rigid")?,
        t_new: read("T_new")?,
        flag: read("T_new_flag")?,
    })
}
