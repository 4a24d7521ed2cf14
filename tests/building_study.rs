//! A study over buildings (docs/model.md, "A study over buildings"): `configs/mdof-quick.yaml`
//! through motions and sweep, xarray reading the labelled dimensions, a `kill -9` resumed bit
//! for bit, the `storeys: [1]` identity, the config's refusals and the stages that refuse a
//! building study.

mod common;

use common::{ok, shards, slidestack};

use slidestack::dynamics::{ExactOptions, G, Ground};
use slidestack::grid::StackFloor;
use slidestack::store::motions::read_zone_motions;
use slidestack::store::sweep::{ZoneSweep, read_zone_sweep};
use slidestack::store::tnew::read_zone_tnew_in;
use slidestack::study::attached::FractionFlag;
use slidestack::study::building::Frame;
use slidestack::study::physics::{Physics, SystemKind};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Units stored in `dir/sweep.units`.
fn units(dir: &Path) -> usize {
    std::fs::read_dir(dir.join("sweep.units"))
        .map(|d| {
            d.filter(|e| {
                e.as_ref()
                    .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "unit"))
            })
            .count()
        })
        .unwrap_or(0)
}

/// Every variable of `z` (`[motion, storeys, stack_floor, …]`) in its first storey count's
/// frame `f`, as bits per motion; a per-floor or per-storey variable's first level only (a study
/// of one storey pads nothing).
fn frame_bits(z: &ZoneSweep, f: usize) -> Vec<(&'static str, Vec<u64>)> {
    use ndarray::{Axis, Slice};
    use slidestack::store::vars::{Data, Trailing};
    let building = z.building.as_ref().expect("a building study's sweep");
    (z.vars.data().into_iter())
        .chain(building.data())
        .map(|(var, data)| {
            let bits: Vec<u64> = match data {
                Data::Values(a) => {
                    let frame = a.index_axis(Axis(1), 0);
                    let frame = frame.index_axis(Axis(1), f);
                    let per_level = matches!(var.trailing, Trailing::Floor | Trailing::Storey);
                    let first = match per_level {
                        true => frame.slice_axis(Axis(frame.ndim() - 1), Slice::from(0..1)),
                        false => frame.view(),
                    };
                    first.iter().map(|x| x.to_bits()).collect()
                }
                Data::Codes(a) => (a.index_axis(Axis(1), 0).index_axis(Axis(1), f).iter())
                    .map(|&c| u64::from(c))
                    .collect(),
            };
            (var.name, bits)
        })
        .collect()
}

