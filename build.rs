//! Links the HDF5 high-level library (`libhdf5_hl`), whose dimension-scale functions
//! (`H5DSset_scale`, `H5DSattach_scale`) label the sweep's dimensions for netCDF readers such as
//! xarray. `hdf5-metno-sys` links `libhdf5` itself; the high-level library sits beside it.

use std::process::Command;

fn main() {
    println!("cargo:rerun-if-env-changed=HDF5_DIR");
    let mut dirs = Vec::new();
    if let Ok(dir) = std::env::var("HDF5_DIR") {
        dirs.push(format!("{dir}/lib"));
    }
    if let Ok(out) = Command::new("pkg-config")
        .args(["--variable=libdir", "hdf5"])
        .output()
        && out.status.success()
    {
        let dir = String::from_utf8_lossy(&out.stdout).trim().to_string();
        if !dir.is_empty() {
            dirs.push(dir);
        }
    }
    for dir in &dirs {
        println!("cargo:rustc-link-search=native={dir}");
    }
    // Debian names it libhdf5_serial_hl in the multiarch directory and libhdf5_hl beside
    // libhdf5 in the serial directory; prefer the one next to the libhdf5 pkg-config found.
    let beside = dirs
        .iter()
        .any(|d| std::path::Path::new(d).join("libhdf5_hl.so").exists());
    if beside || dirs.is_empty() {
        println!("cargo:rustc-link-lib=dylib=hdf5_hl");
    } else {
        println!("cargo:rustc-link-lib=dylib=hdf5_serial_hl");
    }
}
