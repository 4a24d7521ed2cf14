//! The building's RK4 reference (`simulate_building_rk4`) against the building's exact
//! integrator and against the one-storey RK4 (docs/model.md, "A multi-storey building").

#![allow(clippy::needless_range_loop)]

mod common;

use common::{column, max_rel_diff, real_records};
use slidestack::dynamics::building::{
    Building, BuildingResponse, BuildingSpec, DampingBasis, StackSpec, StoreyYielding,
    simulate_building, simulate_building_rk4,
};
use slidestack::dynamics::{
    ExactOptions, Ground, SimError, System, SystemSpec, Yielding, simulate_rk4,
};
use slidestack::limits::{MAX_RK4_SUBSTEPS, RK4_MAX_OMEGA_STEP};

const HIST: ExactOptions = ExactOptions {
    history: true,
    max_switches_per_step: 1000,
    energy_balance: true,
    abs_velocity: true,
    floor_displacements: true,
};

/// Three storeys (stiffnesses 3:2:1, first period 0.6 s), a two-block stack on floor 3 and one
/// block on floor 1.
fn two_stacks() -> BuildingSpec {
    let mut s = BuildingSpec::uniform(3, 0.6);
    s.storey_stiffnesses = vec![3.0, 2.0, 1.0];
    s.stacks = vec![
        StackSpec::new(3, &[0.5, 0.5], &[0.2, 0.1]),
        StackSpec::new(1, &[1.0], &[0.3]),
    ];
    s
}

/// `max_i |a_i − b_i| / max_j |b_j|`.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    max_rel_diff(a, b, scale)
}

/// The largest error of any body's displacement history over that body's peak.
fn history_error(r: &BuildingResponse, e: &BuildingResponse) -> f64 {
    let (h, he) = (r.history.as_ref().unwrap(), e.history.as_ref().unwrap());
    (0..he.bodies)
        .map(|j| {
            rel(
                &column(&h.displacement_m, h.bodies, j),
                &column(&he.displacement_m, he.bodies, j),
            )
        })
        .fold(0.0, f64::max)
}

/// Order of convergence between the first and last `(sub-steps, error)` pairs.
fn order(errs: &[(usize, f64)]) -> f64 {
    let ((s0, e0), (s1, e1)) = (errs[0], errs[errs.len() - 1]);
    (e0 / e1).ln() / (s1 as f64 / s0 as f64).ln()
}

/// RK4 converges to the exact integrator at about first order with sliding (switches resolved
/// to a sub-step). Two stacks on floors 3 and 1 under RSN829 (96 switches). Measured errors at
/// 5, 20, 80, 320 sub-steps: peak floor displacements 8.1e-4, 1.3e-4, 2.5e-5, 1.5e-5 (of each
/// floor's largest); peak slips 4.2e-3, 2.5e-3, 3.1e-4, 7.2e-5; displacement histories 4.0e-2,
/// 1.1e-2, 1.6e-3, 3.3e-4 (order 1.15 from 5 to 320). The switch count equals the exact one
/// (96) at every step. Asserted: order above 0.8 on each measure, the history error falling at
/// every refinement, and at 320 sub-steps peaks within 5e-5, slips within 2e-4, histories
/// within 1e-3.
#[test]
fn rk4_converges_to_the_exact_integrator_with_two_stacks() {
    let rec = &real_records()[0];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let b = Building::new(&two_stacks()).unwrap();
    let exact = simulate_building(&b, &ground, &HIST).unwrap();
    assert!(
        exact.peak_slip_m.iter().all(|&s| s > 1e-2),
        "every block slides"
    );
    let (mut peaks, mut slips, mut hists) = (vec![], vec![], vec![]);
    for sub in [5, 20, 80, 320] {
        let r = simulate_building_rk4(&b, &ground, sub, true).unwrap();
        let (h, he) = (r.history.as_ref().unwrap(), exact.history.as_ref().unwrap());
        assert_eq!(h.bodies, he.bodies);
        assert_eq!(h.time_s, he.time_s);
        assert_eq!(h.displacement_m.len(), he.displacement_m.len());
        assert_eq!(h.abs_accel_mps2.len(), he.abs_accel_mps2.len());
        assert_eq!(h.contact.len(), he.contact.len());
        peaks.push((
            sub,
            rel(
                &r.floor_peak_displacement_m,
                &exact.floor_peak_displacement_m,
            ),
        ));
        slips.push((sub, rel(&r.peak_slip_m, &exact.peak_slip_m)));
        hists.push((sub, history_error(&r, &exact)));
        if sub == 320 {
            assert_eq!(r.switches, exact.switches);
        }
    }
    eprintln!("errors (sub-steps, error): peaks {peaks:?}; slips {slips:?}; histories {hists:?}");
    for errs in [&peaks, &slips, &hists] {
        assert!(order(errs) > 0.8, "order {} of {errs:?}", order(errs));
    }
    assert!(hists.windows(2).all(|w| w[1].1 < w[0].1), "{hists:?}");
    assert!(peaks[3].1 < 5e-5, "{peaks:?}");
    assert!(slips[3].1 < 2e-4, "{slips:?}");
    assert!(hists[3].1 < 1e-3, "{hists:?}");
}