/// What `script` prints when the tests' Python (scripts/install-deps.sh --test: xarray,
/// h5netcdf) runs it with `file` as its argument; panics with its stderr if it fails.
fn python_on(script: &str, file: &Path) -> String {
    let python = common::test_python();
    let o = ok(Command::new(python)
        .args(["-c", script])
        .arg(file)
        .output()
        .unwrap());
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn the_quick_building_study_sweeps_resumes_and_is_labelled() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = repo("configs/mdof-quick.yaml");
    let cfg_s = cfg.to_str().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    ok(slidestack(&["motions", cfg_s, "--out", out_s], "2"));
    let o = ok(slidestack(&["status", cfg_s, "--out", out_s], "2"));
    // 2 zones × 3 motions × 4 buildings × 3 periods: on one storey the roof's and every floor's
    // frames repeat floor 1's building, and have no units of their own.
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("0 of 72"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );

    // Killed with SIGKILL once some units are on disk, then resumed.
    let killed = dir.path().join("killed");
    common::copy_motions(&out, &killed);
    // Held after its third unit is stored: exactly three are on disk at the kill.
    common::kill_at(
        &["sweep", cfg_s, "--out", killed.to_str().unwrap()],
        "sweep.unit:3",
        dir.path(),
    );
    let before = units(&killed);
    assert_eq!(before, 3, "{before} units before the kill");
    assert!(!killed.join("sweep.h5").exists());
    let o = ok(slidestack(
        &["sweep", cfg_s, "--out", killed.to_str().unwrap()],
        "2",
    ));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("{before} already done")), "{text}");

    // Uninterrupted, on two shards: the same bytes.
    for k in ["1/2", "2/2"] {
        ok(slidestack(
            &["sweep", cfg_s, "--out", out_s, "--shard", k],
            "1",
        ));
    }
    ok(slidestack(&["merge", cfg_s, "--out", out_s], "1"));
    let want = std::fs::read(out.join("sweep.h5")).unwrap();
    assert_eq!(std::fs::read(killed.join("sweep.h5")).unwrap(), want);

    // The frames as stored, `[motion, storeys, stack_floor, case]`: in one storey floor 1,
    // the roof and every floor are one building; in three they are three.
    let (grid, axes, z) = read_zone_sweep(&out.join("sweep.h5"), "V", 2, true).unwrap();
    let axes = axes.unwrap();
    assert_eq!(axes.storeys, [1, 3]);
    assert_eq!(
        axes.stack_floor,
        [StackFloor::Floor(1), StackFloor::Roof, StackFloor::All]
    );
    let per_frame = grid.cases();
    let u = z.vars.u_stack.as_slice().unwrap();
    let frame = |m: usize, f: usize| &u[(m * 6 + f) * per_frame..(m * 6 + f + 1) * per_frame];
    for m in 0..3 {
        for f in 1..3 {
            assert_eq!(frame(m, f), frame(m, 0), "one storey: floor 1 = roof = all");
        }
        assert_ne!(frame(m, 3), frame(m, 4));
        assert_ne!(frame(m, 4), frame(m, 5));
    }
    assert!(z.vars.u_stack.iter().all(|x| x.is_finite() && *x > 0.0));

    // The repeated frames' stored results are what their own sweep computes: a study of the
    // one-storey building with the stack on the roof alone, then on every floor alone, stores
    // every variable the study stored for that frame (floor 1's units), bit for bit.
    for (f, floor) in [(1, "roof"), (2, "all")] {
        let text = std::fs::read_to_string(&cfg).unwrap();
        let text = (text.replace("storeys: [1, 3]", "storeys: [1]")).replace(
            "stack_floor: [1, roof, all]",
            &format!("stack_floor: [{floor}]"),
        );
        let alone_cfg = dir.path().join(format!("one-{floor}.yaml"));
        std::fs::write(&alone_cfg, text).unwrap();
        let alone = dir.path().join(format!("one-{floor}"));
        common::copy_motions(&out, &alone);
        ok(slidestack(
            &["sweep", s(&alone_cfg), "--out", s(&alone)],
            "2",
        ));
        let (_, _, one) = read_zone_sweep(&alone.join("sweep.h5"), "V", 2, true).unwrap();
        assert_eq!(
            frame_bits(&one, 0),
            frame_bits(&z, f),
            "one storey, the stack on {floor}"
        );
    }

    // xarray labels every dimension (Python environment made by scripts/install-deps.sh).
    let script = "import sys, xarray as xr\n\
        ds = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_III')\n\
        print(list(ds['u_stack'].dims))\n\
        print(list(ds['slip_peak'].dims)[-1], [int(n) for n in ds['storeys']], \
              [str(f) for f in ds['stack_floor'].values])\n\
        print(float(ds['u_stack'].sel(storeys=3, stack_floor='roof').isel(motion=0, T_p=0, \
              alpha_1=0, alpha_2=0, mu_1=0, mu_2=0)) > 0)\n\
        print(list(ds['block_accel_stack'].dims)[-1], list(ds['slip_residual'].dims)[-1], \
              [int(b) for b in ds['block']], ds['block_velocity_stack'].attrs['units'])\n";
    assert_eq!(
        python_on(script, &out.join("sweep.h5")),
        "['motion', 'storeys', 'stack_floor', 'T_p', 'alpha_1', 'alpha_2', 'mu_1', 'mu_2']\n\
         interface [1, 3] ['1', 'roof', 'all']\nTrue\nblock interface [1, 2] m s-1\n"
    );

    // Per-floor demands and base shear: labelled, NaN above a one-storey building's roof.
    let script = r#"import sys, xarray as xr
ds = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_V')
for v in ['floor_accel_stack', 'floor_accel_rigid', 'drift_ratio_stack',
          'drift_ratio_rigid', 'base_shear_stack', 'base_shear_rigid']:
    print(v, list(ds[v].dims)[1:3], list(ds[v].dims)[-1])
a = ds['floor_accel_stack'].isel(motion=0, T_p=0, alpha_1=0, alpha_2=0, mu_1=0, mu_2=0)
print([int(f) for f in ds['floor']], bool(a.sel(storeys=1, stack_floor='roof', floor=2).isnull()),
      bool((a.sel(storeys=3, stack_floor='roof') > 0).all()))
