//! Block structure of a system's matrices and the bordered block-diagonal
//! LU factorization that uses it.
//!
//! A train's coordinates are its vehicles' stacked in vehicle order: the
//! mass matrix M is block-diagonal (one block per vehicle), and the force
//! Jacobians ∂f/∂q, ∂f/∂q̇ add, between two vehicles, only entries in the
//! coordinates of the bodies that the couplers join (Pogorelov 2005,
//! Sect. 5: vehicles are external subsystems that exchange coupler forces
//! only). A [`BlockPattern`] states this: contiguous diagonal blocks and a
//! set of *border* coordinates; an entry (i, j) with i and j in different
//! blocks may be nonzero only when both are border coordinates. A
//! [`BlockMatrix`] stores such a matrix (the diagonal blocks dense, the
//! entries between blocks in one small border × border matrix), and
//! [`BorderedLu`] solves with it by the Schur complement on the border
//! (bordered block-diagonal elimination):
//!
//! ```text
//!     per block k, interior I and border B of the block:
//!         A_II = P L U                      (dense LU, partial pivoting in the block)
//!         X_k  = A_II⁻¹ A_IB,   S_k = A_BB − A_BI X_k
//!     S = (entries between blocks on the border) + Σ_k S_k      (nb × nb, dense LU)
//!     solve: y_k = A_II⁻¹ b_I,  S x_B = b_B − Σ_k A_BI y_k,  x_I = y_k − X_k x_B
//! ```
//!
//! The work is linear in the number of blocks (each block's own LU plus a
//! dense LU of the small border) where the dense LU of the whole matrix is
//! cubic in its order. The elimination is the same as Gaussian elimination
//! of the whole matrix with the interior coordinates ordered first, except
//! that pivots are searched within a block's interior only; when such a
//! pivot is (numerically) zero the factorization falls back to the dense LU
//! with partial pivoting of the whole matrix ([`BorderedLu::uses_dense`]),
//! so it never refuses a matrix that the dense solve accepts.

use std::ops::Range;
use std::sync::Arc;

use nalgebra::{DMatrix, DVector};

use crate::linalg::{DenseLu, SingularPivot};
use crate::system::SimError;

/// Diagonal blocks (contiguous coordinate ranges covering `0..n` in order)
/// and the border coordinates through which alone the blocks couple.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockPattern {
    blocks: Vec<Range<usize>>,
    border: Vec<usize>,
    /// Per coordinate: its block.
    block_of: Vec<usize>,
    /// Per coordinate: its position in `border`, `usize::MAX` if interior.
    border_pos: Vec<usize>,
}

impl BlockPattern {
    /// The pattern of `blocks` (contiguous, starting at 0, each following
    /// the one before, none empty) and `border` (coordinates, any order,
    /// duplicates allowed; stored sorted).
    ///
    /// # Errors
    /// [`SimError::Other`] when the blocks do not tile `0..n` or a border
    /// coordinate is not below n.
    pub fn new(blocks: Vec<Range<usize>>, mut border: Vec<usize>) -> Result<Self, SimError> {
        let mut end = 0;
        for (k, r) in blocks.iter().enumerate() {
            if r.start != end || r.is_empty() {
                return Err(SimError::Other(format!(
                    "block pattern: block {k} ({r:?}) must be non-empty and start at {end}"
                )));
            }
            end = r.end;
        }
        let n = end;
        border.sort_unstable();
        border.dedup();
        if let Some(&i) = border.iter().find(|&&i| i >= n) {
            return Err(SimError::Other(format!(
                "block pattern: border coordinate {i} is not below the order {n}"
            )));
        }
        let mut block_of = vec![0; n];
        for (k, r) in blocks.iter().enumerate() {
            block_of[r.clone()].fill(k);
        }
        let mut border_pos = vec![usize::MAX; n];
        for (p, &i) in border.iter().enumerate() {
            border_pos[i] = p;
        }
        Ok(Self {
            blocks,
            border,
            block_of,
            border_pos,
        })
    }

    /// Order n of the matrices.
    pub fn dim(&self) -> usize {
        self.block_of.len()
    }

    /// The diagonal blocks' coordinate ranges.
    pub fn blocks(&self) -> &[Range<usize>] {
        &self.blocks
    }

