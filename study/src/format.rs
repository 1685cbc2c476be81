//! The study file: RON syntax, loading, validation with located errors.

use crate::analysis::{Analysis, AnalysisKind};
use crate::cases::{self, Case};
use crate::reduce::{Reduction, ReductionKind, Window};
use crate::series::SeriesFormat;
use railmbs_models::syntax::{Locator, OrderedMap, Value, ron_error};
use railmbs_models::{AnyScenario, Model, ModelError, ModelErrors, Scenario, TrainScenario};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Which equations of motion the cases run on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum EngineKind {
    /// The model's compiled plugin, built once for the study (the default).
    #[default]
    Symbolic,
    /// The numeric-iterative engine (no code generation).
    Numeric,
}

impl EngineKind {
    /// `symbolic` or `numeric`.
    pub fn name(self) -> &'static str {
        match self {
            EngineKind::Symbolic => "symbolic",
            EngineKind::Numeric => "numeric",
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Study", deny_unknown_fields)]
struct RawStudy {
    scenario: String,
    #[serde(default)]
    engine: EngineKind,
    #[serde(default)]
    end_time: Option<f64>,
    #[serde(default)]
    set: OrderedMap<Value>,
    cases: RawCases,
    #[serde(default)]
    reductions: Vec<RawReduction>,
    #[serde(default)]
    time_series: bool,
    /// Written bare (`series_format: Parquet`); `None` when not given.
    #[serde(default, deserialize_with = "given")]
    series_format: Option<SeriesFormat>,
}

/// A value written bare for an `Option` field (`Some` when it is there).
fn given<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

#[derive(Debug, Deserialize)]
enum RawCases {
    Grid(OrderedMap<Vec<Value>>),
    List(Vec<OrderedMap<Value>>),
    Table(String),
    LatinHypercube {
        samples: usize,
        seed: u64,
        ranges: OrderedMap<(f64, f64)>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ColumnArgs {
    column: String,
    #[serde(default)]
    window: Option<Window>,
    #[serde(default)]
    name: Option<String>,
}

#[derive(Debug, Deserialize)]
enum RawReduction {
    Assessment,
    Max(ColumnArgs),
    Min(ColumnArgs),
    MaxAbs(ColumnArgs),
    Rms(ColumnArgs),
    CriticalSpeed {
        column: String,
        amplitude: f64,
        #[serde(default = "default_amplitude_window")]
        window: f64,
        #[serde(default)]
        name: Option<String>,
    },
    LeastDamping(NameArgs),
    LinearCriticalSpeed(SpeedsArgs),
    Curving(CurvingArgs),
}

/// The optional result name of an analysis.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct NameArgs {
    #[serde(default)]
    name: Option<String>,
}

/// `LinearCriticalSpeed(speeds: (FROM, TO, STEP), name: …)`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpeedsArgs {
    speeds: (f64, f64, f64),
    #[serde(default)]
    name: Option<String>,
}

/// `Curving(radius: R, cant: H, speed: Some(V), name: …)`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CurvingArgs {
    radius: f64,
    #[serde(default)]
    cant: f64,
    #[serde(default)]
    speed: Option<f64>,
    #[serde(default)]
    name: Option<String>,
}

fn default_amplitude_window() -> f64 {
    1.0
}

/// Where the cases of a study came from.
#[derive(Debug, Clone, PartialEq)]
pub enum CaseSource {
    /// A full-factorial grid.
    Grid,
    /// An explicit list.
    List,
    /// A CSV table (the file).
    Table(PathBuf),
    /// A seeded Latin hypercube.
    LatinHypercube {
        /// Number of samples.
        samples: usize,
        /// Seed of the ChaCha8 generator.
        seed: u64,
    },
}

/// The scenario a study's cases start from: one vehicle, or a train.
#[derive(Debug, Clone)]
pub enum StudyScenario {
    /// A `Scenario(...)` file.
    Single(Scenario),
    /// A `Train(...)` file (parameters are train-wide: every vehicle whose
    /// model has them).
    Train(TrainScenario),
}

impl StudyScenario {
    /// The scenario file.
    pub fn source(&self) -> &Path {
        match self {
            StudyScenario::Single(s) => &s.source,
            StudyScenario::Train(t) => &t.source,
        }
    }

    /// Whether it runs on a track at constant speed (so `@speed` can set it).
    pub fn constant_speed(&self) -> bool {
        match self {
            StudyScenario::Single(s) => {
                s.track.as_ref().is_some_and(|t| t.speed_profile.is_empty())
            }
            StudyScenario::Train(t) => t.track.speed_profile.is_empty(),
        }
    }

    /// Replaces the end time (s), checked like the file's own.
    ///
    /// # Errors
    /// What is wrong, in one message.
    pub fn set_end_time(&mut self, t: f64) -> Result<(), String> {
        match self {
            StudyScenario::Single(s) => s.set_end_time(t),
            StudyScenario::Train(tr) => tr.set_end_time(t),
        }
    }

