//! Exact linear response spectra of a record (5 %-damped or any `0 ≤ ζ < 1`).
//!
//! The ground acceleration is linear between samples, so a damped linear oscillator has a
//! closed-form solution on each sample interval; stepping it from sample to sample is the
//! Nigam–Jennings recurrence (Nigam & Jennings 1969; Chopra, *Dynamics of Structures*,
//! Table 5.2.1), whose coefficients in φ-function form ([`crate::sdof::Step`]) keep every digit
//! at long periods where the textbook formulas cancel (`2ζ/(ωh)` against `1`).
//!
//! The peak `max_t |u(t)|` is exact too, not only over the samples: sampling alone can be low by
//! up to `1 − cos(π·dt/T)`. A first pass runs the recurrence and takes the sampled peak; a second
//! visits only the intervals that can exceed it: `u̇` or the relative acceleration changes sign
//! at their ends (or they are longer than a quarter period), and a rigorous bound of `max|u|` over
//! them reaches the peak (an energy bound, tight at long periods, or a particular-plus-free split,
//! tight at short ones; `Lanes::may_raise`). In those the zeros of `u̇` are found on the closed
//! form (pieces of at most a quarter damped period, where `u̇` has at most one extremum, so no
//! pair of zeros is missed).
//!
//! Eight oscillators advance together in lanes so the recurrences overlap in the pipeline, and
//! groups of eight run in parallel. The lanes hold eight periods under one record
//! ([`response_spectrum`]) or one period under eight records of one step and length
//! ([`peaks_of_records`]); each lane's peak is the same bits either way.

use crate::dynamics::closed_form::{Basis, Osc, Wave};
use crate::limits::{DT_RANGE_S, MAX_SAMPLES, PERIOD_RANGE_S};
use crate::numeric::bracketed_root;
use crate::sdof::Step;
use rayon::prelude::*;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SpectrumError {
    #[error(
        "period {0:?} s must be within {lo} … {hi} s",
        lo = PERIOD_RANGE_S.0,
        hi = PERIOD_RANGE_S.1
    )]
    Period(f64),
    #[error("damping ratio {0} must be in [0, 1)")]
    Damping(f64),
    #[error(
        "time step {0:?} s must be within {lo} … {hi} s",
        lo = DT_RANGE_S.0,
        hi = DT_RANGE_S.1
    )]
    TimeStep(f64),
    #[error("a record needs 2 to {MAX_SAMPLES} samples, got {0}")]
    TooShort(usize),
    #[error("ground acceleration sample {index} is not finite ({value})")]
    NonFinite { index: usize, value: f64 },
}

/// Peak relative displacement of one oscillator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    /// `max_t |u(t)|`, m.
    pub sd_m: f64,
    /// `u` at the peak (carries its sign), m.
    pub u_m: f64,
    /// Time of the peak from the first sample, s.
    pub time_s: f64,
}

impl Peak {
    /// Pseudo-spectral acceleration `PSA = ω²·Sd` of this peak of an oscillator of `period_s`,
    /// in g.
    pub fn psa_g(&self, period_s: f64) -> f64 {
        let w = std::f64::consts::TAU / period_s;
        w * w * self.sd_m / crate::dynamics::G
    }
}

/// A response spectrum at one damping ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct ResponseSpectrum {
    pub damping: f64,
    pub periods_s: Vec<f64>,
    /// One peak per period.
    pub peaks: Vec<Peak>,
}

impl ResponseSpectrum {
    /// Spectral displacement `Sd`, m.
    pub fn sd_m(&self) -> Vec<f64> {
        self.peaks.iter().map(|p| p.sd_m).collect()
    }
    /// Pseudo-spectral velocity `PSV = ω·Sd`, m/s.
    pub fn psv_mps(&self) -> Vec<f64> {
        self.iter_omega().map(|(w, p)| w * p.sd_m).collect()
    }
    /// Pseudo-spectral acceleration `PSA = ω²·Sd`, in g.
    pub fn psa_g(&self) -> Vec<f64> {
        (self.periods_s.iter().zip(&self.peaks))
            .map(|(&t, p)| p.psa_g(t))
            .collect()
    }
    fn iter_omega(&self) -> impl Iterator<Item = (f64, &Peak)> {
        self.periods_s
            .iter()
            .map(|t| std::f64::consts::TAU / t)
            .zip(&self.peaks)
    }
}

/// Checks a record before any spectrum is computed.
pub fn validate_record(accel_mps2: &[f64], dt_s: f64) -> Result<(), SpectrumError> {
    if !(DT_RANGE_S.0..=DT_RANGE_S.1).contains(&dt_s) {
        return Err(SpectrumError::TimeStep(dt_s));
    }
    if !(2..=MAX_SAMPLES).contains(&accel_mps2.len()) {
        return Err(SpectrumError::TooShort(accel_mps2.len()));
    }
    if let Some((index, &value)) = accel_mps2.iter().enumerate().find(|(_, a)| !a.is_finite()) {
        return Err(SpectrumError::NonFinite { index, value });
    }
    Ok(())
}

