//! The floors stage: the floor response spectra of the `floor_spectra:` section's cases, each
//! on every frame, under every matched motion, sliding and attached → `floors.h5` (layout in
//! [`crate::store::floors`]; one unit's numerics in [`crate::study::floors`]).
//!
//! Units (one zone, one motion, one case, one frame) run in parallel and are collected in their
//! fixed order, so the file's bytes do not depend on the thread count; a frame that is an
//! earlier one's building takes that frame's spectra. The file is written once, atomically, at
//! the end (a run killed before leaves nothing; the rerun computes everything again).
//!
//! Fingerprint: the `zones` and `floor_spectra` sections, the grid's physics, in a building
//! study the `building` section and `grid.stack_floor`, and the motions' fingerprint.

use super::{PipelineError, Session, StageId, StageOutcome, Study};
use crate::spectrum::floor::{FloorSpectraSpec, REFINEMENT};
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::floors::{FloorsAxes, FloorsMeta, ZoneFloors, read_zone_floors, write_floors};
use crate::store::h5::Attr;
use crate::study::building::Frame;
use crate::study::case_units::{CaseUnit, UnitPlan};
use crate::study::config::StudyConfig;
use crate::study::floors::{FloorUnit, FloorsConfig, FloorsError, floor_unit};
use ndarray::{ArrayD, IxDyn};
use rayon::prelude::*;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum FloorsStageError {
    #[error("{}: the `floors` stage needs a `floor_spectra` section", config.display())]
    NoSection { config: PathBuf },
    #[error("zone {zone}, motion {motion}: {why}")]
    Record {
        zone: String,
        motion: String,
        why: String,
    },
    #[error("zone {zone}, motion {motion}, case {case}{frame}: {source}")]
    Unit {
        zone: String,
        motion: String,
        case: usize,
        /// `, 3 storeys, stack on the roof` in a building study, else empty.
        frame: String,
        source: Box<FloorsError>,
    },
}

/// The fingerprint `floors.h5` must carry, `None` without a `floor_spectra` section.
pub fn fingerprint(cfg: &StudyConfig, motions_fingerprint: &str) -> Option<String> {
    let floors = cfg.floor_spectra.as_ref()?;
    let p = cfg.physics();
    let mut section = serde_json::json!({
        "zones": cfg.zones, "floor_spectra": floors, "refinement": REFINEMENT,
        "physics": { "damping": p.damping, "basis": p.basis, "mu_static_ratio": p.mu_static_ratio },
    });
    if let Some(b) = &cfg.building {
        section["building"] = serde_json::json!(b);
        let floors = cfg.grid.as_ref().and_then(|g| g.stack_floor.as_ref());
        section["stack_floor"] = serde_json::json!(floors);
    }
    Some(StageId::Floors.fingerprint(&hash_parts(&[&section.to_string(), motions_fingerprint])))
}

/// The config's `floor_spectra:` section, which the stage needs.
pub fn section(study: &Study) -> Result<&FloorsConfig, FloorsStageError> {
    (study.cfg.floor_spectra.as_ref()).ok_or_else(|| FloorsStageError::NoSection {
        config: study.config_path.clone(),
    })
}

/// The axes the config gives every zone of `floors.h5`.
pub fn axes_of(study: &Study) -> Result<FloorsAxes, PipelineError> {
    let cfg = section(study)?;
    let spec = cfg.spec().map_err(|(key, why)| PipelineError::BadInput {
        file: study.config_path.clone(),
        why: format!("`floor_spectra.{key}`: {why}"),
    })?;
    Ok(FloorsAxes {
        case_period_s: cfg.cases.iter().map(|c| c.period_s).collect(),
        case_alpha: cfg.cases.iter().map(|c| c.alpha.clone()).collect(),
        case_mu: cfg.cases.iter().map(|c| c.mu.clone()).collect(),
        damping: spec.damping,
        periods_s: spec.periods_s,
        floors: study.building().map_or(1, |b| b.max_storeys()),
        building: study.building().cloned(),
    })
}

