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
    Attr, GroupReader, attach_scale, attr_str, coordinate, group, open, write_attrs, write_small,
    write_stage_file,
};
use super::sweep::{
    building_coordinates, case_coordinates, read_building_coordinates, read_case_coordinates,
};
use super::vars::{Codes, Data, Target, Trailing, Var, read_optional, write_declared};
use super::{H5Context, StoreError};
use crate::grid::{BuildingAxes, Grid};
use ndarray::ArrayD;
use std::path::Path;

stored_vars! {
    /// One zone's derived quantities, each shaped `[T_p, alpha…, mu…]` (in a building study
    /// `[storeys, stack_floor, T_p, …]`).
    #[derive(Debug, Clone, PartialEq)]
    pub struct TnewVars {
        u_stack_mean: f64 => "u_stack_mean", Case, "m",
            "mean over the motions of the peak structure displacement with the sliding stack",
            building "mean over the motions of the peak structure displacement with the sliding \
                      stack (a building: its roof's)";
        u_single_mean: f64 => "u_single_mean", Case, "m",
            "mean peak structure displacement with the stack as one block",
            building "mean peak structure displacement with the stack as one block (a building: \
                      its roof's)";
        u_rigid_mean: f64 => "u_rigid_mean", Case, "m",
            "mean peak structure displacement with the stack rigidly attached",
            building "mean peak structure displacement with the stack rigidly attached (a \
                      building: its roof's)";
        t_rigid: f64 => "T_rigid", Case, "s",
            "period with the stack rigidly attached, T_p·sqrt(1+α)",
            building "first-mode period with the stack rigidly attached";
        t_new: f64 => "T_new", Case, "s",
            "period whose mean 5 %-damped spectral displacement equals u_stack_mean (Section 7.1)",
            building "period whose mean 5 %-damped spectral displacement equals u_stack_mean / \
                      roof_participation (the first mode's equivalent SDOF)";
        drr_1: f64 => "DRR_1", Case, "1", "u_stack_mean / u_rigid_mean (Eq. 7)";
        drr_2: f64 => "DRR_2", Case, "1", "u_single_mean / u_rigid_mean (Eq. 8)";
        slides: f64 => "slides", Case, "1", "1 when some interface slips under some motion";
        flag: f64 => "T_new_flag", Case, "1",
            "how T_new was found (file attribute T_new_flag_codes)";
        /// Where `T_new` lies against `[T_p, T_rigid]` (codes in [`TnewMeta::band_flags`]).
        band: u8 => "T_new_band", Case, "", "where T_new lies against [T_p, T_rigid]";
    }
}

/// With `grid.aspect`: per case, the share of the motions under which the stack would start to
/// rock, shaped as [`TnewVars`]' variables.
pub const ROCKS_SHARE: Var = Var {
    name: "rocks_share",
    trailing: Trailing::Case,
    units: "1",
    long_name: "share of the motions under which the stack would start to rock (sweep.h5's \
                rocks_stack averaged): outside the sliding-only model where > 0",
    building_long_name: None,
    codes: Codes::Value,
};

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

/// The long name of every attached fraction's flag variable.
const FRACTION_FLAG: &str = "how the fraction was found: the root of its mean peak on a 0.1 \
                             scan (the one nearest the stuck share of several), the scan point \
                             nearest when none, no_slide when nothing slid";

