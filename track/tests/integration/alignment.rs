//! Alignment, vertical profile and cant against analytic results.
#![allow(clippy::needless_range_loop)] // index loops mirror the vector formulas

use railmbs_track::{
    Alignment, Direction, Section, Track, TrackError, VerticalProfile, cant_angle,
};

/// Fresnel-type integrals C(x) = ∫₀ˣ cos t² dt, S(x) = ∫₀ˣ sin t² dt by their
/// power series (Abramowitz & Stegun 7.3.11-style term by term integration of
/// the Taylor series of cos t², sin t²); converges for all x, used for x < 2.
fn fresnel(x: f64) -> (f64, f64) {
    let (mut c, mut s) = (0.0, 0.0);
    let x2 = x * x;
    let x4 = x2 * x2;
    // term_n = (-1)^n x^{4n} / (2n)!  and  (-1)^n x^{4n+2} / (2n+1)!
    let mut tc = x; // x^{4n+1}/(2n)!
    let mut ts = x * x2; // x^{4n+3}/(2n+1)!
    for n in 0..60 {
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        c += sign * tc / (4 * n + 1) as f64;
        s += sign * ts / (4 * n + 3) as f64;
        let m = n as f64;
        tc *= x4 / ((2.0 * m + 1.0) * (2.0 * m + 2.0));
        ts *= x4 / ((2.0 * m + 2.0) * (2.0 * m + 3.0));
    }
    (c, s)
}

#[test]
fn fresnel_reference_is_right() {
    // Published value: ∫₀¹ cos t² dt = 0.9045242379, ∫₀¹ sin t² dt = 0.3102683017
    // (A&S Table 7.7 via C(√(2/π)·…); standard values of these integrals).
    let (c, s) = fresnel(1.0);
    assert!((c - 0.904_524_237_9).abs() < 1e-10, "{c}");
    assert!((s - 0.310_268_301_7).abs() < 1e-10, "{s}");
}

#[test]
fn straight_positions() {
    let a = Alignment::new(vec![Section::straight(100.0)]).unwrap();
    for s in [0.0, 1.0, 37.5, 100.0] {
        let p = a.point(s).unwrap();
        assert_eq!((p.x, p.y, p.heading, p.curvature), (s, 0.0, 0.0, 0.0));
    }
}

#[test]
fn circular_curve_lies_on_the_circle() {
    for (dir, sign) in [(Direction::Left, 1.0), (Direction::Right, -1.0)] {
        let r = 150.0;
        let a = Alignment::new(vec![Section::curve(300.0, r, dir)]).unwrap();
        // Centre of the circle: (0, ±R) for a start at the origin along x.
        for i in 0..=30 {
            let s = 10.0 * i as f64;
            let p = a.point(s).unwrap();
            let d = (p.x.powi(2) + (p.y - sign * r).powi(2)).sqrt();
            // Rounding only: 1e-12 m on 150 m.
            assert!((d - r).abs() < 1e-11, "radius {d} at s = {s}");
            assert!((p.heading - sign * s / r).abs() < 1e-14);
            assert!((p.x - r * (s / r).sin()).abs() < 1e-11);
            assert!((p.y - sign * r * (1.0 - (s / r).cos())).abs() < 1e-11);
        }
    }
}

#[test]
fn clothoid_matches_fresnel_integrals() {
    // Clothoid from a straight: κ = u/(R L), ψ = u²/(2 R L); with a = √(2RL),
    // x = a C(u/a), y = a S(u/a). Cases: the TC1 transition and a long, sharp
    // spiral turning through 3.3 rad (a hard test of the quadrature).
    for (r, l, dir) in [
        (150.0, 50.0, Direction::Right),
        (30.0, 200.0, Direction::Left),
        (1200.0, 200.0, Direction::Left),
    ] {
        let a = Alignment::new(vec![Section::entry_transition(l, r, dir)]).unwrap();
        let sign = dir.sign();
        let scale = (2.0 * r * l).sqrt();
        for i in 0..=20 {
            let u = l * i as f64 / 20.0;
            let p = a.point(u).unwrap();
            let (c, s) = fresnel(u / scale);
            // Accuracy claim: 1e-9 m over 200 m.
            assert!((p.x - scale * c).abs() < 1e-9, "x {} vs {}", p.x, scale * c);
            assert!(
                (p.y - sign * scale * s).abs() < 1e-9,
                "y {} vs {}",
                p.y,
                scale * s
            );
            assert!((p.heading - sign * u * u / (2.0 * r * l)).abs() < 1e-14);
            assert!((p.curvature - sign * u / (r * l)).abs() < 1e-15);
            assert!((p.curvature_rate - sign / (r * l)).abs() < 1e-18);
        }
    }
}

