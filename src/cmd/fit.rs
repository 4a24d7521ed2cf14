//! `slidestack fit CONFIG`: the study's fourth stage.
//!
//! Reads `OUT/tnew.h5` (up to date with the config) and fits, per zone, the design equation for
//! `T_new` in two forms (`slidestack::fit`): the paper's (Eqs. 16–17, `b·e^d` reparameterised)
//! and a bounded logistic form between `T_p` and `T_rigid`. Every case with a finite `T_new`
//! enters. For each form: coefficients and R², R, RMSE, MSE, MAE on all cases and 5-fold
//! cross-validated; and the paper's own published Eqs. 16–17 evaluated on our `T_new` (zones
//! named III and V, two blocks). Writes `OUT/fit.h5` and the same numbers readable in
//! `OUT/fit.yaml`. Up to date (same fingerprint): nothing is done.

use super::sweep::prepare;
use anyhow::{Context, Result, bail};
use serde::Serialize;
use slidestack::fit::{Fitted, Form, Metrics, cross_validate, fit, metrics, paper_equation};
use slidestack::store::fingerprint::fingerprint;
use slidestack::store::h5::{attr_f64, attr_str, read_attr_str, write_1d, write_stage_file};
use slidestack::store::tnew::{read_fingerprint as read_tnew_fp, read_zone_tnew};
use slidestack::study::tnew::samples;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (YAML).
    pub config: PathBuf,
    /// Output directory [default: the config's output_dir].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

const FOLDS: usize = 5;

#[derive(Debug, Serialize)]
struct FormReport {
    form: Form,
    /// Parameter names and values.
    coefficients: Vec<(String, f64)>,
    all_cases: Metrics,
    cross_validated: Metrics,
}

#[derive(Debug, Serialize)]
struct ZoneReport {
    zone: String,
    cases: usize,
    forms: Vec<FormReport>,
    /// The paper's published equation for this zone on our T_new, when it applies.
    published: Option<Metrics>,
}

#[derive(Debug, Serialize)]
struct FitYaml {
    slidestack_version: String,
    fingerprint: String,
    features: Vec<String>,
    zones: Vec<ZoneReport>,
}

fn names(form: Form, features: &[String]) -> Vec<String> {
    match form {
        Form::Paper => features
            .iter()
            .map(|f| format!("a_{f}"))
            .chain(features.iter().map(|f| format!("c_{f}")))
            .chain(["B (= b·e^d)".to_string(), "e".to_string()])
            .collect(),
        Form::Bounded => features
            .iter()
            .map(|f| format!("w_{f}"))
            .chain(["w_0".to_string()])
            .collect(),
    }
}

