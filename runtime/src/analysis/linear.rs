//! Linearization of the full model about an equilibrium or steady state:
//! the state matrix A of d/dt δx = A δx.
//!
//! With M(q) q̈ = f(q, q̇) + Gᵀλ, g(q) = 0 and first-order element states z
//! (zero rows of M; their equations 0 = f_z(q, q̇, z, ż) are rows of f, with
//! z among the coordinates and ż among the rates), about a state where
//! q̈ = 0 and ż = 0 (an [`super::equilibrium::Equilibrium`]):
//!
//! - the coordinates that second-order equations govern are written
//!   δq = T δy, with T = I without closed loops and otherwise an orthonormal
//!   basis of the null space of G (the constraint's tangent space, Pogorelov
//!   2005, Eqs. 3–4); the constraint forces enter through the derivative of
//!   Gᵀλ at fixed λ (their geometric stiffness);
//! - the state is δx = (δy, δẏ, δz), and
//!
//! ```text
//!     [TᵀMT   −TᵀF_ż] [δÿ]   [TᵀK T   TᵀF_v T   TᵀK_z] [δy]
//!     [ 0     −F_zż ] [δż] = [ K_zq T   F_zv T    K_zz ] [δẏ]
//!                                                         [δz]
//! ```
//!
//!   with K = ∂(f + Gᵀλ)/∂q and F_v = ∂f/∂q̇ (F_ż: the ż columns) by central
//!   differences of [`MechanicalSystem::dynamics`] (steps of
//!   1e-7 max(1, |q|) and 1e-6 max(1, |q̇|), justified in the source): every force
//!   element, the wheel–rail contact at its actual contact geometry and the
//!   creep law at its operating point, the inertia and gyroscopic terms,
//!   exactly as the integrators see them.
//!
//! The wheels' spin angles, on which nothing depends, would give zero
//! eigenvalues (pure integrators of their rates): their positions are left
//! out of the state when the caller says so (the equilibrium's rolling and
//! held coordinates); any other zero eigenvalue [`super::modes`] reports
//! apart.

use super::{CoordinateInfo, ForceEvaluator, position_step, rate_step};
use crate::system::{MechanicalSystem, SimError};
use nalgebra::{DMatrix, DVector};

/// What a state of the linear system is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateKind {
    /// A (reduced) position coordinate δy.
    Position,
    /// Its rate δẏ.
    Rate,
    /// A force element's first-order state δz.
    ElementState,
}

/// The linear system d/dt δx = A δx about a state.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// The state matrix A (square, 2r + n_z).
    pub a: DMatrix<f64>,
    /// What each state is, in order: r_p positions, r rates, n_z element
    /// states.
    pub kinds: Vec<StateKind>,
    /// Names of the states: the coordinates' names (with `.v` for rates)
    /// without closed loops, `y1`, `y2`… (and `.v`) along the constraint's
    /// tangent directions with them.
    pub names: Vec<String>,
    /// P: the system coordinates of a unit of each reduced position
    /// (n × r_p; rows of element states zero): δq = P δy.
    pub positions: DMatrix<f64>,
    /// T: the same for the rates (n × r): δq̇ = T δw. Without closed loops
    /// P is T without the left-out coordinates.
    pub rates: DMatrix<f64>,
    /// Coordinates whose positions are left out of the state (nothing
    /// depends on them: a wheel's spin angle); their rates stay.
    pub left_out: Vec<usize>,
    /// Indices of the element states among the system coordinates.
    pub element_states: Vec<usize>,
    /// The diagonal of M at the state (kg or kg m²; 0 for element states):
    /// the weights of a mode's kinetic energy per coordinate.
    pub mass_diagonal: Vec<f64>,
}

impl Linearization {
    /// The system-coordinate amplitudes (n entries, complex as (re, im)) of
    /// a state vector (re, im parts): δq = P δy and δz; the left-out
    /// coordinates have none.
    pub fn coordinate_amplitudes(&self, re: &[f64], im: &[f64]) -> Vec<(f64, f64)> {
        let (n, rp) = self.positions.shape();
        let offset = rp + self.rates.ncols();
        let mut out = vec![(0.0, 0.0); n];
        for (i, o) in out.iter_mut().enumerate() {
            for k in 0..rp {
                o.0 += self.positions[(i, k)] * re[k];
                o.1 += self.positions[(i, k)] * im[k];
            }
        }
        for (j, &i) in self.element_states.iter().enumerate() {
            out[i] = (re[offset + j], im[offset + j]);
        }
        out
    }
}

