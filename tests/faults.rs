//! The fault-injection suite: concurrent runs, a full disk, damaged and swapped files, stale
//! inputs, and inputs that used to hang, abort or be silently wrong. Each fault must end in one
//! clear message and a non-zero exit, lose nothing that existed, and a rerun must give the files
//! of a clean run bit for bit. `docs/faults.md` lists every fault with the test that proves it.
//!
//! Every child process runs under a wall-clock guard: a hang fails the test instead of the suite.

mod common;

use common::fixture;
use slidestack::pipeline::StageId;
use std::io::BufRead;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a run of the binary did.
#[derive(Debug)]
struct Ran {
    code: i32,
    stdout: String,
    stderr: String,
}

impl Ran {
    fn ok(self) -> Self {
        assert_eq!(self.code, 0, "{}{}", self.stdout, self.stderr);
        self
    }
    /// Failed with `code`, saying `text` on stderr exactly once.
    fn fails(self, code: i32, text: &str) -> Self {
        assert_eq!(self.code, code, "{}{}", self.stdout, self.stderr);
        assert_eq!(
            self.stderr.matches(text).count(),
            1,
            "`{text}` once in: {}",
            self.stderr
        );
        self
    }
}

#[derive(Clone, Copy)]
struct Opts {
    /// Largest file the process may write, bytes (`RLIMIT_FSIZE`): a full disk for it.
    file_size_limit: Option<u64>,
    guard: Duration,
}

/// A run's guard only turns a hang into a failure (it is no speed requirement): generous, so
/// that a loaded machine never trips it.
const PLAIN: Opts = Opts {
    file_size_limit: None,
    guard: Duration::from_secs(600),
};

/// A run expected to be refused at once (the same guard; the name says what is expected).
const QUICK: Opts = PLAIN;

fn spawn(args: &[&str], opts: Opts) -> std::process::Child {
    spawn_in(Path::new("."), args, opts)
}

/// As [`spawn`], the process held at `point` of the test hook (returned once it holds there).
fn spawn_held(args: &[&str], point: &str, dir: &Path) -> (std::process::Child, common::Held) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_slidestack"));
    cmd.args(args)
        .env("RAYON_NUM_THREADS", "2")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let held = common::Held::arm(&mut cmd, point, dir);
    let mut child = cmd.spawn().unwrap();
    held.wait(&mut child);
    (child, held)
}

