//! Numeric-engine systems and what tests compare them by: dynamics at a
//! state, central-difference and analytic Jacobians, mechanical energy.

use nalgebra::{DMatrix, DVector, Matrix3};
use railmbs_models::{Body, Model};
use railmbs_runtime::{Equations, MechanicalSystem, ModelSystem, NumericEquations, Parts};

/// The numeric-engine system of `model` with parameter `overrides` (name,
/// expression text), and its initial q, q̇ at t = 0 (states of first-order
/// elements appended).
pub fn numeric_system(
    model: &Model,
    overrides: &[(&str, &str)],
) -> (ModelSystem, Vec<f64>, Vec<f64>) {
    let ov: Vec<(String, String)> = overrides
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let params = model
        .parameter_values(&[], &ov)
        .unwrap_or_else(|e| panic!("{e}"));
    let (q0, v0) = model.initial_state(&params);
    let mut sys = ModelSystem::new(model, Box::new(NumericEquations::new(model)), params)
        .unwrap_or_else(|e| panic!("{e}"));
    let (q0, v0) = sys
        .initial_state(0.0, &q0, &v0)
        .unwrap_or_else(|e| panic!("{e}"));
    (sys, q0, v0)
}

/// A fresh numeric engine for `model` with default parameters.
pub fn numeric_engine(model: &Model) -> NumericEquations {
    let mut e = NumericEquations::new(model);
    e.set_parameters(&model.default_parameter_values())
        .unwrap_or_else(|e| panic!("{e}"));
    e
}

/// Mass matrix M and f = Q − k at a state, through the `MechanicalSystem`
/// view.
pub fn dynamics(
    sys: &mut ModelSystem,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> (DMatrix<f64>, DVector<f64>) {
    let n = sys.dof();
    let mut m = DMatrix::zeros(n, n);
    let mut f = DVector::zeros(n);
    sys.dynamics(t, q, v, &mut m, &mut f)
        .unwrap_or_else(|e| panic!("{e}"));
    (m, f)
}

/// Central differences (increment `h`) of f = Q − k from `dynamics` at
/// t = 0, with respect to q (`wrt_v` false) or q̇: the oracle of the analytic
/// Jacobians.
pub fn central_difference(
    sys: &mut ModelSystem,
    q: &[f64],
    v: &[f64],
    wrt_v: bool,
    h: f64,
) -> DMatrix<f64> {
    let n = q.len();
    let mut out = DMatrix::zeros(n, n);
    let mut mass = DMatrix::zeros(n, n);
    let (mut fp, mut fm) = (DVector::zeros(n), DVector::zeros(n));
    for j in 0..n {
        let (mut qp, mut vp, mut qm, mut vm) = (q.to_vec(), v.to_vec(), q.to_vec(), v.to_vec());
        if wrt_v {
            vp[j] += h;
            vm[j] -= h;
        } else {
            qp[j] += h;
            qm[j] -= h;
        }
        sys.dynamics(0.0, &qp, &vp, &mut mass, &mut fp)
            .unwrap_or_else(|e| panic!("{e}"));
        sys.dynamics(0.0, &qm, &vm, &mut mass, &mut fm)
            .unwrap_or_else(|e| panic!("{e}"));
        out.set_column(j, &((&fp - &fm) / (2.0 * h)));
    }
    out
}

/// The analytic approximate Jacobians (∂f/∂q, ∂f/∂q̇) at t = 0; panics if
/// the system has none.
pub fn analytic_jacobians(
    sys: &mut ModelSystem,
    q: &[f64],
    v: &[f64],
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = q.len();
    let (mut dq, mut dv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    let available = sys
        .force_jacobian(0.0, q, v, &mut dq, &mut dv)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(available, "the system has no analytic Jacobian");
    (dq, dv)
}

/// Largest entry of |a − b| relative to the largest of |b| (the max norm).
pub fn rel_diff(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1e-300)
}

/// Kinetic energy ½ q̇ᵀ M q̇ plus potential energy −Σ m_j g·r_j (J), at a state
/// of a model whose only forces are gravity (and conservative springs, which
/// are not included here).
pub fn mechanical_energy(
    model: &Model,
    sys: &mut ModelSystem,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> f64 {
    let params = sys.params().to_vec();
    let g: Vec<f64> = model.gravity.iter().map(|e| e.eval(&params, t)).collect();
    let masses: Vec<f64> = model
        .bodies
        .iter()
        .map(|b| b.mass.eval(&params, t))
        .collect();
    let e = sys
        .evaluate(t, q, v, Parts::ALL)
        .unwrap_or_else(|e| panic!("{e}"));
    let vv = DVector::from_column_slice(v);
    let kinetic = 0.5 * vv.dot(&(&e.mass * &vv));
    let potential: f64 = e
        .bodies
        .iter()
        .zip(&masses)
        .map(|(b, m)| -m * (g[0] * b.position.x + g[1] * b.position.y + g[2] * b.position.z))
        .sum();
    kinetic + potential
}

/// Inertia tensor of `body` about its centre of mass in the body frame (kg m²).
pub fn body_inertia(body: &Body, params: &[f64]) -> Matrix3<f64> {
    let i: Vec<f64> = body.inertia.iter().map(|x| x.eval(params, 0.0)).collect();
    Matrix3::new(i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2])
}
