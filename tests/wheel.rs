//! The wheel that `scripts/build-wheel` makes (`dist/slidestack-*.whl`, built and installed by
//! `scripts/install-deps.sh --test`) installs and works without Rust in every CPython >= 3.9 on
//! this machine (one interpreter per minor version, on PATH, under pyenv's versions,
//! /usr/local/bin and /usr/bin): in a fresh venv with the wheel, its `study` extra (xarray,
//! h5netcdf, h5py) and numpy from PyPI, with a PATH that holds no `cargo` nor `rustc`, the
//! module loads the HDF5 library bundled in the wheel; `simulate` of the Section 7.1 case
//! returns the JSON of this build's `slidestack simulate --json`; `spectrum` of a record is the
//! CLI's; `run` of configs/quick.yaml writes the CLI's stage files byte for byte and
//! `open_study` reads them.

mod common;

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The minor versions of CPython 3 looked for; the ones from `REPORTED` up are named when absent.
const MINORS: std::ops::RangeInclusive<u32> = 9..=15;
const REPORTED: std::ops::RangeInclusive<u32> = 9..=13;

/// The stage files of the quick study, compared byte for byte with the CLI's.
const STAGE_FILES: [&str; 5] = ["motions.h5", "sweep.h5", "tnew.h5", "fit.h5", "fit.yaml"];

const RECORD: &str = "tests/fixtures/records/RSN1111_KOBE_NIS000.AT2";
const PERIODS: &str = "0.1:2:0.1";

/// Run in each venv: prints one JSON object with what the checks compare with the CLI.
const SMOKE: &str = r#"
import json, math, os, shutil, sys
record, periods, config, out = sys.argv[1:5]
for tool in ("cargo", "rustc"):
    assert shutil.which(tool) is None, f"{tool} is on PATH: {shutil.which(tool)}"
import slidestack
# The module's HDF5 is the wheel's (slidestack.libs/), not the system's.
libs = os.path.join(os.path.dirname(os.path.dirname(slidestack.__file__)), "slidestack.libs")
with open("/proc/self/maps") as f:
    hdf5 = sorted({l.split()[-1] for l in f if "libhdf5" in l})
assert hdf5, "no libhdf5 mapped after import slidestack"
assert all(p.startswith(libs + os.sep) for p in hdf5), (libs, hdf5)
r = slidestack.simulate(period=1.0, alpha=[0.5, 0.5], mu=[0.2, 0.1])
assert math.isfinite(r["peak_displacement_m"]) and r["peak_displacement_m"] > 0, r
accel, dt = slidestack.read_record(record)
s = slidestack.spectrum(accel, dt, periods)
spectrum = {k: s[k].tolist() for k in ("periods_s", "sd_m", "psa_g")}
done = slidestack.run(config, out=out)
assert list(done) == ["motions", "sweep", "tnew", "fit", "report"], list(done)
assert all(d["outcome"] == "wrote" for d in done.values()), done
study = slidestack.open_study(out)
assert set(study) == {"motions", "sweep", "tnew", "fit"}, set(study)
tnew = study["tnew"]["III"]
assert list(tnew["T_new"].dims) == ["T_p", "alpha_1", "alpha_2", "mu_1", "mu_2"]
assert tnew["T_p"].values.tolist() == [0.3, 0.6, 1.0, 1.5, 2.0]
from importlib.metadata import version
print(json.dumps({
    "python": sys.version.split()[0],
    "packages": ", ".join(f"{p} {version(p)}" for p in ("numpy", "xarray", "h5netcdf", "h5py")),
    "module": slidestack.__file__,
    "hdf5": hdf5,
    "simulate": r,
    "spectrum": spectrum,
    "t_new_finite": int(sum(1 for x in tnew["T_new"].values.ravel() if math.isfinite(x))),
}))
"#;

/// One CPython found: its version and its executable.
struct Interpreter {
    version: String,
    exe: PathBuf,
}

/// Asks `candidate` what it is; a CPython 3.9+ gives its minor version, full version and
/// `sys.executable` (a pyenv shim answers for the interpreter it runs, or fails).
fn probe(candidate: &Path) -> Option<(u32, Interpreter)> {
    let o = Command::new(candidate)
        .args([
            "-c",
            "import platform, sys; print(platform.python_implementation(), \
             sys.version_info[0], sys.version_info[1], platform.python_version(), \
             sys.executable)",
        ])
        .output()
        .ok()?;
    if !o.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&o.stdout);
    let mut words = text.trim().splitn(5, ' ');
    let (imp, major, minor) = (words.next()?, words.next()?, words.next()?);
    let (version, exe) = (words.next()?, words.next()?);
    let minor: u32 = minor.parse().ok()?;
    (imp == "CPython" && major == "3" && minor >= 9 && !exe.is_empty()).then(|| {
        (
            minor,
            Interpreter {
                version: version.to_string(),
                exe: PathBuf::from(exe),
            },
        )
    })
}

