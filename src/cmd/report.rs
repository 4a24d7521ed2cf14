//! `slidestack report CONFIG`: the study's last stage.
//!
//! Reads `motions.h5`, `tnew.h5` and `fit.h5` under `OUT` and writes `OUT/report/index.html`
//! with SVG figures beside it: per zone the target and mean spectra, `DRR_1` and `T_new` against
//! `T_p`, the fit's predicted against computed `T_new`; a displacement history of the
//! Section 7.1 case (stack, single block, rigid) under the zone's first motion; a Table 2-like
//! comparison and a Table 3-like table of fit statistics next to the paper's. Always rebuilt (it
//! takes well under a second).

use super::sweep::{load_motions, prepare};
use anyhow::{Context, Result};
use slidestack::dynamics::{ExactOptions, Ground, System, SystemSpec, simulate_exact};
use slidestack::fit::{Fitted, Form};
use slidestack::report::{Series, chart, page, table};
use slidestack::store::h5::{read_f64, read_group_attr};
use slidestack::store::motions::read_zone_spectra;
use slidestack::study::sweep::rigid_spec;
use slidestack::study::tnew::samples;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The paper's Table 3 (fit quality of Eqs. 16–17): R², R, RMSE, MSE, MAE.
const PAPER_TABLE_3: [(&str, [f64; 5]); 2] = [
    ("III", [0.985, 0.992, 0.094, 0.009, 0.082]),
    ("V", [0.969, 0.985, 0.1, 0.01, 0.09]),
];

/// The paper's Table 2 (record #11, T_p 0.5 s, α 0.5/0.5, μ 0.3/0.1): single block and stack,
/// peak structure displacement, m.
const PAPER_TABLE_2: [(&str, f64, f64); 2] = [("III", 0.028, 0.021), ("V", 0.046, 0.035)];

fn peak_case(
    rec: &slidestack::motion::Record,
    period_s: f64,
    alpha: &[f64],
    mu: &[f64],
    history: bool,
) -> Result<slidestack::dynamics::Response> {
    simulate_spec(rec, &SystemSpec::new(period_s, alpha, mu), history)
}

fn simulate_spec(
    rec: &slidestack::motion::Record,
    spec: &SystemSpec,
    history: bool,
) -> Result<slidestack::dynamics::Response> {
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let sys = System::new(spec)?;
    Ok(simulate_exact(
        &sys,
        &ground,
        &ExactOptions {
            history,
            ..ExactOptions::default()
        },
    )?)
}

