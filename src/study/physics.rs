//! The physics of a case (docs/model.md, "Derived quantities"): what the damping ratio refers to
//! ([`DampingBasis`]), the settings every case of a study shares ([`Physics`]), and the three
//! systems a case is run as ([`SystemKind`]): the stack, the whole stack as one block, and the
//! stack rigidly attached. All three share one viscous damper and, on a yielding structure, one
//! yield force. The one place these systems are built, for the sweep, the T_new stage, the
//! report and the IDA stage; in a study over buildings, the same three in a building
//! ([`Physics::building`], [`Physics::simulate_building`]; one storey is the one-storey case).

use super::building::Frame;
use crate::case::Case;
use crate::dynamics::building::{
    Building, BuildingError, BuildingResponse, BuildingSpec, LinearBuildingError, StackSpec,
    StoreyYielding, simulate_building,
};
use crate::dynamics::{
    ExactOptions, Ground, ModelError, Response, SimError, System, SystemSpec, Yielding,
    simulate_exact,
};
use thiserror::Error;

pub use crate::dynamics::DampingBasis;

/// The three systems of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SystemKind {
    /// The structure with its stack of blocks.
    Stack,
    /// The whole stack as one block of mass ratio `α` sliding on interface 1.
    SingleBlock,
    /// The stack rigidly attached: a one-body system of mass `m_p(1+α)` on the structure's
    /// spring and damper (paper Eqs. 10–13), `T_rigid = T_p·sqrt(1+α)`.
    Rigid,
}

impl SystemKind {
    pub const ALL: [SystemKind; 3] = [
        SystemKind::Stack,
        SystemKind::SingleBlock,
        SystemKind::Rigid,
    ];

    /// For people: `stack`, `single block`, `rigidly attached`.
    pub fn name(self) -> &'static str {
        match self {
            SystemKind::Stack => "stack",
            SystemKind::SingleBlock => "single block",
            SystemKind::Rigid => "rigidly attached",
        }
    }

    /// As stored in files: `stack`, `single_block`, `rigid`.
    pub fn key(self) -> &'static str {
        match self {
            SystemKind::Stack => "stack",
            SystemKind::SingleBlock => "single_block",
            SystemKind::Rigid => "rigid",
        }
    }
}

/// A system of a case that cannot be built or run.
#[derive(Debug, Error)]
pub enum CaseError {
    #[error("case {case}, {} system: {source}", kind.name())]
    Model {
        case: Case,
        kind: SystemKind,
        source: ModelError,
    },
    #[error("case {case}, {} system: {source}", kind.name())]
    Simulation {
        case: Case,
        kind: SystemKind,
        source: SimError,
    },
    #[error("case {case}, {} system: {source}", kind.name())]
    BuildingModel {
        case: Case,
        kind: SystemKind,
        source: Box<BuildingError>,
    },
    /// A linear building (a fraction of the stack attached) the linear kernel could not run.
    #[error("case {case}, {} of the stack attached: {source}", fraction)]
    Linear {
        case: Case,
        fraction: f64,
        source: LinearBuildingError,
    },
    /// A system of a case in a building: the building (`3 storeys, stack on the roof`) and the
    /// error.
    #[error("{frame}: {source}")]
    InBuilding {
        frame: String,
        source: Box<CaseError>,
    },
}

impl CaseError {
    /// This error, raised in the building `frame`.
    pub fn in_frame(self, frame: &Frame) -> Self {
        CaseError::InBuilding {
            frame: frame.to_string(),
            source: Box::new(self),
        }
    }
}

/// The settings every case of a study shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Physics {
    /// Viscous damping ratio `ζ`, of the system named by `basis`.
    pub damping: f64,
    pub basis: DampingBasis,
    /// Static friction coefficients are this × the kinetic ones (≥ 1).
    pub mu_static_ratio: f64,
}

impl Physics {
    /// 5 % of the rigidly loaded structure, static friction equal to kinetic (the paper's).
    pub const DEFAULT: Physics = Physics {
        damping: 0.05,
        basis: DampingBasis::Rigid,
        mu_static_ratio: 1.0,
    };

    /// Damping ratio of the bare structure that gives the study's `c` for a stack of total mass
    /// ratio `alpha_total`.
    pub fn structure_damping(&self, alpha_total: f64) -> f64 {
        match self.basis {
            DampingBasis::Structure => self.damping,
            DampingBasis::Rigid => self.damping * (1.0 + alpha_total).sqrt(),
        }
    }

