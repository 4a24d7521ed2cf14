//! The multi-storey model (docs/model.md, "A multi-storey building"): a shear building of `N`
//! storeys, stacks of rigid blocks on its floors, classical modal damping from a named basis,
//! and storeys that may yield.
//!
//! Bodies are numbered floors first (`0..N`, floor 1 is body 0), then every stack's blocks in
//! the order the stacks are given, bottom-up. Interfaces are numbered the same way as the blocks
//! they carry: interface `k` lies under block body `N + k`, so a stack's interface 1 is between
//! its floor and its bottom block. Displacements are relative to the ground.

pub use super::super::model::DampingBasis;
use super::super::model::{G, ModelError, System, SystemSpec, Yielding};
use super::super::rocking::Rocking;
use crate::limits::{
    MAX_ALPHA, MAX_BLOCKS, MAX_MU, MAX_STACKS, MAX_STOREYS, STOREY_RATIO_RANGE,
    STRENGTH_RATIO_RANGE, STRUCTURE_PERIOD_RANGE_S,
};
use nalgebra::{DMatrix, SymmetricEigen};
use thiserror::Error;

/// A storey's height when none is given, m (a common floor-to-floor height of framed
/// buildings; it scales the drift ratios and the overturning moment).
pub const DEFAULT_STOREY_HEIGHT_M: f64 = 3.0;

/// Storey heights a config or case file may give, m: beyond this range a value is a typing
/// error.
pub const STOREY_HEIGHT_RANGE_M: (f64, f64) = (0.5, 100.0);

/// A stack of blocks on one floor, as a user states it.
#[derive(Debug, Clone, PartialEq)]
pub struct StackSpec {
    /// The floor it stands on, `1..=N` (1 the lowest).
    pub floor: usize,
    /// Block masses over the floor's mass, bottom block first.
    pub alpha: Vec<f64>,
    /// Kinetic friction coefficients, interface 1 (floor–block 1) first.
    pub mu: Vec<f64>,
    /// Static friction coefficients; `None` means equal to the kinetic ones.
    pub mu_static: Option<Vec<f64>>,
    /// Width-to-height ratio of each block, bottom first; `None`: rocking not checked
    /// ([`crate::dynamics::rocking`]).
    pub aspect: Option<Vec<f64>>,
}

impl StackSpec {
    /// A stack on `floor` whose static friction equals its kinetic friction.
    pub fn new(floor: usize, alpha: &[f64], mu: &[f64]) -> Self {
        StackSpec {
            floor,
            alpha: alpha.to_vec(),
            mu: mu.to_vec(),
            mu_static: None,
            aspect: None,
        }
    }
}

/// Storeys that yield: bilinear with kinematic hardening per storey.
#[derive(Debug, Clone, PartialEq)]
pub struct StoreyYielding {
    /// `C_y,i` per storey, storey 1 first: `F_y,i = C_y,i·g·Σ_{j≥i} m_j` (bare floor masses).
    pub strength_ratios: Vec<f64>,
    /// Post-yield stiffness ratio `r`, `0 ≤ r < 1`, one value for all storeys.
    pub post_yield_ratio: f64,
}

/// A building as a user states it; [`Building::new`] validates it.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildingSpec {
    /// First-mode period of the bare building, s.
    pub period_s: f64,
    /// Relative floor masses, floor 1 first (taken as kg).
    pub floor_masses: Vec<f64>,
    /// Relative storey stiffnesses, storey 1 first (scaled to give `period_s`).
    pub storey_stiffnesses: Vec<f64>,
    /// Damping ratio `ζ` of every mode of the basis.
    pub damping_ratio: f64,
    pub damping_basis: DampingBasis,
    /// Storey heights, m, storey 1 first: they enter only the overturning moment at the base
    /// (docs/model.md, "Storey shears and the overturning moment"). The callers check them
    /// against the study's limits (`study::building::STOREY_HEIGHT_RANGE_M`).
    pub storey_heights_m: Vec<f64>,
    /// `None`: every storey elastic.
    pub yielding: Option<StoreyYielding>,
    pub stacks: Vec<StackSpec>,
}

