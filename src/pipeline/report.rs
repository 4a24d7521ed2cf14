//! The report stage: `OUT/report/index.html` with SVG figures beside it, from `motions.h5`,
//! `tnew.h5` and `fit.yaml`: per zone the target and mean spectra, `DRR_1` and `T_new` against
//! `T_p`, the fit's predicted against computed `T_new`; a displacement history of the
//! Section 7.1 case (stack, single block, rigid) under the zone's first motion; a Table 2-like
//! comparison and a Table 3-like table of fit statistics next to the paper's. Every simulation
//! uses the study's own physics ([`crate::study::sweep::Physics`]). The directory is replaced
//! as a whole ([`crate::store::report`]).
//!
//! Fingerprint: the fit's and the motions' (which carry everything upstream), and the report's
//! own version.

use super::{Outcome, PipelineError, Session, StageId};
use crate::dynamics::{ExactOptions, Ground, ModelError, Response, SimError, System, SystemSpec};
use crate::fit::Fitted;
use crate::motion::Record;
use crate::report::{Series, chart, page, table};
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::read_fit;
use crate::store::motions::read_zone_spectra;
use crate::store::report::write_report_dir;
use crate::store::tnew::read_zone_tnew;
use crate::study::cases::{PAPER_TABLE_2, PAPER_TABLE_3, SECTION_7_1, TABLE_2};
use crate::study::tnew::samples;
use thiserror::Error;

/// Changes when the report's contents change.
const REPORT_VERSION: &str = "report-1";

#[derive(Debug, Error)]
pub enum ReportError {
    #[error("the report's case {case}: {source}")]
    Model { case: String, source: ModelError },
    #[error("the report's case {case} under {motion}: {source}")]
    Simulation {
        case: String,
        motion: String,
        source: SimError,
    },
}

/// The fingerprint the report must carry.
pub fn fingerprint(fit_fingerprint: &str, motions_fingerprint: &str) -> String {
    hash_parts(&[fit_fingerprint, motions_fingerprint, REPORT_VERSION])
}

fn simulate(rec: &Record, spec: &SystemSpec, history: bool) -> Result<Response, ReportError> {
    let case = format!(
        "T_p {} s, α {:?}, μ {:?}",
        spec.period_s, spec.alpha, spec.mu
    );
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let sys = System::new(spec).map_err(|source| ReportError::Model {
        case: case.clone(),
        source,
    })?;
    crate::dynamics::simulate_exact(
        &sys,
        &ground,
        &ExactOptions {
            history,
            ..ExactOptions::default()
        },
    )
    .map_err(|source| ReportError::Simulation {
        case,
        motion: rec.name.clone(),
        source,
    })
}

