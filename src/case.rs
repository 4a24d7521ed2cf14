//! A case: one structure and its stack, the unit the study's systems are built from (a point of
//! the sweep's grid, a case of the `ida:` section, one of the paper's named cases). Pure data.

use serde::{Deserialize, Serialize};
use std::fmt;

/// The bare structure's period and the stack on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Period of the bare structure `T_p`, s.
    pub period_s: f64,
    /// Mass ratios `α_i = m_i/m_p`, per block, bottom first.
    pub alpha: Vec<f64>,
    /// Kinetic friction coefficients, per interface, interface 1 (structure–block 1) first.
    pub mu: Vec<f64>,
}

impl Case {
    /// `α = Σα_i`, the whole stack's mass ratio.
    pub fn alpha_total(&self) -> f64 {
        self.alpha.iter().sum()
    }

    /// `T_rigid = T_p·sqrt(1+α)`, s: the period with the whole stack rigidly attached.
    pub fn t_rigid_s(&self) -> f64 {
        self.period_s * (1.0 + self.alpha_total()).sqrt()
    }

    /// Checks a case of a config's list whose cases have `blocks` blocks (those of its first):
    /// the period in range, one `α` and one `μ` per block, each in range; the key
    /// (`period_s`, `alpha`, `mu`) and why otherwise.
    pub fn check(&self, blocks: usize) -> Result<(), (&'static str, String)> {
        use crate::limits::{MAX_ALPHA, MAX_BLOCKS, MAX_MU, PERIOD_RANGE_S};
        let (lo, hi) = PERIOD_RANGE_S;
        if !(self.period_s.is_finite() && self.period_s >= lo && self.period_s <= hi) {
            return Err((
                "period_s",
                format!("{} must be in [{lo}, {hi}]", self.period_s),
            ));
        }
        let n = self.alpha.len();
        if n == 0 || n > MAX_BLOCKS || n != blocks {
            return Err((
                "alpha",
                format!(
                    "{n} blocks: every case needs the same number, 1 to {MAX_BLOCKS} ({blocks} in \
                     the first)"
                ),
            ));
        }
        if self.mu.len() != blocks {
            return Err(("mu", format!("needs one value per interface ({blocks})")));
        }
        if self.alpha.iter().any(|a| !(a.is_finite() && *a > 0.0)) || self.alpha_total() > MAX_ALPHA
        {
            return Err((
                "alpha",
                format!("values must be > 0 with a sum ≤ {MAX_ALPHA}"),
            ));
        }
        if (self.mu.iter()).any(|m| !(m.is_finite() && (0.0..=MAX_MU).contains(m))) {
            return Err(("mu", format!("values must be in [0, {MAX_MU}]")));
        }
        Ok(())
    }
}

/// `T_p = 1 s, α = [0.5, 0.5], μ = [0.2, 0.1]`.
impl fmt::Display for Case {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "T_p = {} s, α = {:?}, μ = {:?}",
            self.period_s, self.alpha, self.mu
        )
    }
}
