//! The paper's named cases run on the study's motions: the three systems of a case (stack,
//! single block, rigidly attached) under every motion of a zone, through the study's physics.

use super::text::{mean, num, nums};
use super::{ReportError, Zone};
use crate::dynamics::{ExactOptions, Ground, Response, System, SystemSpec};
use crate::motion::Record;
use crate::study::cases::NamedCase;
use crate::study::sweep::Physics;
use crate::study::tnew::{TnewFlag, period_at_displacement};
use rayon::prelude::*;

pub(super) fn simulate(
    rec: &Record,
    spec: &SystemSpec,
    history: bool,
) -> Result<Response, ReportError> {
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

/// The three systems of a case (docs/model.md, "Derived quantities").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum System3 {
    Stack,
    Single,
    Rigid,
}

impl System3 {
    pub(super) const ALL: [System3; 3] = [System3::Stack, System3::Single, System3::Rigid];

    pub(super) fn name(self) -> &'static str {
        match self {
            System3::Stack => "stack",
            System3::Single => "single block",
            System3::Rigid => "rigidly attached",
        }
    }

    pub(super) fn spec(self, physics: &Physics, tp: f64, alpha: &[f64], mu: &[f64]) -> SystemSpec {
        let total: f64 = alpha.iter().sum();
        match self {
            System3::Stack => physics.stack(tp, alpha, mu),
            System3::Single => physics.single(tp, total, mu[0]),
            System3::Rigid => physics.rigid(tp, total),
        }
    }
}

/// A named case of the paper, as run on this study's motions.
pub(super) struct CaseRun {
    pub(super) period_s: f64,
    pub(super) alpha: Vec<f64>,
    pub(super) mu: Vec<f64>,
    /// Per motion: stack, single block, rigid.
    pub(super) runs: Vec<[Response; 3]>,
}

impl CaseRun {
    pub(super) fn new(
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

    pub(super) fn alpha_total(&self) -> f64 {
        self.alpha.iter().sum()
    }

    /// Mean over the motions of the peak structure displacement of system `s`, m.
    pub(super) fn mean_peak(&self, s: System3) -> f64 {
        mean(self.runs.iter().map(|r| r[s as usize].peak_displacement_m))
    }

    pub(super) fn slides(&self) -> bool {
        self.runs
            .iter()
            .any(|r| r[0].peak_slip_m.iter().any(|&x| x > 0.0))
    }

    /// The motion whose stack peak is the median of the motions' (the lower one of an even set).
    pub(super) fn median_motion(&self) -> usize {
        let mut order: Vec<usize> = (0..self.runs.len()).collect();
        order.sort_by(|&a, &b| {
            self.runs[a][0]
                .peak_displacement_m
                .total_cmp(&self.runs[b][0].peak_displacement_m)
        });
        order[(order.len() - 1) / 2]
    }

    pub(super) fn describe(&self) -> String {
        format!(
            "T_p = {} s, α = {}, μ = {}",
            num(self.period_s),
            nums(&self.alpha),
            nums(&self.mu)
        )
    }
}

/// The Section 7.1 case's `T_new` in one zone: the mean peak displacement, `T_rigid`, `T_new`.
pub(super) fn section71_tnew(z: &Zone, physics: &Physics) -> (f64, f64, f64, TnewFlag) {
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
