//! Constant-ductility response spectra (Chopra, *Dynamics of Structures*, Section 7.5): per
//! period, the yield strength of a bare elastic–perfectly-plastic (or bilinear) SDOF whose peak
//! displacement is a target multiple `μ` of its yield displacement.
//!
//! The strength is the yield strength ratio `C_y = F_y/(m·g) = A_y/g` (`A_y = ω²·u_y`, the
//! pseudo-acceleration at yield), normalised by the elastic one `C_e = ω²·u_o/g` (`u_o` the
//! elastic peak) as `f̄_y = C_y/C_e`. For `f̄_y ≥ 1` the SDOF stays elastic and `μ = 1/f̄_y`, so
//! `μ = 1` is `C_y = C_e`, the elastic pseudo-acceleration spectrum. For `μ > 1`, `μ(f̄_y)` is
//! continuous but not monotone: several strengths can give the same ductility. As Chopra does,
//! the largest is taken: `f̄_y` is scanned down from 1 in steps of
//! [`crate::limits::DUCTILITY_SCAN_STEP`] until `μ ≥ μ_target`, then bisected between that
//! point and the one above it to a relative width of [`STRENGTH_TOLERANCE`]. A root inside an
//! excursion of `μ(f̄_y)` above the target narrower than one scan step can be missed.
//!
//! Every response is the exact integrator's (`crate::dynamics::exact`, bare structure, no
//! blocks), so the peaks are exact between samples and yielding is located exactly.

use crate::dynamics::{
    ExactOptions, G, Ground, ModelError, SimError, System, SystemSpec, Yielding, simulate_exact,
};
use crate::limits::{DUCTILITY_SCAN_STEP, MAX_TARGET_DUCTILITY, PERIOD_RANGE_S};
use crate::spectrum::response::{SpectrumError, validate_record};
use rayon::prelude::*;
use thiserror::Error;

/// Relative width of the final bracket on the strength, `(f̄_hi − f̄_lo)/f̄_hi`.
pub const STRENGTH_TOLERANCE: f64 = 1e-10;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum DuctilityError {
    #[error("target ductility must be within 1 … {MAX_TARGET_DUCTILITY}, got {0:?}")]
    Target(f64),
    #[error(
        "period {0:?} s must be within {lo} … {hi} s",
        lo = PERIOD_RANGE_S.0,
        hi = PERIOD_RANGE_S.1
    )]
    Period(f64),
    #[error(transparent)]
    Record(#[from] SpectrumError),
    #[error("{0}")]
    Model(#[from] ModelError),
    #[error("T = {period_s} s: {source}")]
    Simulation { period_s: f64, source: SimError },
    #[error(
        "T = {period_s} s: the record leaves the oscillator at rest; no strength has a ductility"
    )]
    NoResponse { period_s: f64 },
    #[error(
        "T = {period_s} s: no strength down to C_y = {floor:e} reaches ductility {ductility} \
         (largest reached {reached})"
    )]
    NotReached {
        period_s: f64,
        ductility: f64,
        floor: f64,
        reached: f64,
    },
}

/// The oscillator family of a constant-ductility spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DuctilityOptions {
    /// Viscous damping ratio `ζ` of the elastic oscillator (`0 ≤ ζ < 1`).
    pub damping: f64,
    /// Post-yield stiffness ratio `r` (0: elastic–perfectly plastic, Chopra's case).
    pub post_yield_ratio: f64,
}

/// One period of a constant-ductility spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DuctilityPoint {
    pub period_s: f64,
    /// Yield strength ratio `C_y = F_y/(m·g) = A_y/g` that gives the target ductility.
    pub strength_ratio: f64,
    /// Yield displacement `D_y = u_y = C_y·g/ω²`, m.
    pub yield_displacement_m: f64,
    /// Peak displacement `u_m` at that strength, m.
    pub peak_displacement_m: f64,
    /// `u_m/u_y` at that strength (the target to within the bisection's tolerance).
    pub ductility: f64,
    /// Elastic strength ratio `C_e = ω²·u_o/g` (the elastic pseudo-acceleration `PSA/g`).
    pub elastic_strength_ratio: f64,
    /// Yield strength reduction factor `R_y = C_e/C_y` (Chopra, Eq. 7.3.3).
    pub reduction_factor: f64,
    /// Simulations spent on this period.
    pub runs: usize,
}

