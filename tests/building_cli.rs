//! `slidestack simulate --config CASE.yaml` with `building` and `stacks`, end to end: the JSON
//! contract, one storey bit for bit as the case without `building`, the history file's layout,
//! the figure, and every kind of bad input refused before any work with the file and key named.

use std::path::Path;
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
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

fn case_file(dir: &Path, name: &str, yaml: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, yaml).unwrap();
    p.to_str().unwrap().to_string()
}

/// The worked example of docs/building.md (configs/building.yaml): every key of the contract, with
/// the lengths the building gives them, and a closed energy balance.
#[test]
fn the_worked_example_prints_the_building_contract() {
    let v = json(&["simulate", "--config", "configs/building.yaml", "--json"]);
    for key in [
        "floor_peak_displacement_m",
        "floor_peak_abs_accel_g",
        "storey_peak_drift_m",
        "storey_residual_drift_m",
        "modes_s",
    ] {
        assert_eq!(v[key].as_array().unwrap().len(), 3, "{key}");
    }
    assert!(v["storey_ductility"].is_null());
    assert!((v["modes_s"][0].as_f64().unwrap() - 0.6).abs() < 1e-12);
    let stacks = v["stacks"].as_array().unwrap();
    assert_eq!(stacks.len(), 2);
    assert_eq!(stacks[0]["floor"], 3);
    assert_eq!(stacks[0]["peak_slip_m"].as_array().unwrap().len(), 2);
    assert_eq!(stacks[1]["peak_abs_accel_g"].as_array().unwrap().len(), 1);
    assert!(v["switches"].as_u64().unwrap() > 0);
    for key in [
        "input",
        "kinetic",
        "strain",
        "damping",
        "friction",
        "hysteretic",
    ] {
        assert!(v["energy"][key].is_number(), "{key}");
    }
    assert!(v["energy_balance_error"].as_f64().unwrap() < 1e-9);
    // Drift of storey 1 is floor 1's displacement.
    assert_eq!(
        v["storey_peak_drift_m"][0],
        v["floor_peak_displacement_m"][0]
    );
    // Drift ratios over the default 3 m storeys; the base shear of three storeys. (Within
    // 2 ulp: serde_json's default float parsing may be 1 ulp off.)
    let close = |a: f64, b: f64| assert!((a - b).abs() <= 4.5e-16 * b.abs(), "{a} vs {b}");
    for i in 0..3 {
        let d = v["storey_peak_drift_m"][i].as_f64().unwrap();
        close(v["storey_peak_drift_ratio"][i].as_f64().unwrap(), d / 3.0);
        assert_eq!(v["building"]["storey_heights_m"][i].as_f64().unwrap(), 3.0);
    }
    assert!(v["peak_base_shear_ratio"].as_f64().unwrap() > 0.0);
    // Given heights, storey 1 first.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("configs/building.yaml")
        .unwrap()
        .replace(
            "  structure: elastic\n",
            "  structure: elastic\n  storey_heights_m: [4.5, 3, 3]\n",
        );
    let case = case_file(dir.path(), "heights.yaml", &text);
    let w = json(&["simulate", "--config", &case, "--json"]);
    let d = w["storey_peak_drift_m"][0].as_f64().unwrap();
    close(w["storey_peak_drift_ratio"][0].as_f64().unwrap(), d / 4.5);
    assert_eq!(w["storey_peak_drift_m"], v["storey_peak_drift_m"]);
}

