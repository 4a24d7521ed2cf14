//! `slidestack simulate` end to end: the JSON contract, history files and refused input.

use std::process::Command;

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn json_contract_and_history_files() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("h.h5");
    let csv = dir.path().join("h.csv");
    for hist in [&h5, &csv] {
        let out = run(&["simulate", "--json", "--history", hist.to_str().unwrap()]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for key in [
            "peak_displacement_m",
            "peak_displacement_time_s",
            "switches",
            "energy_balance_error",
        ] {
            assert!(v[key].is_number(), "{key}");
        }
        assert_eq!(v["peak_abs_accel_g"].as_array().unwrap().len(), 3);
        assert_eq!(v["peak_slip_m"].as_array().unwrap().len(), 2);
        assert_eq!(v["residual_slip_m"].as_array().unwrap().len(), 2);
        for key in ["input", "kinetic", "strain", "damping", "friction"] {
            assert!(v["energy"][key].is_number(), "energy.{key}");
        }
        assert!(v["energy_balance_error"].as_f64().unwrap() < 1e-9);
        assert!(hist.metadata().unwrap().len() > 1000);
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 1 + 1999);
}

#[test]
fn bad_input_is_refused_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.AT2");
    std::fs::write(
        &bad,
        "PEER\nx\nUNITS OF G\nNPTS=  3, DT= .01 SEC\n0.1 0.2\n",
    )
    .unwrap();
    let out = run(&["simulate", "--record", bad.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("bad.AT2:5: header says NPTS = 3 but the file has 2 values"),
        "{err}"
    );
    let out = run(&["simulate", "--mu=-0.1,0.1"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("mu_1"));
    let case = dir.path().join("case.yaml");
    std::fs::write(&case, "period: 1.0\nmass_ratio: [0.5]\n").unwrap();
    let out = run(&["simulate", "--config", case.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("line 2: unknown key `mass_ratio`"),
        "{err}"
    );
    let out = run(&["simulate", "--history", "out.txt"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("must end in .h5, .hdf5 or .csv"));
}
