//! The sweep's numerics: the skip rules, and one work unit (one motion, one
//! structure period, every block and friction combination).
//!
//! Three systems per case ([`super::physics::SystemKind`]): the stack, the single block (the
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
//!   docs/model.md "Stated special cases");
//! * a stack whose coefficients are an earlier simulated case's of the same masses, or higher
//!   only at interfaces that stuck throughout that run, moves as that run did
//!   ([`SkipRule::Held`], the same place).
//!
//! In a building ([`Frame`]) each rule holds as stated, the rigid system's acceleration being
//! that of every floor carrying a stack (docs/model.md, "A study over buildings", gives the
//! reasoning); the structure's peaks are then the roof's. A building's per-floor and per-storey
//! peaks and its base shear, for a stack a rule stands in for, are those of the system it
//! stands in with (the rigid system, or the single block): the rule that makes the stack that
//! system makes every response of it that system's (checked against brute force,
//! tests/sweep.rs).

use super::building::Frame;
use super::physics::{CaseError, Physics, SystemKind, held_at_lower_friction};
use crate::case::Case;
use crate::dynamics::building::BuildingResponse;
use crate::dynamics::{ExactOptions, G, Ground, Rocking};
use crate::grid::Grid;
use std::collections::HashMap;

flag_enum! {
    /// Which rule gave a case's stack result (stored as `skip_rule`).
    pub enum SkipRule;
    /// `(code, word)` of each rule, for the CF `flag_values`/`flag_meanings` attributes.
    pub const SKIP_RULE_FLAGS;
    {
        /// The stack was simulated.
        Simulated = 0 => "simulated",
        /// No interface can slip: the stack is the rigid system.
        NoSlip = 1 => "no_slip",
        /// Coefficients never decrease upward (static = kinetic): the stack is the single block.
        SingleBlock = 2 => "single_block",
        /// The run of an earlier case of the same masses whose coefficients differ only where
        /// this case's are higher, at interfaces that stuck throughout that run.
        Held = 3 => "held_at_lower_friction",
    }
}

/// Meaning of the `skip_rule` codes, for the file attribute.
pub const SKIP_RULE_CODES: &str = "0 simulated; 1 no interface can slip (rigid absolute \
     acceleration never exceeds min μ_s·g): stack = rigid; 2 friction never decreases upward \
     with static = kinetic: stack = single block; 3 only higher friction at interfaces that \
     stuck throughout an earlier case's run of the same masses: stack = that run";

/// What the sweep keeps of one system's run.
#[derive(Debug, Clone, PartialEq)]
struct Peaks {
    /// Peak displacement of the structure (a building's roof) relative to the ground, m.
    u_m: f64,
    /// Peak absolute acceleration of the structure (a building's roof), m/s².
    a_mps2: f64,
    /// The largest peak absolute acceleration of the floors carrying a stack, m/s² (the
    /// structure's on one storey): what the no-slip rules compare with `μ_s·g`.
    a_hold_mps2: f64,
    /// Peak slip per interface of the case's stack, m; with a stack on several floors, the
    /// largest over them.
    slip_m: Vec<f64>,
    /// Energy dissipated by friction, J per kg of the bare structure's mass.
    friction: f64,
    /// Each floor's peak absolute acceleration, g, floor 1 first.
    floor_a_g: Vec<f64>,
    /// Each storey's peak drift ratio `max|δ_i|/h_i`, storey 1 first.
    drift_ratio: Vec<f64>,
    /// Each floor's peak absolute velocity, m/s, floor 1 first.
    floor_v_mps: Vec<f64>,
    /// Each storey's drift at the record's end over its height (signed),
    /// storey 1 first.
    residual_drift_ratio: Vec<f64>,
    /// In a building: peak base shear over the bare building's weight `g·Σm_j` (NaN on one
    /// storey, whose integrator does not give it).
    base_shear: f64,
    /// Each storey's peak shear over the bare building's weight, storey 1 first
    /// (NaN on one storey).
    storey_shear: Vec<f64>,
    /// In a building: the peak overturning moment at the base over the bare building's weight
    /// times its height (NaN on one storey).
    overturning: f64,
    /// In a building: the stacks' stuck mass share (NaN on one storey, and for a system
    /// without stacks).
    stuck_share: f64,
    /// The largest peak absolute velocity of the floors carrying a stack, m/s (the
    /// structure's on one storey): a block that moves with its floor moves at it.
    v_hold_mps: f64,
    /// Peak absolute acceleration of each block, m/s², bottom first; with a stack on several
    /// floors, the largest over them (empty without blocks).
    block_a_mps2: Vec<f64>,
    /// Peak absolute velocity of each block, m/s, idem.
    block_v_mps: Vec<f64>,
    /// Slip of each interface at the record's end, m (signed); with a stack on several
    /// floors, the one of the largest magnitude.
    residual_slip_m: Vec<f64>,
    /// Whether a stack started to rock (its rocking checked; false otherwise).
    rocks: bool,
    /// Whether each interface stuck throughout the run, in every stack (empty without blocks).
    held: Vec<bool>,
}

