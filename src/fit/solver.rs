//! The machinery: argmin's trust-region method with the Steihaug (truncated conjugate
//! gradient) subproblem on the Gauss–Newton model `½‖r + J·s‖²` (gradient `Jᵀr`, Hessian
//! `JᵀJ`, both from the forms' analytic derivatives), from several starts; Nelder–Mead only
//! when the trust region has not converged.
//!
//! argmin 0.10 with the `vec` backend of argmin-math 0.4 offers this method (`TrustRegion` with
//! `Steihaug`; `Dogleg` and `GaussNewton` need a matrix inverse the `vec` backend lacks) and
//! L-BFGS. The trust region uses the curvature `JᵀJ` that a least-squares problem gives for
//! free and is the Levenberg–Marquardt idea in trust-region form; L-BFGS would learn that
//! curvature from gradients. argmin's trust region has no stopping rule of its own (it runs to
//! its iteration limit), so `GaussNewtonTrustRegion` wraps it with two: converged when the
//! Bates–Watts relative offset is below [`RELATIVE_OFFSET_TOLERANCE`] (the Gauss–Newton step
//! that remains, against the radius of the parameters' statistical uncertainty: free of their
//! scales and conditioning, unlike a gradient norm), stalled when the cost has not decreased
//! for [`STALL_ITERATIONS`] iterations (steps rejected at round-off). An exact fit (residuals at
//! round-off, where the relative offset is that of noise, about 1) also counts as converged.
//!
//! Several starts ([`crate::fit::Form::starts`]): each is probed for [`PROBE_ITERATIONS`]
//! iterations, and the one with the lowest sum of squares then runs to convergence (up to
//! [`MAX_ITERATIONS`]). Every fit is sequential and its sums in a fixed order: the same data
//! give the same result on any machine thread count.

use super::FitError;
use super::Form;
use super::problem::{Problem, Projected, Scaled, relative_offset};
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, Gradient, Hessian, IterState, KV,
    OptimizationResult, Problem as ArgminProblem, Solver, State, TerminationReason,
    TerminationStatus,
};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::trustregion::{Steihaug, TrustRegion};
use serde::{Deserialize, Serialize};

/// Converged when the Bates–Watts relative offset is below this: the Gauss–Newton step that
/// remains is 1e-4 of the radius of the parameters' statistical uncertainty (module doc).
pub const RELATIVE_OFFSET_TOLERANCE: f64 = 1e-4;

/// Trust-region iterations of each start's probe.
pub const PROBE_ITERATIONS: u64 = 30;

/// Trust-region iterations of the best start's run to convergence, at most.
pub const MAX_ITERATIONS: u64 = 400;

/// Iterations without a decrease of the cost after which the trust region stops.
pub const STALL_ITERATIONS: u64 = 20;

/// Nelder–Mead iterations at most.
pub const MAX_NELDER_MEAD_ITERATIONS: u64 = 20_000;

/// Which solver gave the result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// argmin's trust region (Steihaug) on the Gauss–Newton model.
    #[default]
    TrustRegion,
    /// argmin's Nelder–Mead, from the trust region's best point (fallback).
    NelderMead,
    /// The paper form's fallback: argmin's Nelder–Mead on its exponent weights alone, the
    /// linear parameters projected out (variable projection), from the trust region's best
    /// point.
    ProjectedNelderMead,
}

/// How the solver went.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SolverReport {
    pub method: Method,
    /// Trust region: the relative-offset test (or the exact-fit test) passed; Nelder–Mead: it
    /// stopped on its own tolerance.
    pub converged: bool,
    /// Starts tried (trust region from each).
    pub starts: usize,
    /// Iterations of all the trust-region runs, and of Nelder–Mead when it ran.
    pub iterations: u64,
    /// The Bates–Watts relative offset at the result (zero at a stationary point).
    pub relative_offset: f64,
}

type TrState = IterState<Vec<f64>, Vec<f64>, (), Vec<Vec<f64>>, (), f64>;

