//! Parameter values with macros and overrides; structural hash.

use crate::common;

use common::*;

fn s(x: &str) -> String {
    x.to_string()
}

fn over(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs.iter().map(|(a, b)| (s(a), s(b))).collect()
}

#[test]
fn defaults_and_indices() {
    let m = full();
    let p = m.parameter_values(&[], &[]).unwrap();
    assert_eq!(p, m.default_parameter_values());
    assert_eq!(m.parameter_index("L0"), Some(7));
    assert_eq!(m.parameter_index("WS1.r0"), Some(8));
    assert_eq!(m.parameter_index("nope"), None);
    assert_eq!(m.force_index("nope"), None);
    assert_eq!(m.coordinate_index("nope"), None);
}

#[test]
fn macros_apply_in_order_then_overrides() {
    let m = full();
    let i = |n: &str| m.parameter_index(n).unwrap();
    // heavy: m1 = 2, m2 = 2*m1.
    let p = m.parameter_values(&[s("heavy")], &[]).unwrap();
    assert_eq!((p[i("m1")], p[i("m2")]), (2.0, 4.0));
    // An override after the macro: m2 = 2*m1 follows it.
    let p = m
        .parameter_values(&[s("heavy")], &over(&[("m1", "5")]))
        .unwrap();
    assert_eq!((p[i("m1")], p[i("m2")]), (5.0, 10.0));
    // Two macros; the later one wins where both assign.
    let p = m.parameter_values(&[s("heavy"), s("long")], &[]).unwrap();
    assert_eq!((p[i("m1")], p[i("l1")], p[i("l2")]), (2.0, 3.0, 3.0));
}

#[test]
fn overrides_are_expressions_and_dependents_follow() {
    let m = full();
    let i = |n: &str| m.parameter_index(n).unwrap();
    // l2 = "l1" by default: follows an override of l1.
    let p = m.parameter_values(&[], &over(&[("l1", "2.5")])).unwrap();
    assert_eq!((p[i("l1")], p[i("l2")]), (2.5, 2.5));
    // An overridden dependent keeps its own value.
    let p = m
        .parameter_values(&[], &over(&[("l1", "2.5"), ("l2", "l1/5 + g")]))
        .unwrap();
    assert_eq!(p[i("l2")], 2.5 / 5.0 + 9.81);
    assert_eq!(p[i("k")], 100.0);
}

#[test]
fn parameter_value_errors_name_the_element() {
    let m = full();
    let e = m.parameter_values(&[s("nope")], &[]).unwrap_err();
    assert_eq!(e.element, "macro \"nope\"");
    assert!(e.message.contains("unknown macro"), "{e}");
    assert!(e.message.contains("heavy, long"), "{e}");
    assert!(e.to_string().starts_with(FILE), "{e}");

    let e = m.parameter_values(&[], &over(&[("zz", "1")])).unwrap_err();
    assert_eq!(e.element, "parameter \"zz\"");
    assert!(e.message.contains("unknown parameter"), "{e}");

    let e = m
        .parameter_values(&[], &over(&[("k", "2*kk")]))
        .unwrap_err();
    assert_eq!(e.element, "parameter \"k\"");
    assert!(e.message.contains("unknown identifier \"kk\""), "{e}");

    let e = m.parameter_values(&[], &over(&[("k", "2*")])).unwrap_err();
    assert!(e.message.contains("column 3"), "{e}");

    let e = m.parameter_values(&[], &over(&[("k", "t")])).unwrap_err();
    assert!(e.message.contains("not allowed"), "{e}");

    let e = m.parameter_values(&[], &over(&[("l1", "l2")])).unwrap_err();
    assert!(e.message.contains("cycle"), "{e}");
    assert!(
        e.message.contains("l1 -> l2 -> l1") || e.message.contains("l2 -> l1 -> l2"),
        "{e}"
    );

    let e = m
        .parameter_values(&[], &over(&[("k", "1/(g - g)")]))
        .unwrap_err();
    assert_eq!(e.element, "parameter \"k\"");
    assert!(e.message.contains("not finite"), "{e}");
}

