//! Track-following frame against analytic results and finite differences.
#![allow(clippy::needless_range_loop)] // index loops mirror the vector formulas

use railmbs_track::{
    Alignment, ConstantSpeed, Direction, Section, SpeedLaw, SpeedTable, Track, TrackFrame,
    VerticalProfile, balancing_speed, cant_deficiency, uncompensated_lateral_acceleration,
};

fn mat_t_vec(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    let mut o = [0.0; 3];
    for (j, oj) in o.iter_mut().enumerate() {
        *oj = (0..3).map(|i| r[i][j] * v[i]).sum();
    }
    o
}

#[test]
fn circular_curve_frame_kinematics() {
    let (r, v) = (150.0, 12.0);
    for (dir, sign) in [(Direction::Left, 1.0), (Direction::Right, -1.0)] {
        let a = Alignment::new(vec![Section::curve(400.0, r, dir).with_cant(0.1, 0.1)]).unwrap();
        let track = Track::new(a).unwrap();
        let law = ConstantSpeed::new(5.0, v).unwrap();
        for t in [0.0, 3.0, 17.5] {
            let f = track.frame_at_time(&law, t).unwrap();
            let s = 5.0 + v * t;
            assert!((f.heading - sign * s / r).abs() < 1e-14);
            // Angular velocity v/R about SC0 z (constant cant, level track).
            let w = f.angular_velocity;
            assert!(w[0].abs() < 1e-15 && w[1].abs() < 1e-15);
            assert!((w[2] - sign * v / r).abs() < 1e-15);
            assert!(f.angular_acceleration.iter().all(|x| x.abs() < 1e-15));
            // Centripetal acceleration v²/R toward the centre (0, ±R).
            let c = [0.0, sign * r];
            let d = [c[0] - f.position[0], c[1] - f.position[1]];
            let n = (d[0] * d[0] + d[1] * d[1]).sqrt();
            assert!((n - r).abs() < 1e-10);
            for k in 0..2 {
                assert!((f.acceleration[k] - v * v / r * d[k] / n).abs() < 1e-12);
            }
            assert!(f.acceleration[2].abs() < 1e-15);
            // Speed along the tangent.
            let speed = (f.velocity[0].powi(2) + f.velocity[1].powi(2)).sqrt();
            assert!((speed - v).abs() < 1e-13);
            assert!((f.velocity_local[0] - v).abs() < 1e-13);
        }
    }
}

fn frame(track: &Track, law: &impl SpeedLaw, t: f64) -> TrackFrame {
    track.frame_at_time(law, t).unwrap()
}

/// Angular velocity from the rotation matrices: Ω̃ = Ȧ Aᵀ by central differences.
fn omega_fd(track: &Track, law: &impl SpeedLaw, t: f64, h: f64) -> [f64; 3] {
    let (p, m, c) = (
        frame(track, law, t + h),
        frame(track, law, t - h),
        frame(track, law, t),
    );
    let mut w = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            w[i][j] = (0..3)
                .map(|k| (p.rotation[i][k] - m.rotation[i][k]) / (2.0 * h) * c.rotation[j][k])
                .sum();
        }
    }
    [w[2][1], w[0][2], w[1][0]]
}

