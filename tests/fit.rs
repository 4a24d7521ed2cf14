//! The design-equation fit (`slidestack::fit`) against independent oracles: central finite
//! differences for every analytic Jacobian, noise-free synthetic data for every form, the
//! standard errors against the spread of refits to noisy data, the box check (finite and inside
//! `[½·T_p, 1.5·T_rigid]` 25 % beyond the grid) of the recommended form with the coefficients
//! fitted to the paper grid, and the issue's goals refitted from the committed paper-grid data.

use slidestack::fit::extrapolation::{BOX_MARGIN, BOX_POINTS};
use slidestack::fit::{
    DesignBox, Fitted, Form, Method, Sample, check_box, cross_validate, fit, metrics,
    paper_equation, uncertainty,
};
use std::path::Path;

/// A grid of cases like the paper's (5 features, `T_rigid = T_p·√(1 + α_1 + α_2)`), `T_new`
/// from `t_new` of each case.
fn grid(t_new: impl Fn(&Sample) -> f64) -> Vec<Sample> {
    let mut v = Vec::new();
    for tp in [0.2, 0.6, 1.0, 1.4, 1.8] {
        for m1 in [0.05, 0.2, 0.4, 0.6] {
            for m2 in [0.1, 0.3, 0.7] {
                for a1 in [0.1f64, 0.5, 1.0] {
                    for a2 in [0.1f64, 1.0] {
                        let mut s = Sample {
                            x: vec![tp, m1, m2, a1, a2],
                            t_rigid_s: tp * (1.0 + a1 + a2).sqrt(),
                            t_new_s: 0.0,
                        };
                        s.t_new_s = t_new(&s);
                        v.push(s);
                    }
                }
            }
        }
    }
    v
}

/// Parameters of every form that make a plausible `T_new` on [`grid`].
fn truths() -> Vec<(Form, Vec<f64>)> {
    vec![
        (
            Form::Paper,
            vec![0.5, 0.2, 0.1, 0.3, 0.2, 0.4, 0.3, -0.2, 0.1, 0.2, 0.7, -0.5],
        ),
        (Form::Bounded, vec![0.8, 2.0, 1.5, -0.4, -0.3, -1.0]),
        (
            Form::Damped,
            vec![
                1.5, 2.0, 0.3, 0.5, 0.4, 0.3, 2.0, -1.0, 0.5, -1.5, 0.3, 0.2, -0.5, -1.0,
            ],
        ),
        // A fraction (a building's λ) falling with T_p and rising with μ: 0.03 … 0.99.
        (Form::Fraction, vec![-1.2, 0.8, 0.3, 0.2, -0.1, 0.4, 1.0]),
    ]
}

#[test]
fn jacobians_match_central_differences() {
    // Central differences with h_j = 1e-6·max(1, |p_j|): the truncation error h²·|f'''|/6 is
    // below 1e-9 here, so 1e-7·(1 + |∂T/∂p|) leaves a margin of 100; the round-off
    // ε·|T_new|/h of the difference is added (10 ε, for the paper form's e^{c·x} of 1e5 at the
    // steep point). Points: the truths, moved, steep (logistic terms saturating), and every
    // start.
    let data = grid(|_| 0.0);
    for (form, truth) in truths() {
        let moved: Vec<f64> = truth
            .iter()
            .enumerate()
            .map(|(j, v)| 3.0 * v + 0.1 * j as f64)
            .collect();
        let steep: Vec<f64> = truth.iter().map(|v| 8.0 * v).collect();
        let mut points = vec![truth.clone(), moved, steep];
        points.extend(form.starts(5));
        let m = truth.len();
        for p in &points {
            for s in data.iter().step_by(7) {
                let z = form.regressors(&s.x);
                let mut g = vec![0.0; m];
                let t = form.evaluate(p, &z, s.t_p_s(), s.t_rigid_s, Some(&mut g));
                assert!((t - form.predict(p, s)).abs() <= 1e-15 * t.abs().max(1.0));
                for j in 0..m {
                    let h = 1e-6 * p[j].abs().max(1.0);
                    let (mut up, mut down) = (p.clone(), p.clone());
                    up[j] += h;
                    down[j] -= h;
                    let fd = (form.predict(&up, s) - form.predict(&down, s)) / (2.0 * h);
                    let round_off = 10.0 * f64::EPSILON * t.abs() / h;
                    assert!(
                        (g[j] - fd).abs() <= 1e-7 * (1.0 + g[j].abs()) + round_off,
                        "{form:?} ∂/∂p_{j} at {p:?}, x {:?}: analytic {} vs {fd}",
                        s.x,
                        g[j]
                    );
                }
            }
        }
    }
}

