//! The case grid of the study: its axes and how a flat case index maps onto them.
//!
//! A grid is the outer product of the structure periods `T_p`, one list of mass ratios per block
//! (`α_1 … α_n`, bottom first) and one list of kinetic friction coefficients per interface
//! (`μ_1 … μ_n`, interface 1 first). Stored arrays use the axis order
//! `[T_p, alpha_1 … alpha_n, mu_1 … mu_n]` (with `motion` in front in `sweep.h5`), row-major, the
//! last `μ` fastest. A *work unit* is one `T_p` (under one motion): all `α` and `μ` combinations.
//!
//! Pure data: no physics, no files. A point of the grid is a [`Case`]; the study's physics
//! settings (damping, static friction) live in [`crate::study::physics::Physics`], the file
//! layouts in [`crate::store`].

use crate::case::Case;

/// A point outside the grid's range in one of its dimensions.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{dim} = {value} lies outside the grid's {lo} … {hi}")]
pub struct OutsideGrid {
    pub dim: String,
    pub value: f64,
    pub lo: f64,
    pub hi: f64,
}

/// `from, from + step, …` up to `to` (inclusive within 1e-9 of a step), each value rounded to
/// 12 significant digits so that `0.1 + 2·0.1` reads back as `0.3`; at most `max` values,
/// counted before anything is allocated. The one expansion of a `{from, to, step}` range, for
/// the study grid and for period lists alike.
pub fn linear_range(from: f64, to: f64, step: f64, max: usize) -> Result<Vec<f64>, String> {
    if !(from.is_finite() && to.is_finite() && step.is_finite() && step > 0.0 && to >= from) {
        return Err(format!(
            "range from {from} to {to} by {step}: needs finite values, step > 0 and to ≥ from"
        ));
    }
    let steps = ((to - from) / step + 1e-9).floor();
    if steps + 1.0 > max as f64 {
        return Err(format!(
            "range from {from} to {to} by {step} has {:.0} values; at most {max}",
            steps + 1.0
        ));
    }
    Ok((0..=steps as usize)
        .map(|k| {
            let v = from + step * k as f64;
            format!("{v:.12e}").parse().unwrap_or(v)
        })
        .collect())
}

/// The grid's axes.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Grid {
    /// Periods of the bare structure `T_p`, s, increasing.
    pub periods_s: Vec<f64>,
    /// Mass ratios `α_i = m_i/m_p`, one list per block, bottom first.
    pub alpha: Vec<Vec<f64>>,
    /// Kinetic friction coefficients, one list per interface, interface 1 first.
    pub mu: Vec<Vec<f64>>,
}

impl Grid {
    pub fn blocks(&self) -> usize {
        self.alpha.len()
    }

    /// Sizes of the case dimensions `alpha_1 … alpha_n, mu_1 … mu_n`.
    pub fn case_shape(&self) -> Vec<usize> {
        self.alpha.iter().chain(&self.mu).map(|v| v.len()).collect()
    }

    /// Shape `[T_p, alpha_1 … alpha_n, mu_1 … mu_n]` of a per-case array.
    pub fn shape(&self) -> Vec<usize> {
        let mut s = vec![self.periods_s.len()];
        s.extend(self.case_shape());
        s
    }

    /// Names of the dimensions of [`Grid::shape`], as stored.
    pub fn dim_names(&self) -> Vec<String> {
        let n = self.blocks();
        std::iter::once("T_p".to_string())
            .chain((1..=n).map(|i| format!("alpha_{i}")))
            .chain((1..=n).map(|i| format!("mu_{i}")))
            .collect()
    }

    /// Cases in one work unit.
    pub fn cases_per_unit(&self) -> usize {
        self.case_shape().iter().product()
    }

    /// Cases over all periods.
    pub fn cases(&self) -> usize {
        self.periods_s.len() * self.cases_per_unit()
    }

    /// The case at flat `index` over `[T_p][case]`.
    pub fn case(&self, index: usize) -> Case {
        let per = self.cases_per_unit();
        let (alpha, mu) = self.stack(index % per);
        Case {
            period_s: self.periods_s[index / per],
            alpha,
            mu,
        }
    }

