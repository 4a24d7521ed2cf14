//! The designer's entry point: `T_new` of one structure from a finished study.
//!
//! For a zone, a structure period `T_p` and a stack (`α_i`, `μ_i`): `T_rigid = T_p·sqrt(1+α)`;
//! `T_new` by multilinear interpolation in the study's stored grid (`tnew.h5`; outside the grid
//! only with `extrapolate`, and then from the fit); `T_new` from the zone's recommended fitted
//! form (`fit.yaml`); `T_new` from the paper's Eqs. 16–17 (zones III and V, two blocks); and
//! the zone's design spectral acceleration (its target spectrum, `Z·Sa/g` for IS 1893) at `T_p`
//! and at `T_new`, from the target spectrum stored in `motions.h5` (never from a table file,
//! which may have changed since). Reads only verified files of the study directory, and only a
//! `motions.h5` that `tnew.h5` was made from.
//!
//! In a building study the question names a frame, a storey count and the floor carrying the
//! stack (`floor N` is the roof): `T_p` is then the bare building's first-mode period `T_1`,
//! `T_rigid` the first-mode period with the stack rigidly attached to its floor(s)
//! ([`crate::study::building::Frame::t_rigid_s`], from the frame `fit.yaml` stores), the grid's
//! `T_new` the frame's own, the fit evaluated with the building's features. Between storey
//! counts or floors nothing is interpolated: a frame the study does not hold is refused.

use crate::case::Case;
use crate::fit::{BuildingFeatures, Fitted, PaperEquation, Sample, features};
use crate::grid::{BuildingAxes, Grid, OutsideGrid, StackFloor};
use crate::spectrum::target::TargetSpectrum;
use crate::store::StoreError;
use crate::store::fit::{FitReport, FormFit, FrameSpec, ZoneFit, read_fit};
use crate::store::h5::stored_fingerprint;
use crate::store::motions::read_zone_target;
use crate::store::tnew::{
    is_building, read_motions_fingerprint, read_zone_tnew_in, zones_and_blocks,
};
use serde::Serialize;
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum DesignError {
    #[error("{}: no {file} (run the study into it first)", dir.display())]
    Missing { dir: PathBuf, file: &'static str },
    #[error("zone `{zone}` is not in the study; it has {known}")]
    UnknownZone { zone: String, known: String },
    #[error("`{what}` lists {got} values but the study's stacks have {blocks} blocks")]
    Count {
        what: &'static str,
        got: usize,
        blocks: usize,
    },
    #[error("{what} = {value} must be finite and > 0")]
    Value { what: String, value: f64 },
    #[error("{0}; with `extrapolate` the fitted form answers there")]
    Outside(OutsideGrid),
    #[error("{}: belongs to another tnew.h5 than the study's: rerun `slidestack fit`", file.display())]
    Mismatch { file: PathBuf },
    /// `motions.h5` is not the one `tnew.h5` was made from (or `tnew.h5` does not say which).
    #[error("{}: {why}", file.display())]
    OtherMotions { file: PathBuf, why: &'static str },
    #[error(
        "{}: is a building study's (`building`): say which building, its storey count and the \
         floor carrying the stack (`storeys`, `floor`)",
        file.display()
    )]
    Building { file: PathBuf },
    #[error("{}: is a one-storey study's: `storeys` and `floor` are for a building study", file.display())]
    NotBuilding { file: PathBuf },
    #[error(
        "the study has no building of {storeys} storeys with the stack on floor `{floor}`; it has {known}"
    )]
    UnknownFrame {
        storeys: usize,
        floor: String,
        known: String,
    },
    #[error(transparent)]
    Store(#[from] StoreError),
}

impl DesignError {
    /// Whether the question (or a missing study) is at fault rather than the study's files.
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            DesignError::Store(_) | DesignError::Mismatch { .. } | DesignError::OtherMotions { .. }
        )
    }
}

/// What a designer asks.
#[derive(Debug, Clone, PartialEq)]
pub struct Query {
    pub zone: String,
    /// Period of the bare structure `T_p`, s.
    pub period_s: f64,
    /// Block mass ratios, bottom first.
    pub alpha: Vec<f64>,
    /// Kinetic friction coefficients, interface 1 first.
    pub mu: Vec<f64>,
    /// Outside the grid, answer from the fit instead of refusing.
    pub extrapolate: bool,
    /// A building study's: the storey count and the floor carrying the stack (`period_s` is
    /// then the bare building's first-mode period `T_1`).
    pub building: Option<(usize, StackFloor)>,
}

