//! Lognormal fragility functions fitted by maximum likelihood to multiple-stripe data (Baker
//! 2015, "Efficient analytical fragility function fitting using dynamic structural analysis",
//! Earthquake Spectra 31(1), Eq. 11):
//!
//! `P(exceed | Sa = x) = Φ(ln(x/θ)/β)`; at stripe `j` (intensity `x_j`) `z_j` of `n_j` runs
//! exceed; the stripes are independent binomial observations and `(θ, β)` maximise
//! `Σ_j z_j·ln Φ(u_j) + (n_j − z_j)·ln Φ(−u_j)`, `u_j = (ln x_j − ln θ)/β`.
//!
//! The maximum is found by a coarse grid over `(ln θ, ln β)` then Newton steps with analytic
//! derivatives and step halving. Confidence intervals are Wald intervals from the observed
//! information matrix (the negative Hessian in `(ln θ, β)` at the maximum), on `ln θ` and on
//! `ln β` (delta method), at 95 %.

use crate::numeric::special::normal_cdf;

/// `β` is sought in this range; a maximum on its edge is [`FitStatus::Degenerate`] (stripes
/// perfectly separated: every stripe below some intensity has no exceedance, every one above
/// only exceedances).
pub const BETA_RANGE: (f64, f64) = (1e-3, 10.0);

/// The two-sided 95 % standard normal quantile.
pub const Z_95: f64 = 1.959_963_984_540_054;

flag_enum! {
    /// How a fit ended (stored as a code).
    pub enum FitStatus;
    /// `(code, word)` pairs for the CF flag attributes.
    pub const FIT_STATUS_FLAGS;
    {
        Fitted = 0 => "fitted",
        /// No stripe has an exceedance: `θ` is above the data.
        NoExceedance = 1 => "no_exceedance",
        /// Every run of every stripe exceeds: `θ` is below the data.
        AllExceed = 2 => "all_exceed",
        /// `β` on the edge of [`BETA_RANGE`], fewer than two stripes with some but not all runs
        /// exceeding (`(θ, β)` then lie on a ridge of equal likelihood), or a singular information
        /// matrix: the estimates are kept, without intervals.
        Degenerate = 3 => "degenerate",
    }
}

/// A fitted fragility function; NaN where the status gives no value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fragility {
    /// Median capacity `θ`, g.
    pub theta_sa_g: f64,
    /// Logarithmic standard deviation `β`.
    pub beta: f64,
    /// 95 % Wald interval of `θ`, g.
    pub theta_ci_sa_g: (f64, f64),
    /// 95 % Wald interval of `β`.
    pub beta_ci: (f64, f64),
    pub log_likelihood: f64,
    pub status: FitStatus,
}

impl Fragility {
    /// `Φ(ln(x/θ)/β)`.
    pub fn probability(&self, sa_g: f64) -> f64 {
        normal_cdf((sa_g / self.theta_sa_g).ln() / self.beta)
    }
}

/// The log-likelihood of `(ln θ, β)` for stripes at intensities whose natural logarithms are
/// `ln_sa` (`ln` of g) with `trials` runs of which `exceed` exceed (the binomial coefficients
/// left out).
pub fn log_likelihood(
    ln_sa: &[f64],
    trials: &[u32],
    exceed: &[u32],
    ln_theta: f64,
    beta: f64,
) -> f64 {
    let mut l = 0.0;
    for ((ln_x, &n), &z) in ln_sa.iter().zip(trials).zip(exceed) {
        let u = (ln_x - ln_theta) / beta;
        if z > 0 {
            l += z as f64 * normal_cdf(u).ln();
        }
        if n > z {
            l += (n - z) as f64 * normal_cdf(-u).ln();
        }
    }
    l
}

/// `φ(u)/Φ(u)`, with its asymptote where `Φ` underflows.
fn mills(u: f64) -> f64 {
    let cdf = normal_cdf(u);
    if cdf > 1e-290 {
        (-0.5 * u * u).exp() / (std::f64::consts::TAU.sqrt() * cdf)
    } else {
        -u - 1.0 / u
    }
}

