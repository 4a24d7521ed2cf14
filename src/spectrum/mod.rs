//! Response spectra of records and target (design) spectra.
//!
//! * [`response`]: exact linear response spectra (Nigam–Jennings, peaks between samples included).

pub mod response;

pub use response::{Peak, ResponseSpectrum, SpectrumError, peak_response, response_spectrum};