/// The constant-ductility spectrum of `accel_mps2` (m/s², step `dt_s`) for target ductility
/// `ductility` at `periods_s`; periods run in parallel.
pub fn constant_ductility_spectrum(
    accel_mps2: &[f64],
    dt_s: f64,
    periods_s: &[f64],
    ductility: f64,
    opts: DuctilityOptions,
) -> Result<Vec<DuctilityPoint>, DuctilityError> {
    validate_record(accel_mps2, dt_s)?;
    if !(1.0..=MAX_TARGET_DUCTILITY).contains(&ductility) {
        return Err(DuctilityError::Target(ductility));
    }
    for &t in periods_s {
        if !(PERIOD_RANGE_S.0..=PERIOD_RANGE_S.1).contains(&t) {
            return Err(DuctilityError::Period(t));
        }
    }
    // The oscillator family is refused once, not per period (`ζ/√r` does not depend on it).
    if let Some(&t) = periods_s.first() {
        bare(t, opts.damping)?.with_yielding(Yielding::bilinear(1.0, opts.post_yield_ratio))?;
    }
    let ground = Ground { dt_s, accel_mps2 };
    periods_s
        .par_iter()
        .map(|&t| point(&ground, t, ductility, opts))
        .collect()
}

fn bare(period_s: f64, damping: f64) -> Result<System, ModelError> {
    let mut spec = SystemSpec::new(period_s, &[], &[]);
    spec.damping_ratio = damping;
    System::new(&spec)
}

const RUN: ExactOptions = ExactOptions {
    history: false,
    max_switches_per_step: 1000,
    energy_balance: false,
    abs_velocity: false,
    floor_displacements: true,
};

fn point(
    ground: &Ground,
    period_s: f64,
    target: f64,
    opts: DuctilityOptions,
) -> Result<DuctilityPoint, DuctilityError> {
    let elastic = bare(period_s, opts.damping)?;
    let sim = |e: SimError| DuctilityError::Simulation {
        period_s,
        source: e,
    };
    let u_o = simulate_exact(&elastic, ground, &RUN)
        .map_err(sim)?
        .peak_displacement_m;
    let omega2 = elastic.stiffness() / elastic.mass_kg();
    let c_e = omega2 * u_o / G;
    if c_e <= 0.0 {
        return Err(DuctilityError::NoResponse { period_s });
    }
    let mut runs = 1;
    // Ductility and peak displacement at f̄_y, exact.
    let mut at = |f: f64| -> Result<(f64, f64), DuctilityError> {
        runs += 1;
        let sys = elastic
            .clone()
            .with_yielding(Yielding::bilinear(f * c_e, opts.post_yield_ratio))?;
        let r = simulate_exact(&sys, ground, &RUN).map_err(sim)?;
        Ok((r.ductility.unwrap_or(0.0), r.peak_displacement_m))
    };
    // f̄_y = 1 gives μ = 1 exactly (the elastic peak just reaches u_y); above, μ = 1/f̄_y < 1.
    let (mut lo, mut hi) = (1.0, 1.0);
    let mut at_lo = (1.0, u_o);
    let floor = crate::limits::STRENGTH_RATIO_RANGE.0 / c_e;
    let mut reached = 1.0f64;
    while at_lo.0 < target {
        hi = lo;
        lo *= DUCTILITY_SCAN_STEP;
        if lo < floor {
            return Err(DuctilityError::NotReached {
                period_s,
                ductility: target,
                floor: crate::limits::STRENGTH_RATIO_RANGE.0,
                reached,
            });
        }
        at_lo = at(lo)?;
        reached = reached.max(at_lo.0);
    }
    // μ(lo) ≥ target > μ(hi) (or lo = hi = 1 when the target is 1).
    while (hi - lo) > STRENGTH_TOLERANCE * hi {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let m = at(mid)?;
        if m.0 >= target {
            (lo, at_lo) = (mid, m);
        } else {
            hi = mid;
        }
    }
    let strength_ratio = lo * c_e;
    Ok(DuctilityPoint {
        period_s,
        strength_ratio,
        yield_displacement_m: strength_ratio * G / omega2,
        peak_displacement_m: at_lo.1,
        ductility: at_lo.0,
        elastic_strength_ratio: c_e,
        reduction_factor: 1.0 / lo,
        runs,
    })
}
