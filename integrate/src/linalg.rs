//! Small dense linear algebra used inside the step loop (public so that
//! `umsim bench` times the integrators' own kernels): an LU factorization
//! with partial pivoting that works in place on a preallocated matrix, so the
//! integrators never allocate while stepping.

use nalgebra::{DMatrix, DVector};

/// LU factorization `P A = L U` with partial (row) pivoting, stored in place:
/// the strict lower triangle holds L (unit diagonal implied), the upper
/// triangle holds U, `piv[k]` is the row swapped with row k at elimination
/// step k.
#[derive(Debug, Clone)]
pub struct DenseLu {
    lu: DMatrix<f64>,
    piv: Vec<usize>,
    valid: bool,
}

/// Why a factorization failed: the elimination column with a (relatively)
/// zero or non-finite pivot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingularPivot {
    /// The elimination column (0-based).
    pub column: usize,
}

impl DenseLu {
    /// Workspace for an `n × n` system.
    pub fn new(n: usize) -> Self {
        Self {
            lu: DMatrix::zeros(n, n),
            piv: vec![0; n],
            valid: false,
        }
    }

    /// Order of the system.
    pub fn dim(&self) -> usize {
        self.piv.len()
    }

    /// Whether a successful factorization is stored.
    #[cfg(test)]
    pub(crate) fn is_valid(&self) -> bool {
        self.valid
    }

    /// The matrix to be factorized; fill it, then call [`DenseLu::factorize`].
    pub fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        self.valid = false;
        &mut self.lu
    }

    /// Factorize the matrix filled through [`DenseLu::matrix_mut`] in place.
    /// A pivot that is non-finite or below `n·ε·max|a_ij|` is reported as
    /// singular (the matrix is then numerically rank-deficient).
    pub fn factorize(&mut self) -> Result<(), SingularPivot> {
        let n = self.dim();
        self.valid = false;
        let a = self.lu.as_mut_slice(); // column-major: a[i + j n]
        let mut amax = 0.0_f64;
        for &x in a.iter() {
            if !x.is_finite() {
                return Err(SingularPivot { column: 0 });
            }
            amax = amax.max(x.abs());
        }
        let tiny = (n.max(1) as f64) * f64::EPSILON * amax;
        for k in 0..n {
            // Pivot: the first entry of largest magnitude in column k, rows k..n.
            let col_k = &a[k * n..(k + 1) * n];
            let mut p = k;
            let mut pmax = col_k[k].abs();
            for (i, v) in col_k.iter().enumerate().skip(k + 1) {
                if v.abs() > pmax {
                    pmax = v.abs();
                    p = i;
                }
            }
            self.piv[k] = p;
            if pmax <= tiny || !pmax.is_finite() {
                return Err(SingularPivot { column: k });
            }
            if p != k {
                for col in a.chunks_exact_mut(n) {
                    col.swap(k, p);
                }
            }
            let (left, right) = a.split_at_mut((k + 1) * n);
            let col_k = &mut left[k * n..];
            let inv = 1.0 / col_k[k];
            for x in &mut col_k[k + 1..] {
                *x *= inv;
            }
            let lcol = &col_k[k + 1..];
            for col in right.chunks_exact_mut(n) {
                let akj = col[k];
                if akj != 0.0 {
                    // a[k+1.., j] -= l[k+1.., k] * a[k, j]
                    for (c, l) in col[k + 1..].iter_mut().zip(lcol) {
                        *c -= l * akj;
                    }
                }
            }
        }
        self.valid = true;
        Ok(())
    }

    /// Solve `A x = b` in place (b becomes x) with the stored factorization.
    pub fn solve_in_place(&self, b: &mut DVector<f64>) {
        self.solve_slice(b.as_mut_slice());
    }

    /// [`DenseLu::solve_in_place`] on a slice of length [`DenseLu::dim`].
    pub fn solve_slice(&self, x: &mut [f64]) {
        debug_assert!(self.valid, "solve with an invalid LU factorization");
        let n = self.dim();
        let a = self.lu.as_slice();
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                x.swap(k, p);
            }
        }
        if n == 0 {
            return;
        }
        // Forward substitution with unit lower triangle (column oriented).
        for (j, col) in a.chunks_exact(n).enumerate() {
            let (head, tail) = x.split_at_mut(j + 1);
            let xj = head[j];
            if xj != 0.0 {
                for (xi, l) in tail.iter_mut().zip(&col[j + 1..]) {
                    *xi -= l * xj;
                }
            }
        }
        // Back substitution with U (column oriented).
        for (j, col) in a.chunks_exact(n).enumerate().rev() {
            let (head, _) = x.split_at_mut(j + 1);
            head[j] /= col[j];
            let xj = head[j];
            if xj != 0.0 {
                for (xi, u) in head[..j].iter_mut().zip(col) {
                    *xi -= u * xj;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system_exactly() {
        // A needs a row swap at the first step (zero leading entry); the exact
        // solution of A x = b with b = A·(1, 2, 3) is (1, 2, 3).
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 4.0]);
        let x_true = DVector::from_vec(vec![1.0, 2.0, 3.0]);
        let mut b = &a * &x_true;
        let mut lu = DenseLu::new(3);
        lu.matrix_mut().copy_from(&a);
        lu.factorize().unwrap();
        lu.solve_in_place(&mut b);
        assert!((b - x_true).amax() < 1e-14);
    }

    #[test]
    fn singular_matrix_is_reported() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        let mut lu = DenseLu::new(2);
        lu.matrix_mut().copy_from(&a);
        assert_eq!(lu.factorize(), Err(SingularPivot { column: 1 }));
        assert!(!lu.is_valid());
    }
}

