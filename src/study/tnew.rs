//! `T_new` and the displacement response ratios (paper Section 7.1, Eqs. 7–8; docs/model.md "Derived
//! quantities").
//!
//! For one case and one zone: the mean over the motions of the peak structure displacement with
//! the stack, `ū`, is read off the mean 5 %-damped displacement spectrum `S̄d(T)` of the same
//! motions: `T_new` is the period where `S̄d(T) = ū`, by linear interpolation between the
//! spectrum's periods. When no motion makes any interface slip, `T_new = T_rigid` (step 1 of
//! Section 7.1). `DRR_1 = ū_stack/ū_rigid`, `DRR_2 = ū_single/ū_rigid` (ratios of the means).
//!
//! Several crossings: the spectrum need not be monotone. The rule: take the crossing nearest
//! to `T_rigid` (in log period); the stack can only soften the structure up to the rigidly
//! attached mass, and the crossing near `T_rigid` is the one that continues the `μ → ∞` limit.
//! The flag says which case applied.
//!
//! A zone ([`zone`]): every case of every frame of a building study (docs/model.md, "A study
//! over buildings") alike; one storey keeps the paper's `T_new`, bit for bit; a building of
//! several storeys reads it off the attached fraction of the roof's mean peak displacement, the
//! first-mode period of the building carrying that fraction of its stack (and keeps the
//! first-mode definition as `T_new_first_mode`). Its cases also get their attached fractions
//! ([`crate::study::attached`]: `λ` of the base shear, of each storey's shear and of the
//! overturning moment, `λ_code`), which run the linear building with part of the stack
//! attached.

use crate::dynamics::Ground;
use crate::fit::{BuildingFeatures, Sample, features};
use crate::grid::{BuildingAxes, Grid};
use crate::ground_motion::Record;
use crate::spectrum::{SpectrumError, TARGET_DAMPING, response_spectrum};
use crate::store::sweep::{BuildingVars, ZoneSweep};
use crate::store::tnew::{AttachedVars, TnewVars, ZoneTnew};
use crate::study::attached::{
    self, AttachedError, CaseFractions, FRACTION_FLAGS, FractionFlag, FractionUnit, ZoneFamily,
};
use crate::study::building::{Frame, repeats};
use crate::study::physics::Physics;
use ndarray::{ArrayD, Axis};
use rayon::prelude::*;

/// Step of the period grid of the mean displacement spectrum, s.
pub const SD_STEP_S: f64 = 0.005;

/// The periods of the mean displacement spectrum: they reach past every `T_rigid` of the grid
/// (in a building too: a load of at most `α` times each floor's mass lengthens the first mode
/// by at most `sqrt(1+α)`, Rayleigh's quotient).
pub fn spectrum_periods_s(grid: &Grid) -> Vec<f64> {
    let alpha_max: f64 = grid
        .alpha
        .iter()
        .map(|a| a.iter().copied().fold(0.0, f64::max))
        .sum();
    let t_max = grid.periods_s.last().copied().unwrap_or(1.0) * (1.0 + alpha_max).sqrt() * 1.5;
    let steps = (t_max.max(4.0) / SD_STEP_S).ceil() as usize;
    (1..=steps).map(|k| k as f64 * SD_STEP_S).collect()
}

/// The fit's samples: every case of `grid` (flat over `[T_p][case]`) with a finite `T_new`,
/// features `(T_p, μ_1 … μ_n, α_1 … α_n)`.
pub fn samples(grid: &Grid, t_rigid_s: &[f64], t_new_s: &[f64]) -> Vec<Sample> {
    (0..t_new_s.len())
        .filter(|&c| t_new_s[c].is_finite())
        .map(|c| {
            let case = grid.case(c);
            Sample {
                x: features(case.period_s, &case.alpha, &case.mu),
                t_rigid_s: t_rigid_s[c],
                t_new_s: t_new_s[c],
            }
        })
        .collect()
}

