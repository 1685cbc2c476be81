//! Cases from grids, lists, CSV tables and Latin hypercubes.

use super::{load, scenario, write};
use railmbs_models::syntax::Value;

fn numbers(case: &railmbs_study::Case) -> Vec<f64> {
    case.inputs
        .iter()
        .map(|v| match v {
            Value::Num(x) => *x,
            Value::Text(t) => panic!("not a number: {t}"),
        })
        .collect()
}

#[test]
fn a_grid_is_every_combination_with_the_last_variable_fastest() {
    let dir = tempfile::tempdir().unwrap();
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{}", engine: Numeric,
                     cases: Grid({{ "k": [100, 200], "m": [1, 2, 3] }}))"#,
            scenario("spring_mass.ron")
        ),
    );
    assert_eq!(study.variables, ["k", "m"]);
    let got: Vec<Vec<f64>> = study.cases().iter().map(numbers).collect();
    let want = [
        [100., 1.],
        [100., 2.],
        [100., 3.],
        [200., 1.],
        [200., 2.],
        [200., 3.],
    ];
    assert_eq!(got, want.map(|r| r.to_vec()));
    for (k, c) in study.cases().iter().enumerate() {
        assert_eq!(c.index, k);
        assert_eq!(
            c.overrides.parameters,
            [
                ("k".to_string(), format!("{}", want[k][0])),
                ("m".to_string(), format!("{}", want[k][1]))
            ]
        );
    }
}

#[test]
fn a_list_keeps_its_cases_and_a_table_reads_numbers_and_expressions() {
    let dir = tempfile::tempdir().unwrap();
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{}", engine: Numeric,
                     cases: List([{{ "k": 150, "zeta": 0.2 }}, {{ "zeta": 0.05, "k": "2*m*100" }}]))"#,
            scenario("spring_mass.ron")
        ),
    );
    assert_eq!(study.cases().len(), 2);
    assert_eq!(study.cases()[0].input_texts(), ["150", "0.2"]);
    assert_eq!(study.cases()[1].input_texts(), ["2*m*100", "0.05"]);

    write(dir.path(), "cases.csv", "k,zeta\n150,0.2\n2*m*100,0.05\n");
    let table = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{}", engine: Numeric, cases: Table("cases.csv"))"#,
            scenario("spring_mass.ron")
        ),
    );
    // The same runs, hence the same ids, whichever way they are written.
    let ids = |s: &railmbs_study::Study| s.cases().iter().map(|c| c.id.clone()).collect::<Vec<_>>();
    assert_eq!(ids(&table), ids(&study));
    assert_eq!(table.cases()[1].inputs[0], Value::Text("2*m*100".into()));
}

#[test]
fn a_latin_hypercube_has_one_sample_in_every_stratum_of_every_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = |seed: u64| {
        format!(
            r#"Study(scenario: "{}", engine: Numeric,
                     cases: LatinHypercube(samples: 20, seed: {seed},
                         ranges: {{ "k": (50.0, 250.0), "m": (0.5, 1.5), "zeta": (0.01, 0.3) }}))"#,
            scenario("spring_mass.ron")
        )
    };
    let study = load(dir.path(), &text(7));
    let n = 20;
    assert_eq!(study.cases().len(), n);
    let ranges = [(50.0, 250.0), (0.5, 1.5), (0.01, 0.3)];
    for (d, (lo, hi)) in ranges.iter().enumerate() {
        let mut hits = vec![0; n];
        for c in study.cases() {
            let x = numbers(c)[d];
            assert!((*lo..*hi).contains(&x), "{x} outside ({lo}, {hi})");
            let stratum = ((x - lo) / (hi - lo) * n as f64).floor() as usize;
            hits[stratum] += 1;
        }
        assert_eq!(hits, vec![1; n], "variable {d}: samples per stratum");
    }
    // Not the identity pairing of strata (a permutation per variable).
    let strata = |d: usize| -> Vec<usize> {
        let (lo, hi) = ranges[d];
        study
            .cases()
            .iter()
            .map(|c| ((numbers(c)[d] - lo) / (hi - lo) * n as f64) as usize)
            .collect()
    };
    assert_ne!(strata(0), strata(1));
    // The seed fixes the cases; another seed gives others.
    let again = load(dir.path(), &text(7));
    assert_eq!(again.cases(), study.cases());
    let other = load(dir.path(), &text(8));
    assert_ne!(numbers(&other.cases()[0]), numbers(&study.cases()[0]));
}

#[test]
fn the_crate_docs_example_study_loads_with_the_cases_it_describes() {
    let docs = std::fs::read_to_string(railmbs_testkit::repo_path("study/src/lib.rs")).unwrap();
    let start = docs.find("//! ```ron\n").unwrap() + "//! ```ron\n".len();
    let end = start + docs[start..].find("//! ```\n").unwrap();
    let text: String = docs[start..end]
        .lines()
        .map(|l| {
            l.strip_prefix("//!")
                .unwrap_or(l)
                .strip_prefix(' ')
                .unwrap_or("")
        })
        .map(|l| format!("{l}\n"))
        .collect();
    // As if it were a file of models/studies (its scenario path is relative).
    let path = railmbs_testkit::model_path("studies/docs_example.ron");
    let study = railmbs_study::Study::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(study.cases().len(), 4);
    let c = &study.cases()[1];
    assert_eq!(c.input_texts(), ["15000000", "6"]);
    assert_eq!(c.overrides.speed, Some(6.0));
    assert_eq!(c.overrides.end_time, Some(3.0));
    let set: Vec<(&str, &str)> = c
        .overrides
        .parameters
        .iter()
        .map(|(a, b)| (a.as_str(), b.as_str()))
        .collect();
    assert_eq!(
        set,
        [
            ("Bogie1.kx", "(15000000)"),
            ("Bogie2.kx", "(15000000)"),
            ("v0", "(6)")
        ]
    );
    assert_eq!(study.reductions.len(), 3);
}
