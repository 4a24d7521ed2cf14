//! Whether a stack leaves the sliding-only model: the rigid-block rocking criterion on every
//! interface (docs/model.md, "Rocking: when a case leaves the model").
//!
//! The blocks of a stack share one footprint width `w` and stand centred on each other; block
//! `j` is `h_j = w/r_j` tall, `r_j` its width-to-height ratio (`aspect`). The blocks above
//! interface `i` (block `i` and all on it) stay flat while the contact's resultant at interface
//! `i` lies within block `i`'s base, which by the moment balance of those blocks about the base's
//! edge is `|Σ_{j≥i} m_j·a_j·z_ij| ≤ g·(w/2)·Σ_{j≥i} m_j`, `a_j` block `j`'s absolute
//! acceleration and `z_ij` the height of its centre above interface `i`. Divided through, the
//! check is `|Σ_{j≥i} w_ij·a_j| ≤ g` with the weights `w_ij = 2·m_j·(z_ij/w) / Σ_{k≥i} m_k`.
//! One block: `w = 1/r`, so `|a| ≤ g·b/h`; a stuck group: `|a| ≤ g·r_group`, `r_group =
//! 1/Σ_j w_ij` (the width over twice the group's centre height).

use super::model::{G, ModelError};
use serde::Serialize;

/// The rocking check of one stack: per interface, the weights of the blocks above it.
#[derive(Debug, Clone, PartialEq)]
pub struct Rocking {
    /// `weights[i][j − i]` = `w_ij` (1/1, so `Σ w·a` is an acceleration), interface `i`
    /// (0-based, under block `i`) and block `j ≥ i`.
    weights: Vec<Vec<f64>>,
    /// The ratios as given, bottom block first.
    aspect: Vec<f64>,
}

/// Where and when a stack would first start to rock.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RockingOnset {
    /// The block whose base the rocking group pivots on, 1 = the bottom block.
    pub block: usize,
    /// Time from the record's start, s.
    pub time_s: f64,
}

impl Rocking {
    /// The check of a stack of blocks of masses `masses_kg` (bottom first) and width-to-height
    /// ratios `aspect`; each ratio must be finite and > 0, one per block.
    pub fn new(masses_kg: &[f64], aspect: &[f64]) -> Result<Self, ModelError> {
        let n = masses_kg.len();
        if aspect.len() != n {
            return Err(ModelError::Count {
                what: "aspect",
                got: aspect.len(),
                expected: n,
            });
        }
        if let Some((i, &value)) =
            (aspect.iter().enumerate()).find(|(_, r)| !(r.is_finite() && **r > 0.0))
        {
            return Err(ModelError::Aspect {
                index: i + 1,
                value,
            });
        }
        // Heights over the common width: h_j/w = 1/r_j.
        let weights = (0..n)
            .map(|i| {
                let mass: f64 = masses_kg[i..].iter().sum();
                let mut base = 0.0;
                (i..n)
                    .map(|j| {
                        let centre = base + 0.5 / aspect[j];
                        base += 1.0 / aspect[j];
                        2.0 * masses_kg[j] * centre / mass
                    })
                    .collect()
            })
            .collect();
        Ok(Self {
            weights,
            aspect: aspect.to_vec(),
        })
    }

    /// Width over height of each block, bottom first.
    pub fn aspect(&self) -> &[f64] {
        &self.aspect
    }

    /// Number of blocks.
    pub fn blocks(&self) -> usize {
        self.weights.len()
    }

    /// The weights `w_ij` of the blocks `j = i, i+1, …` on interface `i` (0-based).
    pub fn weights(&self, interface: usize) -> &[f64] {
        &self.weights[interface]
    }

    /// The width-to-height ratio of the group above `interface` moving as one body:
    /// `1/Σ_j w_ij` (a single block's own ratio).
    pub fn group_aspect(&self, interface: usize) -> f64 {
        1.0 / self.weights[interface].iter().sum::<f64>()
    }

    /// The lowest interface (0-based) whose group rocks under the blocks' absolute
    /// accelerations `accel_mps2` (bottom first): `|Σ_j w_ij·a_j| > g`.
    pub fn rocking_interface(&self, accel_mps2: &[f64]) -> Option<usize> {
        (0..self.blocks()).find(|&i| self.demand(i, &accel_mps2[i..]).abs() > G)
    }

