//! A simulation's time history as HDF5 (one dataset per quantity, `[time, body]` or
//! `[time, interface]`, with `units` and `long_name` attributes) or CSV (one row per sample).

use super::atomic::Temp;
use super::h5::attr_str as attr;
use super::{H5Context, StoreError};
use crate::dynamics::History;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

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
            _ => Err(StoreError::Format(path.to_path_buf())),
        }
    }
}

/// The names of a history's bodies and interfaces, in order, and what the file holds.
#[derive(Debug, Clone, PartialEq)]
pub struct HistoryLayout {
    pub contents: String,
    pub bodies: Vec<String>,
    pub interfaces: Vec<String>,
}

impl HistoryLayout {
    /// One storey: `ps` (the structure), then `block1…` bottom-up; `interface1…`.
    pub fn one_storey(blocks: usize) -> Self {
        let mut bodies = vec!["ps".to_string()];
        bodies.extend((1..=blocks).map(|j| format!("block{j}")));
        Self {
            contents: "slidestack simulate time history; body 0 is the structure, blocks \
                       bottom-up"
                .into(),
            bodies,
            interfaces: (1..=blocks).map(|i| format!("interface{i}")).collect(),
        }
    }

    /// A building of `storeys` with stacks of `blocks[s]` blocks: `floor1…`, then
    /// `stack1_block1…`; `stack1_interface1…` (interface 1 between the floor and block 1).
    pub fn building(storeys: usize, blocks: &[usize]) -> Self {
        let mut bodies: Vec<String> = (1..=storeys).map(|j| format!("floor{j}")).collect();
        let mut interfaces = Vec::new();
        for (s, &nb) in blocks.iter().enumerate() {
            bodies.extend((1..=nb).map(|b| format!("stack{}_block{b}", s + 1)));
            interfaces.extend((1..=nb).map(|b| format!("stack{}_interface{b}", s + 1)));
        }
        Self {
            contents: "slidestack simulate time history of a building; bodies: the floors \
                       (floor 1 the lowest), then each stack's blocks bottom-up"
                .into(),
            bodies,
            interfaces,
        }
    }
}

/// Writes `history` to `path` in the format its extension names: into a temporary, checked
/// (every write, the flush and, for HDF5, the close), synced and renamed, so a full disk or a
/// kill leaves no partial or zero-filled file behind.
pub fn write_history(
    path: &Path,
    history: &History,
    layout: &HistoryLayout,
) -> Result<(), StoreError> {
    let format = HistoryFormat::from_path(path)?;
    let tmp = Temp::for_path(path);
    match format {
        HistoryFormat::Csv => write_csv(tmp.path(), history, layout)
            .map_err(|e| StoreError::io(path, "cannot write", e))?,
        HistoryFormat::Hdf5 => write_hdf5(tmp.path(), history, layout).at(path)?,
    }
    tmp.commit(path)
}

/// One row per sample through the `csv` crate (the column names are ours and need no quoting;
/// the numbers are Rust's shortest round-trip text).
fn write_csv(path: &Path, h: &History, layout: &HistoryLayout) -> std::io::Result<()> {
    let mut w = csv::Writer::from_writer(std::io::BufWriter::new(std::fs::File::create(path)?));
    let (nb, ni) = (h.bodies, h.interfaces);
    let mut cols = vec!["time_s".to_string(), "ground_accel_mps2".to_string()];
    for (what, unit) in [("disp", "m"), ("vel", "mps"), ("abs_accel", "mps2")] {
        cols.extend(layout.bodies.iter().map(|b| format!("{b}_{what}_{unit}")));
    }
    cols.extend(layout.interfaces.iter().map(|i| format!("{i}_state")));
    w.write_record(&cols)?;
    let mut field = String::new();
    let mut put = |w: &mut csv::Writer<_>, v: &dyn std::fmt::Display| {
        field.clear();
        write!(field, "{v}").expect("writing to a String");
        w.write_field(&field)
    };
    for r in 0..h.rows() {
        put(&mut w, &h.time_s[r])?;
        put(&mut w, &h.ground_accel_mps2[r])?;
        for data in [&h.displacement_m, &h.velocity_mps, &h.abs_accel_mps2] {
            for v in &data[r * nb..(r + 1) * nb] {
                put(&mut w, v)?;
            }
        }
        for c in &h.contact[r * ni..(r + 1) * ni] {
            put(&mut w, c)?;
        }
        w.write_record(None::<&[u8]>)?;
    }
    w.into_inner()
        .map_err(|e| std::io::Error::new(e.error().kind(), e.error().to_string()))?
        .flush()
}

fn write_hdf5(path: &Path, h: &History, layout: &HistoryLayout) -> hdf5::Result<()> {
    let f = hdf5::File::create(path)?;
    fill_hdf5(&f, h, layout)?;
    f.flush()?;
    f.close()
}

fn fill_hdf5(f: &hdf5::File, h: &History, layout: &HistoryLayout) -> hdf5::Result<()> {
    let rows = h.rows();
    let nb = h.bodies;
    attr(f, "contents", &layout.contents)?;
    attr(f, "slidestack_version", env!("CARGO_PKG_VERSION"))?;
    attr(
        f,
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
        attr(&ds, "dims", "time, body")?;
        attr(&ds, "bodies", &layout.bodies.join(", "))
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
        .shape((rows, h.interfaces))
        .create("contact")?;
    ds.write_raw(&h.contact)?;
    attr(
        &ds,
        "long_name",
        "interface state (see file attribute contact_codes)",
    )?;
    attr(&ds, "dims", "time, interface")?;
    attr(&ds, "interfaces", &layout.interfaces.join(", "))?;
    Ok(())
}
