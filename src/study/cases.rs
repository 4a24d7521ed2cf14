//! The paper's named cases, stated once for the report, tests and examples.

/// A structure and its stack: `T_p`, `α_i` (bottom first), kinetic `μ_i` (interface 1 first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NamedCase {
    pub period_s: f64,
    pub alpha: &'static [f64],
    pub mu: &'static [f64],
}

impl NamedCase {
    /// `α = Σα_i`.
    pub fn alpha_total(&self) -> f64 {
        self.alpha.iter().sum()
    }

    /// `(α, μ)` of the case for a stack of `n` blocks: its own when it has `n` blocks; otherwise
    /// the same total mass in `n` equal blocks, `μ_1` kept and every upper interface given the
    /// case's top coefficient (one block: the whole stack on interface 1).
    pub fn for_blocks(&self, n: usize) -> (Vec<f64>, Vec<f64>) {
        if n == self.alpha.len() {
            return (self.alpha.to_vec(), self.mu.to_vec());
        }
        let top = self.mu.last().copied().unwrap_or(self.mu[0]);
        let mu = (0..n)
            .map(|i| if i == 0 { self.mu[0] } else { top })
            .collect();
        (vec![self.alpha_total() / n as f64; n], mu)
    }
}

/// Section 7.1, the paper's example of `T_new`: `T_p` = 1 s, α = 0.5/0.5, μ = 0.2/0.1; in
/// Zone III the mean peak displacement 5.49 cm gives `T_new` = 1.38 s (docs/model.md).
pub const SECTION_7_1: NamedCase = NamedCase {
    period_s: 1.0,
    alpha: &[0.5, 0.5],
    mu: &[0.2, 0.1],
};

/// The paper's Section 7.1 result: zone, mean peak structure displacement (m), `T_new` (s).
pub const PAPER_SECTION_7_1: (&str, f64, f64) = ("III", 0.0549, 1.38);

/// Table 2: record #11, `T_p` = 0.5 s, α = 0.5/0.5, μ = 0.3/0.1.
pub const TABLE_2: NamedCase = NamedCase {
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
pub const SECTION_9: NamedCase = NamedCase {
    period_s: 0.7,
    alpha: &[1.0, 1.0],
    mu: &[0.3, 0.1],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_cases_for_other_stacks_keep_the_total_mass_and_the_bottom_friction() {
        assert_eq!(SECTION_7_1.for_blocks(2), (vec![0.5, 0.5], vec![0.2, 0.1]));
        assert_eq!(SECTION_7_1.for_blocks(1), (vec![1.0], vec![0.2]));
        let (a, m) = TABLE_2.for_blocks(4);
        assert_eq!((a, m), (vec![0.25; 4], vec![0.3, 0.1, 0.1, 0.1]));
    }
}
