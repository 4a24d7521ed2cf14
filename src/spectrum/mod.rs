//! Response spectra of records and the target (design) spectra they are compared with.
//!
//! * [`response`]: exact linear response spectra (Nigam–Jennings, peaks between samples included).
//! * [`ductility`]: constant-ductility spectra of yielding oscillators (Chopra, Section 7.5).
//! * [`floor`]: floor response spectra of a structure's floors (the request, the refinement).
//! * [`periods`]: period lists as users write them (`0.05:4:0.01`, `log:…`, lists).
//! * [`target`]: target spectra: IS 1893 (Part 1):2016, ASCE 7-16 and tabulated spectra, parsed
//!   from SPEC strings such as `is1893:zone=III,soil=I`.

pub mod ductility;
pub mod floor;
pub mod periods;
pub mod response;
pub mod target;

pub use periods::{PeriodsError, log_space, parse_periods, periods_from_list};
pub use response::{Peak, ResponseSpectrum, SpectrumError, peak_response, response_spectrum};
pub use target::{TARGET_DAMPING, TargetError, TargetSpectrum};
