//! Which panels and lines the figures over the grid draw: panels over the mass ratios, lines
//! over the friction coefficients, picked from the grid's own axes so that any grid (any block
//! count) gives readable figures.

use super::text::num;
use crate::grid::Grid;
use crate::render::chart::{PALETTE, Stroke};
use plotters::style::RGBColor;

/// At most this many panels over the mass ratios, and lines of friction pairs per panel.
pub(super) const MAX_PANELS: usize = 9;
pub(super) const MAX_LINES: usize = 6;

/// Evenly spaced picks of `k` of `len` indices, first and last included (`k` = 1: the middle).
pub(super) fn picks(len: usize, k: usize) -> Vec<usize> {
    match k.min(len) {
        0 => Vec::new(),
        1 => vec![(len - 1) / 2],
        k => (0..k)
            .map(|i| ((i * (len - 1)) as f64 / (k - 1) as f64).round() as usize)
            .collect(),
    }
}

/// Index subsets of axes of lengths `lens` whose product is at most `max`: the axis with the
/// most picks (the later one on a tie) is cut to 3, then 2, then 1 evenly spaced values until
/// the product fits.
pub(super) fn subset(lens: &[usize], max: usize) -> Vec<Vec<usize>> {
    let mut count: Vec<usize> = lens.to_vec();
    while count.iter().product::<usize>() > max {
        let (axis, &c) = count
            .iter()
            .enumerate()
            .max_by_key(|(_, c)| **c)
            .expect("at least one axis");
        if c <= 1 {
            break;
        }
        count[axis] = if c > 3 { 3 } else { c - 1 };
    }
    lens.iter()
        .zip(&count)
        .map(|(&len, &c)| picks(len, c))
        .collect()
}

/// Every combination of the index lists, the last fastest.
pub(super) fn combinations(lists: &[Vec<usize>]) -> Vec<Vec<usize>> {
    lists.iter().fold(vec![Vec::new()], |acc, list| {
        acc.iter()
            .flat_map(|prefix| {
                list.iter().map(move |&i| {
                    let mut v = prefix.clone();
                    v.push(i);
                    v
                })
            })
            .collect()
    })
}

/// Flat case index within a work unit from per-axis indices (`α` axes, then `μ` axes).
pub(super) fn case_index(grid: &Grid, alpha: &[usize], mu: &[usize]) -> usize {
    grid.case_shape()
        .iter()
        .zip(alpha.iter().chain(mu))
        .fold(0, |idx, (&len, &i)| idx * len + i)
}

pub(super) fn label_of(name: &str, axes: &[Vec<f64>], idx: &[usize]) -> String {
    idx.iter()
        .enumerate()
        .map(|(d, &i)| format!("{name}_{} = {}", d + 1, num(axes[d][i])))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The panels over the mass ratios and the lines over the friction pairs of the `T_p` figures.
pub(super) struct Selection {
    /// `α` index per block, one entry per panel.
    pub(super) panels: Vec<Vec<usize>>,
    pub(super) columns: usize,
    /// `μ` index per interface, one entry per line, with its colour and stroke.
    pub(super) lines: Vec<(Vec<usize>, RGBColor, Stroke)>,
    /// Every `μ` combination (drawn faint).
    pub(super) all_mu: Vec<Vec<usize>>,
    pub(super) mu_note: String,
}

impl Selection {
    pub(super) fn new(grid: &Grid) -> Self {
        let alpha_lens: Vec<usize> = grid.alpha.iter().map(Vec::len).collect();
        let alpha_sets = subset(&alpha_lens, MAX_PANELS);
        let panels = combinations(&alpha_sets);
        let columns = if alpha_sets.len() >= 2 {
            alpha_sets[1..].iter().map(Vec::len).product::<usize>()
        } else {
            panels.len()
        };
        let columns = if columns > 4 {
            (panels.len() as f64).sqrt().ceil() as usize
        } else {
            columns
        };
        let mu_lens: Vec<usize> = grid.mu.iter().map(Vec::len).collect();
        let mu_sets = subset(&mu_lens, MAX_LINES);
        let chosen = combinations(&mu_sets);
        let others: usize = mu_sets[1..].iter().map(Vec::len).product();
        let strokes = [Stroke::Solid, Stroke::Dashed, Stroke::Dotted];
        let by_mu_1 = others <= strokes.len();
        let lines = chosen
            .iter()
            .enumerate()
            .map(|(k, idx)| {
                if by_mu_1 {
                    let c = mu_sets[0].iter().position(|&i| i == idx[0]).unwrap_or(0);
                    (idx.clone(), PALETTE[c % PALETTE.len()], strokes[k % others])
                } else {
                    (idx.clone(), PALETTE[k % PALETTE.len()], Stroke::Solid)
                }
            })
            .collect();
        let all_mu = combinations(
            &mu_lens
                .iter()
                .map(|&l| (0..l).collect())
                .collect::<Vec<_>>(),
        );
        let picked: Vec<String> = mu_sets
            .iter()
            .enumerate()
            .map(|(d, s)| {
                format!(
                    "μ_{} ∈ {{{}}}",
                    d + 1,
                    s.iter()
                        .map(|&i| num(grid.mu[d][i]))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
            .collect();
        let mu_note = if chosen.len() == all_mu.len() {
            format!("every friction combination ({})", chosen.len())
        } else {
            format!(
                "{} of the grid's {} friction combinations drawn out ({}), every one in grey",
                chosen.len(),
                all_mu.len(),
                picked.join(", ")
            )
        };
        Self {
            panels,
            columns,
            lines,
            all_mu,
            mu_note,
        }
    }

    pub(super) fn panel_title(&self, grid: &Grid, p: usize) -> String {
        label_of("α", &grid.alpha, &self.panels[p])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subsets_keep_the_ends_and_fit_the_limit() {
        assert_eq!(picks(7, 3), vec![0, 3, 6]);
        assert_eq!(picks(8, 2), vec![0, 7]);
        assert_eq!(picks(3, 1), vec![1]);
        // The paper's friction axes (7, 8) → 3 × 2 lines; its mass ratios (3, 3) → 9 panels.
        assert_eq!(subset(&[7, 8], 6), vec![vec![0, 3, 6], vec![0, 7]]);
        assert_eq!(subset(&[3, 3], 9), vec![vec![0, 1, 2], vec![0, 1, 2]]);
        let three = subset(&[3, 3, 3], 9);
        assert!(three.iter().map(Vec::len).product::<usize>() <= 9);
        assert_eq!(
            combinations(&[vec![0, 2], vec![1]]),
            vec![vec![0, 1], vec![2, 1]]
        );
    }
}
