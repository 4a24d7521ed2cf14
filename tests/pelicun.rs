//! `slidestack export edp` (docs/building.md, "FEMA P-58 demands through pelicun"): the demand
//! sample of a building case under a set of records agrees with `simulate --json` under each
//! record, its ground row with the record itself, and pelicun (installed by
//! `scripts/install-deps.sh --test` in `.venv-pelicun/`) loads it with the values and units
//! written and runs a FEMA P-58 damage-and-loss assessment of two contents components on it
//! (`scripts/pelicun_assess.py`), with the stacks sliding and rigidly attached.

mod common;

use common::{fixture, ok, slidestack};
use serde_json::Value;
use slidestack::dynamics::G;
use slidestack::ground_motion::read_record;
use std::path::{Path, PathBuf};
use std::process::Command;

const RECORDS: [&str; 3] = [
    "RSN829_CAPEMEND_RIO360.AT2",
    "RSN960_NORTHR_LOS270.AT2",
    "RSN1633_MANJIL_ABBAR--L.AT2",
];

fn case() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/building.yaml")
}

/// A demand sample read back: its header, its units row and its rows of (label, values).
struct Sample {
    header: Vec<String>,
    units: Vec<String>,
    rows: Vec<(String, Vec<f64>)>,
}

/// `export edp` of configs/building.yaml under [`RECORDS`] into `out` (with `--attached` when
/// asked), read back.
fn export(out: &Path, attached: bool) -> Sample {
    let case = case();
    let records: Vec<String> = RECORDS
        .iter()
        .map(|r| fixture(r).display().to_string())
        .collect();
    let mut args = vec![
        "export",
        "edp",
        "--config",
        case.to_str().unwrap(),
        "--record",
    ];
    args.extend(records.iter().map(String::as_str));
    args.extend(["--out", out.to_str().unwrap()]);
    if attached {
        args.push("--attached");
    }
    ok(slidestack(&args, "1"));
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_path(out)
        .unwrap();
    let lines: Vec<Vec<String>> = r
        .records()
        .map(|l| l.unwrap().iter().map(str::to_string).collect())
        .collect();
    let rows = lines[2..]
        .iter()
        .map(|l| {
            let values = l[1..].iter().map(|v| v.parse().unwrap()).collect();
            (l[0].clone(), values)
        })
        .collect();
    Sample {
        header: lines[0].clone(),
        units: lines[1].clone(),
        rows,
    }
}

/// Peak `|v_g|` of the record's ground velocity by dense sampling, the record linear between
/// samples and each interval cut in 1000 (an oracle apart from the library's vertex formula),
/// and how far it may fall short of the true peak: a parabola `v* − |ȧ_g|·(t − t*)²/2` sampled
/// within `dt/2000` of its vertex.
fn sampled_pgv(accel: &[f64], dt: f64) -> (f64, f64) {
    let jerk = (accel.windows(2)).fold(0.0f64, |m, w| m.max((w[1] - w[0]).abs() / dt));
    let short = 0.5 * jerk * (dt / 2000.0).powi(2);
    let (mut v, mut peak) = (0.0f64, 0.0f64);
    for w in accel.windows(2) {
        let slope = (w[1] - w[0]) / dt;
        for i in 1..=1000 {
            let t = dt * i as f64 / 1000.0;
            peak = peak.max((v + w[0] * t + 0.5 * slope * t * t).abs());
        }
        v += 0.5 * dt * (w[0] + w[1]);
    }
    (peak, short)
}

/// The sample's columns are pelicun's labels for three storeys, one row per record, and every
/// value is the one `simulate --json` prints for that record (PFA, PFV per floor, the drift
/// ratio, the residual drift over the storey's height) or, for the ground, the record's own PGA
/// and PGV (the case's scale 1.5 applied; the PGV at or above a dense sampling's, by no more
/// than the sampling can miss).
#[test]
fn the_sample_is_simulate_s_numbers_in_pelicun_s_labels() {
    let dir = tempfile::tempdir().unwrap();
    let Sample {
        header,
        units,
        rows,
    } = export(&dir.path().join("edp.csv"), false);
    let mut expect = vec![String::new()];
    let mut expect_units = vec!["Units".to_string()];
    for (kind, unit, levels) in [
        ("PFA", "g", 0..=3),
        ("PFV", "mps", 0..=3),
        ("PID", "rad", 1..=3),
        ("RID", "rad", 1..=3),
    ] {
        for at in levels {
            expect.push(format!("1-{kind}-{at}-1"));
            expect_units.push(unit.to_string());
        }
    }
    assert_eq!(header, expect);
    assert_eq!(units, expect_units);
    assert_eq!(rows.len(), RECORDS.len());
    let case = case();
    for ((label, values), name) in rows.iter().zip(RECORDS) {
        assert_eq!(label, name);
        let record = fixture(name);
        let o = ok(slidestack(
            &[
                "simulate",
                "--config",
                case.to_str().unwrap(),
                "--record",
                record.to_str().unwrap(),
                "--json",
            ],
            "1",
        ));
        let s: Value = serde_json::from_slice(&o.stdout).unwrap();
        let list = |key: &str| -> Vec<f64> {
            s[key]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        };
        let heights = s["building"]["storey_heights_m"].as_array().unwrap();
        let rid: Vec<f64> = (list("storey_residual_drift_m").iter().zip(heights))
            .map(|(d, h)| d.abs() / h.as_f64().unwrap())
            .collect();
        let rec = read_record(&record).unwrap();
        let accel = rec.accel_mps2(1.5);
        let pga_g = accel.iter().fold(0.0f64, |p, a| p.max(a.abs())) / G;
        let (pgv, short) = sampled_pgv(&accel, rec.dt_s);
        assert_eq!(values[0], pga_g, "{name}: PFA-0");
        let above = values[4] - pgv;
        assert!(
            above >= -1e-12 * pgv && above <= short + 1e-12 * pgv,
            "{name}: PFV-0 {} vs sampled {pgv} (short by {short} at most)",
            values[4]
        );
        assert_eq!(
            values[1..4],
            list("floor_peak_abs_accel_g")[..],
            "{name}: PFA"
        );
        assert_eq!(
            values[5..8],
            list("floor_peak_abs_velocity_mps")[..],
            "{name}: PFV"
        );
        assert_eq!(
            values[8..11],
            list("storey_peak_drift_ratio")[..],
            "{name}: PID"
        );
        assert_eq!(values[11..14], rid[..], "{name}: RID");
    }
}

