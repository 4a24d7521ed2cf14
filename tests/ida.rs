//! The IDA stage end to end on `configs/ida-quick.yaml`: it runs, a rerun is skipped, a
//! `kill -9` then a rerun gives the same bytes, so does one thread against two, xarray reads the
//! labelled dimensions; shards, a killed shard and a damaged unit give the unsharded bytes; bad
//! `ida:` keys are refused before any work; the report shows the IDA
//! and needs `ida.h5`. And hunt & fill on a bare bilinear SDOF, whose response is homogeneous in
//! the intensity (docs/model.md, "For a study stage").

mod common;

use common::{ok, shards, slidestack};

use slidestack::dynamics::{ExactOptions, Ground, System, SystemSpec, Yielding, simulate_exact};
use slidestack::ida::trace::{HuntFill, hunt_fill};
use std::path::{Path, PathBuf};
use std::process::Command;

fn quick() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("configs/ida-quick.yaml")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn the_stage_runs_skips_resumes_after_a_kill_and_ignores_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = quick();
    let out = dir.path().join("ref");
    ok(slidestack(&["motions", s(&cfg), "--out", s(&out)], "2"));

    let start = std::time::Instant::now();
    let o = ok(slidestack(&["ida", s(&cfg), "--out", s(&out)], "2"));
    let secs = start.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("ida: wrote"), "{text}");
    assert!(text.contains("fitted"), "{text}");
    assert!(out.join("ida.h5.sha256").exists());
    let want = std::fs::read(out.join("ida.h5")).unwrap();
    eprintln!("ida on the quick config: {secs:.2} s");

    // Up to date: skipped; `status` says so.
    let o = ok(slidestack(&["ida", s(&cfg), "--out", s(&out)], "2"));
    assert!(String::from_utf8_lossy(&o.stdout).contains("is up to date"));
    let o = ok(slidestack(
        &["status", s(&cfg), "--out", s(&out), "--format", "env"],
        "1",
    ));
    assert!(String::from_utf8_lossy(&o.stdout).contains("IDA=up_to_date"));

    // SIGKILL once the stage has started computing, then a rerun: the same bytes.
    let killed = dir.path().join("killed");
    common::copy_motions(&out, &killed);
    // Held after its first trace: the stage is computing, nothing written yet.
    common::kill_at(
        &["ida", s(&cfg), "--out", s(&killed)],
        "ida.trace:1",
        dir.path(),
    );
    assert!(!killed.join("ida.h5").exists());
    ok(slidestack(&["ida", s(&cfg), "--out", s(&killed)], "2"));
    assert_eq!(std::fs::read(killed.join("ida.h5")).unwrap(), want);
    let leftovers: Vec<_> = std::fs::read_dir(&killed)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");

    // One thread: the same bytes.
    let one = dir.path().join("one");
    common::copy_motions(&out, &one);
    ok(slidestack(&["ida", s(&cfg), "--out", s(&one)], "1"));
    assert_eq!(std::fs::read(one.join("ida.h5")).unwrap(), want);

    // xarray opens a zone with its named dimensions (scripts/install-deps.sh --test).
    let python = common::test_python();
    let script = "import sys, xarray as xr\n\
        ds = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_III')\n\
        print(list(ds['fractile_curve'].dims), list(ds['theta'].dims), list(ds['run_demand'].dims))\n\
        print(ds['Sa'].attrs['units'], [str(v) for v in ds['demand'].values[:2]], [str(v) for v in ds['system'].values])\n";
    let o = ok(Command::new(python)
        .args(["-c", script, s(&out.join("ida.h5"))])
        .output()
        .unwrap());
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        text.lines().collect::<Vec<_>>(),
        [
            "['system', 'case', 'fractile', 'Sa', 'demand'] ['system', 'case', 'limit_state'] \
             ['system', 'record', 'case', 'run', 'demand']",
            "g ['ductility', 'residual_drift_m'] ['stack', 'rigid']",
        ],
        "{text}"
    );
}

