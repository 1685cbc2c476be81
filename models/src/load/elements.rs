//! Cut joints and force elements: each force element resolves itself
//! (`crate::forces`); here are the name checks, the range checks with the
//! default parameters and the subsystems' elements.

use super::*;

impl Cx<'_> {
    pub(super) fn cut_joints(
        &mut self,
        raw: &RawModel,
        lookup: &Lookup,
        subs: &[Sub],
    ) -> Vec<CutJoint> {
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

    pub(super) fn forces(
        &mut self,
        raw: &RawModel,
        lookup: &Lookup,
        subs: &[Sub],
    ) -> Vec<ForceElement> {
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
}

/// Resolves force elements written outside a model file (the couplers of a
/// train file, `text` of `file`) against the bodies `bodies` (long names;
/// index = the body index in the result), without parameters: the same
/// resolution and range checks as a model file's own elements, errors
/// located in `text`.
pub(crate) fn resolve_foreign_forces(
    file: &Path,
    text: &str,
    raws: &[&crate::forces::RawForce],
    bodies: &[String],
) -> (Vec<ForceKind>, Vec<ModelError>) {
    let mut cx = Cx {
        file,
        loc: Locator::new(text),
        errors: Vec::new(),
        nested: Vec::new(),
        failed: Vec::new(),
        names: Vec::new(),
        defaults: Some(Vec::new()),
        track_offsets: HashMap::new(),
    };
    let mut lookup = Lookup {
        names: HashMap::new(),
    };
    for (i, name) in bodies.iter().enumerate() {
        lookup
            .names
            .insert(name.clone(), Target::Body(BodyRef::Body(i)));
    }
    let mut out = Vec::new();
    for (i, f) in raws.iter().enumerate() {
        let name = f.name();
        let nth = raws[..i].iter().filter(|o| o.name() == name).count();
        let w = Where::Elem(FORCE, name.to_string(), nth);
        let kind = f.resolve(&mut cx, &w, &lookup);
        cx.check(&w, &kind);
        out.push(kind);
    }
    (out, cx.errors)
}
