//! Included subsystems: loading the files (recursively, once each, with cycle
//! detection), and renumbering an included model's parameters and bodies into
//! its includer's.

use super::*;
use std::rc::Rc;

/// A resolved file: its flattened model and the connection points it offers
/// to an includer (its own and, with their long names, its subsystems').
#[derive(Debug, Clone)]
pub(super) struct Loaded {
    pub model: Model,
    pub connections: Vec<Connection>,
}

/// A named point fixed to a body, in the body frame.
#[derive(Debug, Clone)]
pub(super) struct Connection {
    pub name: String,
    pub body: BodyRef,
    pub point: [Expr; 3],
}

/// Where a file was included: instance name and the `Subsystem(` position.
#[derive(Debug, Clone)]
struct Site {
    instance: String,
    file: PathBuf,
    position: Option<(usize, usize)>,
}

/// A file being loaded.
#[derive(Debug)]
struct Open {
    /// Canonical path (cycle detection, cache).
    key: PathBuf,
    /// The path as shown in messages.
    file: PathBuf,
    /// How it was included; `None` for the top file.
    site: Option<Site>,
}

/// State shared by the files of one model: the chain of files being loaded
/// (outermost first) and the files already loaded (`None`: they had errors,
/// which were reported with their first inclusion).
#[derive(Debug)]
pub(super) struct Includes {
    stack: Vec<Open>,
    cache: HashMap<PathBuf, Option<Rc<Loaded>>>,
}

fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| normalize(path))
}

/// `a/b/../c` → `a/c`, without touching the file system.
pub(super) fn normalize(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if matches!(out.components().next_back(), Some(Component::Normal(_))) {
                    out.pop();
                } else {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

impl Loaded {
    /// Stands in for a subsystem that could not be loaded.
    fn empty() -> Loaded {
        Loaded {
            model: Model {
                name: String::new(),
                source: None,
                parameters: Vec::new(),
                macros: Vec::new(),
                gravity: std::array::from_fn(|_| Expr::Num(0.0)),
                bodies: Vec::new(),
                coordinates: Vec::new(),
                cut_joints: Vec::new(),
                forces: Vec::new(),
                track_frames: Vec::new(),
            },
            connections: Vec::new(),
        }
    }
}

impl Includes {
    pub(super) fn top(file: &Path) -> Includes {
        Includes {
            stack: vec![Open {
                key: canonical(file),
                file: file.to_path_buf(),
                site: None,
            }],
            cache: HashMap::new(),
        }
    }

    /// Appends to the errors of the innermost file how it was included:
    /// `(included as "Bogie1.WS2" from vehicle.ron:12:9 via bogie.ron:20:9)`.
    pub(super) fn annotate(&self, errors: &mut [ModelError]) {
        let sites: Vec<&Site> = self.stack.iter().filter_map(|o| o.site.as_ref()).collect();
        let Some(first) = sites.first() else {
            return;
        };
        let at = |s: &Site| match s.position {
            Some((line, col)) => format!("{}:{line}:{col}", s.file.display()),
            None => s.file.display().to_string(),
        };
        let long: Vec<&str> = sites.iter().map(|s| s.instance.as_str()).collect();
        let mut note = format!("included as \"{}\" from {}", long.join("."), at(first));
        for s in &sites[1..] {
            note.push_str(&format!(" via {}", at(s)));
        }
        for e in errors {
            e.message = format!("{} ({note})", e.message);
        }
    }
}

/// An included subsystem of the file being resolved.
pub(super) struct Sub<'r> {
    pub raw: &'r RawSubsystem,
    /// Occurrence of its instance name (for locating it).
    pub nth: usize,
    /// `"<instance>."`.
    pub prefix: String,
    /// The included file, as shown in messages.
    pub path: PathBuf,
    pub loaded: Rc<Loaded>,
    /// Index of its first parameter in the includer's parameters.
    pub param_offset: usize,
    /// Its body `j` is the includer's body `body_map[j]`.
    pub body_map: Vec<usize>,
    /// It could not be loaded (and `loaded` is empty).
    pub failed: bool,
}

impl Sub<'_> {
    /// Renumbers the parameters of an expression of the subsystem.
    pub fn shift(&self, e: &mut Expr) {
        let offset = self.param_offset;
        *e = e.map_params(&mut |p| Expr::Param(p + offset));
    }

    /// Renumbers a body index of the subsystem.
    pub fn body(&self, b: &mut usize) {
        *b = self.body_map.get(*b).copied().unwrap_or(0);
    }

    pub fn renumber_force(&self, kind: &mut ForceKind) {
        kind.exprs_mut(&mut |e| self.shift(e));
        kind.bodies_mut(&mut |b| self.body(b));
    }

    pub fn renumber_cut(&self, c: &mut CutJoint) {
        c.exprs_mut(&mut |e| self.shift(e));
        c.bodies_mut(&mut |b| self.body(b));
    }
}

