//! One linear SDOF step, `ü + 2ζωu̇ + ω²u = p(τ)` with `p` linear over the step, exact and
//! stable for every `ω·h` (down to `ω = 0`, the free mass). Used by the response spectra
//! (`spectrum::response`), the spectral matcher (`ground_motion::matching`) and the exact integrator's
//! structure cluster at long periods (`dynamics::exact`; `docs/model.md`, "Long periods").
//!
//! With the state `x = (u, u̇)`, `M = [[0, 1], [−ω², −2ζω]]` and `b = (0, 1)`, the exact solution
//! under a load linear from `p₀` to `p₁` over `[0, h]` is the Nigam–Jennings recurrence (Nigam &
//! Jennings 1969; Chopra, *Dynamics of Structures*, Table 5.2.1) written with the φ-functions of
//! exponential integrators (Hochbruck & Ostermann 2010, *Acta Numerica* 19):
//! `x₁ = e^{Mh}x₀ + h[φ₁(Mh) − φ₂(Mh)]·b·p₀ + h·φ₂(Mh)·b·p₁`. A function `f` of the 2×2 matrix
//! `Mh` is `αI + β·Mh` with `α + β·z = f(z)` at its eigenvalue `z = λh`; `φ_k` by their series
//! near 0 (`numeric::phi1`), so no coefficient cancels when `ω·h` is small, where the textbook
//! formulas subtract terms of order `1/(ωh)²`.
//!
//! [`Step`] holds the coefficients for one `h` (the spectra and the matcher step many samples
//! with them); [`piece`] gives the end state and the energy integrals of one piece of any length;
//! [`decay_piece`] is the same for an SDOF without stiffness (`ü + a·u̇ = p₀ + p₁τ`, the plastic
//! branch of an elastic–perfectly-plastic structure), whose eigenvalues `0` and `−a` are real.

use crate::numeric::{Cx, GAUSS8, phi_series, phi1, phi2, phi3};

/// `(α, β)` with `f(Mh) = αI + β·Mh`, from `f(z)` at the eigenvalue `z` of `Mh` in the upper half
/// plane; at `z = 0` (`ω·h = 0`, `Mh` nilpotent) from `f(0)` and `f'(0)`.
fn alpha_beta(z: Cx, f: Cx, at_zero: (f64, f64)) -> (f64, f64) {
    if z.1 == 0.0 {
        return at_zero;
    }
    let beta = f.1 / z.1;
    (f.0 - beta * z.0, beta)
}

/// The eigenvalue `λh = −ζωh + iω_d h` of `Mh`.
fn eigen_step(omega: f64, zeta: f64, h: f64) -> Cx {
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    Cx(-zeta * omega * h, wd * h)
}

/// One step of length `h` of `ü + 2ζωu̇ + ω²u = −a_g` (`a_g` linear from `a_g0` to `a_g1`):
/// `u₁ = uu·u₀ + uv·v₀ + ug0·a_g0 + ug1·a_g1`, likewise `v₁`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    pub uu: f64,
    pub uv: f64,
    pub vu: f64,
    pub vv: f64,
    pub ug0: f64,
    pub ug1: f64,
    pub vg0: f64,
    pub vg1: f64,
}

impl Step {
    /// Coefficients for circular frequency `omega` (rad/s, `≥ 0`), damping `zeta` (`0 ≤ ζ < 1`)
    /// and step `h` (s, `≥ 0`).
    pub fn new(omega: f64, zeta: f64, h: f64) -> Self {
        let z = eigen_step(omega, zeta, h);
        // f(Mh)·b = (β·h, α − 2ζω·β·h).
        let e = Cx(z.0.exp() * z.1.cos(), z.0.exp() * z.1.sin());
        let (ae, be) = alpha_beta(z, e, (1.0, 1.0));
        let p1 = phi1(z);
        let p2 = phi2(z);
        let (a2, b2) = alpha_beta(z, p2, (0.5, 1.0 / 6.0));
        let (a12, b12) = alpha_beta(z, Cx(p1.0 - p2.0, p1.1 - p2.1), (0.5, 1.0 / 3.0));
        let two_zw = 2.0 * zeta * omega;
        // The load p = −a_g enters with a minus sign.
        Self {
            uu: ae,
            uv: be * h,
            vu: -be * h * omega * omega,
            vv: ae - two_zw * be * h,
            ug0: -h * b12 * h,
            ug1: -h * b2 * h,
            vg0: -h * (a12 - two_zw * b12 * h),
            vg1: -h * (a2 - two_zw * b2 * h),
        }
    }