"#;
    assert_eq!(
        python_on(script, &out.join("sweep.h5")),
        "floor_accel_stack ['storeys', 'stack_floor'] floor\n\
         floor_accel_rigid ['storeys', 'stack_floor'] floor\n\
         drift_ratio_stack ['storeys', 'stack_floor'] storey\n\
         drift_ratio_rigid ['storeys', 'stack_floor'] storey\n\
         base_shear_stack ['storeys', 'stack_floor'] mu_2\n\
         base_shear_rigid ['storeys', 'stack_floor'] mu_2\n\
         [1, 2, 3] True True\n"
    );

    // The profiles are a direct run's: every case of one motion, three storeys, stack on the
    // roof, against `Physics::simulate_building` of the system the skip rule names.
    let bv = z.building.as_ref().unwrap();
    let recs = read_zone_motions(&out.join("motions.h5"), "V").unwrap();
    let accel = recs[1].accel_mps2(1.0);
    let ground = Ground::new(recs[1].dt_s, &accel);
    let frame = Frame {
        floor_masses: vec![1.0; 3],
        storey_stiffnesses: vec![1.0; 3],
        storey_heights_m: vec![3.0; 3],
        stack_floor: StackFloor::Roof,
    };
    let opts = ExactOptions {
        energy_balance: false,
        ..ExactOptions::default()
    };
    let f = 4; // storeys 3, stack_floor roof
    let mut checked = [0; 3];
    for c in 0..per_frame {
        let at = (6 + f) * per_frame + c; // motion 1
        let case = grid.case(c);
        let rule = z.vars.skip_rule.as_slice().unwrap()[at];
        let single = z.vars.single_rule.as_slice().unwrap()[at] == 1;
        let kind = match rule {
            0 => SystemKind::Stack,
            2 if !single => SystemKind::SingleBlock,
            _ => SystemKind::Rigid,
        };
        checked[rule as usize] += 1;
        let run = |kind| {
            Physics::DEFAULT
                .simulate_building(kind, &case, &frame, &ground, &opts, None)
                .unwrap()
        };
        let (s, r) = (run(kind), run(SystemKind::Rigid));
        let row = |v: &ndarray::ArrayD<f64>| v.as_slice().unwrap()[at * 3..at * 3 + 3].to_vec();
        let g = |v: &[f64]| v.iter().map(|a| a / G).collect::<Vec<_>>();
        let d = |v: &[f64]| v.iter().map(|x| x / 3.0).collect::<Vec<_>>();
        assert_eq!(
            row(&bv.floor_accel_stack),
            g(&s.floor_peak_abs_accel_mps2),
            "{c}"
        );
        assert_eq!(
            row(&bv.floor_accel_rigid),
            g(&r.floor_peak_abs_accel_mps2),
            "{c}"
        );
        assert_eq!(row(&bv.drift_ratio_stack), d(&s.storey_peak_drift_m), "{c}");
        assert_eq!(row(&bv.drift_ratio_rigid), d(&r.storey_peak_drift_m), "{c}");
        assert_eq!(
            row(&bv.floor_velocity_stack),
            s.floor_peak_abs_velocity_mps,
            "{c}"
        );
        assert_eq!(
            row(&bv.floor_velocity_rigid),
            r.floor_peak_abs_velocity_mps,
            "{c}"
        );
        assert_eq!(
            row(&bv.residual_drift_ratio_stack),
            d(&s.storey_residual_drift_m),
            "{c}"
        );
        assert_eq!(
            row(&bv.residual_drift_ratio_rigid),
            d(&r.storey_residual_drift_m),
            "{c}"
        );
        // The goods' own demands (two blocks, on the roof): the system's blocks, or with a
        // rule, the body every block moves with.
        let blocks = |v: &ndarray::ArrayD<f64>| v.as_slice().unwrap()[at * 2..at * 2 + 2].to_vec();
        let (a_block, v_block, residual) = match kind {
            SystemKind::Stack => (
                g(&s.block_peak_abs_accel_mps2),
                s.block_peak_abs_velocity_mps.clone(),
                s.residual_slip_m.clone(),
            ),
            SystemKind::SingleBlock => (
                g(&[s.block_peak_abs_accel_mps2[0]; 2]),
                vec![s.block_peak_abs_velocity_mps[0]; 2],
                vec![s.residual_slip_m[0], 0.0],
            ),
            SystemKind::Rigid => (
                g(&[r.floor_peak_abs_accel_mps2[2]; 2]),
                vec![r.floor_peak_abs_velocity_mps[2]; 2],
                vec![0.0; 2],
            ),
        };
        assert_eq!(blocks(&z.vars.block_accel_stack), a_block, "{c}");
        assert_eq!(blocks(&z.vars.block_velocity_stack), v_block, "{c}");
        assert_eq!(blocks(&z.vars.slip_residual), residual, "{c}");
        assert_eq!(
            bv.base_shear_stack.as_slice().unwrap()[at],
            frame.base_shear_ratio(s.peak_base_shear_n)
        );
        assert_eq!(
            bv.base_shear_rigid.as_slice().unwrap()[at],
            frame.base_shear_ratio(r.peak_base_shear_n)
        );
    }
    eprintln!("profiles checked by skip rule (simulated, no slip, single block): {checked:?}");
    assert!(checked[0] > 0);

    // `export edp --study`: a simulated case's row of motion 1 is the direct run's demands (the
    // ground's: the motion's PGA and PGV), sliding and attached.
    let c = (0..per_frame)
        .find(|&c| z.vars.skip_rule.as_slice().unwrap()[(6 + f) * per_frame + c] == 0)
        .unwrap();
    let case = grid.case(c);
    let (s, r) = {
        let run = |kind| {
            Physics::DEFAULT
                .simulate_building(kind, &case, &frame, &ground, &opts, None)
                .unwrap()
        };
        (run(SystemKind::Stack), run(SystemKind::Rigid))
    };
    let join = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(",");
    let (period, alpha, mu) = (case.period_s.to_string(), join(&case.alpha), join(&case.mu));
    for (flag, want) in [(None, &s), (Some("--attached"), &r)] {
        let csv = out.join("edp.csv");
        let mut args = vec![
            "export",
            "edp",
            "--study",
            out_s,
            "--zone",
            "V",
            "--storeys",
            "3",
            "--stack-floor",
            "roof",
            "--period",
            &period,
            "--alpha",
            &alpha,
            "--mu",
            &mu,
            "--out",
            csv.to_str().unwrap(),
        ];
        args.extend(flag);
        ok(slidestack(&args, "1"));
        let text = std::fs::read_to_string(&csv).unwrap();
        let row: Vec<f64> = text
            .lines()
            .nth(3)
            .unwrap()
            .split(',')
            .skip(1)
            .map(|v| v.parse().unwrap())
            .collect();
        let mut expect = vec![recs[1].pga_g()];
        expect.extend(want.floor_peak_abs_accel_mps2.iter().map(|a| a / G));
        expect.push(recs[1].pgv_mps(1.0));
        expect.extend(&want.floor_peak_abs_velocity_mps);
        expect.extend(want.storey_peak_drift_m.iter().map(|d| d / 3.0));
        expect.extend(want.storey_residual_drift_m.iter().map(|d| (d / 3.0).abs()));
        assert_eq!(row, expect, "{flag:?}");
    }
    // A case the study does not hold is refused, naming the key and what it holds; a list of
    // another length than the stacks' blocks, naming the key and the count.
    for (period, alpha, why) in [
        (
            "0.45",
            alpha.as_str(),
            "sweep.h5: `period` 0.45 is not in the study",
        ),
        (
            period.as_str(),
            "0.5",
            "sweep.h5: `alpha` lists 1 values; the study's stacks have 2 blocks",
        ),
    ] {
        let o = slidestack(
            &[
                "export",
                "edp",
                "--study",
                out_s,
                "--zone",
                "V",
                "--storeys",
                "3",
                "--stack-floor",
                "roof",
                "--period",
                period,
                "--alpha",
                alpha,
                "--mu",
                &mu,
                "--out",
                out.join("no.csv").to_str().unwrap(),
            ],
            "1",
        );
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(why), "{err}");
        assert!(!out.join("no.csv").exists());
    }

    // T_new per frame: the first mode's, labelled; in one storey the three floors agree.
    ok(slidestack(&["tnew", cfg_s, "--out", out_s], "2"));
    let (_, frames, t) = read_zone_tnew_in(&out.join("tnew.h5"), "V", 2, true).unwrap();
    assert_eq!(frames.as_ref(), Some(&axes));
    assert_eq!(t.roof_participation[0], 1.0);
    // Three uniform storeys: the first mode is φ_j = sin(πj/7), Γ_1·φ_1,3 = φ_3·Σφ/Σφ².
    let phi: Vec<f64> = (1..=3)
        .map(|j| (std::f64::consts::PI * j as f64 / 7.0).sin())
        .collect();
    let want = phi[2] * phi.iter().sum::<f64>() / phi.iter().map(|p| p * p).sum::<f64>();
    assert!((t.roof_participation[1] - want).abs() < 1e-13, "{want}");
    let tn = t.vars.t_new.as_slice().unwrap();
    for f in 1..3 {
        let same = |v: &[f64]| v[f * per_frame..(f + 1) * per_frame] == v[..per_frame];
        assert!(same(tn) && same(t.vars.drr_1.as_slice().unwrap()));
    }
    assert_eq!(
        python_on(
            "import sys, xarray as xr\n\
                 t = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_V')\n\
                 print(list(t['T_new'].dims), list(t['roof_participation'].dims))\n",
            &out.join("tnew.h5")
        ),
        "['storeys', 'stack_floor', 'T_p', 'alpha_1', 'alpha_2', 'mu_1', 'mu_2'] ['storeys']\n"
    );
    // λ's root searches run in parallel: one thread writes the same bytes.
    let two = std::fs::read(out.join("tnew.h5")).unwrap();
    ok(slidestack(&["tnew", cfg_s, "--out", out_s, "--force"], "1"));
    assert_eq!(std::fs::read(out.join("tnew.h5")).unwrap(), two);
    tnew_shards_a_kill_and_a_damaged_unit_give_the_unsharded_bytes(dir.path(), &out, &two);
    // λ: 1 where nothing slid, between the family's ends otherwise (unclamped: below 0 where
    // the stack lowers the base shear below the bare building's), the same on one storey's
    // three floors; labelled.
    let l = t.lambda.as_ref().unwrap();
    let (lam, flag) = (l.lambda.as_slice().unwrap(), l.flag.as_slice().unwrap());
    let slides = t.vars.slides.as_slice().unwrap();
    assert_eq!(lam[..per_frame], lam[per_frame..2 * per_frame]);
    assert_eq!(lam[..per_frame], lam[2 * per_frame..3 * per_frame]);
    for c in 0..6 * per_frame {
        if slides[c] == 0.0 {
            assert!(lam[c] == 1.0 && flag[c] == FractionFlag::NoSlide as u8);
        } else {
            let f = flag[c];
            assert!(
                (-1.0..=2.0).contains(&lam[c]) && f != 3,
                "{c}: {} ({f})",
                lam[c]
            );
        }
    }
    let roots = (flag.iter())
        .filter(|&&f| f == FractionFlag::Root as u8 || f == FractionFlag::Several as u8)
        .count();
    let sliding = slides.iter().filter(|&&s| s > 0.0).count();
    eprintln!("λ flags: {roots} roots of {sliding} sliding cases");
    assert!(roots > 0);
    assert_eq!(
        python_on(
            "import sys, xarray as xr\n\
                 t = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_V')\n\
                 print(list(t['lambda'].dims)[:2], t['lambda_flag'].attrs['flag_meanings'])\n",
            &out.join("tnew.h5")
        ),
        "['storeys', 'stack_floor'] root below_range_clamped above_range_clamped no_slide \
         several_roots_nearest_stuck_share stationary_within_tolerance\n"
    );

    several_frames_are_fitted_and_designed_for(&out);
}

