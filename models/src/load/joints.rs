//! Joints: the shorthand joints and elementary transformations expanded into
//! fixed, coordinate, time and track-frame motions.

use super::*;

impl Cx<'_> {
    pub(super) fn fixed(
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

    pub(super) fn fixed3(
        &mut self,
        w: &Where,
        jb: &mut JointBuilder,
        translate: bool,
        label: &str,
        v: &Vec3,
    ) {
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
    pub(super) fn coordinate(
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
    pub(super) fn track_frame(
        &mut self,
        w: &Where,
        jb: &mut JointBuilder,
        parent: &str,
        offset: &Value,
    ) {
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

    pub(super) fn expand_joint(&mut self, w: &Where, joint: &RawJoint, jb: &mut JointBuilder) {
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

/// The joint and coordinates of one body, as its transformations are expanded.
pub(super) struct JointBuilder<'a> {
    /// Index of the body (in the resolved model's order).
    pub(super) body: usize,
    /// Its long name (coordinate names are built on it).
    pub(super) body_name: &'a str,
    /// Elementary transformations so far.
    pub(super) joint: Vec<Elementary>,
    /// Coordinates so far.
    pub(super) coords: Vec<Coordinate>,
}

fn axis_name(a: Axis) -> &'static str {
    match a {
        Axis::X => "x",
        Axis::Y => "y",
        Axis::Z => "z",
    }
}
