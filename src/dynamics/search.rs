//! Certified searches over one piece of a closed-form motion: the first instant a switching
//! function goes negative, and the largest `|f|` over an interval (docs/model.md, "The physical
//! system": every switch and every peak is found exactly, not sampled).
//!
//! A function is known through [`Smooth`]: its value and slope at a point, its second derivative,
//! and an upper bound of `|f⁽ᵏ⁾|` (`k = 2, 3, 4`) over an interval. From these, a stretch is
//! cleared without evaluation inside it by the better of two bounds: the curvature bound
//! (`max|f''|·w²/8` beyond the end values) and the cubic Hermite bound (`max|f⁗|·w⁴/384` beyond
//! the Hermite interpolant of the end values and slopes); a stretch whose slope keeps one sign
//! (`max|f'''|·w²/8` below the end slopes) is monotone. What is not cleared is halved. A root is
//! refined by Illinois regula falsi to a few ulps of the sample interval; an extremum by Newton's
//! method on `f'` until its value is certified to `ε/8` (docs/model.md, "The physical system").
//!
//! The building integrator (`super::building`) uses these on its modal functions.
//!
//! A search that cannot make progress says so ([`SearchError`]) instead of running on: a value,
//! slope or bound that is not finite (the arithmetic overflowed) clears nothing, so halving it
//! would visit every stretch down to the depth limit, `2^80` of them; and however the bounds
//! behave, a search evaluates the function at most [`MAX_SEARCH_NODES`] times.

use super::closed_form::hermite_range;
use thiserror::Error;

/// Evaluations one search may make. A certified search halves only the stretches its bounds
/// cannot clear: near a root or a peak, a few per level down to the resolution `4·ε·dt`
/// (about 50 levels). Measured over the fixture records on one storey (elastic, bilinear,
/// EPP, three blocks with static friction, `T_p` from 1 µs to 5 s, `--scale 1e6`) and in
/// buildings: at most 32 evaluations (at `T_p = 1 µs`, ten thousand periods in a sample
/// interval). This many means the bounds certify nothing, which only values beyond what double
/// precision resolves give; it costs milliseconds.
pub(crate) const MAX_SEARCH_NODES: usize = 100_000;

/// Why a certified search gave up.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum SearchError {
    /// A value, slope or derivative bound is infinite or NaN: the arithmetic overflowed.
    #[error("a switching or peak function is not finite (the arithmetic overflowed)")]
    NonFinite,
    /// `MAX_SEARCH_NODES` evaluations certified nothing.
    #[error(
        "the certified search made no progress within {MAX_SEARCH_NODES} evaluations (its \
         bounds certify nothing: values beyond what double precision resolves)"
    )]
    NoProgress,
}

/// The evaluations left to one search.
struct Budget(usize);

impl Budget {
    fn new() -> Self {
        Budget(MAX_SEARCH_NODES)
    }

    /// `Node::of(s, tau)`, counted and checked finite.
    fn node<S: Smooth>(&mut self, s: &S, tau: f64) -> Result<Node<S::At>, SearchError> {
        if self.0 == 0 {
            return Err(SearchError::NoProgress);
        }
        self.0 -= 1;
        let n = Node::of(s, tau);
        finite(s, &n)?;
        Ok(n)
    }
}

/// A node whose time, value and slope are finite.
fn finite<S: Smooth>(_: &S, n: &Node<S::At>) -> Result<(), SearchError> {
    if S::tau(&n.at).is_finite() && n.f.is_finite() && n.df.is_finite() {
        Ok(())
    } else {
        Err(SearchError::NonFinite)
    }
}