    /// Sets a parameter (train-wide for a train) to the expression `value`.
    pub fn set_parameter(&mut self, name: &str, value: &str) {
        match self {
            StudyScenario::Single(s) => s.set_parameter(name, value),
            StudyScenario::Train(t) => t.set_parameter(name, value),
        }
    }
}

/// A loaded, validated study: its scenario and model, its cases and
/// reductions.
#[derive(Debug, Clone)]
pub struct Study {
    /// The study file.
    pub source: PathBuf,
    /// The scenario path as written in the study file (part of the case ids).
    pub scenario_text: String,
    /// The scenario every case starts from.
    pub scenario: StudyScenario,
    /// The distinct models of the scenario (one for a single vehicle; a
    /// train's distinct model files), the same for all cases: a model's
    /// macros only set parameters.
    pub models: Vec<Model>,
    /// For a train, the index in `models` of each vehicle's model.
    pub vehicle_models: Vec<usize>,
    /// The engine of the cases.
    pub engine: EngineKind,
    /// End time of every case unless it sets `@end_time`, s.
    pub end_time: Option<f64>,
    /// Parameter templates set in every case (`{name}` is a variable's value).
    pub set: Vec<(String, String)>,
    /// Names of the case variables, in the study's order.
    pub variables: Vec<String>,
    /// Where the cases came from.
    pub case_source: CaseSource,
    /// The cases, in order (index = position).
    pub cases: Vec<Case>,
    /// The reductions of every case's time run.
    pub reductions: Vec<Reduction>,
    /// The analyses of every case (`LeastDamping`, `LinearCriticalSpeed`,
    /// `Curving` in the file's `reductions`), in the file's order; their
    /// columns follow the run's reductions.
    pub analyses: Vec<Analysis>,
    /// Whether each case's output is written as `series/<case id>.csv`
    /// (or `.parquet`, after `series_format`).
    pub time_series: bool,
    /// The file format of the time series.
    pub series_format: SeriesFormat,
}

/// Errors of a study file, collected, each at the position of `key` (or of
/// the string `literal`) in the file.
pub(crate) struct Problems<'a> {
    pub(crate) file: &'a Path,
    pub(crate) loc: Locator<'a>,
    pub(crate) errors: Vec<ModelError>,
}

impl Problems<'_> {
    /// A problem of `element` at the first string literal `literal` (else at
    /// the key `key`, else without a position).
    pub(crate) fn at(&mut self, literal: Option<&str>, key: &str, element: &str, message: String) {
        let top = self.loc.top();
        let tok = top.and_then(|top| {
            literal
                .and_then(|l| self.loc.string_in(top, l))
                .or_else(|| self.loc.key_anywhere(top, key))
        });
        self.errors.push(ModelError {
            file: self.file.to_path_buf(),
            element: element.to_string(),
            message,
            position: tok.map(|k| self.loc.pos(k)),
        });
    }

    /// A problem at token `tok`.
    pub(crate) fn at_token(&mut self, tok: Option<usize>, element: &str, message: String) {
        self.errors.push(ModelError {
            file: self.file.to_path_buf(),
            element: element.to_string(),
            message,
            position: tok.map(|k| self.loc.pos(k)),
        });
    }
}

