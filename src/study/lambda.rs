//! The effective live-load fraction `λ` of a case (docs/model.md, "The effective live-load
//! fraction λ"; the paper's references \[12\] and \[14\], the "portion of the live load to be
//! included as seismic weight"): the fraction of the stack's mass which, rigidly attached to
//! its floor with the rest absent from the dynamics, gives the same mean peak base shear over
//! a zone's motions as the sliding stack.
//!
//! `V̄(λ)`, the mean over the motions of the peak base shear of the linear building carrying
//! `λ` of the stack attached
//! ([`crate::dynamics::building::Building::with_stacks_attached_fraction`]: the same `K` and
//! `C`), is computed exactly by the building's integrator (no interfaces: one modal basis).
//! It is not monotone in general (measured: 7 of 18 three-storey curves are,
//! `tests/building_lambda.rs`): the attached mass raises the inertia but lengthens the periods,
//! and a real spectrum need not fall as slowly as `1/sqrt(mass)`. So `V̄` is first scanned at
//! `λ = k/10`; the last scan interval whose ends straddle `V̄_stack` holds the root taken, the
//! largest `λ` that gives the stack's base shear (the larger seismic weight, the safe side of
//! several), found by Brent's method (argmin's `BrentRoot`) to [`LAMBDA_TOL`]; with no
//! crossing `λ` is the scan point whose `V̄` is nearest, flagged ([`LambdaFlag`]). Two
//! crossings closer than a scan step can go unseen (the interval then holds an odd number).

use super::building::Frame;
use super::physics::{CaseError, Physics, SystemKind};
use crate::case::Case;
use crate::dynamics::building::simulate_building;
use crate::dynamics::{ExactOptions, Ground};
use argmin::core::{CostFunction, Error as ArgminError, Executor, State};
use argmin::solver::brent::BrentRoot;
use std::cell::RefCell;

/// The root's tolerance in `λ` (absolute): Brent stops once the bracket is narrower than
/// about this, far below any physical meaning of `λ` and well above the round-off of `V̄`.
pub const LAMBDA_TOL: f64 = 1e-9;

/// Steps of the scan of `V̄(λ)` over `[0, 1]` that brackets its crossings (module doc).
pub const LAMBDA_SCAN_STEPS: usize = 10;

/// How a case's `λ` was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum LambdaFlag {
    /// `V̄(λ) = V̄_stack` crosses once on the scan: its root.
    Root = 0,
    /// `V̄_stack` below every scanned `V̄`: `λ` is the scan point of the smallest.
    Below = 1,
    /// `V̄_stack` above every scanned `V̄`: `λ` is the scan point of the largest.
    Above = 2,
    /// Nothing slid under any motion: the stack is the rigidly attached load, `λ = 1`.
    NoSlide = 3,
    /// Several crossings on the scan: the root of the largest `λ`.
    Several = 4,
}

/// `(code, word)` of each [`LambdaFlag`], for the CF `flag_values`/`flag_meanings`.
pub const LAMBDA_FLAGS: [(u8, &str); 5] = [
    (LambdaFlag::Root as u8, "root"),
    (LambdaFlag::Below as u8, "below_range_clamped"),
    (LambdaFlag::Above as u8, "above_range_clamped"),
    (LambdaFlag::NoSlide as u8, "no_slide"),
    (LambdaFlag::Several as u8, "several_roots_largest"),
];

/// `λ` for a mean peak base shear `target` of the sliding stack, given the ends' values
/// `v0 = V̄(0)`, `v1 = V̄(1)` and `v(λ)` for the values between (module doc): `V̄` is scanned at
/// `k/`[`LAMBDA_SCAN_STEPS`]; the last scan interval whose ends straddle the target holds the
/// root taken (Brent's method inside it, to [`LAMBDA_TOL`]); with none, the scan point whose
/// `V̄` is nearest. `target == v1` (a stack that did not slide, by the sweep's rule) is `λ = 1`
/// at once. Errors of `v` are returned as they are.
pub fn solve<E>(
    target: f64,
    v0: f64,
    v1: f64,
    mut v: impl FnMut(f64) -> Result<f64, E>,
) -> Result<(f64, LambdaFlag), E> {
    if target == v1 {
        return Ok((1.0, LambdaFlag::Root));
    }
    solve_on(target, &scan(v0, v1, &mut v)?, v)
}

