//! `run`, make and `status` run exactly the stages a config configures (`Study::configured`):
//! the IDA-only `configs/ida-quick.yaml` (no grid: motions, ida, report) and
//! `configs/mdof-ida-quick.yaml` (a one-case grid that names the IDA's frames, too small to fit:
//! no fit) both end in a report; make gives the same bytes as `run`; the least case count the
//! fit asks of a grid is the one at which the fit and its cross-validation stop refusing.

mod common;

use common::{ok, slidestack};
use slidestack::fit::{FitError, Form, Sample, cross_validate, fit};
use slidestack::study::equations::{FOLDS, cases_needed};
use std::path::{Path, PathBuf};

fn config(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn an_ida_only_config_runs_motions_ida_and_report_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config("ida-quick.yaml");
    let out = dir.path().join("out");
    let o = ok(slidestack(&["run", s(&cfg), "--out", s(&out)], "2"));
    let text = stdout(&o);
    assert!(
        text.contains("run: stages motions, ida, report\n"),
        "{text}"
    );
    assert_eq!(text.lines().last(), Some(s(&out.join("report/index.html"))));
    for absent in [
        "sweep.h5",
        "tnew.h5",
        "fit.h5",
        "fit.yaml",
        "report/design.html",
    ] {
        assert!(!out.join(absent).exists(), "{absent}");
    }
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    for part in [
        "spectra_III.svg",
        "spectra_V.svg",
        "ida.svg",
        "ida-fragility",
    ] {
        assert!(html.contains(part), "{part}");
    }
    // The report is up to date on a second run; `status` lists the same stages.
    let o = ok(slidestack(&["run", s(&cfg), "--out", s(&out)], "1"));
    assert!(stdout(&o).contains("report: ") && stdout(&o).contains("is up to date"));
    let o = ok(slidestack(
        &["status", s(&cfg), "--out", s(&out), "--format", "env"],
        "1",
    ));
    let env = stdout(&o);
    assert!(env.contains("STAGES=motions,ida,report\n"), "{env}");
    assert!(
        env.contains("REPORT=up_to_date\n") && !env.contains("SWEEP="),
        "{env}"
    );
    // A stage it does not configure is refused naming the file and the key, before any work.
    let o = slidestack(&["sweep", s(&cfg), "--out", s(&out)], "1");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("ida-quick.yaml") && err.contains("`grid`"),
        "{err}"
    );
}

#[test]
fn a_grid_too_small_to_fit_runs_every_stage_but_the_fit() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config("mdof-ida-quick.yaml");
    let out = dir.path().join("out");
    let o = ok(slidestack(&["run", s(&cfg), "--out", s(&out)], "2"));
    let text = stdout(&o);
    assert!(
        text.contains("run: stages motions, sweep, tnew, ida, report\n"),
        "{text}"
    );
    // One case × two frames of six features (T_1, μ_1, μ_2, α_1, α_2, z_stack); the count
    // `cases_needed` gives is checked against the fit itself below.
    let needed = format!("at least {} cases", cases_needed(6));
    assert!(
        text.contains("run: no fit: ") && text.contains(&needed),
        "{text}"
    );
    assert!(!out.join("fit.h5").exists() && !out.join("report/design.html").exists());
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    for part in [
        "No design equations and no design page",
        "building_period_III.svg",
        "ida.svg",
    ] {
        assert!(html.contains(part), "{part}");
    }
    let o = slidestack(&["fit", s(&cfg), "--out", s(&out)], "1");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("mdof-ida-quick.yaml") && err.contains(&needed) && err.contains("gives 2"),
        "{err}"
    );
}

/// Every study config shipped in `configs/` loads and configures the stages it is for (a new
/// config must be listed here); `status --format make` says which, as make reads them.
#[test]
fn every_shipped_study_config_configures_its_stages() {
    let want = [
        ("fema-p695-11.yaml", "motions report"),
        ("ida-quick.yaml", "motions ida report"),
        ("mdof-fema-rigid.yaml", "motions sweep tnew fit report"),
        ("mdof-fema-structure.yaml", "motions sweep tnew fit report"),
        ("mdof-floors-quick.yaml", "motions sweep tnew floors report"),
        ("mdof-ida-quick.yaml", "motions sweep tnew ida report"),
        ("mdof-quick.yaml", "motions sweep tnew fit report"),
        ("mdof-research.yaml", "motions sweep tnew fit report"),
        ("mdof-structure.yaml", "motions sweep tnew fit report"),
        ("mdof.yaml", "motions sweep tnew fit report"),
        ("paper.yaml", "motions sweep tnew fit report"),
        ("quick.yaml", "motions sweep tnew fit report"),
        ("yielding.yaml", "motions sweep tnew fit ida report"),
    ];
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut studies: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let text = std::fs::read_to_string(p).unwrap_or_default();
            text.lines().any(|l| l.starts_with("zones:"))
        })
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    studies.sort();
    let listed: Vec<&str> = want.iter().map(|w| w.0).collect();
    assert_eq!(studies, listed, "the study configs of configs/");
    for (name, stages) in want {
        let o = ok(slidestack(
            &["status", s(&config(name)), "--format", "make"],
            "1",
        ));
        let line = format!("\nSTAGES := {stages}\n");
        assert!(stdout(&o).contains(&line), "{name}: {}", stdout(&o));
    }
}