impl Study {
    /// Reads and validates the study file `path`, its scenario and model.
    ///
    /// # Errors
    /// Every problem found, each naming the file, the element and (where
    /// known) the line and column.
    pub fn load(path: &Path) -> Result<Study, ModelErrors> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| ModelError::new(path, "", format!("cannot read the study file: {e}")))?;
        Self::parse(&text, path)
    }

    /// [`Study::load`] of the text of a study file at `path` (for errors and
    /// relative paths).
    ///
    /// # Errors
    /// As [`Study::load`].
    pub fn parse(text: &str, path: &Path) -> Result<Study, ModelErrors> {
        let loc = Locator::new(text);
        // `Max(column: …)` for the newtype variants.
        let raw: RawStudy = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
            .from_str(text)
            .map_err(|e| ron_error(&loc, path, e))?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let (scenario, models, vehicle_models) =
            match railmbs_models::load_any_scenario(&dir.join(&raw.scenario))? {
                AnyScenario::Single(s) => {
                    let model = railmbs_models::load_model(&s.model)?;
                    (StudyScenario::Single(s), vec![model], Vec::new())
                }
                AnyScenario::Train(t) => {
                    let mut files: Vec<PathBuf> = Vec::new();
                    let mut models = Vec::new();
                    let mut which = Vec::new();
                    for v in &t.vehicles {
                        let k = match files.iter().position(|f| f == &v.model) {
                            Some(k) => k,
                            None => {
                                models.push(railmbs_models::load_model(&v.model)?);
                                files.push(v.model.clone());
                                files.len() - 1
                            }
                        };
                        which.push(k);
                    }
                    let refs: Vec<&Model> = which.iter().map(|&k| &models[k]).collect();
                    t.check_names(&refs)?;
                    (StudyScenario::Train(t), models, which)
                }
            };
        let model_names = models
            .iter()
            .map(|m| format!("\"{}\"", m.name))
            .collect::<Vec<_>>()
            .join(", ");
        let mut p = Problems {
            file: path,
            loc,
            errors: Vec::new(),
        };
        if let Some(t) = raw.end_time {
            let mut probe = scenario.clone();
            if let Err(e) = probe.set_end_time(t) {
                p.at(None, "end_time", "", format!("end_time: {e}"));
            }
        }
        let set: Vec<(String, String)> = raw
            .set
            .0
            .iter()
            .map(|(k, v)| (k.clone(), value_text(v)))
            .collect();
        for (name, _) in &set {
            if !models.iter().any(|m| m.parameter_index(name).is_some()) {
                p.at(
                    Some(name),
                    "set",
                    &format!("set \"{name}\""),
                    format!("no parameter of model {model_names} is named so"),
                );
            }
        }
        let (case_source, variables, rows) = match raw.cases {
            RawCases::Grid(grid) => {
                let (vars, rows) = cases::grid(&grid, &mut p);
                (CaseSource::Grid, vars, rows)
            }
            RawCases::List(list) => {
                let (vars, rows) = cases::list(&list, &mut p);
                (CaseSource::List, vars, rows)
            }
            RawCases::Table(file) => {
                let table = dir.join(&file);
                let (vars, rows) = cases::table(&table, &mut p, &file);
                (CaseSource::Table(table), vars, rows)
            }
            RawCases::LatinHypercube {
                samples,
                seed,
                ranges,
            } => {
                let (vars, rows) = cases::latin_hypercube(samples, seed, &ranges, &mut p);
                (CaseSource::LatinHypercube { samples, seed }, vars, rows)
            }
        };
        cases::check_variables(&variables, &set, &models, &scenario, &mut p);
        let (reductions, analyses) = reductions(raw.reductions, &scenario, &mut p);
        let mut study = Study {
            source: path.to_path_buf(),
            scenario_text: raw.scenario,
            scenario,
            models,
            vehicle_models,
            engine: raw.engine,
            end_time: raw.end_time,
            set,
            variables,
            case_source,
            cases: Vec::new(),
            reductions,
            analyses,
            time_series: raw.time_series,
            series_format: raw.series_format.unwrap_or_default(),
        };
        if p.errors.is_empty() {
            study.cases = cases::resolve(&study, rows, &mut p);
        }
        if !p.errors.is_empty() {
            p.errors
                .sort_by_key(|e| e.position.unwrap_or((usize::MAX, usize::MAX)));
            return Err(ModelErrors(p.errors));
        }
        Ok(study)
    }

    /// Whether a model of the study has parameter `name`.
    pub fn has_parameter(&self, name: &str) -> bool {
        self.models
            .iter()
            .any(|m| m.parameter_index(name).is_some())
    }

    /// The cases, in order.
    pub fn cases(&self) -> &[Case] {
        &self.cases
    }

    /// The case with id `id`.
    pub fn case_by_id(&self, id: &str) -> Option<&Case> {
        self.cases.iter().find(|c| c.id == id)
    }

    /// The header of the result table (see the crate docs).
    pub fn result_header(&self) -> Vec<String> {
        let mut h: Vec<String> = vec!["index".into(), "case_id".into()];
        h.extend(self.variables.iter().cloned());
        h.extend(
            [
                "status",
                "error",
                "steps",
                "rejected_steps",
                "t_end[s]",
                "integration_time[s]",
                "cpu_time[s]",
                "wall_time[s]",
            ]
            .map(String::from),
        );
        for r in &self.reductions {
            h.extend(r.columns());
        }
        for a in &self.analyses {
            h.extend(a.columns());
        }
        h
    }

    /// Whether a case runs in time: when it has a run reduction or time
    /// series, or no analysis (a study of analyses alone runs none).
    pub fn time_run(&self) -> bool {
        !self.reductions.is_empty() || self.time_series || self.analyses.is_empty()
    }

    /// The scenario of `case`: the study's scenario with the case's
    /// overrides (and the study's end time) applied.
    ///
    /// # Errors
    /// An end time or speed the scenario refuses (checked at load for every
    /// case, so only for a case built by hand).
    pub fn case_scenario(&self, case: &Case) -> Result<StudyScenario, String> {
        case.overrides.apply(&self.scenario)
    }
}

