//! The report's floor response spectra (with a `floor_spectra:` section): the first case's mean
//! spectra of the roof and a middle floor, sliding and attached, and every floor's measured
//! amplifications beside ASCE 7-16's and ASCE 7-22's, from `floors.h5` through
//! [`crate::pipeline::files::floors_zone`].

use super::{Files, PipelineError, ReportError};
use crate::pipeline::StageId;
use crate::pipeline::Study;
use crate::pipeline::files::floors_zone;
use crate::render::page::{Section, para, table_with_id};
use crate::store::floors::{FloorsAxes, Offsets, ZoneFloors};
use crate::study::building::Frame;
use ndarray::ArrayD;

pub(super) fn floors_section(study: &Study, files: &mut Files) -> Result<Section, PipelineError> {
    let building = study.building().is_some();
    let fig = files
        .figure(
            "floors.svg",
            &figure_of(study)?,
            "Mean floor response spectra (pseudo-acceleration of an oscillator standing on the \
             floor, the first damping ratio) of the first case, over the zone's motions: the roof \
             and, with three storeys or more, the middle floor, with the stacks sliding (solid) \
             and rigidly attached (dashed), and the codes' floor spectra at that height \
             (dotted; Eq. 13.3-1 of each with I_p = 1 and the motions' mean PGA for 0.4·S_DS, \
             rigid up to 0.06 s): ASCE 7-16 with R_p = 1, a_p = 1 then 2.5, times 1 + 2z/h; \
             ASCE 7-22 with R_po = 1, C_AR = 1 then 2.2 (a resonant component above grade), \
             times H_f/R_μ, R_μ = 1.3 (an elastic frame: R = Ω_0 = I_e = 1; T_a the case's \
             bare T_1).",
        )
        .map_err(|e: ReportError| PipelineError::from(e))?;
    let f2 = |x: f64| format!("{x:.2}");
    let rows: Vec<Vec<String>> = amplification_table(study)?
        .into_iter()
        .map(|r| {
            let mut row = vec![
                r.zone,
                r.case.to_string(),
                r.floor.to_string(),
                f2(r.z_over_h),
                f2(r.pfa_ratio_stack),
                f2(r.pfa_ratio_rigid),
                f2(r.asce7_16),
                f2(r.asce7_22),
                f2(r.psa_peak_ratio_stack),
                f2(r.psa_peak_ratio_rigid),
            ];
            if let Some(f) = r.frame {
                row.insert(2, f);
            }
            row
        })
        .collect();
    let mut headers = vec![
        "zone",
        "case",
        "floor",
        "z/h",
        "PFA/PGA sliding",
        "PFA/PGA attached",
        "ASCE 7-16 1 + 2z/h",
        "ASCE 7-22 H_f",
        "peak PSA/PFA sliding",
        "peak PSA/PFA attached",
    ];
    if building {
        headers.insert(2, "building");
    }
    let body = para(
        "Each floor's response spectrum is that of its absolute acceleration history, from a run \
         on the motion refined 64 times (docs/model.md, \"Floor response spectra\"). PFA/PGA is \
         the mean over the zone's motions of each motion's peak floor acceleration over its peak \
         ground acceleration; the code's factors are the same ratio as ASCE 7-16 Eq. 13.3-1 \
         (1 + 2z/h) and ASCE 7-22 Eq. 13.3-4 (H_f, with T_a the case's bare first-mode period \
         T_1) give it for an elastic building; peak PSA/PFA is the largest ordinate of the mean \
         floor spectrum over the mean PFA, the component amplification (ASCE 7-16 takes a_p up \
         to 2.5; ASCE 7-22's C_AR, 2.2 for a resonant component above grade). The cases are the config's `floor_spectra.cases`, each on every building.",
    ) + &fig
        + &table_with_id("floor-amplification", &headers, &rows);
    Ok(Section::new("floors", "Floor response spectra", body))
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
    /// Each shown frame's stored index and the frame.
    frames: Vec<(usize, Frame)>,
}

impl Shown {
    fn read(study: &Study, zone: &str) -> Result<Self, PipelineError> {
        let (axes, zone) = floors_zone(study, zone)?;
        let offsets = Offsets::of(&axes, study.frames().len());
        let frames = (study.shape.distinct().into_iter())
            .map(|(f, frame)| (f, frame.clone()))
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
                for j in 0..frame.storeys() {
                    // One storey: the structure is the roof.
                    let z_over_h = frame.height_ratio(j + 1);
                    let ratio = |pfa: &ArrayD<f64>| v.mean(|m| v.pfa(pfa, m, c, f, j) / z.pga_g[m]);
                    let peak = |psa: &ArrayD<f64>, pfa: &ArrayD<f64>| {
                        let spectrum = v.mean_spectrum(psa, c, f, j);
                        spectrum.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                            / v.mean(|m| v.pfa(pfa, m, c, f, j))
                    };
                    rows.push(FloorRow {
                        zone: zone.name.clone(),
                        case: c + 1,
                        frame: study.shape.label(f),
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
            let floors = frame.storeys();
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
                let z_over_h = frame.height_ratio(j);
                let pga_g = v.mean(|m| v.zone.pga_g[m]);
                for (code, (x, y)) in
                    code_floor_spectra(z_over_h, a.case_period_s[0], pga_g, &a.periods_s)
                {
                    series.push(
                        Series::line(format!("{place}, {code}"), x, y).stroke(Stroke::Dotted, 2),
                    );
                }
            }
            let at = study.shape.label_suffix(*f);
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
