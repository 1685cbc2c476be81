//! General train couplers (any force element of the model language between
//! bodies of different vehicles), couplers with their own bodies (the
//! automatic couplings of `train3_sa3_tc1.ron`) and the parallel evaluation
//! of a train's vehicles (`railmbs_runtime::train`; Pogorelov 2005, Sect. 5).

use railmbs_models::{Model, TrainScenario, load_model, parse_train};
use railmbs_runtime::train::run_train;
use railmbs_runtime::{Equations, NumericEquations};
use railmbs_testkit::*;
use std::path::Path;

fn numeric(model: &Model) -> Box<dyn Equations> {
    Box::new(NumericEquations::new(model))
}

/// Runs `train` with the numeric engine, writing the CSV to `out`.
fn run(train: &TrainScenario, out: &Path) -> Table {
    let models: Vec<Model> = train
        .vehicles
        .iter()
        .map(|v| load_model(&v.model).unwrap())
        .collect();
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(numeric).collect();
    let summary = run_train(train, &refs, engines, Some(out), |_| {}).unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    Table::read(out)
}

/// The text of the bundled train file `name` with absolute paths, written
/// to `dir/<file>` and read there.
pub(crate) fn bundled_text(name: &str) -> String {
    std::fs::read_to_string(model_path(&format!("scenarios/{name}")))
        .unwrap()
        .replace(
            "\"../vehicles/",
            &format!("\"{}/", model_path("vehicles").display()),
        )
        .replace(
            "\"../tracks/",
            &format!("\"{}/", model_path("tracks").display()),
        )
}