    /// The stack `(α, μ)` of case `index` within a unit (row-major over `case_shape`, the last
    /// `μ` fastest).
    pub fn stack(&self, mut index: usize) -> (Vec<f64>, Vec<f64>) {
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

/// The floor a building case's stack stands on (`grid.stack_floor`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StackFloor {
    /// Floor `j`, `1 … N` (1 the lowest).
    Floor(usize),
    /// The top floor `N`, whatever `N` is.
    Roof,
    /// The floor at mid-height, `⌈N/2⌉` (floor 2 of 3, 3 of 6, 5 of 10, 10 of 20; floor 1 of 1),
    /// whatever `N` is.
    Mid,
    /// Every floor its own stack, each with the case's `α`, `μ` (the warehouse case).
    All,
}

impl StackFloor {
    /// The floors named by a word rather than a number, in the order the page offers them.
    pub const NAMED: [StackFloor; 3] = [StackFloor::Roof, StackFloor::Mid, StackFloor::All];

    /// The floors (1-based, lowest first) carrying a stack in a building of `storeys` storeys.
    pub fn floors(self, storeys: usize) -> Vec<usize> {
        match self {
            StackFloor::Floor(f) => vec![f],
            StackFloor::Roof => vec![storeys],
            StackFloor::Mid => vec![storeys.div_ceil(2)],
            StackFloor::All => (1..=storeys).collect(),
        }
    }
}

/// `3`, `roof`, `mid`, `all`: as the config writes it and the `stack_floor` coordinate stores it.
impl std::fmt::Display for StackFloor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StackFloor::Floor(j) => write!(f, "{j}"),
            StackFloor::Roof => f.write_str("roof"),
            StackFloor::Mid => f.write_str("mid"),
            StackFloor::All => f.write_str("all"),
        }
    }
}

impl std::str::FromStr for StackFloor {
    type Err = String;

    /// The inverse of `Display`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "roof" => Ok(StackFloor::Roof),
            "mid" => Ok(StackFloor::Mid),
            "all" => Ok(StackFloor::All),
            _ => (s.parse().ok())
                .filter(|&j| j >= 1)
                .map(StackFloor::Floor)
                .ok_or_else(|| format!("`{s}` is not a floor, `roof`, `mid` or `all`")),
        }
    }
}

/// The building axes of a building study, outside the case grid: storey counts `N` and the
/// floors the stack stands on. Stored arrays put them in front of the case dimensions,
/// `[storeys, stack_floor, T_p, alpha…, mu…]`, row-major; a *frame* is one pair of them.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildingAxes {
    /// Storey counts, increasing.
    pub storeys: Vec<usize>,
    pub stack_floor: Vec<StackFloor>,
}

