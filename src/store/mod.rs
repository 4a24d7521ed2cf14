//! Writing results to files: time histories as HDF5 or CSV.

pub mod history;

pub use history::{HistoryFormat, StoreError, write_history};
