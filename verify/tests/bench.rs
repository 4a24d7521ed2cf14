//! `slidestack-verify accuracy` end to end on one real record (quick mode): the files it writes,
//! the exact integrator's self-check, RK4's convergence toward it, and refused input.

use std::path::Path;
use std::process::Command;

const RECORD: &str = "tests/fixtures/records/RSN960_NORTHR_LOS270.AT2";

fn bench(args: &[&str]) -> std::process::Output {
    // From the repository root, where the default records and scripts are.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap();
    Command::new(env!("CARGO_BIN_EXE_slidestack-verify"))
        .args(args)
        .current_dir(root)
        .output()
        .unwrap()
}

#[test]
fn accuracy_quick_writes_its_tables_and_rk4_converges_to_exact() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let run = bench(&["accuracy", "--quick", "--record", RECORD, "--out", out]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("## Summary") && stdout.contains("RK4 ×100"));
    for name in ["accuracy.md", "accuracy.csv", "accuracy.html"] {
        assert!(
            dir.path().join(name).metadata().unwrap().len() > 1000,
            "{name}"
        );
    }
    for name in ["accuracy.svg", "accuracy-peak.svg"] {
        let svg = std::fs::read_to_string(dir.path().join(name)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("RK4"), "{name}");
    }

    // Per system: the exact integrator on the ×8 refined record (the same piecewise-linear motion)
    // agrees to round-off, and RK4's history error falls from 1 to 100 sub-steps.
    let csv = std::fs::read_to_string(Path::new(out).join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (method, steps, hist) = (col("method"), col("steps_per_interval"), col("history_err"));
    // The system label is quoted and has commas inside: split it off first.
    let rows: Vec<(String, Vec<String>)> = lines
        .map(|l| {
            let (head, rest) = l.split_once(",\"").unwrap();
            let (system, tail) = rest.split_once("\",").unwrap();
            let mut fields: Vec<String> = vec![head.to_string(), system.to_string()];
            fields.extend(tail.split(',').map(str::to_string));
            (system.to_string(), fields)
        })
        .collect();
    let systems: std::collections::BTreeSet<&String> = rows.iter().map(|r| &r.0).collect();
    assert_eq!(systems.len(), 6);
    assert_eq!(rows.len(), 6 * (2 + 3));
    for system in systems {
        let err = |m: &str, s: &str| -> f64 {
            rows.iter()
                .find(|r| &r.0 == system && r.1[method] == m && r.1[steps] == s)
                .unwrap_or_else(|| panic!("{system}: no {m} ×{s} row"))
                .1[hist]
                .parse()
                .unwrap()
        };
        assert!(err("exact_refined_record", "8") < 1e-9, "{system}");
        let (coarse, fine) = (err("rk4", "1"), err("rk4", "100"));
        assert!(
            fine < coarse && fine < 1e-3,
            "{system}: {coarse:e} → {fine:e}"
        );
    }
}

#[test]
fn accuracy_refuses_missing_inputs_before_any_work() {
    let run = bench(&["accuracy", "--quick", "--record", "no/such/record.AT2"]);
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("record no/such/record.AT2 not found"), "{err}");

    let run = bench(&["accuracy", "--quick", "--opensees", "no/such/python"]);
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("Python no/such/python not found"), "{err}");
    assert!(
        !err.contains("accuracy: RSN"),
        "ran cases before refusing: {err}"
    );
}
