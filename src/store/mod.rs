//! Writing and reading result files: time histories (HDF5 or CSV), the stage files, input
//! fingerprints.
//!
//! * [`history`]: one simulation's time history.
//! * [`motions`]: `motions.h5`, the ground-motion stage.
//! * [`sweep`]: the sweep's unit files and `sweep.h5`.
//! * [`tnew`]: the T_new stage file, `tnew.h5`.
//! * [`fingerprint`]: SHA-256 of inputs, for up-to-date checks.
//! * [`h5`]: small HDF5 helpers.

pub mod fingerprint;
pub mod h5;
pub mod history;
pub mod motions;
pub mod sweep;
pub mod tnew;

pub use history::{HistoryFormat, StoreError, write_history};
