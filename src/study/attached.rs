//! Attached fractions (docs/model.md, "The attached fraction"): the fraction `f` of a case's
//! stack which, rigidly attached to its floor with the rest of its mass absent from the
//! dynamics, gives the same mean peak over a zone's motions as the sliding stack, for one peak
//! quantity at a time. Applied to the base shear it is the effective live-load fraction `λ`
//! (the paper's references \[12\] and \[14\]: the portion of the live load a code counts as
//! seismic weight); to each storey's shear and to the overturning moment at the base, the same
//! question for what a code user checks above the base; to the roof displacement, the fraction
//! whose first-mode period is a building's `T_new` ([`super::tnew::zone`]).
//!
//! **The family.** `B(f)` is the building carrying `f` of every stack rigidly attached
//! ([`crate::dynamics::building::Building::with_stacks_attached_fraction`]: the same `K` and the
//! same damping matrix `C` of the study's basis). `B(1)` is the rigid system, bit for bit
//! (`1·m = m`); `B(0)` is the bare building with the loaded `C`, which is exactly what a
//! frictionless stack leaves: so both limits are exact by construction under both damping
//! bases, a stack that never slides giving `f = 1` and a frictionless one `f → 0`. Below 0 the
//! family takes mass off the loaded floors (a stack that lowers a peak below the bare building's
//! does so as much as removing `|f|` of its mass would), down to [`lowest_fraction`]: half the
//! floor's mass kept, at most the whole stack removed.
//!
//! **Which fraction.** A mean peak is not monotone in `f` (attaching mass raises the inertia but
//! lengthens the periods), so several fractions may give it; and where it is stationary in `f`
//! a root can vanish under a change of the target far below what the motions resolve (a nearly
//! frictionless stack lowers a mean peak by 1e-5 of it; at a minimum of the family's no
//! fraction near 0 lowers it that much). So a fraction *matches* when its mean peak lies within
//! [`MATCH_TOL`] of the target, and of the matching fractions the one nearest the case's *stuck
//! mass share* `s̄` is taken (the time average of the stack's mass moving with its floor,
//! [`crate::dynamics::building::BuildingResponse::stuck_mass_share`], averaged over the
//! motions): the fraction of the stack that, in the simulation itself, moved as an attached
//! load. It is exactly 1 for a stack that never slides and near 0 for a frictionless one, so
//! the rule keeps both limits: `s̄` itself when it matches, else the nearest end of a matching
//! stretch (within `tol/|q̄'|` of a root, a few 1e-4 in `f` where `q̄` is not flat). The family is
//! scanned at `f = k/10` ([`SCAN_STEP`]); a stretch's end is a root of `value = target ±
//! tolerance`, on the side the stretch is entered from, found by Brent's method (argmin's
//! `BrentRoot`) to [`FRACTION_TOL`]. With nothing matching on `[lowest, 1]` the scan
//! is extended above 1 up to [`MAX_FRACTION`]; with nothing there either the flag says on which
//! side the target lies and the scan point nearest it is taken.

use super::building::Frame;
use super::physics::{CaseError, Physics, SystemKind, held_at_lower_friction};
use crate::case::Case;
use crate::dynamics::building::{
    Building, BuildingResponse, LinearBuilding, LinearOutput, simulate_building,
};
use crate::dynamics::{ExactOptions, G, Ground};
use crate::spectrum::response::RecordSet;
use crate::spectrum::{SpectrumError, TARGET_DAMPING};
use argmin::core::{CostFunction, Error as ArgminError, Executor, State};
use argmin::solver::brent::BrentRoot;
use std::cell::RefCell;
use std::collections::BTreeMap;

/// A root's tolerance in `f` (absolute): far below any physical meaning, well above the
/// round-off of a mean peak.
pub const FRACTION_TOL: f64 = 1e-9;

/// Steps of the scan per unit of `f`: the scan's fractions are `k/10`.
pub const SCAN_STEPS_PER_UNIT: i64 = 10;

/// Step of the scan that brackets the roots.
pub const SCAN_STEP: f64 = 1.0 / SCAN_STEPS_PER_UNIT as f64;

/// A fraction matches a mean peak when its value lies within this of it (relative): far below
/// what a zone's few motions resolve (their means differ by percents), far above the round-off
/// of a mean peak. Where a mean peak is flat in `f` (a stationary stretch), every fraction of
/// the stretch matches, and the stuck mass share decides among them.
pub const MATCH_TOL: f64 = 1e-4;

/// Largest fraction the scan is extended to when no root lies on `[lowest, 1]`.
pub const MAX_FRACTION: f64 = 2.0;

flag_enum! {
    /// How a fraction was found.
    pub enum FractionFlag;
    /// `(code, word)` of each [`FractionFlag`], for the CF `flag_values`/`flag_meanings`.
    pub const FRACTION_FLAGS;
    {
        /// One crossing on the scan: its root.
        Root = 0 => "root",
        /// The target below every scanned value: the scan point of the smallest.
        Below = 1 => "below_range_clamped",
        /// The target above every scanned value: the scan point of the largest.
        Above = 2 => "above_range_clamped",
        /// Nothing slid under any motion (the value is computed all the same: 1).
        NoSlide = 3 => "no_slide",
        /// Several crossings: the matching fraction nearest the stuck mass share.
        Several = 4 => "several_roots_nearest_stuck_share",
        /// No crossing, but a stretch where the value stays within [`MATCH_TOL`] of the target (a
        /// stationary point): the matching fraction nearest the stuck mass share.
        Near = 5 => "stationary_within_tolerance",
    }
}

/// Mean peaks over a zone's motions (each summed in motion order, then divided), each over the
/// bare building: the roof's displacement (m), every storey's shear over the bare building's
/// weight (storey 1 the base), the overturning moment at the base over that weight times the
/// height.
#[derive(Debug, Clone, PartialEq)]
pub struct Means {
    pub roof_m: f64,
    pub storey_shear: Vec<f64>,
    pub overturning: f64,
}

/// One of the mean peaks of [`Means`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Quantity {
    Roof,
    /// Storey `i`'s shear, 0 the base.
    StoreyShear(usize),
    Overturning,
}

impl Quantity {
    /// The quantities of a building of `storeys`, in [`Means`]' order.
    pub fn all(storeys: usize) -> Vec<Quantity> {
        let shears = (0..storeys).map(Quantity::StoreyShear);
        (std::iter::once(Quantity::Roof).chain(shears))
            .chain([Quantity::Overturning])
            .collect()
    }

