//! The designer's arithmetic: `T_new` of one structure from a study's data ([`ZoneDesign`]),
//! which `slidestack design` reads from a finished study's files ([`crate::design`]) and the
//! report's design page embeds.
//!
//! For a zone, a structure period `T_p` and a stack (`α_i`, `μ_i`): `T_rigid = T_p·sqrt(1+α)`;
//! `T_new` by multilinear interpolation in the study's stored grid (`tnew.h5`; outside the grid
//! only with `extrapolate`, and then from the fit, on the box beyond the grid where the fit stage
//! checked it, [`ZoneDesign::extrapolation_margin`]); `T_new` from the zone's recommended fitted
//! form (`fit.yaml`); `T_new` from the paper's Eqs. 16–17 (zones III and V, two blocks; a fitted
//! or paper `T_new` that is no period is left out with a note); and
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
use crate::fit::extrapolation::{LOWER_T_P, UPPER_T_RIGID};
use crate::fit::{BuildingFeatures, Fitted, PaperEquation, Sample, features};
use crate::grid::{BuildingAxes, Grid, OutsideGrid, StackFloor};
use crate::limits::STRUCTURE_PERIOD_RANGE_S;
use crate::spectrum::target::TargetSpectrum;
use crate::store::StoreError;
use crate::store::fit::{FitReport, FormFit, FrameSpec, ZoneFit};
use crate::store::tnew::ZoneTnew;
use crate::study::building::{Frame, repeats};
use serde::Serialize;
use std::ops::Range;
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
    /// A period no structure `simulate` runs has ([`STRUCTURE_PERIOD_RANGE_S`]).
    #[error(
        "{what} = {value:?} must be within {} … {} s, the periods of a structure `simulate` runs",
        STRUCTURE_PERIOD_RANGE_S.0,
        STRUCTURE_PERIOD_RANGE_S.1
    )]
    Period { what: String, value: f64 },
    #[error("{0}; with `extrapolate` the fitted form answers there")]
    Outside(OutsideGrid),
    /// Outside the grid with `extrapolate`, where the fitted form was not checked
    /// ([`ZoneDesign::extrapolation_margin`]).
    #[error(
        "{dim} = {value:?} lies outside {} … {}, the study's grid ({} … {}) and {:.0} % beyond, \
         the only range where the fitted form was checked to stay a period of the structure \
         (finite, T_new within {LOWER_T_P}·T_p … {UPPER_T_RIGID}·T_rigid): nothing answers there",
        shown(*lo), shown(*hi), shown(*grid_lo), shown(*grid_hi), 100.0 * margin
    )]
    BeyondFit {
        dim: String,
        value: f64,
        lo: f64,
        hi: f64,
        grid_lo: f64,
        grid_hi: f64,
        margin: f64,
    },
    /// Outside the grid with `extrapolate`, and no fitted form passed its check beyond the grid.
    #[error(
        "{0}; no fitted form was found to stay a period of the structure beyond the grid \
         (fit.yaml's box check), so nothing answers there"
    )]
    Unchecked(OutsideGrid),
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
    /// … and from the zone's fitted equation for `λ` (of `max(λ, 0)`, the fraction a designer
    /// counts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_fit: Option<f64>,
    /// A building study's code-format fraction `λ_code` (docs/model.md, "The code-format
    /// fraction"), by multilinear interpolation in the frame's cases: the fraction of the live
    /// load that, counted as seismic weight with the zone's mean spectrum at the loaded first
    /// mode, gives the sliding stack's base shear.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_code_grid: Option<f64>,
    /// With `grid.aspect`: the share of the motions under which the stack would start to
    /// rock, by multilinear interpolation in the grid (> 0: some grid case around this one
    /// leaves the sliding-only model under some motion, and a note says so).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rocks_share: Option<f64>,
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
    /// A building study's frame and the building features of its fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub building: Option<FrameDesign>,
    /// A building study's `λ` per case of the frame and its fitted equation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda: Option<LambdaDesign>,
    /// A building study's code-format `λ_code` per case of the frame (grid's flat order).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda_code: Option<Vec<f64>>,
    /// With `grid.aspect`: per case (grid's flat order), the share of the motions under which
    /// the stack would start to rock (`tnew.h5`'s `rocks_share`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rocks_share: Option<Vec<f64>>,
    /// How far beyond the grid the fitted form answers (`extrapolate`): the margin, a fraction
    /// of each axis's extreme values, of the box on which the recommended form was checked to
    /// stay finite and inside `[½·T_p, 1.5·T_rigid]` (`fit.yaml`'s `box_check`). `None` when
    /// it failed that check or there is none: then nothing answers outside the grid.
    pub extrapolation_margin: Option<f64>,
}

