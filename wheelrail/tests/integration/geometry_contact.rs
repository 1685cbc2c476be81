//! Contact geometry: symmetry, analytic cone, S1002 on UIC60 1:40 two-point contact, tables.

use crate::common::s1002_uic60;
use railmbs_wheelrail::conicity::{RollTreatment, RollingRadiusDifference, conicity_curve};
use railmbs_wheelrail::geometry::{
    Contact, ContactGeometry, ContactTable, GeometryError, SearchSettings, TableSettings, Track,
    Wheelset,
};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfilePoints, ProfileSettings};

#[test]
fn centred_symmetric_wheelset_has_mirror_contacts() {
    let (ws, tr) = s1002_uic60();
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    let c = geo.contacts(0.0, 0.0).unwrap();
    let (l, r) = (c[0].deepest(), c[1].deepest());
    // identical profiles placed as mirror images: the same numbers up to rounding
    assert!((l.wheel_u - r.wheel_u).abs() < 1e-9);
    assert!((l.rail_y + r.rail_y).abs() < 1e-9 && (l.wheel_y + r.wheel_y).abs() < 1e-9);
    assert!((l.gap - r.gap).abs() < 1e-12);
    assert!((l.contact_angle - r.contact_angle).abs() < 1e-9);
    assert!((l.yaw_lead + r.yaw_lead).abs() < 1e-9);
    // and a shift to the left mirrors a shift to the right
    for y in [1e-3, 4e-3, 7e-3] {
        let a = geo.rigid(y).unwrap();
        let b = geo.rigid(-y).unwrap();
        assert!((a.roll + b.roll).abs() < 1e-9, "{} {}", a.roll, b.roll);
        assert!((a.z - b.z).abs() < 1e-9);
        let (al, br) = (a.sides[0].deepest(), b.sides[1].deepest());
        assert!((al.wheel_u - br.wheel_u).abs() < 1e-6);
        assert!((a.rolling_radius_difference() + b.rolling_radius_difference()).abs() < 1e-9);
    }
}

#[test]
fn s1002_on_uic60_two_point_contact_and_monotonic_tread() {
    let (ws, tr) = s1002_uic60();
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    // The jump from tread to flange moves the contact by more than 5 mm on the wheel.
    let tp = geo
        .two_point_shift(0.012, 0.1e-3, 5e-3, 45f64.to_radians())
        .unwrap()
        .expect("S1002 on UIC60 1:40 reaches flange contact within 12 mm");
    println!(
        "y* = {:.3} mm, flange contact angle {:.2}°, tread {:.2}° at u = {:.2} mm, flange at u = {:.2} mm",
        tp.y_star * 1e3,
        tp.flange.contact_angle.to_degrees(),
        tp.tread.contact_angle.to_degrees(),
        tp.tread.wheel_u * 1e3,
        tp.flange.wheel_u * 1e3
    );
    // Flange clearance: flange thickness 32.5 mm and back-to-back 1360 mm leave
    // (1435 − 1360 − 2·32.5)/2 = 5 mm at the gauge depth; contact comes a little later (the
    // flange is measured 10 mm above the tread, the gauge 14 mm below the rail top).
    assert!(tp.y_star > 4e-3 && tp.y_star < 9e-3, "y* = {}", tp.y_star);
    // S1002's flange flank is inclined 70° (EN 13715); the jump lands on the flank.
    let a = tp.flange.contact_angle.to_degrees();
    assert!(a > 60.0 && a < 71.0, "flange contact angle {a}°");
    // at y* the left wheel touches at two points
    let r = geo.rigid(tp.y_star).unwrap();
    assert_eq!(r.sides[0].count, 2);
    // Δr grows monotonically over the tread, 0 ≤ y < y*
    let ys: Vec<f64> = (0..((tp.y_star / 1e-4) as usize))
        .map(|k| k as f64 * 1e-4)
        .collect();
    let f = geo.rigid_functions(&ys).unwrap();
    for w in f.windows(2) {
        let (a, b) = (
            w[0].rolling_radius_difference(),
            w[1].rolling_radius_difference(),
        );
        assert!(
            b >= a - 1e-9,
            "Δr decreases from {a} to {b} at y = {}",
            w[1].y
        );
    }
    // flange climbing continues past y*: the contact stays on the flange and climbs it
    let c = geo.rigid(tp.y_star + 2e-3).unwrap();
    let fl = c.sides[0].deepest();
    assert!(fl.wheel_u < tp.flange.wheel_u && fl.contact_angle.to_degrees() > 50.0);
    assert!(c.z > r.z && c.roll > r.roll);
}

