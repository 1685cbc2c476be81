//! Studies of analyses: a case reduced by the runtime's analyses (least
//! damped lateral mode, linear critical speed, quasi-static curving) gives
//! the numbers of the direct calls for the same case, with or without a
//! time run, and bad analysis entries get located errors.

use super::{load, scenario, write};
use railmbs_models::Model;
use railmbs_runtime::analysis::curving::{Curve, curving};
use railmbs_runtime::analysis::speed::{critical_speed, root_locus, scenario_modes};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::RunError;
use railmbs_runtime::{Equations, NumericEquations};
use railmbs_study::{CaseOptions, CaseStatus, Study, StudyEngine, StudyScenario};

/// The cell of column `name` in a case's record.
fn cell<'a>(study: &Study, record: &'a [String], name: &str) -> &'a str {
    let k = study
        .result_header()
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no result column {name}: {:?}", study.result_header()));
    &record[k]
}

fn number(study: &Study, record: &[String], name: &str) -> f64 {
    cell(study, record, name)
        .parse()
        .unwrap_or_else(|_| panic!("{name} = {:?} is not a number", cell(study, record, name)))
}

/// The case's scenario (its overrides applied) and the study's model.
fn case_scenario(study: &Study, k: usize) -> (railmbs_models::Scenario, &Model) {
    let StudyScenario::Single(s) = study.case_scenario(&study.cases()[k]).unwrap() else {
        panic!("a single-vehicle study")
    };
    (s, &study.models[0])
}

#[test]
fn a_study_of_analyses_gives_the_direct_calls_numbers_without_a_time_run() {
    let dir = tempfile::tempdir().unwrap();
    // The wheelset on springs on the soft primary suspension of
    // wheelset_on_springs_critical.ron (0.5 MN/m lateral per axlebox; its
    // linear critical speed is about 51 m/s) at two longitudinal
    // stiffnesses, at 30 m/s.
    let study = load(
        dir.path(),
        &format!(
            r#"Study(
                scenario: "{}",
                engine: Numeric,
                set: {{ "ky": 0.5e6 }},
                cases: Grid({{ "kx": [0.4e6, 0.5e6] }}),
                reductions: [
                    LeastDamping(),
                    LinearCriticalSpeed(speeds: (40.0, 60.0, 2.5), name: Some("vcrit[m/s]")),
                    Curving(radius: 1200.0, cant: 0.05),
                ],
            )"#,
            scenario("wheelset_on_springs_30.ron")
        ),
    );
    assert!(!study.time_run(), "analyses alone run no time simulation");
    assert_eq!(study.analyses.len(), 3);
    let engine = StudyEngine::prepare(&study, None).unwrap();
    let mut vcrit = Vec::new();
    for k in 0..study.cases().len() {
        let r = engine
            .run_case(&study, &study.cases()[k], &CaseOptions::default())
            .unwrap();
        assert_eq!(r.status, CaseStatus::Ok, "{:?}", r.error);
        let rec = r.record();
        assert_eq!(number(&study, &rec, "steps"), 0.0);
        assert_eq!(number(&study, &rec, "t_end[s]"), 0.0);

        // The same analyses called directly on the case's scenario.
        let (s, model) = case_scenario(&study, k);
        let make = || Box::new(NumericEquations::new(model)) as Box<dyn Equations>;
        let one = scenario_modes(&s, model, make(), &ContactTableCache::new()).unwrap();
        let m = one.modes.least_damped_lateral().unwrap();
        assert_eq!(number(&study, &rec, "least_damping"), m.damping_ratio);
        assert_eq!(number(&study, &rec, "least_damping.f[Hz]"), m.frequency);
        assert_eq!(cell(&study, &rec, "least_damping.mode"), m.name);
        // Stable at 30 m/s, below the critical speed.
        assert!(m.damping_ratio > 0.0, "{m:?}");

        let mut fresh = || -> Result<Box<dyn Equations>, RunError> { Ok(make()) };
        let speeds: Vec<f64> = (0..9).map(|j| 40.0 + 2.5 * j as f64).collect();
        let locus = root_locus(&s, model, &speeds, &mut fresh).unwrap();
        let v = critical_speed(&locus).expect("the hunting mode goes unstable in 40–60 m/s");
        assert_eq!(number(&study, &rec, "vcrit[m/s]"), v);
        // The damping ratio changes sign across it: stable below, unstable above.
        let zeta = |v: f64| {
            let i = speeds.iter().position(|&x| x == v).unwrap();
            locus[i].modes.least_damped_lateral().unwrap().damping_ratio
        };
        let below = speeds.iter().rev().find(|&&x| x < v).copied().unwrap();
        let above = speeds.iter().find(|&&x| x > v).copied().unwrap();
        assert!(zeta(below) > 0.0 && zeta(above) < 0.0);
        vcrit.push(v);

        let c = curving(
            &s,
            model,
            &mut fresh,
            &ContactTableCache::new(),
            &Curve {
                radius: 1200.0,
                cant: 0.05,
                speed: 30.0,
            },
        )
        .unwrap();
        let w = &c.wheelsets[0];
        let yq = ["L.Y/Q [-]", "R.Y/Q [-]"]
            .map(|n| w.output(n).unwrap())
            .into_iter()
            .fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(number(&study, &rec, "curving.YQ.max"), yq);
        assert_eq!(
            number(&study, &rec, "curving.sumY.max[N]"),
            w.output("SumY [N]").unwrap().abs()
        );
        let q = ["L.Q [N]", "R.Q [N]"].map(|n| w.output(n).unwrap());
        assert_eq!(number(&study, &rec, "curving.Q.max[N]"), q[0].max(q[1]));
        assert_eq!(number(&study, &rec, "curving.Q.min[N]"), q[0].min(q[1]));
        assert_eq!(
            number(&study, &rec, "curving.y.max[m]"),
            w.lateral.unwrap().abs()
        );
        // The wheel loads carry the axle, statics by hand: normal to the
        // canted track plane (tilt φ = h/(2 e0), 2 e0 = 1.5 m) the two
        // primary springs push down with their preload plus kz (z − r0)
        // each (z the wheelset's height in the track frame; their roll
        // deflections ±b1·φx cancel), and the wheelset's weight and
        // centripetal force act with m (g cos φ + V²/R sin φ).
        let z = c.equilibrium.q[c.coordinates.iter().position(|x| x.name == "ws.z").unwrap()];
        let phi: f64 = 0.05 / 1.5;
        let axle = 2.0 * (45650.0 + 1220e3 * (z - 0.46))
            + 1813.0 * (9.81 * phi.cos() + 30.0f64.powi(2) / 1200.0 * phi.sin());
        // Left out: terms of second order in the small angles (1e-5).
        assert!(
            ((q[0] + q[1]) - axle).abs() < 1e-4 * axle,
            "{q:?} vs {axle}"
        );
    }
    // The two cases differ (the stiffness is a parameter of the analysis).
    assert_ne!(vcrit[0], vcrit[1]);
}

