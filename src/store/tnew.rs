//! `tnew.h5`, the T_new stage's file.
//!
//! ```text
//! /                  attrs: contents, slidestack_version, fingerprint, sweep_fingerprint,
//!                           motions_fingerprint, T_new_flag_codes, + the writer's settings
//! /zone_<name>/      attrs: target
//!     T_p, alpha_1 … alpha_n, mu_1 … mu_n                 coordinates (dimension scales)
//!     u_stack_mean, u_single_mean, u_rigid_mean (m), T_rigid, T_new (s), DRR_1, DRR_2,
//!     slides (0/1), T_new_flag, T_new_band (CF flags)     [T_p, alpha_1 … alpha_n, mu_1 … mu_n]
//!     period_sd (s), sd_mean (m): the zone's mean 5 %-damped displacement spectrum
//! ```
//! A building study's variables have the dimensions `storeys` and `stack_floor` in front
//! (coordinates as in `sweep.h5`), and `roof_participation` `[storeys]` is `Γ_1·φ_1,N`, by which
//! the mean peak roof displacement is divided before `T_new` is read off the spectrum. It also
//! holds the effective live-load fraction (docs/model.md, "The effective live-load fraction
//! λ"), per case:
//! ```text
//!     base_shear_stack_mean, base_shear_rigid_mean, base_shear_bare_mean (1),
//!     lambda (1), lambda_flag (CF flags)       [storeys, stack_floor, T_p, alpha…, mu…]
//! ```

use super::h5::{
    Attr, GroupReader, attach_all, attach_scale, attr_str, coordinate, group, open, write_attrs,
    write_flags, write_small, write_stage_file, write_var,
};
use super::sweep::{
    building_coordinates, case_coordinates, read_building_coordinates, read_case_coordinates,
};
use super::{H5Context, StoreError};
use crate::grid::{BuildingAxes, Grid};
use ndarray::ArrayD;
use std::path::Path;

/// One zone's derived quantities, each shaped `[T_p, alpha…, mu…]`.
#[derive(Debug, Clone, PartialEq)]
pub struct TnewVars {
    pub u_stack_mean: ArrayD<f64>,
    pub u_single_mean: ArrayD<f64>,
    pub u_rigid_mean: ArrayD<f64>,
    pub t_rigid: ArrayD<f64>,
    pub t_new: ArrayD<f64>,
    pub drr_1: ArrayD<f64>,
    pub drr_2: ArrayD<f64>,
    pub slides: ArrayD<f64>,
    pub flag: ArrayD<f64>,
    /// Where `T_new` lies against `[T_p, T_rigid]` (codes in [`TnewMeta::band_flags`]).
    pub band: ArrayD<u8>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ZoneTnew {
    pub name: String,
    pub target: String,
    pub vars: TnewVars,
    /// The zone's mean 5 %-damped displacement spectrum: periods, s, and values, m.
    pub period_sd_s: Vec<f64>,
    pub sd_mean_m: Vec<f64>,
    /// A building study's `Γ_1·φ_1,N` per storey count (empty on one storey).
    pub roof_participation: Vec<f64>,
    /// A building study's effective live-load fraction (`None` on one storey).
    pub lambda: Option<AttachedVars>,
    /// With `grid.aspect`: per case, the share of the motions under which the stack would
    /// start to rock (the sweep's `rocks_stack`, averaged); `None` when not checked.
    pub rocks_share: Option<ArrayD<f64>>,
}

/// A building study's attached fractions of every case (docs/model.md, "The attached
/// fraction") and the mean peaks they come from, each over the bare building; shaped as
/// [`TnewVars`]' variables, the per-storey ones with a trailing `storey` axis of length `N_max`
/// (NaN, and 255 for flags, above a building's roof).
#[derive(Debug, Clone, PartialEq)]
pub struct AttachedVars {
    /// `V̄_stack`: with the sliding stack, over the bare building's weight.
    pub base_shear_stack_mean: ArrayD<f64>,
    /// `V̄(1)`: with the whole stack rigidly attached.
    pub base_shear_rigid_mean: ArrayD<f64>,
    /// `V̄(0)`: with the stack's mass absent (the building's own damping matrix).
    pub base_shear_bare_mean: ArrayD<f64>,
    /// `V̄_stack/V̄(0)` and `V̄_stack/V̄(1)`, unclamped.
    pub base_shear_ratio_bare: ArrayD<f64>,
    pub base_shear_ratio_rigid: ArrayD<f64>,
    /// The stuck mass share's mean over the motions.
    pub stuck_share_mean: ArrayD<f64>,
    /// `λ`: the attached fraction of the base shear, unclamped.
    pub lambda: ArrayD<f64>,
    pub flag: ArrayD<u8>,
    /// The attached fraction of each storey's shear (storey 1's is `λ`).
    pub lambda_storey: ArrayD<f64>,
    pub lambda_storey_flag: ArrayD<u8>,
    /// The attached fraction of the overturning moment at the base.
    pub lambda_overturning: ArrayD<f64>,
    pub lambda_overturning_flag: ArrayD<u8>,
    /// The code-format fraction.
    pub lambda_code: ArrayD<f64>,
    pub lambda_code_flag: ArrayD<u8>,
    /// The attached fraction of the roof's mean peak displacement (a building's `T_new` is the
    /// first-mode period with it attached).
    pub attached_fraction_roof: ArrayD<f64>,
    pub attached_fraction_roof_flag: ArrayD<u8>,
    /// The earlier definition of a building's `T_new` (the roof's mean peak over the bare
    /// building's `Γ_1·φ_1,N`, read off the mean displacement spectrum), kept for one release.
    pub t_new_first_mode: ArrayD<f64>,
}

/// Whether a variable has a trailing `storey` axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PerStorey {
    No,
    Yes,
}

