//! Closed-form motion within one stick/slip mode over a piece of a sample interval.
//!
//! Within a mode the friction forces are constant and the ground acceleration is linear in the
//! local time `τ`, so every quantity of interest (a cluster's displacement or velocity, a relative
//! velocity, a required friction force) has the form
//! `g(τ) = p₀ + p₁τ + p₂τ² + p₃τ³ + e^{−aτ}·(c·cos ωτ + d·sin ωτ)`,
//! where `a`, `ω` are the decay rate and damped frequency of the cluster that holds the structure
//! (the Nigam–Jennings solution of a linear SDOF under linearly varying load). [`Wave`] is that
//! form; [`Basis`] caches `e^{−aτ}`, `cos ωτ`, `sin ωτ` at one `τ` so many waves share them.

use crate::numeric::{Cx, phi1};

/// Decay rate `a = ζ_e·ω_n` (1/s) and damped circular frequency `ω = ω_n·sqrt(1−ζ_e²)` (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Osc {
    pub decay: f64,
    pub omega: f64,
}

impl Osc {
    /// Undamped circular frequency `ω_n = √(a² + ω²)`, rad/s: each `τ`-derivative of
    /// `e^{−aτ}(c·cos ωτ + d·sin ωτ)` is again of that form with its amplitude `√(c² + d²)`
    /// multiplied by `ω_n`.
    pub fn natural(&self) -> f64 {
        (self.decay * self.decay + self.omega * self.omega).sqrt()
    }

    /// `[A, A·ω_n, …, A·ω_n⁴]`: the oscillation amplitude of a wave with amplitude `A` and of its
    /// first four derivatives (see [`Osc::natural`]).
    pub fn amplitudes(natural: f64, amplitude: f64) -> [f64; 5] {
        let mut out = [amplitude; 5];
        for k in 1..5 {
            out[k] = out[k - 1] * natural;
        }
        out
    }
}

/// `e^{−aτ}`, `cos ωτ`, `sin ωτ` at one `τ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Basis {
    pub tau: f64,
    pub exp: f64,
    pub cos: f64,
    pub sin: f64,
}

impl Basis {
    /// The basis at `τ = 0`, equal bit for bit to `Basis::at(osc, 0.0)` for any `osc`.
    pub const ZERO: Basis = Basis {
        tau: 0.0,
        exp: 1.0,
        cos: 1.0,
        sin: 0.0,
    };

    #[inline]
    pub fn at(osc: Osc, tau: f64) -> Self {
        if tau == 0.0 {
            return Self::ZERO;
        }
        let (sin, cos) = (osc.omega * tau).sin_cos();
        Self {
            tau,
            exp: (-osc.decay * tau).exp(),
            cos,
            sin,
        }
    }
}

/// `p₀ + p₁τ + p₂τ² + p₃τ³ + e^{−aτ}·(c·cos ωτ + d·sin ωτ)`; see the module doc.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wave {
    pub p: [f64; 4],
    pub c: f64,
    pub d: f64,
}

impl Wave {
    pub const ZERO: Wave = Wave {
        p: [0.0; 4],
        c: 0.0,
        d: 0.0,
    };

    pub fn constant(v: f64) -> Self {
        Wave {
            p: [v, 0.0, 0.0, 0.0],
            ..Wave::ZERO
        }
    }

    #[inline]
    pub fn eval(&self, b: &Basis) -> f64 {
        let t = b.tau;
        let poly = self.p[0] + t * (self.p[1] + t * (self.p[2] + t * self.p[3]));
        poly + b.exp * (self.c * b.cos + self.d * b.sin)
    }

    /// `dg/dτ`.
    pub fn deriv(&self, osc: Osc) -> Wave {
        Wave {
            p: [self.p[1], 2.0 * self.p[2], 3.0 * self.p[3], 0.0],
            c: -osc.decay * self.c + osc.omega * self.d,
            d: -osc.decay * self.d - osc.omega * self.c,
        }
    }