/// Two stacks on one floor: the top-down rule takes them in the order given, each split
/// re-solving the floor's acceleration, so a stack decided before a split on its floor sees it
/// a sub-step later; that costs nothing in order. Both stacks of `two_stacks` on floor 3 under
/// RSN960 (44 switches). Measured at 5, 20, 80, 320, 1280 sub-steps: peak slips 3.8e-3, 2.6e-3,
/// 1.3e-4, 1.7e-4, 7.6e-6 (order 1.12; the peaks converge irregularly, hence the longer run);
/// displacement histories 1.8e-2, 3.1e-3, 1.2e-3, 1.4e-4, 7.9e-5 (order 0.98). Asserted: order
/// above 0.8 on both, and at 1280 sub-steps slips within 5e-5, histories within 3e-4.
#[test]
fn two_stacks_on_one_floor_converge_too() {
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let mut spec = two_stacks();
    spec.stacks[1].floor = 3;
    let b = Building::new(&spec).unwrap();
    let exact = simulate_building(&b, &ground, &HIST).unwrap();
    assert!(
        exact.peak_slip_m.iter().all(|&s| s > 1e-2),
        "every block slides"
    );
    let (mut slips, mut hists) = (vec![], vec![]);
    for sub in [5, 20, 80, 320, 1280] {
        let r = simulate_building_rk4(&b, &ground, sub, true).unwrap();
        slips.push((sub, rel(&r.peak_slip_m, &exact.peak_slip_m)));
        hists.push((sub, history_error(&r, &exact)));
    }
    eprintln!("errors (sub-steps, error): slips {slips:?}; histories {hists:?}");
    for errs in [&slips, &hists] {
        assert!(order(errs) > 0.8, "order {} of {errs:?}", order(errs));
    }
    assert!(slips[4].1 < 5e-5, "{slips:?}");
    assert!(hists[4].1 < 3e-4, "{hists:?}");
}

/// Without stacks the elastic building's equations are smooth within each sample interval (the
/// ground linear in it, sub-steps aligned with the samples), so RK4 is fourth order. Measured
/// displacement-history errors (of the peak) against the exact integrator at 1, 2, 4, 8, 16
/// sub-steps: 1.2e-4, 7.5e-6, 4.7e-7, 2.9e-8, 1.8e-9, ratios 15.9, 16.1, 16.1, 16.0 (1.1e-10
/// at 32, still far above the exact integrator's round-off).
#[test]
fn a_bare_elastic_building_is_fourth_order() {
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let mut spec = two_stacks();
    spec.stacks.clear();
    let b = Building::new(&spec).unwrap();
    let exact = simulate_building(&b, &ground, &HIST).unwrap();
    let errs: Vec<f64> = [1, 2, 4, 8, 16]
        .iter()
        .map(|&sub| {
            history_error(
                &simulate_building_rk4(&b, &ground, sub, true).unwrap(),
                &exact,
            )
        })
        .collect();
    let ratios: Vec<f64> = errs.windows(2).map(|w| w[0] / w[1]).collect();
    eprintln!("errors {errs:?}, ratios {ratios:?}");
    assert!(
        ratios.iter().all(|r| (14.0..18.0).contains(r)),
        "{ratios:?}"
    );
}

