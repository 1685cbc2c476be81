//! Expressions: parsing, evaluation against hand-computed values, time
//! derivatives against central differences, display round trip.

use proptest::prelude::*;
use railmbs_models::{Expr, Func, ParseErrorKind, VAR_NAMES, parse_expr, parse_expr_vars};
use std::f64::consts::PI;

fn names() -> Vec<String> {
    ["a", "b", "WS1.r0", "k_2"]
        .iter()
        .map(|s| s.to_string())
        .collect()
}

const P: [f64; 4] = [2.0, 3.0, 0.46, 0.5];

fn ev(text: &str, t: f64) -> f64 {
    parse_expr(text, &names(), true)
        .unwrap_or_else(|e| panic!("{e}"))
        .eval(&P, t)
}

#[test]
fn evaluates_hand_computed_values() {
    // Values computed by hand from a = 2, b = 3, WS1.r0 = 0.46, k_2 = 0.5.
    let cases: &[(&str, f64)] = &[
        ("1", 1.0),
        ("1.5", 1.5),
        ("1e-3", 1e-3),
        ("2.5E+2", 250.0),
        (".5", 0.5),
        ("a + b * 2", 8.0),
        ("(a + b) * 2", 10.0),
        ("a - b - 1", -2.0),
        ("a / b / 2", 2.0 / 3.0 / 2.0),
        ("2^3^2", 512.0),
        ("-a^2", -4.0),
        ("(-a)^2", 4.0),
        ("2^-1", 0.5),
        ("-2*-b", 6.0),
        ("+a", 2.0),
        ("WS1.r0*2", 0.92),
        ("k_2", 0.5),
        ("sqrt(16) + abs(-3) + exp(0) + ln(1)", 8.0),
        ("sin(pi/2) + cos(0) + tan(0) + atan(1)*4", 2.0 + PI),
        ("  a*( b -1 ) ", 4.0),
    ];
    for (text, want) in cases {
        let got = ev(text, 0.0);
        // Each case involves at most a handful of correctly rounded operations.
        assert!(
            (got - want).abs() <= 1e-14 * want.abs().max(1.0),
            "{text}: got {got}, want {want}"
        );
    }
    assert_eq!(ev("t*a", 1.5), 3.0);
}

#[test]
fn structure_of_precedence() {
    let e = parse_expr("-x^2", &["x".to_string()], false).unwrap();
    assert_eq!(
        e,
        Expr::Neg(Box::new(Expr::Pow(
            Box::new(Expr::Param(0)),
            Box::new(Expr::Num(2.0))
        )))
    );
    assert_eq!(
        parse_expr("pi", &[], false).unwrap(),
        Expr::Num(PI),
        "pi is a constant"
    );
}

#[test]
fn params_used_and_has_time() {
    let e = parse_expr("b*a + sin(b*t) + k_2", &names(), true).unwrap();
    assert_eq!(e.params_used(), vec![0, 1, 3]);
    assert!(e.has_time());
    assert!(!parse_expr("a*b", &names(), true).unwrap().has_time());
    assert!(Expr::num(0.0).is_zero());
    assert!(!Expr::num(1.0).is_zero());
    assert!(!parse_expr("0*a", &names(), false).unwrap().is_zero());
}

#[test]
fn parse_errors_give_text_column_and_expectation() {
    let e = parse_expr("a + * b", &names(), false).unwrap_err();
    assert_eq!(e.column, 5);
    let msg = e.to_string();
    assert!(msg.contains("\"a + * b\""), "{msg}");
    assert!(msg.contains("column 5"), "{msg}");
    assert!(msg.contains("expected a number, an identifier"), "{msg}");

    let e = parse_expr("(a + b", &names(), false).unwrap_err();
    assert_eq!(e.column, 7);
    assert!(e.to_string().contains("expected ')'"), "{e}");

    let e = parse_expr("2*zz", &names(), false).unwrap_err();
    assert_eq!(e.column, 3);
    assert_eq!(e.kind, ParseErrorKind::UnknownIdentifier("zz".into()));

    let e = parse_expr("a*sin(t)", &names(), false).unwrap_err();
    assert_eq!(e.kind, ParseErrorKind::TimeNotAllowed);
    assert_eq!(e.column, 7);

    for bad in [
        "", "a b", "2a", "sin a", "1e", "a.", "a +", "()", "1..2", "a)",
    ] {
        assert!(
            parse_expr(bad, &names(), true).is_err(),
            "\"{bad}\" should not parse"
        );
    }
}

