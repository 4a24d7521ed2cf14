//! Limit cases with closed-form or independent oracles (docs/model.md, "Stated special cases").

#![allow(clippy::needless_range_loop)]

mod common;

use common::{column, max_rel_diff, real_records, sdof_oracle};
use slidestack::dynamics::{ExactOptions, Ground, System, SystemSpec, simulate_exact};

const HIST: ExactOptions = ExactOptions {
    history: true,
    max_switches_per_step: 1000,
    energy_balance: true,
    abs_velocity: true,
    floor_displacements: true,
};

/// μ large: the stack never slides and the structure is a linear SDOF of mass m_p(1+α) with the
/// bare structure's c (paper Eqs. 10–13). Oracle: matrix exponential. Tolerance 1e-9 of the
/// peak: both are exact up to round-off, accumulated over ~2000 steps.
#[test]
fn rigid_limit_equals_sdof_of_total_mass() {
    for rec in real_records() {
        let accel = rec.accel_mps2(1.0);
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &accel,
        };
        for (tp, alpha) in [
            (0.5, vec![0.5, 0.5]),
            (1.2, vec![1.0]),
            (0.2, vec![0.1, 0.3, 0.2]),
        ] {
            let mu = vec![100.0; alpha.len()];
            let sys = System::new(&SystemSpec::new(tp, &alpha, &mu)).unwrap();
            let r = simulate_exact(&sys, &ground, &HIST).unwrap();
            assert_eq!(r.switches, 0);
            assert!(r.peak_slip_m.iter().all(|&s| s == 0.0));
            let total = 1.0 + sys.alpha_total();
            let omega = (sys.stiffness() / total).sqrt();
            let zeta = sys.damping() / (2.0 * (sys.stiffness() * total).sqrt());
            let o = sdof_oracle(omega, zeta, rec.dt_s, &accel);
            let h = r.history.as_ref().unwrap();
            let u = column(&h.displacement_m, h.bodies, 0);
            let hist_err = max_rel_diff(&u, &o.displacement, o.peak);
            let peak_err = (r.peak_displacement_m - o.peak).abs() / o.peak;
            assert!(hist_err < 1e-9, "{} T={tp}: history {hist_err:e}", rec.name);
            assert!(peak_err < 1e-9, "{} T={tp}: peak {peak_err:e}", rec.name);
        }
    }
}

/// μ = 0: the blocks never load the structure, which responds alone; each block's displacement
/// relative to the ground is −∬a_g, a cubic per sample interval summed exactly here.
#[test]
fn frictionless_stack_leaves_structure_alone() {
    for rec in real_records() {
        let accel = rec.accel_mps2(1.0);
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &accel,
        };
        let sys = System::new(&SystemSpec::new(0.7, &[0.5, 2.0], &[0.0, 0.0])).unwrap();
        let r = simulate_exact(&sys, &ground, &HIST).unwrap();
        let omega = 2.0 * std::f64::consts::PI / 0.7;
        let o = sdof_oracle(omega, 0.05, rec.dt_s, &accel);
        let h = r.history.as_ref().unwrap();
        let u = column(&h.displacement_m, h.bodies, 0);
        assert!(max_rel_diff(&u, &o.displacement, o.peak) < 1e-9);
        assert!((r.peak_displacement_m - o.peak).abs() / o.peak < 1e-9);
        // Free blocks: x(t+dt) = x + v·dt − (2a_k + a_{k+1})·dt²/6, v(t+dt) = v − (a_k + a_{k+1})·dt/2.
        let (mut x, mut v) = (vec![0.0], 0.0);
        for k in 0..accel.len() - 1 {
            let dt = rec.dt_s;
            let next = x[k] + v * dt - (2.0 * accel[k] + accel[k + 1]) * dt * dt / 6.0;
            v -= (accel[k] + accel[k + 1]) * dt / 2.0;
            x.push(next);
        }
        let scale = x.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        for body in [1, 2] {
            let xb = column(&h.displacement_m, h.bodies, body);
            assert!(max_rel_diff(&xb, &x, scale) < 1e-9);
        }
        assert_eq!(r.energy.friction, 0.0);
    }
}