/// `ida --shard K/N` on the one-storey and the building IDA: the shards in any order and
/// thread count, one of them killed (SIGKILL) after its first unit and run again, a unit file
/// damaged before the assembly: `ida` then gives the unsharded run's bytes, and its unit files
/// are gone. A split into more shards than units is bad input (exit 2).
#[test]
fn shards_a_kill_and_a_damaged_unit_give_the_unsharded_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for config in ["configs/ida-quick.yaml", "configs/mdof-ida-quick.yaml"] {
        let cfg = repo.join(config);
        let name = config
            .trim_start_matches("configs/")
            .trim_end_matches(".yaml");
        let (whole, split) = (
            dir.path().join(name),
            dir.path().join(format!("{name}-split")),
        );
        ok(slidestack(&["motions", s(&cfg), "--out", s(&whole)], "2"));
        common::copy_motions(&whole, &split);
        ok(slidestack(&["ida", s(&cfg), "--out", s(&whole)], "2"));
        let want = std::fs::read(whole.join("ida.h5")).unwrap();

        shards::run("ida", &cfg, &split, "3/3", "1");
        common::kill_at(
            &["ida", s(&cfg), "--out", s(&split), "--shard", "1/3"],
            "ida.trace:1",
            dir.path(),
        );
        shards::run("ida", &cfg, &split, "1/3", "2");
        shards::run("ida", &cfg, &split, "2/3", "2");
        assert!(!split.join("ida.h5").exists());
        let units = split.join("ida.units");
        let files = shards::unit_files(&units);
        assert!(files.len() >= 3, "{files:?}");
        shards::rerun_with_a_damaged_unit("ida", &cfg, &split, &files[1]);
        assert_eq!(
            std::fs::read(split.join("ida.h5")).unwrap(),
            want,
            "{config}"
        );
        assert!(!units.exists());
        shards::refuses_more_shards_than_units("ida", &cfg, &split, 999, "1 ≤ K ≤ N ≤");
    }
}

#[test]
fn bad_ida_keys_are_refused_naming_the_file_and_key_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(quick()).unwrap();
    let cases = [
        (
            "period_s: 1.0, alpha",
            "period_s: -1.0, alpha",
            "ida.cases[0].period_s",
        ),
        (
            "c_y: 0.3 ",
            "c_y: 0.3\n    design: { importance: 1, response_reduction: 3 }\n    # ",
            "ida.structure",
        ),
        (
            "post_yield_ratio: 0.05",
            "post_yield_ratio: 1.5",
            "ida.structure.post_yield_ratio",
        ),
        ("first_sa_g: 0.1", "first_sa_g: 1e-9", "ida.tracing"),
        ("grid_points: 40", "grid_points: 1", "ida.grid_points"),
        (
            "collapse_ductility: 10",
            "collapse_ductility: 1e9",
            "ida.collapse_ductility",
        ),
        (
            "{ name: LS, ductility: 4 }",
            "{ name: DL, ductility: 4 }",
            "ida.limit_states[1].name",
        ),
        (
            "{ name: fall, slip_m: 0.3 }",
            "{ name: fall, slip_m: 0.3, ductility: 2 }",
            "ida.limit_states[2]",
        ),
        ("pad_s: 2", "pad_s: 1e6", "ida.pad_s"),
        (
            "cap_sa_g: 2.0",
            "cap_sa_g: 2.0\n    hunt_more: 1",
            "hunt_more",
        ),
        // r = 0.001 makes the post-yield branch overdamped.
        (
            "post_yield_ratio: 0.05",
            "post_yield_ratio: 0.001",
            "ida.structure",
        ),
    ];
    for (i, (from, to, key)) in cases.iter().enumerate() {
        assert!(text.contains(from), "{from}");
        let cfg = dir.path().join(format!("bad{i}.yaml"));
        let out = dir.path().join(format!("out{i}"));
        std::fs::write(&cfg, text.replacen(from, to, 1)).unwrap();
        let o = slidestack(&["ida", s(&cfg), "--out", s(&out)], "1");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{to}: {err}");
        assert!(err.contains(s(&cfg)) && err.contains(key), "{to}: {err}");
        assert!(!out.exists(), "{to}: work started");
    }
    // `cases: grid` without a grid, and with a grid of more cases than an IDA takes.
    let listed = "cases:\n    - { period_s: 1.0, alpha: [0.5, 0.5], mu: [0.2, 0.1] }";
    let big_grid = "grid:\n  period_s: [0.5, 1.0]\n  alpha: [[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, \
                    0.8, 0.9, 1.0], [0.5]]\n  mu: [[0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, \
                    0.45, 0.5], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]]\n";
    for (i, (extra, says)) in [
        ("", "and the config has none"),
        (
            big_grid,
            "the grid has 1200 cases; an IDA takes at most 1000",
        ),
    ]
    .iter()
    .enumerate()
    {
        let cfg = dir.path().join(format!("grid{i}.yaml"));
        let out = dir.path().join(format!("grid-out{i}"));
        std::fs::write(&cfg, text.replacen(listed, "cases: grid", 1) + extra).unwrap();
        let o = slidestack(&["ida", s(&cfg), "--out", s(&out)], "1");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("ida.cases") && err.contains(says), "{err}");
        assert!(!out.exists(), "work started");
    }
    // A word other than `grid`: refused at the line of the `ida` section.
    let cfg = dir.path().join("word.yaml");
    std::fs::write(&cfg, text.replacen(listed, "cases: all", 1)).unwrap();
    let o = slidestack(&["ida", s(&cfg), "--out", s(&dir.path().join("word"))], "1");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("`all`: give a list of cases or `grid`"),
        "{err}"
    );
    // Without an `ida` section: refused, naming the file.
    let cfg = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("configs/quick.yaml");
    let out = dir.path().join("none");
    let o = slidestack(&["ida", s(&cfg), "--out", s(&out)], "1");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("needs an `ida` section"));
}