/// Central difference of `e` at `t`: error O(h²·f‴); with h = 1e-5 and the
/// smooth functions below (|f‴| ≲ 10²) truncation is ~1e-8 and rounding
/// ~1e-16/1e-5 = 1e-11, so 1e-6 relative is a safe bound.
fn central_difference(e: &Expr, t: f64) -> f64 {
    let h = 1e-5;
    (e.eval(&P, t + h) - e.eval(&P, t - h)) / (2.0 * h)
}

#[test]
fn time_derivative_matches_central_differences() {
    let texts = [
        "a*t^2 + b*t + 1",
        "sin(2*pi*b*t) * exp(-t)",
        "cos(a*t)/(1 + t^2)",
        "tan(0.3*t) + sqrt(1 + t) + ln(2 + t)",
        "atan(a*t) - abs(t - 5)",
        "(1 + t)^(a*t)",
        "-(t^3)/b + 2^t",
        "WS1.r0 * a",
    ];
    for text in texts {
        let e = parse_expr(text, &names(), true).unwrap();
        let d = e.time_derivative();
        for &t in &[0.1, 0.7, 1.3, 2.9] {
            let want = central_difference(&e, t);
            let got = d.eval(&P, t);
            assert!(
                (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                "d/dt {text} at t = {t}: got {got}, central difference {want}"
            );
        }
    }
}

#[test]
fn local_variables_evaluate_and_differentiate() {
    let names = names();
    let resolve = |id: &str| names.iter().position(|n| n == id);
    let e = parse_expr_vars("a*x^2*y + sin(b*y) - x/WS1.r0", false, &VAR_NAMES, resolve).unwrap();
    assert!(e.has_vars() && !e.has_time());
    let (x, y): (f64, f64) = (0.3, -0.7);
    let want = 2.0 * x * x * y + (3.0 * y).sin() - x / 0.46;
    assert!((e.eval_vars(&P, 0.0, &[x, y]) - want).abs() < 1e-15);
    // Without the variables bound the value is NaN, never a silent number.
    assert!(e.eval(&P, 0.0).is_nan());
    for (i, exact) in [
        (0, 4.0 * x * y - 1.0 / 0.46),
        (1, 2.0 * x * x + 3.0 * (3.0 * y).cos()),
    ] {
        let d = e.var_derivative(i).eval_vars(&P, 0.0, &[x, y]);
        assert!(
            (d - exact).abs() < 1e-14,
            "d/d{}: {d} vs {exact}",
            VAR_NAMES[i]
        );
    }
    // A variable shadows a parameter of the same name; `z` is unknown.
    assert_eq!(
        parse_expr_vars("x", false, &VAR_NAMES, |_| Some(0)).unwrap(),
        Expr::Var(0)
    );
    assert!(matches!(
        parse_expr_vars("z", false, &VAR_NAMES, resolve)
            .unwrap_err()
            .kind,
        ParseErrorKind::UnknownIdentifier(_)
    ));
}

#[test]
fn time_derivative_simplifies_trivial_terms() {
    let n = names();
    let d = |s: &str| parse_expr(s, &n, true).unwrap().time_derivative();
    assert!(d("a*b + sin(a)").is_zero());
    assert_eq!(d("t"), Expr::Num(1.0));
    assert_eq!(d("a*t"), Expr::Param(0));
    assert_eq!(d("t + b"), Expr::Num(1.0));
    assert_eq!(d("-t"), Expr::Neg(Box::new(Expr::Num(1.0))));
}

#[test]
fn display_round_trips() {
    let n = names();
    for text in [
        "a - (b - 1)",
        "a/(b/2)",
        "-a^2",
        "(-a)^2",
        "2^3^2",
        "(2^3)^2",
        "a*(-b)",
        "-(-a)",
        "sin(a + t)*WS1.r0",
        "1e-7 + 0.1",
        "-(a*b)",
        "a^(-1)",
    ] {
        let e = parse_expr(text, &n, true).unwrap();
        let shown = e.display(&n);
        let back = parse_expr(&shown, &n, true).unwrap_or_else(|err| panic!("{shown}: {err}"));
        assert_eq!(back, e, "{text} displayed as {shown}");
    }
    let e = Expr::Add(Box::new(Expr::Num(-2.5)), Box::new(Expr::Num(1e300)));
    let back = parse_expr(&e.display(&n), &n, true).unwrap();
    assert_eq!(back.eval(&P, 0.0), e.eval(&P, 0.0));
}

/// A run of signs is displayed as a run of signs, not as nested
/// parentheses `-(-(…))` of twice the nesting depth, which the parser's
/// depth bound (200) refused: found by the `expr` fuzz target (fuzz/,
/// 113 signs in "1e-8-8*1e1-1e8-8*1e-8---…---8*1e1-1e8-8").
#[test]
fn a_long_run_of_signs_displays_within_the_parsers_depth_bound() {
    let n = names();
    for signs in [2, 3, 113, 190] {
        let text = format!("a - {}b*2", "-".repeat(signs));
        let e = parse_expr(&text, &n, true).unwrap_or_else(|err| panic!("{text}: {err}"));
        let shown = e.display(&n);
        let back = parse_expr(&shown, &n, true).unwrap_or_else(|err| panic!("{shown}: {err}"));
        assert_eq!(back, e, "{text} displayed as {shown}");
    }
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let deep = format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000));
    let e = parse_expr(&deep, &[], false).unwrap_err();
    assert!(e.to_string().contains("nested"), "{e}");
    let e = parse_expr(&"-".repeat(100_000), &[], false).unwrap_err();
    assert!(e.to_string().contains("nested"), "{e}");
    // Reasonable nesting is fine.
    let ok = format!("{}1{}", "(".repeat(50), ")".repeat(50));
    assert_eq!(parse_expr(&ok, &[], false).unwrap(), Expr::Num(1.0));
    // A long flat chain nests one tree level per operator: refused past 1000
    // operators (100 000 terms overflowed the stack), accepted up to it.
    for op in ["+", "*", "-", "/"] {
        let long = vec!["1"; 100_000].join(op);
        let e = parse_expr(&long, &[], false).unwrap_err().to_string();
        assert!(e.contains("at most 1000 operators"), "{op}: {e}");
        // The message quotes the text around the column, not all of it.
        assert!(
            e.len() < 400 && e.contains("(199999 characters) at column 2003"),
            "{e}"
        );
    }
    // Powers nest to the right: the nesting limit comes first.
    let e = parse_expr(&vec!["1"; 100_000].join("^"), &[], false).unwrap_err();
    assert!(e.to_string().contains("nested"), "{e}");
    let at_limit = vec!["1"; 1001].join("+");
    assert_eq!(
        parse_expr(&at_limit, &[], false).unwrap().eval(&[], 0.0),
        1001.0
    );
}

