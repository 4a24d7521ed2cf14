//! The parametric study: its configuration and the stages that compose the numerical kernels.
//!
//! * [`config`]: the study file (YAML), validated before any work.
//! * [`motions`]: the first stage: seeds, spectral matching per zone, the set checks.
//! * [`sweep`]: the grid of cases, the skip rules, one work unit.
//! * [`tnew`]: `T_new` from the mean displacement spectrum.

pub mod config;
pub mod motions;
pub mod sweep;
pub mod tnew;