/// `tnew` of `configs/mdof-quick.yaml` (motions and sweep done in `out`, whose unsharded
/// `tnew.h5` is `want`) split in three shards, one of them killed with SIGKILL after its first
/// unit file and rerun, then a stored unit damaged: the unsharded stage recomputes that unit,
/// assembles the same bytes and removes the unit files. A split into more shards than units is
/// bad input (exit 2).
fn tnew_shards_a_kill_and_a_damaged_unit_give_the_unsharded_bytes(
    tmp: &Path,
    out: &Path,
    want: &[u8],
) {
    let cfg = repo("configs/mdof-quick.yaml");
    let split = tmp.join("tnew-split");
    std::fs::create_dir_all(&split).unwrap();
    for f in [
        "motions.h5",
        "motions.h5.sha256",
        "sweep.h5",
        "sweep.h5.sha256",
    ] {
        std::fs::copy(out.join(f), split.join(f)).unwrap();
    }
    // 2 zones × 2 distinct buildings (one storey, and 3 storeys ×3 floors: 4) × 3 periods × 2
    // total α.
    let o = ok(slidestack(
        &["status", s(&cfg), "--out", s(&split), "--format", "env"],
        "1",
    ));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("TNEW_UNITS=48\n") && text.contains("TNEW_UNITS_DONE=0\n"),
        "{text}"
    );
    shards::run("tnew", &cfg, &split, "3/3", "1");
    common::kill_at(
        &["tnew", s(&cfg), "--out", s(&split), "--shard", "1/3"],
        "tnew.unit:1",
        tmp,
    );
    let units = split.join("tnew.units");
    assert_eq!(std::fs::read_dir(&units).unwrap().count(), 16 + 1);
    shards::run("tnew", &cfg, &split, "1/3", "2");
    shards::run("tnew", &cfg, &split, "2/3", "2");
    assert!(!split.join("tnew.h5").exists());
    let files = shards::unit_files(&units);
    assert_eq!(files.len(), 48);
    let o = ok(slidestack(&["status", s(&cfg), "--out", s(&split)], "1"));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("tnew units: 48 of 48 stored"), "{text}");
    let o = shards::rerun_with_a_damaged_unit("tnew", &cfg, &split, &files[5]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("1 of 24 units"), "{text}");
    assert_eq!(std::fs::read(split.join("tnew.h5")).unwrap(), want);
    assert!(!units.exists());
    shards::refuses_more_shards_than_units("tnew", &cfg, &split, 49, "1 ≤ K ≤ N ≤ 48");
}

