//! Loading every construct of the model language.

use crate::common;

use common::*;
use railmbs_models::*;

fn fixed(kind: ElementaryKind, value: f64, params: &[f64], e: &Elementary) {
    assert_eq!(e.kind, kind);
    match &e.motion {
        Motion::Fixed(x) => assert_eq!(x.eval(params, 0.0), value),
        other => panic!("expected fixed {kind:?}, got {other:?}"),
    }
}

fn coord(kind: ElementaryKind, index: usize, e: &Elementary) {
    assert_eq!(e.kind, kind);
    assert_eq!(e.motion, Motion::Coordinate(index));
}

use ElementaryKind::{Rotation as R, Translation as T};

#[test]
fn parameters_in_file_order_stay_symbolic() {
    let m = full();
    let names: Vec<&str> = m.parameters.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        ["l1", "m1", "l2", "m2", "g", "k", "d", "L0", "WS1.r0"]
    );
    // "l2": "l1" stays an expression over l1.
    assert_eq!(m.parameters[2].default, Expr::Param(0));
    assert_eq!(m.parameters[3].doc, "kg");
    assert_eq!(
        m.default_parameter_values(),
        vec![1.0, 1.0, 1.0, 2.0, 9.81, 100.0, 1.5, 0.5, 0.46]
    );
    // Gravity (0, "-g", 0) refers to g symbolically.
    assert_eq!(m.gravity[1], Expr::Neg(Box::new(Expr::Param(4))));
    assert_eq!(m.name, "everything");
    assert_eq!(m.source.as_deref(), Some(std::path::Path::new(FILE)));
}

#[test]
fn default_gravity_is_minus_z() {
    let m = load(BASE).unwrap();
    let p = m.default_parameter_values();
    let g: Vec<f64> = m.gravity.iter().map(|e| e.eval(&p, 0.0)).collect();
    assert_eq!(g, [0.0, 0.0, -9.81]);
}

#[test]
fn bodies_are_sorted_parent_first() {
    let m = full();
    let names: Vec<&str> = m.bodies.iter().map(|b| b.name.as_str()).collect();
    // link2 (child of link1) comes first in the file.
    assert_eq!(names, ["link1", "link2", "Bogie1.WS1", "fix", "slider"]);
    assert_eq!(m.bodies[0].parent, BodyRef::Ground);
    assert_eq!(m.bodies[1].parent, BodyRef::Body(0));
    assert_eq!(m.bodies[3].parent, BodyRef::Body(2));
    for (i, b) in m.bodies.iter().enumerate() {
        if let BodyRef::Body(p) = b.parent {
            assert!(p < i);
        }
    }
    assert_eq!(m.body_index("fix"), Some(3));
    assert_eq!(m.body_index("ground"), None);
}

#[test]
fn revolute_expands_to_at_coordinate_to_com() {
    let m = full();
    let p = m.default_parameter_values();
    let j = &m.bodies[0].joint;
    // at = (0, 0, 0) is dropped; Rz(q0); to_com = (0, -l1/2, 0) keeps only Ty.
    assert_eq!(j.len(), 2);
    coord(R(Axis::Z), 0, &j[0]);
    fixed(T(Axis::Y), -0.5, &p, &j[1]);
    let mass = m.bodies[0].mass.eval(&p, 0.0);
    assert_eq!(mass, 1.0);
    // ixx = m1 l1²/12.
    assert_eq!(m.bodies[0].inertia[0].eval(&p, 0.0), 1.0 / 12.0);
}

#[test]
fn general_joint_has_fixed_coordinate_and_time_transforms() {
    let m = full();
    let p = m.default_parameter_values();
    let j = &m.bodies[1].joint;
    assert_eq!(j.len(), 6, "{j:?}");
    fixed(T(Axis::Y), -0.5, &p, &j[0]);
    coord(R(Axis::Z), 1, &j[1]);
    match &j[2].motion {
        Motion::Time(e) => {
            // 0.1 sin(2π t) at t = 0.25 s is 0.1.
            assert!((e.eval(&p, 0.25) - 0.1).abs() < 1e-15);
        }
        other => panic!("expected a time function, got {other:?}"),
    }
    assert_eq!(j[2].kind, R(Axis::X));
    fixed(T(Axis::Y), -0.5, &p, &j[3]);
    // An explicit zero in the general form is kept as written.
    fixed(T(Axis::X), 0.0, &p, &j[4]);
    coord(R(Axis::Z), 2, &j[5]);
}