#[test]
fn frame_rates_match_finite_differences() {
    // Clothoid with a cant ramp, on a vertical curve, with an accelerating
    // speed profile: every term of the velocity and acceleration formulas acts.
    let a = Alignment::new(vec![
        Section::straight(20.0),
        Section::clothoid(60.0, 0.0, -1.0 / 200.0).with_cant(0.0, 0.12),
        Section::curve(100.0, 200.0, Direction::Right).with_cant(0.12, 0.12),
    ])
    .unwrap();
    let track = Track::new(a).unwrap().with_vertical(
        VerticalProfile::from_grade_knots(&[(0.0, 0.0), (50.0, 0.04)], 1.0).unwrap(),
    );
    let law = SpeedTable::new(0.0, &[(0.0, 10.0), (5.0, 20.0)]).unwrap();
    let h = 1e-4;
    for t in [2.2, 2.5, 3.0] {
        let f = frame(&track, &law, t);
        assert!(
            f.s > 20.0 && f.s < 50.0,
            "inside clothoid and vertical curve"
        );
        let (p, m) = (frame(&track, &law, t + h), frame(&track, &law, t - h));
        // Central differences: truncation h²/6·(third derivative) with h = 1e-4 s
        // is < 1e-8 here; rounding ≈ 1e-14·|x|/h < 1e-8. Tolerance 1e-6.
        for k in 0..3 {
            let v = (p.position[k] - m.position[k]) / (2.0 * h);
            assert!(
                (f.velocity[k] - v).abs() < 1e-6,
                "v[{k}] {} vs {v}",
                f.velocity[k]
            );
            let acc = (p.velocity[k] - m.velocity[k]) / (2.0 * h);
            assert!(
                (f.acceleration[k] - acc).abs() < 1e-6,
                "a[{k}] {} vs {acc}",
                f.acceleration[k]
            );
            let al = (p.angular_velocity[k] - m.angular_velocity[k]) / (2.0 * h);
            assert!(
                (f.angular_acceleration[k] - al).abs() < 1e-6,
                "alpha[{k}] {} vs {al}",
                f.angular_acceleration[k]
            );
        }
        let w = omega_fd(&track, &law, t, h);
        for k in 0..3 {
            assert!(
                (f.angular_velocity[k] - w[k]).abs() < 1e-7,
                "w[{k}] {} vs {}",
                f.angular_velocity[k],
                w[k]
            );
        }
        // The frame's pitch and roll are really there.
        assert!(f.pitch < -1e-3 && f.roll > 1e-3);
        assert!(f.angular_velocity[0].abs() > 1e-3, "roll rate present");
        // Resolved components are Aᵀ·v.
        let vl = mat_t_vec(&f.rotation, f.velocity);
        let al = mat_t_vec(&f.rotation, f.angular_acceleration);
        for k in 0..3 {
            assert!((vl[k] - f.velocity_local[k]).abs() < 1e-13);
            assert!((al[k] - f.angular_acceleration_local[k]).abs() < 1e-13);
        }
        // Velocity along the frame's x axis only.
        assert!(f.velocity_local[1].abs() < 1e-12 && f.velocity_local[2].abs() < 1e-12);
        // s(t) of the speed table: s = 10 t + t², ṡ = 10 + 2t, s̈ = 2.
        assert!((f.s - (10.0 * t + t * t)).abs() < 1e-12);
        assert!((f.s_dot - (10.0 + 2.0 * t)).abs() < 1e-13 && f.s_ddot == 2.0);
    }
    // Orthonormal rotation.
    let f = frame(&track, &law, 2.5);
    for i in 0..3 {
        for j in 0..3 {
            let d: f64 = (0..3).map(|k| f.rotation[k][i] * f.rotation[k][j]).sum();
            assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-15);
        }
    }
}

#[test]
fn balancing_speed_balances_gravity_in_the_rail_plane() {
    let g = 9.81;
    let (r, h, e2): (f64, f64, f64) = (150.0, 0.1, 1.5);
    let phi = (h / e2).asin();
    let veq = balancing_speed(r, phi, g).unwrap();
    // √(g R tan φ) with tan(asin(1/15)) = 1/√224.
    assert!((veq - (g * r / 224f64.sqrt()).sqrt()).abs() < 1e-12);
    // At v_eq the specific force a − g_vec has no component along the canted
    // frame's y axis (the definition of balance).
    let a = Alignment::new(vec![
        Section::curve(200.0, r, Direction::Right).with_cant(h, h),
    ])
    .unwrap();
    let track = Track::new(a).unwrap();
    let f = track.frame(50.0, veq, 0.0).unwrap();
    let spec = [f.acceleration[0], f.acceleration[1], f.acceleration[2] + g];
    let local = mat_t_vec(&f.rotation, spec);
    assert!(
        local[1].abs() < 1e-12,
        "lateral specific force {}",
        local[1]
    );
    // Cant deficiency and a_q: a_q = v²/R − g h/2e0, deficiency = a_q 2e0/g.
    let v = 20.0;
    let aq = uncompensated_lateral_acceleration(v, r, h, e2, g).unwrap();
    assert!((aq - (400.0 / 150.0 - 9.81 / 15.0)).abs() < 1e-14);
    let d = cant_deficiency(v, r, h, e2, g).unwrap();
    assert!((d - (e2 * 400.0 / (g * 150.0) - h)).abs() < 1e-14);
    assert!(uncompensated_lateral_acceleration(0.0, r, h, e2, g).unwrap() < 0.0);
    assert!(balancing_speed(-1.0, phi, g).is_err());
    assert!(balancing_speed(r, f64::NAN, g).is_err());
}