/// The fit's samples of a building study of several frames: every case of every frame (flat
/// over `[frame][T_1][case]`, as `tnew.h5` stores them) with a finite `T_new`, with its frame's
/// index and the features `features` names.
pub fn building_samples(
    grid: &Grid,
    frames: &[Frame],
    features: BuildingFeatures,
    t_rigid_s: &[f64],
    t_new_s: &[f64],
) -> Vec<(usize, Sample)> {
    let per_frame = grid.cases();
    (0..t_new_s.len())
        .filter(|&c| t_new_s[c].is_finite())
        .map(|c| {
            let (f, case) = (c / per_frame, grid.case(c % per_frame));
            let frame = &frames[f];
            let x = features.features(
                case.period_s,
                &case.alpha,
                &case.mu,
                frame.storeys(),
                frame.stack_height_ratio(),
            );
            let sample = Sample {
                x,
                t_rigid_s: t_rigid_s[c],
                t_new_s: t_new_s[c],
            };
            (f, sample)
        })
        .collect()
}

/// How `T_new` was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum TnewFlag {
    /// One crossing.
    Unique = 0,
    /// Several crossings: the one nearest `T_rigid` (log period) was taken.
    Several = 1,
    /// `ū` lies outside the spectrum's range on its period grid: `T_new` is NaN.
    OutsideRange = 2,
    /// Nothing slid: `T_new = T_rigid`.
    NoSlide = 3,
}

/// Meaning of the `T_new_flag` codes, for the file attribute.
pub const TNEW_FLAG_CODES: &str = "0 one crossing (one storey: of the mean displacement \
     spectrum; a building of several storeys: of the mean peak roof displacement of the building \
     carrying a fraction of the stack attached); 1 several crossings, the one nearest T_rigid (log \
     period) taken (a building: the fraction nearest the stuck mass share); 2 the mean \
     displacement lies outside the spectrum's (the attached family's) range, T_new NaN; 3 \
     nothing slid, T_new = T_rigid";

/// A building's `T_new` from the first-mode period `t1_s` of the building carrying the attached
/// fraction of its roof's mean peak displacement, found as `how`
/// ([`crate::study::attached`]): NaN when no fraction gives it.
pub fn of_attached(t1_s: f64, how: FractionFlag) -> (f64, TnewFlag) {
    match how {
        FractionFlag::Root => (t1_s, TnewFlag::Unique),
        FractionFlag::Several | FractionFlag::Near => (t1_s, TnewFlag::Several),
        FractionFlag::Below | FractionFlag::Above => (f64::NAN, TnewFlag::OutsideRange),
        FractionFlag::NoSlide => (t1_s, TnewFlag::NoSlide),
    }
}

flag_enum! {
    /// Where a case's `T_new` lies against its physical band `[T_p, T_rigid]` (paper Section 10:
    /// generally `T_p < T_new < T_rigid`; docs/model.md, "Derived quantities").
    pub enum Band;
    /// `(code, word)` of each [`Band`], for the CF `flag_values`/`flag_meanings` attributes.
    pub const BAND_FLAGS;
    {
        /// One crossing, `T_p ≤ T_new ≤ T_rigid`.
        Band = 0 => "band",
        /// `T_new < T_p`: friction lowered the displacement below the bare structure's.
        BelowTp = 1 => "below_T_p",
        /// `T_new > T_rigid`.
        AboveTrigid = 2 => "above_T_rigid",
        /// No crossing of the mean displacement spectrum (`T_new` NaN).
        NoCrossing = 3 => "no_crossing",
        /// Inside the band, the nearest of several crossings.
        SeveralCrossings = 4 => "several_crossings",
        /// Nothing slid: `T_new = T_rigid`.
        NoSlide = 5 => "no_slide",
    }
}

impl Band {
    /// The category of `T_new` (s) found as `flag` for a structure of periods `t_p_s`,
    /// `t_rigid_s`; earlier rules win: no slide, no crossing, above, below, several.
    pub fn of(t_p_s: f64, t_rigid_s: f64, t_new_s: f64, flag: TnewFlag) -> Band {
        match flag {
            TnewFlag::NoSlide => Band::NoSlide,
            TnewFlag::OutsideRange => Band::NoCrossing,
            _ if t_new_s > t_rigid_s => Band::AboveTrigid,
            _ if t_new_s < t_p_s => Band::BelowTp,
            TnewFlag::Several => Band::SeveralCrossings,
            TnewFlag::Unique => Band::Band,
        }
    }
}