    /// The border coordinates, sorted.
    pub fn border(&self) -> &[usize] {
        &self.border
    }

    /// The block of coordinate `i`.
    pub fn block_of(&self, i: usize) -> usize {
        self.block_of[i]
    }

    /// The position of coordinate `i` in [`BlockPattern::border`], if it is
    /// a border coordinate.
    pub fn border_index(&self, i: usize) -> Option<usize> {
        let p = self.border_pos[i];
        (p != usize::MAX).then_some(p)
    }

    /// Whether entry (i, j) may be nonzero: i and j in the same block, or
    /// both on the border.
    pub fn allows(&self, i: usize, j: usize) -> bool {
        self.block_of[i] == self.block_of[j]
            || (self.border_pos[i] != usize::MAX && self.border_pos[j] != usize::MAX)
    }

    /// Groups of coordinates that a finite-difference Jacobian may perturb
    /// together (Curtis, Powell & Reid 1974, "On the estimation of sparse
    /// Jacobian matrices", IMA J. Appl. Math. 13): the g-th interior
    /// coordinate of every block in group g (an interior coordinate moves
    /// only its own block's rows, so the columns of one group touch disjoint
    /// rows), then every border coordinate alone. Each coordinate is in
    /// exactly one group; rows of column j are [`BlockPattern::column_rows`].
    pub fn difference_groups(&self) -> Vec<Vec<usize>> {
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for r in &self.blocks {
            for (g, i) in r
                .clone()
                .filter(|&i| self.border_pos[i] == usize::MAX)
                .enumerate()
            {
                if g == groups.len() {
                    groups.push(Vec::new());
                }
                groups[g].push(i);
            }
        }
        groups.extend(self.border.iter().map(|&i| vec![i]));
        groups
    }

    /// Whether row i of column j may be nonzero, for the columns of one
    /// group of [`BlockPattern::difference_groups`]: the rows of j's block,
    /// and for a border coordinate j also the border rows of other blocks.
    pub fn column_rows(&self, j: usize) -> impl Iterator<Item = usize> + '_ {
        let k = self.block_of[j];
        let own = self.blocks[k].clone();
        let others = if self.border_pos[j] == usize::MAX {
            &self.border[..0]
        } else {
            &self.border[..]
        };
        own.chain(
            others
                .iter()
                .copied()
                .filter(move |&i| self.block_of[i] != k),
        )
    }

    /// Multiply–add count of one dense LU factorization of the whole
    /// matrix, n³/3, and of one [`BorderedLu::factorize`] (each block's
    /// interior LU, its border columns' solves and Schur products, the
    /// border's LU): what [`BlockPattern::pays`] compares.
    pub fn factorization_work(&self) -> (f64, f64) {
        let n = self.dim() as f64;
        let mut block = 0.0;
        for r in &self.blocks {
            let nb = self.border.iter().filter(|&&i| r.contains(&i)).count() as f64;
            let ni = r.len() as f64 - nb;
            block += ni * ni * ni / 3.0 + nb * ni * ni + nb * nb * ni;
        }
        let nb = self.border.len() as f64;
        (n * n * n / 3.0, block + nb * nb * nb / 3.0)
    }

    /// Whether the bordered factorization saves at least half of the dense
    /// work (else the dense solve, with its simpler loops, is as fast).
    pub fn pays(&self) -> bool {
        let (dense, block) = self.factorization_work();
        2.0 * block <= dense
    }
}

/// A matrix of a [`BlockPattern`]: the diagonal blocks dense, the entries
/// between different blocks (on the border only) in one border × border
/// matrix.
#[derive(Debug, Clone)]
pub struct BlockMatrix {
    pattern: Arc<BlockPattern>,
    diag: Vec<DMatrix<f64>>,
    /// Entry (a, b): the entry (border[a], border[b]) when the two are in
    /// different blocks; zero where they are in the same block (that entry
    /// lives in the diagonal block).
    coupling: DMatrix<f64>,
}