/// The answer (`slidestack design --json` prints it).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Answer {
    pub zone: String,
    pub target: String,
    /// A building study's frame (`3 storeys, stack on the roof`); `period_s` is its `T_1`,
    /// `t_rigid_s` its `T_1,rigid` and every `T_new` the first mode's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub building: Option<String>,
    pub period_s: f64,
    pub alpha: Vec<f64>,
    pub mu: Vec<f64>,
    pub t_rigid_s: f64,
    /// By multilinear interpolation in the stored grid; `None` outside it, or where a grid
    /// point it needs has no `T_new`.
    pub t_new_grid_s: Option<f64>,
    /// From the zone's recommended fitted form.
    pub t_new_fit_s: Option<f64>,
    pub fit_form: String,
    /// The paper's Eq. 16 (Zone III) or 17 (Zone V), two blocks only.
    pub t_new_paper_s: Option<f64>,
    /// Design spectral acceleration of the zone at `T_p`, g.
    pub sa_tp_g: f64,
    /// At the grid's `T_new`, else the fit's, g.
    pub sa_new_g: Option<f64>,
    /// Design spectral acceleration at each `T_new`, g (`None` where that `T_new` is).
    pub sa_new_grid_g: Option<f64>,
    pub sa_new_fit_g: Option<f64>,
    pub sa_new_paper_g: Option<f64>,
    /// A building study's effective live-load fraction `λ` of the stack's mass, by
    /// multilinear interpolation in the frame's cases (`None` outside the grid or where a
    /// corner has none) …
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_grid: Option<f64>,
    /// … and from the zone's fitted equation for `λ`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_fit: Option<f64>,
    /// Anything the designer should know about these numbers.
    pub notes: Vec<String>,
}

/// What the answers for one zone are computed from, and all of it: the report's design page
/// embeds it as JSON (its script repeats [`answer`]'s arithmetic on the same numbers).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ZoneDesign {
    pub zone: String,
    /// The zone's target spectrum, as stored in `motions.h5`.
    pub target: TargetSpectrum,
    pub grid: Grid,
    /// `T_new` (s) per case, in the grid's flat order (NaN, `null` in JSON, where none).
    pub t_new_s: Vec<f64>,
    /// The zone's recommended fitted form and its parameters.
    pub fit: Option<Fitted>,
    /// The paper's Eq. 16 or 17, for zones III and V with two blocks.
    pub paper: Option<PaperEquation>,
    /// A building study's frame, and the building features of its fit (`None`: the
    /// one-storey features, a study of one frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub building: Option<(FrameSpec, Option<BuildingFeatures>)>,
    /// A building study's `λ` per case of the frame (grid's flat order) and its fitted
    /// equation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda: Option<(Vec<f64>, Option<Fitted>)>,
}

impl ZoneDesign {
    /// From a zone's stored `T_new` (`grid`'s flat order), its fit and its target.
    pub fn new(
        zone: &str,
        target: TargetSpectrum,
        grid: Grid,
        t_new_s: Vec<f64>,
        fit: Option<&ZoneFit>,
    ) -> Self {
        let paper = PaperEquation::of_zone(zone).filter(|_| grid.blocks() == 2);
        Self {
            zone: zone.to_string(),
            target,
            fit: fit.and_then(|z| z.recommended_fit()).map(FormFit::fitted),
            grid,
            t_new_s,
            paper,
            building: None,
            lambda: None,
        }
    }
}

/// `Err` unless `value` is finite and positive.
fn positive(what: String, value: f64) -> Result<(), DesignError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(DesignError::Value { what, value })
    }
}

/// The question's numbers are finite and positive.
fn check_values(q: &Query) -> Result<(), DesignError> {
    positive("`period_s`".into(), q.period_s)?;
    for (i, &a) in q.alpha.iter().enumerate() {
        positive(format!("alpha_{}", i + 1), a)?;
    }
    for (i, &m) in q.mu.iter().enumerate() {
        positive(format!("mu_{}", i + 1), m)?;
    }
    Ok(())
}