impl BuildingAxes {
    /// Names of the two dimensions, as stored.
    pub const DIMS: [&'static str; 2] = ["storeys", "stack_floor"];

    /// `[storeys, stack_floor]` sizes.
    pub fn shape(&self) -> [usize; 2] {
        [self.storeys.len(), self.stack_floor.len()]
    }

    /// Frames: every `(storeys, stack_floor)` pair.
    pub fn frame_count(&self) -> usize {
        self.storeys.len() * self.stack_floor.len()
    }

    /// `N_max`: the largest storey count, the length of the stored per-floor axes.
    pub fn max_storeys(&self) -> usize {
        self.storeys.iter().copied().max().unwrap_or(0)
    }

    /// Frame `index` (row-major, the stack floor fastest).
    pub fn frame(&self, index: usize) -> (usize, StackFloor) {
        let per = self.stack_floor.len();
        (self.storeys[index / per], self.stack_floor[index % per])
    }
}

impl Grid {
    /// The multilinear interpolation at `point` (`[T_p, α_1 … α_n, μ_1 … μ_n]`, the order of
    /// [`Grid::shape`]) of `values`, one per case in flat order: in each dimension between the
    /// two bracketing grid values (exact at grid values; a dimension of one value must be met
    /// exactly). `Ok(None)` when a corner that carries weight is NaN.
    pub fn interpolate(&self, values: &[f64], point: &[f64]) -> Result<Option<f64>, OutsideGrid> {
        let axes: Vec<&[f64]> = std::iter::once(self.periods_s.as_slice())
            .chain(self.alpha.iter().map(Vec::as_slice))
            .chain(self.mu.iter().map(Vec::as_slice))
            .collect();
        let names = self.dim_names();
        // Per dimension: the lower index and the weight of the upper one.
        let mut brackets = Vec::with_capacity(axes.len());
        for ((axis, &x), dim) in axes.iter().zip(point).zip(&names) {
            let (lo, hi) = (axis[0], axis[axis.len() - 1]);
            if !(lo..=hi).contains(&x) {
                return Err(OutsideGrid {
                    dim: dim.clone(),
                    value: x,
                    lo,
                    hi,
                });
            }
            let i = axis
                .partition_point(|&v| v <= x)
                .clamp(1, axis.len().max(2) - 1)
                - 1;
            if axis.len() == 1 {
                brackets.push((0, 0.0));
            } else {
                let w = (x - axis[i]) / (axis[i + 1] - axis[i]);
                brackets.push((i, w));
            }
        }
        let shape = self.shape();
        let mut total = 0.0;
        for corner in 0..1usize << axes.len() {
            let mut weight = 1.0;
            let mut flat = 0;
            for (d, &(i, w)) in brackets.iter().enumerate() {
                let up = corner >> d & 1 == 1;
                weight *= if up { w } else { 1.0 - w };
                flat = flat * shape[d] + i + usize::from(up);
            }
            if weight == 0.0 {
                continue;
            }
            let v = values[flat];
            if v.is_nan() {
                return Ok(None);
            }
            total += weight * v;
        }
        Ok(Some(total))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_exact_for_multilinear_data_and_refuses_outside() {
        // A multilinear function of the five coordinates is reproduced exactly (to round-off)
        // anywhere inside; the grid values themselves exactly.
        let g = Grid {
            periods_s: vec![0.1, 0.5, 1.0, 2.0],
            alpha: vec![vec![0.1, 0.5, 1.0], vec![0.5, 1.0]],
            mu: vec![vec![0.05, 0.3], vec![0.1, 0.2, 0.7]],
        };
        let f = |p: &[f64]| {
            1.0 + 2.0 * p[0] - 0.5 * p[1] + 0.3 * p[2] * p[0] + p[3] * p[4]
                - 0.7 * p[0] * p[1] * p[4]
        };
        let values: Vec<f64> = (0..g.cases())
            .map(|c| {
                let case = g.case(c);
                let mut p = vec![case.period_s];
                p.extend(&case.alpha);
                p.extend(&case.mu);
                f(&p)
            })
            .collect();
        for p in [
            [0.7, 0.3, 0.75, 0.1, 0.4],
            [0.1, 0.1, 0.5, 0.05, 0.1],
            [2.0, 1.0, 1.0, 0.3, 0.7],
            [1.3, 0.9, 0.6, 0.2, 0.15],
        ] {
            let got = g.interpolate(&values, &p).unwrap().unwrap();
            assert!((got - f(&p)).abs() < 1e-13, "{p:?}: {got} vs {}", f(&p));
        }
        let e = g
            .interpolate(&values, &[2.5, 0.5, 0.5, 0.1, 0.1])
            .unwrap_err();
        assert_eq!(e.to_string(), "T_p = 2.5 lies outside the grid's 0.1 … 2");
        // A NaN corner with weight: no value; with zero weight: ignored.
        let mut v2 = values.clone();
        v2[0] = f64::NAN;
        assert_eq!(
            g.interpolate(&v2, &[0.12, 0.1, 0.5, 0.05, 0.1]).unwrap(),
            None
        );
        assert!(
            g.interpolate(&v2, &[0.5, 0.1, 0.5, 0.05, 0.1])
                .unwrap()
                .is_some()
        );
    }

    #[test]
    fn ranges_round_and_refuse_before_allocating() {
        assert_eq!(
            linear_range(0.1, 0.5, 0.1, 100).unwrap(),
            vec![0.1, 0.2, 0.3, 0.4, 0.5]
        );
        assert_eq!(linear_range(1.0, 1.0, 0.5, 100).unwrap(), vec![1.0]);
        let e = linear_range(0.0, 1e12, 1e-6, 100_000).unwrap_err();
        assert!(e.contains("values; at most 100000"), "{e}");
        assert!(linear_range(1.0, 0.0, 0.1, 10).is_err());
        assert!(linear_range(0.0, 1.0, 0.0, 10).is_err());
        assert!(linear_range(0.0, f64::INFINITY, 1.0, 10).is_err());
    }

    #[test]
    fn flat_index_is_row_major_with_the_last_mu_fastest() {
        let g = Grid {
            periods_s: vec![0.5, 1.0],
            alpha: vec![vec![0.1, 0.5], vec![1.0]],
            mu: vec![vec![0.2], vec![0.05, 0.1, 0.3]],
        };
        assert_eq!(g.shape(), vec![2, 2, 1, 1, 3]);
        assert_eq!(g.cases(), 12);
        assert_eq!(g.dim_names(), ["T_p", "alpha_1", "alpha_2", "mu_1", "mu_2"]);
        // Index 10 = T_p 1 (6 per unit), then case 4 = alpha_1 index 1, mu_2 index 1.
        let c = g.case(10);
        assert_eq!(c.period_s, 1.0);
        assert_eq!(c.alpha, vec![0.5, 1.0]);
        assert_eq!(c.mu, vec![0.2, 0.1]);
        assert_eq!(c.alpha_total(), 1.5);
    }
}
