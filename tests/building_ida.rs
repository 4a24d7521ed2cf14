//! The IDA of a yielding building (docs/model.md, "Incremental dynamic analysis", "In a
//! building") end to end on `configs/mdof-ida-quick.yaml`: it runs, one thread and two give the
//! same bytes, so does a `kill -9` then a rerun, xarray labels the frames' dimensions, the
//! stored storey strengths are the code's distribution; a building of one storey is the
//! one-storey IDA; a stack that cannot slide is the rigidly attached load; the keys that do not
//! fit a building (or one storey) are refused by name before any work.

mod common;

use common::{ok, slidestack};

use slidestack::store::ida::{IdaAxes, ZoneIda, read_zone_ida};
use slidestack::study::storey_strength::storey_strength_ratios;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The motions shared by the quick IDA configs (the same zones and seeds), made once per test.
fn motions(dir: &Path) -> PathBuf {
    let out = dir.join("motions");
    ok(slidestack(
        &[
            "motions",
            s(&repo("configs/mdof-ida-quick.yaml")),
            "--out",
            s(&out),
        ],
        "2",
    ));
    out
}

fn zone(out: &Path, name: &str) -> (IdaAxes, ZoneIda) {
    read_zone_ida(&out.join("ida.h5"), name).unwrap()
}

#[test]
fn the_building_ida_runs_is_deterministic_resumes_and_is_labelled() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = repo("configs/mdof-ida-quick.yaml");
    let m = motions(dir.path());
    let out = dir.path().join("ref");
    common::copy_motions(&m, &out);
    let start = std::time::Instant::now();
    let o = ok(slidestack(&["ida", s(&cfg), "--out", s(&out)], "2"));
    let secs = start.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("× 2 frames"), "{text}");
    assert!(text.contains("3 storeys, stack on the roof"), "{text}");
    assert!(text.contains("median peak_drift_ratio"), "{text}");
    eprintln!("ida on the quick building config: {secs:.2} s");
    let want = std::fs::read(out.join("ida.h5")).unwrap();

    // The stored storey strengths are IS 1893's distribution of c_y (the kernel is tested
    // against the formula by hand, src/study/storey_strength.rs); storey 1 is c_y itself.
    let (axes, z) = zone(&out, "III");
    assert_eq!(axes.frame_count(), 2);
    let stored = z.storey_c_y.as_ref().unwrap();
    let want_c = storey_strength_ratios(0.3, &[1.0; 3], &[3.0; 3]);
    for (i, w) in want_c.iter().enumerate() {
        assert_eq!(stored[[0, 0, i]], *w);
    }
    assert_eq!(want_c[0], 0.3);
    // Every trace started at the first intensity; demands are drift ratios (well below 1).
    let d = &z.vars.run_demand;
    assert!(
        d[[0, 0, 0, 0, 0]] > 0.0 && d[[0, 0, 0, 0, 0]] < 0.1,
        "{d:?}"
    );

    // The report's IDA figure, per frame (`--figure` draws what the report's IDA section does).
    let fig = dir.path().join("ida.svg");
    let o = ok(slidestack(
        &["ida", s(&cfg), "--out", s(&out), "--figure", s(&fig)],
        "1",
    ));
    assert!(String::from_utf8_lossy(&o.stdout).contains("is up to date"));
    let svg = std::fs::read_to_string(&fig).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    for needle in [
        "peak interstorey drift ratio",
        "3 storeys, stack on floor 1",
        "3 storeys, stack on the roof",
    ] {
        assert!(svg.contains(needle), "{needle}");
    }

    // One thread: the same bytes.
    let one = dir.path().join("one");
    common::copy_motions(&m, &one);
    ok(slidestack(&["ida", s(&cfg), "--out", s(&one)], "1"));
    assert_eq!(std::fs::read(one.join("ida.h5")).unwrap(), want);

    // SIGKILL once the stage computes, then a rerun: the same bytes (the stage writes its file
    // once, atomically, at the end; a rerun computes it again).
    let killed = dir.path().join("killed");
    common::copy_motions(&m, &killed);
    // Held after its first trace: the stage is computing, nothing written yet.
    common::kill_at(
        &["ida", s(&cfg), "--out", s(&killed)],
        "ida.trace:1",
        dir.path(),
    );
    assert!(!killed.join("ida.h5").exists());
    ok(slidestack(&["ida", s(&cfg), "--out", s(&killed)], "2"));
    assert_eq!(std::fs::read(killed.join("ida.h5")).unwrap(), want);

    // xarray names every dimension, the frames' among them (scripts/install-deps.sh --test).
    let python = common::test_python();
    let script = "import sys, xarray as xr\n\
        ds = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_V')\n\
        print(list(ds['fractile_curve'].dims), list(ds['theta'].dims), list(ds['run_demand'].dims))\n\
        print(list(ds['storey_c_y'].dims), list(ds['c_y'].dims), [int(v) for v in ds['storeys'].values], [str(v) for v in ds['stack_floor'].values])\n\
        print([str(v) for v in ds['demand'].values[:4]])\n\
        root = xr.open_dataset(sys.argv[1], engine='h5netcdf')\n\
        print([a.split(' of')[0] for a in (root.attrs['intensity_measure'], ds['Sa'].attrs['long_name'], ds['record_Sa'].attrs['long_name'])])\n";
    let o = ok(Command::new(python)
        .args(["-c", script, s(&out.join("ida.h5"))])
        .output()
        .unwrap());
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        text.lines().collect::<Vec<_>>(),
        [
            "['system', 'case', 'storeys', 'stack_floor', 'fractile', 'Sa', 'demand'] \
             ['system', 'case', 'storeys', 'stack_floor', 'limit_state'] \
             ['system', 'record', 'case', 'storeys', 'stack_floor', 'run', 'demand']",
            "['case', 'storeys', 'storey'] ['case'] [3] ['1', 'roof']",
            "['peak_drift_ratio', 'residual_drift_ratio', 'peak_floor_accel_g', 'ductility']",
            "['Sa(T_1, 5 %)', 'Sa(T_1, 5 %)', 'Sa(T_1, 5 %)']",
        ],
        "{text}"
    );
}

