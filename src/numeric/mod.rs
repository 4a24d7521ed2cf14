//! Small numerical kernels, each written once and tested against its own oracle:
//!
//! * here: complex arithmetic, the φ-functions of exponential integrators, 8-point
//!   Gauss–Legendre nodes, a bracketed Newton root finder;
//! * [`linalg`]: Cholesky, least squares by `nalgebra`'s SVD, the 4×4 matrix exponential;
//! * [`special`]: `ln Γ`, the regularised incomplete gamma functions and the gamma quantile,
//!   the normal distribution function;
//! * [`rng`]: the seeded generator of the stochastic motions;
//! * [`filter`]: Butterworth high-pass sections.

pub mod filter;
pub mod linalg;
pub mod rng;
pub mod special;

pub use linalg::cholesky_solve;

/// Complex number `re + i·im`, just what the closed-form integrals need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cx(pub f64, pub f64);

impl Cx {
    pub fn mul(self, o: Cx) -> Cx {
        Cx(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    pub fn div(self, o: Cx) -> Cx {
        let den = o.0 * o.0 + o.1 * o.1;
        Cx(
            (self.0 * o.0 + self.1 * o.1) / den,
            (self.1 * o.0 - self.0 * o.1) / den,
        )
    }
    pub fn add(self, o: Cx) -> Cx {
        Cx(self.0 + o.0, self.1 + o.1)
    }
    pub fn sub(self, o: Cx) -> Cx {
        Cx(self.0 - o.0, self.1 - o.1)
    }
    pub fn scale(self, s: f64) -> Cx {
        Cx(self.0 * s, self.1 * s)
    }
    /// `|x|`.
    pub fn abs(self) -> f64 {
        self.0.hypot(self.1)
    }
    /// `|x|²` (cheaper than `hypot` where only a comparison is needed).
    pub fn norm_sqr(self) -> f64 {
        self.0 * self.0 + self.1 * self.1
    }
    /// `eˣ`.
    pub fn exp(self) -> Cx {
        let e = self.0.exp();
        let (s, c) = self.1.sin_cos();
        Cx(e * c, e * s)
    }
}

/// Taylor series `Σ_{k≥0} x^k/(k+j)!` of `φ_j`, used where the closed forms cancel (`|x| < 2`),
/// summed until a term no longer changes the sum (at most 30 terms).
pub(crate) fn phi_series(x: Cx, j: u32) -> Cx {
    let first = (1..=j).fold(1.0, |f, k| f * k as f64);
    let mut term = Cx(1.0 / first, 0.0);
    let mut sum = term;
    for k in 1..=30 {
        let t = term.mul(x);
        let inv = 1.0 / (k + j) as f64;
        term = Cx(t.0 * inv, t.1 * inv);
        let next = sum.add(term);
        if next == sum {
            break;
        }
        sum = next;
    }
    sum
}

/// `φ₁(x) = (eˣ − 1)/x` for complex `x`, accurate also near 0.
pub(crate) fn phi1(x: Cx) -> Cx {
    if x.norm_sqr() < 0.25 {
        phi_series(x, 1)
    } else {
        let e = x.0.exp();
        let (s, c) = x.1.sin_cos();
        Cx(e * c - 1.0, e * s).div(x)
    }
}

/// `φ₂(x) = (eˣ − 1 − x)/x²` for complex `x`, accurate also near 0.
pub(crate) fn phi2(x: Cx) -> Cx {
    if x.norm_sqr() < 1.0 {
        phi_series(x, 2)
    } else {
        phi1(x).add(Cx(-1.0, 0.0)).div(x)
    }
}

/// `φ₃(x) = (eˣ − 1 − x − x²/2)/x³` for complex `x`, accurate also near 0.
pub(crate) fn phi3(x: Cx) -> Cx {
    if x.norm_sqr() < 4.0 {
        phi_series(x, 3)
    } else {
        phi2(x).add(Cx(-0.5, 0.0)).div(x)
    }
}

/// Nodes and weights of 8-point Gauss–Legendre quadrature on `[0, 1]` (the roots of `P₈` by
/// Newton's method at 50 digits, rounded).
pub(crate) const GAUSS8: [(f64, f64); 8] = [
    (0.019855071751231884, 0.05061426814518813),
    (0.10166676129318664, 0.11119051722668724),
    (0.2372337950418355, 0.15685332293894363),
    (0.4082826787521751, 0.181341891689181),
    (0.591717321247825, 0.181341891689181),
    (0.7627662049581645, 0.15685332293894363),
    (0.8983332387068134, 0.11119051722668724),
    (0.9801449282487681, 0.05061426814518813),
];

/// A root in `[lo, hi]` of `f`, where `f_lo = f(lo)` and `f_hi = f(hi)` differ in sign (or one
/// is zero), by Newton steps kept inside the shrinking bracket (bisection when a step leaves
/// it); `f_df(x)` returns `(f(x), f'(x))`. Returns a point within a few ulps of the root.
pub(crate) fn bracketed_root(
    f_df: impl Fn(f64) -> (f64, f64),
    mut lo: f64,
    mut hi: f64,
    f_lo: f64,
    f_hi: f64,
) -> f64 {
    if f_lo == 0.0 {
        return lo;
    }
    if f_hi == 0.0 {
        return hi;
    }
    let lo_sign = f_lo.is_sign_positive();
    // Start from the secant point: good when the bracket is short against the curvature.
    let mut x = lo + (hi - lo) * f_lo / (f_lo - f_hi);
    if !(x > lo && x < hi) {
        x = 0.5 * (lo + hi);
    }
    for _ in 0..100 {
        let (fx, dfx) = f_df(x);
        if fx == 0.0 {
            return x;
        }
        if fx.is_sign_positive() == lo_sign {
            lo = x;
        } else {
            hi = x;
        }
        let step = fx / dfx;
        let mut next = x - step;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 2.0 * f64::EPSILON * x.abs() || next == lo || next == hi {
            return next;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phi_functions_match_their_definitions_away_from_zero() {
        for &(re, im) in &[(-0.3, 2.0), (0.9, -0.4), (-4.0, 7.0), (0.2, 0.1)] {
            let x = Cx(re, im);
            let e = Cx(re.exp() * im.cos(), re.exp() * im.sin());
            let p1 = Cx(e.0 - 1.0, e.1).div(x);
            let p2 = Cx(e.0 - 1.0 - re, e.1 - im).div(x.mul(x));
            let (s1, s2) = (phi_series(x, 1), phi_series(x, 2));
            // The series at |x| ≤ 8 with 30 terms: truncation below 8^31/32! ≈ 1e-7 relative only
            // at the largest point, so compare the series where it is used (|x| < 1).
            if x.norm_sqr() < 1.0 {
                assert!((s1.0 - p1.0).abs() + (s1.1 - p1.1).abs() < 1e-14);
                assert!((s2.0 - p2.0).abs() + (s2.1 - p2.1).abs() < 1e-13);
            }
            let (q1, q2) = (phi1(x), phi2(x));
            assert!((q1.0 - p1.0).abs() + (q1.1 - p1.1).abs() < 1e-14);
            assert!((q2.0 - p2.0).abs() + (q2.1 - p2.1).abs() < 1e-13);
        }
    }

    #[test]
    fn phi_functions_at_tiny_and_huge_arguments() {
        // Tiny: the first three Taylor terms are exact to round-off at |x| = 1e-9.
        for x in [Cx(-1e-9, 3e-10), Cx(0.0, 1e-12), Cx(-1e-300, 0.0)] {
            let x2 = x.mul(x);
            for (got, c) in [
                (phi1(x), [1.0, 1.0 / 2.0, 1.0 / 6.0]),
                (phi2(x), [1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0]),
                (phi3(x), [1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0]),
            ] {
                let want = Cx(c[0] + c[1] * x.0 + c[2] * x2.0, c[1] * x.1 + c[2] * x2.1);
                assert!((got.0 - want.0).abs() <= 1e-16 * c[0], "{x:?} {got:?}");
                assert!(
                    (got.1 - want.1).abs() <= 1e-16 * (c[1] * x.1).abs(),
                    "{x:?} {got:?}"
                );
            }
        }
        // Huge, in the left half plane: eˣ vanishes, φ₁ = −1/x, φ₂ = −(1 + x)/x², φ₃ = …
        for x in [Cx(-1e3, 0.0), Cx(-50.0, 1e4), Cx(-800.0, -2e5)] {
            let inv = Cx(1.0, 0.0).div(x);
            let w1 = Cx(-inv.0, -inv.1);
            let w2 = w1.add(Cx(-1.0, 0.0)).div(x);
            let w3 = w2.add(Cx(-0.5, 0.0)).div(x);
            let e = Cx(x.0.exp() * x.1.cos(), x.0.exp() * x.1.sin());
            let (w1, w2, w3) = (
                w1.add(e.div(x)),
                w2.add(e.div(x.mul(x))),
                w3.add(e.div(x.mul(x).mul(x))),
            );
            for (got, want) in [(phi1(x), w1), (phi2(x), w2), (phi3(x), w3)] {
                let err = ((got.0 - want.0).powi(2) + (got.1 - want.1).powi(2)).sqrt();
                assert!(
                    err <= 1e-15 * want.norm_sqr().sqrt(),
                    "{x:?} {got:?} {want:?}"
                );
            }
        }
        // φ₃ on both sides of its switch from the series (|x| = 2) against the definition.
        for x in [Cx(-1.99, 0.1), Cx(-2.01, 0.1), Cx(0.3, -2.5)] {
            let e = Cx(x.0.exp() * x.1.cos(), x.0.exp() * x.1.sin());
            let x2 = x.mul(x);
            let want = Cx(e.0 - 1.0 - x.0 - x2.0 / 2.0, e.1 - x.1 - x2.1 / 2.0).div(x2.mul(x));
            let got = phi3(x);
            assert!(
                (got.0 - want.0).abs() + (got.1 - want.1).abs() < 1e-14,
                "{x:?}"
            );
        }
    }

    #[test]
    fn root_of_cosine() {
        let r = bracketed_root(|x| (x.cos(), -x.sin()), 0.0, 3.0, 1.0, 3f64.cos());
        // Within a few ulps (2.2e-16 each) of π/2.
        assert!((r - std::f64::consts::FRAC_PI_2).abs() < 2e-15);
        // A derivative that lies sends Newton outside: bisection still converges.
        let r = bracketed_root(|x| (x * x * x - 2.0, 1e-9), 0.0, 2.0, -2.0, 6.0);
        assert!((r - 2f64.cbrt()).abs() < 1e-14);
    }
}
