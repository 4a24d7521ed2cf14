//! Hunt & fill tracing (Vamvatsikos & Cornell 2002, "Incremental dynamic analysis", Earthquake
//! Engng Struct. Dyn. 31, Section 5): the intensities at which one record is run.
//!
//! 1. **Hunt:** up from `first_sa_g` with a step that grows by `step_increment_sa_g` after every
//!    run, until a run collapses or the cap is run (the last step is cut to land on the cap).
//! 2. **Bracket:** `bracket_runs` bisections between the highest non-collapsing and the lowest
//!    collapsing intensity (only when the hunt found a collapse).
//! 3. **Fill:** `fill_runs` runs, each at the middle of the widest gap between the non-collapsing
//!    intensities (zero included); ties go to the lowest gap.
//!
//! Every non-collapsing run then lies below every collapsing one (bisection keeps the bracket),
//! so the collapse capacity is bracketed by [`Trace::capacity_sa_g`].

use serde::{Deserialize, Serialize};

/// The tracing parameters, intensities in g.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HuntFill {
    /// Intensity of the first run and the first step.
    pub first_sa_g: f64,
    /// Added to the step after every hunting run.
    pub step_increment_sa_g: f64,
    /// Bisections of the collapse bracket.
    pub bracket_runs: usize,
    /// Runs filling the widest gaps below the capacity.
    pub fill_runs: usize,
    /// Highest intensity run.
    pub cap_sa_g: f64,
}

impl HuntFill {
    /// Hunting runs when nothing collapses: the most the hunt can take.
    pub fn max_hunt_runs(&self) -> usize {
        let mut sa = self.first_sa_g;
        let mut step = self.first_sa_g;
        let mut n = 1;
        while sa < self.cap_sa_g {
            step += self.step_increment_sa_g;
            sa = (sa + step).min(self.cap_sa_g);
            n += 1;
        }
        n
    }

    /// The most runs one trace takes.
    pub fn max_runs(&self) -> usize {
        self.max_hunt_runs() + self.bracket_runs + self.fill_runs
    }
}

/// One run of a trace.
#[derive(Debug, Clone, PartialEq)]
pub struct Run<D> {
    pub sa_g: f64,
    pub demand: D,
    pub collapsed: bool,
}

/// The runs of one trace, in the order they were made.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace<D> {
    pub runs: Vec<Run<D>>,
}

impl<D> Trace<D> {
    /// `(highest non-collapsing, lowest collapsing)` intensity, `None` without a collapse.
    pub fn capacity_sa_g(&self) -> Option<(f64, f64)> {
        let hi = self
            .runs
            .iter()
            .filter(|r| r.collapsed)
            .map(|r| r.sa_g)
            .fold(f64::INFINITY, f64::min);
        let lo = self
            .runs
            .iter()
            .filter(|r| !r.collapsed)
            .map(|r| r.sa_g)
            .fold(0.0, f64::max);
        hi.is_finite().then_some((lo, hi))
    }
}