fn validate_oscillator(period_s: f64, damping: f64) -> Result<(), SpectrumError> {
    if !(PERIOD_RANGE_S.0..=PERIOD_RANGE_S.1).contains(&period_s) {
        return Err(SpectrumError::Period(period_s));
    }
    if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
        return Err(SpectrumError::Damping(damping));
    }
    Ok(())
}

/// The response spectrum of `accel_mps2` (m/s², step `dt_s`) at `periods_s` and one damping
/// ratio, from rest, over the record's duration.
pub fn response_spectrum(
    accel_mps2: &[f64],
    dt_s: f64,
    periods_s: &[f64],
    damping: f64,
) -> Result<ResponseSpectrum, SpectrumError> {
    validate_record(accel_mps2, dt_s)?;
    for &t in periods_s {
        validate_oscillator(t, damping)?;
    }
    let reach = Reach::new(accel_mps2, dt_s);
    // Groups of eight periods are independent: in parallel, the result does not depend on the
    // thread count.
    let groups: Vec<Vec<Peak>> = periods_s
        .par_chunks(LANES)
        .map(|chunk| {
            let mut lanes = [periods_s[0]; LANES];
            lanes[..chunk.len()].copy_from_slice(chunk);
            let record = Shared {
                accel: accel_mps2,
                reach: &reach,
            };
            peaks_in_lanes(&record, dt_s, &lanes, damping)[..chunk.len()].to_vec()
        })
        .collect();
    let peaks: Vec<Peak> = groups.into_iter().flatten().collect();
    Ok(ResponseSpectrum {
        damping,
        periods_s: periods_s.to_vec(),
        peaks,
    })
}

/// [`response_spectrum`] on this thread, eight periods at a time in order, each group's peaks
/// handed to `keep_going` with the index of its first period; stops with `None` as soon as that
/// says no. The peaks computed are the same bits as [`response_spectrum`]'s.
pub fn response_spectrum_while(
    accel_mps2: &[f64],
    dt_s: f64,
    periods_s: &[f64],
    damping: f64,
    mut keep_going: impl FnMut(usize, &[Peak]) -> bool,
) -> Result<Option<ResponseSpectrum>, SpectrumError> {
    validate_record(accel_mps2, dt_s)?;
    for &t in periods_s {
        validate_oscillator(t, damping)?;
    }
    let reach = Reach::new(accel_mps2, dt_s);
    let record = Shared {
        accel: accel_mps2,
        reach: &reach,
    };
    let mut peaks = Vec::with_capacity(periods_s.len());
    for (i, chunk) in periods_s.chunks(LANES).enumerate() {
        let mut lanes = [periods_s[0]; LANES];
        lanes[..chunk.len()].copy_from_slice(chunk);
        let group = peaks_in_lanes(&record, dt_s, &lanes, damping);
        if !keep_going(i * LANES, &group[..chunk.len()]) {
            return Ok(None);
        }
        peaks.extend_from_slice(&group[..chunk.len()]);
    }
    Ok(Some(ResponseSpectrum {
        damping,
        periods_s: periods_s.to_vec(),
        peaks,
    }))
}

/// The peak of one oscillator (`period_s`, `damping`) under each of `records`
/// (`(accel_mps2, dt_s)`), in their order, on this thread: each the bits of
/// [`response_spectrum`] of its record at `period_s`. Records of one step and length run eight
/// at a time, one per lane; the inputs are checked in the order [`response_spectrum`] of each
/// record in turn would check them.
pub fn peaks_of_records(
    records: &[(&[f64], f64)],
    period_s: f64,
    damping: f64,
) -> Result<Vec<Peak>, SpectrumError> {
    for &(accel_mps2, dt_s) in records {
        validate_record(accel_mps2, dt_s)?;
        validate_oscillator(period_s, damping)?;
    }
    Ok(RecordSet::checked(records).peaks_in_lanes(period_s, damping))
}

/// Records whose peaks are taken at many periods one period at a time ([`Self::peaks`]): each
/// checked, and what its every spectrum needs of it computed, once.
pub struct RecordSet<'a> {
    records: Vec<(&'a [f64], f64)>,
    reaches: Vec<Reach>,
    /// The records of each step and length, in their order.
    groups: Vec<Vec<usize>>,
}

