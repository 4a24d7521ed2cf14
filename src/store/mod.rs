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