    /// The linear kernel's output whose peaks this quantity's mean is over, in a building of
    /// `storeys`.
    fn output(self, storeys: usize) -> LinearOutput {
        match self {
            Quantity::Roof => LinearOutput::FloorDisplacement(storeys - 1),
            Quantity::StoreyShear(i) => LinearOutput::StoreyShear(i),
            Quantity::Overturning => LinearOutput::OverturningMoment,
        }
    }

    /// This quantity's peak in one motion's response.
    fn peak_of(self, r: &BuildingResponse) -> f64 {
        match self {
            Quantity::Roof => r.floor_peak_displacement_m[r.floor_peak_displacement_m.len() - 1],
            Quantity::StoreyShear(i) => r.storey_peak_shear_n[i],
            Quantity::Overturning => r.peak_overturning_n_m,
        }
    }

    /// The mean of `peaks` (one per motion, in order: summed, then divided) of this quantity
    /// in `frame`: the roof's displacement (m) as it is, a storey's shear (N) over the bare
    /// building's weight, the overturning moment (N·m) over that weight times the height.
    fn mean(self, frame: &Frame, peaks: impl ExactSizeIterator<Item = f64>) -> f64 {
        let m = peaks.len() as f64;
        let sum: f64 = match self {
            Quantity::Roof => peaks.sum(),
            Quantity::StoreyShear(_) => peaks.map(|p| frame.base_shear_ratio(p)).sum(),
            Quantity::Overturning => peaks.map(|p| frame.overturning_ratio(p)).sum(),
        };
        sum / m
    }
}

impl Means {
    pub fn get(&self, q: Quantity) -> f64 {
        match q {
            Quantity::Roof => self.roof_m,
            Quantity::StoreyShear(i) => self.storey_shear[i],
            Quantity::Overturning => self.overturning,
        }
    }

    /// The means of `frame`'s quantities, in [`Quantity::all`]'s order.
    fn of_values(frame: &Frame, values: &[f64]) -> Self {
        let n = frame.storeys();
        Self {
            roof_m: values[0],
            storey_shear: values[1..=n].to_vec(),
            overturning: values[n + 1],
        }
    }

    /// The means of the responses (one per motion, in order) of `frame`.
    fn of(responses: &[BuildingResponse], frame: &Frame) -> Self {
        let values: Vec<f64> = (Quantity::all(frame.storeys()).into_iter())
            .map(|q| q.mean(frame, responses.iter().map(|r| q.peak_of(r))))
            .collect();
        Self::of_values(frame, &values)
    }
}

/// The lowest fraction of the family for `case`: every loaded floor keeps at least half its
/// mass, and at most the whole stack is removed.
pub fn lowest_fraction(case: &Case) -> f64 {
    (-0.5 / case.alpha_total()).max(-1.0)
}

/// The scan's fractions for `case`: `k/10` from the first at or above [`lowest_fraction`] to 1.
pub fn scan_fractions(case: &Case) -> Vec<f64> {
    let per = SCAN_STEPS_PER_UNIT;
    let lo = (lowest_fraction(case) * per as f64).ceil() as i64;
    (lo..=per).map(|k| k as f64 / per as f64).collect()
}

/// The scan's next fraction after `f` (one of its fractions).
fn next_fraction(f: f64) -> f64 {
    let per = SCAN_STEPS_PER_UNIT as f64;
    ((f * per).round() + 1.0) / per
}

/// What the means need ([`Quantity`]): the peaks of the roof's displacement, the storeys'
/// shears and the overturning moment.
fn options() -> ExactOptions {
    ExactOptions {
        energy_balance: false,
        abs_velocity: false,
        floor_displacements: false,
        ..ExactOptions::default()
    }
}

/// [`Means`] of `B(fraction)` for `case` in `frame` ([`Physics::building`]'s single block, its
/// stacks then attached by `fraction`), by the linear building's kernel
/// ([`crate::dynamics::building::LinearBuilding`]: the modal basis once, every motion after it;
/// it agrees with the building's integrator to 2e-13, docs/model.md).
pub fn family_means(
    physics: &Physics,
    case: &Case,
    frame: &Frame,
    fraction: f64,
    grounds: &[Ground],
) -> Result<Means, CaseError> {
    let all = Quantity::all(frame.storeys());
    let values = family_values(physics, case, frame, fraction, grounds, &all)?;
    Ok(Means::of_values(frame, &values))
}

/// The mean of one quantity of `B(fraction)`: [`family_means`]' value of `q`, to the bit (each
/// of the kernel's outputs is computed on its own), at the cost of one output.
pub fn family_mean(
    physics: &Physics,
    case: &Case,
    frame: &Frame,
    fraction: f64,
    grounds: &[Ground],
    q: Quantity,
) -> Result<f64, CaseError> {
    Ok(family_values(physics, case, frame, fraction, grounds, &[q])?[0])
}

/// The means of `quantities` of `B(fraction)`, in their order.
fn family_values(
    physics: &Physics,
    case: &Case,
    frame: &Frame,
    fraction: f64,
    grounds: &[Ground],
    quantities: &[Quantity],
) -> Result<Vec<f64>, CaseError> {
    let b = physics
        .building(SystemKind::SingleBlock, case, frame)
        .map(|b| b.with_stacks_attached_fraction(fraction))
        .map_err(|source| {
            CaseError::BuildingModel {
                case: case.clone(),
                kind: SystemKind::Rigid,
                source: Box::new(source),
            }
            .in_frame(frame)
        })?;
    let linear = |source| {
        CaseError::Linear {
            case: case.clone(),
            fraction,
            source,
        }
        .in_frame(frame)
    };
    let kernel = LinearBuilding::new(&b).map_err(linear)?;
    let n = frame.storeys();
    let outputs: Vec<LinearOutput> = quantities.iter().map(|q| q.output(n)).collect();
    let selection = kernel.select(&outputs);
    let peaks = (kernel.peaks_of_records(&selection, grounds)).map_err(linear)?;
    Ok((quantities.iter().enumerate())
        .map(|(k, q)| q.mean(frame, peaks.iter().map(|p| p[k])))
        .collect())
}

/// The building of system `kind` of `case` in `frame` ([`Physics::building`]), its error
/// named with the frame.
fn building_of(
    physics: &Physics,
    kind: SystemKind,
    case: &Case,
    frame: &Frame,
) -> Result<Building, CaseError> {
    physics.building(kind, case, frame).map_err(|source| {
        CaseError::BuildingModel {
            case: case.clone(),
            kind,
            source: Box::new(source),
        }
        .in_frame(frame)
    })
}

