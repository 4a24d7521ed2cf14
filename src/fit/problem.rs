//! One form against one data set as a nonlinear least-squares problem: weighted residuals
//! `r_i = w_i·(T_new,i(p) − T_new,i)` (`w_i` of [`Form::weight`]: 1, or `1/T_p` for a fit of
//! `T_new/T_p`), their sum of squares, the Jacobian `J = ∂r/∂p` from the form's analytic
//! derivatives, and the Gauss–Newton normal equations `Jᵀr`, `JᵀJ`.
//!
//! The argmin adapter ([`Scaled`]) poses it in scaled parameters `q_j = d_j·p_j`, `d_j` the
//! root mean square of Jacobian column `j` at the start: a unit step in any `q_j` then moves the
//! predictions by about 1 s in root mean square, so a spherical trust region suits every
//! parameter alike (the Jacobi scaling of Moré's Levenberg–Marquardt).

use super::{FitError, Form, Sample};
use argmin::core::{CostFunction, Error as ArgminError, Gradient, Hessian};
use nalgebra::{DMatrix, DVector};
use std::cell::RefCell;

/// One form against one data set.
pub(crate) struct Problem {
    pub form: Form,
    /// Features per case.
    pub k: usize,
    /// Parameters.
    pub m: usize,
    /// Regressors per case ([`Form::regressors`]).
    width: usize,
    /// Regressors, `n × width` row-major.
    z: Vec<f64>,
    t_p_s: Vec<f64>,
    t_rigid_s: Vec<f64>,
    /// Computed `T_new`, s.
    y: Vec<f64>,
    /// Weight of each case ([`Form::weight`]).
    w: Vec<f64>,
}

/// `Jᵀr`, `JᵀJ` (`m × m`, row-major) and the sum of squared residuals (s²) at one point.
#[derive(Debug, Clone)]
pub(crate) struct NormalEquations {
    pub sse: f64,
    pub gradient: Vec<f64>,
    pub jtj: Vec<f64>,
}

impl Problem {
    /// The problem of `form` on `data`: at least three cases per parameter, and regressors
    /// finite for every case.
    pub fn new(form: Form, data: &[Sample]) -> Result<Self, FitError> {
        let k = data.first().map_or(0, |s| s.x.len());
        let m = form.parameter_count(k);
        if k == 0 || data.len() < 3 * m {
            return Err(FitError::TooFew {
                cases: data.len(),
                needed: 3 * m.max(1),
            });
        }
        let width = form.regressors(&data[0].x).len();
        let mut z = Vec::with_capacity(data.len() * width);
        for s in data {
            if s.x.len() != k {
                return Err(FitError::Features {
                    expected: k,
                    got: s.x.len(),
                });
            }
            let r = form.regressors(&s.x);
            if let Some(j) = r.iter().position(|v| !v.is_finite()) {
                return Err(FitError::NotApplicable {
                    form: form.name(),
                    reason: format!(
                        "feature {} is {} in a case; the form takes its logarithm",
                        j + 1,
                        s.x[j]
                    ),
                });
            }
            z.extend(r);
        }
        Ok(Self {
            form,
            k,
            m,
            width,
            z,
            t_p_s: data.iter().map(Sample::t_p_s).collect(),
            t_rigid_s: data.iter().map(|s| s.t_rigid_s).collect(),
            y: data.iter().map(|s| s.t_new_s).collect(),
            w: data.iter().map(|s| form.weight(s.t_p_s())).collect(),
        })
    }

    /// Cases.
    pub fn n(&self) -> usize {
        self.y.len()
    }

    fn row(&self, i: usize) -> &[f64] {
        &self.z[i * self.width..(i + 1) * self.width]
    }

    /// Weighted residual of case `i`; with `grad`, its row of the Jacobian.
    fn residual(&self, p: &[f64], i: usize, grad: Option<&mut [f64]>) -> f64 {
        let w = self.w[i];
        match grad {
            Some(g) => {
                let t = self.form.evaluate(
                    p,
                    self.row(i),
                    self.t_p_s[i],
                    self.t_rigid_s[i],
                    Some(&mut *g),
                );
                g.iter_mut().for_each(|v| *v *= w);
                w * (t - self.y[i])
            }
            None => {
                w * (self
                    .form
                    .evaluate(p, self.row(i), self.t_p_s[i], self.t_rigid_s[i], None)
                    - self.y[i])
            }
        }
    }

