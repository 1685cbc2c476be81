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
    ///
    /// On x86-64 CPUs with AVX2 (detected at run time) the same code runs
    /// compiled for AVX2: four lanes per vector instruction instead of
    /// SSE2's two in the elimination's column updates. The IEEE operations
    /// and their order are the same (Rust neither contracts nor reassociates
    /// floating-point arithmetic, and AVX2 brings no fused multiply–add),
    /// so the factors are bit for bit the same (test
    /// `avx2_build_is_bit_identical`). Measured on dense random matrices
    /// (one run, a timing loop of 2·10⁶/n² factorizations): order 42 8 µs
    /// against 10, 54 (a freight bogie's block) 14 against 19, 114 120
    /// against 175; orders 18–24 the same.
    pub fn factorize(&mut self) -> Result<(), SingularPivot> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.factorize_avx2() };
        }
        self.factorize_lanes()
    }

    /// [`Self::factorize_lanes`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn factorize_avx2(&mut self) -> Result<(), SingularPivot> {
        self.factorize_lanes()
    }

    /// The factorization of [`Self::factorize`], for either build.
    #[inline(always)]
    fn factorize_lanes(&mut self) -> Result<(), SingularPivot> {
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
    /// (Not built for AVX2 as the factorization is: measured on orders
    /// 18–114, the substitutions were no faster with it.)
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

    /// The AVX2 build of the factorization gives the portable build's
    /// numbers bit for bit: matrices of orders 1–70 with
    /// random entries of mixed magnitude and sign, a fifth of them zero
    /// (the zero skips), pivoting on every column.
    #[test]
    fn avx2_build_is_bit_identical() {
        #[cfg(target_arch = "x86_64")]
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        // xorshift64*: deterministic, no dependency.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        };
        for n in 1..=70 {
            let mut a = DMatrix::zeros(n, n);
            for x in a.iter_mut() {
                let u = next();
                *x = if u < 0.2 {
                    0.0
                } else {
                    (u - 0.6) * 10f64.powi((next() * 6.0) as i32 - 3)
                };
            }
            for i in 0..n {
                a[(i, i)] += 1.0;
            }
            let (mut fast, mut plain) = (DenseLu::new(n), DenseLu::new(n));
            fast.matrix_mut().copy_from(&a);
            plain.matrix_mut().copy_from(&a);
            let (rf, rp) = (fast.factorize(), plain.factorize_lanes());
            assert_eq!(rf, rp, "n = {n}");
            if rf.is_err() {
                continue;
            }
            let bits = |m: &DMatrix<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast.lu), bits(&plain.lu), "n = {n}");
            assert_eq!(fast.piv, plain.piv, "n = {n}");
        }
    }

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

/// [`cholesky_kernel`] for a constant order `N` ≤ 16: the loop over the
/// columns is written out (`j` a constant in each copy of
/// [`cholesky_column`]), so that every inner loop has a constant length
/// and is unrolled and vectorized.
fn cholesky_small<const N: usize>(data: &mut [f64]) -> bool {
    let Ok(a) = <&mut [[f64; N]; N]>::try_from(data.as_chunks_mut::<N>().0) else {
        return false;
    };
    macro_rules! columns {
        ($($j:literal)*) => {
            $(if $j < N && !cholesky_column::<N>(a, $j) {
                return false;
            })*
        };
    }
    columns!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
    true
}

/// Column `j` of [`cholesky_small`]: the operations of [`cholesky_kernel`]
/// on that column, in the same order, with all rows i ≥ j accumulated in
/// registers.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // ranges from the constant j: unrolled as written
fn cholesky_column<const N: usize>(a: &mut [[f64; N]; N], j: usize) -> bool {
    let mut acc = a[j];
    for k in 0..j {
        let ljk = a[k][j];
        if ljk != 0.0 {
            for i in j..N {
                acc[i] -= a[k][i] * ljk;
            }
        }
    }
    let d = acc[j];
    if !is_positive_pivot(d) {
        return false;
    }
    let ljj = d.sqrt();
    a[j][j] = ljj;
    let inv = 1.0 / ljj;
    for i in j + 1..N {
        a[j][i] = acc[i] * inv;
    }
    true
}

