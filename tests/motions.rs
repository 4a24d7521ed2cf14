//! Ground motions end to end: matching eleven real records to both zones of the paper, the
//! `spectrum`, `match` and `motions` commands, and refused input.

mod common;

use common::{ELEVEN, eleven_records, fixture};
use slidestack::ground_motion::matching::MatchSettings;
use slidestack::ground_motion::process::drift;
use slidestack::ground_motion::read_record;
use slidestack::study::config::{MotionsConfig, RecordSeeds, SeedsConfig};
use slidestack::study::motions::match_zone;
use std::process::Command;

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn eleven_real_records_match_both_zones() {
    // The paper's targets (IS 1893 soil I, Z·Sa/g, zones III and V) and the default acceptance:
    // 200 log-spaced periods in 0.05–4 s, each within ±10 % of the target.
    let seeds = eleven_records();
    let cfg = MotionsConfig {
        seeds: SeedsConfig {
            stochastic: None,
            records: Some(RecordSeeds {
                files: Vec::new(),
                units: None,
                dt_s: None,
            }),
        },
        matching: MatchSettings::default(),
        set_mean_min: 1.0,
        allow_unmatched: false,
    };
    assert_eq!(cfg.matching.check_grid_s().len(), 200);
    for zone in ["III", "V"] {
        let target = format!("is1893:zone={zone},soil=I").parse().unwrap();
        let z = match_zone(zone, &target, &seeds, &cfg).unwrap();
        for (name, r) in z.seeds.iter().zip(&z.reports) {
            assert!(r.converged, "zone {zone}: {name} misfit {}", r.worst_misfit);
            assert!(r.worst_misfit <= 0.1);
        }
        assert_eq!(z.kept.len(), 11);
        // The set mean reaches 100 % of the target (after the set scale), hence also ASCE
        // 7-16's 90 %, and every motion is still within the band.
        assert!(
            z.set_mean_ok && z.asce7_ok && z.all_within_band,
            "zone {zone}: {}",
            z.mean_ratio_min
        );
        for (m, psa) in z.motions.iter().zip(&z.psa_g) {
            // Drift: every matched motion ends at rest (the linear end correction, exact up
            // to round-off), and its peak ground displacement stays below 1 m.
            let (v_end, d_end) = drift(&m.accel_g, m.dt_s);
            assert!(
                v_end.abs() < 1e-9 && d_end.abs() < 1e-9,
                "{}: {v_end} {d_end}",
                m.name
            );
            let (mut v, mut d, mut pgd) = (0.0, 0.0f64, 0.0f64);
            for w in m.accel_g.windows(2) {
                let g = slidestack::dynamics::G;
                d += v * m.dt_s + m.dt_s * m.dt_s * g * (2.0 * w[0] + w[1]) / 6.0;
                v += 0.5 * m.dt_s * g * (w[0] + w[1]);
                pgd = pgd.max(d.abs());
            }
            assert!(pgd < 1.0, "{}: PGD {pgd} m", m.name);
            // Within the band after the set scale, checked on the stored motion's own spectrum.
            let own = slidestack::spectrum::response_spectrum(
                &m.accel_mps2(1.0),
                m.dt_s,
                &z.periods_s,
                0.05,
            )
            .unwrap()
            .psa_g();
            for ((p, q), o) in psa.iter().zip(&z.target_psa_g).zip(&own) {
                let r = p / q;
                assert!((o / p - 1.0).abs() < 1e-9, "{}: {o} vs {p}", m.name);
                assert!((0.9..=1.1).contains(&r), "{}: {r}", m.name);
            }
        }
    }
}