#[test]
fn bad_inputs_are_errors() {
    let a = Alignment::new(vec![Section::straight(10.0)]).unwrap();
    let track = Track::new(a).unwrap();
    assert!(track.frame(5.0, f64::NAN, 0.0).is_err());
    assert!(track.frame(11.0, 1.0, 0.0).is_err());
    let law = ConstantSpeed::new(0.0, 1.0).unwrap();
    assert!(track.frame_at_time(&law, f64::INFINITY).is_err());
    assert!(SpeedTable::new(0.0, &[(1.0, 1.0), (1.0, 2.0)]).is_err());
    assert!(SpeedTable::new(0.0, &[]).is_err());
    // Cant reaching the rail distance is rejected.
    let a = Alignment::new(vec![
        Section::curve(10.0, 100.0, Direction::Left).with_cant(1.6, 1.6),
    ])
    .unwrap();
    assert!(Track::new(a).is_err());
    // A transition of astronomic length (found by the track fuzz target: its
    // plan integration would take ~1e75 steps) is refused, named.
    let e = Alignment::new(vec![
        Section::straight(50.0),
        Section::entry_transition(4.3e78, 600.0, Direction::Right),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("section 1 (transition)") && e.contains("turns by"),
        "{e}"
    );
    // A real one passes (100 m into a 150 m radius: 0.33 rad).
    assert!(
        Alignment::new(vec![Section::entry_transition(
            100.0,
            150.0,
            Direction::Left
        )])
        .is_ok()
    );
}

#[test]
fn rheonomic_inputs_are_consistent_rates() {
    // Each input's rate and acceleration against central differences of its
    // value and rate (same error budget as above), on a clothoid with cant ramp
    // and a vertical curve, two frames 19 m apart.
    let a = Alignment::new(vec![
        Section::straight(30.0),
        Section::clothoid(80.0, 0.0, 1.0 / 300.0).with_cant(0.0, -0.1),
        Section::curve(50.0, 300.0, Direction::Left).with_cant(0.1, 0.1),
    ])
    .unwrap();
    let track = Track::new(a).unwrap().with_vertical(
        VerticalProfile::from_grade_knots(&[(0.0, 0.0), (150.0, -0.03)], 0.0).unwrap(),
    );
    let law = SpeedTable::new(60.0, &[(0.0, 15.0), (4.0, 25.0)]).unwrap();
    let offsets = [9.5, -9.5];
    let mut u = [0.0; 36];
    let mut up = [0.0; 36];
    let mut um = [0.0; 36];
    let (t, h) = (1.5, 1e-4);
    track.write_inputs(&law, t, &offsets, &mut u).unwrap();
    track.write_inputs(&law, t + h, &offsets, &mut up).unwrap();
    track.write_inputs(&law, t - h, &offsets, &mut um).unwrap();
    for k in 0..12 {
        let (v, r, acc) = (3 * k, 3 * k + 1, 3 * k + 2);
        let fd_rate = (up[v] - um[v]) / (2.0 * h);
        let fd_acc = (up[r] - um[r]) / (2.0 * h);
        assert!(
            (u[r] - fd_rate).abs() < 1e-6,
            "input {k}: rate {} vs {fd_rate}",
            u[r]
        );
        assert!(
            (u[acc] - fd_acc).abs() < 1e-6,
            "input {k}: acc {} vs {fd_acc}",
            u[acc]
        );
    }
    // Yaw, pitch and roll all move here.
    for k in [3, 4, 5, 9, 10, 11] {
        assert!(u[3 * k + 1].abs() > 1e-4, "input {k} rate {}", u[3 * k + 1]);
    }
    let f = track.frame_at_time_offset(&law, t, 9.5).unwrap();
    assert_eq!(f.rheonomic_inputs()[..], u[..18]);
    assert!(
        track
            .write_inputs(&law, t, &offsets, &mut [0.0; 35])
            .is_err()
    );
}
