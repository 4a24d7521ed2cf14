//! The rocking check (docs/model.md, "Rocking: when a case leaves the model") against hand
//! cases: a stuck stack on an undamped structure under a ramp, whose absolute acceleration is
//! a closed form, so the onset time is the root of an equation the test solves itself; a stuck
//! stack under a real record, whose peak absolute acceleration is the exact response spectrum's
//! `ω²·S_d`, with ratios a hair above and below it; a sliding block, whose acceleration friction
//! caps at `μ_s·g`.

mod common;

use common::real_records;
use slidestack::dynamics::building::{
    Building, BuildingSpec, StackSpec, simulate_building, simulate_building_rk4,
};
use slidestack::dynamics::{
    ExactOptions, G, Ground, RockingOnset, System, SystemSpec, simulate_exact, simulate_rk4,
};
use slidestack::spectrum::peak_response;
use std::f64::consts::TAU;

/// Friction no record here overcomes: the stack moves with the structure.
const STUCK_MU: f64 = 1e3;

/// An undamped one-storey system of period `period_s` carrying blocks `alpha` that never slide,
/// with ratios `aspect`.
fn stuck(period_s: f64, alpha: &[f64], aspect: &[f64]) -> System {
    let spec = SystemSpec {
        damping_ratio: 0.0,
        ..SystemSpec::new(period_s, alpha, &vec![STUCK_MU; alpha.len()])
    };
    System::new(&spec).unwrap().with_aspect(aspect).unwrap()
}

/// A ground acceleration rising from 0 at `slope_mps3`, `steps` samples `dt_s` apart.
fn ramp(slope_mps3: f64, dt_s: f64, steps: usize) -> Vec<f64> {
    (0..=steps).map(|k| slope_mps3 * k as f64 * dt_s).collect()
}

/// The absolute acceleration of an undamped oscillator of circular frequency `omega` at rest
/// under the ramp `a_g = s·t`: `u = −(s/ω²)(t − sin(ωt)/ω)`, so `a = a_g + ü = s·(t − sin(ωt)/ω)`,
/// which never decreases; the time it reaches `level` by bisection.
fn ramp_crossing(slope: f64, omega: f64, level: f64) -> f64 {
    let a = |t: f64| slope * (t - (omega * t).sin() / omega);
    let (mut lo, mut hi) = (0.0, 1.0);
    while a(hi) < level {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if a(mid) < level { lo = mid } else { hi = mid }
    }
    hi
}

fn opts() -> ExactOptions {
    ExactOptions::default()
}

