//! Bodies: this file's and its subsystems' bodies in one tree, sorted
//! parent-first, resolved with their joints and coordinates.
//!
//! The stages, in the order [`Cx::bodies`] runs them (and reports their
//! problems):
//! * [`tree`]: the bodies' names, each body's parent and the parent-first
//!   order (with loops in the body tree found);
//! * [`resolve`]: each body of that order resolved (mass, inertia, joint) or
//!   re-attached from its subsystem, and the coordinates numbered;
//! * [`inertia`]: the mass and inertia checks both use.

use super::*;

mod inertia;
pub(crate) use inertia::mass_problems;
mod resolve;
mod tree;

/// A body of the includer: one of its own (raw index) or a subsystem's
/// (subsystem, body index in the subsystem's model).
#[derive(Debug, Clone, Copy)]
enum Node {
    Raw(usize),
    Sub(usize, usize),
}

/// The bodies of the file being resolved as nodes of one tree: this file's
/// bodies in file order, then each subsystem's in its order.
struct BodyNodes<'a> {
    raw: &'a RawModel,
    subs: &'a [Sub<'a>],
    nodes: Vec<Node>,
    /// Long name of each node (`"<instance>.<body>"` for a subsystem's).
    names: Vec<String>,
    /// Index of each subsystem's first node.
    sub_first: Vec<usize>,
}

impl<'a> BodyNodes<'a> {
    fn new(raw: &'a RawModel, subs: &'a [Sub<'a>]) -> Self {
        let mut nodes: Vec<Node> = (0..raw.bodies.len()).map(Node::Raw).collect();
        let mut names: Vec<String> = raw.bodies.iter().map(|b| b.name.clone()).collect();
        let mut sub_first = Vec::with_capacity(subs.len());
        for (k, sub) in subs.iter().enumerate() {
            sub_first.push(nodes.len());
            for (j, b) in sub.loaded.model.bodies.iter().enumerate() {
                nodes.push(Node::Sub(k, j));
                names.push(format!("{}{}", sub.prefix, b.name));
            }
        }
        Self {
            raw,
            subs,
            nodes,
            names,
            sub_first,
        }
    }

    /// Number of nodes.
    fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Number of this file's own bodies (the first nodes).
    fn own(&self) -> usize {
        self.raw.bodies.len()
    }

    /// Where node `i`'s problems are reported: its body, or the subsystem
    /// instance it comes from.
    fn place(&self, i: usize) -> Where {
        match self.nodes[i] {
            Node::Raw(r) => Where::Elem(BODY, self.raw.bodies[r].name.clone(), 0),
            Node::Sub(k, _) => {
                Where::Elem(SUBSYSTEM, self.subs[k].raw.name.clone(), self.subs[k].nth)
            }
        }
    }
}

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
        let nodes = BodyNodes::new(raw, subs);
        let (first, mut valid) = self.check_body_names(&nodes);
        let parent = self.parents(&nodes, &first, &mut valid);
        let order = self.parent_first_order(&nodes, &parent, &valid);
        let mut node_to_new = vec![None; nodes.len()];
        for (k, &i) in order.iter().enumerate() {
            node_to_new[i] = Some(k);
        }
        let (bodies, coords) = self.resolve_bodies(&nodes, &parent, &order, &node_to_new);
        let lookup = body_lookup(&nodes.names, &node_to_new);
        let sub_first = nodes.sub_first;
        for (k, sub) in subs.iter_mut().enumerate() {
            sub.body_map = (0..sub.loaded.model.bodies.len())
                .map(|j| node_to_new[sub_first[k] + j].unwrap_or(0))
                .collect();
        }
        (bodies, coords, lookup)
    }
}

/// The names bodies are known by: node `i` named `names[i]` is body
/// `node_to_new[i]`, or invalid (reported where it is defined) if it has
/// none. A valid body wins over an invalid one of the same name.
fn body_lookup(names: &[String], node_to_new: &[Option<usize>]) -> Lookup {
    let mut lookup = Lookup {
        names: HashMap::new(),
    };
    for (i, name) in names.iter().enumerate() {
        let target = match node_to_new[i] {
            Some(k) => Target::Body(BodyRef::Body(k)),
            None => Target::Invalid,
        };
        if !lookup.names.contains_key(name) || node_to_new[i].is_some() {
            lookup.names.insert(name.clone(), target);
        }
    }
    lookup
}
