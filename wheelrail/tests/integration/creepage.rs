//! Creepages of a hand-computed wheelset case.
//!
//! Wheelset rolling forward at V along x (SC0: x forward, y left, z up), nominal
//! rolling radius r0, spinning at Ω = V/r0 about its axle. Material velocity of
//! the wheel at the contact point c (relative to the axle centre): v = v_axle + ω × c.

use railmbs_wheelrail::creepage::{ContactFrame, CreepageError, Creepages};

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Left wheel (at y = +e0) on a cone of contact angle δ: the contact normal tilts
/// inward, n = (0, −sin δ, cos δ). Yaw ψ, yaw rate ψ̇, lateral velocity ẏ, and
/// a rolling radius r ≠ r0. By hand, with ω × c = −(Ω r + ψ̇ e0)·x_ws:
/// ξ = (V cos ψ + ẏ sin ψ − Ω r − ψ̇ e0)/V, η = (−V sin ψ + ẏ cos ψ) cos δ / V,
/// φ = (ω·n)/V = −sin δ/r0 + ψ̇ cos δ/V; to first order ξ ≈ 1 − r/r0 − ψ̇e0/V,
/// η ≈ −ψ + ẏ/V.
#[test]
fn wheelset_creepages_by_hand() {
    let v = 20.0;
    let r0 = 0.46;
    let r = 0.462; // rolling radius at this contact
    let e0 = 0.75;
    let delta: f64 = 0.05; // contact angle, rad
    let psi: f64 = 2e-3; // yaw
    let psi_dot = 0.01; // rad/s
    let y_dot = 0.02; // m/s
    let omega_spin = v / r0;
    // Wheelset frame axes after yaw ψ about z.
    let (s, c) = psi.sin_cos();
    let ax = [c, s, 0.0];
    let ay = [-s, c, 0.0];
    // Angular velocity: spin about the axle (+y_ws, forward rolling) plus yaw rate.
    let omega = [
        omega_spin * ay[0],
        omega_spin * ay[1],
        omega_spin * ay[2] + psi_dot,
    ];
    // Contact point of the left wheel relative to the axle centre: e0 along the
    // axle, r below. (Velocity along x of the axle: V; lateral ẏ.)
    let cpt = [e0 * ay[0], e0 * ay[1], -r];
    let v_wheel = add([v, y_dot, 0.0], cross(omega, cpt));
    // Contact frame: normal tilted inward (towards −y_ws), rolling direction the
    // wheelset's x axis.
    let n = [-delta.sin() * ay[0], -delta.sin() * ay[1], delta.cos()];
    let frame = ContactFrame::from_normal_and_forward(n, ax).unwrap();
    let cr = Creepages::from_velocities(v_wheel, [0.0; 3], omega, [0.0; 3], &frame, v).unwrap();

    // Hand results. Longitudinal: the axle moves at V cos ψ along ax (plus ẏ sin ψ),
    // the spin subtracts Ω r; the yaw rate moves the left contact back by ψ̇ e0.
    let xi = (v * c + y_dot * s - omega_spin * r - psi_dot * e0) / v;
    // Lateral along ey = n × ex (in the tangent plane): −V sin ψ + ẏ cos ψ projected
    // with cos δ (ey tilts by δ), the vertical velocity component is zero.
    let eta = (-v * s + y_dot * c) * delta.cos() / v;
    let phi = -delta.sin() / r0 + psi_dot * delta.cos() / v;
    assert!((cr.xi - xi).abs() < 1e-12, "{} vs {xi}", cr.xi);
    assert!((cr.eta - eta).abs() < 1e-12, "{} vs {eta}", cr.eta);
    assert!((cr.phi - phi).abs() < 1e-12, "{} vs {phi}", cr.phi);
    // The classic first-order relations.
    assert!((cr.xi - (1.0 - r / r0 - psi_dot * e0 / v)).abs() < 1e-5);
    assert!((cr.eta - (-psi + y_dot / v)).abs() < 1e-5);
}

#[test]
fn bad_input() {
    let f = ContactFrame::from_normal_and_forward([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]).unwrap();
    assert_eq!(f.ey, [0.0, 1.0, 0.0]);
    let z = [0.0; 3];
    assert_eq!(
        Creepages::from_velocities(z, z, z, z, &f, 0.0),
        Err(CreepageError::RollingSpeed(0.0))
    );
    assert!(matches!(
        Creepages::from_velocities([f64::NAN, 0.0, 0.0], z, z, z, &f, 1.0),
        Err(CreepageError::NotFinite("wheel velocity"))
    ));
    let bad = ContactFrame {
        ey: [0.0, -1.0, 0.0],
        ..f
    };
    assert_eq!(
        Creepages::from_velocities(z, z, z, z, &bad, 1.0),
        Err(CreepageError::Frame)
    );
    assert!(ContactFrame::from_normal_and_forward([0.0, 0.0, 1.0], [0.0, 0.0, 2.0]).is_none());
}