/// `ida.cases: grid` traces every case of the grid, in its stored order: `ida.h5` holds the
/// same axes and numbers, zone by zone, as from a file listing those cases, and the same
/// fingerprint (the section serialises as the list).
#[test]
fn cases_grid_traces_every_case_of_the_grid() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(quick()).unwrap();
    let listed = "cases:\n    - { period_s: 1.0, alpha: [0.5, 0.5], mu: [0.2, 0.1] }";
    assert!(text.contains(listed));
    let grid = "grid:\n  period_s: [0.6, 1.0]\n  alpha: [[0.5], [0.5]]\n  mu: [[0.2], [0.1, 0.15]]\n  \
                damping: 0.05\n  damping_basis: rigid\n";
    let cases: String = [0.6, 1.0]
        .iter()
        .flat_map(|t| {
            [0.1, 0.15].map(|m2| {
                format!("\n    - {{ period_s: {t}, alpha: [0.5, 0.5], mu: [0.2, {m2}] }}")
            })
        })
        .collect();
    let outs: Vec<PathBuf> = [format!("cases:{cases}"), "cases: grid".to_string()]
        .iter()
        .enumerate()
        .map(|(i, ida_cases)| {
            let cfg = dir.path().join(format!("c{i}.yaml"));
            let out = dir.path().join(format!("o{i}"));
            std::fs::write(&cfg, text.replacen(listed, ida_cases, 1) + grid).unwrap();
            ok(slidestack(&["motions", s(&cfg), "--out", s(&out)], "2"));
            ok(slidestack(&["ida", s(&cfg), "--out", s(&out)], "2"));
            out
        })
        .collect();
    let fingerprint = |o: &Path| slidestack::store::h5::stored_fingerprint(&o.join("ida.h5"));
    assert_eq!(
        fingerprint(&outs[0]).unwrap(),
        fingerprint(&outs[1]).unwrap()
    );
    for zone in ["III", "V"] {
        let read = |o: &Path| slidestack::store::ida::read_zone_ida(&o.join("ida.h5"), zone);
        let (listed, gridded) = (read(&outs[0]).unwrap(), read(&outs[1]).unwrap());
        assert_eq!(listed.0.case_period_s.len(), 4);
        // Compared as their Debug text: shortest round-trip numbers, and NaN (a trace's unused
        // runs) equal to NaN.
        assert_eq!(format!("{listed:?}"), format!("{gridded:?}"), "zone {zone}");
    }
}

/// Hunt & fill on a bare bilinear SDOF: `λ·a_g` on `F_y` gives `λ` times the displacements of
/// `a_g` on `F_y/λ` and the same ductility (the response is homogeneous), so every traced run
/// has an independent twin; the collapse bracket holds the cap.
#[test]
fn hunt_and_fill_on_a_bare_bilinear_sdof_matches_its_homogeneous_twin() {
    let rec = &common::real_records()[0];
    let accel = rec.accel_mps2(1.0);
    let (c_y, r, cap) = (0.05, 0.05, 6.0);
    let spec = SystemSpec::new(0.8, &[], &[]);
    let opts = ExactOptions {
        energy_balance: false,
        ..ExactOptions::default()
    };
    let run = |c_y: f64, scale: f64| {
        let sys = System::new(&spec)
            .unwrap()
            .with_yielding(Yielding::bilinear(c_y, r))
            .unwrap();
        let a: Vec<f64> = accel.iter().map(|x| scale * x).collect();
        simulate_exact(
            &sys,
            &Ground {
                dt_s: rec.dt_s,
                accel_mps2: &a,
            },
            &opts,
        )
        .unwrap()
    };
    let p = HuntFill {
        first_sa_g: 0.2,
        step_increment_sa_g: 0.1,
        bracket_runs: 4,
        fill_runs: 3,
        cap_sa_g: 5.0,
    };
    // The intensity is the scale factor itself here: the twin identity does not depend on it.
    let trace = hunt_fill(&p, |lambda| {
        let resp = run(c_y, lambda);
        let mu = resp.ductility.unwrap();
        Ok::<_, ()>(((mu, resp.peak_displacement_m), mu >= cap))
    })
    .unwrap();
    assert!(trace.runs.len() > 6);
    for t in &trace.runs {
        let twin = run(c_y / t.sa_g, 1.0);
        let (mu, u) = t.demand;
        let mu_twin = twin.ductility.unwrap();
        assert!(
            (mu - mu_twin).abs() <= 1e-9 * mu,
            "λ = {}: {mu} vs {mu_twin}",
            t.sa_g
        );
        assert!((u - t.sa_g * twin.peak_displacement_m).abs() <= 1e-9 * u);
    }
    let (lo, hi) = trace
        .capacity_sa_g()
        .expect("the cap is reached below λ = 5");
    let at = |l: f64| run(c_y, l).ductility.unwrap();
    assert!(at(lo) < cap && at(hi) >= cap, "{lo} {hi}");
}