    /// Sum of squared weighted residuals (`+∞` when not finite).
    pub fn sse(&self, p: &[f64]) -> f64 {
        let s: f64 = (0..self.n())
            .map(|i| self.residual(p, i, None).powi(2))
            .sum();
        if s.is_finite() { s } else { f64::INFINITY }
    }

    /// The normal equations at `p`: from the Jacobian's columns (contiguous, so each of the
    /// `m·(m + 1)/2` products is one vectorised dot product).
    pub fn normal_equations(&self, p: &[f64]) -> NormalEquations {
        let m = self.m;
        let (j, r) = self.jacobian_and_residuals(p);
        let rv = DVector::from_vec(r);
        let sse = rv.norm_squared();
        let gradient = (0..m).map(|a| j.column(a).dot(&rv)).collect();
        let mut jtj = vec![0.0; m * m];
        for a in 0..m {
            for b in 0..=a {
                let v = j.column(a).dot(&j.column(b));
                jtj[a * m + b] = v;
                jtj[b * m + a] = v;
            }
        }
        NormalEquations {
            sse: if sse.is_finite() { sse } else { f64::INFINITY },
            gradient,
            jtj,
        }
    }

    /// The Jacobian `∂r/∂p` at `p`, `n × m`.
    pub fn jacobian(&self, p: &[f64]) -> DMatrix<f64> {
        self.jacobian_and_residuals(p).0
    }

    /// The Jacobian `∂r/∂p` (`n × m`) and the residuals at `p`.
    fn jacobian_and_residuals(&self, p: &[f64]) -> (DMatrix<f64>, Vec<f64>) {
        let n = self.n();
        let mut j = DMatrix::zeros(n, self.m);
        let mut r = Vec::with_capacity(n);
        let mut row = vec![0.0; self.m];
        for i in 0..n {
            r.push(self.residual(p, i, Some(&mut row)));
            for (c, v) in row.iter().enumerate() {
                j[(i, c)] = *v;
            }
        }
        (j, r)
    }

    /// A sum of squares at or below this is an exact fit: weighted residuals of 1e-12 of the
    /// weighted data's root mean square, a few hundred ulps of each `T_new`.
    pub fn round_off_sse(&self) -> f64 {
        let mean_square = self
            .y
            .iter()
            .zip(&self.w)
            .map(|(y, w)| (w * y).powi(2))
            .sum::<f64>()
            / self.n() as f64;
        self.n() as f64 * 1e-24 * mean_square
    }

    /// The Bates–Watts relative offset here ([`relative_offset`]).
    pub fn relative_offset(&self, ne: &NormalEquations) -> f64 {
        relative_offset(&ne.gradient, &ne.jtj, ne.sse, self.n())
    }

    /// A start of [`Form::starts`] made complete: the paper form's linear parameters
    /// `(a, B, e)` by least squares for its exponent weights `c` (SVD, which also copes with a
    /// rank-deficient design); other forms as given.
    pub fn complete_start(&self, start: &[f64]) -> Vec<f64> {
        if self.form != Form::Paper {
            return start.to_vec();
        }
        let k = self.k;
        let c = &start[k..2 * k];
        let cols: Vec<Vec<f64>> = (0..k + 2)
            .map(|j| {
                (0..self.n())
                    .map(|i| {
                        let z = self.row(i);
                        let v = if j < k {
                            z[j]
                        } else if j == k {
                            z.iter().zip(c).map(|(x, w)| x * w).sum::<f64>().exp()
                        } else {
                            1.0
                        };
                        v * self.w[i]
                    })
                    .collect()
            })
            .collect();
        let y: Vec<f64> = self.y.iter().zip(&self.w).map(|(y, w)| y * w).collect();
        let theta = crate::numeric::linalg::least_squares(&cols, &y);
        let mut p = theta[..k].to_vec();
        p.extend_from_slice(c);
        p.extend_from_slice(&theta[k..]);
        p
    }

