//! Runs of studies: a study's row against an independent single run,
//! failing cases, resume after an interruption or a kill, per-case files,
//! one plugin build per study.

use super::{load, scenario};
use railmbs_study::{
    CaseOptions, CaseStatus, PoolOptions, ResultStore, Study, StudyEngine, run_local,
};
use railmbs_testkit::plugin_cache_dir;
use std::path::Path;

/// The cell of column `name` in a result record.
fn cell<'a>(study: &Study, record: &'a [String], name: &str) -> &'a str {
    let k = study
        .result_header()
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no result column {name}"));
    &record[k]
}

fn number(study: &Study, record: &[String], name: &str) -> f64 {
    cell(study, record, name)
        .parse()
        .unwrap_or_else(|_| panic!("{name} is not a number"))
}

/// The result table's rows (after the header).
fn rows(path: &Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    r.records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect()
}

#[test]
fn a_study_row_equals_the_reductions_of_a_single_run_of_the_same_case() {
    let dir = tempfile::tempdir().unwrap();
    let path = scenario("wheelset_on_springs_30.ron");
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{path}", end_time: Some(0.6),
                     cases: Grid({{ "mu": [0.3, 0.45] }}),
                     reductions: [Assessment,
                                  Max(column: "contact.L.Y [N]"),
                                  Rms(column: "ws.y", window: Some(Distance(12.0, 20.0))),
                                  MaxAbs(column: "contact.*.Fy [N]")],
                     time_series: true)"#
        ),
    );
    let engine = StudyEngine::prepare(&study, Some(plugin_cache_dir())).unwrap();
    let series = dir.path().join("series");
    let options = CaseOptions {
        series_dir: Some(series.clone()),
        stop: None,
    };
    let case = &study.cases()[1];
    let result = engine.run_case(&study, case, &options).unwrap();
    assert_eq!(result.status, CaseStatus::Ok, "{:?}", result.error);
    let record = result.record();

    // The same case as `umsim run --set mu=0.45 --end-time 0.6` does it.
    let mut scenario = railmbs_models::load_scenario(Path::new(&path)).unwrap();
    scenario.set_parameter("mu", "0.45");
    scenario.set_end_time(0.6).unwrap();
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let csv = dir.path().join("single.csv");
    let equations = Box::new(railmbs_testkit::symbolic_engine(&model));
    let summary =
        railmbs_runtime::run::run_scenario(&scenario, &model, equations, Some(&csv), |_| {})
            .unwrap();
    assert!(summary.error.is_none());
    // The study's time series is that run's output, byte for byte.
    let single = std::fs::read(&csv).unwrap();
    assert_eq!(
        std::fs::read(series.join(format!("{}.csv", case.id))).unwrap(),
        single
    );

    // Reductions computed here from the CSV.
    let table = railmbs_testkit::Table::read(&csv);
    let (t, s) = (table.col("time"), table.col("s[m]"));
    let y = table.col("contact.L.Y [N]");
    let k = (0..y.len()).max_by(|&a, &b| y[a].total_cmp(&y[b])).unwrap();
    assert_eq!(number(&study, &record, "max(contact.L.Y [N])"), y[k]);
    assert_eq!(number(&study, &record, "max(contact.L.Y [N]).t[s]"), t[k]);
    let ws_y = table.col("ws.y");
    let inside: Vec<f64> = (0..t.len())
        .filter(|&k| (12.0..=20.0).contains(&s[k]))
        .map(|k| ws_y[k])
        .collect();
    assert!(inside.len() > 10);
    let rms = (inside.iter().map(|x| x * x).sum::<f64>() / inside.len() as f64).sqrt();
    // The same sum in another order: a few roundings.
    let got = number(&study, &record, "rms(ws.y; s 12..20 m)");
    assert!((got - rms).abs() <= 1e-12 * rms, "{got} against {rms}");
    let (fl, fr) = (table.col("contact.L.Fy [N]"), table.col("contact.R.Fy [N]"));
    let (l, r) = (
        fl.iter().fold(0.0f64, |m, x| m.max(x.abs())),
        fr.iter().fold(0.0f64, |m, x| m.max(x.abs())),
    );
    assert_eq!(
        number(&study, &record, "maxabs(contact.*.Fy [N])"),
        l.max(r)
    );
    let side = if l >= r {
        "contact.L.Fy [N]"
    } else {
        "contact.R.Fy [N]"
    };
    assert_eq!(
        cell(&study, &record, "maxabs(contact.*.Fy [N]).column"),
        side
    );

    // The assessment is the run's own table: its largest judged Y/Q.
    let judged = summary
        .assessment
        .iter()
        .filter(|a| a.quantity.starts_with("Y/Q") && a.limit.is_some())
        .max_by(|a, b| a.max.total_cmp(&b.max))
        .unwrap();
    assert_eq!(number(&study, &record, "YQ.max"), judged.max);
    assert_eq!(number(&study, &record, "YQ.limit"), judged.limit.unwrap());
    assert_eq!(number(&study, &record, "YQ.t[s]"), judged.time);
    let q_min = summary
        .assessment
        .iter()
        .filter(|a| a.quantity.starts_with("Q ") && a.quantity.ends_with(" min"))
        .map(|a| a.max)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(number(&study, &record, "Q.min[N]"), q_min);
    assert_eq!(number(&study, &record, "steps"), summary.steps as f64);
}