/// `case`'s system `kind` in `frame` under one motion, by the building's integrator even on one
/// storey (whose sweep runs the one-storey integrator, which gives neither the shears nor the
/// stuck mass share).
fn run_one(
    b: &Building,
    kind: SystemKind,
    case: &Case,
    frame: &Frame,
    ground: &Ground,
) -> Result<BuildingResponse, CaseError> {
    simulate_building(b, ground, &options()).map_err(|source| {
        CaseError::Simulation {
            case: case.clone(),
            kind,
            source,
        }
        .in_frame(frame)
    })
}

/// The stuck mass share's mean over the motions' responses.
fn mean_share(responses: &[BuildingResponse]) -> f64 {
    responses.iter().map(|r| r.stuck_mass_share).sum::<f64>() / responses.len() as f64
}

/// Whether `case`'s stack holds under every motion of the rigid system's `rigid` responses in
/// `frame`: the peak absolute acceleration of every floor carrying it stays below the least
/// `μ_s·g`, with the sweep's margin (its no-slip rule, whose argument holds whatever the
/// integrator).
fn holds_everywhere(
    physics: &Physics,
    case: &Case,
    frame: &Frame,
    rigid: &[BuildingResponse],
) -> bool {
    let min_mu_s = (case.mu.iter())
        .map(|m| m * physics.mu_static_ratio)
        .fold(f64::INFINITY, f64::min);
    rigid.iter().all(|r| {
        let a = (frame.floors().iter())
            .map(|&f| r.floor_peak_abs_accel_mps2[f - 1])
            .fold(0.0, f64::max);
        a < min_mu_s * G * (1.0 - 1e-9)
    })
}

/// The fraction whose value matches `target` (module doc): `scan` holds `(f, value)` at the
/// scan's fractions (ascending), `prior` is the stuck mass share, `values` gives the value at any
/// other fraction (errors returned as they are). Of the fractions whose value lies within
/// [`MATCH_TOL`] of the target, the one nearest the prior: the prior itself when it matches,
/// else the nearest end of a matching stretch, a root of `value = target ± tolerance` on the
/// side the stretch is entered from ([`Values::root`]).
pub fn solve<E>(
    target: f64,
    prior: f64,
    scan: &[(f64, f64)],
    values: &mut Values<'_, E>,
) -> Result<(f64, FractionFlag), E> {
    let tol = MATCH_TOL * target.abs();
    let prior = prior_fraction(prior, scan);
    let mut points = scan.to_vec();
    if !points.iter().any(|p| p.0 == prior) {
        let at = points.partition_point(|p| p.0 < prior);
        points.insert(at, (prior, values.get(prior)?));
    }
    let at_prior = points.iter().find(|p| p.0 == prior).expect("inserted").1;
    let matches = |v: f64| (v - target).abs() <= tol;
    // An interval enters the band from its end nearest the prior: (the level crossed, the
    // interval) where it does.
    let entered = |points: &[(f64, f64)], from: usize| -> Vec<(f64, usize)> {
        (from..points.len().saturating_sub(1))
            .filter_map(|k| {
                let (a, b) = (points[k], points[k + 1]);
                let (near, far) = if a.0 >= prior { (a, b) } else { (b, a) };
                if matches(near.1) {
                    return None;
                }
                let level = if near.1 > target {
                    target + tol
                } else {
                    target - tol
                };
                let crosses = matches(far.1) || (near.1 - level) * (far.1 - level) < 0.0;
                crosses.then_some((level, k))
            })
            .collect()
    };
    let mut found = entered(&points, 0);
    // Above 1 only when nothing matches below: the scan grows a step at a time.
    while found.is_empty() && !points.iter().any(|p| matches(p.1)) {
        let next = next_fraction(points[points.len() - 1].0);
        if next > MAX_FRACTION + 1e-12 {
            break;
        }
        points.push((next, values.get(next)?));
        found = entered(&points, points.len() - 2);
    }
    let flag = match crossings(target, &points).len() {
        0 => FractionFlag::Near,
        1 => FractionFlag::Root,
        _ => FractionFlag::Several,
    };
    if matches(at_prior) {
        return Ok((prior, flag));
    }
    if found.is_empty() {
        let pick = |better: fn(f64, f64) -> bool| {
            (scan.iter().copied())
                .reduce(|a, b| if better(b.1, a.1) { b } else { a })
                .expect("the scan has points")
        };
        // No interval meets the band: every value lies on one side of it.
        return Ok(if target < points[0].1 {
            (pick(|b, a| b < a).0, FractionFlag::Below)
        } else {
            (pick(|b, a| b > a).0, FractionFlag::Above)
        });
    }
    // The intervals that may hold the matching fraction nearest the prior: within a scan step
    // of the nearest one (a band's end lies anywhere in its interval).
    let distance = |k: usize| {
        let (a, b) = (points[k].0, points[k + 1].0);
        if prior < a {
            a - prior
        } else if prior > b {
            prior - b
        } else {
            0.0
        }
    };
    let nearest = found
        .iter()
        .map(|&(_, k)| distance(k))
        .fold(f64::INFINITY, f64::min);
    let mut best: Option<f64> = None;
    for &(level, k) in found
        .iter()
        .filter(|(_, k)| distance(*k) <= nearest + SCAN_STEP)
    {
        let (a, b) = (points[k], points[k + 1]);
        let (near, far) = if a.0 >= prior { (a, b) } else { (b, a) };
        // A far end inside the band with no crossing of the level: the band's end is where the
        // level is met, or the far end itself when the band is entered there exactly.
        let end = if (near.1 - level) * (far.1 - level) < 0.0 || far.1 == level {
            values.root(level, a, b)?
        } else {
            far.0
        };
        let closer = best.is_none_or(|b| {
            let (d, db) = ((end - prior).abs(), (b - prior).abs());
            d < db || (d == db && end > b)
        });
        if closer {
            best = Some(end);
        }
    }
    Ok((best.expect("a band was entered"), flag))
}

/// The fraction [`solve`] evaluates for the prior `share` over `scan` (ascending `(f, value)`):
/// the share clamped to the scan's range, its top (1) when the share is not finite.
pub fn prior_fraction<T>(share: f64, scan: &[(f64, T)]) -> f64 {
    let (lo, hi) = (scan[0].0, scan[scan.len() - 1].0);
    if share.is_finite() {
        share.clamp(lo, hi)
    } else {
        hi
    }
}