impl Peaks {
    /// `blocks` blocks per stack, in `frame` (on its floors). On one storey the structure's
    /// own peaks, to the bit (each value is the only one its maximum runs over).
    fn of(r: BuildingResponse, frame: &Frame, floors: &[usize], blocks: usize) -> Self {
        let roof = r.floor_peak_displacement_m.len() - 1;
        let a_hold_mps2 = floors
            .iter()
            .map(|&f| r.floor_peak_abs_accel_mps2[f - 1])
            .fold(0.0, f64::max);
        let v_hold_mps = floors
            .iter()
            .map(|&f| r.floor_peak_abs_velocity_mps[f - 1])
            .fold(0.0, f64::max);
        let largest = |values: &[f64]| -> Vec<f64> {
            (0..blocks)
                .map(|i| of_block(values, blocks, i).fold(0.0, f64::max))
                .collect()
        };
        let slip_m = largest(&r.peak_slip_m);
        let residual_slip_m = (0..blocks)
            .map(|i| {
                of_block(&r.residual_slip_m, blocks, i)
                    .reduce(|a: f64, b: f64| if b.abs() > a.abs() { b } else { a })
                    .unwrap_or(0.0)
            })
            .collect();
        Self {
            u_m: r.floor_peak_displacement_m[roof],
            a_mps2: r.floor_peak_abs_accel_mps2[roof],
            a_hold_mps2,
            slip_m,
            friction: r.energy.friction,
            floor_a_g: r.floor_peak_abs_accel_mps2.iter().map(|a| a / G).collect(),
            drift_ratio: (r.storey_peak_drift_m.iter().zip(&frame.storey_heights_m))
                .map(|(d, h)| d / h)
                .collect(),
            floor_v_mps: r.floor_peak_abs_velocity_mps.clone(),
            residual_drift_ratio: (r.storey_residual_drift_m.iter())
                .zip(&frame.storey_heights_m)
                .map(|(d, h)| d / h)
                .collect(),
            base_shear: frame.base_shear_ratio(r.peak_base_shear_n),
            storey_shear: (r.storey_peak_shear_n.iter())
                .map(|&v| frame.base_shear_ratio(v))
                .collect(),
            overturning: frame.overturning_ratio(r.peak_overturning_n_m),
            stuck_share: r.stuck_mass_share,
            v_hold_mps,
            block_a_mps2: largest(&r.block_peak_abs_accel_mps2),
            block_v_mps: largest(&r.block_peak_abs_velocity_mps),
            residual_slip_m,
            rocks: r.rocking_onset.iter().any(Option::is_some),
            held: (0..blocks)
                .map(|i| {
                    r.held.len() == r.peak_slip_m.len() && of_block(&r.held, blocks, i).all(|h| h)
                })
                .collect(),
        }
    }
}

/// Block (or interface) `i` of every stack of `blocks` blocks, stacks in order.
fn of_block<T: Copy>(values: &[T], blocks: usize, i: usize) -> impl Iterator<Item = T> + '_ {
    values.iter().skip(i).step_by(blocks.max(1)).copied()
}

