//! A simulation's time history as HDF5 (one dataset per quantity, `[time, body]` or
//! `[time, interface]`, with `units` and `long_name` attributes) or CSV (one row per sample).

use super::h5::attr_str as attr;
use crate::dynamics::History;
use std::io::Write;
use std::path::Path;
use thiserror::Error;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryFormat {
    Hdf5,
    Csv,
}

impl HistoryFormat {
    /// From the file extension: `.h5`/`.hdf5` or `.csv`.
    pub fn from_path(path: &Path) -> Result<Self, StoreError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("h5" | "hdf5") => Ok(Self::Hdf5),
            Some("csv") => Ok(Self::Csv),
            _ => Err(StoreError::Format(path.display().to_string())),
        }
    }
}

#[derive(Debug, Error)]
pub enum StoreError {
    #[error("{0}: history file must end in .h5, .hdf5 or .csv")]
    Format(String),
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: HDF5 error: {source}")]
    Hdf5 {
        file: String,
        #[source]
        source: hdf5::Error,
    },
}

/// Writes `history` to `path` in the format its extension names.
pub fn write_history(path: &Path, history: &History) -> Result<(), StoreError> {
    let file = path.display().to_string();
    match HistoryFormat::from_path(path)? {
        HistoryFormat::Csv => {
            write_csv(path, history).map_err(|source| StoreError::Io { file, source })
        }
        HistoryFormat::Hdf5 => {
            write_hdf5(path, history).map_err(|source| StoreError::Hdf5 { file, source })
        }
    }
}

fn write_csv(path: &Path, h: &History) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let nb = h.bodies;
    let body = |j: usize| {
        if j == 0 {
            "ps".to_string()
        } else {
            format!("block{j}")
        }
    };
    let mut cols = vec!["time_s".to_string(), "ground_accel_mps2".to_string()];
    for (what, unit) in [("disp", "m"), ("vel", "mps"), ("abs_accel", "mps2")] {
        cols.extend((0..nb).map(|j| format!("{}_{what}_{unit}", body(j))));
    }
    cols.extend((1..nb).map(|i| format!("interface{i}_state")));
    writeln!(w, "{}", cols.join(","))?;
    for r in 0..h.rows() {
        write!(w, "{},{}", h.time_s[r], h.ground_accel_mps2[r])?;
        for data in [&h.displacement_m, &h.velocity_mps, &h.abs_accel_mps2] {
            for v in &data[r * nb..(r + 1) * nb] {
                write!(w, ",{v}")?;
            }
        }
        for c in &h.contact[r * (nb - 1)..(r + 1) * (nb - 1)] {
            write!(w, ",{c}")?;
        }
        writeln!(w)?;
    }
    w.flush()
}

fn write_hdf5(path: &Path, h: &History) -> hdf5::Result<()> {
    let f = hdf5::File::create(path)?;
    let rows = h.rows();
    let nb = h.bodies;
    attr(
        &f,
        "contents",
        "slidestack simulate time history; body 0 is the structure, blocks bottom-up",
    )?;
    attr(&f, "slidestack_version", env!("CARGO_PKG_VERSION"))?;
    attr(
        &f,
        "contact_codes",
        "0 stick, 1 slip with positive relative velocity, -1 slip negative, 2 frictionless",
    )?;
    let one = |name: &str, data: &[f64], units: &str, long: &str| -> hdf5::Result<()> {
        let ds = f.new_dataset::<f64>().shape(rows).create(name)?;
        ds.write_raw(data)?;
        attr(&ds, "units", units)?;
        attr(&ds, "long_name", long)
    };
    one("time", &h.time_s, "s", "time")?;
    one(
        "ground_accel",
        &h.ground_accel_mps2,
        "m/s^2",
        "ground acceleration",
    )?;
    let two = |name: &str, data: &[f64], units: &str, long: &str| -> hdf5::Result<()> {
        let ds = f.new_dataset::<f64>().shape((rows, nb)).create(name)?;
        ds.write_raw(data)?;
        attr(&ds, "units", units)?;
        attr(&ds, "long_name", long)?;
        attr(&ds, "dims", "time, body")
    };
    two(
        "displacement",
        &h.displacement_m,
        "m",
        "displacement relative to the ground",
    )?;
    two(
        "velocity",
        &h.velocity_mps,
        "m/s",
        "velocity relative to the ground",
    )?;
    two(
        "abs_accel",
        &h.abs_accel_mps2,
        "m/s^2",
        "absolute acceleration",
    )?;
    let ds = f
        .new_dataset::<i8>()
        .shape((rows, nb - 1))
        .create("contact")?;
    ds.write_raw(&h.contact)?;
    attr(
        &ds,
        "long_name",
        "interface state (see file attribute contact_codes)",
    )?;
    attr(&ds, "dims", "time, interface")?;
    Ok(())
}