/// A function of a piece's local time `τ ≥ 0` with certified derivative bounds.
pub(crate) trait Smooth {
    /// What an evaluation at a point computes and a bound from that point can reuse.
    type At: Copy;
    fn at(&self, tau: f64) -> Self::At;
    fn tau(at: &Self::At) -> f64;
    /// `(f, f')` at the point.
    fn eval(&self, at: &Self::At) -> (f64, f64);
    /// `f` at the point (what a search for a root refines): `eval`'s, the same bits.
    fn value(&self, at: &Self::At) -> f64 {
        self.eval(at).0
    }
    /// `f'` at the point (what an extremum's refinement falls back to, as a root of `f'`).
    fn slope(&self, at: &Self::At) -> f64 {
        self.eval(at).1
    }
    /// `f''` at the point.
    fn second(&self, at: &Self::At) -> f64;
    /// `(f, f', f'')` at the point (an extremum's Newton step): `eval`'s value and slope, the
    /// same bits, and `second`'s curvature to round-off (it steers the step and certifies
    /// nothing).
    fn eval_second(&self, at: &Self::At) -> (f64, f64, f64) {
        let (f, df) = self.eval(at);
        (f, df, self.second(at))
    }
    /// An upper bound of `|f⁽ᵏ⁾|` over `[tau(lo), t1]`, `k ∈ {2, 3, 4}`.
    fn bound(&self, k: usize, lo: &Self::At, t1: f64) -> f64;
}

/// A point of a piece with the function's value and slope there.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node<A> {
    pub at: A,
    pub f: f64,
    pub df: f64,
}

impl<A: Copy> Node<A> {
    pub fn of<S: Smooth<At = A>>(s: &S, tau: f64) -> Self {
        let at = s.at(tau);
        let (f, df) = s.eval(&at);
        Node { at, f, df }
    }
}

/// Whether `lower ≤ f ≤ upper` on `[lo, hi]`, certified from the end values and slopes.
pub(crate) fn range_within<S: Smooth>(
    s: &S,
    lo: &Node<S::At>,
    hi: &Node<S::At>,
    lower: f64,
    upper: f64,
) -> bool {
    let (t_lo, t_hi) = (S::tau(&lo.at), S::tau(&hi.at));
    let w = t_hi - t_lo;
    let curv = s.bound(2, &lo.at, t_hi) * w * w / 8.0;
    if lo.f.min(hi.f) - curv >= lower && lo.f.max(hi.f) + curv <= upper {
        return true;
    }
    let quart = s.bound(4, &lo.at, t_hi) * (w * w) * (w * w) / 384.0;
    let (h_lo, h_hi) = hermite_range(lo.f, hi.f, lo.df * w, hi.df * w);
    (lo.f.min(hi.f) - curv).max(h_lo - quart) >= lower
        && (lo.f.max(hi.f) + curv).min(h_hi + quart) <= upper
}

/// Whether `f'` keeps one sign on `[lo, hi]`: then the end values are the extremes.
pub(crate) fn monotone<S: Smooth>(s: &S, lo: &Node<S::At>, hi: &Node<S::At>) -> bool {
    let t_hi = S::tau(&hi.at);
    let w = t_hi - S::tau(&lo.at);
    lo.df * hi.df > 0.0 && lo.df.abs().min(hi.df.abs()) > s.bound(3, &lo.at, t_hi) * w * w / 8.0
}

/// Earliest `τ ∈ (τ(start), τ(end)]` where `f` goes negative, refined to a few ulps of `dt`;
/// `None` if it stays non-negative. A start exactly on the boundary (`f = 0`, a fresh slip or a
/// branch just left) is cleared for a first stretch by the Taylor bound
/// `f ≥ f'·τ + f''·τ²/2 − max|f'''|·τ³/6`. An error when a value is not finite or the search
/// makes no progress ([`SearchError`]).
pub(crate) fn first_violation<S: Smooth>(
    s: &S,
    start: &Node<S::At>,
    end: &Node<S::At>,
    dt: f64,
) -> Result<Option<f64>, SearchError> {
    finite(s, start)?;
    finite(s, end)?;
    let (t0, h) = (S::tau(&start.at), S::tau(&end.at));
    if start.f < 0.0 {
        return Ok(Some(t0));
    }
    let mut budget = Budget::new();
    let mut lo = *start;
    if start.f == 0.0 {
        let g2 = s.second(&start.at);
        let g3 = s.bound(3, &start.at, h);
        let tc = taylor_clearance(start.df, g2, g3);
        if tc.is_nan() || !g2.is_finite() || g3.is_nan() {
            return Err(SearchError::NonFinite);
        }
        if tc <= 0.0 {
            return Ok(Some(t0));
        }
        let clear = t0 + 0.999 * tc;
        if clear >= h {
            return Ok(None);
        }
        lo = budget.node(s, clear)?;
    }
    let min_width = 4.0 * f64::EPSILON * dt;
    let Some((a, b)) = search(s, &lo, end, min_width, 0, &mut budget)? else {
        return Ok(None);
    };
    Ok(Some(refine(|t| s.value(&s.at(t)), a, b, min_width)))
}

