//! Loading a model file: RON → raw syntax → resolved, validated [`Model`].

use crate::error::{ModelError, ModelErrors};
use crate::expr::{Expr, VAR_NAMES};
use crate::forces::{Checks, ForceSpec};
use crate::locate::{Locator, Span};
use crate::model::*;
use crate::parser::{ParseErrorKind, is_identifier, is_reserved_name, parse_expr, parse_expr_vars};
use crate::raw::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

mod include;
use include::{Connection, Includes, Loaded, Node, Sub, close_matches};

/// Reads and resolves a model file, flattening its subsystems (recursively).
/// All problems found are returned together.
pub fn load_model(path: &Path) -> Result<Model, ModelErrors> {
    let text = crate::error::read_text(path, "model")?;
    parse_model(&text, path)
}

/// Resolves model text; `file` names the source in errors and in [`Model::source`].
/// Subsystem files are read relative to `file`'s folder.
pub fn parse_model(text: &str, file: &Path) -> Result<Model, ModelErrors> {
    let mut inc = Includes::top(file);
    parse_with(text, file, &mut inc).map(|loaded| loaded.model)
}

/// Resolves the text of `file`, the innermost file of `inc.stack`.
fn parse_with(text: &str, file: &Path, inc: &mut Includes) -> Result<Loaded, ModelErrors> {
    let loc = Locator::new(text);
    let raw: RawModel = match ron::Options::default().from_str(text) {
        Ok(raw) => raw,
        Err(e) => {
            let mut errors = ron_error(&loc, file, e);
            inc.annotate(&mut errors.0);
            return Err(errors);
        }
    };
    let mut cx = Cx {
        file,
        loc,
        errors: Vec::new(),
        nested: Vec::new(),
        failed: Vec::new(),
        names: Vec::new(),
        defaults: None,
        track_offsets: HashMap::new(),
    };
    let loaded = cx.resolve(raw, inc);
    if cx.errors.is_empty() && cx.nested.is_empty() {
        Ok(loaded)
    } else {
        let mut errors = cx.errors;
        errors.sort_by_key(|e| e.position.unwrap_or((usize::MAX, usize::MAX)));
        inc.annotate(&mut errors);
        // Then the included files' errors, in the order of inclusion.
        errors.extend(cx.nested);
        Err(ModelErrors(errors))
    }
}

/// A RON syntax or structure error, with its position and the element around it.
pub(crate) fn ron_error(loc: &Locator, file: &Path, e: ron::error::SpannedError) -> ModelErrors {
    let pos = (e.span.start.line, e.span.start.col);
    let element = loc
        .enclosing_named(loc.offset_of(pos.0, pos.1))
        .map(|(ctor, name)| format!("{} \"{name}\"", kind_of(&ctor)))
        .unwrap_or_default();
    ModelErrors(vec![ModelError {
        file: file.to_path_buf(),
        element,
        message: e.code.to_string(),
        position: Some(pos),
    }])
}

const BODY: &[&str] = &["Body"];
const SUBSYSTEM: &[&str] = &["Subsystem"];
const CUT: &[&str] = &["CutJoint"];
const FORCE: &[&str] = crate::forces::CONSTRUCTORS;

fn kind_of(ctor: &str) -> &'static str {
    match ctor {
        "Body" => "body",
        "CutJoint" => "cut joint",
        c if FORCE.contains(&c) => "force",
        "Subsystem" => "subsystem",
        "Scenario" => "scenario",
        "Model" => "model",
        _ => "element",
    }
}

/// Where an error is: used to name the element and to find its position.
#[derive(Debug, Clone)]
pub(crate) enum Where {
    Top,
    /// Constructors, name, occurrence (0 = first element with that name).
    Elem(&'static [&'static str], String, usize),
    /// Name, occurrence.
    Param(String, usize),
    Macro(String, usize),
    /// Connection point name, occurrence.
    Conn(String, usize),
    /// The override of parameter `.2` in subsystem `.0` (occurrence `.1`).
    Override(String, usize, String),
}

impl Where {
    fn label(&self) -> String {
        match self {
            Where::Top => String::new(),
            Where::Elem(c, n, _) => format!("{} \"{n}\"", kind_of(c[0])),
            Where::Param(n, _) => format!("parameter \"{n}\""),
            Where::Macro(n, _) => format!("macro \"{n}\""),
            Where::Conn(n, _) => format!("connection \"{n}\""),
            Where::Override(n, _, _) => format!("subsystem \"{n}\""),
        }
    }
}

pub(crate) struct Cx<'a> {
    pub(crate) file: &'a Path,
    loc: Locator<'a>,
    errors: Vec<ModelError>,
    /// Errors of included files, complete with their inclusion note.
    nested: Vec<ModelError>,
    /// Prefixes (`"WS1."`) of subsystems that could not be loaded: unknown
    /// names under them are not reported again.
    failed: Vec<String>,
    /// Parameter names, index = `Expr::Param` index.
    names: Vec<String>,
    /// Default parameter values, when they could all be evaluated.
    pub(crate) defaults: Option<Vec<f64>>,
    /// Track-frame offsets by body name (bodies whose joint starts with a
    /// track-following frame).
    track_offsets: HashMap<String, Expr>,
}

fn axis_name(a: Axis) -> &'static str {
    match a {
        Axis::X => "x",
        Axis::Y => "y",
        Axis::Z => "z",
    }
}