impl BlockMatrix {
    /// The zero matrix of `pattern`.
    pub fn zeros(pattern: &Arc<BlockPattern>) -> Self {
        let nb = pattern.border.len();
        Self {
            diag: pattern
                .blocks
                .iter()
                .map(|r| DMatrix::zeros(r.len(), r.len()))
                .collect(),
            coupling: DMatrix::zeros(nb, nb),
            pattern: pattern.clone(),
        }
    }

    /// The pattern.
    pub fn pattern(&self) -> &Arc<BlockPattern> {
        &self.pattern
    }

    /// Diagonal block `k` (coordinates `pattern().blocks()[k]`).
    pub fn block(&self, k: usize) -> &DMatrix<f64> {
        &self.diag[k]
    }

    /// Diagonal block `k`, mutable.
    pub fn block_mut(&mut self, k: usize) -> &mut DMatrix<f64> {
        &mut self.diag[k]
    }

    /// All diagonal blocks, mutable (to fill them independently).
    pub fn blocks_mut(&mut self) -> &mut [DMatrix<f64>] {
        &mut self.diag
    }

    /// The entries between blocks: entry (a, b) is the matrix entry
    /// `(border[a], border[b])` for border coordinates of different blocks;
    /// entries of coordinates in the same block must stay zero here.
    pub fn coupling(&self) -> &DMatrix<f64> {
        &self.coupling
    }

    /// Copies the entries of `other` (of the same pattern).
    pub fn copy_from(&mut self, other: &BlockMatrix) {
        for (d, o) in self.diag.iter_mut().zip(&other.diag) {
            d.copy_from(o);
        }
        self.coupling.copy_from(&other.coupling);
    }

    /// Sets the entries between blocks to zero (the diagonal blocks stay).
    pub fn clear_coupling(&mut self) {
        self.coupling.as_mut_slice().fill(0.0);
    }

    /// Sets every entry to zero.
    pub fn fill_zero(&mut self) {
        for d in &mut self.diag {
            d.as_mut_slice().fill(0.0);
        }
        self.coupling.as_mut_slice().fill(0.0);
    }

