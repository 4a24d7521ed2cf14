//! The T_new stage: per zone and case, the mean peak displacements over the motions, `T_rigid`,
//! `T_new` read off the zone's mean 5 %-damped displacement spectrum (paper Section 7.1; the
//! rule for several crossings in [`crate::study::tnew`]), whether anything slid, `DRR_1` and
//! `DRR_2` → `tnew.h5` (layout in [`crate::store::tnew`]).
//!
//! In a building study (docs/model.md, "A study over buildings") every frame (`storeys`,
//! `stack_floor`) is done alike, with the first mode's `T_1,rigid` and the mean peak roof
//! displacement divided by `Γ_1·φ_1,N` (the first mode's equivalent-SDOF displacement) before
//! `T_new` is read off the spectrum; one storey is today's arithmetic, bit for bit. A building
//! study's cases also get their effective live-load fraction `λ` ([`crate::study::lambda`]),
//! which simulates the linear building with part of the stack attached (the stage's only
//! simulations; on one storey also the stack and the rigid system, whose base shear the
//! sweep's one-storey integrator does not give).
//!
//! Fingerprint: the sweep's, and the step of the spectrum's period grid.

use super::{Outcome, PipelineError, Session, StageId, Study};
use crate::dynamics::Ground;
use crate::grid::Grid;
use crate::ground_motion::Record;
use crate::spectrum::{SpectrumError, TARGET_DAMPING, response_spectrum};
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::sweep::read_zone_sweep;
use crate::store::tnew::{LambdaVars, TnewMeta, TnewVars, ZoneTnew, read_zone_tnew_in, write_tnew};
use crate::study::building::{Frame, first_of_building};
use crate::study::lambda::{self, LAMBDA_FLAGS, LambdaFlag};
use crate::study::physics::{CaseError, Physics, SystemKind};
use crate::study::tnew::{self, BAND_FLAGS, Band, BandCounts, TNEW_FLAG_CODES};
use ndarray::{ArrayD, Axis};
use rayon::prelude::*;
use std::collections::BTreeMap;
use thiserror::Error;

/// Step of the period grid of the mean displacement spectrum, s.
pub const SD_STEP_S: f64 = 0.005;

#[derive(Debug, Error)]
pub enum TnewError {
    #[error("zone {zone}: spectrum of motion {motion}: {source}")]
    Spectrum {
        zone: String,
        motion: String,
        source: SpectrumError,
    },
    #[error("zone {zone}: the effective live-load fraction: {source}")]
    Lambda {
        zone: String,
        source: Box<CaseError>,
    },
}

/// One case's effective live-load fraction and the mean base shears it comes from.
#[derive(Debug, Clone, Copy)]
struct Fraction {
    stack: f64,
    rigid: f64,
    bare: f64,
    lambda: f64,
    flag: LambdaFlag,
}

