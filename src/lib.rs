//! slidestack: seismic response of a linear structure carrying stacks of sliding rigid blocks.
//!
//! * [`dynamics`]: the structure-and-stack model, the exact and RK4 integrators, energy.
//! * [`ground_motion`]: ground-motion records, processing, spectral matching, stochastic motions.
//! * [`sdof`]: one linear SDOF step, exact for piecewise-linear load, stable at every period.
//! * [`spectrum`]: response spectra and target spectra (IS 1893, ASCE 7, tables).
//! * [`fit`]: the design equation for T_new: forms, argmin problems, metrics.
//! * [`render`]: SVG charts and HTML pages from plain series (the report stage draws with it).
//! * [`limits`]: the limits every input is checked against, with their reasons.
//! * [`case`]: a case, one structure and its stack.
//! * [`grid`]: the study's case grid (axes and indexing).
//! * [`ida`]: incremental dynamic analysis kernels: hunt & fill, fractiles, fragility fits.
//! * [`study`]: the study's numerics and configuration.
//! * [`one_case`]: one case under one ground motion (`slidestack simulate`).
//! * [`match_files`]: record files matched to a target and written (`slidestack match`).
//! * [`design`]: `T_new` of one structure from a finished study (the designer's query).
//! * [`pipeline`]: the study's stages as library code: one shape, the output lock, checks.
//! * [`store`]: result files (time histories, stage files) and input fingerprints.
//!
//! `docs/model.md` states the model, the numbers checked by hand and the choices the paper leaves
//! open; the code cites its sections as `docs/model.md, "<section>"`.

/// Declares a flag stored as a code (`#[repr(u8)]`, `Debug, Clone, Copy, PartialEq, Eq`) and its
/// `(code, word)` table for the CF `flag_values`/`flag_meanings` attributes, from one list of
/// `Variant = code => "word"`: the code, the word and the variant cannot drift apart.
macro_rules! flag_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident;
        $(#[$table_meta:meta])*
        $table_vis:vis const $table:ident;
        {
            $($(#[$variant_meta:meta])* $variant:ident = $code:literal => $word:literal,)+
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        #[repr(u8)]
        $vis enum $name {
            $($(#[$variant_meta])* $variant = $code,)+
        }

        $(#[$table_meta])*
        $table_vis const $table: &[(u8, &str)] = &[$(($name::$variant as u8, $word),)+];

        impl $name {
            /// The flag stored as `code`, if it is one.
            #[allow(dead_code)]
            $vis fn from_code(code: u8) -> Option<Self> {
                match code {
                    $($code => Some(Self::$variant),)+
                    _ => None,
                }
            }
        }
    };
}

pub mod case;
pub mod design;
pub mod dynamics;
pub mod fault;
pub mod fit;
pub mod frame_edp;
pub mod grid;
pub mod ground_motion;
pub mod ida;
pub mod limits;
pub mod match_files;
pub mod methods;
mod numeric;
pub mod one_case;
pub mod pipeline;
pub mod render;
pub mod sdof;
pub mod spectrum;
pub mod store;
pub mod study;

/// The crate's version (`slidestack --version`, the Python module's `__version__`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