/// The scan intervals whose ends straddle `target` (a point on it counts once, in the interval
/// it ends, or the first interval it starts).
fn crossings(target: f64, points: &[(f64, f64)]) -> Vec<usize> {
    crossings_from(target, points, 0)
}

fn crossings_from(target: f64, points: &[(f64, f64)], from: usize) -> Vec<usize> {
    (from..points.len().saturating_sub(1))
        .filter(|&k| {
            let (a, b) = (points[k].1 - target, points[k + 1].1 - target);
            a * b < 0.0 || b == 0.0 || (k == 0 && a == 0.0)
        })
        .collect()
}

/// One function of the family over the cases of a unit (a quantity's mean peak, or the
/// code-format ratio): every value known so far, by fraction, and how to compute another. The
/// unit's cases search the same function (it depends on the unit's key alone), so they share it:
/// a case whose search repeats an earlier one's (the same target and prior, as cases whose stacks
/// move alike have) computes nothing, and every search takes the steps it would take alone.
pub struct Values<'a, E> {
    /// By the fraction's bits.
    known: BTreeMap<u64, f64>,
    compute: Box<dyn FnMut(f64) -> Result<f64, E> + 'a>,
}

impl<'a, E> Values<'a, E> {
    /// `known` values `(f, value)` (the scan's, the priors'), then `compute` for any other `f`.
    pub fn new(
        known: impl IntoIterator<Item = (f64, f64)>,
        compute: impl FnMut(f64) -> Result<f64, E> + 'a,
    ) -> Self {
        Self {
            known: (known.into_iter()).map(|(f, x)| (f.to_bits(), x)).collect(),
            compute: Box::new(compute),
        }
    }

    /// The value at `f`: known, else computed and kept.
    pub fn get(&mut self, f: f64) -> Result<f64, E> {
        if let Some(&x) = self.known.get(&f.to_bits()) {
            return Ok(x);
        }
        let x = (self.compute)(f)?;
        self.known.insert(f.to_bits(), x);
        Ok(x)
    }

    /// The root of `value(f) = level` between the ends `a` and `b` (`(f, value)`, ascending,
    /// their values across the level) by Brent's method (argmin's `BrentRoot`) to
    /// [`FRACTION_TOL`]; an end on the level is the root.
    pub fn root(&mut self, level: f64, a: (f64, f64), b: (f64, f64)) -> Result<f64, E> {
        if b.1 == level {
            return Ok(b.0);
        }
        if a.1 == level {
            return Ok(a.0);
        }
        for (f, x) in [a, b] {
            self.known.entry(f.to_bits()).or_insert(x);
        }
        let problem = Crossing {
            level,
            values: RefCell::new(self),
            error: RefCell::new(None),
        };
        let best = Executor::new(&problem, BrentRoot::new(a.0, b.0, FRACTION_TOL))
            .configure(|s| s.max_iters(200))
            .run()
            .map(|r| r.state().get_best_param().copied());
        if let Some(e) = problem.error.into_inner() {
            return Err(e);
        }
        Ok(best
            .expect("the ends bracket the root and every value is finite")
            .expect("Brent keeps its best"))
    }
}

/// `value(f) − level`, remembering the first error of the values.
struct Crossing<'v, 'a, E> {
    level: f64,
    values: RefCell<&'v mut Values<'a, E>>,
    error: RefCell<Option<E>>,
}

impl<E> CostFunction for &Crossing<'_, '_, E> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, f: &f64) -> Result<f64, ArgminError> {
        match self.values.borrow_mut().get(*f) {
            Ok(v) => Ok(v - self.level),
            Err(e) => {
                self.error.borrow_mut().get_or_insert(e);
                Err(ArgminError::msg("the mean peak could not be computed"))
            }
        }
    }
}

/// The code-format fraction's ingredients for `case` in `frame` (docs/model.md, "The
/// code-format fraction"): the stack's weight over the bare building's, `W_L/W`, and the first
/// mode's period of `B(f)`.
pub fn load_ratio(case: &Case, frame: &Frame) -> f64 {
    let loaded: f64 = frame
        .floors()
        .iter()
        .map(|&f| frame.floor_masses[f - 1])
        .sum();
    case.alpha_total() * loaded / frame.floor_masses.iter().sum::<f64>()
}

/// The mean over the motions `records` of their 5 %-damped pseudo-spectral acceleration at
/// `period_s` exactly (each summed in motion order, then divided), g; the motions in the
/// spectrum's lanes ([`RecordSet::peaks`]).
pub fn mean_psa_g(records: &RecordSet, period_s: f64) -> Result<f64, SpectrumError> {
    let peaks = records.peaks(period_s, TARGET_DAMPING)?;
    let sum = (peaks.iter()).fold(0.0, |sum, p| sum + p.psa_g(period_s));
    Ok(sum / peaks.len() as f64)
}

