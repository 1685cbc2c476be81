//! Integrated motion of the bundled mechanisms against analytic solutions and
//! conservation laws (issue 2's physics tests).

use nalgebra::{Matrix3, Vector3};
use railmbs_runtime::integrate::ParkSettings;
use railmbs_runtime::{MechanicalSystem, Parts};
use railmbs_testkit::*;

/// Complete elliptic integral of the first kind K(k) by the arithmetic–geometric mean.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        a = an;
        b = bn;
    }
    std::f64::consts::PI / (2.0 * a)
}

/// Times at which coordinate `i` crosses zero going downwards, located on the
/// cubic Hermite interpolant of each step by bisection.
fn downward_crossings(steps: &[(f64, Vec<f64>, Vec<f64>)], i: usize) -> Vec<f64> {
    let mut out = Vec::new();
    for w in steps.windows(2) {
        let (t0, q0, v0) = (&w[0].0, w[0].1[i], w[0].2[i]);
        let (t1, q1, v1) = (&w[1].0, w[1].1[i], w[1].2[i]);
        if q0 > 0.0 && q1 <= 0.0 {
            let h = t1 - t0;
            let f = |s: f64| {
                let (s2, s3) = (s * s, s * s * s);
                (2.0 * s3 - 3.0 * s2 + 1.0) * q0
                    + (s3 - 2.0 * s2 + s) * h * v0
                    + (-2.0 * s3 + 3.0 * s2) * q1
                    + (s3 - s2) * h * v1
            };
            let (mut a, mut b) = (0.0, 1.0);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if f(m) > 0.0 { a = m } else { b = m }
            }
            out.push(t0 + 0.5 * (a + b) * h);
        }
    }
    out
}