#[test]
fn six_dof_uses_order_and_long_names() {
    let m = full();
    let p = m.default_parameter_values();
    let b = m.body_index("Bogie1.WS1").unwrap();
    let j = &m.bodies[b].joint;
    assert_eq!(j.len(), 9);
    fixed(T(Axis::X), 1.0, &p, &j[0]);
    fixed(T(Axis::Y), 2.0, &p, &j[1]);
    fixed(T(Axis::Z), 0.46, &p, &j[2]);
    let base = m.coordinate_index("Bogie1.WS1.x").unwrap();
    coord(T(Axis::X), base, &j[3]);
    coord(T(Axis::Y), base + 1, &j[4]);
    coord(T(Axis::Z), base + 2, &j[5]);
    // order "zxy": yaw, roll, spin.
    coord(R(Axis::Z), base + 3, &j[6]);
    coord(R(Axis::X), base + 4, &j[7]);
    coord(R(Axis::Y), base + 5, &j[8]);
    let names: Vec<&str> = m.coordinates[base..base + 6]
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "Bogie1.WS1.x",
            "Bogie1.WS1.y",
            "Bogie1.WS1.z",
            "Bogie1.WS1.rz",
            "Bogie1.WS1.rx",
            "Bogie1.WS1.ry"
        ]
    );
    // init (x, y, z, about x, about y, about z) = (0.1 … 0.6).
    let (q, v) = m.initial_state(&p);
    assert_eq!(&q[base..base + 6], &[0.1, 0.2, 0.3, 0.6, 0.4, 0.5]);
    assert_eq!(v[base], 1.0);
    assert_eq!(v[base + 5], 1.0 / 0.46);
    assert_eq!(m.bodies[b].inertia[3].eval(&p, 0.0), 1.0);
}

#[test]
fn rigid_and_prismatic() {
    let m = full();
    let p = m.default_parameter_values();
    let j = &m.bodies[m.body_index("fix").unwrap()].joint;
    assert_eq!(j.len(), 2);
    fixed(T(Axis::X), 1.0, &p, &j[0]);
    fixed(R(Axis::Y), 0.5, &p, &j[1]);
    let s = m.body_index("slider").unwrap();
    let j = &m.bodies[s].joint;
    let qi = m.coordinate_index("slider.tx").unwrap();
    coord(T(Axis::X), qi, &j[0]);
    fixed(T(Axis::Z), 0.25, &p, &j[1]);
    assert_eq!(m.coordinates[qi].body, s);
    assert_eq!(m.coordinates[qi].elementary, 0);
}

#[test]
fn coordinates_in_body_then_transform_order() {
    let m = full();
    let names: Vec<&str> = m.coordinates.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names[..3], ["q0", "q1", "q2"]);
    assert_eq!(names.len(), 3 + 6 + 1);
    for (i, c) in m.coordinates.iter().enumerate() {
        assert_eq!(
            m.bodies[c.body].joint[c.elementary].motion,
            Motion::Coordinate(i),
            "{}",
            c.name
        );
    }
    let p = m.default_parameter_values();
    let (q, v) = m.initial_state(&p);
    assert_eq!(q[0], 0.5);
    assert_eq!(q[1], 0.1); // "0.1*l1"
    assert_eq!(v[1], 2.0);
    assert_eq!(q[2], 0.0);
    assert_eq!(m.coordinate_index("q2"), Some(2));
}

#[test]
fn cut_joints() {
    let m = full();
    let p = m.default_parameter_values();
    let c = &m.cut_joints[0];
    assert_eq!(c.name, "closure");
    assert_eq!(c.body1, BodyRef::Body(1));
    assert_eq!(c.body2, BodyRef::Ground);
    assert_eq!(c.frame1.origin[1].eval(&p, 0.0), -0.5);
    assert_eq!(c.frame2.origin[0].eval(&p, 0.0), 2.0);
    assert_eq!(c.constrained, vec![Component::Tx, Component::Ty]);
}