/// Largest `τ_c` with `g₁τ + g₂τ²/2 − g₃τ³/6 > 0` on `(0, τ_c)`; 0 if there is none.
pub(crate) fn taylor_clearance(g1: f64, g2: f64, g3: f64) -> f64 {
    if g1 < 0.0 || (g1 == 0.0 && g2 <= 0.0) {
        return 0.0;
    }
    let (qa, qb, qc) = (g3 / 6.0, g2 / 2.0, g1);
    if qa == 0.0 {
        return if qb >= 0.0 { f64::INFINITY } else { -qc / qb };
    }
    (qb + (qb * qb + 4.0 * qa * qc).sqrt()) / (2.0 * qa)
}

/// Bracket `(a, b)` with `f(a) ≥ 0 > f(b)` around the earliest sign change in `[lo, hi]`.
fn search<S: Smooth>(
    s: &S,
    lo: &Node<S::At>,
    hi: &Node<S::At>,
    min_width: f64,
    depth: u32,
    budget: &mut Budget,
) -> Result<Option<(f64, f64)>, SearchError> {
    if range_within(s, lo, hi, 0.0, f64::INFINITY) {
        return Ok(None);
    }
    let (t_lo, t_hi) = (S::tau(&lo.at), S::tau(&hi.at));
    let width = t_hi - t_lo;
    if monotone(s, lo, hi) || width <= min_width || depth > 80 {
        return Ok((hi.f < 0.0).then_some((t_lo, t_hi)));
    }
    let mid = budget.node(s, t_lo + 0.5 * width)?;
    match search(s, lo, &mid, min_width, depth + 1, budget)? {
        Some(bracket) => Ok(Some(bracket)),
        None => search(s, &mid, hi, min_width, depth + 1, budget),
    }
}

/// Shrinks a bracket `g(a) ≥ 0 > g(b)` (Illinois regula falsi with a bisection safeguard) and
/// returns its right end: the first representable time at which the function is negative.
pub(crate) fn refine(g: impl Fn(f64) -> f64, mut a: f64, mut b: f64, min_width: f64) -> f64 {
    let mut ga = g(a);
    let mut gb = g(b);
    if gb >= 0.0 {
        return b;
    }
    let mut side = 0;
    for _ in 0..200 {
        if b - a <= min_width {
            break;
        }
        let mut t = (a * gb - b * ga) / (gb - ga);
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
        }
        let gt = g(t);
        if gt < 0.0 {
            b = t;
            gb = gt;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            a = t;
            ga = gt;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
    }
    b
}

/// Newton steps an extremum's refinement may take before it falls back to a root's regula
/// falsi (measured: two or three suffice, `extremum_is_the_closed_forms`).
const NEWTON_STEPS: usize = 8;

