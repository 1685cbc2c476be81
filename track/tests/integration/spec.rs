//! RON track descriptions build the same tracks as the constructors.

use std::path::Path;

use railmbs_track::cases::manchester_tc1;
use railmbs_track::{TrackDescription, TrackError};

const TC1_RON: &str = r#"Custom((
    sections: [
        Straight(length: 25.0),
        Transition(length: 50.0, direction: Right, radius_end: Some(150.0), cant_end: 0.1),
        Curve(length: 50.0, radius: 150.0, direction: Right, cant: 0.1),
        Transition(length: 50.0, direction: Right, radius_start: Some(150.0), cant_start: 0.1),
        Straight(length: 100.0),
    ],
    irregularities: [
        Dip(rail: Left, start: 170.0, length: 10.0, depth: 0.02, shape: Linear),
    ],
))"#;

#[test]
fn ron_description_equals_the_constructor() {
    let d: TrackDescription = ron::from_str(TC1_RON).unwrap();
    let t = d.build(Path::new(".")).unwrap();
    let c = manchester_tc1().unwrap();
    assert_eq!(t, c);
    let d: TrackDescription = ron::from_str("Case(ManchesterTc1)").unwrap();
    assert_eq!(d.build(Path::new(".")).unwrap(), c);
    let d: TrackDescription = ron::from_str("Case(ManchesterTc3(length: 1000.0))").unwrap();
    assert!(d.build(Path::new(".")).is_ok());
}

#[test]
fn bad_descriptions_name_the_problem() {
    let bad = TC1_RON.replace(
        "radius: 150.0, direction: Right, cant: 0.1",
        "radius: 140.0, direction: Right, cant: 0.1",
    );
    let d: TrackDescription = ron::from_str(&bad).unwrap();
    let e = d.build(Path::new(".")).unwrap_err();
    assert!(
        matches!(
            e,
            TrackError::Discontinuity {
                quantity: "curvature",
                before: 1,
                after: 2,
                ..
            }
        ),
        "{e}"
    );
    let d: TrackDescription =
        ron::from_str("Custom((sections: [Transition(length: 10.0, direction: Left)]))").unwrap();
    let e = d.build(Path::new(".")).unwrap_err();
    assert!(e.to_string().contains("section 0 (transition)"), "{e}");
    // Unknown fields are refused by the parser.
    assert!(
        ron::from_str::<TrackDescription>(
            "Custom((sections: [Straight(length: 1.0, lenght: 2.0)]))"
        )
        .is_err()
    );
    let d: TrackDescription = ron::from_str(
        "Custom((sections: [Straight(length: 100.0)], irregularities: [Measured(file: \"no_such.csv\")]))",
    )
    .unwrap();
    let e = d.build(Path::new("/nonexistent")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/no_such.csv"), "{e}");
}