    /// Root mean square of each Jacobian column at `p` (1 where a column is zero or not
    /// finite): the scales `d` of [`Scaled`].
    pub fn column_scales(&self, p: &[f64]) -> Vec<f64> {
        let ne = self.normal_equations(p);
        (0..self.m)
            .map(|j| {
                let d = (ne.jtj[j * self.m + j] / self.n() as f64).sqrt();
                if d.is_finite() && d > 0.0 { d } else { 1.0 }
            })
            .collect()
    }
}

/// The Bates–Watts relative offset (Bates & Watts 1981, the convergence test of R's `nls`) from
/// the gradient `g = Jᵀr`, `h = JᵀJ` (`m × m` row-major, any column scaling of `J`), the sum of
/// squares `sse = ‖r‖²` and `n` cases: `√((‖P_J r‖²/m)/((‖r‖² − ‖P_J r‖²)/(n − m)))` with
/// `‖P_J r‖² = gᵀ·h⁺·g`, the decrease a full Gauss–Newton step would give. It is the remaining
/// step measured against the radius of the parameters' confidence region, zero at a stationary
/// point, free of the parameters' scales and of their conditioning. `h⁺` by the SVD of the
/// unit-diagonal `h` (directions below 1e-13 of the largest singular value are left out: they
/// are the round-off of a singular `JᵀJ`).
pub(crate) fn relative_offset(g: &[f64], h: &[f64], sse: f64, n: usize) -> f64 {
    let m = g.len();
    if sse == 0.0 {
        return 0.0;
    }
    if !sse.is_finite() || n <= m {
        return f64::INFINITY;
    }
    let d: Vec<f64> = (0..m)
        .map(|j| {
            let v = h[j * m + j].sqrt();
            if v > 0.0 && v.is_finite() { v } else { 1.0 }
        })
        .collect();
    let hs = DMatrix::from_fn(m, m, |a, b| h[a * m + b] / (d[a] * d[b]));
    let gs = DVector::from_iterator(m, g.iter().zip(&d).map(|(g, d)| g / d));
    if !(hs.iter().all(|v| v.is_finite()) && gs.iter().all(|v| v.is_finite())) {
        return f64::INFINITY;
    }
    let svd = hs.svd(true, true);
    let eps = 1e-13 * svd.singular_values.max();
    let Ok(step) = svd.solve(&gs, eps) else {
        return f64::INFINITY;
    };
    let decrement = gs.dot(&step).max(0.0);
    let rest = (sse - decrement).max(f64::MIN_POSITIVE);
    ((decrement / m as f64) / (rest / (n - m) as f64)).sqrt()
}

/// The problem for argmin in scaled parameters `q = d ⊙ p`: cost `½·SSE`, gradient `Jᵀr`,
/// Hessian the Gauss–Newton `JᵀJ` (all with respect to `q`).
pub(crate) struct Scaled<'a> {
    pub problem: &'a Problem,
    pub d: Vec<f64>,
    /// The normal equations at the last point asked for: a trust-region step asks for the
    /// gradient and the Hessian at the same point.
    cache: RefCell<Option<(Vec<f64>, NormalEquations)>>,
}

impl<'a> Scaled<'a> {
    pub fn new(problem: &'a Problem, d: Vec<f64>) -> Self {
        Self {
            problem,
            d,
            cache: RefCell::new(None),
        }
    }

    pub fn to_p(&self, q: &[f64]) -> Vec<f64> {
        q.iter().zip(&self.d).map(|(q, d)| q / d).collect()
    }

    pub fn to_q(&self, p: &[f64]) -> Vec<f64> {
        p.iter().zip(&self.d).map(|(p, d)| p * d).collect()
    }

    fn normal_equations(&self, q: &[f64]) -> NormalEquations {
        if let Some((at, ne)) = self.cache.borrow().as_ref()
            && at.as_slice() == q
        {
            return ne.clone();
        }
        let ne = self.problem.normal_equations(&self.to_p(q));
        *self.cache.borrow_mut() = Some((q.to_vec(), ne.clone()));
        ne
    }
}

impl CostFunction for Scaled<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, q: &Vec<f64>) -> Result<f64, ArgminError> {
        Ok(0.5 * self.problem.sse(&self.to_p(q)))
    }
}

