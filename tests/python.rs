//! The Python module's tests (python/tests/, pytest) in the environment
//! `scripts/install-deps.sh --test` makes and installs the module into (.venv-test/), against the
//! `slidestack` binary this build made.

mod common;

use std::path::Path;
use std::process::Command;

#[test]
fn python_module_tests_pass() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = common::test_python();
    let installed = Command::new(&python)
        .args(["-c", "import slidestack; print(slidestack.__version__)"])
        .output()
        .unwrap();
    assert!(
        installed.status.success(),
        "the slidestack module is not installed in .venv-test: run scripts/install-deps.sh \
         --test\n{}",
        String::from_utf8_lossy(&installed.stderr)
    );
    let o = Command::new(&python)
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "python/tests",
        ])
        .current_dir(root)
        .env("SLIDESTACK_BIN", env!("CARGO_BIN_EXE_slidestack"))
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    println!("{out}");
    assert!(
        o.status.success(),
        "pytest failed:\n{out}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains(" passed"), "pytest ran no test:\n{out}");
}