/// How many cases of a zone fall in each [`Band`], and how many sliding cases exceed
/// `1.005·T_rigid` (the band goal's measure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BandCounts {
    /// Indexed by the [`Band`] code.
    pub counts: [usize; 6],
    pub above_1_005: usize,
}

impl BandCounts {
    pub fn new(band: &[u8], t_new_s: &[f64], t_rigid_s: &[f64]) -> Self {
        let mut c = Self::default();
        for ((&b, &tn), &tr) in band.iter().zip(t_new_s).zip(t_rigid_s) {
            c.counts[b as usize] += 1;
            if b != Band::NoSlide as u8 && tn > 1.005 * tr {
                c.above_1_005 += 1;
            }
        }
        c
    }

    /// Cases in which something slid.
    pub fn sliding(&self) -> usize {
        self.counts.iter().sum::<usize>() - self.counts[Band::NoSlide as usize]
    }

    /// One line: the count of every category.
    pub fn summary(&self) -> String {
        let parts: Vec<String> = BAND_FLAGS
            .iter()
            .map(|(code, word)| format!("{word} {}", self.counts[*code as usize]))
            .collect();
        format!(
            "{}; {} slide, of which {} have T_new > 1.005·T_rigid",
            parts.join(", "),
            self.sliding(),
            self.above_1_005
        )
    }
}

/// `T_new` of a case whose mean peak displacement with the stack is `u_m`: where the mean
/// displacement spectrum `(periods_s, sd_m)` equals it ([`period_at_displacement`]) when some
/// interface slipped, `T_rigid` when none did.
pub fn t_new(
    periods_s: &[f64],
    sd_m: &[f64],
    u_m: f64,
    t_rigid_s: f64,
    slides: bool,
) -> (f64, TnewFlag) {
    if slides {
        period_at_displacement(periods_s, sd_m, u_m, t_rigid_s)
    } else {
        (t_rigid_s, TnewFlag::NoSlide)
    }
}

/// The period at which the piecewise-linear curve `(periods_s, sd_m)` equals `u_m`, by the rule
/// of the module doc; `periods_s` increasing.
pub fn period_at_displacement(
    periods_s: &[f64],
    sd_m: &[f64],
    u_m: f64,
    t_rigid_s: f64,
) -> (f64, TnewFlag) {
    let mut crossings = Vec::new();
    for i in 0..periods_s.len().saturating_sub(1) {
        let (a, b) = (sd_m[i] - u_m, sd_m[i + 1] - u_m);
        if a == 0.0 {
            crossings.push(periods_s[i]);
        } else if a * b < 0.0 {
            let f = a / (a - b);
            crossings.push(periods_s[i] + f * (periods_s[i + 1] - periods_s[i]));
        }
    }
    if let (Some(&last_t), Some(&last_s)) = (periods_s.last(), sd_m.last())
        && last_s == u_m
    {
        crossings.push(last_t);
    }
    match crossings.len() {
        0 => (f64::NAN, TnewFlag::OutsideRange),
        1 => (crossings[0], TnewFlag::Unique),
        _ => {
            let best = crossings
                .iter()
                .copied()
                .min_by(|x, y| {
                    (x / t_rigid_s)
                        .ln()
                        .abs()
                        .total_cmp(&(y / t_rigid_s).ln().abs())
                })
                .expect("non-empty");
            (best, TnewFlag::Several)
        }
    }
}

// A zone's `T_new`: what the stage computes between reading the sweep and writing `tnew.h5`.

/// Why a zone's `T_new` could not be made.
#[derive(Debug, thiserror::Error)]
pub enum TnewError {
    #[error("zone {zone}: spectrum of motion {motion}: {source}")]
    Spectrum {
        zone: String,
        motion: String,
        source: SpectrumError,
    },
    #[error("zone {zone}: the attached fractions: {source}")]
    Attached {
        zone: String,
        source: Box<AttachedError>,
    },
}

impl TnewError {
    /// Whether `keep_going` said stop (Ctrl-C), rather than an input the zone cannot take.
    pub fn is_stopped(&self) -> bool {
        matches!(self, Self::Attached { source, .. } if matches!(**source, AttachedError::Stopped))
    }
}