/// The extremum of `f` on `[lo, hi]`, where `f'` changes sign once and `m ≤ |f''| ≤ M`
/// (`curvature = (m, M)`, `m > 0`): `(t, f(t))` with `|f(t) − f(t*)| ≤ ε/8·max(|f(t)|, best)`
/// at the extremum `t*`. Newton's method on `f'`, started at the secant root of the end
/// slopes, each step kept inside the bracket the slopes' signs leave (halved where a step
/// would leave it), stops once `t*` is certified near enough:
/// `|t − t*| ≤ d = |f'(t)|/m`, so `|f(t) − f(t*)| ≤ M·d²/2` (docs/model.md, "The physical
/// system"). The value is exact to its evaluation's round-off; the time to `d`, which that
/// tolerance makes about `√ε` of the curvature's time scale, not the few ulps a root gets.
fn extremum<S: Smooth>(
    s: &S,
    lo: &Node<S::At>,
    hi: &Node<S::At>,
    (m, big_m): (f64, f64),
    best: f64,
    min_width: f64,
) -> (f64, f64) {
    let sign = lo.df.signum();
    let (mut a, mut b) = (S::tau(&lo.at), S::tau(&hi.at));
    let (ga, gb) = (lo.df * sign, hi.df * sign);
    let mut t = (a * gb - b * ga) / (gb - ga);
    if !(t > a && t < b) {
        t = 0.5 * (a + b);
    }
    for _ in 0..NEWTON_STEPS {
        let (f, g, g2) = s.eval_second(&s.at(t));
        let d = g.abs() / m;
        if big_m * d * d <= 0.25 * f64::EPSILON * f.abs().max(best) || b - a <= min_width {
            return (t, f);
        }
        if g * sign > 0.0 {
            a = t;
        } else {
            b = t;
        }
        let next = t - g / g2;
        t = if next > a && next < b {
            next
        } else {
            0.5 * (a + b)
        };
    }
    // Not converged (no case met in the tests): the bracket's root to a few ulps, as a
    // switch's.
    let t = refine(|t| s.slope(&s.at(t)) * sign, a, b, min_width);
    (t, s.value(&s.at(t)))
}

/// Peak `|f|` over `[lo, hi]` if it exceeds `best`, with its time; else `(best, NaN)`. The end
/// values count (at a switch they are the one-sided limits). Branch and bound: a stretch is
/// dropped when `|f| ≤ best` is certified on it or it is monotone; where `f'` changes sign once
/// (certified by the bound on `f'''`) the extremum is refined. An error when a value is not
/// finite or the search makes no progress ([`SearchError`]).
pub(crate) fn peak_abs<S: Smooth>(
    s: &S,
    lo: &Node<S::At>,
    hi: &Node<S::At>,
    best: f64,
    dt: f64,
) -> Result<(f64, f64), SearchError> {
    finite(s, lo)?;
    finite(s, hi)?;
    let mut out = (best, f64::NAN);
    for n in [lo, hi] {
        if n.f.abs() > out.0 {
            out = (n.f.abs(), S::tau(&n.at));
        }
    }
    let min_width = 4.0 * f64::EPSILON * dt;
    peak_rec(s, lo, hi, &mut out, min_width, 0, &mut Budget::new())?;
    Ok(out)
}

