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
            "apply only to --structure epp or bilinear",
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