fn arb_expr() -> impl Strategy<Value = Expr> {
    let leaf = prop_oneof![
        (-1e3f64..1e3).prop_map(Expr::Num),
        (0usize..4).prop_map(Expr::Param),
        Just(Expr::Time),
    ];
    leaf.prop_recursive(5, 40, 2, |inner| {
        let b = |e: Expr| Box::new(e);
        prop_oneof![
            inner.clone().prop_map(move |a| Expr::Neg(b(a))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Expr::Add(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Expr::Sub(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Expr::Mul(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Expr::Div(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Expr::Pow(b(x), b(y))),
            (0usize..8, inner).prop_map(move |(f, x)| Expr::Call(Func::ALL[f], b(x))),
        ]
    })
}

fn same_value(x: f64, y: f64) -> bool {
    x == y || (x.is_nan() && y.is_nan())
}

proptest! {
    /// Arbitrary text never panics: it parses or gives an error with a column inside it.
    #[test]
    fn arbitrary_text_parses_or_errors(text in "[-+*/^() .0-9a-zA-Z_eE]{0,40}") {
        match parse_expr(&text, &names(), true) {
            Ok(e) => { let _ = e.eval(&P, 0.5); }
            Err(err) => prop_assert!(err.column >= 1 && err.column <= text.chars().count() + 1),
        }
    }

    #[test]
    fn random_trees_display_and_reparse_to_equal_values(e in arb_expr(), t in -3.0f64..3.0) {
        let n = names();
        let shown = e.display(&n);
        let back = parse_expr(&shown, &n, true).map_err(|err| TestCaseError::fail(format!("{shown}: {err}")))?;
        // The same operations in the same order: bitwise equal values.
        prop_assert!(same_value(back.eval(&P, t), e.eval(&P, t)), "{} -> {}", shown, back.display(&n));
    }
}
