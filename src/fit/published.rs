//! The paper's published design equations, Eqs. 16 (Zone III) and 17 (Zone V), as printed.

use serde::Serialize;

/// One of the paper's equations, `T_new = a·x + b·e^{c·x + d} + e` at
/// `x = (T_p, μ_1, μ_2, α_1, α_2)`, `T_p` in s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperEquation {
    pub a: [f64; 5],
    pub b: f64,
    pub c: [f64; 5],
    pub d: f64,
    pub e: f64,
}

impl PaperEquation {
    /// The printed coefficients of Eq. 16 (zone `"III"`) or 17 (`"V"`); `None` for another zone.
    pub fn of_zone(zone: &str) -> Option<Self> {
        let (a, b, c, d, e) = match zone {
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
        Some(Self { a, b, c, d, e })
    }

    /// `T_new` (s) at `x`; `None` unless `x` has the equation's five features.
    pub fn evaluate(&self, x: &[f64]) -> Option<f64> {
        let dot = |w: &[f64; 5]| w.iter().zip(x).map(|(w, x)| w * x).sum::<f64>();
        (x.len() == 5).then(|| dot(&self.a) + self.b * (dot(&self.c) + self.d).exp() + self.e)
    }
}

/// `T_new` (s) by the paper's Eq. 16 (zone `"III"`) or 17 (`"V"`) at
/// `x = (T_p, μ_1, μ_2, α_1, α_2)`, `T_p` in s; `None` for another zone or another number of
/// features. docs/model.md ("The design equations") checks the worked example (1.138 s and 0.926 s) and the equations' flaws.
pub fn paper_equation(zone: &str, x: &[f64]) -> Option<f64> {
    PaperEquation::of_zone(zone)?.evaluate(x)
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
