//! The physical system: a linear SDOF primary structure (PS) carrying a stack of rigid blocks
//! with Coulomb friction at every interface (docs/model.md, "The physical system").
//!
//! Body 0 is the PS, bodies `1..=n` are the blocks bottom-up; interface `i` lies under block `i`,
//! so interface 1 is PS–block 1. All displacements are relative to the ground.
//!
//! The PS is linear unless [`System::with_yielding`] gives it a bilinear restoring force
//! (docs/model.md, "Yielding structure").

use crate::limits::{
    MAX_ALPHA, MAX_MU, MAX_POST_YIELD_DAMPING, STRENGTH_RATIO_RANGE, STRUCTURE_PERIOD_RANGE_S,
};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Standard gravity, m/s².
pub const G: f64 = 9.80665;

/// What a damping ratio `ζ` refers to (docs/model.md, "Damping basis"): on one storey the
/// system whose ratio it is; for a building the system whose modes the damping matrix is built
/// from (`rigid`: every stack's mass on its floor; `structure`: the bare floors).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DampingBasis {
    /// `ζ` of the structure with its whole load rigidly attached: one physical
    /// `c = 2·ζ·sqrt(1+α)·ω_p·m_p` for the stack, the single block and the rigid system, so the
    /// rigid system is damped at `ζ`, as the 5 %-damped spectrum it is read against (`T_new`
    /// equals `T_rigid` when nothing slides).
    #[default]
    Rigid,
    /// `ζ` of the bare structure, `c = 2·ζ·ω_p·m_p` (the rigidly loaded system then has
    /// `ζ/sqrt(1+α)`): the convention of the first versions of the study.
    Structure,
}

impl DampingBasis {
    pub fn name(self) -> &'static str {
        match self {
            DampingBasis::Rigid => "rigid",
            DampingBasis::Structure => "structure",
        }
    }
}

impl std::str::FromStr for DampingBasis {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "rigid" => Ok(DampingBasis::Rigid),
            "structure" => Ok(DampingBasis::Structure),
            other => Err(format!(
                "damping basis `{other}`: expected `rigid` or `structure`"
            )),
        }
    }
}

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
    #[error(
        "aspect_{index} (width over height of block {index}) must be finite and > 0, got {value}"
    )]
    Aspect { index: usize, value: f64 },
    #[error("{what} lists {got} values but the stack has {expected} blocks (one per interface)")]
    Count {
        what: &'static str,
        got: usize,
        expected: usize,
    },
    #[error(
        "yield strength ratio C_y = F_y/(m_p·g) must be within {lo} … {hi}, got {0:?}",
        lo = STRENGTH_RATIO_RANGE.0,
        hi = STRENGTH_RATIO_RANGE.1
    )]
    StrengthRatio(f64),
    #[error(
        "post-yield stiffness ratio r must be finite, >= 0 and < 1 (r = 1 is the elastic \
         structure), got {0:?}"
    )]
    PostYieldRatio(f64),
    #[error(
        "post-yield stiffness ratio r = {r} makes the post-yield branch {what} (damping ratio \
         ζ/√r = {zeta_post:.3} with the bare structure's ζ = {zeta:.4}; at most \
         {MAX_POST_YIELD_DAMPING} is supported): use r = 0 (elastic–perfectly plastic) or \
         r >= {r_min:.4}"
    )]
    PostYieldOverdamped {
        r: f64,
        zeta: f64,
        zeta_post: f64,
        r_min: f64,
        what: &'static str,
    },
}

/// A yielding primary structure as a user states it (docs/model.md, "Yielding structure"):
/// bilinear with kinematic hardening, elastic stiffness `k`, yield force `F_y`, post-yield
/// stiffness `r·k`; `r = 0` is elastic–perfectly plastic (EPP). [`System::with_yielding`]
/// validates it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Yielding {
    /// Yield strength ratio `C_y = F_y/(m_p·g)`, `m_p` the bare structure's mass (Chopra,
    /// *Dynamics of Structures*, Section 7.1: the yield pseudo-acceleration `A_y/g`).
    pub strength_ratio: f64,
    /// Post-yield stiffness ratio `r`, `0 ≤ r < 1`.
    pub post_yield_ratio: f64,
}

impl Yielding {
    /// Elastic–perfectly plastic with `C_y = F_y/(m_p·g)`.
    pub fn epp(strength_ratio: f64) -> Self {
        Self {
            strength_ratio,
            post_yield_ratio: 0.0,
        }
    }

