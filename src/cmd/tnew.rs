//! `slidestack tnew CONFIG`: the study's third stage.
//!
//! Reads `OUT/sweep.h5` (which must be up to date with the config and `motions.h5`) and the
//! zone's motions from `OUT/motions.h5`. Writes `OUT/tnew.h5` (layout in
//! `slidestack::store::tnew`): per zone and case the mean peak displacements over the motions,
//! `T_rigid`, `T_new` read off the zone's mean 5 %-damped displacement spectrum (Section 7.1,
//! rule for several crossings in `slidestack::study::tnew`), whether anything slid, `DRR_1` and
//! `DRR_2`. Up to date (same fingerprint): nothing is done.

use super::sweep::{load_motions, prepare};
use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use slidestack::store::fingerprint::fingerprint;
use slidestack::store::sweep::{read_fingerprint as read_sweep_fp, read_zone_sweep};
use slidestack::store::tnew::{ZoneTnew, read_fingerprint, write_tnew};
use slidestack::study::sweep::rigid_spec;
use slidestack::study::tnew::{TnewFlag, period_at_displacement};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Step of the period grid of the mean displacement spectrum, s.
const SD_STEP_S: f64 = 0.005;

pub fn run(args: Args) -> Result<()> {
    let stage = prepare(&args.config, args.out)?;
    let sweep_path = stage.out.join("sweep.h5");
    if read_sweep_fp(&sweep_path).as_deref() != Some(stage.fingerprint.as_str()) {
        bail!(
            "{} is missing or out of date with {}: run `slidestack sweep {}` first",
            sweep_path.display(),
            args.config.display(),
            args.config.display()
        );
    }
    let fp = fingerprint(&[&stage.fingerprint, &format!("sd_step_s={SD_STEP_S}")]);
    let path = stage.out.join("tnew.h5");
    if read_fingerprint(&path).as_deref() == Some(fp.as_str()) {
        println!("tnew: {} is up to date", path.display());
        return Ok(());
    }
    let motions = load_motions(&stage)?;
    let grid = &stage.grid;
    let cases = grid.periods_s.len() * grid.cases_per_unit();
    let n = grid.blocks();
    // The spectrum must reach past every T_rigid of the grid.
    let alpha_max: f64 = grid
        .alpha
        .iter()
        .map(|a| a.iter().copied().fold(0.0, f64::max))
        .sum();
    let t_max = grid.periods_s.last().copied().unwrap_or(1.0) * (1.0 + alpha_max).sqrt() * 1.5;
    let steps = (t_max.max(4.0) / SD_STEP_S).ceil() as usize;
    let period_sd_s: Vec<f64> = (1..=steps).map(|k| k as f64 * SD_STEP_S).collect();
    let mut zones = Vec::new();
    for (z, zc) in stage.cfg.zones.iter().enumerate() {
        let sw = read_zone_sweep(&sweep_path, &zc.name, grid)
            .with_context(|| format!("cannot read zone {} of {}", zc.name, sweep_path.display()))?;
        let m = sw.motions.len();
        let spectra = motions[z]
            .par_iter()
            .map(|r| {
                slidestack::spectrum::response_spectrum(
                    &r.accel_mps2(1.0),
                    r.dt_s,
                    &period_sd_s,
                    0.05,
                )
                .map(|s| s.sd_m())
            })
            .collect::<Result<Vec<_>, _>>()?;
        let sd_mean_m: Vec<f64> = (0..period_sd_s.len())
            .map(|p| spectra.iter().map(|s| s[p]).sum::<f64>() / m as f64)
            .collect();
        let mean = |v: &[f64], c: usize| (0..m).map(|k| v[k * cases + c]).sum::<f64>() / m as f64;
        let mut t = ZoneTnew {
            name: zc.name.clone(),
            target: zc.target.clone(),
            period_sd_s: period_sd_s.clone(),
            sd_mean_m: sd_mean_m.clone(),
            ..ZoneTnew::default()
        };
        for c in 0..cases {
            let (us, ui, ur) = (
                mean(&sw.u_stack, c),
                mean(&sw.u_single, c),
                mean(&sw.u_rigid, c),
            );
            let (tp, alpha, _) = grid.point(c);
            let t_rigid = rigid_spec(tp, alpha.iter().sum(), grid.damping).period_s;
            let slides = (0..m).any(|k| {
                sw.slip_peak[(k * cases + c) * n..(k * cases + c + 1) * n]
                    .iter()
                    .any(|&s| s > 0.0)
            });
            let (t_new, flag) = if slides {
                period_at_displacement(&period_sd_s, &sd_mean_m, us, t_rigid)
            } else {
                (t_rigid, TnewFlag::NoSlip)
            };
            t.u_stack_mean.push(us);
            t.u_single_mean.push(ui);
            t.u_rigid_mean.push(ur);
            t.t_rigid.push(t_rigid);
            t.t_new.push(t_new);
            t.drr_1.push(us / ur);
            t.drr_2.push(ui / ur);
            t.slides.push(if slides { 1.0 } else { 0.0 });
            t.flag.push(f64::from(flag as u8));
        }
        let outside = t.flag.iter().filter(|&&f| f == 2.0).count();
        let several = t.flag.iter().filter(|&&f| f == 1.0).count();
        println!(
            "tnew: zone {}: {cases} cases, {} slide; T_new from several crossings: {several}, outside the spectrum: {outside}",
            zc.name,
            t.slides.iter().filter(|&&s| s == 1.0).count()
        );
        zones.push(t);
    }
    write_tnew(&path, &fp, &stage.fingerprint, grid, &zones)
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!("tnew: wrote {}", path.display());
    Ok(())
}
