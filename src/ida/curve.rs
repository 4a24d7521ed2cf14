//! A traced IDA curve on a common intensity grid, and fractiles over records (Vamvatsikos &
//! Cornell 2002, Section 6: curves summarised by their 16/50/84 % fractiles given the intensity).
//!
//! Conventions (docs/model.md, "Incremental dynamic analysis"): the curve starts at the origin
//! (no demand at zero intensity) and is linear between the traced runs in intensity order; from
//! the lowest collapsing intensity on, the demand is `+∞` (collapse); above the highest traced
//! intensity of a curve without collapse there is no data (NaN).

/// The demand of one traced curve at every intensity of `grid_sa_g`. `sa_g`, `demand` and
/// `collapsed` describe the runs (any order); `demand` values are finite.
pub fn on_grid(sa_g: &[f64], demand: &[f64], collapsed: &[bool], grid_sa_g: &[f64]) -> Vec<f64> {
    let collapse_sa = sa_g
        .iter()
        .zip(collapsed)
        .filter(|(_, c)| **c)
        .map(|(s, _)| *s)
        .fold(f64::INFINITY, f64::min);
    let mut points: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
        .chain(
            sa_g.iter()
                .zip(demand)
                .filter(|(s, _)| **s <= collapse_sa)
                .map(|(s, d)| (*s, *d)),
        )
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let top = points.last().map_or(0.0, |p| p.0);
    grid_sa_g
        .iter()
        .map(|&x| {
            if x >= collapse_sa {
                return f64::INFINITY;
            }
            if x > top {
                return f64::NAN;
            }
            let j = points.partition_point(|p| p.0 < x);
            if points[j].0 == x {
                return points[j].1;
            }
            let ((x0, y0), (x1, y1)) = (points[j - 1], points[j]);
            y0 + (y1 - y0) * (x - x0) / (x1 - x0)
        })
        .collect()
}

/// The `p`-fractile of `values` (Hyndman & Fan's type 7, the linear interpolation of the order
/// statistics at `h = (n − 1)·p`), `+∞` allowed (a collapsed record); NaN when any value is NaN
/// or there are none.
pub fn fractile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() || values.iter().any(|v| v.is_nan()) {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let h = (v.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let frac = h - lo as f64;
    if frac == 0.0 || v[lo] == v[lo + 1] {
        return v[lo];
    }
    if v[lo + 1].is_infinite() {
        return f64::INFINITY;
    }
    v[lo] + frac * (v[lo + 1] - v[lo])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_curve_interpolates_the_runs_and_flatlines_at_collapse() {
        let sa = [0.4, 0.1, 0.8, 0.6];
        let d = [4.0, 1.0, 12.0, 7.0];
        let c = [false, false, true, false];
        let g = on_grid(&sa, &d, &c, &[0.05, 0.1, 0.25, 0.5, 0.7, 0.8, 0.9]);
        let want = [0.5, 1.0, 2.5, 5.5, 9.5, f64::INFINITY, f64::INFINITY];
        for (x, y) in g.iter().zip(want) {
            assert!((x - y).abs() < 1e-12 || x == &y, "{g:?}");
        }
        // No collapse: no data above the last run.
        let g = on_grid(&[0.2], &[3.0], &[false], &[0.2, 0.3]);
        assert_eq!(g[0], 3.0);
        assert!(g[1].is_nan());
    }

    /// Type 7 by brute force: each value's rank counted (no sort), then the two order
    /// statistics around `h` interpolated.
    fn brute(values: &[f64], p: f64) -> f64 {
        let n = values.len();
        let order = |k: usize| -> f64 {
            for (i, &v) in values.iter().enumerate() {
                let below = values
                    .iter()
                    .enumerate()
                    .filter(|&(j, &w)| w < v || (w == v && j < i))
                    .count();
                if below == k {
                    return v;
                }
            }
            unreachable!()
        };
        let h = (n - 1) as f64 * p;
        let k = h.floor() as usize;
        if k + 1 >= n {
            return order(k);
        }
        let (a, b) = (order(k), order(k + 1));
        if a == b || h == k as f64 {
            a
        } else if b.is_infinite() {
            b
        } else {
            a + (h - k as f64) * (b - a)
        }
    }

    #[test]
    fn fractiles_match_a_brute_force_over_ranks() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for n in 1..40 {
            let mut v: Vec<f64> = (0..n).map(|_| (next() * 10.0).round() / 4.0).collect();
            if n % 3 == 0 {
                v[n / 2] = f64::INFINITY;
            }
            for p in [0.0, 0.16, 0.5, 0.84, 1.0] {
                let (got, want) = (fractile(&v, p), brute(&v, p));
                assert!(got == want || (got - want).abs() < 1e-12, "{v:?} {p}");
            }
        }
        assert!(fractile(&[1.0, f64::NAN], 0.5).is_nan());
        assert_eq!(fractile(&[1.0, 3.0], 0.5), 2.0);
    }
}