/// The fit over the six frames of `configs/mdof-quick.yaml` (finished through `tnew` in `out`)
/// with the building's features, and `design` in each frame.
fn several_frames_are_fitted_and_designed_for(out: &Path) {
    let cfg = repo("configs/mdof-quick.yaml");
    let (cfg_s, out_s) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    let design = |extra: &[&str]| {
        let mut args = vec![
            "design", "--study", out_s, "--zone", "V", "--alpha", "0.25,0.5", "--mu", "0.1,0.05",
        ];
        args.extend(extra);
        slidestack(&args, "1")
    };
    // Before the fit, design says what is missing.
    let o = design(&["--period", "0.6", "--storeys", "3", "--floor", "roof"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no fit.yaml"), "{}", stderr(&o));

    ok(slidestack(&["fit", cfg_s, "--out", out_s], "2"));
    let text = std::fs::read_to_string(out.join("fit.yaml")).unwrap();
    let fit: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let names: Vec<&str> = (fit["features"].as_sequence().unwrap().iter())
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["T_1", "mu_1", "mu_2", "alpha_1", "alpha_2", "N", "z_stack"]
    );
    let frames = fit["frames"].as_sequence().unwrap();
    assert_eq!(frames.len(), 6);
    // fit.h5 labels every coefficient by its name, λ's among them (xarray).
    let script = "import sys, xarray as xr\n\
        for form in ['damped', 'lambda']:\n\
        \x20   ds = xr.open_dataset(sys.argv[1], engine='h5netcdf', group='zone_V/' + form)\n\
        \x20   c = ds['coefficients']\n\
        \x20   print(list(c.dims), list(ds['standard_errors'].dims), str(c['parameter'].values[-1]))\n";
    assert_eq!(
        python_on(script, &out.join("fit.h5")),
        "['parameter'] ['parameter'] v_0\n['parameter'] ['parameter'] w_0\n"
    );
    let zone_v = (fit["zones"].as_sequence().unwrap().iter())
        .find(|z| z["zone"].as_str() == Some("V"))
        .unwrap();
    // The fit counts each building once: floor 1, the roof and every floor of one storey are
    // one building (of 3 periods × 8 stacks × 4 distinct frames, those with a T_new).
    let (_, _, t) = read_zone_tnew_in(&out.join("tnew.h5"), "V", 2, true).unwrap();
    let t_new = t.vars.t_new.as_slice().unwrap();
    let per = t_new.len() / 6;
    let distinct = [0, 3, 4, 5];
    let with_t_new = (distinct.iter())
        .flat_map(|f| &t_new[f * per..(f + 1) * per])
        .filter(|t| t.is_finite())
        .count();
    assert!(with_t_new > 90, "{with_t_new}");
    assert_eq!(zone_v["cases"].as_u64(), Some(with_t_new as u64));
    let per_frame = zone_v["frames"].as_sequence().unwrap();
    assert_eq!(per_frame.len(), 6);
    // The one-storey equation on the one-storey frame is its own fit: the same R².
    let one = &zone_v["one_storey"]["all_cases"]["r2"];
    assert!(
        (per_frame[0]["one_storey"]["r2"].as_f64().unwrap() - one.as_f64().unwrap()).abs() < 1e-12
    );

    // design at every grid point of each frame: the grid's T_new is the stored one, its
    // T_rigid the stored T_1,rigid, and the fitted T_new gives back the frame's R² in fit.yaml
    // (the design's features and the fit's agree).
    let (grid, axes, t) = read_zone_tnew_in(&out.join("tnew.h5"), "V", 2, true).unwrap();
    let axes = axes.unwrap();
    let per = grid.cases();
    let t_new = t.vars.t_new.as_slice().unwrap();
    let t_rigid = t.vars.t_rigid.as_slice().unwrap();
    for f in 0..axes.frame_count() {
        let (n, floor) = axes.frame(f);
        let (mut observed, mut fitted) = (Vec::new(), Vec::new());
        for c in 0..per {
            let case = grid.case(c);
            let join = |v: &[f64]| {
                v.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            };
            let (p, a, m) = (case.period_s.to_string(), join(&case.alpha), join(&case.mu));
            let (n_s, floor_s) = (n.to_string(), floor.to_string());
            let o = ok(slidestack(
                &[
                    "design",
                    "--study",
                    out_s,
                    "--zone",
                    "V",
                    "--period",
                    &p,
                    "--alpha",
                    &a,
                    "--mu",
                    &m,
                    "--storeys",
                    &n_s,
                    "--floor",
                    &floor_s,
                    "--json",
                ],
                "1",
            ));
            let a: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            let want = t_new[f * per + c];
            match a["t_new_grid_s"].as_f64() {
                Some(got) => assert_eq!(got, want, "frame {f} case {c}"),
                None => assert!(!want.is_finite()),
            }
            let tr = a["t_rigid_s"].as_f64().unwrap();
            assert!(
                (tr - t_rigid[f * per + c]).abs() < 1e-12 * tr,
                "frame {f} case {c}"
            );
            if want.is_finite() {
                observed.push(want);
                fitted.push(a["t_new_fit_s"].as_f64().unwrap());
            }
        }
        let r2 = slidestack::fit::metrics(&observed, &fitted).r2;
        let stored = per_frame[f]["building"]["r2"].as_f64().unwrap();
        assert!((r2 - stored).abs() < 1e-12, "frame {f}: {r2} vs {stored}");
    }

    // A frame the study does not hold, and a building study asked without one, are refused.
    let o = design(&["--period", "0.6", "--storeys", "3", "--floor", "2"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no building of 3 storeys with the stack on floor `2`; it has"),
        "{}",
        stderr(&o)
    );
    let o = design(&["--period", "0.6"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("is a building study's (`building`): say which building"),
        "{}",
        stderr(&o)
    );
}

/// `configs/quick.yaml` with `extra` appended to its `grid:` section and `top` added at the top.
fn quick_with(dir: &Path, name: &str, top: &str, grid_extra: &str) -> PathBuf {
    let text = std::fs::read_to_string(repo("configs/quick.yaml")).unwrap();
    let text = text.replace(
        "  damping_basis: rigid\n",
        &format!("  damping_basis: rigid\n{grid_extra}"),
    );
    let path = dir.join(name);
    std::fs::write(&path, format!("{top}{text}")).unwrap();
    path
}

fn zone(out: &Path, name: &str, building: bool) -> ZoneSweep {
    read_zone_sweep(&out.join("sweep.h5"), name, 2, building)
        .unwrap()
        .2
}

#[test]
fn one_storey_buildings_are_the_one_storey_study() {
    // `building: {storeys: [1]}` gives the one-storey study's sweep, T_new, DRR and fit: every
    // number the same to the bit (the tolerance the issue asks is 1e-12; a building of one
    // storey runs the one-storey systems, docs/model.md, "A study over buildings").
    let dir = tempfile::tempdir().unwrap();
    let plain = quick_with(dir.path(), "plain.yaml", "", "");
    let one = quick_with(dir.path(), "one.yaml", "building: { storeys: [1] }\n", "");
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for (cfg, out) in [(&plain, &a), (&one, &b)] {
        let (c, o) = (cfg.to_str().unwrap(), out.to_str().unwrap());
        ok(slidestack(&["motions", c, "--out", o], "2"));
        ok(slidestack(&["sweep", c, "--out", o], "2"));
        ok(slidestack(&["tnew", c, "--out", o], "2"));
        ok(slidestack(&["fit", c, "--out", o], "2"));
    }
    // A one-storey study's tnew has no units to split.
    let args = [
        "tnew",
        s(&plain),
        "--out",
        s(&a),
        "--shard",
        "1/2",
        "--force",
    ];
    let o = slidestack(&args, "1");
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("has nothing to split"),
        "{}",
        stderr(&o)
    );
    // The fit: every number the same; fit.yaml names the frame and carries its own fingerprint.
    let fit = |out: &Path| -> serde_yaml::Value {
        let text = std::fs::read_to_string(out.join("fit.yaml")).unwrap();
        let mut v: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
        let map = v.as_mapping_mut().unwrap();
        map.remove("fingerprint").unwrap();
        if let Some(b) = map.remove("building") {
            assert_eq!(b.as_str(), Some("1 storey, stack on the roof"));
        }
        if let Some(f) = map.remove("frames") {
            assert_eq!(f[0]["storeys"].as_u64(), Some(1));
        }
        // A building study also fits its effective live-load fraction λ.
        for z in map
            .get_mut("zones")
            .and_then(|z| z.as_sequence_mut())
            .unwrap()
        {
            z.as_mapping_mut().unwrap().remove("lambda");
        }
        v
    };
    let (fa, fb) = (fit(&a), fit(&b));
    assert_eq!(fa, fb);
    assert!(
        fa["zones"][0]["forms"]
            .as_sequence()
            .is_some_and(|f| !f.is_empty())
    );
    for name in ["III", "V"] {
        let (za, zb) = (zone(&a, name, false), zone(&b, name, true));
        let (va, vb) = (&za.vars, &zb.vars);
        // `y` has the building's two dimensions of length 1 at `at`.
        let same_at = |at: usize, x: &ndarray::ArrayD<f64>, y: &ndarray::ArrayD<f64>| {
            let mut squeezed = y.shape().to_vec();
            assert_eq!(squeezed.drain(at..at + 2).collect::<Vec<_>>(), [1, 1]);
            assert_eq!(squeezed, x.shape());
            let y: Vec<u64> = y.iter().map(|v| v.to_bits()).collect();
            let x: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
            assert_eq!(x, y);
        };
        let same = |x, y| same_at(1, x, y);
        same(&va.u_stack, &vb.u_stack);
        same(&va.u_single, &vb.u_single);
        same(&va.u_rigid, &vb.u_rigid);
        same(&va.a_stack, &vb.a_stack);
        same(&va.friction_energy, &vb.friction_energy);
        same(&va.slip_peak, &vb.slip_peak);
        same(&va.slip_residual, &vb.slip_residual);
        same(&va.block_accel_stack, &vb.block_accel_stack);
        same(&va.block_velocity_stack, &vb.block_velocity_stack);
        assert_eq!(
            va.skip_rule.iter().collect::<Vec<_>>(),
            vb.skip_rule.iter().collect::<Vec<_>>()
        );
        let ta = read_zone_tnew_in(&a.join("tnew.h5"), name, 2, false)
            .unwrap()
            .2;
        let tb = read_zone_tnew_in(&b.join("tnew.h5"), name, 2, true)
            .unwrap()
            .2;
        let (va, vb) = (&ta.vars, &tb.vars);
        same_at(0, &va.t_new, &vb.t_new);
        same_at(0, &va.t_rigid, &vb.t_rigid);
        same_at(0, &va.drr_1, &vb.drr_1);
        same_at(0, &va.drr_2, &vb.drr_2);
        same_at(0, &va.flag, &vb.flag);
        assert_eq!(
            va.band.iter().collect::<Vec<_>>(),
            vb.band.iter().collect::<Vec<_>>()
        );
        assert!(va.t_new.iter().any(|t| t.is_finite()));
    }
}

#[test]
fn a_building_study_refuses_what_it_cannot_do_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&str, &str, &str); 9] = [
        (
            "building: { storeys: [2, 3], storey_heights_m: [4, 3] }\n",
            "",
            "`building.storey_heights_m`: lists 2 values; a list needs one per storey",
        ),
        (
            "building: { storeys: 2, storey_heights_m: 0.1 }\n",
            "",
            "`building.storey_heights_m`: 0.1: a storey height must be within 0.5 … 100 m",
        ),
        (
            "",
            "  stack_floor: roof\n",
            "`grid.stack_floor`: needs a `building` section",
        ),
        (
            "building: { storeys: [3, 6] }\n",
            "  stack_floor: [1, 4]\n",
            "`grid.stack_floor`: floor 4 is not a floor of every building",
        ),
        (
            "building: { storeys: 3, period: 1.0 }\n",
            "",
            "`building.period`: a study's periods are `grid.period_s`",
        ),
        (
            "building: { storeys: [2, 3], floor_masses: [1, 1] }\n",
            "",
            "`building.floor_masses`: lists 2 values; it needs one per storey",
        ),
        (
            "building: { storeys: [3, 2] }\n",
            "",
            "`building.storeys`: values must be strictly increasing",
        ),
        (
            "building: { storeys: 2, structure: epp }\n",
            "",
            "`building.structure`: a building study's sweep is elastic",
        ),
        (
            "building: { storeys: 2 }\n",
            "  stack_floor: cellar\n",
            "`grid.stack_floor`: `cellar`: a floor number, `roof`, `mid` or `all`",
        ),
    ];
    for (i, (top, grid, want)) in cases.iter().enumerate() {
        let cfg = quick_with(d, &format!("c{i}.yaml"), top, grid);
        let o = slidestack(&["motions", cfg.to_str().unwrap(), "--out", "unused"], "1");
        assert_eq!(o.status.code(), Some(2), "{want}");
        assert!(stderr(&o).contains(want), "{}", stderr(&o));
    }
    let cfg = quick_with(d, "ida.yaml", "building: { storeys: 2 }\n", "");
    let text = std::fs::read_to_string(repo("configs/ida-quick.yaml")).unwrap();
    let ida = &text[text.find("ida:").unwrap()..];
    std::fs::write(&cfg, std::fs::read_to_string(&cfg).unwrap() + ida).unwrap();
    // The one-storey IDA's collapse criterion does not fit a building (tests/building_ida.rs
    // runs the IDA of a building).
    let o = slidestack(&["motions", cfg.to_str().unwrap(), "--out", "unused"], "1");
    assert!(
        stderr(&o).contains("`ida.collapse_ductility`: a building study's collapse is its peak"),
        "{}",
        stderr(&o)
    );
}

