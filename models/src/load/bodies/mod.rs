//! Bodies: mass and inertia, joints sorted parent-first, subsystem bodies
//! re-attached, coordinates collected.

use super::*;

impl Cx<'_> {
    /// Bodies of this file and of its subsystems in topological order
    /// (parents first; otherwise this file's bodies in file order, then each
    /// subsystem's in its order), their coordinates, and the names bodies are
    /// known by. Sets each subsystem's `body_map`.
    pub(super) fn bodies(
        &mut self,
        raw: &RawModel,
        subs: &mut [Sub],
    ) -> (Vec<Body>, Vec<Coordinate>, Lookup) {
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
    pub(super) fn check_mass(&mut self, w: &Where, mass: &Expr, inertia: &[Expr; 6]) {
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