/// Builds `floors.h5`.
pub fn build(s: &Session) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Floors;
    let cfg = section(study)?;
    let fp = study.fingerprint(me)?;
    let axes = axes_of(study)?;
    let spec = FloorSpectraSpec {
        periods_s: axes.periods_s.clone(),
        damping: axes.damping.clone(),
    };
    let motions = super::files::motions(study)?;
    // Every record refined before any run: one whose history the spectrum cannot take is
    // refused here, naming it.
    for (z, ms) in motions.iter().enumerate() {
        for m in ms {
            m.check_refinable(REFINEMENT)
                .map_err(|why| FloorsStageError::Record {
                    zone: study.cfg.zones[z].name.clone(),
                    motion: m.name.clone(),
                    why,
                })?;
        }
    }
    let physics = study.physics();
    let frames = study.frames();
    let nf = frames.len();
    let counts: Vec<usize> = motions.iter().map(Vec::len).collect();
    let plan = UnitPlan::new(&counts, cfg.cases.len(), &frames);
    let units = &plan.run;
    s.reporter.info(
        me,
        &format!(
            "{} units (motions × cases{}), each two runs on the record refined {REFINEMENT} \
             times and {} spectra of {} periods per floor",
            units.len(),
            if study.building().is_some() {
                " × distinct buildings"
            } else {
                ""
            },
            spec.damping.len(),
            spec.periods_s.len()
        ),
    );
    let bar = s.reporter.progress(me, units.len() as u64);
    let outs: Vec<FloorUnit> = units
        .par_iter()
        .map(|&u| -> Result<FloorUnit, PipelineError> {
            s.check_cancelled(me)?;
            let rec = &motions[u.zone][u.motion];
            let frame = frames[u.frame].as_ref();
            let unit =
                floor_unit(&physics, &cfg.cases[u.case], frame, rec, &spec).map_err(|source| {
                    FloorsStageError::Unit {
                        zone: study.cfg.zones[u.zone].name.clone(),
                        motion: rec.name.clone(),
                        case: u.case,
                        frame: frame.map_or(String::new(), |f| format!(", {f}")),
                        source: Box::new(source),
                    }
                })?;
            bar.inc();
            Ok(unit)
        })
        .collect::<Result<_, _>>()?;
    bar.finish();
    let done: std::collections::BTreeMap<CaseUnit, &FloorUnit> =
        units.iter().copied().zip(&outs).collect();
    let mut zones = Vec::new();
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let ms = &motions[z];
        let unit = |motion: usize, case: usize, frame: usize| {
            done[&plan.source(CaseUnit {
                zone: z,
                motion,
                case,
                frame,
            })]
        };
        zones.push(zone_floors(
            &axes,
            ms.len(),
            nf,
            unit,
            ZoneNames {
                name: zc.name.clone(),
                target: zc.target.clone(),
                motions: ms.iter().map(|r| r.name.clone()).collect(),
                pga_g: ms.iter().map(|r| r.pga_g()).collect(),
            },
        ));
    }
    let physics_attrs = super::sweep::physics_attrs(&physics);
    let building_json = super::sweep::building_attr(study);
    let mut settings: Vec<(&str, Attr)> = physics_attrs.to_vec();
    settings.push(("refinement", Attr::F64(REFINEMENT as f64)));
    if let Some(b) = &building_json {
        settings.push(("building", Attr::Str(b)));
    }
    let meta = FloorsMeta {
        fingerprint: fp,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        config_sha256: &study.config_sha256,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_floors(&path, &meta, &axes, &zones)?;
    s.reporter.info(me, &format!("verified {}", path.display()));
    Ok(StageOutcome::Wrote(vec![path]))
}

/// A zone's names, and its motions' peak ground accelerations, g.
struct ZoneNames {
    name: String,
    target: String,
    motions: Vec<String>,
    pga_g: Vec<f64>,
}

