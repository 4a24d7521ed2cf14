//! The report stage: `OUT/report/index.html` with SVG figures beside it, side by side with the
//! paper where the paper has a number:
//!
//! * the matched motions (Figs 4–5): target, mean and matching band, every motion faint;
//! * the Section 7.1 case: displacement histories of the stack, the single block and the rigid
//!   system; the construction of `T_new` on the mean displacement spectrum (Fig. 12); the
//!   energy partition (input, kinetic, strain, damping, friction per interface);
//! * Table 2 (stack against single block) next to the paper's;
//! * `DRR_1`, `DRR_2` (Figs 10–11) and `T_new` (Figs 16–17) against `T_p`, panels over the mass
//!   ratios, a subset of friction pairs drawn out over every pair in grey;
//! * the band counts of `T_new`, Table 3 next to the paper's, the recommended form's
//!   coefficients with their standard errors, and the residuals of every fitted form.
//!
//! Panels and lines are picked from the grid's own axes, so any grid (other block counts
//! included) gives a report. Every simulation uses the study's physics
//! ([`crate::study::sweep::Physics`]). The directory is replaced as a whole
//! ([`crate::store::report`]).
//!
//! Fingerprint: the fit's and the motions' (which carry everything upstream), and the report's
//! own version.

use super::{Outcome, PipelineError, Session, StageId, Study};
use crate::dynamics::{ExactOptions, Ground, ModelError, Response, SimError, System, SystemSpec};
use crate::fit::Fitted;
use crate::grid::Grid;
use crate::motion::Record;
use crate::report::chart::{
    self, Axis, ChartError, FAINT, Figure, Mark, PALETTE, Panel, Plot, Segment, Series, Stroke,
};
use crate::report::page::{Section, document, figure, list, para, table_with_id};
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::{FitReport, ZoneFit, read_fit};
use crate::store::motions::{ZoneSpectra, read_zone_spectra};
use crate::store::report::write_report_dir;
use crate::store::tnew::{ZoneTnew, read_band_flags, read_zone_tnew};
use crate::study::cases::{
    NamedCase, PAPER_SECTION_7_1, PAPER_TABLE_2, PAPER_TABLE_3, SECTION_7_1, TABLE_2,
};
use crate::study::sweep::Physics;
use crate::study::tnew::{BandCounts, TnewFlag, period_at_displacement, samples};
use plotters::style::RGBColor;
use rayon::prelude::*;
use thiserror::Error;

/// Changes when the report's contents change.
const REPORT_VERSION: &str = "report-2";

/// At most this many panels over the mass ratios, and lines of friction pairs per panel.
const MAX_PANELS: usize = 9;
const MAX_LINES: usize = 6;

#[derive(Debug, Error)]
pub enum ReportError {
    #[error("the report's case {case}: {source}")]
    Model { case: String, source: ModelError },
    #[error("the report's case {case} under {motion}: {source}")]
    Simulation {
        case: String,
        motion: String,
        source: SimError,
    },
    #[error("zone {zone} has no motions")]
    NoMotions { zone: String },
    #[error(transparent)]
    Chart(#[from] ChartError),
}

/// The fingerprint the report must carry.
pub fn fingerprint(fit_fingerprint: &str, motions_fingerprint: &str) -> String {
    hash_parts(&[fit_fingerprint, motions_fingerprint, REPORT_VERSION])
}

fn simulate(rec: &Record, spec: &SystemSpec, history: bool) -> Result<Response, ReportError> {
    let case = format!(
        "T_p {} s, α {:?}, μ {:?}",
        spec.period_s, spec.alpha, spec.mu
    );
    let accel = rec.accel_mps2(1.0);
    let ground = Ground {
        dt_s: rec.dt_s,
        accel_mps2: &accel,
    };
    let sys = System::new(spec).map_err(|source| ReportError::Model {
        case: case.clone(),
        source,
    })?;
    crate::dynamics::simulate_exact(
        &sys,
        &ground,
        &ExactOptions {
            history,
            ..ExactOptions::default()
        },
    )
    .map_err(|source| ReportError::Simulation {
        case,
        motion: rec.name.clone(),
        source,
    })
}

/// The three systems of a case (NOTES.md, "Derived quantities").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum System3 {
    Stack,
    Single,
    Rigid,
}

impl System3 {
    const ALL: [System3; 3] = [System3::Stack, System3::Single, System3::Rigid];

    fn name(self) -> &'static str {
        match self {
            System3::Stack => "stack",
            System3::Single => "single block",
            System3::Rigid => "rigidly attached",
        }
    }

    fn spec(self, physics: &Physics, tp: f64, alpha: &[f64], mu: &[f64]) -> SystemSpec {
        let total: f64 = alpha.iter().sum();
        match self {
            System3::Stack => physics.stack(tp, alpha, mu),
            System3::Single => physics.single(tp, total, mu[0]),
            System3::Rigid => physics.rigid(tp, total),
        }
    }
}

/// A named case of the paper, as run on this study's motions.
struct CaseRun {
    period_s: f64,
    alpha: Vec<f64>,
    mu: Vec<f64>,
    /// Per motion: stack, single block, rigid.
    runs: Vec<[Response; 3]>,
}

impl CaseRun {
    fn new(
        physics: &Physics,
        case: &NamedCase,
        blocks: usize,
        motions: &[Record],
    ) -> Result<Self, ReportError> {
        let (alpha, mu) = case.for_blocks(blocks);
        let tp = case.period_s;
        let runs = motions
            .par_iter()
            .map(|rec| -> Result<[Response; 3], ReportError> {
                let run = |s: System3| simulate(rec, &s.spec(physics, tp, &alpha, &mu), false);
                Ok([
                    run(System3::Stack)?,
                    run(System3::Single)?,
                    run(System3::Rigid)?,
                ])
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            period_s: tp,
            alpha,
            mu,
            runs,
        })
    }

    fn alpha_total(&self) -> f64 {
        self.alpha.iter().sum()
    }

    /// Mean over the motions of the peak structure displacement of system `s`, m.
    fn mean_peak(&self, s: System3) -> f64 {
        mean(self.runs.iter().map(|r| r[s as usize].peak_displacement_m))
    }

