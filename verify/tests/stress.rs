//! The numerical stress suite (`slidestack_verify::stress`): every case passes every check, the known
//! limit stays within the suite's rules where they claim to hold, and each check can fail.

use slidestack::dynamics::{ExactOptions, G, Ground, System, SystemSpec, simulate_exact};
use slidestack_verify::stress::{
    Check, Expect, FRICTION_TOLERANCE, GroundMotion, Reference, RunEnd, Scale, StressCase, cases,
    friction_bound_excess, limit_survey, markdown_table, non_finite_count, refine_linear, run,
    run_all,
};

#[test]
fn every_case_passes_every_check() {
    let all = cases();
    assert!(all.len() >= 25, "only {} cases", all.len());
    let outcomes = run_all(&all);
    let failures: Vec<String> = outcomes.iter().flat_map(|o| o.failures()).collect();
    assert!(
        failures.is_empty(),
        "{} failed checks:\n{}\n\n{}",
        failures.len(),
        failures.join("\n"),
        markdown_table(&outcomes)
    );
    // The suite covers what issue 5 asks for.
    let max_blocks = all.iter().map(|c| c.spec.alpha.len()).max().unwrap();
    let max_duration = all
        .iter()
        .map(|c| c.motion.duration_s())
        .fold(0.0, f64::max);
    let periods: Vec<f64> = all.iter().map(|c| c.spec.period_s).collect();
    assert_eq!(max_blocks, 20);
    assert!(max_duration >= 300.0);
    assert!(periods.contains(&0.01) && periods.contains(&20.0));
    assert!(all.iter().any(|c| c.motion.dt_s() == 0.0005));
    assert!(all.iter().any(|c| c.motion.dt_s() == 0.05));
    assert_eq!(
        all.iter().filter(|c| c.expect == Expect::Zeno).count(),
        1,
        "exactly one case is built to trip the guard"
    );
    // Every case that may slide does (the others are the zero and never-sliding kinds).
    for (c, o) in all.iter().zip(&outcomes) {
        if c.expect == Expect::Completes && o.switch_budget > 0 {
            assert!(o.peak_slip_m > 0.0, "{}: nothing slid", c.name);
        }
    }
}