/// One storey and one stack as a building are the case without `building`, bit for bit (the
/// one-storey integrator runs both), in both damping bases, elastic and yielding.
#[test]
fn one_storey_is_the_case_without_building_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for (basis, structure, yield_keys) in [
        ("rigid", "elastic", ("", "")),
        ("structure", "elastic", ("", "")),
        (
            "rigid",
            "bilinear",
            (
                "yield_strength_ratio: 0.15\npost_yield_ratio: 0.05\n",
                "  yield_strength_ratios: [0.15]\n  post_yield_ratio: 0.05\n",
            ),
        ),
    ] {
        let one = case_file(
            dir.path(),
            "one.yaml",
            &format!(
                "period: 0.8\nalpha: [0.5, 0.5]\nmu: [0.2, 0.1]\nmu_static: [0.25, 0.1]\n\
                 damping_basis: {basis}\nstructure: {structure}\n{}",
                yield_keys.0
            ),
        );
        let building = case_file(
            dir.path(),
            "building.yaml",
            &format!(
                "damping_basis: {basis}\nbuilding:\n  storeys: 1\n  period: 0.8\n  \
                 structure: {structure}\n{}stacks:\n  - floor: roof\n    alpha: [0.5, 0.5]\n    \
                 mu: [0.2, 0.1]\n    mu_static: [0.25, 0.1]\n",
                yield_keys.1
            ),
        );
        let a = json(&["simulate", "--config", &one, "--json"]);
        let b = json(&["simulate", "--config", &building, "--json"]);
        let what = format!("{basis} {structure}");
        assert_eq!(
            b["floor_peak_displacement_m"][0], a["peak_displacement_m"],
            "{what}"
        );
        assert_eq!(
            b["floor_peak_abs_accel_g"][0], a["peak_abs_accel_g"][0],
            "{what}"
        );
        assert_eq!(b["stacks"][0]["peak_slip_m"], a["peak_slip_m"], "{what}");
        assert_eq!(
            b["stacks"][0]["residual_slip_m"], a["residual_slip_m"],
            "{what}"
        );
        assert_eq!(
            b["storey_residual_drift_m"][0], a["residual_displacement_m"],
            "{what}"
        );
        assert_eq!(b["switches"], a["switches"], "{what}");
        assert_eq!(b["energy"], a["energy"], "{what}");
        if structure == "bilinear" {
            assert_eq!(b["storey_ductility"][0], a["ductility"], "{what}");
        }
    }
}