/// Whether `d` is a usable Cholesky pivot: positive and finite (false for
/// NaN, in two comparisons).
#[inline(always)]
fn is_positive_pivot(d: f64) -> bool {
    d > 0.0 && d < f64::INFINITY
}

/// Ends column j of L in place: its pivot (the updated diagonal entry
/// `col_j[0]`) becomes √d and the entries below are divided by it; false if
/// the pivot is not positive and finite. Shared by the factorization and
/// its test reference.
#[inline(always)]
fn finish_column(col_j: &mut [f64]) -> bool {
    let d = col_j[0];
    if !is_positive_pivot(d) {
        return false;
    }
    let ljj = d.sqrt();
    col_j[0] = ljj;
    let inv = 1.0 / ljj;
    for x in &mut col_j[1..] {
        *x *= inv;
    }
    true
}

/// Rows of a column of L accumulated together in registers by
/// [`cholesky_kernel`] (four SSE2 or two AVX registers).
const ROW_BLOCK: usize = 8;

/// The factorization of [`cholesky_in_place`] on the column-major data of
/// an `n × n` matrix.
///
/// Column j of L is `l_ij = (a_ij − Σ_{k<j} l_ik l_jk) / l_jj`, the sum
/// taken in the order k = 0, 1, … with the terms of zero `l_jk` skipped
/// (the structural zeros of a vehicle's block-diagonal M cost nothing). The
/// rows i ≥ j are taken [`ROW_BLOCK`] at a time, each block accumulated in
/// registers over all k and stored once, so that the inner loop is a
/// vectorizable `acc[t] −= l_{i+t,k} l_jk` without a load and a store of
/// column j per term. Every entry sees the same operations in the same
/// order whatever the blocking, hence the same bits at every size.
#[inline(always)]
fn cholesky_kernel(data: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let (left, right) = data.split_at_mut(j * n);
        let col_j = &mut right[j..n];
        let len = n - j;
        if len >= ROW_BLOCK {
            // Whole blocks from row j down; the rows a whole block leaves at
            // the bottom are done as the last ROW_BLOCK rows of the column,
            // from their original values saved here (the rows it shares
            // with the block above get the same values again).
            let tail = len - ROW_BLOCK;
            let saved: [f64; ROW_BLOCK] = col_j[tail..].try_into().expect("the last block");
            let mut start = 0;
            while start + ROW_BLOCK <= len {
                let block: &mut [f64; ROW_BLOCK] = (&mut col_j[start..start + ROW_BLOCK])
                    .try_into()
                    .expect("a block within the column");
                *block = column_rows(left, n, j, j + start, *block);
                start += ROW_BLOCK;
            }
            if start < len {
                let block: &mut [f64; ROW_BLOCK] =
                    (&mut col_j[tail..]).try_into().expect("the last block");
                *block = column_rows(left, n, j, j + tail, saved);
            }
        } else {
            // A short column: blocks of 4, 2 and 1 rows.
            let mut start = 0;
            macro_rules! rows {
                ($b:literal) => {
                    if len - start >= $b {
                        let block: &mut [f64; $b] = (&mut col_j[start..start + $b])
                            .try_into()
                            .expect("a block within the column");
                        *block = column_rows(left, n, j, j + start, *block);
                        start += $b;
                    }
                };
            }
            rows!(4);
            rows!(2);
            if len - start == 1 {
                let block: &mut [f64; 1] = (&mut col_j[start..]).try_into().expect("the last row");
                *block = column_rows(left, n, j, j + start, *block);
            }
        }
        if !finish_column(col_j) {
            return false;
        }
    }
    true
}

