//! Massless elastic rail: static load (springs in series), lateral equilibrium,
//! one- and two-point contact, damping.

use railmbs_wheelrail::creep::{Creepages, FastsimA};
use railmbs_wheelrail::elastic_rail::{
    ContactMaterial, ElasticRailSettings, LateralDamping, LinearizedContacts, RailContact,
    RailSupport, solve,
};
use railmbs_wheelrail::hertz::{HertzShape, wheel_rail_curvatures};

fn steel() -> ContactMaterial {
    ContactMaterial {
        g: 210e9 / (2.0 * 1.3),
        nu: 0.3,
        mu: 0.3,
    }
}

/// The reference README's Hertz example: wheel radius 0.46 m on a rail crown
/// radius 0.3 m, E = 210 GPa, ν = 0.3: approach 0.1041 mm at 100 kN (published).
fn tread_shape() -> HertzShape {
    let (ca, cb) = wheel_rail_curvatures(0.46, 0.0, 1.0 / 0.3);
    HertzShape::new(ca, cb, 210e9, 0.3).unwrap()
}

/// A wheel pressed vertically into a rail on a vertical spring kz: the rail
/// deflects by N/kz and the Hertz contact compresses in series. With kz =
/// 100 MN/m and the wheel lowered by 1 mm + 0.1041 mm (rail deflection at
/// 100 kN plus the published Hertz approach at 100 kN), the load must be
/// 100 kN and the rail deflection 1 mm. The published approach has 4 digits
/// (±0.05 µm of 1.1041 mm total): N within 1e-4 relative.
#[test]
fn static_load_springs_in_series() {
    let support = RailSupport {
        ky: 50e6,
        cy: 0.0,
        kz: 100e6,
        cz: 0.0,
        lateral_damping: LateralDamping::Always,
    };
    let geo = LinearizedContacts {
        contacts: vec![RailContact {
            approach: 1.0e-3 + 0.1041e-3,
            normal: [0.0, 1.0],
            hertz: tread_shape(),
            creepages: Creepages::default(),
        }],
    };
    let law = FastsimA::new(10).unwrap();
    let s = solve(
        &support,
        &steel(),
        &geo,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap();
    assert_eq!(s.n_contacts, 1);
    let n = s.contacts[0].normal_force;
    assert!((n / 100e3 - 1.0).abs() < 1e-4, "N = {n}");
    assert!(
        (s.displacement[1] / -1.0e-3 - 1.0).abs() < 1e-4,
        "dz = {}",
        s.displacement[1]
    );
    assert!(s.displacement[0].abs() < 1e-12);
    // Vertical equilibrium exactly: kz·dz + N = 0.
    assert!((support.kz * s.displacement[1] + n).abs() < 1e-5);
    assert!((s.contacts[0].approach / 0.1041e-3 - 1.0).abs() < 1e-3);
}

/// Tilted contact with lateral creepage: the support forces balance the wheel
/// force in both directions (k d = −F_wheel), the creep force is the law's for
/// the equilibrium normal force, and the normal force is Hertz's for the
/// equilibrium approach δ₀ + n·d.
#[test]
fn lateral_equilibrium_balances() {
    let support = RailSupport {
        ky: 40e6,
        cy: 0.0,
        kz: 120e6,
        cz: 0.0,
        lateral_damping: LateralDamping::Always,
    };
    let gamma: f64 = 0.2; // contact angle, rad; normal tilted towards −y
    let normal = [-gamma.sin(), gamma.cos()];
    let c0 = RailContact {
        approach: 0.6e-3,
        normal,
        hertz: tread_shape(),
        creepages: Creepages {
            xi: 0.0,
            eta: 2e-3,
            phi: -0.3,
        },
    };
    let geo = LinearizedContacts { contacts: vec![c0] };
    let law = FastsimA::new(20).unwrap();
    let s = solve(
        &support,
        &steel(),
        &geo,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap();
    // Balance to the outer tolerance (creep forces settled to 1e-9 of the load).
    let k = [support.ky, support.kz];
    for (i, ki) in k.iter().enumerate() {
        let bal = ki * s.displacement[i] + s.wheel_force[i];
        assert!(
            bal.abs() < 1e-8 * s.contacts[0].normal_force,
            "direction {i}: {bal}"
        );
    }
    let c = &s.contacts[0];
    let delta = 0.6e-3 + normal[0] * s.displacement[0] + normal[1] * s.displacement[1];
    let n_hertz = tread_shape().normal_force(delta).unwrap();
    assert!((c.normal_force / n_hertz - 1.0).abs() < 1e-9);
    // Creep force on the wheel opposes the positive lateral creepage.
    assert!(c.creep.fy < 0.0 && c.creep.fy.abs() <= 0.3 * c.normal_force * (1.0 + 1e-9));
    assert!(s.outer_iterations >= 2);
}

/// Two-point contact (tread + flange): both contacts carry load, each normal
/// force is Hertz's at its own approach, and the rail balances their sum.
#[test]
fn two_point_contact() {
    let support = RailSupport {
        ky: 30e6,
        cy: 0.0,
        kz: 100e6,
        cz: 0.0,
        lateral_damping: LateralDamping::Always,
    };
    let flange_angle: f64 = 1.1; // ~63°
    let (ca, cb) = wheel_rail_curvatures(0.47, -1.0 / 0.015, 1.0 / 0.013);
    let flange = HertzShape::new(ca, cb, 210e9, 0.3).unwrap();
    let contacts = vec![
        RailContact {
            approach: 0.8e-3,
            normal: [0.0, 1.0],
            hertz: tread_shape(),
            creepages: Creepages {
                xi: 1e-3,
                eta: -1e-3,
                phi: 0.1,
            },
        },
        RailContact {
            approach: 0.3e-3,
            normal: [-flange_angle.sin(), flange_angle.cos()],
            hertz: flange,
            creepages: Creepages {
                xi: -2e-3,
                eta: -1e-3,
                phi: -1.5,
            },
        },
    ];
    let geo = LinearizedContacts {
        contacts: contacts.clone(),
    };
    let law = FastsimA::new(10).unwrap();
    let s = solve(
        &support,
        &steel(),
        &geo,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap();
    assert_eq!(s.n_contacts, 2);
    for (i, c0) in contacts.iter().enumerate() {
        let c = &s.contacts[i];
        assert!(c.normal_force > 0.0, "contact {i} unloaded");
        let delta =
            c0.approach + c0.normal[0] * s.displacement[0] + c0.normal[1] * s.displacement[1];
        let nh = c0.hertz.normal_force(delta).unwrap();
        assert!((c.normal_force / nh - 1.0).abs() < 1e-9);
    }
    let load = s.contacts[0].normal_force + s.contacts[1].normal_force;
    assert!((support.ky * s.displacement[0] + s.wheel_force[0]).abs() < 1e-8 * load);
    assert!((support.kz * s.displacement[1] + s.wheel_force[1]).abs() < 1e-8 * load);
}

/// With a damper, a step from rest gives the backward-Euler response: the
/// vertical deflection is smaller than the static one, and with h → ∞ it is
/// the static one.
#[test]
fn damping_and_errors() {
    let support = RailSupport {
        ky: 50e6,
        cy: 0.0,
        kz: 100e6,
        cz: 1e5,
        lateral_damping: LateralDamping::Always,
    };
    let geo = LinearizedContacts {
        contacts: vec![RailContact {
            approach: 1.1041e-3,
            normal: [0.0, 1.0],
            hertz: tread_shape(),
            creepages: Creepages::default(),
        }],
    };
    let law = FastsimA::new(10).unwrap();
    let stat = solve(
        &support,
        &steel(),
        &geo,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap();
    let settings = ElasticRailSettings {
        h: 1e-3,
        v_roll: 20.0,
        ..Default::default()
    };
    let dyn_ = solve(&support, &steel(), &geo, &law, [0.0; 2], &settings).unwrap();
    assert!(dyn_.displacement[1] > stat.displacement[1] && dyn_.displacement[1] < 0.0);
    // Equilibrium with the damper: kz dz + cz (dz − 0)/h + N = 0.
    let n = dyn_.contacts[0].normal_force;
    let r = support.kz * dyn_.displacement[1] + support.cz * dyn_.displacement[1] / 1e-3 + n;
    assert!(r.abs() < 1e-5, "{r}");
    assert!((dyn_.velocity[1] - dyn_.displacement[1] / 1e-3).abs() < 1e-12);
    // Bad parameters are named.
    let bad = RailSupport { kz: 0.0, ..support };
    let e = solve(
        &bad,
        &steel(),
        &geo,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("kz = 0"), "{e}");
    // No contact: zero forces, rail at rest.
    let apart = LinearizedContacts {
        contacts: vec![RailContact {
            approach: -1e-4,
            ..geo.contacts[0]
        }],
    };
    let s = solve(
        &support,
        &steel(),
        &apart,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap();
    assert_eq!(s.contacts[0].normal_force, 0.0);
    assert_eq!(s.displacement, [0.0, 0.0]);
}

/// With the profile contact geometry (S1002 on UIC60 1:40, centred wheelset):
/// the left wheel lowered 1 mm into its rail on stiff lateral and 100 MN/m
/// vertical support. The vertical overlap splits into rail deflection and
/// Hertz approach (springs in series): −d_z + δ/cos δ_c = 1 mm, N follows Hertz
/// at the final approach, and both equilibria hold.
#[test]
fn profile_geometry_static_load() {
    use railmbs_wheelrail::elastic_rail::ProfileRailContacts;
    use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
    use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};
    let s = ProfileSettings::default();
    let w = Profile::read(
        &railmbs_testkit::model_path("profiles/MBench_S1002_v3.prw"),
        ProfileKind::Wheel,
        &s,
    )
    .unwrap();
    let r = Profile::read(
        &railmbs_testkit::model_path("profiles/MBench_UIC60_v3.prr"),
        ProfileKind::Rail,
        &s,
    )
    .unwrap();
    let ws = Wheelset::new(w.clone(), w, 0.46, 1.360);
    let tr = Track::new(r.clone(), r, 1.435);
    let geo = ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap();
    let c0 = *geo.contacts(0.0, 0.0).unwrap()[0].deepest();
    let lower = 1.0e-3;
    let rc = ProfileRailContacts {
        geometry: &geo,
        side: 0,
        y: 0.0,
        roll: 0.0,
        z: -c0.gap - lower,
        e: 210e9,
        nu: 0.3,
        creepages: |_c: &railmbs_wheelrail::geometry::Contact| Creepages::default(),
    };
    let support = RailSupport {
        ky: 1e12,
        cy: 0.0,
        kz: 100e6,
        cz: 0.0,
        lateral_damping: LateralDamping::Always,
    };
    let law = FastsimA::new(10).unwrap();
    let sol = solve(
        &support,
        &steel(),
        &rc,
        &law,
        [0.0; 2],
        &ElasticRailSettings::default(),
    )
    .unwrap();
    assert!(sol.n_contacts >= 1);
    let c = &sol.contacts[0];
    let cosd = c.normal[1];
    let split = -sol.displacement[1] + c.approach / cosd;
    assert!((split / lower - 1.0).abs() < 1e-3, "{split}");
    let load = c.normal_force;
    assert!(load > 10e3 && load < 200e3, "{load}");
    assert!((support.kz * sol.displacement[1] + sol.wheel_force[1]).abs() < 1e-8 * load);
    assert!((support.ky * sol.displacement[0] + sol.wheel_force[0]).abs() < 1e-8 * load + 1e-3);
}

/// Lateral rail damping in two-point contact only (Pogorelov 2005, Sect.
/// 4.2) against `Always` (the default): over a 1 ms step from rest, a
/// one-point tread contact with lateral creep sees no lateral damper (the
/// lateral equilibrium is `k_y d_y + F_y = 0` with the step's creep
/// forces), while the same wheel in two-point contact (tread and flange) is
/// solved with it (`k_y d_y + c_y d_y/h + F_y = 0`) exactly as with
/// `Always`. Tolerances: the equilibria to 1e-8 of the load (the solver's
/// force tolerance is 1e-6 N on loads of 1e5 N).
#[test]
fn lateral_damping_in_two_point_contact_only() {
    let (ca, cb) = wheel_rail_curvatures(0.47, -1.0 / 0.015, 1.0 / 0.013);
    let flange_angle: f64 = 1.1;
    let tread = RailContact {
        approach: 0.8e-3,
        normal: [-0.025_f64.sin(), 0.025_f64.cos()],
        hertz: tread_shape(),
        creepages: Creepages {
            xi: 1e-3,
            eta: -2e-3,
            phi: 0.1,
        },
    };
    let flange = RailContact {
        approach: 1.0e-3,
        normal: [-flange_angle.sin(), flange_angle.cos()],
        hertz: HertzShape::new(ca, cb, 210e9, 0.3).unwrap(),
        creepages: Creepages {
            xi: -2e-3,
            eta: -1e-3,
            phi: -1.5,
        },
    };
    let paper = RailSupport {
        ky: 30e6,
        cy: 2e5,
        kz: 100e6,
        cz: 0.0,
        lateral_damping: LateralDamping::TwoPointContact,
    };
    let always = RailSupport {
        lateral_damping: LateralDamping::default(),
        ..paper
    };
    assert_eq!(always.lateral_damping, LateralDamping::Always);
    let h = 1e-3;
    let settings = ElasticRailSettings {
        h,
        v_roll: 30.0,
        ..Default::default()
    };
    let law = FastsimA::new(10).unwrap();
    let run = |support: &RailSupport, contacts: Vec<RailContact>| {
        solve(
            support,
            &steel(),
            &LinearizedContacts { contacts },
            &law,
            [0.0; 2],
            &settings,
        )
        .unwrap()
    };
    let lateral_residual = |s: &railmbs_wheelrail::elastic_rail::ElasticRailSolution, cy: f64| {
        paper.ky * s.displacement[0] + cy * s.displacement[0] / h + s.wheel_force[0]
    };
    // One-point: undamped under the paper's rule, damped under Always.
    let one = run(&paper, vec![tread]);
    let one_always = run(&always, vec![tread]);
    let load = one.contacts[0].normal_force;
    assert!(!one.lateral_damped && one_always.lateral_damped);
    assert!(lateral_residual(&one, 0.0).abs() < 1e-8 * load);
    assert!(lateral_residual(&one_always, paper.cy).abs() < 1e-8 * load);
    // The damper holds the rail back over the step: a smaller lateral
    // displacement (the creep force, through the rail's velocity in the
    // creepage, damps it too, so not by c_y/h against k_y alone).
    eprintln!(
        "one-point lateral rail displacement: {:.4e} m undamped, {:.4e} m damped",
        one.displacement[0], one_always.displacement[0]
    );
    assert!(one_always.displacement[0].abs() < 0.99 * one.displacement[0].abs());
    // Two-point: damped either way, the same solution.
    let two = run(&paper, vec![tread, flange]);
    let two_always = run(&always, vec![tread, flange]);
    assert!(two.lateral_damped);
    assert!(two.contacts[0].normal_force > 0.0 && two.contacts[1].normal_force > 0.0);
    assert_eq!(two.displacement, two_always.displacement);
    let load = two.contacts[0].normal_force + two.contacts[1].normal_force;
    assert!(lateral_residual(&two, paper.cy).abs() < 1e-8 * load);
}
