//! `design.html`: `slidestack design` in the browser, and an explorer of the grid's figures.
//! The page embeds each zone's [`ZoneDesign`], the very data the command answers from, and the
//! grid's `DRR_1` and `DRR_2` for the explorer (4 significant digits: they are only drawn).

use super::text::num;
use super::{Files, Inputs};
use crate::design::ZoneDesign;
use crate::fit::forms::DAMPING_DEPTH;
use crate::pipeline::PipelineError;
use crate::render::design::design_page;
use crate::render::page::escape;
use crate::store::motions::read_zone_target;
use serde::Serialize;

/// One zone's response ratios per case, in the grid's flat order.
#[derive(Serialize)]
struct Ratios {
    zone: String,
    drr_1: Vec<f64>,
    drr_2: Vec<f64>,
}

/// What the page's script reads.
#[derive(Serialize)]
struct PageData {
    /// [`DAMPING_DEPTH`] of the damped form.
    damping_depth: f64,
    zones: Vec<ZoneDesign>,
    drr: Vec<Ratios>,
}

/// `v` to 4 significant digits (NaN stays NaN).
fn drawn(v: f64) -> f64 {
    format!("{v:.3e}").parse().unwrap_or(v)
}

/// The page's query for the paper's Section 9 worked example (two blocks only).
pub const SECTION_9_QUERY: &str = "zone=III&period=0.7&alpha=1,1&mu=0.3,0.1";

/// Writes `design.html` into `files`.
pub(super) fn design_file(inp: &Inputs, files: &mut Files) -> Result<(), PipelineError> {
    let grid = inp.grid;
    let motions = inp.study.path("motions.h5");
    let mut zones = Vec::new();
    let mut drr = Vec::new();
    for z in &inp.zones {
        let target = read_zone_target(&motions, &z.name)?;
        let v = &z.tnew.vars;
        zones.push(ZoneDesign::new(
            &z.name,
            target,
            grid.clone(),
            v.t_new.iter().copied().collect(),
            Some(&z.fit),
        ));
        drr.push(Ratios {
            zone: z.name.clone(),
            drr_1: v.drr_1.iter().map(|&x| drawn(x)).collect(),
            drr_2: v.drr_2.iter().map(|&x| drawn(x)).collect(),
        });
    }
    let names: Vec<String> = inp.zones.iter().map(|z| z.name.clone()).collect();
    let data = serde_json::to_string(&PageData {
        damping_depth: DAMPING_DEPTH,
        zones,
        drr,
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
    let example = if grid.blocks() == 2 {
        format!(
            " The paper's Section 9 worked example: <a href='design.html?{q}'>design.html?{q}</a>.",
            q = escape(SECTION_9_QUERY)
        )
    } else {
        String::new()
    };
    let intro = format!(
        "<p>The period a structure carrying stacks of sliding goods responds with, T_new, and \
         the design spectral acceleration there, for your structure, from this study: the same \
         numbers as <code>slidestack design --study DIR --zone Z --period T_p --alpha α_1,… \
         --mu μ_1,… --json</code> (interpolated in the study's grid, refused outside it unless \
         you tick <em>extrapolate</em>; the recommended fitted equation; the paper's Eqs. 16–17 \
         for zones III and V with two blocks). The inputs can be given in the address: \
         <code>design.html?zone=III&amp;period=0.7&amp;alpha=1,1&amp;mu=0.3,0.1</code> (add \
         <code>&amp;extrapolate=1</code> to extrapolate).{example}</p>"
    );
    let html = design_page(
        &format!("T_new for your structure: {}", report_name(inp)),
        &intro,
        &names,
        grid.blocks(),
        &ranges,
        &data,
    );
    files.files.push(("design.html".into(), html.into_bytes()));
    Ok(())
}

fn report_name(inp: &Inputs) -> String {
    inp.study.config_path.file_name().map_or_else(
        || inp.study.config_path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    )
}
