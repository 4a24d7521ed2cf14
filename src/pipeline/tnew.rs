//! The T_new stage: per zone and case, the mean peak displacements over the motions, `T_rigid`,
//! `T_new` read off the zone's mean 5 %-damped displacement spectrum (paper Section 7.1; the
//! rule for several crossings in [`crate::study::tnew`]), whether anything slid, `DRR_1` and
//! `DRR_2` → `tnew.h5` (layout in [`crate::store::tnew`]).
//!
//! In a building study (docs/model.md, "A study over buildings") every frame (`storeys`,
//! `stack_floor`) is done alike: one storey keeps the paper's `T_new`, bit for bit; a building
//! of several storeys reads it off the attached fraction of the roof's mean peak displacement,
//! the first-mode period of the building carrying that fraction of its stack (and keeps the
//! earlier first-mode definition as `T_new_first_mode`). Its cases also get their attached
//! fractions ([`crate::study::attached`]: `λ` of the base shear, of each storey's shear and of
//! the overturning moment, `λ_code`), which run the linear building with part of the stack
//! attached (the stage's only simulations; on one storey also the stack and the rigid system,
//! whose shears the sweep's one-storey integrator does not give).
//!
//! Fingerprint: the sweep's, the step of the spectrum's period grid, the methods' versions.

use super::{PipelineError, Session, StageId, StageOutcome};
use crate::dynamics::Ground;
use crate::spectrum::{SpectrumError, TARGET_DAMPING, response_spectrum};
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::sweep::BuildingVars;
use crate::store::tnew::{AttachedVars, TnewMeta, TnewVars, ZoneTnew, write_tnew};
use crate::study::attached::{self, FRACTION_FLAGS, FractionFlag};
use crate::study::building::Frame;
use crate::study::tnew::{
    self, BAND_FLAGS, Band, BandCounts, SD_STEP_S, TNEW_FLAG_CODES, spectrum_periods_s,
};
use ndarray::{ArrayD, Axis};
use rayon::prelude::*;
use thiserror::Error;

#[derive(Debug, Error)]
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
        source: Box<attached::AttachedError>,
    },
}

/// The sweep's means over the motions (summed in motion order, then divided) of every case of
/// a building study's zone that [`attached::zone_fractions`] needs: per case (flat over
/// `[frame][case]`) the stack's and the rigid system's mean peaks and the mean stuck share, `None`
/// in a building of one storey (its integrator gives neither the shears nor the share).
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

/// The fingerprint `tnew.h5` must carry (`λ`'s definition and search are the `lambda` method's
/// version).
pub fn fingerprint(sweep_fingerprint: &str) -> String {
    let step = format!("sd_step_s={SD_STEP_S}");
    StageId::Tnew.fingerprint(&hash_parts(&[sweep_fingerprint, &step]))
}

