//! The parametric study's numerics and configuration (the stages that drive them are in
//! [`crate::pipeline`]).
//!
//! * [`attached`]: attached fractions: `λ` of the base shear, of each storey's shear and of the
//!   overturning moment, the code-format `λ`, a building's `T_new` (the roof's).
//! * [`building`]: a study over buildings: the `building:` section, `grid.stack_floor`, a frame.
//! * [`case_units`]: the work units of a stage over listed cases (the IDA, the floor spectra),
//!   a repeated building's taken from its first frame.
//! * [`cases`]: the paper's named cases (Section 7.1, Table 2, Section 9).
//! * [`config`]: the study file (YAML), validated before any work.
//! * [`floors`]: floor response spectra of listed cases on every frame (`floor_spectra:`),
//!   and the code's floor amplifications (ASCE 7-16, 7-22).
//! * [`equations`]: the design equations: every form fitted to each zone's `T_new` (and a
//!   building study's `λ`), cross-validated and box-checked, the recommended one.
//! * [`design`]: the designer's arithmetic: `T_new` of one structure from a zone's (or frame's)
//!   data.
//! * [`ida`]: the `ida:` section, a case's systems on a yielding structure, one traced unit.
//! * [`ida_zone`]: one zone of the IDA: a unit traced, the zone's curves, fractiles and
//!   fragilities.
//! * [`motions`]: seeds, spectral matching per zone, the set checks.
//! * [`physics`]: the physics of a case: damping basis, shared settings, its three systems.
//! * [`shape`]: what a study is over: its grid and its frames (one on one storey), their
//!   distinct buildings and labels.
//! * [`storey_strength`]: a building's storey strengths from a base-shear coefficient (IS 1893).
//! * [`sweep`]: the skip rules, one work unit.
//! * [`tnew`]: `T_new` from the mean displacement spectrum; the fit's samples.
//! * [`yaml`]: YAML values read by hand, refused in words with their key's line.

pub mod attached;
pub mod building;
pub mod case_units;
pub mod cases;
pub mod config;
pub mod cost;
pub mod design;
pub mod equations;
pub mod floors;
pub mod ida;
pub mod ida_zone;
pub mod motions;
pub mod physics;
pub mod shape;
pub mod storey_strength;
pub mod sweep;
pub mod tnew;
pub mod yaml;