impl BuildingSpec {
    /// A uniform bare building: `storeys` equal floor masses and storey stiffnesses, storeys
    /// of [`DEFAULT_STOREY_HEIGHT_M`], `ζ = 0.05` in the rigid basis, elastic.
    pub fn uniform(storeys: usize, period_s: f64) -> Self {
        Self {
            period_s,
            floor_masses: vec![1.0; storeys],
            storey_stiffnesses: vec![1.0; storeys],
            damping_ratio: 0.05,
            damping_basis: DampingBasis::Rigid,
            storey_heights_m: vec![DEFAULT_STOREY_HEIGHT_M; storeys],
            yielding: None,
            stacks: Vec::new(),
        }
    }
}

/// An impossible building, named by the case file's keys (lists 0-based).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum BuildingError {
    #[error("building.storeys must be 1 … {MAX_STOREYS}, got {0}")]
    Storeys(usize),
    #[error(
        "building.period must be within {lo} … {hi} s, got {0:?}",
        lo = STRUCTURE_PERIOD_RANGE_S.0,
        hi = STRUCTURE_PERIOD_RANGE_S.1
    )]
    Period(f64),
    #[error("building.{key} lists {got} values but the building has {expected} storeys")]
    Count {
        key: &'static str,
        got: usize,
        expected: usize,
    },
    #[error(
        "building.{key}[{index}] must be finite and within {lo} … {hi} (a relative value), got {value:?}",
        lo = STOREY_RATIO_RANGE.0,
        hi = STOREY_RATIO_RANGE.1
    )]
    Ratio {
        key: &'static str,
        index: usize,
        value: f64,
    },
    #[error("damping must be finite and in [0, 1), got {0}")]
    Damping(f64),
    #[error("building.storey_heights_m[{index}] must be finite and > 0, got {value:?}")]
    Height { index: usize, value: f64 },
    #[error(
        "building.yield_strength_ratios[{index}] must be within {lo} … {hi}, got {value:?}",
        lo = STRENGTH_RATIO_RANGE.0,
        hi = STRENGTH_RATIO_RANGE.1
    )]
    StrengthRatio { index: usize, value: f64 },
    #[error(
        "building.post_yield_ratio must be finite, >= 0 and < 1 (r = 1 is the elastic storey), got {0:?}"
    )]
    PostYieldRatio(f64),
    #[error(
        "building: an elastic–perfectly plastic storey (post_yield_ratio 0) needs damping > 0 in a \
         building of several storeys: without it the floors above a yielded storey move as a \
         free mass whose modes coincide (use damping > 0, or a small post_yield_ratio)"
    )]
    UndampedPlastic,
    #[error("stacks: at most {MAX_STACKS} stacks, got {0}")]
    Stacks(usize),
    #[error("stacks[{stack}].floor must be 1 … {storeys} (a floor of the building), got {floor}")]
    Floor {
        stack: usize,
        floor: usize,
        storeys: usize,
    },
    #[error("stacks[{stack}].alpha must list 1 … {MAX_BLOCKS} blocks, got {got}")]
    Blocks { stack: usize, got: usize },
    #[error("stacks[{stack}].{key} lists {got} values but the stack has {expected} blocks")]
    StackCount {
        stack: usize,
        key: &'static str,
        got: usize,
        expected: usize,
    },
    #[error(
        "stacks[{stack}].alpha[{index}] (block mass over its floor's) must be finite, > 0 and ≤ {MAX_ALPHA}, got {value:?}"
    )]
    Alpha {
        stack: usize,
        index: usize,
        value: f64,
    },
    #[error(
        "stacks[{stack}].mu[{index}] (kinetic friction) must be finite, >= 0 and <= {MAX_MU}, got {value:?}"
    )]
    MuKinetic {
        stack: usize,
        index: usize,
        value: f64,
    },
    #[error(
        "stacks[{stack}].mu_static[{index}] must be finite, >= mu[{index}] ({kinetic}) and <= {MAX_MU}, got {value:?}"
    )]
    MuStatic {
        stack: usize,
        index: usize,
        value: f64,
        kinetic: f64,
    },
    #[error(
        "floor {floor} carries a load of {ratio:?} times its own mass; at most {MAX_ALPHA} (beyond \
         it round-off spoils the energy balance)"
    )]
    LoadRatio { floor: usize, ratio: f64 },
    #[error(
        "stacks[{stack}].aspect[{index}] (width over height of the block) must be finite and > 0, got {value:?}"
    )]
    Aspect {
        stack: usize,
        index: usize,
        value: f64,
    },
}

