//! Bad study files: errors name the file, the element, line and column.

use super::{scenario, write};

/// The error text of loading `text` as `study.ron`.
fn error(text: &str) -> (String, String) {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "cases.csv", "k,zeta\n100,0.1\n120,\n");
    let path = write(dir.path(), "study.ron", text);
    let e = railmbs_study::Study::load(&path).unwrap_err().to_string();
    (e, path.display().to_string())
}

#[test]
fn bad_study_files_get_located_errors() {
    let s = scenario("spring_mass.ron");
    let cases = [
        // (study text, expected "file:line:col", expected words)
        (
            format!("Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"kk\": [1, 2] }}),\n)"),
            ":3:17",
            "neither a parameter",
        ),
        (
            format!("Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"k\": [] }}),\n)"),
            ":3:17",
            "has no values",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"k\": [1] }}),\n  time_series: true, series_format: Arrow,\n)"
            ),
            ":4:",
            "Arrow",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  engine: Fast,\n  cases: Grid({{ \"k\": [1] }}),\n)"
            ),
            ":3:",
            "Fast",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: LatinHypercube(samples: 4, seed: 1,\n    ranges: {{ \"k\": (5.0, 1.0) }}),\n)"
            ),
            ":4:15",
            "low < high",
        ),
        (
            format!("Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"@sped\": [1] }}),\n)"),
            ":3:17",
            "unknown reserved name",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: List([{{ \"k\": 1 }},\n    {{ \"m\": 2 }}]),\n)"
            ),
            ":4:5",
            "the same variables",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"k\": [1] }}),\n  reductions: [Max(column: \"z\", window: Some(Time(2.0, 1.0)))],\n)"
            ),
            ":4:",
            "from ≤ to",
        ),
        (
            format!("Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"@speed\": [10] }}),\n)"),
            ":3:17",
            "track at constant speed",
        ),
        (
            format!(
                "Study(\n  scenario: \"{}\",\n  cases: Grid({{ \"@macro\": [\"x\"] }}),\n)",
                scenario("train3_straight.ron")
            ),
            ":3:17",
            "@macro needs a single-vehicle scenario",
        ),
    ];
    for (text, position, words) in &cases {
        let (e, path) = error(text);
        assert!(
            e.contains(&format!("{path}{position}")) && e.contains(words),
            "expected {path}{position} … {words}, got: {e}"
        );
    }
}

#[test]
fn a_bad_case_table_is_located_in_the_table_and_a_missing_scenario_is_named() {
    let s = scenario("spring_mass.ron");
    let (e, path) = error(&format!(
        "Study(scenario: \"{s}\", cases: Table(\"cases.csv\"))"
    ));
    let table = path.replace("study.ron", "cases.csv");
    assert!(
        e.contains(&format!("{table}:3:1")) && e.contains("column \"zeta\": empty cell"),
        "{e}"
    );
    let (e, _) = error("Study(scenario: \"nowhere.ron\", cases: Grid({ \"k\": [1] }))");
    assert!(
        e.contains("nowhere.ron") && e.contains("cannot read"),
        "{e}"
    );
}
