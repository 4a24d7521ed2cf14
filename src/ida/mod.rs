//! Incremental dynamic analysis kernels (docs/model.md, "Incremental dynamic analysis"): plain
//! functions free of I/O and configuration, each tested against its own oracle.
//!
//! * [`trace`]: hunt & fill tracing of one record's IDA curve (Vamvatsikos & Cornell 2002);
//! * [`curve`]: a traced curve on a common intensity grid, and fractiles over records;
//! * [`fragility`]: lognormal fragility functions fitted by maximum likelihood to
//!   multiple-stripe data (Baker 2015), with Wald confidence intervals.

pub mod curve;
pub mod fragility;
pub mod trace;