/// `configs/ida-quick.yaml` with `edit` applied (pairs of from → to, each present once).
fn ida_quick_with(dir: &Path, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(repo("configs/ida-quick.yaml")).unwrap();
    for (from, to) in edits {
        assert_eq!(text.matches(from).count(), 1, "{from}");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_building_of_one_storey_is_the_one_storey_ida() {
    // configs/ida-quick.yaml (C_y = 0.3, T_p = 1 s, collapse at ductility 10) against the same
    // with `building: {storeys: [1]}`, H = 3 m and collapse at the same drift, as a ratio:
    // 10·u_y/H, u_y = C_y·g/ω². A building of one storey runs the one-storey model, so every
    // intensity, ductility and slip is the same to the bit (a collapse decision could differ
    // only were a peak within round-off of the threshold), and the drift ratios are the
    // one-storey drifts over H to round-off (1e-15 relative: one division each).
    let dir = tempfile::tempdir().unwrap();
    let m = motions(dir.path());
    let h = 3.0;
    let omega = std::f64::consts::TAU / 1.0;
    let u_y = 0.3 * slidestack::dynamics::G / (omega * omega);
    let cap = format!("collapse_drift_ratio: {:e}", 10.0 * u_y / h);
    let plain = repo("configs/ida-quick.yaml");
    let one = ida_quick_with(
        dir.path(),
        "one.yaml",
        &[
            (
                "motions:\n",
                "building: { storeys: [1], storey_heights_m: 3.0 }\nmotions:\n",
            ),
            ("collapse_ductility: 10", &cap),
        ],
    );
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for (cfg, out) in [(&plain, &a), (&one, &b)] {
        common::copy_motions(&m, out);
        ok(slidestack(&["ida", s(cfg), "--out", s(out)], "2"));
    }
    for name in ["III", "V"] {
        let ((ax, za), (bx, zb)) = (zone(&a, name), zone(&b, name));
        assert!(ax.building.is_none());
        assert_eq!(bx.building.as_ref().unwrap().storeys, vec![1]);
        let (va, vb) = (&za.vars, &zb.vars);
        let bits =
            |x: &ndarray::ArrayD<f64>| -> Vec<u64> { x.iter().map(|v| v.to_bits()).collect() };
        assert_eq!(bits(&va.run_sa_g), bits(&vb.run_sa_g), "zone {name}");
        assert_eq!(va.run_collapsed, vb.run_collapsed);
        assert_eq!(bits(&va.collapse_sa_g), bits(&vb.collapse_sa_g));
        assert_eq!(bits(&za.c_y), bits(&zb.c_y));
        let blocks = 2;
        // One-storey demands: ductility, residual drift (m), slips; the building's: peak drift
        // ratio, residual drift ratio, floor acceleration, ductility, slips.
        let sh = va.run_demand.shape().to_vec();
        let mut compared = 0;
        for s in 0..sh[0] {
            for r in 0..sh[1] {
                for k in 0..sh[3] {
                    let x = |j: usize| va.run_demand[[s, r, 0, k, j]];
                    let y = |j: usize| vb.run_demand[[s, r, 0, k, j]];
                    if x(0).is_nan() {
                        assert!(y(0).is_nan());
                        continue;
                    }
                    compared += 1;
                    assert_eq!(x(0).to_bits(), y(3).to_bits(), "ductility");
                    assert!((x(1) / h - y(1)).abs() <= 1e-15 * y(1).max(1e-300));
                    // The peak drift ratio is the ductility times u_y/H, to round-off.
                    assert!((x(0) * u_y / h - y(0)).abs() <= 1e-12 * y(0));
                    assert!(y(2) > 0.0);
                    for i in 0..2 * blocks {
                        assert_eq!(x(2 + i).to_bits(), y(4 + i).to_bits(), "slip {i}");
                    }
                }
            }
        }
        assert!(compared > 20, "{compared}");
        // The ductility and slip fragilities: the same stripes, so the same fits, bit for bit.
        // One-storey limit states DL, LS (ductility) and fall (slip) are the same here.
        assert_eq!(bits(&va.theta_sa_g), bits(&vb.theta_sa_g));
        assert_eq!(bits(&va.beta), bits(&vb.beta));
        assert_eq!(va.fit_status, vb.fit_status);
    }
}

#[test]
fn a_stack_that_cannot_slide_is_the_rigidly_attached_load() {
    // μ = 100 on both interfaces: no floor of the quick building reaches 100 g, so the stack
    // stays stuck and its building is the rigid one (docs/model.md, "In a building"); the
    // integrator reaches it by another route (stuck blocks in a sliding model against masses
    // added to the floors), so the demands agree to round-off: 1e-9 relative.
    let dir = tempfile::tempdir().unwrap();
    let m = motions(dir.path());
    let text = std::fs::read_to_string(repo("configs/mdof-ida-quick.yaml")).unwrap();
    let text = text.replace(
        "{ period_s: 1.0, alpha: [0.5, 0.5], mu: [0.2, 0.1] }",
        "{ period_s: 1.0, alpha: [0.5, 0.5], mu: [100, 100] }",
    );
    let cfg = dir.path().join("stuck.yaml");
    std::fs::write(&cfg, text).unwrap();
    let out = dir.path().join("out");
    common::copy_motions(&m, &out);
    ok(slidestack(&["ida", s(&cfg), "--out", s(&out)], "2"));
    for name in ["III", "V"] {
        let (axes, z) = zone(&out, name);
        let v = &z.vars;
        let sh = v.run_demand.shape().to_vec();
        let mut compared = 0;
        for r in 0..sh[1] {
            for c in 0..sh[2] {
                for k in 0..sh[3] {
                    let (sa0, sa1) = (v.run_sa_g[[0, r, c, k]], v.run_sa_g[[1, r, c, k]]);
                    assert_eq!(sa0.to_bits(), sa1.to_bits(), "{name} r{r} c{c} k{k}");
                    if sa0.is_nan() {
                        continue;
                    }
                    compared += 1;
                    for d in 0..sh[4] {
                        let (x, y) = (v.run_demand[[0, r, c, k, d]], v.run_demand[[1, r, c, k, d]]);
                        let what = &axes.demands[d];
                        if what.contains("slip") {
                            assert_eq!(x, 0.0, "{what}");
                            assert_eq!(y, 0.0, "{what}");
                        } else {
                            assert!(
                                (x - y).abs() <= 1e-9 * y.abs().max(1e-12),
                                "{what}: {x} vs {y}"
                            );
                        }
                    }
                }
            }
        }
        assert!(compared > 20, "{compared}");
    }
}

#[test]
fn keys_that_do_not_fit_are_refused_by_name_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let building = std::fs::read_to_string(repo("configs/mdof-ida-quick.yaml")).unwrap();
    let one = std::fs::read_to_string(repo("configs/ida-quick.yaml")).unwrap();
    // A list of heights needs a single storey count.
    let two = building.replace("storeys: [3]", "storeys: [2, 3]");
    let cases = [
        (
            &building,
            "collapse_drift_ratio: 0.1 ",
            "collapse_ductility: 10 ",
            "ida.collapse_ductility",
        ),
        (
            &building,
            "collapse_drift_ratio: 0.1 ",
            "collapse_drift_ratio: 2 ",
            "ida.collapse_drift_ratio",
        ),
        (
            &building,
            "{ name: IO, drift_ratio: 0.01 }",
            "{ name: IO, drift_ratio: 0.01, ductility: 2 }",
            "ida.limit_states[0]",
        ),
        (
            &building,
            "storey_heights_m: 3.0 ",
            "storey_heights_m: -3.0 ",
            "building.storey_heights_m",
        ),
        (
            &two,
            "storey_heights_m: 3.0 ",
            "storey_heights_m: [3, 3, 3] ",
            "building.storey_heights_m",
        ),
        (
            &one,
            "{ name: DL, ductility: 2 }",
            "{ name: DL, drift_ratio: 0.01 }",
            "ida.limit_states[0].drift_ratio",
        ),
        (
            &one,
            "collapse_ductility: 10",
            "collapse_ductility: 10\n  collapse_drift_ratio: 0.1",
            "ida.collapse_drift_ratio",
        ),
    ];
    for (i, (text, from, to, key)) in cases.iter().enumerate() {
        assert!(text.contains(from), "{from}");
        let cfg = dir.path().join(format!("bad{i}.yaml"));
        let out = dir.path().join(format!("out{i}"));
        std::fs::write(&cfg, text.replacen(from, to, 1)).unwrap();
        let o = slidestack(&["ida", s(&cfg), "--out", s(&out)], "1");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{to}: {err}");
        assert!(err.contains(s(&cfg)) && err.contains(key), "{to}: {err}");
        assert!(!out.exists(), "{to}: work started");
    }
}

#[test]
fn design_strengths_come_from_the_zone_s_spectrum_at_t_1() {
    // `design: {importance: 1, response_reduction: 3}` at T_1 = 1 s on rock: IS 1893
    // (Part 1):2016 gives Sa/g = 1/T = 1 (Clause 6.4.2, soil type I, 0.4 s < T < 4 s), so
    // C_y = (Z/2)·(I/R)·1 = 0.16/6 in Zone III and 0.36/6 in Zone V, by hand; storey 1 carries
    // it all and the storeys above are stronger for their mass.
    let dir = tempfile::tempdir().unwrap();
    let m = motions(dir.path());
    let text = std::fs::read_to_string(repo("configs/mdof-ida-quick.yaml")).unwrap();
    let from = "c_y: 0.3                     # base shear / bare weight, V_B/(g Σm)";
    assert!(text.contains(from));
    let cfg = dir.path().join("design.yaml");
    std::fs::write(
        &cfg,
        text.replace(from, "design: { importance: 1.0, response_reduction: 3.0 }"),
    )
    .unwrap();
    let out = dir.path().join("out");
    common::copy_motions(&m, &out);
    ok(slidestack(&["ida", s(&cfg), "--out", s(&out)], "2"));
    for (name, z) in [("III", 0.16), ("V", 0.36)] {
        let (_, zone) = zone(&out, name);
        let want = z / 2.0 / 3.0;
        let c_y = zone.c_y[[0]];
        assert!(
            (c_y - want).abs() <= 1e-12 * want,
            "{name}: {c_y} vs {want}"
        );
        let storeys = zone.storey_c_y.unwrap();
        assert_eq!(storeys[[0, 0, 0]], c_y);
        assert!(storeys[[0, 0, 1]] > c_y && storeys[[0, 0, 2]] > storeys[[0, 0, 1]]);
        // Every trace ran: the first run of every record and system has a drift.
        let first = zone
            .vars
            .run_demand
            .slice(ndarray::s![.., .., .., 0, 0])
            .to_owned();
        assert!(first.iter().all(|d| *d > 0.0), "{first:?}");
    }
}

/// `configs/mdof-ida-quick.yaml` with its stack floors `floors` (the rest as it is).
fn mdof_ida_quick_with(dir: &Path, name: &str, floors: &str) -> PathBuf {
    let text = std::fs::read_to_string(repo("configs/mdof-ida-quick.yaml")).unwrap();
    let from = "stack_floor: [1, roof]";
    assert_eq!(text.matches(from).count(), 1);
    let path = dir.join(name);
    std::fs::write(
        &path,
        text.replacen(from, &format!("stack_floor: {floors}"), 1),
    )
    .unwrap();
    path
}

#[test]
fn a_frame_that_repeats_a_building_takes_its_traces_which_are_the_traced_ones() {
    // Floor 3 of three storeys is the roof: with both, the stage traces floor 3 and gives the
    // roof its traces; a study of the roof alone traces the roof. Every stored trace,
    // intensity, curve and fragility of the roof is the same to the bit either way (a trace is
    // deterministic, and floor 3 and the roof are the same masses, stiffnesses and stack).
    let dir = tempfile::tempdir().unwrap();
    let m = motions(dir.path());
    let both = mdof_ida_quick_with(dir.path(), "both.yaml", "[3, roof]");
    let roof = mdof_ida_quick_with(dir.path(), "roof.yaml", "[roof]");
    let (out_both, out_roof) = (dir.path().join("both"), dir.path().join("roof"));
    for (cfg, out) in [(&both, &out_both), (&roof, &out_roof)] {
        common::copy_motions(&m, out);
        let o = ok(slidestack(&["ida", s(cfg), "--out", s(out)], "2"));
        let text = String::from_utf8_lossy(&o.stdout);
        assert_eq!(
            text.contains("units of frames that repeat a building take its traces"),
            cfg == &both,
            "{text}"
        );
    }
    let same = |a: ndarray::ArrayViewD<f64>, b: ndarray::ArrayViewD<f64>, what: &str| {
        assert_eq!(a.shape(), b.shape(), "{what}");
        for (x, y) in a.iter().zip(b.iter()) {
            assert_eq!(x.to_bits(), y.to_bits(), "{what}: {x} vs {y}");
        }
    };
    for zone_name in ["III", "V"] {
        let (axes, z_both) = zone(&out_both, zone_name);
        let (_, z_roof) = zone(&out_roof, zone_name);
        assert_eq!(axes.building.as_ref().unwrap().frame_count(), 2);
        let (vb, vr) = (&z_both.vars, &z_roof.vars);
        // The case axis holds case·frames + frame: one case, so the frame's index.
        for (what, a, b, axis) in [
            ("run_sa_g", &vb.run_sa_g, &vr.run_sa_g, 2),
            ("run_demand", &vb.run_demand, &vr.run_demand, 2),
            ("curve", &vb.curve, &vr.curve, 2),
            ("theta_sa_g", &vb.theta_sa_g, &vr.theta_sa_g, 1),
            ("beta", &vb.beta, &vr.beta, 1),
        ] {
            let roof_traced = b.index_axis(ndarray::Axis(axis), 0);
            for f in [0, 1] {
                let what = format!("zone {zone_name}, {what}, frame {f}");
                same(
                    a.index_axis(ndarray::Axis(axis), f),
                    roof_traced.clone(),
                    &what,
                );
            }
        }
    }
}