impl Gradient for Scaled<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, q: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        let ne = self.normal_equations(q);
        Ok(ne
            .gradient
            .iter()
            .zip(&self.d)
            .map(|(g, d)| g / d)
            .collect())
    }
}

impl Hessian for Scaled<'_> {
    type Param = Vec<f64>;
    type Hessian = Vec<Vec<f64>>;

    fn hessian(&self, q: &Vec<f64>) -> Result<Vec<Vec<f64>>, ArgminError> {
        let ne = self.normal_equations(q);
        let m = self.problem.m;
        Ok((0..m)
            .map(|a| {
                (0..m)
                    .map(|b| ne.jtj[a * m + b] / (self.d[a] * self.d[b]))
                    .collect()
            })
            .collect())
    }
}

/// The paper form's variable-projection problem for argmin ([`Projected::sse`]): cost
/// `½·SSE` over the exponent weights alone, scaled as in [`Scaled`] (`q_j = d_j·c_j`).
///
/// Of the linear problem's `k + 2` weighted columns `(w·z_1 … w·z_k, w·e^{c·z}, w)` only the
/// exponential one depends on `c`: the others, and their entries of the normal equations, are
/// computed once here, each summed over the cases in their order as at every point.
pub(crate) struct Projected<'a> {
    pub problem: &'a Problem,
    pub d: Vec<f64>,
    /// The weighted columns per case, `n × (k + 2)` row-major, the exponential one (`k`) zero.
    columns: Vec<f64>,
    /// `w_i·y_i`.
    wy: Vec<f64>,
    /// The normal equations' lower triangle (`(k + 2)²`, row-major) and right-hand side without
    /// the exponential column's entries.
    gram: Vec<f64>,
    rhs: Vec<f64>,
}

impl<'a> Projected<'a> {
    /// The projected problem of the paper form's `problem`, its exponent weights scaled by `d`.
    pub fn new(problem: &'a Problem, d: Vec<f64>) -> Self {
        debug_assert_eq!(problem.form, Form::Paper);
        let (k, n, q) = (problem.k, problem.n(), problem.k + 2);
        let mut columns = vec![0.0; n * q];
        for (i, v) in columns.chunks_exact_mut(q).enumerate() {
            let w = problem.w[i];
            for (vj, z) in v.iter_mut().zip(&problem.row(i)[..k]) {
                *vj = z * w;
            }
            v[k + 1] = w;
        }
        let wy: Vec<f64> = (0..n).map(|i| problem.w[i] * problem.y[i]).collect();
        let (mut gram, mut rhs) = (vec![0.0; q * q], vec![0.0; q]);
        for (v, wy) in columns.chunks_exact(q).zip(&wy) {
            for a in (0..q).filter(|&a| a != k) {
                rhs[a] += v[a] * wy;
                for b in (0..=a).filter(|&b| b != k) {
                    gram[a * q + b] += v[a] * v[b];
                }
            }
        }
        Self {
            problem,
            d,
            columns,
            wy,
            gram,
            rhs,
        }
    }

    pub fn to_c(&self, q: &[f64]) -> Vec<f64> {
        q.iter().zip(&self.d).map(|(q, d)| q / d).collect()
    }