/// In-place Cholesky factorization M = L Lᵀ of a symmetric positive definite
/// matrix (column-major, only the lower triangle is read and overwritten by L).
/// Column-oriented ("left-looking") so that every inner loop runs down a
/// contiguous column. Returns `false` if a pivot is not positive (M not
/// positive definite, or not finite).
pub fn cholesky_in_place(m: &mut DMatrix<f64>) -> bool {
    let n = m.nrows();
    let data = m.as_mut_slice();
    // Small orders get their own copy of the kernel with n a constant, which
    // the compiler unrolls (the loops of a 10×10 factorization are a few
    // elements long: loop overhead would cost more than the arithmetic).
    // Same operations in the same order at every size.
    macro_rules! sized {
        ($($k:literal)*) => {
            match n {
                $($k => cholesky_small::<$k>(data),)*
                _ => cholesky_kernel(data, n),
            }
        };
    }
    sized!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// [`cholesky_kernel`] for a constant order `N` (loops of constant length,
/// unrolled by the compiler). Each entry of L is accumulated in a register,
/// `a_ij − l_i0 l_j0 − l_i1 l_j1 − …` with the terms of zero `l_jk` skipped,
/// which are the operations of [`cholesky_kernel`] in the same order: the
/// factor is the same bit for bit.
fn cholesky_small<const N: usize>(data: &mut [f64]) -> bool {
    let Ok(a) = <&mut [[f64; N]; N]>::try_from(data.as_chunks_mut::<N>().0) else {
        return false;
    };
    for j in 0..N {
        let mut d = a[j][j];
        for col_k in &a[..j] {
            let ljk = col_k[j];
            if ljk != 0.0 {
                d -= ljk * ljk;
            }
        }
        if d.is_nan() || d <= 0.0 || d.is_infinite() {
            return false;
        }
        let ljj = d.sqrt();
        a[j][j] = ljj;
        let inv = 1.0 / ljj;
        for i in j + 1..N {
            let mut s = a[j][i];
            for col_k in &a[..j] {
                let ljk = col_k[j];
                if ljk != 0.0 {
                    s -= col_k[i] * ljk;
                }
            }
            a[j][i] = s * inv;
        }
    }
    true
}

/// The factorization of [`cholesky_in_place`] on the column-major data of
/// an `n × n` matrix.
#[inline(always)]
fn cholesky_kernel(data: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let (left, right) = data.split_at_mut(j * n);
        let col_j = &mut right[j..n];
        // Column j of L from the columns before it (rows j..n only; the
        // slices carry their bounds, so the inner loop has no index checks).
        for col_k in left.chunks_exact(n) {
            let ljk = col_k[j];
            if ljk != 0.0 {
                for (c, l) in col_j.iter_mut().zip(&col_k[j..]) {
                    *c -= l * ljk;
                }
            }
        }
        let d = col_j[0];
        if d.is_nan() || d <= 0.0 || d.is_infinite() {
            return false;
        }
        let ljj = d.sqrt();
        col_j[0] = ljj;
        let inv = 1.0 / ljj;
        for x in &mut col_j[1..] {
            *x *= inv;
        }
    }
    true
}