/// `"; close matches: \"a\", \"b\""` for the candidates close to `name`
/// (small edit distance, or the same last part of a long name), or `""`.
pub(super) fn close_matches<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> String {
    let last = name.rsplit('.').next().unwrap_or(name);
    // Very short names would match almost anything.
    let len = name.chars().count();
    let limit = if len <= 2 { 0 } else { (len / 4).clamp(1, 3) };
    let mut found: Vec<&str> = candidates
        .filter(|c| {
            *c != name
                && (strsim::levenshtein(c, name) <= limit || c.rsplit('.').next() == Some(last))
        })
        .collect();
    found.sort_unstable();
    found.dedup();
    if found.is_empty() {
        return String::new();
    }
    let shown: Vec<String> = found.iter().take(5).map(|c| format!("\"{c}\"")).collect();
    let more = if found.len() > 5 { ", …" } else { "" };
    format!("; close matches: {}{more}", shown.join(", "))
}

impl<'a> Cx<'a> {
    /// Loads the subsystems of this file (each file once per model). One
    /// that cannot be loaded (the errors are recorded) stands in as an empty
    /// model, and its prefix goes to `self.failed` so that references to its
    /// names raise no further errors.
    pub(super) fn load_subsystems<'r>(
        &mut self,
        raw: &'r RawModel,
        inc: &mut Includes,
    ) -> Vec<Sub<'r>> {
        let mut subs = Vec::new();
        let dir = self.file.parent().unwrap_or(Path::new("")).to_path_buf();
        for (i, rs) in raw.subsystems.iter().enumerate() {
            let nth = super::occurrence(&raw.subsystems, i, |o| &o.name);
            let w = Where::Elem(SUBSYSTEM, rs.name.clone(), nth);
            if !is_identifier(&rs.name) || rs.name.contains('.') {
                self.err(
                    &w,
                    Some("name"),
                    None,
                    format!(
                        "instance name \"{}\" is not a valid name (letters, digits and '_', starting with a letter or '_'; no '.')",
                        rs.name
                    ),
                );
                continue;
            }
            if nth > 0 {
                self.err(&w, Some("name"), None, "duplicate subsystem name".into());
                continue;
            }
            let prefix = format!("{}.", rs.name);
            let path = normalize(&dir.join(&rs.file));
            let mut sub = Sub {
                raw: rs,
                nth,
                prefix,
                path: path.clone(),
                loaded: Rc::new(Loaded::empty()),
                param_offset: 0,
                body_map: Vec::new(),
                failed: true,
            };
            let text = match std::fs::read_to_string(&path) {
                Ok(text) => text,
                Err(e) => {
                    self.err(
                        &w,
                        Some("file"),
                        Some(&rs.file),
                        format!("cannot read the subsystem file {}: {e}", path.display()),
                    );
                    self.failed.push(sub.prefix.clone());
                    subs.push(sub);
                    continue;
                }
            };
            let key = canonical(&path);
            if let Some(k) = inc.stack.iter().position(|o| o.key == key) {
                let mut chain: Vec<String> = inc.stack[k..]
                    .iter()
                    .map(|o| o.file.display().to_string())
                    .collect();
                chain.push(path.display().to_string());
                self.err(
                    &w,
                    Some("file"),
                    Some(&rs.file),
                    format!("include cycle: {}", chain.join(" -> ")),
                );
                self.failed.push(sub.prefix.clone());
                subs.push(sub);
                continue;
            }
            let loaded = match inc.cache.get(&key) {
                Some(Some(loaded)) => loaded.clone(),
                Some(None) => {
                    // Its errors were reported where it was first included.
                    self.failed.push(sub.prefix.clone());
                    subs.push(sub);
                    continue;
                }
                None => {
                    let position = self
                        .span_of(&w)
                        .map(|span| self.loc.pos(self.loc.start_of(span)));
                    inc.stack.push(Open {
                        key: key.clone(),
                        file: path.clone(),
                        site: Some(Site {
                            instance: rs.name.clone(),
                            file: self.file.to_path_buf(),
                            position,
                        }),
                    });
                    let result = parse_with(&text, &path, inc);
                    inc.stack.pop();
                    match result {
                        Ok(loaded) => {
                            let loaded = Rc::new(loaded);
                            inc.cache.insert(key, Some(loaded.clone()));
                            loaded
                        }
                        Err(errors) => {
                            inc.cache.insert(key, None);
                            self.nested.extend(errors.0);
                            self.failed.push(sub.prefix.clone());
                            subs.push(sub);
                            continue;
                        }
                    }
                }
            };
            sub.loaded = loaded;
            sub.failed = false;
            subs.push(sub);
        }
        subs
    }
}
