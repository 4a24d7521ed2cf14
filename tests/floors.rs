//! The floors stage (docs/model.md, "Floor response spectra", "In a study"), on
//! configs/mdof-floors-quick.yaml: `run` ends in a report with the floor spectra section;
//! `floors.h5` is labelled and the same bytes on one thread and two; every stored spectrum of
//! the three-storey building with its stack on the roof is what `simulate` gives the same case
//! from a case file (the sliding stack), and what it gives the case with a friction no motion
//! overcomes (the stack attached); the report's table is the stored arrays' means beside the
//! code's factors. The spectra's own accuracy (the refined history against the cascade's matrix
//! exponential and a denser history) is tests/floor_spectra.rs's.

mod common;

use common::{ok, slidestack};
use slidestack::one_case::{Outcome, Settings};
use slidestack::store::floors::read_zone_floors;
use slidestack::store::motions::read_zone_motions;
use slidestack::study::floors::{asce7_16_height_factor, asce7_22_h_f};
use std::path::{Path, PathBuf};

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The case file of the study's case on three storeys, the stack on the roof, with friction
/// `mu` (the study's floors: equal masses and stiffnesses, 3 m storeys).
fn case_file(mu: &str) -> Settings {
    let yaml = format!(
        "building:\n  storeys: 3\n  period: 1.0\n  floor_masses: [1, 1, 1]\n  \
         storey_stiffnesses: [1, 1, 1]\n  storey_heights_m: 3.0\n  structure: elastic\n\
         stacks:\n  - {{ floor: 3, alpha: [0.5, 0.5], mu: {mu} }}\n\
         damping: 0.05\ndamping_basis: rigid\n\
         floor_spectra: {{ periods: \"0.05:4:0.05\", damping: [0.02, 0.05] }}\n"
    );
    serde_yaml::from_str(&yaml).unwrap()
}