impl Cx<'_> {
    fn span_of(&self, w: &Where) -> Option<Span> {
        match w {
            Where::Top => self.loc.top(),
            Where::Elem(ctors, name, nth) => {
                let mut found = self.loc.element(ctors, name, *nth);
                if found.is_none() {
                    found = self.loc.element(ctors, name, 0);
                }
                found
            }
            Where::Param(n, nth) => {
                let map = self.loc.field_group(self.loc.top()?, "parameters")?;
                let k = self.loc.map_entry(map, n, *nth)?;
                Some((k, k + 3))
            }
            Where::Macro(n, nth) => {
                let map = self.loc.field_group(self.loc.top()?, "macros")?;
                let k = self.loc.map_entry(map, n, *nth)?;
                let (_, close) = self.loc.group_after(k + 2)?;
                Some((k, close))
            }
            Where::Conn(n, nth) => {
                let map = self.loc.field_group(self.loc.top()?, "connections")?;
                let k = self.loc.map_entry(map, n, *nth)?;
                let close = self.loc.group_after(k + 2).map_or(k + 3, |g| g.1);
                Some((k, close))
            }
            Where::Override(n, nth, key) => {
                let sub = self.loc.element(SUBSYSTEM, n, *nth)?;
                let map = self.loc.field_group(sub, "parameters")?;
                let k = self.loc.map_entry(map, key, 0)?;
                Some((k, k + 3))
            }
        }
    }

    /// True if `name` is under a subsystem that could not be loaded.
    fn under_failed(&self, name: &str) -> bool {
        self.failed.iter().any(|p| name.starts_with(p.as_str()))
    }

    /// Records an error at the string literal `literal` or the key `key` inside the element.
    pub(crate) fn err(
        &mut self,
        w: &Where,
        key: Option<&str>,
        literal: Option<&str>,
        message: String,
    ) {
        let position = self.span_of(w).map(|span| {
            let tok = literal
                .and_then(|l| self.loc.string_in(span, l))
                .or_else(|| key.and_then(|k| self.loc.key_anywhere(span, k)))
                .unwrap_or_else(|| self.loc.start_of(span));
            self.loc.pos(tok)
        });
        self.errors.push(ModelError {
            file: self.file.to_path_buf(),
            element: w.label(),
            message,
            position,
        });
    }

    /// Resolves a numeric field. `label` names it in messages, `key` is its RON key.
    /// The height z = f(x, y) of a point–Z-surface contact: an expression in
    /// the local variables x, y and the parameters, finite with the default
    /// parameters at x = y = 0.
    pub(crate) fn surface_expr(&mut self, w: &Where, v: &Value) -> Expr {
        let s = match v {
            Value::Num(x) => return self.expr(w, "surface", "surface", &Value::Num(*x), false),
            Value::Text(s) => s,
        };
        let names = &self.names;
        match parse_expr_vars(s, false, &VAR_NAMES, |id| {
            names.iter().position(|n| n == id)
        }) {
            Ok(e) => {
                if let Some(d) = &self.defaults {
                    let z = e.eval_vars(d, 0.0, &[0.0, 0.0]);
                    if !z.is_finite() {
                        self.err(
                            w,
                            Some("surface"),
                            Some(s),
                            format!("surface \"{s}\" is not finite at x = y = 0 with the default parameters: {z}"),
                        );
                    }
                }
                e
            }
            Err(pe) => {
                let msg = match &pe.kind {
                    ParseErrorKind::UnknownIdentifier(n) => format!(
                        "unknown identifier \"{n}\" in surface (\"{s}\"): use x, y (m, in the surface body's frame) and parameters{}",
                        close_matches(n, self.names.iter().map(String::as_str))
                    ),
                    ParseErrorKind::TimeNotAllowed => {
                        format!("time t is not allowed in surface (\"{s}\")")
                    }
                    ParseErrorKind::Syntax { .. } => format!("surface: {pe}"),
                };
                self.err(w, Some("surface"), Some(s), msg);
                Expr::Num(f64::NAN)
            }
        }
    }

    pub(crate) fn expr(
        &mut self,
        w: &Where,
        label: &str,
        key: &str,
        v: &Value,
        allow_time: bool,
    ) -> Expr {
        match v {
            Value::Num(x) => {
                if !x.is_finite() {
                    self.err(w, Some(key), None, format!("{label} is not finite: {x}"));
                }
                Expr::Num(*x)
            }
            Value::Text(s) => match parse_expr(s, &self.names, allow_time) {
                Ok(e) => {
                    if !e.has_time()
                        && let Some(d) = &self.defaults
                    {
                        let x = e.eval(d, 0.0);
                        if !x.is_finite() {
                            self.err(
                                w,
                                Some(key),
                                Some(s),
                                format!(
                                    "{label} = \"{s}\" is not finite with the default parameters: {x}"
                                ),
                            );
                        }
                    }
                    e
                }
                Err(pe) => {
                    let msg = match &pe.kind {
                        ParseErrorKind::UnknownIdentifier(n) if self.under_failed(n) => {
                            return Expr::Num(f64::NAN);
                        }
                        ParseErrorKind::UnknownIdentifier(n) => format!(
                            "unknown identifier \"{n}\" in {label} (\"{s}\"){}",
                            close_matches(n, self.names.iter().map(String::as_str))
                        ),
                        ParseErrorKind::TimeNotAllowed => format!(
                            "time t is not allowed in {label} (\"{s}\"); only elementary transforms and applied forces may depend on time"
                        ),
                        ParseErrorKind::Syntax { .. } => format!("{label}: {pe}"),
                    };
                    self.err(w, Some(key), Some(s), msg);
                    Expr::Num(f64::NAN)
                }
            },
        }
    }

    pub(crate) fn vec3(&mut self, w: &Where, label: &str, v: &Vec3, allow_time: bool) -> [Expr; 3] {
        let comps = [&v.0, &v.1, &v.2];
        std::array::from_fn(|i| {
            let l = format!("{label}.{}", ["x", "y", "z"][i]);
            self.expr(w, &l, label, comps[i], allow_time)
        })
    }

    pub(crate) fn vec6(&mut self, w: &Where, label: &str, v: &Vec6) -> [Expr; 6] {
        let comps = [&v.0, &v.1, &v.2, &v.3, &v.4, &v.5];
        std::array::from_fn(|i| self.expr(w, &format!("{label}[{i}]"), label, comps[i], false))
    }

    fn resolve(&mut self, raw: RawModel, inc: &mut Includes) -> Loaded {
        let own = self.parameter_names(&raw);
        let mut subs = self.load_subsystems(&raw, inc);
        let parameters = self.parameters(own, &mut subs);
        let macros = self.macros(&raw, &subs);
        let gravity = self.vec3(&Where::Top, "gravity", &raw.gravity, false);
        let (bodies, coordinates, mut lookup) = self.bodies(&raw, &mut subs);
        let connections = self.connections(&raw, &subs, &mut lookup);
        let cut_joints = self.cut_joints(&raw, &lookup, &subs);
        let forces = self.forces(&raw, &lookup, &subs);
        // Number the track-following frames in body order; their input
        // transformations carry the component (0..6) until now.
        let mut bodies = bodies;
        let mut track_frames = Vec::new();
        for (b, body) in bodies.iter_mut().enumerate() {
            if let Some(offset) = self.track_offsets.get(&body.name) {
                let frame = track_frames.len();
                for el in &mut body.joint {
                    if let Motion::Input(component) = &mut el.motion {
                        *component += 6 * frame;
                    }
                }
                track_frames.push(TrackFrame {
                    body: b,
                    offset: offset.clone(),
                });
            }
        }
        self.check_instance_values(&subs, &bodies, &coordinates, &cut_joints, &forces);
        let model = Model {
            track_frames,
            name: raw.name.clone(),
            source: Some(self.file.to_path_buf()),
            parameters,
            macros,
            gravity,
            bodies,
            coordinates,
            cut_joints,
            forces,
        };
        Loaded { model, connections }
    }

    /// The values of the subsystems' elements are finite with the defaults of
    /// this file (which include the instances' overrides). This file's own
    /// elements were checked as they were resolved.
    fn check_instance_values(
        &mut self,
        subs: &[Sub],
        bodies: &[Body],
        coordinates: &[Coordinate],
        cut_joints: &[CutJoint],
        forces: &[ForceElement],
    ) {
        let Some(d) = self.defaults.clone() else {
            return;
        };
        let bad = |e: &mut Expr, found: &mut Option<f64>| {
            let x = e.eval(&d, 0.0);
            if found.is_none() && !e.has_time() && !x.is_finite() {
                *found = Some(x);
            }
        };
        let mut problems: Vec<(String, String, f64)> = Vec::new();
        for b in bodies {
            let mut found = None;
            let mut b = b.clone();
            bad(&mut b.mass, &mut found);
            b.inertia.iter_mut().for_each(|e| bad(e, &mut found));
            for el in &mut b.joint {
                if let Motion::Fixed(e) | Motion::Time(e) = &mut el.motion {
                    bad(e, &mut found);
                }
            }
            if let Some(x) = found {
                problems.push((format!("body \"{}\"", b.name), b.name, x));
            }
        }
        for c in coordinates {
            let mut found = None;
            let mut c = c.clone();
            bad(&mut c.initial, &mut found);
            bad(&mut c.initial_velocity, &mut found);
            if let Some(x) = found {
                problems.push((format!("coordinate \"{}\"", c.name), c.name, x));
            }
        }
        for c in cut_joints {
            let mut found = None;
            c.clone().exprs_mut(&mut |e| bad(e, &mut found));
            if let Some(x) = found {
                problems.push((format!("cut joint \"{}\"", c.name), c.name.clone(), x));
            }
        }
        let mut ranges: Vec<(String, String)> = Vec::new();
        for f in forces {
            let mut found = None;
            f.kind.clone().exprs_mut(&mut |e| bad(e, &mut found));
            if let Some(x) = found {
                problems.push((format!("force \"{}\"", f.name), f.name.clone(), x));
            }
            let mut checks = Checks::new(&d);
            f.kind.check(&mut checks);
            for (_, message) in checks.problems {
                ranges.push((f.name.clone(), message));
            }
        }
        let problems = problems
            .into_iter()
            .map(|(what, name, x)| {
                (
                    name,
                    format!("{what}, with this instance's parameters: a value is not finite: {x}"),
                )
            })
            .chain(ranges.into_iter().map(|(name, message)| {
                let m = format!("force \"{name}\", with this instance's parameters: {message}");
                (name, m)
            }));
        for (name, message) in problems {
            // Elements of this file were checked when they were resolved.
            if let Some(sub) = subs.iter().find(|s| name.starts_with(&s.prefix)) {
                let w = Where::Elem(SUBSYSTEM, sub.raw.name.clone(), sub.nth);
                self.err(&w, None, None, message);
            }
        }
    }

    /// Validates the names of this file's own parameters and puts them in
    /// `self.names`; returns their raw values (same order).
    fn parameter_names<'r>(&mut self, raw: &'r RawModel) -> Vec<&'r ParamValue> {
        let mut kept = Vec::new();
        for (i, (name, pv)) in raw.parameters.0.iter().enumerate() {
            let nth = occurrence(&raw.parameters.0, i, |p| &p.0);
            let w = Where::Param(name.clone(), nth);
            if !is_identifier(name) {
                self.err(
                    &w,
                    None,
                    None,
                    "not a valid identifier (letters, digits, '_' and '.', starting with a letter or '_')".into(),
                );
            } else if is_reserved_name(name) {
                self.err(
                    &w,
                    None,
                    None,
                    "the name is reserved (t, pi and function names)".into(),
                );
            } else if self.names.contains(name) {
                self.err(&w, None, None, "duplicate parameter name".into());
                continue;
            }
            self.names.push(name.clone());
            kept.push(pv);
        }
        kept
    }

    /// Where parameter `i` (of `self.names`) is defined or overridden in this file.
    fn param_where(&self, i: usize, own: usize, subs: &[Sub]) -> Where {
        if i < own {
            return Where::Param(self.names[i].clone(), 0);
        }
        for sub in subs {
            let n = sub.loaded.model.parameters.len();
            if (sub.param_offset..sub.param_offset + n).contains(&i) {
                let local = &sub.loaded.model.parameters[i - sub.param_offset].name;
                let overridden = sub.raw.parameters.0.iter().any(|(k, _)| k == local);
                return if overridden {
                    Where::Override(sub.raw.name.clone(), sub.nth, local.clone())
                } else {
                    Where::Elem(SUBSYSTEM, sub.raw.name.clone(), sub.nth)
                };
            }
        }
        Where::Top
    }

    /// Parameters: this file's own (file order), then each subsystem's with
    /// its prefix, overridden ones taking the override as their default. Sets
    /// `self.names` and, when they can all be evaluated, `self.defaults`.
    fn parameters(&mut self, kept: Vec<&ParamValue>, subs: &mut [Sub]) -> Vec<Parameter> {
        let own = self.names.len();
        for sub in subs.iter_mut() {
            sub.param_offset = self.names.len();
            for p in &sub.loaded.model.parameters {
                let long = format!("{}{}", sub.prefix, p.name);
                if self.names[..own].contains(&long) {
                    let w = Where::Param(long.clone(), 0);
                    self.err(
                        &w,
                        None,
                        None,
                        format!(
                            "duplicate parameter name: subsystem \"{}\" has a parameter \"{}\"",
                            sub.raw.name, p.name
                        ),
                    );
                }
                self.names.push(long);
            }
        }
        let mut params: Vec<Parameter> = kept
            .iter()
            .zip(self.names.clone())
            .map(|(pv, name)| {
                let w = Where::Param(name.clone(), 0);
                Parameter {
                    default: self.expr(&w, "the default value", "", &pv.value, false),
                    name,
                    doc: pv.doc.clone(),
                }
            })
            .collect();
        for sub in subs.iter() {
            let offset = sub.param_offset;
            for (i, p) in sub.loaded.model.parameters.iter().enumerate() {
                params.push(Parameter {
                    name: self.names[offset + i].clone(),
                    default: p.default.map_params(&mut |j| Expr::Param(j + offset)),
                    doc: p.doc.clone(),
                });
            }
        }
        for sub in subs.iter().filter(|s| !s.failed) {
            let model = &sub.loaded.model;
            for (k, (pname, v)) in sub.raw.parameters.0.iter().enumerate() {
                let w = Where::Override(sub.raw.name.clone(), sub.nth, pname.clone());
                let Some(i) = model.parameter_index(pname) else {
                    let known: Vec<&str> =
                        model.parameters.iter().map(|p| p.name.as_str()).collect();
                    self.err(
                        &w,
                        None,
                        None,
                        format!(
                            "unknown parameter \"{pname}\" of subsystem file {}{}",
                            sub.path.display(),
                            close_matches(pname, known.iter().copied())
                        ),
                    );
                    continue;
                };
                if sub.raw.parameters.0[..k].iter().any(|(n, _)| n == pname) {
                    self.err(&w, None, None, format!("overrides \"{pname}\" twice"));
                    continue;
                }
                let label = format!("the override of \"{pname}\"");
                params[sub.param_offset + i].default = self.expr(&w, &label, "", v, false);
            }
        }
        let exprs: Vec<Expr> = params.iter().map(|p| p.default.clone()).collect();
        let cycles = find_cycles(&exprs);
        for cycle in &cycles {
            let mut path: Vec<&str> = cycle.iter().map(|&i| self.names[i].as_str()).collect();
            path.push(path[0]);
            let message = format!("cycle in parameter default values: {}", path.join(" -> "));
            // Prefer a place in this file that the user can edit: an own
            // parameter, else an override.
            let at = cycle
                .iter()
                .copied()
                .find(|&i| i < own)
                .or_else(|| {
                    cycle
                        .iter()
                        .copied()
                        .find(|&i| matches!(self.param_where(i, own, subs), Where::Override(..)))
                })
                .unwrap_or(cycle[0]);
            let w = self.param_where(at, own, subs);
            self.err(&w, None, None, message);
        }
        // Not evaluated with an unloadable subsystem: its parameters are missing.
        if self.errors.is_empty()
            && self.failed.is_empty()
            && let Ok(values) = evaluate_parameters(&exprs)
        {
            for (i, v) in values.iter().enumerate() {
                if !v.is_finite() {
                    let w = self.param_where(i, own, subs);
                    let message = if i < own {
                        format!("default value is not finite: {v}")
                    } else {
                        format!("parameter \"{}\" is not finite: {v}", self.names[i])
                    };
                    self.err(&w, None, None, message);
                }
            }
            if values.iter().all(|v| v.is_finite()) {
                self.defaults = Some(values);
            }
        }
        params
    }

    fn macros(&mut self, raw: &RawModel, subs: &[Sub]) -> Vec<Macro> {
        let mut out: Vec<Macro> = Vec::new();
        for (i, (name, assigns)) in raw.macros.0.iter().enumerate() {
            let nth = occurrence(&raw.macros.0, i, |m| &m.0);
            let w = Where::Macro(name.clone(), nth);
            if out.iter().any(|m| &m.name == name) {
                self.err(&w, None, None, "duplicate macro name".into());
                continue;
            }
            let mut assignments = Vec::new();
            for (pname, v) in &assigns.0 {
                match self.names.iter().position(|n| n == pname) {
                    Some(i) => {
                        let e = self.expr(&w, &format!("the value of \"{pname}\""), "", v, false);
                        if assignments.iter().any(|(j, _)| *j == i) {
                            self.err(&w, None, Some(pname), format!("assigns \"{pname}\" twice"));
                        }
                        assignments.push((i, e));
                    }
                    None => self.err(
                        &w,
                        None,
                        Some(pname),
                        format!("unknown parameter \"{pname}\""),
                    ),
                }
            }
            out.push(Macro {
                name: name.clone(),
                assignments,
            });
        }
        // The subsystems' macros, with long names.
        for sub in subs {
            let offset = sub.param_offset;
            for m in &sub.loaded.model.macros {
                let name = format!("{}{}", sub.prefix, m.name);
                if let Some(nth) = raw.macros.0.iter().position(|(n, _)| *n == name) {
                    let w = Where::Macro(name.clone(), nth);
                    self.err(
                        &w,
                        None,
                        None,
                        format!(
                            "duplicate macro name: subsystem \"{}\" has a macro \"{}\"",
                            sub.raw.name, m.name
                        ),
                    );
                    continue;
                }
                let assignments = m
                    .assignments
                    .iter()
                    .map(|(i, e)| (i + offset, e.map_params(&mut |j| Expr::Param(j + offset))))
                    .collect();
                out.push(Macro { name, assignments });
            }
        }
        out
    }

    /// Bodies of this file and of its subsystems in topological order
    /// (parents first; otherwise this file's bodies in file order, then each
    /// subsystem's in its order), their coordinates, and the names bodies are
    /// known by. Sets each subsystem's `body_map`.
    fn bodies(&mut self, raw: &RawModel, subs: &mut [Sub]) -> (Vec<Body>, Vec<Coordinate>, Lookup) {
        // Nodes: this file's bodies, then every subsystem's bodies.
        let n_raw = raw.bodies.len();
        let mut nodes: Vec<Node> = (0..n_raw).map(Node::Raw).collect();
        let mut names: Vec<String> = raw.bodies.iter().map(|b| b.name.clone()).collect();
        let mut sub_first = Vec::with_capacity(subs.len());
        for (k, sub) in subs.iter().enumerate() {
            sub_first.push(nodes.len());
            for (j, b) in sub.loaded.model.bodies.iter().enumerate() {
                nodes.push(Node::Sub(k, j));
                names.push(format!("{}{}", sub.prefix, b.name));
            }
        }
        let n = nodes.len();
        let mut first: HashMap<&str, usize> = HashMap::new();
        for (i, name) in names.iter().enumerate().skip(n_raw) {
            first.insert(name.as_str(), i);
        }
        let mut valid = vec![true; n];
        for (i, b) in raw.bodies.iter().enumerate() {
            let nth = occurrence(&raw.bodies, i, |o| &o.name);
            let w = Where::Elem(BODY, b.name.clone(), nth);
            if b.name.is_empty() {
                self.err(
                    &w,
                    Some("name"),
                    None,
                    "a body needs a non-empty name".into(),
                );
            }
            if b.name == "ground" {
                self.err(
                    &w,
                    Some("name"),
                    None,
                    "\"ground\" is the inertial frame and cannot name a body".into(),
                );
                valid[i] = false;
            } else if let Some(&other) = first.get(b.name.as_str()) {
                let message = match nodes[other] {
                    Node::Sub(k, j) => format!(
                        "duplicate body name: subsystem \"{}\" has a body \"{}\"",
                        subs[k].raw.name, subs[k].loaded.model.bodies[j].name
                    ),
                    Node::Raw(_) => "duplicate body name".into(),
                };
                self.err(&w, Some("name"), None, message);
                valid[i] = false;
            } else {
                first.insert(&b.name, i);
            }
        }
        let connection_names: Vec<String> = raw
            .connections
            .0
            .iter()
            .map(|(n, _)| n.clone())
            .chain(subs.iter().flat_map(|s| {
                s.loaded
                    .connections
                    .iter()
                    .map(|c| format!("{}{}", s.prefix, c.name))
            }))
            .collect();
        let unknown_parent = |p: &str| {
            if connection_names.iter().any(|c| c == p) {
                format!(
                    "\"{p}\" is a connection point, not a body: a joint's parent must be a body"
                )
            } else {
                format!(
                    "unknown body \"{p}\" as parent{}",
                    close_matches(p, names.iter().map(String::as_str))
                )
            }
        };
        // The body each subsystem's ground-attached bodies hang on.
        let mut sub_parent: Vec<Option<usize>> = vec![None; subs.len()];
        for (k, sub) in subs.iter().enumerate() {
            let Some(p) = &sub.raw.parent else { continue };
            let w = Where::Elem(SUBSYSTEM, sub.raw.name.clone(), sub.nth);
            if p == "ground" {
                continue;
            }
            match first.get(p.as_str()) {
                Some(&q) => sub_parent[k] = Some(q),
                None if self.under_failed(p) => {}
                None => {
                    let message = unknown_parent(p);
                    self.err(&w, Some("parent"), Some(p), message);
                }
            }
            for t in &sub.loaded.model.track_frames {
                let body = &sub.loaded.model.bodies[t.body].name;
                self.err(
                    &w,
                    Some("parent"),
                    Some(p),
                    format!(
                        "cannot re-attach body \"{}{body}\" to \"{p}\": it hangs on a track-following frame (SixDof with track), which moves relative to ground",
                        sub.prefix
                    ),
                );
            }
        }
        // Parent node of each node: None = ground.
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for i in 0..n {
            match nodes[i] {
                Node::Raw(r) => {
                    let b = &raw.bodies[r];
                    let p = b.joint.parent();
                    if !valid[i] || p == "ground" {
                        continue;
                    }
                    match first.get(p) {
                        Some(&j) => parent[i] = Some(j),
                        None if self.under_failed(p) => valid[i] = false,
                        None => {
                            let w = Where::Elem(BODY, b.name.clone(), 0);
                            let message = unknown_parent(p);
                            self.err(&w, Some("parent"), Some(p), message);
                            valid[i] = false;
                        }
                    }
                }
                Node::Sub(k, j) => {
                    let model = &subs[k].loaded.model;
                    parent[i] = match model.bodies[j].parent {
                        BodyRef::Body(pj) => Some(sub_first[k] + pj),
                        BodyRef::Ground if model.track_frames.iter().any(|t| t.body == j) => None,
                        BodyRef::Ground => sub_parent[k],
                    };
                }
            }
        }
        let node_where = |i: usize| match nodes[i] {
            Node::Raw(r) => Where::Elem(BODY, raw.bodies[r].name.clone(), 0),
            Node::Sub(k, _) => Where::Elem(SUBSYSTEM, subs[k].raw.name.clone(), subs[k].nth),
        };
        // Topological order, keeping file order where possible; detect loops.
        // state: 0 unvisited, 1 placed, 2 excluded (in or below a loop, or invalid).
        let mut state = vec![0u8; n];
        for i in 0..n {
            if !valid[i] {
                state[i] = 2;
            }
        }
        let mut order = Vec::new();
        for i in 0..n {
            if state[i] != 0 {
                continue;
            }
            let mut path = Vec::new();
            let mut cur = Some(i);
            let mut bad = false;
            while let Some(c) = cur {
                if state[c] == 1 {
                    break;
                }
                if state[c] == 2 {
                    bad = true;
                    break;
                }
                if let Some(k) = path.iter().position(|&p| p == c) {
                    let cycle: &[usize] = &path[k..];
                    let mut cycle_names: Vec<&str> =
                        cycle.iter().map(|&j| names[j].as_str()).collect();
                    cycle_names.push(cycle_names[0]);
                    // Report at a body of this file if the loop has one.
                    let at = cycle
                        .iter()
                        .copied()
                        .find(|&j| j < n_raw)
                        .unwrap_or(cycle[0]);
                    self.err(
                        &node_where(at),
                        Some("parent"),
                        None,
                        format!(
                            "loop in the body tree (body -> its parent): {}",
                            cycle_names.join(" -> ")
                        ),
                    );
                    bad = true;
                    break;
                }
                path.push(c);
                cur = parent[c];
            }
            for &c in path.iter().rev() {
                if bad {
                    state[c] = 2;
                } else {
                    state[c] = 1;
                    order.push(c);
                }
            }
        }
        let mut node_to_new = vec![None; n];
        for (k, &i) in order.iter().enumerate() {
            node_to_new[i] = Some(k);
        }
        let mut bodies = Vec::new();
        let mut coords: Vec<Coordinate> = Vec::new();
        for (k, &i) in order.iter().enumerate() {
            let parent = match parent[i] {
                None => BodyRef::Ground,
                Some(j) => BodyRef::Body(node_to_new[j].unwrap_or(0)),
            };
            let (w, body, new_coords) = match nodes[i] {
                Node::Raw(r) => {
                    let b = &raw.bodies[r];
                    let w = Where::Elem(BODY, b.name.clone(), 0);
                    let mass = self.expr(&w, "mass", "mass", &b.mass, false);
                    let r = &b.inertia;
                    let inertia = [
                        self.expr(&w, "inertia.ixx", "ixx", &r.ixx, false),
                        self.expr(&w, "inertia.iyy", "iyy", &r.iyy, false),
                        self.expr(&w, "inertia.izz", "izz", &r.izz, false),
                        self.expr(&w, "inertia.ixy", "ixy", &r.ixy, false),
                        self.expr(&w, "inertia.ixz", "ixz", &r.ixz, false),
                        self.expr(&w, "inertia.iyz", "iyz", &r.iyz, false),
                    ];
                    self.check_mass(&w, &mass, &inertia);
                    let mut jb = JointBuilder {
                        body: k,
                        body_name: &b.name,
                        joint: Vec::new(),
                        coords: Vec::new(),
                    };
                    self.expand_joint(&w, &b.joint, &mut jb);
                    let body = Body {
                        name: b.name.clone(),
                        mass,
                        inertia,
                        parent,
                        joint: jb.joint,
                    };
                    (w, body, jb.coords)
                }
                Node::Sub(s, j) => {
                    let sub = &subs[s];
                    let model = &sub.loaded.model;
                    let w = Where::Elem(SUBSYSTEM, sub.raw.name.clone(), sub.nth);
                    let offset = sub.param_offset;
                    let shift = |e: &Expr| e.map_params(&mut |p| Expr::Param(p + offset));
                    let cb = &model.bodies[j];
                    let name = names[i].clone();
                    let mass = shift(&cb.mass);
                    let inertia = cb.inertia.each_ref().map(shift);
                    // The subsystem was checked with its own defaults; with
                    // this instance's parameters it may no longer be valid.
                    let before = self.errors.len();
                    self.check_mass(&w, &mass, &inertia);
                    for e in &mut self.errors[before..] {
                        e.message = format!(
                            "body \"{name}\", with this instance's parameters: {}",
                            e.message
                        );
                    }
                    let mut joint = Vec::with_capacity(cb.joint.len());
                    for el in &cb.joint {
                        let motion = match &el.motion {
                            Motion::Fixed(e) => Motion::Fixed(shift(e)),
                            Motion::Time(e) => Motion::Time(shift(e)),
                            // Numbered below, with the coordinates.
                            Motion::Coordinate(_) => Motion::Coordinate(usize::MAX),
                            Motion::Input(m) => {
                                if let Some(frame) = model.track_frames.get(m / 6) {
                                    self.track_offsets
                                        .insert(name.clone(), shift(&frame.offset));
                                }
                                Motion::Input(m % 6)
                            }
                        };
                        joint.push(Elementary {
                            kind: el.kind,
                            motion,
                        });
                    }
                    let new_coords = model
                        .coordinates
                        .iter()
                        .filter(|c| c.body == j)
                        .map(|c| Coordinate {
                            name: format!("{}{}", sub.prefix, c.name),
                            body: k,
                            elementary: c.elementary,
                            initial: shift(&c.initial),
                            initial_velocity: shift(&c.initial_velocity),
                        })
                        .collect();
                    let body = Body {
                        name,
                        mass,
                        inertia,
                        parent,
                        joint,
                    };
                    (w, body, new_coords)
                }
            };
            let mut body = body;
            for mut c in new_coords {
                if let Some(other) = coords.iter().find(|o| o.name == c.name) {
                    let other_body = bodies
                        .get(other.body)
                        .map_or(body.name.as_str(), |ob: &Body| ob.name.as_str())
                        .to_string();
                    self.err(
                        &w,
                        None,
                        Some(&c.name),
                        format!(
                            "duplicate coordinate name \"{}\" (also in body \"{other_body}\")",
                            c.name
                        ),
                    );
                } else if c.name.is_empty() {
                    self.err(&w, Some("coord"), None, "empty coordinate name".into());
                } else {
                    let global = coords.len();
                    c.body = k;
                    if let Some(el) = body.joint.get_mut(c.elementary) {
                        el.motion = Motion::Coordinate(global);
                    }
                    coords.push(c);
                }
            }
            bodies.push(body);
        }
        let mut lookup = Lookup {
            names: HashMap::new(),
        };
        for (i, name) in names.iter().enumerate() {
            let target = match node_to_new[i] {
                Some(k) => Target::Body(BodyRef::Body(k)),
                // Invalid (reported where it is defined).
                None => Target::Invalid,
            };
            if !lookup.names.contains_key(name) || node_to_new[i].is_some() {
                lookup.names.insert(name.clone(), target);
            }
        }
        for (k, sub) in subs.iter_mut().enumerate() {
            sub.body_map = (0..sub.loaded.model.bodies.len())
                .map(|j| node_to_new[sub_first[k] + j].unwrap_or(0))
                .collect();
        }
        (bodies, coords, lookup)
    }

    /// Mass positive; inertia positive definite and physically realizable
    /// (principal moments satisfy the triangle inequality), with default parameters.
    fn check_mass(&mut self, w: &Where, mass: &Expr, inertia: &[Expr; 6]) {
        let Some(d) = self.defaults.clone() else {
            return;
        };
        let m = mass.eval(&d, 0.0);
        if m.is_finite() && m <= 0.0 {
            self.err(
                w,
                Some("mass"),
                None,
                format!("mass must be positive, got {m}"),
            );
        }
        let i: Vec<f64> = inertia.iter().map(|e| e.eval(&d, 0.0)).collect();
        if i.iter().any(|x| !x.is_finite()) {
            return;
        }
        let (ixx, iyy, izz) = (i[0], i[1], i[2]);
        // Relative slack for rounding in the defaults' expressions.
        let slack = 1e-9 * (ixx.abs() + iyy.abs() + izz.abs());
        for (a, b, c, na, nb, nc) in [
            (ixx, iyy, izz, "ixx", "iyy", "izz"),
            (iyy, izz, ixx, "iyy", "izz", "ixx"),
            (izz, ixx, iyy, "izz", "ixx", "iyy"),
        ] {
            if a + b < c - slack {
                self.err(
                    w,
                    Some("inertia"),
                    None,
                    format!(
                        "inertia violates the triangle inequality: {na} + {nb} = {} < {nc} = {c}",
                        a + b
                    ),
                );
                return;
            }
        }
        let ev = sym3_eigenvalues([[ixx, i[3], i[4]], [i[3], iyy, i[5]], [i[4], i[5], izz]]);
        if ev.iter().any(|&l| l <= 0.0) {
            self.err(
                w,
                Some("inertia"),
                None,
                format!(
                    "inertia tensor is not positive definite: principal moments {:?} kg m²",
                    ev
                ),
            );
            return;
        }
        let [a, b, c] = ev;
        if a + b < c - slack || b + c < a - slack || c + a < b - slack {
            self.err(
                w,
                Some("inertia"),
                None,
                format!(
                    "inertia violates the triangle inequality for its principal moments {:?} kg m²",
                    ev
                ),
            );
        }
    }

    fn fixed(
        &mut self,
        w: &Where,
        jb: &mut JointBuilder,
        kind: ElementaryKind,
        label: &str,
        key: &str,
        v: &Value,
    ) {
        if v.is_literal_zero() {
            return;
        }
        let e = self.expr(w, label, key, v, false);
        jb.joint.push(Elementary {
            kind,
            motion: Motion::Fixed(e),
        });
    }

    fn fixed3(&mut self, w: &Where, jb: &mut JointBuilder, translate: bool, label: &str, v: &Vec3) {
        let comps = [&v.0, &v.1, &v.2];
        for (k, axis) in [Axis::X, Axis::Y, Axis::Z].into_iter().enumerate() {
            let kind = if translate {
                ElementaryKind::Translation(axis)
            } else {
                ElementaryKind::Rotation(axis)
            };
            let l = format!("joint.{label}.{}", axis_name(axis));
            self.fixed(w, jb, kind, &l, label, comps[k]);
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn coordinate(
        &mut self,
        w: &Where,
        jb: &mut JointBuilder,
        kind: ElementaryKind,
        name: String,
        init: &Value,
        vel: &Value,
        key_init: &str,
        key_vel: &str,
    ) {
        let initial = self.expr(
            w,
            &format!("the initial value of \"{name}\""),
            key_init,
            init,
            false,
        );
        let initial_velocity = self.expr(
            w,
            &format!("the initial velocity of \"{name}\""),
            key_vel,
            vel,
            false,
        );
        jb.coords.push(Coordinate {
            name,
            body: jb.body,
            elementary: jb.joint.len(),
            initial,
            initial_velocity,
        });
        // The global coordinate index is set by `bodies` once the coordinate's
        // name is known to be unique.
        jb.joint.push(Elementary {
            kind,
            motion: Motion::Coordinate(usize::MAX),
        });
    }

    /// Starts the joint of `jb` with a track-following frame at arc offset
    /// `offset` (six input transformations: x, y, z, yaw, pitch, roll).
    fn track_frame(&mut self, w: &Where, jb: &mut JointBuilder, parent: &str, offset: &Value) {
        if parent != "ground" {
            self.err(
                        w,
                        Some("track"),
                        None,
                        format!(
                            "a track-following frame moves relative to SC0: the parent must be \"ground\", not \"{parent}\""
                        ),
                    );
        }
        let e = self.expr(w, "track offset", "track", offset, false);
        self.track_offsets.insert(jb.body_name.to_string(), e);
        // Pose of the frame: x, y, z, then yaw (z), pitch (y), roll (x).
        let kinds = [
            ElementaryKind::Translation(Axis::X),
            ElementaryKind::Translation(Axis::Y),
            ElementaryKind::Translation(Axis::Z),
            ElementaryKind::Rotation(Axis::Z),
            ElementaryKind::Rotation(Axis::Y),
            ElementaryKind::Rotation(Axis::X),
        ];
        for (component, kind) in kinds.into_iter().enumerate() {
            jb.joint.push(Elementary {
                kind,
                motion: Motion::Input(component),
            });
        }
    }

    fn expand_joint(&mut self, w: &Where, joint: &RawJoint, jb: &mut JointBuilder) {
        match joint {
            RawJoint::Revolute {
                at,
                axis,
                coord,
                init,
                vel,
                to_com,
                ..
            }
            | RawJoint::Prismatic {
                at,
                axis,
                coord,
                init,
                vel,
                to_com,
                ..
            } => {
                let revolute = matches!(joint, RawJoint::Revolute { .. });
                self.fixed3(w, jb, true, "at", at);
                let (kind, prefix) = if revolute {
                    (ElementaryKind::Rotation(*axis), "r")
                } else {
                    (ElementaryKind::Translation(*axis), "t")
                };
                let name = if coord.is_empty() {
                    format!("{}.{prefix}{}", jb.body_name, axis_name(*axis))
                } else {
                    coord.clone()
                };
                self.coordinate(w, jb, kind, name, init, vel, "init", "vel");
                self.fixed3(w, jb, true, "to_com", to_com);
            }
            RawJoint::SixDof {
                parent,
                at,
                order,
                init,
                vel,
                track,
            } => {
                if let Some(offset) = track {
                    self.track_frame(w, jb, parent, offset);
                }
                self.fixed3(w, jb, true, "at", at);
                let inits = [&init.0, &init.1, &init.2, &init.3, &init.4, &init.5];
                let vels = [&vel.0, &vel.1, &vel.2, &vel.3, &vel.4, &vel.5];
                for (k, axis) in [Axis::X, Axis::Y, Axis::Z].into_iter().enumerate() {
                    let name = format!("{}.{}", jb.body_name, axis_name(axis));
                    self.coordinate(
                        w,
                        jb,
                        ElementaryKind::Translation(axis),
                        name,
                        inits[k],
                        vels[k],
                        "init",
                        "vel",
                    );
                }
                let lower = order.to_ascii_lowercase();
                let mut axes = Vec::new();
                for c in lower.chars() {
                    match c {
                        'x' => axes.push(Axis::X),
                        'y' => axes.push(Axis::Y),
                        'z' => axes.push(Axis::Z),
                        _ => {}
                    }
                }
                let permutation = lower.len() == 3
                    && axes.len() == 3
                    && axes.contains(&Axis::X)
                    && axes.contains(&Axis::Y)
                    && axes.contains(&Axis::Z);
                if !permutation {
                    self.err(
                        w,
                        Some("order"),
                        Some(order),
                        format!("rotation order must be a permutation of \"xyz\", got \"{order}\""),
                    );
                    return;
                }
                for axis in axes {
                    let name = format!("{}.r{}", jb.body_name, axis_name(axis));
                    let k = 3 + axis.index();
                    self.coordinate(
                        w,
                        jb,
                        ElementaryKind::Rotation(axis),
                        name,
                        inits[k],
                        vels[k],
                        "init",
                        "vel",
                    );
                }
            }
            RawJoint::Rigid {
                parent,
                at,
                rotation,
                track,
            } => {
                if let Some(offset) = track {
                    self.track_frame(w, jb, parent, offset);
                }
                self.fixed3(w, jb, true, "at", at);
                self.fixed3(w, jb, false, "rotation", rotation);
            }
            RawJoint::Joint { transforms, .. } => {
                for (k, t) in transforms.iter().enumerate() {
                    let (kind, arg, tn) = match t {
                        RawTransform::Tx(a) => (ElementaryKind::Translation(Axis::X), a, "Tx"),
                        RawTransform::Ty(a) => (ElementaryKind::Translation(Axis::Y), a, "Ty"),
                        RawTransform::Tz(a) => (ElementaryKind::Translation(Axis::Z), a, "Tz"),
                        RawTransform::Rx(a) => (ElementaryKind::Rotation(Axis::X), a, "Rx"),
                        RawTransform::Ry(a) => (ElementaryKind::Rotation(Axis::Y), a, "Ry"),
                        RawTransform::Rz(a) => (ElementaryKind::Rotation(Axis::Z), a, "Rz"),
                    };
                    match arg {
                        TransformArg::Value(v) => {
                            let label = format!("joint transform {} ({tn})", k + 1);
                            let e = self.expr(w, &label, tn, v, true);
                            let motion = if e.has_time() {
                                Motion::Time(e)
                            } else {
                                Motion::Fixed(e)
                            };
                            jb.joint.push(Elementary { kind, motion });
                        }
                        TransformArg::Coord { coord, init, vel } => {
                            self.coordinate(w, jb, kind, coord.clone(), init, vel, "init", "vel");
                        }
                    }
                }
            }
        }
    }
}

struct JointBuilder<'a> {
    body: usize,
    body_name: &'a str,
    joint: Vec<Elementary>,
    coords: Vec<Coordinate>,
}