/// make (pipelines/paper.mk) on the IDA-only config: the configured stages only, the same bytes
/// as `run`, and a second make rewrites nothing.
#[test]
fn make_runs_the_configured_stages_with_the_bytes_of_run() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config("ida-quick.yaml");
    let by_run = dir.path().join("run");
    ok(slidestack(&["run", s(&cfg), "--out", s(&by_run)], "2"));
    let mk = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/paper.mk");
    let make = || {
        let o = std::process::Command::new("make")
            .args(["-f", s(&mk)])
            .arg(format!("CONFIG={}", s(&cfg)))
            .arg("OUT=out")
            .arg(format!("SLIDESTACK={}", env!("CARGO_BIN_EXE_slidestack")))
            .current_dir(dir.path())
            .env("RAYON_NUM_THREADS", "2")
            .output()
            .expect("make (scripts/install-deps.sh --test installs it)");
        ok(o)
    };
    let o = make();
    let text = stdout(&o);
    assert!(
        !text.contains(" sweep ") && text.contains(" ida "),
        "{text}"
    );
    let by_make = dir.path().join("out");
    let stages = std::fs::read_to_string(by_make.join("make/stages.mk")).unwrap();
    assert!(
        stages.contains("STAGES := motions ida report\n"),
        "{stages}"
    );
    let files = |d: &Path| common::output_files(d, &["make"]);
    let (a, b) = (files(&by_run), files(&by_make));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "the same files"
    );
    for (path, f) in &a {
        assert!(f.bytes == b[path].bytes, "{} differs", path.display());
    }
    make();
    let again = files(&by_make);
    for (path, f) in &b {
        assert_eq!(
            f.inode,
            again[path].inode,
            "{} was rewritten",
            path.display()
        );
    }
}

/// make's plan for a config with a `floor_spectra:` section (`make -n`: what it would run)
/// includes the floors stage, before the report.
#[test]
fn make_plans_the_floors_stage_where_the_config_has_one() {
    let dir = tempfile::tempdir().unwrap();
    let mk = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/paper.mk");
    let o = std::process::Command::new("make")
        .args(["-n", "-f", s(&mk)])
        .arg(format!("CONFIG={}", s(&config("mdof-floors-quick.yaml"))))
        .arg("OUT=out")
        .arg(format!("SLIDESTACK={}", env!("CARGO_BIN_EXE_slidestack")))
        .current_dir(dir.path())
        .output()
        .expect("make (scripts/install-deps.sh --test installs it)");
    let text = stdout(&ok(o));
    let at = |stage: &str| {
        text.find(&format!("slidestack' {stage} "))
            .unwrap_or_else(|| panic!("{stage}: {text}"))
    };
    assert!(
        at("tnew") < at("floors") && at("floors") < at("report"),
        "{text}"
    );
    assert!(!text.contains("slidestack' fit "), "{text}");
}

/// `cases_needed(k)` against the fit itself: with one case fewer every form refuses (in the
/// whole fit or a fold of its cross-validation) for too few cases; with that many, some form
/// does not.
#[test]
fn the_least_case_count_is_where_the_fit_stops_refusing() {
    let mut rng = common::Rng::new(35);
    for k in [3, 5, 6, 7] {
        let needed = cases_needed(k);
        let data = |n: usize, rng: &mut common::Rng| -> Vec<Sample> {
            (0..n)
                .map(|_| {
                    let x: Vec<f64> = (0..k).map(|_| rng.range(0.05, 2.0)).collect();
                    let t_rigid_s = x[0];
                    Sample {
                        t_new_s: t_rigid_s * rng.range(1.0, 1.3),
                        t_rigid_s,
                        x,
                    }
                })
                .collect()
        };
        let too_few = |form: Form, d: &[Sample]| {
            let whole = matches!(fit(form, d), Err(FitError::TooFew { .. }));
            whole || matches!(cross_validate(form, d, FOLDS), Err(FitError::TooFew { .. }))
        };
        let below = data(needed - 1, &mut rng);
        assert!(
            Form::FOR_T_NEW.iter().all(|&f| too_few(f, &below)),
            "k {k}: {} cases",
            needed - 1
        );
        let at = data(needed, &mut rng);
        assert!(
            Form::FOR_T_NEW.iter().any(|&f| !too_few(f, &at)),
            "k {k}: {needed} cases"
        );
    }
}
