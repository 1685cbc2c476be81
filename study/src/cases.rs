//! The cases of a study: generation (grid, list, table, Latin hypercube),
//! resolution into scenario overrides, canonical text and id.

use crate::format::{Problems, Study, StudyScenario, value_text};
use railmbs_models::syntax::{OrderedMap, Value};
use railmbs_models::{Model, ModelError};
use std::path::Path;

/// Reserved variable: the running speed, m/s.
pub(crate) const SPEED: &str = "@speed";
/// Reserved variable: the end time, s.
pub(crate) const END_TIME: &str = "@end_time";
/// Reserved variable: a macro applied after the scenario's own.
pub(crate) const MACRO: &str = "@macro";

/// One case as read: its values (one per variable) and the token of the
/// file where it is written (for errors).
pub(crate) struct RawRow {
    values: Vec<Value>,
    token: Option<usize>,
    /// For a table row: (file, line).
    line: Option<(std::path::PathBuf, usize)>,
}

/// What a case changes in the study's scenario.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Overrides {
    /// (parameter, expression text), sorted by name, each once.
    pub parameters: Vec<(String, String)>,
    /// Macros applied after the scenario's own.
    pub macros: Vec<String>,
    /// Running speed, m/s.
    pub speed: Option<f64>,
    /// End time, s.
    pub end_time: Option<f64>,
}

impl Overrides {
    /// `scenario` with these overrides.
    ///
    /// # Errors
    /// An end time the scenario's limits refuse, or a speed for a scenario
    /// that has none to set.
    pub fn apply(&self, scenario: &StudyScenario) -> Result<StudyScenario, String> {
        let mut s = scenario.clone();
        for (name, value) in &self.parameters {
            s.set_parameter(name, value);
        }
        if let Some(t) = self.end_time {
            s.set_end_time(t).map_err(|e| format!("end time: {e}"))?;
        }
        let no_speed = || "@speed needs a scenario on a track at constant speed".to_string();
        match &mut s {
            StudyScenario::Single(single) => {
                single.macros.extend(self.macros.iter().cloned());
                if let Some(v) = self.speed {
                    match &mut single.track {
                        Some(track) if track.speed_profile.is_empty() => track.speed = v,
                        _ => return Err(no_speed()),
                    }
                }
            }
            StudyScenario::Train(train) => {
                if !self.macros.is_empty() {
                    return Err("@macro needs a single-vehicle scenario".into());
                }
                if let Some(v) = self.speed {
                    if !train.track.speed_profile.is_empty() {
                        return Err(no_speed());
                    }
                    train.track.speed = v;
                }
            }
        }
        Ok(s)
    }
}

/// One case of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Position in the study (0-based).
    pub index: usize,
    /// Stable id: 16 hex digits of the BLAKE3 hash of [`Case::canonical`].
    pub id: String,
    /// The value of each variable (in [`Study::variables`] order).
    pub inputs: Vec<Value>,
    /// What the case changes in the scenario.
    pub overrides: Overrides,
    canonical: String,
}

impl Case {
    /// The canonical text the id hashes (see the crate docs).
    pub fn canonical(&self) -> &str {
        &self.canonical
    }

    /// The inputs as text (numbers in shortest round-trip form).
    pub fn input_texts(&self) -> Vec<String> {
        self.inputs.iter().map(value_text).collect()
    }
}

/// The canonical text of a case of `study` with `overrides`.
fn canonical(study: &Study, o: &Overrides) -> String {
    use std::fmt::Write;
    let opt = |x: Option<f64>| x.map(|v| format!("{v}")).unwrap_or_default();
    let mut s = String::from("railmbs-study-case/1\n");
    let _ = writeln!(s, "scenario={}", study.scenario_text);
    let _ = writeln!(s, "engine={}", study.engine.name());
    let _ = writeln!(s, "end_time={}", opt(o.end_time));
    let _ = writeln!(s, "speed={}", opt(o.speed));
    let _ = writeln!(s, "macros={}", o.macros.join(","));
    for (name, value) in &o.parameters {
        let _ = writeln!(s, "parameter {name}={value}");
    }
    s
}

/// 16 hex digits of the BLAKE3 hash of `text`.
fn case_id(text: &str) -> String {
    blake3::hash(text.as_bytes()).to_hex()[..16].to_string()
}