/// The scan of [`solve`]: `(λ, V̄)` at `λ = k/`[`LAMBDA_SCAN_STEPS`], the ends given. It does
/// not depend on the stack's friction, so a study computes it once for all the cases that share
/// a building, `T_p` and `α`.
pub fn scan<E>(
    v0: f64,
    v1: f64,
    mut v: impl FnMut(f64) -> Result<f64, E>,
) -> Result<Vec<(f64, f64)>, E> {
    let steps = LAMBDA_SCAN_STEPS;
    let mut out = vec![(0.0, v0)];
    for k in 1..steps {
        let l = k as f64 / steps as f64;
        out.push((l, v(l)?));
    }
    out.push((1.0, v1));
    Ok(out)
}

/// [`solve`] on its scan, already made ([`scan`]).
pub fn solve_on<E>(
    target: f64,
    scan: &[(f64, f64)],
    v: impl FnMut(f64) -> Result<f64, E>,
) -> Result<(f64, LambdaFlag), E> {
    let steps = scan.len() - 1;
    if target == scan[steps].1 {
        return Ok((1.0, LambdaFlag::Root));
    }
    // A scan point on the target counts once, in the interval it ends (or, λ = 0, starts).
    let crossings: Vec<usize> = (0..steps)
        .filter(|&k| {
            let (a, b) = (scan[k].1 - target, scan[k + 1].1 - target);
            a * b < 0.0 || b == 0.0 || (k == 0 && a == 0.0)
        })
        .collect();
    let Some(&last) = crossings.last() else {
        let nearest = |pick: fn(f64, f64) -> bool| {
            (scan.iter().copied())
                .reduce(|a, b| if pick(b.1, a.1) { b } else { a })
                .expect("the scan has its ends")
        };
        return Ok(if target < scan[0].1 {
            (nearest(|b, a| b < a).0, LambdaFlag::Below)
        } else {
            (nearest(|b, a| b > a).0, LambdaFlag::Above)
        });
    };
    let flag = if crossings.len() == 1 {
        LambdaFlag::Root
    } else {
        LambdaFlag::Several
    };
    let (a, b) = (scan[last], scan[last + 1]);
    if b.1 == target {
        return Ok((b.0, flag));
    }
    if a.1 == target {
        return Ok((a.0, flag));
    }
    let problem = Shear {
        target,
        ends: [a, b],
        v: RefCell::new(v),
        error: RefCell::new(None),
    };
    let best = Executor::new(&problem, BrentRoot::new(a.0, b.0, LAMBDA_TOL))
        .configure(|s| s.max_iters(200))
        .run()
        .map(|r| r.state().get_best_param().copied());
    if let Some(e) = problem.error.into_inner() {
        return Err(e);
    }
    let lambda = best
        .expect("the ends bracket the root and every value is finite")
        .expect("Brent keeps its best");
    Ok((lambda, flag))
}

/// `V̄(λ) − target`, remembering the first error of `v`.
struct Shear<F, E> {
    target: f64,
    /// The bracket's ends, `(λ, V̄)`, already known.
    ends: [(f64, f64); 2],
    v: RefCell<F>,
    error: RefCell<Option<E>>,
}

impl<F: FnMut(f64) -> Result<f64, E>, E> CostFunction for &Shear<F, E> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, lambda: &f64) -> Result<f64, ArgminError> {
        let known = self.ends.iter().find(|e| e.0 == *lambda);
        let v = match known {
            Some(&(_, v)) => Ok(v),
            None => (self.v.borrow_mut())(*lambda),
        };
        match v {
            Ok(v) => Ok(v - self.target),
            Err(e) => {
                self.error.borrow_mut().get_or_insert(e);
                Err(ArgminError::msg("the base shear could not be computed"))
            }
        }
    }
}

/// `V̄(λ)`: the mean over `grounds` (summed in order, then divided) of the peak base shear over
/// the bare building's weight of `frame` carrying `λ` of `case`'s stack rigidly attached
/// ([`Physics::building`]'s rigid system before attaching: each stack as one block).
pub fn mean_base_shear(
    physics: &Physics,
    case: &Case,
    frame: &Frame,
    lambda: f64,
    grounds: &[Ground],
) -> Result<f64, CaseError> {
    mean_peak(physics, None, case, frame, lambda, grounds)
}