/// The ramp's onset times are exact: one block rocks at `|a| = g·b/h`; two equal stuck blocks
/// are one block twice as tall, rocking at half the ratio on the bottom block's base; the same
/// through the building's modal integrator (one storey, so the same closed form). Tolerance
/// 1e-9 s: the searches refine a crossing to a few ulps of the step, and the structure's state
/// carries round-off of about 1e-13 relative over the ramp's samples.
#[test]
fn a_stuck_stack_under_a_ramp_rocks_when_the_closed_form_says() {
    let (slope, dt, steps) = (0.4 * G, 0.01, 1000); // 0.4 g per second, 10 s
    let (period, alpha) = (0.7, 0.5);
    // The stuck system's period is T·sqrt(1 + Σα).
    for (blocks, aspect, level_g, block) in [
        (1, vec![0.3], 0.3, 1),
        (2, vec![0.6, 0.6], 0.3, 1),
        // Masses 0.25 each, h/w = 1/0.9 and 4: the bottom group's ratio is 1/Σw =
        // 0.5/(2·0.25·(0.5/0.9 + 1/0.9 + 2)) = 0.273, so the top block alone (0.25) rocks first.
        (2, vec![0.9, 0.25], 0.25, 2),
    ] {
        let alphas = vec![alpha / blocks as f64; blocks];
        let sys = stuck(period, &alphas, &aspect);
        let omega = TAU / (period * (1.0f64 + alpha).sqrt());
        let expect = ramp_crossing(slope, omega, level_g * G);
        let accel = ramp(slope, dt, steps);
        let ground = Ground::new(dt, &accel);
        let r = simulate_exact(&sys, &ground, &opts()).unwrap();
        let onset = r.rocking_onset.expect("the ramp passes the level");
        assert_eq!(onset.block, block, "{aspect:?}");
        assert!(
            (onset.time_s - expect).abs() < 1e-9,
            "{aspect:?}: {onset:?} vs {expect}"
        );
        // The building's modal integrator on the same one storey.
        let mut spec = BuildingSpec::uniform(1, period);
        spec.damping_ratio = 0.0;
        spec.stacks = vec![StackSpec {
            aspect: Some(aspect.clone()),
            ..StackSpec::new(1, &alphas, &vec![STUCK_MU; blocks])
        }];
        let b = Building::new(&spec).unwrap();
        let rb = simulate_building(&b, &ground, &opts()).unwrap();
        let onset = rb.rocking_onset[0].expect("the ramp passes the level");
        assert_eq!(onset.block, block);
        assert!(
            (onset.time_s - expect).abs() < 1e-9,
            "{onset:?} vs {expect}"
        );
        // RK4 checks at its sub-steps' starts: the first sub-step at or after the crossing.
        let substeps = 10;
        let h = dt / substeps as f64;
        for onset in [
            simulate_rk4(&sys, &ground, substeps, false)
                .unwrap()
                .rocking_onset,
            simulate_building_rk4(&b, &ground, substeps, false)
                .unwrap()
                .rocking_onset[0],
        ] {
            let RockingOnset { block: got, time_s } = onset.unwrap();
            assert_eq!(got, block);
            assert!(
                time_s >= expect - 1e-9 && time_s < expect + h + 1e-9,
                "{time_s} vs {expect}"
            );
        }
    }
}

/// A stuck block on an undamped structure moves with it: its peak absolute acceleration is
/// `ω²·S_d` at `T_rigid`, from the exact response spectrum (an independent code path). A ratio
/// 1e-9 above that peak over g never rocks; 1e-9 below it rocks, at most 1 ms before the
/// spectrum's peak time (a smooth maximum is crossed within `sqrt(2·1e-9)/ω` of its time).
#[test]
fn a_stuck_block_rocks_exactly_when_its_peak_exceeds_g_times_its_ratio() {
    let period = 0.5;
    for record in real_records() {
        let accel = record.accel_mps2(1.0);
        let ground = Ground::new(record.dt_s, &accel);
        let t_rigid = period * 1.5f64.sqrt();
        let peak = peak_response(&accel, record.dt_s, t_rigid, 0.0).unwrap();
        let peak_g = (TAU / t_rigid).powi(2) * peak.sd_m / G;
        for (factor, rocks) in [(1.0 + 1e-9, false), (1.0 - 1e-9, true)] {
            let sys = stuck(period, &[0.5], &[peak_g * factor]);
            let r = simulate_exact(&sys, &ground, &opts()).unwrap();
            assert_eq!(
                r.rocking_onset.is_some(),
                rocks,
                "{}: {factor}",
                record.name
            );
            if let Some(onset) = r.rocking_onset {
                assert_eq!(onset.block, 1);
                assert!(onset.time_s <= peak.time_s + 1e-12, "{}", record.name);
                assert!(
                    peak.time_s - onset.time_s < 1e-3,
                    "{}: {onset:?}",
                    record.name
                );
            }
        }
    }
}

