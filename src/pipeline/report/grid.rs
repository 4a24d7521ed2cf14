//! Figures over the grid: the displacement response ratios (Figs 10–11), `T_new` (Figs 16–17)
//! and the band counts of `T_new`.

use super::select::{Selection, case_index, label_of};
use super::text::{num, paper_figure};
use super::{Files, Inputs, ReportError};
use crate::grid::Grid;
use crate::render::chart::{Axis, Figure, Mark, Panel, Series, Stroke};
use crate::render::page::{Section, para, table_with_id};
use crate::study::tnew::BandCounts;
use plotters::style::RGBColor;

/// One faint line per friction pair of a panel (`column` gives a pair's values over `T_p`),
/// `label` on the first for the legend.
fn every_pair(
    sel: &Selection,
    tp: &[f64],
    label: String,
    column: impl Fn(&[usize]) -> Vec<f64>,
) -> Vec<Series> {
    let mut series: Vec<Series> = sel
        .all_mu
        .iter()
        .map(|m| Series::faint(tp.to_vec(), column(m)))
        .collect();
    if let Some(first) = series.first_mut() {
        first.label = label;
    }
    series
}

/// What names one zone's figure over the mass-ratio panels.
struct ZoneFigure {
    file: String,
    title: String,
    y_label: &'static str,
    caption: String,
}

/// One zone's figure: a panel per selected mass-ratio pair with `T_p` on the x axis and the
/// lines `series(α indices)` gives, rendered into `files`; returns its HTML.
fn zone_figure(
    files: &mut Files,
    sel: &Selection,
    grid: &Grid,
    fig: ZoneFigure,
    series: impl Fn(&[usize]) -> Vec<Series>,
) -> Result<String, ReportError> {
    let panels = sel
        .panels
        .iter()
        .enumerate()
        .map(|(p, a)| {
            Panel::xy(
                sel.panel_title(grid, p),
                Axis::new("T_p (s)"),
                Axis::new(fig.y_label),
                series(a),
            )
        })
        .collect();
    let figure = Figure::grid(fig.title, panels, sel.columns);
    files.figure(&fig.file, &figure, &fig.caption)
}

pub(super) fn drr_section(
    inp: &Inputs,
    sel: &Selection,
    files: &mut Files,
) -> Result<Section, ReportError> {
    let grid = inp.grid;
    let per = grid.cases_per_unit();
    let tp = &grid.periods_s;
    let mut body = para(&format!(
        "Figs 10–11 of the paper: DRR_1 = u_stack / u_rigid (Eq. 7) and DRR_2 = u_single / \
         u_rigid (Eq. 8) against T_p, ratios of the means over the motions, one panel per mass \
         ratio pair; {}. DRR_2 depends on μ_1 only. DRR_1 < DRR_2 where friction within the \
         stack dissipates energy (μ_2 < μ_1 in the paper).",
        sel.mu_note
    ));
    for z in &inp.zones {
        let v = &z.tnew.vars;
        body += &zone_figure(
            files,
            sel,
            grid,
            ZoneFigure {
                file: format!("drr_{}.svg", z.name),
                title: format!(
                    "Zone {}: displacement response ratios against T_p ({})",
                    z.name,
                    paper_figure(&z.name, 10, 11)
                ),
                y_label: "DRR (–)",
                caption: format!(
                    "Zone {}: DRR_1 (lines) and DRR_2 (lines with dots) against T_p, panels over \
                     the mass ratios.",
                    z.name
                ),
            },
            |a| {
                let mut series = every_pair(
                    sel,
                    tp,
                    format!("DRR_1, each of the {} friction pairs", sel.all_mu.len()),
                    |m| z.column(&v.drr_1, per, case_index(grid, a, m)),
                );
                let mut drawn_mu1 = Vec::new();
                let mut drr2 = Vec::new();
                for (m, colour, stroke) in &sel.lines {
                    let c = case_index(grid, a, m);
                    series.push(
                        Series::line(
                            format!("DRR_1: {}", label_of("μ", &grid.mu, m)),
                            tp.clone(),
                            z.column(&v.drr_1, per, c),
                        )
                        .colour(*colour)
                        .stroke(*stroke, 2),
                    );
                    if !drawn_mu1.contains(&m[0]) {
                        drawn_mu1.push(m[0]);
                        drr2.push(
                            Series::line(
                                format!("DRR_2 (single block): μ_1 = {}", num(grid.mu[0][m[0]])),
                                tp.clone(),
                                z.column(&v.drr_2, per, c),
                            )
                            .mark(Mark::LinePoints)
                            .colour(*colour),
                        );
                    }
                }
                // DRR_2 and the no-slide line under the DRR_1 lines.
                let under = sel.all_mu.len();
                series.splice(under..under, drr2);
                series.insert(
                    under,
                    Series::hline("DRR = 1 (nothing slides)", tp[0], tp[tp.len() - 1], 1.0)
                        .colour(RGBColor(0, 0, 0))
                        .stroke(Stroke::Dotted, 1),
                );
                series
            },
        )?;
    }
    Ok(Section::new(
        "drr",
        "Displacement response ratios (Figs 10–11)",
        body,
    ))
}