/// One storey's bilinear spring (kinematic hardening), in the terms of the SDOF model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StoreySpring {
    /// Elastic and post-yield stiffness, N/m.
    pub k: f64,
    pub k_post: f64,
    /// `F_y`, N, and `u_y = F_y/k`, m (of the drift).
    pub yield_force_n: f64,
    pub yield_drift_m: f64,
    /// `(1 − r)·F_y`, N: the bounding lines' intercept.
    pub intercept_n: f64,
}

/// A stack placed in the building.
#[derive(Debug, Clone, PartialEq)]
pub struct Stack {
    /// Floor index, 0-based (body index of the floor).
    pub floor: usize,
    /// Global index of its bottom block's interface (and `N +` that is its body).
    pub first: usize,
    /// Number of blocks.
    pub blocks: usize,
    /// Its rocking check, when its blocks' ratios are given.
    pub rocking: Option<Rocking>,
}

/// A validated building. Construct with [`Building::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct Building {
    spec: BuildingSpec,
    storeys: usize,
    /// Masses of every body, kg: floors, then blocks.
    masses: Vec<f64>,
    /// Storey stiffness `k_i`, N/m, storey 1 first.
    stiffness: Vec<f64>,
    /// Damping matrix, row-major `N × N`, N·s/m, acting on the floors' relative velocities.
    damping: Vec<f64>,
    /// Periods of the bare building's modes, s, first first.
    periods_s: Vec<f64>,
    stacks: Vec<Stack>,
    /// Per interface: the body below it, the static and kinetic limits, N.
    below: Vec<usize>,
    lim_s: Vec<f64>,
    lim_k: Vec<f64>,
    mu_s: Vec<f64>,
    /// Per storey, when the storeys yield.
    springs: Option<Vec<StoreySpring>>,
    /// The bare floors' total mass, kg.
    bare_mass_kg: f64,
    /// For one storey: the damping ratio of floor 1 alone that gives its damper,
    /// `c/(2·sqrt(k·m_1))`, as the one-storey model states it.
    first_floor_damping_ratio: f64,
}

impl Building {
    pub fn new(spec: &BuildingSpec) -> Result<Self, BuildingError> {
        let n = spec.floor_masses.len();
        if !(1..=MAX_STOREYS).contains(&n) {
            return Err(BuildingError::Storeys(n));
        }
        if !(STRUCTURE_PERIOD_RANGE_S.0..=STRUCTURE_PERIOD_RANGE_S.1).contains(&spec.period_s) {
            return Err(BuildingError::Period(spec.period_s));
        }
        for (key, values) in [
            ("floor_masses", &spec.floor_masses),
            ("storey_stiffnesses", &spec.storey_stiffnesses),
        ] {
            if values.len() != n {
                return Err(BuildingError::Count {
                    key,
                    got: values.len(),
                    expected: n,
                });
            }
            if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| {
                !(v.is_finite() && (STOREY_RATIO_RANGE.0..=STOREY_RATIO_RANGE.1).contains(*v))
            }) {
                return Err(BuildingError::Ratio { key, index, value });
            }
        }
        if spec.storey_heights_m.len() != n {
            return Err(BuildingError::Count {
                key: "storey_heights_m",
                got: spec.storey_heights_m.len(),
                expected: n,
            });
        }
        if let Some((index, &value)) =
            (spec.storey_heights_m.iter().enumerate()).find(|(_, h)| !(h.is_finite() && **h > 0.0))
        {
            return Err(BuildingError::Height { index, value });
        }
        let zeta = spec.damping_ratio;
        if !(zeta.is_finite() && (0.0..1.0).contains(&zeta)) {
            return Err(BuildingError::Damping(zeta));
        }
        if spec.stacks.len() > MAX_STACKS {
            return Err(BuildingError::Stacks(spec.stacks.len()));
        }
        let mut masses = spec.floor_masses.clone();
        let mut stacks = Vec::with_capacity(spec.stacks.len());
        let (mut below, mut lim_s, mut lim_k, mut mu_s) = (vec![], vec![], vec![], vec![]);
        let mut load = vec![0.0; n];
        for (si, s) in spec.stacks.iter().enumerate() {
            check_stack(si, s, n)?;
            let floor = s.floor - 1;
            let m_floor = spec.floor_masses[floor];
            let first = masses.len() - n;
            let block_masses: Vec<f64> = s.alpha.iter().map(|a| a * m_floor).collect();
            load[floor] += s.alpha.iter().sum::<f64>();
            let mu_static = s.mu_static.clone().unwrap_or_else(|| s.mu.clone());
            let mut above: f64 = block_masses.iter().sum();
            for (b, &m) in block_masses.iter().enumerate() {
                below.push(if b == 0 { floor } else { n + first + b - 1 });
                lim_s.push(mu_static[b] * G * above);
                lim_k.push(s.mu[b] * G * above);
                mu_s.push(mu_static[b]);
                above -= m;
            }
            let rocking = (s.aspect.as_deref())
                .map(|a| {
                    Rocking::new(&block_masses, a).map_err(|e| match e {
                        ModelError::Aspect { index, value } => BuildingError::Aspect {
                            stack: si,
                            index: index - 1,
                            value,
                        },
                        _ => BuildingError::StackCount {
                            stack: si,
                            key: "aspect",
                            got: a.len(),
                            expected: block_masses.len(),
                        },
                    })
                })
                .transpose()?;
            masses.extend_from_slice(&block_masses);
            stacks.push(Stack {
                floor,
                first,
                blocks: s.alpha.len(),
                rocking,
            });
        }
        if let Some((f, &ratio)) = load.iter().enumerate().find(|(_, r)| **r > MAX_ALPHA) {
            return Err(BuildingError::LoadRatio {
                floor: f + 1,
                ratio,
            });
        }
        let springs_spec = spec.yielding.as_ref();
        if let Some(y) = springs_spec {
            if y.strength_ratios.len() != n {
                return Err(BuildingError::Count {
                    key: "yield_strength_ratios",
                    got: y.strength_ratios.len(),
                    expected: n,
                });
            }
            if let Some((index, &value)) = y
                .strength_ratios
                .iter()
                .enumerate()
                .find(|(_, c)| !(STRENGTH_RATIO_RANGE.0..=STRENGTH_RATIO_RANGE.1).contains(*c))
            {
                return Err(BuildingError::StrengthRatio { index, value });
            }
            let r = y.post_yield_ratio;
            if !(r.is_finite() && (0.0..1.0).contains(&r)) {
                return Err(BuildingError::PostYieldRatio(r));
            }
            if r == 0.0 && zeta == 0.0 && n > 1 {
                return Err(BuildingError::UndampedPlastic);
            }
        }

