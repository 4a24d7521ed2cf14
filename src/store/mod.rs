//! Result files: their layouts, how they are written (atomically, checked) and how they prove on
//! reading that they are what was written. Knows file layouts, not the study: every writer takes
//! plain data (slices, [`ndarray`] arrays, the [`crate::grid::Grid`] axes).
//!
//! * [`atomic`]: checked atomic writes (unique temporary, fsync, rename).
//! * [`h5`]: HDF5 helpers: labelled variables with checksummed chunks, dimension scales, the
//!   stage-file envelope (fingerprint, checksum sidecar, verification).
//! * [`units`]: the sweep's per-unit files (identity, checksum) for resuming and sharding.
//! * [`motions`], [`sweep`], [`tnew`], [`fit`], [`ida`]: the stage files.
//! * [`history`]: one simulation's time history.
//! * [`fingerprint`]: SHA-256 of inputs, for up-to-date checks.

// First, so that `stored_vars!` is in scope in the stage files' modules below.
#[macro_use]
pub mod vars;

pub mod atomic;
pub mod checksum;
pub mod fingerprint;
pub mod fit;
pub mod floors;
pub mod h5;
pub mod history;
pub mod ida;
pub mod motions;
pub mod report;
pub mod sweep;
pub mod tnew;
pub mod units;

pub use history::{HistoryFormat, HistoryLayout, write_history};

use std::path::{Path, PathBuf};
use thiserror::Error;

/// A file that could not be written or read as it should be; always names the file.
#[derive(Debug, Error)]
pub enum StoreError {
    #[error("{}: {op}: {source}", file.display())]
    Io {
        file: PathBuf,
        op: &'static str,
        source: std::io::Error,
    },
    /// The HDF5 library's message, condensed to its description and system error.
    #[error("{}: HDF5: {message}", file.display())]
    Hdf5 { file: PathBuf, message: String },
    /// The file exists but is not what was written: checksum, identity or layout differs.
    #[error("{}: {why}", file.display())]
    Corrupt { file: PathBuf, why: String },
    /// A variable whose shape is not the one its dimensions give.
    #[error(
        "{}: {variable} has shape {found:?} where its dimensions give {expected:?}",
        file.display()
    )]
    Shape {
        file: PathBuf,
        variable: String,
        found: Vec<usize>,
        expected: Vec<usize>,
    },
    #[error("{}: history file must end in .h5, .hdf5 or .csv", .0.display())]
    Format(PathBuf),
}

impl StoreError {
    pub fn io(file: &Path, op: &'static str, source: std::io::Error) -> Self {
        Self::Io {
            file: file.to_path_buf(),
            op,
            source,
        }
    }

    pub fn hdf5(file: &Path, source: hdf5::Error) -> Self {
        Self::Hdf5 {
            file: file.to_path_buf(),
            message: condense(&source.to_string()),
        }
    }

    pub fn corrupt(file: &Path, why: impl Into<String>) -> Self {
        Self::Corrupt {
            file: file.to_path_buf(),
            why: why.into(),
        }
    }

    pub fn shape(
        file: &Path,
        variable: impl Into<String>,
        found: &[usize],
        expected: &[usize],
    ) -> Self {
        Self::Shape {
            file: file.to_path_buf(),
            variable: variable.into(),
            found: found.to_vec(),
            expected: expected.to_vec(),
        }
    }

    /// The file this error is about.
    pub fn file(&self) -> &Path {
        match self {
            Self::Io { file, .. }
            | Self::Hdf5 { file, .. }
            | Self::Corrupt { file, .. }
            | Self::Shape { file, .. } => file,
            Self::Format(file) => file,
        }
    }
}

/// HDF5's message without its time stamp, temporary name, buffer address and byte counts:
/// `H5Fflush(): … file write failed (File too large)`.
fn condense(message: &str) -> String {
    let description = message
        .split(": time =")
        .next()
        .unwrap_or(message)
        .trim()
        .to_string();
    match message
        .split("error message = '")
        .nth(1)
        .and_then(|rest| rest.split('\'').next())
    {
        Some(os) => format!("{description} ({os})"),
        None => description,
    }
}

/// Attaches the file name to an HDF5 result.
pub(crate) trait H5Context<T> {
    fn at(self, file: &Path) -> Result<T, StoreError>;
}