    /// `self·s + other·t`.
    #[inline]
    pub fn combine(&self, s: f64, other: &Wave, t: f64) -> Wave {
        Wave {
            p: [
                self.p[0] * s + other.p[0] * t,
                self.p[1] * s + other.p[1] * t,
                self.p[2] * s + other.p[2] * t,
                self.p[3] * s + other.p[3] * t,
            ],
            c: self.c * s + other.c * t,
            d: self.d * s + other.d * t,
        }
    }

    pub fn scale(&self, s: f64) -> Wave {
        self.combine(s, &Wave::ZERO, 0.0)
    }

    pub fn plus_constant(mut self, v: f64) -> Wave {
        self.p[0] += v;
        self
    }

    /// Upper bound of `|g(τ)|` over `[t0, t1]` (`0 ≤ t0 ≤ t1`): the polynomial part bounded
    /// term by term, the oscillation by its amplitude times `e^{−a·t0}`.
    pub fn abs_bound(&self, osc: Osc, t0: f64, t1: f64) -> f64 {
        let exp_t0 = if t0 == 0.0 {
            1.0
        } else {
            (-osc.decay * t0).exp()
        };
        self.bound_with(t0, t1, exp_t0)
    }

    /// [`Wave::abs_bound`] over `[b0.tau, t1]`, reusing the exponential already in `b0`.
    #[inline]
    pub fn abs_bound_from(&self, b0: &Basis, t1: f64) -> f64 {
        self.bound_with(b0.tau, t1, b0.exp)
    }

    #[inline]
    fn bound_with(&self, t0: f64, t1: f64, exp_t0: f64) -> f64 {
        let tm = t1.max(t0.abs());
        let poly = self.p[0].abs()
            + tm * (self.p[1].abs() + tm * (self.p[2].abs() + tm * self.p[3].abs()));
        poly + (self.c * self.c + self.d * self.d).sqrt() * exp_t0
    }

    /// `√(c² + d²)`: the amplitude of the oscillation at `τ = 0`.
    pub fn amplitude(&self) -> f64 {
        (self.c * self.c + self.d * self.d).sqrt()
    }

    /// Upper bound of `|dᵏg/dτᵏ|` (`k ≤ 4`) over `[t0, t1]`, `0 ≤ t0 ≤ t1`: the polynomial part's
    /// k-th derivative bounded term by term at `t1`, plus `amp_k·e^{−a·t0}` where `amp_k` is the
    /// k-th entry of [`Osc::amplitudes`] for this wave and `exp_t0 = e^{−a·t0}`. The same bound
    /// as [`Wave::abs_bound`] of the k-th derivative wave, without building it.
    #[inline]
    pub fn deriv_abs_bound(&self, k: usize, t1: f64, exp_t0: f64, amp_k: f64) -> f64 {
        let (p1, p2, p3) = (self.p[1].abs(), self.p[2].abs(), self.p[3].abs());
        let poly = match k {
            0 => self.p[0].abs() + t1 * (p1 + t1 * (p2 + t1 * p3)),
            1 => p1 + t1 * (2.0 * p2 + 3.0 * t1 * p3),
            2 => 2.0 * p2 + 6.0 * t1 * p3,
            3 => 6.0 * p3,
            _ => 0.0,
        };
        poly + amp_k * exp_t0
    }

    /// `∫₀^τ g(t) dt` at the basis point.
    pub fn integral(&self, osc: Osc, b: &Basis) -> f64 {
        self.integral_with(b, &PieceIntegrals::new(osc, b))
    }

    /// [`Wave::integral`] with the oscillation's integral precomputed for this piece.
    pub fn integral_with(&self, b: &Basis, pi: &PieceIntegrals) -> f64 {
        let t = b.tau;
        let poly =
            t * (self.p[0] + t * (self.p[1] / 2.0 + t * (self.p[2] / 3.0 + t * self.p[3] / 4.0)));
        let osc_part = Cx(self.c, -self.d).mul(pi.osc).0;
        poly + osc_part
    }
}

