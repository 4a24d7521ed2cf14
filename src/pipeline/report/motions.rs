//! The matched motions against their target (paper Figs 4–5).

use super::{Files, ReportError, ZoneMotions};
use crate::pipeline::Study;
use crate::render::chart::{Axis, FAINT, Figure, PALETTE, Panel, Series, Stroke};
use crate::render::page::{Section, para};
use crate::store::motions::ZoneSpectra;
use plotters::style::RGBColor;

pub(super) fn motions_section(
    study: &Study,
    zones: &[ZoneMotions],
    files: &mut Files,
) -> Result<Section, ReportError> {
    let m = &study.cfg.motions.matching;
    let (lo, hi) = (m.lower, m.upper);
    let damping = format!("{} %", 100.0 * m.damping);
    let mut body = para(&format!(
        "Figs 4–5 of the paper: the {damping}-damped target spectrum of each zone (the paper's: \
         IS 1893:2016, hard soil, Z·Sa/g), the mean spectrum of the zone's matched motions, and \
         the matching band {lo}–{hi} × target; every motion in grey. The right panel shows mean \
         / target: ASCE 7-16 asks that it not fall below 0.9."
    ));
    for z in zones {
        let (series, ratio_series, (r0, r1)) = spectra_series(z.spectra, lo, hi);
        let pad = 0.15 * (r1 - r0);
        let x = || Axis::new("period T (s)");
        let mut fig = Figure::grid(
            format!(
                "Zone {}: {damping}-damped spectra of the matched motions (Figs 4–5)",
                z.name
            ),
            vec![
                Panel::xy(
                    "pseudo-spectral acceleration",
                    x(),
                    Axis::new("PSA (g)"),
                    series,
                ),
                Panel::xy(
                    "mean / target",
                    x(),
                    Axis::new("mean PSA / target PSA (–)").range(r0 - pad, r1 + pad),
                    ratio_series,
                ),
            ],
            2,
        )
        .panel_px(440, 330);
        fig.share_y = false;
        body += &files.figure(
            &format!("spectra_{}.svg", z.name),
            &fig,
            &format!(
                "Zone {}: target ({}), mean of the {} matched motions and the matching band \
                 (paper Figs 4–5).",
                z.name, z.target, z.count
            ),
        )?;
    }
    Ok(Section::new("motions", "Ground motions (Figs 4–5)", body))
}

/// A zone's spectra panel (every motion, the band `lo`–`hi` × target, the target, the mean) and
/// its mean-over-target panel, with that panel's range.
fn spectra_series(
    spectra: &ZoneSpectra,
    lo: f64,
    hi: f64,
) -> (Vec<Series>, Vec<Series>, (f64, f64)) {
    let s = spectra;
    let t = &s.periods_s;
    let scaled = |f: f64| s.target_psa_g.iter().map(|v| v * f).collect::<Vec<_>>();
    let mut series: Vec<Series> = s
        .psa_g
        .rows()
        .into_iter()
        .map(|r| Series::faint(t.clone(), r.to_vec()).colour(FAINT))
        .collect();
    if let Some(first) = series.first_mut() {
        first.label = format!("each matched motion ({})", s.psa_g.nrows());
    }
    series.push(
        Series::band(
            format!("matching band {lo}–{hi} × target"),
            t.clone(),
            scaled(lo),
            scaled(hi),
        )
        .colour(PALETTE[0]),
    );
    series
        .push(Series::line("target", t.clone(), s.target_psa_g.clone()).colour(RGBColor(0, 0, 0)));
    series.push(
        Series::line("mean of the motions", t.clone(), s.mean_psa_g.clone()).colour(PALETTE[1]),
    );
    let ratio: Vec<f64> = s
        .mean_psa_g
        .iter()
        .zip(&s.target_psa_g)
        .map(|(m, t)| m / t)
        .collect();
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let (r0, r1) = ratio
        .iter()
        .fold((lo, hi), |(a, b), &v| (a.min(v), b.max(v)));
    let ratio_series = vec![
        Series::band(
            format!("matching band {lo}–{hi} × target"),
            vec![t0, t1],
            vec![lo, lo],
            vec![hi, hi],
        )
        .colour(PALETTE[0]),
        Series::hline("ASCE 7-16 minimum (0.9)", t0, t1, 0.9)
            .colour(RGBColor(0, 0, 0))
            .stroke(Stroke::Dashed, 1),
        Series::line("mean of the motions", t.clone(), ratio).colour(PALETTE[1]),
    ];
    (series, ratio_series, (r0, r1))
}
