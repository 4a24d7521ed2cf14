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

use crate::fit::{BuildingFeatures, Sample, features};
use crate::grid::Grid;
use crate::study::attached::FractionFlag;
use crate::study::building::Frame;

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