#[test]
fn known_coefficients_are_recovered_from_noise_free_data() {
    // Data made by each form itself: the trust region converges (Gauss–Newton is quadratic
    // on a zero-residual problem) to an exact fit, residuals below 1e-9 s RMS, and the
    // coefficients to 1e-6 (the data's round-off, 1e-16 s, amplified by the conditioning).
    for (form, truth) in truths() {
        let data = grid(|s| form.predict(&truth, s));
        let sol = fit(form, &data).unwrap();
        assert_eq!(sol.solver.method, Method::TrustRegion, "{form:?}");
        assert!(sol.solver.converged, "{form:?}: {:?}", sol.solver);
        let obs: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
        let pred: Vec<f64> = data.iter().map(|s| sol.fitted.predict(s)).collect();
        let m = metrics(&obs, &pred);
        assert!(m.rmse < 1e-9, "{form:?}: {m:?}");
        for (p, t) in sol.fitted.params.iter().zip(&truth) {
            assert!(
                (p - t).abs() < 1e-6 * t.abs().max(1.0),
                "{form:?}: {:?}",
                sol.fitted.params
            );
        }
    }
}

/// Deterministic standard normal deviates (SplitMix64 and Box–Muller).
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

#[test]
fn standard_errors_match_the_spread_of_refits() {
    // The oracle: refit the same form to 200 data sets of truth + noise of the kind each form's
    // least squares assume (N(0, 0.01 s) for the bounded form, N(0, 0.01·T_p) for the damped
    // form fitted to T_new/T_p); the standard deviation of each estimate over the refits is
    // what the standard error estimates. With 200 refits that deviation carries 1/√400 = 5 % sampling error, and the
    // linearisation behind s²·(JᵀJ)⁻¹ is exact to first order in the noise: agreement to 20 %
    // (4 sampling σ). Checked for the bounded and damped forms (the paper form's near
    // degeneracy makes a linearised error a poor guide, which is why its errors can be NaN).
    for (form, truth) in truths().into_iter().skip(1) {
        let clean = grid(|s| form.predict(&truth, s));
        let mut rng = Normal(11);
        let runs = 200;
        let m = truth.len();
        let mut estimates = vec![Vec::with_capacity(runs); m];
        let mut reported = vec![0.0; m];
        for run in 0..runs {
            let noisy: Vec<Sample> = clean
                .iter()
                .map(|s| Sample {
                    t_new_s: s.t_new_s + 0.01 / form.weight(s.t_p_s()) * rng.next(),
                    ..s.clone()
                })
                .collect();
            let sol = fit(form, &noisy).unwrap();
            for (e, p) in estimates.iter_mut().zip(&sol.fitted.params) {
                e.push(*p);
            }
            if run == 0 {
                reported = uncertainty(&sol.fitted, &noisy).unwrap().standard_errors;
            }
        }
        for (j, e) in estimates.iter().enumerate() {
            let mean = e.iter().sum::<f64>() / runs as f64;
            let sd = (e.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs - 1) as f64).sqrt();
            assert!(
                (reported[j] / sd - 1.0).abs() < 0.2,
                "{form:?} parameter {j}: standard error {} vs spread {sd}",
                reported[j]
            );
        }
    }
}

/// The paper grid's `T_new` (configs/paper.yaml with the rigid damping basis, main aaef5a7):
/// features and `T_new` of zones III and V, every case.
fn paper_grid() -> (Vec<Sample>, Vec<Sample>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fit/paper_grid_tnew.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let (mut iii, mut v) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let x = f[..5].to_vec();
        let t_rigid_s = x[0] * (1.0 + x[3] + x[4]).sqrt();
        iii.push(Sample {
            x: x.clone(),
            t_rigid_s,
            t_new_s: f[5],
        });
        v.push(Sample {
            x,
            t_rigid_s,
            t_new_s: f[6],
        });
    }
    (iii, v)
}

/// The recommended (damped) form's coefficients fitted to [`paper_grid`] (`w_ln_T_p …
/// w_ln_alpha_2, w_ln_T_p_sq, w_0`, then the same for `v`); `fit.yaml` of configs/paper.yaml
/// gives the same to about 1e-5 (its `T_new` are not rounded).
const DAMPED_III: [f64; 14] = [
    5.165645093140098,
    4.493136691853178,
    -0.19638043616186687,
    0.5200600481055525,
    0.5756875158916341,
    1.4080585049361005,
    12.77344213381178,
    -3.237499089166902,
    0.947710154933748,
    -2.5402135252257105,
    -0.21346391721609098,
    1.2403573378670603,
    -1.2614772507751033,
    -6.606041242837897,
];
const DAMPED_V: [f64; 14] = [
    3.645934360288069,
    4.260069596751396,
    -1.2922334308053254,
    0.2431708648772153,
    0.8198413760647997,
    0.6441791234487702,
    8.384430859246793,
    -1.7014284842184162,
    -0.5299678774846591,
    -1.578600394050326,
    -0.056489785612074794,
    0.9833138398314013,
    -0.9670209556485465,
    -3.5826363810381046,
];