/// What a zone's `T_new` is made from: the study's shape, the zone's motions and its sweep.
pub struct ZoneInputs<'a> {
    pub name: &'a str,
    pub target: &'a str,
    pub grid: &'a Grid,
    pub physics: &'a Physics,
    /// A building study's axes (`None` on one storey): the stored shape and `N_max`.
    pub building: Option<&'a BuildingAxes>,
    /// The study's frames in stored order ([`Frame::one_storey`] on one storey).
    pub frames: &'a [Frame],
    pub motions: &'a [Record],
    /// The zone's sweep, its motion axis the order of `motions`.
    pub sweep: &'a ZoneSweep,
    /// Asked before each case of the attached fractions (Ctrl-C).
    pub keep_going: &'a (dyn Fn() -> bool + Sync),
}

/// A zone's `T_new` and what the stage reports of it.
pub struct ZoneOutcome {
    pub tnew: ZoneTnew,
    /// The zone's cases (over the frames).
    pub cases: usize,
    pub bands: BandCounts,
    /// A building study's effective live-load fractions, counted.
    pub fractions: Option<FractionCounts>,
}

/// How a zone's `λ` fell over the cases of its distinct buildings (a frame that repeats another
/// is its copy, [`crate::study::building::repeats`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FractionCounts {
    pub cases: usize,
    /// Cases per flag word, in [`FRACTION_FLAGS`]' order.
    pub by_flag: Vec<(&'static str, usize)>,
    /// Cases whose `λ` is below 0.
    pub below_zero: usize,
}

impl FractionCounts {
    fn new(fractions: &[CaseFractions], frames: &[Frame], per_frame: usize) -> Self {
        let repeated = repeats(frames);
        let counted: Vec<&CaseFractions> = (0..frames.len())
            .filter(|&f| !repeated[f])
            .flat_map(|f| &fractions[f * per_frame..(f + 1) * per_frame])
            .collect();
        let by_flag = (FRACTION_FLAGS.iter())
            .map(|&(code, word)| {
                let k = (counted.iter())
                    .filter(|x| x.storey[0].1 as u8 == code)
                    .count();
                (word, k)
            })
            .collect();
        Self {
            cases: counted.len(),
            by_flag,
            below_zero: counted.iter().filter(|x| x.storey[0].0 < 0.0).count(),
        }
    }

    /// One line: the cases counted, per flag, and below 0.
    pub fn summary(&self) -> String {
        let counts: Vec<String> = (self.by_flag.iter())
            .map(|(word, k)| format!("{word} {k}"))
            .collect();
        format!(
            "over the {} cases of the distinct buildings: {}; {} below 0 (the stack lowers the \
             base shear below the bare building's)",
            self.cases,
            counts.join(", "),
            self.below_zero
        )
    }
}

/// A zone's `T_new` (paper Section 7.1; a building of several storeys: `T_1` of the attached
/// fraction of its roof's mean peak displacement, docs/model.md, "A study over buildings"),
/// its `DRR`s and, in a building study, its attached fractions: [`ZoneWork`] with every unit
/// computed here (the units in parallel).
pub fn zone(inp: &ZoneInputs) -> Result<ZoneOutcome, TnewError> {
    let units = fraction_units(inp.grid, inp.building, inp.frames);
    let work = ZoneWork::new(inp, &units);
    let of_units = (work.units().par_iter())
        .map(|u| work.fractions_of(u))
        .collect::<Result<Vec<_>, _>>()?;
    work.finish(of_units)
}

/// The units of a zone's attached fractions: [`attached::fraction_units`] of `grid`'s cases in
/// each of `frames` in a building study (of `building` axes); none on one storey, which stores
/// no `λ`.
pub fn fraction_units(
    grid: &Grid,
    building: Option<&BuildingAxes>,
    frames: &[Frame],
) -> Vec<FractionUnit> {
    match building {
        Some(_) => attached::fraction_units(grid, frames),
        None => Vec::new(),
    }
}

