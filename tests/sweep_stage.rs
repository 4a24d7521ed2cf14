//! The sweep stage end to end: resume after a real `kill -9`, identical files whatever the
//! thread count or shard split, xarray reading the result, refused input.

mod common;

use common::{ok, slidestack};

use common::fixture;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A study on two real records, zone III, 24 units of 12 cases.
fn config(dir: &Path) -> PathBuf {
    let cfg = dir.join("study.yaml");
    std::fs::write(
        &cfg,
        format!(
            "output_dir: {out}\nzones: [{{ name: III, target: \"is1893:zone=III,soil=I\" }}]\n\
             motions:\n  seeds:\n    records:\n      files: [{a}, {b}]\n\
             grid:\n  period_s: {{ from: 0.2, to: 2.4, step: 0.2 }}\n\
             \x20 alpha: [[0.5, 1.0], [0.5]]\n  mu: [[0.1, 0.3, 0.5], [0.05, 0.2]]\n",
            out = dir.join("out").display(),
            a = fixture("RSN829_CAPEMEND_RIO360.AT2").display(),
            b = fixture("RSN960_NORTHR_LOS270.AT2").display(),
        ),
    )
    .unwrap();
    cfg
}

#[test]
fn resume_after_kill_gives_the_same_file_and_shards_and_threads_too() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(dir.path());
    let cfg_s = cfg.to_str().unwrap();
    let out = dir.path().join("out");
    ok(slidestack(&["motions", cfg_s], "2"));

    // Reference: one uninterrupted run on two threads.
    let reference = dir.path().join("ref");
    common::copy_motions(&out, &reference);
    ok(slidestack(
        &["sweep", cfg_s, "--out", reference.to_str().unwrap()],
        "2",
    ));
    let want = std::fs::read(reference.join("sweep.h5")).unwrap();

    // Killed with SIGKILL once some units are on disk, then resumed.
    let killed = dir.path().join("killed");
    common::copy_motions(&out, &killed);
    // Held after its third unit is stored: exactly three are on disk at the kill.
    common::kill_at(
        &["sweep", cfg_s, "--out", killed.to_str().unwrap()],
        "sweep.unit:3",
        dir.path(),
    );
    let units = killed.join("sweep.units");
    let count = || {
        std::fs::read_dir(&units)
            .map(|d| {
                d.filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "unit"))
                })
                .count()
            })
            .unwrap_or(0)
    };
    let done_before = count();
    assert_eq!(done_before, 3, "{done_before} units before the kill");
    assert!(!killed.join("sweep.h5").exists());
    let o = ok(slidestack(
        &["sweep", cfg_s, "--out", killed.to_str().unwrap()],
        "2",
    ));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!("{} already done", done_before)),
        "{text}"
    );
    assert_eq!(std::fs::read(killed.join("sweep.h5")).unwrap(), want);

    // Three shards on one thread each, then merge.
    let sharded = dir.path().join("sharded");
    common::copy_motions(&out, &sharded);
    let s = sharded.to_str().unwrap();
    for k in ["1/3", "3/3"] {
        ok(slidestack(&["sweep", cfg_s, "--out", s, "--shard", k], "1"));
    }
    let o = slidestack(&["merge", cfg_s, "--out", s], "1");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("units are missing"));
    ok(slidestack(
        &["sweep", cfg_s, "--out", s, "--shard", "2/3"],
        "1",
    ));
    ok(slidestack(&["merge", cfg_s, "--out", s], "1"));
    assert_eq!(std::fs::read(sharded.join("sweep.h5")).unwrap(), want);

    // Up to date: nothing is redone.
    let o = ok(slidestack(&["sweep", cfg_s, "--out", s], "2"));
    assert!(String::from_utf8_lossy(&o.stdout).contains("is up to date"));

    // tnew: no slip gives T_new = T_rigid; DRR_1 = 1 there.
    ok(slidestack(&["tnew", cfg_s, "--out", s], "2"));
    let o = ok(slidestack(&["tnew", cfg_s, "--out", s], "2"));
    assert!(String::from_utf8_lossy(&o.stdout).contains("is up to date"));

    // xarray opens the group with its named dimensions (Python environment made by
    // scripts/install-deps.sh).
    let python = common::test_python();
    let script = "import sys, xarray as xr\n\
        ds = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_III')\n\
        print(list(ds['u_stack'].dims), list(ds['slip_peak'].dims))\n\
        print(list(ds['block_accel_stack'].dims)[-1], ds['block_accel_stack'].attrs['units'], \
              ds['slip_residual'].attrs['units'], int(ds['block_velocity_stack'].isnull().sum()))\n\
        print(ds['T_p'].attrs['units'], ds['u_stack'].attrs['units'], float(ds['mu_1'][1]))\n\
        print(int(ds['u_stack'].isnull().sum()))\n\
        t = xr.open_dataset(sys.argv[2], engine='h5netcdf', group='zone_III')\n\
        print(list(t['T_new'].dims))\n\
        ns = t['T_new_flag'] == 3\n\
        print(bool(ns.any()), bool((t['T_new'] == t['T_rigid']).where(ns, True).all()),\n\
              bool((t['DRR_1'] == 1).where(ns, True).all()))\n";
    let o = Command::new(python)
        .args([
            "-c",
            script,
            sharded.join("sweep.h5").to_str().unwrap(),
            sharded.join("tnew.h5").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        text,
        "['motion', 'T_p', 'alpha_1', 'alpha_2', 'mu_1', 'mu_2'] \
         ['motion', 'T_p', 'alpha_1', 'alpha_2', 'mu_1', 'mu_2', 'interface']\nblock g m 0\n\
         s m 0.3\n0\n\
         ['T_p', 'alpha_1', 'alpha_2', 'mu_1', 'mu_2']\nTrue True True\n"
    );
}

