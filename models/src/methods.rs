//! Queries on a resolved [`Model`]: parameter values, names, initial state, hash.

use crate::error::ModelError;
use crate::expr::Expr;
use crate::load::{evaluate_parameters, find_cycles, mass_problems};
use crate::model::Model;
use crate::parser::{ParseErrorKind, parse_expr};
use std::path::PathBuf;

impl Model {
    fn source_path(&self) -> PathBuf {
        self.source.clone().unwrap_or_default()
    }

    /// Checks every body's mass and inertia at the parameter values `params`
    /// as loading checks them at the defaults (mass positive, inertia
    /// positive definite and realizable): a scenario's or study's overrides
    /// must not make a body impossible. `Err` lists each problem as
    /// `body "<name>": <what is wrong>`.
    pub fn check_body_values(&self, params: &[f64]) -> Result<(), Vec<String>> {
        let mut problems = Vec::new();
        for body in &self.bodies {
            let mass = body.mass.eval(params, 0.0);
            let inertia = body.inertia.each_ref().map(|e| e.eval(params, 0.0));
            for (_, message) in mass_problems(mass, inertia) {
                problems.push(format!("body \"{}\": {message}", body.name));
            }
            if !mass.is_finite() || inertia.iter().any(|x| !x.is_finite()) {
                problems.push(format!(
                    "body \"{}\": mass {mass} kg or inertia {inertia:?} kg m² is not finite",
                    body.name
                ));
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems)
        }
    }

    /// Replaces the creep law of every wheel–rail element by `law` (`umsim
    /// bench --creep`, the Python package's `Scenario.set_creep_law`);
    /// returns the number of elements changed (0: the model has none).
    pub fn set_creep_law(&mut self, law: &crate::model::CreepLawSpec<Expr>) -> usize {
        let mut changed = 0;
        for f in &mut self.forces {
            if let crate::forces::ForceKind::WheelRail(w) = &mut f.kind {
                w.creep = law.clone();
                changed += 1;
            }
        }
        changed
    }

    /// Parameter names, index = `Expr::Param` index.
    pub fn parameter_names(&self) -> Vec<String> {
        self.parameters.iter().map(|p| p.name.clone()).collect()
    }

    /// Coordinate names in coordinate order.
    pub fn coordinate_names(&self) -> Vec<String> {
        self.coordinates.iter().map(|c| c.name.clone()).collect()
    }

    /// Values of the parameters with their default expressions. The loader has
    /// checked that they are acyclic and finite, so this cannot fail for a
    /// loaded model (a hand-built model with a cycle gets NaN for the cycle).
    pub fn default_parameter_values(&self) -> Vec<f64> {
        let exprs: Vec<Expr> = self.parameters.iter().map(|p| p.default.clone()).collect();
        evaluate_parameters(&exprs).unwrap_or_else(|_| vec![f64::NAN; exprs.len()])
    }