impl<T> H5Context<T> for hdf5::Result<T> {
    fn at(self, file: &Path) -> Result<T, StoreError> {
        self.map_err(|e| StoreError::hdf5(file, e))
    }
}

/// `docs/variables.md`: the table of every declared stage-file variable, made from the
/// declarations themselves ([`vars`]); `tests/variables_doc.rs` holds the file to it.
pub fn variables_doc() -> String {
    let one = "motion, T_p, alpha_1 … alpha_n, mu_1 … mu_n";
    let building = "motion, storeys, stack_floor, T_p, …";
    let mut s = String::from(
        "# Stored variables\n\n\
         Made by `slidestack::store::variables_doc()` from the declarations in `src/store/` \
         (`stored_vars!`), which also drive the writers and the readers' shape checks; \
         `SLIDESTACK_BLESS=1 cargo test --release --test variables_doc` rewrites it \
         (`fit.h5`, the fit's attributes beside `fit.yaml`, is described in its module, \
         `src/store/fit.rs`). \
         \"codes\" are `u8` CF flags (`flag_values`, `flag_meanings` on the variable, 255 the \
         fill); every other variable is `f64` with NaN as fill. A building study's variables \
         have the dimensions `storeys, stack_floor` after `motion` (`sweep.h5`) or in front \
         (`tnew.h5`); their layouts are described in [model.md](model.md).\n",
    );
    let mut section = |title: &str, note: &str, case: &str, vars: &[vars::Var]| {
        s.push_str(&format!("\n## {title}\n\n{note}\n\n"));
        s.push_str(&vars::table(case, vars));
    };
    section(
        "`sweep.h5`: every case under every motion",
        "Per zone; `rocks_stack` only with `grid.aspect`.",
        one,
        &[sweep::SweepVars::VARS, &[sweep::ROCKS_STACK]].concat(),
    );
    section(
        "`sweep.h5`: a building study's floors and storeys",
        "Over the building's floors or storeys up to the largest `storeys` (NaN above a \
         building's roof).",
        building,
        sweep::BuildingVars::VARS,
    );
    let case = "T_p, alpha_1 … alpha_n, mu_1 … mu_n";
    section(
        "`tnew.h5`: per case, over the motions",
        "Per zone; `rocks_share` only with `grid.aspect`.",
        case,
        &[tnew::TnewVars::VARS, &[tnew::ROCKS_SHARE]].concat(),
    );
    section(
        "`tnew.h5`: a building study's attached fractions",
        "Every flag's codes are the file's `lambda_flag` codes.",
        "storeys, stack_floor, T_p, …",
        tnew::AttachedVars::VARS,
    );
    section(
        "`motions.h5`: each zone's spectra",
        "Over the check periods; `psa_g` is over `motion, period`.",
        "period",
        &motions::SPECTRA,
    );
    section(
        "`motions.h5`: each seed's matching",
        "Per zone, over every seed (kept or not).",
        "seed",
        &motions::SEED_REPORT,
    );
    section(
        "`motions.h5`: a table target's rows",
        "Only for a `table:FILE` target.",
        "target_row",
        &motions::TARGET_TABLE,
    );
    section(
        "`floors.h5`: the floors' peaks",
        "Per zone, over the listed cases (`floor_spectra.cases`).",
        "motion, case, (storeys, stack_floor)",
        &floors::PEAKS,
    );
    section(
        "`floors.h5`: the floor response spectra",
        "Per zone, over the oscillators' damping ratios and periods.",
        "motion, case, (storeys, stack_floor,) damping, floor, period",
        &floors::SPECTRA,
    );
    s.push_str(
        "\n## `ida.h5`: traces, curves and fragility fits\n\n\
         Per zone, over the listed cases (`ida.cases`); `case` is `case, storeys, stack_floor` \
         in a building study. Beside them the coordinates, `case_T_p`, `case_alpha`, `case_mu`, \
         `c_y` [case] and, in a building study, `storey_c_y` [case, storeys, storey] \
         (`src/store/ida.rs`). `fit_status` takes its codes from the fragility fit's flags.\n\n",
    );
    s.push_str(&ida::variables_table());
    s
}