pub(crate) fn grid(grid: &OrderedMap<Vec<Value>>, p: &mut Problems) -> (Vec<String>, Vec<RawRow>) {
    let vars: Vec<String> = grid.0.iter().map(|(k, _)| k.clone()).collect();
    for (name, values) in &grid.0 {
        if values.is_empty() {
            p.at(
                Some(name),
                "cases",
                &format!("grid variable \"{name}\""),
                "has no values".into(),
            );
        }
    }
    if grid.0.is_empty() {
        p.at(None, "cases", "", "the grid has no variables".into());
    }
    if !p.errors.is_empty() {
        return (vars, Vec::new());
    }
    let token = |p: &Problems, name: &str| p.loc.top().and_then(|t| p.loc.string_in(t, name));
    let total: usize = grid.0.iter().map(|(_, v)| v.len()).product();
    let mut rows = Vec::with_capacity(total);
    for k in 0..total {
        // Odometer: the last variable turns fastest.
        let mut rest = k;
        let mut values = vec![Value::Num(0.0); grid.0.len()];
        for (j, (_, vs)) in grid.0.iter().enumerate().rev() {
            values[j] = vs[rest % vs.len()].clone();
            rest /= vs.len();
        }
        rows.push(RawRow {
            values,
            token: token(p, &grid.0[0].0),
            line: None,
        });
    }
    (vars, rows)
}

pub(crate) fn list(list: &[OrderedMap<Value>], p: &mut Problems) -> (Vec<String>, Vec<RawRow>) {
    let Some(first) = list.first() else {
        p.at(None, "cases", "", "the list has no cases".into());
        return (Vec::new(), Vec::new());
    };
    let vars: Vec<String> = first.0.iter().map(|(k, _)| k.clone()).collect();
    // The `List([...])` group's entries, for positions.
    let entries: Vec<usize> = p
        .loc
        .top()
        .and_then(|top| p.loc.field_group(top, "cases"))
        .and_then(|g| p.loc.children(g).first().copied())
        .and_then(|k| p.loc.group_after(k))
        .map(|g| p.loc.children(g))
        .unwrap_or_default()
        .into_iter()
        .filter(|&k| p.loc.group_after(k).is_some())
        .collect();
    let mut rows = Vec::new();
    for (k, case) in list.iter().enumerate() {
        let token = entries.get(k).copied();
        let mut names: Vec<&String> = case.0.iter().map(|(n, _)| n).collect();
        names.sort();
        let mut expected: Vec<&String> = vars.iter().collect();
        expected.sort();
        if names != expected {
            p.at_token(
                token,
                &format!("case {k}"),
                format!(
                    "sets {} but the first case sets {}; every case of a list sets the same variables",
                    join(&names),
                    join(&expected)
                ),
            );
            continue;
        }
        let values = vars
            .iter()
            .map(|v| {
                case.0
                    .iter()
                    .find(|(n, _)| n == v)
                    .map(|(_, x)| x.clone())
                    .unwrap_or(Value::Num(0.0))
            })
            .collect();
        rows.push(RawRow {
            values,
            token,
            line: None,
        });
    }
    (vars, rows)
}

fn join(names: &[&String]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

pub(crate) fn table(path: &Path, p: &mut Problems, written: &str) -> (Vec<String>, Vec<RawRow>) {
    let fail = |p: &mut Problems, line: Option<usize>, element: String, message: String| {
        p.errors.push(ModelError {
            file: path.to_path_buf(),
            element,
            message,
            position: line.map(|l| (l, 1)),
        });
    };
    let mut reader = match csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
    {
        Ok(r) => r,
        Err(e) => {
            p.at(
                Some(written),
                "cases",
                "cases",
                format!("cannot read the case table {}: {e}", path.display()),
            );
            return (Vec::new(), Vec::new());
        }
    };
    let vars: Vec<String> = match reader.headers() {
        Ok(h) => h.iter().map(String::from).collect(),
        Err(e) => {
            fail(p, Some(1), String::new(), format!("header: {e}"));
            return (Vec::new(), Vec::new());
        }
    };
    if vars.is_empty() || vars.iter().any(String::is_empty) {
        fail(
            p,
            Some(1),
            String::new(),
            "the header names no variables (or an empty one)".into(),
        );
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                let line = e.position().map(|q| q.line() as usize);
                fail(p, line, String::new(), e.to_string());
                continue;
            }
        };
        let line = record.position().map_or(0, |q| q.line() as usize);
        let mut values = Vec::new();
        for (name, cell) in vars.iter().zip(record.iter()) {
            if cell.is_empty() {
                fail(
                    p,
                    Some(line),
                    format!("column \"{name}\""),
                    "empty cell".into(),
                );
            }
            values.push(match cell.parse::<f64>() {
                Ok(x) => Value::Num(x),
                Err(_) => Value::Text(cell.to_string()),
            });
        }
        rows.push(RawRow {
            values,
            token: None,
            line: Some((path.to_path_buf(), line)),
        });
    }
    if rows.is_empty() && p.errors.is_empty() {
        fail(p, None, String::new(), "the case table has no cases".into());
    }
    (vars, rows)
}