/// The code-format base shear of `B(f)` over the rigid system's, as a design code would estimate
/// it from the mean spectrum of the zone's motions `records`:
/// `(W + f·W_L)·S̄a(T_1(f)) / ((W + W_L)·S̄a(T_1,rigid))`; exactly 1 at `f = 1`.
pub fn code_shear_ratio(
    case: &Case,
    frame: &Frame,
    records: &RecordSet,
    fraction: f64,
    psa_rigid_g: f64,
) -> Result<f64, SpectrumError> {
    let r = load_ratio(case, frame);
    let psa = mean_psa_g(records, frame.t1_attached_s(case, fraction))?;
    Ok((1.0 + fraction * r) * psa / ((1.0 + r) * psa_rigid_g))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_matching_fraction_nearest_the_prior_clamps_and_ends() {
        let scan = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
            (0..=10)
                .map(|k| (k as f64 / 10.0, f(k as f64 / 10.0)))
                .collect()
        };
        let fresh = |f: fn(f64) -> f64| Values::new([], move |l| Ok::<_, ()>(f(l)));
        let near = |l: f64, want: f64| (l - want).abs() < FRACTION_TOL;
        let (lo, hi) = (1.0 - MATCH_TOL, 1.0 + MATCH_TOL);
        // V = 1 + f²: 1.49 is met at 0.7; from a prior below, the matching stretch is entered at
        // its lower end, where 1 + f² = 1.49·(1 − tol).
        let sq = |l: f64| 1.0 + l * l;
        let (l, flag) = solve(1.49, 0.5, &scan(&sq), &mut fresh(sq)).unwrap();
        assert_eq!(flag, FractionFlag::Root);
        assert!(near(l, (1.49 * lo - 1.0f64).sqrt()), "{l}");
        // From a prior above, at its upper end.
        let (l, _) = solve(1.49, 0.95, &scan(&sq), &mut fresh(sq)).unwrap();
        assert!(near(l, (1.49 * hi - 1.0f64).sqrt()), "{l}");
        // A prior whose value matches is taken itself (f² = 0.49 ± 1.5e-4: 0.7 ± 1.1e-4).
        let (l, _) = solve(1.49, 0.70001, &scan(&sq), &mut fresh(sq)).unwrap();
        assert_eq!(l, 0.70001);
        // Below and above the range: the scan point of the smallest (largest) value.
        assert_eq!(
            solve(0.5, 0.5, &scan(&sq), &mut fresh(sq)).unwrap(),
            (0.0, FractionFlag::Below)
        );
        // Above 1 the scan grows: 1 + f² = 3.25 near 1.5.
        let (l, flag) = solve(3.25, 0.5, &scan(&sq), &mut fresh(sq)).unwrap();
        assert_eq!(flag, FractionFlag::Root);
        assert!(near(l, (3.25 * lo - 1.0f64).sqrt()), "{l}");
        assert_eq!(
            solve(9.0, 0.5, &scan(&sq), &mut fresh(sq)).unwrap(),
            (1.0, FractionFlag::Above)
        );
        // The end itself with a prior of 1 (a stack that never slid): exactly 1.
        assert_eq!(
            solve(
                2.0,
                1.0,
                &scan(&sq),
                &mut Values::new([], |_| Ok::<_, ()>(f64::NAN))
            )
            .unwrap(),
            (1.0, FractionFlag::Root)
        );
        // A stationary point: V = 1 + f² has its minimum 1 at 0; a target 1e-5 below it has no
        // root, but f = 0 matches within the tolerance: the prior 0.001 is taken, and from a
        // prior of 0.5 the stretch's end, where 1 + f² = target·(1 + tol).
        let t = 1.0 - 1e-5;
        let (l, flag) = solve(t, 0.001, &scan(&sq), &mut fresh(sq)).unwrap();
        assert_eq!((l, flag), (0.001, FractionFlag::Near));
        let (l, flag) = solve(t, 0.5, &scan(&sq), &mut fresh(sq)).unwrap();
        assert_eq!(flag, FractionFlag::Near);
        assert!(near(l, (t * hi - 1.0f64).sqrt()), "{l}");
        // A hump: 1 + sin(πf) meets 1.5 at 1/6 and 5/6; the stretch nearest the prior is taken,
        // entered from the prior's side (below the band outside the hump, above inside it).
        let hump = |l: f64| 1.0 + (std::f64::consts::PI * l).sin();
        let edge = |s: f64| (s).asin() / std::f64::consts::PI;
        let (below, above) = (edge(1.5 * lo - 1.0), edge(1.5 * hi - 1.0));
        for (prior, want) in [
            (0.0, below),
            (0.3, above),
            (0.6, 1.0 - above),
            (1.0, 1.0 - below),
        ] {
            let (l, flag) = solve(1.5, prior, &scan(&hump), &mut fresh(hump)).unwrap();
            assert_eq!(flag, FractionFlag::Several);
            assert!(near(l, want), "prior {prior}: {l} vs {want}");
        }
        // An error of the value comes back as it is.
        assert_eq!(
            solve(
                1.49,
                0.55,
                &scan(&sq)[..5],
                &mut Values::new([], |_| Err::<f64, _>(7))
            ),
            Err(7)
        );
    }

    #[test]
    fn one_storey_stacks_take_earlier_runs_only_where_they_repeat_them() {
        // Oracle: brute force, every case's stack simulated under every motion. A stack that
        // takes an earlier case's run (the held rule) must give the same means and share to the
        // bit, a holding one the rigid system's means; and some case must take a run whose
        // friction was lower at an interface that held, or the rule went untested.
        use crate::study::config::{GridConfig, Values as Axis};
        let config = GridConfig {
            period_s: Axis::List(vec![0.3, 1.0]),
            alpha: vec![Axis::List(vec![0.5, 1.0]), Axis::List(vec![0.5, 1.0])],
            mu: vec![
                Axis::List(vec![0.05, 0.2, 0.9]),
                Axis::List(vec![0.05, 0.1, 0.3, 0.9]),
            ],
            mu_static_ratio: 1.0,
            damping: 0.05,
            damping_basis: Default::default(),
            stack_floor: None,
            aspect: None,
        };
        let (grid, physics) = (config.axes(), config.physics());
        let frames = [Frame::one_storey()];
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/records/");
        let records: Vec<_> = ["RSN960_NORTHR_LOS270.AT2", "RSN829_CAPEMEND_RIO360.AT2"]
            .iter()
            .map(|n| crate::ground_motion::read_record(format!("{dir}{n}").as_ref()).unwrap())
            .collect();
        let accels: Vec<Vec<f64>> = records.iter().map(|r| r.accel_mps2(1.0)).collect();
        let grounds: Vec<Ground> = (records.iter().zip(&accels))
            .map(|(r, a)| Ground::new(r.dt_s, a))
            .collect();
        let cases = grid.cases();
        let (swept, slides) = (vec![None; cases], vec![true; cases]);
        let family = ZoneFamily {
            physics: &physics,
            grid: &grid,
            frames: &frames,
            grounds: &grounds,
            swept: &swept,
            slides: &slides,
            keep_going: &|| true,
        };
        let frame = &frames[0];
        let mut repeated = 0;
        for unit in fraction_units(&grid, &frames) {
            let first = family.case(unit.cases[0]);
            let b = building_of(&physics, SystemKind::Rigid, &first, frame).unwrap();
            let rigid = family
                .under_every_motion(|g| run_one(&b, SystemKind::Rigid, &first, frame, &grounds[g]))
                .unwrap();
            let scan = [(1.0, Means::of(&rigid, frame))];
            let setups = family.one_storey_setups(&unit, &rigid, &scan).unwrap();
            let mut brute: Vec<(Case, Vec<BuildingResponse>)> = Vec::new();
            for (&c, setup) in unit.cases.iter().zip(&setups) {
                let case = family.case(c);
                let b = building_of(&physics, SystemKind::Stack, &case, frame).unwrap();
                let runs: Vec<BuildingResponse> = (grounds.iter())
                    .map(|g| run_one(&b, SystemKind::Stack, &case, frame, g).unwrap())
                    .collect();
                let want = match holds_everywhere(&physics, &case, frame, &rigid) {
                    true => (scan[0].1.clone(), 1.0),
                    false => (Means::of(&runs, frame), mean_share(&runs)),
                };
                assert_eq!((&setup.stack, setup.share), (&want.0, want.1), "{case:?}");
                for (earlier, earlier_runs) in &brute {
                    repeated += (0..grounds.len())
                        .filter(|&g| {
                            earlier.mu != case.mu
                                && held_at_lower_friction(&case, earlier, &earlier_runs[g].held)
                        })
                        .count();
                }
                brute.push((case, runs));
            }
        }
        assert!(repeated > 0, "no stack repeated an earlier run");
    }

    #[test]
    fn a_units_searches_share_values_and_take_their_own_steps() {
        // One function searched for several targets and priors, as a unit's cases search it:
        // with the values shared, each fraction is the one a search alone finds, to the bit,
        // and a search that repeats an earlier one computes nothing.
        let hump = |l: f64| 1.0 + (std::f64::consts::PI * l).sin();
        let fresh = |f: fn(f64) -> f64| Values::new([], move |l| Ok::<_, ()>(f(l)));
        let scan: Vec<(f64, f64)> = (0..=10)
            .map(|k| k as f64 / 10.0)
            .map(|l| (l, hump(l)))
            .collect();
        let calls = std::cell::Cell::new(0);
        let mut shared = Values::new(scan.iter().copied(), |l| {
            calls.set(calls.get() + 1);
            Ok::<_, ()>(hump(l))
        });
        let searches = [(1.5, 0.0, true), (1.5, 0.3, true), (1.7, 0.05, true)];
        let repeats = [(1.5, 0.3, false), (1.5, 0.0, false)];
        for (target, prior, new) in searches.into_iter().chain(repeats) {
            let alone = solve(target, prior, &scan, &mut fresh(hump));
            let before = calls.get();
            let (f, flag) = solve(target, prior, &scan, &mut shared).unwrap();
            let (want, want_flag) = alone.unwrap();
            assert_eq!(
                (f.to_bits(), flag),
                (want.to_bits(), want_flag),
                "{target} from {prior}"
            );
            assert_eq!(
                calls.get() > before,
                new,
                "{target} from {prior}: {}",
                calls.get()
            );
        }
    }

    #[test]
    fn the_scan_reaches_below_zero_keeping_half_the_floor() {
        let case = |a: f64| Case {
            period_s: 1.0,
            alpha: vec![a],
            mu: vec![0.2],
        };
        let s = scan_fractions(&case(0.25));
        assert_eq!((s[0], s.len()), (-1.0, 21));
        let s = scan_fractions(&case(2.0));
        assert!((s[0] + 0.2).abs() < 1e-12 && s.len() == 13, "{s:?}");
        assert!(s.contains(&0.0) && s[s.len() - 1] == 1.0);
    }
}