        // Stiffness scaled so that the bare building's first mode has `period_s`.
        let floor_m = &spec.floor_masses;
        let rel = modes(floor_m, &spec.storey_stiffnesses);
        let omega1 = std::f64::consts::TAU / spec.period_s;
        let scale = omega1 * omega1 / rel.0[0];
        let stiffness: Vec<f64> = spec.storey_stiffnesses.iter().map(|k| k * scale).collect();
        let periods_s = rel
            .0
            .iter()
            .map(|w2| std::f64::consts::TAU / (w2 * scale).sqrt())
            .collect();
        let basis_masses: Vec<f64> = match spec.damping_basis {
            DampingBasis::Structure => floor_m.clone(),
            DampingBasis::Rigid => floor_m
                .iter()
                .zip(&load)
                .map(|(m, a)| m * (1.0 + a))
                .collect(),
        };
        let damping = modal_damping(&basis_masses, &stiffness, zeta);
        let springs = springs_spec.map(|y| {
            let mut above: f64 = floor_m.iter().sum();
            (0..n)
                .map(|i| {
                    let k = stiffness[i];
                    let fy = y.strength_ratios[i] * G * above;
                    above -= floor_m[i];
                    StoreySpring {
                        k,
                        k_post: y.post_yield_ratio * k,
                        yield_force_n: fy,
                        yield_drift_m: fy / k,
                        intercept_n: (1.0 - y.post_yield_ratio) * fy,
                    }
                })
                .collect()
        });
        let first_floor_damping_ratio = zeta * (basis_masses[0] / floor_m[0]).sqrt();
        Ok(Self {
            spec: spec.clone(),
            bare_mass_kg: floor_m.iter().sum(),
            first_floor_damping_ratio,
            storeys: n,
            masses,
            stiffness,
            damping,
            periods_s,
            stacks,
            below,
            lim_s,
            lim_k,
            mu_s,
            springs,
        })
    }

    pub fn spec(&self) -> &BuildingSpec {
        &self.spec
    }

    /// Storey heights, m, storey 1 first.
    pub fn storey_heights_m(&self) -> &[f64] {
        &self.spec.storey_heights_m
    }
    /// Number of storeys (and floors) `N`.
    pub fn storeys(&self) -> usize {
        self.storeys
    }
    /// Masses of every body, kg: floors first, then the blocks.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }
    /// The bare floors' total mass, kg (energies are per kg of it).
    pub fn bare_mass_kg(&self) -> f64 {
        self.bare_mass_kg
    }
    /// Storey stiffnesses `k_i`, N/m, storey 1 first.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }
    /// The damping matrix, row-major `N × N`, N·s/m.
    pub fn damping(&self) -> &[f64] {
        &self.damping
    }
    /// Periods of the bare building's modes, s, first first.
    pub fn periods_s(&self) -> &[f64] {
        &self.periods_s
    }
    pub fn stacks(&self) -> &[Stack] {
        &self.stacks
    }
    /// Total number of blocks (and interfaces).
    pub fn blocks(&self) -> usize {
        self.masses.len() - self.storeys
    }
    /// The body under interface `k`.
    pub fn below(&self, k: usize) -> usize {
        self.below[k]
    }
    /// Static and kinetic friction limits `μ·N` of interface `k`, N.
    pub fn static_limit(&self, k: usize) -> f64 {
        self.lim_s[k]
    }
    pub fn kinetic_limit(&self, k: usize) -> f64 {
        self.lim_k[k]
    }
    /// Static friction coefficient of interface `k`.
    pub fn mu_static(&self, k: usize) -> f64 {
        self.mu_s[k]
    }
    /// The storeys' springs when they yield; `None` when every storey is elastic.
    pub fn springs(&self) -> Option<&[StoreySpring]> {
        self.springs.as_deref()
    }
    /// The same building as the one-storey model, when it is one: one storey with at most one
    /// stack. Its `System` has the floor's mass, the storey's stiffness (`T_p` = `period_s`),
    /// the bare structure's damping ratio that gives this building's damper, the stack and the
    /// storey's yielding, so the one-storey integrator runs it bit for bit as a `simulate` case
    /// without `building` (docs/model.md, "A multi-storey building").
    pub fn one_storey(&self) -> Option<System> {
        if self.storeys != 1 || self.spec.stacks.len() > 1 {
            return None;
        }
        let m = self.masses[0];
        let (alpha, mu, mu_static, aspect) = match self.spec.stacks.first() {
            Some(s) => (
                s.alpha.clone(),
                s.mu.clone(),
                s.mu_static.clone(),
                s.aspect.clone(),
            ),
            None => (Vec::new(), Vec::new(), None, None),
        };
        let spec = SystemSpec {
            // The attached variant's floor carries its stacks: T·sqrt(M/m) (exactly T otherwise).
            period_s: self.spec.period_s * (m / self.bare_mass_kg).sqrt(),
            damping_ratio: self.first_floor_damping_ratio,
            mass_kg: m,
            alpha,
            mu,
            mu_static,
        };
        let mut sys = System::new(&spec).ok()?;
        if let Some(a) = aspect {
            sys = sys.with_aspect(&a).ok()?;
        }
        match &self.spec.yielding {
            None => Some(sys),
            // The same F_y = C_y·m·g on the system's mass (the loaded floor's, when attached).
            Some(y) => sys
                .with_yielding(Yielding::bilinear(
                    y.strength_ratios[0] * (self.bare_mass_kg / m),
                    y.post_yield_ratio,
                ))
                .ok(),
        }
    }

    /// The same building with every stack rigidly attached to its floor: the stacks' masses
    /// added to their floors', the same stiffnesses `K`, damping matrix `C` and storey springs
    /// (so the same `F_y`), no interfaces. The sliding stacks' reference system, as the rigid
    /// system is on one storey (docs/model.md, "Derived quantities").
    pub fn with_stacks_attached(&self) -> Building {
        self.with_stacks_attached_fraction(1.0)
    }

    /// [`Self::with_stacks_attached`] with only the fraction `lambda` (0 … 1) of every block's
    /// mass attached and the rest absent from the dynamics (the same `K`, `C` and springs): the
    /// building whose seismic weight counts `λ` of the live load (docs/model.md, "The effective
    /// live-load fraction λ"). `lambda = 1` is [`Self::with_stacks_attached`] bit for bit
    /// (`1·m = m`).
    pub fn with_stacks_attached_fraction(&self, lambda: f64) -> Building {
        let n = self.storeys;
        let mut masses = self.masses[..n].to_vec();
        for s in &self.stacks {
            for q in 0..s.blocks {
                masses[s.floor] += lambda * self.masses[n + s.first + q];
            }
        }
        let mut spec = self.spec.clone();
        spec.floor_masses = masses.clone();
        spec.stacks.clear();
        // The same damper on the loaded floor: c = 2ζ·sqrt(k·m) = 2ζ'·sqrt(k·M).
        let first_floor_damping_ratio =
            self.first_floor_damping_ratio * (self.masses[0] / masses[0]).sqrt();
        Building {
            spec,
            bare_mass_kg: self.bare_mass_kg,
            first_floor_damping_ratio,
            storeys: n,
            masses,
            stiffness: self.stiffness.clone(),
            damping: self.damping.clone(),
            periods_s: self.periods_s.clone(),
            stacks: Vec::new(),
            below: Vec::new(),
            lim_s: Vec::new(),
            lim_k: Vec::new(),
            mu_s: Vec::new(),
            springs: self.springs.clone(),
        }
    }

    /// The stack interface `k` belongs to.
    pub fn stack_of(&self, k: usize) -> usize {
        self.stacks
            .iter()
            .rposition(|s| s.first <= k)
            .unwrap_or_default()
    }
}