    /// Entry (i, j) (global coordinates).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let p = &self.pattern;
        let (k, l) = (p.block_of[i], p.block_of[j]);
        if k == l {
            let s = p.blocks[k].start;
            self.diag[k][(i - s, j - s)]
        } else if p.allows(i, j) {
            self.coupling[(p.border_pos[i], p.border_pos[j])]
        } else {
            0.0
        }
    }

    /// Adds `x` to entry (i, j). Returns `false` (and adds nothing) when the
    /// pattern has no place for the entry.
    pub fn add(&mut self, i: usize, j: usize, x: f64) -> bool {
        let p = &self.pattern;
        let (k, l) = (p.block_of[i], p.block_of[j]);
        if k == l {
            let s = p.blocks[k].start;
            self.diag[k][(i - s, j - s)] += x;
            true
        } else if p.allows(i, j) {
            self.coupling[(p.border_pos[i], p.border_pos[j])] += x;
            true
        } else {
            false
        }
    }

    /// `y = A x`.
    pub fn mul_to(&self, x: &[f64], y: &mut [f64]) {
        let p = &self.pattern;
        for (d, r) in self.diag.iter().zip(&p.blocks) {
            let n = r.len();
            let yk = &mut y[r.clone()];
            yk.fill(0.0);
            // Column by column (column-major blocks).
            for (col, &xj) in d.as_slice().chunks_exact(n).zip(&x[r.clone()]) {
                if xj != 0.0 {
                    for (yi, a) in yk.iter_mut().zip(col) {
                        *yi += a * xj;
                    }
                }
            }
        }
        let nb = p.border.len();
        if nb > 0 {
            for (b, col) in self.coupling.as_slice().chunks_exact(nb).enumerate() {
                let xj = x[p.border[b]];
                if xj != 0.0 {
                    for (a, c) in col.iter().enumerate() {
                        y[p.border[a]] += c * xj;
                    }
                }
            }
        }
    }

    /// Overwrites every entry the pattern holds with the dense n × n `m`'s
    /// (the inverse of [`BlockMatrix::to_dense`]; `m`'s entries outside the
    /// pattern, structurally zero, are not read).
    pub fn copy_from_dense(&mut self, m: &DMatrix<f64>) {
        let p = &self.pattern;
        for (d, r) in self.diag.iter_mut().zip(&p.blocks) {
            d.copy_from(&m.view((r.start, r.start), (r.len(), r.len())));
        }
        for (b, &j) in p.border.iter().enumerate() {
            for (a, &i) in p.border.iter().enumerate() {
                self.coupling[(a, b)] = if p.block_of[i] != p.block_of[j] {
                    m[(i, j)]
                } else {
                    0.0
                };
            }
        }
    }

    /// The dense n × n matrix (for tests and for solves that need it).
    pub fn to_dense(&self) -> DMatrix<f64> {
        let p = &self.pattern;
        let n = p.dim();
        let mut m = DMatrix::zeros(n, n);
        for (d, r) in self.diag.iter().zip(&p.blocks) {
            m.view_mut((r.start, r.start), (r.len(), r.len()))
                .copy_from(d);
        }
        for (b, &j) in p.border.iter().enumerate() {
            for (a, &i) in p.border.iter().enumerate() {
                if p.block_of[i] != p.block_of[j] {
                    m[(i, j)] = self.coupling[(a, b)];
                }
            }
        }
        m
    }

    /// The stored entries as slices (for finiteness checks): each diagonal
    /// block's, then the coupling entries'.
    pub fn slices(&self) -> impl Iterator<Item = &[f64]> + '_ {
        self.diag
            .iter()
            .map(|d| d.as_slice())
            .chain(std::iter::once(self.coupling.as_slice()))
    }

    /// Sets `self = a − β d − β² c` entry by entry (all three of the same
    /// pattern): the iteration matrix of Park's method from M, ∂f/∂q̇ and
    /// ∂f/∂q, with the operations of the dense assembly.
    pub fn set_iteration_matrix(
        &mut self,
        a: &BlockMatrix,
        d: &BlockMatrix,
        c: &BlockMatrix,
        beta: f64,
    ) {
        let b2 = beta * beta;
        let combine =
            |out: &mut DMatrix<f64>, a: &DMatrix<f64>, d: &DMatrix<f64>, c: &DMatrix<f64>| {
                let it = out
                    .as_mut_slice()
                    .iter_mut()
                    .zip(a.as_slice())
                    .zip(d.as_slice())
                    .zip(c.as_slice());
                for (((x, &a), &d), &c) in it {
                    *x = a - beta * d - b2 * c;
                }
            };
        for k in 0..self.diag.len() {
            combine(&mut self.diag[k], &a.diag[k], &d.diag[k], &c.diag[k]);
        }
        combine(&mut self.coupling, &a.coupling, &d.coupling, &c.coupling);
    }
}

/// Indices of one diagonal block in the bordered factorization.
#[derive(Debug, Clone)]
struct BlockPart {
    /// Global start of the block.
    start: usize,
    /// Local indices of the interior coordinates.
    interior: Vec<usize>,
    /// Local indices of the border coordinates.
    border: Vec<usize>,
    /// Positions of `border` in the pattern's border.
    border_pos: Vec<usize>,
    /// LU of A_II.
    lu: DenseLu,
    /// X = A_II⁻¹ A_IB (interior × border).
    x: DMatrix<f64>,
    /// A_BI (border × interior).
    a_bi: DMatrix<f64>,
    /// y = A_II⁻¹ b_I during a solve.
    y: Vec<f64>,
}

/// The bordered block-diagonal LU factorization of a [`BlockMatrix`]
/// (module documentation), with the workspace for its solves; the ordering
/// (interior coordinates of each block, then the border) is computed once
/// from the pattern.
#[derive(Debug, Clone)]
pub struct BorderedLu {
    pattern: Arc<BlockPattern>,
    parts: Vec<BlockPart>,
    schur: DenseLu,
    r: Vec<f64>,
    /// The dense LU of the whole matrix when a block's interior pivot
    /// failed (allocated on first need).
    dense: Option<DenseLu>,
    use_dense: bool,
    valid: bool,
}