/// A zone's `T_new` in two parts, so that its costly part can be split (`tnew --shard`): the
/// attached fractions' units ([`attached::fraction_units`]: none on one storey), each computed
/// on its own by [`Self::fractions_of`], and [`Self::finish`] with every unit's fractions.
pub struct ZoneWork<'a> {
    inp: &'a ZoneInputs<'a>,
    /// The motions' accelerations, m/s² (empty without units).
    accels: Vec<Vec<f64>>,
    /// The means over the motions (summed in motion order, then divided), `[(frame,) case…]`.
    u_stack: ArrayD<f64>,
    u_single: ArrayD<f64>,
    u_rigid: ArrayD<f64>,
    /// Per case (flat over `[frame][case]`): whether any interface slipped under any motion.
    slides: Vec<bool>,
    /// A building study's sweep means per case and its units; empty on one storey.
    swept: Vec<attached::Swept>,
    units: &'a [FractionUnit],
}

impl<'a> ZoneWork<'a> {
    /// The zone's means over the motions, from the sweep (no simulation), and its `units`:
    /// [`attached::fraction_units`] of the study's grid and frames (none on one storey).
    pub fn new(inp: &'a ZoneInputs<'a>, units: &'a [FractionUnit]) -> Self {
        let (grid, v) = (inp.grid, &inp.sweep.vars);
        let m = inp.motions.len();
        let mean = |v: &ArrayD<f64>| v.sum_axis(Axis(0)) / m as f64;
        let (u_stack, u_single, u_rigid) = (mean(&v.u_stack), mean(&v.u_single), mean(&v.u_rigid));
        let per_frame = grid.cases();
        let cases = inp.frames.len() * per_frame;
        let slides = slides(&v.slip_peak, m, cases, grid.blocks());
        let swept = match (&inp.sweep.building, inp.building) {
            (Some(bv), Some(_)) => swept(bv, &u_stack, &u_rigid, inp.frames, per_frame, m),
            _ => Vec::new(),
        };
        // The motions' accelerations, for the units' simulations only.
        let accels = match units.is_empty() {
            true => Vec::new(),
            false => inp.motions.iter().map(|r| r.accel_mps2(1.0)).collect(),
        };
        Self {
            inp,
            accels,
            u_stack,
            u_single,
            u_rigid,
            slides,
            swept,
            units,
        }
    }

    /// The units of the zone's attached fractions (none on one storey).
    pub fn units(&self) -> &[FractionUnit] {
        self.units
    }

    /// The attached fractions of `unit`'s cases, in its order.
    pub fn fractions_of(&self, unit: &FractionUnit) -> Result<Vec<CaseFractions>, TnewError> {
        let grounds: Vec<Ground> = (self.inp.motions.iter().zip(&self.accels))
            .map(|(r, a)| Ground::new(r.dt_s, a))
            .collect();
        let family = ZoneFamily {
            physics: self.inp.physics,
            grid: self.inp.grid,
            frames: self.inp.frames,
            grounds: &grounds,
            swept: &self.swept,
            slides: &self.slides,
            keep_going: self.inp.keep_going,
        };
        family.unit(unit).map_err(|e| TnewError::Attached {
            zone: self.inp.name.to_string(),
            source: Box::new(e),
        })
    }

