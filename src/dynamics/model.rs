//! The physical system: a linear SDOF primary structure (PS) carrying a stack of rigid blocks
//! with Coulomb friction at every interface (docs/model.md, "The physical system").
//!
//! Body 0 is the PS, bodies `1..=n` are the blocks bottom-up; interface `i` lies under block `i`,
//! so interface 1 is PS–block 1. All displacements are relative to the ground.

use crate::limits::{MAX_ALPHA, MAX_MU, STRUCTURE_PERIOD_RANGE_S};
use thiserror::Error;

/// Standard gravity, m/s².
pub const G: f64 = 9.80665;

/// A parameter that makes the model impossible, named as the user wrote it.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModelError {
    #[error(
        "period_s must be within {lo} … {hi} s, got {0:?}",
        lo = STRUCTURE_PERIOD_RANGE_S.0,
        hi = STRUCTURE_PERIOD_RANGE_S.1
    )]
    Period(f64),
    #[error("damping ratio must be finite and in [0, 1), got {0}")]
    Damping(f64),
    #[error("structure mass_kg must be finite and > 0, got {0}")]
    Mass(f64),
    #[error(
        "alpha_{index} (mass ratio of block {index}) must be finite, > 0 and ≤ {MAX_ALPHA}, got {value:?}"
    )]
    Alpha { index: usize, value: f64 },
    #[error(
        "the stack's mass ratio Σα = {0:?} exceeds {MAX_ALPHA}: beyond it round-off spoils the \
         energy balance (the structure is a negligible appendage of its load)"
    )]
    AlphaTotal(f64),
    #[error(
        "mu_{index} (kinetic friction of interface {index}) must be finite, >= 0 and <= {MAX_MU}, got {value}"
    )]
    MuKinetic { index: usize, value: f64 },
    #[error("mu_static_{index} must be finite and >= mu_{index} (kinetic, {kinetic}), got {value}")]
    MuStatic {
        index: usize,
        value: f64,
        kinetic: f64,
    },
    #[error("{what} lists {got} values but the stack has {expected} blocks (one per interface)")]
    Count {
        what: &'static str,
        got: usize,
        expected: usize,
    },
}

/// A validated structure-and-stack system. Construct with [`System::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    period_s: f64,
    damping_ratio: f64,
    mass_kg: f64,
    /// Masses of all bodies, kg: `[m_p, m_1, …, m_n]`.
    masses: Vec<f64>,
    /// Kinetic friction coefficient per interface, interface 1 first.
    mu_k: Vec<f64>,
    /// Static friction coefficient per interface (`≥ mu_k`).
    mu_s: Vec<f64>,
    /// Normal force per interface, N: `N_i = g·Σ_{j≥i} m_j`.
    normal: Vec<f64>,
    stiffness: f64,
    damping: f64,
}

/// What a user states about a system; [`System::new`] validates it.
#[derive(Debug, Clone, PartialEq)]
pub struct SystemSpec {
    /// Period of the bare structure `T_p`, s.
    pub period_s: f64,
    /// Viscous damping ratio `ζ` of the bare structure.
    pub damping_ratio: f64,
    /// Structure mass `m_p`, kg. Results per kg do not depend on it.
    pub mass_kg: f64,
    /// Block mass ratios `α_i = m_i/m_p`, bottom block first.
    pub alpha: Vec<f64>,
    /// Kinetic friction coefficients `μ_k,i`, interface 1 first.
    pub mu: Vec<f64>,
    /// Static friction coefficients `μ_s,i`; `None` means equal to the kinetic ones.
    pub mu_static: Option<Vec<f64>>,
}

impl SystemSpec {
    /// A spec with `ζ = 0.05`, `m_p = 1 kg`, static friction equal to kinetic.
    pub fn new(period_s: f64, alpha: &[f64], mu: &[f64]) -> Self {
        Self {
            period_s,
            damping_ratio: 0.05,
            mass_kg: 1.0,
            alpha: alpha.to_vec(),
            mu: mu.to_vec(),
            mu_static: None,
        }
    }
}

impl System {
    /// Validates every parameter and derives `k = m_p·(2π/T_p)²`, `c = 2ζ·sqrt(k·m_p)`.
    pub fn new(spec: &SystemSpec) -> Result<Self, ModelError> {
        let SystemSpec {
            period_s,
            damping_ratio,
            mass_kg,
            ref alpha,
            ref mu,
            ref mu_static,
        } = *spec;
        if !(STRUCTURE_PERIOD_RANGE_S.0..=STRUCTURE_PERIOD_RANGE_S.1).contains(&period_s) {
            return Err(ModelError::Period(period_s));
        }
        if !(mass_kg.is_finite() && mass_kg > 0.0) {
            return Err(ModelError::Mass(mass_kg));
        }
        let n = alpha.len();
        if mu.len() != n {
            return Err(ModelError::Count {
                what: "mu",
                got: mu.len(),
                expected: n,
            });
        }
        for (i, &a) in alpha.iter().enumerate() {
            if !(a.is_finite() && a > 0.0 && a <= MAX_ALPHA) {
                return Err(ModelError::Alpha {
                    index: i + 1,
                    value: a,
                });
            }
        }
        let total: f64 = alpha.iter().sum();
        if total > MAX_ALPHA {
            return Err(ModelError::AlphaTotal(total));
        }
        for (i, &m) in mu.iter().enumerate() {
            if !(m.is_finite() && (0.0..=MAX_MU).contains(&m)) {
                return Err(ModelError::MuKinetic {
                    index: i + 1,
                    value: m,
                });
            }
        }
        let mu_s = match mu_static {
            None => mu.clone(),
            Some(s) => {
                if s.len() != n {
                    return Err(ModelError::Count {
                        what: "mu_static",
                        got: s.len(),
                        expected: n,
                    });
                }
                for (i, (&ms, &mk)) in s.iter().zip(mu).enumerate() {
                    if !(ms.is_finite() && ms >= mk && ms <= MAX_MU) {
                        return Err(ModelError::MuStatic {
                            index: i + 1,
                            value: ms,
                            kinetic: mk,
                        });
                    }
                }
                s.clone()
            }
        };
        if !(damping_ratio.is_finite() && (0.0..1.0).contains(&damping_ratio)) {
            return Err(ModelError::Damping(damping_ratio));
        }
        let mut masses = Vec::with_capacity(n + 1);
        masses.push(mass_kg);
        masses.extend(alpha.iter().map(|a| a * mass_kg));
        let mut normal = vec![0.0; n];
        let mut above = 0.0;
        for i in (0..n).rev() {
            above += masses[i + 1];
            normal[i] = G * above;
        }
        let omega = 2.0 * std::f64::consts::PI / period_s;
        let stiffness = mass_kg * omega * omega;
        let damping = 2.0 * damping_ratio * (stiffness * mass_kg).sqrt();
        Ok(Self {
            period_s,
            damping_ratio,
            mass_kg,
            masses,
            mu_k: mu.clone(),
            mu_s,
            normal,
            stiffness,
            damping,
        })
    }

