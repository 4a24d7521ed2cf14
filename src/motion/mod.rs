//! Ground-motion records: readers, the built-in default motion, and built-in stochastic motions
//! ([`stochastic`]).

pub mod record;
pub mod stochastic;

pub use record::{Record, RecordError, read_record};
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
