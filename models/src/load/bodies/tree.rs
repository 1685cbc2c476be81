//! The body tree: the bodies' names, each body's parent (a subsystem's
//! ground-attached bodies hang on the subsystem's `parent`), and the
//! parent-first order, with loops found.

use super::super::*;
use super::{BodyNodes, Node};

/// Node indices by long name: the first definition of each.
type FirstByName<'a> = HashMap<&'a str, usize>;

impl Cx<'_> {
    /// Checks this file's body names (non-empty, not `ground`, not already
    /// defined here or by a subsystem). Returns the first node of each name
    /// (subsystems' bodies first: their names were checked in their files)
    /// and which nodes are valid.
    pub(super) fn check_body_names<'a>(
        &mut self,
        nodes: &'a BodyNodes,
    ) -> (FirstByName<'a>, Vec<bool>) {
        let (raw, subs) = (nodes.raw, nodes.subs);
        let mut first: FirstByName = HashMap::new();
        for (i, name) in nodes.names.iter().enumerate().skip(nodes.own()) {
            first.insert(name.as_str(), i);
        }
        let mut valid = vec![true; nodes.len()];
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
                let message = match nodes.nodes[other] {
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
        (first, valid)
    }

    /// The parent node of each node (None: ground). A subsystem's bodies
    /// keep their parents inside it; its ground-attached bodies hang on the
    /// subsystem's `parent`, except those on a track-following frame. A
    /// body whose parent is unknown becomes invalid.
    pub(super) fn parents(
        &mut self,
        nodes: &BodyNodes,
        first: &FirstByName,
        valid: &mut [bool],
    ) -> Vec<Option<usize>> {
        let (raw, subs) = (nodes.raw, nodes.subs);
        let unknown = UnknownParent::new(nodes);
        let sub_parent = self.subsystem_parents(subs, first, &unknown);
        let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
        for i in 0..nodes.len() {
            match nodes.nodes[i] {
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
                            self.err(&w, Some("parent"), Some(p), unknown.message(p));
                            valid[i] = false;
                        }
                    }
                }
                Node::Sub(k, j) => {
                    let model = &subs[k].loaded.model;
                    parent[i] = match model.bodies[j].parent {
                        BodyRef::Body(pj) => Some(nodes.sub_first[k] + pj),
                        BodyRef::Ground if model.track_frames.iter().any(|t| t.body == j) => None,
                        BodyRef::Ground => sub_parent[k],
                    };
                }
            }
        }
        parent
    }

    /// The node each subsystem's ground-attached bodies hang on (its
    /// `parent`; None: ground). A subsystem with track-following frames
    /// cannot be re-attached.
    fn subsystem_parents(
        &mut self,
        subs: &[Sub],
        first: &FirstByName,
        unknown: &UnknownParent,
    ) -> Vec<Option<usize>> {
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
                None => self.err(&w, Some("parent"), Some(p), unknown.message(p)),
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
        sub_parent
    }

    /// The valid nodes in topological order (parents first), keeping file
    /// order where possible. A loop in the body tree is reported (at a body
    /// of this file if the loop has one) and its nodes, and those below it,
    /// are left out.
    pub(super) fn parent_first_order(
        &mut self,
        nodes: &BodyNodes,
        parent: &[Option<usize>],
        valid: &[bool],
    ) -> Vec<usize> {
        #[derive(Clone, Copy, PartialEq)]
        enum State {
            Unvisited,
            Placed,
            /// In or below a loop, or invalid.
            Excluded,
        }
        let n = nodes.len();
        let mut state: Vec<State> = valid
            .iter()
            .map(|&v| if v { State::Unvisited } else { State::Excluded })
            .collect();
        let mut order = Vec::new();
        for i in 0..n {
            if state[i] != State::Unvisited {
                continue;
            }
            let mut path = Vec::new();
            let mut cur = Some(i);
            let mut bad = false;
            while let Some(c) = cur {
                if state[c] == State::Placed {
                    break;
                }
                if state[c] == State::Excluded {
                    bad = true;
                    break;
                }
                if let Some(k) = path.iter().position(|&p| p == c) {
                    let cycle: &[usize] = &path[k..];
                    let mut cycle_names: Vec<&str> =
                        cycle.iter().map(|&j| nodes.names[j].as_str()).collect();
                    cycle_names.push(cycle_names[0]);
                    let at = cycle
                        .iter()
                        .copied()
                        .find(|&j| j < nodes.own())
                        .unwrap_or(cycle[0]);
                    self.err(
                        &nodes.place(at),
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
                    state[c] = State::Excluded;
                } else {
                    state[c] = State::Placed;
                    order.push(c);
                }
            }
        }
        order
    }
}

/// The message for a joint or subsystem parent that names no body.
struct UnknownParent<'a> {
    /// This file's and its subsystems' connection points.
    connections: Vec<String>,
    /// Every body's long name (for "close matches").
    bodies: &'a [String],
}

impl<'a> UnknownParent<'a> {
    fn new(nodes: &'a BodyNodes) -> Self {
        let connections = nodes
            .raw
            .connections
            .0
            .iter()
            .map(|(n, _)| n.clone())
            .chain(nodes.subs.iter().flat_map(|s| {
                s.loaded
                    .connections
                    .iter()
                    .map(|c| format!("{}{}", s.prefix, c.name))
            }))
            .collect();
        Self {
            connections,
            bodies: &nodes.names,
        }
    }

    /// Why `p` cannot be a parent: a connection point, or unknown (with
    /// close matches).
    fn message(&self, p: &str) -> String {
        if self.connections.iter().any(|c| c == p) {
            format!("\"{p}\" is a connection point, not a body: a joint's parent must be a body")
        } else {
            format!(
                "unknown body \"{p}\" as parent{}",
                close_matches(p, self.bodies.iter().map(String::as_str))
            )
        }
    }
}