/// The same in a building: a stuck stack on the roof of three storeys rides the roof, so the
/// roof's peak absolute acceleration (the integrator's floor peak, tested against independent
/// oracles in tests/building.rs) decides: a ratio a hair below it over g rocks, a hair above
/// does not.
#[test]
fn a_stuck_stack_on_a_roof_rocks_exactly_when_the_roof_peak_exceeds_its_ratio() {
    let record = &real_records()[1];
    let accel = record.accel_mps2(1.0);
    let ground = Ground::new(record.dt_s, &accel);
    let building = |aspect: Option<f64>| {
        let mut spec = BuildingSpec::uniform(3, 0.6);
        spec.stacks = vec![StackSpec {
            aspect: aspect.map(|a| vec![a]),
            ..StackSpec::new(3, &[0.5], &[STUCK_MU])
        }];
        Building::new(&spec).unwrap()
    };
    let r = simulate_building(&building(None), &ground, &opts()).unwrap();
    assert_eq!(r.rocking_onset, vec![None]);
    let roof_g = r.floor_peak_abs_accel_mps2[2] / G;
    for (factor, rocks) in [(1.0 + 1e-9, false), (1.0 - 1e-9, true)] {
        let rb = simulate_building(&building(Some(roof_g * factor)), &ground, &opts()).unwrap();
        assert_eq!(rb.rocking_onset[0].is_some(), rocks, "{factor}");
        assert_eq!(rb.floor_peak_abs_accel_mps2, r.floor_peak_abs_accel_mps2);
    }
}

/// Friction caps a sliding block's acceleration at `μ_s·g` (the static limit, reached at
/// break-away; `μ_k·g` while it slips): under a record strong enough to slide it, a ratio just
/// above `μ_s` never rocks whatever the shaking, one just below does.
#[test]
fn a_block_that_slides_first_never_rocks() {
    let (mu, mu_s) = (0.15, 0.2);
    for record in real_records() {
        let accel = record.accel_mps2(2.0);
        let ground = Ground::new(record.dt_s, &accel);
        for (aspect, rocks) in [(mu_s * (1.0 + 1e-6), false), (mu_s * (1.0 - 1e-6), true)] {
            let spec = SystemSpec {
                mu_static: Some(vec![mu_s]),
                ..SystemSpec::new(0.5, &[0.5], &[mu])
            };
            let sys = System::new(&spec).unwrap().with_aspect(&[aspect]).unwrap();
            let r = simulate_exact(&sys, &ground, &opts()).unwrap();
            assert!(r.peak_slip_m[0] > 1e-3, "{}: it slides", record.name);
            assert_eq!(
                r.rocking_onset.is_some(),
                rocks,
                "{}: {aspect}",
                record.name
            );
        }
    }
}