/// The directories searched, in order: PATH, pyenv's versions, /usr/local/bin, /usr/bin.
fn search_dirs() -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).collect())
        .unwrap_or_default();
    let pyenv_root = Command::new("pyenv")
        .arg("root")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()));
    if let Some(root) = pyenv_root
        && let Ok(entries) = std::fs::read_dir(root.join("versions"))
    {
        let mut versions: Vec<PathBuf> = entries.flatten().map(|e| e.path().join("bin")).collect();
        versions.sort();
        dirs.extend(versions);
    }
    dirs.extend(["/usr/local/bin", "/usr/bin"].map(PathBuf::from));
    dirs
}

/// One CPython per minor version >= 3.9, the first found in [`search_dirs`] order.
fn interpreters() -> BTreeMap<u32, Interpreter> {
    let mut found = BTreeMap::new();
    for dir in search_dirs() {
        for minor in MINORS {
            let candidate = dir.join(format!("python3.{minor}"));
            if found.contains_key(&minor) || !candidate.is_file() {
                continue;
            }
            if let Some((m, interp)) = probe(&candidate) {
                found.entry(m).or_insert(interp);
            }
        }
    }
    found
}

/// The only `dist/slidestack-*.whl`; fails without one.
fn wheel(root: &Path) -> PathBuf {
    let wheels: Vec<PathBuf> = std::fs::read_dir(root.join("dist"))
        .map(|d| {
            d.flatten()
                .map(|e| e.path())
                .filter(|p| {
                    let name = p.file_name().unwrap().to_string_lossy().into_owned();
                    name.starts_with("slidestack-") && name.ends_with(".whl")
                })
                .collect()
        })
        .unwrap_or_default();
    assert!(
        !wheels.is_empty(),
        "no dist/slidestack-*.whl: run scripts/install-deps.sh --test"
    );
    assert_eq!(
        wheels.len(),
        1,
        "more than one wheel in dist/ ({wheels:?}): run scripts/install-deps.sh --test"
    );
    wheels.into_iter().next().unwrap()
}

/// `cmd` with an environment of its own: PATH `path`, and of this one only what pip needs to
/// reach PyPI and its cache (HOME, proxies, certificates, PIP_*), no CARGO_*, RUSTUP_*,
/// LD_LIBRARY_PATH nor PYTHON*.
fn clean_env<'a>(cmd: &'a mut Command, path: &OsString) -> &'a mut Command {
    cmd.env_clear().env("PATH", path);
    for (key, value) in std::env::vars_os() {
        let k = key.to_string_lossy().to_ascii_uppercase();
        let keep = matches!(
            k.as_str(),
            "HOME"
                | "USER"
                | "LANG"
                | "LC_ALL"
                | "TMPDIR"
                | "XDG_CACHE_HOME"
                | "HTTP_PROXY"
                | "HTTPS_PROXY"
                | "NO_PROXY"
                | "ALL_PROXY"
                | "SSL_CERT_FILE"
                | "SSL_CERT_DIR"
                | "REQUESTS_CA_BUNDLE"
        ) || k.starts_with("PIP_");
        if keep {
            cmd.env(key, value);
        }
    }
    cmd
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The CLI's answers the module's are compared with.
struct Expected {
    simulate: serde_json::Value,
    spectrum: serde_json::Value,
    study: PathBuf,
}