/// `stack_floor: mid` is the floor at mid-height, `⌈N/2⌉`: a five-storey study with the stack
/// at mid-height sweeps to the same bits as one with it on floor 3 (each simulated: two
/// studies), labelled `mid` in `sweep.h5` and by its floor in words.
#[test]
fn a_stack_at_mid_height_is_the_floor_at_half_the_height() {
    let dir = tempfile::tempdir().unwrap();
    let top = "building: { storeys: 5 }\n";
    let mid = quick_with(dir.path(), "mid.yaml", top, "  stack_floor: mid\n");
    let third = quick_with(dir.path(), "third.yaml", top, "  stack_floor: 3\n");
    let (a, b) = (dir.path().join("mid"), dir.path().join("third"));
    for (cfg, out) in [(&mid, &a), (&third, &b)] {
        ok(slidestack(&["motions", s(cfg), "--out", s(out)], "2"));
        ok(slidestack(&["sweep", s(cfg), "--out", s(out)], "2"));
    }
    let read = |out: &Path| read_zone_sweep(&out.join("sweep.h5"), "V", 2, true).unwrap();
    let ((_, axes_a, za), (_, axes_b, zb)) = (read(&a), read(&b));
    assert_eq!(axes_a.unwrap().stack_floor, [StackFloor::Mid]);
    assert_eq!(axes_b.unwrap().stack_floor, [StackFloor::Floor(3)]);
    assert!(za.vars.u_stack.iter().any(|&u| u > 0.0));
    assert_eq!(za.vars.u_stack, zb.vars.u_stack);
    assert_eq!(za.vars.slip_peak, zb.vars.slip_peak);
    let (ba, bb) = (za.building.unwrap(), zb.building.unwrap());
    assert_eq!(ba.storey_shear_stack, bb.storey_shear_stack);
    assert_eq!(ba.floor_accel_stack, bb.floor_accel_stack);
    let mid_height = [1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10];
    for (n, want) in (1..=20).zip(mid_height) {
        assert_eq!(StackFloor::Mid.floors(n), [want], "{n} storeys");
    }
    let frame = Frame {
        floor_masses: vec![1.0; 5],
        storey_stiffnesses: vec![1.0; 5],
        storey_heights_m: vec![3.0; 5],
        stack_floor: StackFloor::Mid,
    };
    assert_eq!(frame.floors(), [3]);
    assert_eq!(
        frame.to_string(),
        "5 storeys, stack at mid-height (floor 3)"
    );
    for f in [
        StackFloor::Floor(4),
        StackFloor::Roof,
        StackFloor::Mid,
        StackFloor::All,
    ] {
        assert_eq!(f.to_string().parse::<StackFloor>(), Ok(f));
    }
}