/// `μ_2 ≥ μ_1` with `μ_s = μ_k`: the top block never slips on the lower one, so the stack is one
/// block of mass `m_1 + m_2` on `μ_1` (paper Section 6.1, Eq. 9). Both runs use the exact
/// integrator with different cluster layouts; tolerance 1e-10 of the peak.
#[test]
fn stack_with_upward_nondecreasing_friction_is_one_block() {
    for rec in real_records() {
        let accel = rec.accel_mps2(1.5);
        let ground = Ground {
            dt_s: rec.dt_s,
            accel_mps2: &accel,
        };
        for (tp, a1, a2, m1, m2) in [
            (1.0, 0.5, 0.5, 0.1, 0.2),
            (0.5, 1.0, 0.1, 0.05, 0.05),
            (2.0, 0.1, 1.0, 0.04, 0.7),
        ] {
            let stack = System::new(&SystemSpec::new(tp, &[a1, a2], &[m1, m2])).unwrap();
            let single = System::new(&SystemSpec::new(tp, &[a1 + a2], &[m1])).unwrap();
            let rs = simulate_exact(&stack, &ground, &HIST).unwrap();
            let r1 = simulate_exact(&single, &ground, &HIST).unwrap();
            assert!(
                rs.peak_slip_m[0] > 1e-3,
                "{} T={tp}: must slide: {:?}",
                rec.name,
                rs.peak_slip_m
            );
            // The top block never slips: at most round-off (a release undone at once).
            assert!(
                rs.peak_slip_m[1] < 1e-12,
                "{} T={tp}: top block slips: {:?}",
                rec.name,
                rs.peak_slip_m
            );
            let peak = r1.peak_displacement_m;
            assert!((rs.peak_displacement_m - peak).abs() / peak < 1e-10);
            let (hs, h1) = (rs.history.unwrap(), r1.history.unwrap());
            let us = column(&hs.displacement_m, hs.bodies, 0);
            let u1 = column(&h1.displacement_m, h1.bodies, 0);
            assert!(max_rel_diff(&us, &u1, peak) < 1e-10);
            assert!((rs.peak_slip_m[0] - r1.peak_slip_m[0]).abs() < 1e-10 * r1.peak_slip_m[0]);
        }
    }
}

/// Newmark's sliding block: a rigid block on a (nearly) rigid base under a trapezoidal pulse
/// (ramps of one sample). Closed form for the slip, phase by phase. The base is the structure
/// with `T_p = 1 µs` and `ζ = 0.9`: it lags the ground by `2ζ/ω ≈ 3e-7 s`, which shifts the
/// break-away and changes the slip (~0.33 m) by ~1e-6 relative; tolerance 1e-5.
#[test]
fn newmark_block_under_trapezoidal_pulse() {
    let g = slidestack::dynamics::G;
    let dt = 0.001;
    let (amp, mu) = (0.5 * g, 0.2);
    let e = mu * g;
    let (r, t0): (f64, f64) = (dt, 0.3);
    let n0 = (t0 / dt).round() as usize;
    let mut accel = vec![0.0; n0 + 1500];
    for (k, a) in accel.iter_mut().enumerate() {
        if k >= 1 && k <= n0 {
            *a = amp;
        }
    }
    let ground = Ground {
        dt_s: dt,
        accel_mps2: &accel,
    };
    let mut spec = SystemSpec::new(1e-6, &[0.01], &[mu]);
    spec.damping_ratio = 0.9;
    let sys = System::new(&spec).unwrap();
    let res = simulate_exact(&sys, &ground, &ExactOptions::default()).unwrap();
    // Relative velocity w of block to base; slip = ∫w.
    let ts = r * e / amp;
    let d1 = e * (r - ts).powi(2) / 2.0
        - amp / (2.0 * r) * ((r.powi(3) - ts.powi(3)) / 3.0 - ts * ts * (r - ts));
    let w_r = e * (r - ts) - amp * (r * r - ts * ts) / (2.0 * r);
    let d2 = w_r * (t0 - r) + (e - amp) * (t0 - r).powi(2) / 2.0;
    let w_t0 = w_r + (e - amp) * (t0 - r);
    let d3 = w_t0 * r + (e - amp) * r * r / 2.0 + amp * r * r / 6.0;
    let w3 = w_t0 + (e - amp) * r + amp * r / 2.0;
    let d4 = -w3 * w3 / (2.0 * e);
    let slip = d1 + d2 + d3 + d4;
    let newmark = -(amp * t0).powi(2) / (2.0 * e) * (1.0 - e / amp);
    assert!(
        (slip - newmark).abs() / newmark.abs() < 0.01,
        "closed form near Newmark's"
    );
    let got = res.residual_slip_m[0];
    assert!(
        (got - slip).abs() / slip.abs() < 1e-5,
        "slip {got} vs closed form {slip}"
    );
    assert!((res.peak_slip_m[0] - slip.abs()).abs() / slip.abs() < 1e-5);
    assert_eq!(res.switches, 2, "one break-away and one stop");
}