/// What a name in a force element or cut joint refers to.
#[derive(Debug, Clone)]
pub(crate) enum Target {
    Body(BodyRef),
    /// A connection point: a point (in the body frame) of a body.
    Conn(BodyRef, [Expr; 3]),
    /// A body that is invalid (reported where it is defined).
    Invalid,
}

/// Bodies and connection points by (long) name.
pub(crate) struct Lookup {
    pub(crate) names: HashMap<String, Target>,
}

/// `a + b` componentwise, folding literal zeros and numbers.
pub(crate) fn add3(a: &[Expr; 3], b: [Expr; 3]) -> [Expr; 3] {
    let mut b = b.into_iter();
    std::array::from_fn(|k| {
        let y = b.next().unwrap_or(Expr::Num(0.0));
        match (&a[k], y) {
            (x, y) if y.is_zero() => x.clone(),
            (x, y) if x.is_zero() => y,
            (Expr::Num(x), Expr::Num(y)) => Expr::Num(x + y),
            (x, y) => Expr::Add(Box::new(x.clone()), Box::new(y)),
        }
    })
}

impl Cx<'_> {
    /// The body (or connection point) `name` written at `key`: the body and
    /// the connection's point, if it is one.
    pub(crate) fn target(
        &mut self,
        w: &Where,
        key: &str,
        name: &str,
        lookup: &Lookup,
    ) -> (BodyRef, Option<[Expr; 3]>) {
        if name == "ground" {
            return (BodyRef::Ground, None);
        }
        match lookup.names.get(name) {
            Some(Target::Body(b)) => (*b, None),
            Some(Target::Conn(b, p)) => (*b, Some(p.clone())),
            Some(Target::Invalid) => (BodyRef::Ground, None),
            None if self.under_failed(name) => (BodyRef::Ground, None),
            None => {
                let candidates: Vec<&str> = lookup.names.keys().map(String::as_str).collect();
                self.err(
                    w,
                    Some(key),
                    Some(name),
                    format!(
                        "unknown body \"{name}\" in {key}{}",
                        close_matches(name, candidates.into_iter())
                    ),
                );
                (BodyRef::Ground, None)
            }
        }
    }

    /// A body; a connection point is an error here.
    pub(crate) fn body_ref(
        &mut self,
        w: &Where,
        key: &str,
        name: &str,
        lookup: &Lookup,
    ) -> BodyRef {
        let (b, conn) = self.target(w, key, name, lookup);
        if conn.is_some() {
            self.err(
                w,
                Some(key),
                Some(name),
                format!("\"{name}\" is a connection point, but {key} needs a body"),
            );
        }
        b
    }

    /// A body or connection point and a point: `point` is in the body frame,
    /// relative to the connection point if `name` is one.
    pub(crate) fn attach(
        &mut self,
        w: &Where,
        (key, name): (&str, &str),
        (point_key, point): (&str, &Vec3),
        lookup: &Lookup,
    ) -> (BodyRef, [Expr; 3]) {
        let (b, conn) = self.target(w, key, name, lookup);
        let p = self.vec3(w, point_key, point, false);
        match conn {
            Some(c) => (b, add3(&c, p)),
            None => (b, p),
        }
    }

    /// The two ends of a two-point element (see [`Cx::attach`]).
    pub(crate) fn two_points(
        &mut self,
        w: &Where,
        (body1, point1): (&str, &Vec3),
        (body2, point2): (&str, &Vec3),
        lookup: &Lookup,
    ) -> (BodyRef, [Expr; 3], BodyRef, [Expr; 3]) {
        let (b1, p1) = self.attach(w, ("body1", body1), ("point1", point1), lookup);
        let (b2, p2) = self.attach(w, ("body2", body2), ("point2", point2), lookup);
        (b1, p1, b2, p2)
    }

    /// A frame on a body or connection point (see [`Cx::attach`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn attach_frame(
        &mut self,
        w: &Where,
        body: (&str, &str),
        point: (&str, &Vec3),
        rot_key: &str,
        rotation: &Vec3,
        lookup: &Lookup,
    ) -> (BodyRef, Frame) {
        let (b, origin) = self.attach(w, body, point, lookup);
        let rotation_xyz = self.vec3(w, rot_key, rotation, false);
        (
            b,
            Frame {
                origin,
                rotation_xyz,
            },
        )
    }

    fn cut_joints(&mut self, raw: &RawModel, lookup: &Lookup, subs: &[Sub]) -> Vec<CutJoint> {
        let mut out: Vec<CutJoint> = Vec::new();
        for (i, c) in raw.cut_joints.iter().enumerate() {
            let nth = occurrence(&raw.cut_joints, i, |o| &o.name);
            let w = Where::Elem(CUT, c.name.clone(), nth);
            if nth > 0 {
                self.err(&w, Some("name"), None, "duplicate cut joint name".into());
                continue;
            }
            let (body1, frame1) = self.attach_frame(
                &w,
                ("body1", &c.body1),
                ("point1", &c.point1),
                "rotation1",
                &c.rotation1,
                lookup,
            );
            let (body2, frame2) = self.attach_frame(
                &w,
                ("body2", &c.body2),
                ("point2", &c.point2),
                "rotation2",
                &c.rotation2,
                lookup,
            );
            if c.constrain.is_empty() {
                self.err(
                    &w,
                    Some("constrain"),
                    None,
                    "constrains no component: list at least one of Tx, Ty, Tz, Rx, Ry, Rz in constrain".into(),
                );
            }
            let mut constrained = Vec::new();
            for comp in &c.constrain {
                let comp = match comp {
                    RawComponent::Tx => Component::Tx,
                    RawComponent::Ty => Component::Ty,
                    RawComponent::Tz => Component::Tz,
                    RawComponent::Rx => Component::Rx,
                    RawComponent::Ry => Component::Ry,
                    RawComponent::Rz => Component::Rz,
                };
                if constrained.contains(&comp) {
                    self.err(
                        &w,
                        Some("constrain"),
                        None,
                        format!("component {comp:?} is constrained twice"),
                    );
                } else {
                    constrained.push(comp);
                }
            }
            if c.body1 == c.body2 {
                self.err(
                    &w,
                    Some("body2"),
                    None,
                    format!("connects body \"{}\" to itself", c.body1),
                );
            }
            out.push(CutJoint {
                name: c.name.clone(),
                body1,
                frame1,
                body2,
                frame2,
                constrained,
            });
        }
        for sub in subs {
            for c in &sub.loaded.model.cut_joints {
                let mut c = c.clone();
                c.name = format!("{}{}", sub.prefix, c.name);
                sub.renumber_cut(&mut c);
                if out.iter().any(|o| o.name == c.name) {
                    let w = Where::Elem(CUT, c.name.clone(), 0);
                    self.err(
                        &w,
                        Some("name"),
                        None,
                        format!(
                            "duplicate cut joint name: subsystem \"{}\" has one too",
                            sub.raw.name
                        ),
                    );
                }
                out.push(c);
            }
        }
        out
    }

    /// Runs a force element's range checks ([`ForceSpec::check`]) with the
    /// default parameters and reports each problem at its field.
    pub(crate) fn check(&mut self, w: &Where, spec: &impl ForceSpec) {
        let Some(d) = self.defaults.clone() else {
            return;
        };
        let mut checks = Checks::new(&d);
        spec.check(&mut checks);
        for (key, message) in checks.problems {
            self.err(w, Some(key), None, message);
        }
    }

    fn forces(&mut self, raw: &RawModel, lookup: &Lookup, subs: &[Sub]) -> Vec<ForceElement> {
        let mut out = Vec::new();
        for (i, f) in raw.forces.iter().enumerate() {
            let name = f.name();
            let nth = occurrence(&raw.forces, i, |o| o.name());
            let w = Where::Elem(FORCE, name.to_string(), nth);
            if nth > 0 {
                self.err(&w, Some("name"), None, "duplicate force name".into());
                continue;
            }
            if name.is_empty() {
                self.err(
                    &w,
                    Some("name"),
                    None,
                    "a force needs a non-empty name".into(),
                );
            }
            let kind = f.resolve(self, &w, lookup);
            self.check(&w, &kind);
            out.push(ForceElement {
                name: name.to_string(),
                kind,
            });
        }
        for sub in subs {
            for f in &sub.loaded.model.forces {
                let mut f = f.clone();
                f.name = format!("{}{}", sub.prefix, f.name);
                let kind = &mut f.kind;
                sub.renumber_force(kind);
                if out.iter().any(|o| o.name == f.name) {
                    let w = Where::Elem(FORCE, f.name.clone(), 0);
                    self.err(
                        &w,
                        Some("name"),
                        None,
                        format!(
                            "duplicate force name: subsystem \"{}\" has one too",
                            sub.raw.name
                        ),
                    );
                }
                out.push(f);
            }
        }
        out
    }

    /// Resolves this file's connection points (after the subsystems', which
    /// they may refer to) and adds them to `lookup`. Returns the connection
    /// points this file offers to an includer: its own and its subsystems'.
    fn connections(
        &mut self,
        raw: &RawModel,
        subs: &[Sub],
        lookup: &mut Lookup,
    ) -> Vec<Connection> {
        let mut out = Vec::new();
        for sub in subs {
            let w = Where::Elem(SUBSYSTEM, sub.raw.name.clone(), sub.nth);
            for c in &sub.loaded.connections {
                let name = format!("{}{}", sub.prefix, c.name);
                let mut point = c.point.clone();
                let mut body = c.body;
                point.iter_mut().for_each(|e| sub.shift(e));
                if let BodyRef::Body(b) = &mut body {
                    sub.body(b);
                }
                if lookup.names.contains_key(&name) {
                    self.err(
                        &w,
                        None,
                        None,
                        format!("\"{name}\" names both a body and a connection point"),
                    );
                    continue;
                }
                lookup
                    .names
                    .insert(name.clone(), Target::Conn(body, point.clone()));
                out.push(Connection { name, body, point });
            }
        }
        for (i, (name, c)) in raw.connections.0.iter().enumerate() {
            let nth = occurrence(&raw.connections.0, i, |c| &c.0);
            let w = Where::Conn(name.clone(), nth);
            if !is_identifier(name) {
                self.err(
                    &w,
                    None,
                    None,
                    "not a valid name (letters, digits, '_' and '.', starting with a letter or '_')"
                        .into(),
                );
                continue;
            }
            if lookup.names.contains_key(name) || name == "ground" {
                let what = match lookup.names.get(name) {
                    Some(Target::Conn(..)) => "a connection point",
                    _ => "a body",
                };
                self.err(
                    &w,
                    None,
                    None,
                    format!("duplicate name: {what} is already called \"{name}\""),
                );
                continue;
            }
            let (body, point) = self.attach(&w, ("body", &c.body), ("point", &c.point), lookup);
            lookup
                .names
                .insert(name.clone(), Target::Conn(body, point.clone()));
            out.push(Connection {
                name: name.clone(),
                body,
                point,
            });
        }
        out
    }
}

