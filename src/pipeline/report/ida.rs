//! The report's IDA section (with an `ida:` section): the first case's curves, every fragility
//! fit and the median ductility of the stack against the rigidly attached load, from `ida.h5`
//! through [`crate::pipeline::files::ida_zone`]. In a building study the same per frame (`storeys`,
//! `stack_floor`), the curves and medians in the peak interstorey drift ratio. The tables are
//! also what `slidestack ida` prints.

use super::{Files, PipelineError, ReportError};
use crate::ida::fragility::FIT_STATUS_FLAGS;
use crate::pipeline::files::{self, ida_zone};
use crate::pipeline::{StageId, Study};
use crate::render::page::{Section, para, table_with_id};
use crate::study::ida::DemandLayout;
use crate::study::ida_zone::FRACTILES;

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
    let distinct: Vec<String> = (study.shape.distinct().iter())
        .map(|(_, f)| f.to_string())
        .collect();
    let shown = |frame: &Option<String>| frame.as_ref().is_none_or(|f| distinct.contains(f));
    let rows = fragility_rows(study, &shown)?;
    let medians = median_rows(study, &shown)?;
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

/// The fragility table's rows of the frames `shown` (every row on one storey).
fn fragility_rows(
    study: &Study,
    shown: &dyn Fn(&Option<String>) -> bool,
) -> Result<Vec<Vec<String>>, PipelineError> {
    Ok(fragility_table(study)?
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
        .collect())
}

/// The median demands' rows of the frames `shown` (a building's drift ratios to 4 decimals).
fn median_rows(
    study: &Study,
    shown: &dyn Fn(&Option<String>) -> bool,
) -> Result<Vec<Vec<String>>, PipelineError> {
    let building = study.building().is_some();
    Ok(median_demand(study)?
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
        .collect())
}

/// One row of the fragility table.
#[derive(Debug, Clone, PartialEq)]
pub struct FragilityRow {
    pub zone: String,
    pub case: usize,
    /// The frame of a building study (`3 storeys, stack on the roof`).
    pub frame: Option<String>,
    pub system: String,
    pub limit_state: String,
    pub theta_sa_g: f64,
    pub theta_ci_sa_g: (f64, f64),
    pub beta: f64,
    pub beta_ci: (f64, f64),
    /// The fit's status word.
    pub status: &'static str,
}

