//! Every validation error names the file, the element and the position.

use crate::common;

use common::*;

#[test]
fn base_model_is_valid() {
    let m = load(BASE).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.bodies.len(), 2);
}

#[test]
fn ron_syntax_error_has_ron_position() {
    let text = BASE.replacen("mass: 1,", "mass: 1 inertia", 1);
    let errs = load(&text).unwrap_err();
    assert_eq!(errs.len(), 1);
    let e = &errs.0[0];
    let (line, _) = e.position.expect("position");
    assert_eq!(line, line_of(&text, "mass: 1 inertia"));
    assert_eq!(e.element, "body \"b\"");
    assert!(e.to_string().starts_with(&format!("{FILE}:{line}:")), "{e}");
}

#[test]
fn body_without_joint_is_an_error() {
    let text = BASE.replacen(
        "            joint: Joint(parent: \"a\", transforms: [Ty(\"-l\"), Rz((coord: \"qb\"))]),\n",
        "",
        1,
    );
    let errs = load(&text).unwrap_err();
    let e = find(&errs, "body \"b\"", "joint");
    assert!(e.message.contains("missing"), "{e}");
}

#[test]
fn unknown_field_is_an_error() {
    let errs = base_errors("mass: 1,", "mass: 1, colour: 3,");
    find(&errs, "body \"b\"", "colour");
}

#[test]
fn unknown_identifier_names_the_field() {
    let errs = base_errors("mass: \"m\"", "mass: \"2*mm\"");
    let e = find(&errs, "body \"a\"", "unknown identifier \"mm\" in mass");
    let text = BASE.replacen("mass: \"m\"", "mass: \"2*mm\"", 1);
    assert_eq!(e.line(), Some(line_of(&text, "\"2*mm\"")));
    // Column of the expression string's opening quote.
    let line = text.lines().nth(e.line().unwrap() - 1).unwrap();
    assert_eq!(e.column(), Some(line.find("\"2*mm\"").unwrap() + 1));

    let errs = base_errors("Ty(\"-l\")", "Ty(\"-l - w\")");
    find(
        &errs,
        "body \"b\"",
        "unknown identifier \"w\" in joint transform 1 (Ty)",
    );
    let errs = base_errors("c: \"k\"", "c: \"kk\"");
    find(&errs, "force \"s\"", "unknown identifier \"kk\" in c");
    let errs = base_errors("point2: (1, 0, 0)", "point2: (1, \"y0\", 0)");
    find(
        &errs,
        "cut joint \"cj\"",
        "unknown identifier \"y0\" in point2.y",
    );
    let errs = base_errors("\"k\": 10", "\"k\": \"10*q\"");
    find(
        &errs,
        "parameter \"k\"",
        "unknown identifier \"q\" in the default value",
    );
}

#[test]
fn expression_syntax_error_gives_text_and_column() {
    let errs = base_errors("mass: \"m\"", "mass: \"2*\"");
    let e = find(
        &errs,
        "body \"a\"",
        "mass: in expression \"2*\" at column 3",
    );
    assert!(e.message.contains("expected"), "{e}");
}

#[test]
fn unknown_parent_body() {
    let errs = base_errors("parent: \"a\"", "parent: \"zz\"");
    let e = find(&errs, "body \"b\"", "unknown body \"zz\" as parent");
    let text = BASE.replacen("parent: \"a\"", "parent: \"zz\"", 1);
    assert_eq!(e.line(), Some(line_of(&text, "\"zz\"")));
}

#[test]
fn unknown_body_in_force_and_cut_joint() {
    let errs = base_errors(
        "body2: \"b\", point2: (0, 0, 0), c",
        "body2: \"bb\", point2: (0, 0, 0), c",
    );
    find(&errs, "force \"s\"", "unknown body \"bb\" in body2");
    let errs = base_errors("body1: \"b\"", "body1: \"x\"");
    find(&errs, "cut joint \"cj\"", "unknown body \"x\" in body1");
}