/// Results of one work unit, one entry per case (order of [`Grid::case`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UnitResult {
    /// Peak structure displacement (a building's roof), m: stack, single block, rigid.
    pub u_stack: Vec<f64>,
    pub u_single: Vec<f64>,
    pub u_rigid: Vec<f64>,
    /// Peak absolute structure (a building's roof) acceleration with the stack, g.
    pub a_stack: Vec<f64>,
    /// Peak slip per interface, m, `[case][interface]` row-major.
    pub slip_peak: Vec<f64>,
    /// Slip per interface at the record's end (signed), m, `[case][interface]`.
    pub slip_residual: Vec<f64>,
    /// The goods' own demands: each block's peak absolute acceleration, g, and velocity, m/s,
    /// `[case][block]` (block `i` rests on interface `i`); with a stack on several floors, the
    /// largest over them.
    pub block_accel_stack: Vec<f64>,
    pub block_velocity_stack: Vec<f64>,
    /// Energy dissipated by friction in the stack, J per kg of structure mass.
    pub friction_energy: Vec<f64>,
    pub skip_rule: Vec<u8>,
    /// 0: single block simulated; 1: it cannot slip, equal to the rigid system.
    pub single_rule: Vec<u8>,
    /// Simulations run for this unit (not stored; for rates).
    pub simulations: usize,
    /// Each floor's peak absolute acceleration, g, `[case][floor]` row-major, the frame's `N`
    /// floors per case, with the stack and with it rigidly attached (and so on below: one
    /// storey's are its structure's, which a one-storey `sweep.h5` does not store).
    pub floor_accel_stack: Vec<f64>,
    pub floor_accel_rigid: Vec<f64>,
    /// Each storey's peak drift ratio, `[case][storey]`, idem.
    pub drift_ratio_stack: Vec<f64>,
    pub drift_ratio_rigid: Vec<f64>,
    /// Each floor's peak absolute velocity, m/s, `[case][floor]`, idem.
    pub floor_velocity_stack: Vec<f64>,
    pub floor_velocity_rigid: Vec<f64>,
    /// Each storey's drift at the record's end over its height (signed),
    /// `[case][storey]`, idem.
    pub residual_drift_ratio_stack: Vec<f64>,
    pub residual_drift_ratio_rigid: Vec<f64>,
    /// In a building: peak base shear over the bare building's weight, per case, idem (NaN in
    /// a building of one storey).
    pub base_shear_stack: Vec<f64>,
    pub base_shear_rigid: Vec<f64>,
    /// Each storey's peak shear over the bare building's weight, `[case][storey]`,
    /// idem (NaN in a building of one storey).
    pub storey_shear_stack: Vec<f64>,
    pub storey_shear_rigid: Vec<f64>,
    /// In a building: the peak overturning moment at the base over the bare building's weight
    /// times its height, per case, idem (NaN in a building of one storey).
    pub overturning_stack: Vec<f64>,
    pub overturning_rigid: Vec<f64>,
    /// In a building: the stack's stuck mass share (the time average of its mass moving with
    /// its floor over its mass), per case: exactly 1 where a skip rule shows it never slides
    /// (NaN in a building of one storey).
    pub stuck_share_stack: Vec<f64>,
    /// With the blocks' ratios given ([`UnitOptions::aspect`]; empty otherwise): 1 where the
    /// stack (any of its stacks, in a building) would start to rock, per case.
    pub rocks_stack: Vec<u8>,
}

impl UnitResult {
    /// Appends the per-floor and per-storey peaks of the stack system `s` and the rigid system
    /// `r`; `held`: a skip rule showed
    /// that the stack never slides (its stuck share is then 1: the rule's state is the one the
    /// integrator keeps).
    fn push_profiles(&mut self, s: &Peaks, r: &Peaks, held: bool) {
        self.floor_accel_stack.extend_from_slice(&s.floor_a_g);
        self.floor_accel_rigid.extend_from_slice(&r.floor_a_g);
        self.drift_ratio_stack.extend_from_slice(&s.drift_ratio);
        self.drift_ratio_rigid.extend_from_slice(&r.drift_ratio);
        self.floor_velocity_stack.extend_from_slice(&s.floor_v_mps);
        self.floor_velocity_rigid.extend_from_slice(&r.floor_v_mps);
        self.residual_drift_ratio_stack
            .extend_from_slice(&s.residual_drift_ratio);
        self.residual_drift_ratio_rigid
            .extend_from_slice(&r.residual_drift_ratio);
        self.storey_shear_stack.extend_from_slice(&s.storey_shear);
        self.storey_shear_rigid.extend_from_slice(&r.storey_shear);
        self.base_shear_stack.push(s.base_shear);
        self.base_shear_rigid.push(r.base_shear);
        self.overturning_stack.push(s.overturning);
        self.overturning_rigid.push(r.overturning);
        // One storey's integrator gives no share (NaN, as its base shear).
        let one_storey = r.base_shear.is_nan();
        self.stuck_share_stack.push(if held && !one_storey {
            1.0
        } else {
            s.stuck_share
        });
    }
}