/// Gradient and Hessian of the log-likelihood in `(ln θ, β)` ([`log_likelihood`]'s
/// arguments).
pub fn derivatives(
    ln_sa: &[f64],
    trials: &[u32],
    exceed: &[u32],
    ln_theta: f64,
    beta: f64,
) -> ([f64; 2], [[f64; 2]; 2]) {
    let (mut g, mut h) = ([0.0; 2], [[0.0; 2]; 2]);
    for ((ln_x, &n), &z) in ln_sa.iter().zip(trials).zip(exceed) {
        let u = (ln_x - ln_theta) / beta;
        let (z, rest) = (z as f64, (n - z) as f64);
        let (hu, ku) = (mills(u), mills(-u));
        let d1 = z * hu - rest * ku;
        let d2 = -z * hu * (u + hu) - rest * ku * (ku - u);
        g[0] -= d1 / beta;
        g[1] -= d1 * u / beta;
        let b2 = beta * beta;
        h[0][0] += d2 / b2;
        h[0][1] += (d2 * u + d1) / b2;
        h[1][1] += (d2 * u * u + 2.0 * d1 * u) / b2;
    }
    h[1][0] = h[0][1];
    (g, h)
}

/// Fits `(θ, β)` to stripes at intensities `sa_g` (g, > 0) with `trials` runs of which
/// `exceed` exceed the limit state (module doc).
pub fn fit_lognormal(sa_g: &[f64], trials: &[u32], exceed: &[u32]) -> Fragility {
    let nan = Fragility {
        theta_sa_g: f64::NAN,
        beta: f64::NAN,
        theta_ci_sa_g: (f64::NAN, f64::NAN),
        beta_ci: (f64::NAN, f64::NAN),
        log_likelihood: f64::NAN,
        status: FitStatus::NoExceedance,
    };
    if exceed.iter().all(|&z| z == 0) {
        return nan;
    }
    if exceed.iter().zip(trials).all(|(z, n)| z == n) {
        return Fragility {
            status: FitStatus::AllExceed,
            ..nan
        };
    }
    // The logarithms once: the grid search below evaluates the likelihood 3,321 times.
    let ln_sa: Vec<f64> = sa_g.iter().map(|x| x.ln()).collect();
    let ll = |m: f64, b: f64| log_likelihood(&ln_sa, trials, exceed, m, b.exp());
    let (lo, hi) = ln_sa
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let (b_lo, b_hi) = (BETA_RANGE.0.ln(), BETA_RANGE.1.ln());
    let mut best = (lo, b_lo, f64::NEG_INFINITY);
    for i in 0..=80 {
        let m = lo - 1.0 + (hi - lo + 2.0) * i as f64 / 80.0;
        for j in 0..=40 {
            let b = b_lo + (b_hi - b_lo) * j as f64 / 40.0;
            let l = ll(m, b);
            if l > best.2 {
                best = (m, b, l);
            }
        }
    }
    let (mut m, mut b, mut l) = best;
    for _ in 0..200 {
        let beta = b.exp();
        let (g, h) = derivatives(&ln_sa, trials, exceed, m, beta);
        // In (m, ln β): ∂/∂ln β = β·∂/∂β.
        let gb = [g[0], beta * g[1]];
        let hb = [
            [h[0][0], beta * h[0][1]],
            [beta * h[0][1], beta * beta * h[1][1] + beta * g[1]],
        ];
        let det = hb[0][0] * hb[1][1] - hb[0][1] * hb[1][0];
        let mut step = if hb[0][0] < 0.0 && det > 0.0 {
            [
                -(hb[1][1] * gb[0] - hb[0][1] * gb[1]) / det,
                -(hb[0][0] * gb[1] - hb[1][0] * gb[0]) / det,
            ]
        } else {
            let scale = 0.1 / (gb[0].hypot(gb[1])).max(1e-300);
            [gb[0] * scale, gb[1] * scale]
        };
        let mut moved = false;
        for _ in 0..60 {
            let (m1, b1) = (m + step[0], (b + step[1]).clamp(b_lo, b_hi));
            let l1 = ll(m1, b1);
            if l1 >= l {
                moved = (m1, b1) != (m, b);
                (m, b, l) = (m1, b1, l1);
                break;
            }
            step = [0.5 * step[0], 0.5 * step[1]];
        }
        if !moved || step[0].hypot(step[1]) < 1e-13 {
            break;
        }
    }
    let beta = b.exp();
    let on_edge = b <= b_lo + 1e-9 || b >= b_hi - 1e-9;
    let (_, h) = derivatives(&ln_sa, trials, exceed, m, beta);
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    let mut fit = Fragility {
        theta_sa_g: m.exp(),
        beta,
        log_likelihood: l,
        status: FitStatus::Degenerate,
        ..nan
    };
    let partial = exceed
        .iter()
        .zip(trials)
        .filter(|&(z, n)| *z > 0 && z < n)
        .count();
    if on_edge || partial < 2 || !(h[0][0] < 0.0 && det > 0.0) {
        return fit;
    }
    // Covariance = (−H)⁻¹.
    let var_m = -h[1][1] / det;
    let var_beta = -h[0][0] / det;
    let (sm, sb) = (var_m.sqrt(), var_beta.sqrt() / beta);
    fit.theta_ci_sa_g = ((m - Z_95 * sm).exp(), (m + Z_95 * sm).exp());
    fit.beta_ci = (beta * (-Z_95 * sb).exp(), beta * (Z_95 * sb).exp());
    fit.status = FitStatus::Fitted;
    fit
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::Rng;

    fn stripes() -> (Vec<f64>, Vec<u32>, Vec<u32>) {
        let x = vec![0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.6];
        let n = vec![20; 7];
        let z = vec![0, 2, 5, 9, 13, 15, 19];
        (x, n, z)
    }

    #[test]
    fn the_maximum_is_that_of_a_brute_force_grid_of_the_likelihood() {
        let (x, n, z) = stripes();
        let f = fit_lognormal(&x, &n, &z);
        assert_eq!(f.status, FitStatus::Fitted);
        // The likelihood written out independently, on a 1e-3 grid around the optimum region.
        let like = |m: f64, beta: f64| -> f64 {
            x.iter()
                .zip(&n)
                .zip(&z)
                .map(|((x, &n), &z)| {
                    let p = normal_cdf((x.ln() - m) / beta);
                    z as f64 * p.ln() + (n - z) as f64 * (1.0 - p).ln()
                })
                .sum()
        };
        let mut best = (0.0, 0.0, f64::NEG_INFINITY);
        for i in 0..=1000 {
            let m = -1.0 + 1.5 * i as f64 / 1000.0;
            for j in 0..=1000 {
                let beta = 0.05 + 1.45 * j as f64 / 1000.0;
                let l = like(m, beta);
                if l > best.2 {
                    best = (m, beta, l);
                }
            }
        }
        assert!((f.theta_sa_g.ln() - best.0).abs() < 2e-3, "{f:?} {best:?}");
        assert!((f.beta - best.1).abs() < 2e-3, "{f:?} {best:?}");
        assert!(f.log_likelihood >= best.2 - 1e-12);
        assert!(f.theta_ci_sa_g.0 < f.theta_sa_g && f.theta_sa_g < f.theta_ci_sa_g.1);
        assert!(f.beta_ci.0 < f.beta && f.beta < f.beta_ci.1);
    }

    #[test]
    fn analytic_derivatives_match_central_differences() {
        let (x, n, z) = stripes();
        let x: Vec<f64> = x.iter().map(|v| v.ln()).collect();
        let (m, beta) = (-0.1, 0.45);
        let (g, h) = derivatives(&x, &n, &z, m, beta);
        let e = 1e-5;
        let ll = |m: f64, b: f64| log_likelihood(&x, &n, &z, m, b);
        let gm = (ll(m + e, beta) - ll(m - e, beta)) / (2.0 * e);
        let gb = (ll(m, beta + e) - ll(m, beta - e)) / (2.0 * e);
        assert!((g[0] - gm).abs() < 1e-6 * gm.abs().max(1.0), "{g:?} {gm}");
        assert!((g[1] - gb).abs() < 1e-6 * gb.abs().max(1.0), "{g:?} {gb}");
        let d = |f: &dyn Fn(f64, f64) -> [f64; 2], i: usize| {
            let p = f(
                m + if i == 0 { e } else { 0.0 },
                beta + if i == 1 { e } else { 0.0 },
            );
            let q = f(
                m - if i == 0 { e } else { 0.0 },
                beta - if i == 1 { e } else { 0.0 },
            );
            [(p[0] - q[0]) / (2.0 * e), (p[1] - q[1]) / (2.0 * e)]
        };
        let grad = |m: f64, b: f64| derivatives(&x, &n, &z, m, b).0;
        for i in 0..2 {
            let col = d(&grad, i);
            for k in 0..2 {
                assert!(
                    (h[k][i] - col[k]).abs() < 1e-5 * h[k][i].abs().max(1.0),
                    "{h:?}"
                );
            }
        }
    }

    #[test]
    fn recovers_a_known_lognormal_from_synthetic_stripes() {
        // 25 stripes of 200 independent runs each, capacities lognormal with θ = 0.8 g,
        // β = 0.4 (fixed seed): θ within 3 %, β within 10 %.
        let (theta, beta) = (0.8f64, 0.4);
        let mut rng = Rng::new(2015);
        let x: Vec<f64> = (1..=25).map(|j| 0.1 * j as f64).collect();
        let f = fit_lognormal(
            &x,
            &vec![200; x.len()],
            &draw(&mut rng, &x, 200, theta, beta),
        );
        assert_eq!(f.status, FitStatus::Fitted);
        assert!((f.theta_sa_g / theta - 1.0).abs() < 0.03, "{f:?}");
        assert!((f.beta / beta - 1.0).abs() < 0.10, "{f:?}");
    }

    /// `z_j` of `n` runs at each stripe exceeding, capacities lognormal `(θ, β)`.
    fn draw(rng: &mut Rng, x: &[f64], n: u32, theta: f64, beta: f64) -> Vec<u32> {
        x.iter()
            .map(|&xj| {
                (0..n)
                    .filter(|_| (theta.ln() + beta * rng.normal()).exp() <= xj)
                    .count() as u32
            })
            .collect()
    }

    #[test]
    fn the_95_percent_intervals_cover_the_truth_about_95_percent_of_the_time() {
        // 400 synthetic data sets of 10 stripes × 40 runs: each interval must cover the true
        // value in 90–99 % of them (binomial sd of the coverage at 95 %: 1.1 %).
        let (theta, beta) = (0.6f64, 0.5);
        let mut rng = Rng::new(11);
        let x: Vec<f64> = (1..=10).map(|j| 0.15 * j as f64).collect();
        let (mut t_in, mut b_in, mut fits) = (0, 0, 0);
        for _ in 0..400 {
            let f = fit_lognormal(&x, &[40; 10], &draw(&mut rng, &x, 40, theta, beta));
            if f.status != FitStatus::Fitted {
                continue;
            }
            fits += 1;
            t_in += usize::from(f.theta_ci_sa_g.0 < theta && theta < f.theta_ci_sa_g.1);
            b_in += usize::from(f.beta_ci.0 < beta && beta < f.beta_ci.1);
        }
        assert_eq!(fits, 400);
        for (what, k) in [("θ", t_in), ("β", b_in)] {
            let c = k as f64 / fits as f64;
            assert!((0.90..=0.99).contains(&c), "{what}: coverage {c}");
        }
    }

    #[test]
    fn data_without_a_transition_give_no_fit() {
        let x = [0.5, 1.0];
        assert_eq!(
            fit_lognormal(&x, &[3, 3], &[0, 0]).status,
            FitStatus::NoExceedance
        );
        assert_eq!(
            fit_lognormal(&x, &[3, 3], &[3, 3]).status,
            FitStatus::AllExceed
        );
        assert_eq!(
            fit_lognormal(&x, &[3, 3], &[0, 3]).status,
            FitStatus::Degenerate
        );
        // One stripe between none and all: a ridge, no interval.
        let f = fit_lognormal(&[0.5, 1.0, 1.5], &[10; 3], &[0, 4, 10]);
        assert_eq!(f.status, FitStatus::Degenerate);
        assert!(f.theta_ci_sa_g.0.is_nan() && f.theta_sa_g > 0.5 && f.theta_sa_g < 1.5);
    }
}