/// Rows `r0..r0 + B` of column `j` in [`cholesky_kernel`]: `acc` (the
/// original entries of those rows) minus `l_ik l_jk` for the columns k < j
/// in `left` (column-major, `n` rows each), k ascending, zero `l_jk`
/// skipped, accumulated in registers.
#[inline(always)]
fn column_rows<const B: usize>(
    left: &[f64],
    n: usize,
    j: usize,
    r0: usize,
    mut acc: [f64; B],
) -> [f64; B] {
    for col_k in left.chunks_exact(n) {
        let ljk = col_k[j];
        if ljk != 0.0 {
            let src: &[f64; B] = col_k[r0..r0 + B]
                .try_into()
                .expect("rows within the column");
            for (a, l) in acc.iter_mut().zip(src) {
                *a -= l * ljk;
            }
        }
    }
    acc
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

/// [`cholesky_solve_kernel`] for a constant order `N` ≤ 16, the loops over
/// the columns written out (the same operations in the same order).
#[allow(clippy::needless_range_loop)] // ranges from the constant j: unrolled as written
fn cholesky_solve_small<const N: usize>(data: &[f64], b: &mut [f64]) {
    let (Ok(l), Ok(x)) = (
        <&[[f64; N]; N]>::try_from(data.as_chunks::<N>().0),
        <&mut [f64; N]>::try_from(b),
    ) else {
        return;
    };
    // L y = b, column j: y_j, then subtract it from the rows below.
    macro_rules! forward {
        ($($j:literal)*) => {
            $(if $j < N {
                let col = &l[$j];
                let yj = x[$j] / col[$j];
                x[$j] = yj;
                if yj != 0.0 {
                    for i in $j + 1..N {
                        x[i] -= col[i] * yj;
                    }
                }
            })*
        };
    }
    forward!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
    // Lᵀ x = y, row j: a dot product down column j, from the last row up.
    macro_rules! backward {
        ($($j:literal)*) => {
            $(if $j < N {
                let col = &l[$j];
                let mut s = x[$j];
                for i in $j + 1..N {
                    s -= col[i] * x[i];
                }
                x[$j] = s / col[$j];
            })*
        };
    }
    backward!(15 14 13 12 11 10 9 8 7 6 5 4 3 2 1 0);
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

/// The factorization and solve as they were before the row blocking (one
/// load and store of column j per term), the reference the tests compare
/// the blocked kernel with bit for bit.
#[cfg(test)]
fn cholesky_reference(data: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let (left, right) = data.split_at_mut(j * n);
        let col_j = &mut right[j..n];
        for col_k in left.chunks_exact(n) {
            let ljk = col_k[j];
            if ljk != 0.0 {
                for (c, l) in col_j.iter_mut().zip(&col_k[j..]) {
                    *c -= l * ljk;
                }
            }
        }
        if !finish_column(col_j) {
            return false;
        }
    }
    true
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
    fn blocked_kernels_round_exactly_like_the_unblocked_reference() {
        // The row-blocked factorization (sized copies for orders ≤ 16, the
        // general one above) must give the unblocked reference's factor and
        // solution bit for bit (the scenario outputs must not depend on the
        // blocking); orders up to 40 cover whole blocks, remainders and both
        // paths. Every third matrix has structural zeros (two uncoupled
        // diagonal blocks, as in a vehicle's M), which both skip.
        for n in 1usize..=40 {
            let b = DMatrix::from_fn(n, n, |i, j| ((i * 5 + j * 11) % 13) as f64 / 7.0 - 0.8);
            let mut a = &b * b.transpose() + DMatrix::identity(n, n) * 0.1;
            if n % 3 == 0 {
                let h = n / 2;
                for i in 0..n {
                    for j in 0..n {
                        if (i < h) != (j < h) {
                            a[(i, j)] = 0.0;
                        }
                    }
                }
            }
            let mut blocked = a.clone();
            let mut reference = a.clone();
            assert!(cholesky_in_place(&mut blocked));
            assert!(cholesky_reference(reference.as_mut_slice(), n));
            let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.91).cos()).collect();
            let mut xs = rhs.clone();
            let mut xg = rhs.clone();
            cholesky_solve(&blocked, &mut xs);
            cholesky_solve_kernel(reference.as_slice(), &mut xg, n);
            for j in 0..n {
                for i in j..n {
                    assert_eq!(
                        blocked[(i, j)].to_bits(),
                        reference[(i, j)].to_bits(),
                        "n = {n}, entry ({i}, {j})"
                    );
                }
            }
            for (u, w) in xs.iter().zip(&xg) {
                assert_eq!(u.to_bits(), w.to_bits(), "n = {n}");
            }
        }
    }
}