pub fn run(args: Args) -> Result<()> {
    let stage = prepare(&args.config, args.out)?;
    let out = &stage.out;
    let dir = out.join("report");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let motions = load_motions(&stage)?;
    let (mh5, th5, fh5) = (
        out.join("motions.h5"),
        out.join("tnew.h5"),
        out.join("fit.h5"),
    );
    let grid = &stage.grid;
    let n = grid.blocks();
    let per = grid.cases_per_unit();
    let mut sections = Vec::new();
    let svg = |name: &str, text: String| -> Result<String> {
        let p = dir.join(name);
        std::fs::write(&p, text).with_context(|| format!("cannot write {}", p.display()))?;
        Ok(format!("<img src='{name}' alt='{name}'>"))
    };
    // The Section 7.1 case for two blocks; for other stacks, equal blocks of total 1 and μ
    // falling upward.
    let (case_alpha, case_mu) = if n == 2 {
        (vec![0.5, 0.5], vec![0.2, 0.1])
    } else {
        (
            vec![1.0 / n as f64; n],
            (1..=n).map(|i| 0.2 / i as f64).collect(),
        )
    };
    let mut table2 = Vec::new();
    let mut table3 = Vec::new();
    for (z, zc) in stage.cfg.zones.iter().enumerate() {
        let group = format!("zone_{}", zc.name);
        let (periods, target, mean) = read_zone_spectra(&mh5, &zc.name)?;
        let psa = read_f64(&mh5, &group, "psa_g")?;
        let mut series: Vec<Series> = psa
            .chunks(periods.len())
            .map(|s| Series::faint(periods.clone(), s.to_vec()))
            .collect();
        series.push(Series::line("target", periods.clone(), target));
        series.push(Series::line("mean of the motions", periods.clone(), mean));
        let img = svg(
            &format!("spectra_{}.svg", zc.name),
            chart(
                &format!("Zone {}: 5 %-damped PSA", zc.name),
                "T (s)",
                "PSA (g)",
                &series,
            ),
        )?;
        sections.push((format!("Zone {}: target and motions", zc.name), img));

        // Displacement history of the case under the zone's first motion.
        let rec = &motions[z][0];
        let total: f64 = case_alpha.iter().sum();
        let stack = peak_case(rec, 1.0, &case_alpha, &case_mu, true)?;
        let single = peak_case(rec, 1.0, &[total], &case_mu[..1], true)?;
        let rigid = simulate_spec(rec, &rigid_spec(1.0, total, 0.05), true)?;
        let hist = |r: &slidestack::dynamics::Response, label: &str| {
            let h = r.history.as_ref().expect("history requested");
            let u: Vec<f64> = h
                .displacement_m
                .chunks(h.bodies)
                .map(|row| row[0] * 100.0)
                .collect();
            Series::line(label, h.time_s.clone(), u)
        };
        let img = svg(
            &format!("history_{}.svg", zc.name),
            chart(
                &format!(
                    "Zone {}, {}: T_p = 1 s, α = {:?}, μ = {:?}",
                    zc.name, rec.name, case_alpha, case_mu
                ),
                "t (s)",
                "structure displacement (cm)",
                &[
                    hist(&stack, "stack"),
                    hist(&single, "single block"),
                    hist(&rigid, "rigid"),
                ],
            ),
        )?;
        sections.push((format!("Zone {}: displacement history", zc.name), img));

        // Table 2-like: T_p 0.5 s, α 0.5/0.5, μ 0.3/0.1 (two blocks), every motion.
        if n == 2 {
            let mut single_stack = Vec::new();
            for rec in &motions[z] {
                single_stack.push((
                    peak_case(rec, 0.5, &[1.0], &[0.3], false)?.peak_displacement_m,
                    peak_case(rec, 0.5, &[0.5, 0.5], &[0.3, 0.1], false)?.peak_displacement_m,
                ));
            }
            let m = single_stack.len() as f64;
            let (first_s, first_k) = single_stack[0];
            let s_sum: f64 = single_stack.iter().map(|p| p.0).sum();
            let k_sum: f64 = single_stack.iter().map(|p| p.1).sum();
            let paper = PAPER_TABLE_2.iter().find(|p| p.0 == zc.name);
            table2.push(vec![
                zc.name.clone(),
                format!("{first_s:.4} / {first_k:.4}"),
                format!("{:.4} / {:.4}", s_sum / m, k_sum / m),
                paper.map_or("–".into(), |p| format!("{:.3} / {:.3}", p.1, p.2)),
            ]);
        }

        // DRR_1 and T_new against T_p: middle α, smallest μ_2, every μ_1.
        let t_new = read_f64(&th5, &group, "T_new")?;
        let drr = read_f64(&th5, &group, "DRR_1")?;
        let t_rigid = read_f64(&th5, &group, "T_rigid")?;
        let shape = grid.case_shape();
        let pick_case = |mu1: usize| -> usize {
            // Index within a unit: α at the middle of each list, μ_1 = mu1, other μ first.
            let mut idx = 0;
            for (d, &len) in shape.iter().enumerate() {
                let v = if d < n {
                    len / 2
                } else if d == n {
                    mu1
                } else {
                    0
                };
                idx = idx * len + v;
            }
            idx
        };
        let (alpha_mid, _) = grid.case(pick_case(0));
        let mut drr_series = Vec::new();
        let mut tn_series = Vec::new();
        for (j, mu1) in grid.mu[0].iter().enumerate() {
            let c = pick_case(j);
            let col = |v: &[f64]| {
                (0..grid.periods_s.len())
                    .map(|p| v[p * per + c])
                    .collect::<Vec<_>>()
            };
            drr_series.push(Series::line(
                format!("μ_1 = {mu1}"),
                grid.periods_s.clone(),
                col(&drr),
            ));
            tn_series.push(Series::line(
                format!("μ_1 = {mu1}"),
                grid.periods_s.clone(),
                col(&t_new),
            ));
            if j + 1 == grid.mu[0].len() {
                tn_series.push(Series::line(
                    "T_rigid",
                    grid.periods_s.clone(),
                    col(&t_rigid),
                ));
                tn_series.push(Series::line(
                    "T_p",
                    grid.periods_s.clone(),
                    grid.periods_s.clone(),
                ));
            }
        }
        let what = format!(
            "α = {alpha_mid:?}, μ_2 = {}",
            grid.mu.get(1).map_or(f64::NAN, |m| m[0])
        );
        let img = svg(
            &format!("drr_{}.svg", zc.name),
            chart(
                &format!("Zone {}: DRR_1 ({what})", zc.name),
                "T_p (s)",
                "DRR_1",
                &drr_series,
            ),
        )?;
        let img2 = svg(
            &format!("tnew_{}.svg", zc.name),
            chart(
                &format!("Zone {}: T_new ({what})", zc.name),
                "T_p (s)",
                "T (s)",
                &tn_series,
            ),
        )?;
        sections.push((
            format!("Zone {}: DRR and T_new against T_p", zc.name),
            format!("{img}{img2}"),
        ));

        // Fit: predicted against computed, and Table 3-like rows.
        let mut fit_series = Vec::new();
        for (form, name) in [(Form::Paper, "paper"), (Form::Bounded, "bounded")] {
            let params = read_f64(&fh5, &format!("{group}/{name}"), "coefficients")?;
            let f = Fitted { form, params };
            let (mut xs, mut ys) = (Vec::new(), Vec::new());
            for s in samples(grid, &t_rigid, &t_new) {
                xs.push(s.t_new_s);
                ys.push(f.predict(&s));
            }
            fit_series.push(Series::points(format!("{name} form"), xs, ys));
            let g = format!("{group}/{name}");
            let a = |k: &str| read_group_attr(&fh5, &g, k).map(|v| format!("{v:.3}"));
            table3.push(vec![
                zc.name.clone(),
                format!("{name} (ours)"),
                a("r2")?,
                a("r")?,
                a("rmse_s")?,
                a("mse_s2")?,
                a("mae_s")?,
                format!("{} / {}", a("cv_r2")?, a("cv_rmse_s")?),
            ]);
        }
        if let Ok(r2) = read_group_attr(&fh5, &format!("{group}/published"), "r2") {
            let g = format!("{group}/published");
            let a = |k: &str| read_group_attr(&fh5, &g, k).map(|v| format!("{v:.3}"));
            table3.push(vec![
                zc.name.clone(),
                "published Eq. on our T_new".into(),
                format!("{r2:.3}"),
                a("r")?,
                a("rmse_s")?,
                a("mse_s2")?,
                a("mae_s")?,
                "–".into(),
            ]);
        }
        if let Some((_, p)) = PAPER_TABLE_3.iter().find(|p| p.0 == zc.name) {
            table3.push(vec![
                zc.name.clone(),
                "paper Table 3".into(),
                format!("{:.3}", p[0]),
                format!("{:.3}", p[1]),
                format!("{:.3}", p[2]),
                format!("{:.3}", p[3]),
                format!("{:.3}", p[4]),
                "–".into(),
            ]);
        }
        let lo = grid.periods_s[0];
        fit_series.push(Series::line("1:1", vec![lo, 4.0], vec![lo, 4.0]));
        let img = svg(
            &format!("fit_{}.svg", zc.name),
            chart(
                &format!("Zone {}: design equation", zc.name),
                "computed T_new (s)",
                "predicted T_new (s)",
                &fit_series,
            ),
        )?;
        sections.push((
            format!(
                "Zone {}: design equation, predicted against computed",
                zc.name
            ),
            img,
        ));
    }
    if !table2.is_empty() {
        sections.push((
            "Table 2-like: peak structure displacement (m), single block / stack".into(),
            "<p>T_p = 0.5 s, α = 0.5/0.5, μ = 0.3/0.1. The paper's column is its record #11; ours are \
             the zone's first motion and the mean over its motions.</p>"
                .to_string()
                + &table(&["zone", "first motion", "mean of the motions", "paper (record #11)"], &table2),
        ));
    }
    sections.push((
        "Table 3-like: fit quality".into(),
        table(
            &[
                "zone",
                "equation",
                "R²",
                "R",
                "RMSE (s)",
                "MSE (s²)",
                "MAE (s)",
                "5-fold CV R² / RMSE",
            ],
            &table3,
        ),
    ));
    let html = page(
        &format!("slidestack report: {}", args.config.display()),
        &sections,
    );
    let index = dir.join("index.html");
    std::fs::write(&index, html).with_context(|| format!("cannot write {}", index.display()))?;
    println!("report: wrote {}", index.display());
    Ok(())
}
