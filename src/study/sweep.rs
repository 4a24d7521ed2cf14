//! The sweep's numerics: the grid of cases, the skip rules, and one work unit (one motion, one
//! structure period, every block and friction combination).
//!
//! Three systems per case (NOTES.md, "Derived quantities"): the stack, the single block (the
//! whole stack as one block on interface 1) and the rigidly attached stack (a linear SDOF of
//! mass `m_p(1+α)`, `T_rigid = T_p·sqrt(1+α)`, same `c`). What a case does not need is skipped,
//! exactly:
//! * the rigid system depends only on `α = Σα_i` (for a given `T_p` and damping): computed once
//!   per `α`;
//! * the single block depends only on `α` and `μ_1`: computed once per pair;
//! * when the rigid system's absolute acceleration never exceeds `min_i μ_s,i·g`, every
//!   interface can hold the stack rigidly, so the stack *is* the rigid system
//!   ([`SkipRule::NoSlip`]); likewise the single block when it stays below `μ_s,1·g`;
//! * when the coefficients never decrease upward and static equals kinetic, no upper interface
//!   can slip before the one below it, so the stack acts as one block ([`SkipRule::SingleBlock`],
//!   NOTES.md "Stated special cases").

use super::config::GridConfig;
use crate::dynamics::{
    ExactOptions, G, Ground, ModelError, Response, SimError, System, SystemSpec, simulate_exact,
};
use std::collections::HashMap;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum SweepError {
    #[error("case T_p = {period_s} s, α = {alpha:?}, μ = {mu:?}: {source}")]
    Model {
        period_s: f64,
        alpha: Vec<f64>,
        mu: Vec<f64>,
        source: ModelError,
    },
    #[error("case T_p = {period_s} s, α = {alpha:?}, μ = {mu:?}: {source}")]
    Simulation {
        period_s: f64,
        alpha: Vec<f64>,
        mu: Vec<f64>,
        source: SimError,
    },
}

/// Which rule gave a case's stack result (stored as `skip_rule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum SkipRule {
    /// The stack was simulated.
    Simulated = 0,
    /// No interface can slip: the stack is the rigid system.
    NoSlip = 1,
    /// Coefficients never decrease upward (static = kinetic): the stack is the single block.
    SingleBlock = 2,
}

/// Meaning of the `skip_rule` codes, for the file attribute.
pub const SKIP_RULE_CODES: &str = "0 simulated; 1 no interface can slip (rigid absolute \
     acceleration never exceeds min μ_s·g): stack = rigid; 2 friction never decreases upward \
     with static = kinetic: stack = single block";

/// The grid with its values expanded.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    pub periods_s: Vec<f64>,
    /// Per block, bottom first.
    pub alpha: Vec<Vec<f64>>,
    /// Kinetic, per interface.
    pub mu: Vec<Vec<f64>>,
    pub mu_static_ratio: f64,
    pub damping: f64,
}

impl Grid {
    pub fn from_config(g: &GridConfig) -> Self {
        Self {
            periods_s: g.period_s.values(),
            alpha: g.alpha.iter().map(|v| v.values()).collect(),
            mu: g.mu.iter().map(|v| v.values()).collect(),
            mu_static_ratio: g.mu_static_ratio,
            damping: g.damping,
        }
    }

    pub fn blocks(&self) -> usize {
        self.alpha.len()
    }

    /// Sizes of the case dimensions `alpha_1 … alpha_n, mu_1 … mu_n`.
    pub fn case_shape(&self) -> Vec<usize> {
        self.alpha.iter().chain(&self.mu).map(|v| v.len()).collect()
    }

    /// Cases in one work unit.
    pub fn cases_per_unit(&self) -> usize {
        self.case_shape().iter().product()
    }

    /// `(T_p, α, μ)` at `index` over `[T_p][case]`, the order of the case variables of
    /// `tnew.h5` (and of `sweep.h5` within one motion).
    pub fn point(&self, index: usize) -> (f64, Vec<f64>, Vec<f64>) {
        let per = self.cases_per_unit();
        let (alpha, mu) = self.case(index % per);
        (self.periods_s[index / per], alpha, mu)
    }

    /// `(α, μ)` of case `index` (row-major over `case_shape`, the last `μ` fastest).
    pub fn case(&self, mut index: usize) -> (Vec<f64>, Vec<f64>) {
        let shape = self.case_shape();
        let mut pick = vec![0; shape.len()];
        for d in (0..shape.len()).rev() {
            pick[d] = index % shape[d];
            index /= shape[d];
        }
        let n = self.blocks();
        let alpha = (0..n).map(|i| self.alpha[i][pick[i]]).collect();
        let mu = (0..n).map(|i| self.mu[i][pick[n + i]]).collect();
        (alpha, mu)
    }
}

/// Results of one work unit, one entry per case (order of [`Grid::case`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UnitResult {
    /// Peak structure displacement, m: stack, single block, rigid.
    pub u_stack: Vec<f64>,
    pub u_single: Vec<f64>,
    pub u_rigid: Vec<f64>,
    /// Peak absolute structure acceleration with the stack, g.
    pub a_stack: Vec<f64>,
    /// Peak slip per interface, m, `[case][interface]` row-major.
    pub slip_peak: Vec<f64>,
    /// Energy dissipated by friction in the stack, J per kg of structure mass.
    pub friction_energy: Vec<f64>,
    pub skip_rule: Vec<u8>,
    /// 0: single block simulated; 1: it cannot slip, equal to the rigid system.
    pub single_rule: Vec<u8>,
    /// Simulations run for this unit (not stored; for rates).
    pub simulations: usize,
}