/// A numeric spring–mass study of `cases` (a `cases:` value), 2 s each.
fn spring_mass(dir: &Path, cases: &str) -> Study {
    load(
        dir,
        &format!(
            r#"Study(scenario: "{}", engine: Numeric, end_time: Some(2.0), cases: {cases},
                     reductions: [Max(column: "z"), Min(column: "z")])"#,
            scenario("spring_mass.ron")
        ),
    )
}

#[test]
fn a_diverging_case_is_recorded_with_its_error_and_the_study_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    // Damping ratio −50: the motion grows like e^(1000 t) and overflows.
    let study = spring_mass(
        dir.path(),
        r#"List([{ "zeta": 0.1 }, { "zeta": -50 }, { "zeta": 0.2 }])"#,
    );
    let engine = StudyEngine::prepare(&study, None).unwrap();
    let table = dir.path().join("out/results.csv");
    let mut store = ResultStore::open(&table, study.result_header()).unwrap();
    let options = PoolOptions {
        jobs: 2,
        ..PoolOptions::default()
    };
    let summary = run_local(&study, &engine, &mut store, &options, |_| {}).unwrap();
    assert_eq!((summary.recorded, summary.failed), (3, 1));
    let mut rows = rows(&table);
    rows.sort_by_key(|r| r[0].parse::<usize>().unwrap());
    assert_eq!(rows.len(), 3);
    for (k, r) in rows.iter().enumerate() {
        let status = cell(&study, r, "status");
        if k == 1 {
            assert_eq!(status, "failed");
            assert!(!cell(&study, r, "error").is_empty());
            assert_eq!(
                cell(&study, r, "max(z)"),
                "",
                "a failed case has no reductions"
            );
        } else {
            assert_eq!(status, "ok", "{}", cell(&study, r, "error"));
            assert!(number(&study, r, "max(z)") > number(&study, r, "min(z)"));
            assert_eq!(number(&study, r, "t_end[s]"), 2.0);
        }
    }
}