impl BorderedLu {
    /// Workspace for matrices of `pattern`.
    pub fn new(pattern: &Arc<BlockPattern>) -> Self {
        let parts = pattern
            .blocks
            .iter()
            .map(|r| {
                let (border, interior): (Vec<usize>, Vec<usize>) =
                    (0..r.len()).partition(|&i| pattern.border_pos[r.start + i] != usize::MAX);
                let border_pos = border
                    .iter()
                    .map(|&i| pattern.border_pos[r.start + i])
                    .collect();
                let (ni, nb) = (interior.len(), border.len());
                BlockPart {
                    start: r.start,
                    lu: DenseLu::new(ni),
                    x: DMatrix::zeros(ni, nb),
                    a_bi: DMatrix::zeros(nb, ni),
                    y: vec![0.0; ni],
                    interior,
                    border,
                    border_pos,
                }
            })
            .collect();
        let nb = pattern.border.len();
        Self {
            pattern: pattern.clone(),
            parts,
            schur: DenseLu::new(nb),
            r: vec![0.0; nb],
            dense: None,
            use_dense: false,
            valid: false,
        }
    }

    /// Whether the last factorization fell back to the dense LU of the
    /// whole matrix (an interior pivot of a block was zero).
    pub fn uses_dense(&self) -> bool {
        self.use_dense
    }

    /// Factorizes `a` (of this workspace's pattern).
    ///
    /// # Errors
    /// [`SingularPivot`] (a global column) when the matrix is numerically
    /// singular: its dense LU with partial pivoting fails too.
    pub fn factorize(&mut self, a: &BlockMatrix) -> Result<(), SingularPivot> {
        debug_assert!(Arc::ptr_eq(&self.pattern, &a.pattern) || *self.pattern == *a.pattern);
        self.valid = false;
        self.use_dense = false;
        match self.factorize_blocks(a) {
            Ok(()) => {
                self.valid = true;
                Ok(())
            }
            Err(_) => {
                let n = self.pattern.dim();
                let dense = self.dense.get_or_insert_with(|| DenseLu::new(n));
                dense.matrix_mut().copy_from(&a.to_dense());
                dense.factorize()?;
                self.use_dense = true;
                self.valid = true;
                Ok(())
            }
        }
    }

    fn factorize_blocks(&mut self, a: &BlockMatrix) -> Result<(), SingularPivot> {
        let schur = self.schur.matrix_mut();
        schur.copy_from(&a.coupling);
        for (part, d) in self.parts.iter_mut().zip(&a.diag) {
            let (ni, nb) = (part.interior.len(), part.border.len());
            {
                let m = part.lu.matrix_mut();
                for (c, &jc) in part.interior.iter().enumerate() {
                    for (r, &ir) in part.interior.iter().enumerate() {
                        m[(r, c)] = d[(ir, jc)];
                    }
                }
            }
            part.lu.factorize().map_err(|p| SingularPivot {
                column: part.start + part.interior.get(p.column).copied().unwrap_or(0),
            })?;
            for (c, &jc) in part.border.iter().enumerate() {
                let col = &mut part.x.as_mut_slice()[c * ni..(c + 1) * ni];
                for (x, &ir) in col.iter_mut().zip(&part.interior) {
                    *x = d[(ir, jc)];
                }
                part.lu.solve_slice(col);
            }
            for (c, &jc) in part.interior.iter().enumerate() {
                for (r, &ir) in part.border.iter().enumerate() {
                    part.a_bi[(r, c)] = d[(ir, jc)];
                }
            }
            // S_k = A_BB − A_BI X, into the border rows and columns of the block.
            for c in 0..nb {
                let xc = &part.x.as_slice()[c * ni..(c + 1) * ni];
                for r in 0..nb {
                    let mut s = d[(part.border[r], part.border[c])];
                    for (l, xl) in xc.iter().enumerate() {
                        s -= part.a_bi[(r, l)] * xl;
                    }
                    schur[(part.border_pos[r], part.border_pos[c])] = s;
                }
            }
        }
        let border = &self.pattern.border;
        self.schur.factorize().map_err(|p| SingularPivot {
            column: border.get(p.column).copied().unwrap_or(0),
        })
    }

