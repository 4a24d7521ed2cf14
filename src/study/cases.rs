//! The paper's named cases and its numbers for them, stated once for the report, tests and
//! examples.

use crate::case::Case;

/// A case the paper names, as constants: `T_p`, `α_i` (bottom first), kinetic `μ_i`
/// (interface 1 first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperCase {
    pub period_s: f64,
    pub alpha: &'static [f64],
    pub mu: &'static [f64],
}

impl PaperCase {
    /// The case for a stack of `n` blocks: its own when it has `n` blocks; otherwise the same
    /// total mass in `n` equal blocks, `μ_1` kept and every upper interface given the case's
    /// top coefficient (one block: the whole stack on interface 1).
    pub fn case(&self, n: usize) -> Case {
        let period_s = self.period_s;
        if n == self.alpha.len() {
            return Case {
                period_s,
                alpha: self.alpha.to_vec(),
                mu: self.mu.to_vec(),
            };
        }
        let top = self.mu.last().copied().unwrap_or(self.mu[0]);
        let total: f64 = self.alpha.iter().sum();
        Case {
            period_s,
            alpha: vec![total / n as f64; n],
            mu: (0..n)
                .map(|i| if i == 0 { self.mu[0] } else { top })
                .collect(),
        }
    }
}

/// Section 7.1, the paper's example of `T_new`: `T_p` = 1 s, α = 0.5/0.5, μ = 0.2/0.1; in
/// Zone III the mean peak displacement 5.49 cm gives `T_new` = 1.38 s (docs/model.md).
pub const SECTION_7_1: PaperCase = PaperCase {
    period_s: 1.0,
    alpha: &[0.5, 0.5],
    mu: &[0.2, 0.1],
};

/// The paper's Section 7.1 result: zone, mean peak structure displacement (m), `T_new` (s).
pub const PAPER_SECTION_7_1: (&str, f64, f64) = ("III", 0.0549, 1.38);

/// Table 2: record #11, `T_p` = 0.5 s, α = 0.5/0.5, μ = 0.3/0.1.
pub const TABLE_2: PaperCase = PaperCase {
    period_s: 0.5,
    alpha: &[0.5, 0.5],
    mu: &[0.3, 0.1],
};

/// The paper's Table 2 values: zone, peak structure displacement with the single block and
/// with the stack, m.
pub const PAPER_TABLE_2: [(&str, f64, f64); 2] = [("III", 0.028, 0.021), ("V", 0.046, 0.035)];

/// The paper's Table 3 (fit quality of Eqs. 16–17): zone, R², R, RMSE (s), MSE (s²), MAE (s).
pub const PAPER_TABLE_3: [(&str, [f64; 5]); 2] = [
    ("III", [0.985, 0.992, 0.094, 0.009, 0.082]),
    ("V", [0.969, 0.985, 0.1, 0.01, 0.09]),
];

/// Section 9's worked example of the design equations: `T_p` = 0.7 s, α = 1/1, μ = 0.3/0.1;
/// Eq. 16 gives 1.138 s (Zone III), Eq. 17 gives 0.926 s (Zone V).
pub const SECTION_9: PaperCase = PaperCase {
    period_s: 0.7,
    alpha: &[1.0, 1.0],
    mu: &[0.3, 0.1],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_cases_for_other_stacks_keep_the_total_mass_and_the_bottom_friction() {
        let stack = |c: Case| (c.alpha, c.mu);
        assert_eq!(stack(SECTION_7_1.case(2)), (vec![0.5, 0.5], vec![0.2, 0.1]));
        assert_eq!(stack(SECTION_7_1.case(1)), (vec![1.0], vec![0.2]));
        assert_eq!(
            stack(TABLE_2.case(4)),
            (vec![0.25; 4], vec![0.3, 0.1, 0.1, 0.1])
        );
        assert_eq!(TABLE_2.case(4).period_s, 0.5);
    }
}
