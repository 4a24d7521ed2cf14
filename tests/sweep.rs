//! The sweep's skip rules against brute force: every system of every case simulated (in a
//! building, its per-floor profiles and base shear too; the goods' own demands, per block).

mod common;

use common::real_records;
use slidestack::dynamics::Ground;
use slidestack::grid::{Grid, StackFloor};
use slidestack::study::building::Frame;
use slidestack::study::config::{GridConfig, Values};
use slidestack::study::physics::Physics;
use slidestack::study::sweep::{UnitOptions, run_unit};

fn grid(ratio: f64) -> (Grid, Physics) {
    let g = GridConfig {
        period_s: Values::List(vec![0.3, 1.0]),
        alpha: vec![Values::List(vec![0.1, 1.0]), Values::List(vec![0.5, 1.0])],
        // From "never slips" (0.9) to sliding (0.05), with increasing and decreasing pairs.
        mu: vec![
            Values::List(vec![0.05, 0.2, 0.9]),
            Values::List(vec![0.05, 0.1, 0.3, 0.9]),
        ],
        mu_static_ratio: ratio,
        damping: 0.05,
        damping_basis: Default::default(),
        stack_floor: None,
        aspect: None,
    };
    (g.axes(), g.physics())
}

#[test]
fn skip_rules_equal_brute_force() {
    skip_rules_hold(&Frame::one_storey(), 2);
}

/// The same in buildings (docs/model.md, "A study over buildings"): three storeys whose storeys
/// stiffen downward, the stack on floor 1, on the roof, and on every floor; one record.
#[test]
fn skip_rules_equal_brute_force_in_a_building() {
    for stack_floor in [StackFloor::Floor(1), StackFloor::Roof, StackFloor::All] {
        let frame = Frame {
            floor_masses: vec![1.0, 1.0, 0.8],
            storey_stiffnesses: vec![3.0, 2.0, 1.0],
            storey_heights_m: vec![4.0, 3.0, 3.0],
            stack_floor,
        };
        skip_rules_hold(&frame, 1);
    }
}