/// Linearizes `system` about (t, q, q̇) with constraint multipliers
/// `lambda` (empty without closed loops); `names` in system order. The
/// positions of the coordinates `left_out` (those an equilibrium found
/// rolling or held: no force depends on them) are left out of the state,
/// their rates kept (without closed loops; with them all are kept).
///
/// # Errors
/// The model's evaluation errors, or a singular left-hand side (a mass
/// matrix without inertia, an element state whose equation does not
/// contain its rate).
pub fn linearize<S: MechanicalSystem + ?Sized>(
    system: &mut S,
    names: &[CoordinateInfo],
    (t, q, v): (f64, &[f64], &[f64]),
    lambda: &[f64],
    left_out: &[usize],
) -> Result<Linearization, SimError> {
    let (n, nc) = (system.dof(), system.n_constraints());
    if q.len() != n || v.len() != n || lambda.len() != nc || names.len() != n {
        return Err(SimError::Other(format!(
            "linearization of a system of {n} coordinates and {nc} constraints at a state of \
             {} and {} with {} multipliers and {} names",
            q.len(),
            v.len(),
            lambda.len(),
            names.len()
        )));
    }
    let mut eval = ForceEvaluator::new(system, t);
    let lam = DVector::from_column_slice(lambda);
    let constrained_force = |system: &mut S, eval: &mut ForceEvaluator, q: &[f64], v: &[f64]| {
        let mut f = eval.force(system, q, v)?.clone();
        if nc > 0 {
            eval.constraints(system, q)?;
            f += eval.g_jacobian.transpose() * &lam;
        }
        Ok::<_, SimError>(f)
    };
    let (mut qp, mut vp) = (q.to_vec(), v.to_vec());
    let mut k = DMatrix::zeros(n, n);
    let mut fv = DMatrix::zeros(n, n);
    for i in 0..n {
        let h = position_step(q[i]);
        qp[i] = q[i] + h;
        let plus = constrained_force(system, &mut eval, &qp, v)?;
        qp[i] = q[i] - h;
        let minus = constrained_force(system, &mut eval, &qp, v)?;
        qp[i] = q[i];
        k.set_column(i, &((plus - minus) / (2.0 * h)));
        let h = rate_step(v[i]);
        vp[i] = v[i] + h;
        let plus = eval.force(system, q, &vp)?.clone();
        vp[i] = v[i] - h;
        let minus = eval.force(system, q, &vp)?.clone();
        vp[i] = v[i];
        fv.set_column(i, &((plus - minus) / (2.0 * h)));
    }
    eval.force(system, q, v)?;
    let mass = eval.mass().clone();
    let zs: Vec<usize> = (0..n).filter(|&i| system.is_first_order(i)).collect();
    let cs: Vec<usize> = (0..n).filter(|&i| !system.is_first_order(i)).collect();
    // T over the second-order coordinates (rows: all n, element states 0).
    let basis = if nc == 0 {
        let mut t = DMatrix::zeros(n, cs.len());
        for (k, &i) in cs.iter().enumerate() {
            t[(i, k)] = 1.0;
        }
        t
    } else {
        eval.constraints(system, q)?;
        tangent_basis(&eval.g_jacobian, &cs, n)?
    };
    // Positions: without the left-out coordinates (nothing depends on
    // them: their columns of K are zero and their rows are ẏ = w alone).
    let left_out: Vec<usize> = if nc == 0 {
        left_out
            .iter()
            .copied()
            .filter(|&i| !system.is_first_order(i))
            .collect()
    } else {
        Vec::new()
    };
    let kept: Vec<usize> = (0..basis.ncols())
        .filter(|&k| !left_out.iter().any(|&i| basis[(i, k)] != 0.0))
        .collect();
    let positions = DMatrix::from_fn(n, kept.len(), |i, k| basis[(i, kept[k])]);
    let (rp, r, nz) = (positions.ncols(), basis.ncols(), zs.len());
    let pick = |m: &DMatrix<f64>, rows: &[usize], cols: &[usize]| {
        DMatrix::from_fn(rows.len(), cols.len(), |a, b| m[(rows[a], cols[b])])
    };
    let all: Vec<usize> = (0..n).collect();
    // Rows: Tᵀ over the coordinates' rows, then the element states' rows.
    let tt = basis.transpose();
    let project = |m: &DMatrix<f64>| -> DMatrix<f64> {
        let mut out = DMatrix::zeros(r + nz, m.ncols());
        out.rows_mut(0, r).copy_from(&(&tt * m));
        for (j, &i) in zs.iter().enumerate() {
            out.row_mut(r + j).copy_from(&m.row(i));
        }
        out
    };
    let mut lhs = DMatrix::zeros(r + nz, r + nz);
    lhs.view_mut((0, 0), (r + nz, r))
        .copy_from(&project(&(&mass * &basis)));
    lhs.view_mut((0, r), (r + nz, nz))
        .copy_from(&(-project(&pick(&fv, &all, &zs))));
    let mut rhs = DMatrix::zeros(r + nz, rp + r + nz);
    rhs.view_mut((0, 0), (r + nz, rp))
        .copy_from(&project(&(&k * &positions)));
    rhs.view_mut((0, rp), (r + nz, r))
        .copy_from(&project(&(&fv * &basis)));
    rhs.view_mut((0, rp + r), (r + nz, nz))
        .copy_from(&project(&pick(&k, &all, &zs)));
    let lu = lhs.lu();
    let accelerations = lu.solve(&rhs).ok_or_else(|| {
        SimError::Other(format!(
            "linearization at t = {t} s: the left-hand side [TᵀMT, −TᵀF_ż; 0, −F_zż] is \
             singular (a coordinate without inertia, or an element state whose equation \
             does not contain its rate)"
        ))
    })?;
    let m = rp + r + nz;
    let mut a = DMatrix::zeros(m, m);
    // ẏ = Pᵀ T w.
    a.view_mut((0, rp), (rp, r))
        .copy_from(&(positions.transpose() * &basis));
    a.view_mut((rp, 0), (r + nz, m)).copy_from(&accelerations);
    let (mut state_names, mut kinds) = (Vec::with_capacity(m), Vec::with_capacity(m));
    let rate_names: Vec<String> = if nc == 0 {
        cs.iter().map(|&i| names[i].name.clone()).collect()
    } else {
        (1..=r).map(|k| format!("y{k}")).collect()
    };
    for &k in &kept {
        state_names.push(rate_names[k].clone());
        kinds.push(StateKind::Position);
    }
    for p in &rate_names {
        state_names.push(format!("{p}.v"));
        kinds.push(StateKind::Rate);
    }
    for &i in &zs {
        state_names.push(names[i].name.clone());
        kinds.push(StateKind::ElementState);
    }
    Ok(Linearization {
        a,
        kinds,
        names: state_names,
        positions,
        rates: basis,
        left_out,
        element_states: zs,
        mass_diagonal: (0..n).map(|i| mass[(i, i)]).collect(),
    })
}