fn pendulum_period(phi0: f64) -> (f64, f64) {
    let model = mechanism("pendulum");
    let amp = format!("{phi0}");
    let (mut sys, q0, v0) = numeric_system(&model, &[("phi0", amp.as_str())]);
    let p = sys.params().to_vec();
    let get = |n: &str| p[model.parameter_index(n).unwrap()];
    let (l, m, r, g) = (get("l"), get("m"), get("r"), get("g"));
    // Equivalent length of the compound pendulum: (I + m l²)/(m l), I = 2/5 m r².
    let leq = (0.4 * m * r * r + m * l * l) / (m * l);
    let exact = 4.0 * (leq / g).sqrt() * elliptic_k((phi0 / 2.0).sin());
    // RK4 at 1 ms: phase error per period ~ (ω h)⁴ ≈ 1e-13; Park (second
    // order) at 0.1 ms: ~ (ω h)² ≈ 1e-7.
    let rk = run_rk4(&mut sys, &q0, &v0, 5.0 * exact, 1e-3);
    let (park, _) = run_park(&mut sys, &ParkSettings::fixed(1e-4), &q0, &v0, 5.0 * exact);
    let period = |steps: &[(f64, Vec<f64>, Vec<f64>)]| {
        let c = downward_crossings(steps, 0);
        assert!(c.len() >= 4, "too few crossings: {c:?}");
        (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
    };
    let (p_rk, p_park) = (period(&rk), period(&park));
    assert!(
        ((p_park - exact) / exact).abs() < 1e-6,
        "Park: period {p_park}, exact {exact}"
    );
    (p_rk, exact)
}

#[test]
fn pendulum_small_amplitude_period_is_2pi_sqrt_l_over_g() {
    // At 1 mrad the finite-amplitude correction θ0²/16 is 6e-8, below the 1e-6 check.
    let (measured, exact) = pendulum_period(1e-3);
    let model = mechanism("pendulum");
    let p = model.default_parameter_values();
    let get = |n: &str| p[model.parameter_index(n).unwrap()];
    let leq = (0.4 * get("r").powi(2) + get("l").powi(2)) / get("l");
    let small = 2.0 * std::f64::consts::PI * (leq / get("g")).sqrt();
    assert!(
        ((measured - small) / small).abs() < 1e-6,
        "measured {measured}, 2π√(l/g) = {small}"
    );
    assert!(((measured - exact) / exact).abs() < 1e-6);
}

#[test]
fn pendulum_large_amplitude_period_matches_elliptic_integral() {
    for phi0 in [1.0, 2.5] {
        let (measured, exact) = pendulum_period(phi0);
        assert!(
            ((measured - exact) / exact).abs() < 1e-6,
            "θ0 = {phi0}: measured {measured}, exact {exact}"
        );
    }
}

/// Largest |E(t) − E(0)| over a run.
fn energy_drift(model_name: &str, steps: &[(f64, Vec<f64>, Vec<f64>)]) -> f64 {
    let model = mechanism(model_name);
    let (mut sys, _, _) = numeric_system(&model, &[]);
    let e0 = mechanical_energy(&model, &mut sys, steps[0].0, &steps[0].1, &steps[0].2);
    steps
        .iter()
        .map(|(t, q, v)| (mechanical_energy(&model, &mut sys, *t, q, v) - e0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn energy_drift_falls_at_rk4_order() {
    for (name, t_end, h) in [("double_pendulum", 10.0, 2e-3), ("chain10", 10.0, 1e-3)] {
        let model = mechanism(name);
        let drift: Vec<f64> = [h, h / 2.0]
            .iter()
            .map(|&h| {
                let (mut sys, q0, v0) = numeric_system(&model, &[]);
                energy_drift(name, &run_rk4(&mut sys, &q0, &v0, t_end, h))
            })
            .collect();
        let order = (drift[0] / drift[1]).log2();
        assert!(drift[1] < 1e-4, "{name}: RK4 energy drift {drift:?} J");
        // Energy error of RK4 falls at least at its order 4 (measured 4.1–4.7:
        // for these oscillatory runs the leading energy term is partly O(h⁵)).
        assert!(
            (3.5..5.2).contains(&order),
            "{name}: energy drift {drift:?} falls with order {order}"
        );
    }
}

#[test]
fn energy_drift_falls_at_park_order() {
    for (name, t_end, h) in [("double_pendulum", 10.0, 2e-3), ("chain10", 10.0, 2e-3)] {
        let model = mechanism(name);
        let drift: Vec<f64> = [h, h / 2.0]
            .iter()
            .map(|&h| {
                let (mut sys, q0, v0) = numeric_system(&model, &[]);
                let (steps, _) = run_park(&mut sys, &ParkSettings::fixed(h), &q0, &v0, t_end);
                energy_drift(name, &steps)
            })
            .collect();
        let order = (drift[0] / drift[1]).log2();
        // Park's method is dissipative (stiffly stable): energy decays at O(h²).
        assert!(
            (1.6..2.6).contains(&order),
            "{name}: Park energy drift {drift:?} falls with order {order}"
        );
    }
}

#[test]
fn park_and_rk4_convergence_orders_on_the_double_pendulum() {
    // Global error = max over the grid t = k·0.02 s of |q − q_ref|, q_ref from
    // RK4 at 1e-4 s (its own error ~1e-14, far below the errors measured).
    let model = mechanism("double_pendulum");
    let t_end = 2.0;
    let grid = 0.02;
    let on_grid = |steps: Vec<(f64, Vec<f64>, Vec<f64>)>| -> Vec<Vec<f64>> {
        steps
            .into_iter()
            .filter(|(t, _, _)| {
                let k = (t / grid).round();
                (t - k * grid).abs() < 1e-9
            })
            .map(|(_, q, _)| q)
            .collect()
    };
    let (mut sys, q0, v0) = numeric_system(&model, &[]);
    let reference = on_grid(run_rk4(&mut sys, &q0, &v0, t_end, 1e-4));
    let err = |qs: Vec<Vec<f64>>| -> f64 {
        assert_eq!(qs.len(), reference.len());
        qs.iter()
            .zip(&reference)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max)
    };
    let slope = |e: &[f64]| ((e[0] / e[2]).log2()) / 2.0;
    let hs = [0.005, 0.0025, 0.00125];
    let rk: Vec<f64> = hs
        .iter()
        .map(|&h| {
            let (mut s, q0, v0) = numeric_system(&model, &[]);
            err(on_grid(run_rk4(&mut s, &q0, &v0, t_end, h)))
        })
        .collect();
    let pk: Vec<f64> = hs
        .iter()
        .map(|&h| {
            let (mut s, q0, v0) = numeric_system(&model, &[]);
            err(on_grid(
                run_park(&mut s, &ParkSettings::fixed(h / 2.0), &q0, &v0, t_end).0,
            ))
        })
        .collect();
    assert!(
        (3.6..4.4).contains(&slope(&rk)),
        "RK4 errors {rk:?}, order {}",
        slope(&rk)
    );
    assert!(
        (1.8..2.3).contains(&slope(&pk)),
        "Park errors {pk:?}, order {}",
        slope(&pk)
    );
}

/// Angular momentum about the SC0 origin (kg m²/s) and kinetic energy (J) of the free body.
fn momentum_and_energy(
    sys: &mut railmbs_runtime::ModelSystem,
    q: &[f64],
    v: &[f64],
    inertia: Matrix3<f64>,
    m: f64,
) -> (Vector3<f64>, f64, Matrix3<f64>) {
    let e = sys.evaluate(0.0, q, v, Parts::KINEMATICS).unwrap();
    let b = e.bodies[0];
    let ig = b.rotation * inertia * b.rotation.transpose();
    let l = m * b.position.cross(&b.velocity) + ig * b.angular_velocity;
    let t = 0.5 * m * b.velocity.norm_squared()
        + 0.5 * b.angular_velocity.dot(&(ig * b.angular_velocity));
    (l, t, b.rotation)
}

/// Angular momentum, kinetic energy and orientation at every step.
type RigidBodyRun = Vec<(Vector3<f64>, f64, Matrix3<f64>)>;

fn free_body_run(wx: &str, wy: &str, wz: &str, rz0: &str) -> (RigidBodyRun, Matrix3<f64>) {
    let model = mechanism("free_body");
    let (mut sys, q0, v0) =
        numeric_system(&model, &[("wx", wx), ("wy", wy), ("wz", wz), ("rz0", rz0)]);
    let p = sys.params().to_vec();
    let get = |n: &str| p[model.parameter_index(n).unwrap()];
    let inertia = Matrix3::from_diagonal(&Vector3::new(get("Ixx"), get("Iyy"), get("Izz")));
    let m = get("m");
    // RK4 at 0.5 ms conserves L and T to ~(ω h)⁴ ≈ 1e-10 relative over the run.
    let steps = run_rk4(&mut sys, &q0, &v0, 10.0, 5e-4);
    let out = steps
        .iter()
        .map(|(_, q, v)| momentum_and_energy(&mut sys, q, v, inertia, m))
        .collect();
    (out, inertia)
}

#[test]
fn torque_free_body_conserves_momentum_and_energy_and_flips_about_the_intermediate_axis() {
    // Spin about the intermediate axis y with a small perturbation: unstable,
    // the body y axis turns over (its component along L changes sign).
    let (run, _) = free_body_run("1e-3", "5.0", "1e-3", "0");
    let (l0, t0, _) = run[0];
    let mut min_alignment: f64 = 1.0;
    for (l, t, a) in &run {
        assert!(
            (l - l0).norm() < 1e-6 * l0.norm(),
            "angular momentum drifted: {l} vs {l0}"
        );
        assert!(
            (t - t0).abs() < 1e-6 * t0,
            "kinetic energy drifted: {t} vs {t0}"
        );
        min_alignment = min_alignment.min(a.column(1).dot(&l0.normalize()));
    }
    assert!(
        min_alignment < -0.9,
        "the intermediate axis did not flip: min alignment {min_alignment}"
    );
    // Spin about the smallest (x) and largest (z) axes: stable. For x, the body
    // is first turned so that its x axis lies along global y (see the model file).
    for (w, axis) in [
        (("1e-3", "5.0", "1e-3", "pi/2"), 0),
        (("1e-3", "1e-3", "5.0", "0"), 2),
    ] {
        let (run, _) = free_body_run(w.0, w.1, w.2, w.3);
        let l0 = run[0].0.normalize();
        for (l, _, a) in &run {
            assert!((l.normalize() - l0).norm() < 1e-6);
            assert!(
                a.column(axis).dot(&l0) > 0.99,
                "spin about axis {axis} is not stable"
            );
        }
    }
}

#[test]
fn spring_mass_damper_follows_the_exact_solution() {
    let model = mechanism("spring_mass");
    let (mut sys, q0, v0) = numeric_system(&model, &[]);
    let p = sys.params().to_vec();
    let get = |n: &str| p[model.parameter_index(n).unwrap()];
    let (m, k, zeta, g, l0) = (get("m"), get("k"), get("zeta"), get("g"), get("L0"));
    // z'' = -g + (k (−z − L0) + c (−z'))/m along the spring: equilibrium z_e = −L0 − m g/k.
    let wn = (k / m).sqrt();
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let ze = -l0 - m * g / k;
    let x0 = q0[0] - ze;
    let exact = |t: f64| {
        ze + (-zeta * wn * t).exp() * (x0 * (wd * t).cos() + zeta * wn * x0 / wd * (wd * t).sin())
    };
    // Park, second order, 0.1 ms: error ~ (ω h)² ≈ 1e-7 of the amplitude.
    let (steps, _) = run_park(&mut sys, &ParkSettings::fixed(1e-4), &q0, &v0, 5.0);
    let amplitude = x0.abs();
    for (t, q, _) in &steps {
        assert!(
            (q[0] - exact(*t)).abs() < 1e-6 * amplitude,
            "t = {t}: z = {}, exact {}",
            q[0],
            exact(*t)
        );
    }
    // Park with error control: the tolerance bounds the local error; the global
    // error over 5 s (≈ 8 periods) stays within 1e-4 of the amplitude.
    let (steps, _) = run_park(
        &mut sys,
        &ParkSettings::with_tolerances(1e-8, 1e-8),
        &q0,
        &v0,
        5.0,
    );
    for (t, q, _) in &steps {
        assert!(
            (q[0] - exact(*t)).abs() < 1e-4 * amplitude,
            "adaptive Park, t = {t}: z = {}, exact {}",
            q[0],
            exact(*t)
        );
    }
    let rk = run_rk4(&mut sys, &q0, &v0, 5.0, 1e-3);
    for (t, q, _) in &rk {
        assert!((q[0] - exact(*t)).abs() < 1e-8 * amplitude);
    }
}

#[test]
fn parallelogram_four_bar_moves_like_its_one_dof_equivalent() {
    let model = mechanism("fourbar");
    let (mut sys, q0, v0) = numeric_system(&model, &[]);
    assert_eq!(sys.n_constraints(), 2);
    let p = sys.params().to_vec();
    let get = |n: &str| p[model.parameter_index(n).unwrap()];
    let (a, m1, m2, m3, g, th0) = (
        get("a"),
        get("m1"),
        get("m2"),
        get("m3"),
        get("g"),
        get("theta0"),
    );
    let settings = ParkSettings {
        max_step: 1e-3,
        ..ParkSettings::with_tolerances(1e-9, 1e-9)
    };
    let (steps, _) = run_park(&mut sys, &settings, &q0, &v0, 5.0);
    // Constraint residual along the run.
    let mut gbuf = nalgebra::DVector::zeros(2);
    let mut jbuf = nalgebra::DMatrix::zeros(2, 3);
    for (t, q, _) in &steps {
        sys.constraints(*t, q, &mut gbuf, &mut jbuf).unwrap();
        assert!(
            gbuf.abs().max() < 1e-9,
            "t = {t}: constraint residual {}",
            gbuf.abs().max()
        );
        // The coupler keeps its orientation: absolute angle q1 + q2 = π/2.
        assert!((q[0] + q[1] - std::f64::consts::FRAC_PI_2).abs() < 1e-7);
    }
    // 1-DOF equivalent: I_eq θ̈ = −g a (m1/2 + m2 + m3/2) sin θ,
    // I_eq = (m1 + m3) a²/3 + m2 a² (rods about their pivots; the coupler translates).
    let ieq = (m1 + m3) * a * a / 3.0 + m2 * a * a;
    let kk = g * a * (0.5 * m1 + m2 + 0.5 * m3) / ieq;
    let (mut th, mut w, h) = (th0, 0.0, 1e-4);
    let f = |th: f64| -kk * th.sin();
    // (θ, ω) on the grid k·h of the reference integration.
    let mut grid = vec![(th, w)];
    for _ in 0..50_000 {
        let (k1t, k1w) = (w, f(th));
        let (k2t, k2w) = (w + 0.5 * h * k1w, f(th + 0.5 * h * k1t));
        let (k3t, k3w) = (w + 0.5 * h * k2w, f(th + 0.5 * h * k2t));
        let (k4t, k4w) = (w + h * k3w, f(th + h * k3t));
        th += h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
        w += h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
        grid.push((th, w));
    }
    // The reference at any step time: cubic Hermite between its grid points
    // from θ and ω = θ̇ (error ~ h⁴ θ⁗ ≈ 1e-16 rad at h = 0.1 ms, far below the
    // 1e-5 rad checked).
    let reference = |t: f64| -> f64 {
        let k = ((t / h).floor() as usize).min(grid.len() - 2);
        let ((th0, w0), (th1, w1)) = (grid[k], grid[k + 1]);
        let s = t / h - k as f64;
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * th0
            + (s3 - 2.0 * s2 + s) * h * w0
            + (-2.0 * s3 + 3.0 * s2) * th1
            + (s3 - s2) * h * w1
    };
    // The crank angle converges to the equivalent pendulum at Park's order 2
    // (fixed steps; measured 5.9e-6, 1.5e-6, 3.7e-7 rad over 5 s). Every step
    // state is compared.
    let errors: Vec<f64> = [4e-4, 2e-4, 1e-4]
        .iter()
        .map(|&hp| {
            let (mut s, q0, v0) = numeric_system(&model, &[]);
            let (st, _) = run_park(&mut s, &ParkSettings::fixed(hp), &q0, &v0, 5.0);
            assert!(st.len() > 10_000);
            st.iter()
                .map(|(t, q, _)| (q[0] - reference(*t)).abs())
                .fold(0.0, f64::max)
        })
        .collect();
    assert!(
        errors[2] < 1e-6,
        "crank vs equivalent pendulum: {errors:?} rad"
    );
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!(
            (1.8..2.2).contains(&order),
            "errors {errors:?} fall with order {order}"
        );
    }
}