/// The paper grid's box 25 % beyond its axes: T_p 0.1–2.0 s, μ_1 0.05–0.6, μ_2 0.05–0.7,
/// α_i 0.1–1.0.
fn paper_box() -> DesignBox {
    DesignBox::beyond(
        &[(0.1, 2.0), (0.05, 0.6), (0.05, 0.7), (0.1, 1.0), (0.1, 1.0)],
        BOX_MARGIN,
    )
}

#[test]
fn recommended_form_stays_physical_on_the_box_beyond_the_grid() {
    // The damped form is bounded by construction (½·T_p ≤ T_new ≤ T_rigid for any finite
    // parameters): the check confirms the theorem at the 32 corners and 20,000 Halton points,
    // and that the extremes found lie inside the bounds (measured: T_new/T_p ≥ 0.72 in Zone III
    // and ≥ 0.54 in Zone V on this box).
    let bx = paper_box();
    assert!((bx.lower[0] - 0.075).abs() < 1e-15 && (bx.upper[2] - 0.875).abs() < 1e-15);
    for params in [DAMPED_III, DAMPED_V] {
        let f = Fitted {
            form: Form::Damped,
            params: params.to_vec(),
        };
        let c = check_box(&f, &bx, 20_000, BOX_MARGIN);
        assert!(c.passed, "{c:?}");
        assert_eq!(c.points, 32 + 20_000);
        assert!(
            c.min_t_new_over_t_p >= 0.5 && c.max_t_new_over_t_rigid <= 1.0,
            "{c:?}"
        );
    }
    // The check does catch a form that leaves the band: the published Eq. 16 gives 0.016 s at
    // T_p = 0.1 s, small μ, α = 0.1 (docs/model.md, "The design equations"), far below ½·T_p.
    let (a, b, c, d, e) = (
        [-4.284, -0.173, 0.015, -4.365, -4.567],
        2.022f64,
        [0.053, 0.003, 0.002, 0.044, 0.045],
        3.873f64,
        -97.3,
    );
    let mut p = a.to_vec();
    p.extend(c);
    p.extend([b * d.exp(), e]);
    let eq16 = Fitted {
        form: Form::Paper,
        params: p,
    };
    let x = [0.7, 0.3, 0.1, 1.0, 1.0];
    let s = Sample {
        x: x.to_vec(),
        t_rigid_s: 0.7 * 3f64.sqrt(),
        t_new_s: f64::NAN,
    };
    assert!((eq16.predict(&s) - paper_equation("III", &x).unwrap()).abs() < 1e-12);
    let check = check_box(&eq16, &bx, BOX_POINTS, BOX_MARGIN);
    assert!(!check.passed && check.min_t_new_over_t_p < 0.5, "{check:?}");
}

#[test]
fn paper_grid_meets_the_goals_of_issue_11() {
    // Refit from the committed data: R² ≥ 0.985 (III) and ≥ 0.969 (V), the 5-fold
    // cross-validated R² within 0.01 of it, and the coefficients those of the box test (to
    // 1e-4 relative: the solver stops within 1e-4 of the statistical uncertainty, and the
    // committed T_new are rounded to 7 digits).
    let (iii, v) = paper_grid();
    for (data, goal, fixture) in [(iii, 0.985, DAMPED_III), (v, 0.969, DAMPED_V)] {
        let sol = fit(Form::Damped, &data).unwrap();
        assert!(sol.solver.converged && sol.solver.method == Method::TrustRegion);
        let obs: Vec<f64> = data.iter().map(|s| s.t_new_s).collect();
        let pred: Vec<f64> = data.iter().map(|s| sol.fitted.predict(s)).collect();
        let all = metrics(&obs, &pred);
        let cv = cross_validate(Form::Damped, &data, 5).unwrap();
        assert!(all.r2 >= goal, "{all:?}");
        assert!(
            (all.r2 - cv.metrics.r2).abs() < 0.01,
            "{all:?} {:?}",
            cv.metrics
        );
        for (p, q) in sol.fitted.params.iter().zip(fixture) {
            assert!(
                (p - q).abs() <= 1e-4 * q.abs().max(1.0),
                "{:?}",
                sol.fitted.params
            );
        }
        let check = check_box(&sol.fitted, &paper_box(), BOX_POINTS, BOX_MARGIN);
        assert!(check.passed, "{check:?}");
    }
}
