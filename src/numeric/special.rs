//! Special functions of the gamma family, for the stochastic motions' Arias-intensity envelope
//! (a gamma-shaped Husid curve), and the normal distribution function through them (the IDA
//! fragility fits).
//!
//! Kept here rather than taken from `statrs` (measured in `docs/ARCHITECTURE.md`, "Our own
//! numerics and the crates we measured"): `statrs` agrees with `ln Γ` and `P(a, x)` to 1e-14, but
//! its gamma quantile round-trips `P(q) = p` only to 3e-10 where this one does to 2e-15.

/// Stirling's correction `ln Γ(a) − [(a − ½)·ln a − a + ½·ln 2π]`, for `a ≥ 10` (error < 10⁻¹⁶).
fn stirling_correction(a: f64) -> f64 {
    let r = 1.0 / a;
    let r2 = r * r;
    r * (1.0 / 12.0
        - r2 * (1.0 / 360.0
            - r2 * (1.0 / 1260.0
                - r2 * (1.0 / 1680.0
                    - r2 * (1.0 / 1188.0 - r2 * (691.0 / 360_360.0 - r2 / 156.0))))))
}

const HALF_LN_2PI: f64 = 0.918_938_533_204_672_8;

/// `ln Γ(a)` for `a > 0`: Lanczos (g = 7, 9 coefficients) below 10, Stirling above.
pub fn ln_gamma(a: f64) -> f64 {
    if a >= 10.0 {
        return (a - 0.5) * a.ln() - a + HALF_LN_2PI + stirling_correction(a);
    }
    if a < 0.5 {
        // Reflection: Γ(a)·Γ(1 − a) = π / sin(πa).
        let pi = std::f64::consts::PI;
        return (pi / (pi * a).sin()).ln() - ln_gamma(1.0 - a);
    }
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let z = a - 1.0;
    let mut s = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        s += c / (z + i as f64);
    }
    let t = z + 7.5;
    HALF_LN_2PI + (z + 0.5) * t.ln() - t + s.ln()
}

/// `a·ln x − x − ln Γ(a)`, written for large `a` without cancellation.
pub fn ln_gamma_prefactor(a: f64, x: f64) -> f64 {
    if a < 10.0 {
        return a * x.ln() - x - ln_gamma(a);
    }
    let d = (x - a) / a;
    a * (d.ln_1p() - d) + 0.5 * a.ln() - HALF_LN_2PI - stirling_correction(a)
}

/// Regularised lower incomplete gamma function `P(a, x)`, `a > 0`.
pub fn reg_lower_gamma(a: f64, x: f64) -> f64 {
    reg_gamma_pair(a, x).0
}

/// Regularised upper incomplete gamma function `Q(a, x) = 1 − P(a, x)`, `a > 0`, accurate
/// relative to itself in the tail (from the continued fraction, not as `1 − P`).
pub fn reg_upper_gamma(a: f64, x: f64) -> f64 {
    reg_gamma_pair(a, x).1
}

/// The standard normal distribution function `Φ(z) = ½·erfc(−z/√2)`, through
/// `erf(x) = P(½, x²)`: relative accuracy of the incomplete gamma function in both tails.
pub fn normal_cdf(z: f64) -> f64 {
    if z.is_nan() {
        return f64::NAN;
    }
    let q = 0.5 * reg_upper_gamma(0.5, 0.5 * z * z);
    if z < 0.0 { q } else { 1.0 - q }
}

/// `(P(a, x), Q(a, x))`: the series for `P` below `x = a + 1`, the continued fraction for `Q`
/// above, the other as the complement.
fn reg_gamma_pair(a: f64, x: f64) -> (f64, f64) {
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    if x.is_infinite() {
        return (1.0, 0.0);
    }
    let pre = ln_gamma_prefactor(a, x).exp();
    if x < a + 1.0 {
        // Series: P = pre · Σ_n x^n / (a (a+1) … (a+n)).
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut ap = a;
        for _ in 0..10_000_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-17 {
                break;
            }
        }
        let p = (pre * sum).min(1.0);
        (p, 1.0 - p)
    } else {
        // Continued fraction for Q (modified Lentz).
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        let q = (pre * h).min(1.0);
        ((1.0 - q).max(0.0), q)
    }
}