/// Yielding storeys (return mapping per storey) with lighter friction, so that the building
/// both yields (128 yield and unloading events, storey ductilities 6.3, 4.8, 11.0) and slides
/// (115 switches) under RSN960. Measured at 5, 20, 80, 320 sub-steps: storey ductilities
/// 1.3e-4, 6.6e-5, 1.8e-5, 6.4e-6 (of the largest; order 0.73, peaks being sampled); peak slips
/// 3.0e-3, 6.4e-4, 9.6e-5, 1.5e-5 (order 1.28); displacement histories 3.8e-3, 8.7e-4, 1.6e-4,
/// 4.3e-5 (order 1.07); hysteretic energy 1.0e-4, 3.5e-5, 1.1e-5, 3.1e-6 (order 0.84). Yield
/// events and switches equal the exact ones at every step. Asserted: order above 0.8 on slips
/// and histories, above 0.6 on ductility and hysteretic energy, and the values at 320 below
/// 2e-5 (ductility), 1e-4 (slips), 2e-4 (histories), 1e-5 (hysteretic energy).
#[test]
fn a_yielding_building_converges_to_the_exact_integrator() {
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let mut spec = two_stacks();
    spec.stacks[0].mu = vec![0.05, 0.1];
    spec.stacks[1].mu = vec![0.08];
    spec.yielding = Some(StoreyYielding {
        strength_ratios: vec![0.15, 0.12, 0.1],
        post_yield_ratio: 0.05,
    });
    let b = Building::new(&spec).unwrap();
    let exact = simulate_building(&b, &ground, &HIST).unwrap();
    let mu_exact = exact.storey_ductility.clone().unwrap();
    assert!(mu_exact.iter().all(|&m| m > 2.0), "every storey yields");
    assert!(exact.peak_slip_m[0] > 1e-2 && exact.peak_slip_m[2] > 1e-2);
    let (mut duct, mut slips, mut hists, mut hyst) = (vec![], vec![], vec![], vec![]);
    for sub in [5, 20, 80, 320] {
        let r = simulate_building_rk4(&b, &ground, sub, true).unwrap();
        duct.push((sub, rel(r.storey_ductility.as_ref().unwrap(), &mu_exact)));
        slips.push((sub, rel(&r.peak_slip_m, &exact.peak_slip_m)));
        hists.push((sub, history_error(&r, &exact)));
        hyst.push((
            sub,
            (r.energy.hysteretic - exact.energy.hysteretic).abs() / exact.energy.hysteretic,
        ));
        if sub == 320 {
            assert_eq!(r.yield_events, exact.yield_events);
            assert_eq!(r.switches, exact.switches);
        }
    }
    eprintln!(
        "errors (sub-steps, error): ductility {duct:?}; slips {slips:?}; histories {hists:?}; \
         hysteretic {hyst:?}"
    );
    for errs in [&slips, &hists] {
        assert!(order(errs) > 0.8, "order {} of {errs:?}", order(errs));
    }
    for errs in [&duct, &hyst] {
        assert!(order(errs) > 0.6, "order {} of {errs:?}", order(errs));
    }
    assert!(duct[3].1 < 2e-5, "{duct:?}");
    assert!(slips[3].1 < 1e-4, "{slips:?}");
    assert!(hists[3].1 < 2e-4, "{hists:?}");
    assert!(hyst[3].1 < 1e-5, "{hyst:?}");
}

