//! Many cases under many records in one call (the Python module's `simulate_many`): every case
//! and record checked before any run, then the runs (each case under each record) spread over a
//! thread pool. Each run is the one [`Simulation::run_watched`] makes of that case alone, so the
//! numbers are those of one `simulate` per case, whatever the thread count or order.

use super::{Model, Outcome, Settings, Simulation, SimulationError, check_peak};
use crate::dynamics::Watch;
use crate::ground_motion::Record;
use rayon::prelude::*;

/// Checked cases and the records they run under.
#[derive(Debug)]
pub struct Batch {
    /// Each case, resolved under the first record.
    cases: Vec<Simulation>,
    records: Vec<Record>,
}

/// What a batch gives: `outcomes[case][record]`, and the integrator's warnings of all runs,
/// each distinct one once.
#[derive(Debug)]
pub struct BatchOutcome {
    pub outcomes: Vec<Vec<Outcome>>,
    pub warnings: Vec<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    #[error("no case to run: give at least one")]
    NoCase,
    #[error("no record to run under: give at least one")]
    NoRecord,
    /// A case that fails its checks, by index (0 the first).
    #[error("case {case}: {source}")]
    Case {
        case: usize,
        #[source]
        source: Box<SimulationError>,
    },
    #[error(
        "case {case} is a {kind} case and case 0 a {first} one: one call takes cases of one kind"
    )]
    Mixed {
        case: usize,
        kind: &'static str,
        first: &'static str,
    },
    /// A run that failed (the first by case, then record).
    #[error("case {case} under {record}: {source}")]
    Run {
        case: usize,
        record: String,
        #[source]
        source: Box<SimulationError>,
    },
    /// The watch stopped the runs (Ctrl-C).
    #[error("stopped (interrupted) with {done} of {runs} runs done")]
    Stopped { done: usize, runs: usize },
    #[error("could not start a pool of {threads} threads: {why}")]
    Pool { threads: usize, why: String },
}

fn kind(model: &Model) -> &'static str {
    match model {
        Model::OneStorey { .. } => "one-storey",
        Model::Building { .. } => "building",
    }
}

impl Batch {
    /// Every case checked (as [`Settings::resolve`] checks it) under every record, all of one
    /// kind (one storey or building), before any run.
    pub fn new(cases: Vec<Settings>, records: Vec<Record>) -> Result<Batch, BatchError> {
        let first_record = records.first().ok_or(BatchError::NoRecord)?;
        if cases.is_empty() {
            return Err(BatchError::NoCase);
        }
        let cases = (cases.into_iter().enumerate())
            .map(|(case, settings)| {
                let sim =
                    settings
                        .resolve_with(first_record.clone())
                        .map_err(|e| BatchError::Case {
                            case,
                            source: Box::new(e),
                        })?;
                for r in &records[1..] {
                    check_peak(&r.name, r, sim.scale).map_err(|m| BatchError::Case {
                        case,
                        source: Box::new(SimulationError::Invalid(m)),
                    })?;
                }
                Ok(sim)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let first = kind(&cases[0].model);
        if let Some(case) = cases.iter().position(|c| kind(&c.model) != first) {
            return Err(BatchError::Mixed {
                case,
                kind: kind(&cases[case].model),
                first,
            });
        }
        Ok(Batch { cases, records })
    }

    /// Runs in all: cases times records.
    pub fn runs(&self) -> usize {
        self.cases.len() * self.records.len()
    }

    /// Runs every case under every record on `threads` threads (`None`: rayon's global pool),
    /// each under `watch`; the first failure (by case, then record) is the error.
    pub fn run(
        &self,
        threads: Option<usize>,
        watch: &dyn Watch,
    ) -> Result<BatchOutcome, BatchError> {
        let runs = self.runs();
        let n_records = self.records.len();
        let one = |k: usize| {
            let (case, record) = (k / n_records, k % n_records);
            let sim = &self.cases[case];
            let sim = match record {
                0 => None,
                _ => Some(sim.with_record(self.records[record].clone())),
            }
            .transpose()?;
            let sim = sim.as_ref().unwrap_or(&self.cases[case]);
            let accel = sim.accel_mps2();
            let warnings = sim.warnings(&accel);
            let (outcome, _) = sim.run_watched(&accel, false, watch)?;
            Ok::<_, SimulationError>((outcome, warnings))
        };
        let all: Vec<_> = match threads {
            None => (0..runs).into_par_iter().map(one).collect(),
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| BatchError::Pool {
                    threads: n,
                    why: e.to_string(),
                })?
                .install(|| (0..runs).into_par_iter().map(one).collect()),
        };
        let stopped = |e: &SimulationError| {
            matches!(
                e,
                SimulationError::Simulation {
                    source: crate::dynamics::SimError::Stopped { .. },
                    ..
                }
            )
        };
        if all.iter().any(|r| r.as_ref().is_err_and(stopped)) {
            let done = all.iter().filter(|r| r.is_ok()).count();
            return Err(BatchError::Stopped { done, runs });
        }
        let mut outcomes = Vec::with_capacity(self.cases.len());
        let mut warnings = Warnings::default();
        for (k, r) in all.into_iter().enumerate() {
            let (case, record) = (k / n_records, k % n_records);
            let (outcome, said) = r.map_err(|e| BatchError::Run {
                case,
                record: self.records[record].name.clone(),
                source: Box::new(e),
            })?;
            if record == 0 {
                outcomes.push(Vec::with_capacity(n_records));
            }
            outcomes[case].push(outcome);
            for w in said {
                warnings.add(w, case, &self.records[record].name);
            }
        }
        Ok(BatchOutcome {
            outcomes,
            warnings: warnings.said(runs),
        })
    }
}

/// Each distinct warning once, with the first run that gave it and how many did.
#[derive(Default)]
struct Warnings(Vec<(String, usize, String, usize)>);

impl Warnings {
    fn add(&mut self, text: String, case: usize, record: &str) {
        match self.0.iter_mut().find(|(t, ..)| *t == text) {
            Some((.., n)) => *n += 1,
            None => self.0.push((text, case, record.to_string(), 1)),
        }
    }