#[test]
fn sweep_refuses_what_it_cannot_do() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(dir.path());
    let cfg_s = cfg.to_str().unwrap();
    let o = slidestack(&["sweep", cfg_s], "1");
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr)
            .contains("motions.h5 is missing: run `slidestack motions"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = slidestack(&["sweep", cfg_s, "--shard", "4/3"], "1");
    assert!(String::from_utf8_lossy(&o.stderr).contains("needs 1 ≤ K ≤ N"));
    let text = std::fs::read_to_string(&cfg).unwrap();
    std::fs::write(
        &cfg,
        text.replace("[0.5, 1.0], [0.5]", "[0.5, -1.0], [0.5]"),
    )
    .unwrap();
    let o = slidestack(&["sweep", cfg_s], "1");
    assert!(
        String::from_utf8_lossy(&o.stderr)
            .contains("`grid.alpha[0]`: value -1.0 must be finite, > 0 and ≤ 10000"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn run_does_the_whole_quick_study_and_ends_with_the_report_path() {
    // The README's first command, into a temporary directory.
    let dir = tempfile::tempdir().unwrap();
    let cfg = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quick.yaml");
    let out = dir.path().join("quick");
    let o = ok(slidestack(
        &["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()],
        "2",
    ));
    let text = String::from_utf8_lossy(&o.stdout);
    let last = text.lines().last().unwrap();
    assert_eq!(Path::new(last), out.join("report/index.html"));
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    for part in [
        "spectra_III.svg",
        "history_V.svg",
        "tnew_III.svg",
        "residuals_V.svg",
        "Table 3",
    ] {
        assert!(html.contains(part), "{part}");
    }
    let fit = std::fs::read_to_string(out.join("fit.yaml")).unwrap();
    assert!(fit.contains("cross_validated") && fit.contains("form: bounded"));
    // A second run finds every stage up to date.
    let o = ok(slidestack(
        &["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()],
        "2",
    ));
    let text = String::from_utf8_lossy(&o.stdout);
    for stage in ["motions", "sweep", "tnew", "fit"] {
        let up = text
            .lines()
            .any(|l| l.starts_with(&format!("{stage}: ")) && l.ends_with("is up to date"));
        assert!(up, "{stage}: {text}");
    }
}
