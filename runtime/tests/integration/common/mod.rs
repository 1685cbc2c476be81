//! Helpers shared by the runtime's integration tests: a model from text, its
//! system with parameter overrides and initial state, and the
//! central-difference Jacobian of `dynamics` (the oracle of the analytic one).
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};
use railmbs_models::Model;
use railmbs_runtime::{MechanicalSystem, ModelSystem, NumericEquations};
use std::path::Path;

/// A model from text, or the loader's error message.
pub fn try_parse(text: &str) -> Result<Model, String> {
    railmbs_models::parse_model(text, Path::new("test.ron")).map_err(|e| e.to_string())
}

/// A model from text (panics with the loader's message).
pub fn parse(text: &str) -> Model {
    try_parse(text).unwrap_or_else(|e| panic!("{e}"))
}

/// The numeric-engine system of `model` with parameter `overrides` (name,
/// expression text) and its initial q, q̇ (element states appended).
pub fn system(model: &Model, overrides: &[(&str, String)]) -> (ModelSystem, Vec<f64>, Vec<f64>) {
    let ov: Vec<(String, String)> = overrides
        .iter()
        .map(|(a, b)| (a.to_string(), b.clone()))
        .collect();
    let params = model
        .parameter_values(&[], &ov)
        .unwrap_or_else(|e| panic!("{e}"));
    let (q0, v0) = model.initial_state(&params);
    let mut sys = ModelSystem::new(model, Box::new(NumericEquations::new(model)), params).unwrap();
    let (q0, v0) = sys.initial_state(0.0, &q0, &v0).unwrap();
    (sys, q0, v0)
}

/// Central differences (increment `h`) of f = Q − k from `dynamics` at t = 0,
/// with respect to q (`wrt_v` false) or q̇.
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
        sys.dynamics(0.0, &qp, &vp, &mut mass, &mut fp).unwrap();
        sys.dynamics(0.0, &qm, &vm, &mut mass, &mut fm).unwrap();
        out.set_column(j, &((&fp - &fm) / (2.0 * h)));
    }
    out
}

/// The analytic approximate Jacobians (∂f/∂q, ∂f/∂q̇) at t = 0.
pub fn analytic(sys: &mut ModelSystem, q: &[f64], v: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = q.len();
    let (mut dq, mut dv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    assert!(sys.force_jacobian(0.0, q, v, &mut dq, &mut dv).unwrap());
    (dq, dv)
}