    /// Solves `A x = b` in place (b becomes x) with the stored
    /// factorization.
    pub fn solve_in_place(&mut self, b: &mut [f64]) {
        debug_assert!(self.valid, "solve with an invalid bordered factorization");
        if self.use_dense {
            if let Some(d) = &self.dense {
                d.solve_slice(b);
            }
            return;
        }
        for (p, &i) in self.pattern.border.iter().enumerate() {
            self.r[p] = b[i];
        }
        for part in &mut self.parts {
            for (y, &i) in part.y.iter_mut().zip(&part.interior) {
                *y = b[part.start + i];
            }
            part.lu.solve_slice(&mut part.y);
            // r_B −= A_BI y
            let nb = part.border.len();
            for (l, &yl) in part.y.iter().enumerate() {
                if yl != 0.0 {
                    let col = &part.a_bi.as_slice()[l * nb..(l + 1) * nb];
                    for (a, &pos) in col.iter().zip(&part.border_pos) {
                        self.r[pos] -= a * yl;
                    }
                }
            }
        }
        self.schur.solve_slice(&mut self.r);
        for part in &mut self.parts {
            let ni = part.interior.len();
            // x_I = y − X x_B
            for (c, &pos) in part.border_pos.iter().enumerate() {
                let xb = self.r[pos];
                if xb != 0.0 {
                    let col = &part.x.as_slice()[c * ni..(c + 1) * ni];
                    for (y, xc) in part.y.iter_mut().zip(col) {
                        *y -= xc * xb;
                    }
                }
            }
            for (y, &i) in part.y.iter().zip(&part.interior) {
                b[part.start + i] = *y;
            }
        }
        for (p, &i) in self.pattern.border.iter().enumerate() {
            b[i] = self.r[p];
        }
    }

