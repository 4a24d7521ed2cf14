//! HDF5 helpers shared by the stage files: attributes, labelled variables, dimension scales and
//! the stage-file envelope.
//!
//! Every stage file is written by [`write_stage_file`]: into a temporary unique to the process,
//! flushed and closed with both results checked, read back, synced and renamed; then its SHA-256
//! goes into a sidecar `NAME.sha256` (the format of `sha256sum`, so `sha256sum -c` checks it
//! too). [`stored_fingerprint`] accepts a file only when it matches its sidecar, so a file
//! changed, truncated or damaged after it was written is never taken as up to date. Chunked
//! variables also carry HDF5's Fletcher32 filter, so any reader (h5py, xarray) fails on a
//! damaged chunk instead of returning wrong numbers.

use super::atomic::Temp;
use super::{H5Context, StoreError, checksum};
use hdf5::types::VarLenUnicode;
use ndarray::{ArrayD, ArrayViewD};
use std::path::Path;

/// Writes (or replaces) the string attribute `name`.
pub fn attr_str(obj: &hdf5::Location, name: &str, value: &str) -> hdf5::Result<()> {
    let v: VarLenUnicode = value
        .parse()
        .map_err(|e| hdf5::Error::from(format!("{e:?}")))?;
    if obj.attr(name).is_ok() {
        obj.delete_attr(name)?;
    }
    obj.new_attr::<VarLenUnicode>()
        .create(name)?
        .write_scalar(&v)
}

/// Reads the string attribute `name`, if present.
pub fn read_attr_str(obj: &hdf5::Location, name: &str) -> Option<String> {
    let a = obj.attr(name).ok()?;
    a.read_scalar::<VarLenUnicode>().ok().map(|v| v.to_string())
}

/// Writes a scalar `f64` attribute.
pub fn attr_f64(obj: &hdf5::Location, name: &str, value: f64) -> hdf5::Result<()> {
    obj.new_attr::<f64>().create(name)?.write_scalar(&value)
}

pub fn read_attr_f64(obj: &hdf5::Location, name: &str) -> hdf5::Result<f64> {
    obj.attr(name)?.read_scalar::<f64>()
}

/// A scalar attribute value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Attr<'a> {
    F64(f64),
    Str(&'a str),
}

/// Writes scalar attributes in order.
pub fn write_attrs(obj: &hdf5::Location, attrs: &[(&str, Attr)]) -> hdf5::Result<()> {
    for (name, value) in attrs {
        match value {
            Attr::F64(v) => attr_f64(obj, name, *v)?,
            Attr::Str(v) => attr_str(obj, name, v)?,
        }
    }
    Ok(())
}

/// A small contiguous `f64` dataset of any shape with its units and description.
pub fn write_small(
    g: &hdf5::Group,
    name: &str,
    data: ArrayViewD<f64>,
    units: &str,
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = g
        .new_dataset::<f64>()
        .shape(data.shape())
        .obj_track_times(false)
        .create(name)?;
    ds.write(data)?;
    attr_str(&ds, "units", units)?;
    attr_str(&ds, "long_name", long_name)?;
    Ok(ds)
}

/// A 1-D `f64` dataset with its units and description.
pub fn write_1d(
    g: &hdf5::Group,
    name: &str,
    data: &[f64],
    units: &str,
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    write_small(
        g,
        name,
        ndarray::ArrayView1::from(data).into_dyn(),
        units,
        long_name,
    )
}

/// A 1-D dataset of strings.
pub fn write_strings(
    g: &hdf5::Group,
    name: &str,
    values: &[String],
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let v = values
        .iter()
        .map(|s| s.parse::<VarLenUnicode>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| hdf5::Error::from(format!("{e:?}")))?;
    let ds = g
        .new_dataset::<VarLenUnicode>()
        .shape(v.len())
        .obj_track_times(false)
        .create(name)?;
    ds.write_raw(&v)?;
    attr_str(&ds, "long_name", long_name)?;
    Ok(ds)
}

/// A 1-D coordinate of strings (names, labels), made a dimension scale named after itself.
pub fn string_coordinate(
    g: &hdf5::Group,
    name: &str,
    values: &[String],
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = write_strings(g, name, values, long_name)?;
    set_scale(&ds, name)?;
    Ok(ds)
}