/// `text` written to `dir/file` and read as a train.
pub(crate) fn train_at(dir: &Path, file: &str, text: &str) -> TrainScenario {
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    parse_train(text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// `Coupler(...)` of train3_straight.ron as the model language's `Linear6`.
fn as_linear6(text: &str) -> String {
    let mut out = text.to_string();
    for (a, b) in [("C12", "Coach1", "Coach2"), ("C23", "Coach2", "Coach3")]
        .map(|(n, a, b)| (format!("Coupler(name: \"{n}\", body1: \"{a}.body\", point1: (-13.0, 0.0, -0.75),\n                body2: \"{b}.body\", point2: (13.0, 0.0, -0.75),\n                stiffness: (2e6, 2e4, 1e5), damping: (2e4, 5e3, 5e3)),"),
                            format!("Linear6(name: \"{n}\", body1: \"{a}.body\", point1: (-13.0, 0.0, -0.75),\n                body2: \"{b}.body\", point2: (13.0, 0.0, -0.75),\n                stiffness: Diag((2e6, 2e4, 1e5, 0, 0, 0)), damping: Diag((2e4, 5e3, 5e3, 0, 0, 0))),")))
    {
        assert!(out.contains(&a), "train3_straight.ron changed");
        out = out.replace(&a, &b);
    }
    out
}

/// The bundled three-coach train with its `Coupler(...)` couplers written as
/// the model language's `Linear6` elements (the same points, stiffness and
/// damping) runs to the same bytes: both are one element type, one home.
#[test]
fn a_linear6_coupler_element_runs_like_the_coupler_syntax() {
    let dir = tempfile::tempdir().unwrap();
    let text = bundled_text("train3_straight.ron");
    let mut plain = train_at(dir.path(), "plain.ron", &text);
    let mut general = train_at(dir.path(), "general.ron", &as_linear6(&text));
    assert_eq!((general.couplers.len(), general.elements.len()), (0, 2));
    plain.end_time = 0.3;
    general.end_time = 0.3;
    let (a, b) = (dir.path().join("plain.csv"), dir.path().join("general.csv"));
    run(&plain, &a);
    run(&general, &b);
    assert!(
        std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
        "the CSVs differ"
    );
}

/// The vehicles evaluated in 2 or 3 threads give the same CSV bytes as the
/// sequential run: the bundled linear-coupler train and the train with
/// automatic couplings (five vehicles, friction contacts with stick).
#[test]
fn parallel_vehicles_give_the_bytes_of_the_sequential_run() {
    let dir = tempfile::tempdir().unwrap();
    for (file, end) in [("train3_straight.ron", 0.3), ("train3_sa3_tc1.ron", 0.3)] {
        let mut train = train_at(dir.path(), file, &bundled_text(file));
        train.end_time = end;
        let mut csv = Vec::new();
        for threads in [1, 2, 3] {
            train.threads = threads;
            let out = dir.path().join(format!("{file}.{threads}.csv"));
            run(&train, &out);
            csv.push(std::fs::read(&out).unwrap());
        }
        assert!(
            csv[0] == csv[1] && csv[0] == csv[2],
            "{file}: the CSVs differ"
        );
    }
}

/// Draft gear `LoadFriction` (Pogorelov 2005, Sect. 3.1, Fig. 3): a spring
/// c1 in series with a spring c2 parallel to friction μ·|c2 x2|. Sliding,
/// F = c1 a x / (c1 + a) with a = c2 (1 ± μ) (+ loading, − unloading);
/// sticking, F = c1 (x − x2) with c2 |x2| (1 − μ) ≤ |F| ≤ c2 |x2| (1 + μ),
/// which keeps (x, F) between the two sliding lines.
fn draft_gear_branches(x: f64) -> (f64, f64) {
    let (c1, c2, mu) = (1e8, 6e6, 0.6);
    let line = |a: f64| c1 * a * x / (c1 + a);
    let (lo, hi) = (line(c2 * (1.0 - mu)), line(c2 * (1.0 + mu)));
    (lo.min(hi), lo.max(hi))
}

/// The three coaches with automatic couplings in the track-case-1 curve,
/// braked at the last coach (`train3_sa3_tc1.ron`, numeric engine):
/// * the coupling transmits the force (action and reaction): the draft
///   gears on both sides of a coupling and the pulling contour contact
///   carry the same force, up to the inertia of the 200 kg coupler bodies;
/// * every draft gear's (x, F) lies between its loading and unloading lines
///   (the hysteresis of its characteristic), and the run loads and unloads
///   it along both (sliding) lines.
#[test]
fn automatic_couplings_transmit_the_braking_force_with_draft_gear_hysteresis() {
    let dir = tempfile::tempdir().unwrap();
    let file = "train3_sa3_tc1.ron";
    let train = train_at(dir.path(), file, &bundled_text(file));
    let t = run(&train, &dir.path().join("out.csv"));
    for k in ["K12", "K23"] {
        let f1 = t.col(&format!("{k}.DraftGear1.F[N]"));
        let f2 = t.col(&format!("{k}.DraftGear2.F[N]"));
        let pull: Vec<f64> = (0..t.rows.len())
            .map(|i| t.col(&format!("{k}.Pull.0.N[N]"))[i] + t.col(&format!("{k}.Pull.1.N[N]"))[i])
            .collect();
        let peak = f1.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        assert!(
            peak > 1e4,
            "{k}: the coupling should carry the braking force: {peak}"
        );
        for i in 0..f1.len() {
            // The two 200 kg coupler bodies at up to 2.5 m/s².
            let tol = 1e3;
            assert!(
                (f1[i] - f2[i]).abs() < tol,
                "{k} row {i}: {} vs {}",
                f1[i],
                f2[i]
            );
            if f1[i] > 5e3 {
                assert!(
                    (f1[i] - pull[i]).abs() < tol,
                    "{k} row {i}: {} vs pull {}",
                    f1[i],
                    pull[i]
                );
            }
        }
        for side in ["DraftGear1", "DraftGear2"] {
            let x = t.col(&format!("{k}.{side}.x[m]"));
            let f = t.col(&format!("{k}.{side}.F[N]"));
            let sliding = t.col(&format!("{k}.{side}.sliding[-]"));
            let (mut on_loading, mut on_unloading) = (0, 0);
            for i in 0..x.len() {
                let (lo, hi) = draft_gear_branches(x[i]);
                let tol = 1e-6 * hi.abs().max(1.0) + 1.0;
                assert!(
                    f[i] >= lo - tol && f[i] <= hi + tol,
                    "{k}.{side} row {i}: F = {} outside [{lo}, {hi}] at x = {}",
                    f[i],
                    x[i]
                );
                if sliding[i] == 1.0 && x[i] > 1e-3 {
                    if (f[i] - hi).abs() <= tol {
                        on_loading += 1;
                    } else if (f[i] - lo).abs() <= tol {
                        on_unloading += 1;
                    }
                }
            }
            assert!(
                on_loading > 5 && on_unloading > 5,
                "{k}.{side}: {on_loading} rows on the loading line, {on_unloading} on the unloading line"
            );
        }
    }
}

/// Errors in a general coupler name the train file, the element and the
/// position: an unknown body, a bad value (the element's own range check),
/// an element within one vehicle.
#[test]
fn general_coupler_errors_name_the_element_and_position() {
    let dir = tempfile::tempdir().unwrap();
    let car = model_path("vehicles/train/track_car.ron")
        .display()
        .to_string();
    let track = model_path("tracks/straight.ron").display().to_string();
    let text = |element: &str| {
        format!(
            r#"Train(
    vehicles: [
        Vehicle(name: "A", model: "{car}"),
        Vehicle(name: "B", model: "{car}", offset: -10.0),
    ],
    couplers: [
        {element},
    ],
    track: (file: "{track}", start: 100.0, speed: 10.0),
    end_time: 1.0,
    integrator: Rk4(step: 0.001),
    output: (interval: 0.1),
)"#
        )
    };
    let build = |element: &str| {
        let path = dir.path().join("bad.ron");
        let text = text(element);
        std::fs::write(&path, &text).unwrap();
        let train = parse_train(&text, &path).unwrap_or_else(|e| panic!("{e}"));
        let model = load_model(&train.vehicles[0].model).unwrap();
        let engines = vec![numeric(&model), numeric(&model)];
        railmbs_runtime::train::build_train(&train, &[&model, &model], engines)
            .err()
            .expect("an error")
            .to_string()
    };
    let e = build(r#"Spring(name: "S", body1: "A.body", body2: "B.bdy", c: 1e5)"#);
    assert!(e.contains("bad.ron:7:"), "{e}");
    assert!(e.contains("force \"S\""), "{e}");
    assert!(e.contains("unknown body \"B.bdy\""), "{e}");
    let e = build(r#"SeriesSpring(name: "S", body1: "A.body", body2: "B.body", c: -1e5, d: 1e3)"#);
    assert!(e.contains("bad.ron:7:"), "{e}");
    assert!(e.contains("c must be positive"), "{e}");
    let e =
        build(r#"Spring(name: "S", body1: "A.body", body2: "A.body", point2: (1, 0, 0), c: 1e5)"#);
    assert!(e.contains("bad.ron:7:"), "{e}");
    assert!(e.contains("belong to vehicle \"A\""), "{e}");
    let e = build(r#"SeriesSpring(name: "S", body1: "A.body", body2: "B.body", c: 1e5, d: 1e3)"#);
    assert!(
        e.contains("bad.ron:7:") && e.contains("first-order state"),
        "{e}"
    );
    // An unknown constructor lists the coupler syntax too.
    let path = dir.path().join("bad2.ron");
    let e = parse_train(&text(r#"Sprung(name: "S")"#), &path)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bad2.ron:7:") && e.contains("Coupler") && e.contains("Spring"),
        "{e}"
    );
}