/// The integrals over a piece `[0, h]` that every wave of a mode shares: they depend only on the
/// oscillator and `h`, so a full sample interval's are computed once per cluster and reused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PieceIntegrals {
    /// `∫₀^h e^{zτ} dτ = (e^{zh} − 1)/z`, `z = −a + iω`.
    osc: Cx,
    /// `∫₀^h e^{−2aτ} dτ` and `∫₀^h e^{−2aτ}(cos 2ωτ, sin 2ωτ) dτ`.
    exp2: f64,
    exp2_cos: f64,
    exp2_sin: f64,
}

impl PieceIntegrals {
    /// Through φ₁ so that short pieces lose no digits to cancellation.
    pub fn new(osc: Osc, b: &Basis) -> Self {
        let t = b.tau;
        let (a, w) = (osc.decay, osc.omega);
        let zh = Cx(-a * t, w * t);
        let osc_int = if zh.norm_sqr() < 0.25 {
            let p = phi1(zh);
            Cx(p.0 * t, p.1 * t)
        } else {
            Cx(b.exp * b.cos - 1.0, b.exp * b.sin).div(Cx(-a, w))
        };
        let z2 = phi1(Cx(-2.0 * a * t, 2.0 * w * t));
        Self {
            osc: osc_int,
            exp2: t * phi1(Cx(-2.0 * a * t, 0.0)).0,
            exp2_cos: t * z2.0,
            exp2_sin: t * z2.1,
        }
    }
}

/// `∫₀^h (B + e^{−aτ}(c·cos ωτ + d·sin ωτ))² dτ` for a velocity wave whose polynomial part is the
/// constant `B` (the structure's velocity within a mode). Used for the damping energy `∫c·u̇²`.
pub fn integral_of_square(v: &Wave, osc: Osc, b: &Basis) -> f64 {
    integral_of_square_with(v, b, &PieceIntegrals::new(osc, b))
}

/// [`integral_of_square`] with the piece's integrals precomputed.
pub fn integral_of_square_with(v: &Wave, b: &Basis, pi: &PieceIntegrals) -> f64 {
    debug_assert!(v.p[1] == 0.0 && v.p[2] == 0.0 && v.p[3] == 0.0);
    let h = b.tau;
    let big_b = v.p[0];
    let osc_only = Wave {
        p: [0.0; 4],
        c: v.c,
        d: v.d,
    };
    let cross = 2.0 * big_b * osc_only.integral_with(b, pi);
    // (c cos + d sin)² = (c²+d²)/2 + (c²−d²)/2·cos 2ωτ + c·d·sin 2ωτ
    let mean = 0.5 * (v.c * v.c + v.d * v.d);
    big_b * big_b * h
        + cross
        + mean * pi.exp2
        + 0.5 * (v.c * v.c - v.d * v.d) * pi.exp2_cos
        + v.c * v.d * pi.exp2_sin
}

/// `ψ_k(x) = ∫₀¹ θᵏ·e^{−xθ} dθ` for `x ≥ 0`, `k ≤ 4`. For `x ≤ 20` the series
/// `e^{−x}·k!·Σ_m x^m/(m+k+1)!` (positive terms, no cancellation); beyond,
/// `k!/x^{k+1}·(1 − e^{−x}·Σ_{m≤k} x^m/m!)`, whose subtracted term is below `2e-5`.
fn exp_moment(k: u32, x: f64) -> f64 {
    let k_fact = (1..=k).fold(1.0, |f, j| f * f64::from(j));
    if x <= 20.0 {
        let mut term = 1.0 / (1..=k + 1).fold(1.0, |f, j| f * f64::from(j));
        let mut sum = term;
        for m in 1..200 {
            term *= x / f64::from(m + k + 1);
            let next = sum + term;
            if next == sum {
                break;
            }
            sum = next;
        }
        (-x).exp() * k_fact * sum
    } else {
        let mut head = 1.0;
        let mut term = 1.0;
        for m in 1..=k {
            term *= x / f64::from(m);
            head += term;
        }
        k_fact / x.powi(k as i32 + 1) * (1.0 - (-x).exp() * head)
    }
}