/// `--history` names every floor, block and interface; HDF5 and CSV carry the same layout.
#[test]
fn the_history_has_every_floor_and_block() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("h.csv");
    let out = run(&[
        "simulate",
        "--config",
        "configs/building.yaml",
        "--history",
        csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    for col in [
        "floor1_disp_m",
        "floor3_abs_accel_mps2",
        "stack1_block2_vel_mps",
        "stack2_block1_disp_m",
        "stack1_interface2_state",
        "stack2_interface1_state",
    ] {
        assert!(header.contains(&col), "{col} in {header:?}");
    }
    // 2 + 3 quantities × 6 bodies + 3 interfaces.
    assert_eq!(header.len(), 2 + 3 * 6 + 3);
    let rows = text.lines().count() - 1;
    assert_eq!(rows, 1999);
    let h5 = dir.path().join("h.h5");
    let out = run(&[
        "simulate",
        "--config",
        "configs/building.yaml",
        "--history",
        h5.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let f = hdf5::File::open(&h5).unwrap();
    assert_eq!(f.dataset("displacement").unwrap().shape(), vec![1999, 6]);
    assert_eq!(f.dataset("contact").unwrap().shape(), vec![1999, 3]);
    // The RK4 reference writes the same layout.
    let rk4 = dir.path().join("rk4.csv");
    let out = run(&[
        "simulate",
        "--config",
        "configs/building.yaml",
        "--integrator",
        "rk4",
        "--history",
        rk4.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&rk4).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').count();
    assert_eq!(header, 2 + 3 * 6 + 3);
    assert!(lines.all(|l| l.split(',').count() == header));
}

/// `--figure` draws a building case and writes nothing for a one-storey case, which it refuses.
#[test]
fn the_figure_is_drawn_for_a_building() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("b.svg");
    let out = run(&[
        "simulate",
        "--config",
        "configs/building.yaml",
        "--figure",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("stacks rigidly attached"));
    let one = dir.path().join("one.svg");
    let out = run(&["simulate", "--figure", one.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--figure draws a building case"));
    assert!(!one.exists());
}

/// Every kind of bad building input: refused with exit code 2, the file and the key named,
/// before the record is read (the case names a record that does not exist).
#[test]
fn bad_building_input_is_refused_naming_the_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let good_building = "building:\n  storeys: 3\n  period: 0.6\n";
    let good_stack = "stacks:\n  - floor: 3\n    alpha: [0.5]\n    mu: [0.2]\n";
    let cases: Vec<(String, &str)> = vec![
        (
            format!("{good_building}stacks:\n  - floor: 0\n    alpha: [0.5]\n    mu: [0.2]\n"),
            "stacks[0].floor must be 1 … 3",
        ),
        (
            format!("{good_building}stacks:\n  - floor: 4\n    alpha: [0.5]\n    mu: [0.2]\n"),
            "stacks[0].floor must be 1 … 3",
        ),
        (
            format!("{good_building}stacks:\n  - floor: top\n    alpha: [0.5]\n    mu: [0.2]\n"),
            "stacks[0].floor must be a floor number 1 … 3 or `roof`",
        ),
        (
            format!("{good_building}stacks:\n  - floor: 2\n    alpha: [0.5, 0.5]\n    mu: [0.2]\n"),
            "stacks[0].mu lists 1 values but the stack has 2 blocks",
        ),
        (
            format!("building:\n  storeys: 3\n  period: 0.6\n  floor_masses: [1, 1]\n{good_stack}"),
            "building.floor_masses lists 2 values but the building has 3 storeys",
        ),
        (
            format!(
                "building:\n  storeys: 3\n  period: 0.6\n  storey_stiffnesses: [1, 0, 1]\n\
                 {good_stack}"
            ),
            "building.storey_stiffnesses[1]",
        ),
        (
            format!(
                "building:\n  storeys: 3\n  period: 0.6\n  floor_masses: [1, -2, 1]\n{good_stack}"
            ),
            "building.floor_masses[1]",
        ),
        (
            format!("{good_building}  storey_heights_m: [3, 3]\n{good_stack}"),
            "building.storey_heights_m lists 2 values but the building has 3 storeys",
        ),
        (
            format!("{good_building}  storey_heights_m: 200\n{good_stack}"),
            "building.storey_heights_m[0] must be within 0.5 … 100 m",
        ),
        (
            "building:\n  storeys: 61\n  period: 2.0\n".to_string(),
            "building.storeys must be 1 … 60",
        ),
        (
            "building:\n  storeys: 0\n  period: 2.0\n".to_string(),
            "building.storeys must be 1 … 60",
        ),
        (
            "building:\n  storeys: 2\n  period: 2e4\n".to_string(),
            "building.period must be within",
        ),
        (
            format!("{good_building}  structure: epp\n{good_stack}"),
            "building.structure epp needs building.yield_strength_ratios",
        ),
        (
            format!(
                "building:\n  storeys: 3\n  period: 0.6\n  structure: bilinear\n  \
                 yield_strength_ratios: [0.2, 0.2, 0.2]\n{good_stack}"
            ),
            "building.structure bilinear needs building.post_yield_ratio",
        ),
        (
            format!(
                "building:\n  storeys: 3\n  period: 0.6\n  structure: bilinear\n  \
                 yield_strength_ratios: [0.2, 0.2]\n  post_yield_ratio: 0.05\n{good_stack}"
            ),
            "building.yield_strength_ratios lists 2 values but the building has 3",
        ),
        (
            format!("{good_building}  yield_strength_ratios: [0.2, 0.2, 0.2]\n"),
            "apply only to building.structure epp or bilinear",
        ),
        (
            format!("{good_building}{good_stack}alpha: [0.5]\n"),
            "alpha (a key or flag of a one-storey case) does not apply to a case with `building`",
        ),
        (
            format!("{good_building}{good_stack}period: 1.0\n"),
            "period (a key or flag of a one-storey case) does not apply",
        ),
        (
            format!(
                "{good_building}stacks:\n  - floor: 2\n    alpha: [0.5, 0.5]\n    mu: [0.2, 0.1]\n    \
                 aspect: [0.5]\n"
            ),
            "stacks[0].aspect lists 1 values but the stack has 2 blocks",
        ),
        (
            format!("{good_building}{good_stack}    aspect: [0]\n"),
            "stacks[0].aspect[0] (width over height of the block) must be finite and > 0, got 0.0",
        ),
        (
            format!("{good_building}{good_stack}    aspect: [-1]\n"),
            "stacks[0].aspect[0] (width over height of the block) must be finite and > 0",
        ),
        (
            format!("{good_building}{good_stack}    aspect: [.nan]\n"),
            "stacks[0].aspect[0] (width over height of the block) must be finite and > 0, got NaN",
        ),
        (
            format!("{good_building}{good_stack}aspect: [0.5]\n"),
            "aspect (a key or flag of a one-storey case) does not apply",
        ),
        (good_stack.to_string(), "`stacks` needs `building`"),
        (
            format!("{good_building}  floors: 3\n"),
            "unknown key `floors`",
        ),
        (
            format!(
                "{good_building}stacks:\n  - floor: 1\n    alpha: [0.5]\n    mu: [0.2]\n    friction: 1\n"
            ),
            "unknown key `friction`",
        ),
    ];
    for (i, (yaml, needle)) in cases.iter().enumerate() {
        let yaml = format!("record: /nonexistent/record.AT2\n{yaml}");
        let file = case_file(dir.path(), &format!("bad{i}.yaml"), &yaml);
        let out = run(&["simulate", "--config", &file, "--json"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{yaml}\n{err}");
        assert!(err.contains(needle), "{yaml}\nexpected {needle:?} in {err}");
        assert!(
            err.contains(&format!("bad{i}.yaml")),
            "the file is named: {err}"
        );
        assert!(
            !err.contains("/nonexistent/record.AT2"),
            "before the record: {err}"
        );
        assert!(out.stdout.is_empty());
    }
}
