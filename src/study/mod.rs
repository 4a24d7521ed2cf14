//! The parametric study: its configuration and the stages that compose the numerical kernels.
//!
//! * [`config`]: the study file (YAML), validated before any work.
//! * [`motions`]: the first stage: seeds, spectral matching per zone, the set checks.

pub mod config;
pub mod motions;