    fn slides(&self) -> bool {
        self.runs
            .iter()
            .any(|r| r[0].peak_slip_m.iter().any(|&x| x > 0.0))
    }

    /// The motion whose stack peak is the median of the motions' (the lower one of an even set).
    fn median_motion(&self) -> usize {
        let mut order: Vec<usize> = (0..self.runs.len()).collect();
        order.sort_by(|&a, &b| {
            self.runs[a][0]
                .peak_displacement_m
                .total_cmp(&self.runs[b][0].peak_displacement_m)
        });
        order[(order.len() - 1) / 2]
    }

    fn describe(&self) -> String {
        format!(
            "T_p = {} s, α = {}, μ = {}",
            num(self.period_s),
            nums(&self.alpha),
            nums(&self.mu)
        )
    }
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n as f64
}

/// A value as the shortest text that reads back to it (`0.5`, `1`, `0.05`).
fn num(v: f64) -> String {
    format!("{v}")
}

fn nums(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join("/")
}

/// `n` significant digits, in scientific notation outside [1e-3, 1e5).
fn sig(v: f64, n: usize) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..5).contains(&mag) {
        return format!("{v:.*e}", n - 1);
    }
    let decimals = (n as i32 - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

fn fixed(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "–".into()
    }
}

/// Evenly spaced picks of `k` of `len` indices, first and last included (`k` = 1: the middle).
fn picks(len: usize, k: usize) -> Vec<usize> {
    match k.min(len) {
        0 => Vec::new(),
        1 => vec![(len - 1) / 2],
        k => (0..k)
            .map(|i| ((i * (len - 1)) as f64 / (k - 1) as f64).round() as usize)
            .collect(),
    }
}

/// Index subsets of axes of lengths `lens` whose product is at most `max`: the axis with the
/// most picks (the later one on a tie) is cut to 3, then 2, then 1 evenly spaced values until
/// the product fits.
fn subset(lens: &[usize], max: usize) -> Vec<Vec<usize>> {
    let mut count: Vec<usize> = lens.to_vec();
    while count.iter().product::<usize>() > max {
        let (axis, &c) = count
            .iter()
            .enumerate()
            .max_by_key(|(_, c)| **c)
            .expect("at least one axis");
        if c <= 1 {
            break;
        }
        count[axis] = if c > 3 { 3 } else { c - 1 };
    }
    lens.iter()
        .zip(&count)
        .map(|(&len, &c)| picks(len, c))
        .collect()
}

/// Every combination of the index lists, the last fastest.
fn combinations(lists: &[Vec<usize>]) -> Vec<Vec<usize>> {
    lists.iter().fold(vec![Vec::new()], |acc, list| {
        acc.iter()
            .flat_map(|prefix| {
                list.iter().map(move |&i| {
                    let mut v = prefix.clone();
                    v.push(i);
                    v
                })
            })
            .collect()
    })
}

/// Flat case index within a work unit from per-axis indices (`α` axes, then `μ` axes).
fn case_index(grid: &Grid, alpha: &[usize], mu: &[usize]) -> usize {
    grid.case_shape()
        .iter()
        .zip(alpha.iter().chain(mu))
        .fold(0, |idx, (&len, &i)| idx * len + i)
}