/// `x` with `P(k, x) = p` (unit scale): bisection on a bracket, each step replaced by a Newton
/// step (`dP/dx` is the gamma density) when that step stays inside the current bracket, which
/// keeps bisection's guarantee and converges in a handful of steps; stops at the last bit.
pub fn gamma_quantile(k: f64, p: f64) -> f64 {
    let mut hi = k.max(1.0);
    while reg_lower_gamma(k, hi) < p {
        hi *= 2.0;
    }
    let mut lo = 0.0;
    let mut x = 0.5 * (lo + hi);
    for _ in 0..2000 {
        let f = reg_lower_gamma(k, x) - p;
        if f < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let density = ln_gamma_prefactor(k, x).exp() / x;
        let newton = x - f / density;
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if next == x || (next - x).abs() <= 2.0 * f64::EPSILON * x || hi - lo <= f64::EPSILON * hi {
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
    fn ln_gamma_matches_known_values() {
        // Lanczos (g = 7, n = 9) is good to ~1e-15 relative; Stirling with 7 terms to ~1e-16
        // above 10: 1e-13 leaves room for the sums.
        let sqrt_pi = std::f64::consts::PI.sqrt();
        let cases = [
            (0.5, sqrt_pi.ln()),
            (1.0, 0.0),
            (1.5, (0.5 * sqrt_pi).ln()),
            (5.0, 24f64.ln()),
            (10.0, 362_880f64.ln()),
            (20.0, 121_645_100_408_832_000f64.ln()),
            (100.0, 359.134_205_369_575_4),
        ];
        for (a, want) in cases {
            let got = ln_gamma(a);
            assert!(
                (got - want).abs() < 1e-13 * want.abs().max(1.0),
                "ln Γ({a}) = {got}, want {want}"
            );
        }
        // Continuity across the Lanczos/Stirling switch: Γ(a+1) = aΓ(a) with a < 10 < a+1.
        for a in [9.2, 9.5, 9.999_999] {
            let lhs = ln_gamma(a + 1.0);
            let rhs = a.ln() + ln_gamma(a);
            assert!((lhs - rhs).abs() < 1e-13 * lhs, "a = {a}: {lhs} vs {rhs}");
        }
    }

    #[test]
    fn incomplete_gamma_matches_closed_form_for_integer_shape() {
        // P(n, x) = 1 − e^(−x)·Σ_{j<n} x^j/j!  (exact for integer n); 1e-13 absolute.
        for n in [1u32, 2, 3, 7, 30] {
            for x in [0.01, 0.5, 1.0, 2.5, 6.0, 15.0, 29.0, 31.0, 45.0] {
                let mut term = 1.0;
                let mut sum = 1.0;
                for j in 1..n {
                    term *= x / j as f64;
                    sum += term;
                }
                let want = 1.0 - (-x).exp() * sum;
                let got = reg_lower_gamma(n as f64, x);
                assert!(
                    (got - want).abs() < 1e-13,
                    "P({n}, {x}) = {got}, want {want}"
                );
            }
        }
        // Large shape (the envelope may reach k ≈ 10⁶): P(k, k) → 1/2 + 1/(3√(2πk)).
        let k = 1e6;
        let want = 0.5 + 1.0 / (3.0 * (2.0 * std::f64::consts::PI * k).sqrt());
        assert!((reg_lower_gamma(k, k) - want).abs() < 1e-8);
    }

    #[test]
    fn normal_cdf_matches_tabulated_values_in_both_tails() {
        // Φ(z) to 17 digits (Abramowitz & Stegun 26.2, extended with mpmath): 1e-14 relative.
        let cases = [
            (0.0, 0.5),
            (1.0, 0.841_344_746_068_542_9),
            (-1.0, 0.158_655_253_931_457_05),
            (-1.959_963_984_540_054, 0.025),
            (2.5, 0.993_790_334_674_223_8),
            (-5.0, 2.866_515_718_791_939e-7),
            (-10.0, 7.619_853_024_160_527e-24),
            (-30.0, 4.906_713_927_148_187e-198),
        ];
        for (z, want) in cases {
            let got = normal_cdf(z);
            assert!(
                (got - want).abs() <= 1e-14 * want,
                "Φ({z}) = {got:e}, want {want:e}"
            );
        }
        // Symmetry Φ(−z) + Φ(z) = 1 across the series/continued-fraction switch (z² / 2 = 1.5).
        for z in [0.3, 1.5, 1.732, 1.733, 3.0] {
            assert!((normal_cdf(-z) + normal_cdf(z) - 1.0).abs() < 1e-15);
        }
    }
}