    fn said(self, runs: usize) -> Vec<String> {
        (self.0.into_iter())
            .map(|(text, case, record, n)| {
                format!("{text} (case {case} under {record}; {n} of the {runs} runs)")
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::Unwatched;
    use crate::ground_motion;

    fn case(yaml: &str) -> Settings {
        serde_yaml::from_str(yaml).unwrap()
    }

    fn json(o: &Outcome) -> String {
        serde_json::to_string(o).unwrap()
    }

    /// Each run equals the case run alone (`resolve` then `run`), to the byte of its JSON, on
    /// one thread and on three.
    #[test]
    fn each_run_is_the_case_run_alone() {
        let cases = [
            "period: 1.0\nalpha: [0.5, 0.5]\nmu: [0.2, 0.1]",
            "period: 0.4\nmu: [0.05, 0.3]",
        ];
        let short = Record::from_samples(
            "short",
            0.02,
            (0..300).map(|k| 0.3 * (0.05 * k as f64).sin()).collect(),
        )
        .unwrap();
        let records = vec![ground_motion::builtin(), short];
        let batch = Batch::new(cases.iter().map(|c| case(c)).collect(), records.clone()).unwrap();
        assert_eq!(batch.runs(), 4);
        for threads in [Some(1), Some(3)] {
            let ran = batch.run(threads, &Unwatched).unwrap();
            for (i, c) in cases.iter().enumerate() {
                for (j, r) in records.iter().enumerate() {
                    let alone = case(c).resolve_with(r.clone()).unwrap();
                    let (o, _) = alone.run(&alone.accel_mps2()).unwrap();
                    assert_eq!(json(&ran.outcomes[i][j]), json(&o), "case {i} record {j}");
                }
            }
        }
    }

    #[test]
    fn a_bad_case_is_named_by_its_index_before_any_run() {
        let cases = vec![case("period: 1.0"), case("period: -1.0")];
        let e = Batch::new(cases, vec![ground_motion::builtin()]).unwrap_err();
        assert!(matches!(e, BatchError::Case { case: 1, .. }), "{e}");
        assert!(e.to_string().starts_with("case 1: "), "{e}");
    }

    #[test]
    fn one_storey_and_building_cases_do_not_mix() {
        let cases = vec![
            case("period: 1.0"),
            case("building: {storeys: 2, period: 0.5}"),
        ];
        let e = Batch::new(cases, vec![ground_motion::builtin()]).unwrap_err();
        assert!(matches!(e, BatchError::Mixed { case: 1, .. }), "{e}");
    }

    /// A watch that stops every run: the batch says how many runs were done (none).
    #[test]
    fn a_stopped_watch_stops_the_batch() {
        struct Stop;
        impl Watch for Stop {
            fn going_on(&self, _: usize, _: usize) -> bool {
                false
            }
        }
        let batch = Batch::new(vec![case("period: 1.0")], vec![ground_motion::builtin()]).unwrap();
        let e = batch.run(Some(1), &Stop).unwrap_err();
        assert!(matches!(e, BatchError::Stopped { done: 0, runs: 1 }), "{e}");
    }
}