/// Every dependency cycle among parameter defaults (each once, as indices in order).
pub(crate) fn find_cycles(exprs: &[Expr]) -> Vec<Vec<usize>> {
    let deps: Vec<Vec<usize>> = exprs.iter().map(Expr::params_used).collect();
    let n = exprs.len();
    let mut state = vec![0u8; n];
    let mut stack = Vec::new();
    let mut cycles: Vec<Vec<usize>> = Vec::new();
    fn visit(
        i: usize,
        deps: &[Vec<usize>],
        state: &mut [u8],
        stack: &mut Vec<usize>,
        cycles: &mut Vec<Vec<usize>>,
    ) {
        state[i] = 1;
        stack.push(i);
        for &j in &deps[i] {
            if j >= state.len() {
                continue;
            }
            match state[j] {
                0 => visit(j, deps, state, stack, cycles),
                1 => {
                    let k = stack.iter().position(|&s| s == j).unwrap_or(0);
                    let cycle = stack[k..].to_vec();
                    let mut key = cycle.clone();
                    key.sort_unstable();
                    if !cycles.iter().any(|c| {
                        let mut s = c.clone();
                        s.sort_unstable();
                        s == key
                    }) {
                        cycles.push(cycle);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state[i] = 2;
    }
    for i in 0..n {
        if state[i] == 0 {
            visit(i, &deps, &mut state, &mut stack, &mut cycles);
        }
    }
    cycles
}

/// Evaluates parameter expressions in dependency order; `Err(cycle)` on a cycle.
pub(crate) fn evaluate_parameters(exprs: &[Expr]) -> Result<Vec<f64>, Vec<usize>> {
    if let Some(c) = find_cycles(exprs).into_iter().next() {
        return Err(c);
    }
    let n = exprs.len();
    let mut values = vec![f64::NAN; n];
    let mut done = vec![false; n];
    fn eval(i: usize, exprs: &[Expr], values: &mut [f64], done: &mut [bool]) {
        if done[i] {
            return;
        }
        for j in exprs[i].params_used() {
            if j < exprs.len() {
                eval(j, exprs, values, done);
            }
        }
        values[i] = exprs[i].eval(values, 0.0);
        done[i] = true;
    }
    for i in 0..n {
        eval(i, exprs, &mut values, &mut done);
    }
    Ok(values)
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending (closed form, O. K. Smith,
/// "Eigenvalues of a symmetric 3 × 3 matrix", CACM 4(4), 1961).
pub(crate) fn sym3_eigenvalues(a: [[f64; 3]; 3]) -> [f64; 3] {
    let p1 = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
    let mut ev = if p1 == 0.0 {
        [a[0][0], a[1][1], a[2][2]]
    } else {
        let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
        let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let b = |i: usize, j: usize| (a[i][j] - if i == j { q } else { 0.0 }) / p;
        let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(2, 1))
            - b(0, 1) * (b(1, 0) * b(2, 2) - b(1, 2) * b(2, 0))
            + b(0, 2) * (b(1, 0) * b(2, 1) - b(1, 1) * b(2, 0));
        let r = (det / 2.0).clamp(-1.0, 1.0);
        let phi = r.acos() / 3.0;
        let e1 = q + 2.0 * p * phi.cos();
        let e3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
        [e1, 3.0 * q - e1 - e3, e3]
    };
    ev.sort_by(f64::total_cmp);
    ev
}

/// How many items before `items[i]` carry its name (`name_of`): which
/// occurrence of a repeated name `items[i]` is, to locate it in the file.
fn occurrence<T>(items: &[T], i: usize, name_of: impl Fn(&T) -> &str) -> usize {
    let name = name_of(&items[i]);
    items[..i].iter().filter(|o| name_of(o) == name).count()
}