    /// The variable-projection cost of the paper form (Golub & Pereyra 1973): its `k`
    /// exponent weights `c` given, the linear parameters `(a, B, e)` that minimise the sum of
    /// squares are a linear least-squares problem; this is the sum of squares they leave
    /// (`+∞` when not finite). The linear solve is by the normal equations and Cholesky, a
    /// `(k + 2)²` system: its error in `(a, B, e)` is of the order of the squared condition
    /// number times round-off (about 1e-7 relative at the paper grid's 3e4), which moves a sum
    /// of squares at its minimum by the square of that, 1e-14; [`Problem::complete_start`]
    /// gives the SVD's solution for the result.
    pub fn sse(&self, c: &[f64]) -> f64 {
        let (p, k) = (self.problem, self.problem.k);
        let q = k + 2;
        let ex: Vec<f64> = (0..p.n())
            .map(|i| (p.row(i).iter().zip(c).map(|(x, w)| x * w).sum::<f64>()).exp() * p.w[i])
            .collect();
        let (mut gram, mut rhs) = (self.gram.clone(), self.rhs.clone());
        for ((v, wy), &e) in self.columns.chunks_exact(q).zip(&self.wy).zip(&ex) {
            rhs[k] += e * wy;
            for b in 0..k {
                gram[k * q + b] += e * v[b];
            }
            gram[k * q + k] += e * e;
            gram[(k + 1) * q + k] += v[k + 1] * e;
        }
        let largest = (0..q).map(|j| gram[j * q + j]).fold(0.0, f64::max);
        if !largest.is_finite() {
            return f64::INFINITY;
        }
        crate::numeric::linalg::cholesky_solve(&mut gram, &mut rhs, q, 1e-14 * largest);
        let s: f64 = (self.columns.chunks_exact(q).zip(&self.wy).zip(&ex))
            .map(|((v, wy), &e)| {
                let fit: f64 = (0..q).map(|j| rhs[j] * if j == k { e } else { v[j] }).sum();
                (fit - wy).powi(2)
            })
            .sum();
        if s.is_finite() { s } else { f64::INFINITY }
    }
}

