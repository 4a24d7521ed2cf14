//! Response spectra of records and the target (design) spectra they are compared with.
//!
//! * [`response`]: exact linear response spectra (Nigam–Jennings, peaks between samples included).
//! * [`target`]: target spectra: IS 1893 (Part 1):2016, ASCE 7-16 and tabulated spectra, parsed
//!   from SPEC strings such as `is1893:zone=III,soil=I`.

pub mod response;
pub mod target;

pub use response::{Peak, ResponseSpectrum, SpectrumError, peak_response, response_spectrum};
pub use target::{TargetError, TargetSpectrum};