/// Solves L Lᵀ x = b in place with the factor of [`cholesky_in_place`].
pub fn cholesky_solve(l: &DMatrix<f64>, b: &mut [f64]) {
    let n = l.nrows();
    if n == 0 {
        return;
    }
    let data = l.as_slice();
    macro_rules! sized {
        ($($k:literal)*) => {
            match n {
                $($k => cholesky_solve_small::<$k>(data, &mut b[..$k]),)*
                _ => cholesky_solve_kernel(data, &mut b[..n], n),
            }
        };
    }
    sized!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// [`cholesky_solve_kernel`] for a constant order `N` (loops of constant
/// length, unrolled; the same operations in the same order).
fn cholesky_solve_small<const N: usize>(data: &[f64], b: &mut [f64]) {
    let (cols, _) = data.as_chunks::<N>();
    for j in 0..N {
        let col = &cols[j];
        let yj = b[j] / col[j];
        b[j] = yj;
        if yj != 0.0 {
            for i in 0..N {
                if i > j {
                    b[i] -= col[i] * yj;
                }
            }
        }
    }
    for j in (0..N).rev() {
        let col = &cols[j];
        let mut s = b[j];
        for i in 0..N {
            if i > j {
                s -= col[i] * b[i];
            }
        }
        b[j] = s / col[j];
    }
}

/// The solve of [`cholesky_solve`] with the factor's column-major data
/// (`n × n`) and the right-hand side `b` (`n`).
#[inline(always)]
fn cholesky_solve_kernel(data: &[f64], b: &mut [f64], n: usize) {
    // L y = b (column oriented: y_j, then subtract it from the rows below).
    for (j, col) in data.chunks_exact(n).enumerate() {
        let (head, tail) = b.split_at_mut(j + 1);
        let yj = head[j] / col[j];
        head[j] = yj;
        if yj != 0.0 {
            for (x, c) in tail.iter_mut().zip(&col[j + 1..]) {
                *x -= c * yj;
            }
        }
    }
    // Lᵀ x = y (row j of Lᵀ is column j of L: a dot product down the column).
    for (j, col) in data.chunks_exact(n).enumerate().rev() {
        let (head, tail) = b.split_at_mut(j + 1);
        let mut s = head[j];
        for (c, x) in col[j + 1..].iter().zip(tail.iter()) {
            s -= c * x;
        }
        head[j] = s / col[j];
    }
}

#[cfg(test)]
mod cholesky_tests {
    use super::*;

    #[test]
    fn cholesky_solves_spd_systems_like_nalgebra_and_refuses_indefinite_ones() {
        // Deterministic SPD matrices A = B Bᵀ + n·I.
        for n in [1usize, 2, 5, 13, 30] {
            let b = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 11) as f64 / 11.0 - 0.4);
            let a = &b * b.transpose() + DMatrix::identity(n, n) * n as f64;
            let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut l = a.clone();
            assert!(cholesky_in_place(&mut l));
            let mut x = rhs.clone();
            cholesky_solve(&l, &mut x);
            let expect = a
                .clone()
                .cholesky()
                .unwrap()
                .solve(&nalgebra::DVector::from_vec(rhs));
            for (u, w) in x.iter().zip(expect.iter()) {
                assert!(
                    (u - w).abs() < 1e-12 * (1.0 + w.abs()),
                    "n = {n}: {u} vs {w}"
                );
            }
        }
        let mut indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky_in_place(&mut indefinite));
        let mut indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky_kernel(indefinite.as_mut_slice(), 2));
        assert!(!cholesky_in_place(&mut indefinite));
        let mut nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(!cholesky_kernel(nan.as_mut_slice(), 1));
        assert!(!cholesky_in_place(&mut nan));
    }

    #[test]
    fn sized_kernels_round_exactly_like_the_general_ones() {
        // The unrolled kernels of orders ≤ 16 must give the general kernel's
        // factor and solution bit for bit (the scenario outputs must not
        // depend on which one ran).
        for n in 1usize..=16 {
            let b = DMatrix::from_fn(n, n, |i, j| ((i * 5 + j * 11) % 13) as f64 / 7.0 - 0.8);
            let a = &b * b.transpose() + DMatrix::identity(n, n) * 0.1;
            let mut small = a.clone();
            let mut general = a.clone();
            assert!(cholesky_in_place(&mut small));
            assert!(cholesky_kernel(general.as_mut_slice(), n));
            let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.91).cos()).collect();
            let mut xs = rhs.clone();
            let mut xg = rhs.clone();
            cholesky_solve(&small, &mut xs);
            cholesky_solve_kernel(general.as_slice(), &mut xg, n);
            for j in 0..n {
                for i in j..n {
                    assert_eq!(
                        small[(i, j)].to_bits(),
                        general[(i, j)].to_bits(),
                        "n = {n}"
                    );
                }
            }
            for (u, w) in xs.iter().zip(&xg) {
                assert_eq!(u.to_bits(), w.to_bits(), "n = {n}");
            }
        }
    }
}