/// Answers `q` from the finished study in `dir`.
pub fn design(dir: &Path, q: &Query) -> Result<Answer, DesignError> {
    check_values(q)?;
    let tnew = dir.join("tnew.h5");
    let fit_yaml = dir.join("fit.yaml");
    let motions = dir.join("motions.h5");
    let missing = |file| DesignError::Missing {
        dir: dir.to_path_buf(),
        file,
    };
    let tnew_fp = stored_fingerprint(&tnew)?.ok_or_else(|| missing("tnew.h5"))?;
    let building = is_building(&tnew)?;
    match (building, q.building) {
        (true, None) => return Err(DesignError::Building { file: tnew }),
        (false, Some(_)) => return Err(DesignError::NotBuilding { file: tnew }),
        _ => {}
    }
    let motions_fp = stored_fingerprint(&motions)?.ok_or_else(|| missing("motions.h5"))?;
    match read_motions_fingerprint(&tnew)? {
        Some(fp) if fp == motions_fp => {}
        Some(_) => {
            return Err(DesignError::OtherMotions {
                file: motions,
                why: "tnew.h5 was made from another motions.h5: rerun the study",
            });
        }
        None => {
            return Err(DesignError::OtherMotions {
                file: tnew,
                why: "made by an earlier slidestack, it does not record its motions.h5: rebuild it \
                      (the tnew stage, forced)",
            });
        }
    }
    let fit = read_fit(&fit_yaml)?.ok_or_else(|| missing("fit.yaml"))?;
    if fit.fingerprint != crate::pipeline::fit::fingerprint(&tnew_fp, building) {
        return Err(DesignError::Mismatch { file: fit_yaml });
    }
    let (zones, blocks) = zones_and_blocks(&tnew)?;
    fit.check_blocks(&fit_yaml, blocks)?;
    if !zones.contains(&q.zone) {
        return Err(DesignError::UnknownZone {
            zone: q.zone.clone(),
            known: zones.join(", "),
        });
    }
    check_counts(q, blocks)?;
    let (grid, axes, t) = read_zone_tnew_in(&tnew, &q.zone, blocks, building)?;
    let target = read_zone_target(&motions, &q.zone)?;
    let zone_fit = fit.zones.iter().find(|z| z.zone == q.zone);
    let t_new: Vec<f64> = t.vars.t_new.iter().copied().collect();
    let (t_new, frame, lambda) = match (q.building, axes) {
        (Some((storeys, floor)), Some(axes)) => {
            let f = frame_index(&fit, &axes, storeys, floor, &fit_yaml)?;
            let cases = f * grid.cases()..(f + 1) * grid.cases();
            let features = BuildingFeatures::of_names(&fit.features, blocks);
            let frame = (fit.frames[f].clone(), features);
            let lambda = t.lambda.as_ref().map(|l| {
                let values: Vec<f64> = l.lambda.iter().copied().collect();
                let fitted = zone_fit
                    .and_then(|z| z.lambda.as_ref())
                    .map(FormFit::fitted);
                (values[cases.clone()].to_vec(), fitted)
            });
            (t_new[cases].to_vec(), Some(frame), lambda)
        }
        _ => (t_new, None, None),
    };
    let mut data = ZoneDesign::new(&q.zone, target, grid, t_new, zone_fit);
    data.building = frame;
    data.lambda = lambda;
    answer(&data, q)
}

