//! Record files end to end: units and time-step declarations, refused files (exact messages with
//! file and line), the bit-identical `.AT2` round trip, and processing of the real fixtures.

mod common;

use common::{Rng, fixture, real_records};
use slidestack::ground_motion::process::{BaselineCorrection, drift, refine};
use slidestack::ground_motion::{
    ReadOptions, Record, RecordError, Units, checked_at2, format_at2, read_record, read_record_with,
};
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn err(path: &Path, opts: &ReadOptions) -> String {
    read_record_with(path, opts).unwrap_err().to_string()
}

const NONE: ReadOptions = ReadOptions {
    units: None,
    dt_s: None,
};

/// Every malformed file is refused with a message naming the file and the 1-based line.
#[test]
fn malformed_files_name_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let at2_head = |line3: &str| format!("PEER NGA STRONG MOTION DATABASE RECORD\nx\n{line3}\n");
    let cases: Vec<(PathBuf, ReadOptions, String)> = vec![
        // Units: file against options, text and AT2.
        (
            write(d, "conflict.txt", "# units: cm/s2\n# dt: 0.01\n1\n2\n"),
            ReadOptions {
                units: Some(Units::Mps2),
                dt_s: None,
            },
            "1: the file says units cm/s2 but m/s2 was given".into(),
        ),
        (
            write(
                d,
                "conflict.AT2",
                &format!(
                    "{}NPTS=  2, DT= .01 SEC\n 1.0 2.0\n",
                    at2_head("ACCELERATION TIME SERIES IN UNITS OF CM/S/S")
                ),
            ),
            ReadOptions {
                units: Some(Units::G),
                dt_s: None,
            },
            "3: the file says units cm/s2 but g was given".into(),
        ),
        // Time step: file against options.
        (
            write(d, "dt.txt", "# dt: 0.01\n1\n2\n"),
            ReadOptions {
                units: None,
                dt_s: Some(0.02),
            },
            "1: the file says dt = 0.01 s but dt = 0.02 s was given".into(),
        ),
        // Single column without a step.
        (
            write(d, "single.txt", "# units: g\n\n0.1\n0.2\n"),
            NONE,
            "3: single-column record needs a time step: add `# dt: <s>` to the file or give dt"
                .into(),
        ),
        // Non-uniform two-column step.
        (
            write(d, "uneven.txt", "0 0\n0.5 0.1\n1.0 0.2\n2.0 0.1\n"),
            NONE,
            "4: time step 1 s differs from the first step 0.5 s (non-uniform sampling)".into(),
        ),
        // Non-finite values, plain text and AT2.
        (
            write(d, "nan.txt", "0 0.1\n0.01 nan\n"),
            NONE,
            "2: value NaN is not finite".into(),
        ),
        (
            write(
                d,
                "inf.AT2",
                &format!(
                    "{}NPTS=  3, DT= .01 SEC\n 0.1 0.2\n -inf\n",
                    at2_head("ACCELERATION TIME SERIES IN UNITS OF G")
                ),
            ),
            NONE,
            "6: value -inf is not finite".into(),
        ),
        // Wrong count: too few and too many.
        (
            write(
                d,
                "few.AT2",
                &format!(
                    "{}NPTS=  5, DT= .01 SEC\n 0.1 0.2\n 0.3\n\n",
                    at2_head("ACCELERATION TIME SERIES IN UNITS OF G")
                ),
            ),
            NONE,
            "6: header says NPTS = 5 but the file has 3 values".into(),
        ),
        (
            write(
                d,
                "many.AT2",
                &format!(
                    "{}NPTS=  2, DT= .01 SEC\n 0.1 0.2\n 0.3\n",
                    at2_head("ACCELERATION TIME SERIES IN UNITS OF G")
                ),
            ),
            NONE,
            "6: header says NPTS = 2 but the file has 3 values".into(),
        ),
        // Unknown units, plain text and AT2.
        (
            write(d, "ft.txt", "# dt: 0.01\n# units: ft/s2\n1\n2\n"),
            NONE,
            "2: unknown acceleration unit `ft/s2`: expected g, m/s2 (or m/s^2), cm/s2 (or \
             cm/s^2, gal)"
                .into(),
        ),
        (
            write(
                d,
                "ft.AT2",
                &format!(
                    "{}NPTS=  2, DT= .01 SEC\n 1.0 2.0\n",
                    at2_head("ACCELERATION TIME SERIES IN UNITS OF IN/S/S")
                ),
            ),
            NONE,
            "3: unknown acceleration unit `IN/S/S`: expected g, m/s2 (or m/s^2), cm/s2 (or \
             cm/s^2, gal)"
                .into(),
        ),
        // Mixed layouts.
        (
            write(d, "mixed.txt", "0 0.1\n0.01 0.2\n0.3\n"),
            NONE,
            "3: expected 2 columns (time, acceleration in g), found 1".into(),
        ),
    ];
    for (path, opts, tail) in cases {
        assert_eq!(
            err(&path, &opts),
            format!("{}:{tail}", path.display()),
            "{}",
            path.display()
        );
    }
}

