//! slidestack-verify: the evidence that slidestack is fast and accurate, kept apart from the
//! product. Nothing here is needed to run a study.
//!
//! * [`stress`]: the numerical stress suite: extreme but legal cases and their checks
//!   (`docs/stress.md`).
//! * [`accuracy`]: work-precision measures (errors against a reference, observed orders).
//! * [`work_precision`]: the work-precision comparison of the exact integrator, the paper's RK4
//!   and OpenSees on real records (`docs/evidence/accuracy.*`).
//! * [`timing`]: CPU time of the running thread, batched medians, the machine's description.

pub mod accuracy;
pub mod stress;
pub mod timing;
pub mod work_precision;