    /// The zone's `T_new`, `DRR`s and attached fractions from every unit's fractions
    /// (`of_units`, in [`Self::units`]' order).
    pub fn finish(self, of_units: Vec<Vec<CaseFractions>>) -> Result<ZoneOutcome, TnewError> {
        let (inp, grid) = (self.inp, self.inp.grid);
        let period_sd_s = spectrum_periods_s(grid);
        let sd_mean_m = mean_displacement_spectrum(inp.name, inp.motions, &period_sd_s)?;
        let per_frame = grid.cases();
        let cases = inp.frames.len() * per_frame;
        let mut shape: Vec<usize> = inp.building.iter().flat_map(|b| b.shape()).collect();
        shape.extend(grid.shape());
        let shaped = |v: Vec<f64>| {
            ArrayD::from_shape_vec(shape.clone(), v).expect("one value per case of the grid")
        };
        let fractions = match (&inp.sweep.building, inp.building) {
            (Some(_), Some(_)) => Some(attached::spread(grid, inp.frames, self.units, &of_units)),
            _ => None,
        };
        let participation: Vec<f64> = inp.frames.iter().map(Frame::roof_participation).collect();
        let p = CasePeriods::of(
            grid,
            inp.frames,
            &participation,
            (&period_sd_s, &sd_mean_m),
            &self.u_stack,
            &self.slides,
            fractions.as_deref(),
        );
        let bands = BandCounts::new(&p.band, &p.t_new, &p.t_rigid);
        let lambda = match (&fractions, inp.building) {
            (Some(l), Some(axes)) => Some(attached_vars(
                l,
                &shape,
                axes.max_storeys(),
                shaped(p.t_first_mode.clone()),
            )),
            _ => None,
        };
        let (u_stack, u_single, u_rigid) = (self.u_stack, self.u_single, self.u_rigid);
        let vars = TnewVars {
            drr_1: &u_stack / &u_rigid,
            drr_2: &u_single / &u_rigid,
            u_stack_mean: u_stack,
            u_single_mean: u_single,
            u_rigid_mean: u_rigid,
            t_rigid: shaped(p.t_rigid),
            t_new: shaped(p.t_new),
            slides: shaped(
                self.slides
                    .iter()
                    .map(|&b| f64::from(u8::from(b)))
                    .collect(),
            ),
            flag: shaped(p.flag),
            band: ArrayD::from_shape_vec(shape.clone(), p.band).expect("one code per case"),
        };
        // Γ_1·φ_1,N per storey count (stored).
        let roof_participation = match inp.building {
            None => Vec::new(),
            Some(b) => (0..b.storeys.len())
                .map(|s| participation[s * b.stack_floor.len()])
                .collect(),
        };
        let m = inp.motions.len();
        Ok(ZoneOutcome {
            fractions: (fractions.as_deref())
                .map(|l| FractionCounts::new(l, inp.frames, per_frame)),
            tnew: ZoneTnew {
                name: inp.name.to_string(),
                target: inp.target.to_string(),
                vars,
                period_sd_s,
                sd_mean_m,
                roof_participation,
                lambda,
                rocks_share: (inp.sweep.rocks_stack.as_ref())
                    .map(|r| r.mapv(f64::from).sum_axis(Axis(0)) / m as f64),
            },
            cases,
            bands,
        })
    }
}

