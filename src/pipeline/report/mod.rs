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
//!   coefficients with their standard errors, and the residuals of every fitted form;
//! * `design.html`: `slidestack design` in the browser, and an explorer of the grid's figures;
//! * with an `ida:` section: the first IDA case's curves, the fragility fits and the median
//!   ductility of the stack against the rigidly attached load (from `ida.h5`).
//!
//! A building study's report (`building:`) has the matched motions, the building section
//! (`building.rs`: per zone and frame, the demands with and without sliding, `T_new/T_1` and `λ`
//! against `T_1`, the drift and floor-acceleration profiles), the design equations over the
//! frames and frame by frame, and the IDA per frame; the paper's one-storey cases are a
//! one-storey study's.
//!
//! Panels and lines are picked from the grid's own axes, so any grid (other block counts
//! included) gives a report. Every simulation uses the study's physics
//! ([`crate::study::physics::Physics`]). The directory is replaced as a whole
//! ([`crate::store::report`]).
//!
//! A config that does not configure the fit (a grid too small to fit a design equation to) gets
//! the same without the design equations and the design page; one without a grid gets the
//! matched motions and the IDA.
//!
//! Fingerprint: the fit's (else `tnew`'s, else none) and the motions' (which carry everything
//! upstream), `ida.h5`'s with an `ida:` section, and the report's own version.

mod building;
mod cases;
mod design;
mod fit;
pub mod floors;
mod grid;
pub mod ida;
mod motions;
mod rocking;
mod runs;
mod select;
mod text;