/// What a case's attached fractions come from and what they are (docs/model.md, "The attached
/// fraction").
#[derive(Debug, Clone, PartialEq)]
pub struct CaseFractions {
    /// Mean peaks with the sliding stack, with it rigidly attached (`f = 1`) and without its
    /// mass (`f = 0`).
    pub stack: Means,
    pub rigid: Means,
    pub bare: Means,
    /// The stuck mass share's mean over the motions (the prior of the roots).
    pub share: f64,
    /// The fraction of the roof's mean peak displacement (a building's `T_new` is `T_1` of it).
    pub roof: (f64, FractionFlag),
    /// Each storey's shear's, storey 1 (the base: `λ`) first.
    pub storey: Vec<(f64, FractionFlag)>,
    /// The overturning moment's at the base.
    pub overturning: (f64, FractionFlag),
    /// The code-format fraction ([`code_shear_ratio`] equal to the base shear's
    /// `V̄_stack/V̄_rigid`).
    pub code: (f64, FractionFlag),
}

/// What the sweep stored of a case in a building of several storeys: its mean peaks with the
/// sliding stack and with it attached, and its mean stuck mass share (one storey: `None`, its
/// integrator gives neither the shears nor the share, and they are simulated here).
pub type Swept = Option<(Means, Means, f64)>;

/// Why a zone's fractions could not be made.
#[derive(Debug, thiserror::Error)]
pub enum AttachedError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error("the mean spectrum at T_1 = {period_s} s: {source}")]
    Spectrum {
        period_s: f64,
        source: SpectrumError,
    },
    /// `keep_going` said stop.
    #[error("stopped")]
    Stopped,
}

/// One unit of a zone's attached fractions, the work that `tnew --shard` splits: a scan key (a
/// distinct building's frame, `T_p` and total `α`: the scan depends on them, through the
/// damping matrix, but not on `μ`) and the cases of that frame that share it.
#[derive(Debug, Clone, PartialEq)]
pub struct FractionUnit {
    pub frame: usize,
    pub period_s: f64,
    pub alpha_total: f64,
    /// Its cases, flat over `[frame][case]` and ascending; the first makes the scan.
    pub cases: Vec<usize>,
}

/// The units of a zone's attached fractions over `grid`'s cases in each of `frames`, in the
/// order of their keys (frame, `T_p`, total `α`); frames that are one building
/// ([`super::building::first_of_building`]) give units for the first only.
pub fn fraction_units(grid: &crate::grid::Grid, frames: &[Frame]) -> Vec<FractionUnit> {
    let per_frame = grid.cases();
    let mut units: BTreeMap<(usize, u64, u64), FractionUnit> = BTreeMap::new();
    let cases = (super::building::distinct_frames(frames).into_iter())
        .flat_map(|f| f * per_frame..(f + 1) * per_frame);
    for c in cases {
        let case = grid.case(c % per_frame);
        let (period_s, alpha_total) = (case.period_s, case.alpha_total());
        let key = (c / per_frame, period_s.to_bits(), alpha_total.to_bits());
        (units.entry(key))
            .or_insert_with(|| FractionUnit {
                frame: c / per_frame,
                period_s,
                alpha_total,
                cases: Vec::new(),
            })
            .cases
            .push(c);
    }
    units.into_values().collect()
}