pub(crate) fn latin_hypercube(
    samples: usize,
    seed: u64,
    ranges: &OrderedMap<(f64, f64)>,
    p: &mut Problems,
) -> (Vec<String>, Vec<RawRow>) {
    use rand::{Rng, SeedableRng, seq::SliceRandom};
    let vars: Vec<String> = ranges.0.iter().map(|(k, _)| k.clone()).collect();
    if samples == 0 {
        p.at(
            None,
            "samples",
            "LatinHypercube",
            "samples must be at least 1".into(),
        );
    }
    if ranges.0.is_empty() {
        p.at(None, "ranges", "LatinHypercube", "no ranges".into());
    }
    for (name, (lo, hi)) in &ranges.0 {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            p.at(
                Some(name),
                "ranges",
                &format!("range \"{name}\""),
                format!("a range is (low, high) with low < high, both finite; got ({lo}, {hi})"),
            );
        }
    }
    if !p.errors.is_empty() {
        return (vars, Vec::new());
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n = samples;
    let mut columns = Vec::new();
    for (_, (lo, hi)) in &ranges.0 {
        // Stratum k of n is [k, k+1)/n of the range; one sample in each.
        let mut strata: Vec<usize> = (0..n).collect();
        strata.shuffle(&mut rng);
        let column: Vec<f64> = strata
            .iter()
            .map(|&k| {
                let u: f64 = rng.random();
                lo + (hi - lo) * (k as f64 + u) / n as f64
            })
            .collect();
        columns.push(column);
    }
    let token = p.loc.top().and_then(|t| p.loc.key_anywhere(t, "ranges"));
    let rows = (0..n)
        .map(|i| RawRow {
            values: columns.iter().map(|c| Value::Num(c[i])).collect(),
            token,
            line: None,
        })
        .collect();
    (vars, rows)
}

/// The names used as `{name}` in a template.
fn template_names(template: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = template;
    while let Some(a) = rest.find('{') {
        let Some(b) = rest[a..].find('}') else { break };
        out.push(&rest[a + 1..a + b]);
        rest = &rest[a + b + 1..];
    }
    out
}

/// `template` with each `{name}` replaced by `(value)`.
fn substitute(template: &str, variables: &[String], values: &[Value]) -> String {
    let mut out = template.to_string();
    for (name, value) in variables.iter().zip(values) {
        out = out.replace(&format!("{{{name}}}"), &format!("({})", value_text(value)));
    }
    out
}

