//! The bordered block-diagonal solve of Park's method on single vehicles
//! (blocks by top-level subsystem: the bogies, and the car body's own
//! block) and the check it shares with trains: M and the force Jacobians in
//! blocks equal the dense ones entry for entry, and the bordered LU solves
//! the iteration matrix and M like the dense LU.

use railmbs_models::{LinearSolverKind, Model, Scenario, load_model, load_scenario};
use railmbs_runtime::integrate::linalg::DenseLu;
use railmbs_runtime::integrate::{BlockMatrix, BlockPattern, BorderedLu};
use railmbs_runtime::run::scenario::scenario_system;
use railmbs_runtime::{MechanicalSystem, NumericEquations};
use railmbs_testkit::*;
use std::sync::Arc;

/// At (q, v) of `sys` with its block `pattern`: M, f, ∂f/∂q and ∂f/∂q̇
/// assembled in blocks equal the dense ones exactly (the same entries,
/// copied), and the bordered block-diagonal LU solves Park's iteration
/// matrix M − β ∂f/∂q̇ − β² ∂f/∂q (β = 0.6 ms) and M itself like the dense
/// LU with partial pivoting, to 1e-10 relative (both are backward stable:
/// their solutions differ by the condition number times rounding, far
/// below that here), with residuals at rounding level.
pub fn assert_block_solve_matches_dense(
    sys: &mut dyn MechanicalSystem,
    pattern: &Arc<BlockPattern>,
    q: &[f64],
    v: &[f64],
) {
    let n = sys.dof();
    let pattern = pattern.clone();
    let (mut mass, mut f) = (nalgebra::DMatrix::zeros(n, n), nalgebra::DVector::zeros(n));
    let (mut dq, mut dv) = (
        nalgebra::DMatrix::zeros(n, n),
        nalgebra::DMatrix::zeros(n, n),
    );
    sys.dynamics(0.1, q, v, &mut mass, &mut f).unwrap();
    assert!(sys.force_jacobian(0.1, q, v, &mut dq, &mut dv).unwrap());
    let z = || BlockMatrix::zeros(&pattern);
    let (mut mb, mut dqb, mut dvb, mut ab) = (z(), z(), z(), z());
    let mut fb = nalgebra::DVector::zeros(n);
    sys.dynamics_blocks(0.1, q, v, &mut mb, &mut fb).unwrap();
    assert!(
        sys.force_jacobian_blocks(0.1, q, v, &mut dqb, &mut dvb)
            .unwrap()
    );
    assert_eq!(f, fb);
    assert_eq!(mb.to_dense(), mass);
    assert_eq!(dqb.to_dense(), dq);
    assert_eq!(dvb.to_dense(), dv);
    let beta = 6e-4;
    ab.set_iteration_matrix(&mb, &dvb, &dqb, beta);
    let a = &mass - &dv * beta - &dq * (beta * beta);
    for (label, dense, blocks) in [("iteration matrix", &a, &ab), ("M", &mass, &mb)] {
        let b: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin() * 1e3).collect();
        let mut lu = DenseLu::new(n);
        lu.matrix_mut().copy_from(dense);
        lu.factorize().unwrap();
        let mut xd = b.clone();
        lu.solve_slice(&mut xd);
        let mut blu = BorderedLu::new(&pattern);
        blu.factorize(blocks).unwrap();
        assert!(
            !blu.uses_dense(),
            "{label}: no pivot outside a block needed"
        );
        let mut xb = b.clone();
        blu.solve_in_place(&mut xb);
        let scale = xd.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (i, (u, w)) in xb.iter().zip(&xd).enumerate() {
            assert!(
                (u - w).abs() <= 1e-10 * scale,
                "{label}: x[{i}] = {u} (block) vs {w} (dense)"
            );
        }
        let bn = b.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for x in [&xd, &xb] {
            let r = dense * nalgebra::DVector::from_column_slice(x);
            let res = r
                .iter()
                .zip(&b)
                .fold(0.0_f64, |m, (u, w)| m.max((u - w).abs()));
            assert!(res <= 1e-10 * bn, "{label}: residual {res:e}");
        }
    }
}

/// A vehicle's scenario at its start, numeric engine, the state perturbed
/// (so that no Jacobian entry is zero by symmetry).
fn start(
    rel: &str,
) -> (
    Model,
    railmbs_runtime::run::scenario::ScenarioSystem,
    Vec<f64>,
    Vec<f64>,
) {
    let scenario = load_scenario(&model_path(rel)).unwrap();
    let model = load_model(&scenario.model).unwrap();
    let setup = scenario_system(&scenario, &model, Box::new(NumericEquations::new(&model)))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut rng = seeded_rng(5);
    let q: Vec<f64> = setup
        .q0
        .iter()
        .map(|x| x + rng.random_range(-1e-6..1e-6))
        .collect();
    let v: Vec<f64> = setup
        .v0
        .iter()
        .map(|x| x + rng.random_range(-1e-5..1e-5))
        .collect();
    (model, setup, q, v)
}