/// The same motion written in cm/s² (single column, declared step), in m/s² (two columns) and in
/// cm/s² with the units given as an option reads back equal in g. Tolerance 1e-15 relative: each
/// path rounds the decimal, the factor (1/g or 1/(100·g)) and the product, at most 2 ulp apart.
#[test]
fn cm_and_m_per_s2_read_back_equal_in_g() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng::new(7);
    let ints: Vec<i64> = (0..3000)
        .map(|_| rng.below(2_000_001) as i64 - 1_000_000)
        .collect();
    // The value k·1e-3 cm/s² is k·1e-5 m/s²; the decimal strings are exact in both.
    let mut cm = String::from("# record in cm/s^2\n# units: cm/s^2\n# dt: 0.01\n");
    let mut cm_bare = String::new();
    let mut m = String::from("# units: m/s2\n");
    for (k, i) in ints.iter().enumerate() {
        cm.push_str(&format!("{i}e-3\n"));
        cm_bare.push_str(&format!("{i}e-3\n"));
        m.push_str(&format!("{} {i}e-5\n", k as f64 * 0.01));
    }
    let a = read_record(&write(dir.path(), "cm.txt", &cm)).unwrap();
    let b = read_record(&write(dir.path(), "m.txt", &m)).unwrap();
    let c = read_record_with(
        &write(dir.path(), "bare.txt", &cm_bare),
        &ReadOptions {
            units: Some(Units::Cmps2),
            dt_s: Some(0.01),
        },
    )
    .unwrap();
    assert_eq!(a.accel_g.len(), ints.len());
    assert_eq!(a.dt_s, 0.01);
    assert!((b.dt_s - 0.01).abs() < 1e-17);
    assert_eq!(c.accel_g, a.accel_g);
    let mut worst: f64 = 0.0;
    for (x, y) in a.accel_g.iter().zip(&b.accel_g) {
        assert!((x - y).abs() <= 1e-15 * y.abs(), "{x:e} vs {y:e}");
        if *y != 0.0 {
            worst = worst.max((x - y).abs() / y.abs());
        }
    }
    assert!(worst < 1e-15, "{worst}");
    // And the same values in g, to the same tolerance.
    let g = 9.80665;
    for (x, i) in a.accel_g.iter().zip(&ints) {
        let expected = *i as f64 * 1e-5 / g;
        assert!((x - expected).abs() <= 1e-15 * expected.abs());
    }
}

fn assert_same_bits(a: &Record, b: &Record) {
    assert_eq!(a.dt_s.to_bits(), b.dt_s.to_bits());
    assert_eq!(a.accel_g.len(), b.accel_g.len());
    for (k, (x, y)) in a.accel_g.iter().zip(&b.accel_g).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "sample {k}: {x:e} vs {y:e}");
    }
}

/// `checked_at2` then a checked atomic write, as `slidestack match` writes its records.
fn write_at2(r: &Record, description: &str, path: &std::path::Path) -> Result<(), RecordError> {
    let text = checked_at2(r, description, &path.display().to_string())?;
    slidestack::store::atomic::write_bytes(path, text.as_bytes()).expect("writable temp dir");
    Ok(())
}

/// Fixtures written with `write_at2` read back bit-identical, and carry the same digits as the
/// PEER originals (which have 8 significant digits, so the writer uses PEER's `%.7E` form).
#[test]
fn at2_round_trip_on_fixtures_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "RSN829_CAPEMEND_RIO360.AT2",
        "RSN960_NORTHR_LOS270.AT2",
        "RSN1633_MANJIL_ABBAR--L.AT2",
    ] {
        let original = read_record(&fixture(name)).unwrap();
        let out = dir.path().join(name);
        write_at2(&original, &format!("copy of {name}"), &out).unwrap();
        let back = read_record(&out).unwrap();
        assert_same_bits(&back, &original);
        let tokens = |p: &Path| -> Vec<String> {
            std::fs::read_to_string(p)
                .unwrap()
                .lines()
                .skip(4)
                .flat_map(|l| l.split_whitespace().map(str::to_string).collect::<Vec<_>>())
                .collect()
        };
        assert_eq!(tokens(&out), tokens(&fixture(name)), "{name}");
    }
}

