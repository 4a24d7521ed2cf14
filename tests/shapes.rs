//! Every stage reader checks each array against the shape its dimensions give. Each test writes
//! a valid stage file with the library's own writer, then gives one variable another shape and a
//! fresh checksum sidecar (`common::reshape`): the sidecar check passes, so only the shape check
//! can refuse the file, with an error naming the file and the variable.

mod common;

use common::reshape;
use ndarray::{ArrayD, IxDyn};
use slidestack::fit::{Form, metrics};
use slidestack::grid::Grid;
use slidestack::ground_motion::Record;
use slidestack::ground_motion::matching::MatchReport;
use slidestack::ground_motion::set::ZoneMotions;
use slidestack::spectrum::TargetSpectrum;
use slidestack::store::StoreError;
use slidestack::store::fit::{FitReport, FormFit, ZoneFit, read_fit, write_fit};
use slidestack::store::ida::{IdaAxes, IdaMeta, IdaVars, ZoneIda, read_zone_ida, write_ida};
use slidestack::store::motions::{
    StageMeta, read_zone_motions, read_zone_report, read_zone_spectra, read_zone_target,
    write_motions,
};
use slidestack::store::sweep::{SweepMeta, SweepVars, ZoneSweep, read_zone_sweep, write_sweep};
use slidestack::store::tnew::{TnewMeta, TnewVars, ZoneTnew, read_zone_tnew, write_tnew};
use std::path::{Path, PathBuf};

fn zeros<T: Clone + Default>(shape: &[usize]) -> ArrayD<T> {
    ArrayD::from_elem(IxDyn(shape), T::default())
}

/// Refused with [`StoreError::Shape`] naming `path` and `variable`.
fn assert_refused<T: std::fmt::Debug>(r: Result<T, StoreError>, path: &Path, variable: &str) {
    match r {
        Err(StoreError::Shape {
            file, variable: v, ..
        }) => {
            assert_eq!((file.as_path(), v.as_str()), (path, variable));
        }
        other => panic!("{variable}: expected a shape error, got {other:?}"),
    }
}

/// For each of `variables`, a fresh file from `write` with that variable reshaped, read by
/// `read`, which must refuse it naming the variable (`zone_III/` in front).
fn each_variable<T: std::fmt::Debug>(
    variables: &[&str],
    write: impl Fn(&Path),
    read: impl Fn(&Path, &str) -> Result<T, StoreError>,
) {
    let dir = tempfile::tempdir().unwrap();
    for (i, v) in variables.iter().enumerate() {
        let path = dir.path().join(format!("{i}.h5"));
        write(&path);
        read(&path, v).unwrap();
        let variable = format!("zone_III/{v}");
        reshape(&path, &variable);
        assert_refused(read(&path, v), &path, &variable);
    }
}

fn grid() -> Grid {
    Grid {
        periods_s: vec![0.5, 1.0],
        alpha: vec![vec![0.5]],
        mu: vec![vec![0.1, 0.2]],
    }
}

fn write_sweep_file(path: &Path) {
    let shape = [2, 2, 1, 2];
    let zone = ZoneSweep {
        name: "III".into(),
        target: "is1893:zone=III,soil=I".into(),
        motions: vec!["a".into(), "b".into()],
        vars: SweepVars {
            u_stack: zeros(&shape),
            u_single: zeros(&shape),
            u_rigid: zeros(&shape),
            a_stack: zeros(&shape),
            friction_energy: zeros(&shape),
            slip_peak: zeros(&[2, 2, 1, 2, 1]),
            slip_residual: zeros(&[2, 2, 1, 2, 1]),
            block_accel_stack: zeros(&[2, 2, 1, 2, 1]),
            block_velocity_stack: zeros(&[2, 2, 1, 2, 1]),
            skip_rule: zeros(&shape),
            single_rule: zeros(&shape),
        },
        rocks_stack: None,
        building: None,
    };
    let meta = SweepMeta {
        fingerprint: "f",
        config_sha256: "c",
        motions_fingerprint: "m",
        skip_rule_codes: "",
        skip_rule_flags: &[(0, "simulated")],
        mu_static_ratio: 1.0,
        settings: &[],
    };
    write_sweep(path, &meta, &grid(), None, &[zone]).unwrap();
}

#[test]
fn sweep_h5() {
    // The coordinates, then every declared variable.
    let mut variables = vec!["motion", "T_p", "alpha_1", "mu_1"];
    variables.extend(SweepVars::VARS.iter().map(|v| v.name));
    each_variable(&variables, write_sweep_file, |p, _| {
        read_zone_sweep(p, "III", 1, false)
    });
}

const BAND_FLAGS: [(u8, &str); 2] = [(0, "band"), (5, "no_slide")];

