//! Whether a fitted form stays physical beyond the data: on a box a fraction beyond the grid in
//! every feature, `T_new` must be finite and inside `[½·T_p, 1.5·T_rigid]` (issue 11, item 4).
//!
//! The box is `[(1 − m)·min, (1 + m)·max]` for each feature, `m` the margin (25 %): a
//! multiplicative margin keeps every period, friction coefficient and mass ratio positive
//! (an additive 25 % of the range would take `T_p` below zero on the paper grid,
//! 0.1 − 0.25·1.9 s). It is sampled at its corners (all `2^k` of them for `k ≤ 12` features,
//! otherwise 4,096 chosen by the quasi-random points) and at quasi-random points of the Halton
//! sequence (bases the first `k` primes), which fill the box evenly and are the same on every
//! run. `T_rigid = T_p·√(1 + Σα)` (paper Eqs. 10–13).

use super::{Fitted, Form, Sample};
use serde::{Deserialize, Serialize};

/// The margin of the box beyond the grid, as a fraction of each feature's extreme values.
pub const BOX_MARGIN: f64 = 0.25;

/// Quasi-random points sampled inside the box (besides its corners).
pub const BOX_POINTS: usize = 4096;

/// The physical band the check asks for: `T_new ≥ LOWER·T_p` …
pub const LOWER_T_P: f64 = 0.5;
/// … and `T_new ≤ UPPER·T_rigid`.
pub const UPPER_T_RIGID: f64 = 1.5;

/// A box in feature space, `(T_p, μ_1 … μ_n, α_1 … α_n)` and, for a building study,
/// `building` features after them ([`crate::fit::BuildingFeatures`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignBox {
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// Features after the stack's (a building's `N`, `z_stack`).
    pub building: usize,
}

impl DesignBox {
    /// The box `[(1 − margin)·min, (1 + margin)·max]` around features whose extreme values
    /// are `ranges` (`(min, max)` each).
    pub fn beyond(ranges: &[(f64, f64)], margin: f64) -> Self {
        Self {
            lower: ranges.iter().map(|r| (1.0 - margin) * r.0).collect(),
            upper: ranges.iter().map(|r| (1.0 + margin) * r.1).collect(),
            building: 0,
        }
    }

    /// The box around the extreme features of `data`.
    pub fn around(data: &[Sample], margin: f64) -> Self {
        let k = data.first().map_or(0, |s| s.x.len());
        let ranges: Vec<(f64, f64)> = (0..k)
            .map(|j| {
                data.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                        (lo.min(s.x[j]), hi.max(s.x[j]))
                    })
            })
            .collect();
        Self::beyond(&ranges, margin)
    }

    fn at(&self, unit: &[f64]) -> Vec<f64> {
        unit.iter()
            .zip(self.lower.iter().zip(&self.upper))
            .map(|(u, (lo, hi))| lo + u * (hi - lo))
            .collect()
    }

    /// The sample points: corners, then `quasi` Halton points.
    pub fn points(&self, quasi: usize) -> Vec<Vec<f64>> {
        let k = self.lower.len();
        let mut v = Vec::new();
        if k <= 12 {
            for c in 0..1usize << k {
                let unit: Vec<f64> = (0..k).map(|j| ((c >> j) & 1) as f64).collect();
                v.push(self.at(&unit));
            }
        } else {
            for i in 1..=4096 {
                let unit: Vec<f64> = halton(i, k).iter().map(|u| u.round()).collect();
                v.push(self.at(&unit));
            }
        }
        for i in 1..=quasi {
            v.push(self.at(&halton(i, k)));
        }
        v
    }
}

/// The first 29 primes (bases of the Halton sequence; 29 = features of the largest stack,
/// `1 + 2·MAX_BLOCKS`).
const PRIMES: [u64; 29] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
    101, 103, 107, 109,
];

/// The radical inverse of `i` in base `b`: `i`'s base-`b` digits mirrored about the point.
fn radical_inverse(mut i: u64, b: u64) -> f64 {
    let (mut inv, mut f) = (0.0, 1.0 / b as f64);
    while i > 0 {
        inv += (i % b) as f64 * f;
        i /= b;
        f /= b as f64;
    }
    inv
}

/// Point `i` of the `k`-dimensional Halton sequence, in `[0, 1)^k` (`k ≤ 29`; beyond, the
/// bases repeat).
pub fn halton(i: usize, k: usize) -> Vec<f64> {
    (0..k)
        .map(|j| radical_inverse(i as u64, PRIMES[j % PRIMES.len()]))
        .collect()
}