use super::{PipelineError, Session, StageId, StageOutcome, Study};
use crate::grid::Grid;
use crate::ground_motion::Record;
use crate::render::chart::{self, ChartError, Figure};
use crate::render::page::{Section, document, escape, figure, list, para, table_with_id};
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::fit::{FitReport, FrameFit, ZoneFit};
use crate::store::motions::{ZoneSpectra, read_zone_spectra};
use crate::store::report::write_report_dir;
use crate::store::tnew::{ZoneTnew, read_band_flags};
use crate::study::cases::{PAPER_SECTION_7_1, PAPER_TABLE_2, PAPER_TABLE_3, SECTION_7_1, TABLE_2};
use crate::study::physics::{CaseError, Physics, SystemKind};
use crate::study::tnew::BAND_FLAGS;
use cases::{section71_section, table2_section};
use fit::fit_section;
use grid::{drr_section, tnew_section};
use motions::motions_section;
use runs::{CaseRun, section71_tnew};
use select::Selection;
use text::{fixed, joined, num, nums};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ReportError {
    #[error("the report's {source}, under {motion}")]
    Case {
        motion: String,
        source: Box<CaseError>,
    },
    #[error("zone {zone} has no motions")]
    NoMotions { zone: String },
    #[error(transparent)]
    Chart(#[from] ChartError),
    #[error(transparent)]
    Design(#[from] crate::study::design::DesignError),
}

/// The fingerprint the report must carry: `grid_fingerprint` is the fit's, or `tnew`'s when the
/// grid is too small to fit, or `None` without a grid; with an `ida:` section, `ida.h5`'s too
/// (the report then shows it), and with `report.compare_with` the compared study's fit's (its
/// `T_new`, `λ` and fit enter the building section).
pub fn fingerprint(
    grid_fingerprint: Option<&str>,
    motions_fingerprint: &str,
    ida_fingerprint: Option<&str>,
    floors_fingerprint: Option<&str>,
    compared_fit_fingerprint: Option<&str>,
) -> String {
    let mut parts: Vec<&str> = grid_fingerprint.into_iter().collect();
    parts.push(motions_fingerprint);
    parts.extend(ida_fingerprint);
    if let Some(f) = floors_fingerprint {
        parts.extend(["floors", f]);
    }
    if let Some(c) = compared_fit_fingerprint {
        parts.extend(["compare_with", c]);
    }
    StageId::Report.fingerprint(&hash_parts(&parts))
}

/// One zone's inputs.
struct Zone {
    name: String,
    motions: Vec<Record>,
    spectra: ZoneSpectra,
    tnew: ZoneTnew,
    band_flags: Vec<(u8, String)>,
    /// `None` when the config does not configure the fit (a grid too small to fit).
    fit: Option<ZoneFit>,
    /// The paper's named one-storey cases run on the zone's motions (`None` in a building
    /// study, whose report has the building section instead).
    paper: Option<PaperCases>,
}

/// The paper's Section 7.1 and Table 2 cases of one zone.
struct PaperCases {
    section71: CaseRun,
    table2: CaseRun,
}

impl Zone {
    /// The paper's cases: only the one-storey report's sections ask, and it has them.
    fn paper(&self) -> &PaperCases {
        self.paper
            .as_ref()
            .expect("the paper's cases are run for a one-storey study")
    }

    /// The zone's fit: only the fit's sections and the design page ask, and they are made only
    /// when the study has one.
    fn fit(&self) -> &ZoneFit {
        self.fit
            .as_ref()
            .expect("the fit's sections are made with a fit")
    }

    /// Column `case` of a `[T_p, case…]` variable: one value per `T_p`.
    fn column(&self, v: &ndarray::ArrayD<f64>, per: usize, case: usize) -> Vec<f64> {
        v.iter().skip(case).step_by(per).copied().collect()
    }
}

/// Everything the report is made of: the study and each zone's data.
struct Inputs<'a> {
    study: &'a Study,
    grid: &'a Grid,
    physics: Physics,
    /// `None` when the config does not configure the fit ([`Study::configured`]).
    fit: Option<FitReport>,
    zones: Vec<Zone>,
}

impl<'a> Inputs<'a> {
    fn load(study: &'a Study) -> Result<Self, PipelineError> {
        let grid = study.grid(StageId::Report)?;
        let physics = study.physics();
        let motions = super::files::motions(study)?;
        let (th5, fyaml) = (study.path("tnew.h5"), study.path("fit.yaml"));
        let n = grid.blocks();
        let fit = match study.configured(StageId::Fit) {
            true => Some(super::files::fit(study)?),
            false => None,
        };
        let mut zones = Vec::new();
        for (zc, motions) in study.cfg.zones.iter().zip(motions) {
            let spectra = zone_spectra(study, &zc.name, &motions)?;
            let tnew = super::files::tnew_zone(study, &zc.name)?;
            let band_flags = read_band_flags(&th5, &zc.name)?;
            if !same_flags(&band_flags, BAND_FLAGS) {
                let why = format!(
                    "zone_{}: T_new_band's flag_values/flag_meanings are not this version's",
                    zc.name
                );
                return Err(StoreError::corrupt(&th5, why).into());
            }
            let zf = match &fit {
                Some(fit) => Some(
                    (fit.zones.iter())
                        .find(|f| f.zone == zc.name)
                        .cloned()
                        .ok_or_else(|| {
                            StoreError::corrupt(&fyaml, format!("has no zone {}", zc.name))
                        })?,
                ),
                None => None,
            };
            zones.push(Zone {
                name: zc.name.clone(),
                spectra,
                band_flags,
                paper: match study.building() {
                    Some(_) => None,
                    None => Some(PaperCases {
                        section71: CaseRun::new(&physics, &SECTION_7_1, n, &motions)?,
                        table2: CaseRun::new(&physics, &TABLE_2, n, &motions)?,
                    }),
                },
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

    /// The study's fit: only the fit's sections and the design page ask, and they are made
    /// only when the study has one.
    fn fit(&self) -> &FitReport {
        self.fit
            .as_ref()
            .expect("the fit's sections are made with a fit")
    }

    /// Every zone's matched motions, as the motions section shows them.
    fn motions(&self) -> Vec<ZoneMotions<'_>> {
        (self.zones.iter())
            .map(|z| ZoneMotions {
                name: &z.name,
                target: &z.tnew.target,
                count: z.motions.len(),
                spectra: &z.spectra,
            })
            .collect()
    }
}

/// Zone `zone`'s stored spectra of its matched `motions`, refused when it has none or when
/// `motions.h5` checked them on other periods than the config's.
fn zone_spectra(
    study: &Study,
    zone: &str,
    motions: &[Record],
) -> Result<ZoneSpectra, PipelineError> {
    if motions.is_empty() {
        return Err(ReportError::NoMotions {
            zone: zone.to_string(),
        }
        .into());
    }
    let mh5 = study.path("motions.h5");
    let spectra = read_zone_spectra(&mh5, zone)?;
    if spectra.periods_s != study.cfg.motions.matching.check_grid_s() {
        let why = format!("zone_{zone}: its check periods are not the config's");
        return Err(StoreError::corrupt(&mh5, why).into());
    }
    Ok(spectra)
}

/// "Matched motions: 3 in Zone III, 3 in Zone V." of a report's facts.
fn motions_fact(zones: &[ZoneMotions]) -> String {
    let counts: Vec<String> = (zones.iter())
        .map(|z| format!("{} in Zone {}", z.count, z.name))
        .collect();
    format!("Matched motions: {}.", counts.join(", "))
}

/// One zone's matched motions and their stored spectra: what every report shows.
struct ZoneMotions<'a> {
    name: &'a str,
    /// The target spectrum as the config names it.
    target: &'a str,
    count: usize,
    spectra: &'a ZoneSpectra,
}

/// Whether stored `(code, word)` flags are `want`.
fn same_flags(stored: &[(u8, String)], want: &[(u8, &str)]) -> bool {
    stored.len() == want.len()
        && stored
            .iter()
            .zip(want)
            .all(|(a, b)| a.0 == b.0 && a.1 == b.1)
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

/// The study in a few lines: config, motions, grid, the buildings of a building study, physics.
fn facts(inp: &Inputs) -> Vec<String> {
    let study = inp.study;
    let g = inp.grid;
    let ph = &inp.physics;
    let period = if study.building().is_some() {
        "T_1"
    } else {
        "T_p"
    };
    let mut facts = vec![
        // Not the output directory: a study's report is the same wherever it is written.
        format!("Config {}.", study.config_path.display()),
        motions_fact(&inp.motions()),
        format!(
            "Grid: {period} {} to {} s ({} values); {}; {}; {} cases per {}.",
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
            g.cases(),
            if study.building().is_some() {
                "frame"
            } else {
                "zone"
            }
        ),
        format!(
            "Physics: viscous damping ζ = {} of the {} basis (one damper for the stack, single \
             block and rigid systems); static friction = {} × kinetic.",
            ph.damping,
            ph.basis.name(),
            ph.mu_static_ratio
        ),
    ];
    let mut shown: Vec<usize> = Vec::new();
    // A building study names its buildings, once per storey count; the one-storey structure
    // is described above.
    for f in study.shape.building_frames() {
        if shown.contains(&f.storeys()) {
            continue;
        }
        shown.push(f.storeys());
        facts.push(format!(
            "Building of {} storey{}: relative floor masses {}, storey stiffnesses {}, storey \
             heights {} m (floor 1 first); its first-mode period is the grid's T_1.",
            f.storeys(),
            if f.storeys() == 1 { "" } else { "s" },
            nums(&f.floor_masses),
            nums(&f.storey_stiffnesses),
            nums(&f.storey_heights_m)
        ));
    }
    facts
}

fn summary(inp: &Inputs) -> String {
    let g = inp.grid;
    let mut rows = Vec::new();
    for z in &inp.zones {
        let (u, _, tn, _) = section71_tnew(z);
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
        let c = &z.paper().table2;
        let red =
            100.0 * (1.0 - c.mean_peak(SystemKind::Stack) / c.mean_peak(SystemKind::SingleBlock));
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
        if let Some(ff) = z.fit.as_ref().and_then(ZoneFit::recommended_fit) {
            rows.push(vec![
                format!("design equation R² (ours: {} form)", ff.form.name()),
                z.name.clone(),
                p3.map_or("–".into(), |p| format!("{:.3}", p.1[0])),
                format!("{:.3}", ff.all_cases.r2),
            ]);
        }
    }
    let facts = facts(inp);
    let example = if g.blocks() == 2 {
        format!(
            " (the paper's Section 9 worked example: <a href='design.html?{q}'>design.html?{q}</a>)",
            q = escape(design::SECTION_9_QUERY)
        )
    } else {
        String::new()
    };
    let design = match inp.fit {
        Some(_) => format!(
            "<p id='design-link'><a href='design.html'>The design page</a>: T_new and the design \
             spectral acceleration of your structure from this study, in the browser{example}; \
             and an explorer of the grid's figures.</p>"
        ),
        None => no_fit(inp.study),
    };
    design
        + &list(&facts)
        + &para("The paper's numbers next to ours (details in the sections below):")
        + &table_with_id("summary", &["quantity", "zone", "paper", "ours"], &rows)
}

/// A building study's summary: the facts, how to get design numbers, and per zone the fit of
/// the design equations over the frames.
fn building_summary(inp: &Inputs) -> String {
    let mut rows = Vec::new();
    for z in &inp.zones {
        let Some(zf) = &z.fit else { continue };
        if let Some(ff) = zf.recommended_fit() {
            rows.push(vec![
                format!(
                    "T_new: the building equation ({} form), R² over every frame",
                    ff.form.name()
                ),
                z.name.clone(),
                format!("{:.3}", ff.all_cases.r2),
            ]);
        }
        let lowest = |m: &dyn Fn(&FrameFit) -> Option<f64>| {
            (zf.frames.iter())
                .filter_map(|f| m(f).map(|r| (r, f.frame.as_str())))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        for (what, m) in [
            (
                "T_new: the building equation",
                (|f: &FrameFit| Some(f.building.r2)) as fn(&FrameFit) -> Option<f64>,
            ),
            ("T_new: the one-storey equation", |f: &FrameFit| {
                f.one_storey.as_ref().map(|m| m.r2)
            }),
            ("T_new: the paper's equation as printed", |f: &FrameFit| {
                f.published.as_ref().map(|m| m.r2)
            }),
            ("λ: the fitted fraction equation", |f: &FrameFit| {
                f.lambda.as_ref().map(|m| m.r2)
            }),
        ] {
            if let Some((r2, frame)) = lowest(&m) {
                rows.push(vec![
                    format!("{what}, lowest R² of a frame ({frame})"),
                    z.name.clone(),
                    format!("{r2:.3}"),
                ]);
            }
        }
    }
    if inp.fit.is_none() {
        return no_fit(inp.study) + &list(&facts(inp));
    }
    let q = escape(&design::building_example(inp).unwrap_or_default());
    let design = format!(
        "<p id='design-link'><a href='design.html'>The design page</a>: T_new, T_1,rigid, λ \
         and the design spectral acceleration of one building of this study, in the browser \
         (e.g. <a href='design.html?{q}'>design.html?{q}</a>), as <code>slidestack design \
         --study OUT --zone Z --period T_1 --alpha … --mu … --storeys N --floor F</code> gives \
         them; and an explorer of the grid's figures, frame by frame.</p>"
    );
    design
        + &list(&facts(inp))
        + &para(
            "The design equations over the frames (fit.yaml; per frame in the design equations' \
             section):",
        )
        + &table_with_id("summary", &["quantity", "zone", "ours"], &rows)
}

/// The paragraph of a study whose config does not configure the fit: why, and so no design
/// equations and no design page.
fn no_fit(study: &Study) -> String {
    let why = study.not_configured_why(StageId::Fit).unwrap_or_default();
    para(&format!(
        "No design equations and no design page: {why}. The sections below show the grid's \
         cases as computed."
    ))
}

/// What the report leaves out (`building`: of a building study).
fn not_shown(building: bool) -> Section {
    let mut items = vec![
        "Figs 1–3 (the model's sketches) and Figs 6–8 (the ABAQUS validation): the solver is \
         checked against independent references instead (docs/accuracy)."
            .to_string(),
    ];
    if building {
        items.push(
            "The paper's one-storey cases and figures (Section 7.1 and Fig. 12, Table 2, Figs \
             9–11 and 16–17, Table 3's paper column): a building study's report has the building \
             section instead; a one-storey config (configs/paper.yaml) gives them."
                .into(),
        );
    } else {
        items.push(
            "Fig. 9 (histories of the Table 2 case under record #11): the paper's records are \
             not available; the histories shown are the Section 7.1 case's."
                .into(),
        );
    }
    items
        .push("Figs 13–15 (the OLE validation of the T_new method against reference [12]).".into());
    items.push(
        "Table 1 (the paper's PEER NGA records): this study's motions come from its config.".into(),
    );
    Section::new("not-shown", "Not reproduced here", list(&items))
}

/// Builds the report.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    if !study.configured(StageId::Sweep) {
        return build_without_grid(s);
    }
    let inp = Inputs::load(study)?;
    let sel = Selection::new(inp.grid);
    let mut files = Files::default();
    let building = study.building().is_some();
    let mut sections = vec![motions_section(study, &inp.motions(), &mut files)?];
    if building {
        // The compared study (`report.compare_with`), its files checked as an upstream stage's.
        let compared = match &study.compare {
            Some(other) => {
                other.require(StageId::Tnew)?;
                other.require(StageId::Fit)?;
                if other.grid(StageId::Report)? != inp.grid || other.building() != study.building()
                {
                    return Err(PipelineError::BadInput {
                        file: study.config_path.clone(),
                        why: format!(
                            "`report.compare_with`: {} has other buildings or another grid than \
                             this study: compare the same cases",
                            other.config_path.display()
                        ),
                    });
                }
                Some(Inputs::load(other)?)
            }
            None => None,
        };
        sections.push(building::building_section(
            &inp,
            compared.as_ref(),
            &mut files,
        )?);
    } else {
        sections.extend([
            section71_section(&inp, &mut files)?,
            table2_section(&inp),
            drr_section(&inp, &sel, &mut files)?,
            tnew_section(&inp, &sel, &mut files)?,
        ]);
    }
    if inp.fit.is_some() {
        sections.push(fit_section(&inp, &mut files)?);
    }
    sections.extend(rocking::rocking_section(study)?);
    if study.configured(StageId::Ida) {
        sections.push(ida::ida_section(study, &mut files)?);
    }
    if study.configured(StageId::Floors) {
        sections.push(floors::floors_section(study, &mut files)?);
    }
    sections.push(not_shown(building));
    if inp.fit.is_some() {
        design::design_file(&inp, &mut files)?;
    }
    let summary = if building {
        building_summary(&inp)
    } else {
        summary(&inp)
    };
    write(study, &summary, &sections, files)
}

/// The report of a config without a grid: the matched motions and, with an `ida:` section, the
/// IDA.
fn build_without_grid(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let motions = super::files::motions(study)?;
    let spectra = (study.cfg.zones.iter())
        .zip(&motions)
        .map(|(zc, m)| zone_spectra(study, &zc.name, m))
        .collect::<Result<Vec<_>, _>>()?;
    let zones: Vec<ZoneMotions> = (study.cfg.zones.iter())
        .zip(&motions)
        .zip(&spectra)
        .map(|((zc, m), s)| ZoneMotions {
            name: &zc.name,
            target: &zc.target,
            count: m.len(),
            spectra: s,
        })
        .collect();
    let mut files = Files::default();
    let mut sections = vec![motions_section(study, &zones, &mut files)?];
    let ida = study.configured(StageId::Ida);
    if ida {
        sections.push(ida::ida_section(study, &mut files)?);
    }
    if study.configured(StageId::Floors) {
        sections.push(floors::floors_section(study, &mut files)?);
    }
    let facts = vec![
        format!("Config {}.", study.config_path.display()),
        motions_fact(&zones),
        format!(
            "No grid: this config runs the motions{}; a `grid` section adds the sweep, T_new and \
             the design equations.",
            if ida { " and the IDA" } else { "" }
        ),
    ];
    write(study, &list(&facts), &sections, files)
}

/// Writes the report's directory: `index.html` of `summary` and `sections`, and `files`.
fn write(
    study: &Study,
    summary: &str,
    sections: &[Section],
    files: Files,
) -> Result<StageOutcome, PipelineError> {
    let html = document(
        &format!(
            "slidestack report: {}",
            study.config_path.file_name().map_or_else(
                || study.config_path.display().to_string(),
                |f| { f.to_string_lossy().into_owned() }
            )
        ),
        summary,
        sections,
    );
    let mut out = files.files;
    out.push(("index.html".into(), html.into_bytes()));
    let dir = study.path("report");
    write_report_dir(&dir, study.fingerprint(StageId::Report)?, &out)?;
    Ok(StageOutcome::Wrote(vec![dir.join("index.html")]))
}