    #[inline(always)]
    pub fn step(&self, u: f64, v: f64, ag0: f64, ag1: f64) -> (f64, f64) {
        (
            self.uu * u + self.uv * v + self.ug0 * ag0 + self.ug1 * ag1,
            self.vu * u + self.vv * v + self.vg0 * ag0 + self.vg1 * ag1,
        )
    }
}

/// Free vibration: `u(t)` of `ü + 2ζωu̇ + ω²u = 0` from `(u₀, v₀)`, `ω > 0`, `0 ≤ ζ < 1`
/// (Chopra, Eq. 2.2.4), for any `t ≥ 0`.
pub fn free_displacement(omega: f64, zeta: f64, (u0, v0): (f64, f64), t: f64) -> f64 {
    let zw = zeta * omega;
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let (sn, cs) = (wd * t).sin_cos();
    (-zw * t).exp() * (u0 * cs + (v0 + zw * u0) / wd * sn)
}

/// End state and integrals of one piece of `ü + 2ζωu̇ + ω²u = p₀ + p₁τ` over `[0, h]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    /// `u(h)`, `u̇(h)`.
    pub u: f64,
    pub v: f64,
    /// `∫₀^h u dτ` and `∫₀^h u̇² dτ` (NaN unless asked for).
    pub int_u: f64,
    pub int_v2: f64,
}

/// [`Piece`] from `(u₀, v₀)` for `ω·h ≤ 1`: the state by [`Step`], `∫u` from the first row of
/// `hφ₁(Mh)x₀ + h²φ₂(Mh)b·p₀ + h³φ₃(Mh)b·p₁`, and `∫u̇²` (when `square`) by 8-point
/// Gauss–Legendre on [`Step`] at the nodes: the integrand is a quadratic plus terms in
/// `e^{λτ}`, `e^{2λτ}` with `|λ|h ≤ 1`, whose 16th derivative bounds the error below
/// `1e-17·h·max u̇²`.
pub fn piece(
    omega: f64,
    zeta: f64,
    (p0, p1): (f64, f64),
    (u0, v0): (f64, f64),
    h: f64,
    square: bool,
) -> Piece {
    debug_assert!(omega * h <= 1.0);
    let at = |t: f64| Step::new(omega, zeta, t).step(u0, v0, -p0, -(p0 + p1 * t));
    let (u, v) = at(h);
    let z = eigen_step(omega, zeta, h);
    let (a1, b1) = alpha_beta(z, phi1(z), (1.0, 0.5));
    let b2 = alpha_beta(z, phi2(z), (0.5, 1.0 / 6.0)).1;
    let b3 = alpha_beta(z, phi3(z), (1.0 / 6.0, 1.0 / 24.0)).1;
    // First rows: (αI + β·Mh)·x₀ → α·u₀ + β·h·v₀, (αI + β·Mh)·b → β·h.
    let int_u = h * (a1 * u0 + b1 * h * v0) + h * h * (b2 * h * p0 + b3 * h * h * p1);
    let int_v2 = if square {
        h * GAUSS8
            .iter()
            .map(|&(node, weight)| weight * at(node * h).1.powi(2))
            .sum::<f64>()
    } else {
        f64::NAN
    };
    Piece {
        u,
        v,
        int_u,
        int_v2,
    }
}

/// `φ_k(x)` for real `−1 ≤ x ≤ 0` by its series (alternating terms that fall at least tenfold per
/// two, so the sum keeps every digit).
fn phi_small(k: u32, x: f64) -> f64 {
    phi_series(Cx(x, 0.0), k).0
}