fn skip_rules_hold(frame: &Frame, records: usize) {
    // Tolerances: NoSlip compares the rigid SDOF with the stack simulated with every interface
    // stuck (two exact solutions, 1e-9 relative); SingleBlock compares the single block with
    // the stack whose upper interfaces never slip (1e-9, the limit tests' bound is 1e-10).
    // The rocking flag under a rule is the stand-in's peak against the stuck stack's criterion;
    // brute force simulates the stack with the check: equal flags (a tie within round-off of
    // the threshold would be the only way to differ, and none occurs here).
    // Held takes an earlier case's run whose trajectory this case's repeats exactly: every
    // number of the stack equal to the bit.
    let mut counts = [0usize; 4];
    let mut rocking = [[0usize; 2]; 4];
    for ratio in [1.0, 1.5] {
        let (g, physics) = grid(ratio);
        for rec in &real_records()[..records] {
            let accel = rec.accel_mps2(1.0);
            let ground = Ground {
                dt_s: rec.dt_s,
                accel_mps2: &accel,
            };
            for p in 0..g.periods_s.len() {
                let aspect = Some(&ASPECT[..]);
                let unit = |skip| {
                    run_unit(
                        &g,
                        &physics,
                        frame,
                        &ground,
                        p,
                        UnitOptions { skip, aspect },
                    )
                };
                let (fast, slow) = (unit(true).unwrap(), unit(false).unwrap());
                assert!(slow.skip_rule.iter().all(|&r| r == 0));
                for c in 0..g.cases_per_unit() {
                    counts[fast.skip_rule[c] as usize] += 1;
                    rocking[fast.skip_rule[c] as usize][fast.rocks_stack[c] as usize] += 1;
                    assert_eq!(
                        fast.rocks_stack[c],
                        slow.rocks_stack[c],
                        "{} {frame:?} T={} case {c} ({:?}) rule {}: rocks",
                        rec.name,
                        g.periods_s[p],
                        g.stack(c),
                        fast.skip_rule[c]
                    );
                    let held = fast.skip_rule[c] == 3;
                    let close = |a: f64, b: f64, what: &str| {
                        let scale = a.abs().max(b.abs()).max(1e-12);
                        let of_stack = !(what.contains("single") || what.contains("rigid"));
                        let tol = if held && of_stack { 0.0 } else { 1e-9 * scale };
                        assert!(
                            (a - b).abs() <= tol,
                            "{} {frame:?} T={} case {c} ({:?}) rule {}: {what} {a} vs {b}",
                            rec.name,
                            g.periods_s[p],
                            g.stack(c),
                            fast.skip_rule[c]
                        );
                    };
                    close(fast.u_stack[c], slow.u_stack[c], "u_stack");
                    close(fast.u_single[c], slow.u_single[c], "u_single");
                    close(fast.u_rigid[c], slow.u_rigid[c], "u_rigid");
                    close(fast.a_stack[c], slow.a_stack[c], "a_stack");
                    for i in 0..g.blocks() {
                        let k = c * g.blocks() + i;
                        close(fast.slip_peak[k], slow.slip_peak[k], "slip_peak");
                        // The goods' own demands: an interface that never slips ends at 0
                        // exactly; a block that moves with its floor (or with the single
                        // block) has that body's peaks, to the same 1e-9.
                        close(
                            fast.slip_residual[k],
                            slow.slip_residual[k],
                            "slip_residual",
                        );
                        close(
                            fast.block_accel_stack[k],
                            slow.block_accel_stack[k],
                            "block_accel_stack",
                        );
                        close(
                            fast.block_velocity_stack[k],
                            slow.block_velocity_stack[k],
                            "block_velocity_stack",
                        );
                        assert!(
                            fast.block_accel_stack[k] > 0.0 && fast.block_velocity_stack[k] > 0.0
                        );
                    }
                    // The profiles (one storey: the structure's) and a building's base shear,
                    // with and without sliding.
                    let levels = frame.storeys();
                    for (what, a, b) in [
                        (
                            "floor_accel_stack",
                            &fast.floor_accel_stack,
                            &slow.floor_accel_stack,
                        ),
                        (
                            "floor_accel_rigid",
                            &fast.floor_accel_rigid,
                            &slow.floor_accel_rigid,
                        ),
                        (
                            "drift_ratio_stack",
                            &fast.drift_ratio_stack,
                            &slow.drift_ratio_stack,
                        ),
                        (
                            "drift_ratio_rigid",
                            &fast.drift_ratio_rigid,
                            &slow.drift_ratio_rigid,
                        ),
                        (
                            "floor_velocity_stack",
                            &fast.floor_velocity_stack,
                            &slow.floor_velocity_stack,
                        ),
                        (
                            "floor_velocity_rigid",
                            &fast.floor_velocity_rigid,
                            &slow.floor_velocity_rigid,
                        ),
                        (
                            "residual_drift_ratio_stack",
                            &fast.residual_drift_ratio_stack,
                            &slow.residual_drift_ratio_stack,
                        ),
                        (
                            "residual_drift_ratio_rigid",
                            &fast.residual_drift_ratio_rigid,
                            &slow.residual_drift_ratio_rigid,
                        ),
                    ] {
                        assert_eq!(a.len(), levels * g.cases_per_unit(), "{what}");
                        for j in c * levels..(c + 1) * levels {
                            close(a[j], b[j], what);
                        }
                    }
                    if frame.storeys() > 1 {
                        close(
                            fast.base_shear_stack[c],
                            slow.base_shear_stack[c],
                            "V_stack",
                        );
                        close(
                            fast.base_shear_rigid[c],
                            slow.base_shear_rigid[c],
                            "V_rigid",
                        );
                        assert!(fast.base_shear_stack[c] > 0.0);
                    }
                    let fe = (fast.friction_energy[c] - slow.friction_energy[c]).abs();
                    let tol = if held { 0.0 } else { 1e-9 };
                    assert!(
                        fe <= tol * slow.friction_energy[c].max(1e-9),
                        "friction {fe}"
                    );
                }
            }
        }
    }
    // Every rule was exercised, under each some stacks rock, and some stacks do not.
    assert!(counts.iter().all(|&n| n > 0), "{counts:?}");
    assert!(rocking.iter().all(|r| r[1] > 0), "{rocking:?}");
    assert!(rocking.iter().any(|r| r[0] > 0), "{rocking:?}");
}

/// The blocks' width over height in the skip-rule checks: the top block rocks beyond 0.25 g on
/// its own; the pair, stuck, beyond about 0.2 g.
const ASPECT: [f64; 2] = [0.8, 0.25];
