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