/// Where a value of a zone's variables lies in their flat row-major arrays
/// ([`crate::store::floors`]: `[motion, case, frame, …]`, the frame axis `storeys ×
/// stack_floor` folded into one).
struct Offsets {
    cases: usize,
    frames: usize,
    damping: usize,
    floors: usize,
    periods: usize,
}

impl Offsets {
    fn of(axes: &FloorsAxes, frames: usize) -> Self {
        Self {
            cases: axes.case_period_s.len(),
            frames,
            damping: axes.damping.len(),
            floors: axes.floors,
            periods: axes.periods_s.len(),
        }
    }

    fn unit(&self, m: usize, c: usize, f: usize) -> usize {
        (m * self.cases + c) * self.frames + f
    }

    /// Floor `j`'s peak of `pfa_*`.
    fn pfa(&self, m: usize, c: usize, f: usize, j: usize) -> usize {
        self.unit(m, c, f) * self.floors + j
    }

    /// The first period of floor `j`'s spectrum at damping ratio `d` in `psa_*`.
    fn psa(&self, m: usize, c: usize, f: usize, d: usize, j: usize) -> usize {
        ((self.unit(m, c, f) * self.damping + d) * self.floors + j) * self.periods
    }
}

/// One zone's variables from its units: `unit(m, c, f)` of motion `m`, case `c`, frame `f`,
/// padded with NaN above each building's roof.
fn zone_floors<'u>(
    axes: &FloorsAxes,
    motions: usize,
    frames: usize,
    unit: impl Fn(usize, usize, usize) -> &'u FloorUnit,
    names: ZoneNames,
) -> ZoneFloors {
    let o = Offsets::of(axes, frames);
    let mut head = vec![motions, o.cases];
    head.extend(axes.building.iter().flat_map(|b| b.shape()));
    let nan = |tail: &[usize]| {
        let mut shape = head.clone();
        shape.extend_from_slice(tail);
        ArrayD::from_elem(IxDyn(&shape), f64::NAN)
    };
    let mut pfa = [nan(&[o.floors]), nan(&[o.floors])];
    let per_floor = [o.damping, o.floors, o.periods];
    let mut psa = [nan(&per_floor), nan(&per_floor)];
    for m in 0..motions {
        for c in 0..o.cases {
            for f in 0..frames {
                let u = unit(m, c, f);
                for s in 0..2 {
                    let at = o.pfa(m, c, f, 0);
                    let rows = pfa[s].as_slice_mut().expect("standard layout");
                    rows[at..at + u.pfa_g[s].len()].copy_from_slice(&u.pfa_g[s]);
                    let rows = psa[s].as_slice_mut().expect("standard layout");
                    for (d, floors) in u.psa_g[s].iter().enumerate() {
                        for (j, spectrum) in floors.iter().enumerate() {
                            let at = o.psa(m, c, f, d, j);
                            rows[at..at + o.periods].copy_from_slice(spectrum);
                        }
                    }
                }
            }
        }
    }
    let [pfa_stack, pfa_rigid] = pfa;
    let [psa_stack, psa_rigid] = psa;
    ZoneFloors {
        name: names.name,
        target: names.target,
        pga_g: names.pga_g,
        motions: names.motions,
        pfa_stack,
        pfa_rigid,
        psa_stack,
        psa_rigid,
    }
}

/// Zone `zone` of `floors.h5` (the caller has required it up to date), refused unless its axes
/// are the ones the config's `floor_spectra:` section gives.
pub fn read_zone(study: &Study, zone: &str) -> Result<(FloorsAxes, ZoneFloors), PipelineError> {
    let path = study.path(StageId::Floors.output());
    let (axes, z) = read_zone_floors(&path, zone, study.building().is_some())?;
    if axes != axes_of(study)? {
        let why =
            format!("zone_{zone}: its axes differ from the config's `floor_spectra:` section");
        return Err(StoreError::corrupt(&path, why).into());
    }
    Ok((axes, z))
}