fn check_stack(si: usize, s: &StackSpec, storeys: usize) -> Result<(), BuildingError> {
    if !(1..=storeys).contains(&s.floor) {
        return Err(BuildingError::Floor {
            stack: si,
            floor: s.floor,
            storeys,
        });
    }
    let nb = s.alpha.len();
    if !(1..=MAX_BLOCKS).contains(&nb) {
        return Err(BuildingError::Blocks { stack: si, got: nb });
    }
    let count = |key, got| {
        (got != nb).then_some(BuildingError::StackCount {
            stack: si,
            key,
            got,
            expected: nb,
        })
    };
    if let Some(e) = count("mu", s.mu.len()) {
        return Err(e);
    }
    if let Some(e) = s
        .mu_static
        .as_ref()
        .and_then(|m| count("mu_static", m.len()))
    {
        return Err(e);
    }
    for (index, &value) in s.alpha.iter().enumerate() {
        if !(value.is_finite() && value > 0.0 && value <= MAX_ALPHA) {
            return Err(BuildingError::Alpha {
                stack: si,
                index,
                value,
            });
        }
    }
    for (index, &value) in s.mu.iter().enumerate() {
        if !(value.is_finite() && (0.0..=MAX_MU).contains(&value)) {
            return Err(BuildingError::MuKinetic {
                stack: si,
                index,
                value,
            });
        }
    }
    if let Some(ms) = &s.mu_static {
        for (index, (&value, &kinetic)) in ms.iter().zip(&s.mu).enumerate() {
            if !(value.is_finite() && value >= kinetic && value <= MAX_MU) {
                return Err(BuildingError::MuStatic {
                    stack: si,
                    index,
                    value,
                    kinetic,
                });
            }
        }
    }
    Ok(())
}