/// With an `ida:` section beside a grid, `run` builds `ida.h5` before the report, and the report
/// shows the curves and the fits; without an up-to-date `ida.h5` the report is refused.
#[test]
fn the_report_shows_the_ida_section_and_needs_ida_h5() {
    let dir = tempfile::tempdir().unwrap();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let grid = std::fs::read_to_string(root.join("configs/quick.yaml")).unwrap();
    let ida = std::fs::read_to_string(quick()).unwrap();
    let cfg = dir.path().join("both.yaml");
    std::fs::write(&cfg, grid + &ida[ida.find("\nida:").unwrap()..]).unwrap();
    let out = dir.path().join("out");
    let o = ok(slidestack(&["run", s(&cfg), "--out", s(&out)], "2"));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("ida 0.") || text.contains("ida 1."), "{text}");
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    for needle in ["ida-fragility", "ida-median", "ida.svg", "fitted"] {
        assert!(html.contains(needle), "{needle}");
    }
    let svg = std::fs::read_to_string(out.join("report/ida.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    std::fs::remove_file(out.join("ida.h5")).unwrap();
    let o = slidestack(&["report", s(&cfg), "--out", s(&out), "--force"], "1");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("ida.h5 is missing") && err.contains("slidestack ida"),
        "{err}"
    );
}

/// An IDA hunt that scales a record beyond `limits::MAX_PEAK_ACCEL_G` (a million g) gets a
/// typed error for that run, an input error, after the runs below the limit gave their
/// demands; the stage reports it naming the zone, motion, case and system
/// (`IdaStageError::Simulation`). Every cap of the repository's configs and tests is 5 g or
/// less, some 10⁵ times below.
#[test]
fn a_run_scaled_beyond_the_peak_limit_is_a_clean_error_of_that_run() {
    use slidestack::dynamics::SimError;
    let rec = &common::real_records()[0];
    let accel = rec.accel_mps2(1.0);
    let pga_g = rec.pga_g();
    let sys = System::new(&SystemSpec::new(0.8, &[0.5], &[0.2])).unwrap();
    let opts = ExactOptions {
        energy_balance: false,
        ..ExactOptions::default()
    };
    // Intensities are scale factors here: a hunt in steps of 0.19 million g.
    let step = 0.19e6 / pga_g;
    let p = HuntFill {
        first_sa_g: step,
        step_increment_sa_g: 0.0,
        bracket_runs: 0,
        fill_runs: 0,
        cap_sa_g: 10.0 * step,
    };
    let mut below = 0;
    let err = hunt_fill(&p, |lambda| {
        let a: Vec<f64> = accel.iter().map(|x| lambda * x).collect();
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &a,
        };
        let r = simulate_exact(&sys, &ground, &opts)?;
        below += 1;
        Ok::<_, SimError>((r.peak_displacement_m, false))
    })
    .unwrap_err();
    // Runs at 0.19, 0.38, …, 0.95 million g ran; the next (1.14) was refused.
    assert_eq!(below, 5);
    assert!(
        matches!(err, SimError::PeakAccel { value_g, .. } if value_g.abs() > 1e6),
        "{err}"
    );
    assert_eq!(
        slidestack::fault::classify(&err).kind,
        slidestack::fault::FaultKind::BadInput
    );
    assert!(err.to_string().contains("beyond the 1e6 g"), "{err}");
}