/// Whether `case`'s stack of blocks of ratios `aspect`, every block moving at one absolute
/// acceleration of peak `peak_mps2`, rocks ([`Rocking::rocks_as_one`]): the criterion the
/// integrators search, here at the stand-in's exact peak (the two can differ only for a peak
/// within round-off of the threshold).
fn stuck_rocks(case: &Case, aspect: &[f64], peak_mps2: f64) -> Result<bool, CaseError> {
    let rocking = Rocking::new(&case.alpha, aspect).map_err(|source| CaseError::Model {
        case: case.clone(),
        kind: SystemKind::Stack,
        source,
    })?;
    Ok(rocking.rocks_as_one(peak_mps2))
}

/// Options for [`run_unit`].
#[derive(Debug, Clone, Copy)]
pub struct UnitOptions<'a> {
    /// Apply the skip rules (off: simulate every system of every case, for checking them).
    pub skip: bool,
    /// The blocks' width-to-height ratios, bottom first: check whether each case's stack
    /// rocks (docs/model.md, "Rocking: when a case leaves the model").
    pub aspect: Option<&'a [f64]>,
}

/// Every case of the grid at structure period `grid.periods_s[period_index]` under `ground`, in
/// `frame` (one storey: [`Frame::one_storey`]).
pub fn run_unit(
    grid: &Grid,
    physics: &Physics,
    frame: &Frame,
    ground: &Ground,
    period_index: usize,
    opts: UnitOptions<'_>,
) -> Result<UnitResult, CaseError> {
    let tp = grid.periods_s[period_index];
    let n = grid.blocks();
    let cases = grid.cases_per_unit();
    let mut out = UnitResult::default();
    // Only friction energy is stored: the input and damping integrals are not needed; of the
    // floors' displacements only the roof's.
    let exact = ExactOptions {
        energy_balance: false,
        floor_displacements: false,
        ..ExactOptions::default()
    };
    let floors = frame.floors();
    let simulate = |kind, case: &Case| {
        let blocks = match kind {
            SystemKind::Stack => n,
            SystemKind::SingleBlock => 1,
            SystemKind::Rigid => 0,
        };
        (physics.simulate_building(kind, case, frame, ground, &exact, opts.aspect))
            .map(|r| Peaks::of(r, frame, &floors, blocks))
    };
    // Keyed by the bits of α (and the index of μ_1): the same floating-point sum, the same system.
    let mut rigid: HashMap<u64, Peaks> = HashMap::new();
    let mut single: HashMap<(u64, u64), Peaks> = HashMap::new();
    // The stacks simulated so far, with their runs.
    let mut stacks: Vec<(Case, Peaks)> = Vec::new();
    for c in 0..cases {
        let (alpha, mu) = grid.stack(c);
        let case = Case {
            period_s: tp,
            alpha,
            mu,
        };
        let mu = &case.mu;
        let mu_s: Vec<f64> = mu.iter().map(|m| m * physics.mu_static_ratio).collect();
        let key = case.alpha_total().to_bits();
        if !rigid.contains_key(&key) || !opts.skip {
            rigid.insert(key, simulate(SystemKind::Rigid, &case)?);
            out.simulations += 1;
        }
        let r = &rigid[&key];
        // Holding needs |a| ≤ μ_s·g at every instant on every floor carrying a stack; the
        // margin keeps clear of the integrator's own switch tolerance.
        let holds = |mu_s: f64| r.a_hold_mps2 < mu_s * G * (1.0 - 1e-9);

        let skey = (key, mu[0].to_bits());
        let single_holds = opts.skip && holds(mu_s[0]);
        if !single_holds && (!single.contains_key(&skey) || !opts.skip) {
            single.insert(skey, simulate(SystemKind::SingleBlock, &case)?);
            out.simulations += 1;
        }
        let u_single = if single_holds {
            r.u_m
        } else {
            single[&skey].u_m
        };

        let min_mu_s = mu_s.iter().copied().fold(f64::INFINITY, f64::min);
        let non_decreasing = physics.mu_static_ratio == 1.0 && mu.windows(2).all(|w| w[1] >= w[0]);
        let repeats = |(ran, run): &(Case, Peaks)| held_at_lower_friction(&case, ran, &run.held);
        let (rule, resp) = if opts.skip && holds(min_mu_s) {
            (SkipRule::NoSlip, None)
        } else if opts.skip && non_decreasing {
            (SkipRule::SingleBlock, None)
        } else if let Some(i) = opts.skip.then(|| stacks.iter().position(repeats)).flatten() {
            (SkipRule::Held, Some(&stacks[i].1))
        } else {
            out.simulations += 1;
            let run = simulate(SystemKind::Stack, &case)?;
            stacks.push((case.clone(), run));
            (SkipRule::Simulated, stacks.last().map(|(_, run)| run))
        };
        out.u_rigid.push(r.u_m);
        out.u_single.push(u_single);
        out.single_rule.push(u8::from(single_holds));
        out.skip_rule.push(rule as u8);
        // The stack's profiles come from the same system as its other peaks.
        let (profile, held) = match (rule, resp) {
            (_, Some(s)) => (s, false),
            (SkipRule::NoSlip, None) => (r, true),
            (_, None) if single_holds => (r, true),
            (_, None) => (&single[&skey], false),
        };
        out.push_profiles(profile, r, held);
        // A rule's stack moves as one body with the system standing in for it: with the floor
        // (`held`: NoSlip, or a single block that holds; the rigid system's peaks on the floors
        // carrying a stack) or with the single block. Its peak absolute acceleration (m/s²)
        // and velocity (m/s).
        let one_body = if held {
            (profile.a_hold_mps2, profile.v_hold_mps)
        } else {
            (profile.block_a_mps2[0], profile.block_v_mps[0])
        };
        if let Some(aspect) = opts.aspect {
            let rocks = match resp {
                Some(s) => s.rocks,
                None => stuck_rocks(&case, aspect, one_body.0)?,
            };
            out.rocks_stack.push(u8::from(rocks));
        }
        match (rule, resp) {
            (_, Some(s)) => {
                out.u_stack.push(s.u_m);
                out.a_stack.push(s.a_mps2 / G);
                out.slip_peak.extend_from_slice(&s.slip_m);
                out.slip_residual.extend_from_slice(&s.residual_slip_m);
                out.friction_energy.push(s.friction);
            }
            (SkipRule::NoSlip, None) => {
                out.u_stack.push(r.u_m);
                out.a_stack.push(r.a_mps2 / G);
                out.slip_peak.extend(std::iter::repeat_n(0.0, n));
                out.slip_residual.extend(std::iter::repeat_n(0.0, n));
                out.friction_energy.push(0.0);
            }
            (_, None) => {
                let s = if single_holds { r } else { &single[&skey] };
                out.u_stack.push(s.u_m);
                out.a_stack.push(s.a_mps2 / G);
                out.slip_peak.push(s.slip_m.first().copied().unwrap_or(0.0));
                out.slip_peak.extend(std::iter::repeat_n(0.0, n - 1));
                out.slip_residual
                    .push(s.residual_slip_m.first().copied().unwrap_or(0.0));
                out.slip_residual.extend(std::iter::repeat_n(0.0, n - 1));
                out.friction_energy
                    .push(if single_holds { 0.0 } else { s.friction });
            }
        }
        // Every block of a stack a rule stands in for moves with the stand-in's one body.
        match resp {
            Some(s) => {
                out.block_accel_stack
                    .extend(s.block_a_mps2.iter().map(|a| a / G));
                out.block_velocity_stack.extend_from_slice(&s.block_v_mps);
            }
            None => {
                out.block_accel_stack
                    .extend(std::iter::repeat_n(one_body.0 / G, n));
                out.block_velocity_stack
                    .extend(std::iter::repeat_n(one_body.1, n));
            }
        }
    }
    Ok(out)
}
