//! The independent answers a case is compared with ([`Reference`]): the same record refined,
//! closed forms, the one-block equivalent of a stack and the paper's RK4. Each comparison returns
//! a relative error, or why it could not be computed.

use super::{Check, Reference, ReferenceOutcome, Samples, StressCase, options, refine_linear};
use slidestack::dynamics::{
    G, History, Response, System, SystemSpec, simulate_exact, simulate_rk4,
};
use slidestack::sdof::Step;
use slidestack::spectrum::response::peak_response;

pub(super) fn compare(
    case: &StressCase,
    sys: &System,
    samples: &Samples,
    resp: &Response,
    reference: &Reference,
) -> ReferenceOutcome {
    let (label, error, tolerance) = match *reference {
        Reference::Refined { factor, tolerance } => (
            format!("refined dt/{factor}"),
            against_refined(case, sys, samples, resp, factor),
            tolerance,
        ),
        Reference::Zero => ("exactly zero".into(), against_zero(resp), 0.0),
        Reference::RigidSdof { tolerance } => (
            "rigid SDOF".into(),
            against_rigid_sdof(sys, samples, resp),
            tolerance,
        ),
        Reference::Frictionless { tolerance } => (
            "frictionless".into(),
            against_frictionless(sys, samples, resp),
            tolerance,
        ),
        Reference::StepHand {
            step_s,
            accel_mps2,
            tolerance,
        } => (
            "hand solution".into(),
            against_step_hand(sys, samples, resp, step_s, accel_mps2),
            tolerance,
        ),
        Reference::OneBlock { tolerance } => (
            "one block".into(),
            against_one_block(case, samples, resp),
            tolerance,
        ),
        Reference::Rk4 {
            substeps,
            tolerance,
        } => (
            format!("RK4 ×{substeps}"),
            against_rk4(sys, samples, resp, substeps),
            tolerance,
        ),
    };
    ReferenceOutcome {
        label,
        error: error.map(|e| Check::new(e, tolerance)),
    }
}

/// Column `body` of a row-major `[time][body]` history array.
fn column(data: &[f64], bodies: usize, body: usize) -> Vec<f64> {
    data.iter().skip(body).step_by(bodies).copied().collect()
}

/// `max(a, b)`, but NaN if either is (`f64::max` would drop it and let a NaN pass).
fn worst(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// `max|x|`, NaN if `x` holds one.
fn peak_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| worst(m, v.abs()))
}

/// `max|a − b| / max|b|` (0 when both are identically zero, infinite when only `b` is, NaN if
/// either holds a NaN or their lengths differ).
fn relative_gap(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    let gap = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| worst(m, (x - y).abs()));
    if gap == 0.0 { 0.0 } else { gap / peak_abs(b) }
}

/// `|a − b| / |b|` with the same conventions as [`relative_gap`].
fn relative_diff(a: f64, b: f64) -> f64 {
    relative_gap(&[a], &[b])
}

fn history(r: &Response) -> Result<&History, String> {
    r.history.as_ref().ok_or_else(|| "no history".to_string())
}

fn against_refined(
    case: &StressCase,
    sys: &System,
    samples: &Samples,
    resp: &Response,
    factor: usize,
) -> Result<f64, String> {
    let fine = refine_linear(samples, factor);
    let reference =
        simulate_exact(sys, &fine.ground(), &options(case)).map_err(|e| e.to_string())?;
    let (hc, hf) = (history(resp)?, history(&reference)?);
    let mut err = relative_diff(resp.peak_displacement_m, reference.peak_displacement_m);
    for body in 0..hc.bodies {
        let coarse = column(&hc.displacement_m, hc.bodies, body);
        let fine_at_coarse: Vec<f64> = column(&hf.displacement_m, hf.bodies, body)
            .into_iter()
            .step_by(factor)
            .collect();
        err = worst(err, relative_gap(&coarse, &fine_at_coarse));
    }
    Ok(err)
}