/// Composite Simpson's rule of (cos ψ, sin ψ), independent of the crate's
/// Gauss–Legendre rule; with 20 000 panels its error is ~1e-13 m here.
fn simpson_position(psi: impl Fn(f64) -> f64, u: f64) -> (f64, f64) {
    let n = 20_000;
    let h = u / n as f64;
    let (mut x, mut y) = (0.0, 0.0);
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let p = psi(i as f64 * h);
        x += w * p.cos();
        y += w * p.sin();
    }
    (x * h / 3.0, y * h / 3.0)
}

#[test]
fn general_clothoid_matches_quadrature_and_joints_are_continuous() {
    // Straight → entry spiral → curve → exit spiral → straight, right-hand, and
    // a compound spiral between two radii.
    let (r, l) = (150.0, 50.0);
    let k = -1.0 / r;
    let a = Alignment::new(vec![
        Section::straight(20.0),
        Section::entry_transition(l, r, Direction::Right),
        Section::curve(40.0, r, Direction::Right),
        Section::clothoid(30.0, k, -1.0 / 400.0),
        Section::clothoid(60.0, -1.0 / 400.0, 0.0),
        Section::straight(10.0),
    ])
    .unwrap();
    // Position at every s against an independent integration of the heading
    // function ψ(s) built from the section data.
    let psi = |s: f64| -> f64 {
        // ψ(s) = ∫ κ: piecewise quadratic.
        let secs = a.sections();
        let mut acc = 0.0;
        let mut s0 = 0.0;
        for sec in secs {
            let u = (s - s0).clamp(0.0, sec.length);
            acc += sec.curvature_start * u + 0.5 * sec.curvature_rate() * u * u;
            s0 += sec.length;
            if s < s0 {
                break;
            }
        }
        acc
    };
    for i in 0..=42 {
        let s = a.length() * i as f64 / 42.0;
        let p = a.point(s).unwrap();
        let (x, y) = simpson_position(psi, s);
        // Simpson's error with a kink in κ at joints: O(h²) locally, < 1e-8 m.
        assert!(
            (p.x - x).abs() < 1e-8 && (p.y - y).abs() < 1e-8,
            "s = {s}: {p:?} vs {x} {y}"
        );
        assert!((p.heading - psi(s)).abs() < 1e-13);
    }
    // Continuity at each joint: evaluate just before and at the joint.
    for i in 1..a.sections().len() {
        let sj = a.section_start(i).unwrap();
        let e = 1e-9;
        let (p0, p1) = (a.point(sj - e).unwrap(), a.point(sj).unwrap());
        assert!((p0.x - p1.x).abs() < 2e-9 && (p0.y - p1.y).abs() < 2e-9);
        assert!((p0.heading - p1.heading).abs() < 1e-11);
        assert!((p0.curvature - p1.curvature).abs() < 1e-11);
    }
}