    /// Parameter values after applying `macros` in order, then `overrides`
    /// (parameter name, expression text over the parameters). Every parameter is
    /// then evaluated in dependency order: an assigned parameter takes its new
    /// expression, the others keep their defaults (so `l2 = "l1"` follows an
    /// override of `l1`).
    ///
    /// Errors name the macro or parameter; their `file` is the model's source
    /// (a caller resolving a scenario replaces it by the scenario file).
    pub fn parameter_values(
        &self,
        macros: &[String],
        overrides: &[(String, String)],
    ) -> Result<Vec<f64>, ModelError> {
        let file = self.source_path();
        let names = self.parameter_names();
        let mut exprs: Vec<Expr> = self.parameters.iter().map(|p| p.default.clone()).collect();
        for name in macros {
            let m = self
                .macros
                .iter()
                .find(|m| &m.name == name)
                .ok_or_else(|| {
                    let known: Vec<&str> = self.macros.iter().map(|m| m.name.as_str()).collect();
                    ModelError::new(
                        &file,
                        format!("macro \"{name}\""),
                        format!(
                            "unknown macro of model \"{}\" (known: {})",
                            self.name,
                            if known.is_empty() {
                                "none".to_string()
                            } else {
                                known.join(", ")
                            }
                        ),
                    )
                })?;
            for (i, e) in &m.assignments {
                if let Some(slot) = exprs.get_mut(*i) {
                    *slot = e.clone();
                }
            }
        }
        for (name, text) in overrides {
            let element = format!("parameter \"{name}\"");
            let i = names.iter().position(|n| n == name).ok_or_else(|| {
                ModelError::new(
                    &file,
                    element.clone(),
                    format!("unknown parameter of model \"{}\"", self.name),
                )
            })?;
            exprs[i] = parse_expr(text, &names, false).map_err(|e| {
                let msg = match &e.kind {
                    ParseErrorKind::UnknownIdentifier(n) => {
                        format!("unknown identifier \"{n}\" in the value \"{text}\"")
                    }
                    _ => format!("value: {e}"),
                };
                ModelError::new(&file, element.clone(), msg)
            })?;
        }
        if let Some(cycle) = find_cycles(&exprs).into_iter().next() {
            let mut path: Vec<&str> = cycle.iter().map(|&i| names[i].as_str()).collect();
            path.push(path[0]);
            return Err(ModelError::new(
                &file,
                format!("parameter \"{}\"", names[cycle[0]]),
                format!(
                    "cycle in parameter values after macros and overrides: {}",
                    path.join(" -> ")
                ),
            ));
        }
        let values = evaluate_parameters(&exprs).unwrap_or_else(|_| vec![f64::NAN; exprs.len()]);
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::new(
                &file,
                format!("parameter \"{}\"", names[i]),
                format!(
                    "value \"{}\" is not finite: {}",
                    exprs[i].display(&names),
                    values[i]
                ),
            ));
        }
        Ok(values)
    }

    /// Index of the body with this long name.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Index of the generalized coordinate with this long name.
    pub fn coordinate_index(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }

    /// Index of the force element with this long name.
    pub fn force_index(&self, name: &str) -> Option<usize> {
        self.forces.iter().position(|f| f.name == name)
    }

    /// Index of the parameter with this name.
    pub fn parameter_index(&self, name: &str) -> Option<usize> {
        self.parameters.iter().position(|p| p.name == name)
    }

    /// Initial coordinates (m, rad) and velocities (m/s, rad/s) for the
    /// parameter values `params`.
    pub fn initial_state(&self, params: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let q = self
            .coordinates
            .iter()
            .map(|c| c.initial.eval(params, 0.0))
            .collect();
        let v = self
            .coordinates
            .iter()
            .map(|c| c.initial_velocity.eval(params, 0.0))
            .collect();
        (q, v)
    }

    /// Hex BLAKE3 hash of the model's structure: bodies, joints, every
    /// expression, coordinates (names and places), forces, cut joints, gravity
    /// and parameter names — but not the parameters' default values, their
    /// docs, the macros, the coordinates' initial values and velocities, the
    /// model's name or its source file. A compiled plugin stays valid when only
    /// those inputs change: parameters are its runtime inputs and the initial
    /// state is taken from the model by the runtime.
    pub fn structural_hash(&self) -> String {
        let mut hasher = blake3::Hasher::new();
        hasher.update(self.canonical_structure().as_bytes());
        hasher.finalize().to_hex().to_string()
    }

    /// The canonical text that [`Model::structural_hash`] hashes. Literals are
    /// written with Rust's round-trip `f64` formatting, so equal text means equal
    /// structure.
    pub fn canonical_structure(&self) -> String {
        let mut stripped = self.clone();
        stripped.name.clear();
        stripped.source = None;
        stripped.macros.clear();
        for p in &mut stripped.parameters {
            p.default = Expr::Num(0.0);
            p.doc.clear();
        }
        for c in &mut stripped.coordinates {
            c.initial = Expr::Num(0.0);
            c.initial_velocity = Expr::Num(0.0);
        }
        format!("railmbs-model-structure-v1\n{stripped:?}")
    }
}