#[test]
fn mass_must_be_positive() {
    let errs = base_errors("mass: 1,", "mass: -1,");
    let e = find(&errs, "body \"b\"", "mass must be positive, got -1");
    let text = BASE.replacen("mass: 1,", "mass: -1,", 1);
    assert_eq!(e.line(), Some(line_of(&text, "mass: -1")));
    // Evaluated with the default parameters.
    let errs = base_errors("\"m\": 2.0", "\"m\": 0");
    find(&errs, "body \"a\"", "mass must be positive, got 0");
}

#[test]
fn inertia_triangle_inequality() {
    let errs = base_errors(
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 1)",
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 2.5)",
    );
    find(
        &errs,
        "body \"b\"",
        "triangle inequality: ixx + iyy = 2 < izz = 2.5",
    );
    // Equality (a thin plate) is allowed.
    let ok = BASE.replacen(
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 1)",
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 2)",
        1,
    );
    load(&ok).unwrap();
}

#[test]
fn inertia_positive_definite() {
    // Diagonal entries satisfy the triangle inequality, but the principal
    // moments are 1 ± 2: not positive definite.
    let errs = base_errors(
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 1)",
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 1, ixy: 2)",
    );
    find(&errs, "body \"b\"", "not positive definite");
    let errs = base_errors(
        "mass: 1,\n            inertia: (ixx: 1, iyy: 1, izz: 1)",
        "mass: 1,\n            inertia: (ixx: 0, iyy: 0, izz: 0)",
    );
    find(&errs, "body \"b\"", "not positive definite");
}

#[test]
fn loop_in_the_body_tree() {
    let errs = base_errors("parent: \"ground\", axis: Z", "parent: \"b\", axis: Z");
    let e = errs
        .iter()
        .find(|e| e.message.contains("loop in the body tree"))
        .unwrap_or_else(|| panic!("{errs}"));
    assert!(
        e.message.contains("a -> b -> a") || e.message.contains("b -> a -> b"),
        "{e}"
    );
    find(&errs, &e.element, "loop");
    assert!(e.element == "body \"a\"" || e.element == "body \"b\"");
}

#[test]
fn duplicate_names() {
    let errs = base_errors("name: \"b\",", "name: \"a\",");
    let e = find(&errs, "body \"a\"", "duplicate body name");
    let text = BASE.replacen("name: \"b\",", "name: \"a\",", 1);
    // The second occurrence is reported.
    let second = text.rfind("name: \"a\"").unwrap();
    assert_eq!(e.line(), Some(text[..second].matches('\n').count() + 1));

    let errs = base_errors("(coord: \"qb\")", "(coord: \"qa\")");
    find(
        &errs,
        "body \"b\"",
        "duplicate coordinate name \"qa\" (also in body \"a\")",
    );

    let errs = base_errors(
        "c: \"k\"),",
        "c: \"k\"),\n        Spring(name: \"s\", body1: \"ground\", body2: \"a\", c: 1),",
    );
    let e = find(&errs, "force \"s\"", "duplicate force name");
    let text = BASE.replacen(
        "c: \"k\"),",
        "c: \"k\"),\n        Spring(name: \"s\", body1: \"ground\", body2: \"a\", c: 1),",
        1,
    );
    assert_eq!(e.line(), Some(line_of(&text, "body2: \"a\", c: 1")));

    let errs = base_errors(
        "constrain: [Tx]),",
        "constrain: [Tx]),\n        CutJoint(name: \"cj\", body1: \"a\", body2: \"ground\", constrain: [Ty]),",
    );
    find(&errs, "cut joint \"cj\"", "duplicate cut joint name");

    let errs = base_errors("\"k\": 10 }", "\"k\": 10, \"m\": 3 }");
    find(&errs, "parameter \"m\"", "duplicate parameter name");

    let errs = base_errors(
        "\"k\": 10 },",
        "\"k\": 10 },\n    macros: { \"x\": { \"m\": 1 }, \"x\": { \"m\": 2 } },",
    );
    find(&errs, "macro \"x\"", "duplicate macro name");

    let errs = base_errors(
        "\"k\": 10 },",
        "\"k\": 10 },\n    macros: { \"x\": { \"m\": 1, \"m\": 2 } },",
    );
    find(&errs, "macro \"x\"", "assigns \"m\" twice");
}

