//! Resolving the bodies in parent-first order: this file's bodies from their
//! syntax (mass, inertia, joint), a subsystem's re-attached with its
//! parameters and coordinates renumbered; then the coordinates numbered
//! across the model.

use super::super::*;
use super::{BodyNodes, Node};

impl Cx<'_> {
    /// The bodies of `order` (node indices, parents first) and their
    /// coordinates; node `i` becomes body `node_to_new[i]`.
    pub(super) fn resolve_bodies(
        &mut self,
        nodes: &BodyNodes,
        parent: &[Option<usize>],
        order: &[usize],
        node_to_new: &[Option<usize>],
    ) -> (Vec<Body>, Vec<Coordinate>) {
        let mut bodies = Vec::new();
        let mut coords: Vec<Coordinate> = Vec::new();
        for (k, &i) in order.iter().enumerate() {
            let parent = match parent[i] {
                None => BodyRef::Ground,
                Some(j) => BodyRef::Body(node_to_new[j].unwrap_or(0)),
            };
            let (w, mut body, new_coords) = match nodes.nodes[i] {
                Node::Raw(r) => self.own_body(&nodes.raw.bodies[r], k, parent),
                Node::Sub(s, j) => {
                    self.subsystem_body(&nodes.subs[s], j, nodes.names[i].clone(), k, parent)
                }
            };
            self.number_coordinates(&w, &mut body, k, new_coords, &mut coords, &bodies);
            bodies.push(body);
        }
        (bodies, coords)
    }

    /// A body of this file, as body `k` of the model with parent `parent`:
    /// mass and inertia (checked), its joint and the coordinates it
    /// declares. Also returns where its problems are reported.
    fn own_body(
        &mut self,
        b: &RawBody,
        k: usize,
        parent: BodyRef,
    ) -> (Where, Body, Vec<Coordinate>) {
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

    /// Body `j` of subsystem `sub`, named `name` here, as body `k` of the
    /// model with parent `parent`: its expressions with the subsystem's
    /// parameters renumbered, its mass and inertia checked again with this
    /// instance's parameters, its track-frame inputs and coordinates carried
    /// over (the coordinates are numbered by
    /// [`Cx::number_coordinates`]). Also returns where its problems are
    /// reported: the subsystem instance.
    fn subsystem_body(
        &mut self,
        sub: &Sub,
        j: usize,
        name: String,
        k: usize,
        parent: BodyRef,
    ) -> (Where, Body, Vec<Coordinate>) {
        let model = &sub.loaded.model;
        let w = Where::Elem(SUBSYSTEM, sub.raw.name.clone(), sub.nth);
        let offset = sub.param_offset;
        let shift = |e: &Expr| e.map_params(&mut |p| Expr::Param(p + offset));
        let cb = &model.bodies[j];
        let mass = shift(&cb.mass);
        let inertia = cb.inertia.each_ref().map(shift);
        // The subsystem was checked with its own defaults; with this
        // instance's parameters it may no longer be valid.
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
                // Numbered with the coordinates.
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

    /// Appends the coordinates `new` of `body` (body `k`, not yet in
    /// `bodies`) to the model's `coords`, pointing its joint's elementary
    /// transformations at their global numbers. A name already taken, or
    /// empty, is reported at `w` and the coordinate dropped.
    fn number_coordinates(
        &mut self,
        w: &Where,
        body: &mut Body,
        k: usize,
        new: Vec<Coordinate>,
        coords: &mut Vec<Coordinate>,
        bodies: &[Body],
    ) {
        for mut c in new {
            if let Some(other) = coords.iter().find(|o| o.name == c.name) {
                let other_body = bodies
                    .get(other.body)
                    .map_or(body.name.as_str(), |ob: &Body| ob.name.as_str())
                    .to_string();
                self.err(
                    w,
                    None,
                    Some(&c.name),
                    format!(
                        "duplicate coordinate name \"{}\" (also in body \"{other_body}\")",
                        c.name
                    ),
                );
            } else if c.name.is_empty() {
                self.err(w, Some("coord"), None, "empty coordinate name".into());
            } else {
                let global = coords.len();
                c.body = k;
                if let Some(el) = body.joint.get_mut(c.elementary) {
                    el.motion = Motion::Coordinate(global);
                }
                coords.push(c);
            }
        }
    }
}