#[test]
fn long_period_survey_stays_within_the_rules_where_they_claim_to_hold() {
    let points = limit_survey();
    assert_eq!(points.len(), 5 * 3 * 3);
    // Where the φ-function step carries the state (ω_n·dt < 5e-3) the energy balance holds to
    // round-off on either motion, up to T_rigid/dt = 1e7 (the wave gave 5e-3 and 1.1).
    for p in &points {
        let dt_s = if p.motion.contains("0.01 s") {
            0.01
        } else {
            0.0005
        };
        if std::f64::consts::TAU / p.period_rigid_s() * dt_s < 5e-3 {
            let e = p.outcome.energy.value;
            let bound = if p.checked { 1e-12 } else { 1e-7 };
            assert!(
                e < bound,
                "T_p {} s, α {}, {}: {e:e}",
                p.period_s,
                p.alpha,
                p.motion
            );
        }
    }
    let mut failures = Vec::new();
    for p in points.iter().filter(|p| p.checked) {
        for f in p.outcome.failures() {
            failures.push(format!(
                "T_p {} s, α {}, {}: {f}",
                p.period_s, p.alpha, p.motion
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The unchecked column ran to the end with finite numbers all the same.
    for p in points.iter().filter(|p| !p.checked) {
        assert_eq!(p.outcome.end, RunEnd::Completed, "{}", p.motion);
        assert!(p.outcome.non_finite.passed());
    }
}

fn one_block(period_s: f64, mu: f64) -> SystemSpec {
    SystemSpec::new(period_s, &[1.0], &[mu])
}

fn quake(dt_s: f64, pga_g: f64) -> GroundMotion {
    GroundMotion::Stochastic {
        seed: 3,
        dt_s,
        duration_s: 10.0,
        d595_s: 4.0,
        t_mid_s: 3.0,
        scale: Scale::PgaG(pga_g),
    }
}

fn plain_case(spec: SystemSpec, motion: GroundMotion, references: Vec<Reference>) -> StressCase {
    StressCase {
        name: "probe",
        stresses: "a check's ability to fail",
        spec,
        motion,
        expect: Expect::Completes,
        max_switches_per_step: 1000,
        switch_budget: 1_000_000,
        energy_tolerance: 1e-9,
        references,
    }
}

#[test]
fn friction_and_finiteness_checks_catch_a_corrupted_history() {
    let samples = quake(0.01, 0.6).samples().unwrap();
    let ground = Ground {
        dt_s: samples.dt_s,
        accel_mps2: &samples.accel_mps2,
    };
    let sys = System::new(&one_block(0.5, 0.1)).unwrap();
    let opts = ExactOptions {
        history: true,
        ..ExactOptions::default()
    };
    let mut r = simulate_exact(&sys, &ground, &opts).unwrap();
    assert!(r.switches > 0, "the probe must slide");
    assert!(friction_bound_excess(&sys, &r) <= FRICTION_TOLERANCE);
    assert_eq!(non_finite_count(&r), 0);
    // A stuck block asked to carry 1 % more than its static limit, and a slipping one carrying
    // 1 % less than its kinetic force: both are seen (as 1e-3 of the weight plus the forces,
    // 1e6 times the tolerance).
    let h = r.history.as_mut().unwrap();
    let stuck = (0..h.rows()).find(|&k| h.contact[k] == 0).unwrap();
    let slipping = (0..h.rows()).find(|&k| h.contact[k].abs() == 1).unwrap();
    let limit = sys.static_limit(1) / sys.masses()[1];
    h.abs_accel_mps2[2 * stuck + 1] = 1.01 * limit;
    let excess = friction_bound_excess(&sys, &r);
    assert!(excess > 1e-4, "stuck excess {excess:e}");
    let h = r.history.as_mut().unwrap();
    h.abs_accel_mps2[2 * stuck + 1] = 0.0;
    h.abs_accel_mps2[2 * slipping + 1] *= 0.99;
    let excess = friction_bound_excess(&sys, &r);
    assert!(excess > 1e-4, "slipping excess {excess:e}");
    r.history.as_mut().unwrap().abs_accel_mps2[2 * slipping + 1] = f64::NAN;
    assert!(
        friction_bound_excess(&sys, &r).is_nan(),
        "a NaN must not pass"
    );
    r.history.as_mut().unwrap().velocity_mps[7] = f64::NAN;
    r.energy.friction = f64::INFINITY;
    assert_eq!(non_finite_count(&r), 3);
    r.history = None;
    assert!(
        friction_bound_excess(&sys, &r).is_nan(),
        "no history must fail"
    );
}

#[test]
fn references_catch_wrong_answers() {
    let error = |c: &StressCase| -> Result<Check, String> { run(c).references[0].error.clone() };
    // A non-zero record is not zero.
    let c = plain_case(one_block(1.0, 5.0), quake(0.01, 0.1), vec![Reference::Zero]);
    assert!(!error(&c).unwrap().passed());
    // A stack that slides is not the rigid SDOF.
    let c = plain_case(
        one_block(1.0, 0.05),
        quake(0.01, 0.6),
        vec![Reference::RigidSdof { tolerance: 1e-9 }],
    );
    let e = error(&c).unwrap_err();
    assert!(e.contains("slid"), "{e}");
    // Friction at the interface: the structure does not respond alone.
    let c = plain_case(
        one_block(1.0, 0.05),
        quake(0.01, 0.6),
        vec![Reference::Frictionless { tolerance: 1e-9 }],
    );
    assert!(error(&c).unwrap().value > 1e-3);
    // μ_2 < μ_1: the top block slips, the stack is not one block.
    let c = plain_case(
        SystemSpec::new(1.0, &[0.5, 0.5], &[0.2, 0.05]),
        quake(0.01, 1.0),
        vec![Reference::OneBlock { tolerance: 1e-9 }],
    );
    assert!(error(&c).is_err());
    let c = plain_case(
        SystemSpec::new(1.0, &[0.5, 0.5], &[0.05, 0.05]),
        quake(0.01, 1.0),
        vec![Reference::OneBlock { tolerance: 1e-9 }],
    );
    assert!(error(&c).unwrap().passed(), "μ_2 = μ_1 is one block");
    // The hand solution for a step to a different level than the record's.
    let step = |a: f64| GroundMotion::Polyline {
        dt_s: 0.005,
        duration_s: 5.0,
        points: vec![(0.0, 0.0), (0.5, 0.0), (0.505, a)],
    };
    let spec = SystemSpec {
        mu_static: Some(vec![0.4]),
        ..SystemSpec::new(0.01, &[1.0], &[0.2])
    };
    let hand = |a: f64| Reference::StepHand {
        step_s: 0.5,
        accel_mps2: a,
        tolerance: 1e-3,
    };
    let c = plain_case(spec.clone(), step(0.6 * G), vec![hand(0.6 * G)]);
    assert!(error(&c).unwrap().passed());
    let c = plain_case(spec, step(0.6 * G), vec![hand(0.62 * G)]);
    assert!(error(&c).unwrap().value > 1e-2);
    // RK4 with one sub-step per sample is far from the exact answer on a sliding case.
    let c = plain_case(
        one_block(0.3, 0.05),
        quake(0.05, 0.8),
        vec![Reference::Rk4 {
            substeps: 1,
            tolerance: 1e-3,
        }],
    );
    assert!(error(&c).unwrap().value > 1e-3);
}

#[test]
fn ending_switch_and_energy_checks_can_fail() {
    // A guard of one switch per sample on a stack under ±2 g steps: the run is refused as Zeno,
    // which fails a case that expects completion and passes the one built for it.
    let mut c = plain_case(
        SystemSpec::new(0.5, &[0.5, 0.3, 0.2], &[0.3, 0.2, 0.1]),
        GroundMotion::Square {
            dt_s: 0.05,
            duration_s: 2.0,
            amplitude_mps2: 2.0 * G,
            half_period_s: 0.05,
        },
        vec![],
    );
    c.max_switches_per_step = 1;
    let o = run(&c);
    assert!(matches!(o.end, RunEnd::Zeno { .. }), "{:?}", o.end);
    assert!(
        o.failures()[0].contains("expected Completes"),
        "{:?}",
        o.failures()
    );
    c.expect = Expect::Zeno;
    assert!(run(&c).passed());
    // Without the guard it completes, with switches beyond a budget of 0.
    c.expect = Expect::Completes;
    c.max_switches_per_step = ExactOptions::default().max_switches_per_step;
    c.switch_budget = 0;
    let o = run(&c);
    assert_eq!(o.end, RunEnd::Completed);
    assert!(
        o.failures().iter().any(|f| f.contains("exceed the budget")),
        "{:?}",
        o.failures()
    );
    // An energy tolerance below the round-off of the run fails.
    c.switch_budget = u64::MAX;
    c.energy_tolerance = 0.0;
    let o = run(&c);
    assert!(o.energy.value > 0.0);
    assert!(
        o.failures()
            .iter()
            .any(|f| f.contains("probe: energy balance error")),
        "{:?}",
        o.failures()
    );
    // A case that cannot be built is a failure, not a panic.
    c.motion = GroundMotion::Polyline {
        dt_s: 0.01,
        duration_s: 1.0,
        points: vec![(0.0, 0.0), (0.505, 1.0)],
    };
    let o = run(&c);
    assert!(
        matches!(&o.end, RunEnd::Failed(e) if e.contains("grid")),
        "{:?}",
        o.end
    );
    assert!(!o.passed());
}

#[test]
fn ground_motions_are_what_the_cases_say() {
    let mu = 0.3;
    let ramp = GroundMotion::Polyline {
        dt_s: 0.01,
        duration_s: 3.0,
        points: vec![(0.0, 0.0), (1.0, mu * G), (2.0, 0.0)],
    }
    .samples()
    .unwrap();
    assert_eq!(ramp.accel_mps2.len(), 301);
    assert_eq!(ramp.accel_mps2[100], mu * G, "the ramp reaches μ·g exactly");
    assert!(ramp.accel_mps2.iter().all(|&a| a <= mu * G));
    assert_eq!(ramp.accel_mps2[300], 0.0);
    let fine = refine_linear(&ramp, 4);
    assert_eq!(fine.accel_mps2.len(), 1201);
    assert_eq!(fine.dt_s, 0.0025);
    for (k, &a) in ramp.accel_mps2.iter().enumerate() {
        assert_eq!(fine.accel_mps2[4 * k], a);
    }
    let square = GroundMotion::Square {
        dt_s: 0.01,
        duration_s: 1.0,
        amplitude_mps2: 2.0,
        half_period_s: 0.02,
    }
    .samples()
    .unwrap();
    assert_eq!(&square.accel_mps2[..6], &[0.0, 2.0, 2.0, -2.0, -2.0, 2.0]);
    let q = quake(0.01, 0.4).samples().unwrap();
    let pga = q.accel_mps2.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!((pga - 0.4 * G).abs() < 1e-12);
    let tiny = GroundMotion::Stochastic {
        seed: 3,
        dt_s: 0.01,
        duration_s: 10.0,
        d595_s: 4.0,
        t_mid_s: 3.0,
        scale: Scale::Factor(1e-12),
    }
    .samples()
    .unwrap();
    let tiny_pga = tiny.accel_mps2.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!(tiny_pga > 0.0 && tiny_pga < 1e-10);
    let zero = GroundMotion::Zero {
        dt_s: 0.01,
        duration_s: 2.0,
    }
    .samples()
    .unwrap();
    assert!(zero.accel_mps2.iter().all(|&a| a == 0.0));
}