/// RK4's energy balance closes to its own accuracy: the pattern is frozen within a sub-step,
/// so the energy rates are smooth there and integrated with the state (fourth order), and the
/// kinetic energy removed by merging at-rest groups is booked exactly as friction. Measured
/// largest residual over the input at 5, 20, 80, 320 sub-steps: 2.5e-6, 1.2e-8, 5.0e-11,
/// 1.9e-13 (order 3.9). The energy terms themselves converge to the exact ones at first order
/// (friction 2.8e-3 at 5 sub-steps, 3.5e-5 at 320).
#[test]
fn the_energy_balance_closes_to_rk4_accuracy() {
    let rec = &real_records()[0];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let b = Building::new(&two_stacks()).unwrap();
    let exact = simulate_building(&b, &ground, &ExactOptions::default()).unwrap();
    let mut bal = Vec::new();
    for sub in [5, 20, 80, 320] {
        let r = simulate_building_rk4(&b, &ground, sub, false).unwrap();
        assert!(r.history.is_none());
        let with = simulate_building_rk4(&b, &ground, sub, true).unwrap();
        assert!(with.history.is_some());
        assert_eq!(
            BuildingResponse {
                history: None,
                ..with
            },
            r,
            "keeping the history changes nothing else"
        );
        let e = &r.energy;
        let per_interface: f64 = e.friction_per_interface.iter().sum();
        assert!((per_interface - e.friction).abs() < 1e-12 * e.friction);
        assert!(e.balance_error() <= r.energy_balance_error_max * 1.0001 + 1e-15);
        bal.push((sub, r.energy_balance_error_max));
        if sub == 320 {
            let ee = &exact.energy;
            for (name, a, x) in [
                ("input", e.input, ee.input),
                ("damping", e.damping, ee.damping),
                ("friction", e.friction, ee.friction),
            ] {
                assert!((a - x).abs() < 1e-4 * x, "{name}: {a} vs {x}");
            }
        }
    }
    eprintln!(
        "balance (sub-steps, error): {bal:?}, order {:.2}",
        order(&bal[..3])
    );
    assert!(order(&bal[..3]) > 3.5, "{bal:?}");
    assert!(bal[3].1 < 1e-11, "{bal:?}");
}

#[test]
fn refuses_zero_too_many_and_unstable_substeps() {
    let rec = &real_records()[0];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let b = Building::new(&two_stacks()).unwrap();
    for sub in [0, MAX_RK4_SUBSTEPS + 1] {
        assert_eq!(
            simulate_building_rk4(&b, &ground, sub, false).unwrap_err(),
            SimError::Substeps(sub)
        );
    }
    // A stiff building: its shortest bare period sets the step.
    let mut spec = two_stacks();
    spec.period_s = 0.05;
    let b = Building::new(&spec).unwrap();
    let shortest = *b.periods_s().last().unwrap();
    let omega_dt = std::f64::consts::TAU / shortest * rec.dt_s;
    let needed = (omega_dt / RK4_MAX_OMEGA_STEP).ceil() as usize;
    assert!(needed >= 3, "{needed}");
    for sub in [1, needed - 1] {
        match simulate_building_rk4(&b, &ground, sub, false).unwrap_err() {
            SimError::Rk4Unstable {
                period_s,
                dt_s,
                substeps,
                omega_step,
                needed: n,
            } => {
                assert_eq!(
                    (period_s, dt_s, substeps, n),
                    (shortest, rec.dt_s, sub, needed)
                );
                assert!(omega_step > RK4_MAX_OMEGA_STEP);
            }
            e => panic!("{e}"),
        }
    }
    assert!(simulate_building_rk4(&b, &ground, needed, false).is_ok());
}