fn simulate_json(args: &[&str]) -> serde_json::Value {
    let out = common::ok(common::slidestack(args, "1"));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `simulate --json`: without `aspect` nothing is said of rocking; with it the ratios are echoed
/// and `rocking_onset` is `null` or `{block, time_s}` (one storey at the top level, a building
/// per stack); the run's other numbers do not change (the check only watches).
#[test]
fn simulate_reports_the_onset_only_when_asked_and_changes_nothing_else() {
    let base = [
        "simulate", "--alpha", "0.5,0.5", "--mu", "0.3,0.2", "--json",
    ];
    let plain = simulate_json(&base);
    assert!(plain.get("rocking_onset").is_none() && plain.get("aspect").is_none());
    let with = |aspect: &str| simulate_json(&[&base[..], &["--aspect", aspect]].concat());
    let calm = with("1,1");
    assert!(calm["rocking_onset"].is_null());
    assert_eq!(calm["aspect"], serde_json::json!([1.0, 1.0]));
    let rocks = with("0.5,0.15");
    assert_eq!(rocks["rocking_onset"]["block"], 2);
    assert!(rocks["rocking_onset"]["time_s"].as_f64().unwrap() > 0.0);
    // Every other key, bit for bit (the check only watches), here and on a stack that never
    // slides (the integrator's quiet intervals are not taken while the check looks).
    let without = |mut v: serde_json::Value| {
        let m = v.as_object_mut().unwrap();
        m.remove("aspect");
        m.remove("rocking_onset");
        v
    };
    assert_eq!(without(rocks), plain);
    assert_eq!(without(calm), plain);
    let stuck = [
        "simulate", "--alpha", "0.5,0.5", "--mu", "0.9,0.9", "--json",
    ];
    let aspect = ["--aspect", "5,5"];
    assert_eq!(
        without(simulate_json(&[&stuck[..], &aspect].concat())),
        simulate_json(&stuck)
    );
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("building.yaml");
    std::fs::write(
        &case,
        "building: {storeys: 3, period: 0.6}\nstacks:\n  \
         - {floor: roof, alpha: [0.5, 0.5], mu: [0.3, 0.2], aspect: [0.5, 0.15]}\n  \
         - {floor: 1, alpha: [0.5], mu: [0.3], aspect: [2.0]}\n  \
         - {floor: 2, alpha: [0.5], mu: [0.3]}\n",
    )
    .unwrap();
    let b = simulate_json(&["simulate", "--config", case.to_str().unwrap(), "--json"]);
    let stacks = b["stacks"].as_array().unwrap();
    assert_eq!(stacks[0]["rocking_onset"]["block"], 2);
    assert!(
        stacks[1]["rocking_onset"].is_null() && stacks[1]["aspect"] == serde_json::json!([2.0])
    );
    assert!(stacks[2].get("rocking_onset").is_none());
}

/// A one-storey `--aspect` of the wrong length, ≤ 0 or not finite: exit 2, the key named, before
/// the record is read.
#[test]
fn a_bad_aspect_is_refused_naming_it() {
    for (aspect, expect) in [
        ("0.5", "aspect lists 1 values but the stack has 2 blocks"),
        (
            "0.5,0",
            "aspect_2 (width over height of block 2) must be finite and > 0, got 0",
        ),
        (
            "-1,0.5",
            "aspect_1 (width over height of block 1) must be finite and > 0, got -1",
        ),
        (
            "0.5,inf",
            "aspect_2 (width over height of block 2) must be finite and > 0, got inf",
        ),
        (
            "NaN,0.5",
            "aspect_1 (width over height of block 1) must be finite and > 0, got NaN",
        ),
    ] {
        let out = common::slidestack(
            &[
                "simulate",
                "--record",
                "/nonexistent/r.AT2",
                "--alpha",
                "0.5,0.5",
                "--mu",
                "0.3,0.2",
                "--aspect",
                aspect,
            ],
            "1",
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{aspect}: {err}");
        assert!(err.contains(expect), "{aspect}: {err}");
        assert!(!err.contains("/nonexistent"), "{err}");
    }
}

/// A study with `grid.aspect` (configs/quick.yaml with it, one storey): `sweep.h5`'s
/// `rocks_stack` is, for every zone, motion and case, whether `simulate` of that case under
/// that motion says it rocks (most cases take a skip rule, whose flag comes from the system
/// standing in for the stack: here checked against the stack itself); the report's table
/// counts them; `tnew.h5` keeps each case's share of rocking motions and `design` warns where
/// it is above 0. The same config without `aspect` stores neither and shows no section.
#[test]
fn a_study_stores_which_cases_rock_the_report_counts_them_and_design_warns() {
    use slidestack::one_case::{Outcome, Settings};
    use slidestack::store::motions::read_zone_motions;
    use slidestack::store::sweep::read_zone_sweep;
    let dir = tempfile::tempdir().unwrap();
    let quick = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quick.yaml"),
    )
    .unwrap();
    let config = |name: &str, aspect: &str| {
        let out = dir.path().join(name);
        let text = quick
            .replace(
                "output_dir: out/quick",
                &format!("output_dir: {}", out.display()),
            )
            .replace(
                "  damping_basis: rigid\n",
                &format!("  damping_basis: rigid\n{aspect}"),
            );
        let path = dir.path().join(format!("{name}.yaml"));
        std::fs::write(&path, text).unwrap();
        common::ok(common::slidestack(&["run", path.to_str().unwrap()], "2"));
        out
    };
    let out = config("rocking", "  aspect: [0.8, 0.25]\n");
    let (mut runs, mut rocking) = (0, 0);
    let mut per_zone = Vec::new();
    for zone in ["III", "V"] {
        let (grid, _, sweep) = read_zone_sweep(&out.join("sweep.h5"), zone, 2, false).unwrap();
        let motions = read_zone_motions(&out.join("motions.h5"), zone).unwrap();
        let rocks = sweep.rocks_stack.expect("stored with grid.aspect");
        let mut count = 0;
        for (idx, &flag) in rocks.indexed_iter() {
            let settings = Settings {
                period: Some(grid.periods_s[idx[1]]),
                alpha: Some(vec![grid.alpha[0][idx[2]], grid.alpha[1][idx[3]]]),
                mu: Some(vec![grid.mu[0][idx[4]], grid.mu[1][idx[5]]]),
                aspect: Some(vec![0.8, 0.25]),
                ..Settings::default()
            };
            let sim = settings.resolve_with(motions[idx[0]].clone()).unwrap();
            let (outcome, _) = sim.run(&sim.accel_mps2()).unwrap();
            let Outcome::OneStorey(s) = outcome else {
                panic!("one storey")
            };
            let rocks = s.rocking_onset.expect("checked").is_some();
            assert_eq!(flag, u8::from(rocks), "zone {zone} {idx:?}");
            // The same runs check the goods' own demands the sweep stores per block: those of
            // the stack simulated, or under a skip rule of the body every block moves with
            // (two exact solutions: 1e-9 relative, as tests/sweep.rs; an interface that never
            // slips ends at 0).
            for b in 0..2 {
                let mut at = ndarray::Dimension::slice(&idx).to_vec();
                at.push(b);
                let close = |stored: f64, direct: f64, what: &str| {
                    let scale = stored.abs().max(direct.abs()).max(1e-12);
                    assert!(
                        (stored - direct).abs() <= 1e-9 * scale,
                        "zone {zone} {idx:?} block {}: {what} {stored} vs {direct}",
                        b + 1
                    );
                };
                close(
                    sweep.vars.block_accel_stack[&at[..]],
                    s.peak_abs_accel_g[b + 1],
                    "block_accel_stack",
                );
                close(
                    sweep.vars.block_velocity_stack[&at[..]],
                    s.peak_abs_velocity_mps[b + 1],
                    "block_velocity_stack",
                );
                let residual = sweep.vars.slip_residual[&at[..]];
                assert!(
                    (residual - s.residual_slip_m[b]).abs() <= 1e-9,
                    "zone {zone} {idx:?} interface {}: {residual} vs {}",
                    b + 1,
                    s.residual_slip_m[b]
                );
            }
            count += usize::from(rocks);
            runs += 1;
        }
        rocking += count;
        per_zone.push(format!("{count} of {}", rocks.len()));
    }
    assert!(rocking > 0 && rocking < runs, "{rocking} of {runs}");
    let report = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(report.contains("Where the stacks would rock"));
    for counted in &per_zone {
        assert!(report.contains(&format!("({counted})")), "{counted}");
    }
    // tnew.h5's rocks_share is the flags' mean over the motions, and `design` warns where it
    // is above 0 (at a grid case, its share exactly).
    let (grid, _, sweep) = read_zone_sweep(&out.join("sweep.h5"), "V", 2, false).unwrap();
    let rocks = sweep.rocks_stack.unwrap().mapv(f64::from);
    let share = rocks.mean_axis(ndarray::Axis(0)).unwrap();
    let (_, _, t) =
        slidestack::store::tnew::read_zone_tnew_in(&out.join("tnew.h5"), "V", 2, false).unwrap();
    assert_eq!(t.rocks_share.as_ref(), Some(&share));
    let mut warned = [false; 2];
    for (idx, &s) in share.indexed_iter() {
        let q = slidestack::study::design::Query {
            zone: "V".into(),
            period_s: grid.periods_s[idx[0]],
            alpha: vec![grid.alpha[0][idx[1]], grid.alpha[1][idx[2]]],
            mu: vec![grid.mu[0][idx[3]], grid.mu[1][idx[4]]],
            extrapolate: false,
            building: None,
        };
        let a = slidestack::design::design(&out, &q).unwrap();
        assert!((a.rocks_share.unwrap() - s).abs() < 1e-12, "{idx:?}");
        let note = a.notes.iter().any(|n| n.starts_with("rocking:"));
        assert_eq!(note, s > 0.0, "{idx:?}");
        warned[usize::from(note)] = true;
    }
    assert_eq!(warned, [true, true]);
    let plain = config("plain", "");
    let (_, _, sweep) = read_zone_sweep(&plain.join("sweep.h5"), "III", 2, false).unwrap();
    assert!(sweep.rocks_stack.is_none());
    let report = std::fs::read_to_string(plain.join("report/index.html")).unwrap();
    assert!(!report.contains("Where the stacks would rock"));
    let (_, _, t) =
        slidestack::store::tnew::read_zone_tnew_in(&plain.join("tnew.h5"), "V", 2, false).unwrap();
    assert!(t.rocks_share.is_none());
}

/// Sliding stacks under real records, against the integrator's own history on the record
/// refined 16 times (the same ground motion, sampled densely; each row the exact state): no
/// sampled instant before the reported onset has the criterion exceeded, and the first sampled
/// instant that has it comes at or after the onset. A check skipped over some stretch of the
/// record (a quiet interval, say) would report a later onset or none, and fail here.
#[test]
fn no_sampled_instant_rocks_before_the_reported_onset() {
    const REFINE: usize = 16;
    let mut onsets = 0;
    for record in real_records() {
        let fine = {
            let a = &record.accel_g;
            let mut v = Vec::with_capacity(a.len() * REFINE);
            for w in a.windows(2) {
                v.extend((0..REFINE).map(|k| w[0] + (w[1] - w[0]) * k as f64 / REFINE as f64));
            }
            v.push(*a.last().unwrap());
            v.iter().map(|g| g * G).collect::<Vec<f64>>()
        };
        let dt = record.dt_s / REFINE as f64;
        for (period, alpha, mu, mu_s, aspect) in [
            (
                0.3,
                vec![0.5, 0.5],
                vec![0.15, 0.1],
                vec![0.2, 0.12],
                vec![0.35, 0.11],
            ),
            (
                0.8,
                vec![0.3, 0.3, 0.3],
                vec![0.2, 0.3, 0.05],
                vec![0.25, 0.3, 0.08],
                vec![0.5, 0.3, 0.07],
            ),
            (
                1.5,
                vec![1.0, 0.2],
                vec![0.3, 0.1],
                vec![0.3, 0.2],
                vec![0.3, 0.15],
            ),
            // Mostly stuck: the pair rocks as one (ratio 0.3) while quiet stretches abound.
            (
                0.5,
                vec![0.4, 0.4],
                vec![0.6, 0.6],
                vec![0.6, 0.6],
                vec![0.6, 0.6],
            ),
            (
                0.5,
                vec![0.4, 0.4],
                vec![0.05, 0.4],
                vec![0.06, 0.4],
                vec![0.25, 0.05],
            ),
        ] {
            let spec = SystemSpec {
                mu_static: Some(mu_s),
                ..SystemSpec::new(period, &alpha, &mu)
            };
            let sys = System::new(&spec).unwrap().with_aspect(&aspect).unwrap();
            let opts = ExactOptions {
                history: true,
                ..ExactOptions::default()
            };
            let r = simulate_exact(&sys, &Ground::new(dt, &fine), &opts).unwrap();
            let h = r.history.unwrap();
            let rocking = sys.rocking().unwrap();
            let first = (0..h.rows()).find(|&k| {
                let row = &h.abs_accel_mps2[k * h.bodies + 1..(k + 1) * h.bodies];
                rocking.rocking_interface(row).is_some()
            });
            let what = format!("{} T={period} {aspect:?}", record.name);
            match (r.rocking_onset, first) {
                (None, None) => {}
                (Some(o), None) => assert!(o.time_s.is_finite(), "{what}"),
                (None, Some(k)) => panic!("{what}: sampled at {} s, none reported", h.time_s[k]),
                (Some(o), Some(k)) => {
                    assert!(
                        o.time_s <= h.time_s[k] + 1e-12,
                        "{what}: {o:?} after {}",
                        h.time_s[k]
                    );
                    onsets += 1;
                }
            }
        }
    }
    assert!(onsets >= 10, "{onsets}");
}
