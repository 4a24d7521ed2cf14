//! The paper's named cases run on the study's motions: the three systems of a case (stack,
//! single block, rigidly attached) under every motion of a zone, through the study's physics.

use super::text::{mean, num, nums};
use super::{ReportError, Zone};
use crate::case::Case;
use crate::dynamics::{ExactOptions, Ground, Response};
use crate::ground_motion::Record;
use crate::study::cases::PaperCase;
use crate::study::physics::{Physics, SystemKind};
use crate::study::tnew::{TnewFlag, t_new};
use rayon::prelude::*;

/// System `kind` of `case` under `rec`, by the study's physics; `history` keeps the time history.
pub(super) fn simulate(
    physics: &Physics,
    kind: SystemKind,
    case: &Case,
    rec: &Record,
    history: bool,
) -> Result<Response, ReportError> {
    let accel = rec.accel_mps2(1.0);
    let ground = Ground::new(rec.dt_s, &accel);
    let opts = ExactOptions {
        history,
        ..ExactOptions::default()
    };
    physics
        .simulate(kind, case, &ground, &opts, None)
        .map_err(|source| ReportError::Case {
            motion: rec.name.clone(),
            source: Box::new(source),
        })
}

/// A named case of the paper, as run on this study's motions.
pub(super) struct CaseRun {
    pub(super) case: Case,
    /// Per motion, the responses of the systems in [`SystemKind::ALL`] order.
    pub(super) runs: Vec<[Response; 3]>,
}

impl CaseRun {
    pub(super) fn new(
        physics: &Physics,
        named: &PaperCase,
        blocks: usize,
        motions: &[Record],
    ) -> Result<Self, ReportError> {
        let case = named.case(blocks);
        let runs = motions
            .par_iter()
            .map(|rec| -> Result<[Response; 3], ReportError> {
                let run = |kind| simulate(physics, kind, &case, rec, false);
                Ok([
                    run(SystemKind::Stack)?,
                    run(SystemKind::SingleBlock)?,
                    run(SystemKind::Rigid)?,
                ])
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { case, runs })
    }

    /// Mean over the motions of the peak structure displacement of system `kind`, m.
    pub(super) fn mean_peak(&self, kind: SystemKind) -> f64 {
        mean(
            self.runs
                .iter()
                .map(|r| r[kind as usize].peak_displacement_m),
        )
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
        let c = &self.case;
        format!(
            "T_p = {} s, α = {}, μ = {}",
            num(c.period_s),
            nums(&c.alpha),
            nums(&c.mu)
        )
    }
}

/// The Section 7.1 case's `T_new` in one zone: the mean peak displacement, `T_rigid`, `T_new`.
pub(super) fn section71_tnew(z: &Zone) -> (f64, f64, f64, TnewFlag) {
    let c = &z.paper().section71;
    let u = c.mean_peak(SystemKind::Stack);
    let tr = c.case.t_rigid_s();
    let (tn, flag) = t_new(&z.tnew.period_sd_s, &z.tnew.sd_mean_m, u, tr, c.slides());
    (u, tr, tn, flag)
}