#[test]
fn a_study_stores_floor_spectra_as_simulate_gives_them_and_reports_them_beside_the_code() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = repo("configs/mdof-floors-quick.yaml");
    let out = dir.path().join("a");
    let o = ok(slidestack(&["run", s(&cfg), "--out", s(&out)], "2"));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("floors"), "{text}");
    // One thread: the same bytes.
    let one = dir.path().join("b");
    common::copy_motions(&out, &one);
    let o = ok(slidestack(&["floors", s(&cfg), "--out", s(&one)], "1"));
    // The command prints the report's table, a row per floor of every distinct building.
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(printed.contains("ASCE7-16"), "{printed}");
    assert_eq!(
        printed.matches("3 storeys, stack on the roof").count(),
        2 * 3
    );
    assert_eq!(
        std::fs::read(out.join("floors.h5")).unwrap(),
        std::fs::read(one.join("floors.h5")).unwrap()
    );

    let (axes, z) = read_zone_floors(&out.join("floors.h5"), "V", true).unwrap();
    assert_eq!(axes.damping, [0.02, 0.05]);
    assert_eq!(axes.periods_s.len(), 80);
    assert_eq!(axes.floors, 3);
    // [motion, case, storeys, stack_floor, damping, floor, period]
    assert_eq!(z.psa_stack.shape(), [3, 1, 2, 3, 2, 3, 80]);
    let motions = read_zone_motions(&out.join("motions.h5"), "V").unwrap();
    // A building of one storey: NaN above its roof; its three stack floors are one building.
    assert!(z.pfa_stack[[0, 0, 0, 0, 1]].is_nan());
    assert_eq!(
        z.psa_stack[[0, 0, 0, 1, 1, 0, 7]],
        z.psa_stack[[0, 0, 0, 0, 1, 0, 7]]
    );

    // Three storeys, the stack on the roof: the case file's `simulate`, sliding (μ 0.2/0.1),
    // and with a friction it never overcomes (μ 5: peak floor accelerations stay far below
    // 5 g), which is the stack attached. Two constructions of one model, each exact: 1e-9
    // relative of the largest ordinate (the sweep's skip-rule tolerance).
    let mut worst = [0.0f64; 2];
    for (sys, mu) in [(0, "[0.2, 0.1]"), (1, "[5.0, 5.0]")] {
        let (psa, pfa) = if sys == 0 {
            (&z.psa_stack, &z.pfa_stack)
        } else {
            (&z.psa_rigid, &z.pfa_rigid)
        };
        for (m, record) in motions.iter().enumerate() {
            let sim = case_file(mu).resolve_with(record.clone()).unwrap();
            let (outcome, _) = sim.run(&sim.accel_mps2()).unwrap();
            let Outcome::Building(b) = outcome else {
                panic!("a building")
            };
            let fs = b.floor_spectra.as_ref().expect("asked for");
            for d in 0..2 {
                for j in 0..3 {
                    let scale = fs.psa_g[d][j].iter().fold(0.0f64, |a, &b| a.max(b));
                    for p in 0..80 {
                        let stored = psa[[m, 0, 1, 1, d, j, p]];
                        let diff = (stored - fs.psa_g[d][j][p]).abs() / scale;
                        worst[sys] = worst[sys].max(diff);
                    }
                }
            }
            for j in 0..3 {
                let direct = b.floor_peak_abs_accel_g[j];
                assert!((pfa[[m, 0, 1, 1, j]] - direct).abs() <= 1e-9 * direct);
            }
            assert_eq!(z.pga_g[m], record.pga_g());
        }
    }
    eprintln!("stored against simulate, sliding and attached: {worst:?}");
    assert!(worst.iter().all(|&w| w <= 1e-9), "{worst:?}");
    assert!(
        (0..80).any(|p| z.psa_stack[[0, 0, 1, 1, 1, 2, p]] != z.psa_rigid[[0, 0, 1, 1, 1, 2, p]]),
        "the sliding stack changes the roof's spectrum"
    );

    // The report: the section, the figure, and the roof's row of that building in zone V,
    // the stored arrays' mean ratios beside ASCE 7-16's 3 and ASCE 7-22's H_f at T_a = 1 s.
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(html.contains("Floor response spectra"));
    let svg = std::fs::read_to_string(out.join("report/floors.svg")).unwrap();
    for series in ["roof, sliding", "roof, ASCE 7-16", "roof, ASCE 7-22"] {
        assert!(svg.contains(series), "{series}");
    }
    assert!(svg.contains("floor 2, attached"));
    let ratio = |pfa: &ndarray::ArrayD<f64>| {
        (0..3)
            .map(|m| pfa[[m, 0, 1, 1, 2]] / z.pga_g[m])
            .sum::<f64>()
            / 3.0
    };
    let row = format!(
        "<td>V</td><td>1</td><td>3 storeys, stack on the roof</td><td>3</td><td>1.00</td>\
         <td>{:.2}</td><td>{:.2}</td><td>{:.2}</td><td>{:.2}</td>",
        ratio(&z.pfa_stack),
        ratio(&z.pfa_rigid),
        asce7_16_height_factor(1.0),
        asce7_22_h_f(1.0, 1.0)
    );
    assert!(html.contains(&row), "{row}");
    assert!(html.contains("<td>3.00</td><td>2.84</td>"));
}

#[test]
fn bad_floor_spectra_sections_are_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo("configs/mdof-floors-quick.yaml")).unwrap();
    for (from, to, key) in [
        (
            "mu: [0.2, 0.1] }",
            "mu: [0.2] }",
            "floor_spectra.cases[0].mu",
        ),
        (
            "damping: [0.02, 0.05]",
            "damping: [1.5]",
            "floor_spectra.damping",
        ),
        (
            "periods: \"0.05:4:0.05\"",
            "periods: \"4:0.05\"",
            "floor_spectra.periods",
        ),
    ] {
        let bad = dir.path().join("bad.yaml");
        assert!(text.contains(from));
        std::fs::write(&bad, text.replace(from, to)).unwrap();
        let o = slidestack(&["floors", s(&bad), "--out", s(&dir.path().join("o"))], "1");
        assert_eq!(o.status.code(), Some(2), "{key}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(key) && err.contains("bad.yaml"), "{err}");
        assert!(!dir.path().join("o").exists());
    }
    // A config without the section: `floors` says what it needs.
    let o = slidestack(&["floors", s(&repo("configs/mdof-quick.yaml"))], "1");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("needs a `floor_spectra` section"), "{err}");
}

