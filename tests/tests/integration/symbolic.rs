//! Symbolic ≡ numeric: the compiled plugin of every bundled model against the
//! numeric-iterative engine on random states (relative 1e-12 on M, k, Q_g,
//! kinematics, Jacobians, constraints), and the same trajectories.

use nalgebra::DMatrix;
use railmbs_runtime::{Equations, Evaluation, Parts};
use railmbs_testkit::*;

fn close(a: &DMatrix<f64>, b: &DMatrix<f64>, what: &str, model: &str) {
    close_scaled(a, b, b.abs().max().max(1e-300), what, model);
}

/// Relative to `scale`, the natural magnitude of the quantity (a term that is
/// exactly zero symbolically is ~1e-17 numerically).
fn close_scaled(a: &DMatrix<f64>, b: &DMatrix<f64>, scale: f64, what: &str, model: &str) {
    let err = (a - b).abs().max() / scale;
    assert!(
        err < 1e-12,
        "{model}: {what} differs by {err:e} relative (symbolic vs numeric)"
    );
}

#[test]
fn symbolic_equals_numeric_on_every_bundled_model() {
    for model in all_mechanisms().into_iter().chain(all_vehicles()) {
        let mut num = numeric_engine(&model);
        let mut sym = symbolic_engine(&model);
        let mut en = Evaluation::for_equations(&num);
        let mut es = Evaluation::for_equations(&sym);
        let mut rng = seeded_rng(42);
        for _ in 0..100 {
            let n = num.dof();
            let t = rng.random_range(0.0..3.0);
            let q = uniform_vec(&mut rng, n, -2.0, 2.0);
            let v = uniform_vec(&mut rng, n, -3.0, 3.0);
            // Track-following frames: a random pose, rates and accelerations.
            let u = uniform_vec(&mut rng, 3 * num.input_count(), -2.0, 2.0);
            if !u.is_empty() {
                num.set_inputs(&u).unwrap();
                sym.set_inputs(&u).unwrap();
            }
            num.evaluate(t, &q, &v, Parts::ALL, &mut en).unwrap();
            sym.evaluate(t, &q, &v, Parts::ALL, &mut es).unwrap();
            // Also the dynamics-only program (what the integrator calls most).
            let mut ed = Evaluation::for_equations(&sym);
            let dynamics = Parts {
                gravity: true,
                ..Parts::MASS_AND_BIAS
            };
            sym.evaluate(t, &q, &v, dynamics, &mut ed).unwrap();
            let col =
                |x: &nalgebra::DVector<f64>| DMatrix::from_column_slice(x.len(), 1, x.as_slice());
            // Natural scales: inertia forces |M|(1 + |q̇|²), gravity |M|·|g|.
            let vmax = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let k_scale = en.mass.abs().max() * (1.0 + vmax * vmax);
            let g_scale = en.mass.abs().max() * 9.81;
            for (e, program) in [(&es, ""), (&ed, " (dynamics only)")] {
                close(&e.mass, &en.mass, &format!("M{program}"), &model.name);
                close_scaled(
                    &col(&e.bias),
                    &col(&en.bias),
                    k_scale.max(en.bias.abs().max()),
                    &format!("k{program}"),
                    &model.name,
                );
                close_scaled(
                    &col(&e.gravity),
                    &col(&en.gravity),
                    g_scale.max(en.gravity.abs().max()),
                    &format!("Q_g{program}"),
                    &model.name,
                );
            }
            close(&es.jacobians, &en.jacobians, "Γ", &model.name);
            // Position, rotation, velocity and angular velocity of a body as one column.
            let stacked = |b: &railmbs_runtime::BodyKinematics| {
                DMatrix::from_iterator(
                    18,
                    1,
                    b.position
                        .iter()
                        .chain(b.rotation.iter())
                        .chain(b.velocity.iter())
                        .chain(b.angular_velocity.iter())
                        .copied(),
                )
            };
            for (a, b) in es.bodies.iter().zip(&en.bodies) {
                let (pa, pb) = (stacked(a), stacked(b));
                close(&pa, &pb, "body kinematics", &model.name);
            }
            if num.constraint_count() > 0 {
                close(
                    &es.constraint_jacobian,
                    &en.constraint_jacobian,
                    "G",
                    &model.name,
                );
                let ga = col(&es.constraints);
                let gb = col(&en.constraints);
                close(&ga, &gb, "g", &model.name);
            }
        }
    }
}