pub fn read_strings(g: &hdf5::Group, name: &str) -> hdf5::Result<Vec<String>> {
    Ok(g.dataset(name)?
        .read_raw::<VarLenUnicode>()?
        .into_iter()
        .map(|s| s.to_string())
        .collect())
}

unsafe extern "C" {
    fn H5DSset_scale(dsid: i64, dimname: *const std::ffi::c_char) -> i32;
    fn H5DSattach_scale(did: i64, dsid: i64, idx: std::ffi::c_uint) -> i32;
}

/// Makes `scale` a dimension scale named `name` (HDF5 high-level library, `H5DSset_scale`).
pub fn set_scale(scale: &hdf5::Dataset, name: &str) -> hdf5::Result<()> {
    let c = std::ffi::CString::new(name).map_err(|e| hdf5::Error::from(e.to_string()))?;
    // SAFETY: both ids are valid open dataset handles owned by `scale`; the string outlives the
    // call.
    let rc = hdf5::sync::sync(|| unsafe { H5DSset_scale(scale.id(), c.as_ptr()) });
    if rc < 0 {
        return Err(hdf5::Error::from(format!("H5DSset_scale({name}) failed")));
    }
    Ok(())
}

/// Attaches dimension scale `scale` to dimension `idx` of `data` (`H5DSattach_scale`).
pub fn attach_scale(data: &hdf5::Dataset, scale: &hdf5::Dataset, idx: usize) -> hdf5::Result<()> {
    // SAFETY: as in `set_scale`.
    let rc = hdf5::sync::sync(|| unsafe { H5DSattach_scale(data.id(), scale.id(), idx as u32) });
    if rc < 0 {
        return Err(hdf5::Error::from("H5DSattach_scale failed".to_string()));
    }
    Ok(())
}

/// Attaches `scales` to the leading dimensions of `ds`, in order.
pub fn attach_all(ds: &hdf5::Dataset, scales: &[hdf5::Dataset]) -> hdf5::Result<()> {
    for (d, s) in scales.iter().enumerate() {
        attach_scale(ds, s, d)?;
    }
    Ok(())
}

/// A chunked variable: shuffle + deflate compressed, Fletcher32-checksummed, with `fill` as the
/// fill value.
fn chunked<T: hdf5::H5Type + Copy>(
    g: &hdf5::Group,
    name: &str,
    data: ArrayViewD<T>,
    chunk: &[usize],
    fill: T,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = g
        .new_dataset::<T>()
        .shape(data.shape())
        .chunk(chunk.to_vec())
        .shuffle()
        .deflate(4)
        .fletcher32()
        .fill_value(fill)
        .obj_track_times(false)
        .create(name)?;
    ds.write(data)?;
    Ok(ds)
}

/// A chunked `f64` variable with NaN fill, its units and description.
pub fn write_var(
    g: &hdf5::Group,
    name: &str,
    data: ArrayViewD<f64>,
    chunk: &[usize],
    units: &str,
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = chunked(g, name, data, chunk, f64::NAN)?;
    attr_str(&ds, "units", units)?;
    attr_str(&ds, "long_name", long_name)?;
    Ok(ds)
}

/// A chunked `u8` code variable with fill 255 and CF `flag_values`/`flag_meanings` attributes
/// (`meanings` pairs each code with a one-word meaning).
pub fn write_flags(
    g: &hdf5::Group,
    name: &str,
    data: ArrayViewD<u8>,
    chunk: &[usize],
    long_name: &str,
    meanings: &[(u8, &str)],
) -> hdf5::Result<hdf5::Dataset> {
    let ds = chunked(g, name, data, chunk, 255u8)?;
    attr_str(&ds, "long_name", long_name)?;
    let values: Vec<u8> = meanings.iter().map(|m| m.0).collect();
    ds.new_attr::<u8>()
        .shape(values.len())
        .create("flag_values")?
        .write_raw(&values)?;
    let words: Vec<&str> = meanings.iter().map(|m| m.1).collect();
    attr_str(&ds, "flag_meanings", &words.join(" "))?;
    Ok(ds)
}

/// A 1-D coordinate, made a dimension scale named after itself.
pub fn coordinate(
    g: &hdf5::Group,
    name: &str,
    values: &[f64],
    units: &str,
    long: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = write_1d(g, name, values, units, long)?;
    set_scale(&ds, name)?;
    Ok(ds)
}