impl AttachedVars {
    /// `(name, data, units, long name, per storey)` of every value variable.
    fn vars(
        &self,
    ) -> [(
        &'static str,
        &ArrayD<f64>,
        &'static str,
        &'static str,
        PerStorey,
    ); 12] {
        use PerStorey::*;
        [
            (
                "base_shear_stack_mean",
                &self.base_shear_stack_mean,
                "1",
                "mean over the motions of the peak base shear over the bare building's weight, \
                 with the sliding stack",
                No,
            ),
            (
                "base_shear_rigid_mean",
                &self.base_shear_rigid_mean,
                "1",
                "the same with the stack rigidly attached (fraction 1)",
                No,
            ),
            (
                "base_shear_bare_mean",
                &self.base_shear_bare_mean,
                "1",
                "the same with the stack's mass absent (fraction 0)",
                No,
            ),
            (
                "base_shear_ratio_bare",
                &self.base_shear_ratio_bare,
                "1",
                "base_shear_stack_mean / base_shear_bare_mean (below 1: the sliding stack lowers \
                 the base shear below the bare building's)",
                No,
            ),
            (
                "base_shear_ratio_rigid",
                &self.base_shear_ratio_rigid,
                "1",
                "base_shear_stack_mean / base_shear_rigid_mean",
                No,
            ),
            (
                "stuck_share_mean",
                &self.stuck_share_mean,
                "1",
                "mean over the motions of the time average of the stack's mass moving with its \
                 floor, over its mass (1: it never slid)",
                No,
            ),
            (
                "lambda",
                &self.lambda,
                "1",
                "effective live-load fraction: the fraction of the stack which, rigidly attached \
                 (below 0: removed), gives base_shear_stack_mean; unclamped (lambda_flag)",
                No,
            ),
            (
                "lambda_storey",
                &self.lambda_storey,
                "1",
                "the same for each storey's mean peak shear (storey 1: lambda)",
                Yes,
            ),
            (
                "lambda_overturning",
                &self.lambda_overturning,
                "1",
                "the same for the mean peak overturning moment at the base",
                No,
            ),
            (
                "lambda_code",
                &self.lambda_code,
                "1",
                "code-format fraction: (W + lambda·W_L)·Sa(T_1(lambda)) / ((W + W_L)·Sa(T_1,rigid)) \
                 = base_shear_ratio_rigid, Sa the zone's mean 5 %-damped spectrum exactly at the \
                 period",
                No,
            ),
            (
                "attached_fraction_roof",
                &self.attached_fraction_roof,
                "1",
                "the fraction of the stack which, rigidly attached, gives the mean peak roof \
                 displacement (a building of several storeys: T_new is T_1 with it attached)",
                No,
            ),
            (
                "T_new_first_mode",
                &self.t_new_first_mode,
                "s",
                "the earlier T_new of a building (kept for one release): the period whose mean \
                 5 %-damped spectral displacement equals u_stack_mean / roof_participation",
                No,
            ),
        ]
    }