#[test]
fn structural_hash_ignores_default_values() {
    let h = full().structural_hash();
    assert_eq!(h.len(), 64);
    assert!(h.chars().all(|c| c.is_ascii_hexdigit()));
    assert_eq!(h, full().structural_hash(), "deterministic");
    for (from, to) in [
        ("\"k\": 100,", "\"k\": 200,"),
        ("\"l2\": \"l1\"", "\"l2\": \"2*l1\""),
        ("(value: 2, doc: \"kg\")", "(value: 3, doc: \"kilogram\")"),
        ("description: \"test model\"", "description: \"changed\""),
        ("\"m2\": \"2*m1\"", "\"m2\": \"3*m1\""),
        // Initial conditions are inputs too.
        ("init: 0.5", "init: 0.25"),
        ("init: \"0.1*l1\", vel: 2", "init: \"0.2*l1\", vel: 3"),
    ] {
        assert!(FULL.contains(from), "{from}");
        let m = load(&FULL.replacen(from, to, 1)).unwrap();
        assert_eq!(m.structural_hash(), h, "changing {from} to {to}");
    }
}

#[test]
fn structural_hash_changes_with_structure() {
    let h = full().structural_hash();
    for (from, to) in [
        ("iyy: 1e-4", "iyy: 2e-4"),
        ("Rx(\"0.1*sin(2*pi*t)\")", "Ry(\"0.1*sin(2*pi*t)\")"),
        ("coord: \"q0\"", "coord: \"theta\""),
        ("\"L0\": 0.5,", "\"L1\": 0.5,\n        \"L0\": 0.5,"),
        ("order: \"zxy\"", "order: \"zyx\""),
        ("constrain: [Tx, Ty]", "constrain: [Tx]"),
        ("c: \"k\"", "c: \"d\""),
        ("frame: Body", "frame: Global"),
        ("gravity: (0, \"-g\", 0)", "gravity: (0, 0, \"-g\")"),
    ] {
        assert!(FULL.contains(from), "{from}");
        let m = load(&FULL.replacen(from, to, 1)).unwrap_or_else(|e| panic!("{e}"));
        assert_ne!(m.structural_hash(), h, "changing {from} to {to}");
    }
}

/// `Parameter::unit`: the unit after the doc's last ", " (before a remark),
/// only SI-style symbols; the docs of the bundled models as written.
#[test]
fn parameter_units_from_docs() {
    let unit = |doc: &str| {
        railmbs_models::Parameter {
            name: "p".into(),
            default: railmbs_models::Expr::num(1.0),
            doc: doc.into(),
        }
        .unit()
        .map(str::to_owned)
    };
    for (doc, expected) in [
        ("car body mass whose half the bogie carries, kg", Some("kg")),
        ("gravitational acceleration, m/s2", Some("m/s2")),
        (
            "wheelset roll inertia, kg m2 (estimate: two 920 mm wheels)",
            Some("kg m2"),
        ),
        ("primary lateral damping, N s/m (choice)", Some("N s/m")),
        ("yaw stiffness, N m/rad", Some("N m/rad")),
        (
            "static deflection, m: the static position under an axle load",
            Some("m"),
        ),
        (
            "initial sinking, m: the static position under a Vehicle 1 axle load (109 kN) \
             on S1002/UIC60 1:40, so runs start near equilibrium",
            Some("m"),
        ),
        (
            "running speed at the start (initial spin v0/r0), m/s",
            Some("m/s"),
        ),
        ("kg", Some("kg")),
        ("spin creepage, 1/m", Some("1/m")),
        ("wheel–rail coefficient of friction", None),
        ("a fraction of the static spring load (choice)", None),
        ("settled from rest, so runs start near equilibrium", None),
        ("lateral spacing (UIC 510-2)", None),
        ("", None),
    ] {
        assert_eq!(unit(doc).as_deref(), expected, "doc {doc:?}");
    }
    // The bundled Vehicle 1 as loaded (its subsystems' parameters included).
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("vehicles/vehicle1.ron");
    let model = railmbs_models::load_model(&file).expect("vehicle1 loads");
    let unit_of = |name: &str| {
        let p = model.parameters.iter().find(|p| p.name == name);
        p.expect(name).unit()
    };
    assert_eq!(unit_of("mc"), Some("kg"));
    assert_eq!(unit_of("g"), Some("m/s2"));
    assert_eq!(unit_of("mu"), None);
}