/// A value as expression text: a number in Rust's shortest round-trip form.
pub(crate) fn value_text(v: &Value) -> String {
    match v {
        Value::Num(x) => format!("{x}"),
        Value::Text(s) => s.clone(),
    }
}

/// The run reductions and the analyses of the file's `reductions`.
fn reductions(
    raw: Vec<RawReduction>,
    scenario: &StudyScenario,
    p: &mut Problems,
) -> (Vec<Reduction>, Vec<Analysis>) {
    let mut out = Vec::new();
    let mut analyses = Vec::new();
    for r in raw {
        let (kind, args) = match r {
            RawReduction::LeastDamping(NameArgs { name }) => {
                analyses.push(Analysis::new(AnalysisKind::LeastDamping, name));
                continue;
            }
            RawReduction::LinearCriticalSpeed(SpeedsArgs {
                speeds: (from, to, step),
                name,
            }) => {
                match railmbs_runtime::analysis::speed::speed_grid(from, to, step) {
                    Ok(speeds) => analyses.push(Analysis::new(
                        AnalysisKind::LinearCriticalSpeed { speeds },
                        name,
                    )),
                    Err(e) => p.at(
                        None,
                        "speeds",
                        "LinearCriticalSpeed",
                        format!("speeds (FROM, TO, STEP): {e}"),
                    ),
                }
                continue;
            }
            RawReduction::Curving(CurvingArgs {
                radius,
                cant,
                speed,
                name,
            }) => {
                let probe = railmbs_runtime::analysis::curving::Curve {
                    radius,
                    cant,
                    speed: speed.unwrap_or(1.0),
                };
                let on_track = match scenario {
                    StudyScenario::Single(s) => s.track.is_some(),
                    StudyScenario::Train(_) => true,
                };
                if let Err(e) = probe.track() {
                    let key = if e.starts_with("speed") {
                        "speed"
                    } else if e.starts_with("cant") {
                        "cant"
                    } else {
                        "radius"
                    };
                    p.at(None, key, "Curving", e);
                } else if !on_track {
                    p.at(
                        None,
                        "radius",
                        "Curving",
                        "quasi-static curving needs a vehicle on a track: the scenario has no \
                         `track`"
                            .into(),
                    );
                } else {
                    analyses.push(Analysis::new(
                        AnalysisKind::Curving {
                            radius,
                            cant,
                            speed,
                        },
                        name,
                    ));
                }
                continue;
            }
            RawReduction::Assessment => {
                out.push(Reduction::new(ReductionKind::Assessment, None));
                continue;
            }
            RawReduction::CriticalSpeed {
                column,
                amplitude,
                window,
                name,
            } => {
                if !(amplitude > 0.0 && amplitude.is_finite()) {
                    p.at(
                        None,
                        "amplitude",
                        &format!("CriticalSpeed \"{column}\""),
                        format!("amplitude must be positive and finite, got {amplitude}"),
                    );
                }
                if !(window > 0.0 && window.is_finite()) {
                    p.at(
                        None,
                        "window",
                        &format!("CriticalSpeed \"{column}\""),
                        format!("window must be a positive time, s, got {window}"),
                    );
                }
                out.push(Reduction::new(
                    ReductionKind::CriticalSpeed {
                        column,
                        amplitude,
                        window,
                    },
                    name,
                ));
                continue;
            }
            RawReduction::Max(a) => ("Max", a),
            RawReduction::Min(a) => ("Min", a),
            RawReduction::MaxAbs(a) => ("MaxAbs", a),
            RawReduction::Rms(a) => ("Rms", a),
        };
        if let Some(w) = &args.window
            && let Err(e) = w.check()
        {
            p.at(
                Some(&args.column),
                "window",
                &format!("{kind} \"{}\"", args.column),
                e,
            );
        }
        if let Err(e) = crate::reduce::column_matcher(&args.column) {
            p.at(
                Some(&args.column),
                "column",
                &format!("{kind} \"{}\"", args.column),
                format!("not a column name or glob: {e}"),
            );
            continue;
        }
        let stat = match kind {
            "Max" => crate::reduce::Stat::Max,
            "Min" => crate::reduce::Stat::Min,
            "MaxAbs" => crate::reduce::Stat::MaxAbs,
            _ => crate::reduce::Stat::Rms,
        };
        out.push(Reduction::new(
            ReductionKind::Column {
                stat,
                column: args.column,
                window: args.window,
            },
            args.name,
        ));
    }
    if !analyses.is_empty() && matches!(scenario, StudyScenario::Train(_)) {
        p.at(
            None,
            "reductions",
            "reductions",
            format!(
                "{}: the analyses (LeastDamping, LinearCriticalSpeed, Curving) apply to a \
                 single-vehicle scenario, not to a train",
                analyses
                    .iter()
                    .map(|a| a.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
    (out, analyses)
}