fn tnew_zone(band: u8) -> ZoneTnew {
    let shape = [2, 1, 2];
    ZoneTnew {
        name: "III".into(),
        target: "is1893:zone=III,soil=I".into(),
        vars: TnewVars {
            u_stack_mean: zeros(&shape),
            u_single_mean: zeros(&shape),
            u_rigid_mean: zeros(&shape),
            t_rigid: zeros(&shape),
            t_new: zeros(&shape),
            drr_1: zeros(&shape),
            drr_2: zeros(&shape),
            slides: zeros(&shape),
            flag: zeros(&shape),
            band: ArrayD::from_elem(IxDyn(&shape), band),
        },
        rocks_share: None,
        period_sd_s: vec![0.1, 0.2, 0.3],
        sd_mean_m: vec![0.0; 3],
        roof_participation: Vec::new(),
        lambda: None,
    }
}

fn write_tnew_with(path: &Path, zone: ZoneTnew, flags: &[(u8, &str)]) {
    let meta = TnewMeta {
        fingerprint: "f",
        sweep_fingerprint: "s",
        motions_fingerprint: "m",
        flag_codes: "",
        band_flags: flags,
        lambda_flags: &[],
        mu_static_ratio: 1.0,
        settings: &[],
    };
    write_tnew(path, &meta, &grid(), None, &[zone]).unwrap();
}

#[test]
fn tnew_h5() {
    let mut variables = vec!["T_p", "alpha_1", "mu_1"];
    variables.extend(TnewVars::VARS.iter().map(|v| v.name));
    variables.extend(["period_sd", "sd_mean"]);
    each_variable(
        &variables,
        |p| write_tnew_with(p, tnew_zone(0), &BAND_FLAGS),
        |p, _| read_zone_tnew(p, "III", 1),
    );
    // A band code that is not one of the variable's flag_values, and a flag word too many: the
    // report counts cases by code, so neither may pass.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("code.h5");
    write_tnew_with(&p, tnew_zone(7), &BAND_FLAGS);
    let e = read_zone_tnew(&p, "III", 1).unwrap_err().to_string();
    assert!(
        e.ends_with("zone_III/T_new_band holds code 7, which is not one of its flag_values"),
        "{e}"
    );
    let p = dir.path().join("words.h5");
    write_tnew_with(&p, tnew_zone(0), &[(0, "band"), (5, "no slide")]);
    assert_refused(
        read_zone_tnew(&p, "III", 1),
        &p,
        "zone_III/T_new_band@flag_meanings",
    );
}

fn report() -> MatchReport {
    MatchReport {
        converged: true,
        iterations: 1,
        attempts: 1,
        stalls: 0,
        worst_misfit: 0.0,
        worst_period_s: 1.0,
        worst_ratio: 1.0,
        scale: 1.0,
        target_factor: 1.0,
        pga_before_g: 0.1,
        pga_after_g: 0.1,
        final_velocity_mps: 0.0,
        final_displacement_m: 0.0,
        arias_ratio: 1.0,
    }
}

fn write_motions_file(path: &Path) {
    let motion = |name: &str| Record {
        name: name.into(),
        dt_s: 0.01,
        accel_g: vec![0.0, 0.1, 0.0],
    };
    let zone = ZoneMotions {
        name: "III".into(),
        target: TargetSpectrum::Table {
            source: "t.txt".into(),
            periods_s: vec![0.1, 1.0, 4.0],
            sa_g: vec![0.4, 0.2, 0.05],
        },
        periods_s: vec![0.1, 1.0],
        target_psa_g: vec![0.4, 0.2],
        seeds: vec!["a".into(), "b".into()],
        reports: vec![report(), report()],
        kept: vec![0, 1],
        motions: vec![motion("a"), motion("b")],
        psa_g: vec![vec![0.4, 0.2]; 2],
        mean_psa_g: vec![0.4, 0.2],
        set_scale: 1.0,
        mean_ratio_min: 1.0,
        set_mean_ok: true,
        asce7_ok: true,
        all_within_band: true,
        unmatched: Vec::new(),
    };
    let meta = StageMeta {
        fingerprint: "f".into(),
        config_sha256: "c".into(),
        inputs: "[]".into(),
    };
    write_motions(
        path,
        &meta,
        &[motion("a"), motion("b")],
        &[(zone, "z".into())],
    )
    .unwrap();
}

#[test]
fn motions_h5() {
    each_variable(
        &["period", "target_psa_g", "mean_psa_g", "psa_g", "motion"],
        write_motions_file,
        |p, _| read_zone_spectra(p, "III"),
    );
    each_variable(
        &["motion", "accel/motion_00", "accel/motion_01"],
        write_motions_file,
        |p, _| read_zone_motions(p, "III"),
    );
    each_variable(&["seed", "converged"], write_motions_file, |p, _| {
        read_zone_report(p, "III")
    });
    each_variable(
        &["target_table_period", "target_table_sa_g"],
        write_motions_file,
        |p, _| read_zone_target(p, "III"),
    );
    // One motion fewer than the zone's list names.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.h5");
    write_motions_file(&p);
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        f.group("zone_III/accel")
            .unwrap()
            .unlink("motion_01")
            .unwrap();
    }
    let bytes = std::fs::read(&p).unwrap();
    slidestack::store::checksum::write_with_sidecar(&p, &bytes).unwrap();
    assert_refused(read_zone_motions(&p, "III"), &p, "zone_III/accel");
}