pub fn run(args: Args) -> Result<()> {
    let stage = prepare(&args.config, args.out)?;
    let tnew_path = stage.out.join("tnew.h5");
    let Some(tnew_fp) = read_tnew_fp(&tnew_path) else {
        bail!(
            "{} is missing: run `slidestack tnew {}` first",
            tnew_path.display(),
            args.config.display()
        );
    };
    let sweep_fp = hdf5::File::open(&tnew_path)
        .ok()
        .and_then(|f| read_attr_str(&f, "sweep_fingerprint"));
    if sweep_fp.as_deref() != Some(stage.fingerprint.as_str()) {
        bail!(
            "{} is out of date: run `slidestack tnew {}`",
            tnew_path.display(),
            args.config.display()
        );
    }
    let fp = fingerprint(&[&tnew_fp, &format!("folds={FOLDS}")]);
    let path = stage.out.join("fit.h5");
    let yaml_path = stage.out.join("fit.yaml");
    if read_fp(&path).as_deref() == Some(fp.as_str()) && yaml_path.exists() {
        println!("fit: {} is up to date", path.display());
        return Ok(());
    }
    let n = stage.grid.blocks();
    let mut features = vec!["T_p".to_string()];
    features.extend((1..=n).map(|i| format!("mu_{i}")));
    features.extend((1..=n).map(|i| format!("alpha_{i}")));
    let mut zones = Vec::new();
    for zc in &stage.cfg.zones {
        let t = read_zone_tnew(&tnew_path, &zc.name, n)
            .with_context(|| format!("cannot read zone {} of {}", zc.name, tnew_path.display()))?;
        let data = samples(&stage.grid, &t.t_rigid, &t.t_new);
        let observed: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
        let mut forms = Vec::new();
        for form in [Form::Paper, Form::Bounded] {
            let f: Fitted = fit(form, &data)
                .with_context(|| format!("zone {}: {} form", zc.name, form.name()))?;
            let pred: Vec<f64> = data.iter().map(|s| f.predict(s)).collect();
            let cv = cross_validate(form, &data, FOLDS)?;
            let m = metrics(&observed, &pred);
            println!(
                "fit: zone {}: {:<7} R² {:.3}  R {:.3}  RMSE {:.3} s  MAE {:.3} s   ({FOLDS}-fold CV: R² {:.3}, RMSE {:.3} s)",
                zc.name,
                form.name(),
                m.r2,
                m.r,
                m.rmse,
                m.mae,
                cv.r2,
                cv.rmse
            );
            forms.push(FormReport {
                form,
                coefficients: names(form, &features).into_iter().zip(f.params).collect(),
                all_cases: m,
                cross_validated: cv,
            });
        }
        let published: Option<Vec<f64>> = data
            .iter()
            .map(|s| paper_equation(&zc.name, &s.x))
            .collect();
        let published = published.map(|p| metrics(&observed, &p));
        if let Some(m) = &published {
            println!(
                "fit: zone {}: published Eq. {} on our T_new: R² {:.3}  RMSE {:.3} s",
                zc.name,
                if zc.name == "III" { 16 } else { 17 },
                m.r2,
                m.rmse
            );
        }
        zones.push(ZoneReport {
            zone: zc.name.clone(),
            cases: data.len(),
            forms,
            published,
        });
    }
    let report = FitYaml {
        slidestack_version: env!("CARGO_PKG_VERSION").to_string(),
        fingerprint: fp.clone(),
        features,
        zones,
    };
    write_fit(&path, &report).with_context(|| format!("cannot write {}", path.display()))?;
    std::fs::write(&yaml_path, serde_yaml::to_string(&report)?)
        .with_context(|| format!("cannot write {}", yaml_path.display()))?;
    println!("fit: wrote {} and {}", path.display(), yaml_path.display());
    Ok(())
}

fn read_fp(path: &Path) -> Option<String> {
    let f = hdf5::File::open(path).ok()?;
    read_attr_str(&f, "fingerprint")
}

fn write_metrics(g: &hdf5::Location, prefix: &str, m: &Metrics) -> hdf5::Result<()> {
    for (k, v) in [
        ("r2", m.r2),
        ("r", m.r),
        ("rmse_s", m.rmse),
        ("mse_s2", m.mse),
        ("mae_s", m.mae),
        ("n", m.n as f64),
    ] {
        attr_f64(g, &format!("{prefix}{k}"), v)?;
    }
    Ok(())
}

fn write_fit(path: &Path, r: &FitYaml) -> hdf5::Result<()> {
    write_stage_file(
        path,
        "slidestack fit stage: design equations for T_new (see fit.yaml)",
        &r.fingerprint,
        |f| {
            attr_str(f, "features", &r.features.join(", "))?;
            for z in &r.zones {
                let g = f.create_group(&format!("zone_{}", z.zone))?;
                for fr in &z.forms {
                    let sub = g.create_group(match fr.form {
                        Form::Paper => "paper",
                        Form::Bounded => "bounded",
                    })?;
                    let values: Vec<f64> = fr.coefficients.iter().map(|c| c.1).collect();
                    let names: Vec<String> = fr.coefficients.iter().map(|c| c.0.clone()).collect();
                    let ds = write_1d(
                        &sub,
                        "coefficients",
                        &values,
                        "mixed (s, s per unit feature)",
                        "fitted coefficients",
                    )?;
                    attr_str(&ds, "names", &names.join(", "))?;
                    write_metrics(&sub, "", &fr.all_cases)?;
                    write_metrics(&sub, "cv_", &fr.cross_validated)?;
                }
                if let Some(m) = &z.published {
                    let sub = g.create_group("published")?;
                    write_metrics(&sub, "", m)?;
                }
            }
            Ok(())
        },
    )
}
