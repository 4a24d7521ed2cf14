//! `design.html`: `slidestack design` in the browser, and an explorer of the grid's figures.
//! The page embeds each zone's [`ZoneDesign`], the very data the command answers from (in a
//! building study one per zone and frame, [`frame_designs`], the frames `design` answers
//! from), and the grid's `DRR_1` and `DRR_2` for the explorer (4 significant digits: they are
//! only drawn).

use super::text::num;
use super::{Files, Inputs, ReportError};
use crate::fit::extrapolation::{LOWER_T_P, UPPER_T_RIGID};
use crate::fit::forms::DAMPING_DEPTH;
use crate::grid::{Grid, StackFloor};
use crate::limits::STRUCTURE_PERIOD_RANGE_S;
use crate::pipeline::{PipelineError, files};
use crate::render::design::{FrameInputs, PageForm, design_page};
use crate::render::page::escape;
use crate::study::design::{ZoneDesign, frame_cases, frame_designs, known_frames};
use serde::Serialize;

/// One zone's (in a building study, one zone and frame's) response ratios per case, in the
/// grid's flat order.
#[derive(Serialize)]
struct Ratios {
    zone: String,
    drr_1: Vec<f64>,
    drr_2: Vec<f64>,
}

/// A building study's frames as the page offers them.
#[derive(Serialize)]
struct Frames {
    /// `3 storeys, stack on the roof` of each entry of `zones` (as the command's `building`).
    labels: Vec<String>,
    /// Every frame of the study, as the command's refusal lists them.
    known: String,
    /// The query of [`building_example`].
    example: String,
}

/// What the page's script reads.
#[derive(Serialize)]
struct PageData {
    /// [`DAMPING_DEPTH`] of the damped form.
    damping_depth: f64,
    /// [`STRUCTURE_PERIOD_RANGE_S`]: the periods `design` takes, s.
    period_range_s: (f64, f64),
    /// The physical band of the fit's box check, `[LOWER_T_P·T_p, UPPER_T_RIGID·T_rigid]`.
    band: (f64, f64),
    /// One per zone; in a building study one per zone and frame (zone by zone, the frames in
    /// stored order), as [`frame_designs`] gives them.
    zones: Vec<ZoneDesign>,
    /// One per entry of `zones`.
    drr: Vec<Ratios>,
    #[serde(skip_serializing_if = "Option::is_none")]
    frames: Option<Frames>,
}

/// `v` to 4 significant digits (NaN stays NaN).
fn drawn(v: f64) -> f64 {
    format!("{v:.3e}").parse().unwrap_or(v)
}

/// The page's query for the paper's Section 9 worked example (two blocks only).
pub const SECTION_9_QUERY: &str = "zone=III&period=0.7&alpha=1,1&mu=0.3,0.1";

/// A building study's example query, a point of its grid: the first zone, the middle value
/// (the lower of two) of each axis, the most storeys, the stack on the roof.
pub(super) fn building_example(inp: &Inputs) -> Option<String> {
    let axes = inp.study.building()?;
    let g = inp.grid;
    let mid = |a: &[f64]| num(a[(a.len() - 1) / 2]);
    let list = |v: &[Vec<f64>]| v.iter().map(|a| mid(a)).collect::<Vec<_>>().join(",");
    Some(format!(
        "zone={}&period={}&alpha={}&mu={}&storeys={}&floor=roof",
        inp.zones.first()?.name,
        mid(&g.periods_s),
        list(&g.alpha),
        list(&g.mu),
        axes.max_storeys()
    ))
}

/// What the page shows of every zone.
struct Designs {
    /// Each zone's design (a building study: one per frame of each zone).
    zones: Vec<ZoneDesign>,
    /// The `DRR`s drawn beside each.
    drr: Vec<Ratios>,
    /// The frames' labels, every zone's in order (none on one storey).
    labels: Vec<String>,
}

fn zone_designs(inp: &Inputs) -> Result<Designs, PipelineError> {
    let grid = inp.grid;
    // Each zone's stored target, in the config's order, as `inp.zones` is.
    let targets = files::targets(inp.study)?;
    let mut zones = Vec::new();
    let mut drr = Vec::new();
    let drawn_all = |v: &ndarray::ArrayD<f64>, cases: std::ops::Range<usize>| -> Vec<f64> {
        (v.iter().skip(cases.start).take(cases.len()))
            .map(|&x| drawn(x))
            .collect()
    };
    let mut labels = Vec::new();
    for (z, target) in inp.zones.iter().zip(targets) {
        let v = &z.tnew.vars;
        match inp.study.building() {
            None => {
                zones.push(ZoneDesign::of_zone(
                    &z.name,
                    target,
                    grid.clone(),
                    &z.tnew,
                    Some(z.fit()),
                ));
                drr.push(Ratios {
                    zone: z.name.clone(),
                    drr_1: drawn_all(&v.drr_1, 0..v.drr_1.len()),
                    drr_2: drawn_all(&v.drr_2, 0..v.drr_2.len()),
                });
            }
            Some(axes) => {
                let fit_yaml = inp.study.path("fit.yaml");
                let frames =
                    frame_designs(&z.name, &target, grid, axes, &z.tnew, inp.fit(), &fit_yaml)
                        .map_err(ReportError::from)?;
                for (f, d) in frames {
                    let cases = frame_cases(grid, f);
                    labels.push(d.frame_label().unwrap_or_default());
                    drr.push(Ratios {
                        zone: z.name.clone(),
                        drr_1: drawn_all(&v.drr_1, cases.clone()),
                        drr_2: drawn_all(&v.drr_2, cases),
                    });
                    zones.push(d);
                }
            }
        }
    }
    Ok(Designs { zones, drr, labels })
}