fn against_zero(resp: &Response) -> Result<f64, String> {
    let h = history(resp)?;
    let e = &resp.energy;
    let mut all = vec![
        resp.peak_displacement_m,
        resp.switches as f64,
        e.input,
        e.kinetic,
        e.strain,
        e.damping,
        e.friction,
        resp.energy_balance_error_max,
    ];
    all.extend(&resp.peak_abs_accel_mps2);
    all.extend(&resp.peak_slip_m);
    all.extend(&resp.residual_slip_m);
    all.extend(&resp.slip_time_s);
    all.extend(&h.displacement_m);
    all.extend(&h.velocity_mps);
    all.extend(&h.abs_accel_mps2);
    Ok(peak_abs(&all))
}

/// Displacements at the samples of `ü + 2ζωu̇ + ω²u = −a_g`, from rest.
fn sdof_displacements(omega: f64, zeta: f64, samples: &Samples) -> Vec<f64> {
    let step = Step::new(omega, zeta, samples.dt_s);
    let (mut u, mut v) = (0.0, 0.0);
    let mut out = Vec::with_capacity(samples.accel_mps2.len());
    out.push(0.0);
    for w in samples.accel_mps2.windows(2) {
        (u, v) = step.step(u, v, w[0], w[1]);
        out.push(u);
    }
    out
}

/// Error of the structure's response against a linear SDOF with the given period and damping:
/// history at the samples over the peak, and the exact peak.
fn against_sdof(
    period_s: f64,
    zeta: f64,
    samples: &Samples,
    resp: &Response,
) -> Result<f64, String> {
    let h = history(resp)?;
    let u = column(&h.displacement_m, h.bodies, 0);
    let oracle = sdof_displacements(std::f64::consts::TAU / period_s, zeta, samples);
    let peak = peak_response(&samples.accel_mps2, samples.dt_s, period_s, zeta)
        .map_err(|e| e.to_string())?
        .sd_m;
    Ok(worst(
        relative_gap(&u, &oracle),
        relative_diff(resp.peak_displacement_m, peak),
    ))
}

fn against_rigid_sdof(sys: &System, samples: &Samples, resp: &Response) -> Result<f64, String> {
    if resp.switches != 0 || resp.peak_slip_m.iter().any(|&s| s != 0.0) {
        return Err(format!(
            "the stack slid ({} switches, peak slips {:?} m)",
            resp.switches, resp.peak_slip_m
        ));
    }
    let total = 1.0 + sys.alpha_total();
    let zeta = sys.damping_ratio() / total.sqrt();
    against_sdof(sys.period_rigid_s(), zeta, samples, resp)
}

fn against_frictionless(sys: &System, samples: &Samples, resp: &Response) -> Result<f64, String> {
    let mut err = against_sdof(sys.period_s(), sys.damping_ratio(), samples, resp)?;
    // Free blocks: x(t+dt) = x + v·dt − (2a_k + a_{k+1})·dt²/6, v(t+dt) = v − (a_k + a_{k+1})·dt/2.
    let dt = samples.dt_s;
    let (mut x, mut v) = (vec![0.0], 0.0);
    for w in samples.accel_mps2.windows(2) {
        let last = x[x.len() - 1];
        x.push(last + v * dt - (2.0 * w[0] + w[1]) * dt * dt / 6.0);
        v -= (w[0] + w[1]) * dt / 2.0;
    }
    let h = history(resp)?;
    for body in 1..h.bodies {
        err = worst(
            err,
            relative_gap(&column(&h.displacement_m, h.bodies, body), &x),
        );
    }
    Ok(err)
}