/// The coordinates of the bodies named (long names) in `names`, in
/// coordinate order.
fn coordinates_of(model: &Model, names: &[&str]) -> Vec<usize> {
    (0..model.coordinates.len())
        .filter(|&i| names.contains(&model.bodies[model.coordinates[i].body].name.as_str()))
        .collect()
}

/// Vehicle 1 (car body, two bogies of a frame and two wheelsets, and the
/// speed hold's `drive` body): three blocks, the vehicle's own bodies'
/// coordinates and each bogie's; the border is
/// the car body and the two bogie frames (the secondary suspension joins
/// them; the wheelsets hang on the frames only), and the block solve
/// equals the dense one.
#[test]
fn vehicle1_is_solved_in_bogie_blocks_bordered_by_car_body_and_frames() {
    let (model, mut setup, q, v) = start("scenarios/vehicle1_tc1.ron");
    let pattern = setup
        .system
        .block_pattern()
        .expect("Vehicle 1 has a block pattern");
    let ranges: Vec<_> = pattern.blocks().to_vec();
    assert_eq!(ranges.len(), 3, "{ranges:?}");
    assert_eq!(
        coordinates_of(&model, &["drive", "body"]),
        ranges[0].clone().collect::<Vec<_>>()
    );
    let frames = coordinates_of(&model, &["body", "Bogie1.frame", "Bogie2.frame"]);
    assert_eq!(frames.len(), 18);
    assert_eq!(pattern.border(), &frames[..]);
    assert_block_solve_matches_dense(&mut setup.system, &pattern, &q, &v);
}

/// The freight car (Pogorelov 2005, Sect. 7.2; 114 coordinates, 264
/// point–plane contacts): two 54-coordinate bogie blocks bordered by the
/// car body and the two bolsters (centre plates and side bearers join
/// them; wedges, side frames and wheelsets stay inside their bogie), a
/// bordered LU of at most a quarter of the dense one's work, and the block
/// solve equals the dense one.
#[test]
fn freight_car_is_solved_in_bogie_blocks_bordered_by_car_body_and_bolsters() {
    let (model, mut setup, q, v) = start("scenarios/freight_straight_loaded.ron");
    let pattern = setup
        .system
        .block_pattern()
        .expect("the freight car has a block pattern");
    let sizes: Vec<usize> = pattern.blocks().iter().map(|r| r.len()).collect();
    assert_eq!(sizes, [6, 54, 54]);
    let border = coordinates_of(&model, &["body", "Bogie1.bolster", "Bogie2.bolster"]);
    assert_eq!(border.len(), 18);
    assert_eq!(pattern.border(), &border[..]);
    let (dense, block) = pattern.factorization_work();
    assert!(block <= 0.25 * dense, "work {block} against dense {dense}");
    assert_block_solve_matches_dense(&mut setup.system, &pattern, &q, &v);
}

/// A model without subsystems (one wheelset on springs) has one block:
/// no pattern, the dense LU.
#[test]
fn a_model_without_subsystems_has_no_block_pattern() {
    let (_, setup, _, _) = start("scenarios/wheelset_on_springs_30.ron");
    assert!(setup.system.block_pattern().is_none());
}

/// Vehicle 1 on track case 1 (the 150 m curve with its irregularities), the
/// whole bundled run with the dense and with the block solver: every
/// coordinate within twice the integration tolerance (rtol 1e-4, atol 1e-6
/// of the scenario) at every output row: the solutions of the two LUs
/// differ by rounding, which moves the step-size decisions, so the two runs
/// are two solutions each held to the tolerance by the step control, not
/// one solution twice (measured: 0.94 tolerances, in a wheelset's roll; the
/// numeric and symbolic engines differ as much).
#[test]
fn vehicle1_runs_the_same_with_block_and_dense_solver() {
    let mut tables = Vec::new();
    for solver in [LinearSolverKind::Dense, LinearSolverKind::Block] {
        let mut scenario: Scenario =
            load_scenario(&model_path("scenarios/vehicle1_tc1.ron")).unwrap();
        scenario.output.coordinates = true;
        if let railmbs_models::IntegratorSpec::Park { solver: s, .. } = &mut scenario.integrator {
            *s = solver;
        }
        let model = load_model(&scenario.model).unwrap();
        tables.push(run_to_table(
            &scenario,
            &model,
            Box::new(NumericEquations::new(&model)),
        ));
    }
    let d = tables[0].coordinate_difference(&tables[1], 1e-4, 1e-6);
    assert!(
        d.differs,
        "the block run should round differently from the dense one"
    );
    assert!(
        d.tolerances < 2.0,
        "{}: difference {} tolerances",
        d.column,
        d.tolerances
    );
}
