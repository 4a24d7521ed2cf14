//! The report's IDA section (with an `ida:` section): the first case's curves, every fragility
//! fit and the median ductility of the stack against the rigidly attached load, from `ida.h5`
//! through [`crate::pipeline::ida`].

use super::{Files, PipelineError, ReportError};
use crate::pipeline::Study;
use crate::pipeline::ida::{figure_of, fragility_table, median_ductility};
use crate::render::page::{Section, para, table_with_id};

fn g3(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "–".into()
    }
}

pub(super) fn ida_section(study: &Study, files: &mut Files) -> Result<Section, PipelineError> {
    let fig = files
        .figure(
            "ida.svg",
            &figure_of(study)?,
            "IDA curves of the first case: ductility against Sa(T_p, 5 %), every motion faint, the \
             16–84 % band and median of the sliding stack (solid) and of the rigidly attached \
             load (dashed); collapse drawn at the collapse ductility.",
        )
        .map_err(|e: ReportError| PipelineError::from(e))?;
    let rows: Vec<Vec<String>> = fragility_table(study)?
        .into_iter()
        .map(|r| {
            vec![
                r.zone,
                r.case.to_string(),
                r.system,
                r.limit_state,
                g3(r.theta_sa_g),
                format!("{}–{}", g3(r.theta_ci_sa_g.0), g3(r.theta_ci_sa_g.1)),
                g3(r.beta),
                format!("{}–{}", g3(r.beta_ci.0), g3(r.beta_ci.1)),
                r.status.into(),
            ]
        })
        .collect();
    let medians: Vec<Vec<String>> = median_ductility(study)?
        .into_iter()
        .map(|m| {
            vec![
                m.zone,
                m.case.to_string(),
                format!("{} × {:.3} g", m.factor, m.target_sa_g),
                g3(m.stack),
                g3(m.rigid),
                if m.stack.is_finite() && m.rigid.is_finite() {
                    format!("{:+.1}", 100.0 * (m.stack / m.rigid - 1.0))
                } else {
                    "–".into()
                },
                format!("{:.4}", m.stack_max_slip_m),
            ]
        })
        .collect();
    let body = para(
        "A yielding structure traced by hunt & fill (Vamvatsikos & Cornell 2002) with its stack \
         sliding and with the same load rigidly attached (docs/model.md, \"Incremental dynamic \
         analysis\").",
    ) + &fig
        + &para(
            "Lognormal fragility functions, maximum likelihood on the stripes read off the curves \
             (Baker 2015), 95 % Wald intervals from the observed information:",
        )
        + &table_with_id(
            "ida-fragility",
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
            &rows,
        )
        + &para("Median ductility at multiples of the zone's target Sa(T_p):")
        + &table_with_id(
            "ida-median",
            &[
                "zone",
                "case",
                "Sa",
                "stack",
                "rigid load",
                "stack vs rigid (%)",
                "largest slip (m)",
            ],
            &medians,
        );
    Ok(Section::new(
        "ida",
        "Incremental dynamic analysis of a yielding structure",
        body,
    ))
}