/// Slip `s = u_1 − u_0` of a block on a rigid base under `a_g` = 0 before `t_s`, rising
/// linearly to `A` over `[t_s, t_s + dt]`, `A` after: stuck until `a_g = μ_s·g` at
/// `t_b = t_s + dt·μ_s·g/A`, then `s̈ = μ_k·g − a_g(t)` (the block lags, friction drags it on).
fn step_hand_slip(t: f64, step_s: f64, dt: f64, accel: f64, mu_s: f64, mu_k: f64) -> f64 {
    let t_b = step_s + dt * mu_s * G / accel;
    let t_r = step_s + dt;
    if t <= t_b {
        return 0.0;
    }
    // During the ramp: s̈ = (μ_k − μ_s)·g − A·τ/dt, τ = t − t_b.
    let ramp = |tau: f64| -> (f64, f64) {
        let c = (mu_k - mu_s) * G;
        let j = accel / dt;
        (
            c * tau * tau / 2.0 - j * tau.powi(3) / 6.0,
            c * tau - j * tau * tau / 2.0,
        )
    };
    if t <= t_r {
        return ramp(t - t_b).0;
    }
    let (s_r, v_r) = ramp(t_r - t_b);
    let tau = t - t_r;
    s_r + v_r * tau + (mu_k * G - accel) * tau * tau / 2.0
}

fn against_step_hand(
    sys: &System,
    samples: &Samples,
    resp: &Response,
    step_s: f64,
    accel: f64,
) -> Result<f64, String> {
    if sys.blocks() != 1 {
        return Err("the hand solution is for one block".into());
    }
    let h = history(resp)?;
    let (mu_s, mu_k) = (sys.mu_static()[0], sys.mu_kinetic()[0]);
    let slip: Vec<f64> = (0..h.rows())
        .map(|r| h.displacement_m[r * 2 + 1] - h.displacement_m[r * 2])
        .collect();
    let hand: Vec<f64> = h
        .time_s
        .iter()
        .map(|&t| step_hand_slip(t, step_s, samples.dt_s, accel, mu_s, mu_k))
        .collect();
    Ok(relative_gap(&slip, &hand))
}

fn against_one_block(case: &StressCase, samples: &Samples, resp: &Response) -> Result<f64, String> {
    let spec = &case.spec;
    if spec.alpha.len() != 2 || spec.mu_static.is_some() || spec.mu[1] < spec.mu[0] {
        return Err("needs two blocks with μ_2 ≥ μ_1 and static = kinetic".into());
    }
    let single = SystemSpec {
        alpha: vec![spec.alpha[0] + spec.alpha[1]],
        mu: vec![spec.mu[0]],
        ..spec.clone()
    };
    let sys1 = System::new(&single).map_err(|e| e.to_string())?;
    let r1 = simulate_exact(&sys1, &samples.ground(), &options(case)).map_err(|e| e.to_string())?;
    let (hs, h1) = (history(resp)?, history(&r1)?);
    let us = column(&hs.displacement_m, hs.bodies, 0);
    let u1 = column(&h1.displacement_m, h1.bodies, 0);
    let s1 = r1.peak_slip_m[0];
    let top_slip = if resp.peak_slip_m[1] == 0.0 {
        0.0
    } else {
        resp.peak_slip_m[1] / s1
    };
    Ok([
        relative_diff(resp.peak_displacement_m, r1.peak_displacement_m),
        relative_diff(resp.peak_slip_m[0], s1),
        top_slip,
    ]
    .into_iter()
    .fold(relative_gap(&us, &u1), worst))
}

fn against_rk4(
    sys: &System,
    samples: &Samples,
    resp: &Response,
    substeps: usize,
) -> Result<f64, String> {
    let r = simulate_rk4(sys, &samples.ground(), substeps, true).map_err(|e| e.to_string())?;
    let (he, hr) = (history(resp)?, history(&r)?);
    let mut err = relative_diff(r.peak_displacement_m, resp.peak_displacement_m);
    for body in 0..he.bodies {
        let exact = column(&he.displacement_m, he.bodies, body);
        let rk4 = column(&hr.displacement_m, hr.bodies, body);
        err = worst(err, relative_gap(&rk4, &exact));
    }
    Ok(err)
}