/// Every fit of `ida.h5` (which must be up to date), zone, case, system, limit state in order.
pub fn fragility_table(study: &Study) -> Result<Vec<FragilityRow>, PipelineError> {
    study.require(StageId::Ida)?;
    let mut rows = Vec::new();
    for zone in &study.cfg.zones {
        let (axes, z) = ida_zone(study, &zone.name)?;
        let v = &z.vars;
        let labels = frame_labels(study);
        let nf = labels.len();
        for c in 0..axes.case_period_s.len() * nf {
            for (s, system) in axes.systems.iter().enumerate() {
                for (l, limit) in axes.limit_states.iter().enumerate() {
                    let at = [s, c, l];
                    let code = v.fit_status[at];
                    rows.push(FragilityRow {
                        zone: zone.name.clone(),
                        case: c / nf,
                        frame: labels[c % nf].clone(),
                        system: system.clone(),
                        limit_state: limit.clone(),
                        theta_sa_g: v.theta_sa_g[at],
                        theta_ci_sa_g: (v.theta_ci_low_sa_g[at], v.theta_ci_high_sa_g[at]),
                        beta: v.beta[at],
                        beta_ci: (v.beta_ci_low[at], v.beta_ci_high[at]),
                        status: FIT_STATUS_FLAGS
                            .iter()
                            .find(|f| f.0 == code)
                            .map_or("unknown", |f| f.1),
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// The frames' labels in stored order (`[None]` on one storey).
fn frame_labels(study: &Study) -> Vec<Option<String>> {
    (0..study.frames().len())
        .map(|f| study.shape.label(f))
        .collect()
}

/// The median primary demand (ductility on one storey, the peak interstorey drift ratio in a
/// building) of the stack and of the rigidly attached load at one intensity.
#[derive(Debug, Clone, PartialEq)]
pub struct MedianDemand {
    pub zone: String,
    pub case: usize,
    /// The frame of a building study (`3 storeys, stack on the roof`).
    pub frame: Option<String>,
    /// The demand compared: `ductility` or `peak_drift_ratio`.
    pub demand: String,
    pub period_s: f64,
    pub alpha: Vec<f64>,
    pub mu: Vec<f64>,
    /// The intensity is `factor × target_sa_g`.
    pub factor: f64,
    /// The zone's target `Sa(T_p)` (`Sa(T_1)` in a building), g: the level the motions are
    /// matched to.
    pub target_sa_g: f64,
    pub stack: f64,
    pub rigid: f64,
    /// The stack's largest peak slip at any interface in any run of the case, m.
    pub stack_max_slip_m: f64,
}

/// Multiples of the zone's target at which [`median_demand`] compares the systems.
pub const TARGET_FACTORS: [f64; 3] = [0.5, 1.0, 2.0];

/// `y` on the grid `x` at `at`, linearly (`+∞` where either neighbour is; NaN outside).
fn interpolate(x: &[f64], y: &[f64], at: f64) -> f64 {
    let j = x.partition_point(|&v| v < at);
    if j == x.len() {
        return f64::NAN;
    }
    if x[j] == at || j == 0 {
        return if x[j] == at { y[j] } else { f64::NAN };
    }
    let w = (at - x[j - 1]) / (x[j] - x[j - 1]);
    if y[j - 1].is_infinite() || y[j].is_infinite() {
        return f64::INFINITY;
    }
    y[j - 1] + w * (y[j] - y[j - 1])
}

/// The median ductility of both systems at [`TARGET_FACTORS`] × the zone's target `Sa(T_p)`,
/// read off the median curves of `ida.h5` (NaN above the grid).
pub fn median_demand(study: &Study) -> Result<Vec<MedianDemand>, PipelineError> {
    study.require(StageId::Motions)?;
    study.require(StageId::Ida)?;
    let targets = files::targets(study)?;
    let mut rows = Vec::new();
    let labels = frame_labels(study);
    let nf = labels.len();
    for (zone, target) in study.cfg.zones.iter().zip(&targets) {
        let (axes, z) = ida_zone(study, &zone.name)?;
        let median = FRACTILES.iter().position(|&p| p == 0.5).unwrap_or(1);
        for cf in 0..axes.case_period_s.len() * nf {
            let c = cf / nf;
            let curve = |s: usize| -> Vec<f64> {
                (0..axes.sa_grid_g.len())
                    .map(|j| z.vars.fractile_curve[[s, cf, median, j, DemandLayout::PRIMARY]])
                    .collect()
            };
            let (stack, rigid) = (curve(0), curve(1));
            let target_sa_g = target.sa_g(axes.case_period_s[c]);
            let n = axes.case_alpha[c].len();
            let slip = DemandLayout {
                building: axes.building.is_some(),
                blocks: n,
            }
            .first_slip();
            let stack_max_slip_m = z
                .vars
                .run_demand
                .slice(ndarray::s![0, .., cf, .., slip..slip + n])
                .iter()
                .copied()
                .filter(|v| !v.is_nan())
                .fold(0.0, f64::max);
            for factor in TARGET_FACTORS {
                let at = factor * target_sa_g;
                rows.push(MedianDemand {
                    zone: zone.name.clone(),
                    case: c,
                    frame: labels[cf % nf].clone(),
                    demand: axes.demands[DemandLayout::PRIMARY].clone(),
                    period_s: axes.case_period_s[c],
                    alpha: axes.case_alpha[c].clone(),
                    mu: axes.case_mu[c].clone(),
                    factor,
                    target_sa_g,
                    stack: interpolate(&axes.sa_grid_g, &stack, at),
                    rigid: interpolate(&axes.sa_grid_g, &rigid, at),
                    stack_max_slip_m,
                });
            }
        }
    }
    Ok(rows)
}

/// SVG of [`figure_of`].
pub fn figure(study: &Study) -> Result<String, PipelineError> {
    let fig = figure_of(study)?;
    crate::render::chart::render(&fig).map_err(|e| {
        let path = study.path(StageId::Ida.output());
        PipelineError::Store(crate::store::StoreError::corrupt(&path, e.to_string()))
    })
}

/// The first case's ductility (in a building: peak interstorey drift ratio) against intensity,
/// one panel per zone (and frame): every record's curve (faint) and the 16–50–84 % fractiles
/// of the stack and of the rigidly attached load. Collapsed values (`+∞`) are drawn at the
/// collapse ductility (drift ratio).
pub fn figure_of(study: &Study) -> Result<crate::render::chart::Figure, PipelineError> {
    use crate::render::chart::{Axis, Figure, Panel, Series, Stroke};
    study.require(StageId::Ida)?;
    let cfg = study.ida_config()?;
    let building = study.building().is_some();
    let (cap, y_label) = if building {
        let cap = cfg.collapse_drift_ratio.unwrap_or(f64::NAN);
        (cap, "peak interstorey drift ratio")
    } else {
        let cap = cfg.collapse_ductility.unwrap_or(f64::NAN);
        (cap, "ductility u_m/u_y")
    };
    let clip = |v: f64| if v.is_infinite() { cap } else { v };
    let labels = frame_labels(study);
    // Each building once (on one storey every stack floor is the first's).
    let distinct: Vec<usize> = study.shape.distinct().iter().map(|(f, _)| *f).collect();
    let d = DemandLayout::PRIMARY;
    let mut panels = Vec::new();
    for zone in &study.cfg.zones {
        let (axes, z) = ida_zone(study, &zone.name)?;
        let x = axes.sa_grid_g.clone();
        // The first case in every frame: folded index `f` (crate::store::ida).
        for (f, label) in labels.iter().enumerate() {
            if !distinct.contains(&f) {
                continue;
            }
            let mut series = Vec::new();
            for s in 0..axes.systems.len() {
                for r in 0..z.records.len() {
                    let y: Vec<f64> = (0..x.len())
                        .map(|j| clip(z.vars.curve[[s, r, f, j, d]]))
                        .collect();
                    series.push(Series::faint(x.clone(), y));
                }
            }
            for (s, name) in axes.systems.iter().enumerate() {
                let q = |k: usize| -> Vec<f64> {
                    (0..x.len())
                        .map(|j| clip(z.vars.fractile_curve[[s, f, k, j, d]]))
                        .collect()
                };
                series.push(Series::band(
                    format!("{name}: 16–84 %"),
                    x.clone(),
                    q(0),
                    q(2),
                ));
                let line = Series::line(format!("{name}: median"), x.clone(), q(1));
                series.push(if s == 0 {
                    line
                } else {
                    line.stroke(Stroke::Dashed, 2)
                });
            }
            let a = &axes;
            let at = label.as_ref().map_or(String::new(), |l| format!(", {l}"));
            panels.push(Panel::xy(
                format!(
                    "zone {}{at}: T_p = {} s, α = {:?}, μ = {:?}, C_y = {:.3}",
                    zone.name,
                    a.case_period_s[0],
                    a.case_alpha[0],
                    a.case_mu[0],
                    z.c_y[[0]]
                ),
                Axis::new("Sa(T_p, 5 %), g"),
                Axis::new(y_label).range(0.0, cap),
                series,
            ));
        }
    }
    Ok(Figure::grid(
        "IDA curves: sliding stack vs rigidly attached load",
        panels,
        labels.len().min(3),
    ))
}