#[test]
fn a_building_study_of_one_frame_is_fitted_and_says_which() {
    // Three storeys, the stack on the roof: the fit over (T_1, α, μ), as on one storey.
    let dir = tempfile::tempdir().unwrap();
    let cfg = quick_with(dir.path(), "three.yaml", "building: { storeys: 3 }\n", "");
    let (c, out) = (cfg.to_str().unwrap(), dir.path().join("out"));
    let o = out.to_str().unwrap();
    for stage in ["motions", "sweep", "tnew", "fit"] {
        ok(slidestack(&[stage, c, "--out", o], "2"));
    }
    let text = std::fs::read_to_string(out.join("fit.yaml")).unwrap();
    assert!(
        text.contains("building: 3 storeys, stack on the roof"),
        "{text}"
    );
    // The report takes it: its building section has the one frame.
    ok(slidestack(&["report", c, "--out", o], "1"));
    let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(html.contains("<td>3 storeys, roof</td>"), "{html}");
    // Its design page with the one frame (tests/design_page.rs holds a building study's page
    // to `slidestack design`).
    let page = std::fs::read_to_string(out.join("report/design.html")).unwrap();
    assert!(
        page.contains("<option value='0'>3 storeys, stack on the roof</option>"),
        "{page}"
    );
    ok(slidestack(
        &[
            "design",
            "--study",
            o,
            "--zone",
            "V",
            "--period",
            "0.6",
            "--alpha",
            "1,1",
            "--mu",
            "0.3,0.1",
            "--storeys",
            "3",
            "--floor",
            "3",
        ],
        "1",
    ));
}