#[test]
fn spectrum_command_prints_the_exact_spectrum() {
    let rec = fixture("RSN960_NORTHR_LOS270.AT2");
    let out = run(&[
        "spectrum",
        "--record",
        rec.to_str().unwrap(),
        "--periods",
        "0.1,1,2",
        "--damping",
        "0.02,0.05",
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 2);
    let r = read_record(&rec).unwrap();
    let lib =
        slidestack::spectrum::response_spectrum(&r.accel_mps2(1.0), r.dt_s, &[0.1, 1.0, 2.0], 0.05)
            .unwrap()
            .psa_g();
    let cli: Vec<f64> = v[1]["psa_g"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(cli, lib);
    let out = run(&[
        "spectrum",
        "--record",
        rec.to_str().unwrap(),
        "--periods",
        "0:1:0.1",
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("periods `0:1:0.1`: period 0.0 s is outside 0.001 … 10000 s"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn match_command_writes_accepted_motions_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let rec = fixture(ELEVEN[3]);
    let out = run(&[
        "match",
        "--record",
        rec.to_str().unwrap(),
        "--target",
        "asce7:sds=1.0,sd1=0.6,tl=8",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let matched = read_record(&dir.path().join(ELEVEN[3])).unwrap();
    let seed = read_record(&rec).unwrap();
    assert_eq!(matched.accel_g.len(), seed.accel_g.len());
    assert_eq!(matched.dt_s, seed.dt_s);
    let summary = std::fs::read_to_string(dir.path().join("summary.csv")).unwrap();
    assert!(summary.starts_with("record,converged,iterations,worst_misfit"));
    assert!(summary.lines().nth(1).unwrap().contains(",true,"));

    // A settings file with an unknown key is refused before any work, naming the key.
    let bad = dir.path().join("bad.yaml");
    std::fs::write(&bad, "passes: [10]\ntolerence: 0.05\n").unwrap();
    let out = run(&[
        "match",
        "--record",
        rec.to_str().unwrap(),
        "--target",
        "is1893:zone=III,soil=I",
        "--out",
        dir.path().to_str().unwrap(),
        "--settings",
        bad.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("unknown key `tolerence`"),
        "{}",
        stderr(&out)
    );
    // An impossible value too.
    std::fs::write(&bad, "gain: 1.5\n").unwrap();
    let out = run(&[
        "match",
        "--record",
        rec.to_str().unwrap(),
        "--target",
        "is1893:zone=III,soil=I",
        "--out",
        dir.path().to_str().unwrap(),
        "--settings",
        bad.to_str().unwrap(),
    ]);
    assert!(
        stderr(&out).contains("matching setting `gain` = 1.5: must be in (0, 1]"),
        "{}",
        stderr(&out)
    );
    // A bad target names itself.
    let out = run(&[
        "match",
        "--record",
        rec.to_str().unwrap(),
        "--target",
        "is1893:zone=VI,soil=I",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("invalid --target `is1893:zone=VI,soil=I`"),
        "{}",
        stderr(&out)
    );
}

fn write_config(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    let cfg = dir.join("study.yaml");
    let recs: Vec<String> = ELEVEN[..2]
        .iter()
        .map(|n| format!("        - {}", fixture(n).display()))
        .collect();
    std::fs::write(
        &cfg,
        format!(
            "output_dir: {}\nzones:\n  - {{ name: III, target: \"is1893:zone=III,soil=I\" }}\n\
             motions:\n  seeds:\n    records:\n      files:\n{}\n{extra}",
            dir.join("out").display(),
            recs.join("\n")
        ),
    )
    .unwrap();
    cfg
}

#[test]
fn motions_stage_writes_skips_and_rebuilds() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), "");
    let cfg_s = cfg.to_str().unwrap();
    let out = run(&["motions", cfg_s]);
    assert!(out.status.success(), "{}", stderr(&out));
    let path = dir.path().join("out/motions.h5");
    let zones = slidestack::store::motions::zone_names(&path).unwrap();
    assert_eq!(zones, vec!["III".to_string()]);
    let motions = slidestack::store::motions::read_zone_motions(&path, "III").unwrap();
    let report = slidestack::store::motions::read_zone_report(&path, "III").unwrap();
    assert_eq!(motions.len(), report.iter().filter(|r| r.1).count());
    let s = slidestack::store::motions::read_zone_spectra(&path, "III").unwrap();
    let sizes = (s.periods_s.len(), s.target_psa_g.len(), s.mean_psa_g.len());
    assert_eq!(sizes, (200, 200, 200));
    assert_eq!(s.psa_g.dim(), (motions.len(), 200));
    let before = std::fs::read(&path).unwrap();

    // Up to date: nothing is redone and the file is untouched.
    let out = run(&["motions", cfg_s]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("is up to date"));
    assert_eq!(std::fs::read(&path).unwrap(), before);

    // A changed input rebuilds it.
    let cfg = write_config(
        dir.path(),
        "  allow_unmatched: true\n  set_mean_min: 0.95\n",
    );
    let out = run(&["motions", cfg.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("wrote"));
}

#[test]
fn motions_stage_refuses_bad_configs_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for (extra, want) in [
        ("  colour: red\n", "unknown key `colour`"),
        (
            "  set_mean_min: -1\n",
            "`motions.set_mean_min`: -1 must be in (0, matching.upper]",
        ),
    ] {
        let cfg = write_config(dir.path(), extra);
        let out = run(&["motions", cfg.to_str().unwrap()]);
        assert!(!out.status.success());
        assert!(stderr(&out).contains(want), "{}", stderr(&out));
        assert!(!dir.path().join("out").exists(), "refused before any work");
    }
    let cfg = dir.path().join("bad.yaml");
    std::fs::write(
        &cfg,
        "output_dir: out\nzones: [{ name: III, target: \"is1893:zone=III,soil=I\" }]\n\
         motions: { seeds: { stochastic: { count: 0, seed: 1 } } }\n",
    )
    .unwrap();
    let out = run(&["motions", cfg.to_str().unwrap()]);
    assert!(
        stderr(&out).contains("`motions.seeds.stochastic.count`: must be ≥ 1 and ≤ 10000"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn motions_file_does_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("s.yaml");
    std::fs::write(
        &cfg,
        "output_dir: unused\nzones: [{ name: V, target: \"is1893:zone=V,soil=I\" }]\n\
         motions: { seeds: { stochastic: { count: 2, seed: 7, spare: 1 } } }\n",
    )
    .unwrap();
    let mut read = Vec::new();
    for threads in ["1", "2"] {
        let out_dir = dir.path().join(threads);
        let out = Command::new(env!("CARGO_BIN_EXE_slidestack"))
            .args([
                "motions",
                cfg.to_str().unwrap(),
                "--out",
                out_dir.to_str().unwrap(),
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        let path = out_dir.join("motions.h5");
        read.push((
            slidestack::store::motions::read_zone_motions(&path, "V").unwrap(),
            slidestack::store::motions::read_zone_spectra(&path, "V").unwrap(),
        ));
    }
    assert_eq!(read[0], read[1]);
}

#[test]
fn stochastic_mean_spectrum_peaks_near_the_filter_frequency() {
    // The model's spectral intent: a filter of frequency f_mid (5.87 Hz at t_mid, falling by
    // 0.089 Hz/s) shapes the motion, so the mean 5 %-damped PSA of 100 draws peaks near
    // T = 1/f_mid = 0.17 s. Bound: within a factor 1.5 either side (the filter's damping of 0.21
    // and its drift over the strong phase spread the peak); the peak is also well above the
    // long-period end (ratio > 5 at 2 s).
    let model = slidestack::ground_motion::StochasticModel::default();
    let motions = model.simulate_set(99, 100, "s").unwrap();
    let periods = slidestack::ground_motion::matching::log_space(0.03, 2.0, 120);
    let mut mean = vec![0.0; periods.len()];
    for m in &motions {
        let s = slidestack::spectrum::response_spectrum(&m.accel_mps2(1.0), m.dt_s, &periods, 0.05)
            .unwrap()
            .psa_g();
        for (a, b) in mean.iter_mut().zip(s) {
            *a += b / 100.0;
        }
    }
    let i = (0..periods.len())
        .max_by(|&a, &b| mean[a].total_cmp(&mean[b]))
        .unwrap();
    let t_peak = periods[i];
    let t_filter = 1.0 / model.f_mid_hz;
    assert!(
        t_peak > t_filter / 1.5 && t_peak < t_filter * 1.5,
        "peak of the mean PSA at {t_peak} s, filter period {t_filter} s"
    );
    assert!(mean[i] / mean[periods.len() - 1] > 5.0);
}
