//! Per-case analyses: instead of (or besides) a time run, a case can be
//! reduced to the result of one of the runtime's analyses at the case's
//! parameters and speed (`railmbs_runtime::analysis`, the functions `umsim
//! modes` and `umsim curving` call; nothing is recomputed here): the least
//! damped lateral mode at the case's speed, the linear critical speed of a
//! root locus, and the quasi-static curving solution in a constant curve.

use crate::reduce::Cell;
use railmbs_models::{Model, Scenario};
use railmbs_runtime::Equations;
use railmbs_runtime::analysis::curving::{Curve, curving};
use railmbs_runtime::analysis::speed::{critical_speed, root_locus, scenario_modes};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::RunError;

/// What an analysis of a case computes.
#[derive(Debug, Clone, PartialEq)]
pub enum AnalysisKind {
    /// The least damped lateral (hunting candidate) mode at the case's
    /// steady state and speed, as `umsim modes` reports it
    /// (`Modes::least_damped_lateral`): its damping ratio, damped
    /// frequency (Hz) and name.
    LeastDamping,
    /// The linear critical speed, m/s: the root locus at `speeds` (m/s,
    /// ascending) and where the least damped lateral mode's damping ratio
    /// first crosses zero (`umsim modes --speed`); empty when it does not
    /// cross in the range.
    LinearCriticalSpeed {
        /// Speeds of the root locus, m/s.
        speeds: Vec<f64>,
    },
    /// The quasi-static curving solution (`umsim curving`) on a circular
    /// curve, reduced over its wheelsets.
    Curving {
        /// Radius, m (positive left, negative right).
        radius: f64,
        /// Cant, m.
        cant: f64,
        /// Running speed, m/s; `None`: the case's (its track's) speed.
        speed: Option<f64>,
    },
}

/// One analysis of a study, with the name of its (first) result column.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// What it computes.
    pub kind: AnalysisKind,
    /// Name of its first result column; the others are `NAME.…`.
    pub name: String,
}

/// The curving analysis's result columns after its name.
const CURVING_COLUMNS: [&str; 8] = [
    ".YQ.max",
    ".YQ.wheel",
    ".sumY.max[N]",
    ".sumY.element",
    ".Q.max[N]",
    ".Q.min[N]",
    ".y.max[m]",
    ".yaw.max[rad]",
];

impl Analysis {
    /// An analysis named `name`, or by default `least_damping`,
    /// `linear_critical_speed[m/s]` or `curving`.
    pub fn new(kind: AnalysisKind, name: Option<String>) -> Self {
        let name = name.unwrap_or_else(|| {
            match &kind {
                AnalysisKind::LeastDamping => "least_damping",
                AnalysisKind::LinearCriticalSpeed { .. } => "linear_critical_speed[m/s]",
                AnalysisKind::Curving { .. } => "curving",
            }
            .to_string()
        });
        Analysis { kind, name }
    }

    /// Its result columns (see the crate docs).
    pub fn columns(&self) -> Vec<String> {
        let n = &self.name;
        match &self.kind {
            AnalysisKind::LeastDamping => {
                vec![n.clone(), format!("{n}.f[Hz]"), format!("{n}.mode")]
            }
            AnalysisKind::LinearCriticalSpeed { .. } => vec![n.clone()],
            AnalysisKind::Curving { .. } => {
                CURVING_COLUMNS.iter().map(|c| format!("{n}{c}")).collect()
            }
        }
    }

    /// The cells of this analysis of the case scenario `scenario` (its
    /// parameters and speed set) of `model`, with engines from `engine`,
    /// sharing the contact tables `tables`.
    ///
    /// # Errors
    /// The analysis's failure (no equilibrium, no steady curving state…),
    /// as its message.
    pub(crate) fn cells(
        &self,
        scenario: &Scenario,
        model: &Model,
        engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
        tables: &ContactTableCache,
    ) -> Result<Vec<Cell>, String> {
        let failed = |e: RunError| format!("{}: {e}", self.name);
        match &self.kind {
            AnalysisKind::LeastDamping => {
                let one = scenario_modes(scenario, model, engine().map_err(failed)?, tables)
                    .map_err(failed)?;
                Ok(match one.modes.least_damped_lateral() {
                    Some(m) => vec![
                        Cell::num(m.damping_ratio),
                        Cell::num(m.frequency),
                        Cell::Text(m.name.clone()),
                    ],
                    None => vec![Cell::Empty, Cell::Empty, Cell::Empty],
                })
            }
            AnalysisKind::LinearCriticalSpeed { speeds } => {
                let locus = root_locus(scenario, model, speeds, engine).map_err(failed)?;
                Ok(vec![critical_speed(&locus).map_or(Cell::Empty, Cell::num)])
            }
            AnalysisKind::Curving {
                radius,
                cant,
                speed,
            } => {
                let speed = match speed {
                    Some(v) => *v,
                    None => scenario.track.as_ref().map(|t| t.speed).ok_or_else(|| {
                        format!("{}: the scenario has no track (no speed)", self.name)
                    })?,
                };
                let curve = Curve {
                    radius: *radius,
                    cant: *cant,
                    speed,
                };
                let c = curving(scenario, model, engine, tables, &curve).map_err(failed)?;
                Ok(curving_cells(&c))
            }
        }
    }
}

/// The largest of `(value, label)` pairs by `key` (`None` when there are none).
fn largest<'a>(
    items: impl Iterator<Item = (f64, String)> + 'a,
    key: impl Fn(f64) -> f64,
) -> Option<(f64, String)> {
    items
        .filter(|(x, _)| x.is_finite())
        .max_by(|a, b| key(a.0).total_cmp(&key(b.0)))
}

/// The curving columns of a solution: over all wheels the largest Y/Q (with
/// the wheel, `element left|right`), the largest |ΣY| (N, with the element),
/// the largest and smallest Q (N), over all wheelsets the largest |lateral
/// position| (m) and |angle of attack| (rad).
fn curving_cells(c: &railmbs_runtime::analysis::curving::Curving) -> Vec<Cell> {
    let wheels = |name: &'static str| {
        c.wheelsets.iter().flat_map(move |w| {
            [("L", "left"), ("R", "right")]
                .into_iter()
                .filter_map(move |(side, word)| {
                    w.output(&format!("{side}.{name}"))
                        .map(|x| (x, format!("{} {word}", w.element)))
                })
        })
    };
    let pair = |best: Option<(f64, String)>| match best {
        Some((x, label)) => [Cell::num(x), Cell::Text(label)],
        None => [Cell::Empty, Cell::Empty],
    };
    let mut out = Vec::new();
    out.extend(pair(largest(wheels("Y/Q [-]"), |x| x)));
    let sum_y = c
        .wheelsets
        .iter()
        .filter_map(|w| w.output("SumY [N]").map(|x| (x.abs(), w.element.clone())));
    out.extend(pair(largest(sum_y, |x| x)));
    out.push(largest(wheels("Q [N]"), |x| x).map_or(Cell::Empty, |b| Cell::num(b.0)));
    out.push(largest(wheels("Q [N]"), |x| -x).map_or(Cell::Empty, |b| Cell::num(b.0)));
    let abs_max = |xs: Vec<Option<f64>>| {
        xs.into_iter()
            .flatten()
            .map(f64::abs)
            .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))))
            .map_or(Cell::Empty, Cell::num)
    };
    out.push(abs_max(c.wheelsets.iter().map(|w| w.lateral).collect()));
    out.push(abs_max(c.wheelsets.iter().map(|w| w.yaw).collect()));
    out
}