/// The end state and integrals ([`Piece`]) of a piece of `ü + a·u̇ = p₀ + p₁τ` (a structure
/// without stiffness, a yielding structure's branch with `r = 0`) from `(u₀, v₀)` over `[0, h]`,
/// in φ-function form, for `a·h ≤ 1`: with `φ_k = φ_k(−aτ)`,
/// `u̇ = v₀φ₀ + p₀τφ₁ + p₁τ²φ₂`, `u = u₀ + v₀τφ₁ + p₀τ²φ₂ + p₁τ³φ₃`,
/// `∫u = u₀h + v₀h²φ₂ + p₀h³φ₃ + p₁h⁴φ₄` (at `τ = h`), and `∫u̇²` by 8-point Gauss–Legendre
/// (exact to round-off: the integrand is a quartic plus terms in `e^{−aτ}` with `2a·h ≤ 2`,
/// whose 16th derivative bounds the error below `1e-18·h·max u̇²`). The same motion as the
/// structure wave of `r = 0` (`dynamics::exact`), without its terms of order `p₀/a²`
/// that cancel when `a·h` is small. `square`: whether to compute `∫u̇²` (eight evaluations).
pub fn decay_piece(
    decay: f64,
    (p0, p1): (f64, f64),
    (u0, v0): (f64, f64),
    h: f64,
    square: bool,
) -> Piece {
    debug_assert!(decay * h <= 1.0);
    let vel = |t: f64| {
        let x = -decay * t;
        v0 * phi_small(0, x) + t * (p0 * phi_small(1, x) + t * p1 * phi_small(2, x))
    };
    let x = -decay * h;
    let (f1, f2, f3, f4) = (
        phi_small(1, x),
        phi_small(2, x),
        phi_small(3, x),
        phi_small(4, x),
    );
    let int_v2 = if square {
        h * GAUSS8
            .iter()
            .map(|&(node, weight)| weight * vel(node * h).powi(2))
            .sum::<f64>()
    } else {
        f64::NAN
    };
    Piece {
        u: u0 + h * (v0 * f1 + h * (p0 * f2 + h * p1 * f3)),
        v: vel(h),
        int_u: h * (u0 + h * (v0 * f2 + h * (p0 * f3 + h * p1 * f4))),
        int_v2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
    }

    /// RK4 with `n` sub-steps of the same equation: the fine-step reference.
    fn rk4(
        omega: f64,
        zeta: f64,
        (p0, p1): (f64, f64),
        (u0, v0): (f64, f64),
        h: f64,
        n: usize,
    ) -> (f64, f64) {
        let f =
            |t: f64, u: f64, v: f64| (v, p0 + p1 * t - 2.0 * zeta * omega * v - omega * omega * u);
        let (mut u, mut v) = (u0, v0);
        let dt = h / n as f64;
        for i in 0..n {
            let t = i as f64 * dt;
            let k1 = f(t, u, v);
            let k2 = f(t + dt / 2.0, u + dt / 2.0 * k1.0, v + dt / 2.0 * k1.1);
            let k3 = f(t + dt / 2.0, u + dt / 2.0 * k2.0, v + dt / 2.0 * k2.1);
            let k4 = f(t + dt, u + dt * k3.0, v + dt * k3.1);
            u += dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            v += dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        }
        (u, v)
    }

    #[test]
    fn free_vibration_matches_the_closed_form() {
        for &(t_n, zeta, h) in &[
            (1.0, 0.05, 0.01),
            (0.3, 0.0, 0.7),
            (20.0, 0.5, 3.0),
            (1e-3, 0.02, 0.01),
        ] {
            let omega = TAU / t_n;
            let (u, v) = Step::new(omega, zeta, h).step(0.3, -1.1, 0.0, 0.0);
            let want_u = free_displacement(omega, zeta, (0.3, -1.1), h);
            let eps = 1e-7 * h;
            let want_v = (free_displacement(omega, zeta, (0.3, -1.1), h + eps)
                - free_displacement(omega, zeta, (0.3, -1.1), h - eps))
                / (2.0 * eps);
            assert!((u - want_u).abs() < 1e-14, "{t_n} {u} {want_u}");
            assert!(
                (v - want_v).abs() < 1e-6 * (1.0 + want_v.abs()),
                "{t_n} {v} {want_v}"
            );
        }
    }

    #[test]
    fn step_and_ramp_loads_match_the_closed_forms() {
        // Undamped, from rest: step p₀ → u = p₀(1 − cos ωt)/ω²; ramp p₁t → u = p₁(t − sin(ωt)/ω)/ω²
        // (Chopra, Eqs. 4.3.2 and 4.4.2).
        let (omega, h) = (TAU / 0.8, 0.37);
        let (p0, p1) = (2.5, -4.0);
        let (u, _) = Step::new(omega, 0.0, h).step(0.0, 0.0, -p0, -p0);
        let want = p0 * (1.0 - (omega * h).cos()) / (omega * omega);
        assert!(rel(u, want) < 1e-14, "{u} {want}");
        let (u, v) = Step::new(omega, 0.0, h).step(0.0, 0.0, 0.0, -p1 * h);
        let want_u = p1 * (h - (omega * h).sin() / omega) / (omega * omega);
        let want_v = p1 * (1.0 - (omega * h).cos()) / (omega * omega);
        assert!(rel(u, want_u) < 1e-13, "{u} {want_u}");
        assert!(rel(v, want_v) < 1e-13, "{v} {want_v}");
    }

    #[test]
    fn the_free_mass_is_the_limit() {
        // ω → 0: u = u₀ + v₀τ + p₀τ²/2 + p₁τ³/6 (slope form), for ω from 0 to 1e-18 rad/s
        // (where the terms in ζω and ω² fall below 1e-17 of u).
        let (u0, v0, p0, p1, h): (f64, f64, f64, f64, f64) = (0.4, -0.7, 3.0, -11.0, 0.25);
        let want_u = u0 + v0 * h + p0 * h * h / 2.0 + p1 * h * h * h / 6.0;
        let want_v = v0 + p0 * h + p1 * h * h / 2.0;
        let want_int = u0 * h + v0 * h * h / 2.0 + p0 * h.powi(3) / 6.0 + p1 * h.powi(4) / 24.0;
        for &omega in &[0.0, 1e-300, 1e-18] {
            for &zeta in &[0.0, 0.05, 0.9] {
                let p = piece(omega, zeta, (p0, p1), (u0, v0), h, true);
                assert!(rel(p.u, want_u) < 1e-15, "{omega} {zeta} {} {want_u}", p.u);
                assert!(rel(p.v, want_v) < 1e-15, "{omega} {zeta} {} {want_v}", p.v);
                assert!(rel(p.int_u, want_int) < 1e-15, "{omega} {zeta} {}", p.int_u);
                // ∫u̇² of the quadratic velocity in closed form.
                let (a, b, c) = (v0, p0, p1 / 2.0);
                let want_v2 = h
                    * (a * a
                        + h * (a * b
                            + h * ((b * b + 2.0 * a * c) / 3.0
                                + h * (b * c / 2.0 + h * c * c / 5.0))));
                assert!(
                    rel(p.int_v2, want_v2) < 1e-14,
                    "{omega} {zeta} {}",
                    p.int_v2
                );
            }
        }
    }

    #[test]
    fn pieces_match_a_fine_step_reference() {
        // Long to short periods at ω·h ≤ 1: state against RK4 with 20000 sub-steps, ∫u and
        // ∫u̇² against the composite Simpson rule on the reference.
        for &(omega, zeta, h) in &[
            (1e-4, 0.05, 0.01),
            (0.3, 0.02, 0.5),
            (2.0, 0.7, 0.4),
            (50.0, 0.0, 0.02),
        ] {
            let (p0, p1, u0, v0) = (1.3, -7.0, 0.02, 0.5);
            let p = piece(omega, zeta, (p0, p1), (u0, v0), h, true);
            let (ur, vr) = rk4(omega, zeta, (p0, p1), (u0, v0), h, 20_000);
            let scale_u = u0.abs() + v0.abs() * h + p0.abs() * h * h;
            assert!((p.u - ur).abs() < 1e-14 * scale_u, "{omega}: {} {ur}", p.u);
            assert!(
                (p.v - vr).abs() < 1e-14 * (v0.abs() + p0.abs() * h),
                "{omega}: {} {vr}",
                p.v
            );
            let n = 2000;
            let (mut iu, mut iv2) = (0.0, 0.0);
            let mut prev = (u0, v0);
            let dt = h / n as f64;
            let mut vals = vec![(u0, v0)];
            for i in 0..n {
                let t0 = i as f64 * dt;
                prev = rk4(omega, zeta, (p0 + p1 * t0, p1), prev, dt, 10);
                vals.push(prev);
            }
            for (i, (u, v)) in vals.iter().enumerate() {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                iu += w * u;
                iv2 += w * v * v;
            }
            iu *= dt / 3.0;
            iv2 *= dt / 3.0;
            assert!(
                (p.int_u - iu).abs() < 1e-13 * scale_u * h,
                "{omega}: {} {iu}",
                p.int_u
            );
            assert!(rel(p.int_v2, iv2) < 1e-12, "{omega}: {} {iv2}", p.int_v2);
        }
    }

    #[test]
    fn a_long_period_step_keeps_its_digits() {
        // ω·h = 6e-7: the step from rest under a constant load is p₀h²/2 to 1e-15, where the
        // particular-plus-homogeneous form (p₀/ω²·(1 − e^{…}(cos + …))) keeps about 3 digits.
        let (omega, h, p0) = (TAU / 1e4, 0.001, 9.81);
        let (u, v) = Step::new(omega, 0.05, h).step(0.0, 0.0, -p0, -p0);
        // Taylor: u⁽³⁾(0) = −2ζω·p₀, u⁽⁴⁾(0) = (4ζ² − 1)ω²·p₀; the next terms are below 1e-19.
        let (zw, w2h2) = (
            0.05 * omega * h,
            (4.0 * 0.05 * 0.05 - 1.0) * (omega * h).powi(2),
        );
        let want_u = p0 * h * h / 2.0 * (1.0 - 2.0 * zw / 3.0 + w2h2 / 12.0);
        let want_v = p0 * h * (1.0 - zw + w2h2 / 6.0);
        assert!(rel(u, want_u) < 1e-15, "{u} {want_u}");
        assert!(rel(v, want_v) < 1e-15, "{v} {want_v}");
    }
}