/// One storey through the building's RK4 is the one-storey RK4 (`simulate_rk4`) written again:
/// same pattern rule, same return mapping, so the two agree to round-off (measured 1.4e-15 and
/// 5.4e-15 of the peak on the displacement histories, with identical contact histories). The
/// friction per interface may differ in how a merge's loss is attributed, never in its sum.
#[test]
fn one_storey_equals_the_one_storey_rk4() {
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    for yielding in [None, Some((0.15, 0.05))] {
        let mut spec = BuildingSpec::uniform(1, 1.0);
        spec.damping_basis = DampingBasis::Structure;
        spec.stacks = vec![StackSpec::new(1, &[0.5, 0.5], &[0.2, 0.1])];
        let mut sys = System::new(&SystemSpec::new(1.0, &[0.5, 0.5], &[0.2, 0.1])).unwrap();
        if let Some((c, r)) = yielding {
            spec.yielding = Some(StoreyYielding {
                strength_ratios: vec![c],
                post_yield_ratio: r,
            });
            sys = sys.with_yielding(Yielding::bilinear(c, r)).unwrap();
        }
        let b = Building::new(&spec).unwrap();
        for sub in [4, 40] {
            let rb = simulate_building_rk4(&b, &ground, sub, true).unwrap();
            let rs = simulate_rk4(&sys, &ground, sub, true).unwrap();
            let (hb, hs) = (rb.history.as_ref().unwrap(), rs.history.as_ref().unwrap());
            let what = format!("{yielding:?} at {sub} sub-steps");
            assert_eq!(hb.contact, hs.contact, "{what}");
            for (a, s) in [
                (&hb.displacement_m, &hs.displacement_m),
                (&hb.velocity_mps, &hs.velocity_mps),
                (&hb.abs_accel_mps2, &hs.abs_accel_mps2),
            ] {
                assert!(rel(a, s) < 1e-12, "{what}: {:e}", rel(a, s));
            }
            let close = |a: f64, s: f64| (a - s).abs() <= 1e-12 * s.abs().max(1e-300);
            assert!(close(
                rb.floor_peak_displacement_m[0],
                rs.peak_displacement_m
            ));
            assert!(close(
                rb.floor_peak_abs_accel_mps2[0],
                rs.peak_abs_accel_mps2[0]
            ));
            for i in 0..2 {
                assert!(close(
                    rb.block_peak_abs_accel_mps2[i],
                    rs.peak_abs_accel_mps2[i + 1]
                ));
                assert!((rb.peak_slip_m[i] - rs.peak_slip_m[i]).abs() <= 1e-12 * rs.peak_slip_m[1]);
            }
            assert_eq!(
                (rb.switches, rb.yield_events),
                (rs.switches, rs.yield_events),
                "{what}"
            );
            let (eb, es) = (&rb.energy, &rs.energy);
            for (a, s) in [
                (eb.input, es.input),
                (eb.damping, es.damping),
                (eb.friction, es.friction),
                (eb.kinetic, es.kinetic),
                (eb.strain, es.strain),
                (eb.hysteretic, es.hysteretic),
            ] {
                assert!((a - s).abs() <= 1e-12 * es.input, "{what}: {a} vs {s}");
            }
            if let Some(d) = &rb.storey_ductility {
                assert!(close(d[0], rs.ductility.unwrap()));
            }
        }
    }
}

