//! Response spectra and the target (design) spectra they are compared with.
//!
//! * [`target`]: target spectra: IS 1893 (Part 1):2016, ASCE 7-16 and tabulated spectra, parsed
//!   from SPEC strings such as `is1893:zone=III,soil=I`.

pub mod target;
