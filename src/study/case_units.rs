//! The work units of a stage that runs listed cases (the IDA's `ida.cases`, the floors'
//! `floor_spectra.cases`) under every motion of every zone, on every frame of a building study:
//! one unit per (zone, motion, case, frame), in stored order, the frame fastest. A frame that
//! is an earlier one's building (floor 1, the roof and every floor of one storey:
//! [`super::building::first_of_building`]) gives the same numbers to the bit, so only the first
//! of them is run and the others take its results.

use super::building::{Frame, first_of_building};

/// One work unit; indices in stored order (`frame` 0 on one storey).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct CaseUnit {
    pub zone: usize,
    pub motion: usize,
    pub case: usize,
    pub frame: usize,
}

/// Every unit of a stage in stored order, and the ones run.
pub struct UnitPlan {
    pub all: Vec<CaseUnit>,
    pub run: Vec<CaseUnit>,
    /// Per frame, the first frame of its building.
    first: Vec<usize>,
}

impl UnitPlan {
    /// The units of `motions[z]` motions in each zone, `cases` cases and `frames` (one on one
    /// storey).
    pub fn new(motions: &[usize], cases: usize, frames: &[Frame]) -> Self {
        let first = first_of_building(frames);
        let mut all = Vec::new();
        for (zone, &n) in motions.iter().enumerate() {
            for motion in 0..n {
                for case in 0..cases {
                    for frame in 0..frames.len() {
                        all.push(CaseUnit {
                            zone,
                            motion,
                            case,
                            frame,
                        });
                    }
                }
            }
        }
        let run = (all.iter())
            .filter(|u| first[u.frame] == u.frame)
            .copied()
            .collect();
        Self { all, run, first }
    }

    /// The unit run for `u`: `u` itself, or the same unit on the first frame of its building.
    pub fn source(&self, u: CaseUnit) -> CaseUnit {
        CaseUnit {
            frame: self.first[u.frame],
            ..u
        }
    }

    /// Every unit's result in stored order from those of the units run (`results`, in
    /// [`Self::run`]'s order).
    pub fn expand<T: Clone>(&self, results: &[T]) -> Vec<T> {
        let run: std::collections::BTreeMap<_, _> = self.run.iter().zip(results).collect();
        (self.all.iter())
            .map(|&u| run[&self.source(u)].clone())
            .collect()
    }
}