pub(super) fn band_table(inp: &Inputs) -> String {
    let flags = &inp.zones[0].band_flags;
    let mut header: Vec<String> = vec!["zone".into(), "cases".into()];
    header.extend(flags.iter().map(|(_, w)| w.clone()));
    header.extend([
        "sliding cases".to_string(),
        "T_new > 1.005·T_rigid (sliding)".to_string(),
    ]);
    let mut rows = Vec::new();
    for z in &inp.zones {
        let v = &z.tnew.vars;
        let band: Vec<u8> = v.band.iter().copied().collect();
        let tn: Vec<f64> = v.t_new.iter().copied().collect();
        let tr: Vec<f64> = v.t_rigid.iter().copied().collect();
        let counts = BandCounts::new(&band, &tn, &tr);
        let mut row = vec![z.name.clone(), band.len().to_string()];
        row.extend(
            z.band_flags
                .iter()
                .map(|(code, _)| band.iter().filter(|&&b| b == *code).count().to_string()),
        );
        row.push(counts.sliding().to_string());
        row.push(counts.above_1_005.to_string());
        rows.push(row);
    }
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    table_with_id("bands", &h, &rows)
}

pub(super) fn tnew_section(
    inp: &Inputs,
    sel: &Selection,
    files: &mut Files,
) -> Result<Section, ReportError> {
    let grid = inp.grid;
    let per = grid.cases_per_unit();
    let tp = &grid.periods_s;
    let mut body = para(&format!(
        "Figs 16–17 of the paper: T_new against T_p, one panel per mass ratio pair, with the \
         bare structure's period (T_new = T_p) and the rigidly loaded one (T_new = T_rigid); {}.",
        sel.mu_note
    ));
    let black = RGBColor(0, 0, 0);
    for z in &inp.zones {
        let v = &z.tnew.vars;
        body += &zone_figure(
            files,
            sel,
            grid,
            ZoneFigure {
                file: format!("tnew_{}.svg", z.name),
                title: format!(
                    "Zone {}: T_new against T_p ({})",
                    z.name,
                    paper_figure(&z.name, 16, 17)
                ),
                y_label: "T_new (s)",
                caption: format!(
                    "Zone {}: T_new against T_p, panels over the mass ratios, between T_p and \
                     T_rigid.",
                    z.name
                ),
            },
            |a| {
                let mut series = every_pair(
                    sel,
                    tp,
                    format!("each of the {} friction pairs", sel.all_mu.len()),
                    |m| z.column(&v.t_new, per, case_index(grid, a, m)),
                );
                // The limits under the data.
                let c0 = case_index(grid, a, &sel.all_mu[0]);
                series.push(
                    Series::line("T_p (bare structure)", tp.clone(), tp.clone())
                        .colour(black)
                        .stroke(Stroke::Solid, 1),
                );
                series.push(
                    Series::line(
                        "T_rigid (load rigidly attached)",
                        tp.clone(),
                        z.column(&v.t_rigid, per, c0),
                    )
                    .colour(black)
                    .stroke(Stroke::Dashed, 1),
                );
                for (m, colour, stroke) in &sel.lines {
                    series.push(
                        Series::line(
                            label_of("μ", &grid.mu, m),
                            tp.clone(),
                            z.column(&v.t_new, per, case_index(grid, a, m)),
                        )
                        .colour(*colour)
                        .stroke(*stroke, 2),
                    );
                }
                series
            },
        )?;
    }
    body += &para(
        "Where T_new lies against its physical band [T_p, T_rigid] (tnew.h5, T_new_band; the \
         paper states T_p < T_new < T_rigid in general): cases per category.",
    );
    body += &band_table(inp);
    Ok(Section::new("tnew", "T_new against T_p (Figs 16–17)", body))
}