/// An orthonormal basis (n × r) of the null space of G restricted to the
/// second-order coordinates `cs` (rows of element states zero): the right
/// singular vectors of G with singular values below 1e-10 of the largest.
fn tangent_basis(g: &DMatrix<f64>, cs: &[usize], n: usize) -> Result<DMatrix<f64>, SimError> {
    let nc = g.nrows();
    let m = cs.len();
    // Padded to square so that the SVD returns all m right singular vectors.
    let mut padded = DMatrix::zeros(m.max(nc), m);
    for c in 0..nc {
        for (k, &i) in cs.iter().enumerate() {
            padded[(c, k)] = g[(c, i)];
        }
    }
    let svd = padded.svd(false, true);
    let v_t = svd
        .v_t
        .ok_or_else(|| SimError::Other("SVD of the constraint Jacobian failed".into()))?;
    let smax = svd.singular_values.max();
    let null: Vec<usize> = (0..m)
        .filter(|&k| svd.singular_values[k] <= 1e-10 * smax)
        .collect();
    let mut t = DMatrix::zeros(n, null.len());
    for (j, &k) in null.iter().enumerate() {
        for (row, &i) in cs.iter().enumerate() {
            t[(i, j)] = v_t[(k, row)];
        }
    }
    Ok(t)
}