/// The effective live-load fraction of every case (flat over `[frame][case]`) of a building
/// study's zone ([`crate::study::lambda`]): `V̄_stack` and `V̄(1)` are the means over the
/// motions (summed in motion order, then divided, as [`lambda::mean_base_shear`] sums) of the
/// sweep's `base_shear_stack`/`base_shear_rigid` (`[motion][frame][case]`; on one storey,
/// where those are NaN, simulated here by the building's integrator); `V̄(0)` and the values
/// between are simulated. Cases in parallel, each on its own: the same numbers whatever the
/// threads.
fn effective_fractions(
    physics: &Physics,
    grid: &Grid,
    frames: &[Option<Frame>],
    motions: &[Record],
    base_shear_stack: &[f64],
    base_shear_rigid: &[f64],
    slides: &[bool],
) -> Result<Vec<Fraction>, CaseError> {
    let per_frame = grid.cases();
    let cases = frames.len() * per_frame;
    let m = motions.len();
    let accel: Vec<Vec<f64>> = motions.iter().map(|r| r.accel_mps2(1.0)).collect();
    let grounds: Vec<Ground> = (motions.iter().zip(&accel))
        .map(|(r, a)| Ground::new(r.dt_s, a))
        .collect();
    let grounds = &grounds[..];
    let mean = |v: &[f64], c: usize| (0..m).map(|k| v[k * cases + c]).sum::<f64>() / m as f64;
    let frame_of = |c: usize| {
        frames[c / per_frame]
            .as_ref()
            .expect("a building study has a frame per case")
    };
    // Frames that are one building have the same sweep results, so the same λ: each is
    // computed for the first of them only.
    let first = first_of_building(&frames.iter().flatten().cloned().collect::<Vec<_>>());
    let own: Vec<usize> = (0..cases)
        .filter(|&c| first[c / per_frame] == c / per_frame)
        .collect();
    // V̄(λ) depends on the frame, T_p and α (through the damping matrix) but not on μ: its
    // scan once per key, the first case of each standing for it.
    let bare_key = |c: usize| {
        let case = grid.case(c % per_frame);
        (
            c / per_frame,
            case.period_s.to_bits(),
            case.alpha_total().to_bits(),
        )
    };
    let mut keyed = BTreeMap::new();
    for &c in &own {
        keyed.entry(bare_key(c)).or_insert(c);
    }
    let keyed: Vec<((usize, u64, u64), usize)> = keyed.into_iter().collect();
    let scans: BTreeMap<(usize, u64, u64), Vec<(f64, f64)>> = keyed
        .par_iter()
        .map(|&(key, c)| {
            let case = grid.case(c % per_frame);
            let at = |l| lambda::mean_base_shear(physics, &case, frame_of(c), l, grounds);
            // V̄(1) is the sweep's rigid mean; the scan's end is only a placeholder here.
            lambda::scan(at(0.0)?, f64::NAN, at).map(|v| (key, v))
        })
        .collect::<Result<_, _>>()?;
    let computed: Vec<Fraction> = own
        .par_iter()
        .map(|&c| {
            let frame = frame_of(c);
            let case = grid.case(c % per_frame);
            // One storey's sweep runs the one-storey integrator, which gives no base shear.
            let (stack, rigid) = if frame.storeys() == 1 {
                let run =
                    |kind| lambda::mean_system_base_shear(physics, kind, &case, frame, grounds);
                (run(SystemKind::Stack)?, run(SystemKind::Rigid)?)
            } else {
                (mean(base_shear_stack, c), mean(base_shear_rigid, c))
            };
            let mut scan = scans[&bare_key(c)].clone();
            let bare = scan[0].1;
            scan.last_mut().expect("the scan has its ends").1 = rigid;
            let at = |l| lambda::mean_base_shear(physics, &case, frame, l, grounds);
            let (lambda, flag) = if slides[c] {
                lambda::solve_on(stack, &scan, at)?
            } else {
                (1.0, LambdaFlag::NoSlide)
            };
            Ok(Fraction {
                stack,
                rigid,
                bare,
                lambda,
                flag,
            })
        })
        .collect::<Result<_, CaseError>>()?;
    let at: BTreeMap<usize, usize> = own.iter().enumerate().map(|(i, &c)| (c, i)).collect();
    Ok((0..cases)
        .map(|c| computed[at[&(first[c / per_frame] * per_frame + c % per_frame)]])
        .collect())
}

/// The fingerprint `tnew.h5` must carry (`λ`'s definition and search are the `lambda` method's
/// version).
pub fn fingerprint(sweep_fingerprint: &str) -> String {
    let step = format!("sd_step_s={SD_STEP_S}");
    StageId::Tnew.fingerprint(&hash_parts(&[sweep_fingerprint, &step]))
}

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