    /// Bilinear with kinematic hardening: `C_y = F_y/(m_p·g)`, post-yield stiffness ratio `r`.
    pub fn bilinear(strength_ratio: f64, post_yield_ratio: f64) -> Self {
        Self {
            strength_ratio,
            post_yield_ratio,
        }
    }

    /// From the yield displacement `u_y` (m) of a structure of period `T_p` (s):
    /// `C_y = ω_p²·u_y/g`.
    pub fn from_yield_displacement(period_s: f64, yield_displacement_m: f64, r: f64) -> Self {
        let omega = std::f64::consts::TAU / period_s;
        Self::bilinear(omega * omega * yield_displacement_m / G, r)
    }
}

/// The validated bilinear restoring force of a yielding structure, with its derived constants.
///
/// For a given history the force lies between the two bounding lines
/// `F = r·k·u ± (1 − r)·F_y` (kinematic hardening: they do not move); between them it follows an
/// elastic line of slope `k`. Elastic range: `2·u_y` wide.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    /// `C_y = F_y/(m_p·g)`.
    pub strength_ratio: f64,
    /// `r`, post-yield over elastic stiffness.
    pub post_yield_ratio: f64,
    /// Elastic stiffness `k`, N/m.
    pub stiffness: f64,
    /// `F_y = C_y·m_p·g`, N.
    pub yield_force_n: f64,
    /// `u_y = F_y/k`, m.
    pub yield_displacement_m: f64,
}

impl Hysteresis {
    /// `(1 − r)·F_y`, N: the bounding lines' intercept.
    pub fn intercept_n(&self) -> f64 {
        (1.0 - self.post_yield_ratio) * self.yield_force_n
    }

    /// Force on the bounding line of side `dir` (±1) at `u` (m): `r·k·u + dir·(1 − r)·F_y`, N.
    pub fn bound_n(&self, u: f64, dir: f64) -> f64 {
        self.post_yield_ratio * self.stiffness * u + dir * self.intercept_n()
    }

    /// The restoring force at `u` (m) of a structure whose last elastic line passes through
    /// `(anchor_u, anchor_f)` (m, N): that line clamped between the bounding lines. Used by the
    /// fixed-step RK4 (`rk4.rs`); the exact integrator follows the branches as events instead.
    pub fn force_n(&self, u: f64, anchor_u: f64, anchor_f: f64) -> f64 {
        let trial = anchor_f + self.stiffness * (u - anchor_u);
        trial.clamp(self.bound_n(u, -1.0), self.bound_n(u, 1.0))
    }

