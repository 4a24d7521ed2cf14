//! What a sweep unit costs, for sizing cluster jobs (`pipelines/slurm-submit.sh` reads it from
//! `slidestack status --format env`, `SWEEP_NS_PER_SAMPLE`): CPU nanoseconds per record sample of
//! the work bound `SWEEP_SAMPLES_PER_UNIT` (3 systems × a unit's cases × the mean samples per
//! motion).
//!
//! A one-storey study's figure is a bound: 188 ns per *simulated* sample, measured by the paper
//! study on 2 threads (docs/performance.md, "The paper's study"), charged to every sample of the
//! bound although the skip rules leave most cases unsimulated. A building's costs far more per
//! sample and grows with its storeys, so a building study's figure is an estimate instead: the
//! mean over its frames of [`NS_PER_SAMPLE_BY_STOREYS`], measured per storey count on shards of
//! the research grid with the skip rules at work (`scripts/storey-cost`); a grid whose skip rules
//! save less than the research grid's costs more than it says. The job scripts' time limit is
//! twice the estimate plus 5 minutes.

use super::building::distinct_frames;
use super::shape::StudyShape;

/// A one-storey study: ns per simulated record sample per thread (a bound on the sweep's cost
/// when charged to every sample).
pub const ONE_STOREY_NS_PER_SAMPLE: f64 = 188.0;

/// `(storeys, ns per sample of the work bound)` of a building study's sweep, measured by
/// `scripts/storey-cost` (configs/mdof-research.yaml cut to zone V, `T_1` of 0.5, 1 and 1.5 s,
/// the stack on floor 1, at mid-height, on the roof and on every floor; `sweep --shard 1/7`, 19
/// units; CPU seconds, user + system) at commit 742f196 on this project's 2-core machine, idle.
/// Zone V's middle periods are where the stacks slide most: the whole research grid costs less
/// (pipelines/README.md, "A research-sized building study").
pub const NS_PER_SAMPLE_BY_STOREYS: [(usize, f64); 5] = [
    (1, 13.0),
    (3, 118.0),
    (6, 328.0),
    (10, 1007.0),
    (20, 10278.0),
];

/// ns per work-bound sample of a building of `storeys` storeys: [`NS_PER_SAMPLE_BY_STOREYS`]
/// interpolated linearly between its rows; beyond the last, the power law through the last two.
pub fn building_ns_per_sample(storeys: usize) -> f64 {
    let table = &NS_PER_SAMPLE_BY_STOREYS;
    let n = storeys as f64;
    let ((n0, y0), (last_n, last_ns)) = (table[table.len() - 2], table[table.len() - 1]);
    if storeys >= last_n {
        let power = (last_ns / y0).ln() / (last_n as f64 / n0 as f64).ln();
        return last_ns * (n / last_n as f64).powf(power);
    }
    let hi = table.iter().position(|&(s, _)| s >= storeys).unwrap_or(0);
    if hi == 0 {
        return table[0].1;
    }
    let ((n0, y0), (n1, y1)) = (table[hi - 1], table[hi]);
    y0 + (y1 - y0) * (n - n0 as f64) / (n1 - n0) as f64
}

/// A study's ns per work-bound sample: [`ONE_STOREY_NS_PER_SAMPLE`] on one storey, else the mean
/// of [`building_ns_per_sample`] over the frames the sweep computes ([`distinct_frames`]: each
/// has as many units of as many cases).
pub fn ns_per_sample(shape: &StudyShape) -> f64 {
    if !shape.is_building() {
        return ONE_STOREY_NS_PER_SAMPLE;
    }
    let frames = shape.frames();
    let computed = distinct_frames(frames);
    let sum: f64 = (computed.iter())
        .map(|&f| building_ns_per_sample(frames[f].storeys()))
        .sum();
    sum / computed.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows are the measurement itself, and between and beyond them the estimate grows
    /// with the storeys.
    #[test]
    fn the_table_is_met_at_its_rows_and_grows_between_and_beyond() {
        for &(n, ns) in &NS_PER_SAMPLE_BY_STOREYS {
            assert_eq!(building_ns_per_sample(n), ns);
        }
        let mut last = 0.0;
        for n in 1..=40 {
            let ns = building_ns_per_sample(n);
            assert!(ns > last, "{n} storeys: {ns} after {last}");
            last = ns;
        }
        // Beyond the table, as from the row before the last to the last: here 10 to 20 storeys.
        let [.., (n0, y0), (n1, y1)] = NS_PER_SAMPLE_BY_STOREYS;
        assert_eq!((n0, 2 * n0), (10, n1));
        let twice = building_ns_per_sample(2 * n1);
        assert!((twice / y1 - y1 / y0).abs() < 1e-12, "{twice}");
    }
}
