//! `slidestack simulate --structure` and `slidestack spectrum --ductility` end to end: the JSON
//! fields a study stage reads, the elastic default unchanged, and refused combinations.

use std::process::Command;

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(args)
        .output()
        .unwrap()
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = run(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn simulate_reports_ductility_residual_drift_and_hysteretic_energy() {
    let elastic = json(&["simulate", "--json"]);
    assert_eq!(elastic["structure"], "elastic");
    assert!(elastic["ductility"].is_null() && elastic["yield_displacement_m"].is_null());
    assert_eq!(elastic["energy"]["hysteretic"], 0.0);
    assert!(elastic["residual_displacement_m"].is_number());
    // Same case, a strength the record cannot reach: every number of the elastic run.
    let strong = json(&[
        "simulate",
        "--json",
        "--structure",
        "bilinear",
        "--yield-strength-ratio",
        "1e5",
        "--post-yield-ratio",
        "0.1",
    ]);
    for key in [
        "peak_displacement_m",
        "peak_abs_accel_g",
        "peak_slip_m",
        "residual_slip_m",
        "switches",
        "residual_displacement_m",
    ] {
        assert_eq!(elastic[key], strong[key], "{key}");
    }
    let epp = json(&[
        "simulate",
        "--json",
        "--structure",
        "epp",
        "--yield-strength-ratio",
        "0.1",
    ]);
    assert_eq!(epp["structure"], "epp");
    assert_eq!(epp["post_yield_ratio"], 0.0);
    let uy = epp["yield_displacement_m"].as_f64().unwrap();
    // T_p = 1 s: u_y = C_y·g/(2π)² m.
    assert!((uy - 0.1 * 9.80665 / (4.0 * std::f64::consts::PI.powi(2))).abs() < 1e-15);
    let mu = epp["ductility"].as_f64().unwrap();
    let peak = epp["peak_displacement_m"].as_f64().unwrap();
    assert!(mu > 1.0 && (mu - peak / uy).abs() < 1e-12 * mu);
    assert!(epp["energy"]["hysteretic"].as_f64().unwrap() > 0.0);
    assert!(epp["yield_events"].as_u64().unwrap() >= 2);
    assert!(epp["energy_balance_error"].as_f64().unwrap() < 1e-9);
    // The paper's RK4 carries the same model.
    let rk4 = json(&[
        "simulate",
        "--json",
        "--structure",
        "epp",
        "--yield-strength-ratio",
        "0.1",
        "--integrator",
        "rk4",
        "--rk4-substeps",
        "200",
    ]);
    let mu_rk4 = rk4["ductility"].as_f64().unwrap();
    assert!((mu_rk4 - mu).abs() < 1e-3 * mu, "{mu_rk4} vs {mu}");
}

#[test]
fn simulate_refuses_yielding_flags_that_do_not_fit() {
    for (args, needle) in [
        (
            vec!["--structure", "epp"],
            "--structure epp needs --yield-strength-ratio",
        ),
        (
            vec!["--yield-strength-ratio", "0.2"],
            "apply only to --structure epp or --structure bilinear",
        ),
        (
            vec!["--structure", "bilinear", "--yield-strength-ratio", "0.2"],
            "needs --post-yield-ratio",
        ),
        (
            vec![
                "--structure",
                "epp",
                "--yield-strength-ratio",
                "0.2",
                "--post-yield-ratio",
                "0.1",
            ],
            "use --structure bilinear",
        ),
        (
            vec![
                "--structure",
                "bilinear",
                "--yield-strength-ratio",
                "0.2",
                "--post-yield-ratio",
                "0.001",
            ],
            "overdamped",
        ),
        (
            vec!["--structure", "epp", "--yield-strength-ratio", "-1"],
            "yield strength ratio C_y",
        ),
    ] {
        let mut all = vec!["simulate"];
        all.extend(args);
        let out = run(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{all:?}: {err}");
        assert!(err.contains(needle), "{all:?}: {err}");
    }
}

#[test]
fn spectrum_ductility_reports_strengths_and_refuses_bad_targets() {
    let rec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/records/RSN960_NORTHR_LOS270.AT2"
    );
    let v = json(&[
        "spectrum",
        "--record",
        rec,
        "--periods",
        "0.2,1",
        "--ductility",
        "1,4",
        "--json",
    ]);
    let arr = v.as_array().unwrap();
    assert_eq!(arr.len(), 2);
    for s in arr {
        let mu = s["ductility"].as_f64().unwrap();
        let cy = s["strength_ratio"].as_array().unwrap();
        let ce = s["elastic_strength_ratio"].as_array().unwrap();
        let ry = s["reduction_factor"].as_array().unwrap();
        assert_eq!(cy.len(), 2);
        for i in 0..2 {
            let (cy, ce, ry) = (
                cy[i].as_f64().unwrap(),
                ce[i].as_f64().unwrap(),
                ry[i].as_f64().unwrap(),
            );
            assert!((ry - ce / cy).abs() < 1e-12 * ry);
            if mu == 1.0 {
                assert_eq!(ry, 1.0);
            } else {
                assert!(ry > 1.0);
            }
            let reached = s["ductility_reached"][i].as_f64().unwrap();
            assert!((reached - mu).abs() < 1e-8 * mu);
        }
    }
    let csv = run(&[
        "spectrum",
        "--record",
        rec,
        "--periods",
        "0.5",
        "--ductility",
        "2",
        "--csv",
    ]);
    let text = String::from_utf8_lossy(&csv.stdout);
    assert!(text.starts_with("record,damping,ductility,post_yield_ratio,period_s,strength_ratio,"));
    assert_eq!(text.lines().count(), 2);
    for (args, needle) in [
        (
            vec!["--ductility", "0.5"],
            "target ductility must be within 1",
        ),
        (
            vec!["--ductility", "2", "--post-yield-ratio", "0.0001"],
            "overdamped",
        ),
    ] {
        let mut all = vec!["spectrum", "--record", rec, "--periods", "0.5"];
        all.extend(args);
        let out = run(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{all:?}: {err}");
        assert!(err.contains(needle), "{all:?}: {err}");
    }
    let out = run(&["spectrum", "--record", rec, "--post-yield-ratio", "0.1"]);
    assert_eq!(out.status.code(), Some(2));
}
