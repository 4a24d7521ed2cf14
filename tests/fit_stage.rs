//! The fit stage end to end on configs/quick.yaml: every form fitted with standard errors,
//! metrics on all cases and cross-validated, the solver that converged, the box check, the
//! recommended form among those that pass it; the same `fit.yaml` whatever the thread count.

mod common;

use common::{ok, slidestack};

use slidestack::fit::Form;
use slidestack::fit::extrapolation::BOX_POINTS;
use slidestack::store::fit::read_fit;
use std::path::Path;

#[test]
fn fit_stage_on_the_quick_study() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quick.yaml");
    let cfg = cfg.to_str().unwrap();
    let out = dir.path().join("quick");
    let out_s = out.to_str().unwrap();
    let mut fit_stdout = String::new();
    for stage in ["motions", "sweep", "tnew", "fit"] {
        let o = ok(slidestack(&[stage, cfg, "--out", out_s], "2"));
        if stage == "fit" {
            fit_stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        }
    }
    // The stage says how long it took.
    assert!(
        fit_stdout
            .lines()
            .any(|l| l.starts_with("fit: 2 zones × 3 forms") && l.ends_with(" s")),
        "{fit_stdout}"
    );
    let yaml = out.join("fit.yaml");
    let report = read_fit(&yaml).unwrap().expect("fit.yaml verifies");
    assert_eq!(report.folds, 5);
    assert_eq!(
        report.features,
        ["T_p", "mu_1", "mu_2", "alpha_1", "alpha_2"]
    );
    assert_eq!(report.zones.len(), 2);
    for z in &report.zones {
        assert!(z.not_fitted.is_empty(), "{:?}", z.not_fitted);
        let forms: Vec<Form> = z.forms.iter().map(|f| f.form).collect();
        assert_eq!(forms, Form::FOR_T_NEW);
        for f in &z.forms {
            let m = f.form.parameter_count(5);
            assert_eq!(f.coefficients.len(), m);
            assert_eq!(f.standard_errors.len(), m);
            assert!(f.coefficients.iter().all(|c| c.1.is_finite()));
            assert_eq!(f.all_cases.n, z.cases);
            assert_eq!(f.cross_validated.n, z.cases);
            assert!(f.all_cases.r2.is_finite() && f.cross_validated.r2.is_finite());
            assert!(f.all_cases.rmse >= 0.0 && f.residual_std >= 0.0);
            assert_eq!(f.cv_solvers.len(), 5);
            assert!(f.solver.relative_offset.is_finite(), "{:?}", f.solver);
            // Corners (2⁵) and the quasi-random points.
            assert_eq!(f.box_check.points, 32 + BOX_POINTS);
            if f.form.bounded_by_construction() {
                assert!(f.box_check.passed, "{:?}: {:?}", f.form, f.box_check);
            }
            assert!(!f.equation.is_empty());
        }
        // The recommended form passes the box check and has the best cross-validated R² of
        // those that do.
        let rec = z.recommended_fit().unwrap();
        assert!(rec.box_check.passed);
        for f in z.forms.iter().filter(|f| f.box_check.passed) {
            assert!(f.cross_validated.r2 <= rec.cross_validated.r2);
        }
        assert!(z.recommendation.contains("best cross-validated R²"));
        // The published Eqs. 16–17 apply to zones III and V with two blocks.
        assert!(z.published.is_some());
    }
    // One thread gives the same file as two.
    let first = std::fs::read(&yaml).unwrap();
    ok(slidestack(&["fit", cfg, "--out", out_s, "--force"], "1"));
    assert_eq!(std::fs::read(&yaml).unwrap(), first);
}