    /// `(name, codes, per storey)` of every flag variable (codes: `lambda_flag`'s).
    fn flags(&self) -> [(&'static str, &ArrayD<u8>, PerStorey); 5] {
        use PerStorey::*;
        [
            ("lambda_flag", &self.flag, No),
            ("lambda_storey_flag", &self.lambda_storey_flag, Yes),
            ("lambda_overturning_flag", &self.lambda_overturning_flag, No),
            ("lambda_code_flag", &self.lambda_code_flag, No),
            (
                "attached_fraction_roof_flag",
                &self.attached_fraction_roof_flag,
                No,
            ),
        ]
    }
}

/// Provenance written on `tnew.h5`.
#[derive(Debug, Clone)]
pub struct TnewMeta<'a> {
    pub fingerprint: &'a str,
    pub sweep_fingerprint: &'a str,
    /// The fingerprint of the `motions.h5` whose motions gave the displacement spectra (and
    /// whose target spectra `design` reads).
    pub motions_fingerprint: &'a str,
    /// Long description of the `T_new_flag` codes.
    pub flag_codes: &'a str,
    /// `(code, word)` pairs of the `T_new_band` codes.
    pub band_flags: &'a [(u8, &'a str)],
    /// `(code, word)` pairs of the `lambda_flag` codes (a building study's).
    pub lambda_flags: &'a [(u8, &'a str)],
    /// Static friction = this × kinetic.
    pub mu_static_ratio: f64,
    pub settings: &'a [(&'a str, Attr<'a>)],
}

