//! Small dense linear algebra: each kernel once (least squares through `nalgebra`'s SVD).

/// Solves `A·x = rhs` for a symmetric positive definite `n×n` matrix `a` (row-major; only the
/// lower triangle is read, and `a` is overwritten by its Cholesky factor), in place of `rhs`.
/// Pivots are floored at `min_pivot` (> 0) against round-off in nearly singular systems.
pub fn cholesky_solve(a: &mut [f64], rhs: &mut [f64], n: usize, min_pivot: f64) {
    for j in 0..n {
        let mut s = a[j * n + j];
        for k in 0..j {
            s -= a[j * n + k] * a[j * n + k];
        }
        let ljj = s.max(min_pivot).sqrt();
        a[j * n + j] = ljj;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / ljj;
        }
    }
    for i in 0..n {
        let s = rhs[i] - (0..i).map(|k| a[i * n + k] * rhs[k]).sum::<f64>();
        rhs[i] = s / a[i * n + i];
    }
    for i in (0..n).rev() {
        let s = rhs[i] - (i + 1..n).map(|k| a[k * n + i] * rhs[k]).sum::<f64>();
        rhs[i] = s / a[i * n + i];
    }
}

/// Least-squares solution of `A·c ≈ b` (minimum norm where `A` is rank-deficient), by the
/// SVD of `nalgebra`, singular values below `1e-12` of the largest dropped; `cols` holds the
/// columns of `A`, each of `b`'s length. The one least-squares solver of the project.
pub fn least_squares(cols: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    LeastSquares::new(cols).solve(b)
}

/// [`least_squares`] factorised once for many right-hand sides: the SVD of `A` kept, each
/// [`LeastSquares::solve`] the same arithmetic (and bits) as `least_squares` on that `b`.
pub struct LeastSquares {
    svd: nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>,
    cutoff: f64,
    rows: usize,
    cols: usize,
}

impl LeastSquares {
    /// The factorisation of the matrix whose columns are `cols` (each of the same length).
    pub fn new(cols: &[Vec<f64>]) -> Self {
        let m = cols.len();
        let n = cols.first().map_or(0, Vec::len);
        let a = nalgebra::DMatrix::from_fn(n, m, |i, j| cols[j][i]);
        let svd = a.svd(true, true);
        let cutoff = 1e-12 * svd.singular_values.max();
        Self {
            svd,
            cutoff,
            rows: n,
            cols: m,
        }
    }

    /// The least-squares solution for `b` (of the columns' length).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        assert_eq!(b.len(), self.rows, "right-hand side of the wrong length");
        let y = nalgebra::DVector::from_column_slice(b);
        self.svd
            .solve(&y, self.cutoff)
            .map(|c| c.iter().copied().collect())
            .unwrap_or_else(|_| vec![0.0; self.cols])
    }
}

pub type Mat4 = [[f64; 4]; 4];

fn matmul4(a: &Mat4, b: &Mat4) -> Mat4 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

/// `exp(m)` by Taylor series after scaling `m` to norm ≤ 0.5, then squaring back.
pub fn expm4(m: Mat4) -> Mat4 {
    let norm = m
        .iter()
        .map(|r| r.iter().map(|x| x.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut squarings = 0;
    let mut scale = 1.0;
    while norm * scale > 0.5 {
        scale *= 0.5;
        squarings += 1;
    }
    let a: Mat4 = std::array::from_fn(|i| std::array::from_fn(|j| m[i][j] * scale));
    let mut sum: Mat4 = std::array::from_fn(|i| std::array::from_fn(|j| f64::from(i == j)));
    let mut term = sum;
    for n in 1..40 {
        term = matmul4(&term, &a);
        for row in term.iter_mut() {
            for x in row.iter_mut() {
                *x /= n as f64;
            }
        }
        let mut biggest = 0.0_f64;
        for i in 0..4 {
            for j in 0..4 {
                sum[i][j] += term[i][j];
                biggest = biggest.max(term[i][j].abs());
            }
        }
        if biggest < 1e-18 {
            break;
        }
    }
    for _ in 0..squarings {
        sum = matmul4(&sum, &sum);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_hand_system() {
        // A = [[4, 2], [2, 3]] (lower triangle read), x = (1, −2): b = (0, −4). Exact in binary.
        let mut a = vec![4.0, 0.0, 2.0, 3.0];
        let mut b = vec![0.0, -4.0];
        cholesky_solve(&mut a, &mut b, 2, f64::MIN_POSITIVE);
        assert!(
            (b[0] - 1.0).abs() < 1e-15 && (b[1] + 2.0).abs() < 1e-15,
            "{b:?}"
        );
    }

    #[test]
    fn least_squares_recovers_an_exact_fit_and_projects_a_residual() {
        // y = 1 − 2t + 0.5t² on 11 points is reproduced to round-off (1e-13); the residual of a
        // fit is orthogonal to the columns, so fitting it gives zero coefficients (1e-14).
        let t: Vec<f64> = (0..11).map(|k| k as f64 / 10.0).collect();
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|j| t.iter().map(|x| x.powi(j)).collect())
            .collect();
        let y: Vec<f64> = t.iter().map(|x| 1.0 - 2.0 * x + 0.5 * x * x).collect();
        let c = least_squares(&cols, &y);
        for (got, want) in c.iter().zip([1.0, -2.0, 0.5]) {
            assert!((got - want).abs() < 1e-13, "{c:?}");
        }
        let r: Vec<f64> = t.iter().map(|x| (x - 0.5).powi(3)).collect();
        let c_r = least_squares(&cols, &r);
        let resid: Vec<f64> = (0..t.len())
            .map(|k| r[k] - (0..3).map(|j| c_r[j] * cols[j][k]).sum::<f64>())
            .collect();
        let c0 = least_squares(&cols, &resid);
        assert!(c0.iter().all(|v| v.abs() < 1e-14), "{c0:?}");
    }

    #[test]
    fn matrix_exponential_of_a_rotation_and_a_nilpotent() {
        // exp([[0, θ], [−θ, 0]]) is the rotation by θ; exp(N) of a nilpotent N is I + N + N²/2.
        let th = 2.5;
        let mut m = [[0.0; 4]; 4];
        m[0][1] = th;
        m[1][0] = -th;
        m[2][3] = 1.0;
        let e = expm4(m);
        assert!((e[0][0] - th.cos()).abs() < 1e-14 && (e[0][1] - th.sin()).abs() < 1e-14);
        assert!((e[1][0] + th.sin()).abs() < 1e-14 && (e[1][1] - th.cos()).abs() < 1e-14);
        assert_eq!((e[2][2], e[2][3], e[3][3]), (1.0, 1.0, 1.0));
    }
}