#[test]
fn force_elements() {
    let m = full();
    let p = m.default_parameter_values();
    assert_eq!(m.force_index("bush"), Some(1));
    match &m.forces[0].kind {
        ForceKind::Bipolar(railmbs_models::forces::Bipolar {
            ends: railmbs_models::forces::PointPair { body1, body2, .. },
            stiffness,
            damping,
            preload,
            free_length,
        }) => {
            assert_eq!(*body1, BodyRef::Ground);
            assert_eq!(*body2, BodyRef::Body(4));
            assert_eq!(stiffness.eval(&p, 0.0), 100.0);
            assert_eq!(damping.eval(&p, 0.0), 1.5);
            assert!(preload.is_zero());
            assert_eq!(free_length.eval(&p, 0.0), 0.5);
        }
        other => panic!("{other:?}"),
    }
    match &m.forces[1].kind {
        ForceKind::Linear6(railmbs_models::forces::Linear6 {
            body1,
            body2,
            stiffness,
            damping,
            preload,
            ..
        }) => {
            assert_eq!(*body1, BodyRef::Body(2));
            assert_eq!(*body2, BodyRef::Body(3));
            for r in 0..6 {
                for c in 0..6 {
                    let k = stiffness[6 * r + c].eval(&p, 0.0);
                    let want = match (r == c, r < 3) {
                        (false, _) => 0.0,
                        (true, true) => 1e6,
                        (true, false) => 1e3,
                    };
                    assert_eq!(k, want, "stiffness[{r}][{c}]");
                }
            }
            assert_eq!(damping[35].eval(&p, 0.0), 100.0);
            assert_eq!(damping[0].eval(&p, 0.0), 1.0);
            assert_eq!(damping[1].eval(&p, 0.0), 0.0);
            assert_eq!(preload[2].eval(&p, 0.0), 9.81);
        }
        other => panic!("{other:?}"),
    }
    match &m.forces[2].kind {
        ForceKind::Applied(railmbs_models::forces::Applied {
            body, force, frame, ..
        }) => {
            assert_eq!(*body, 4);
            assert!(force[0].has_time());
            assert_eq!(*frame, VectorFrame::Body);
        }
        other => panic!("{other:?}"),
    }
    match &m.forces[3].kind {
        ForceKind::Applied(railmbs_models::forces::Applied {
            point,
            force,
            torque,
            frame,
            ..
        }) => {
            assert!(point.iter().all(Expr::is_zero));
            assert!(torque.iter().all(Expr::is_zero));
            assert_eq!(force[2].eval(&p, 0.0), -1.0);
            assert_eq!(*frame, VectorFrame::Global);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn load_model_reads_a_file() {
    let dir = std::env::temp_dir().join(format!("railmbs-models-load-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("everything.ron");
    std::fs::write(&path, FULL).unwrap();
    let m = load_model(&path).unwrap();
    assert_eq!(m.source.as_deref(), Some(path.as_path()));
    assert_eq!(m.bodies.len(), 5);
    let missing = load_model(&dir.join("missing.ron")).unwrap_err();
    assert!(missing.to_string().contains("missing.ron"), "{missing}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `free_wheelset.ron` with `creep` set to `law` (profiles by absolute path).
fn wheelset_with_creep(law: &str) -> Result<Model, ModelErrors> {
    let file = railmbs_testkit::model_path("vehicles/free_wheelset.ron");
    let text = std::fs::read_to_string(file).unwrap();
    let profiles = railmbs_testkit::model_path("profiles")
        .display()
        .to_string();
    let text = text
        .replace("\"../profiles", &format!("\"{profiles}"))
        .replace(
            "normal_damping: \"cn\",",
            &format!("normal_damping: \"cn\", creep: {law},"),
        );
    let path = std::env::temp_dir().join(format!(
        "railmbs-creep-law-{}-{}.ron",
        std::process::id(),
        law.len()
    ));
    std::fs::write(&path, text).unwrap();
    let model = load_model(&path);
    std::fs::remove_file(&path).unwrap();
    model
}

/// The creep law of a wheel–rail element is wheelrail's `CreepLawSpec`, its
/// real-valued settings expressions over the parameters, checked by the law's
/// own rules at the default parameters.
#[test]
fn wheel_rail_creep_law_settings_are_expressions() {
    let creep = |m: &Model| {
        m.forces
            .iter()
            .find_map(|f| match &f.kind {
                ForceKind::WheelRail(w) => Some(w.creep.clone()),
                _ => None,
            })
            .unwrap()
    };
    let m = wheelset_with_creep("Mueller(exponent: \"2*mu + 1\")").unwrap();
    let defaults: Vec<f64> = m
        .parameters
        .iter()
        .map(|p| p.default.eval(&[], 0.0))
        .collect();
    assert_eq!(
        creep(&m).map(|_, e| e.eval(&defaults, 0.0)),
        CreepLawSpec::Mueller { exponent: 1.8 }
    );
    let m = wheelset_with_creep("Polach(ks: 0.5, friction_decrease: (\"mu\", 0.6))").unwrap();
    assert_eq!(
        creep(&m).map(|_, e| e.eval(&defaults, 0.0)),
        CreepLawSpec::Polach {
            ka: 1.0,
            ks: 0.5,
            friction_decrease: Some((0.4, 0.6))
        }
    );
    let m = wheelset_with_creep("FastsimA(strips: 7, sliding: Picard(nodes: 3))").unwrap();
    assert_eq!(
        creep(&m),
        "fastsim-a:7,sliding=picard,nodes=3"
            .parse::<CreepLawSpec>()
            .unwrap()
            .map(|_, &x| Expr::Num(x))
    );
    for (law, expected) in [
        (
            "FastsimA(strips: 0)",
            "FastSim_A number of strips must be in 1..=",
        ),
        (
            "Mueller(exponent: \"mu - 1\")",
            "Mueller exponent must be positive and finite, got -0.6",
        ),
        ("Polach(ka: 2)", "Polach k_A = 2 is invalid"),
        ("Fastsim(nx: 10)", "ny"),
    ] {
        let e = wheelset_with_creep(law).unwrap_err().to_string();
        assert!(e.contains(expected), "{law}: {e}");
    }
}

/// The elastic rail's lateral damping: in every contact mode unless the
/// model says `lateral_damping: TwoPointContact` (Pogorelov 2005, Sect. 4.2).
#[test]
fn elastic_rail_lateral_damping_mode() {
    use railmbs_wheelrail::elastic_rail::LateralDamping;
    let mode = |rail: &str| {
        let m = wheelset_with_creep(&format!("Kalker, rail: {rail}")).unwrap();
        m.forces
            .iter()
            .find_map(|f| match &f.kind {
                ForceKind::WheelRail(w) => match &w.rail {
                    RailKind::Elastic {
                        lateral_damping, ..
                    } => Some(*lateral_damping),
                    RailKind::Rigid => None,
                },
                _ => None,
            })
            .unwrap()
    };
    assert_eq!(
        mode("Elastic(ky: 5e7, cy: 1e5, kz: 1e8)"),
        LateralDamping::Always
    );
    assert_eq!(
        mode("Elastic(ky: 5e7, cy: 1e5, kz: 1e8, lateral_damping: TwoPointContact)"),
        LateralDamping::TwoPointContact
    );
    assert!(
        wheelset_with_creep("Kalker, rail: Elastic(ky: 5e7, kz: 1e8, lateral_damping: Never)")
            .is_err()
    );
}

/// Found by `fuzz/run` (target `study`): a `/* */` comment holding a
/// multi-byte character (`kx·b1²`) made the locator slice inside the
/// character and panic. Now the error is reported as for any other text.
#[test]
fn block_comment_with_multibyte_characters_is_no_panic() {
    let file = std::path::Path::new("comment.ron");
    for text in [
        "/* stiffness, kx·b1² per axlebox */ Model(",
        "/* unterminated kx·b1²",
        "// kx·b1²\n/* · */ Model(name: 1)",
    ] {
        let e = railmbs_models::parse_model(text, file).expect_err(text);
        assert!(e.to_string().contains("comment.ron"), "{e}");
    }
}