pub(crate) fn check_variables(
    variables: &[String],
    set: &[(String, String)],
    models: &[Model],
    scenario: &StudyScenario,
    p: &mut Problems,
) {
    let is_parameter = |n: &str| models.iter().any(|m| m.parameter_index(n).is_some());
    let model_names = models
        .iter()
        .map(|m| format!("\"{}\"", m.name))
        .collect::<Vec<_>>()
        .join(", ");
    for (k, name) in variables.iter().enumerate() {
        if variables[..k].contains(name) {
            p.at(
                Some(name),
                "cases",
                &format!("variable \"{name}\""),
                "given twice".into(),
            );
        }
        let used = set
            .iter()
            .any(|(_, t)| template_names(t).contains(&name.as_str()));
        match name.as_str() {
            SPEED => {
                if !scenario.constant_speed() {
                    p.at(
                        Some(name),
                        "cases",
                        &format!("variable \"{name}\""),
                        format!(
                            "the scenario {} does not run on a track at constant speed",
                            scenario.source().display()
                        ),
                    );
                }
            }
            MACRO if matches!(scenario, StudyScenario::Train(_)) => p.at(
                Some(name),
                "cases",
                &format!("variable \"{name}\""),
                "a train's vehicles have their own macros; @macro needs a single-vehicle scenario"
                    .into(),
            ),
            END_TIME | MACRO => {}
            n if n.starts_with('@') => p.at(
                Some(name),
                "cases",
                &format!("variable \"{name}\""),
                format!("unknown reserved name (there are {SPEED}, {END_TIME} and {MACRO})"),
            ),
            n if is_parameter(n) || used => {}
            _ => p.at(
                Some(name),
                "cases",
                &format!("variable \"{name}\""),
                format!(
                    "neither a parameter of model {model_names}, nor a reserved name ({SPEED}, \
                     {END_TIME}, {MACRO}), nor used as {{{name}}} in `set`"
                ),
            ),
        }
    }
    for (target, template) in set {
        for used in template_names(template) {
            if !variables.iter().any(|v| v == used) {
                p.at(
                    Some(target),
                    "set",
                    &format!("set \"{target}\""),
                    format!("{{{used}}} is not a variable of the cases"),
                );
            }
        }
    }
}

/// The cases of `study` from the rows read, checked.
pub(crate) fn resolve(study: &Study, rows: Vec<RawRow>, p: &mut Problems) -> Vec<Case> {
    let mut cases: Vec<Case> = Vec::new();
    for (index, row) in rows.into_iter().enumerate() {
        let before = p.errors.len();
        let fail = |p: &mut Problems, message: String| match &row.line {
            Some((file, line)) => p.errors.push(ModelError {
                file: file.clone(),
                element: format!("case {index}"),
                message,
                position: Some((*line, 1)),
            }),
            None => p.at_token(row.token, &format!("case {index}"), message),
        };
        let mut o = Overrides {
            end_time: study.end_time,
            ..Overrides::default()
        };
        for (name, value) in study.variables.iter().zip(&row.values) {
            let number = match value {
                Value::Num(x) => Some(*x),
                Value::Text(_) => None,
            };
            match name.as_str() {
                SPEED => match number {
                    Some(v) if v > 0.0 && v.is_finite() => o.speed = Some(v),
                    _ => fail(
                        p,
                        format!(
                            "{SPEED} must be a positive speed, m/s, got {}",
                            value_text(value)
                        ),
                    ),
                },
                END_TIME => match number {
                    Some(t) => o.end_time = Some(t),
                    None => fail(
                        p,
                        format!(
                            "{END_TIME} must be a number, s, got \"{}\"",
                            value_text(value)
                        ),
                    ),
                },
                MACRO => match value {
                    Value::Text(m) if m.is_empty() => {}
                    Value::Text(m) if study.models[0].macros.iter().any(|x| &x.name == m) => {
                        o.macros.push(m.clone());
                    }
                    _ => fail(
                        p,
                        format!(
                            "{MACRO}: model \"{}\" has no macro \"{}\"",
                            study.models[0].name,
                            value_text(value)
                        ),
                    ),
                },
                n if study.has_parameter(n) => {
                    if number.is_some_and(|x| !x.is_finite()) {
                        fail(p, format!("\"{n}\" is not finite"));
                    }
                    set_sorted(&mut o.parameters, n, value_text(value));
                }
                _ => {}
            }
        }
        for (target, template) in &study.set {
            let text = substitute(template, &study.variables, &row.values);
            set_sorted(&mut o.parameters, target, text);
        }
        if let Err(e) = o.apply(&study.scenario) {
            fail(p, e);
        }
        if p.errors.len() > before {
            continue;
        }
        let text = canonical(study, &o);
        let id = case_id(&text);
        if let Some(other) = cases.iter().find(|c| c.id == id) {
            fail(p, format!("the same run as case {} (id {id})", other.index));
            continue;
        }
        cases.push(Case {
            index,
            id,
            inputs: row.values,
            overrides: o,
            canonical: text,
        });
    }
    cases
}

/// Sets `name` to `value` in a list sorted by name.
fn set_sorted(list: &mut Vec<(String, String)>, name: &str, value: String) {
    match list.binary_search_by(|(n, _)| n.as_str().cmp(name)) {
        Ok(k) => list[k].1 = value,
        Err(k) => list.insert(k, (name.to_string(), value)),
    }
}