/// A cone of conicity γ (h = γu, radius r0 − γu) against a rail whose head is a circle of
/// radius `head` over ±25 mm, continued by steep flanks (so that a gauge face exists).
fn cone_on_circle(gamma: f64, head: f64) -> (Wheelset, Track) {
    let n = 1000;
    let wheel = ProfilePoints {
        kind: ProfileKind::Wheel,
        name: "cone".into(),
        points: (0..=n)
            .map(|k| {
                let u = -0.04 + 0.1 * k as f64 / n as f64;
                [u, gamma * u]
            })
            .collect(),
    };
    let edge = 0.025;
    let h_edge = -(head - (head * head - edge * edge).sqrt());
    let s_edge = -edge / (head * head - edge * edge).sqrt(); // slope at +edge
    let mut rail = Vec::new();
    let mut u: f64 = -0.029;
    while u <= 0.029 + 1e-12 {
        let h = if u.abs() <= edge {
            -(head - (head * head - u * u).sqrt())
        } else {
            // tangent continuation, then a steep 1:0.1 flank
            let d = u.abs() - edge;
            h_edge + s_edge * d.min(0.0005) - 10.0 * (d - 0.0005).max(0.0)
        };
        rail.push([u, h]);
        u += 0.05e-3;
    }
    let rail = ProfilePoints {
        kind: ProfileKind::Rail,
        name: "circle".into(),
        points: rail,
    };
    let s = ProfileSettings::default();
    let w = Profile::from_points(&wheel, &s).unwrap();
    let r = Profile::from_points(&rail, &s).unwrap();
    (
        Wheelset::new(w.clone(), w, 0.46, 1.360),
        Track::new(r.clone(), r, 1.435),
    )
}

#[test]
fn cone_on_circular_head_gives_linear_delta_r_and_its_conicity() {
    // the contact (where the head's slope is γ, at γR from the crown) stays on the circle
    for (gamma, head) in [(0.05, 0.3), (0.15, 0.08)] {
        let (ws, tr) = cone_on_circle(gamma, head);
        let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
        // Roll neglected: the rail contact stays where the head's slope is γ and the wheel
        // contact moves by y, so Δr = 2γy exactly; the golden-section search locates the
        // minimum to 1e-9 m on the wheel, i.e. Δr to γ·2e-9.
        for k in -50..=50 {
            let y = k as f64 * 0.1e-3;
            let c = geo.contacts(y, 0.0).unwrap();
            let dr = c[0].deepest().rolling_radius - c[1].deepest().rolling_radius;
            assert!(
                (dr - 2.0 * gamma * y).abs() < 1e-8,
                "γ {gamma}, y {y}: Δr {dr}"
            );
            // contact angle = cone angle on both sides
            assert!((c[0].deepest().contact_angle - gamma.atan()).abs() < 1e-6);
        }
        // Klingel: a cone has tan γe = γ at every amplitude. The Δr samples are exact and the
        // Annex B integral with 4000 midpoints is exact to ~1e-7 for a linear Δr.
        let amps: Vec<f64> = (1..=10).map(|k| k as f64 * 0.5e-3).collect();
        let curve = conicity_curve(&geo, &amps, RollTreatment::Neglected).unwrap();
        for (a, t) in curve {
            assert!((t - gamma).abs() < 1e-6, "γ {gamma} ŷ {a}: {t}");
        }
        // Rigid wheelset: roll φ shifts both wheels laterally by r0 φ (the axle turns about its
        // centre, r0 above the contact) and turns the cones' slopes by ±φ, which moves the
        // contacts on the crowned heads (radius R) by ∓R φ, so Δr = 2γy + 2γ(R + r0)φ. The
        // moved contacts sit lower/higher on the crowns by ∓γRφ, so the roll that keeps both
        // wheels on their rails is φ = Δr/(2(e + γR)) (e half the contact distance). Together:
        // tan γe = γ/(1 − γ(R + r0)/(e + γR)), first order in φ (≈ 1e-4 rad here); the
        // neglected terms are of relative order φ and the variations of r and e along the
        // oscillation below 1e-4 relative; tolerance 1e-3 relative.
        let c = geo.rigid(0.0).unwrap();
        let e = 0.5 * (c.sides[0].deepest().rail_y - c.sides[1].deepest().rail_y);
        let expected = gamma / (1.0 - gamma * (head + 0.46) / (e + gamma * head));
        let curve = conicity_curve(&geo, &amps, RollTreatment::Rigid).unwrap();
        for (a, t) in curve {
            assert!(
                (t / expected - 1.0).abs() < 1e-3,
                "γ {gamma} ŷ {a}: {t} vs {expected}"
            );
        }
    }
}