/// Builds the report.
pub fn build(s: &Session) -> Result<Outcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Report;
    let grid = study.grid(me)?;
    let physics = study.physics();
    let motions = super::sweep::load_motions(study)?;
    let (mh5, th5, fyaml) = (
        study.path("motions.h5"),
        study.path("tnew.h5"),
        study.path("fit.yaml"),
    );
    let fit = read_fit(&fyaml)?.ok_or_else(|| StoreError::corrupt(&fyaml, "is missing"))?;
    let n = grid.blocks();
    let per = grid.cases_per_unit();
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    let mut sections = Vec::new();
    let mut svg = |name: String, text: String| -> String {
        let img = format!("<img src='{name}' alt='{name}'>");
        files.push((name, text.into_bytes()));
        img
    };
    // The Section 7.1 case for two blocks; for other stacks, equal blocks of total 1 and μ
    // falling upward.
    let (case_alpha, case_mu) = if n == 2 {
        (SECTION_7_1.alpha.to_vec(), SECTION_7_1.mu.to_vec())
    } else {
        (
            vec![1.0 / n as f64; n],
            (1..=n).map(|i| 0.2 / i as f64).collect(),
        )
    };
    let tp = SECTION_7_1.period_s;
    let mut table2 = Vec::new();
    let mut table3 = Vec::new();
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let spectra = read_zone_spectra(&mh5, &zc.name)?;
        let periods = &spectra.periods_s;
        let mut series: Vec<Series> = spectra
            .psa_g
            .rows()
            .into_iter()
            .map(|s| Series::faint(periods.clone(), s.to_vec()))
            .collect();
        series.push(Series::line(
            "target",
            periods.clone(),
            spectra.target_psa_g.clone(),
        ));
        series.push(Series::line(
            "mean of the motions",
            periods.clone(),
            spectra.mean_psa_g.clone(),
        ));
        let img = svg(
            format!("spectra_{}.svg", zc.name),
            chart(
                &format!("Zone {}: 5 %-damped PSA", zc.name),
                "T (s)",
                "PSA (g)",
                &series,
            ),
        );
        sections.push((format!("Zone {}: target and motions", zc.name), img));

        // Displacement history of the case under the zone's first motion.
        let rec = &motions[z][0];
        let total: f64 = case_alpha.iter().sum();
        let stack = simulate(rec, &physics.stack(tp, &case_alpha, &case_mu), true)?;
        let single = simulate(rec, &physics.single(tp, total, case_mu[0]), true)?;
        let rigid = simulate(rec, &physics.rigid(tp, total), true)?;
        let hist = |r: &Response, label: &str| {
            let h = r.history.as_ref().expect("history requested");
            let u: Vec<f64> = h
                .displacement_m
                .chunks(h.bodies)
                .map(|row| row[0] * 100.0)
                .collect();
            Series::line(label, h.time_s.clone(), u)
        };
        let img = svg(
            format!("history_{}.svg", zc.name),
            chart(
                &format!(
                    "Zone {}, {}: T_p = {tp} s, α = {case_alpha:?}, μ = {case_mu:?}",
                    zc.name, rec.name
                ),
                "t (s)",
                "structure displacement (cm)",
                &[
                    hist(&stack, "stack"),
                    hist(&single, "single block"),
                    hist(&rigid, "rigid"),
                ],
            ),
        );
        sections.push((format!("Zone {}: displacement history", zc.name), img));

        // Table 2-like (two blocks), every motion.
        if n == 2 {
            let c = TABLE_2;
            let mut single_stack = Vec::new();
            for rec in &motions[z] {
                single_stack.push((
                    simulate(
                        rec,
                        &physics.single(c.period_s, c.alpha_total(), c.mu[0]),
                        false,
                    )?
                    .peak_displacement_m,
                    simulate(rec, &physics.stack(c.period_s, c.alpha, c.mu), false)?
                        .peak_displacement_m,
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
        let (_, t) = read_zone_tnew(&th5, &zc.name, n)?;
        let flat = |a: &ndarray::ArrayD<f64>| a.iter().copied().collect::<Vec<f64>>();
        let (t_new, drr, t_rigid) = (
            flat(&t.vars.t_new),
            flat(&t.vars.drr_1),
            flat(&t.vars.t_rigid),
        );
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
            format!("drr_{}.svg", zc.name),
            chart(
                &format!("Zone {}: DRR_1 ({what})", zc.name),
                "T_p (s)",
                "DRR_1",
                &drr_series,
            ),
        );
        let img2 = svg(
            format!("tnew_{}.svg", zc.name),
            chart(
                &format!("Zone {}: T_new ({what})", zc.name),
                "T_p (s)",
                "T (s)",
                &tn_series,
            ),
        );
        sections.push((
            format!("Zone {}: DRR and T_new against T_p", zc.name),
            format!("{img}{img2}"),
        ));

        // Fit: predicted against computed, and Table 3-like rows.
        let zf = fit
            .zones
            .iter()
            .find(|f| f.zone == zc.name)
            .ok_or_else(|| StoreError::corrupt(&fyaml, format!("has no zone {}", zc.name)))?;
        let mut fit_series = Vec::new();
        let f3 = |v: f64| format!("{v:.3}");
        for ff in &zf.forms {
            let f = Fitted {
                form: ff.form,
                params: ff.coefficients.iter().map(|c| c.1).collect(),
            };
            let (mut xs, mut ys) = (Vec::new(), Vec::new());
            for smp in samples(grid, &t_rigid, &t_new) {
                xs.push(smp.t_new_s);
                ys.push(f.predict(&smp));
            }
            let name = ff.form.name();
            fit_series.push(Series::points(format!("{name} form"), xs, ys));
            let (m, cv) = (&ff.all_cases, &ff.cross_validated);
            table3.push(vec![
                zc.name.clone(),
                format!("{name} (ours)"),
                f3(m.r2),
                f3(m.r),
                f3(m.rmse),
                f3(m.mse),
                f3(m.mae),
                format!("{} / {}", f3(cv.r2), f3(cv.rmse)),
            ]);
        }
        if let Some(m) = &zf.published {
            table3.push(vec![
                zc.name.clone(),
                "published Eq. on our T_new".into(),
                f3(m.r2),
                f3(m.r),
                f3(m.rmse),
                f3(m.mse),
                f3(m.mae),
                "–".into(),
            ]);
        }
        if let Some((_, p)) = PAPER_TABLE_3.iter().find(|p| p.0 == zc.name) {
            let mut row = vec![zc.name.clone(), "paper Table 3".into()];
            row.extend(p.iter().map(|&v| f3(v)));
            row.push("–".into());
            table3.push(row);
        }
        let lo = grid.periods_s[0];
        fit_series.push(Series::line("1:1", vec![lo, 4.0], vec![lo, 4.0]));
        let img = svg(
            format!("fit_{}.svg", zc.name),
            chart(
                &format!("Zone {}: design equation", zc.name),
                "computed T_new (s)",
                "predicted T_new (s)",
                &fit_series,
            ),
        );
        sections.push((
            format!(
                "Zone {}: design equation, predicted against computed",
                zc.name
            ),
            img,
        ));
    }
    if !table2.is_empty() {
        let c = TABLE_2;
        sections.push((
            "Table 2-like: peak structure displacement (m), single block / stack".into(),
            format!(
                "<p>T_p = {} s, α = {:?}, μ = {:?}. The paper's column is its record #11; ours \
                 are the zone's first motion and the mean over its motions.</p>",
                c.period_s, c.alpha, c.mu
            ) + &table(
                &[
                    "zone",
                    "first motion",
                    "mean of the motions",
                    "paper (record #11)",
                ],
                &table2,
            ),
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
        &format!("slidestack report: {}", study.config_path.display()),
        &sections,
    );
    files.push(("index.html".into(), html.into_bytes()));
    let dir = study.path("report");
    write_report_dir(&dir, study.fingerprint(me)?, &files)?;
    Ok(Outcome::Wrote(vec![dir.join("index.html")]))
}