/// Writes `tnew.h5` (checked and atomic); `building` the building axes of a building study.
pub fn write_tnew(
    path: &Path,
    meta: &TnewMeta,
    grid: &Grid,
    building: Option<&BuildingAxes>,
    zones: &[ZoneTnew],
) -> Result<(), StoreError> {
    write_stage_file(
        path,
        "slidestack tnew stage: T_new and displacement response ratios",
        meta.fingerprint,
        |f| {
            attr_str(f, "sweep_fingerprint", meta.sweep_fingerprint)?;
            attr_str(f, "motions_fingerprint", meta.motions_fingerprint)?;
            attr_str(f, "T_new_flag_codes", meta.flag_codes)?;
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
    z: &ZoneTnew,
    meta: &TnewMeta,
) -> hdf5::Result<()> {
    let g = f.create_group(&format!("zone_{}", z.name))?;
    attr_str(&g, "target", &z.target)?;
    let mut scales = Vec::new();
    if let Some(b) = building {
        scales.extend(building_coordinates(&g, b)?);
        let ds = write_small(
            &g,
            "roof_participation",
            ndarray::ArrayView1::from(&z.roof_participation).into_dyn(),
            "1",
            "Γ_1·φ_1,N of the bare building: roof displacement per first-mode equivalent-SDOF \
             displacement",
        )?;
        attach_scale(&ds, &scales[0], 0)?;
    }
    scales.extend(case_coordinates(&g, grid, meta.mu_static_ratio)?);
    let mut chunk = vec![1; if building.is_some() { 3 } else { 1 }];
    chunk.extend(grid.case_shape());
    let v = &z.vars;
    let vars: [(&str, &ArrayD<f64>, &str, &str); 9] = [
        (
            "u_stack_mean",
            &v.u_stack_mean,
            "m",
            "mean over the motions of the peak structure displacement with the sliding stack",
        ),
        (
            "u_single_mean",
            &v.u_single_mean,
            "m",
            "mean peak structure displacement with the stack as one block",
        ),
        (
            "u_rigid_mean",
            &v.u_rigid_mean,
            "m",
            "mean peak structure displacement with the stack rigidly attached",
        ),
        (
            "T_rigid",
            &v.t_rigid,
            "s",
            if building.is_some() {
                "first-mode period with the stack rigidly attached"
            } else {
                "period with the stack rigidly attached, T_p·sqrt(1+α)"
            },
        ),
        (
            "T_new",
            &v.t_new,
            "s",
            if building.is_some() {
                "period whose mean 5 %-damped spectral displacement equals u_stack_mean / \
                 roof_participation (the first mode's equivalent SDOF)"
            } else {
                "period whose mean 5 %-damped spectral displacement equals u_stack_mean (Section 7.1)"
            },
        ),
        (
            "DRR_1",
            &v.drr_1,
            "1",
            "u_stack_mean / u_rigid_mean (Eq. 7)",
        ),
        (
            "DRR_2",
            &v.drr_2,
            "1",
            "u_single_mean / u_rigid_mean (Eq. 8)",
        ),
        (
            "slides",
            &v.slides,
            "1",
            "1 when some interface slips under some motion",
        ),
        (
            "T_new_flag",
            &v.flag,
            "1",
            "how T_new was found (file attribute T_new_flag_codes)",
        ),
    ];
    for (name, data, units, long) in vars {
        // In a building the structure's peaks are the roof's.
        let long = match name {
            "u_stack_mean" | "u_single_mean" | "u_rigid_mean" if building.is_some() => {
                format!("{long} (a building: its roof's)")
            }
            _ => long.to_string(),
        };
        let ds = write_var(&g, name, data.view(), &chunk, units, &long)?;
        attach_all(&ds, &scales)?;
    }
    let ds = write_flags(
        &g,
        "T_new_band",
        v.band.view(),
        &chunk,
        "where T_new lies against [T_p, T_rigid]",
        meta.band_flags,
    )?;
    attach_all(&ds, &scales)?;
    if let Some(share) = &z.rocks_share {
        let ds = write_var(
            &g,
            "rocks_share",
            share.view(),
            &chunk,
            "1",
            "share of the motions under which the stack would start to rock (sweep.h5's \
             rocks_stack averaged): outside the sliding-only model where > 0",
        )?;
        attach_all(&ds, &scales)?;
    }
    if let (Some(l), Some(b)) = (&z.lambda, building) {
        let levels: Vec<f64> = (1..=b.max_storeys()).map(|j| j as f64).collect();
        let storey = coordinate(&g, "storey", &levels, "1", "storey (1 the lowest)")?;
        let mut chunk_s = chunk.clone();
        chunk_s.push(levels.len());
        let per = |p: PerStorey| {
            if p == PerStorey::Yes {
                &chunk_s
            } else {
                &chunk
            }
        };
        for (name, data, units, long, p) in l.vars() {
            let ds = write_var(&g, name, data.view(), per(p), units, long)?;
            attach_all(&ds, &scales)?;
            if p == PerStorey::Yes {
                attach_scale(&ds, &storey, scales.len())?;
            }
        }
        for (name, codes, p) in l.flags() {
            let ds = write_flags(
                &g,
                name,
                codes.view(),
                per(p),
                "how the fraction was found: the root of its mean peak on a 0.1 scan (the one \
                 nearest the stuck share of several), the scan point nearest when none, \
                 no_slide when nothing slid",
                meta.lambda_flags,
            )?;
            attach_all(&ds, &scales)?;
            if p == PerStorey::Yes {
                attach_scale(&ds, &storey, scales.len())?;
            }
        }
    }
    let p = coordinate(
        &g,
        "period_sd",
        &z.period_sd_s,
        "s",
        "period of the mean displacement spectrum",
    )?;
    let ds = write_small(
        &g,
        "sd_mean",
        ndarray::ArrayView1::from(&z.sd_mean_m).into_dyn(),
        "m",
        "mean 5 %-damped displacement spectrum of the zone's motions",
    )?;
    attach_scale(&ds, &p, 0)?;
    Ok(())
}

/// Zone `zone` of a one-storey study's `tnew.h5` ([`read_zone_tnew_in`]).
pub fn read_zone_tnew(
    path: &Path,
    zone: &str,
    blocks: usize,
) -> Result<(Grid, ZoneTnew), StoreError> {
    read_zone_tnew_in(path, zone, blocks, false).map(|(grid, _, z)| (grid, z))
}

/// Zone `zone` of `tnew.h5` (`building`: of a building study) and the axes stored with it;
/// every variable has the shape its coordinates give, and every `T_new_band` code is one of
/// its `flag_values`.
pub fn read_zone_tnew_in(
    path: &Path,
    zone: &str,
    blocks: usize,
    building: bool,
) -> Result<(Grid, Option<BuildingAxes>, ZoneTnew), StoreError> {
    let g = GroupReader::open(path, &format!("zone_{zone}"))?;
    let grid = read_case_coordinates(&g, blocks)?;
    let axes = building
        .then(|| read_building_coordinates(&g))
        .transpose()?;
    let mut shape: Vec<usize> = axes.iter().flat_map(|b| b.shape()).collect();
    shape.extend(grid.shape());
    let roof_participation = match &axes {
        Some(b) => (g.array::<f64>("roof_participation", &[b.storeys.len()])?)
            .iter()
            .copied()
            .collect(),
        None => Vec::new(),
    };
    let vars = TnewVars {
        u_stack_mean: g.array("u_stack_mean", &shape)?,
        u_single_mean: g.array("u_single_mean", &shape)?,
        u_rigid_mean: g.array("u_rigid_mean", &shape)?,
        t_rigid: g.array("T_rigid", &shape)?,
        t_new: g.array("T_new", &shape)?,
        drr_1: g.array("DRR_1", &shape)?,
        drr_2: g.array("DRR_2", &shape)?,
        slides: g.array("slides", &shape)?,
        flag: g.array("T_new_flag", &shape)?,
        band: g.array("T_new_band", &shape)?,
    };
    let codes: Vec<u8> = band_flags(&g)?.into_iter().map(|f| f.0).collect();
    if let Some(code) = vars.band.iter().find(|c| !codes.contains(c)) {
        return Err(StoreError::corrupt(
            path,
            format!(
                "{} holds code {code}, which is not one of its flag_values",
                g.label("T_new_band")
            ),
        ));
    }
    let lambda = match &axes {
        None => None,
        Some(a) => {
            let mut per_storey = shape.clone();
            per_storey.push(a.max_storeys());
            Some(AttachedVars {
                base_shear_stack_mean: g.array("base_shear_stack_mean", &shape)?,
                base_shear_rigid_mean: g.array("base_shear_rigid_mean", &shape)?,
                base_shear_bare_mean: g.array("base_shear_bare_mean", &shape)?,
                base_shear_ratio_bare: g.array("base_shear_ratio_bare", &shape)?,
                base_shear_ratio_rigid: g.array("base_shear_ratio_rigid", &shape)?,
                stuck_share_mean: g.array("stuck_share_mean", &shape)?,
                lambda: g.array("lambda", &shape)?,
                flag: g.array("lambda_flag", &shape)?,
                lambda_storey: g.array("lambda_storey", &per_storey)?,
                lambda_storey_flag: g.array("lambda_storey_flag", &per_storey)?,
                lambda_overturning: g.array("lambda_overturning", &shape)?,
                lambda_overturning_flag: g.array("lambda_overturning_flag", &shape)?,
                lambda_code: g.array("lambda_code", &shape)?,
                lambda_code_flag: g.array("lambda_code_flag", &shape)?,
                attached_fraction_roof: g.array("attached_fraction_roof", &shape)?,
                attached_fraction_roof_flag: g.array("attached_fraction_roof_flag", &shape)?,
                t_new_first_mode: g.array("T_new_first_mode", &shape)?,
            })
        }
    };
    let period_sd_s = g.vector("period_sd")?;
    let sd_mean_m = g.array("sd_mean", &[period_sd_s.len()])?;
    let z = ZoneTnew {
        name: zone.to_string(),
        target: g.attr_str("target").unwrap_or_default(),
        vars,
        period_sd_s,
        sd_mean_m: sd_mean_m.iter().copied().collect(),
        roof_participation,
        lambda,
        rocks_share: (g.has("rocks_share"))
            .then(|| g.array("rocks_share", &shape))
            .transpose()?,
    };
    Ok((grid, axes, z))
}

/// Whether `tnew.h5` is a building study's (its first zone has a `storeys` coordinate).
pub fn is_building(path: &Path) -> Result<bool, StoreError> {
    let (zones, _) = zones_and_blocks(path)?;
    let f = open(path)?;
    let g = group(&f, path, &format!("zone_{}", zones[0]))?;
    Ok(g.link_exists("storeys"))
}

/// The fingerprint of the `motions.h5` that `tnew.h5` was made from; `None` in a file made
/// before it was recorded.
pub fn read_motions_fingerprint(path: &Path) -> Result<Option<String>, StoreError> {
    let f = open(path)?;
    Ok(super::h5::read_attr_str(&f, "motions_fingerprint"))
}

/// The zone names of `tnew.h5` (file order) and its number of blocks.
pub fn zones_and_blocks(path: &Path) -> Result<(Vec<String>, usize), StoreError> {
    let f = super::h5::open(path)?;
    let zones: Vec<String> = f
        .member_names()
        .at(path)?
        .into_iter()
        .filter_map(|n| n.strip_prefix("zone_").map(str::to_string))
        .collect();
    let Some(first) = zones.first() else {
        return Err(StoreError::corrupt(path, "holds no zone"));
    };
    let g = group(&f, path, &format!("zone_{first}"))?;
    let blocks = g
        .member_names()
        .at(path)?
        .iter()
        .filter(|n| n.starts_with("alpha_"))
        .count();
    Ok((zones, blocks))
}

/// The CF `flag_values`/`flag_meanings` of zone `zone`'s `T_new_band`: `(code, word)` pairs.
pub fn read_band_flags(path: &Path, zone: &str) -> Result<Vec<(u8, String)>, StoreError> {
    band_flags(&GroupReader::open(path, &format!("zone_{zone}"))?)
}

/// The `(code, word)` pairs of `T_new_band` in `g`: one word per code.
fn band_flags(g: &GroupReader) -> Result<Vec<(u8, String)>, StoreError> {
    let variable = "T_new_band";
    let read = || -> hdf5::Result<(Vec<u8>, String)> {
        let ds = g.group().dataset(variable)?;
        let values = ds.attr("flag_values")?.read_raw::<u8>()?;
        let words = super::h5::read_attr_str(&ds, "flag_meanings").unwrap_or_default();
        Ok((values, words))
    };
    let (values, words) = read().map_err(|e| StoreError::hdf5(g.file(), e))?;
    let words: Vec<String> = words.split_whitespace().map(str::to_string).collect();
    g.expect(
        &format!("{variable}@flag_meanings"),
        &[words.len()],
        &[values.len()],
    )?;
    if values.is_empty() {
        return Err(StoreError::corrupt(
            g.file(),
            format!("{} has no flag_values/flag_meanings", g.label(variable)),
        ));
    }
    Ok(values.into_iter().zip(words).collect())
}