/// The table's central conicity (the linear conicity that the conicity
/// override of the quasi-linear analyses scales,
/// `ContactTable::central_conicity`) of a cone on a crowned head is the
/// rigid wheelset's analytic conicity with roll, γ/(1 − γ(R + r0)/(e + γR))
/// (derived in `cone_on_circular_head_gives_linear_delta_r_and_its_conicity`;
/// first order in the roll, ≈ 1e-5 rad at ±0.1 mm: tolerance 1e-3), and an
/// error for a table without nodes beside the centre.
#[test]
fn table_central_conicity_of_a_cone_is_the_analytic_one() {
    for (gamma, head) in [(0.05, 0.3), (0.15, 0.08)] {
        let (ws, tr) = cone_on_circle(gamma, head);
        let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
        let settings = TableSettings {
            y_max: 0.001,
            dy: 0.1e-3,
            roll_max: 0.004,
            droll: 2e-3,
        };
        let table = ContactTable::from_geometry(&geo, settings).unwrap();
        let c = geo.rigid(0.0).unwrap();
        let e = 0.5 * (c.sides[0].deepest().rail_y - c.sides[1].deepest().rail_y);
        let expected = gamma / (1.0 - gamma * (head + 0.46) / (e + gamma * head));
        let lambda = table.central_conicity().unwrap();
        println!("γ {gamma}, R {head} m: table {lambda:.6}, analytic {expected:.6}");
        assert!(
            (lambda / expected - 1.0).abs() < 1e-3,
            "γ {gamma}: {lambda} vs {expected}"
        );
        let single = ContactTable::from_geometry(
            &geo,
            TableSettings {
                y_max: 0.0,
                ..settings
            },
        );
        // A zero range is refused when the table is built, or the
        // conicity is.
        assert!(single.is_err() || single.unwrap().central_conicity().is_err());
    }
}