#[test]
fn curvature_and_cant_jumps_are_rejected() {
    let e = Alignment::new(vec![
        Section::straight(10.0),
        Section::curve(10.0, 100.0, Direction::Left),
    ])
    .unwrap_err();
    assert!(
        matches!(
            e,
            TrackError::Discontinuity {
                quantity: "curvature",
                before: 0,
                after: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("curvature jumps"));
    // Allowed when asked for, but cant must still be continuous.
    Alignment::new_allowing_curvature_jumps(vec![
        Section::straight(10.0),
        Section::curve(10.0, 100.0, Direction::Left),
    ])
    .unwrap();
    let e = Alignment::new_allowing_curvature_jumps(vec![
        Section::straight(10.0),
        Section::curve(10.0, 100.0, Direction::Left).with_cant(0.1, 0.1),
    ])
    .unwrap_err();
    assert!(
        matches!(
            e,
            TrackError::Discontinuity {
                quantity: "cant",
                ..
            }
        ),
        "{e}"
    );
    // Bad inputs name what is wrong.
    let e = Alignment::new(vec![Section::straight(-1.0)]).unwrap_err();
    assert!(e.to_string().contains("section 0 length"), "{e}");
    let e = Alignment::new(vec![Section::curve(10.0, f64::NAN, Direction::Left)]).unwrap_err();
    assert!(e.to_string().contains("section 0 curvature"), "{e}");
    let a = Alignment::new(vec![Section::straight(10.0)]).unwrap();
    assert!(matches!(a.point(10.5), Err(TrackError::OutOfRange { .. })));
    assert!(matches!(
        a.point(f64::NAN),
        Err(TrackError::NotFinite { .. })
    ));
}

#[test]
fn cant_ramps_linearly_and_gives_the_cant_angle() {
    let (r, l, h) = (150.0, 50.0, 0.1);
    let a = Alignment::new(vec![
        Section::straight(10.0),
        Section::entry_transition(l, r, Direction::Right).with_cant(0.0, h),
        Section::curve(20.0, r, Direction::Right).with_cant(h, h),
    ])
    .unwrap();
    let track = Track::new(a).unwrap();
    for i in 0..=10 {
        let u = l * i as f64 / 10.0;
        let p = track.point(10.0 + u).unwrap();
        // Right curve: the outer (left) rail is raised, h > 0, roll > 0.
        assert!((p.plan.cant - h * u / l).abs() < 1e-15);
        assert!((p.roll - (h * u / l / 1.5).asin()).abs() < 1e-15);
    }
    let p = track.point(75.0).unwrap();
    // 100 mm over 2e0 = 1.5 m: φ = asin(1/15) = 0.066716 rad (3.8226°).
    assert!((p.roll - 0.066_716_2).abs() < 1e-7);
    assert!((cant_angle(0.1, 1.5).unwrap() - (1.0f64 / 15.0).asin()).abs() < 1e-16);
    assert!(cant_angle(1.6, 1.5).is_err());
    // A left curve's cant is negative (right rail raised).
    let left = Section::curve(10.0, 300.0, Direction::Left).with_cant(0.05, 0.05);
    assert_eq!(left.cant_start, -0.05);
}

#[test]
fn vertical_profile_grade_and_vertical_curve() {
    // Grade 0 to 2 % over a 100 m parabolic vertical curve (Rv = 5000 m), then
    // 2 %: z = s²/(2Rv) on the curve, z = 1 + 0.02 (s − 100) after.
    let v = VerticalProfile::from_grade_knots(&[(0.0, 0.0), (100.0, 0.02)], 0.0).unwrap();
    for s in [0.0, 30.0, 100.0, 150.0, 300.0] {
        let p = v.point(s).unwrap();
        let (z, g, gr) = if s <= 100.0 {
            (s * s / 10_000.0, s / 5000.0, 1.0 / 5000.0)
        } else {
            (1.0 + 0.02 * (s - 100.0), 0.02, 0.0)
        };
        assert!(
            (p.z - z).abs() < 1e-12 && (p.grade - g).abs() < 1e-15,
            "{s}: {p:?}"
        );
        if s != 100.0 {
            assert!((p.grade_rate - gr).abs() < 1e-18);
        }
    }
    let a = Alignment::new(vec![Section::straight(300.0)]).unwrap();
    let t = Track::new(a).unwrap().with_vertical(v);
    // Pitch: rotation about y, up-grade → negative.
    assert!((t.point(200.0).unwrap().pitch + 0.02f64.atan()).abs() < 1e-16);
    assert!(VerticalProfile::from_grade_knots(&[(0.0, 0.0), (0.0, 0.01)], 0.0).is_err());
}

#[test]
fn gauge_and_rail_inclination() {
    let a = Alignment::new(vec![Section::straight(100.0)]).unwrap();
    let t = Track::new(a)
        .unwrap()
        .with_gauge_widening(&[(20.0, 0.0), (40.0, 0.01)])
        .unwrap();
    assert_eq!(t.point(0.0).unwrap().gauge, 1.435);
    assert!((t.point(30.0).unwrap().gauge - 1.440).abs() < 1e-15);
    assert!((t.point(90.0).unwrap().gauge - 1.445).abs() < 1e-15);
    // The gauge alone is the point's gauge, bit for bit, with the same
    // errors off the track (the end's slack of 1e-12 relative included).
    for s in [0.0, 10.0, 20.0, 27.3, 40.0, 99.9, 100.0, 100.0 + 1e-11] {
        assert_eq!(t.gauge(s).unwrap(), t.point(s).unwrap().gauge, "s = {s}");
    }
    for s in [-0.1, 100.1, f64::NAN, f64::INFINITY] {
        assert!(t.gauge(s).is_err() && t.point(s).is_err(), "s = {s}");
    }
    assert_eq!(t.rail_inclination(), 1.0 / 40.0);
    assert!(t.clone().with_rail_inclination(-0.1).is_err());
    assert!(t.with_gauge(0.0).is_err());
}

#[test]
fn start_pose_rotates_and_shifts_the_alignment() {
    use railmbs_track::PlanPose;
    let secs = vec![
        Section::straight(10.0),
        Section::entry_transition(40.0, 200.0, Direction::Left),
        Section::curve(30.0, 200.0, Direction::Left),
    ];
    let a = Alignment::new(secs.clone()).unwrap();
    let (x0, y0, h0) = (100.0, -50.0, 0.7f64);
    let b = Alignment::with_start(
        secs,
        PlanPose {
            x: x0,
            y: y0,
            heading: h0,
        },
    )
    .unwrap();
    let (s, c) = h0.sin_cos();
    for u in [0.0, 5.0, 33.0, 80.0] {
        let (p, q) = (a.point(u).unwrap(), b.point(u).unwrap());
        // Rigid motion: q = R(h0) p + (x0, y0), heading + h0.
        assert!((q.x - (x0 + c * p.x - s * p.y)).abs() < 1e-12);
        assert!((q.y - (y0 + s * p.x + c * p.y)).abs() < 1e-12);
        assert!((q.heading - (p.heading + h0)).abs() < 1e-14);
    }
    let e = b.end_pose();
    let q = b.point(80.0).unwrap();
    assert!((e.x - q.x).abs() < 1e-12 && (e.heading - q.heading).abs() < 1e-15);
}