/// The zone's mean 5 %-damped displacement spectrum at `periods_s`, m (summed in motion order,
/// then divided).
fn mean_displacement_spectrum(
    zone: &str,
    motions: &[Record],
    periods_s: &[f64],
) -> Result<Vec<f64>, TnewError> {
    let spectra = (motions.par_iter())
        .map(|r| {
            response_spectrum(&r.accel_mps2(1.0), r.dt_s, periods_s, TARGET_DAMPING)
                .map(|s| s.sd_m())
                .map_err(|source| TnewError::Spectrum {
                    zone: zone.to_string(),
                    motion: r.name.clone(),
                    source,
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((0..periods_s.len())
        .map(|p| spectra.iter().map(|s| s[p]).sum::<f64>() / motions.len() as f64)
        .collect())
}

/// Whether each case slides: any interface slips under any motion (`slip_peak`, `[motion,
/// (frame,) case…, interface]`, folded over its first and last axes).
fn slides(slip_peak: &ArrayD<f64>, motions: usize, cases: usize, blocks: usize) -> Vec<bool> {
    let slip = (slip_peak.view())
        .into_shape_with_order((motions, cases, blocks))
        .expect("slip_peak has shape [motion, cases, interface]");
    (0..cases)
        .map(|c| slip.index_axis(Axis(1), c).iter().any(|&x| x > 0.0))
        .collect()
}

/// Every case's periods and flags, flat over `[frame][case]`.
struct CasePeriods {
    t_rigid: Vec<f64>,
    t_new: Vec<f64>,
    /// The first-mode definition (one storey: the paper's `T_new`).
    t_first_mode: Vec<f64>,
    flag: Vec<f64>,
    band: Vec<u8>,
}

impl CasePeriods {
    /// One storey keeps the paper's `T_new` (its `T_rigid` and participation of 1 are the
    /// paper's arithmetic, [`Frame::t_rigid_s`], [`Frame::roof_participation`]); a building of
    /// several storeys reads it off the attached fraction of its roof's mean peak displacement
    /// (`fractions`' `roof`).
    fn of(
        grid: &Grid,
        frames: &[Frame],
        participation: &[f64],
        (period_sd_s, sd_mean_m): (&[f64], &[f64]),
        u_stack: &ArrayD<f64>,
        slides: &[bool],
        fractions: Option<&[CaseFractions]>,
    ) -> Self {
        let per_frame = grid.cases();
        let cases = slides.len();
        let mut p = Self {
            t_rigid: Vec::with_capacity(cases),
            t_new: Vec::with_capacity(cases),
            t_first_mode: Vec::with_capacity(cases),
            flag: Vec::with_capacity(cases),
            band: Vec::with_capacity(cases),
        };
        for (c, (&us, &slid)) in u_stack.iter().zip(slides).enumerate() {
            let case = grid.case(c % per_frame);
            let frame = &frames[c / per_frame];
            let (tr, u) = (frame.t_rigid_s(&case), us / participation[c / per_frame]);
            let (first_mode, paper_flag) = t_new(period_sd_s, sd_mean_m, u, tr, slid);
            let (tn, f) = match fractions {
                Some(l) if frame.storeys() > 1 => {
                    let (fraction, how) = l[c].roof;
                    of_attached(frame.t1_attached_s(&case, fraction), how)
                }
                _ => (first_mode, paper_flag),
            };
            p.t_rigid.push(tr);
            p.t_new.push(tn);
            p.t_first_mode.push(first_mode);
            p.flag.push(f64::from(f as u8));
            p.band.push(Band::of(case.period_s, tr, tn, f) as u8);
        }
        p
    }
}

/// The sweep's means over the motions (summed in motion order, then divided) of every case of
/// a building study's zone that the attached fractions need ([`ZoneFamily`]): per case (flat over
/// `[frame][case]`) the stack's and the rigid system's mean peaks and the mean stuck share,
/// `None` in a building of one storey (its integrator gives neither the shears nor the share).
fn swept(
    bv: &BuildingVars,
    u_stack: &ArrayD<f64>,
    u_rigid: &ArrayD<f64>,
    frames: &[Frame],
    per_frame: usize,
    motions: usize,
) -> Vec<attached::Swept> {
    let cases = frames.len() * per_frame;
    let nmax = bv.storey_shear_stack.shape().last().copied().unwrap_or(0);
    let mean = |v: &ArrayD<f64>| {
        let sum = v.sum_axis(Axis(0)) / motions as f64;
        sum.into_iter().collect::<Vec<f64>>()
    };
    let (ss, sr) = (mean(&bv.storey_shear_stack), mean(&bv.storey_shear_rigid));
    let (os, or) = (mean(&bv.overturning_stack), mean(&bv.overturning_rigid));
    let share = mean(&bv.stuck_share_stack);
    let (us, ur): (Vec<f64>, Vec<f64>) = (
        u_stack.iter().copied().collect(),
        u_rigid.iter().copied().collect(),
    );
    (0..cases)
        .map(|c| {
            let n = frames[c / per_frame].storeys();
            (n > 1).then(|| {
                let means = |roof: f64, shear: &[f64], moment: f64| attached::Means {
                    roof_m: roof,
                    storey_shear: shear[c * nmax..c * nmax + n].to_vec(),
                    overturning: moment,
                };
                (means(us[c], &ss, os[c]), means(ur[c], &sr, or[c]), share[c])
            })
        })
        .collect()
}

/// The stored attached fractions (`tnew.h5`'s `AttachedVars`), shaped as the zone's cases
/// (`shape`), the per-storey ones with a trailing axis of `nmax` (NaN, 255 for flags, above a
/// building's roof).
fn attached_vars(
    l: &[CaseFractions],
    shape: &[usize],
    nmax: usize,
    t_new_first_mode: ArrayD<f64>,
) -> AttachedVars {
    let per_case = |get: &dyn Fn(&CaseFractions) -> f64| {
        ArrayD::from_shape_vec(shape.to_vec(), l.iter().map(get).collect())
            .expect("one value per case of the grid")
    };
    let flags = |get: &dyn Fn(&CaseFractions) -> FractionFlag| {
        ArrayD::from_shape_vec(shape.to_vec(), l.iter().map(|x| get(x) as u8).collect())
            .expect("one code per case of the grid")
    };
    let mut storey_shape = shape.to_vec();
    storey_shape.push(nmax);
    let storey = |get: &dyn Fn(&(f64, FractionFlag)) -> f64| {
        let v = (l.iter())
            .flat_map(|x| (0..nmax).map(|i| x.storey.get(i).map_or(f64::NAN, get)))
            .collect();
        ArrayD::from_shape_vec(storey_shape.clone(), v).expect("one per case and storey")
    };
    AttachedVars {
        base_shear_stack_mean: per_case(&|x| x.stack.storey_shear[0]),
        base_shear_rigid_mean: per_case(&|x| x.rigid.storey_shear[0]),
        base_shear_bare_mean: per_case(&|x| x.bare.storey_shear[0]),
        base_shear_ratio_bare: per_case(&|x| x.stack.storey_shear[0] / x.bare.storey_shear[0]),
        base_shear_ratio_rigid: per_case(&|x| x.stack.storey_shear[0] / x.rigid.storey_shear[0]),
        stuck_share_mean: per_case(&|x| x.share),
        lambda: per_case(&|x| x.storey[0].0),
        flag: flags(&|x| x.storey[0].1),
        lambda_storey: storey(&|s| s.0),
        lambda_storey_flag: storey(&|s| f64::from(s.1 as u8))
            .mapv(|v| if v.is_nan() { 255 } else { v as u8 }),
        lambda_overturning: per_case(&|x| x.overturning.0),
        lambda_overturning_flag: flags(&|x| x.overturning.1),
        lambda_code: per_case(&|x| x.code.0),
        lambda_code_flag: flags(&|x| x.code.1),
        attached_fraction_roof: per_case(&|x| x.roof.0),
        attached_fraction_roof_flag: flags(&|x| x.roof.1),
        t_new_first_mode,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_categories_by_precedence() {
        let b = |t: f64, f| Band::of(1.0, 1.5, t, f);
        assert_eq!(b(1.5, TnewFlag::NoSlide), Band::NoSlide);
        assert_eq!(b(f64::NAN, TnewFlag::OutsideRange), Band::NoCrossing);
        assert_eq!(b(1.6, TnewFlag::Several), Band::AboveTrigid);
        assert_eq!(b(0.9, TnewFlag::Unique), Band::BelowTp);
        assert_eq!(b(1.2, TnewFlag::Several), Band::SeveralCrossings);
        assert_eq!(b(1.0, TnewFlag::Unique), Band::Band);
        assert_eq!(b(1.5, TnewFlag::Unique), Band::Band);
    }

    #[test]
    fn hand_cases() {
        // Sd = 0.1·T on [0.5, 2]: ū = 0.138 m lies at T = 1.38 s (docs/model.md's Section 7.1 number
        // in the 1/T branch, Sd ∝ T), exactly on the straight segment.
        let t = [0.5, 1.0, 1.5, 2.0];
        let sd = [0.05, 0.1, 0.15, 0.2];
        let (tn, f) = period_at_displacement(&t, &sd, 0.138, 1.7);
        assert!((tn - 1.38).abs() < 1e-12 && f == TnewFlag::Unique, "{tn}");
        // On a grid point.
        assert_eq!(
            period_at_displacement(&t, &sd, 0.1, 1.7),
            (1.0, TnewFlag::Unique)
        );
        assert_eq!(
            period_at_displacement(&t, &sd, 0.2, 1.7),
            (2.0, TnewFlag::Unique)
        );
        // Outside the range.
        let (tn, f) = period_at_displacement(&t, &sd, 0.3, 1.7);
        assert!(tn.is_nan() && f == TnewFlag::OutsideRange);
        // Three crossings, at 0.75, 1.25 and 1.75: nearest T_rigid = 1.6 is 1.75; to 0.7, 0.75.
        let sd2 = [0.05, 0.15, 0.05, 0.15];
        let (tn, f) = period_at_displacement(&t, &sd2, 0.1, 1.6);
        assert!((tn - 1.75).abs() < 1e-12 && f == TnewFlag::Several, "{tn}");
        let (tn, _) = period_at_displacement(&t, &sd2, 0.1, 0.7);
        assert!((tn - 0.75).abs() < 1e-12, "{tn}");
    }
}