/// Writes `design.html` into `files`.
pub(super) fn design_file(inp: &Inputs, files: &mut Files) -> Result<(), PipelineError> {
    let grid = inp.grid;
    let Designs { zones, drr, labels } = zone_designs(inp)?;
    let example = building_example(inp);
    let frames = example.as_ref().map(|example| Frames {
        labels: labels.clone(),
        known: known_frames(inp.fit()),
        example: example.clone(),
    });
    let frame_inputs = inp.study.building().map(|axes| {
        let mut floors: Vec<String> = (1..=axes.max_storeys()).map(|j| j.to_string()).collect();
        floors.extend(StackFloor::NAMED.map(|f| f.to_string()));
        let per_zone = labels.len() / inp.zones.len().max(1);
        FrameInputs {
            storeys: axes.storeys.clone(),
            floors,
            frames: labels[..per_zone].to_vec(),
        }
    });
    let names: Vec<String> = inp.zones.iter().map(|z| z.name.clone()).collect();
    let data = serde_json::to_string(&PageData {
        damping_depth: DAMPING_DEPTH,
        period_range_s: STRUCTURE_PERIOD_RANGE_S,
        band: (LOWER_T_P, UPPER_T_RIGID),
        zones,
        drr,
        frames,
    })
    .expect("plain numbers and strings serialize");
    let span = |v: &[f64], unit: &str| {
        format!(
            "the study's grid: {} … {}{unit}",
            num(v[0]),
            num(v[v.len() - 1])
        )
    };
    let mut ranges = vec![span(&grid.periods_s, " s")];
    ranges.extend(grid.alpha.iter().map(|a| span(a, "")));
    ranges.extend(grid.mu.iter().map(|m| span(m, "")));
    let intro = intro(grid, example.as_deref());
    let form = PageForm {
        zones: &names,
        blocks: grid.blocks(),
        ranges: &ranges,
        building: frame_inputs.as_ref(),
        rocking: inp.study.aspect().is_some(),
    };
    let html = design_page(
        &format!("T_new for your structure: {}", report_name(inp)),
        &intro,
        &form,
        &data,
    );
    files.files.push(("design.html".into(), html.into_bytes()));
    Ok(())
}

/// The page's opening paragraph: what it answers, the command that answers the same, and an
/// example address (`example`: a building study's query of a point of its grid).
fn intro(grid: &Grid, example: Option<&str>) -> String {
    match example {
        None => {
            let example = if grid.blocks() == 2 {
                format!(
                    " The paper's Section 9 worked example: <a href='design.html?{q}'>design.html?{q}</a>.",
                    q = escape(SECTION_9_QUERY)
                )
            } else {
                String::new()
            };
            format!(
                "<p>The period a structure carrying stacks of sliding goods responds with, T_new, and \
                 the design spectral acceleration there, for your structure, from this study: the same \
                 numbers as <code>slidestack design --study DIR --zone Z --period T_p --alpha α_1,… \
                 --mu μ_1,… --json</code> (interpolated in the study's grid, refused outside it unless \
                 you tick <em>extrapolate</em>; the recommended fitted equation; the paper's Eqs. 16–17 \
                 for zones III and V with two blocks). The inputs can be given in the address: \
                 <code>design.html?zone=III&amp;period=0.7&amp;alpha=1,1&amp;mu=0.3,0.1</code> (add \
                 <code>&amp;extrapolate=1</code> to extrapolate).{example}</p>"
            )
        }
        Some(example) => format!(
            "<p>The first-mode period a building carrying stacks of sliding goods responds with, \
             T_new, its effective live-load fraction λ, and the design spectral acceleration, for \
             one building of this study: the same numbers as <code>slidestack design --study DIR \
             --zone Z --period T_1 --alpha α_1,… --mu μ_1,… --storeys N --floor F --json</code> \
             (T_new and λ interpolated in the frame's cases, refused outside the grid unless you \
             tick <em>extrapolate</em>; the fitted building equations; T_1,rigid with the stack \
             rigidly attached to its floor(s)). A building the study does not hold (a storey count, \
             a floor) is refused: nothing is interpolated between frames. The inputs can be given \
             in the address (floor a number, <code>mid</code>, <code>roof</code> or \
             <code>all</code>; add \
             <code>&amp;extrapolate=1</code> to extrapolate), e.g. a point of the study's grid: \
             <a href='design.html?{q}'>design.html?{q}</a>.</p>",
            q = escape(example)
        ),
    }
}

fn report_name(inp: &Inputs) -> String {
    inp.study.config_path.file_name().map_or_else(
        || inp.study.config_path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}