/// As [`spawn`], with `cwd` as the working directory.
fn spawn_in(cwd: &Path, args: &[&str], opts: Opts) -> std::process::Child {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_slidestack"));
    cmd.current_dir(cwd)
        .args(args)
        .env("RAYON_NUM_THREADS", "2")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(limit) = opts.file_size_limit {
        // SAFETY: only async-signal-safe calls between fork and exec.
        unsafe {
            cmd.pre_exec(move || {
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                let rl = libc::rlimit {
                    rlim_cur: limit,
                    rlim_max: limit,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &rl) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    cmd.spawn().unwrap()
}

fn finish(mut child: std::process::Child, guard: Duration, what: &str) -> Ran {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > guard {
            child.kill().unwrap();
            panic!("`{what}` did not end within {guard:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let out = child.wait_with_output().unwrap();
    Ran {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

fn run(args: &[&str], opts: Opts) -> Ran {
    finish(spawn(args, opts), opts.guard, &args.join(" "))
}

/// A run from another working directory, as a user who is not in the config's folder.
fn run_in(cwd: &Path, args: &[&str], opts: Opts) -> Ran {
    finish(spawn_in(cwd, args, opts), opts.guard, &args.join(" "))
}

/// A small study on two real records, zone III, 24 work units of 12 cases.
fn study(dir: &Path, extra: &str) -> PathBuf {
    let cfg = dir.join("study.yaml");
    std::fs::write(
        &cfg,
        format!(
            "output_dir: {out}\nzones: [{{ name: III, target: \"is1893:zone=III,soil=I\" }}]\n\
             motions:\n  seeds:\n    records:\n      files: [{a}, {b}]\n\
             grid:\n  period_s: {{ from: 0.2, to: 2.4, step: 0.2 }}\n\
             \x20 alpha: [[0.5, 1.0], [0.5]]\n  mu: [[0.1, 0.3, 0.5], [0.05, 0.2]]\n{extra}",
            out = dir.join("out").display(),
            a = fixture("RSN829_CAPEMEND_RIO360.AT2").display(),
            b = fixture("RSN960_NORTHR_LOS270.AT2").display(),
        ),
    )
    .unwrap();
    cfg
}

/// Every file below `dir` with its bytes, by its path relative to `dir`, in order.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    (common::output_files(dir, &[]).into_iter())
        .map(|(p, f)| (p.display().to_string(), f.bytes))
        .collect()
}

fn assert_same_files(a: &Path, b: &Path) {
    let (fa, fb) = (files(a), files(b));
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&fa), names(&fb));
    for ((n, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(
            x == y,
            "{n} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// A clean full run of `cfg` into `out`.
fn clean_run(cfg: &Path, out: &Path) {
    run(&["run", s(cfg), "--out", s(out)], PLAIN).ok();
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let q = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &q);
        } else {
            std::fs::copy(&p, &q).unwrap();
        }
    }
}

#[test]
fn concurrent_runs_into_one_directory_wait_and_end_as_a_clean_run() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = study(dir.path(), "");
    let reference = dir.path().join("ref");
    clean_run(&cfg, &reference);

    // Two whole runs at once: the first holds the directory (held by the test hook just after
    // it took the lock), the second waits for it, saying so; released, both succeed and the
    // files are a clean run's.
    let out = dir.path().join("both");
    let args = ["run", s(&cfg), "--out", s(&out)];
    let (a, held) = spawn_held(&args, "session.locked", dir.path());
    let mut b = spawn(&args, PLAIN);
    let mut said = String::new();
    let mut lines = std::io::BufReader::new(b.stdout.take().unwrap()).lines();
    while !said.contains("waiting for PID") {
        said = lines
            .next()
            .expect("the second run waits, saying so")
            .unwrap();
    }
    held.release();
    let a = finish(a, PLAIN.guard, "run").ok();
    let rest: Vec<String> = lines.map(|l| l.unwrap()).collect();
    assert!(b.wait().unwrap().success(), "{said}\n{}", rest.join("\n"));
    assert!(!a.stdout.contains("waiting for PID"), "{}", a.stdout);
    assert_same_files(&reference, &out);

    // Without waiting, the second refuses and names the holder.
    let out2 = dir.path().join("nowait");
    let (first, held) = spawn_held(
        &["run", s(&cfg), "--out", s(&out2)],
        "session.locked",
        dir.path(),
    );
    run(&["tnew", s(&cfg), "--out", s(&out2), "--no-wait"], QUICK).fails(1, "is in use by PID");
    held.release();
    finish(first, PLAIN.guard, "run").ok();
    assert_same_files(&reference, &out2);

    // Ten rounds of two forced fits at once: every round leaves a fit that verifies and equals
    // the clean run's.
    for _ in 0..10 {
        let args = ["fit", s(&cfg), "--out", s(&out), "--force"];
        let (a, b) = (spawn(&args, PLAIN), spawn(&args, PLAIN));
        finish(a, PLAIN.guard, "fit").ok();
        finish(b, PLAIN.guard, "fit").ok();
        let r = run(&["report", s(&cfg), "--out", s(&out)], PLAIN).ok();
        assert!(r.stdout.contains("is up to date"), "{}", r.stdout);
    }
    assert_same_files(&reference, &out);
}

#[test]
fn a_full_disk_fails_naming_the_file_keeps_everything_and_a_rerun_is_clean() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = study(dir.path(), "");
    let reference = dir.path().join("ref");
    clean_run(&cfg, &reference);
    let out = dir.path().join("out");
    let full = |limit: u64| Opts {
        file_size_limit: Some(limit),
        ..PLAIN
    };

    // motions.h5 (hundreds of kB) cannot be written under 64 kB.
    run(&["motions", s(&cfg), "--out", s(&out)], full(64_000))
        .fails(1, "motions.h5: HDF5: H5Fflush(): unable to flush file's cached information: file write failed (File too large)");
    assert!(!out.join("motions.h5").exists());
    run(&["motions", s(&cfg), "--out", s(&out)], PLAIN).ok();

    // Units (about 1.5 kB each) fit, sweep.h5 does not: the sweep fails naming it and keeps
    // every unit, so the rerun only assembles.
    let r = run(&["sweep", s(&cfg), "--out", s(&out)], full(8_000));
    r.fails(1, "sweep.h5: HDF5:");
    let units = std::fs::read_dir(out.join("sweep.units")).unwrap().count();
    assert_eq!(units, 24);
    let r = run(&["sweep", s(&cfg), "--out", s(&out)], PLAIN).ok();
    assert!(
        r.stdout.contains("0 of 24 units to compute"),
        "{}",
        r.stdout
    );
    run(&["run", s(&cfg), "--out", s(&out)], PLAIN).ok();
    assert_same_files(&reference, &out);

    // A stage that fails on a full disk leaves the old files of a changed study as they were.
    let before = files(&out);
    let cfg2 = study(dir.path(), "  damping: 0.04\n");
    for stage in ["sweep", "tnew", "fit", "report"] {
        if stage != "sweep" {
            // The upstream stages of the changed study, written with space.
            let prev = match stage {
                "tnew" => "sweep",
                "fit" => "tnew",
                _ => "fit",
            };
            run(&[prev, s(&cfg2), "--out", s(&out)], PLAIN).ok();
        }
        let before = files(&out);
        let r = run(&[stage, s(&cfg2), "--out", s(&out)], full(1_000));
        assert_ne!(r.code, 0, "{stage}: {}", r.stdout);
        assert!(
            r.stderr.contains("File too large") || r.stderr.contains("HDF5"),
            "{stage}: {}",
            r.stderr
        );
        let after = files(&out);
        // Nothing that existed is lost or changed (units written before the failure may be
        // new).
        for (name, bytes) in &before {
            let now = after.iter().find(|f| &f.0 == name);
            assert!(
                now.is_some_and(|f| &f.1 == bytes),
                "{stage}: {name} changed"
            );
        }
        run(&[stage, s(&cfg2), "--out", s(&out)], PLAIN).ok();
    }
    drop(before);
    // motions.h5 rightly keeps the first config's hash (the damping does not touch it), so it is
    // the first reference's; everything else is the changed study's.
    let reference2 = dir.path().join("ref2");
    copy_dir(&reference, &reference2);
    run(&["run", s(&cfg2), "--out", s(&reference2)], PLAIN).ok();
    assert_same_files(&reference2, &out);

    // A time history on a full disk: an error naming the file, no file of zeros.
    let h = dir.path().join("h.h5");
    let r = run(
        &["simulate", "--history", s(&h), "--json"],
        Opts {
            file_size_limit: Some(2_000),
            guard: QUICK.guard,
        },
    );
    r.fails(1, "h.h5");
    assert!(!h.exists());
    let h = dir.path().join("h.csv");
    run(
        &["simulate", "--history", s(&h)],
        Opts {
            file_size_limit: Some(2_000),
            guard: QUICK.guard,
        },
    )
    .fails(1, "h.csv: cannot write: File too large");
    assert!(!h.exists());

    // A spectrum table on a full disk: an error naming the file, and the old table kept whole.
    let table = dir.path().join("spectrum.csv");
    std::fs::write(&table, "an earlier table\n").unwrap();
    run(
        &[
            "spectrum",
            "--record",
            s(&fixture("RSN960_NORTHR_LOS270.AT2")),
            "--periods",
            "log:0.05:5:400",
            "--csv",
            "--out",
            s(&table),
        ],
        Opts {
            file_size_limit: Some(2_000),
            guard: QUICK.guard,
        },
    )
    .fails(1, "spectrum.csv: cannot write: File too large");
    assert_eq!(
        std::fs::read_to_string(&table).unwrap(),
        "an earlier table\n"
    );
}

#[test]
fn a_real_small_file_system_fills_up_cleanly() {
    // A 256 kB tmpfs, where the test may mount one (root on Linux); elsewhere the rlimit test
    // above stands for it.
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("mnt");
    std::fs::create_dir(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=256k", "tmpfs", s(&mnt)])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|st| st.success());
    if !mounted {
        eprintln!("skipped: cannot mount a tmpfs here (needs root on Linux)");
        return;
    }
    let cfg = study(dir.path(), "");
    let out = mnt.join("out");
    let r = run(&["run", s(&cfg), "--out", s(&out)], PLAIN);
    // What the full file system left: no temporary, and a status that calls nothing damaged.
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    let status = run(&["status", s(&cfg), "--out", s(&out)], QUICK);
    let _ = Command::new("umount").arg(&mnt).status();
    // Two records' motions fit, sweep.h5 does not: the sweep says so and keeps its units.
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    let want = format!("{}: HDF5:", out.join("sweep.h5").display());
    assert!(
        r.stderr.contains(&want) && r.stderr.contains("(No space left on device)"),
        "{}",
        r.stderr
    );
    assert!(left.iter().all(|n| !n.ends_with(".tmp")), "{left:?}");
    assert!(left.contains(&"sweep.units".to_string()), "{left:?}");
    let status = status.ok().stdout;
    assert!(status.contains("sweep.h5             missing"), "{status}");
    assert!(
        status.contains("motions.h5           up to date"),
        "{status}"
    );
    assert!(!status.contains("damaged"), "{status}");
}

#[test]
fn damaged_swapped_and_stale_files_are_never_used() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = study(dir.path(), "");
    let c = s(&cfg);
    let reference = dir.path().join("ref");
    clean_run(&cfg, &reference);
    let out = dir.path().join("out");
    let o = s(&out);
    run(&["motions", c, "--out", o], PLAIN).ok();

    // Units from two shards; one damaged, two swapped: merge refuses naming them.
    for k in ["1/2", "2/2"] {
        run(&["sweep", c, "--out", o, "--shard", k], PLAIN).ok();
    }
    let units = out.join("sweep.units");
    let unit = units.join("III_000_003.unit");
    let good = std::fs::read(&unit).unwrap();
    let mut bad = good.clone();
    bad[good.len() / 2] ^= 0x10;
    std::fs::write(&unit, &bad).unwrap();
    run(&["merge", c, "--out", o], PLAIN).fails(1, "III_000_003.unit: fails its checksum");
    std::fs::write(&unit, &good).unwrap();
    let other = units.join("III_001_007.unit");
    let (x, y) = (
        std::fs::read(&unit).unwrap(),
        std::fs::read(&other).unwrap(),
    );
    std::fs::write(&unit, &y).unwrap();
    std::fs::write(&other, &x).unwrap();
    run(&["merge", c, "--out", o], PLAIN).fails(1, "holds unit (zone III, motion 2");
    // The sweep itself recomputes what it cannot trust.
    let r = run(&["sweep", c, "--out", o], PLAIN).ok();
    assert!(r.stderr.contains("computing it again"), "{}", r.stderr);
    assert!(
        r.stdout.contains("2 of 24 units to compute"),
        "{}",
        r.stdout
    );
    assert!(!units.exists());

    // A flipped byte in sweep.h5: tnew refuses naming it; sweep rebuilds it.
    let sweep = out.join("sweep.h5");
    let mut b = std::fs::read(&sweep).unwrap();
    let n = b.len();
    b[n / 2] ^= 1;
    std::fs::write(&sweep, &b).unwrap();
    run(&["tnew", c, "--out", o], PLAIN).fails(1, "sweep.h5: does not match its checksum in");
    let r = run(&["sweep", c, "--out", o], PLAIN).ok();
    assert!(r.stderr.contains("rebuilding it"), "{}", r.stderr);

    // fit.yaml cut to nothing, or replaced by another YAML: report refuses, fit rebuilds.
    run(&["run", c, "--out", o], PLAIN).ok();
    for text in ["", "zones: []\n"] {
        std::fs::write(out.join("fit.yaml"), text).unwrap();
        run(&["report", c, "--out", o, "--force"], PLAIN)
            .fails(1, "fit.yaml: does not match its checksum");
        run(&["fit", c, "--out", o], PLAIN).ok();
    }
    assert_same_files(&reference, &out);

    // A changed config, then the report alone: refused naming the stale file and the stage to
    // run; a stale figure never survives a rebuilt report.
    std::fs::write(out.join("report/stale.svg"), "<svg/>").unwrap();
    let cfg2 = study(dir.path(), "  damping: 0.04\n");
    run(&["report", s(&cfg2), "--out", o], PLAIN)
        .fails(2, "tnew.h5 was made from other inputs than");
    let r = run(&["report", s(&cfg2), "--out", o], PLAIN);
    assert!(r.stderr.contains("run `slidestack sweep"), "{}", r.stderr);
    run(&["run", s(&cfg2), "--out", o], PLAIN).ok();
    assert!(!out.join("report/stale.svg").exists());

    // Unit files left behind by a kill during cleanup are removed by the next sweep.
    std::fs::create_dir_all(&units).unwrap();
    std::fs::write(units.join("III_000_000.unit"), "left over").unwrap();
    let r = run(&["sweep", s(&cfg2), "--out", o], PLAIN).ok();
    assert!(r.stdout.contains("is up to date"));
    assert!(!units.exists());
}

/// A config with one key's line replaced, for the refusal tests.
fn config_with(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const BASE: &str = "zones: [{ name: III, target: \"is1893:zone=III,soil=I\" }]\n\
                    motions:\n  seeds:\n    stochastic: { count: 2, seed: 1 }\n";

#[test]
fn inputs_that_used_to_hang_abort_or_mislead_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out");
    let o = s(&out);
    let at2 = |name: &str, header: &str, values: &str| -> PathBuf {
        let p = d.join(name);
        std::fs::write(
            &p,
            format!("PEER\nx\nACCELERATION TIME SERIES IN UNITS OF G\n{header}\n{values}\n"),
        )
        .unwrap();
        p
    };
    // Records: absurd steps and sample counts, and a 100 kB token.
    for (header, want) in [
        (
            "NPTS= 2, DT= 1e-15 SEC",
            "time step dt = 1e-15 s is outside",
        ),
        (
            "NPTS= 2, DT= 1e-300 SEC",
            "time step dt = 1e-300 s is outside",
        ),
        (
            "NPTS= 2, DT= 1e300 SEC",
            "time step dt = 1e300 s is outside",
        ),
        (
            "NPTS= 1000000000000, DT= .01 SEC",
            "1000000000000.0 samples: a record may have at most 16777216",
        ),
        (
            "NPTS= 1e30, DT= .01 SEC",
            "1e30 samples: a record may have at most",
        ),
    ] {
        let p = at2("r.AT2", header, "0.1 0.2");
        run(&["simulate", "--record", s(&p)], QUICK).fails(2, want);
    }
    let token = "x".repeat(100_000);
    let p = at2("t.AT2", "NPTS= 2, DT= .01 SEC", &format!("0.1 {token}"));
    let r = run(&["simulate", "--record", s(&p)], QUICK).fails(2, "is not a number");
    assert!(r.stderr.len() < 300, "{} bytes echoed", r.stderr.len());
    run(&["simulate", "--record", s(d)], QUICK).fails(2, "Is a directory");

    // Systems: beyond double precision or the integrators' accurate range.
    for (args, code, want) in [
        (
            &["--alpha", "1e17", "--mu", "0.2"][..],
            2,
            "must be finite, > 0 and ≤ 10000, got 1e17",
        ),
        (
            &["--alpha", "1e9", "--mu", "0.2"][..],
            2,
            "≤ 10000, got 1000000000.0",
        ),
        (&["--period", "1e15"][..], 2, "period_s must be within"),
        (&["--period", "1e6"][..], 2, "period_s must be within"),
        (
            &["--period", "-1"][..],
            2,
            "period_s must be within 0.000001 … 10000 s, got -1.0",
        ),
        (
            &[
                "--integrator",
                "rk4",
                "--rk4-substeps",
                "1",
                "--period",
                "0.02",
            ][..],
            2,
            "use at least 2 sub-steps",
        ),
        (
            &["--integrator", "rk4", "--rk4-substeps", "1000000000"][..],
            2,
            "rk4 sub-steps per sample must be 1 … 100000",
        ),
    ] {
        let mut a = vec!["simulate"];
        a.extend_from_slice(args);
        run(&a, QUICK).fails(code, want);
    }
    // Allowed, but near the edge: a warning with the reason, then the answer.
    // (The longest period is no edge of the exact integrator: T_rigid = 1e6 s runs.)
    let r = run(
        &[
            "simulate",
            "--period",
            "10000",
            "--alpha",
            "5000",
            "5000",
            "--damping-basis",
            "structure",
            "--json",
        ],
        QUICK,
    )
    .ok();
    assert!(
        r.stderr.contains("more than ten times the record's"),
        "{}",
        r.stderr
    );

    // Spectra: absurd periods and counts.
    let rec = fixture("RSN960_NORTHR_LOS270.AT2");
    for (periods, want) in [
        ("1e-300", "period 1e-300 s is outside 0.001 … 10000 s"),
        ("log:0.1:1:10000000", "2 ≤ COUNT ≤ 100000"),
        ("0:1e12:1e-6", "values; at most 100000"),
    ] {
        run(
            &["spectrum", "--record", s(&rec), "--periods", periods],
            QUICK,
        )
        .fails(2, want);
    }

    // Configs: every limit refused before any work, naming the file and the key.
    let grid = |g: &str| format!("{BASE}grid:\n{g}");
    let cases: Vec<(String, &str)> = vec![
        (
            grid(
                "  period_s: { from: 0.1, to: 1e12, step: 1e-6 }\n  alpha: [[0.5]]\n  mu: [[0.1]]\n",
            ),
            "`grid.period_s`: range from 0.1 to 1000000000000 by 0.000001 has",
        ),
        (
            grid(&format!(
                "  period_s: [1]\n  alpha: [{}]\n  mu: [{}]\n",
                vec!["[0.1]"; 15].join(", "),
                vec!["[0.1]"; 15].join(", ")
            )),
            "`grid.alpha`: needs one list per block, 1 to 14 blocks",
        ),
        (
            grid(&format!(
                "  period_s: {{ from: 0.01, to: 10, step: 0.01 }}\n  alpha: [{a}]\n  mu: [{a}]\n",
                a = ["{ from: 0.01, to: 1, step: 0.01 }"; 6].join(", ")
            )),
            "case results (cases × motions × zones); at most 50000000",
        ),
        (
            grid(
                "  period_s: [1]\n  alpha: [[0.5], [0.5]]\n  mu: [[0.1], [0.1]]\n  aspect: [0.5]\n",
            ),
            "`grid.aspect`: needs one ratio per block: 2 blocks, 1 ratios",
        ),
        (
            grid(
                "  period_s: [1]\n  alpha: [[0.5], [0.5]]\n  mu: [[0.1], [0.1]]\n  aspect: [0.5, 0]\n",
            ),
            "`grid.aspect[1]`: 0 (width over height of block 2) must be finite and > 0",
        ),
        (
            grid("  period_s: [1]\n  alpha: [[0.5]]\n  mu: [[0.1]]\n  aspect: [.inf]\n"),
            "`grid.aspect[0]`: inf (width over height of block 1) must be finite and > 0",
        ),
        (
            format!("{BASE}  matching: {{ check_periods: 100000000 }}\n"),
            "matching setting `check_periods` = 100000000: must be 2 … 100000",
        ),
        (
            format!("output_dir: /\n{BASE}"),
            "`output_dir` `/` is the root of the file system",
        ),
        (
            format!("output_dir: ~/x\n{BASE}"),
            "`~` is not expanded here",
        ),
        (format!("output_dir: \"\"\n{BASE}"), "`output_dir` is empty"),
        (
            format!("{BASE}x: {}\n", "[".repeat(5000)),
            "levels deep; a config nests at most 32",
        ),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        let with_out = if text.starts_with("output_dir") {
            text.clone()
        } else {
            format!("output_dir: {o}\n{text}")
        };
        let cfg = config_with(d, &format!("c{i}.yaml"), &with_out);
        run(&["motions", s(&cfg)], QUICK).fails(2, want);
    }
    // A byte-order mark is not a mistake.
    let cfg = config_with(d, "bom.yaml", &format!("\u{feff}output_dir: {o}\n{BASE}"));
    let r = run(&["status", s(&cfg)], QUICK).ok();
    assert!(r.stdout.contains("motions"), "{}", r.stdout);
    // A directory given as a record file.
    let cfg = config_with(
        d,
        "dir.yaml",
        &format!(
            "output_dir: {o}\nzones: [{{ name: III, target: \"is1893:zone=III,soil=I\" }}]\n\
             motions:\n  seeds:\n    records: {{ files: [{}] }}\n",
            d.display()
        ),
    );
    run(&["motions", s(&cfg)], QUICK).fails(2, "is a directory, not a record file");
    // An output directory that cannot be made: refused before any matching.
    let blocker = d.join("a-file");
    std::fs::write(&blocker, "").unwrap();
    let cfg = config_with(
        d,
        "unwritable.yaml",
        &format!("output_dir: {}\n{BASE}", blocker.join("out").display()),
    );
    let r = run(&["motions", s(&cfg)], QUICK).fails(1, "cannot create it");
    assert!(!r.stdout.contains("matched"), "{}", r.stdout);
}

#[test]
fn an_error_and_its_cause_print_once() {
    let r = run(&["simulate", "--record", "/nonexistent.AT2"], QUICK)
        .fails(2, "No such file or directory");
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
}

/// A target table beside `cfg`'s folder: the IS 1893 zone III (soil I) spectrum times `factor`,
/// one row every 0.01 s from 0.01 to 6 s, values printed to six decimals.
fn write_table(path: &Path, factor: f64) {
    let code: slidestack::spectrum::TargetSpectrum = "is1893:zone=III,soil=I".parse().unwrap();
    let mut text = String::from("# period_s sa_g\n");
    for k in 1..=600 {
        let t = k as f64 / 100.0;
        text += &format!("{t:.2} {:.6}\n", factor * code.sa_g(t));
    }
    std::fs::write(path, text).unwrap();
}

/// The row of the table at `t` (s) as `write_table` printed it, read back as a number.
fn table_row(path: &Path, t: &str) -> f64 {
    let text = std::fs::read_to_string(path).unwrap();
    let row = text
        .lines()
        .find(|l| l.starts_with(&format!("{t} ")))
        .unwrap();
    row.split_whitespace().nth(1).unwrap().parse().unwrap()
}

fn design_sa_tp_g(study: &Path) -> f64 {
    let r = run(
        &[
            "design",
            "--study",
            s(study),
            "--zone",
            "III",
            "--period",
            "0.70",
            "--alpha",
            "0.5,0.5",
            "--mu",
            "0.3,0.2",
            "--json",
        ],
        QUICK,
    )
    .ok();
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    v["sa_tp_g"].as_f64().unwrap()
}

#[test]
fn a_target_table_is_found_beside_its_config_hashed_and_stored() {
    // The config names `table:zone3.txt` beside it and is run from `/`: the table is found like
    // the record files, relative to the config.
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("study");
    std::fs::create_dir(&folder).unwrap();
    let table = folder.join("zone3.txt");
    write_table(&table, 1.0);
    let text = std::fs::read_to_string(study(dir.path(), ""))
        .unwrap()
        .replace(
            "target: \"is1893:zone=III,soil=I\"",
            "target: \"table:zone3.txt\"",
        );
    let cfg = config_with(&folder, "study.yaml", &text);
    let out = dir.path().join("out");
    let root = Path::new("/");
    run_in(root, &["run", s(&cfg)], PLAIN).ok();
    let st = run_in(root, &["status", s(&cfg), "--format", "env"], QUICK).ok();
    assert!(st.stdout.contains("MOTIONS=up_to_date"), "{}", st.stdout);
    assert!(st.stdout.contains("REPORT=up_to_date"), "{}", st.stdout);
    // `design` answers from the spectrum the study used: the table's row at 0.70 s.
    let first = table_row(&table, "0.70");
    assert_eq!(design_sa_tp_g(&out), first);

    // New contents, same name: the motions stage (and all after it) is stale; `design` still
    // answers from the stored spectrum, also once the file is gone.
    write_table(&table, 1.1);
    let st = run_in(root, &["status", s(&cfg), "--format", "env"], QUICK).ok();
    assert!(st.stdout.contains("MOTIONS=stale"), "{}", st.stdout);
    run(&["report", s(&cfg)], QUICK).fails(2, "motions.h5 was made from other inputs than");
    assert_eq!(design_sa_tp_g(&out), first);
    let changed = std::fs::read(&table).unwrap();
    std::fs::remove_file(&table).unwrap();
    assert_eq!(design_sa_tp_g(&out), first);
    run_in(root, &["status", s(&cfg)], QUICK).fails(2, "`zones[0].target`:");

    // Back with the new contents, `run` rebuilds the motions and `design` follows them.
    std::fs::write(&table, &changed).unwrap();
    let r = run_in(root, &["run", s(&cfg)], PLAIN).ok();
    assert!(r.stdout.contains("motions: wrote"), "{}", r.stdout);
    let second = table_row(&table, "0.70");
    assert!((second / first - 1.1).abs() < 1e-5, "{second} vs {first}");
    assert_eq!(design_sa_tp_g(&out), second);
}

#[test]
fn a_record_that_changes_after_the_config_was_loaded_is_refused() {
    use slidestack::pipeline::lock::LockMode;
    use slidestack::pipeline::{Quiet, Session, StageOptions, Study, execute};
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.AT2");
    std::fs::copy(fixture("RSN829_CAPEMEND_RIO360.AT2"), &a).unwrap();
    let cfg = config_with(
        dir.path(),
        "study.yaml",
        &format!(
            "output_dir: {}\nzones: [{{ name: III, target: \"is1893:zone=III,soil=I\" }}]\n\
             motions:\n  seeds:\n    records: {{ files: [a.AT2] }}\n",
            dir.path().join("out").display()
        ),
    );
    let study = Study::load(&cfg, None).unwrap();
    // Another record under the same name between loading the config and reading the seeds.
    std::fs::copy(fixture("RSN960_NORTHR_LOS270.AT2"), &a).unwrap();
    let session = Session::open(study, LockMode::Exclusive, false, &Quiet).unwrap();
    let e = execute(&session, StageId::Motions, StageOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{}: changed after the study was loaded, while the stage ran: run it again",
            a.display()
        )
    );
    assert!(!session.study.path("motions.h5").exists());
}

#[test]
fn stage_files_of_other_shapes_are_refused_not_indexed() {
    use slidestack::store::units::{Stored, UnitId, read_unit, write_unit};
    let dir = tempfile::tempdir().unwrap();
    let cfg = study(dir.path(), "");
    let (c, out) = (s(&cfg), dir.path().join("out"));
    let o = s(&out);
    run(&["motions", c, "--out", o], PLAIN).ok();

    // A unit whose checksum holds but whose first column is one case short: merge refuses
    // naming it; the sweep computes it again.
    for k in ["1/2", "2/2"] {
        run(&["sweep", c, "--out", o, "--shard", k], PLAIN).ok();
    }
    let unit = out.join("sweep.units/III_000_003.unit");
    let bytes = std::fs::read(&unit).unwrap();
    let header = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
    let id: UnitId = serde_json::from_slice(&bytes[12..12 + header]).unwrap();
    let Stored::Valid(mut columns) = read_unit(&unit, &id).unwrap() else {
        panic!("a valid unit");
    };
    columns.f64s[0].pop();
    write_unit(&unit, &id, &columns).unwrap();
    run(&["merge", c, "--out", o], PLAIN).fails(
        1,
        "III_000_003.unit: columns has shape [11, 12, 12, 12, 12, 24, 24, 24, 24, 12, 12] \
         where its dimensions give [12, 12, 12, 12, 12, 24, 24, 24, 24, 12, 12]",
    );
    let r = run(&["sweep", c, "--out", o], PLAIN).ok();
    assert!(r.stderr.contains("computing it again"), "{}", r.stderr);
    assert!(
        r.stdout.contains("1 of 24 units to compute"),
        "{}",
        r.stdout
    );

    // sweep.h5 verifies, its slip_peak has another shape: tnew refuses instead of indexing it.
    common::reshape(&out.join("sweep.h5"), "zone_III/slip_peak");
    run(&["tnew", c, "--out", o], PLAIN).fails(1, "sweep.h5: zone_III/slip_peak has shape");

    // ida.h5 verifies, its fit_status has another shape: the fragility table is refused.
    let ida_cfg = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/ida-quick.yaml");
    let ida_out = dir.path().join("ida");
    let (ic, io) = (s(&ida_cfg), s(&ida_out));
    run(&["motions", ic, "--out", io], PLAIN).ok();
    run(&["ida", ic, "--out", io], PLAIN).ok();
    common::reshape(&ida_out.join("ida.h5"), "zone_III/fit_status");
    run(&["ida", ic, "--out", io], PLAIN).fails(1, "ida.h5: zone_III/fit_status has shape");
}

/// Runs `args` held at `point` of the test hook on one thread, sends SIGINT while it holds,
/// and returns how it ended.
fn interrupted_at(args: &[&str], point: &str, dir: &Path) -> Ran {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_slidestack"));
    cmd.args(args)
        .env("RAYON_NUM_THREADS", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let held = common::Held::arm(&mut cmd, point, dir);
    let mut child = cmd.spawn().unwrap();
    held.wait(&mut child);
    // SAFETY: a signal to our own child, which has not been waited for.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    finish(child, PLAIN.guard, args[0])
}

#[test]
fn ctrl_c_ends_a_stage_with_130_at_any_point_and_a_rerun_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = study(dir.path(), "");
    let out = dir.path().join("out");
    let units = || {
        std::fs::read_dir(out.join("sweep.units"))
            .map(|d| {
                d.filter(|e| {
                    e.as_ref()
                        .unwrap()
                        .path()
                        .extension()
                        .is_some_and(|x| x == "unit")
                })
                .count()
            })
            .unwrap_or(0)
    };

    // During the motions, before the second record is matched: nothing of the stage is kept.
    let r = interrupted_at(&["motions", s(&cfg)], "motions.record:2", dir.path());
    assert_eq!(r.code, 130, "{}", r.stderr);
    assert!(r.stderr.contains("motions: interrupted"), "{}", r.stderr);
    assert!(!out.join("motions.h5").exists());
    run(&["motions", s(&cfg)], PLAIN).ok();

    // During the units, after the second is stored: those two are kept, and the rerun computes
    // the rest.
    let r = interrupted_at(&["sweep", s(&cfg)], "sweep.unit:2", dir.path());
    assert_eq!(r.code, 130, "{}", r.stderr);
    assert!(r.stderr.contains("sweep: interrupted"), "{}", r.stderr);
    assert_eq!(units(), 2);
    assert!(!out.join("sweep.h5").exists());

    // Before the assembly: every unit kept, no sweep.h5; the rerun only assembles.
    let r = interrupted_at(&["sweep", s(&cfg)], "sweep.assemble", dir.path());
    assert_eq!(r.code, 130, "{}", r.stderr);
    assert!(!out.join("sweep.h5").exists());
    let r = run(&["sweep", s(&cfg)], PLAIN).ok();
    assert!(
        r.stdout.contains("0 of 24 units to compute"),
        "{}",
        r.stdout
    );

    // After the stage's file is written and verified: complete and correct, the interrupt
    // still reported.
    let r = interrupted_at(&["tnew", s(&cfg)], "stage.done", dir.path());
    assert_eq!(r.code, 130, "{}", r.stderr);
    let r = run(&["status", s(&cfg), "--format", "env"], PLAIN).ok();
    assert!(r.stdout.contains("TNEW=up_to_date"), "{}", r.stdout);
}

#[test]
fn every_kind_of_fault_has_its_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cfg = study(d, "");
    // Bad input: 2.
    run(&["simulate", "--period", "-1"], QUICK).fails(2, "period");
    run(
        &[
            "spectrum",
            "--record",
            s(&fixture("RSN68_SFERN_PEL090.AT2")),
            "--dt=-1",
        ],
        QUICK,
    )
    .fails(2, "--dt must be finite and > 0, got -1");
    // A missing file, named by the input or not yet written by an earlier stage: 2.
    run(&["simulate", "--record", "/nonexistent.AT2"], QUICK).fails(2, "No such file");
    run(&["tnew", s(&cfg)], QUICK).fails(2, "is missing: run `slidestack motions");
    // A damaged file: 1.
    run(&["motions", s(&cfg)], PLAIN).ok();
    let m = d.join("out/motions.h5");
    let mut bytes = std::fs::read(&m).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&m, bytes).unwrap();
    run(&["sweep", s(&cfg)], QUICK).fails(1, "does not match its checksum");
    // I/O: 1 (an output directory under a file).
    let blocker = d.join("a-file");
    std::fs::write(&blocker, "").unwrap();
    run(&["motions", s(&cfg), "--out", s(&blocker.join("o"))], QUICK).fails(1, "cannot create it");
    // A grid too small to fit a design equation: 2, before any work (`fit` is not configured).
    let one = d.join("one");
    std::fs::create_dir(&one).unwrap();
    let small = study(&one, "");
    let text = std::fs::read_to_string(&small)
        .unwrap()
        .replace("{ from: 0.2, to: 2.4, step: 0.2 }", "[1.0]")
        .replace("[[0.5, 1.0], [0.5]]", "[[0.5], [0.5]]")
        .replace("[[0.1, 0.3, 0.5], [0.05, 0.2]]", "[[0.1], [0.05]]");
    std::fs::write(&small, text).unwrap();
    run(&["fit", s(&small)], PLAIN).fails(2, "the grid gives 1");
    // A run that cannot produce its result: 1 (a record file changed while the stage ran).
    let changing = d.join("changing");
    std::fs::create_dir(&changing).unwrap();
    let record = changing.join("RSN829_CAPEMEND_RIO360.AT2");
    std::fs::copy(fixture("RSN829_CAPEMEND_RIO360.AT2"), &record).unwrap();
    let text = std::fs::read_to_string(study(&changing, ""))
        .unwrap()
        .replace(s(&fixture("RSN829_CAPEMEND_RIO360.AT2")), s(&record));
    let cfg_changing = changing.join("study.yaml");
    std::fs::write(&cfg_changing, text).unwrap();
    let (child, held) = spawn_held(&["motions", s(&cfg_changing)], "session.locked", &changing);
    let mut bytes = std::fs::read(&record).unwrap();
    bytes.extend_from_slice(b"\n");
    std::fs::write(&record, bytes).unwrap();
    held.release();
    finish(child, PLAIN.guard, "motions").fails(1, "changed after the study was loaded");
    // Interrupted: 130 (ctrl_c_ends_a_stage_with_130_at_any_point_and_a_rerun_resumes).
}

/// Records of extreme values, on one storey and on a building (three storeys, a stack on the
/// roof), with the exact integrator and RK4: every run ends with a result, a refusal before
/// any work (exit 2, a peak beyond `limits::MAX_PEAK_ACCEL_G` after scaling) or a clean error
/// (exit 1). A record of 1e160 g used to hang `simulate` (a certified search halving stretches
/// its overflowed bounds could not clear, 2^80 of them); the test ending is the proof, the guard
/// only turns a hang into a failure. The times are printed, not judged.
#[test]
fn extreme_record_values_end_with_a_result_or_a_clean_refusal() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let record = |name: &str, values: &dyn Fn(usize) -> f64| -> PathBuf {
        let p = d.join(format!("{name}.txt"));
        let mut text = String::from("# dt: 0.01\n");
        for k in 0..1000 {
            text += &format!("{:e}\n", values(k));
        }
        std::fs::write(&p, text).unwrap();
        p
    };
    let wave = |k: usize| (0.05 * k as f64).sin() * (-0.002 * k as f64).exp();
    let ordinary = |k: usize| 0.3 * wave(k);
    // (record, what it must do: Some(2) refused, None a result or a clean error)
    let mut records: Vec<(PathBuf, Option<i32>)> = Vec::new();
    for peak in [1e100, 1e160, 1e200, 1e300, 1.7e308] {
        records.push((
            record(&format!("peak{peak:e}"), &|k| peak * wave(k)),
            Some(2),
        ));
        let alternating = move |k: usize| if k.is_multiple_of(2) { peak } else { -peak };
        records.push((
            record(&format!("alternating{peak:e}"), &alternating),
            Some(2),
        ));
        let one = move |k: usize| if k == 400 { peak } else { ordinary(k) };
        records.push((record(&format!("one{peak:e}"), &one), Some(2)));
    }
    records.push((record("subnormal", &|_| 1e-310), None));
    records.push((
        record("subnormal_alternating", &|k| {
            if k.is_multiple_of(2) { 1e-310 } else { -1e-310 }
        }),
        None,
    ));
    // Inside the limit: up to it, and an ordinary record at the largest scale.
    records.push((record("at_the_limit", &|k| 1e6 * wave(k)), None));
    records.push((
        record("alternating_at_the_limit", &|k| {
            if k.is_multiple_of(2) { 9e5 } else { -9e5 }
        }),
        None,
    ));
    let case = d.join("building.yaml");
    std::fs::write(
        &case,
        "building: {storeys: 3, period: 0.6}\n\
         stacks:\n  - {floor: 3, alpha: [0.5, 0.5], mu: [0.2, 0.1]}\n",
    )
    .unwrap();
    let ord = record("ordinary", &ordinary);
    let mut runs = 0;
    for (rec, want) in &records {
        for structure in [&[][..], &["--config", s(&case)][..]] {
            for integrator in ["exact", "rk4"] {
                let mut args = vec!["simulate", "--record", s(rec), "--integrator", integrator];
                args.extend_from_slice(structure);
                let start = Instant::now();
                let r = run(&args, PLAIN);
                eprintln!(
                    "{:.3} s, exit {}: {}",
                    start.elapsed().as_secs_f64(),
                    r.code,
                    args.join(" ")
                );
                match want {
                    Some(code) => {
                        r.fails(*code, "beyond the 1e6 g a simulation takes");
                    }
                    None => {
                        assert!(
                            r.code == 0 || r.code == 1 && r.stderr.starts_with("error: "),
                            "{}: exit {}: {}",
                            args.join(" "),
                            r.code,
                            r.stderr
                        );
                        assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
                    }
                }
                runs += 1;
            }
        }
    }
    // The largest scale on an ordinary record (0.28 g) runs; on a record of 2.8 g it is refused.
    run(&["simulate", "--record", s(&ord), "--scale", "1e6"], PLAIN).ok();
    let strong = record("strong", &|k| 10.0 * ordinary(k));
    run(
        &["simulate", "--record", s(&strong), "--scale", "1e6"],
        PLAIN,
    )
    .fails(2, "times --scale 1000000 that is 2.8");
    assert_eq!(runs, records.len() * 4);
}