/// The result of the box check of one fitted form.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct BoxCheck {
    /// Margin beyond the grid (fraction).
    pub margin: f64,
    /// Points checked (corners and quasi-random).
    pub points: usize,
    /// Points where `T_new` is not finite.
    pub non_finite: usize,
    /// Points where `T_new < ½·T_p` or `T_new > 1.5·T_rigid`.
    pub outside: usize,
    /// Smallest `T_new/T_p` over the finite points.
    pub min_t_new_over_t_p: f64,
    /// Largest `T_new/T_rigid` over the finite points.
    pub max_t_new_over_t_rigid: f64,
    /// The features of the first failing point, if any.
    pub first_failure: Option<Vec<f64>>,
    pub passed: bool,
}

/// Checks `fitted` on `bx` with `quasi` quasi-random points besides the corners.
///
/// For a building, `T_rigid` at a point is taken as `T_1·√(1 + Σα)`: the first-mode period
/// with every floor's mass scaled by `1 + Σα`, an upper bound of the period with the stack on
/// any of its floors (Rayleigh's quotient: that mass matrix exceeds the loaded one), and the
/// band's upper limit with it.
///
/// A [`Form::Fraction`] (a building's `λ`) must stay in `[0, 1]`; its check's
/// `min_t_new_over_t_p` and `max_t_new_over_t_rigid` then hold the smallest and largest `λ`.
pub fn check_box(fitted: &Fitted, bx: &DesignBox, quasi: usize, margin: f64) -> BoxCheck {
    let k = bx.lower.len();
    let blocks = k.saturating_sub(1 + bx.building) / 2;
    let mut c = BoxCheck {
        margin,
        min_t_new_over_t_p: f64::INFINITY,
        max_t_new_over_t_rigid: f64::NEG_INFINITY,
        ..BoxCheck::default()
    };
    for x in bx.points(quasi) {
        c.points += 1;
        let t_p = x[0];
        let alpha: f64 = x[1 + blocks..1 + 2 * blocks].iter().sum();
        let t_rigid = t_p * (1.0 + alpha).sqrt();
        let s = Sample {
            x,
            t_rigid_s: t_rigid,
            t_new_s: f64::NAN,
        };
        let t = fitted.predict(&s);
        let fail = if !t.is_finite() {
            c.non_finite += 1;
            true
        } else if fitted.form == Form::Fraction {
            c.min_t_new_over_t_p = c.min_t_new_over_t_p.min(t);
            c.max_t_new_over_t_rigid = c.max_t_new_over_t_rigid.max(t);
            let out = !(0.0..=1.0).contains(&t);
            c.outside += usize::from(out);
            out
        } else {
            c.min_t_new_over_t_p = c.min_t_new_over_t_p.min(t / t_p);
            c.max_t_new_over_t_rigid = c.max_t_new_over_t_rigid.max(t / t_rigid);
            let out = t < LOWER_T_P * t_p || t > UPPER_T_RIGID * t_rigid;
            c.outside += usize::from(out);
            out
        };
        if fail && c.first_failure.is_none() {
            c.first_failure = Some(s.x);
        }
    }
    c.passed = c.non_finite == 0 && c.outside == 0;
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_is_the_radical_inverse() {
        // Base 2: 1/2, 1/4, 3/4, 1/8; base 3: 1/3, 2/3, 1/9, 4/9.
        let b2: Vec<f64> = (1..=4).map(|i| halton(i, 2)[0]).collect();
        let b3: Vec<f64> = (1..=4).map(|i| halton(i, 2)[1]).collect();
        assert_eq!(b2, [0.5, 0.25, 0.75, 0.125]);
        for (a, b) in b3.iter().zip([1.0 / 3.0, 2.0 / 3.0, 1.0 / 9.0, 4.0 / 9.0]) {
            assert!((a - b).abs() < 1e-15);
        }
    }

    #[test]
    fn box_points_cover_corners_and_inside() {
        let bx = DesignBox::beyond(&[(0.1, 2.0), (0.05, 0.6), (0.1, 1.0)], 0.25);
        assert!((bx.lower[0] - 0.075).abs() < 1e-15 && (bx.upper[0] - 2.5).abs() < 1e-15);
        let pts = bx.points(100);
        assert_eq!(pts.len(), 8 + 100);
        assert!(pts.contains(&bx.lower) && pts.contains(&bx.upper));
        for p in &pts {
            for ((v, lo), hi) in p.iter().zip(&bx.lower).zip(&bx.upper) {
                assert!(v >= lo && v <= hi);
            }
        }
    }
}