/// What a zone's attached fractions are made from: `swept` per case (flat over `[frame][case]`,
/// `grid`'s cases in each of `frames`), `slides` whether any interface slipped under any motion.
/// `keep_going` is asked before each case (Ctrl-C).
pub struct ZoneFamily<'a> {
    pub physics: &'a Physics,
    pub grid: &'a crate::grid::Grid,
    pub frames: &'a [Frame],
    pub grounds: &'a [Ground<'a>],
    pub swept: &'a [Swept],
    pub slides: &'a [bool],
    pub keep_going: &'a (dyn Fn() -> bool + Sync),
}

/// A unit's scan: the family's means at the scan's fractions, the code-format ratio at each, the
/// rigid system's mean spectral acceleration at `T_1` (g), and the motions prepared for the
/// code-format ratio's other spectra.
type Scan<'a> = (Vec<(f64, Means)>, Vec<(f64, f64)>, f64, RecordSet<'a>);

impl<'a> ZoneFamily<'a> {
    /// The attached fractions of every case of `unit`, in its order: the scan once, each case's
    /// sliding stack (the sweep's, or on one storey simulated here, `one_storey_setups`), the
    /// family's means at each distinct prior not scanned, then each function's searches over the
    /// cases in the unit's order, sharing the function's [`Values`] (the functions in parallel:
    /// the numbers depend on neither the threads nor the shards, a unit being computed whole).
    pub fn unit(&self, unit: &FractionUnit) -> Result<Vec<CaseFractions>, AttachedError> {
        use rayon::prelude::*;
        let first = unit.cases[0];
        let (case, frame) = (self.case(first), self.frame(first));
        let (scan, setups) = match &self.swept[first] {
            Some((_, rigid, _)) => {
                let scan = self.scan(first, rigid.clone())?;
                let setups = (unit.cases.iter())
                    .map(|&c| self.swept_setup(c))
                    .collect::<Result<Vec<_>, _>>()?;
                (scan, setups)
            }
            None => {
                // One storey: the rigid system is the unit's key's, run once for its means and
                // every case's no-slip rule.
                let b = building_of(self.physics, SystemKind::Rigid, &case, frame)?;
                let rigid = self.under_every_motion(|g| {
                    run_one(&b, SystemKind::Rigid, &case, frame, &self.grounds[g])
                })?;
                let scan = self.scan(first, Means::of(&rigid, frame))?;
                let setups = self.one_storey_setups(unit, &rigid, &scan.0)?;
                (scan, setups)
            }
        };
        // Every function's search evaluates its case's prior: one run gives them all, once for
        // cases that share it.
        let storeys = frame.storeys();
        let mut priors: Vec<f64> = (setups.iter())
            .map(|s| prior_fraction(s.share, &scan.0))
            .filter(|p| !scan.0.iter().any(|(f, _)| f == p))
            .collect();
        priors.sort_by(f64::total_cmp);
        priors.dedup_by(|a, b| a.to_bits() == b.to_bits());
        let at_priors = (priors.par_iter())
            .map(|&f| {
                Ok((
                    f,
                    family_means(self.physics, &case, frame, f, self.grounds)?,
                ))
            })
            .collect::<Result<Vec<_>, CaseError>>()?;
        let functions: Vec<Function> = (Quantity::all(storeys).into_iter())
            .map(Function::Mean)
            .chain([Function::Code])
            .collect();
        let found = (functions.par_iter())
            .map(|&function| self.search(unit, function, &scan, &at_priors, &setups))
            .collect::<Result<Vec<_>, _>>()?;
        let (rigid, bare) = (rigid_of(&scan.0), bare_of(&scan.0));
        Ok((setups.into_iter().enumerate())
            .map(|(k, s)| {
                let at = |i: usize| found[i][k];
                CaseFractions {
                    stack: s.stack,
                    rigid: rigid.clone(),
                    bare: bare.clone(),
                    share: s.share,
                    roof: at(0),
                    storey: (1..=storeys).map(at).collect(),
                    overturning: at(storeys + 1),
                    code: at(storeys + 2),
                }
            })
            .collect())
    }

    /// Case `c` of the zone (flat over `[frame][case]`).
    fn case(&self, c: usize) -> Case {
        self.grid.case(c % self.grid.cases())
    }

    /// Case `c`'s frame.
    fn frame(&self, c: usize) -> &Frame {
        &self.frames[c / self.grid.cases()]
    }

    /// Case `c`'s sliding stack, as the sweep stored it.
    fn swept_setup(&self, c: usize) -> Result<Setup, AttachedError> {
        if !(self.keep_going)() {
            return Err(AttachedError::Stopped);
        }
        let (stack, _, share) = self.swept[c]
            .as_ref()
            .expect("a building's sweep stores it");
        Ok(Setup {
            stack: stack.clone(),
            share: *share,
        })
    }

    /// The sliding stacks of a one-storey `unit`'s cases, simulated here, in its order: a stack
    /// that holds under the `rigid` responses takes the rigid system's means (`scan`'s last);
    /// under each motion, a stack that repeats the run of an earlier case of the same masses
    /// ([`held_at_lower_friction`]: the sweep's rule, applied motion by motion) takes that run,
    /// the same bits as simulating it; the rest are simulated, the motions in parallel.
    fn one_storey_setups(
        &self,
        unit: &FractionUnit,
        rigid: &[BuildingResponse],
        scan: &[(f64, Means)],
    ) -> Result<Vec<Setup>, AttachedError> {
        let physics = self.physics;
        // The cases run so far, with their responses per motion.
        let mut runs: Vec<(Case, Vec<BuildingResponse>)> = Vec::new();
        let mut setups = Vec::with_capacity(unit.cases.len());
        for &c in &unit.cases {
            if !(self.keep_going)() {
                return Err(AttachedError::Stopped);
            }
            let (case, frame) = (self.case(c), self.frame(c));
            if holds_everywhere(physics, &case, frame, rigid) {
                setups.push(Setup {
                    stack: rigid_of(scan),
                    share: 1.0,
                });
                continue;
            }
            let b = building_of(physics, SystemKind::Stack, &case, frame)?;
            let responses = self.under_every_motion(|g| {
                let repeated =
                    (runs.iter()).find(|(ran, r)| held_at_lower_friction(&case, ran, &r[g].held));
                match repeated {
                    Some((_, r)) => Ok(r[g].clone()),
                    None => run_one(&b, SystemKind::Stack, &case, frame, &self.grounds[g]),
                }
            })?;
            setups.push(Setup {
                stack: Means::of(&responses, frame),
                share: mean_share(&responses),
            });
            runs.push((case, responses));
        }
        Ok(setups)
    }