/// Builds `tnew.h5`.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Tnew;
    let grid = study.grid(me)?;
    let motions = super::files::motions(study)?;
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
        let sw = super::files::sweep_zone(study, &zc.name, Some(&motions[z]))?;
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
        let shaped = |v: Vec<f64>| {
            ArrayD::from_shape_vec(shape.clone(), v).expect("one value per case of the grid")
        };
        let codes = |v: Vec<u8>| {
            ArrayD::from_shape_vec(shape.clone(), v).expect("one code per case of the grid")
        };
        // The building's attached fractions (docs/model.md, "The attached fraction").
        let fractions = match (&v.building, building) {
            (Some(bv), Some(axes)) => {
                let frames: Vec<Frame> = frames.iter().flatten().cloned().collect();
                let grounds: Vec<Vec<f64>> = motions[z].iter().map(|r| r.accel_mps2(1.0)).collect();
                let grounds: Vec<Ground> = (motions[z].iter().zip(&grounds))
                    .map(|(r, a)| Ground::new(r.dt_s, a))
                    .collect();
                let swept = swept(bv, &u_stack, &u_rigid, &frames, per_frame, m);
                let keep_going = || !s.reporter.cancelled();
                let l = attached::zone_fractions(
                    &physics,
                    grid,
                    &frames,
                    &grounds,
                    &swept,
                    &slides,
                    &keep_going,
                )
                .map_err(|e| match e {
                    attached::AttachedError::Stopped => PipelineError::Cancelled(me),
                    e => TnewError::Attached {
                        zone: zc.name.clone(),
                        source: Box::new(e),
                    }
                    .into(),
                })?;
                Some((l, axes.max_storeys()))
            }
            _ => None,
        };
        let mut t_rigid = Vec::with_capacity(cases);
        let mut t_new = Vec::with_capacity(cases);
        let mut t_first_mode = Vec::with_capacity(cases);
        let mut flag = Vec::with_capacity(cases);
        let mut band = Vec::with_capacity(cases);
        for (c, (&us, &slid)) in u_stack.iter().zip(&slides).enumerate() {
            let case = grid.case(c % per_frame);
            let frame = &frames[c / per_frame];
            let (tr, u) = match frame {
                None => (case.t_rigid_s(), us),
                Some(frame) => (frame.t_rigid_s(&case), us / participation[c / per_frame]),
            };
            let (first_mode, paper_flag) = tnew::t_new(&period_sd_s, &sd_mean_m, u, tr, slid);
            // One storey keeps the paper's T_new; a building of several storeys reads it off
            // the attached fraction of its roof's mean peak displacement.
            let (tn, f) = match (frame, &fractions) {
                (Some(fr), Some((l, _))) if fr.storeys() > 1 => {
                    let (fraction, how) = l[c].roof;
                    tnew::of_attached(fr.t1_attached_s(&case, fraction), how)
                }
                _ => (first_mode, paper_flag),
            };
            t_rigid.push(tr);
            t_new.push(tn);
            t_first_mode.push(first_mode);
            flag.push(f64::from(f as u8));
            band.push(Band::of(case.period_s, tr, tn, f) as u8);
        }
        let lambda = fractions.map(|(l, nmax)| {
            // Counted over the distinct buildings: a frame that repeats another is its copy.
            let distinct = study.distinct_frames();
            let counted: Vec<&attached::CaseFractions> = (distinct.iter())
                .flat_map(|(f, _)| &l[f * per_frame..(f + 1) * per_frame])
                .collect();
            let counts: Vec<String> = (FRACTION_FLAGS.iter())
                .map(|(code, word)| {
                    let k = (counted.iter())
                        .filter(|x| x.storey[0].1 as u8 == *code)
                        .count();
                    format!("{word} {k}")
                })
                .collect();
            let below = counted.iter().filter(|x| x.storey[0].0 < 0.0).count();
            s.reporter.info(
                me,
                &format!(
                    "zone {}: effective live-load fraction λ over the {} cases of the distinct \
                     buildings: {}; {below} below 0 (the stack lowers the base shear below the \
                     bare building's)",
                    zc.name,
                    counted.len(),
                    counts.join(", ")
                ),
            );
            let per_case =
                |get: &dyn Fn(&attached::CaseFractions) -> f64| shaped(l.iter().map(get).collect());
            let flags = |get: &dyn Fn(&attached::CaseFractions) -> FractionFlag| {
                codes(l.iter().map(|x| get(x) as u8).collect())
            };
            let mut storey_shape = shape.clone();
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
                base_shear_ratio_bare: per_case(&|x| {
                    x.stack.storey_shear[0] / x.bare.storey_shear[0]
                }),
                base_shear_ratio_rigid: per_case(&|x| {
                    x.stack.storey_shear[0] / x.rigid.storey_shear[0]
                }),
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
                t_new_first_mode: shaped(t_first_mode.clone()),
            }
        });
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
            rocks_share: (v.rocks_stack.as_ref()).map(|r| mean(&r.mapv(f64::from))),
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
        band_flags: BAND_FLAGS,
        lambda_flags: FRACTION_FLAGS,
        mu_static_ratio: physics.mu_static_ratio,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_tnew(&path, &meta, grid, building, &zones)?;
    Ok(StageOutcome::Wrote(vec![path]))
}