#[test]
fn a_study_resumes_skipping_finished_cases_and_survives_a_cut_last_line() {
    let dir = tempfile::tempdir().unwrap();
    let study = spring_mass(dir.path(), r#"Grid({ "k": [100, 150, 200, 250] })"#);
    let engine = StudyEngine::prepare(&study, None).unwrap();
    let table = dir.path().join("results.csv");
    let run = |expect_skipped: usize| {
        let mut store = ResultStore::open(&table, study.result_header()).unwrap();
        let mut ran = 0;
        let s = run_local(&study, &engine, &mut store, &PoolOptions::default(), |_| {
            ran += 1
        })
        .unwrap();
        assert_eq!(s.skipped, expect_skipped);
        assert_eq!(s.recorded, ran);
        (ran, store.dropped_partial_line())
    };
    assert_eq!(run(0), (4, false));
    assert_eq!(run(4), (0, false), "a second run runs nothing");
    // A kill while the last row was written: half of it is on disk.
    let text = std::fs::read_to_string(&table).unwrap();
    let last = text.trim_end().rfind('\n').unwrap() + 1;
    let cut = last + (text.len() - last) / 2;
    std::fs::write(&table, &text[..cut]).unwrap();
    assert_eq!(run(3), (1, true));
    let rows = rows(&table);
    assert_eq!(rows.len(), 4);
    let mut ids: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    ids.sort();
    let mut want: Vec<&str> = study.cases().iter().map(|c| c.id.as_str()).collect();
    want.sort();
    assert_eq!(ids, want);
    // The rewritten row equals the one cut (same run, same numbers).
    let full: Vec<Vec<String>> = {
        let mut r = csv::Reader::from_reader(text.as_bytes());
        r.records()
            .map(|x| x.unwrap().iter().map(String::from).collect())
            .collect()
    };
    let old = full.iter().find(|r| r[1] == rows[3][1]).unwrap();
    assert_eq!(
        cell(&study, old, "max(z)"),
        cell(&study, &rows[3], "max(z)")
    );
}

#[test]
fn per_case_files_are_collected_into_the_table_once() {
    let dir = tempfile::tempdir().unwrap();
    let study = spring_mass(dir.path(), r#"Grid({ "k": [100, 200, 300] })"#);
    let engine = StudyEngine::prepare(&study, None).unwrap();
    let out = dir.path().join("out");
    for case in study.cases().iter().rev() {
        let r = engine
            .run_case(&study, case, &CaseOptions::default())
            .unwrap();
        railmbs_study::write_case_file(&study, &out, &r).unwrap();
    }
    let mut store = ResultStore::open(&out.join("results.csv"), study.result_header()).unwrap();
    assert_eq!(
        railmbs_study::collect_case_files(&study, &out, &mut store).unwrap(),
        3
    );
    assert_eq!(
        railmbs_study::collect_case_files(&study, &out, &mut store).unwrap(),
        0
    );
    let rows = rows(&out.join("results.csv"));
    let index: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(index, ["0", "1", "2"], "in case order");
}

#[test]
fn a_symbolic_study_builds_its_plugin_once_for_all_cases() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{}", end_time: Some(1.0),
                     cases: Grid({{ "k": [100, 200], "m": [1, 2] }}),
                     reductions: [Max(column: "z")])"#,
            scenario("spring_mass.ron")
        ),
    );
    let engine = StudyEngine::prepare(&study, Some(cache.clone())).unwrap();
    let table = dir.path().join("results.csv");
    let mut store = ResultStore::open(&table, study.result_header()).unwrap();
    let s = run_local(&study, &engine, &mut store, &PoolOptions::default(), |_| {}).unwrap();
    assert_eq!((s.recorded, s.failed), (4, 0));
    let b = engine.builds();
    assert_eq!((b.derived, b.indexed, b.compiled, b.loaded), (1, 0, 1, 1));
    // One library in the fresh cache.
    fn libraries(dir: &Path) -> usize {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .map(|p| {
                if p.is_dir() {
                    libraries(&p)
                } else {
                    let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
                    usize::from(matches!(ext, "so" | "dylib" | "dll"))
                }
            })
            .sum()
    }
    assert_eq!(libraries(&cache), 1);
    // A second engine (a worker) finds it through the plugin index: nothing
    // derived, nothing compiled.
    let worker = StudyEngine::prepare(&study, Some(cache.clone())).unwrap();
    let w = worker.builds();
    assert_eq!((w.derived, w.indexed, w.compiled, w.loaded), (0, 1, 0, 1));
    let shipped = StudyEngine::from_plugins(&study, &engine.plugin_paths()).unwrap();
    assert_eq!(shipped.builds().derived, 0);
    let case = &study.cases()[3];
    let a = engine
        .run_case(&study, case, &CaseOptions::default())
        .unwrap();
    let b = shipped
        .run_case(&study, case, &CaseOptions::default())
        .unwrap();
    assert_eq!(a.values, b.values);
}