#[test]
fn conicity_of_analytic_delta_r() {
    // Δr = 2γy on a sampled grid -> γ; independent of r0 e0 (λ² ∝ r0 e0).
    let gamma = 0.2;
    let y: Vec<f64> = (-100..=100).map(|k| k as f64 * 1e-4).collect();
    let dr = y.iter().map(|v| 2.0 * gamma * v).collect();
    let f = RollingRadiusDifference::new(y, dr).unwrap();
    for a in [0.5e-3, 3e-3, 9e-3] {
        for (r0, e0) in [(0.46, 0.75), (0.3, 0.7)] {
            let t = f.equivalent_conicity(a, r0, e0).unwrap();
            assert!((t - gamma).abs() < 1e-6, "{t}");
        }
    }
    // a Δr that vanishes over the oscillation: no restoring effect, conicity 0
    let y: Vec<f64> = (-100..=100).map(|k| k as f64 * 1e-4).collect();
    let dr = y
        .iter()
        .map(|v| {
            if v.abs() < 3e-3 {
                0.0
            } else {
                v - 3e-3 * v.signum()
            }
        })
        .collect();
    let f = RollingRadiusDifference::new(y, dr).unwrap();
    assert_eq!(f.equivalent_conicity(1e-3, 0.46, 0.75).unwrap(), 0.0);
    assert!(f.equivalent_conicity(8e-3, 0.46, 0.75).unwrap() > 0.0);
    // too large an amplitude and bad input are errors, not NaN
    assert!(f.equivalent_conicity(20e-3, 0.46, 0.75).is_err());
    assert!(f.equivalent_conicity(f64::NAN, 0.46, 0.75).is_err());
    assert!(RollingRadiusDifference::new(vec![0.0, 0.0], vec![0.0, 1.0]).is_err());
}

#[test]
fn table_lookup_matches_direct_search() {
    let (ws, tr) = s1002_uic60();
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    let settings = TableSettings {
        y_max: 0.004,
        dy: 0.1e-3,
        roll_max: 0.004,
        droll: 1e-3,
    };
    let t = std::time::Instant::now();
    let table = ContactTable::from_geometry(&geo, settings).unwrap();
    println!("small table: {:?}", t.elapsed());
    // The deepest of a wheel's two region slots is the direct search's contact.
    let deepest = |slots: &[Contact; 2]| {
        if slots[1].gap < slots[0].gap {
            slots[1]
        } else {
            slots[0]
        }
    };
    // At nodes (roll 0: the table's w grid is the y grid): identical.
    let at = table.lookup_regions(1.2e-3, 0.0).unwrap();
    let d = geo.contacts(1.2e-3, 0.0).unwrap();
    for s in 0..2 {
        let (ca, cb) = (deepest(&at[s]), d[s].deepest());
        assert!((ca.gap - cb.gap).abs() < 1e-12);
        assert!((ca.rolling_radius - cb.rolling_radius).abs() < 1e-12);
    }
    // between nodes on the S1002 tread, rolling radius and gap interpolate to 20 µm (the contact
    // moves continuously except where it jumps; compare where no jump occurs)
    let mut compared = 0;
    for k in 0..40 {
        let y = -3.9e-3 + k as f64 * 0.195e-3;
        let roll = -3.5e-3 + k as f64 * 0.17e-3;
        let a = table.lookup_regions(y, roll).unwrap();
        let b = geo.contacts(y, roll).unwrap();
        for s in 0..2 {
            let (ca, cb) = (deepest(&a[s]), b[s].deepest());
            if (ca.wheel_u - cb.wheel_u).abs() < 1e-3 {
                compared += 1;
                assert!((ca.rolling_radius - cb.rolling_radius).abs() < 20e-6);
                assert!((ca.gap - cb.gap).abs() < 20e-6);
            }
        }
    }
    assert!(compared > 60, "{compared}");
    // One wheel's lookup is that wheel's slots of the both-wheel lookup, bit
    // for bit (the contact looks each wheel up at its own rail's shift).
    for k in 0..40 {
        let (y, roll) = (-3.8e-3 + k as f64 * 0.19e-3, 2e-3 - k as f64 * 0.1e-3);
        let both = table.lookup_regions(y, roll).unwrap();
        for (side, slots) in both.iter().enumerate() {
            let one = table.lookup_regions_of(side, y, roll).unwrap();
            for (a, b) in one.iter().zip(slots) {
                let bits = |c: &Contact| c.values().map(f64::to_bits);
                assert_eq!(bits(a), bits(b), "y {y}, roll {roll}, side {side}");
            }
        }
    }
    assert!(table.lookup_regions_of(2, 0.0, 0.0).is_err());
    // rigid functions are stored over the table's lateral range
    let rf = table.rigid_functions();
    assert_eq!(rf.len(), 81);
    assert!(rf[40].y.abs() < 1e-15 && rf[40].rolling_radius_difference().abs() < 1e-12);
    // outside the table (lateral range plus R sin(roll_max) = 5.84 mm): a clear error
    let e = table.lookup_regions(0.007, 0.0).unwrap_err();
    assert!(matches!(e, GeometryError::OutOfRange { .. }), "{e}");
    let e = table.lookup_regions(0.0, 0.005).unwrap_err();
    assert!(matches!(e, GeometryError::OutOfRange { .. }), "{e}");
    assert!(table.lookup_regions(0.0, f64::NAN).is_err());
}