/// Opens a stage file for reading, naming it on failure.
pub fn open(path: &Path) -> Result<hdf5::File, StoreError> {
    hdf5::File::open(path).at(path)
}

/// A group of a file opened with [`open`], naming the file on failure.
pub fn group(f: &hdf5::File, path: &Path, name: &str) -> Result<hdf5::Group, StoreError> {
    f.group(name).at(path)
}

/// One group of a stage file, read variable by variable, each checked against the shape its
/// dimensions give. A file can verify against its checksum sidecar and still hold other shapes
/// (written by another program, or by a bug): it is refused with an error naming the file and
/// the variable ([`StoreError::Shape`]) before any array of it is indexed.
pub struct GroupReader<'p> {
    file: &'p Path,
    name: String,
    group: hdf5::Group,
}

impl<'p> GroupReader<'p> {
    /// Group `name` of the stage file `file`.
    pub fn open(file: &'p Path, name: &str) -> Result<Self, StoreError> {
        let group = open(file)?.group(name).at(file)?;
        Ok(Self {
            file,
            name: name.to_string(),
            group,
        })
    }

    /// `group/variable`, as errors name it.
    pub fn label(&self, variable: &str) -> String {
        format!("{}/{variable}", self.name)
    }

    fn dataset(&self, variable: &str) -> Result<hdf5::Dataset, StoreError> {
        self.group.dataset(variable).at(self.file)
    }

    /// Refuses `found` unless it is `expected`, naming `variable`.
    pub fn expect(
        &self,
        variable: &str,
        found: &[usize],
        expected: &[usize],
    ) -> Result<(), StoreError> {
        if found == expected {
            Ok(())
        } else {
            Err(StoreError::shape(
                self.file,
                self.label(variable),
                found,
                expected,
            ))
        }
    }

    /// A variable of shape `shape`.
    pub fn array<T: hdf5::H5Type>(
        &self,
        variable: &str,
        shape: &[usize],
    ) -> Result<ArrayD<T>, StoreError> {
        let a = self.dataset(variable)?.read_dyn::<T>().at(self.file)?;
        self.expect(variable, a.shape(), shape)?;
        Ok(a)
    }

    /// A one-dimensional `f64` variable of any length (a coordinate, which gives its dimension's
    /// length, or a record).
    pub fn vector(&self, variable: &str) -> Result<Vec<f64>, StoreError> {
        let a = self.dataset(variable)?.read_dyn::<f64>().at(self.file)?;
        self.expect(variable, a.shape(), &[a.len()])?;
        Ok(a.iter().copied().collect())
    }

    /// A one-dimensional string variable of any length.
    pub fn strings(&self, variable: &str) -> Result<Vec<String>, StoreError> {
        let ds = self.dataset(variable)?;
        self.expect(variable, &ds.shape(), &[ds.size()])?;
        read_strings(&self.group, variable).at(self.file)
    }

    /// The string attribute `name` of the group, if present.
    pub fn attr_str(&self, name: &str) -> Option<String> {
        read_attr_str(&self.group, name)
    }

    /// The names of the group's members.
    /// Whether the group holds `name`.
    pub fn has(&self, name: &str) -> bool {
        self.group.link_exists(name)
    }

    pub fn members(&self) -> Result<Vec<String>, StoreError> {
        self.group.member_names().at(self.file)
    }

    pub fn group(&self) -> &hdf5::Group {
        &self.group
    }

    /// The stage file.
    pub fn file(&self) -> &Path {
        self.file
    }
}

/// Writes a stage file at `path` (see the module doc). `fill` writes the contents into a file
/// that already carries the `contents`, `slidestack_version` and `fingerprint` attributes (object
/// times not tracked, so equal contents give equal bytes).
pub fn write_stage_file(
    path: &Path,
    contents: &str,
    fingerprint: &str,
    fill: impl FnOnce(&hdf5::File) -> hdf5::Result<()>,
) -> Result<(), StoreError> {
    let tmp = Temp::for_path(path);
    let write = || -> hdf5::Result<()> {
        let f = hdf5::File::with_options()
            .with_fcpl(|p| p.obj_track_times(false))
            .create(tmp.path())?;
        attr_str(&f, "contents", contents)?;
        attr_str(&f, "slidestack_version", env!("CARGO_PKG_VERSION"))?;
        attr_str(&f, "fingerprint", fingerprint)?;
        fill(&f)?;
        f.flush()?;
        f.close()
    };
    write().at(path)?;
    let back = hdf5::File::open(tmp.path()).at(path)?;
    let stored = read_attr_str(&back, "fingerprint");
    drop(back);
    if stored.as_deref() != Some(fingerprint) {
        return Err(StoreError::corrupt(
            path,
            "the written file does not read back its fingerprint",
        ));
    }
    checksum::commit_with_sidecar(tmp, path)
}