#[test]
fn a_train_study_builds_one_plugin_for_its_identical_vehicles_and_matches_a_train_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = scenario("train3_straight.ron");
    let study = load(
        dir.path(),
        &format!(
            r#"Study(scenario: "{path}", end_time: Some(0.2),
                     cases: Grid({{ "mu": [0.3, 0.35] }}),
                     reductions: [Max(column: "Coach3.Bogie1.WS1.contact.L.Y [N]"), Assessment])"#
        ),
    );
    assert_eq!(
        (study.models.len(), study.vehicle_models.as_slice()),
        (1, &[0, 0, 0][..])
    );
    let engine = StudyEngine::prepare(&study, Some(plugin_cache_dir())).unwrap();
    let b = engine.builds();
    assert_eq!(b.derived + b.indexed, 1, "one model file, one plugin");
    let result = engine
        .run_case(&study, &study.cases()[1], &CaseOptions::default())
        .unwrap();
    assert_eq!(result.status, CaseStatus::Ok, "{:?}", result.error);
    let record = result.record();

    // The same case as `umsim run train3_straight.ron --set mu=0.35 --end-time 0.2`.
    let mut train = railmbs_models::load_train(Path::new(&path)).unwrap();
    train.set_parameter("mu", "0.35");
    train.set_end_time(0.2).unwrap();
    let model = railmbs_models::load_model(&train.vehicles[0].model).unwrap();
    let engines: Vec<Box<dyn railmbs_runtime::Equations>> = (0..3)
        .map(|_| {
            Box::new(railmbs_testkit::symbolic_engine(&model))
                as Box<dyn railmbs_runtime::Equations>
        })
        .collect();
    let mut table = railmbs_runtime::run::Table::new();
    let summary =
        railmbs_runtime::train::run_train_into(&train, &[&model; 3], engines, &mut table, |_| {})
            .unwrap();
    assert!(summary.error.is_none());
    let y = table.column("Coach3.Bogie1.WS1.contact.L.Y [N]").unwrap();
    let max = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(
        number(&study, &record, "max(Coach3.Bogie1.WS1.contact.L.Y [N])"),
        max
    );
    assert_eq!(number(&study, &record, "assessment.wheelsets"), 12.0);

    // The train's cases share the engine's contact tables: the 12 wheelsets
    // (one profile pair on one track) built one table in the first case, and
    // the next cases build none (the cache holds each table it built once)
    // and give the same numbers as a run that built its own.
    assert_eq!(engine.contact_tables(), 1);
    let other = engine
        .run_case(&study, &study.cases()[0], &CaseOptions::default())
        .unwrap();
    assert_eq!(other.status, CaseStatus::Ok, "{:?}", other.error);
    let again = engine
        .run_case(&study, &study.cases()[1], &CaseOptions::default())
        .unwrap();
    assert_eq!(engine.contact_tables(), 1, "no table built again");
    assert_eq!(again.values, result.values);
}

/// The values of a CSV time series, by column, parsed (Rust's shortest
/// round-trip text: parsing gives back the written `f64` exactly).
fn csv_columns(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let mut cols = vec![Vec::new(); header.len()];
    for rec in r.records() {
        for (c, x) in cols.iter_mut().zip(rec.unwrap().iter()) {
            c.push(x.parse::<f64>().unwrap());
        }
    }
    (header, cols)
}

#[test]
fn a_parquet_time_series_read_back_equals_the_csv_time_series_bit_for_bit() {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::Field;
    let dir = tempfile::tempdir().unwrap();
    // 90 s at 0.01 s: 9001 rows, more than one row group (8192 rows).
    let study_of = |sub: &str, format: &str| {
        let d = dir.path().join(sub);
        std::fs::create_dir_all(&d).unwrap();
        load(
            &d,
            &format!(
                r#"Study(scenario: "{}", engine: Numeric, end_time: Some(90.0),
                         cases: List([{{ "zeta": 0.05 }}]), reductions: [Max(column: "z")],
                         time_series: true, series_format: {format})"#,
                scenario("spring_mass.ron")
            ),
        )
    };
    let (csv_study, pq_study) = (study_of("csv", "Csv"), study_of("pq", "Parquet"));
    let run = |study: &Study| {
        let engine = StudyEngine::prepare(study, None).unwrap();
        let options = CaseOptions {
            series_dir: Some(study.source.parent().unwrap().join("series")),
            stop: None,
        };
        let case = &study.cases()[0];
        let r = engine.run_case(study, case, &options).unwrap();
        assert_eq!(r.status, CaseStatus::Ok, "{:?}", r.error);
        options.series_dir.unwrap()
    };
    let id = &csv_study.cases()[0].id;
    assert_eq!(id, &pq_study.cases()[0].id, "the format is not an input");
    let (header, cols) = csv_columns(&run(&csv_study).join(format!("{id}.csv")));
    assert_eq!(cols[0].len(), 9001);
    let pq_dir = run(&pq_study);
    assert!(!pq_dir.join(format!("{id}.parquet.partial")).exists());
    let reader = SerializedFileReader::new(
        std::fs::File::open(pq_dir.join(format!("{id}.parquet"))).unwrap(),
    )
    .unwrap();
    let meta = reader.metadata();
    assert_eq!(meta.num_row_groups(), 2);
    assert_eq!(meta.file_metadata().num_rows(), 9001);
    let names: Vec<String> = meta
        .file_metadata()
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    assert_eq!(names, header);
    let mut got = vec![Vec::new(); header.len()];
    for row in reader.get_row_iter(None).unwrap() {
        for (k, (_, field)) in row.unwrap().get_column_iter().enumerate() {
            let Field::Double(x) = field else {
                panic!("column {k} is not DOUBLE: {field:?}")
            };
            got[k].push(*x);
        }
    }
    for (k, (a, b)) in got.iter().zip(&cols).enumerate() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(a), bits(b), "column {}", header[k]);
    }
}