    /// `run(g)` for every motion `g`, in parallel, in the motions' order.
    fn under_every_motion(
        &self,
        run: impl Fn(usize) -> Result<BuildingResponse, CaseError> + Sync + Send,
    ) -> Result<Vec<BuildingResponse>, CaseError> {
        use rayon::prelude::*;
        (0..self.grounds.len()).into_par_iter().map(run).collect()
    }

    /// The fraction of `function` for each of `unit`'s cases, in its order: one [`Values`] of
    /// the function (evaluated with the unit's first case: the family depends on the unit's key
    /// alone) for all their searches.
    fn search(
        &self,
        unit: &FractionUnit,
        function: Function,
        (scan, code_scan, psa_rigid, spectra): &Scan,
        // The family's means at the cases' priors the scan does not hold.
        at_priors: &[(f64, Means)],
        setups: &[Setup],
    ) -> Result<Vec<(f64, FractionFlag)>, AttachedError> {
        let (physics, grounds) = (self.physics, self.grounds);
        let (case, frame) = (self.case(unit.cases[0]), self.frame(unit.cases[0]));
        let psa_rigid = *psa_rigid;
        let (points, mut values): (Vec<(f64, f64)>, Values<AttachedError>) = match function {
            Function::Mean(q) => {
                let points: Vec<(f64, f64)> = scan.iter().map(|(f, m)| (*f, m.get(q))).collect();
                let priors = at_priors.iter().map(|(f, m)| (*f, m.get(q)));
                let values = Values::new(points.iter().copied().chain(priors), move |f| {
                    Ok(family_mean(physics, &case, frame, f, grounds, q)?)
                });
                (points, values)
            }
            Function::Code => {
                let values = Values::new(code_scan.iter().copied(), move |f| {
                    code_shear_ratio(&case, frame, spectra, f, psa_rigid).map_err(|source| {
                        AttachedError::Spectrum {
                            period_s: frame.t1_attached_s(&case, f),
                            source,
                        }
                    })
                });
                (code_scan.clone(), values)
            }
        };
        let rigid = rigid_of(scan);
        (unit.cases.iter().zip(setups))
            .map(|(&c, s)| {
                if !(self.keep_going)() {
                    return Err(AttachedError::Stopped);
                }
                let target = match function {
                    Function::Mean(q) => s.stack.get(q),
                    Function::Code => s.stack.storey_shear[0] / rigid.storey_shear[0],
                };
                let (f, flag) = solve(target, s.share, &points, &mut values)?;
                Ok(match self.slides[c] {
                    true => (f, flag),
                    false => (f, FractionFlag::NoSlide),
                })
            })
            .collect()
    }

    /// The scan of the key of case `c`, whose rigid system has the means `rigid` (the sweep's,
    /// or on one storey simulated here).
    fn scan(&self, c: usize, rigid: Means) -> Result<Scan<'a>, AttachedError> {
        let (physics, grounds) = (self.physics, self.grounds);
        if !(self.keep_going)() {
            return Err(AttachedError::Stopped);
        }
        let (case, frame) = (self.case(c), self.frame(c));
        let mut scan = Vec::new();
        for f in scan_fractions(&case) {
            let m = if f == 1.0 {
                rigid.clone()
            } else {
                family_means(physics, &case, frame, f, grounds)?
            };
            scan.push((f, m));
        }
        let t_rigid = frame.t1_attached_s(&case, 1.0);
        let spectrum = |source| AttachedError::Spectrum {
            period_s: t_rigid,
            source,
        };
        let records: Vec<(&'a [f64], f64)> =
            (grounds.iter()).map(|g| (g.accel_mps2, g.dt_s)).collect();
        let spectra = RecordSet::new(&records).map_err(spectrum)?;
        let psa_rigid = mean_psa_g(&spectra, t_rigid).map_err(spectrum)?;
        let code = (scan.iter().map(|(f, _)| *f))
            .map(|f| {
                code_shear_ratio(&case, frame, &spectra, f, psa_rigid)
                    .map(|g| (f, g))
                    .map_err(|source| AttachedError::Spectrum {
                        period_s: frame.t1_attached_s(&case, f),
                        source,
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((scan, code, psa_rigid, spectra))
    }
}

/// What a case's searches start from: its sliding stack's means and stuck mass share (the
/// sweep's, or simulated here on one storey).
struct Setup {
    stack: Means,
    share: f64,
}

/// A function of the family whose fractions a case takes.
#[derive(Debug, Clone, Copy)]
enum Function {
    /// A quantity's mean peak.
    Mean(Quantity),
    /// The code-format base shear ratio ([`code_shear_ratio`]).
    Code,
}

/// The rigid system's means: the scan's last, at `f = 1`.
fn rigid_of(scan: &[(f64, Means)]) -> Means {
    scan[scan.len() - 1].1.clone()
}

/// The bare building's means: the scan's at `f = 0`.
fn bare_of(scan: &[(f64, Means)]) -> Means {
    (scan.iter().find(|(f, _)| *f == 0.0))
        .expect("the scan holds 0")
        .1
        .clone()
}

/// The attached fractions of every case of a zone, flat over `[frame][case]` (`grid`'s cases in
/// each of `frames`; a frame that repeats a building takes its first frame's), from each unit's
/// (`of_units`, in `units`' order, [`fraction_units`]).
pub fn spread(
    grid: &crate::grid::Grid,
    frames: &[Frame],
    units: &[FractionUnit],
    of_units: &[Vec<CaseFractions>],
) -> Vec<CaseFractions> {
    let per_frame = grid.cases();
    let first = super::building::first_of_building(frames);
    let at: BTreeMap<usize, &CaseFractions> = (units.iter().zip(of_units))
        .flat_map(|(u, l)| u.cases.iter().copied().zip(l))
        .collect();
    (0..frames.len() * per_frame)
        .map(|c| at[&(first[c / per_frame] * per_frame + c % per_frame)].clone())
        .collect()
}

/// The attached fractions of every case of a zone, flat over `[frame][case]`
/// ([`spread`] of every unit's, the units in parallel).
pub fn zone_fractions(family: &ZoneFamily) -> Result<Vec<CaseFractions>, AttachedError> {
    use rayon::prelude::*;
    let units = fraction_units(family.grid, family.frames);
    let of_units: Vec<Vec<CaseFractions>> = (units.par_iter())
        .map(|u| family.unit(u))
        .collect::<Result<_, _>>()?;
    Ok(spread(family.grid, family.frames, &units, &of_units))
}
