//! The multi-storey building's exact integrator against independent oracles (docs/model.md,
//! "A multi-storey building": evidence).

#![allow(clippy::needless_range_loop)]

mod common;

use common::real_records;
use slidestack::dynamics::building::{
    Building, BuildingSpec, ModalBasis, StackSpec, StoreyYielding, simulate_building,
};
use slidestack::dynamics::{ExactOptions, Ground, System, SystemSpec, Yielding, simulate_exact};

fn opts() -> ExactOptions {
    ExactOptions::default()
}

fn stack(floor: usize, alpha: &[f64], mu: &[f64], mu_static: Option<&[f64]>) -> StackSpec {
    StackSpec {
        floor,
        alpha: alpha.to_vec(),
        mu: mu.to_vec(),
        mu_static: mu_static.map(<[f64]>::to_vec),
    }
}

/// One storey through the building's general (modal) path equals the SDOF integrator: the same
/// physics written twice (closed forms of a 2×2 state vs eigenvectors of it), so they agree to
/// round-off, not bit for bit. Stated tolerance 1e-11 of each peak: the eigenvector basis has a
/// condition number of a few, and each of the record's thousands of pieces adds a few ulps.
#[test]
fn one_storey_equals_the_sdof_integrator() {
    let records = real_records();
    struct Case {
        basis: ModalBasis,
        yielding: Option<(f64, f64)>,
        alpha: Vec<f64>,
        mu: Vec<f64>,
        mu_static: Option<Vec<f64>>,
    }
    let case = |basis, yielding, alpha: &[f64], mu: &[f64], mu_static: Option<&[f64]>| Case {
        basis,
        yielding,
        alpha: alpha.to_vec(),
        mu: mu.to_vec(),
        mu_static: mu_static.map(<[f64]>::to_vec),
    };
    let cases = [
        case(ModalBasis::Rigid, None, &[], &[], None),
        case(ModalBasis::Rigid, None, &[0.5, 0.5], &[0.2, 0.1], None),
        case(
            ModalBasis::Structure,
            None,
            &[0.5, 0.5],
            &[0.2, 0.1],
            Some(&[0.25, 0.12]),
        ),
        case(ModalBasis::Rigid, Some((0.15, 0.05)), &[1.0], &[0.3], None),
        case(
            ModalBasis::Structure,
            Some((0.2, 0.0)),
            &[0.5, 0.5],
            &[0.2, 0.1],
            None,
        ),
    ];
    for rec in records.iter().take(2) {
        let accel = rec.accel_mps2(1.0);
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &accel,
        };
        for Case {
            basis,
            yielding,
            alpha,
            mu,
            mu_static,
        } in &cases
        {
            let period = 0.8;
            let mut spec = BuildingSpec::uniform(1, period);
            spec.damping_basis = *basis;
            spec.yielding = yielding.map(|(c, r)| StoreyYielding {
                strength_ratios: vec![c],
                post_yield_ratio: r,
            });
            if !alpha.is_empty() {
                spec.stacks = vec![stack(1, alpha, mu, mu_static.as_deref())];
            }
            let b = Building::new(&spec).unwrap();
            let rb = simulate_building(&b, &ground, &opts()).unwrap();
            // The SDOF system: the bare structure's ratio from the basis.
            let total: f64 = alpha.iter().sum();
            let mut s = SystemSpec::new(period, alpha, mu);
            s.mu_static = mu_static.clone();
            s.damping_ratio = match basis {
                ModalBasis::Rigid => 0.05 * (1.0 + total).sqrt(),
                ModalBasis::Structure => 0.05,
            };
            let mut sys = System::new(&s).unwrap();
            if let Some((c, r)) = yielding {
                sys = sys.with_yielding(Yielding::bilinear(*c, *r)).unwrap();
            }
            let rs = simulate_exact(&sys, &ground, &opts()).unwrap();
            let what = format!("{} {basis:?} {yielding:?} α {alpha:?}", rec.name);
            let close = |a: f64, b: f64, tol: f64, name: &str| {
                assert!(
                    (a - b).abs() <= tol * b.abs().max(1e-300),
                    "{what}: {name} {a} vs {b} ({:.1e})",
                    (a - b).abs() / b.abs()
                );
            };
            close(
                rb.floor_peak_displacement_m[0],
                rs.peak_displacement_m,
                1e-11,
                "peak displacement",
            );
            close(
                rb.floor_peak_abs_accel_mps2[0],
                rs.peak_abs_accel_mps2[0],
                1e-11,
                "peak acceleration",
            );
            for i in 0..alpha.len() {
                close(rb.peak_slip_m[i], rs.peak_slip_m[i], 1e-9, "peak slip");
                close(
                    rb.block_peak_abs_accel_mps2[i],
                    rs.peak_abs_accel_mps2[i + 1],
                    1e-11,
                    "block acceleration",
                );
            }
            assert_eq!(rb.switches, rs.switches, "{what}: switches");
            assert_eq!(rb.yield_events, rs.yield_events, "{what}: yield events");
            close(
                rb.energy.friction,
                rs.energy.friction,
                1e-9,
                "friction energy",
            );
            close(rb.energy.input, rs.energy.input, 1e-10, "input energy");
            assert!(rb.energy_balance_error_max < 1e-10, "{what}: balance");
            if let Some(d) = &rb.storey_ductility {
                close(d[0], rs.ductility.unwrap(), 1e-11, "ductility");
            }
        }
    }
}
