//! Case ids: BLAKE3 of the documented canonical text, the same in every run.

use super::{load, scenario};

#[test]
fn a_case_id_is_the_blake3_of_its_documented_canonical_text() {
    let dir = tempfile::tempdir().unwrap();
    let path = scenario("wheelset_on_springs_30.ron");
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{path}", end_time: Some(0.5),
                     set: {{ "v0": "{{@speed}}" }},
                     cases: Grid({{ "@speed": [12.5], "mu": [0.3] }}))"#
        ),
    );
    // Written out by hand from the crate docs' description.
    let canonical = format!(
        "railmbs-study-case/1\nscenario={path}\nengine=symbolic\nend_time=0.5\nspeed=12.5\n\
         macros=\nparameter mu=0.3\nparameter v0=(12.5)\n"
    );
    let case = &study.cases()[0];
    assert_eq!(case.canonical(), canonical);
    let hex = blake3::hash(canonical.as_bytes()).to_hex().to_string();
    assert_eq!(case.id, hex[..16]);
    // The same file loaded again gives the same id.
    let again = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{path}", end_time: Some(0.5),
                     set: {{ "v0": "{{@speed}}" }},
                     cases: List([{{ "mu": 0.3, "@speed": 12.5 }}]))"#
        ),
    );
    assert_eq!(again.cases()[0].id, case.id);
}

#[test]
fn two_cases_that_are_the_same_run_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = super::write(
        dir.path(),
        "study.ron",
        &format!(
            r#"Study(scenario: "{}", engine: Numeric,
                     cases: List([{{ "k": 100 }}, {{ "k": 100.0 }}]))"#,
            scenario("spring_mass.ron")
        ),
    );
    let e = railmbs_study::Study::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("case 1") && e.contains("the same run as case 0"),
        "{e}"
    );
}
