//! The exact integrator at long periods, measured: a stack that cannot slide (`μ` = 5, so the
//! rigid-SDOF closed form is the reference) over `T_p` 0.01–500 s and `α` 1e-6–100 (`T_rigid`
//! 0.01–5025 s), under a stochastic record at `dt` 0.01 s and 0.0005 s, and under steps every
//! sample (module doc of [`super`], "Limits found, not checked").

use super::cases::{Ref, case};
use super::{Check, GroundMotion, Outcome, Scale, run, sci};
use slidestack::dynamics::{G, SystemSpec};
use std::fmt::Write as _;

/// Structure periods of the survey, s.
const PERIODS_S: [f64; 5] = [0.01, 1.0, 5.0, 20.0, 500.0];
/// Block mass ratios of the survey.
const ALPHAS: [f64; 3] = [1e-6, 1.0, 100.0];

/// One run of the survey.
#[derive(Debug, Clone, PartialEq)]
pub struct SurveyPoint {
    /// Structure period `T_p`, s.
    pub period_s: f64,
    /// Mass ratio of the single block.
    pub alpha: f64,
    /// Which motion (a column of the survey table).
    pub motion: &'static str,
    /// Whether the suite's tolerance rules claim to hold for this motion (they are checked);
    /// `false` for the steps every sample, which are shown, not checked.
    pub checked: bool,
    pub outcome: Outcome,
}

impl SurveyPoint {
    /// `T_rigid = T_p·sqrt(1+α)`, s.
    pub fn period_rigid_s(&self) -> f64 {
        self.period_s * (1.0 + self.alpha).sqrt()
    }

    /// The rigid-SDOF reference's error against its tolerance (NaN if it was not computed).
    pub fn displacement(&self) -> Check {
        match self.outcome.references.first().map(|r| &r.error) {
            Some(Ok(c)) => *c,
            _ => Check::new(f64::NAN, f64::NAN),
        }
    }
}

/// The survey's motions: label, motion, checked.
fn motions() -> [(&'static str, GroundMotion, bool); 3] {
    let stochastic = |dt_s: f64| GroundMotion::Stochastic {
        seed: 101,
        dt_s,
        duration_s: 10.0,
        d595_s: 4.0,
        t_mid_s: 3.0,
        scale: Scale::PgaG(0.5),
    };
    [
        ("stochastic, dt 0.01 s", stochastic(0.01), true),
        ("stochastic, dt 0.0005 s", stochastic(0.0005), true),
        (
            "±0.05 g steps every sample, dt 0.0005 s (not checked)",
            GroundMotion::Square {
                dt_s: 0.0005,
                duration_s: 5.0,
                amplitude_mps2: 0.05 * G,
                half_period_s: 0.0005,
            },
            false,
        ),
    ]
}

/// Runs the survey: every period and mass ratio under every motion, with the suite's rules.
pub fn limit_survey() -> Vec<SurveyPoint> {
    let mut points = Vec::new();
    for period_s in PERIODS_S {
        for alpha in ALPHAS {
            for (label, motion, checked) in motions() {
                let spec = SystemSpec::new(period_s, &[alpha], &[5.0]);
                let c = case("survey", "known limit", spec, motion, &[Ref::Rigid]);
                points.push(SurveyPoint {
                    period_s,
                    alpha,
                    motion: label,
                    checked,
                    outcome: run(&c),
                });
            }
        }
    }
    points
}

/// `value (tolerance)`, the tolerance marked when an unchecked value exceeds it.
fn cell(c: Check, checked: bool) -> String {
    let mark = if !checked && !c.passed() {
        ", exceeded"
    } else {
        ""
    };
    format!("{} ({}{mark})", sci(c.value), sci(c.tolerance))
}

/// The survey as a Markdown table: one row per period and mass ratio, for each motion the energy
/// balance error and the displacement error against the rigid SDOF, each with the suite's
/// tolerance for it.
pub fn survey_markdown(points: &[SurveyPoint]) -> String {
    let labels: Vec<&str> = motions().iter().map(|m| m.0).collect();
    let mut s = String::from("| T_p (s) | α | T_rigid (s) |");
    for l in &labels {
        let _ = write!(s, " {l}: energy (tol) | displacement (tol) |");
    }
    s.push_str("\n|---:|---:|---:|");
    s.push_str(&"---|---|".repeat(labels.len()));
    s.push('\n');
    for row in points.chunks(labels.len()) {
        let p = &row[0];
        let _ = write!(
            s,
            "| {} | {} | {:.3} |",
            p.period_s,
            p.alpha,
            p.period_rigid_s()
        );
        for q in row {
            let _ = write!(
                s,
                " {} | {} |",
                cell(q.outcome.energy, q.checked),
                cell(q.displacement(), q.checked)
            );
        }
        s.push('\n');
    }
    s
}