/// argmin's [`TrustRegion`] with stopping rules (module doc).
#[derive(Clone)]
struct GaussNewtonTrustRegion {
    inner: TrustRegion<Steihaug<Vec<f64>, f64>, f64>,
    /// Cases of the problem.
    n: usize,
    /// A cost at or below this is an exact fit ([`Problem::round_off_sse`]).
    exact_cost: f64,
    lowest_cost: f64,
    since_decrease: u64,
}

impl GaussNewtonTrustRegion {
    fn new(m: usize, n: usize, exact_cost: f64) -> Result<Self, ArgminError> {
        // A truncated CG on m unknowns needs m steps in exact arithmetic; allow for round-off.
        let steihaug = Steihaug::new().with_max_iters(4 * m as u64 + 10);
        Ok(Self {
            inner: TrustRegion::new(steihaug)
                .with_radius(1.0)?
                .with_max_radius(1e4)?,
            n,
            exact_cost,
            lowest_cost: f64::INFINITY,
            since_decrease: 0,
        })
    }
}

/// The relative offset from the state (cost `½‖r‖²`, gradient `Jᵀr`, Hessian `JᵀJ`).
fn state_offset(state: &TrState, n: usize) -> f64 {
    let (Some(g), Some(h)) = (state.get_gradient(), state.get_hessian()) else {
        return f64::INFINITY;
    };
    let flat: Vec<f64> = h.iter().flatten().copied().collect();
    relative_offset(g, &flat, 2.0 * state.get_cost(), n)
}

impl<O> Solver<O, TrState> for GaussNewtonTrustRegion
where
    O: CostFunction<Param = Vec<f64>, Output = f64>
        + Gradient<Param = Vec<f64>, Gradient = Vec<f64>>
        + Hessian<Param = Vec<f64>, Hessian = Vec<Vec<f64>>>,
{
    const NAME: &'static str = "Gauss–Newton trust region (Steihaug)";

    fn init(
        &mut self,
        problem: &mut ArgminProblem<O>,
        state: TrState,
    ) -> Result<(TrState, Option<KV>), ArgminError> {
        let (state, kv) = self.inner.init(problem, state)?;
        self.lowest_cost = state.get_cost();
        Ok((state, kv))
    }

    fn next_iter(
        &mut self,
        problem: &mut ArgminProblem<O>,
        state: TrState,
    ) -> Result<(TrState, Option<KV>), ArgminError> {
        let (state, kv) = self.inner.next_iter(problem, state)?;
        if state.get_cost() < self.lowest_cost {
            self.lowest_cost = state.get_cost();
            self.since_decrease = 0;
        } else {
            self.since_decrease += 1;
        }
        Ok((state, kv))
    }

    fn terminate(&mut self, state: &TrState) -> TerminationStatus {
        if state.get_cost() <= self.exact_cost
            || state_offset(state, self.n) <= RELATIVE_OFFSET_TOLERANCE
        {
            TerminationStatus::Terminated(TerminationReason::SolverConverged)
        } else if self.since_decrease >= STALL_ITERATIONS {
            TerminationStatus::Terminated(TerminationReason::SolverExit("stalled".into()))
        } else {
            TerminationStatus::NotTerminated
        }
    }
}

/// One trust-region run from `p0` (natural parameters): the best point, its sum of squares,
/// the iterations and whether it converged.
fn trust_region(
    problem: &Problem,
    p0: &[f64],
    max_iterations: u64,
) -> Result<(Vec<f64>, f64, u64, bool), FitError> {
    let scaled = Scaled::new(problem, problem.column_scales(p0));
    let q0 = scaled.to_q(p0);
    let solver = GaussNewtonTrustRegion::new(problem.m, problem.n(), 0.5 * problem.round_off_sse())
        .map_err(solver_error)?;
    let result = Executor::new(scaled, solver)
        .configure(|s| s.param(q0).max_iters(max_iterations))
        .timer(false)
        .run()
        .map_err(solver_error)?;
    let (p, iterations, converged) = outcome(result, "trust region", Scaled::to_p)?;
    let sse = problem.sse(&p);
    Ok((p, sse, iterations, converged))
}