#[test]
fn yaw_lead_on_the_flange() {
    // x_c = r tan δ ψ on the left wheel, opposite sign on the right (mirror image).
    let (ws, tr) = s1002_uic60();
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    let r = geo.rigid(0.009).unwrap();
    let fl = r.sides[0].deepest();
    let k = fl.rolling_radius * fl.contact_angle.tan();
    assert!((fl.yaw_lead - k).abs() < 1e-12 && k > 0.5);
    assert!((fl.longitudinal_offset(0.01) - 0.01 * k).abs() < 1e-12);
    let l = geo.rigid(-0.009).unwrap().sides[1];
    assert!((l.deepest().yaw_lead + k).abs() < 1e-6);
}

#[test]
fn invalid_inputs_are_errors() {
    let (ws, tr) = s1002_uic60();
    let mut bad = ws.clone();
    bad.radius_left = -1.0;
    assert!(ContactGeometry::new(&bad, &tr, SearchSettings::default()).is_err());
    let mut bad_track = tr.clone();
    bad_track.rail_left = ws.wheel_left.clone();
    let e = ContactGeometry::new(&ws, &bad_track, SearchSettings::default()).unwrap_err();
    assert!(e.to_string().contains("wheel profile"), "{e}");
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    assert!(geo.contacts(f64::INFINITY, 0.0).is_err());
    assert!(geo.contacts(0.5, 0.0).is_err()); // wheel 0.5 m off the rail: no overlap
}

/// Three-dimensional minimum vertical distance between a yawed wheel of revolution and a rail
/// (both with a profile of slope `t` and curvatures `cw`, `cr` at the touching point), found by
/// nested golden-section searches over the axial position and the angle on the wheel circle.
/// Returns the contact's longitudinal position in the wheelset frame and its rolling radius.
fn yawed_contact(r_c: f64, t: f64, cw: f64, cr: f64, psi: f64) -> (f64, f64) {
    let xi_c = 0.75;
    let radius = |xi: f64| r_c + t * (xi_c - xi) + cw * (xi - xi_c).powi(2);
    let rail = |y: f64| -r_c + t * (y - xi_c) - cr * (y - xi_c).powi(2);
    let (s, c) = psi.sin_cos();
    let gap = |xi: f64, th: f64| {
        let r = radius(xi);
        let y = xi * c + r * th.sin() * s;
        -r * th.cos() - rail(y)
    };
    fn golden(mut a: f64, mut b: f64, f: &dyn Fn(f64) -> f64) -> f64 {
        let g = 0.618_033_988_749_894_9;
        while b - a > 1e-13 {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            if f(x1) < f(x2) {
                b = x2;
            } else {
                a = x1;
            }
        }
        0.5 * (a + b)
    }
    let best_theta = |xi: f64| golden(-0.5, 0.5, &|th| gap(xi, th));
    let xi = golden(xi_c - 0.01, xi_c + 0.01, &|xi| gap(xi, best_theta(xi)));
    let th = best_theta(xi);
    (radius(xi) * th.sin(), radius(xi))
}