#[test]
fn analyses_follow_a_time_run_in_the_same_case_row() {
    let dir = tempfile::tempdir().unwrap();
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{}", engine: Numeric, end_time: Some(0.2),
                     cases: List([{{ "@speed": 30.0 }}, {{ "@speed": 35.0 }}]),
                     reductions: [Max(column: "ws.y"), LeastDamping(name: Some("hunting"))])"#,
            scenario("wheelset_on_springs_30.ron")
        ),
    );
    assert!(study.time_run());
    let header = study.result_header();
    let n = header.len();
    assert_eq!(
        &header[n - 5..],
        [
            "max(ws.y)",
            "max(ws.y).t[s]",
            "hunting",
            "hunting.f[Hz]",
            "hunting.mode"
        ]
    );
    let engine = StudyEngine::prepare(&study, None).unwrap();
    for k in 0..2 {
        let r = engine
            .run_case(&study, &study.cases()[k], &CaseOptions::default())
            .unwrap();
        assert_eq!(r.status, CaseStatus::Ok, "{:?}", r.error);
        let rec = r.record();
        assert!(number(&study, &rec, "steps") > 0.0);
        assert_eq!(number(&study, &rec, "t_end[s]"), 0.2);
        // The case's speed reaches the analysis.
        let (s, model) = case_scenario(&study, k);
        assert_eq!(s.track.as_ref().unwrap().speed, [30.0, 35.0][k]);
        let one = scenario_modes(
            &s,
            model,
            Box::new(NumericEquations::new(model)),
            &ContactTableCache::new(),
        )
        .unwrap();
        let m = one.modes.least_damped_lateral().unwrap();
        assert_eq!(number(&study, &rec, "hunting"), m.damping_ratio);
    }
}

#[test]
fn bad_analyses_get_located_errors() {
    let s = scenario("wheelset_on_springs_30.ron");
    let spring = scenario("spring_mass.ron");
    let train = scenario("train3_straight.ron");
    let cases = [
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"kx\": [1e7] }}),\n  reductions: [\n    LinearCriticalSpeed(speeds: (60.0, 40.0, 1.0)),\n  ],\n)"
            ),
            ":5:25",
            "need 0 ≤ FROM ≤ TO",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"kx\": [1e7] }}),\n  reductions: [Curving(\n    radius: 0.0)],\n)"
            ),
            ":5:5",
            "radius 0 m",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"kx\": [1e7] }}),\n  reductions: [Curving(radius: 300.0,\n    cant: -0.1)],\n)"
            ),
            ":5:5",
            "cant -0.1 m",
        ),
        (
            format!(
                "Study(\n  scenario: \"{s}\",\n  cases: Grid({{ \"kx\": [1e7] }}),\n  reductions: [Curving(radius: 300.0, radus: 2.0)],\n)"
            ),
            ":4:",
            "radus",
        ),
        (
            format!(
                "Study(\n  scenario: \"{spring}\",\n  cases: Grid({{ \"k\": [100] }}),\n  reductions: [\n    Curving(radius: 300.0)],\n)"
            ),
            ":5:13",
            "needs a vehicle on a track",
        ),
        (
            format!(
                "Study(\n  scenario: \"{train}\",\n  cases: Grid({{ \"@speed\": [30.0] }}),\n  reductions: [LeastDamping()],\n)"
            ),
            ":4:3",
            "not to a train",
        ),
    ];
    for (text, at, words) in cases {
        let dir = tempfile::tempdir().unwrap();
        let path = write(dir.path(), "study.ron", &text);
        let e = Study::load(&path).unwrap_err().to_string();
        let file = path.display().to_string();
        assert!(
            e.contains(&format!("{file}{at}")) && e.contains(words),
            "expected {file}{at} and {words:?} in:\n{e}"
        );
    }
}