/// `∫₀^h v(τ)² dτ` for a velocity `v = q₀ + q₁τ + q₂τ² + c·e^{−aτ}` (the wave of an oscillator
/// without stiffness, `omega = 0`, `a = decay ≥ 0`; `d` plays no part there): the polynomial
/// squared term by term, the cross and exponential terms through
/// `∫₀^h τᵏe^{−aτ} dτ = h^{k+1}·ψ_k(a·h)`. Used for the damping energy of an
/// elastic–perfectly-plastic structure's plastic branch.
pub fn integral_of_square_decay(v: &Wave, decay: f64, h: f64) -> f64 {
    debug_assert!(v.p[3] == 0.0);
    let [q0, q1, q2, _] = v.p;
    let poly = h
        * (q0 * q0
            + h * (q0 * q1
                + h * ((q1 * q1 + 2.0 * q0 * q2) / 3.0 + h * (q1 * q2 / 2.0 + h * q2 * q2 / 5.0))));
    if v.c == 0.0 {
        return poly;
    }
    let x = decay * h;
    let cross =
        h * (q0 * exp_moment(0, x) + h * (q1 * exp_moment(1, x) + h * q2 * exp_moment(2, x)));
    poly + 2.0 * v.c * cross + v.c * v.c * h * exp_moment(0, 2.0 * x)
}

