//! The paper's published design equations, Eqs. 16 (Zone III) and 17 (Zone V), as printed.

/// `T_new` (s) by the paper's Eq. 16 (zone `"III"`) or 17 (`"V"`) at
/// `x = (T_p, μ_1, μ_2, α_1, α_2)`, `T_p` in s; `None` for another zone or another number of
/// features. docs/model.md ("The design equations") checks the worked example (1.138 s and 0.926 s) and the equations' flaws.
pub fn paper_equation(zone: &str, x: &[f64]) -> Option<f64> {
    let (a, b, c, d, e): ([f64; 5], f64, [f64; 5], f64, f64) = match zone {
        "III" => (
            [-4.284, -0.173, 0.015, -4.365, -4.567],
            2.022,
            [0.053, 0.003, 0.002, 0.044, 0.045],
            3.873,
            -97.3,
        ),
        "V" => (
            [-5.464, -2.268, -4.451, -5.064, -4.693],
            2.197,
            [0.052, 0.02, 0.038, 0.041, 0.038],
            3.97,
            -116.3,
        ),
        _ => return None,
    };
    let dot = |w: &[f64; 5]| w.iter().zip(x).map(|(w, x)| w * x).sum::<f64>();
    (x.len() == 5).then(|| dot(&a) + b * (dot(&c) + d).exp() + e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_equations_reproduce_the_worked_example() {
        // Section 9: T_p = 0.7 s, μ = 0.3/0.1, α = 1/1 → 1.138 s (Eq. 16), 0.926 s (Eq. 17).
        let x = [0.7, 0.3, 0.1, 1.0, 1.0];
        assert!((paper_equation("III", &x).unwrap() - 1.138).abs() < 5e-4);
        assert!((paper_equation("V", &x).unwrap() - 0.926).abs() < 5e-4);
        assert!(paper_equation("II", &x).is_none());
        assert!(paper_equation("III", &x[..4]).is_none());
    }
}