/// Installs the wheel into a fresh venv of `interp` and runs [`SMOKE`]; Err says what failed.
fn check(interp: &Interpreter, wheel: &Path, expected: &Expected) -> Result<String, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let name = format!("CPython {} ({})", interp.version, interp.exe.display());
    let tmp = tempfile::tempdir().unwrap();
    let venv = tmp.path().join("venv");
    let bin = venv.join("bin");
    let path =
        std::env::join_paths([bin.as_path(), Path::new("/usr/bin"), Path::new("/bin")]).unwrap();
    for dir in std::env::split_paths(&path) {
        for tool in ["cargo", "rustc"] {
            assert!(
                !dir.join(tool).exists(),
                "{tool} is in {}: the smoke test's PATH must hold no Rust toolchain",
                dir.display()
            );
        }
    }

    let has_venv = clean_env(&mut Command::new(&interp.exe), &path)
        .args(["-c", "import venv, ensurepip"])
        .output()
        .unwrap();
    if !has_venv.status.success() {
        return Err(format!(
            "{name} lacks the venv module or ensurepip, so it cannot make a venv with pip (on \
             Debian: apt-get install python3.X-venv):\n{}",
            text(&has_venv)
        ));
    }
    let made = clean_env(&mut Command::new(&interp.exe), &path)
        .args(["-m", "venv"])
        .arg(&venv)
        .output()
        .unwrap();
    if !made.status.success() {
        return Err(format!("{name}: python -m venv failed:\n{}", text(&made)));
    }
    let pip = clean_env(&mut Command::new(bin.join("python")), &path)
        .args([
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "--no-input",
            "--only-binary",
            ":all:",
        ])
        .arg(format!("{}[study]", wheel.display()))
        .arg("numpy")
        .output()
        .unwrap();
    if !pip.status.success() {
        return Err(format!(
            "{name}: pip install of the wheel with its `study` extra (xarray, h5netcdf, h5py) \
             and numpy failed:\n{}",
            text(&pip)
        ));
    }

    let out = tmp.path().join("quick");
    let smoke = clean_env(&mut Command::new(bin.join("python")), &path)
        .arg("-c")
        .arg(SMOKE)
        .arg(root.join(RECORD))
        .arg(PERIODS)
        .arg(root.join("configs/quick.yaml"))
        .arg(&out)
        .current_dir(tmp.path())
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .unwrap();
    if !smoke.status.success() {
        return Err(format!("{name}: the smoke test failed:\n{}", text(&smoke)));
    }
    let got: serde_json::Value = serde_json::from_slice(&smoke.stdout).map_err(|e| {
        format!(
            "{name}: the smoke test's output is not JSON ({e}):\n{}",
            text(&smoke)
        )
    })?;

    let mut wrong = Vec::new();
    if got["python"] != interp.version.as_str() {
        wrong.push(format!("ran Python {} in the venv", got["python"]));
    }
    let module = got["module"].as_str().unwrap_or_default();
    if !Path::new(module).starts_with(&venv) {
        wrong.push(format!(
            "imported slidestack from {module}, not from the venv"
        ));
    }
    if got["simulate"] != expected.simulate {
        wrong.push(format!(
            "simulate differs from `slidestack simulate --json`:\n  module {}\n  CLI    {}",
            got["simulate"], expected.simulate
        ));
    }
    for key in ["periods_s", "sd_m", "psa_g"] {
        if got["spectrum"][key] != expected.spectrum[key] {
            wrong.push(format!(
                "spectrum's {key} differs from `slidestack spectrum --json`"
            ));
        }
    }
    if got["t_new_finite"].as_u64().unwrap_or(0) == 0 {
        wrong.push("open_study: zone III's T_new holds no finite value".to_string());
    }
    for file in STAGE_FILES {
        let a = std::fs::read(out.join(file)).map_err(|e| format!("{name}: {file}: {e}"))?;
        if a != std::fs::read(expected.study.join(file)).unwrap() {
            wrong.push(format!(
                "run wrote a {file} that differs from `slidestack run`'s"
            ));
        }
    }
    if wrong.is_empty() {
        Ok(format!(
            "{name}: passed ({}; HDF5 from {})",
            got["packages"].as_str().unwrap_or("?"),
            got["hdf5"][0].as_str().unwrap_or("?")
        ))
    } else {
        Err(format!("{name}:\n  {}", wrong.join("\n  ")))
    }
}

#[test]
fn the_wheel_installs_and_works_without_rust_in_every_cpython_found() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let wheel = wheel(root);
    println!("wheel: {}", wheel.display());

    let found = interpreters();
    for (minor, interp) in &found {
        println!(
            "found CPython 3.{minor}: {} ({})",
            interp.version,
            interp.exe.display()
        );
    }
    let missing: Vec<String> = REPORTED
        .filter(|m| !found.contains_key(m))
        .map(|m| format!("3.{m}"))
        .collect();
    if !missing.is_empty() {
        println!("not found (not tested): CPython {}", missing.join(", "));
    }
    assert!(
        !found.is_empty(),
        "no CPython >= 3.9 found on PATH, under pyenv's versions, /usr/local/bin or /usr/bin"
    );

    let cli = |args: &[&str]| {
        let o = common::ok(common::slidestack(args, "2"));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    let simulate = cli(&[
        "simulate", "--period", "1.0", "--alpha", "0.5,0.5", "--mu", "0.2,0.1", "--json",
    ]);
    let record = root.join(RECORD);
    // One damping ratio: the CLI's list of one spectrum, the module's spectrum.
    let spectra = cli(&[
        "spectrum",
        "--record",
        record.to_str().unwrap(),
        "--periods",
        PERIODS,
        "--json",
    ]);
    let spectrum = match spectra.as_array().map(Vec::as_slice) {
        Some([one]) => one.clone(),
        _ => panic!("`slidestack spectrum --json` with one damping ratio printed {spectra}"),
    };
    let study = tempfile::tempdir().unwrap();
    let config = root.join("configs/quick.yaml");
    common::ok(common::slidestack(
        &[
            "run",
            config.to_str().unwrap(),
            "--out",
            study.path().to_str().unwrap(),
        ],
        "2",
    ));
    let expected = Expected {
        simulate,
        spectrum,
        study: study.path().to_path_buf(),
    };

    // One after another: each venv's install and quick study take both cores.
    let mut failures = Vec::new();
    for interp in found.values() {
        match check(interp, &wheel, &expected) {
            Ok(line) => println!("{line}"),
            Err(e) => {
                println!("FAILED {e}");
                failures.push(e);
            }
        }
    }
    assert!(
        failures.is_empty(),
        "the wheel failed in {} of {} CPythons:\n{}",
        failures.len(),
        found.len(),
        failures.join("\n")
    );
}