fn label_of(name: &str, axes: &[Vec<f64>], idx: &[usize]) -> String {
    idx.iter()
        .enumerate()
        .map(|(d, &i)| format!("{name}_{} = {}", d + 1, num(axes[d][i])))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The panels over the mass ratios and the lines over the friction pairs of the `T_p` figures.
struct Selection {
    /// `α` index per block, one entry per panel.
    panels: Vec<Vec<usize>>,
    columns: usize,
    /// `μ` index per interface, one entry per line, with its colour and stroke.
    lines: Vec<(Vec<usize>, RGBColor, Stroke)>,
    /// Every `μ` combination (drawn faint).
    all_mu: Vec<Vec<usize>>,
    mu_note: String,
}

impl Selection {
    fn new(grid: &Grid) -> Self {
        let alpha_lens: Vec<usize> = grid.alpha.iter().map(Vec::len).collect();
        let alpha_sets = subset(&alpha_lens, MAX_PANELS);
        let panels = combinations(&alpha_sets);
        let columns = if alpha_sets.len() >= 2 {
            alpha_sets[1..].iter().map(Vec::len).product::<usize>()
        } else {
            panels.len()
        };
        let columns = if columns > 4 {
            (panels.len() as f64).sqrt().ceil() as usize
        } else {
            columns
        };
        let mu_lens: Vec<usize> = grid.mu.iter().map(Vec::len).collect();
        let mu_sets = subset(&mu_lens, MAX_LINES);
        let chosen = combinations(&mu_sets);
        let others: usize = mu_sets[1..].iter().map(Vec::len).product();
        let strokes = [Stroke::Solid, Stroke::Dashed, Stroke::Dotted];
        let by_mu_1 = others <= strokes.len();
        let lines = chosen
            .iter()
            .enumerate()
            .map(|(k, idx)| {
                if by_mu_1 {
                    let c = mu_sets[0].iter().position(|&i| i == idx[0]).unwrap_or(0);
                    (idx.clone(), PALETTE[c % PALETTE.len()], strokes[k % others])
                } else {
                    (idx.clone(), PALETTE[k % PALETTE.len()], Stroke::Solid)
                }
            })
            .collect();
        let all_mu = combinations(
            &mu_lens
                .iter()
                .map(|&l| (0..l).collect())
                .collect::<Vec<_>>(),
        );
        let picked: Vec<String> = mu_sets
            .iter()
            .enumerate()
            .map(|(d, s)| {
                format!(
                    "μ_{} ∈ {{{}}}",
                    d + 1,
                    s.iter()
                        .map(|&i| num(grid.mu[d][i]))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
            .collect();
        let mu_note = if chosen.len() == all_mu.len() {
            format!("every friction combination ({})", chosen.len())
        } else {
            format!(
                "{} of the grid's {} friction combinations drawn out ({}), every one in grey",
                chosen.len(),
                all_mu.len(),
                picked.join(", ")
            )
        };
        Self {
            panels,
            columns,
            lines,
            all_mu,
            mu_note,
        }
    }

    fn panel_title(&self, grid: &Grid, p: usize) -> String {
        label_of("α", &grid.alpha, &self.panels[p])
    }
}

/// One zone's inputs.
struct Zone {
    name: String,
    motions: Vec<Record>,
    spectra: ZoneSpectra,
    tnew: ZoneTnew,
    band_flags: Vec<(u8, String)>,
    fit: ZoneFit,
    section71: CaseRun,
    table2: CaseRun,
}

impl Zone {
    /// Column `case` of a `[T_p, case…]` variable: one value per `T_p`.
    fn column(&self, v: &ndarray::ArrayD<f64>, per: usize, case: usize) -> Vec<f64> {
        let flat = v.as_slice().expect("stored arrays are standard-layout");
        (0..flat.len() / per)
            .map(|p| flat[p * per + case])
            .collect()
    }
}

/// Everything the report is made of: the study and each zone's data.
struct Inputs<'a> {
    study: &'a Study,
    grid: &'a Grid,
    physics: Physics,
    fit: FitReport,
    zones: Vec<Zone>,
}

impl<'a> Inputs<'a> {
    fn load(study: &'a Study) -> Result<Self, PipelineError> {
        let grid = study.grid(StageId::Report)?;
        let physics = study.physics();
        let motions = super::sweep::load_motions(study)?;
        let (mh5, th5, fyaml) = (
            study.path("motions.h5"),
            study.path("tnew.h5"),
            study.path("fit.yaml"),
        );
        let fit = read_fit(&fyaml)?.ok_or_else(|| StoreError::corrupt(&fyaml, "is missing"))?;
        let n = grid.blocks();
        let mut zones = Vec::new();
        for (zc, motions) in study.cfg.zones.iter().zip(motions) {
            if motions.is_empty() {
                return Err(ReportError::NoMotions {
                    zone: zc.name.clone(),
                }
                .into());
            }
            let (axes, tnew) = read_zone_tnew(&th5, &zc.name, n)?;
            if axes != *grid {
                return Err(StoreError::corrupt(
                    &th5,
                    format!("zone_{}: its grid differs from the config's", zc.name),
                )
                .into());
            }
            let zf = fit
                .zones
                .iter()
                .find(|f| f.zone == zc.name)
                .cloned()
                .ok_or_else(|| StoreError::corrupt(&fyaml, format!("has no zone {}", zc.name)))?;
            zones.push(Zone {
                name: zc.name.clone(),
                spectra: read_zone_spectra(&mh5, &zc.name)?,
                band_flags: read_band_flags(&th5, &zc.name)?,
                section71: CaseRun::new(&physics, &SECTION_7_1, n, &motions)?,
                table2: CaseRun::new(&physics, &TABLE_2, n, &motions)?,
                motions,
                tnew,
                fit: zf,
            });
        }
        Ok(Self {
            study,
            grid,
            physics,
            fit,
            zones,
        })
    }
}

/// The report's files as they are made.
#[derive(Default)]
struct Files {
    files: Vec<(String, Vec<u8>)>,
}

impl Files {
    /// Renders `fig` as `name` and returns its HTML figure with `caption`.
    fn figure(&mut self, name: &str, fig: &Figure, caption: &str) -> Result<String, ReportError> {
        let svg = chart::render(fig)?;
        self.files.push((name.to_string(), svg.into_bytes()));
        Ok(figure(name, caption))
    }
}

/// The Section 7.1 case's `T_new` in one zone: the mean peak displacement, `T_rigid`, `T_new`.
fn section71_tnew(z: &Zone, physics: &Physics) -> (f64, f64, f64, TnewFlag) {
    let c = &z.section71;
    let u = c.mean_peak(System3::Stack);
    let tr = physics.rigid(c.period_s, c.alpha_total()).period_s;
    let (tn, flag) = if c.slides() {
        period_at_displacement(&z.tnew.period_sd_s, &z.tnew.sd_mean_m, u, tr)
    } else {
        (tr, TnewFlag::NoSlip)
    };
    (u, tr, tn, flag)
}

fn motions_section(inp: &Inputs, files: &mut Files) -> Result<Section, ReportError> {
    let m = &inp.study.cfg.motions.matching;
    let (lo, hi) = (m.lower, m.upper);
    let mut body = para(&format!(
        "Figs 4–5 of the paper: the 5 %-damped target spectrum of each zone (IS 1893:2016, hard \
         soil, scaled by Z), the mean spectrum of the zone's matched motions, and the matching \
         band {lo}–{hi} × target; every motion in grey. The right panel shows mean / target: \
         ASCE 7-16 asks that it not fall below 0.9."
    ));
    for z in &inp.zones {
        let s = &z.spectra;
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
        series.push(
            Series::line("target", t.clone(), s.target_psa_g.clone()).colour(RGBColor(0, 0, 0)),
        );
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
        let pad = 0.15 * (r1 - r0);
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
        let x = || Axis::new("period T (s)");
        let mut fig = Figure::grid(
            format!(
                "Zone {}: 5 %-damped spectra of the matched motions (Figs 4–5)",
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
                "Zone {}: target, mean of the {} matched motions and the matching band (paper \
                 Figs 4–5).",
                z.name,
                z.motions.len()
            ),
        )?;
    }
    Ok(Section::new("motions", "Ground motions (Figs 4–5)", body))
}

fn section71_section(inp: &Inputs, files: &mut Files) -> Result<Section, ReportError> {
    let physics = &inp.physics;
    let n = inp.grid.blocks();
    let first = &inp.zones[0].section71;
    let mut body = para(&format!(
        "The paper's Section 7.1 example: {}{}. Each system runs under every motion of the zone \
         with the study's physics (ζ = {} of the {} basis, μ_s = {} × μ_k).",
        first.describe(),
        if n == SECTION_7_1.alpha.len() {
            String::new()
        } else {
            format!(
                " (the paper's two-block case {} carried to {n} blocks: same total mass in equal \
                 blocks, μ_1 kept, upper interfaces at the paper's top coefficient)",
                nums(SECTION_7_1.alpha)
            )
        },
        physics.damping,
        physics.basis.name(),
        physics.mu_static_ratio
    ));
    let mut rows = Vec::new();
    let mut energy_rows = Vec::new();
    let mut energy_panels = Vec::new();
    for z in &inp.zones {
        let c = &z.section71;
        let k = c.median_motion();
        let rec = &z.motions[k];
        // Histories under the median motion, then all three around their peaks.
        let mut panels = Vec::new();
        let mut lines = Vec::new();
        for (i, s) in System3::ALL.into_iter().enumerate() {
            let r = simulate(rec, &s.spec(physics, c.period_s, &c.alpha, &c.mu), true)?;
            let h = r.history.as_ref().expect("history requested");
            let u: Vec<f64> = h
                .displacement_m
                .chunks(h.bodies)
                .map(|row| row[0] * 100.0)
                .collect();
            panels.push(Panel::xy(
                format!(
                    "{}: peak {:.2} cm at {:.2} s",
                    s.name(),
                    r.peak_displacement_m * 100.0,
                    r.peak_displacement_time_s
                ),
                Axis::new("time t (s)"),
                Axis::new("u_p (cm)"),
                vec![
                    Series::line("", h.time_s.clone(), u.clone())
                        .colour(PALETTE[i])
                        .stroke(Stroke::Solid, 1),
                ],
            ));
            lines.push((s, h.time_s.clone(), u, r.peak_displacement_time_s));
        }
        let end = lines[0].1.last().copied().unwrap_or(0.0);
        let first = lines.iter().map(|l| l.3).fold(f64::INFINITY, f64::min);
        let last = lines.iter().map(|l| l.3).fold(0.0, f64::max);
        let t0 = (first - 3.0).min(last - 5.0).max(0.0);
        let window = (t0, (last + 3.0).max(t0 + 8.0).min(end));
        let overlay = lines
            .into_iter()
            .enumerate()
            .map(|(i, (s, t, u, _))| {
                let (t, u): (Vec<f64>, Vec<f64>) = t
                    .into_iter()
                    .zip(u)
                    .filter(|(t, _)| (window.0..=window.1).contains(t))
                    .unzip();
                Series::line(s.name(), t, u)
                    .colour(PALETTE[i])
                    .stroke(Stroke::Solid, if i == 0 { 2 } else { 1 })
            })
            .collect();
        panels.push(Panel::xy(
            "the three together, around their peaks",
            Axis::new("time t (s)").range(window.0, window.1),
            Axis::new("u_p (cm)"),
            overlay,
        ));
        let fig = Figure::grid(
            format!(
                "Zone {}, Section 7.1 case ({}) under motion {}",
                z.name,
                c.describe(),
                rec.name
            ),
            panels,
            1,
        )
        .panel_px(900, 200);
        body += &files.figure(
            &format!("history_{}.svg", z.name),
            &fig,
            &format!(
                "Zone {}: structure displacement with the stack, the single block and the load \
                 rigidly attached (u_p, relative to the ground), under {} (the motion with the \
                 median stack peak of the {}); the last panel overlays them around their \
                 peaks.",
                z.name,
                rec.name,
                z.motions.len()
            ),
        )?;

        // Fig. 12: the crossing of the mean peak displacement with the mean Sd.
        let (u, tr, tn, flag) = section71_tnew(z, physics);
        let paper = (PAPER_SECTION_7_1.0 == z.name).then_some(PAPER_SECTION_7_1);
        let t = &z.tnew.period_sd_s;
        let t_max = (1.6 * tr).max(2.5).min(t[t.len() - 1]);
        let keep: Vec<usize> = (0..t.len()).filter(|&i| t[i] <= t_max).collect();
        let sd_cm: Vec<f64> = keep.iter().map(|&i| z.tnew.sd_mean_m[i] * 100.0).collect();
        let tk: Vec<f64> = keep.iter().map(|&i| t[i]).collect();
        let y_top = sd_cm.iter().copied().fold(0.0, f64::max) * 1.05;
        let black = RGBColor(0, 0, 0);
        let mut series = vec![
            Series::line("mean 5 %-damped Sd of the motions", tk, sd_cm).colour(PALETTE[0]),
            Series::vline("T_p (bare structure)", c.period_s, 0.0, y_top)
                .colour(black)
                .stroke(Stroke::Dotted, 1),
            Series::vline("T_rigid (load rigidly attached)", tr, 0.0, y_top)
                .colour(black)
                .stroke(Stroke::Dashed, 1),
            Series::hline("mean peak displacement ū (stack)", 0.0, t_max, u * 100.0)
                .colour(PALETTE[1])
                .stroke(Stroke::Dashed, 2),
        ];
        if tn.is_finite() {
            series.push(
                Series::vline("T_new", tn, 0.0, u * 100.0)
                    .colour(PALETTE[1])
                    .stroke(Stroke::Solid, 2),
            );
            series.push(
                Series::points("crossing (T_new, ū)", vec![tn], vec![u * 100.0])
                    .mark(Mark::Points {
                        radius: 5,
                        opacity: 1.0,
                    })
                    .colour(PALETTE[1]),
            );
        }
        if let Some((_, pu, pt)) = paper {
            series.push(
                Series::points("paper: 1.38 s, 5.49 cm", vec![pt], vec![pu * 100.0])
                    .mark(Mark::Points {
                        radius: 5,
                        opacity: 1.0,
                    })
                    .colour(PALETTE[2]),
            );
        }
        let paper_text = paper.map_or(String::new(), |(_, pu, pt)| {
            format!(" (paper {pt} s, {:.2} cm)", pu * 100.0)
        });
        let fig = Figure::single(
            format!("Zone {}: T_new of the Section 7.1 case (Fig. 12)", z.name),
            Panel::xy(
                format!(
                    "T_new = {} s, ū = {:.2} cm{paper_text}",
                    fixed(tn, 3),
                    u * 100.0
                ),
                Axis::new("period T (s)").range(0.0, t_max),
                Axis::new("spectral displacement Sd (cm)").range(0.0, y_top),
                series,
            ),
        )
        .panel_px(700, 440);
        body += &files.figure(
            &format!("tnew_construction_{}.svg", z.name),
            &fig,
            &format!(
                "Zone {}: the mean over the motions of the stack's peak structure displacement, \
                 read off the zone's mean 5 %-damped displacement spectrum (paper Fig. 12).",
                z.name
            ),
        )?;
        rows.push(vec![
            z.name.clone(),
            format!("{:.2}", u * 100.0),
            paper.map_or("–".into(), |p| format!("{:.2}", p.1 * 100.0)),
            fixed(tn, 3),
            paper.map_or("–".into(), |p| format!("{:.2}", p.2)),
            format!("{tr:.3}"),
            match flag {
                TnewFlag::Unique => "one crossing".into(),
                TnewFlag::Several => "several crossings, nearest T_rigid".into(),
                TnewFlag::OutsideRange => "no crossing".into(),
                TnewFlag::NoSlip => "nothing slid: T_rigid".into(),
            },
        ]);

        // Energy partition, mean over the motions.
        let mut segs: Vec<(String, Vec<f64>)> = vec![("viscous damping".into(), Vec::new())];
        for i in 0..n {
            segs.push((format!("friction, interface {}", i + 1), Vec::new()));
        }
        segs.push(("kinetic + strain at the end".into(), Vec::new()));
        for s in System3::ALL {
            // The rigid system is one body of the whole mass: its terms per kg of that mass,
            // times (1 + α), are per kg of structure mass like the others'.
            let scale = if s == System3::Rigid {
                1.0 + c.alpha_total()
            } else {
                1.0
            };
            let e = |f: &dyn Fn(&crate::dynamics::Energy) -> f64| {
                scale * mean(c.runs.iter().map(|r| f(&r[s as usize].energy)))
            };
            let input = e(&|e| e.input);
            let per: Vec<f64> = (0..n)
                .map(|i| e(&|e| e.friction_per_interface.get(i).copied().unwrap_or(0.0)))
                .collect();
            let (kin, strain, damp) = (e(&|e| e.kinetic), e(&|e| e.strain), e(&|e| e.damping));
            let resid = e(&|e| e.residual());
            let mut row = vec![
                z.name.clone(),
                s.name().to_string(),
                sig(input, 4),
                sig(kin, 3),
                sig(strain, 3),
                sig(damp, 4),
            ];
            row.extend(per.iter().map(|v| sig(*v, 4)));
            row.push(sig(resid, 2));
            row.push(format!("{:.1}", 100.0 * damp / input));
            row.push(format!("{:.1}", 100.0 * per.iter().sum::<f64>() / input));
            energy_rows.push(row);
            let pct = |v: f64| 100.0 * v / input;
            segs[0].1.push(pct(damp));
            for i in 0..n {
                segs[1 + i].1.push(pct(per[i]));
            }
            segs[n + 1].1.push(pct(kin + strain));
        }
        energy_panels.push(Panel {
            title: format!("Zone {}", z.name),
            x: Axis::new("share of the input energy (%)").range(0.0, 100.0),
            y: Axis::new(""),
            plot: Plot::StackedBars {
                categories: System3::ALL.iter().map(|s| s.name().to_string()).collect(),
                segments: segs
                    .into_iter()
                    .enumerate()
                    .map(|(i, (label, values))| Segment {
                        label,
                        values,
                        colour: Some(if i == 0 {
                            PALETTE[0]
                        } else if i == n + 1 {
                            RGBColor(170, 170, 170)
                        } else {
                            PALETTE[(i + 2) % PALETTE.len()]
                        }),
                    })
                    .collect(),
            },
        });
    }
    body += &table_with_id(
        "section71",
        &[
            "zone",
            "mean peak displacement ū (cm)",
            "paper ū (cm)",
            "T_new (s)",
            "paper T_new (s)",
            "T_rigid (s)",
            "how T_new was found",
        ],
        &rows,
    );
    let cols = inp.zones.len().min(2);
    let mut fig = Figure::grid(
        format!(
            "Energy partition of the Section 7.1 case ({}), mean over the motions",
            first.describe()
        ),
        energy_panels,
        cols,
    )
    .panel_px(460, 240);
    fig.share_x = true;
    body += &files.figure(
        "energy.svg",
        &fig,
        "Where the input energy of the Section 7.1 case goes, per system: viscous damping, \
         friction at each interface, and what is left as kinetic and strain energy when the \
         record ends (shares of the input energy, mean over the motions).",
    )?;
    let mut header: Vec<String> = [
        "zone",
        "system",
        "input (J/kg)",
        "kinetic at end (J/kg)",
        "strain at end (J/kg)",
        "damping (J/kg)",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    header.extend((1..=n).map(|i| format!("friction, interface {i} (J/kg)")));
    header.extend(
        [
            "balance residual (J/kg)",
            "damping share (%)",
            "friction share (%)",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    body += &para(
        "Energy per kg of structure mass, mean over the motions; input = kinetic + strain + \
         damping + friction up to the residual. The paper discusses the friction dissipated \
         within the stack but gives no numbers.",
    );
    body += &table_with_id("energy", &h, &energy_rows);
    Ok(Section::new(
        "section71",
        "The Section 7.1 case: histories, T_new (Fig. 12), energy",
        body,
    ))
}

fn table2_section(inp: &Inputs) -> Section {
    let c0 = &inp.zones[0].table2;
    let mut rows = Vec::new();
    for z in &inp.zones {
        let c = &z.table2;
        let (single, stack) = (c.mean_peak(System3::Single), c.mean_peak(System3::Stack));
        let reductions: Vec<f64> = c
            .runs
            .iter()
            .map(|r| 100.0 * (1.0 - r[0].peak_displacement_m / r[1].peak_displacement_m))
            .collect();
        let (rmin, rmax) = reductions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let paper = PAPER_TABLE_2.iter().find(|p| p.0 == z.name);
        let dash = || "–".to_string();
        rows.push(vec![
            z.name.clone(),
            format!("{single:.4}"),
            format!("{stack:.4}"),
            format!("{:.1}", 100.0 * (1.0 - stack / single)),
            format!("{rmin:.1} to {rmax:.1}"),
            paper.map_or_else(dash, |p| format!("{:.3}", p.1)),
            paper.map_or_else(dash, |p| format!("{:.3}", p.2)),
            paper.map_or_else(dash, |p| format!("{:.2}", 100.0 * (1.0 - p.2 / p.1))),
        ]);
    }
    let mut body = para(&format!(
        "Table 2 of the paper: peak structure displacement with the whole stack as one sliding \
         block and with the stack, {}. The paper's values are for its record #11 alone; ours are \
         means over the zone's {} motions, with the range of the reduction over the motions.",
        c0.describe(),
        inp.zones[0].motions.len()
    ));
    body += &table_with_id(
        "table2",
        &[
            "zone",
            "single block u_p (m)",
            "stack u_p (m)",
            "reduction (%)",
            "reduction over the motions (%)",
            "paper single block u_p (m)",
            "paper stack u_p (m)",
            "paper reduction (%)",
        ],
        &rows,
    );
    Section::new("table2", "Stack against single block (Table 2)", body)
}

fn drr_section(inp: &Inputs, sel: &Selection, files: &mut Files) -> Result<Section, ReportError> {
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
        let mut panels = Vec::new();
        for (p, a) in sel.panels.iter().enumerate() {
            let mut series = Vec::new();
            for (k, m) in sel.all_mu.iter().enumerate() {
                let mut s =
                    Series::faint(tp.clone(), z.column(&v.drr_1, per, case_index(grid, a, m)));
                if k == 0 {
                    s.label = format!("DRR_1, each of the {} friction pairs", sel.all_mu.len());
                }
                series.push(s);
            }
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
            panels.push(Panel::xy(
                sel.panel_title(grid, p),
                Axis::new("T_p (s)"),
                Axis::new("DRR (–)"),
                series,
            ));
        }
        let fig = Figure::grid(
            format!(
                "Zone {}: displacement response ratios against T_p ({})",
                z.name,
                paper_figure(&z.name, 10, 11)
            ),
            panels,
            sel.columns,
        );
        body += &files.figure(
            &format!("drr_{}.svg", z.name),
            &fig,
            &format!(
                "Zone {}: DRR_1 (lines) and DRR_2 (lines with dots) against T_p, panels over the \
                 mass ratios.",
                z.name
            ),
        )?;
    }
    Ok(Section::new(
        "drr",
        "Displacement response ratios (Figs 10–11)",
        body,
    ))
}

fn band_table(inp: &Inputs) -> String {
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

fn tnew_section(inp: &Inputs, sel: &Selection, files: &mut Files) -> Result<Section, ReportError> {
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
        let mut panels = Vec::new();
        for (p, a) in sel.panels.iter().enumerate() {
            let mut series = Vec::new();
            for (k, m) in sel.all_mu.iter().enumerate() {
                let mut s =
                    Series::faint(tp.clone(), z.column(&v.t_new, per, case_index(grid, a, m)));
                if k == 0 {
                    s.label = format!("each of the {} friction pairs", sel.all_mu.len());
                }
                series.push(s);
            }
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
            panels.push(Panel::xy(
                sel.panel_title(grid, p),
                Axis::new("T_p (s)"),
                Axis::new("T_new (s)"),
                series,
            ));
        }
        let fig = Figure::grid(
            format!(
                "Zone {}: T_new against T_p ({})",
                z.name,
                paper_figure(&z.name, 16, 17)
            ),
            panels,
            sel.columns,
        );
        body += &files.figure(
            &format!("tnew_{}.svg", z.name),
            &fig,
            &format!(
                "Zone {}: T_new against T_p, panels over the mass ratios, between T_p and \
                 T_rigid.",
                z.name
            ),
        )?;
    }
    body += &para(
        "Where T_new lies against its physical band [T_p, T_rigid] (tnew.h5, T_new_band; the \
         paper states T_p < T_new < T_rigid in general): cases per category.",
    );
    body += &band_table(inp);
    Ok(Section::new("tnew", "T_new against T_p (Figs 16–17)", body))
}

fn fit_section(inp: &Inputs, files: &mut Files) -> Result<Section, ReportError> {
    let grid = inp.grid;
    let f3 = |v: f64| fixed(v, 3);
    let mut table3 = Vec::new();
    let mut body = para(&format!(
        "Table 3 of the paper next to ours: the paper's fit quality of its Eqs. 16–17, those \
         equations as printed evaluated on our T_new, and each form fitted here (features {}; \
         5-fold cross-validated columns from fits that did not see the predicted cases).",
        inp.fit.features.join(", ")
    ));
    let mut coef_tables = String::new();
    for z in &inp.zones {
        let zf = &z.fit;
        if let Some((_, p)) = PAPER_TABLE_3.iter().find(|p| p.0 == z.name) {
            let mut row = vec![z.name.clone(), "paper Table 3".into()];
            row.extend(p.iter().map(|&v| f3(v)));
            row.extend(["–".to_string(), "–".to_string()]);
            table3.push(row);
        }
        if let Some(m) = &zf.published {
            table3.push(vec![
                z.name.clone(),
                "paper's equation as printed, on our T_new".into(),
                f3(m.r2),
                f3(m.r),
                f3(m.rmse),
                f3(m.mse),
                f3(m.mae),
                "–".into(),
                "–".into(),
            ]);
        }
        for ff in &zf.forms {
            let (m, cv) = (&ff.all_cases, &ff.cross_validated);
            let rec = if ff.form == zf.recommended {
                ", recommended"
            } else {
                ""
            };
            table3.push(vec![
                z.name.clone(),
                format!("{} form, fitted here{rec}", ff.form.name()),
                f3(m.r2),
                f3(m.r),
                f3(m.rmse),
                f3(m.mse),
                f3(m.mae),
                f3(cv.r2),
                f3(cv.rmse),
            ]);
        }
        if let Some(ff) = zf.recommended_fit() {
            let rows: Vec<Vec<String>> = ff
                .coefficients
                .iter()
                .enumerate()
                .map(|(i, (name, v))| {
                    let se = ff.standard_errors.get(i).copied().unwrap_or(f64::NAN);
                    vec![
                        name.clone(),
                        sig(*v, 6),
                        if se.is_finite() {
                            sig(se, 3)
                        } else {
                            "not estimated".into()
                        },
                        if se.is_finite() && *v != 0.0 {
                            format!("{:.1}", 100.0 * se / v.abs())
                        } else {
                            "–".into()
                        },
                    ]
                })
                .collect();
            coef_tables += &para(&format!(
                "Zone {}: coefficients of the recommended {} form ({} cases).",
                z.name,
                ff.form.name(),
                zf.cases
            ));
            coef_tables += &table_with_id(
                &format!("coefficients_{}", z.name),
                &[
                    "coefficient",
                    "value",
                    "standard error",
                    "standard error / |value| (%)",
                ],
                &rows,
            );
        }
    }
    body += &table_with_id(
        "table3",
        &[
            "zone",
            "equation",
            "R²",
            "R",
            "RMSE (s)",
            "MSE (s²)",
            "MAE (s)",
            "5-fold CV R²",
            "5-fold CV RMSE (s)",
        ],
        &table3,
    );
    body += &coef_tables;
    body += &para(
        "Residuals (computed − predicted T_new) of every fitted form against T_p, the \
         recommended one first; each case coloured by its T_new band category (the categories \
         side by side within each T_p column), with the mean and the 5th/95th percentiles per \
         T_p.",
    );
    for z in &inp.zones {
        let v = &z.tnew.vars;
        let tn: Vec<f64> = v.t_new.iter().copied().collect();
        let tr: Vec<f64> = v.t_rigid.iter().copied().collect();
        let band: Vec<u8> = v.band.iter().copied().collect();
        let data = samples(grid, &tr, &tn);
        let bands: Vec<u8> = (0..tn.len())
            .filter(|&c| tn[c].is_finite())
            .map(|c| band[c])
            .collect();
        let mut forms: Vec<_> = z.fit.forms.iter().collect();
        forms.sort_by_key(|f| f.form != z.fit.recommended);
        let mut panels = Vec::new();
        for ff in forms {
            let f = Fitted {
                form: ff.form,
                params: ff.coefficients.iter().map(|c| c.1).collect(),
            };
            let resid: Vec<f64> = data.iter().map(|s| s.t_new_s - f.predict(s)).collect();
            let mut series = Vec::new();
            // The categories side by side within each T_p column, so none hides another.
            let present: Vec<&(u8, String)> = z
                .band_flags
                .iter()
                .filter(|(code, _)| bands.contains(code))
                .collect();
            let step = grid
                .periods_s
                .windows(2)
                .map(|w| w[1] - w[0])
                .fold(f64::INFINITY, f64::min);
            let step = if step.is_finite() { step } else { 0.1 };
            let dodge = 0.6 * step / present.len().max(1) as f64;
            for (k, (code, word)) in present.iter().enumerate() {
                let shift = (k as f64 - (present.len() - 1) as f64 / 2.0) * dodge;
                let (xs, ys): (Vec<f64>, Vec<f64>) = data
                    .iter()
                    .zip(&resid)
                    .zip(&bands)
                    .filter(|(_, b)| *b == code)
                    .map(|((s, r), _)| (s.t_p_s() + shift, *r))
                    .unzip();
                series.push(
                    Series::points(word.clone(), xs, ys)
                        .mark(Mark::Points {
                            radius: 2,
                            opacity: 0.45,
                        })
                        .colour(PALETTE[*code as usize % PALETTE.len()]),
                );
            }
            let (mut m, mut lo, mut hi) = (Vec::new(), Vec::new(), Vec::new());
            for &t in &grid.periods_s {
                let mut r: Vec<f64> = data
                    .iter()
                    .zip(&resid)
                    .filter(|(s, _)| s.t_p_s() == t)
                    .map(|(_, r)| *r)
                    .collect();
                r.sort_by(f64::total_cmp);
                let q = |p: f64| {
                    r.get(((r.len() as f64 - 1.0) * p).round() as usize)
                        .copied()
                        .unwrap_or(f64::NAN)
                };
                m.push(mean(r.iter().copied()));
                lo.push(q(0.05));
                hi.push(q(0.95));
            }
            let black = RGBColor(0, 0, 0);
            series.push(
                Series::line("mean per T_p", grid.periods_s.clone(), m)
                    .colour(black)
                    .stroke(Stroke::Solid, 2),
            );
            series.push(
                Series::line("5th / 95th percentile per T_p", grid.periods_s.clone(), lo)
                    .colour(black)
                    .stroke(Stroke::Dashed, 1),
            );
            series.push(
                Series::line("5th / 95th percentile per T_p", grid.periods_s.clone(), hi)
                    .colour(black)
                    .stroke(Stroke::Dashed, 1),
            );
            let metrics = &ff.all_cases;
            panels.push(Panel::xy(
                format!(
                    "{} form{}: RMSE {:.3} s, R² {:.3}",
                    ff.form.name(),
                    if ff.form == z.fit.recommended {
                        " (recommended)"
                    } else {
                        ""
                    },
                    metrics.rmse,
                    metrics.r2
                ),
                Axis::new("T_p (s)"),
                Axis::new("computed − predicted T_new (s)"),
                series,
            ));
        }
        let cols = panels.len().min(2);
        let fig = Figure::grid(
            format!(
                "Zone {}: residuals of the design equations for T_new",
                z.name
            ),
            panels,
            cols,
        )
        .panel_px(460, 340);
        body += &files.figure(
            &format!("residuals_{}.svg", z.name),
            &fig,
            &format!(
                "Zone {}: computed − predicted T_new against T_p for every fitted form, the \
                 recommended ({}) first.",
                z.name,
                z.fit.recommended.name()
            ),
        )?;
    }
    Ok(Section::new("fit", "Design equations (Table 3)", body))
}

fn summary(inp: &Inputs) -> String {
    let study = inp.study;
    let g = inp.grid;
    let ph = &inp.physics;
    let mut rows = Vec::new();
    for z in &inp.zones {
        let (u, _, tn, _) = section71_tnew(z, ph);
        let p71 = (PAPER_SECTION_7_1.0 == z.name).then_some(PAPER_SECTION_7_1);
        rows.push(vec![
            "Section 7.1 case: T_new (s)".into(),
            z.name.clone(),
            p71.map_or("–".into(), |p| format!("{:.2}", p.2)),
            fixed(tn, 3),
        ]);
        rows.push(vec![
            "Section 7.1 case: mean peak displacement (cm)".into(),
            z.name.clone(),
            p71.map_or("–".into(), |p| format!("{:.2}", p.1 * 100.0)),
            format!("{:.2}", u * 100.0),
        ]);
        let c = &z.table2;
        let red = 100.0 * (1.0 - c.mean_peak(System3::Stack) / c.mean_peak(System3::Single));
        let p2 = PAPER_TABLE_2.iter().find(|p| p.0 == z.name);
        rows.push(vec![
            "Table 2 case: reduction of the peak by the stack (%)".into(),
            z.name.clone(),
            p2.map_or("–".into(), |p| {
                format!("{:.2}", 100.0 * (1.0 - p.2 / p.1))
            }),
            format!("{red:.1}"),
        ]);
        let p3 = PAPER_TABLE_3.iter().find(|p| p.0 == z.name);
        if let Some(ff) = z.fit.recommended_fit() {
            rows.push(vec![
                format!("design equation R² (ours: {} form)", ff.form.name()),
                z.name.clone(),
                p3.map_or("–".into(), |p| format!("{:.3}", p.1[0])),
                format!("{:.3}", ff.all_cases.r2),
            ]);
        }
    }
    let motions: Vec<String> = inp
        .zones
        .iter()
        .map(|z| format!("{} in Zone {}", z.motions.len(), z.name))
        .collect();
    let facts = vec![
        format!(
            "Config {}, study directory {}.",
            study.config_path.display(),
            study.out.display()
        ),
        format!("Matched motions: {}.", motions.join(", ")),
        format!(
            "Grid: T_p {} to {} s ({} values); {}; {}; {} cases per zone.",
            num(g.periods_s[0]),
            num(g.periods_s[g.periods_s.len() - 1]),
            g.periods_s.len(),
            g.alpha
                .iter()
                .enumerate()
                .map(|(i, a)| format!("α_{} ∈ {{{}}}", i + 1, joined(a)))
                .collect::<Vec<_>>()
                .join(", "),
            g.mu.iter()
                .enumerate()
                .map(|(i, a)| format!("μ_{} ∈ {{{}}}", i + 1, joined(a)))
                .collect::<Vec<_>>()
                .join(", "),
            g.cases()
        ),
        format!(
            "Physics: viscous damping ζ = {} of the {} basis (one damper for the stack, single \
             block and rigid systems); static friction = {} × kinetic.",
            ph.damping,
            ph.basis.name(),
            ph.mu_static_ratio
        ),
    ];
    list(&facts)
        + &para("The paper's numbers next to ours (details in the sections below):")
        + &table_with_id("summary", &["quantity", "zone", "paper", "ours"], &rows)
}

/// The paper's figure of a zone: `zone_iii` for Zone III, `zone_v` for Zone V; both for another.
fn paper_figure(zone: &str, zone_iii: u32, zone_v: u32) -> String {
    match zone {
        "III" => format!("Fig. {zone_iii}"),
        "V" => format!("Fig. {zone_v}"),
        _ => format!("cf. Figs {zone_iii}–{zone_v}"),
    }
}

fn joined(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(", ")
}

fn not_shown() -> Section {
    Section::new(
        "not-shown",
        "Not reproduced here",
        list(&[
            "Figs 1–3 (the model's sketches) and Figs 6–8 (the ABAQUS validation): the solver is \
             checked against independent references instead (docs/accuracy)."
                .into(),
            "Fig. 9 (histories of the Table 2 case under record #11): the paper's records are not \
             available; the histories shown are the Section 7.1 case's."
                .into(),
            "Figs 13–15 (the OLE validation of the T_new method against reference [12]).".into(),
            "Table 1 (the paper's PEER NGA records): this study's motions come from its config."
                .into(),
        ]),
    )
}

/// Builds the report.
pub fn build(s: &Session) -> Result<Outcome, PipelineError> {
    let study = &s.study;
    let inp = Inputs::load(study)?;
    let sel = Selection::new(inp.grid);
    let mut files = Files::default();
    let sections = vec![
        motions_section(&inp, &mut files)?,
        section71_section(&inp, &mut files)?,
        table2_section(&inp),
        drr_section(&inp, &sel, &mut files)?,
        tnew_section(&inp, &sel, &mut files)?,
        fit_section(&inp, &mut files)?,
        not_shown(),
    ];
    let html = document(
        &format!(
            "slidestack report: {}",
            study.config_path.file_name().map_or_else(
                || study.config_path.display().to_string(),
                |f| { f.to_string_lossy().into_owned() }
            )
        ),
        &summary(&inp),
        &sections,
    );
    let mut out = files.files;
    out.push(("index.html".into(), html.into_bytes()));
    let dir = study.path("report");
    write_report_dir(&dir, study.fingerprint(StageId::Report)?, &out)?;
    Ok(Outcome::Wrote(vec![dir.join("index.html")]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subsets_keep_the_ends_and_fit_the_limit() {
        assert_eq!(picks(7, 3), vec![0, 3, 6]);
        assert_eq!(picks(8, 2), vec![0, 7]);
        assert_eq!(picks(3, 1), vec![1]);
        // The paper's friction axes (7, 8) → 3 × 2 lines; its mass ratios (3, 3) → 9 panels.
        assert_eq!(subset(&[7, 8], 6), vec![vec![0, 3, 6], vec![0, 7]]);
        assert_eq!(subset(&[3, 3], 9), vec![vec![0, 1, 2], vec![0, 1, 2]]);
        let three = subset(&[3, 3, 3], 9);
        assert!(three.iter().map(Vec::len).product::<usize>() <= 9);
        assert_eq!(
            combinations(&[vec![0, 2], vec![1]]),
            vec![vec![0, 1], vec![2, 1]]
        );
    }

    #[test]
    fn significant_digits() {
        assert_eq!(sig(4605.324686871364, 6), "4605.32");
        assert_eq!(sig(0.008555841236124935, 4), "0.008556");
        assert_eq!(sig(-38.50715814517285, 4), "-38.51");
        assert_eq!(sig(123456.0, 3), "1.23e5");
        assert_eq!(sig(f64::NAN, 3), "–");
    }
}