/// Smallest and largest value over `s ∈ [0, 1]` of the cubic Hermite interpolant with end values
/// `f0`, `f1` and end slopes `m0`, `m1` (derivatives with respect to `s`). For a function `g` on
/// an interval of width `w`, `|g − H| ≤ max|g⁗|·w⁴/384` there, so the range of `H` widened by that
/// bounds the range of `g` far more tightly than the end values and a curvature bound alone.
pub fn hermite_range(f0: f64, f1: f64, m0: f64, m1: f64) -> (f64, f64) {
    // H(s) = f0 + a1·s + a2·s² + a3·s³.
    let a1 = m0;
    let a2 = 3.0 * (f1 - f0) - 2.0 * m0 - m1;
    let a3 = 2.0 * (f0 - f1) + m0 + m1;
    let (mut lo, mut hi) = (f0.min(f1), f0.max(f1));
    let mut take = |s: f64| {
        if s > 0.0 && s < 1.0 {
            let v = f0 + s * (a1 + s * (a2 + s * a3));
            lo = lo.min(v);
            hi = hi.max(v);
        }
    };
    // H'(s) = a1 + 2·a2·s + 3·a3·s²: its real roots, by the cancellation-free quadratic formula.
    let (qa, qb, qc) = (3.0 * a3, 2.0 * a2, a1);
    if qa == 0.0 {
        if qb != 0.0 {
            take(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let q = -0.5 * (qb + qb.signum() * disc.sqrt());
            take(q / qa);
            if q != 0.0 {
                take(qc / q);
            }
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(f: impl Fn(f64) -> f64, h: f64) -> f64 {
        // Composite Simpson with many panels: an independent numerical check.
        let n = 20_000;
        let dx = h / n as f64;
        let mut s = f(0.0) + f(h);
        for i in 1..n {
            s += f(i as f64 * dx) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * dx / 3.0
    }

    #[test]
    fn derivative_and_integrals_match_numerics() {
        let osc = Osc {
            decay: 0.7,
            omega: 9.0,
        };
        let g = Wave {
            p: [0.3, -1.2, 0.5, 0.25],
            c: 0.8,
            d: -0.4,
        };
        let h = 0.37;
        let f = |t: f64| g.eval(&Basis::at(osc, t));
        let dg = g.deriv(osc);
        let eps = 1e-6;
        let num = (f(0.2 + eps) - f(0.2 - eps)) / (2.0 * eps);
        assert!((dg.eval(&Basis::at(osc, 0.2)) - num).abs() < 1e-7);
        let exact = g.integral(osc, &Basis::at(osc, h));
        assert!((exact - quad(f, h)).abs() < 1e-12, "{exact}");
        let v = Wave {
            p: [0.6, 0.0, 0.0, 0.0],
            c: -0.3,
            d: 1.1,
        };
        let fv = |t: f64| v.eval(&Basis::at(osc, t)).powi(2);
        let sq = integral_of_square(&v, osc, &Basis::at(osc, h));
        assert!((sq - quad(fv, h)).abs() < 1e-12, "{sq}");
        // Tiny pieces and zero damping take the series branch.
        let osc0 = Osc {
            decay: 0.0,
            omega: 3.0,
        };
        let hs = 1e-4;
        let sq0 = integral_of_square(&v, osc0, &Basis::at(osc0, hs));
        let fv0 = |t: f64| v.eval(&Basis::at(osc0, t)).powi(2);
        let rel = ((sq0 - quad(fv0, hs)) / sq0).abs();
        assert!(rel < 1e-12, "{rel:e}");
    }

    #[test]
    fn bounds_hold_without_oscillation() {
        // `Osc { decay: a, omega: 0 }` (a branch without stiffness): the wave's exponential is
        // `c·e^{−aτ}` and each derivative multiplies it by `−a`, so `natural() = a` and the
        // amplitude bounds of `deriv_abs_bound` must hold; checked against dense samples of the
        // derivative waves, with a polynomial part of the size the r = 0 branch gives.
        for decay in [0.0, 0.4, 25.0] {
            let osc = Osc { decay, omega: 0.0 };
            assert_eq!(osc.natural(), decay);
            let g = Wave {
                p: [3.0, -40.0, 2.5, 0.0],
                c: -2.9,
                d: 0.0,
            };
            let amps = Osc::amplitudes(osc.natural(), g.amplitude());
            let (t0, t1) = (0.003, 0.02);
            let exp_t0 = (-decay * t0).exp();
            let mut dk = g;
            for (k, amp) in amps.iter().enumerate() {
                let bound = g.deriv_abs_bound(k, t1, exp_t0, *amp);
                for i in 0..=1000 {
                    let t = t0 + (t1 - t0) * i as f64 / 1000.0;
                    let v = dk.eval(&Basis::at(osc, t)).abs();
                    assert!(
                        v <= bound * (1.0 + 1e-15),
                        "a={decay} k={k} t={t}: {v} > {bound}"
                    );
                }
                dk = dk.deriv(osc);
            }
        }
    }

    #[test]
    fn square_integral_without_stiffness_matches_numerics() {
        // Independent oracle: composite Simpson on the wave evaluated through `Basis`. Decay
        // rates on both sides of the series/asymptotic switch (a·h = 20) and zero.
        for (decay, h) in [
            (0.63, 0.01),
            (3.0, 0.4),
            (70.0, 0.5),
            (0.0, 0.02),
            (1e-6, 0.01),
        ] {
            let osc = Osc { decay, omega: 0.0 };
            let v = Wave {
                p: [0.4, -2.0, 7.0, 0.0],
                c: -0.35,
                d: 0.0,
            };
            let f = |t: f64| v.eval(&Basis::at(osc, t)).powi(2);
            let exact = integral_of_square_decay(&v, decay, h);
            let num = quad(f, h);
            assert!(
                ((exact - num) / num).abs() < 1e-12,
                "a = {decay}, h = {h}: {exact} vs {num}"
            );
        }
    }

    #[test]
    fn decay_piece_matches_an_independent_integration() {
        use crate::sdof::decay_piece;
        // Independent oracle: classical RK4 in 20 000 steps on ü + a·u̇ = p₀ + p₁τ, with ∫u and
        // ∫u̇² carried as two more states (its error, of order (h/20 000)⁴ times the fourth
        // derivatives, lies far below the 1e-12 asked).
        let (p0, p1, u0, v0) = (-2.5, 40.0, 0.03, -0.4);
        for (a, h) in [(0.9, 1.0), (50.0, 0.02), (5.0, 0.1), (0.0, 0.01)] {
            let d = decay_piece(a, (p0, p1), (u0, v0), h, true);
            let e = decay_piece(a, (p0, p1), (u0, v0), h, false);
            assert!(e.int_v2.is_nan() && (e.u, e.v, e.int_u) == (d.u, d.v, d.int_u));
            let rate = |t: f64, y: [f64; 4]| [y[1], p0 + p1 * t - a * y[1], y[0], y[1] * y[1]];
            let steps = 20_000;
            let dt = h / steps as f64;
            let mut y = [u0, v0, 0.0, 0.0];
            for k in 0..steps {
                let t = k as f64 * dt;
                let at =
                    |y: [f64; 4], k: [f64; 4], w: f64| std::array::from_fn(|i| y[i] + w * k[i]);
                let k1 = rate(t, y);
                let k2 = rate(t + 0.5 * dt, at(y, k1, 0.5 * dt));
                let k3 = rate(t + 0.5 * dt, at(y, k2, 0.5 * dt));
                let k4 = rate(t + dt, at(y, k3, dt));
                y = std::array::from_fn(|i| {
                    y[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
                });
            }
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * y.abs().max(1e-3);
            assert!(close(d.u, y[0]), "a = {a}: u {} vs {}", d.u, y[0]);
            assert!(close(d.v, y[1]), "a = {a}: v {} vs {}", d.v, y[1]);
            assert!(close(d.int_u, y[2]), "a = {a}: ∫u {} vs {}", d.int_u, y[2]);
            assert!(
                close(d.int_v2, y[3]),
                "a = {a}: ∫v² {} vs {}",
                d.int_v2,
                y[3]
            );
        }
    }

    #[test]
    fn derivative_bounds_match_the_derivative_waves() {
        let osc = Osc {
            decay: 0.3,
            omega: 12.0,
        };
        let g = Wave {
            p: [0.1, -2.0, 3.0, -1.0],
            c: 0.5,
            d: 0.9,
        };
        let amps = Osc::amplitudes(osc.natural(), g.amplitude());
        let (t0, t1) = (0.05, 0.4);
        let exp_t0 = (-osc.decay * t0).exp();
        let mut dk = g;
        for (k, amp) in amps.iter().enumerate() {
            let direct = dk.abs_bound(osc, t0, t1);
            let ours = g.deriv_abs_bound(k, t1, exp_t0, *amp);
            assert!(
                (direct - ours).abs() <= 1e-12 * direct,
                "k = {k}: {direct} vs {ours}"
            );
            dk = dk.deriv(osc);
        }
    }

    #[test]
    fn hermite_range_brackets_dense_samples_of_the_cubic() {
        // Independent oracle: the cubic in Hermite basis form, sampled densely.
        let cases = [
            (0.0, 1.0, 0.0, 0.0),
            (0.2, -0.3, 2.5, 1.5),
            (1.0, 1.0, -3.0, 3.0),
            (0.0, 0.0, 1.0, 1.0),
            (-0.5, 0.7, 0.0, -4.0),
        ];
        for (f0, f1, m0, m1) in cases {
            let h = |s: f64| {
                let (s2, s3) = (s * s, s * s * s);
                f0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + m0 * (s3 - 2.0 * s2 + s)
                    + f1 * (-2.0 * s3 + 3.0 * s2)
                    + m1 * (s3 - s2)
            };
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..=100_000 {
                let v = h(i as f64 / 100_000.0);
                lo = lo.min(v);
                hi = hi.max(v);
            }
            let (rlo, rhi) = hermite_range(f0, f1, m0, m1);
            assert!(rlo <= lo + 1e-12 && rlo >= lo - 1e-9, "{rlo} vs {lo}");
            assert!(rhi >= hi - 1e-12 && rhi <= hi + 1e-9, "{rhi} vs {hi}");
        }
    }

    #[test]
    fn abs_bound_bounds() {
        let osc = Osc {
            decay: 0.2,
            omega: 30.0,
        };
        let g = Wave {
            p: [0.1, -2.0, 3.0, -1.0],
            c: 0.5,
            d: 0.9,
        };
        let b = g.abs_bound(osc, 0.1, 0.6);
        for i in 0..=1000 {
            let t = 0.1 + 0.5 * i as f64 / 1000.0;
            assert!(g.eval(&Basis::at(osc, t)).abs() <= b);
        }
    }
}