/// pelicun's Python, or `None` (with the reason printed) where install-deps could not install
/// it; without either, the test fails and says how to install it.
fn pelicun_python() -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".venv-pelicun/bin/python");
    let imports = Command::new(&python)
        .args(["-c", "import pelicun"])
        .output()
        .is_ok_and(|o| o.status.success());
    if imports {
        return Some(python);
    }
    let reason =
        std::fs::read_to_string(root.join(".venv-pelicun.unavailable")).unwrap_or_else(|_| {
            panic!("pelicun is not installed in .venv-pelicun: run scripts/install-deps.sh --test")
        });
    eprintln!("SKIPPED: pelicun could not be installed on this machine:\n{reason}");
    None
}

/// pelicun loads both samples (sliding, attached) with exactly the values written, converted to
/// SI as the units row says (g to m/s² by 9.80665, 1e-12 relative), and assesses a PFA-rated
/// and a PFV-rated content on every floor: each floor's damage-state shares sum to 1 and the
/// repair cost is finite and not negative; run twice, the same numbers. The sliding and
/// attached samples differ (the stacks change the floors' motion), and so do their damage
/// shares.
#[test]
fn pelicun_assesses_the_sample_end_to_end() {
    let Some(python) = pelicun_python() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/pelicun_assess.py");
    // FEMA P-58 leaves contents' repair costs to the user: these are the test's own.
    let assess = |path: &Path| {
        Command::new(&python)
            .arg(&script)
            .arg(path)
            .args(["--cost", "E.20.22.001=1500", "--cost", "E.20.22.102a=800"])
            .args(["--realisations", "500", "--json"])
            .output()
            .unwrap()
    };
    let mut shares = Vec::new();
    for attached in [false, true] {
        let path = dir.path().join(format!("edp-{attached}.csv"));
        let Sample {
            header,
            units,
            rows,
        } = export(&path, attached);
        let o = assess(&path);
        assert!(
            o.status.success(),
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        let r: Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(r["storeys"], 3);
        if !attached {
            let again = assess(&path);
            assert_eq!(
                again.stdout, o.stdout,
                "the same file and seed, the same numbers"
            );
        }
        for (c, (label, unit)) in header.iter().zip(&units).enumerate().skip(1) {
            // pelicun drops the event id from its labels.
            let key = label.split_once('-').unwrap().1;
            let loaded = r["raw_si"][key]
                .as_array()
                .unwrap_or_else(|| panic!("pelicun has no {key}: {}", r["raw_si"]));
            let factor = if unit == "g" { 9.80665 } else { 1.0 };
            for (row, v) in rows.iter().zip(loaded) {
                let (want, got) = (row.1[c - 1] * factor, v.as_f64().unwrap());
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs(),
                    "{key}: {got} vs {want}"
                );
            }
        }
        for (id, floors) in r["damage_share"].as_object().unwrap() {
            let floors = floors.as_object().unwrap();
            assert_eq!(floors.len(), 3, "{id}");
            for (floor, states) in floors {
                let total: f64 = states
                    .as_object()
                    .unwrap()
                    .values()
                    .map(|v| v.as_f64().unwrap())
                    .sum();
                assert!((total - 1.0).abs() < 1e-9, "{id} floor {floor}: {total}");
            }
        }
        let cost = r["repair_cost_usd_2011"]["mean"].as_f64().unwrap();
        assert!(cost.is_finite() && cost >= 0.0, "{cost}");
        shares.push((rows, r["damage_share"].clone()));
    }
    assert_ne!(shares[0].0, shares[1].0, "sliding and attached demands");
    assert_ne!(shares[0].1, shares[1].1, "sliding and attached damage");
}

/// A one-storey case (no `building`) and an output that is not a CSV are refused before any
/// run, naming the file and the key.
#[test]
fn bad_requests_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let record = fixture(RECORDS[0]);
    let one = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/section71-case.yaml");
    let out = dir.path().join("edp.csv");
    let o = slidestack(
        &[
            "export",
            "edp",
            "--config",
            one.to_str().unwrap(),
            "--record",
            record.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "1",
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("section71-case.yaml") && err.contains("`building`"),
        "{err}"
    );
    assert!(!out.exists());
    let case = case();
    let o = slidestack(
        &[
            "export",
            "edp",
            "--config",
            case.to_str().unwrap(),
            "--record",
            record.to_str().unwrap(),
            "--out",
            dir.path().join("edp.json").to_str().unwrap(),
        ],
        "1",
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("edp.json"));
}