    /// [`BorderedLu::solve_in_place`] on a vector.
    pub fn solve_vector(&mut self, b: &mut DVector<f64>) {
        self.solve_in_place(b.as_mut_slice());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bordered matrix of `blocks` with border coordinates `border`:
    /// pseudo-random entries where the pattern allows them (a diagonally
    /// heavy block per vehicle, couplings between blocks on the border).
    fn bordered(blocks: &[Range<usize>], border: &[usize], seed: u64) -> BlockMatrix {
        let pattern = Arc::new(BlockPattern::new(blocks.to_vec(), border.to_vec()).unwrap());
        let n = pattern.dim();
        let mut m = BlockMatrix::zeros(&pattern);
        let mut state = seed;
        let mut next = || {
            // xorshift64*: deterministic entries in [−1, 1).
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        for j in 0..n {
            for i in 0..n {
                if pattern.allows(i, j) {
                    let d = if i == j { 4.0 } else { 0.0 };
                    assert!(m.add(i, j, d + next()));
                }
            }
        }
        m
    }

    fn residual(a: &DMatrix<f64>, x: &[f64], b: &[f64]) -> f64 {
        let ax = a * DVector::from_column_slice(x);
        ax.iter()
            .zip(b)
            .map(|(u, w)| (u - w).abs())
            .fold(0.0, f64::max)
    }

    /// The bordered LU solves A x = b for a known x (b = A x) like the dense
    /// LU of the whole matrix, to rounding: three blocks of 7, 5 and 9
    /// coordinates, the border in blocks 1–3 couples 1–2 and 2–3 (a train).
    #[test]
    fn bordered_lu_solves_like_the_dense_lu() {
        let blocks = [0..7, 7..12, 12..21];
        let border = [5, 6, 7, 8, 19, 20];
        let a = bordered(&blocks, &border, 17);
        let dense = a.to_dense();
        // Entries outside the pattern are zero: between the interiors, and
        // between block 1 and the border of block 3 only through the border.
        assert_eq!(dense[(0, 12)], 0.0);
        assert_eq!(dense[(12, 0)], 0.0);
        assert_ne!(dense[(5, 19)], 0.0);
        let x_true: Vec<f64> = (0..21).map(|i| (i as f64 * 0.7).sin() + 0.1).collect();
        let b = (&dense * DVector::from_column_slice(&x_true))
            .as_slice()
            .to_vec();
        let mut mul = vec![0.0; 21];
        a.mul_to(&x_true, &mut mul);
        for (u, w) in mul.iter().zip(&b) {
            assert!((u - w).abs() <= 1e-13 * (1.0 + w.abs()));
        }
        let mut lu = BorderedLu::new(a.pattern());
        lu.factorize(&a).unwrap();
        assert!(!lu.uses_dense());
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        let mut dlu = DenseLu::new(21);
        dlu.matrix_mut().copy_from(&dense);
        dlu.factorize().unwrap();
        let mut xd = b.clone();
        dlu.solve_slice(&mut xd);
        for ((u, w), t) in x.iter().zip(&xd).zip(&x_true) {
            assert!(
                (u - w).abs() <= 1e-12 * w.abs().max(1.0),
                "{u} vs dense {w}"
            );
            assert!(
                (u - t).abs() <= 1e-12 * t.abs().max(1.0),
                "{u} vs exact {t}"
            );
        }
        assert!(residual(&dense, &x, &b) < 1e-13);
        // The factorization is reused for a second right-hand side.
        let mut y = vec![1.0; 21];
        lu.solve_in_place(&mut y);
        assert!(residual(&dense, &y, &[1.0; 21]) < 1e-13);
    }

    /// `copy_from_dense` is the inverse of `to_dense`: every entry of the
    /// pattern is read back, stale entries are overwritten (the coupling of
    /// two border coordinates of one block stays zero there).
    #[test]
    fn copy_from_dense_inverts_to_dense() {
        let blocks = [0..7, 7..12, 12..21];
        let border = [5, 6, 7, 8, 19, 20];
        let a = bordered(&blocks, &border, 29);
        let dense = a.to_dense();
        let mut b = bordered(&blocks, &border, 31);
        b.copy_from_dense(&dense);
        assert_eq!(b.to_dense(), dense);
        for (u, w) in b.slices().zip(a.slices()) {
            assert_eq!(u, w);
        }
    }

    /// A block whose interior needs a pivot from the border (its interior
    /// part is singular, the whole matrix is not) falls back to the dense LU
    /// and still solves exactly; a singular matrix is refused.
    #[test]
    fn a_singular_interior_falls_back_to_the_dense_lu() {
        let pattern = Arc::new(BlockPattern::new(vec![0..2, 2..4], vec![1, 2]).unwrap());
        let mut a = BlockMatrix::zeros(&pattern);
        // Block 0 = [[0, 1], [1, 1]]: interior entry (0, 0) is zero.
        for (i, j, x) in [
            (0, 1, 1.0),
            (1, 0, 1.0),
            (1, 1, 1.0),
            (2, 2, 2.0),
            (3, 3, 3.0),
        ] {
            assert!(a.add(i, j, x));
        }
        assert!(a.add(1, 2, 0.5) && a.add(2, 1, 0.5));
        assert!(!a.add(0, 3, 1.0), "(0, 3) joins two interiors");
        let mut lu = BorderedLu::new(&pattern);
        lu.factorize(&a).unwrap();
        assert!(lu.uses_dense());
        let dense = a.to_dense();
        let x_true = [1.0, -2.0, 3.0, 0.5];
        let b = (&dense * DVector::from_column_slice(&x_true))
            .as_slice()
            .to_vec();
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        for (u, t) in x.iter().zip(&x_true) {
            assert!((u - t).abs() < 1e-14);
        }
        let mut singular = BlockMatrix::zeros(&pattern);
        assert!(singular.add(0, 0, 1.0));
        assert!(lu.factorize(&singular).is_err());
    }

    #[test]
    fn patterns_that_do_not_tile_are_refused_and_small_borders_pay() {
        assert!(BlockPattern::new(vec![0..3, 4..6], vec![]).is_err());
        assert!(BlockPattern::new(vec![0..3, 3..3], vec![]).is_err());
        assert!(BlockPattern::new(vec![0..3, 3..6], vec![6]).is_err());
        // Three vehicles of 42 coordinates joined at one body (6 coordinates)
        // each: the bordered work is a fraction of the dense.
        let train = BlockPattern::new(
            vec![0..42, 42..84, 84..126],
            (0..6).chain(42..48).chain(84..90).collect(),
        )
        .unwrap();
        let (dense, block) = train.factorization_work();
        assert!(train.pays() && block < 0.2 * dense, "{block} vs {dense}");
        // One block: nothing to gain.
        let one_range: Vec<std::ops::Range<usize>> = std::iter::once(0..10).collect();
        let one = BlockPattern::new(one_range, vec![]).unwrap();
        assert!(!one.pays());
    }
}
