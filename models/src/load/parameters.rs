//! Parameters (identifiers) and macros: names, defaults, subsystem overrides.

use super::*;

impl Cx<'_> {
    /// Validates the names of this file's own parameters and puts them in
    /// `self.names`; returns their raw values (same order).
    pub(super) fn parameter_names<'r>(&mut self, raw: &'r RawModel) -> Vec<&'r ParamValue> {
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
    pub(super) fn param_where(&self, i: usize, own: usize, subs: &[Sub]) -> Where {
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
    pub(super) fn parameters(
        &mut self,
        kept: Vec<&ParamValue>,
        subs: &mut [Sub],
    ) -> Vec<Parameter> {
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

    pub(super) fn macros(&mut self, raw: &RawModel, subs: &[Sub]) -> Vec<Macro> {
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
}