/// Options for [`run_unit`].
#[derive(Debug, Clone, Copy)]
pub struct UnitOptions {
    /// Apply the skip rules (off: simulate every system of every case, for checking them).
    pub skip: bool,
}

/// The stack rigidly attached: the bare structure's `k` and `c` on the mass `m_p(1+α)`, so
/// `T_rigid = T_p·sqrt(1+α)` and damping `ζ/sqrt(1+α)` (paper Eqs. 10–13).
pub fn rigid_spec(period_s: f64, alpha_total: f64, zeta: f64) -> SystemSpec {
    let root = (1.0 + alpha_total).sqrt();
    SystemSpec {
        period_s: period_s * root,
        damping_ratio: zeta / root,
        mass_kg: 1.0,
        alpha: Vec::new(),
        mu: Vec::new(),
        mu_static: None,
    }
}

fn simulate(
    spec: &SystemSpec,
    ground: &Ground,
    case: (f64, &[f64], &[f64]),
) -> Result<Response, SweepError> {
    let (period_s, alpha, mu) = case;
    let sys = System::new(spec).map_err(|source| SweepError::Model {
        period_s,
        alpha: alpha.to_vec(),
        mu: mu.to_vec(),
        source,
    })?;
    // Only friction energy is stored: the input and damping integrals are not needed.
    let opts = ExactOptions {
        energy_balance: false,
        ..ExactOptions::default()
    };
    simulate_exact(&sys, ground, &opts).map_err(|source| SweepError::Simulation {
        period_s,
        alpha: alpha.to_vec(),
        mu: mu.to_vec(),
        source,
    })
}

/// Every case of the grid at structure period `grid.periods_s[period_index]` under `ground`.
pub fn run_unit(
    grid: &Grid,
    ground: &Ground,
    period_index: usize,
    opts: UnitOptions,
) -> Result<UnitResult, SweepError> {
    let tp = grid.periods_s[period_index];
    let zeta = grid.damping;
    let n = grid.blocks();
    let cases = grid.cases_per_unit();
    let mut out = UnitResult::default();
    // Keyed by the bits of α (and the index of μ_1): the same floating-point sum, the same system.
    let mut rigid: HashMap<u64, Response> = HashMap::new();
    let mut single: HashMap<(u64, u64), Response> = HashMap::new();
    for c in 0..cases {
        let (alpha, mu) = grid.case(c);
        let mu_s: Vec<f64> = mu.iter().map(|m| m * grid.mu_static_ratio).collect();
        let total: f64 = alpha.iter().sum();
        let key = total.to_bits();
        let case = (tp, alpha.as_slice(), mu.as_slice());
        if !rigid.contains_key(&key) || !opts.skip {
            rigid.insert(key, simulate(&rigid_spec(tp, total, zeta), ground, case)?);
            out.simulations += 1;
        }
        let r = &rigid[&key];
        let a_rigid = r.peak_abs_accel_mps2[0];
        // Holding needs |a| ≤ μ_s·g at every instant; the margin keeps clear of the
        // integrator's own switch tolerance.
        let holds = |mu_s: f64| a_rigid < mu_s * G * (1.0 - 1e-9);

        let skey = (key, mu[0].to_bits());
        let single_holds = opts.skip && holds(mu_s[0]);
        if !single_holds && (!single.contains_key(&skey) || !opts.skip) {
            let mut spec = SystemSpec::new(tp, &[total], &mu[..1]);
            spec.damping_ratio = zeta;
            spec.mu_static = Some(vec![mu_s[0]]);
            single.insert(skey, simulate(&spec, ground, case)?);
            out.simulations += 1;
        }
        let u_single = if single_holds {
            r.peak_displacement_m
        } else {
            single[&skey].peak_displacement_m
        };

        let min_mu_s = mu_s.iter().copied().fold(f64::INFINITY, f64::min);
        let non_decreasing = grid.mu_static_ratio == 1.0 && mu.windows(2).all(|w| w[1] >= w[0]);
        let (rule, resp) = if opts.skip && holds(min_mu_s) {
            (SkipRule::NoSlip, None)
        } else if opts.skip && non_decreasing {
            (SkipRule::SingleBlock, None)
        } else {
            let mut spec = SystemSpec::new(tp, &alpha, &mu);
            spec.damping_ratio = zeta;
            spec.mu_static = Some(mu_s.clone());
            out.simulations += 1;
            (SkipRule::Simulated, Some(simulate(&spec, ground, case)?))
        };
        out.u_rigid.push(r.peak_displacement_m);
        out.u_single.push(u_single);
        out.single_rule.push(u8::from(single_holds));
        out.skip_rule.push(rule as u8);
        match (rule, &resp) {
            (_, Some(s)) => {
                out.u_stack.push(s.peak_displacement_m);
                out.a_stack.push(s.peak_abs_accel_mps2[0] / G);
                out.slip_peak.extend_from_slice(&s.peak_slip_m);
                out.friction_energy.push(s.energy.friction);
            }
            (SkipRule::NoSlip, None) => {
                out.u_stack.push(r.peak_displacement_m);
                out.a_stack.push(a_rigid / G);
                out.slip_peak.extend(std::iter::repeat_n(0.0, n));
                out.friction_energy.push(0.0);
            }
            (_, None) => {
                let s = if single_holds { r } else { &single[&skey] };
                out.u_stack.push(s.peak_displacement_m);
                out.a_stack.push(s.peak_abs_accel_mps2[0] / G);
                out.slip_peak
                    .push(s.peak_slip_m.first().copied().unwrap_or(0.0));
                out.slip_peak.extend(std::iter::repeat_n(0.0, n - 1));
                out.friction_energy
                    .push(if single_holds { 0.0 } else { s.energy.friction });
            }
        }
    }
    Ok(out)
}