    /// Refuses a damping that would need a bare-structure ratio of 1 or more (critical damping)
    /// for a stack of total mass ratio `alpha_total`.
    pub fn check(&self, alpha_total: f64) -> Result<(), String> {
        let bare = self.structure_damping(alpha_total);
        if bare < 1.0 {
            return Ok(());
        }
        Err(format!(
            "damping {} of the rigidly loaded system needs a bare-structure ratio of {bare:.3} for \
             α = {alpha_total}; it must stay below 1 (use a smaller damping, or the `structure` \
             basis)",
            self.damping
        ))
    }

    /// System `kind` of `case` on the elastic structure.
    pub fn spec(&self, kind: SystemKind, case: &Case) -> SystemSpec {
        let total = case.alpha_total();
        match kind {
            SystemKind::Stack => self.stack(case.period_s, &case.alpha, &case.mu),
            SystemKind::SingleBlock => self.stack(case.period_s, &[total], &case.mu[..1]),
            SystemKind::Rigid => {
                let root = (1.0 + total).sqrt();
                SystemSpec {
                    period_s: case.t_rigid_s(),
                    damping_ratio: self.structure_damping(total) / root,
                    mass_kg: 1.0,
                    alpha: Vec::new(),
                    mu: Vec::new(),
                    mu_static: None,
                }
            }
        }
    }

    fn stack(&self, period_s: f64, alpha: &[f64], mu: &[f64]) -> SystemSpec {
        let mut spec = SystemSpec::new(period_s, alpha, mu);
        spec.damping_ratio = self.structure_damping(alpha.iter().sum());
        spec.mu_static = Some(mu.iter().map(|m| m * self.mu_static_ratio).collect());
        spec
    }

    /// System `kind` of `case`, on a structure that yields as `yielding` says (its strength
    /// ratio on the bare structure's mass `m_p`) or elastic. Every kind has the same yield force
    /// `F_y = C_y·m_p·g`, so the rigid system, one body of mass `m_p(1+α)`, has the strength
    /// ratio `C_y/(1+α)` on its own mass.
    pub fn system(
        &self,
        kind: SystemKind,
        case: &Case,
        yielding: Option<Yielding>,
    ) -> Result<System, ModelError> {
        let system = System::new(&self.spec(kind, case))?;
        match yielding {
            None => Ok(system),
            Some(y) if kind == SystemKind::Rigid => system.with_yielding(Yielding {
                strength_ratio: y.strength_ratio / (1.0 + case.alpha_total()),
                ..y
            }),
            Some(y) => system.with_yielding(y),
        }
    }

    /// System `kind` of `case` on the elastic structure under `ground`, by the exact integrator;
    /// `aspect`: the stack's blocks' width-to-height ratios, for its rocking check (the stack
    /// system only; docs/model.md, "Rocking: when a case leaves the model").
    pub fn simulate(
        &self,
        kind: SystemKind,
        case: &Case,
        ground: &Ground,
        opts: &ExactOptions,
        aspect: Option<&[f64]>,
    ) -> Result<Response, CaseError> {
        let model = |source| CaseError::Model {
            case: case.clone(),
            kind,
            source,
        };
        let mut system = self.system(kind, case, None).map_err(model)?;
        if let (SystemKind::Stack, Some(a)) = (kind, aspect) {
            system = system.with_aspect(a).map_err(model)?;
        }
        simulate_exact(&system, ground, opts).map_err(|source| CaseError::Simulation {
            case: case.clone(),
            kind,
            source,
        })
    }

    /// The bare building of `frame` with first-mode period `period_s`: the study's damping
    /// ratio in every mode of its basis, elastic storeys, no stacks.
    pub fn bare_building(&self, period_s: f64, frame: &Frame) -> BuildingSpec {
        BuildingSpec {
            period_s,
            floor_masses: frame.floor_masses.clone(),
            storey_stiffnesses: frame.storey_stiffnesses.clone(),
            damping_ratio: self.damping,
            damping_basis: self.basis,
            storey_heights_m: frame.storey_heights_m.clone(),
            yielding: None,
            stacks: Vec::new(),
        }
    }