/// A finished run of argmin's Nelder–Mead on the problem `P`.
type NmRun<P> =
    OptimizationResult<P, NelderMead<Vec<f64>, f64>, IterState<Vec<f64>, (), (), (), (), f64>>;

/// argmin's Nelder–Mead on `problem` (a scaled problem) from `q0`, simplex steps of 0.1 in
/// every scaled parameter, stopped when the simplex's costs agree to 1e-12 of the starting
/// cost (a relative bound) or after [`MAX_NELDER_MEAD_ITERATIONS`].
fn run_nelder_mead<P>(problem: P, q0: &[f64]) -> Result<NmRun<P>, FitError>
where
    P: CostFunction<Param = Vec<f64>, Output = f64>,
{
    let mut simplex = vec![q0.to_vec()];
    for i in 0..q0.len() {
        let mut v = q0.to_vec();
        v[i] += 0.1;
        simplex.push(v);
    }
    let start_cost = problem.cost(&q0.to_vec()).map_err(solver_error)?;
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-12 * start_cost.max(f64::MIN_POSITIVE))
        .map_err(solver_error)?;
    Executor::new(problem, solver)
        .configure(|s| s.max_iters(MAX_NELDER_MEAD_ITERATIONS))
        .timer(false)
        .run()
        .map_err(solver_error)
}

/// Nelder–Mead from `p0` in the scaled parameters (a step of 0.1 is about 0.1 s of
/// prediction): the best point and whether it stopped on its tolerance.
fn nelder_mead(problem: &Problem, p0: &[f64]) -> Result<(Vec<f64>, u64, bool), FitError> {
    let scaled = Scaled::new(problem, problem.column_scales(p0));
    let q0 = scaled.to_q(p0);
    outcome(run_nelder_mead(scaled, &q0)?, "Nelder–Mead", Scaled::to_p)
}

/// The paper form's fallback: Nelder–Mead over its `k` exponent weights `c` only, the linear
/// parameters `(a, B, e)` solved for at each point (variable projection: a `k`-dimensional
/// simplex instead of a `(2k + 2)`-dimensional one, where Nelder–Mead's iterations grow fast
/// with the dimension), scaled and stopped as [`nelder_mead`]. Every point it visits is at
/// least as good as the full parameters with the same `c`, so its result is no worse than the
/// start's. Returns the full parameters (linear ones by the SVD), iterations, and whether it
/// stopped on its tolerance.
fn projected_nelder_mead(problem: &Problem, p0: &[f64]) -> Result<(Vec<f64>, u64, bool), FitError> {
    let k = problem.k;
    let d = problem.column_scales(p0)[k..2 * k].to_vec();
    let projected = Projected::new(problem, d);
    let q0: Vec<f64> = p0[k..2 * k]
        .iter()
        .zip(&projected.d)
        .map(|(c, d)| c * d)
        .collect();
    let (c, iterations, converged) = outcome(
        run_nelder_mead(projected, &q0)?,
        "Nelder–Mead (projected)",
        Projected::to_c,
    )?;
    let mut start = p0.to_vec();
    start[k..2 * k].copy_from_slice(&c);
    Ok((problem.complete_start(&start), iterations, converged))
}

/// A run of an argmin solver `S` on the problem `P`, as the executor returns it.
type Finished<P, S, G, J, H, R> = OptimizationResult<P, S, IterState<Vec<f64>, G, J, H, R, f64>>;

/// A finished run's best point mapped by `unscale` (from the solver's parameters to the ones
/// the caller wants), its iterations and whether the solver converged (rather than stopped at
/// its limit or stalled).
fn outcome<P, S, G, J, H, R>(
    result: Finished<P, S, G, J, H, R>,
    method: &str,
    unscale: impl Fn(&P, &[f64]) -> Vec<f64>,
) -> Result<(Vec<f64>, u64, bool), FitError> {
    let converged = matches!(
        result.state.get_termination_reason(),
        Some(TerminationReason::SolverConverged)
    );
    let iterations = result.state.get_iter();
    let q = result
        .state
        .get_best_param()
        .ok_or_else(|| FitError::Solver(format!("{method}: no best parameters")))?;
    let p = result
        .problem
        .problem
        .as_ref()
        .map(|s| unscale(s, q))
        .ok_or_else(|| FitError::Solver(format!("{method}: problem not returned")))?;
    Ok((p, iterations, converged))
}