/// Traces one record: `run(sa_g)` returns the demand at that intensity and whether it counts
/// as collapse. Deterministic: the intensities depend only on `p` and the collapse outcomes.
pub fn hunt_fill<D, E>(
    p: &HuntFill,
    mut run: impl FnMut(f64) -> Result<(D, bool), E>,
) -> Result<Trace<D>, E> {
    let mut runs: Vec<Run<D>> = Vec::new();
    let mut one = |sa_g: f64, runs: &mut Vec<Run<D>>| -> Result<bool, E> {
        let (demand, collapsed) = run(sa_g)?;
        runs.push(Run {
            sa_g,
            demand,
            collapsed,
        });
        Ok(collapsed)
    };
    let mut sa = p.first_sa_g.min(p.cap_sa_g);
    let mut step = p.first_sa_g;
    loop {
        if one(sa, &mut runs)? || sa >= p.cap_sa_g {
            break;
        }
        step += p.step_increment_sa_g;
        sa = (sa + step).min(p.cap_sa_g);
    }
    let below = |runs: &[Run<D>]| -> (f64, f64) {
        let lo = runs
            .iter()
            .filter(|r| !r.collapsed)
            .map(|r| r.sa_g)
            .fold(0.0, f64::max);
        let hi = runs
            .iter()
            .filter(|r| r.collapsed)
            .map(|r| r.sa_g)
            .fold(f64::INFINITY, f64::min);
        (lo, hi)
    };
    if runs.last().is_some_and(|r| r.collapsed) {
        for _ in 0..p.bracket_runs {
            let (lo, hi) = below(&runs);
            one(0.5 * (lo + hi), &mut runs)?;
        }
    }
    for _ in 0..p.fill_runs {
        let mut points: Vec<f64> = std::iter::once(0.0)
            .chain(runs.iter().filter(|r| !r.collapsed).map(|r| r.sa_g))
            .collect();
        points.sort_by(f64::total_cmp);
        let Some((a, b)) = points.windows(2).map(|w| (w[0], w[1])).fold(
            None,
            |best: Option<(f64, f64)>, (a, b)| match best {
                Some((p, q)) if q - p >= b - a => best,
                _ => Some((a, b)),
            },
        ) else {
            break;
        };
        one(0.5 * (a + b), &mut runs)?;
    }
    Ok(Trace { runs })
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: HuntFill = HuntFill {
        first_sa_g: 0.1,
        step_increment_sa_g: 0.05,
        bracket_runs: 6,
        fill_runs: 5,
        cap_sa_g: 5.0,
    };

    fn sas(t: &Trace<f64>) -> Vec<f64> {
        t.runs.iter().map(|r| r.sa_g).collect()
    }

    #[test]
    fn hunt_steps_grow_and_the_bracket_closes_on_a_known_capacity() {
        // Demand Sa², collapse from 1.234 g on: the hunt runs 0.1, 0.25, 0.45, 0.7, 1.0, 1.35.
        let t = hunt_fill(&P, |sa| Ok::<_, ()>((sa * sa, sa >= 1.234))).unwrap();
        let s = sas(&t);
        let hunt = [0.1, 0.25, 0.45, 0.7, 1.0, 1.35];
        for (got, want) in s.iter().zip(hunt) {
            assert!((got - want).abs() < 1e-12, "{s:?}");
        }
        assert_eq!(s.len(), hunt.len() + P.bracket_runs + P.fill_runs);
        let (lo, hi) = t.capacity_sa_g().unwrap();
        assert!(lo < 1.234 && 1.234 <= hi, "{lo} {hi}");
        // Six halvings of the hunt's last bracket [1.0, 1.35].
        assert!((hi - lo - 0.35 / 64.0).abs() < 1e-12, "{lo} {hi}");
        for r in &t.runs {
            assert_eq!(r.collapsed, r.sa_g >= 1.234);
            assert_eq!(r.demand, r.sa_g * r.sa_g);
        }
        // The fills go to the widest gaps below the capacity, never above it.
        let fills = &s[hunt.len() + P.bracket_runs..];
        assert!(fills.iter().all(|&x| x < lo), "{fills:?}");
        // After the fills no gap below the capacity is wider than the widest hunting step that
        // was split: [0.7, 1.0] and [0.45, 0.7] and [1.0, lo] were the widest.
        let mut pts: Vec<f64> = std::iter::once(0.0)
            .chain(t.runs.iter().filter(|r| !r.collapsed).map(|r| r.sa_g))
            .collect();
        pts.sort_by(f64::total_cmp);
        let widest = pts.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        assert!(widest <= 0.25 + 1e-12, "{pts:?}");
    }

    #[test]
    fn without_collapse_the_hunt_ends_on_the_cap_and_fills_the_widest_gaps() {
        let p = HuntFill { cap_sa_g: 1.2, ..P };
        let t = hunt_fill(&p, |sa| Ok::<_, ()>((sa, false))).unwrap();
        let s = sas(&t);
        assert_eq!(&s[..6], &[0.1, 0.25, 0.45, 0.7, 1.0, 1.2]);
        assert_eq!(p.max_hunt_runs(), 6);
        assert!(t.capacity_sa_g().is_none());
        // Widest gap 0.3 ([0.7, 1.0]), then 0.25 ([0.45, 0.7]), 0.2 ([0.25, 0.45], [1.0, 1.2]:
        // the lower first), …
        assert!(
            (s[6] - 0.85).abs() < 1e-12 && (s[7] - 0.575).abs() < 1e-12,
            "{s:?}"
        );
        assert!((s[8] - 0.35).abs() < 1e-12, "{s:?}");
        assert_eq!(s.len(), 6 + p.fill_runs);
    }

    #[test]
    fn a_collapse_at_the_first_run_brackets_down_from_it() {
        let t = hunt_fill(&P, |sa| Ok::<_, ()>((sa, sa > 0.03))).unwrap();
        let (lo, hi) = t.capacity_sa_g().unwrap();
        assert!(lo <= 0.03 && 0.03 < hi && hi - lo <= 0.1 / 64.0 + 1e-15);
    }
}