/// The fingerprint stored in the stage file at `path`: `None` when there is no file; an error
/// when the file does not match its checksum sidecar (changed or damaged after it was written,
/// or its write was interrupted) or cannot be read.
pub fn stored_fingerprint(path: &Path) -> Result<Option<String>, StoreError> {
    if !checksum::verify(path)? {
        return Ok(None);
    }
    let f = open(path)?;
    read_attr_str(&f, "fingerprint")
        .map(Some)
        .ok_or_else(|| StoreError::corrupt(path, "has no fingerprint attribute"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(path: &Path, fp: &str) {
        write_stage_file(path, "test", fp, |f| {
            let g = f.create_group("g")?;
            let a = ndarray::Array::from_shape_fn((3, 4), |(i, j)| (i * 4 + j) as f64).into_dyn();
            write_var(&g, "v", a.view(), &[1, 4], "m", "a variable")?;
            Ok(())
        })
        .unwrap();
    }

    #[test]
    fn stage_file_verifies_itself() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.h5");
        assert!(stored_fingerprint(&p).unwrap().is_none());
        sample(&p, "abc");
        assert_eq!(stored_fingerprint(&p).unwrap().as_deref(), Some("abc"));
        let text = std::fs::read_to_string(checksum::sidecar_path(&p)).unwrap();
        assert!(text.ends_with("  x.h5\n"), "{text}");
        // The chunked variable reads back with its shape, and no other shape is taken for it.
        let g = GroupReader::open(&p, "g").unwrap();
        let v = g.array::<f64>("v", &[3, 4]).unwrap();
        assert_eq!(v[[2, 3]], 11.0);
        let e = g.array::<f64>("v", &[4, 3]).unwrap_err().to_string();
        assert!(
            e.ends_with("x.h5: g/v has shape [3, 4] where its dimensions give [4, 3]"),
            "{e}"
        );
        drop(g);

        // One flipped byte anywhere: refused by the sidecar.
        let mut bytes = std::fs::read(&p).unwrap();
        let mid = bytes.len() / 2;
        bytes[mid] ^= 0x40;
        std::fs::write(&p, &bytes).unwrap();
        let e = stored_fingerprint(&p).unwrap_err().to_string();
        assert!(e.contains("does not match its checksum"), "{e}");

        // No sidecar: refused.
        sample(&p, "abc");
        std::fs::remove_file(checksum::sidecar_path(&p)).unwrap();
        let e = stored_fingerprint(&p).unwrap_err().to_string();
        assert!(e.contains("has no checksum file"), "{e}");
    }

    #[test]
    fn fletcher32_catches_a_damaged_chunk_without_the_sidecar() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.h5");
        // Incompressible values so the chunk's bytes can be found and damaged.
        write_stage_file(&p, "test", "f", |f| {
            let g = f.create_group("g")?;
            let a = ndarray::Array::from_shape_fn(64, |i| 1.0 + (i as f64).sin() * 1e-3).into_dyn();
            write_var(&g, "v", a.view(), &[64], "m", "v")?;
            Ok(())
        })
        .unwrap();
        let f = open(&p).unwrap();
        let chunk = f
            .group("g")
            .unwrap()
            .dataset("v")
            .unwrap()
            .chunk_info(0)
            .unwrap();
        drop(f);
        let mut bytes = std::fs::read(&p).unwrap();
        let mid = (chunk.addr + chunk.size / 2) as usize;
        bytes[mid] ^= 0x55;
        std::fs::write(&p, &bytes).unwrap();
        let f = hdf5::File::open(&p);
        let read = f.and_then(|f| f.group("g")?.dataset("v")?.read_raw::<f64>());
        assert!(read.is_err(), "a damaged chunk must not read back");
    }
}