    /// Number of blocks `n`.
    pub fn blocks(&self) -> usize {
        self.masses.len() - 1
    }
    /// Bare-structure period `T_p`, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }
    /// Bare-structure damping ratio `ζ`.
    pub fn damping_ratio(&self) -> f64 {
        self.damping_ratio
    }
    /// Structure mass `m_p`, kg.
    pub fn mass_kg(&self) -> f64 {
        self.mass_kg
    }
    /// Masses `[m_p, m_1, …, m_n]`, kg.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }
    /// Kinetic friction coefficients, interface 1 first.
    pub fn mu_kinetic(&self) -> &[f64] {
        &self.mu_k
    }
    /// Static friction coefficients, interface 1 first.
    pub fn mu_static(&self) -> &[f64] {
        &self.mu_s
    }
    /// Normal force on each interface, N.
    pub fn normal_force(&self) -> &[f64] {
        &self.normal
    }
    /// Lateral stiffness `k`, N/m.
    pub fn stiffness(&self) -> f64 {
        self.stiffness
    }
    /// Viscous damping coefficient `c`, N·s/m (set from the bare structure).
    pub fn damping(&self) -> f64 {
        self.damping
    }
    /// Total block mass ratio `α = Σα_i`.
    pub fn alpha_total(&self) -> f64 {
        self.masses[1..].iter().sum::<f64>() / self.mass_kg
    }
    /// Period with the whole stack rigidly attached, `T_p·sqrt(1+α)` (paper Eq. 13), s.
    pub fn period_rigid_s(&self) -> f64 {
        self.period_s * (1.0 + self.alpha_total()).sqrt()
    }
    /// Kinetic friction force limit of interface `i` (1-based), N.
    pub fn kinetic_limit(&self, i: usize) -> f64 {
        self.mu_k[i - 1] * self.normal[i - 1]
    }
    /// Static friction force limit of interface `i` (1-based), N.
    pub fn static_limit(&self, i: usize) -> f64 {
        self.mu_s[i - 1] * self.normal[i - 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_impossible_parameters_naming_them() {
        let ok = SystemSpec::new(1.0, &[0.5, 0.5], &[0.2, 0.1]);
        assert!(System::new(&ok).is_ok());
        let cases: Vec<(SystemSpec, &str)> = vec![
            (
                SystemSpec {
                    period_s: 0.0,
                    ..ok.clone()
                },
                "period_s",
            ),
            (
                SystemSpec {
                    damping_ratio: 1.0,
                    ..ok.clone()
                },
                "damping ratio",
            ),
            (
                SystemSpec {
                    mass_kg: -1.0,
                    ..ok.clone()
                },
                "mass_kg",
            ),
            (
                SystemSpec {
                    alpha: vec![0.5, -0.1],
                    ..ok.clone()
                },
                "alpha_2",
            ),
            (
                SystemSpec {
                    mu: vec![-0.1, 0.1],
                    ..ok.clone()
                },
                "mu_1",
            ),
            (
                SystemSpec {
                    mu: vec![0.1, f64::NAN],
                    ..ok.clone()
                },
                "mu_2",
            ),
            (
                SystemSpec {
                    mu: vec![0.1],
                    ..ok.clone()
                },
                "mu lists 1",
            ),
            (
                SystemSpec {
                    mu_static: Some(vec![0.1, 0.1]),
                    ..ok.clone()
                },
                "mu_static_1",
            ),
        ];
        for (spec, needle) in cases {
            let msg = System::new(&spec).unwrap_err().to_string();
            assert!(msg.contains(needle), "{msg:?} should name {needle:?}");
        }
    }

    #[test]
    fn derived_quantities() {
        let s = System::new(&SystemSpec::new(1.0, &[0.5, 0.5], &[0.2, 0.1])).unwrap();
        assert!((s.period_rigid_s() - 2f64.sqrt()).abs() < 1e-15);
        assert!((s.normal_force()[0] - G).abs() < 1e-12);
        assert!((s.normal_force()[1] - 0.5 * G).abs() < 1e-12);
        let omega = 2.0 * std::f64::consts::PI;
        assert!((s.damping() - 2.0 * 0.05 * omega).abs() < 1e-12);
    }
}