/// One floor of one case on one building of a zone: the measured amplifications, means over
/// the zone's motions, beside the code's (docs/model.md, "Floor response spectra", "In a study").
#[derive(Debug, Clone, PartialEq)]
pub struct FloorRow {
    pub zone: String,
    /// 1-based, as `floor_spectra.cases` lists them.
    pub case: usize,
    /// The building (`3 storeys, stack on the roof`); `None` on one storey.
    pub frame: Option<String>,
    pub floor: usize,
    /// The floor's height over the roof's.
    pub z_over_h: f64,
    /// `PFA/PGA`, the mean over the motions of each motion's ratio: stacks sliding, attached.
    pub pfa_ratio_stack: f64,
    pub pfa_ratio_rigid: f64,
    /// ASCE 7-16's `1 + 2z/h` and ASCE 7-22's `H_f` at `T_a` = the case's `T_1`.
    pub asce7_16: f64,
    pub asce7_22: f64,
    /// The largest of the mean floor spectrum (the first damping ratio) over the mean PFA:
    /// stacks sliding, attached.
    pub psa_peak_ratio_stack: f64,
    pub psa_peak_ratio_rigid: f64,
}

/// One zone of `floors.h5` with what reading it takes: its axes and offsets, and the study's
/// frames to show (each distinct building once; on one storey the structure), with their
/// stored index.
struct Shown {
    axes: FloorsAxes,
    zone: ZoneFloors,
    offsets: Offsets,
    frames: Vec<(usize, Option<Frame>)>,
}

impl Shown {
    fn read(study: &Study, zone: &str) -> Result<Self, PipelineError> {
        let (axes, zone) = read_zone(study, zone)?;
        let all = study.frames();
        let offsets = Offsets::of(&axes, all.len());
        let distinct: Vec<usize> = study.distinct_frames().iter().map(|(f, _)| *f).collect();
        let frames = (all.into_iter().enumerate())
            .filter(|(f, frame)| frame.is_none() || distinct.contains(f))
            .collect();
        Ok(Self {
            axes,
            zone,
            offsets,
            frames,
        })
    }

    fn motions(&self) -> usize {
        self.zone.motions.len()
    }

    /// The mean over the motions of `values(m)`.
    fn mean(&self, values: impl Fn(usize) -> f64) -> f64 {
        (0..self.motions()).map(values).sum::<f64>() / self.motions() as f64
    }

    /// The mean over the motions of floor `j`'s spectrum (case `c`, frame `f`, the first
    /// damping ratio) in `psa`.
    fn mean_spectrum(&self, psa: &ArrayD<f64>, c: usize, f: usize, j: usize) -> Vec<f64> {
        let s = psa.as_slice().expect("standard layout");
        (0..self.offsets.periods)
            .map(|p| self.mean(|m| s[self.offsets.psa(m, c, f, 0, j) + p]))
            .collect()
    }

    /// Floor `j`'s peak (case `c`, frame `f`) under motion `m` in `pfa`.
    fn pfa(&self, pfa: &ArrayD<f64>, m: usize, c: usize, f: usize, j: usize) -> f64 {
        pfa.as_slice().expect("standard layout")[self.offsets.pfa(m, c, f, j)]
    }
}