#[test]
fn non_finite_values() {
    let errs = base_errors("mass: 1,", "mass: \"1/(l-1)\",");
    find(
        &errs,
        "body \"b\"",
        "mass = \"1/(l-1)\" is not finite with the default parameters",
    );
    let errs = base_errors("\"k\": 10", "\"k\": \"ln(0)\"");
    find(&errs, "parameter \"k\"", "default value is not finite");
    let errs = base_errors("point2: (1, 0, 0)", "point2: (1, 0, 1e999)");
    find(&errs, "cut joint \"cj\"", "point2.z is not finite");
}

#[test]
fn parameter_cycles_name_the_cycle() {
    let errs = base_errors(
        "\"m\": 2.0, \"l\": 1.0, \"k\": 10",
        "\"m\": \"k/5\", \"l\": 1.0, \"k\": \"5*m\"",
    );
    let e = find(
        &errs,
        "parameter \"m\"",
        "cycle in parameter default values",
    );
    assert!(e.message.contains("m -> k -> m"), "{e}");
    let errs = base_errors("\"l\": 1.0", "\"l\": \"2*l\"");
    find(&errs, "parameter \"l\"", "l -> l");
}

#[test]
fn time_only_where_allowed() {
    let errs = base_errors("mass: \"m\"", "mass: \"m*(1+t)\"");
    find(&errs, "body \"a\"", "time t is not allowed in mass");
    let errs = base_errors("\"k\": 10", "\"k\": \"10*t\"");
    find(&errs, "parameter \"k\"", "time t is not allowed");
    let errs = base_errors("c: \"k\"", "c: \"k*t\"");
    find(&errs, "force \"s\"", "time t is not allowed in c");
    let errs = base_errors("point1: (0, 0, 0), body2", "point1: (\"t\", 0, 0), body2");
    find(
        &errs,
        "cut joint \"cj\"",
        "time t is not allowed in point1.x",
    );
    let errs = base_errors(
        "axis: Z, coord: \"qa\"",
        "axis: Z, coord: \"qa\", init: \"t\"",
    );
    find(
        &errs,
        "body \"a\"",
        "time t is not allowed in the initial value of \"qa\"",
    );
    // Allowed in elementary transforms.
    let ok = BASE.replacen("Ty(\"-l\")", "Ty(\"-l*(1 + 0.1*sin(t))\")", 1);
    load(&ok).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn cut_joint_must_constrain_something() {
    let errs = base_errors("constrain: [Tx]", "constrain: []");
    find(&errs, "cut joint \"cj\"", "constrains no component");
}

#[test]
fn reserved_and_bad_names() {
    let errs = base_errors("name: \"b\",", "name: \"ground\",");
    find(&errs, "body \"ground\"", "inertial frame");
    let errs = base_errors("\"k\": 10", "\"sin\": 10");
    find(&errs, "parameter \"sin\"", "reserved");
    let errs = base_errors("\"k\": 10", "\"t\": 10");
    find(&errs, "parameter \"t\"", "reserved");
    let errs = base_errors("\"k\": 10", "\"2k\": 10");
    find(&errs, "parameter \"2k\"", "not a valid identifier");
}

#[test]
fn joint_shorthand_errors() {
    let errs = base_errors(
        "Revolute(parent: \"ground\", axis: Z, coord: \"qa\")",
        "SixDof(parent: \"ground\", order: \"zxx\")",
    );
    find(&errs, "body \"a\"", "permutation of \"xyz\", got \"zxx\"");
}

#[test]
fn force_specific_errors() {
    let errs = base_errors(
        "c: \"k\"),",
        "c: \"k\"),\n        Linear6(name: \"l6\", body1: \"a\", body2: \"b\", stiffness: Full([1, 2, 3])),",
    );
    find(&errs, "force \"l6\"", "stiffness must have 36 values");
    let errs = base_errors(
        "c: \"k\"),",
        "c: \"k\"),\n        Applied(name: \"f\", body: \"ground\", force: (1, 0, 0)),",
    );
    find(&errs, "force \"f\"", "not on ground");
    let errs = base_errors(
        "c: \"k\"),",
        "c: \"k\"),\n        Applied(name: \"f\", body: \"nope\", force: (1, 0, 0)),",
    );
    find(&errs, "force \"f\"", "unknown body \"nope\" in body");
}

#[test]
fn all_errors_are_collected_and_sorted() {
    let text = BASE
        .replacen("mass: \"m\"", "mass: \"mm\"", 1)
        .replacen("mass: 1,", "mass: -1,", 1)
        .replacen("c: \"k\"", "c: \"kk\"", 1)
        .replacen("constrain: [Tx]", "constrain: []", 1);
    let errs = load(&text).unwrap_err();
    assert_eq!(errs.len(), 4, "{errs}");
    find(&errs, "body \"a\"", "unknown identifier \"mm\"");
    find(&errs, "body \"b\"", "mass must be positive");
    find(&errs, "force \"s\"", "unknown identifier \"kk\"");
    find(&errs, "cut joint \"cj\"", "constrains no component");
    let lines: Vec<usize> = errs.iter().map(|e| e.line().unwrap()).collect();
    assert!(lines.windows(2).all(|w| w[0] <= w[1]), "{lines:?}");
    // One error per line in the display.
    assert_eq!(errs.to_string().lines().count(), 4);
}

#[test]
fn model_level_and_macro_errors() {
    let errs = base_errors(
        "\"k\": 10 },",
        "\"k\": 10 },\n    gravity: (0, 0, \"-gg\"),",
    );
    let e = find(&errs, "", "unknown identifier \"gg\" in gravity.z");
    assert_eq!(e.line(), Some(4));
    let errs = base_errors(
        "\"k\": 10 },",
        "\"k\": 10 },\n    macros: { \"heavy\": { \"mass\": 3 } },",
    );
    let e = find(&errs, "macro \"heavy\"", "unknown parameter \"mass\"");
    assert_eq!(e.line(), Some(4));
    let errs = base_errors(
        "\"k\": 10 },",
        "\"k\": 10 },\n    macros: { \"heavy\": { \"m\": \"2*t\" } },",
    );
    find(&errs, "macro \"heavy\"", "time t is not allowed");
}

#[test]
fn cut_joint_to_itself_and_time_in_applied_point() {
    let errs = base_errors(
        "body2: \"ground\", point2: (1, 0, 0)",
        "body2: \"b\", point2: (1, 0, 0)",
    );
    find(&errs, "cut joint \"cj\"", "connects body \"b\" to itself");
    let errs = base_errors(
        "c: \"k\"),",
        "c: \"k\"),\n        Applied(name: \"f\", body: \"a\", point: (\"t\", 0, 0), force: (\"sin(t)\", 0, 0)),",
    );
    let e = find(&errs, "force \"f\"", "time t is not allowed in point.x");
    assert_eq!(errs.len(), 1, "t in force is allowed: {errs}");
    let text = BASE.replacen(
        "c: \"k\"),",
        "c: \"k\"),\n        Applied(name: \"f\", body: \"a\", point: (\"t\", 0, 0), force: (\"sin(t)\", 0, 0)),",
        1,
    );
    assert_eq!(e.line(), Some(line_of(&text, "point: (\"t\"")));
}