/// A building study's frame as the designer's arithmetic (and the page) needs it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameDesign {
    /// The frame as `fit.yaml` stores it.
    pub frame: FrameSpec,
    /// The building features of the fit (`None`: the one-storey features, a study of one
    /// frame).
    pub features: Option<BuildingFeatures>,
}

/// A building study's `λ` on one frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LambdaDesign {
    /// `λ` per case of the frame, in the grid's flat order (NaN, `null` in JSON, where none).
    pub per_case: Vec<f64>,
    /// The zone's fitted fraction equation.
    pub fit: Option<Fitted>,
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
        let recommended = fit.and_then(|z| z.recommended_fit());
        Self {
            zone: zone.to_string(),
            target,
            fit: recommended.map(FormFit::fitted),
            grid,
            t_new_s,
            paper,
            building: None,
            lambda: None,
            lambda_code: None,
            rocks_share: None,
            extrapolation_margin: (recommended.map(|f| &f.box_check))
                .filter(|b| b.passed)
                .map(|b| b.margin),
        }
    }

    /// Zone `zone` of a one-storey study: its stored `T_new` and rocking shares (`t`), its fit
    /// and its target.
    pub fn of_zone(
        zone: &str,
        target: TargetSpectrum,
        grid: Grid,
        t: &ZoneTnew,
        fit: Option<&ZoneFit>,
    ) -> Self {
        let flat = |v: &ndarray::ArrayD<f64>| v.iter().copied().collect::<Vec<f64>>();
        let mut data = Self::new(zone, target, grid, flat(&t.vars.t_new), fit);
        data.rocks_share = t.rocks_share.as_ref().map(flat);
        data
    }

    /// Frame `f` (stored order) of zone `zone` of a building study: the frame's cases of the
    /// zone's stored `T_new` and `λ` (`t` holds every frame's), `fit.yaml`'s frame and
    /// building features, the zone's fits of `T_new` and `λ`.
    pub fn of_frame(
        zone: &str,
        target: TargetSpectrum,
        grid: Grid,
        t: &ZoneTnew,
        fit: &FitReport,
        f: usize,
    ) -> Self {
        let cases = frame_cases(&grid, f);
        let zone_fit = fit.zones.iter().find(|z| z.zone == zone);
        let frame_of = |v: &ndarray::ArrayD<f64>| -> Vec<f64> {
            v.iter()
                .skip(cases.start)
                .take(cases.len())
                .copied()
                .collect()
        };
        let features = BuildingFeatures::of_names(&fit.features, grid.blocks());
        let lambda = t.lambda.as_ref().map(|l| {
            let fitted = zone_fit
                .and_then(|z| z.lambda.as_ref())
                .map(FormFit::fitted);
            LambdaDesign {
                per_case: frame_of(&l.lambda),
                fit: fitted,
            }
        });
        let mut data = Self::new(zone, target, grid, frame_of(&t.vars.t_new), zone_fit);
        data.building = Some(FrameDesign {
            frame: fit.frames[f].clone(),
            features,
        });
        data.lambda = lambda;
        data.lambda_code = t.lambda.as_ref().map(|l| frame_of(&l.lambda_code));
        data.rocks_share = t.rocks_share.as_ref().map(frame_of);
        data
    }

    /// A building study's frame, `3 storeys, stack on the roof` (as [`Answer::building`]).
    pub fn frame_label(&self) -> Option<String> {
        let b = self.building.as_ref()?;
        Some(Frame::of_spec(&b.frame)?.to_string())
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

/// The question's numbers are finite and positive, the period one a structure may have.
pub(crate) fn check_values(q: &Query) -> Result<(), DesignError> {
    positive("`period_s`".into(), q.period_s)?;
    let (lo, hi) = STRUCTURE_PERIOD_RANGE_S;
    if !(lo..=hi).contains(&q.period_s) {
        return Err(DesignError::Period {
            what: "`period_s`".into(),
            value: q.period_s,
        });
    }
    for (i, &a) in q.alpha.iter().enumerate() {
        positive(format!("alpha_{}", i + 1), a)?;
    }
    for (i, &m) in q.mu.iter().enumerate() {
        positive(format!("mu_{}", i + 1), m)?;
    }
    Ok(())
}

/// The cases of frame `f` (stored order) among a building study's, every frame's cases
/// flat (`[storeys, stack_floor, T_p, alpha…, mu…]` row-major).
pub fn frame_cases(grid: &Grid, f: usize) -> Range<usize> {
    f * grid.cases()..(f + 1) * grid.cases()
}

/// `Err` unless `fit.yaml`'s frames are `tnew.h5`'s (`axes`), in the same order.
pub(crate) fn check_frames(
    fit: &FitReport,
    axes: &BuildingAxes,
    fit_yaml: &Path,
) -> Result<(), DesignError> {
    let agrees = fit.frames.len() == axes.frame_count()
        && (fit.frames.iter().enumerate()).all(|(f, a)| {
            let (n, floor) = axes.frame(f);
            a.storeys == n && a.stack_floor == floor.to_string()
        });
    if agrees {
        Ok(())
    } else {
        Err(DesignError::Mismatch {
            file: fit_yaml.to_path_buf(),
        })
    }
}

/// Every frame `f` of zone `zone` of a building study that [`crate::design::design`] answers from, with its
/// [`ZoneDesign`], in stored order: a frame repeating an earlier one's building
/// ([`repeats`]) is left out, since [`crate::design::design`] answers a question about it from the earlier
/// one. `t` is the zone's `tnew.h5` (with its `axes`), `fit` the study's `fit.yaml` (read
/// from `fit_yaml`). The report's design page embeds these.
pub fn frame_designs(
    zone: &str,
    target: &TargetSpectrum,
    grid: &Grid,
    axes: &BuildingAxes,
    t: &ZoneTnew,
    fit: &FitReport,
    fit_yaml: &Path,
) -> Result<Vec<(usize, ZoneDesign)>, DesignError> {
    check_frames(fit, axes, fit_yaml)?;
    let frames: Vec<Frame> = (fit.frames.iter())
        .map(Frame::of_spec)
        .collect::<Option<_>>()
        .ok_or_else(|| DesignError::Mismatch {
            file: fit_yaml.to_path_buf(),
        })?;
    Ok((repeats(&frames).into_iter().enumerate())
        .filter(|(_, r)| !r)
        .map(|(f, _)| {
            let d = ZoneDesign::of_frame(zone, target.clone(), grid.clone(), t, fit, f);
            (f, d)
        })
        .collect())
}

/// `3 storeys, stack on the roof` of every frame of `fit`, each in backticks: the frames a
/// building study holds, as a refusal lists them.
pub fn known_frames(fit: &FitReport) -> String {
    (fit.frames.iter())
        .filter_map(Frame::of_spec)
        .map(|f| format!("`{f}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The index of the frame of `storeys` storeys with the stack on `floor` among the study's
/// (`fit.yaml`'s, `tnew.h5`'s order, checked alike by [`check_frames`]): the first whose
/// stacks stand on the same floors (floor `N` is the roof).
pub(crate) fn frame_index(
    fit: &FitReport,
    axes: &BuildingAxes,
    storeys: usize,
    floor: StackFloor,
) -> Result<usize, DesignError> {
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
    (0..axes.frame_count())
        .map(|f| axes.frame(f))
        .position(|(n, f)| n == storeys && f.floors(n) == wanted)
        .ok_or_else(|| DesignError::UnknownFrame {
            storeys,
            floor: floor.to_string(),
            known: known_frames(fit),
        })
}

/// One value per block in `alpha` and `mu`.
pub(crate) fn check_counts(q: &Query, blocks: usize) -> Result<(), DesignError> {
    for (what, got) in [("alpha", q.alpha.len()), ("mu", q.mu.len())] {
        if got != blocks {
            return Err(DesignError::Count { what, got, blocks });
        }
    }
    Ok(())
}

/// `v` rounded to 7 significant digits, as a message shows a bound computed from the grid.
fn shown(v: f64) -> String {
    format!("{:?}", format!("{v:.6e}").parse::<f64>().unwrap_or(v))
}

/// `Err` unless the fitted form may answer at `point` (`[T_p, α…, μ…]`, outside the grid by
/// `outside`): inside the box beyond the grid on which it was checked
/// ([`ZoneDesign::extrapolation_margin`], the box of the fit stage's check, `fit::DesignBox`).
fn check_extrapolation(
    z: &ZoneDesign,
    point: &[f64],
    outside: OutsideGrid,
) -> Result<(), DesignError> {
    let Some(margin) = z.extrapolation_margin else {
        return Err(DesignError::Unchecked(outside));
    };
    let g = &z.grid;
    let axes = std::iter::once(&g.periods_s).chain(&g.alpha).chain(&g.mu);
    for ((axis, &value), dim) in axes.zip(point).zip(g.dim_names()) {
        let grid_lo = axis.iter().copied().fold(f64::INFINITY, f64::min);
        let grid_hi = axis.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = ((1.0 - margin) * grid_lo, (1.0 + margin) * grid_hi);
        if !(lo..=hi).contains(&value) {
            return Err(DesignError::BeyondFit {
                dim,
                value,
                lo,
                hi,
                grid_lo,
                grid_hi,
                margin,
            });
        }
    }
    Ok(())
}

/// `t`, a `T_new` (s) from `what`, if it is a period (finite and > 0); else `None`, with a
/// note saying so.
fn a_period(t: Option<f64>, what: &str, notes: &mut Vec<String>) -> Option<f64> {
    match t {
        Some(t) if !(t.is_finite() && t > 0.0) => {
            notes.push(format!(
                "{what} gives T_new = {t:?} s here, which is no period: left out"
            ));
            None
        }
        t => t,
    }
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
        (z.building.as_ref()).and_then(|b| Some((Frame::of_spec(&b.frame)?, &b.frame, b.features)));
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
            check_extrapolation(z, &point, outside.clone())?;
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
    let t_new_fit_s = a_period(t_new_fit_s, "the fitted form", &mut notes);
    let (lambda_grid, lambda_fit) = match &z.lambda {
        Some(l) => (
            z.grid.interpolate(&l.per_case, &point).ok().flatten(),
            l.fit.as_ref().map(|f| {
                f.predict(&Sample {
                    x: fit_x,
                    t_rigid_s,
                    t_new_s: f64::NAN,
                })
            }),
        ),
        None => (None, None),
    };
    let lambda_code_grid = (z.lambda_code.as_ref())
        .and_then(|values| z.grid.interpolate(values, &point).ok().flatten());
    let rocks_share = (z.rocks_share.as_ref())
        .and_then(|values| z.grid.interpolate(values, &point).ok().flatten());
    if rocks_share.is_some_and(|s| s > 0.0) {
        notes.push(
            "rocking: the stack would start to rock under some of the motions (rocks_share, \
             interpolated from the grid cases around this structure): there the sliding-only \
             model's T_new and λ are outside their model (docs/model.md, \"Rocking: when a case \
             leaves the model\")"
                .into(),
        );
    }
    let t_new_paper_s = a_period(
        z.paper.and_then(|p| p.evaluate(&x)),
        "the paper's equation",
        &mut notes,
    );
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
        lambda_code_grid,
        rocks_share,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::paper_equation;

    /// Zone V on a grid of `periods_s`, every `T_new` 1 s, no fit unless `margin` (a fit that
    /// passed its box check on that margin: the paper form with every parameter 0, whose
    /// `T_new` is 0 everywhere).
    fn zone_v(periods_s: Vec<f64>, margin: Option<f64>) -> ZoneDesign {
        let grid = Grid {
            periods_s,
            alpha: vec![vec![0.5, 1.0], vec![0.5, 1.0]],
            mu: vec![vec![0.05, 0.3], vec![0.05, 0.1]],
        };
        let mut z = ZoneDesign::new(
            "V",
            "is1893:zone=V,soil=I".parse().unwrap(),
            grid.clone(),
            vec![1.0; grid.cases()],
            None,
        );
        z.extrapolation_margin = margin;
        z.fit = margin.map(|_| Fitted {
            form: crate::fit::Form::Paper,
            params: vec![0.0; 12],
        });
        z
    }

    fn query(period_s: f64, alpha: [f64; 2], extrapolate: bool) -> Query {
        Query {
            zone: "V".into(),
            period_s,
            alpha: alpha.to_vec(),
            mu: vec![0.05, 0.05],
            extrapolate,
            building: None,
        }
    }

    #[test]
    fn a_paper_or_fitted_t_new_that_is_no_period_is_left_out_with_a_note() {
        // Eq. 17 at T_p = 0.01 s, α 1/1, μ 0.05/0.05 is −0.04 s; the fit here gives 0 s.
        let z = zone_v(vec![0.01, 0.5], Some(0.25));
        let a = answer(&z, &query(0.01, [1.0, 1.0], false)).unwrap();
        let paper = paper_equation("V", &[0.01, 0.05, 0.05, 1.0, 1.0]).unwrap();
        assert!(paper < 0.0, "{paper}");
        assert_eq!((a.t_new_paper_s, a.sa_new_paper_g), (None, None));
        assert_eq!((a.t_new_fit_s, a.sa_new_fit_g), (None, None));
        assert_eq!(a.t_new_grid_s, Some(1.0));
        assert_eq!(
            a.notes,
            [
                "the fitted form gives T_new = 0.0 s here, which is no period: left out"
                    .to_string(),
                format!(
                    "the paper's equation gives T_new = {paper:?} s here, which is no period: left out"
                ),
            ]
        );
    }

    #[test]
    fn extrapolation_answers_only_where_the_fit_was_checked() {
        // Grid T_p 0.3 … 2 s: checked 25 % beyond, 0.225 … 2.5 s.
        let z = zone_v(vec![0.3, 2.0], Some(0.25));
        assert!(answer(&z, &query(2.5, [1.0, 1.0], true)).is_ok());
        let e = answer(&z, &query(2.6, [1.0, 1.0], true)).unwrap_err();
        assert_eq!(
            crate::fault::classify(&e).kind,
            crate::fault::FaultKind::BadInput
        );
        assert_eq!(
            e.to_string(),
            "T_p = 2.6 lies outside 0.225 … 2.5, the study's grid (0.3 … 2.0) and 25 % beyond, \
             the only range where the fitted form was checked to stay a period of the structure \
             (finite, T_new within 0.5·T_p … 1.5·T_rigid): nothing answers there"
        );
        let e = answer(&z, &query(1.0, [1.0, 1.3], true)).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("alpha_2 = 1.3 lies outside 0.375 … 1.25"),
            "{e}"
        );
        // Without a checked fit, nothing answers outside the grid.
        let e = answer(&zone_v(vec![0.3, 2.0], None), &query(2.4, [1.0, 1.0], true)).unwrap_err();
        assert!(
            e.to_string().starts_with(
                "T_p = 2.4 lies outside the grid's 0.3 … 2; no fitted form was found to stay a \
                 period"
            ),
            "{e}"
        );
    }

    #[test]
    fn a_period_no_structure_has_is_refused_before_the_grid() {
        let z = zone_v(vec![0.3, 2.0], Some(0.25));
        for (period, shown) in [(1e-300, "1e-300"), (1e9, "1000000000.0"), (2e4, "20000.0")] {
            for extrapolate in [false, true] {
                let e = answer(&z, &query(period, [1.0, 1.0], extrapolate)).unwrap_err();
                assert_eq!(
                    crate::fault::classify(&e).kind,
                    crate::fault::FaultKind::BadInput
                );
                assert_eq!(
                    e.to_string(),
                    format!(
                        "`period_s` = {shown} must be within 0.000001 … 10000 s, the periods of \
                         a structure `simulate` runs"
                    )
                );
            }
        }
    }
}