impl CostFunction for Projected<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, q: &Vec<f64>) -> Result<f64, ArgminError> {
        Ok(0.5 * self.sse(&self.to_c(q)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_jacobian_and_normal_equations_match_differences() {
        // The problem's Jacobian (weighted residuals, weights 1/T_p for the damped form)
        // against central differences of its residuals (h = 1e-6·max(1, |p_j|), tolerance as
        // in tests/fit.rs: 1e-7·(1 + |J|)); and Jᵀr, JᵀJ, SSE against sums over the rows.
        let mut data = Vec::new();
        for (i, tp) in [0.15, 0.4, 0.9, 1.3, 1.7].iter().enumerate() {
            for (j, mu) in [0.05, 0.3, 0.6].iter().enumerate() {
                for a in [0.1, 0.45, 0.8] {
                    data.push(Sample {
                        x: vec![*tp, *mu, 0.2 + 0.1 * j as f64, a, 0.5],
                        t_rigid_s: tp * (1.5f64 + a).sqrt(),
                        t_new_s: tp * (1.0 + 0.05 * (i + j) as f64),
                    });
                }
            }
        }
        for form in Form::FOR_T_NEW {
            let problem = Problem::new(form, &data).unwrap();
            let p: Vec<f64> = (0..problem.m).map(|j| 0.3 - 0.07 * j as f64).collect();
            let (jac, r) = problem.jacobian_and_residuals(&p);
            for c in 0..problem.m {
                let h = 1e-6 * p[c].abs().max(1.0);
                let (mut up, mut down) = (p.clone(), p.clone());
                up[c] += h;
                down[c] -= h;
                let (ru, rd) = (
                    problem.jacobian_and_residuals(&up).1,
                    problem.jacobian_and_residuals(&down).1,
                );
                for i in 0..problem.n() {
                    let fd = (ru[i] - rd[i]) / (2.0 * h);
                    assert!(
                        (jac[(i, c)] - fd).abs() <= 1e-7 * (1.0 + jac[(i, c)].abs()),
                        "{form:?} case {i} parameter {c}: {} vs {fd}",
                        jac[(i, c)]
                    );
                }
            }
            let ne = problem.normal_equations(&p);
            let sse: f64 = r.iter().map(|v| v * v).sum();
            assert!((ne.sse - sse).abs() <= 1e-13 * sse);
            assert!((problem.sse(&p) - sse).abs() <= 1e-13 * sse);
            for a in 0..problem.m {
                let g: f64 = (0..problem.n()).map(|i| jac[(i, a)] * r[i]).sum();
                assert!((ne.gradient[a] - g).abs() <= 1e-12 * (1.0 + g.abs()));
                for b in 0..problem.m {
                    let h: f64 = (0..problem.n()).map(|i| jac[(i, a)] * jac[(i, b)]).sum();
                    assert!((ne.jtj[a * problem.m + b] - h).abs() <= 1e-12 * (1.0 + h.abs()));
                }
            }
        }
    }

    #[test]
    fn projected_sum_of_squares_is_the_least_over_the_linear_parameters() {
        // For fixed exponent weights c, the projected SSE is the minimum over (a, B, e): it
        // equals the SSE at the SVD's linear parameters (complete_start) to 1e-10 relative
        // (normal equations against SVD: the squared error of the linear parameters, module
        // doc), and no perturbation of the linear parameters lowers it (brute force over ±1e-3
        // relative steps in each, which raise the SSE by far more than round-off).
        let mut data = Vec::new();
        for i in 0..40 {
            let (tp, mu, a) = (
                0.1 + 0.05 * i as f64,
                0.05 + 0.01 * (i % 7) as f64,
                0.1 + 0.02 * (i % 5) as f64,
            );
            data.push(Sample {
                x: vec![tp, mu, a],
                t_rigid_s: 2.0 * tp,
                t_new_s: tp * (1.2 + 0.3 * (-mu * 4.0).exp()) + 0.01 * ((i * 3 % 5) as f64 - 2.0),
            });
        }
        let problem = Problem::new(Form::Paper, &data).unwrap();
        let c = [0.4, -1.5, 0.3];
        let mut start = vec![0.0; problem.m];
        start[3..6].copy_from_slice(&c);
        let p = problem.complete_start(&start);
        let projected = Projected::new(&problem, vec![1.0; 3]).sse(&c);
        let sse = problem.sse(&p);
        assert!(
            (projected - sse).abs() <= 1e-10 * sse,
            "{projected} vs {sse}"
        );
        for j in (0..3).chain(6..8) {
            for sign in [-1.0, 1.0] {
                let mut q = p.clone();
                q[j] += sign * 1e-3 * q[j].abs().max(1e-3);
                assert!(problem.sse(&q) > projected, "parameter {j}");
            }
        }
    }

    #[test]
    fn relative_offset_of_a_straight_line() {
        // For linear least squares y ≈ a + b·x the Gauss–Newton step is exact, so at any
        // (a₀, b₀) the decrement is SSE(a₀, b₀) − SSE(â, b̂), with (â, b̂) the textbook closed
        // form: the offset follows without any solve. Agreement to 1e-10 relative (the two
        // routes round differently; the difference of sums of squares loses no more than 1e-3
        // of its digits at this start).
        let x: Vec<f64> = (0..15).map(|i| 0.2 + 0.13 * i as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, x)| 0.9 + 0.6 * x + 0.03 * ((i * 5 % 7) as f64 - 3.0))
            .collect();
        let n = x.len();
        let nf = n as f64;
        let (xm, ym) = (x.iter().sum::<f64>() / nf, y.iter().sum::<f64>() / nf);
        let sxx: f64 = x.iter().map(|v| (v - xm).powi(2)).sum();
        let sxy: f64 = x.iter().zip(&y).map(|(u, v)| (u - xm) * (v - ym)).sum();
        let b = sxy / sxx;
        let a = ym - b * xm;
        let sse = |a: f64, b: f64| -> f64 {
            x.iter().zip(&y).map(|(u, v)| (a + b * u - v).powi(2)).sum()
        };
        let (a0, b0) = (a + 0.05, b - 0.04);
        let r: Vec<f64> = x.iter().zip(&y).map(|(u, v)| a0 + b0 * u - v).collect();
        let g = [
            r.iter().sum::<f64>(),
            r.iter().zip(&x).map(|(r, u)| r * u).sum(),
        ];
        let h = [
            nf,
            x.iter().sum(),
            x.iter().sum(),
            x.iter().map(|u| u * u).sum(),
        ];
        let got = relative_offset(&g, &h, sse(a0, b0), n);
        let (s0, s1) = (sse(a0, b0), sse(a, b));
        let want = (((s0 - s1) / 2.0) / (s1 / (nf - 2.0))).sqrt();
        assert!((got / want - 1.0).abs() < 1e-10, "{got} vs {want}");
        // At the optimum it is zero up to round-off.
        let r: Vec<f64> = x.iter().zip(&y).map(|(u, v)| a + b * u - v).collect();
        let g = [
            r.iter().sum::<f64>(),
            r.iter().zip(&x).map(|(r, u)| r * u).sum(),
        ];
        assert!(relative_offset(&g, &h, s1, n) < 1e-6);
    }
}
