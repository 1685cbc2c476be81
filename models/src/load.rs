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

mod attach;
mod bodies;
mod elements;
mod include;
mod joints;
mod parameters;
mod values;
pub(crate) use attach::{Lookup, Target, add3};
pub(crate) use bodies::mass_problems;
pub(crate) use elements::resolve_foreign_forces;
use include::{Connection, Includes, Loaded, Sub, close_matches};
use joints::JointBuilder;
pub(crate) use values::{evaluate_parameters, find_cycles};

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
/// The RON parse error `e` of `file` as a located error: line, column and
/// the innermost named element around it.
pub fn ron_error(loc: &Locator, file: &Path, e: ron::error::SpannedError) -> ModelErrors {
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
        self.check_contacts_can_move(&raw, &bodies, &coordinates, &forces);
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

    /// A wheel–rail element of this file needs a wheelset that can move: the
    /// wheelset body or one of its ancestors has a coordinate. Without one
    /// the contact's stiff normal force acts on nothing that yields (a wheel
    /// load of 10¹⁰ N). Subsystems' elements were checked in their own files.
    fn check_contacts_can_move(
        &mut self,
        raw: &RawModel,
        bodies: &[Body],
        coordinates: &[Coordinate],
        forces: &[ForceElement],
    ) {
        let can_move = |mut b: usize| loop {
            if coordinates.iter().any(|c| c.body == b) {
                return true;
            }
            match bodies.get(b).map(|body| body.parent) {
                Some(BodyRef::Body(p)) if p != b => b = p,
                _ => return false,
            }
        };
        for f in forces {
            let ForceKind::WheelRail(spec) = &f.kind else {
                continue;
            };
            if !raw.forces.iter().any(|r| r.name() == f.name) || spec.wheelset >= bodies.len() {
                continue;
            }
            if !can_move(spec.wheelset) {
                self.err(
                    &Where::Elem(FORCE, f.name.clone(), 0),
                    Some("wheelset"),
                    None,
                    format!(
                        "the wheelset body \"{}\" cannot move: neither it nor a body it is \
                         attached to has a coordinate, so the contact would press on a fixed \
                         body (give its joint degrees of freedom)",
                        bodies[spec.wheelset].name
                    ),
                );
            }
        }
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
}

/// How many items before `items[i]` carry its name (`name_of`): which
/// occurrence of a repeated name `items[i]` is, to locate it in the file.
fn occurrence<T>(items: &[T], i: usize, name_of: impl Fn(&T) -> &str) -> usize {
    let name = name_of(&items[i]);
    items[..i].iter().filter(|o| name_of(o) == name).count()
}
