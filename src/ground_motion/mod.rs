//! Ground-motion records: readers and writer ([`record`]), processing ([`process`]), spectral
//! matching ([`matching`]) and the matched set ([`set`]), the spectra of several records in
//! parallel ([`spectra`]), built-in stochastic motions ([`stochastic`]) and the built-in
//! default motion.

pub mod matching;
pub mod process;
pub mod record;
pub mod set;
pub mod spectra;
pub mod stochastic;

pub use process::{BaselineCorrection, ProcessError};
pub use record::{
    ReadOptions, Record, RecordError, Units, checked_at2, format_at2, peak_ground_velocity_mps,
    read_record, read_record_with,
};
pub use stochastic::{Envelope, ParameterScatter, StochasticError, StochasticModel};

/// File name of the built-in record (a committed fixture, see `tests/fixtures/records/`).
pub const BUILTIN_NAME: &str = "RSN960_NORTHR_LOS270.AT2";
const BUILTIN_TEXT: &str = include_str!("../../tests/fixtures/records/RSN960_NORTHR_LOS270.AT2");

/// The built-in motion: Northridge 1994, Canyon Country - W Lost Canyon, 270° component, as
/// exported from the FEMA P695 far-field set (PROVENANCE.md beside the file), so the default run
/// needs no download.
pub fn builtin() -> Record {
    record::parse_at2(BUILTIN_TEXT, BUILTIN_NAME).expect("the built-in record is a valid AT2 file")
}