/// The stiffness matrix of a shear building, row-major `N × N`: storey `i` (0-based) joins
/// floor `i − 1` (the ground for `i = 0`) and floor `i`.
pub fn stiffness_matrix(k: &[f64]) -> DMatrix<f64> {
    let n = k.len();
    DMatrix::from_fn(n, n, |r, c| {
        let above = if r + 1 < n { k[r + 1] } else { 0.0 };
        if r == c {
            k[r] + above
        } else if c == r + 1 {
            -k[r + 1]
        } else if r == c + 1 {
            -k[r]
        } else {
            0.0
        }
    })
}

/// `(ω_r², Φ)` of `K·φ = ω²·M·φ` for diagonal `M`, ascending, `Φ` mass-normalised
/// (`Φᵀ·M·Φ = I`; columns are modes), by the symmetric eigenproblem of `M^{-1/2}·K·M^{-1/2}`.
pub fn modes(masses: &[f64], k: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
    let n = masses.len();
    let kk = stiffness_matrix(k);
    let s: Vec<f64> = masses.iter().map(|m| 1.0 / m.sqrt()).collect();
    let sym = DMatrix::from_fn(n, n, |r, c| s[r] * kk[(r, c)] * s[c]);
    let eig = SymmetricEigen::new(sym);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let omega2 = order.iter().map(|&r| eig.eigenvalues[r]).collect();
    let phi = DMatrix::from_fn(n, n, |j, r| s[j] * eig.eigenvectors[(j, order[r])]);
    (omega2, phi)
}