    /// Recoverable strain energy at force `f` (N): `f²/(2k)`, J (released by elastic unloading
    /// to zero force).
    pub fn recoverable_energy(&self, f: f64) -> f64 {
        f * f / (2.0 * self.stiffness)
    }
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
    /// The bilinear restoring force; `None` for the linear structure.
    hysteresis: Option<Hysteresis>,
    /// The rocking check of the stack ([`System::with_aspect`]); `None`: not checked.
    rocking: Option<Box<super::Rocking>>,
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
            hysteresis: None,
            rocking: None,
        })
    }

    /// The same system with its blocks' width-to-height ratios (bottom first), so that a run
    /// reports when the stack would start to rock ([`super::rocking`]).
    pub fn with_aspect(mut self, aspect: &[f64]) -> Result<Self, ModelError> {
        self.rocking = Some(Box::new(super::Rocking::new(&self.masses[1..], aspect)?));
        Ok(self)
    }

    /// The rocking check, when the blocks' ratios are given.
    pub fn rocking(&self) -> Option<&super::Rocking> {
        self.rocking.as_deref()
    }

    /// The same system on a yielding structure (docs/model.md, "Yielding structure"). Refuses a
    /// strength outside [`STRENGTH_RATIO_RANGE`], `r` outside `[0, 1)`, and an `r > 0` whose
    /// post-yield branch is overdamped or nearly so (see [`MAX_POST_YIELD_DAMPING`]): the
    /// bare structure alone (every block sliding) is the lightest cluster and so the most
    /// damped, with `ζ/√r`.
    pub fn with_yielding(mut self, y: Yielding) -> Result<Self, ModelError> {
        let Yielding {
            strength_ratio,
            post_yield_ratio: r,
        } = y;
        if !(STRENGTH_RATIO_RANGE.0..=STRENGTH_RATIO_RANGE.1).contains(&strength_ratio) {
            return Err(ModelError::StrengthRatio(strength_ratio));
        }
        if !(r.is_finite() && (0.0..1.0).contains(&r)) {
            return Err(ModelError::PostYieldRatio(r));
        }
        let zeta = self.damping_ratio;
        if r > 0.0 && zeta > 0.0 {
            let zeta_post = zeta / r.sqrt();
            if zeta_post > MAX_POST_YIELD_DAMPING {
                let r_min = (zeta / MAX_POST_YIELD_DAMPING).powi(2);
                return Err(ModelError::PostYieldOverdamped {
                    r,
                    zeta,
                    zeta_post,
                    r_min: r_min * (1.0 + 1e-12),
                    what: if zeta_post >= 1.0 {
                        "overdamped"
                    } else {
                        "nearly critically damped"
                    },
                });
            }
        }
        let yield_force_n = strength_ratio * self.mass_kg * G;
        self.hysteresis = Some(Hysteresis {
            strength_ratio,
            post_yield_ratio: r,
            stiffness: self.stiffness,
            yield_force_n,
            yield_displacement_m: yield_force_n / self.stiffness,
        });
        Ok(self)
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
    /// The bilinear restoring force of a yielding structure; `None` when linear.
    pub fn hysteresis(&self) -> Option<&Hysteresis> {
        self.hysteresis.as_ref()
    }
    /// Yield displacement `u_y = F_y/k`, m; `None` when linear.
    pub fn yield_displacement_m(&self) -> Option<f64> {
        self.hysteresis.map(|h| h.yield_displacement_m)
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
    fn refuses_impossible_yielding_naming_it() {
        let s = System::new(&SystemSpec::new(1.0, &[0.5, 0.5], &[0.2, 0.1])).unwrap();
        let msg = |y: Yielding| s.clone().with_yielding(y).unwrap_err().to_string();
        assert!(msg(Yielding::epp(0.0)).contains("C_y"));
        assert!(msg(Yielding::epp(f64::NAN)).contains("C_y"));
        assert!(msg(Yielding::bilinear(0.1, 1.0)).contains("r = 1 is the elastic"));
        assert!(msg(Yielding::bilinear(0.1, -0.1)).contains("post-yield stiffness ratio r"));
        // ζ = 0.05: ζ/√r ≥ 1 below r = 0.0025, ≥ 0.9 below r = 0.003086.
        let over = msg(Yielding::bilinear(0.1, 0.002));
        assert!(
            over.contains("r = 0.002") && over.contains("overdamped"),
            "{over}"
        );
        assert!(over.contains("r >= 0.0031"), "{over}");
        let near = msg(Yielding::bilinear(0.1, 0.003));
        assert!(near.contains("nearly critically damped"), "{near}");
        assert!(
            s.clone()
                .with_yielding(Yielding::bilinear(0.1, 0.0031))
                .is_ok()
        );
        assert!(s.clone().with_yielding(Yielding::epp(0.1)).is_ok());
        // Without damping any r is underdamped.
        let mut spec = SystemSpec::new(1.0, &[], &[]);
        spec.damping_ratio = 0.0;
        let bare = System::new(&spec).unwrap();
        assert!(bare.with_yielding(Yielding::bilinear(0.1, 1e-9)).is_ok());
    }

    #[test]
    fn yield_displacement_and_the_bounding_lines() {
        // T_p = 1 s: k = 4π² m_p; C_y = 0.1: u_y = 0.1·g/(4π²) = 0.0248405 m.
        let s = System::new(&SystemSpec::new(1.0, &[], &[]))
            .unwrap()
            .with_yielding(Yielding::bilinear(0.1, 0.1))
            .unwrap();
        let h = *s.hysteresis().unwrap();
        let uy = 0.1 * G / (4.0 * std::f64::consts::PI.powi(2));
        assert!((h.yield_displacement_m - uy).abs() < 1e-15);
        assert!((s.yield_displacement_m().unwrap() - uy).abs() < 1e-15);
        let y = Yielding::from_yield_displacement(1.0, uy, 0.1);
        assert!((y.strength_ratio - 0.1).abs() < 1e-15);
        // The clamped elastic line: elastic inside ±u_y from the origin, on the bounding lines
        // beyond, and continuous.
        let fy = h.yield_force_n;
        assert!((h.force_n(0.5 * uy, 0.0, 0.0) - 0.5 * fy).abs() < 1e-12);
        assert!((h.force_n(uy, 0.0, 0.0) - fy).abs() < 1e-12);
        let f3 = h.force_n(3.0 * uy, 0.0, 0.0);
        assert!((f3 - (fy + 0.1 * h.stiffness * 2.0 * uy)).abs() < 1e-12);
        assert!((h.force_n(-3.0 * uy, 0.0, 0.0) + f3).abs() < 1e-12);
        assert!((h.recoverable_energy(fy) - 0.5 * fy * uy).abs() < 1e-15);
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