#[test]
fn yaw_lead_matches_three_dimensional_minimum_distance() {
    // The stored lead k = r tan δ of the S1002 flange contact predicts the longitudinal offset
    // of the contact of the yawed wheelset, x_c = k ψ. Check it against a direct 3-D minimum
    // vertical distance search for a wheel and rail with the same slope, radius and curvatures
    // at the contact. The exact solution of the idealised problem is x_c = r t sin ψ /
    // √(1 + t² sin² ψ); for ψ = 2 mrad and t ≈ 2.7 it differs from k ψ by t²ψ²/2 ≈ 2e-5
    // relative; the curvature terms shift it by order ψ too. Tolerance 1e-3 relative.
    let (ws, tr) = s1002_uic60();
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    let fl = *geo.rigid(0.008).unwrap().sides[0].deepest();
    let t = fl.contact_angle.tan();
    // transverse curvatures: wheel profile concave in the throat, rail convex at the corner;
    // in the axial coordinate the wheel radius grows as −h, so its second derivative is the
    // profile's h'' = −κ(1 + t²)^{3/2}
    let k3 = (1.0 + t * t).powf(1.5);
    let cw = 0.5 * fl.wheel_transverse_curvature * k3;
    let cr = 0.5 * fl.rail_transverse_curvature * k3;
    for psi in [2e-3, -2e-3] {
        let (x, r) = yawed_contact(fl.rolling_radius, t, cw, cr, psi);
        assert!((r - fl.rolling_radius).abs() < 1e-3);
        let predicted = fl.longitudinal_offset(psi);
        assert!(
            (x / predicted - 1.0).abs() < 1e-3,
            "ψ {psi}: 3-D {x} vs k ψ {predicted}"
        );
    }
}

#[test]
fn region_lookup_is_accurate_and_continuous_across_the_flange_root_jump() {
    // S1002 on UIC60 1:40: the single contact point jumps from the flange
    // root (δ ≈ 0.6) to the flange (δ ≈ 1.2) near y = 6.3 mm. The region
    // table must (a) equal the direct region search between nodes to a few
    // µm in gap (about 1 µm where the gap is smooth; up to 10 µm where a
    // slot's minimum passes from the region's boundary into its interior, a
    // kink of the gap that the cubic interpolation rounds off over one
    // 0.1 mm cell) and (b) never jump: between samples
    // 2 µm apart the gap of each slot changes by at most the distance
    // function's slope (|∂gap/∂y| ≤ tan 1.25 ≈ 3) times the step.
    let (ws, tr) = s1002_uic60();
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    let table = ContactTable::from_geometry(
        &geo,
        TableSettings {
            y_max: 0.009,
            dy: 0.1e-3,
            roll_max: 0.004,
            droll: 2e-3,
        },
    )
    .unwrap();
    let split = table.region_split();
    let roll = 0.7e-3; // between roll nodes
    let mut prev: Option<[[Contact; 2]; 2]> = None;
    let mut worst: f64 = 0.0;
    let dy = 2e-6;
    for k in 0..1000 {
        let y = 5.5e-3 + k as f64 * dy;
        let t = table.lookup_regions(y, roll).unwrap();
        if k % 50 == 0 {
            for side in 0..2 {
                let d = geo.region_contacts(side, y, roll, split[side]).unwrap();
                for slot in 0..2 {
                    worst = worst.max((t[side][slot].gap - d[slot].gap).abs());
                }
            }
        }
        if let Some(p) = prev {
            for side in 0..2 {
                for slot in 0..2 {
                    let jump = (t[side][slot].gap - p[side][slot].gap).abs();
                    assert!(jump <= 3.0 * dy, "gap jumps by {jump:e} m at y = {y}");
                }
            }
        }
        prev = Some(t);
    }
    assert!(worst < 10e-6, "table vs direct region search: {worst:e} m");
    // The deepest slot is the direct search's single contact at the nodes.
    let d = geo.contacts(6.0e-3, 0.0).unwrap();
    let t = table.lookup_regions(6.0e-3, 0.0).unwrap();
    let deepest = t[0][0].gap.min(t[0][1].gap);
    assert!((deepest - d[0].deepest().gap).abs() < 1e-9);
}
