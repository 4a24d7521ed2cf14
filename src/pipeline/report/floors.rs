//! The report's floor response spectra (with a `floor_spectra:` section): the first case's mean
//! spectra of the roof and a middle floor, sliding and attached, and every floor's measured
//! amplifications beside ASCE 7-16's and ASCE 7-22's, from `floors.h5` through
//! [`crate::pipeline::floors`].

use super::{Files, PipelineError, ReportError};
use crate::pipeline::Study;
use crate::pipeline::floors::{amplification_table, figure_of};
use crate::render::page::{Section, para, table_with_id};

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