/// The mean over `grounds` (as [`mean_base_shear`]) of system `kind`'s peak base shear over the
/// bare building's weight, by the building's integrator even on one storey (where the sweep
/// runs the one-storey integrator, which does not follow the base shear).
pub fn mean_system_base_shear(
    physics: &Physics,
    kind: SystemKind,
    case: &Case,
    frame: &Frame,
    grounds: &[Ground],
) -> Result<f64, CaseError> {
    mean_peak(physics, Some(kind), case, frame, 1.0, grounds)
}

/// `kind` `None`: the `λ`-building.
fn mean_peak(
    physics: &Physics,
    kind: Option<SystemKind>,
    case: &Case,
    frame: &Frame,
    lambda: f64,
    grounds: &[Ground],
) -> Result<f64, CaseError> {
    let in_building = |e| CaseError::InBuilding {
        frame: frame.to_string(),
        source: Box::new(e),
    };
    let built = match kind {
        None => physics
            .building(SystemKind::SingleBlock, case, frame)
            .map(|b| b.with_stacks_attached_fraction(lambda)),
        Some(k) => physics.building(k, case, frame),
    };
    let kind = kind.unwrap_or(SystemKind::Rigid);
    let b = built.map_err(|source| {
        in_building(CaseError::BuildingModel {
            case: case.clone(),
            kind,
            source: Box::new(source),
        })
    })?;
    let opts = ExactOptions {
        energy_balance: false,
        ..ExactOptions::default()
    };
    let mut sum = 0.0;
    for g in grounds {
        let r = simulate_building(&b, g, &opts).map_err(|source| {
            in_building(CaseError::Simulation {
                case: case.clone(),
                kind,
                source,
            })
        })?;
        sum += frame.base_shear_ratio(r.peak_base_shear_n);
    }
    Ok(sum / grounds.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_clamps_and_ends() {
        // V̄(λ) = 1 + λ²: the root of 1 + λ² = 1.49 is 0.7.
        let f = |l: f64| Ok::<_, ()>(1.0 + l * l);
        let (l, flag) = solve(1.49, 1.0, 2.0, f).unwrap();
        assert_eq!(flag, LambdaFlag::Root);
        assert!((l - 0.7).abs() < LAMBDA_TOL, "{l}");
        // Decreasing: V̄ = 2 − λ, the root of 1.25 is 0.75.
        let (l, _) = solve(1.25, 2.0, 1.0, |l| Ok::<_, ()>(2.0 - l)).unwrap();
        assert!((l - 0.75).abs() < LAMBDA_TOL, "{l}");
        assert_eq!(solve(0.5, 1.0, 2.0, f).unwrap(), (0.0, LambdaFlag::Below));
        assert_eq!(solve(3.0, 1.0, 2.0, f).unwrap(), (1.0, LambdaFlag::Above));
        assert_eq!(solve(0.5, 2.0, 1.0, f).unwrap(), (1.0, LambdaFlag::Below));
        assert_eq!(solve(2.0, 1.0, 2.0, f).unwrap(), (1.0, LambdaFlag::Root));
        // A hump: V̄ = 1 + sin(πλ) crosses 1.5 at 1/6 and 5/6; the larger is taken. Above its
        // top (2 at λ = 1/2) the nearest scan point, 0.5, is taken.
        let hump = |l: f64| Ok::<_, ()>(1.0 + (std::f64::consts::PI * l).sin());
        let (l, flag) = solve(1.5, 1.0, hump(1.0).unwrap(), hump).unwrap();
        assert_eq!(flag, LambdaFlag::Several);
        assert!((l - 5.0 / 6.0).abs() < LAMBDA_TOL, "{l}");
        assert_eq!(
            solve(2.5, 1.0, hump(1.0).unwrap(), hump).unwrap(),
            (0.5, LambdaFlag::Above)
        );
        // An error of V̄ comes back as it is.
        assert_eq!(solve(1.5, 1.0, 2.0, |_| Err::<f64, _>(7)), Err(7));
    }
}
