//! Numeric fields: expressions over the parameters (and `t`, and the
//! surface variables x, y where allowed), and the parameters' evaluation order.

use super::*;

impl Cx<'_> {
    /// The height z = f(x, y) of a point–Z-surface contact: an expression in
    /// the local variables x, y and the parameters, finite with the default
    /// parameters at x = y = 0.
    pub(crate) fn surface_expr(&mut self, w: &Where, v: &Value) -> Expr {
        let s = match v {
            Value::Num(x) => return self.expr(w, "surface", "surface", &Value::Num(*x), false),
            Value::Text(s) => s,
        };
        let names = &self.names;
        match parse_expr_vars(s, false, &VAR_NAMES, |id| {
            names.iter().position(|n| n == id)
        }) {
            Ok(e) => {
                if let Some(d) = &self.defaults {
                    let z = e.eval_vars(d, 0.0, &[0.0, 0.0]);
                    if !z.is_finite() {
                        self.err(
                            w,
                            Some("surface"),
                            Some(s),
                            format!("surface \"{s}\" is not finite at x = y = 0 with the default parameters: {z}"),
                        );
                    }
                }
                e
            }
            Err(pe) => {
                let msg = match &pe.kind {
                    ParseErrorKind::UnknownIdentifier(n) => format!(
                        "unknown identifier \"{n}\" in surface (\"{s}\"): use x, y (m, in the surface body's frame) and parameters{}",
                        close_matches(n, self.names.iter().map(String::as_str))
                    ),
                    ParseErrorKind::TimeNotAllowed => {
                        format!("time t is not allowed in surface (\"{s}\")")
                    }
                    ParseErrorKind::Syntax { .. } => format!("surface: {pe}"),
                };
                self.err(w, Some("surface"), Some(s), msg);
                Expr::Num(f64::NAN)
            }
        }
    }

    /// Resolves a numeric field. `label` names it in messages, `key` is its RON key.
    pub(crate) fn expr(
        &mut self,
        w: &Where,
        label: &str,
        key: &str,
        v: &Value,
        allow_time: bool,
    ) -> Expr {
        match v {
            Value::Num(x) => {
                if !x.is_finite() {
                    self.err(w, Some(key), None, format!("{label} is not finite: {x}"));
                }
                Expr::Num(*x)
            }
            Value::Text(s) => match parse_expr(s, &self.names, allow_time) {
                Ok(e) => {
                    if !e.has_time()
                        && let Some(d) = &self.defaults
                    {
                        let x = e.eval(d, 0.0);
                        if !x.is_finite() {
                            self.err(
                                w,
                                Some(key),
                                Some(s),
                                format!(
                                    "{label} = \"{s}\" is not finite with the default parameters: {x}"
                                ),
                            );
                        }
                    }
                    e
                }
                Err(pe) => {
                    let msg = match &pe.kind {
                        ParseErrorKind::UnknownIdentifier(n) if self.under_failed(n) => {
                            return Expr::Num(f64::NAN);
                        }
                        ParseErrorKind::UnknownIdentifier(n) => format!(
                            "unknown identifier \"{n}\" in {label} (\"{s}\"){}",
                            close_matches(n, self.names.iter().map(String::as_str))
                        ),
                        ParseErrorKind::TimeNotAllowed => format!(
                            "time t is not allowed in {label} (\"{s}\"); only elementary transforms and applied forces may depend on time"
                        ),
                        ParseErrorKind::Syntax { .. } => format!("{label}: {pe}"),
                    };
                    self.err(w, Some(key), Some(s), msg);
                    Expr::Num(f64::NAN)
                }
            },
        }
    }

    pub(crate) fn vec3(&mut self, w: &Where, label: &str, v: &Vec3, allow_time: bool) -> [Expr; 3] {
        let comps = [&v.0, &v.1, &v.2];
        std::array::from_fn(|i| {
            let l = format!("{label}.{}", ["x", "y", "z"][i]);
            self.expr(w, &l, label, comps[i], allow_time)
        })
    }

    pub(crate) fn vec6(&mut self, w: &Where, label: &str, v: &Vec6) -> [Expr; 6] {
        let comps = [&v.0, &v.1, &v.2, &v.3, &v.4, &v.5];
        std::array::from_fn(|i| self.expr(w, &format!("{label}[{i}]"), label, comps[i], false))
    }
}

/// Every dependency cycle among parameter defaults (each once, as indices in order).
pub(crate) fn find_cycles(exprs: &[Expr]) -> Vec<Vec<usize>> {
    let deps: Vec<Vec<usize>> = exprs.iter().map(Expr::params_used).collect();
    let n = exprs.len();
    let mut state = vec![0u8; n];
    let mut stack = Vec::new();
    let mut cycles: Vec<Vec<usize>> = Vec::new();
    pub(super) fn visit(
        i: usize,
        deps: &[Vec<usize>],
        state: &mut [u8],
        stack: &mut Vec<usize>,
        cycles: &mut Vec<Vec<usize>>,
    ) {
        state[i] = 1;
        stack.push(i);
        for &j in &deps[i] {
            if j >= state.len() {
                continue;
            }
            match state[j] {
                0 => visit(j, deps, state, stack, cycles),
                1 => {
                    let k = stack.iter().position(|&s| s == j).unwrap_or(0);
                    let cycle = stack[k..].to_vec();
                    let mut key = cycle.clone();
                    key.sort_unstable();
                    if !cycles.iter().any(|c| {
                        let mut s = c.clone();
                        s.sort_unstable();
                        s == key
                    }) {
                        cycles.push(cycle);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state[i] = 2;
    }
    for i in 0..n {
        if state[i] == 0 {
            visit(i, &deps, &mut state, &mut stack, &mut cycles);
        }
    }
    cycles
}

/// Evaluates parameter expressions in dependency order; `Err(cycle)` on a cycle.
pub(crate) fn evaluate_parameters(exprs: &[Expr]) -> Result<Vec<f64>, Vec<usize>> {
    if let Some(c) = find_cycles(exprs).into_iter().next() {
        return Err(c);
    }
    let n = exprs.len();
    let mut values = vec![f64::NAN; n];
    let mut done = vec![false; n];
    pub(super) fn eval(i: usize, exprs: &[Expr], values: &mut [f64], done: &mut [bool]) {
        if done[i] {
            return;
        }
        for j in exprs[i].params_used() {
            if j < exprs.len() {
                eval(j, exprs, values, done);
            }
        }
        values[i] = exprs[i].eval(values, 0.0);
        done[i] = true;
    }
    for i in 0..n {
        eval(i, exprs, &mut values, &mut done);
    }
    Ok(values)
}