/// Every floor of every case on every distinct building of every zone, from `floors.h5`.
pub fn amplification_table(study: &Study) -> Result<Vec<FloorRow>, PipelineError> {
    use crate::study::floors::{asce7_16_height_factor, asce7_22_h_f};
    study.require(StageId::Floors)?;
    let mut rows = Vec::new();
    for zone in &study.cfg.zones {
        let v = Shown::read(study, &zone.name)?;
        let z = &v.zone;
        for c in 0..v.offsets.cases {
            for (f, frame) in &v.frames {
                let f = *f;
                let floors = frame.as_ref().map_or(1, Frame::storeys);
                for j in 0..floors {
                    // One storey: the structure is the roof.
                    let z_over_h = frame.as_ref().map_or(1.0, |fr| fr.height_ratio(j + 1));
                    let ratio = |pfa: &ArrayD<f64>| v.mean(|m| v.pfa(pfa, m, c, f, j) / z.pga_g[m]);
                    let peak = |psa: &ArrayD<f64>, pfa: &ArrayD<f64>| {
                        let spectrum = v.mean_spectrum(psa, c, f, j);
                        spectrum.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                            / v.mean(|m| v.pfa(pfa, m, c, f, j))
                    };
                    rows.push(FloorRow {
                        zone: zone.name.clone(),
                        case: c + 1,
                        frame: frame.as_ref().map(|fr| fr.to_string()),
                        floor: j + 1,
                        z_over_h,
                        pfa_ratio_stack: ratio(&z.pfa_stack),
                        pfa_ratio_rigid: ratio(&z.pfa_rigid),
                        asce7_16: asce7_16_height_factor(z_over_h),
                        asce7_22: asce7_22_h_f(z_over_h, v.axes.case_period_s[c]),
                        psa_peak_ratio_stack: peak(&z.psa_stack, &z.pfa_stack),
                        psa_peak_ratio_rigid: peak(&z.psa_rigid, &z.pfa_rigid),
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// A step line's corners: periods, s, and ordinates, g.
type Corners = (Vec<f64>, Vec<f64>);

/// A code's floor spectrum drawn as a step over the periods `periods_s` span (its corners):
/// `floor_g` for a rigid component (period at most 0.06 s), `resonant` times it for a flexible
/// one.
fn code_floor_spectrum(floor_g: f64, resonant: f64, periods_s: &[f64]) -> Corners {
    use crate::study::floors::RIGID_COMPONENT_PERIOD_S;
    let (lo, hi) = (periods_s[0], periods_s[periods_s.len() - 1]);
    let knee = RIGID_COMPONENT_PERIOD_S.clamp(lo, hi);
    (
        vec![lo, knee, knee, hi],
        vec![floor_g, floor_g, resonant * floor_g, resonant * floor_g],
    )
}

/// The codes' floor spectra at height `z/h` of a building whose `T_a` is `t_a_s`, with
/// `0.4·S_DS` the motions' mean PGA (g) and the component's `I_p = 1`: ASCE 7-16 Eq. 13.3-1
/// with `R_p = 1`, `(1 + 2z/h)·PGA` times `a_p` (1, then 2.5); ASCE 7-22 Eq. 13.3-1 with
/// `R_po = 1`, `H_f·PGA/R_μ` times `C_AR` (1, then 2.2), `R_μ` an elastic frame's (1.3).
fn code_floor_spectra(
    z_over_h: f64,
    t_a_s: f64,
    pga_g: f64,
    periods_s: &[f64],
) -> [(&'static str, Corners); 2] {
    use crate::study::floors::{
        ASCE7_22_C_AR_RESONANT, asce7_16_height_factor, asce7_22_h_f, asce7_22_r_mu,
    };
    let elastic_r_mu = asce7_22_r_mu(1.0, 1.0, 1.0);
    [
        (
            "ASCE 7-16",
            code_floor_spectrum(asce7_16_height_factor(z_over_h) * pga_g, 2.5, periods_s),
        ),
        (
            "ASCE 7-22",
            code_floor_spectrum(
                asce7_22_h_f(z_over_h, t_a_s) * pga_g / elastic_r_mu,
                ASCE7_22_C_AR_RESONANT,
                periods_s,
            ),
        ),
    ]
}

/// The report's figure: per zone and distinct building, the first case's mean floor spectra
/// (the first damping ratio) of the roof and, from three storeys, the middle floor, stacks
/// sliding (solid) and attached (dashed), and ASCE 7-16's and ASCE 7-22's floor spectra there
/// (dotted).
pub fn figure_of(study: &Study) -> Result<crate::render::chart::Figure, PipelineError> {
    use crate::render::chart::{Axis, Figure, Panel, Series, Stroke};
    study.require(StageId::Floors)?;
    let (mut panels, mut title) = (Vec::new(), None);
    for zone in &study.cfg.zones {
        let v = Shown::read(study, &zone.name)?;
        let a = &v.axes;
        for (f, frame) in &v.frames {
            let floors = frame.as_ref().map_or(1, Frame::storeys);
            let mut shown = vec![floors];
            if floors >= 3 {
                shown.insert(0, floors.div_ceil(2));
            }
            let mut series = Vec::new();
            for &j in &shown {
                let place = if j == floors {
                    "roof".to_string()
                } else {
                    format!("floor {j}")
                };
                for (name, psa, dashed) in [
                    ("sliding", &v.zone.psa_stack, false),
                    ("attached", &v.zone.psa_rigid, true),
                ] {
                    let mean = v.mean_spectrum(psa, 0, *f, j - 1);
                    let line = Series::line(format!("{place}, {name}"), a.periods_s.clone(), mean);
                    series.push(if dashed {
                        line.stroke(Stroke::Dashed, 2)
                    } else {
                        line
                    });
                }
                let z_over_h = frame.as_ref().map_or(1.0, |fr| fr.height_ratio(j));
                let pga_g = v.mean(|m| v.zone.pga_g[m]);
                for (code, (x, y)) in
                    code_floor_spectra(z_over_h, a.case_period_s[0], pga_g, &a.periods_s)
                {
                    series.push(
                        Series::line(format!("{place}, {code}"), x, y).stroke(Stroke::Dotted, 2),
                    );
                }
            }
            let at = frame.as_ref().map_or(String::new(), |fr| format!(", {fr}"));
            // The case is every panel's: the figure's title names it.
            title.get_or_insert_with(|| {
                format!(
                    "Floor response spectra: T_p = {} s, α = {:?}, μ = {:?}, ζ = {}",
                    a.case_period_s[0], a.case_alpha[0], a.case_mu[0], a.damping[0]
                )
            });
            panels.push(Panel::xy(
                format!("zone {}{at}", zone.name),
                Axis::new("oscillator period (s)"),
                Axis::new("mean floor PSA (g)"),
                series,
            ));
        }
    }
    let title = title.unwrap_or_else(|| "Floor response spectra".into());
    Ok(Figure::grid(title, panels, 2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The codes' lines by hand at the roof of a building with `T_a = 1 s` under a PGA of
    /// 0.2 g: ASCE 7-16 `3·0.2 = 0.6` g, then `2.5·0.6 = 1.5` g; ASCE 7-22
    /// `H_f = 1 + 1 + 0.84 = 2.84`, `2.84·0.2/1.3 = 0.43692…` g, then `2.2` times it; the step
    /// at 0.06 s, the ends at the periods' ends.
    #[test]
    fn the_codes_floor_spectra_by_hand_at_a_roof() {
        let [(c16, (x16, y16)), (c22, (x22, y22))] =
            code_floor_spectra(1.0, 1.0, 0.2, &[0.05, 4.0]);
        assert_eq!((c16, c22), ("ASCE 7-16", "ASCE 7-22"));
        assert_eq!(x16, [0.05, 0.06, 0.06, 4.0]);
        assert_eq!(x22, x16);
        let close = |a: &[f64], b: [f64; 4]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-12);
        assert!(close(&y16, [0.6, 0.6, 1.5, 1.5]), "{y16:?}");
        let rigid = 2.84 * 0.2 / 1.3;
        assert!(
            close(&y22, [rigid, rigid, 2.2 * rigid, 2.2 * rigid]),
            "{y22:?}"
        );
    }
}