    /// System `kind` of `case` in the building `frame` (docs/model.md, "A study over
    /// buildings"): `T_p` is the bare building's first-mode period, the case's stack stands on
    /// each of the frame's floors (`α_i` over that floor's mass). The single block is each stack
    /// as one block on its interface 1; the rigid system is that single block rigidly attached
    /// to its floor ([`Building::with_stacks_attached`]: the same stiffnesses and damping
    /// matrix), so that it is made of `α` alone, as on one storey. The damping matrix is the
    /// basis's, the same for all three: on a rigid basis every loaded floor carries the same
    /// `α` in all of them.
    pub fn building(
        &self,
        kind: SystemKind,
        case: &Case,
        frame: &Frame,
    ) -> Result<Building, BuildingError> {
        self.yielding_building(kind, case, frame, None)
    }

    /// [`Physics::building`] with storeys that yield as `yielding` says (`None`: elastic). The
    /// rigid system keeps the storeys' springs, so all three share each storey's `F_y,i`
    /// ([`Building::with_stacks_attached`]).
    pub fn yielding_building(
        &self,
        kind: SystemKind,
        case: &Case,
        frame: &Frame,
        yielding: Option<StoreyYielding>,
    ) -> Result<Building, BuildingError> {
        self.building_checked(kind, case, frame, yielding, None)
    }

    /// [`Physics::yielding_building`] whose stacks (of the stack system) carry the rocking
    /// check of blocks of ratios `aspect`.
    fn building_checked(
        &self,
        kind: SystemKind,
        case: &Case,
        frame: &Frame,
        yielding: Option<StoreyYielding>,
        aspect: Option<&[f64]>,
    ) -> Result<Building, BuildingError> {
        let total = [case.alpha_total()];
        let (alpha, mu) = match kind {
            SystemKind::SingleBlock | SystemKind::Rigid => (&total[..], &case.mu[..1]),
            SystemKind::Stack => (&case.alpha[..], &case.mu[..]),
        };
        let mut spec = self.bare_building(case.period_s, frame);
        spec.yielding = yielding;
        spec.stacks = frame
            .floors()
            .into_iter()
            .map(|floor| StackSpec {
                floor,
                alpha: alpha.to_vec(),
                mu: mu.to_vec(),
                mu_static: Some(mu.iter().map(|m| m * self.mu_static_ratio).collect()),
                aspect: aspect
                    .filter(|_| kind == SystemKind::Stack)
                    .map(<[f64]>::to_vec),
            })
            .collect();
        let b = Building::new(&spec)?;
        Ok(match kind {
            SystemKind::Rigid => b.with_stacks_attached(),
            SystemKind::Stack | SystemKind::SingleBlock => b,
        })
    }

    /// System `kind` of `case` in the building `frame` on the elastic storeys under `ground`,
    /// by the exact integrator. A building of one storey (one stack) is the one-storey case:
    /// it runs as [`Physics::simulate`] runs it, bit for bit and as fast (the building's
    /// integrator agrees with it to round-off, `tests/building.rs`). `aspect` as for
    /// [`Physics::simulate`].
    pub fn simulate_building(
        &self,
        kind: SystemKind,
        case: &Case,
        frame: &Frame,
        ground: &Ground,
        opts: &ExactOptions,
        aspect: Option<&[f64]>,
    ) -> Result<BuildingResponse, CaseError> {
        if frame.storeys() == 1 {
            return self
                .simulate(kind, case, ground, opts, aspect)
                .map(BuildingResponse::from_one_storey);
        }
        let b = (self.building_checked(kind, case, frame, None, aspect)).map_err(|source| {
            CaseError::BuildingModel {
                case: case.clone(),
                kind,
                source: Box::new(source),
            }
            .in_frame(frame)
        })?;
        simulate_building(&b, ground, opts).map_err(|source| {
            CaseError::Simulation {
                case: case.clone(),
                kind,
                source,
            }
            .in_frame(frame)
        })
    }
}

/// Whether `case`'s stack moves as the run of `run` did under one motion: the same system (the
/// same period and masses) whose coefficients are the run's, or higher at an interface that
/// stuck throughout the run (`held`). Such an interface never needed more than its run's
/// `μ_s·N`, so a higher limit changes no contact selection: the trajectory, every peak with it,
/// is the run's (docs/model.md, "Stated special cases").
pub fn held_at_lower_friction(case: &Case, run: &Case, held: &[bool]) -> bool {
    case.period_s.to_bits() == run.period_s.to_bits()
        && case.alpha == run.alpha
        && case.mu.len() == held.len()
        && (case.mu.iter().zip(&run.mu).zip(held))
            .all(|((m, r), &h)| m.to_bits() == r.to_bits() || (m > r && h))
}