/// `C = M_b·Φ·diag(2ζω_r)·Φᵀ·M_b` from the modes of `(K, M_b)`, row-major.
pub fn modal_damping(basis_masses: &[f64], k: &[f64], zeta: f64) -> Vec<f64> {
    let n = basis_masses.len();
    let (omega2, phi) = modes(basis_masses, k);
    let mut c = vec![0.0; n * n];
    for r in 0..n {
        let w = 2.0 * zeta * omega2[r].max(0.0).sqrt();
        for a in 0..n {
            let pa = basis_masses[a] * phi[(a, r)];
            for b in 0..n {
                c[a * n + b] += w * pa * basis_masses[b] * phi[(b, r)];
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_stacks() -> BuildingSpec {
        let mut s = BuildingSpec::uniform(3, 0.6);
        s.storey_stiffnesses = vec![3.0, 2.0, 1.0];
        s.stacks = vec![
            StackSpec {
                floor: 3,
                alpha: vec![0.5, 0.5],
                mu: vec![0.2, 0.1],
                mu_static: Some(vec![0.25, 0.1]),
                aspect: None,
            },
            StackSpec::new(1, &[1.0], &[0.3]),
        ];
        s
    }

    #[test]
    fn the_first_period_is_the_stated_one_and_the_modes_are_orthonormal() {
        let b = Building::new(&two_stacks()).unwrap();
        assert!((b.periods_s()[0] - 0.6).abs() < 1e-13);
        assert!(b.periods_s().windows(2).all(|w| w[1] < w[0]));
        let (omega2, phi) = modes(&b.masses()[..3], b.stiffness());
        let m = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&b.masses()[..3]));
        let ortho = phi.transpose() * m * &phi;
        assert!((ortho - DMatrix::identity(3, 3)).amax() < 1e-13);
        // K·Φ = M·Φ·Ω², an independent check of the eigenpairs.
        let k = stiffness_matrix(b.stiffness());
        for r in 0..3 {
            for j in 0..3 {
                let lhs: f64 = (0..3).map(|c| k[(j, c)] * phi[(c, r)]).sum();
                let rhs = b.masses()[j] * phi[(j, r)] * omega2[r];
                assert!((lhs - rhs).abs() < 1e-10 * omega2[r], "{lhs} vs {rhs}");
            }
        }
    }

    #[test]
    fn one_storey_damping_is_the_sdof_damper_in_both_bases() {
        // Structure basis: c = 2ζ·sqrt(k·m); rigid: 2ζ·sqrt(k·m(1+α)).
        let mut s = BuildingSpec::uniform(1, 1.0);
        s.stacks = vec![StackSpec::new(1, &[0.5, 0.5], &[0.2, 0.1])];
        let k = (std::f64::consts::TAU).powi(2);
        for (basis, mass) in [(DampingBasis::Structure, 1.0), (DampingBasis::Rigid, 2.0)] {
            s.damping_basis = basis;
            let b = Building::new(&s).unwrap();
            let expect = 2.0 * 0.05 * (k * mass).sqrt();
            assert!((b.damping()[0] - expect).abs() < 1e-14 * expect);
            assert!((b.stiffness()[0] - k).abs() < 1e-12 * k);
        }
    }

    #[test]
    fn the_damping_matrix_gives_zeta_in_every_mode_of_its_basis() {
        let b = Building::new(&two_stacks()).unwrap();
        // Rigid basis: floor masses plus their stacks (floor 1 +1, floor 3 +1).
        let mb = [2.0, 1.0, 2.0];
        let (omega2, phi) = modes(&mb, b.stiffness());
        let c = DMatrix::from_row_slice(3, 3, b.damping());
        let modal = phi.transpose() * c * &phi;
        for r in 0..3 {
            for s in 0..3 {
                let expect = if r == s {
                    2.0 * 0.05 * omega2[r].sqrt()
                } else {
                    0.0
                };
                assert!((modal[(r, s)] - expect).abs() < 1e-12, "{r},{s}");
            }
        }
    }

    /// One storey with its stack attached is the one-storey model's rigid system: period
    /// `T_p·sqrt(1+α)`, the same damper, `C_y/(1+α)` on the loaded mass (docs/model.md,
    /// "Derived quantities" and "Incremental dynamic analysis").
    #[test]
    fn one_storey_attached_is_the_rigid_system() {
        let mut s = BuildingSpec::uniform(1, 1.0);
        s.stacks = vec![StackSpec::new(1, &[0.5, 0.5], &[0.2, 0.1])];
        s.yielding = Some(StoreyYielding {
            strength_ratios: vec![0.3],
            post_yield_ratio: 0.05,
        });
        let b = Building::new(&s).unwrap();
        let loose = b.one_storey().unwrap();
        let rigid = b.with_stacks_attached().one_storey().unwrap();
        assert!((rigid.period_s() - 2f64.sqrt()).abs() < 1e-15);
        assert!((rigid.damping() - loose.damping()).abs() < 1e-15);
        assert!((rigid.stiffness() - loose.stiffness()).abs() < 1e-12);
        let (h, hl) = (rigid.hysteresis().unwrap(), loose.hysteresis().unwrap());
        assert!(
            (h.yield_force_n - hl.yield_force_n).abs() < 1e-12,
            "{h:?} {hl:?}"
        );
        assert!((h.strength_ratio - 0.15).abs() < 1e-15);
        assert_eq!(rigid.blocks(), 0);
    }

    #[test]
    fn interfaces_and_limits() {
        let b = Building::new(&two_stacks()).unwrap();
        assert_eq!(b.blocks(), 3);
        assert_eq!(b.masses(), &[1.0, 1.0, 1.0, 0.5, 0.5, 1.0]);
        assert_eq!((b.below(0), b.below(1), b.below(2)), (2, 3, 0));
        assert!((b.static_limit(0) - 0.25 * G).abs() < 1e-12);
        assert!((b.kinetic_limit(0) - 0.2 * G).abs() < 1e-12);
        assert!((b.static_limit(1) - 0.1 * 0.5 * G).abs() < 1e-12);
        assert!((b.kinetic_limit(2) - 0.3 * G).abs() < 1e-12);
        assert_eq!((b.stack_of(0), b.stack_of(1), b.stack_of(2)), (0, 0, 1));
    }

    #[test]
    fn storey_strength_is_on_the_bare_mass_at_and_above_it() {
        let mut s = two_stacks();
        s.yielding = Some(StoreyYielding {
            strength_ratios: vec![0.3, 0.25, 0.2],
            post_yield_ratio: 0.05,
        });
        let b = Building::new(&s).unwrap();
        let sp = b.springs().unwrap();
        assert!((sp[0].yield_force_n - 0.3 * G * 3.0).abs() < 1e-12);
        assert!((sp[2].yield_force_n - 0.2 * G).abs() < 1e-12);
        assert!((sp[1].yield_drift_m - sp[1].yield_force_n / b.stiffness()[1]).abs() < 1e-15);
    }

    #[test]
    fn refuses_impossible_buildings_naming_the_key() {
        let ok = two_stacks();
        let msg = |f: &dyn Fn(&mut BuildingSpec)| {
            let mut s = ok.clone();
            f(&mut s);
            Building::new(&s).unwrap_err().to_string()
        };
        assert!(msg(&|s| s.stacks[1].floor = 0).contains("stacks[1].floor"));
        assert!(msg(&|s| s.stacks[0].floor = 4).contains("stacks[0].floor must be 1 … 3"));
        assert!(
            msg(&|s| s.storey_stiffnesses = vec![1.0, 1.0])
                .contains("building.storey_stiffnesses lists 2 values but the building has 3")
        );
        assert!(msg(&|s| s.storey_stiffnesses[1] = 0.0).contains("storey_stiffnesses[1]"));
        assert!(msg(&|s| s.floor_masses[2] = -1.0).contains("floor_masses[2]"));
        assert!(msg(&|s| s.period_s = 0.0).contains("building.period"));
        assert!(msg(&|s| s.stacks[0].mu = vec![0.2]).contains("stacks[0].mu lists 1"));
        assert!(msg(&|s| s.stacks[1].alpha = vec![-1.0]).contains("stacks[1].alpha[0]"));
        assert!(msg(&|s| s.stacks[0].mu_static = Some(vec![0.1, 0.1])).contains("mu_static[0]"));
        assert!(msg(&|s| s.floor_masses = vec![]).contains("building.storeys"));
        assert!(
            msg(&|s| {
                s.yielding = Some(StoreyYielding {
                    strength_ratios: vec![0.3, 0.2],
                    post_yield_ratio: 0.0,
                })
            })
            .contains("yield_strength_ratios lists 2")
        );
        assert!(
            msg(&|s| {
                s.damping_ratio = 0.0;
                s.yielding = Some(StoreyYielding {
                    strength_ratios: vec![0.3; 3],
                    post_yield_ratio: 0.0,
                })
            })
            .contains("needs damping > 0")
        );
    }
}