fn solver_error(e: ArgminError) -> FitError {
    FitError::Solver(e.to_string())
}

/// Least squares of `problem` from `starts` ([`crate::fit::Form::starts`]): each probed by the
/// trust region, the best run to convergence; Nelder–Mead from there when that did not
/// converge.
pub(crate) fn solve(
    problem: &Problem,
    starts: &[Vec<f64>],
) -> Result<(Vec<f64>, SolverReport), FitError> {
    let mut best: Option<(Vec<f64>, f64, bool)> = None;
    let mut iterations = 0;
    for start in starts {
        if start.len() != problem.m {
            return Err(FitError::Solver(format!(
                "a start has {} parameters, the form {}",
                start.len(),
                problem.m
            )));
        }
        let p0 = problem.complete_start(start);
        let (p, sse, it, converged) = trust_region(problem, &p0, PROBE_ITERATIONS)?;
        iterations += it;
        if best.as_ref().is_none_or(|b| sse < b.1) {
            best = Some((p, sse, converged));
        }
    }
    let (mut p, mut sse, mut converged) =
        best.ok_or_else(|| FitError::Solver("no start to solve from".into()))?;
    if !sse.is_finite() {
        return Err(FitError::Solver(
            "the sum of squares is not finite at any start".into(),
        ));
    }
    if !converged {
        let (q, s, it, c) = trust_region(problem, &p, MAX_ITERATIONS)?;
        iterations += it;
        if s <= sse {
            (p, sse, converged) = (q, s, c);
        }
    }
    let mut report = SolverReport {
        method: Method::TrustRegion,
        converged,
        starts: starts.len(),
        iterations,
        relative_offset: f64::NAN,
    };
    if !converged {
        let (q, it, nm_converged) = if problem.form == Form::Paper {
            report.method = Method::ProjectedNelderMead;
            projected_nelder_mead(problem, &p)?
        } else {
            report.method = Method::NelderMead;
            nelder_mead(problem, &p)?
        };
        report.converged = nm_converged;
        report.iterations += it;
        if problem.sse(&q) <= sse {
            p = q;
        }
    }
    report.relative_offset = problem.relative_offset(&problem.normal_equations(&p));
    Ok((p, report))
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{Form, Sample};

    #[test]
    fn falls_back_to_nelder_mead_when_the_trust_region_does_not_converge() {
        // T_new = 1 + (x₁ + x₂)²: the paper form a·x + B·e^{c·x} + e approaches it only as
        // c → 0 with B·c² fixed, a least-squares optimum at infinity, so the trust region
        // keeps improving without converging; Nelder–Mead on the exponent weights (variable
        // projection) then takes over from its best point and the result is no worse than
        // that point.
        let mut data = Vec::new();
        for i in 0..60 {
            let x1 = 0.1 + 0.03 * i as f64;
            let x2 = 0.5 + 0.2 * ((i * 7) % 11) as f64 / 11.0;
            data.push(Sample {
                x: vec![x1, x2],
                t_rigid_s: 2.0,
                t_new_s: 1.0 + (x1 + x2).powi(2),
            });
        }
        let problem = Problem::new(Form::Paper, &data).unwrap();
        let starts = Form::Paper.starts(2);
        let (p, report) = solve(&problem, &starts).unwrap();
        assert_eq!(report.method, Method::ProjectedNelderMead, "{report:?}");
        let p0 = problem.complete_start(&starts[1]);
        let (tr, tr_sse, _, converged) = trust_region(&problem, &p0, MAX_ITERATIONS).unwrap();
        assert!(!converged, "{tr:?}");
        assert!(problem.sse(&p) <= tr_sse * (1.0 + 1e-12), "{report:?}");
    }
}