fn peak_rec<S: Smooth>(
    s: &S,
    lo: &Node<S::At>,
    hi: &Node<S::At>,
    best: &mut (f64, f64),
    min_width: f64,
    depth: u32,
    budget: &mut Budget,
) -> Result<(), SearchError> {
    // Both tests are pure, so their order changes only the cost: the monotone test is the
    // cheaper (one bound, after a sign test) and the one that ends most stretches, where the
    // function grows to a new record at an end and no range can be certified.
    if monotone(s, lo, hi) || range_within(s, lo, hi, -best.0, best.0) {
        return Ok(());
    }
    let (t_lo, t_hi) = (S::tau(&lo.at), S::tau(&hi.at));
    let width = t_hi - t_lo;
    if lo.df * hi.df < 0.0 {
        let jerk = s.bound(3, &lo.at, t_hi);
        let c_lo = s.second(&lo.at);
        if c_lo.abs() > jerk * width {
            // f' is monotone here: its single zero is the only interior extremum, and
            // |c_lo| ∓ jerk·width bound |f''| below and above.
            let curvature = (c_lo.abs() - jerk * width, c_lo.abs() + jerk * width);
            let (t, v) = extremum(s, lo, hi, curvature, best.0, min_width);
            if v.abs() > best.0 {
                *best = (v.abs(), t);
            }
            return Ok(());
        }
    }
    if width <= min_width || depth > 60 {
        return Ok(());
    }
    let mid = budget.node(s, t_lo + 0.5 * width)?;
    if mid.f.abs() > best.0 {
        *best = (mid.f.abs(), S::tau(&mid.at));
    }
    peak_rec(s, lo, &mid, best, min_width, depth + 1, budget)?;
    peak_rec(s, &mid, hi, best, min_width, depth + 1, budget)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f(τ) = a·sin(ωτ) + c`: derivatives bounded by `|a|·ωᵏ`.
    struct Sine {
        a: f64,
        omega: f64,
        c: f64,
    }

    impl Smooth for Sine {
        type At = f64;
        fn at(&self, tau: f64) -> f64 {
            tau
        }
        fn tau(at: &f64) -> f64 {
            *at
        }
        fn eval(&self, t: &f64) -> (f64, f64) {
            let (s, c) = (self.omega * t).sin_cos();
            (self.a * s + self.c, self.a * self.omega * c)
        }
        fn second(&self, t: &f64) -> f64 {
            -self.a * self.omega * self.omega * (self.omega * t).sin()
        }
        fn bound(&self, k: usize, _: &f64, _: f64) -> f64 {
            self.a.abs() * self.omega.powi(k as i32)
        }
    }

    #[test]
    fn first_violation_finds_a_grazing_root_between_samples() {
        // sin(ωτ) + c dips below zero only within 1.3e-5 s of 3π/(2ω), between the samples.
        let c = 1.0 - 1e-9;
        let s = Sine {
            a: 1.0,
            omega: 7.0,
            c,
        };
        let h = 1.0;
        let t = first_violation(&s, &Node::of(&s, 0.0), &Node::of(&s, h), h)
            .unwrap()
            .unwrap();
        // Independent: the first root of sin(ωτ) = −c, by its closed form.
        let exact = (std::f64::consts::PI + c.asin()) / 7.0;
        assert!((t - exact).abs() < 1e-11, "{t} vs {exact}");
        // Coarse sampling at 1000 points misses it altogether.
        let sampled_min = (0..=1000)
            .map(|k| s.eval(&(k as f64 * h / 1000.0)).0)
            .fold(f64::INFINITY, f64::min);
        assert!(sampled_min > 0.0);
    }

    #[test]
    fn peak_abs_matches_the_closed_form_extremum() {
        let s = Sine {
            a: -2.5,
            omega: 3.3,
            c: 0.4,
        };
        let h = 2.0;
        let (p, t) = peak_abs(&s, &Node::of(&s, 0.0), &Node::of(&s, h), 0.0, h).unwrap();
        // |f| is largest where sin = +1 (f = −2.1) or −1 (f = 2.9): at ωτ = 3π/2.
        let t_exact = 1.5 * std::f64::consts::PI / 3.3;
        assert!(
            (p - 2.9).abs() < 1e-14 && (t - t_exact).abs() < 1e-7,
            "{p} at {t}"
        );
    }

    /// An extremum's Newton refinement against the closed form `a + c` of `a·sin(ωτ) + c` at
    /// `ωτ* = π/2`: the value to 2 ulps (the evaluation's own rounding of `a·sin + c` near
    /// the top), the time to `1e-7` rad of phase, in at most three evaluations, on brackets of a
    /// tenth of a period placed anywhere around `τ*` and frequencies over four decades.
    #[test]
    fn extremum_is_the_closed_forms() {
        use std::cell::Cell;
        struct Counted<'a>(&'a Sine, &'a Cell<usize>);
        impl Smooth for Counted<'_> {
            type At = f64;
            fn at(&self, tau: f64) -> f64 {
                tau
            }
            fn tau(at: &f64) -> f64 {
                *at
            }
            fn eval(&self, t: &f64) -> (f64, f64) {
                self.1.set(self.1.get() + 1);
                self.0.eval(t)
            }
            fn second(&self, t: &f64) -> f64 {
                self.0.second(t)
            }
            fn bound(&self, k: usize, lo: &f64, t1: f64) -> f64 {
                self.0.bound(k, lo, t1)
            }
        }
        let mut most = 0;
        for omega in [0.05, 3.3, 40.0, 900.0] {
            let sine = Sine {
                a: 1.7,
                omega,
                c: 0.3,
            };
            let t_star = std::f64::consts::FRAC_PI_2 / omega;
            let width = 0.1 * std::f64::consts::TAU / omega;
            for k in 1..20 {
                let lo = t_star - width * k as f64 / 20.0;
                let hi = lo + width;
                let (n0, n1) = (Node::of(&sine, lo), Node::of(&sine, hi));
                // The bounds `peak_rec` hands over: |f''| at `lo` ∓ the jerk over the bracket.
                let (c_lo, jerk) = (sine.second(&lo).abs(), sine.bound(3, &lo, hi));
                assert!(c_lo > jerk * width);
                let count = Cell::new(0);
                let counted = Counted(&sine, &count);
                let curvature = (c_lo - jerk * width, c_lo + jerk * width);
                let (t, v) = extremum(&counted, &n0, &n1, curvature, 0.0, 4.0 * f64::EPSILON);
                assert!(
                    (v - 2.0).abs() <= 2.0 * f64::EPSILON * 2.0,
                    "ω {omega}, k {k}: {v}"
                );
                assert!((t - t_star).abs() * omega <= 1e-7, "ω {omega}, k {k}: {t}");
                most = most.max(count.get());
            }
        }
        assert!(most <= 3, "{most} evaluations");
    }

    #[test]
    fn a_boundary_start_moving_inward_is_cleared_and_moving_outward_is_not() {
        let inward = Sine {
            a: 1.0,
            omega: 2.0,
            c: 0.0,
        };
        let h = 1.0;
        assert_eq!(
            first_violation(&inward, &Node::of(&inward, 0.0), &Node::of(&inward, h), h),
            Ok(None)
        );
        let outward = Sine {
            a: -1.0,
            omega: 2.0,
            c: 0.0,
        };
        let start = Node::of(&outward, 0.0);
        assert_eq!(
            first_violation(&outward, &start, &Node::of(&outward, h), h),
            Ok(Some(0.0))
        );
    }

    /// A sine whose derivative bounds are as loose as `bound` says: with `1e300` (finite) no
    /// stretch is ever cleared, with `inf` or a NaN value nothing is finite.
    struct Loose {
        sine: Sine,
        bound: f64,
    }

    impl Smooth for Loose {
        type At = f64;
        fn at(&self, tau: f64) -> f64 {
            tau
        }
        fn tau(at: &f64) -> f64 {
            *at
        }
        fn eval(&self, t: &f64) -> (f64, f64) {
            self.sine.eval(t)
        }
        fn second(&self, t: &f64) -> f64 {
            self.sine.second(t)
        }
        fn bound(&self, _: usize, _: &f64, _: f64) -> f64 {
            self.bound
        }
    }

    /// Searches that cannot make progress end with an error; they used to halve every stretch
    /// down to the depth limit, `2^80` evaluations (a record of 1e160 g hung `simulate`). The
    /// test ending is the proof.
    #[test]
    fn searches_that_certify_nothing_end_with_an_error() {
        let sine = |c: f64| Sine {
            a: 1.0,
            omega: 2.0,
            c,
        };
        let h = 1.0;
        for (bound, c, want) in [
            (1e300, 1.5, SearchError::NoProgress),
            (f64::INFINITY, 1.5, SearchError::NoProgress),
            (1.0, f64::NAN, SearchError::NonFinite),
            (1.0, f64::INFINITY, SearchError::NonFinite),
        ] {
            let s = Loose {
                sine: sine(c),
                bound,
            };
            let (lo, hi) = (Node::of(&s, 0.0), Node::of(&s, h));
            assert_eq!(first_violation(&s, &lo, &hi, h), Err(want), "{bound} {c}");
            // The peak search above a level the function never reaches.
            assert_eq!(peak_abs(&s, &lo, &hi, 10.0, h), Err(want), "{bound} {c}");
        }
        // A start on the boundary whose jerk bound is not finite.
        let s = Loose {
            sine: sine(0.0),
            bound: f64::INFINITY,
        };
        let (lo, hi) = (Node::of(&s, 0.0), Node::of(&s, h));
        assert_eq!(
            first_violation(&s, &lo, &hi, h),
            Err(SearchError::NonFinite)
        );
        // Bounds that do certify: the same sine with its true bounds is cleared at once.
        let s = Loose {
            sine: sine(1.5),
            bound: 16.0,
        };
        let (lo, hi) = (Node::of(&s, 0.0), Node::of(&s, h));
        assert_eq!(first_violation(&s, &lo, &hi, h), Ok(None));
    }
}
