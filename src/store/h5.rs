//! Small HDF5 helpers shared by the stage files: string attributes, 1-D and 2-D `f64` datasets
//! with `units` and `long_name`, string datasets.

use hdf5::types::VarLenUnicode;

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

/// A 1-D `f64` dataset with its units and description.
pub fn write_1d(
    g: &hdf5::Group,
    name: &str,
    data: &[f64],
    units: &str,
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = g.new_dataset::<f64>().shape(data.len()).create(name)?;
    ds.write_raw(data)?;
    attr_str(&ds, "units", units)?;
    attr_str(&ds, "long_name", long_name)?;
    Ok(ds)
}

/// A row-major 2-D `f64` dataset `[rows][cols]`.
pub fn write_2d(
    g: &hdf5::Group,
    name: &str,
    data: &[f64],
    shape: (usize, usize),
    units: &str,
    long_name: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = g.new_dataset::<f64>().shape(shape).create(name)?;
    ds.write_raw(data)?;
    attr_str(&ds, "units", units)?;
    attr_str(&ds, "long_name", long_name)?;
    Ok(ds)
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

/// A chunked, deflate+shuffle compressed `f64` variable with NaN fill.
pub fn scalar_var(
    g: &hdf5::Group,
    name: &str,
    shape: &[usize],
    chunk: &[usize],
    data: &[f64],
    units: &str,
    long: &str,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = g
        .new_dataset::<f64>()
        .shape(shape.to_vec())
        .chunk(chunk.to_vec())
        .shuffle()
        .deflate(4)
        .fill_value(f64::NAN)
        .obj_track_times(false)
        .create(name)?;
    ds.write_raw(data)?;
    attr_str(&ds, "units", units)?;
    attr_str(&ds, "long_name", long)?;
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
    let ds = g
        .new_dataset::<f64>()
        .shape(values.len())
        .obj_track_times(false)
        .create(name)?;
    ds.write_raw(values)?;
    attr_str(&ds, "units", units)?;
    attr_str(&ds, "long_name", long)?;
    set_scale(&ds, name)?;
    Ok(ds)
}

/// A whole `f64` dataset `group/name` of the file at `path`, flat.
pub fn read_f64(path: &std::path::Path, group: &str, name: &str) -> hdf5::Result<Vec<f64>> {
    hdf5::File::open(path)?
        .group(group)?
        .dataset(name)?
        .read_raw::<f64>()
}

/// A scalar `f64` attribute of `group` in the file at `path`.
pub fn read_group_attr(path: &std::path::Path, group: &str, name: &str) -> hdf5::Result<f64> {
    let g = hdf5::File::open(path)?.group(group)?;
    read_attr_f64(&g, name)
}

/// Writes a stage file at `path` atomically: `fill` writes into a new file `path.h5.tmp` (object
/// times not tracked, so equal contents give equal bytes) that already carries the `contents`,
/// `slidestack_version` and `fingerprint` attributes; the file is then renamed to `path`, so a
/// reader never sees a half-written stage file.
pub fn write_stage_file(
    path: &std::path::Path,
    contents: &str,
    fingerprint: &str,
    fill: impl FnOnce(&hdf5::File) -> hdf5::Result<()>,
) -> hdf5::Result<()> {
    let tmp = path.with_extension("h5.tmp");
    {
        let f = hdf5::File::with_options()
            .with_fcpl(|p| p.obj_track_times(false))
            .create(&tmp)?;
        attr_str(&f, "contents", contents)?;
        attr_str(&f, "slidestack_version", env!("CARGO_PKG_VERSION"))?;
        attr_str(&f, "fingerprint", fingerprint)?;
        fill(&f)?;
    }
    std::fs::rename(&tmp, path).map_err(|e| hdf5::Error::from(e.to_string()))
}