    /// Interface `interface`'s weights split between the blocks that move with their support's
    /// acceleration (`free_accel_mps2(j)` is `None` for block `j`, 0-based) and those that move
    /// at a constant one (`Some(a)`): `(Σ w_ij over the first, Σ w_ij·a_j over the second)`, so
    /// that `Σ_j w_ij·a_j = first·a_support + second` (what the exact integrators search).
    pub fn split(
        &self,
        interface: usize,
        free_accel_mps2: impl Fn(usize) -> Option<f64>,
    ) -> (f64, f64) {
        let (mut on_support, mut constant) = (0.0, 0.0);
        for (k, w) in self.weights[interface].iter().enumerate() {
            match free_accel_mps2(interface + k) {
                None => on_support += w,
                Some(a) => constant += w * a,
            }
        }
        (on_support, constant)
    }

    /// Whether the stack rocks when every block moves at one absolute acceleration of peak
    /// `peak_mps2` (stuck to its support, or sliding as one body): some interface has
    /// `Σ_j w_ij·|a| > g`, written as the integrators' switching function `g − Σw·|a| < 0`.
    pub fn rocks_as_one(&self, peak_mps2: f64) -> bool {
        (0..self.blocks()).any(|i| G - self.split(i, |_| None).0 * peak_mps2 < 0.0)
    }

    /// `Σ_j w_ij·a_j`, m/s², `accel_above` the accelerations of blocks `i, i+1, …`.
    pub fn demand(&self, interface: usize, accel_above: &[f64]) -> f64 {
        (self.weights[interface].iter())
            .zip(accel_above)
            .map(|(w, a)| w * a)
            .sum()
    }
}

/// The earlier of two onsets (the lower block on a tie).
pub fn earlier(a: Option<RockingOnset>, b: Option<RockingOnset>) -> Option<RockingOnset> {
    match (a, b) {
        (Some(x), Some(y)) => Some(if (y.time_s, y.block) < (x.time_s, x.block) {
            y
        } else {
            x
        }),
        (x, y) => x.or(y),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_block_rocks_beyond_g_times_its_aspect() {
        let r = Rocking::new(&[2.0], &[0.25]).unwrap();
        assert_eq!(r.group_aspect(0), 0.25);
        let a = 0.25 * G;
        assert_eq!(r.rocking_interface(&[a]), None);
        assert_eq!(r.rocking_interface(&[a * (1.0 + 1e-12)]), Some(0));
        assert_eq!(r.rocking_interface(&[-a * (1.0 + 1e-12)]), Some(0));
    }

    #[test]
    fn a_stuck_pair_of_equal_blocks_is_one_block_twice_as_tall() {
        // Two blocks of ratio r stacked are one body of ratio r/2 (same width, twice the height).
        let r = Rocking::new(&[1.0, 1.0], &[0.8, 0.8]).unwrap();
        assert!((r.group_aspect(0) - 0.4).abs() < 1e-15);
        assert!((r.group_aspect(1) - 0.8).abs() < 1e-15);
        // Hand case, unequal: m = (3, 1), h/w = (1, 2): centres 0.5 and 2 over interface 1,
        // Σw = 2·(3·0.5 + 1·2)/4 = 1.75.
        let r = Rocking::new(&[3.0, 1.0], &[1.0, 0.5]).unwrap();
        assert!((r.group_aspect(0) - 1.0 / 1.75).abs() < 1e-15);
    }

    #[test]
    fn bad_aspects_are_refused_naming_the_block() {
        for (aspect, expect) in [
            (vec![0.5], "aspect lists 1 values but the stack has 2"),
            (vec![0.5, 0.0], "aspect_2"),
            (vec![-1.0, 0.5], "aspect_1"),
            (vec![0.5, f64::NAN], "aspect_2"),
            (vec![f64::INFINITY, 0.5], "aspect_1"),
        ] {
            let e = Rocking::new(&[1.0, 1.0], &aspect).unwrap_err().to_string();
            assert!(e.contains(expect), "{e}");
        }
    }

    #[test]
    fn the_earlier_onset_wins_and_a_tie_goes_to_the_lower_block() {
        let at = |block, time_s| Some(RockingOnset { block, time_s });
        assert_eq!(earlier(at(2, 1.0), at(1, 2.0)), at(2, 1.0));
        assert_eq!(earlier(at(2, 1.0), at(1, 1.0)), at(1, 1.0));
        assert_eq!(earlier(None, at(1, 1.0)), at(1, 1.0));
        assert_eq!(earlier(None, None), None);
    }
}