/// Zone `zone` of `tnew.h5`, refused unless its grid and its spectrum's periods are the ones
/// the config gives.
pub fn read_zone(study: &Study, zone: &str) -> Result<ZoneTnew, PipelineError> {
    let grid = study.grid(StageId::Tnew)?;
    let path = study.path(StageId::Tnew.output());
    let building = study.building();
    let (axes, frames, t) = read_zone_tnew_in(&path, zone, grid.blocks(), building.is_some())?;
    let why = if axes != *grid || frames.as_ref() != building {
        "its grid differs from the config's"
    } else if t.period_sd_s != spectrum_periods_s(grid) {
        "its spectrum's periods differ from the config's grid"
    } else {
        return Ok(t);
    };
    Err(StoreError::corrupt(&path, format!("zone_{zone}: {why}")).into())
}

/// Builds `tnew.h5`.
pub fn build(s: &Session) -> Result<Outcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Tnew;
    let grid = study.grid(me)?;
    let motions = super::sweep::load_motions(study)?;
    let sweep_path = study.path(StageId::Sweep.output());
    let period_sd_s = spectrum_periods_s(grid);
    let n = grid.blocks();
    let physics = study.physics();
    let building = study.building();
    let frames = study.frames();
    // Γ_1·φ_1,N per frame, and per storey count (stored).
    let participation: Vec<f64> = (frames.iter())
        .map(|f| f.as_ref().map_or(1.0, Frame::roof_participation))
        .collect();
    let per_storeys: Vec<f64> = match building {
        None => Vec::new(),
        Some(b) => (0..b.storeys.len())
            .map(|s| participation[s * b.stack_floor.len()])
            .collect(),
    };
    let mut shape: Vec<usize> = building.iter().flat_map(|b| b.shape()).collect();
    shape.extend(grid.shape());
    let mut zones = Vec::new();
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let (axes, stored, sw) = read_zone_sweep(&sweep_path, &zc.name, n, building.is_some())?;
        let names: Vec<&String> = motions[z].iter().map(|r| &r.name).collect();
        let differs = if axes != *grid || stored.as_ref() != building {
            Some("its grid differs from the config's")
        } else if sw.motions.iter().collect::<Vec<_>>() != names {
            Some("its motions are not those of motions.h5")
        } else {
            None
        };
        if let Some(why) = differs {
            let why = format!("zone_{}: {why}", zc.name);
            return Err(StoreError::corrupt(&sweep_path, why).into());
        }
        let m = sw.motions.len();
        let spectra = motions[z]
            .par_iter()
            .map(|r| {
                response_spectrum(&r.accel_mps2(1.0), r.dt_s, &period_sd_s, TARGET_DAMPING)
                    .map(|s| s.sd_m())
                    .map_err(|source| TnewError::Spectrum {
                        zone: zc.name.clone(),
                        motion: r.name.clone(),
                        source,
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let sd_mean_m: Vec<f64> = (0..period_sd_s.len())
            .map(|p| spectra.iter().map(|s| s[p]).sum::<f64>() / m as f64)
            .collect();
        // Means over the motion axis (summed in motion order, then divided).
        let mean = |v: &ArrayD<f64>| v.sum_axis(Axis(0)) / m as f64;
        let v = &sw.vars;
        let (u_stack, u_single, u_rigid) = (mean(&v.u_stack), mean(&v.u_single), mean(&v.u_rigid));
        // A case slides when any interface slips under any motion: slip_peak [motion, (frame,)
        // case…, interface] folded over its first and last axes.
        let per_frame = grid.cases();
        let cases = frames.len() * per_frame;
        let slip = v
            .slip_peak
            .view()
            .into_shape_with_order((m, cases, n))
            .expect("slip_peak has shape [motion, cases, interface]");
        let slides: Vec<bool> = (0..cases)
            .map(|c| slip.index_axis(Axis(1), c).iter().any(|&x| x > 0.0))
            .collect();
        let mut t_rigid = Vec::with_capacity(cases);
        let mut t_new = Vec::with_capacity(cases);
        let mut flag = Vec::with_capacity(cases);
        let mut band = Vec::with_capacity(cases);
        for (c, (&us, &slid)) in u_stack.iter().zip(&slides).enumerate() {
            let case = grid.case(c % per_frame);
            let (tr, u) = match &frames[c / per_frame] {
                None => (case.t_rigid_s(), us),
                Some(frame) => (frame.t_rigid_s(&case), us / participation[c / per_frame]),
            };
            let (tn, f) = tnew::t_new(&period_sd_s, &sd_mean_m, u, tr, slid);
            t_rigid.push(tr);
            t_new.push(tn);
            flag.push(f64::from(f as u8));
            band.push(Band::of(case.period_s, tr, tn, f) as u8);
        }
        let shaped = |v: Vec<f64>| {
            ArrayD::from_shape_vec(shape.clone(), v).expect("one value per case of the grid")
        };
        let lambda = match &v.building {
            None => None,
            Some(bv) => {
                let l = effective_fractions(
                    &physics,
                    grid,
                    &frames,
                    &motions[z],
                    bv.base_shear_stack.as_slice().expect("standard layout"),
                    bv.base_shear_rigid.as_slice().expect("standard layout"),
                    &slides,
                )
                .map_err(|source| TnewError::Lambda {
                    zone: zc.name.clone(),
                    source: Box::new(source),
                })?;
                let counts: Vec<String> = (LAMBDA_FLAGS.iter())
                    .map(|(code, word)| {
                        let k = l.iter().filter(|x| x.flag as u8 == *code).count();
                        format!("{word} {k}")
                    })
                    .collect();
                s.reporter.info(
                    me,
                    &format!("zone {}: effective live-load fraction λ: {}", zc.name, {
                        counts.join(", ")
                    }),
                );
                Some(LambdaVars {
                    base_shear_stack_mean: shaped(l.iter().map(|x| x.stack).collect()),
                    base_shear_rigid_mean: shaped(l.iter().map(|x| x.rigid).collect()),
                    base_shear_bare_mean: shaped(l.iter().map(|x| x.bare).collect()),
                    lambda: shaped(l.iter().map(|x| x.lambda).collect()),
                    flag: ArrayD::from_shape_vec(
                        shape.clone(),
                        l.iter().map(|x| x.flag as u8).collect(),
                    )
                    .expect("one code per case"),
                })
            }
        };
        let counts = BandCounts::new(&band, &t_new, &t_rigid);
        s.reporter.info(
            me,
            &format!("zone {}: {cases} cases; {}", zc.name, counts.summary()),
        );
        let vars = TnewVars {
            drr_1: &u_stack / &u_rigid,
            drr_2: &u_single / &u_rigid,
            u_stack_mean: u_stack,
            u_single_mean: u_single,
            u_rigid_mean: u_rigid,
            t_rigid: shaped(t_rigid),
            t_new: shaped(t_new),
            slides: shaped(slides.iter().map(|&b| f64::from(u8::from(b))).collect()),
            flag: shaped(flag),
            band: ArrayD::from_shape_vec(shape.clone(), band).expect("one code per case"),
        };
        zones.push(ZoneTnew {
            name: zc.name.clone(),
            target: zc.target.clone(),
            vars,
            period_sd_s: period_sd_s.clone(),
            sd_mean_m,
            roof_participation: per_storeys.clone(),
            lambda,
        });
        s.pass("tnew.zone", me)?;
    }
    let building_json = super::sweep::building_attr(study);
    let mut settings = super::sweep::physics_attrs(&physics).to_vec();
    if let Some(b) = &building_json {
        settings.push(("building", crate::store::h5::Attr::Str(b)));
    }
    let meta = TnewMeta {
        fingerprint: study.fingerprint(me)?,
        sweep_fingerprint: study.fingerprint(StageId::Sweep)?,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        flag_codes: TNEW_FLAG_CODES,
        band_flags: &BAND_FLAGS,
        lambda_flags: &LAMBDA_FLAGS,
        mu_static_ratio: physics.mu_static_ratio,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_tnew(&path, &meta, grid, building, &zones)?;
    Ok(Outcome::Wrote(vec![path]))
}