/// Ctrl-C during `simulate` (held by the test hook after 128 samples of a six-storey building
/// with a stack on every floor; the watch is asked every 64 samples): exit 130, naming the
/// sample it stopped at.
#[test]
fn ctrl_c_stops_a_simulation_within_a_few_samples() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.yaml");
    let stacks: String = (1..=6)
        .map(|j| format!("  - {{ floor: {j}, alpha: [0.5, 0.5], mu: [0.2, 0.1] }}\n"))
        .collect();
    std::fs::write(
        &case,
        format!("building: {{ storeys: 6, period: 1.0 }}\nstacks:\n{stacks}"),
    )
    .unwrap();
    let r = interrupted_at(
        &["simulate", "--config", s(&case)],
        "simulate.samples:3",
        dir.path(),
    );
    assert_eq!(r.code, 130, "{}", r.stderr);
    assert!(
        r.stderr.contains("stopped at sample 128 of"),
        "{}",
        r.stderr
    );
}

/// A case within the limits that runs long says so before it runs (on standard error, with
/// its estimate), draws no bar on a pipe, and stops on Ctrl-C: sixty storeys with a two-block
/// stack on every floor, held by the test hook at its first watch.
#[test]
fn a_long_case_says_its_estimate_and_draws_no_bar_on_a_pipe() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("case.yaml");
    let stacks: String = (1..=60)
        .map(|j| format!("  - {{ floor: {j}, alpha: [0.1, 0.1], mu: [0.2, 0.1] }}\n"))
        .collect();
    std::fs::write(
        &case,
        format!("building: {{ storeys: 60, period: 2.0 }}\nstacks:\n{stacks}"),
    )
    .unwrap();
    let r = interrupted_at(
        &["simulate", "--config", s(&case), "--scale", "2"],
        "simulate.samples:1",
        dir.path(),
    );
    assert_eq!(r.code, 130, "{}", r.stderr);
    assert!(
        r.stderr.contains("simulate: this case takes about"),
        "{}",
        r.stderr
    );
    assert!(!r.stderr.contains("samples, ETA"), "{}", r.stderr);
}