/// The index of the frame of `storeys` storeys with the stack on `floor` among the study's
/// (`fit.yaml`'s, `tnew.h5`'s order): the one whose stacks stand on the same floors (floor `N`
/// is the roof).
fn frame_index(
    fit: &FitReport,
    axes: &BuildingAxes,
    storeys: usize,
    floor: StackFloor,
    fit_yaml: &Path,
) -> Result<usize, DesignError> {
    let stored: Vec<(usize, StackFloor)> = (0..axes.frames()).map(|f| axes.frame(f)).collect();
    let agrees = fit.frames.len() == stored.len()
        && (fit.frames.iter().zip(&stored))
            .all(|(a, b)| a.storeys == b.0 && a.stack_floor == b.1.to_string());
    if !agrees {
        return Err(DesignError::Mismatch {
            file: fit_yaml.to_path_buf(),
        });
    }
    let wanted = floor.floors(storeys);
    if let StackFloor::Floor(j) = floor
        && !(1..=storeys).contains(&j)
    {
        return Err(DesignError::UnknownFrame {
            storeys,
            floor: floor.to_string(),
            known: format!("floors 1 … {storeys} in a building of {storeys} storeys"),
        });
    }
    (stored.iter())
        .position(|&(n, f)| n == storeys && f.floors(n) == wanted)
        .ok_or_else(|| DesignError::UnknownFrame {
            storeys,
            floor: floor.to_string(),
            known: (fit.frames.iter())
                .filter_map(FrameSpec::frame)
                .map(|f| format!("`{f}`"))
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// One value per block in `alpha` and `mu`.
fn check_counts(q: &Query, blocks: usize) -> Result<(), DesignError> {
    for (what, got) in [("alpha", q.alpha.len()), ("mu", q.mu.len())] {
        if got != blocks {
            return Err(DesignError::Count { what, got, blocks });
        }
    }
    Ok(())
}

/// Answers `q` (whose zone is `z`'s) from `z`, files aside.
pub fn answer(z: &ZoneDesign, q: &Query) -> Result<Answer, DesignError> {
    check_values(q)?;
    check_counts(q, z.grid.blocks())?;
    let case = Case {
        period_s: q.period_s,
        alpha: q.alpha.clone(),
        mu: q.mu.clone(),
    };
    let frame =
        (z.building.as_ref()).and_then(|(spec, features)| Some((spec.frame()?, spec, *features)));
    let t_rigid_s = frame
        .as_ref()
        .map_or_else(|| case.t_rigid_s(), |(f, _, _)| f.t_rigid_s(&case));
    let mut notes = Vec::new();
    if frame.is_some() {
        notes.push(
            "a building: T_p is its bare first-mode period T_1, T_rigid its first-mode period \
             with the stacks rigidly attached, T_new the first mode's; the paper's equation is \
             the one-storey one, read at T_1"
                .into(),
        );
    }

    let mut point = vec![q.period_s];
    point.extend(&q.alpha);
    point.extend(&q.mu);
    let t_new_grid_s = match z.grid.interpolate(&z.t_new_s, &point) {
        Ok(Some(v)) => Some(v),
        Ok(None) => {
            notes.push(
                "a grid point next to this structure has no T_new (no crossing of the mean \
                 displacement spectrum): no interpolated value"
                    .into(),
            );
            None
        }
        Err(outside) if q.extrapolate => {
            notes.push(format!("{outside}: T_new from the fitted form"));
            None
        }
        Err(outside) => return Err(DesignError::Outside(outside)),
    };

    let x = features(q.period_s, &q.alpha, &q.mu);
    let fit_x = match &frame {
        Some((f, spec, Some(bf))) => bf.features(
            q.period_s,
            &q.alpha,
            &q.mu,
            spec.storeys,
            f.stack_height_ratio(),
        ),
        _ => x.clone(),
    };
    let t_new_fit_s = z.fit.as_ref().map(|f| {
        f.predict(&Sample {
            x: fit_x.clone(),
            t_rigid_s,
            t_new_s: f64::NAN,
        })
    });
    let (lambda_grid, lambda_fit) = match &z.lambda {
        Some((values, fitted)) => (
            z.grid.interpolate(values, &point).ok().flatten(),
            fitted.as_ref().map(|f| {
                f.predict(&Sample {
                    x: fit_x,
                    t_rigid_s,
                    t_new_s: f64::NAN,
                })
            }),
        ),
        None => (None, None),
    };
    let t_new_paper_s = z.paper.and_then(|p| p.evaluate(&x));
    let target = &z.target;
    let sa = |t: Option<f64>| t.filter(|t| t.is_finite()).map(|t| target.sa_g(t));
    Ok(Answer {
        zone: q.zone.clone(),
        target: target.to_string(),
        building: frame.map(|(f, _, _)| f.to_string()),
        period_s: q.period_s,
        alpha: q.alpha.clone(),
        mu: q.mu.clone(),
        t_rigid_s,
        t_new_grid_s,
        t_new_fit_s,
        fit_form: z
            .fit
            .as_ref()
            .map_or_else(String::new, |f| f.form.name().to_string()),
        t_new_paper_s,
        sa_tp_g: target.sa_g(q.period_s),
        sa_new_g: sa(t_new_grid_s.or(t_new_fit_s)),
        sa_new_grid_g: sa(t_new_grid_s),
        sa_new_fit_g: sa(t_new_fit_s),
        sa_new_paper_g: sa(t_new_paper_s),
        lambda_grid,
        lambda_fit,
        notes,
    })
}