stored_vars! {
    /// A building study's attached fractions of every case (docs/model.md, "The attached
    /// fraction") and the mean peaks they come from, each over the bare building; shaped as
    /// [`TnewVars`]' variables, the per-storey ones with a trailing `storey` axis of length
    /// `N_max` (NaN, and 255 for flags, above a building's roof). Each flag's codes are
    /// [`TnewMeta::lambda_flags`].
    #[derive(Debug, Clone, PartialEq)]
    pub struct AttachedVars {
        /// `V̄_stack`: with the sliding stack, over the bare building's weight.
        base_shear_stack_mean: f64 => "base_shear_stack_mean", Case, "1",
            "mean over the motions of the peak base shear over the bare building's weight, with \
             the sliding stack";
        /// `V̄(1)`: with the whole stack rigidly attached.
        base_shear_rigid_mean: f64 => "base_shear_rigid_mean", Case, "1",
            "the same with the stack rigidly attached (fraction 1)";
        /// `V̄(0)`: with the stack's mass absent (the building's own damping matrix).
        base_shear_bare_mean: f64 => "base_shear_bare_mean", Case, "1",
            "the same with the stack's mass absent (fraction 0)";
        /// `V̄_stack/V̄(0)` and `V̄_stack/V̄(1)`, unclamped.
        base_shear_ratio_bare: f64 => "base_shear_ratio_bare", Case, "1",
            "base_shear_stack_mean / base_shear_bare_mean (below 1: the sliding stack lowers the \
             base shear below the bare building's)";
        base_shear_ratio_rigid: f64 => "base_shear_ratio_rigid", Case, "1",
            "base_shear_stack_mean / base_shear_rigid_mean";
        /// The stuck mass share's mean over the motions.
        stuck_share_mean: f64 => "stuck_share_mean", Case, "1",
            "mean over the motions of the time average of the stack's mass moving with its floor, \
             over its mass (1: it never slid)";
        /// `λ`: the attached fraction of the base shear, unclamped.
        lambda: f64 => "lambda", Case, "1",
            "effective live-load fraction: the fraction of the stack which, rigidly attached \
             (below 0: removed), gives base_shear_stack_mean; unclamped (lambda_flag)";
        flag: u8 => "lambda_flag", Case, "", FRACTION_FLAG;
        /// The attached fraction of each storey's shear (storey 1's is `λ`).
        lambda_storey: f64 => "lambda_storey", Storey, "1",
            "the same for each storey's mean peak shear (storey 1: lambda)";
        lambda_storey_flag: u8 => "lambda_storey_flag", Storey, "", FRACTION_FLAG;
        /// The attached fraction of the overturning moment at the base.
        lambda_overturning: f64 => "lambda_overturning", Case, "1",
            "the same for the mean peak overturning moment at the base";
        lambda_overturning_flag: u8 => "lambda_overturning_flag", Case, "", FRACTION_FLAG;
        /// The code-format fraction.
        lambda_code: f64 => "lambda_code", Case, "1",
            "code-format fraction: (W + lambda·W_L)·Sa(T_1(lambda)) / ((W + W_L)·Sa(T_1,rigid)) \
             = base_shear_ratio_rigid, Sa the zone's mean 5 %-damped spectrum exactly at the \
             period";
        lambda_code_flag: u8 => "lambda_code_flag", Case, "", FRACTION_FLAG;
        /// The attached fraction of the roof's mean peak displacement (a building's `T_new` is
        /// the first-mode period with it attached).
        attached_fraction_roof: f64 => "attached_fraction_roof", Case, "1",
            "the fraction of the stack which, rigidly attached, gives the mean peak roof \
             displacement (a building of several storeys: T_new is T_1 with it attached)";
        attached_fraction_roof_flag: u8 => "attached_fraction_roof_flag", Case, "", FRACTION_FLAG;
        /// The earlier definition of a building's `T_new` (the roof's mean peak over the bare
        /// building's `Γ_1·φ_1,N`, read off the mean displacement spectrum), kept for one
        /// release.
        t_new_first_mode: f64 => "T_new_first_mode", Case, "s",
            "the earlier T_new of a building (kept for one release): the period whose mean \
             5 %-damped spectral displacement equals u_stack_mean / roof_participation";
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
    let levels: Vec<f64> = (1..=building.map_or(0, |b| b.max_storeys()))
        .map(|j| j as f64)
        .collect();
    let storey = (z.lambda.is_some())
        .then(|| coordinate(&g, "storey", &levels, "1", "storey (1 the lowest)"))
        .transpose()?;
    let mut chunk = vec![1; if building.is_some() { 3 } else { 1 }];
    chunk.extend(grid.case_shape());
    let trailing = |t: Trailing| match t {
        Trailing::Storey => storey.as_ref(),
        _ => None,
    };
    let given = |name: &str| match name {
        "T_new_band" => meta.band_flags,
        _ => meta.lambda_flags,
    };
    let to = Target {
        group: &g,
        building: building.is_some(),
        chunk: &chunk,
        scales: &scales,
        trailing: &trailing,
        given: &given,
    };
    write_declared(&to, &z.vars.data())?;
    if let Some(share) = &z.rocks_share {
        write_declared(&to, &[(&ROCKS_SHARE, Data::Values(share))])?;
    }
    if let Some(l) = &z.lambda {
        write_declared(&to, &l.data())?;
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
    let levels = axes.as_ref().map_or(0, BuildingAxes::max_storeys);
    let shape_of = |t: Trailing| {
        let mut s = shape.clone();
        if t == Trailing::Storey {
            s.push(levels);
        }
        s
    };
    let vars = TnewVars::read(&g, shape_of)?;
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
    let lambda = (axes.is_some())
        .then(|| AttachedVars::read(&g, shape_of))
        .transpose()?;
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
        rocks_share: read_optional(&g, ROCKS_SHARE.name, &shape)?,
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