impl<'a> RecordSet<'a> {
    /// `records` (`(accel_mps2, dt_s)`), each checked in their order.
    pub fn new(records: &[(&'a [f64], f64)]) -> Result<Self, SpectrumError> {
        for &(accel_mps2, dt_s) in records {
            validate_record(accel_mps2, dt_s)?;
        }
        Ok(Self::checked(records))
    }

    /// `records`, already checked.
    fn checked(records: &[(&'a [f64], f64)]) -> Self {
        let reaches = (records.iter())
            .map(|&(accel_mps2, dt_s)| Reach::new(accel_mps2, dt_s))
            .collect();
        let mut groups: Vec<((u64, usize), Vec<usize>)> = Vec::new();
        for (i, &(accel_mps2, dt_s)) in records.iter().enumerate() {
            let key = (dt_s.to_bits(), accel_mps2.len());
            match groups.iter_mut().find(|(k, _)| *k == key) {
                Some((_, members)) => members.push(i),
                None => groups.push((key, vec![i])),
            }
        }
        Self {
            records: records.to_vec(),
            reaches,
            groups: groups.into_iter().map(|(_, members)| members).collect(),
        }
    }

    /// [`peaks_of_records`] of these records, to the bit.
    pub fn peaks(&self, period_s: f64, damping: f64) -> Result<Vec<Peak>, SpectrumError> {
        validate_oscillator(period_s, damping)?;
        Ok(self.peaks_in_lanes(period_s, damping))
    }

    fn peaks_in_lanes(&self, period_s: f64, damping: f64) -> Vec<Peak> {
        let records = &self.records;
        let mut peaks: Vec<Option<Peak>> = vec![None; records.len()];
        for members in &self.groups {
            for batch in members.chunks(LANES) {
                // Fewer records than lanes: the first fills the rest, its copies' peaks dropped.
                let pick = |l: usize| *batch.get(l).unwrap_or(&batch[0]);
                let lanes = PerLane {
                    accel: std::array::from_fn(|l| records[pick(l)].0),
                    reach: std::array::from_fn(|l| &self.reaches[pick(l)]),
                };
                let dt_s = records[batch[0]].1;
                let got = peaks_in_lanes(&lanes, dt_s, &[period_s; LANES], damping);
                for (&i, p) in batch.iter().zip(got) {
                    peaks[i] = Some(p);
                }
            }
        }
        peaks
            .into_iter()
            .map(|p| p.expect("every record is in a batch"))
            .collect()
    }
}

/// Peak response of one oscillator.
pub fn peak_response(
    accel_mps2: &[f64],
    dt_s: f64,
    period_s: f64,
    damping: f64,
) -> Result<Peak, SpectrumError> {
    Ok(response_spectrum(accel_mps2, dt_s, &[period_s], damping)?.peaks[0])
}

/// Peak of one oscillator over the samples only (no search between samples): the textbook
/// scalar loop, kept as the baseline of the spectrum benchmark and to show the sampling error.
pub fn sampled_peak(accel_mps2: &[f64], dt_s: f64, period_s: f64, damping: f64) -> f64 {
    let step = Step::new(std::f64::consts::TAU / period_s, damping, dt_s);
    let (mut u, mut v, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for w in accel_mps2.windows(2) {
        (u, v) = step.step(u, v, w[0], w[1]);
        peak = peak.max(u.abs());
    }
    peak
}

/// Oscillators advanced together: eight lanes are two AVX2 (four SSE2) registers, enough
/// independent recurrences to hide the latency of one step.
const LANES: usize = 8;

/// Intervals per block of the first pass (see [`Lanes::peaks_generic`]).
const BLOCK: usize = 16;

/// How far `√E` can grow, m/s: over each interval `h·max(|a_g,k|, |a_g,k+1|)`, and per block of
/// [`BLOCK`] intervals the sum and the largest of those.
struct Reach {
    interval: Vec<f64>,
    block_sum: Vec<f64>,
    block_max: Vec<f64>,
}

impl Reach {
    fn new(accel: &[f64], h: f64) -> Self {
        let interval: Vec<f64> = accel
            .windows(2)
            .map(|w| h * w[0].abs().max(w[1].abs()))
            .collect();
        let block_sum = interval.chunks(BLOCK).map(|b| b.iter().sum()).collect();
        let block_max = interval
            .chunks(BLOCK)
            .map(|b| b.iter().fold(0.0f64, |m, &r| m.max(r)))
            .collect();
        Self {
            interval,
            block_sum,
            block_max,
        }
    }
}

/// The ground accelerations the lanes run under, every lane the same number of samples at the
/// same step: one record in every lane (a spectrum's periods) or one record per lane (one
/// period under several records).
trait Records {
    /// Every lane's ground acceleration at sample `k`, m/s² (read before a step of every lane,
    /// so that the step's stores cannot make them be read again).
    fn accels(&self, k: usize) -> [f64; LANES];
    /// Lane `l`'s [`Reach`].
    fn reach(&self, l: usize) -> &Reach;
    /// Samples of every lane's record.
    fn samples(&self) -> usize;
}

/// One record in every lane.
struct Shared<'a> {
    accel: &'a [f64],
    reach: &'a Reach,
}

impl Records for Shared<'_> {
    #[inline(always)]
    fn accels(&self, k: usize) -> [f64; LANES] {
        [self.accel[k]; LANES]
    }
    #[inline(always)]
    fn reach(&self, _: usize) -> &Reach {
        self.reach
    }
    #[inline(always)]
    fn samples(&self) -> usize {
        self.accel.len()
    }
}

/// A record per lane, all of one length.
struct PerLane<'a> {
    accel: [&'a [f64]; LANES],
    reach: [&'a Reach; LANES],
}

impl Records for PerLane<'_> {
    #[inline(always)]
    fn accels(&self, k: usize) -> [f64; LANES] {
        self.accel.map(|a| a[k])
    }
    #[inline(always)]
    fn reach(&self, l: usize) -> &Reach {
        self.reach[l]
    }
    #[inline(always)]
    fn samples(&self) -> usize {
        self.accel[0].len()
    }
}

/// Oscillators of one damping ratio, advanced together.
struct Lanes {
    omega: [f64; LANES],
    w2: [f64; LANES],
    inv_w2: [f64; LANES],
    /// `2ζ/ω³`: the lag of the particular solution per unit load slope, s³.
    lag: [f64; LANES],
    /// `1/ω_d²`.
    inv_wd2: [f64; LANES],
    /// A quarter of the damped period, s.
    quarter: [f64; LANES],
    steps: [Step; LANES],
    zeta: f64,
    h: f64,
}

/// The ground acceleration over one interval: ends (m/s²), `p`'s slope `−(a_g1 − a_g0)/h`
/// (m/s³) and `reach = h·max|a_g|` (m/s).
struct IntervalLoad {
    ag0: f64,
    ag1: f64,
    slope: f64,
    reach: f64,
}

/// Relative slack on the bounds against round-off.
const SLACK: f64 = 1.0 - 1e-10;

/// `(u, v)` of every lane (m, m/s) at the samples of the blocks that may hold the peak (the
/// other entries are stale), those blocks, and each lane's largest sampled `|u|` with its first
/// sample.
struct SampleStates {
    u: Vec<[f64; LANES]>,
    v: Vec<[f64; LANES]>,
    blocks: Vec<usize>,
    best: [f64; LANES],
    best_k: [usize; LANES],
}

/// `u`, `v` and block buffers of [`SampleStates`].
type StateBuffers = (Vec<[f64; LANES]>, Vec<[f64; LANES]>, Vec<usize>);

thread_local! {
    /// The state buffers of the last spectrum computed on this thread, reused: every element
    /// a spectrum reads is written first, so they need no zeroing.
    static STATES: std::cell::Cell<StateBuffers> =
        const { std::cell::Cell::new((Vec::new(), Vec::new(), Vec::new())) };
}

impl Lanes {
    /// Whether lane `l`, at `(u0, v0)` at the start of an interval with ground acceleration
    /// `ag0 → ag1` and `reach = h·max|a_g|`, can exceed `peak` inside the interval. Two
    /// rigorous bounds of `max|u|`, either of which may clear it:
    /// * energy: `√E` grows by at most `reach`, and `ω|u| ≤ √E` (tight at long periods);
    /// * split: `u = u_p + y` with `u_p` linear in time and `y` a free damped vibration whose
    ///   amplitude `√(y² + ((ẏ + ζωy)/ω_d)²)` cannot grow (tight at short periods, where the
    ///   oscillator follows the ground).
    #[inline(always)]
    fn may_raise(&self, l: usize, peak: f64, (u0, v0): (f64, f64), g: &IntervalLoad) -> bool {
        let e = self.w2[l] * u0 * u0 + v0 * v0;
        let room = self.omega[l] * peak - g.reach;
        if room > 0.0 && e <= room * room * SLACK {
            return false;
        }
        let lag = g.slope * self.lag[l];
        let (up0, up1) = (-g.ag0 * self.inv_w2[l] - lag, -g.ag1 * self.inv_w2[l] - lag);
        let y = u0 - up0;
        let yd = v0 - g.slope * self.inv_w2[l] + self.zeta * self.omega[l] * y;
        let amp2 = y * y + yd * yd * self.inv_wd2[l];
        let room = peak - up0.abs().max(up1.abs());
        !(room > 0.0 && amp2 <= room * room * SLACK)
    }

    /// The exact peaks, in two passes over the samples. The first runs the recurrence and takes
    /// the largest sampled `|u|` of each lane (a lower bound of the true peak, within
    /// `1 − cos(π·dt/T)`); it stores the states only of the blocks of [`BLOCK`] intervals that
    /// can hold a larger `|u|` than the running sampled peak: `√E` grows by at most the block's
    /// reach (`Reach::block_sum`) from its value at the block's start, and a block is passed
    /// over when that bound leaves every lane below the energy test of [`Lanes::may_raise`] at
    /// the running peak less the block's largest interval reach. The second visits only those
    /// blocks and keeps, with the energy test at the sampled peak (branch-free over the lanes),
    /// only the intervals that can hold a larger `|u|`: the few around the largest excursions.
    /// Those face the end tests (an interval can hold a larger `|u|` than its ends only if `u̇`
    /// vanishes inside, which needs a sign change of `u̇` or of the relative acceleration at its
    /// ends, unless it is longer than a quarter period) and both bounds at the running peak, and
    /// the survivors are searched exactly. Every interval that the block test passes over fails
    /// the energy test at the sampled peak (the running peak is below it, the bound is above
    /// `E`, with a margin of `1e-9` against round-off), and that test at the running peak is
    /// implied by the one at the sampled peak, so the same intervals are searched as without
    /// either prefilter.
    ///
    /// Compiled twice: for AVX2 (chosen at run time where the processor has it) and for the
    /// baseline. Neither contracts a multiply and an add, so both give the same bits.
    fn peaks<R: Records>(&self, records: &R) -> [Peak; LANES] {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor has AVX2 (checked just above).
                return unsafe { self.peaks_avx2(records) };
            }
        }
        self.peaks_generic(records)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn peaks_avx2<R: Records>(&self, records: &R) -> [Peak; LANES] {
        self.peaks_generic(records)
    }

    #[inline(always)]
    fn peaks_generic<R: Records>(&self, records: &R) -> [Peak; LANES] {
        let st = self.sample_states(records);
        let mut peaks: [Peak; LANES] = std::array::from_fn(|l| {
            let k = st.best_k[l];
            Peak {
                sd_m: st.best[l],
                u_m: st.u[k][l],
                time_s: k as f64 * self.h,
            }
        });
        let omega_peak: [f64; LANES] = std::array::from_fn(|l| self.omega[l] * st.best[l]);
        let two_zw = self.omega.map(|w| 2.0 * self.zeta * w);
        let inv_h = 1.0 / self.h;
        let intervals = records.samples() - 1;
        for &b in &st.blocks {
            for k in b * BLOCK..((b + 1) * BLOCK).min(intervals) {
                let (u0, v0) = (&st.u[k], &st.v[k]);
                let mut any = false;
                for l in 0..LANES {
                    let e = self.w2[l] * u0[l] * u0[l] + v0[l] * v0[l];
                    let room = omega_peak[l] - records.reach(l).interval[k];
                    any |= !(room > 0.0 && e <= room * room * SLACK);
                }
                if !any {
                    continue;
                }
                let (u1, v1) = (&st.u[k + 1], &st.v[k + 1]);
                let (ground0, ground1) = (records.accels(k), records.accels(k + 1));
                for l in 0..LANES {
                    let (ag0, ag1) = (ground0[l], ground1[l]);
                    let load = IntervalLoad {
                        ag0,
                        ag1,
                        slope: (ag0 - ag1) * inv_h,
                        reach: records.reach(l).interval[k],
                    };
                    let a0 = -ag0 - self.w2[l] * u0[l] - two_zw[l] * v0[l];
                    let a1 = -ag1 - self.w2[l] * u1[l] - two_zw[l] * v1[l];
                    let sign_change =
                        self.h > self.quarter[l] || v0[l] * v1[l] <= 0.0 || a0 * a1 <= 0.0;
                    if sign_change && self.may_raise(l, peaks[l].sd_m, (u0[l], v0[l]), &load) {
                        self.search(
                            l,
                            k,
                            (u0[l], v0[l]),
                            (u1[l], v1[l]),
                            (ag0, ag1),
                            &mut peaks[l],
                        );
                    }
                }
            }
        }
        STATES.set((st.u, st.v, st.blocks));
        peaks
    }

    /// The recurrence over the samples, with the coefficients laid out lane by lane so the
    /// updates of all lanes run side by side, the largest sampled `|u|` of each lane (its first
    /// sample on ties), and the states of the blocks that may hold a larger `|u|`
    /// (see [`Lanes::peaks_generic`]).
    #[inline(always)]
    fn sample_states<R: Records>(&self, records: &R) -> SampleStates {
        let c = |f: fn(&Step) -> f64| self.steps.map(|s| f(&s));
        let (uu, uv, ug0, ug1) = (c(|s| s.uu), c(|s| s.uv), c(|s| s.ug0), c(|s| s.ug1));
        let (vu, vv, vg0, vg1) = (c(|s| s.vu), c(|s| s.vv), c(|s| s.vg0), c(|s| s.vg1));
        let (mut us, mut vs, mut blocks) = STATES.take();
        us.resize(records.samples(), [0.0; LANES]);
        vs.resize(records.samples(), [0.0; LANES]);
        blocks.clear();
        let (mut u, mut v) = ([0.0f64; LANES], [0.0f64; LANES]);
        let mut best = [0.0f64; LANES];
        // The last block in which each lane's sampled peak rose.
        let mut best_block = [usize::MAX; LANES];
        // One recurrence step of every lane over interval `k`, raising the sampled peaks (a
        // macro rather than a closure, so that it is compiled into the AVX2 copy).
        macro_rules! step {
            ($k:expr) => {
                let (a0, a1) = (records.accels($k), records.accels($k + 1));
                for l in 0..LANES {
                    let (ag0, ag1) = (a0[l], a1[l]);
                    let (u0, v0) = (u[l], v[l]);
                    u[l] = uu[l] * u0 + uv[l] * v0 + ug0[l] * ag0 + ug1[l] * ag1;
                    v[l] = vu[l] * u0 + vv[l] * v0 + vg0[l] * ag0 + vg1[l] * ag1;
                    let a = u[l].abs();
                    // `max` without its NaN case (the states are finite): one instruction.
                    best[l] = if a > best[l] { a } else { best[l] };
                }
            };
        }
        const MARGIN: f64 = SLACK * (1.0 - 1e-9);
        let intervals = records.samples() - 1;
        for b in 0..intervals.div_ceil(BLOCK) {
            let k0 = b * BLOCK;
            let grow: [f64; LANES] = std::array::from_fn(|l| records.reach(l).block_sum[b]);
            let near: [f64; LANES] = std::array::from_fn(|l| records.reach(l).block_max[b]);
            let mut may = false;
            for l in 0..LANES {
                let (grow, near) = (grow[l], near[l]);
                let e = self.w2[l] * u[l] * u[l] + v[l] * v[l];
                let bound = e.sqrt() + grow;
                let room = self.omega[l] * best[l] - near;
                may |= !((room > 0.0) & (bound * bound <= room * room * MARGIN));
            }
            let before = best;
            let k1 = (k0 + BLOCK).min(intervals);
            if may {
                blocks.push(b);
                us[k0] = u;
                vs[k0] = v;
                for k in k0..k1 {
                    step!(k);
                    us[k + 1] = u;
                    vs[k + 1] = v;
                }
            } else {
                for k in k0..k1 {
                    step!(k);
                }
            }
            for l in 0..LANES {
                if best[l] > before[l] {
                    best_block[l] = b;
                }
            }
        }
        // The first sample of each lane's peak block at its largest |u| (the peak only rises
        // in a block whose states are kept).
        let best_k = std::array::from_fn(|l| {
            if best_block[l] == usize::MAX {
                return 0;
            }
            let k0 = best_block[l] * BLOCK;
            (k0 + 1..=(k0 + BLOCK).min(intervals))
                .find(|&k| us[k][l].abs() == best[l])
                .expect("the peak block holds the peak")
        });
        SampleStates {
            u: us,
            v: vs,
            blocks,
            best,
            best_k,
        }
    }

    /// Exact search of interval `k` of lane `l` for a `|u|` above `peak`.
    #[cold]
    #[inline(never)]
    fn search(
        &self,
        l: usize,
        k: usize,
        (u0, v0): (f64, f64),
        (u1, v1): (f64, f64),
        (ag0, ag1): (f64, f64),
        peak: &mut Peak,
    ) {
        let interval = Interval {
            t0_s: k as f64 * self.h,
            h: self.h,
            omega: self.omega[l],
            zeta: self.zeta,
            u0,
            v0,
            ag0,
            ag1,
        };
        interval.raise_peak(u1, v1, peak);
    }
}

fn peaks_in_lanes<R: Records>(
    records: &R,
    h: f64,
    periods_s: &[f64; LANES],
    zeta: f64,
) -> [Peak; LANES] {
    let omega = periods_s.map(|t| std::f64::consts::TAU / t);
    let lanes = Lanes {
        omega,
        w2: omega.map(|w| w * w),
        inv_w2: omega.map(|w| 1.0 / (w * w)),
        lag: omega.map(|w| 2.0 * zeta / (w * w * w)),
        inv_wd2: omega.map(|w| 1.0 / (w * w * (1.0 - zeta * zeta))),
        quarter: omega.map(|w| 0.25 * std::f64::consts::TAU / (w * (1.0 - zeta * zeta).sqrt())),
        steps: omega.map(|w| Step::new(w, zeta, h)),
        zeta,
        h,
    };
    lanes.peaks(records)
}

/// One sample interval of one oscillator, for the exact search of `max |u|` inside it.
struct Interval {
    t0_s: f64,
    h: f64,
    omega: f64,
    zeta: f64,
    u0: f64,
    v0: f64,
    ag0: f64,
    ag1: f64,
}

impl Interval {
    /// Raises `peak` to the largest `|u|` over the interval: the end sample `u1` (from the
    /// recurrence) and every interior zero of `u̇`.
    fn raise_peak(&self, u1: f64, v1: f64, peak: &mut Peak) {
        let mut offer = |u: f64, tau: f64| {
            if u.abs() > peak.sd_m {
                *peak = Peak {
                    sd_m: u.abs(),
                    u_m: u,
                    time_s: self.t0_s + tau,
                };
            }
        };
        offer(u1, self.h);
        let (osc, disp) = self.closed_form();
        let vel = disp.deriv(osc);
        let acc = vel.deriv(osc);
        // The relative acceleration is a damped sinusoid (the particular part of u is linear),
        // so |u̇(τ) − u̇(0)| ≤ h·√(c² + d²) of its wave: when both ends are farther from zero
        // than that, with the same sign, u̇ has no zero inside.
        let reach_v = self.h * (acc.c * acc.c + acc.d * acc.d).sqrt();
        if self.v0 * v1 > 0.0 && self.v0.abs().min(v1.abs()) > reach_v {
            return;
        }
        let at = |w: &Wave, tau: f64| w.eval(&Basis::at(osc, tau));
        let jerk = acc.deriv(osc);
        let with_slope = |w: &Wave, dw: &Wave, tau: f64| {
            let b = Basis::at(osc, tau);
            (w.eval(&b), dw.eval(&b))
        };
        // Pieces of at most a quarter damped period: the relative acceleration (a damped
        // sinusoid, the particular part being linear in u) changes sign at most once in each.
        let quarter = 0.25 * std::f64::consts::TAU / osc.omega;
        let pieces = (self.h / quarter).ceil().max(1.0) as usize;
        let mut lo = 0.0;
        let (mut v_lo, mut a_lo) = (self.v0, at(&acc, 0.0));
        for i in 1..=pieces {
            let hi = if i == pieces {
                self.h
            } else {
                self.h * i as f64 / pieces as f64
            };
            let (v_hi, a_hi) = (at(&vel, hi), at(&acc, hi));
            let mut parts = [(lo, v_lo, hi, v_hi), (hi, v_hi, hi, v_hi)];
            if a_lo * a_hi < 0.0 {
                let tc = bracketed_root(|t| with_slope(&acc, &jerk, t), lo, hi, a_lo, a_hi);
                let vc = at(&vel, tc);
                parts = [(lo, v_lo, tc, vc), (tc, vc, hi, v_hi)];
            }
            for &(a, va, b, vb) in &parts {
                if b > a && va * vb <= 0.0 {
                    let tz = bracketed_root(|t| with_slope(&vel, &acc, t), a, b, va, vb);
                    offer(at(&disp, tz), tz);
                }
            }
            lo = hi;
            v_lo = v_hi;
            a_lo = a_hi;
        }
    }

    /// `u(τ)` on the interval: the particular solution for the linear load
    /// `p = −a_g = p₀ + r·τ`, `u_p = (p₀ + rτ)/ω² − 2ζr/ω³`, plus the free vibration that
    /// matches `u₀`, `v₀`.
    fn closed_form(&self) -> (Osc, Wave) {
        let (w, z) = (self.omega, self.zeta);
        let osc = Osc {
            decay: z * w,
            omega: w * (1.0 - z * z).sqrt(),
        };
        let p0 = -self.ag0;
        let r = -(self.ag1 - self.ag0) / self.h;
        let w2 = w * w;
        let up0 = p0 / w2 - 2.0 * z * r / (w2 * w);
        let vp = r / w2;
        let c = self.u0 - up0;
        let d = (self.v0 - vp + osc.decay * c) / osc.omega;
        (
            osc,
            Wave {
                p: [up0, vp, 0.0, 0.0],
                c,
                d,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refused_input_is_named() {
        let a = [0.0, 1.0, 0.0];
        let e = |r: Result<ResponseSpectrum, SpectrumError>| r.unwrap_err().to_string();
        assert_eq!(
            e(response_spectrum(&a, 0.01, &[0.0], 0.05)),
            "period 0.0 s must be within 0.001 … 10000 s"
        );
        assert_eq!(
            e(response_spectrum(&a, 0.01, &[1.0], 1.0)),
            "damping ratio 1 must be in [0, 1)"
        );
        assert_eq!(
            e(response_spectrum(&a, -0.01, &[1.0], 0.05)),
            "time step -0.01 s must be within 0.00001 … 1 s"
        );
        assert_eq!(
            e(response_spectrum(&a[..1], 0.01, &[1.0], 0.05)),
            "a record needs 2 to 16777216 samples, got 1"
        );
        assert_eq!(
            e(response_spectrum(&[0.0, f64::NAN], 0.01, &[1.0], 0.05)),
            "ground acceleration sample 1 is not finite (NaN)"
        );
    }

    #[test]
    fn undamped_coefficients_equal_the_textbook_formulas() {
        // ζ = 0: u(h) = cos(ωh)·u₀ + sin(ωh)/ω·v₀ + (cos ωh/ω² − sin ωh/(hω³))·a_g0
        // + (sin ωh/(hω³) − 1/ω²)·a_g1, evaluated where it does not cancel (ωh ≈ 0.6–6);
        // agreement to a few ulps of the largest term.
        for &(period, h) in &[(0.1, 0.01), (1.0, 0.1), (0.02, 0.02)] {
            let w: f64 = std::f64::consts::TAU / period;
            let s = Step::new(w, 0.0, h);
            let (sn, cs) = (w * h).sin_cos();
            let w2 = w * w;
            let want = [
                (s.uu, cs, 1.0),
                (s.uv, sn / w, 1.0 / w),
                (s.ug0, cs / w2 - sn / (h * w2 * w), 1.0 / w2),
                (s.ug1, sn / (h * w2 * w) - 1.0 / w2, 1.0 / w2),
                (s.vu, -w * sn, w),
                (s.vv, cs, 1.0),
            ];
            for (i, (got, exp, scale)) in want.into_iter().enumerate() {
                let rel = (got - exp).abs() / scale;
                assert!(
                    rel < 1e-15,
                    "T={period} h={h} coefficient {i}: {got} vs {exp} ({rel:e})"
                );
            }
        }
    }

    #[test]
    fn free_vibration_peak_between_samples() {
        // Undamped oscillator under a two-interval triangular pulse, then free. After the pulse
        // u = A·sin(ω(t − t₀) + φ) with A = √(u² + (v/ω)²), exact; during the pulse the peak is
        // found by brute force on 10⁵ sub-steps per interval (the record is linear there, so
        // sub-stepping is exact; sampling error ≤ 1 − cos(π·h/10⁵/T) ≈ 6e-11 here).
        let (period, dt) = (0.05, 0.0173);
        let accel = [0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let w = std::f64::consts::TAU / period;
        let n = 100_000;
        let fine = Step::new(w, 0.0, dt / n as f64);
        let (mut u, mut v, mut during) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..2 {
            for i in 0..n {
                let a = |j: usize| accel[k] + (accel[k + 1] - accel[k]) * j as f64 / n as f64;
                (u, v) = fine.step(u, v, a(i), a(i + 1));
                during = during.max(u.abs());
            }
        }
        let after = (u * u + (v / w).powi(2)).sqrt();
        let exact = during.max(after);
        let p = peak_response(&accel, dt, period, 0.0).unwrap();
        assert!(
            ((p.sd_m - exact) / exact).abs() < 1e-10,
            "{} vs {exact}",
            p.sd_m
        );
        assert!(sampled_peak(&accel, dt, period, 0.0) < 0.99 * exact);
    }

    #[test]
    fn records_in_lanes_give_each_record_its_own_bits() {
        // Eleven records of two steps and three lengths (a batch of eight and one of two at
        // 0.01 s, one alone at 0.02 s): every peak equals its record's own spectrum's at the
        // period, to the bit, at short and long periods, damped and undamped; the first record
        // at fault is named, as the spectrum of each record in turn would.
        let record = |seed: u64, len: usize| -> Vec<f64> {
            let mut x = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (0..len)
                .map(|k| {
                    x = x
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    let noise = (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                    let envelope = (k as f64 / len as f64 * std::f64::consts::PI).sin();
                    3.0 * envelope * noise
                })
                .collect()
        };
        let shapes = [(0.01, 900); 8]
            .into_iter()
            .chain([(0.02, 500), (0.01, 900), (0.01, 700)]);
        let owned: Vec<(Vec<f64>, f64)> = (shapes.enumerate())
            .map(|(i, (dt, len))| (record(i as u64, len), dt))
            .collect();
        let records: Vec<(&[f64], f64)> = owned.iter().map(|(a, dt)| (&a[..], *dt)).collect();
        // One `RecordSet` serves every period with the same bits.
        let set = RecordSet::new(&records).unwrap();
        for period in [0.03, 0.3, 1.0, 6.0] {
            for zeta in [0.0, 0.05] {
                let got = peaks_of_records(&records, period, zeta).unwrap();
                let from_set = set.peaks(period, zeta).unwrap();
                let bits = |p: &Peak| [p.sd_m, p.u_m, p.time_s].map(f64::to_bits);
                for (i, (&(a, dt), p)) in records.iter().zip(&got).enumerate() {
                    let own = response_spectrum(a, dt, &[period], zeta).unwrap().peaks[0];
                    assert_eq!(bits(p), bits(&own), "record {i}, T = {period}, ζ = {zeta}");
                    assert_eq!(
                        bits(&from_set[i]),
                        bits(&own),
                        "set: record {i}, T = {period}"
                    );
                }
            }
        }
        assert_eq!(
            set.peaks(0.0, 0.05).unwrap_err().to_string(),
            "period 0.0 s must be within 0.001 … 10000 s"
        );
        let mut bad = owned.clone();
        bad[9].0[3] = f64::NAN;
        let records: Vec<(&[f64], f64)> = bad.iter().map(|(a, dt)| (&a[..], *dt)).collect();
        assert_eq!(
            peaks_of_records(&records, 1.0, 0.05)
                .unwrap_err()
                .to_string(),
            "ground acceleration sample 3 is not finite (NaN)"
        );
        assert_eq!(
            peaks_of_records(&records, 0.0, 0.05)
                .unwrap_err()
                .to_string(),
            "period 0.0 s must be within 0.001 … 10000 s"
        );
        assert_eq!(
            RecordSet::new(&records).err().unwrap().to_string(),
            "ground acceleration sample 3 is not finite (NaN)"
        );
    }
}