/// Random values (arbitrary bit patterns, and typical magnitudes) through a file.
#[test]
fn at2_round_trip_on_random_values_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng::new(2024);
    let mut accel_g = Vec::new();
    while accel_g.len() < 5000 {
        let v = f64::from_bits(rng.next_u64());
        if v.is_finite() {
            accel_g.push(v);
        }
        accel_g.push(rng.normal() * 0.3);
    }
    let r = Record {
        name: "random.AT2".into(),
        dt_s: 0.1 + 0.2,
        accel_g,
    };
    let out = dir.path().join("random.AT2");
    write_at2(&r, "random values", &out).unwrap();
    assert_same_bits(&read_record(&out).unwrap(), &r);
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        format_at2(&r, "random values")
    );
}

#[test]
fn write_at2_refuses_what_it_cannot_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad.AT2");
    let mut r = Record {
        name: "bad".into(),
        dt_s: 0.01,
        accel_g: vec![0.0; 12],
    };
    r.accel_g[11] = f64::INFINITY;
    assert_eq!(
        write_at2(&r, "x", &out).unwrap_err().to_string(),
        format!("{}:7: value inf is not finite", out.display())
    );
    r.accel_g[11] = 0.0;
    r.dt_s = 0.0;
    assert_eq!(
        write_at2(&r, "x", &out).unwrap_err().to_string(),
        format!(
            "{}:4: time step dt = 0.0 s is outside 0.00001 … 1 s (a unit or header mistake?)",
            out.display()
        )
    );
    assert!(!out.exists());
}

/// Peak |velocity| (m/s) and |displacement| (m) from rest, by the same exact rules: the scale of
/// the roundoff in the final values.
fn peaks(accel_g: &[f64], dt: f64) -> (f64, f64) {
    let g = 9.80665;
    let (mut v, mut d, mut pv, mut pd) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    for w in accel_g.windows(2) {
        d += v * dt + dt * dt * (2.0 * w[0] + w[1]) / 6.0;
        v += dt * (w[0] + w[1]) / 2.0;
        pv = pv.max(v.abs());
        pd = pd.max(d.abs());
    }
    (pv * g, pd * g)
}

/// Refinement is the same piecewise-linear motion: the exact integrals agree to roundoff. The
/// fixtures are processed records that end nearly at rest (final displacement 1e-4 of the peak), so
/// the tolerance is 1e-12 of the peak velocity and displacement, the scale of the values the
/// roundoff accumulates on over ~10⁴ steps (observed ≤ 9e-14).
#[test]
fn refined_fixtures_have_the_same_drift() {
    for r in real_records() {
        let (v0, d0) = drift(&r.accel_g, r.dt_s);
        let (pv, pd) = peaks(&r.accel_g, r.dt_s);
        let f = refine(&r, 5);
        let (v, d) = drift(&f.accel_g, f.dt_s);
        assert!((v - v0).abs() < 1e-12 * pv, "{}: v {v} vs {v0}", r.name);
        assert!((d - d0).abs() < 1e-12 * pd, "{}: d {d} vs {d0}", r.name);
    }
}

/// The fixtures are PEER-processed, already baseline-corrected records, so a typical
/// uncorrected-record error is added: a constant 0.002 g offset (metres of drift), or a 0.002 g
/// baseline step a third of the way in (not a polynomial, so not removed exactly). A quadratic
/// baseline (poly:2) brings the final displacement down to under 1 % (offset; observed ≤ 7e-4)
/// and 5 % (step; observed ≤ 9e-3) of the uncorrected drift, and the peak displacement to within
/// a few times the clean record's.
#[test]
fn polynomial_baseline_reduces_drift_of_real_records() {
    for r in real_records() {
        let n = r.accel_g.len();
        let (_, peak_clean) = peaks(&r.accel_g, r.dt_s);
        let offset: Vec<f64> = r.accel_g.iter().map(|a| a + 0.002).collect();
        let step: Vec<f64> = r
            .accel_g
            .iter()
            .enumerate()
            .map(|(k, a)| if k > n / 3 { a + 0.002 } else { *a })
            .collect();
        for (what, bad, bound) in [("offset", offset, 0.01), ("step", step, 0.05)] {
            let (_, d0) = drift(&bad, r.dt_s);
            let corrected = BaselineCorrection::Polynomial { order: 2 }
                .apply(&bad, r.dt_s)
                .unwrap();
            let (_, d) = drift(&corrected, r.dt_s);
            assert!(d0.abs() > 1.0, "{} {what}: {d0}", r.name);
            assert!(
                d.abs() < bound * d0.abs(),
                "{} {what}: d {d0} -> {d}",
                r.name
            );
            let (_, peak) = peaks(&corrected, r.dt_s);
            assert!(peak < 4.0 * peak_clean, "{} {what}: peak {peak}", r.name);
        }
    }
}