fn write_ida_file(path: &Path) {
    let (s, r, c, n, d, g, l, q) = (2, 1, 1, 2, 4, 3, 1, 3);
    let axes = IdaAxes {
        systems: vec!["stack".into(), "rigid".into()],
        case_period_s: vec![1.0],
        case_alpha: vec![vec![0.5]],
        case_mu: vec![vec![0.2]],
        runs: n,
        sa_grid_g: vec![0.1, 0.2, 0.3],
        demands: [
            "ductility",
            "residual_drift_m",
            "peak_slip_1_m",
            "residual_slip_1_m",
        ]
        .map(String::from)
        .to_vec(),
        limit_states: vec!["DL".into()],
        limit_state_definitions: vec!["ductility >= 2".into()],
        fractiles: vec![0.16, 0.5, 0.84],
        building: None,
    };
    let fit = [s, c, l];
    let vars = IdaVars {
        record_sa_g: zeros(&[r, c]),
        run_sa_g: zeros(&[s, r, c, n]),
        run_demand: zeros(&[s, r, c, n, d]),
        run_collapsed: zeros(&[s, r, c, n]),
        run_slip_exceeded: zeros(&[s, r, c, n]),
        collapse_sa_g: zeros(&[s, r, c]),
        curve: zeros(&[s, r, c, g, d]),
        fractile_curve: zeros(&[s, c, q, g, d]),
        exceed_fraction: zeros(&[s, c, l, g]),
        fragility_curve: zeros(&[s, c, l, g]),
        theta_sa_g: zeros(&fit),
        beta: zeros(&fit),
        theta_ci_low_sa_g: zeros(&fit),
        theta_ci_high_sa_g: zeros(&fit),
        beta_ci_low: zeros(&fit),
        beta_ci_high: zeros(&fit),
        fit_status: zeros(&fit),
    };
    let zone = ZoneIda {
        name: "III".into(),
        target: "is1893:zone=III,soil=I".into(),
        records: vec!["a".into()],
        c_y: zeros(&[c]),
        storey_c_y: None,
        vars,
    };
    let meta = IdaMeta {
        fingerprint: "f",
        motions_fingerprint: "m",
        config_sha256: "c",
        fit_flags: &[(0, "fitted")],
        settings: &[],
    };
    write_ida(path, &meta, &axes, &[zone]).unwrap();
}

#[test]
fn ida_h5() {
    // The coordinates, the cases and their strengths, then every declared variable.
    let mut variables = vec![
        "system",
        "record",
        "case",
        "block",
        "run",
        "Sa",
        "demand",
        "limit_state",
        "limit_state_definition",
        "fractile",
        "case_T_p",
        "case_alpha",
        "case_mu",
        "c_y",
    ];
    variables.extend(IdaVars::VARS.iter().map(|v| v.name));
    each_variable(&variables, write_ida_file, |p, _| read_zone_ida(p, "III"));
}

fn fit_report(coefficients: usize) -> FitReport {
    let m = metrics(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.5]);
    let form = Form::Bounded;
    FitReport {
        slidestack_version: "0".into(),
        fingerprint: "f".into(),
        features: slidestack::fit::feature_names(1),
        folds: 5,
        building: None,
        zones: vec![ZoneFit {
            zone: "III".into(),
            cases: 3,
            forms: vec![FormFit {
                form,
                coefficients: (0..coefficients).map(|i| (format!("w{i}"), 0.1)).collect(),
                standard_errors: vec![0.01; form.parameter_count(3)],
                all_cases: m,
                cross_validated: m,
                equation: String::new(),
                objective: String::new(),
                residual_std: 0.0,
                condition_number: 1.0,
                solver: Default::default(),
                cv_solvers: Vec::new(),
                box_check: Default::default(),
            }],
            recommended: form,
            published: None,
            recommendation: String::new(),
            not_fitted: Vec::new(),
            frames: Vec::new(),
            one_storey: None,
            lambda: None,
        }],
        frames: Vec::new(),
    }
}

#[test]
fn fit_yaml() {
    // The bounded form has one weight per feature and w_0: 4 for one block (T_p, μ_1, α_1).
    let dir = tempfile::tempdir().unwrap();
    let (h5, yaml): (PathBuf, PathBuf) = (dir.path().join("fit.h5"), dir.path().join("fit.yaml"));
    write_fit(&h5, &yaml, &fit_report(4)).unwrap();
    let good = read_fit(&yaml).unwrap().unwrap();
    good.check_blocks(&yaml, 1).unwrap();
    let e = good.check_blocks(&yaml, 2).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "its features (T_p, mu_1, alpha_1) are not those of the study's 2-block stacks"
        ),
        "{e}"
    );
    write_fit(&h5, &yaml, &fit_report(3)).unwrap();
    assert!(slidestack::store::checksum::verify(&yaml).unwrap());
    assert_refused(
        read_fit(&yaml),
        &yaml,
        "zone III, bounded form: coefficients",
    );
}
