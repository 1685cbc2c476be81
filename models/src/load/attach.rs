//! Names of bodies and connection points: what a force element or cut joint
//! refers to, and this file's connection points.

use super::*;

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

    /// Resolves this file's connection points (after the subsystems', which
    /// they may refer to) and adds them to `lookup`. Returns the connection
    /// points this file offers to an includer: its own and its subsystems'.
    pub(super) fn connections(
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
