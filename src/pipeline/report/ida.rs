//! The report's IDA section (with an `ida:` section): the first case's curves, every fragility
//! fit and the median ductility of the stack against the rigidly attached load, from `ida.h5`
//! through [`crate::pipeline::ida`]. In a building study the same per frame (`storeys`,
//! `stack_floor`), the curves and medians in the peak interstorey drift ratio.

use super::{Files, PipelineError, ReportError};
use crate::pipeline::Study;
use crate::pipeline::ida::{figure_of, fragility_table, median_demand};
use crate::render::page::{Section, para, table_with_id};

fn g3(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "–".into()
    }
}

/// `headers` with `frame` after the first two (zone, case) in a building study.
fn with_frame<'a>(building: bool, headers: &[&'a str]) -> Vec<&'a str> {
    let mut h = headers.to_vec();
    if building {
        h.insert(2, "frame");
    }
    h
}

pub(super) fn ida_section(study: &Study, files: &mut Files) -> Result<Section, PipelineError> {
    let building = study.building().is_some();
    let caption = if building {
        "IDA curves of the first case in every frame: peak interstorey drift ratio against \
         Sa(T_1, 5 %), every motion faint, the 16–84 % band and median of the sliding stack \
         (solid) and of the rigidly attached load (dashed); collapse drawn at the collapse drift \
         ratio."
    } else {
        "IDA curves of the first case: ductility against Sa(T_p, 5 %), every motion faint, the \
         16–84 % band and median of the sliding stack (solid) and of the rigidly attached \
         load (dashed); collapse drawn at the collapse ductility."
    };
    let fig = files
        .figure("ida.svg", &figure_of(study)?, caption)
        .map_err(|e: ReportError| PipelineError::from(e))?;
    // Each building once: on one storey every stack floor is the first's.
    let distinct: Vec<String> = (study.distinct_frames().iter())
        .map(|(_, f)| f.to_string())
        .collect();
    let shown = |frame: &Option<String>| frame.as_ref().is_none_or(|f| distinct.contains(f));
    let rows: Vec<Vec<String>> = fragility_table(study)?
        .into_iter()
        .filter(|r| shown(&r.frame))
        .map(|r| {
            let mut row = vec![
                r.zone,
                r.case.to_string(),
                r.system,
                r.limit_state,
                g3(r.theta_sa_g),
                format!("{}–{}", g3(r.theta_ci_sa_g.0), g3(r.theta_ci_sa_g.1)),
                g3(r.beta),
                format!("{}–{}", g3(r.beta_ci.0), g3(r.beta_ci.1)),
                r.status.into(),
            ];
            if let Some(f) = r.frame {
                row.insert(2, f);
            }
            row
        })
        .collect();
    let medians: Vec<Vec<String>> = median_demand(study)?
        .into_iter()
        .filter(|m| shown(&m.frame))
        .map(|m| {
            let value = |x: f64| {
                if building && x.is_finite() {
                    format!("{x:.4}")
                } else {
                    g3(x)
                }
            };
            let mut row = vec![
                m.zone,
                m.case.to_string(),
                format!("{} × {:.3} g", m.factor, m.target_sa_g),
                value(m.stack),
                value(m.rigid),
                if m.stack.is_finite() && m.rigid.is_finite() {
                    format!("{:+.1}", 100.0 * (m.stack / m.rigid - 1.0))
                } else {
                    "–".into()
                },
                format!("{:.4}", m.stack_max_slip_m),
            ];
            if let Some(f) = m.frame {
                row.insert(2, f);
            }
            row
        })
        .collect();
    let what = if building {
        "A yielding building (storey strengths from the base-shear coefficient by IS 1893 \
         Clause 7.6.3) traced by hunt & fill (Vamvatsikos & Cornell 2002) with its stack \
         sliding and with the same load rigidly attached to its floor (docs/model.md, \
         \"Incremental dynamic analysis\", \"In a building\")."
    } else {
        "A yielding structure traced by hunt & fill (Vamvatsikos & Cornell 2002) with its stack \
         sliding and with the same load rigidly attached (docs/model.md, \"Incremental dynamic \
         analysis\")."
    };
    let median_what = if building {
        "Median peak interstorey drift ratio at multiples of the zone's target Sa(T_1):"
    } else {
        "Median ductility at multiples of the zone's target Sa(T_p):"
    };
    let body = para(what)
        + &fig
        + &para(
            "Lognormal fragility functions, maximum likelihood on the stripes read off the curves \
             (Baker 2015), 95 % Wald intervals from the observed information:",
        )
        + &table_with_id(
            "ida-fragility",
            &with_frame(
                building,
                &[
                    "zone",
                    "case",
                    "system",
                    "limit state",
                    "θ (g)",
                    "95 % CI θ",
                    "β",
                    "95 % CI β",
                    "status",
                ],
            ),
            &rows,
        )
        + &para(median_what)
        + &table_with_id(
            "ida-median",
            &with_frame(
                building,
                &[
                    "zone",
                    "case",
                    "Sa",
                    "stack",
                    "rigid load",
                    "stack vs rigid (%)",
                    "largest slip of any run of the case (m)",
                ],
            ),
            &medians,
        );
    let title = if building {
        "Incremental dynamic analysis of a yielding building"
    } else {
        "Incremental dynamic analysis of a yielding structure"
    };
    Ok(Section::new("ida", title, body))
}