/// The exact integrator's peak base shear (`F_1 + 1ᵀ·C·u̇`, the first storey's spring and the
/// dampers on the ground) against RK4's Newton sum over every body (`Σ m·a_abs`, floors and
/// blocks): two independent formulas of one force, continuous through the switches (it is a
/// function of displacements and velocities), so RK4's sampled peak converges to it. Sliding
/// stacks, then the same building yielding, then without stacks, under RSN960. Measured
/// relative errors at 5, 20, 80, 320 sub-steps: stacks 1.2e-4, 1.5e-5, 1.1e-5, 3.7e-6;
/// yielding 1.7e-5, 3.3e-6, 3.0e-7, 5.9e-9; bare 8.7e-5, 2.0e-8, 2.0e-8, 2.0e-8 (the floor of
/// the exact peak search). Asserted at 320 sub-steps: within 2e-5 (RK4 samples the peak at its
/// sub-steps and resolves the switches to a sub-step, the stacks' error of first order). The
/// same for every storey's shear (RK4: the bodies above the cut) and for the overturning
/// moment at the base (RK4: `Σ z·m·a_abs` over every body, `z` its floor's elevation), on
/// storeys of 4, 3 and 3.5 m, each error over that quantity's peak (measured, the worst of
/// them at 5, 20, 80, 320 sub-steps: stacks 4.2e-4, 7.9e-5, 1.3e-5, 4.3e-6; yielding 2.6e-5,
/// 3.3e-6, 3.0e-7, 5.9e-9; bare 8.7e-5, 3.4e-6, 3.4e-8, 2.1e-8).
#[test]
fn the_base_shear_is_newtons_sum_over_every_body() {
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let mut yielding = two_stacks();
    yielding.yielding = Some(StoreyYielding {
        strength_ratios: vec![0.15, 0.12, 0.1],
        post_yield_ratio: 0.05,
    });
    let mut bare = two_stacks();
    bare.stacks.clear();
    for (name, mut spec) in [
        ("stacks", two_stacks()),
        ("yielding", yielding),
        ("bare", bare),
    ] {
        spec.storey_heights_m = vec![4.0, 3.0, 3.5];
        let b = Building::new(&spec).unwrap();
        let exact = simulate_building(&b, &ground, &ExactOptions::default()).unwrap();
        assert!(exact.peak_base_shear_n > 0.0);
        assert_eq!(exact.peak_base_shear_n, exact.storey_peak_shear_n[0]);
        let peaks = |r: &BuildingResponse| {
            let mut p = r.storey_peak_shear_n.clone();
            p.push(r.peak_overturning_n_m);
            p
        };
        let want = peaks(&exact);
        let mut errs = Vec::new();
        for sub in [5, 20, 80, 320] {
            let r = simulate_building_rk4(&b, &ground, sub, false).unwrap();
            let got = peaks(&r);
            let worst = (got.iter().zip(&want))
                .map(|(g, w)| (g - w).abs() / w)
                .fold(0.0, f64::max);
            errs.push((sub, worst));
        }
        eprintln!("{name}: storey shears and overturning moment, worst error {errs:?}");
        assert!(errs[3].1 < 2e-5, "{name}: {errs:?}");
    }
}

/// The stacks' stuck mass share (the time average of the mass moving with its floor) against
/// RK4's, counted sub-step by sub-step from its contacts: the exact integrator switches at the
/// instant, RK4 to a sub-step, so the two agree to first order in the sub-step (asserted: the
/// difference falls with the sub-steps and is below 1e-3 at 320; measured for a share of 0.838
/// under RSN960: 2.2e-5, 5.9e-6, 3.5e-6 at 20, 80, 320). Its limits by simulation: a
/// stack whose friction cannot be overcome (μ = 100) gives exactly 1, a nearly frictionless
/// one (μ = 1e-5) nearly 0, a building without stacks NaN.
#[test]
fn the_stuck_mass_share_agrees_with_rk4_and_is_exact_at_its_limits() {
    let rec = &real_records()[1];
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let b = Building::new(&two_stacks()).unwrap();
    let exact = simulate_building(&b, &ground, &ExactOptions::default()).unwrap();
    let share = exact.stuck_mass_share;
    assert!(share > 0.05 && share < 0.99, "{share}");
    let errs: Vec<f64> = [20, 80, 320]
        .iter()
        .map(|&sub| {
            let r = simulate_building_rk4(&b, &ground, sub, false).unwrap();
            (r.stuck_mass_share - share).abs()
        })
        .collect();
    eprintln!("stuck mass share {share}: RK4 differences at 20, 80, 320 sub-steps {errs:?}");
    assert!(errs[2] < 1e-3 && errs[2] < errs[0], "{errs:?}");
    let with_mu = |mu: f64| {
        let mut s = two_stacks();
        for st in &mut s.stacks {
            st.mu.iter_mut().for_each(|m| *m = mu);
        }
        let b = Building::new(&s).unwrap();
        simulate_building(&b, &ground, &ExactOptions::default())
            .unwrap()
            .stuck_mass_share
    };
    assert_eq!(with_mu(100.0), 1.0);
    let loose = with_mu(1e-5);
    assert!((0.0..1e-3).contains(&loose), "{loose}");
    let mut bare = two_stacks();
    bare.stacks.clear();
    let b = Building::new(&bare).unwrap();
    let r = simulate_building(&b, &ground, &ExactOptions::default()).unwrap();
    assert!(r.stuck_mass_share.is_nan());
}