/// One storey (configs/quick.yaml's motions and physics): the floor is the structure; its
/// stored spectra are `simulate`'s of the case file, bit for bit; a stack whose friction no
/// motion overcomes (μ = 5) has the spectra of the stack attached, to 1e-9 of the largest
/// ordinate (two exact solutions of one model, as the sweep's no-slip rule).
#[test]
fn on_one_storey_the_floor_is_the_structure_and_a_stack_that_cannot_slide_is_attached() {
    let dir = tempfile::tempdir().unwrap();
    let quick = std::fs::read_to_string(repo("configs/quick.yaml")).unwrap();
    let out = dir.path().join("out");
    let cfg = dir.path().join("one.yaml");
    let section = "floor_spectra:\n  periods: \"0.05:4:0.1\"\n  cases:\n    \
                   - { period_s: 0.6, alpha: [0.5, 0.5], mu: [0.2, 0.1] }\n    \
                   - { period_s: 0.6, alpha: [0.5, 0.5], mu: [5, 5] }\n";
    std::fs::write(
        &cfg,
        quick.replace("output_dir: out/quick", &format!("output_dir: {}", s(&out))) + section,
    )
    .unwrap();
    ok(slidestack(&["motions", s(&cfg)], "2"));
    ok(slidestack(&["floors", s(&cfg)], "2"));
    let (axes, z) = read_zone_floors(&out.join("floors.h5"), "III", false).unwrap();
    assert_eq!((axes.floors, axes.damping.as_slice()), (1, &[0.05][..]));
    assert_eq!(z.psa_stack.shape(), [3, 2, 1, 1, 40]);
    let motions = read_zone_motions(&out.join("motions.h5"), "III").unwrap();
    let largest = |a: &ndarray::ArrayD<f64>, m: usize, c: usize| {
        (0..40).fold(0.0f64, |x, p| x.max(a[[m, c, 0, 0, p]]))
    };
    let mut worst = 0.0f64;
    for (m, record) in motions.iter().enumerate() {
        let settings: Settings = serde_yaml::from_str(
            "period: 0.6\nalpha: [0.5, 0.5]\nmu: [0.2, 0.1]\ndamping: 0.05\n\
             damping_basis: rigid\nfloor_spectra: { periods: \"0.05:4:0.1\" }\n",
        )
        .unwrap();
        let sim = settings.resolve_with(record.clone()).unwrap();
        let (outcome, _) = sim.run(&sim.accel_mps2()).unwrap();
        let Outcome::OneStorey(one) = outcome else {
            panic!("one storey")
        };
        let fs = one.floor_spectra.as_ref().expect("asked for");
        let stored: Vec<f64> = (0..40).map(|p| z.psa_stack[[m, 0, 0, 0, p]]).collect();
        assert_eq!(stored, fs.psa_g[0][0], "motion {m}");
        // The stage's peak is from the run on the refined record, simulate's from the record's
        // own: two exact peaks of one history (1e-9, as above).
        let direct = one.peak_abs_accel_g[0];
        assert!(
            (z.pfa_stack[[m, 0, 0]] - direct).abs() <= 1e-9 * direct,
            "motion {m}"
        );
        let scale = largest(&z.psa_rigid, m, 1);
        for p in 0..40 {
            let d = (z.psa_stack[[m, 1, 0, 0, p]] - z.psa_rigid[[m, 1, 0, 0, p]]).abs();
            worst = worst.max(d / scale);
        }
    }
    eprintln!("a stack that cannot slide against the stack attached: {worst:e}");
    assert!(worst <= 1e-9, "{worst}");
    // The sliding stack's spectra differ from the attached ones.
    assert_ne!(largest(&z.psa_stack, 0, 0), largest(&z.psa_rigid, 0, 0));
}
