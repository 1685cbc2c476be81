//! Expressions over identifiers (parameters) and time: the value of every numeric
//! field of a model. Parsed from text such as `"2*pi*f*t"` or `"sqrt(k/m)"`.

/// A function usable in expressions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Func {
    /// `sin`: sine of an angle in radians.
    Sin,
    /// `cos`: cosine of an angle in radians.
    Cos,
    /// `tan`: tangent of an angle in radians.
    Tan,
    /// `sqrt`: square root (NaN for a negative argument).
    Sqrt,
    /// `abs`: absolute value.
    Abs,
    /// `exp`: the exponential e^x.
    Exp,
    /// `ln`: natural logarithm (NaN for a negative argument).
    Ln,
    /// `atan`: arctangent of one argument, radians in [−π/2, π/2].
    Atan,
}

/// An expression tree. `Param(i)` is the identifier `Model::parameters[i]`,
/// which stays a runtime input of both engines; `Time` is `t` in seconds.
/// `Var(i)` is a local variable bound by the force element that evaluates the
/// expression ([`VAR_NAMES`]`[i]`: the coordinates `x`, `y` of a point–Z-surface
/// contact's height `z = f(x, y)`); only such element fields accept them.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A numeric literal (`pi` is parsed to one too).
    Num(f64),
    /// The identifier (parameter) `Model::parameters[i]`.
    Param(usize),
    /// Time `t`, s.
    Time,
    /// The local variable [`VAR_NAMES`]`[i]` of the evaluating force element.
    Var(usize),
    /// `-a`.
    Neg(Box<Expr>),
    /// `a + b`.
    Add(Box<Expr>, Box<Expr>),
    /// `a - b`.
    Sub(Box<Expr>, Box<Expr>),
    /// `a * b`.
    Mul(Box<Expr>, Box<Expr>),
    /// `a / b`.
    Div(Box<Expr>, Box<Expr>),
    /// `a ^ b`.
    Pow(Box<Expr>, Box<Expr>),
    /// `f(a)`: a function applied to one argument.
    Call(Func, Box<Expr>),
}

/// Names of the local variables `Var(0)`, `Var(1)` in expression text.
pub const VAR_NAMES: [&str; 2] = ["x", "y"];

impl Func {
    /// All functions, for iteration.
    pub const ALL: [Func; 8] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Sqrt,
        Func::Abs,
        Func::Exp,
        Func::Ln,
        Func::Atan,
    ];

    /// The name used in expression text.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Sqrt => "sqrt",
            Func::Abs => "abs",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Atan => "atan",
        }
    }

    /// The function with this name, if any.
    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Applies the function (natural logarithm for `Ln`, radians for trigonometric ones).
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Sqrt => x.sqrt(),
            Func::Abs => x.abs(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Atan => x.atan(),
        }
    }
}

/// Binding strength of an expression node when displayed: larger binds tighter.
fn precedence(e: &Expr) -> u8 {
    match e {
        Expr::Add(..) | Expr::Sub(..) => 1,
        Expr::Mul(..) | Expr::Div(..) => 2,
        Expr::Neg(..) => 3,
        Expr::Pow(..) => 4,
        // A negative literal is displayed in parentheses, so it is atomic too.
        Expr::Num(_) | Expr::Param(_) | Expr::Time | Expr::Var(_) | Expr::Call(..) => 5,
    }
}

impl Expr {
    /// A numeric literal.
    pub fn num(x: f64) -> Expr {
        Expr::Num(x)
    }

    /// True if the expression is literally `Num(0.0)` (also `-0.0`).
    pub fn is_zero(&self) -> bool {
        matches!(self, Expr::Num(x) if *x == 0.0)
    }

    /// True if the expression is literally `Num(1.0)`.
    pub fn is_one(&self) -> bool {
        matches!(self, Expr::Num(x) if *x == 1.0)
    }

    /// Evaluates the expression with parameter values `params` (indexed like
    /// `Model::parameters`) at time `t` (s). A parameter index outside `params`
    /// evaluates to NaN (callers validate indices when the model is loaded).
    pub fn eval(&self, params: &[f64], t: f64) -> f64 {
        self.eval_vars(params, t, &[])
    }

    /// Evaluates the expression with the local variables `vars` (`Var(i)` is
    /// `vars[i]`; a missing one is NaN).
    pub fn eval_vars(&self, params: &[f64], t: f64, vars: &[f64]) -> f64 {
        let e = |x: &Expr| x.eval_vars(params, t, vars);
        match self {
            Expr::Num(x) => *x,
            Expr::Param(i) => params.get(*i).copied().unwrap_or(f64::NAN),
            Expr::Time => t,
            Expr::Var(i) => vars.get(*i).copied().unwrap_or(f64::NAN),
            Expr::Neg(a) => -e(a),
            Expr::Add(a, b) => e(a) + e(b),
            Expr::Sub(a, b) => e(a) - e(b),
            Expr::Mul(a, b) => e(a) * e(b),
            Expr::Div(a, b) => e(a) / e(b),
            Expr::Pow(a, b) => pow(e(a), e(b)),
            Expr::Call(f, a) => f.apply(e(a)),
        }
    }

    /// True if the expression depends on time `t`.
    pub fn has_time(&self) -> bool {
        self.depends_on(&Expr::Time)
    }

    /// True if the expression contains the leaf `leaf` (`Time`, a `Param` or
    /// a `Var`).
    fn depends_on(&self, leaf: &Expr) -> bool {
        self.any_leaf(&|e| e == leaf)
    }

    /// True if the expression uses a local variable (`Var`).
    pub fn has_vars(&self) -> bool {
        self.any_leaf(&|e| matches!(e, Expr::Var(_)))
    }

    /// True if some leaf (`Num`, `Param`, `Time` or `Var`) satisfies `pred`.
    fn any_leaf(&self, pred: &impl Fn(&Expr) -> bool) -> bool {
        match self {
            Expr::Num(_) | Expr::Param(_) | Expr::Time | Expr::Var(_) => pred(self),
            Expr::Neg(a) | Expr::Call(_, a) => a.any_leaf(pred),
            Expr::Add(a, b)
            | Expr::Sub(a, b)
            | Expr::Mul(a, b)
            | Expr::Div(a, b)
            | Expr::Pow(a, b) => a.any_leaf(pred) || b.any_leaf(pred),
        }
    }

    /// Indices of the parameters the expression uses, sorted and unique.
    pub fn params_used(&self) -> Vec<usize> {
        let mut out = Vec::new();
        self.collect_params(&mut out);
        out.sort_unstable();
        out.dedup();
        out
    }

    fn collect_params(&self, out: &mut Vec<usize>) {
        match self {
            Expr::Num(_) | Expr::Time | Expr::Var(_) => {}
            Expr::Param(i) => out.push(*i),
            Expr::Neg(a) | Expr::Call(_, a) => a.collect_params(out),
            Expr::Add(a, b)
            | Expr::Sub(a, b)
            | Expr::Mul(a, b)
            | Expr::Div(a, b)
            | Expr::Pow(a, b) => {
                a.collect_params(out);
                b.collect_params(out);
            }
        }
    }

    /// Replaces every `Param(i)` by `f(i)`.
    pub fn map_params(&self, f: &mut impl FnMut(usize) -> Expr) -> Expr {
        let bx = |e: Expr| Box::new(e);
        match self {
            Expr::Num(_) | Expr::Time | Expr::Var(_) => self.clone(),
            Expr::Param(i) => f(*i),
            Expr::Neg(a) => Expr::Neg(bx(a.map_params(f))),
            Expr::Call(g, a) => Expr::Call(*g, bx(a.map_params(f))),
            Expr::Add(a, b) => Expr::Add(bx(a.map_params(f)), bx(b.map_params(f))),
            Expr::Sub(a, b) => Expr::Sub(bx(a.map_params(f)), bx(b.map_params(f))),
            Expr::Mul(a, b) => Expr::Mul(bx(a.map_params(f)), bx(b.map_params(f))),
            Expr::Div(a, b) => Expr::Div(bx(a.map_params(f)), bx(b.map_params(f))),
            Expr::Pow(a, b) => Expr::Pow(bx(a.map_params(f)), bx(b.map_params(f))),
        }
    }

    /// The total derivative with respect to time, parameters held constant.
    /// Terms that are literally 0 or 1 are simplified away, so the derivative
    /// of an expression without `t` is exactly `Num(0.0)`.
    ///
    /// Where the derivative is undefined (`abs` at 0, `sqrt` at 0) it evaluates
    /// to NaN or ±∞ there, as the mathematics says.
    pub fn time_derivative(&self) -> Expr {
        self.derivative(&Expr::Time)
    }

    /// The partial derivative with respect to the local variable `Var(i)`
    /// (parameters, time and other variables held constant), simplified as
    /// [`Expr::time_derivative`].
    pub fn var_derivative(&self, i: usize) -> Expr {
        self.derivative(&Expr::Var(i))
    }

    /// The partial derivative with respect to the leaf `wrt`.
    fn derivative(&self, wrt: &Expr) -> Expr {
        if !self.depends_on(wrt) {
            return Expr::Num(0.0);
        }
        match self {
            Expr::Num(_) | Expr::Param(_) | Expr::Time | Expr::Var(_) => Expr::Num(1.0),
            Expr::Neg(a) => neg(a.derivative(wrt)),
            Expr::Add(a, b) => add(a.derivative(wrt), b.derivative(wrt)),
            Expr::Sub(a, b) => sub(a.derivative(wrt), b.derivative(wrt)),
            // (ab)' = a'b + ab'
            Expr::Mul(a, b) => add(
                mul(a.derivative(wrt), (**b).clone()),
                mul((**a).clone(), b.derivative(wrt)),
            ),
            // (a/b)' = a'/b − a b'/b²
            Expr::Div(a, b) => sub(
                div(a.derivative(wrt), (**b).clone()),
                div(
                    mul((**a).clone(), b.derivative(wrt)),
                    mul((**b).clone(), (**b).clone()),
                ),
            ),
            Expr::Pow(a, b) => {
                if !b.depends_on(wrt) {
                    // (a^b)' = b a^(b−1) a'
                    let exponent = match **b {
                        Expr::Num(n) => Expr::Num(n - 1.0),
                        _ => sub((**b).clone(), Expr::Num(1.0)),
                    };
                    let power = if exponent.is_one() {
                        (**a).clone()
                    } else if exponent.is_zero() {
                        Expr::Num(1.0)
                    } else {
                        Expr::Pow(a.clone(), Box::new(exponent))
                    };
                    mul(mul((**b).clone(), power), a.derivative(wrt))
                } else {
                    // (a^b)' = a^b (b' ln a + b a'/a)
                    mul(
                        self.clone(),
                        add(
                            mul(b.derivative(wrt), call(Func::Ln, (**a).clone())),
                            div(mul((**b).clone(), a.derivative(wrt)), (**a).clone()),
                        ),
                    )
                }
            }
            Expr::Call(f, a) => {
                let da = a.derivative(wrt);
                let x = (**a).clone();
                let outer = match f {
                    Func::Sin => call(Func::Cos, x),
                    Func::Cos => neg(call(Func::Sin, x)),
                    // 1/cos²
                    Func::Tan => div(
                        Expr::Num(1.0),
                        Expr::Pow(Box::new(call(Func::Cos, x)), Box::new(Expr::Num(2.0))),
                    ),
                    Func::Sqrt => div(Expr::Num(0.5), call(Func::Sqrt, x)),
                    // sign(x) = x/|x|
                    Func::Abs => div(x.clone(), call(Func::Abs, x)),
                    Func::Exp => call(Func::Exp, x),
                    Func::Ln => div(Expr::Num(1.0), x),
                    Func::Atan => div(
                        Expr::Num(1.0),
                        add(
                            Expr::Num(1.0),
                            Expr::Pow(Box::new(x), Box::new(Expr::Num(2.0))),
                        ),
                    ),
                };
                mul(outer, da)
            }
        }
    }

    /// Expression text that [`crate::parse_expr`] (with local variables:
    /// [`crate::parse_expr_vars`] with [`VAR_NAMES`]) parses back to an expression
    /// with the same value (the same tree up to literal signs). `names[i]` is the
    /// name of `Param(i)`; an index without a name is shown as `p<i>` (which
    /// re-parses only if such a name exists).
    pub fn display(&self, names: &[String]) -> String {
        let mut s = String::new();
        self.write(names, &mut s);
        s
    }

    fn write_operand(&self, names: &[String], min_prec: u8, out: &mut String) {
        if precedence(self) >= min_prec {
            self.write(names, out);
        } else {
            out.push('(');
            self.write(names, out);
            out.push(')');
        }
    }

    fn write(&self, names: &[String], out: &mut String) {
        use std::fmt::Write;
        match self {
            Expr::Num(x) => write_number(*x, out),
            Expr::Param(i) => match names.get(*i) {
                Some(n) => out.push_str(n),
                None => {
                    let _ = write!(out, "p{i}");
                }
            },
            Expr::Time => out.push('t'),
            Expr::Var(i) => match VAR_NAMES.get(*i) {
                Some(n) => out.push_str(n),
                None => {
                    let _ = write!(out, "var{i}");
                }
            },
            Expr::Neg(a) => {
                out.push('-');
                // A sign binds looser than a power (-a^b is -(a^b)) but a
                // sign after a sign needs no parentheses: --a reads back as
                // it was written, without doubling its nesting depth (which
                // the parser bounds).
                let min_prec = if matches!(**a, Expr::Neg(_)) { 3 } else { 4 };
                a.write_operand(names, min_prec, out);
            }
            Expr::Add(a, b) | Expr::Sub(a, b) => {
                a.write_operand(names, 1, out);
                out.push_str(if matches!(self, Expr::Add(..)) {
                    " + "
                } else {
                    " - "
                });
                // Right operand of the same precedence needs parentheses: a - (b - c).
                b.write_operand(names, 2, out);
            }
            Expr::Mul(a, b) | Expr::Div(a, b) => {
                a.write_operand(names, 2, out);
                out.push_str(if matches!(self, Expr::Mul(..)) {
                    "*"
                } else {
                    "/"
                });
                b.write_operand(names, 4, out);
            }
            Expr::Pow(a, b) => {
                a.write_operand(names, 5, out);
                out.push('^');
                // Right-associative: a^b^c is a^(b^c).
                b.write_operand(names, 4, out);
            }
            Expr::Call(f, a) => {
                out.push_str(f.name());
                out.push('(');
                a.write(names, out);
                out.push(')');
            }
        }
    }
}

/// `a^b` with `x^2` computed as `x*x` (exact, and what generated code does).
fn pow(a: f64, b: f64) -> f64 {
    if b == 2.0 { a * a } else { a.powf(b) }
}

/// Writes a literal so that it parses back to the same `f64`.
fn write_number(x: f64, out: &mut String) {
    use std::fmt::Write;
    if x.is_nan() {
        out.push_str("(0/0)");
    } else if x.is_infinite() {
        out.push_str(if x > 0.0 { "(1/0)" } else { "(-1/0)" });
    } else if x < 0.0 || (x == 0.0 && x.is_sign_negative()) {
        let _ = write!(out, "(-{:?})", -x);
    } else {
        // `{:?}` is the shortest text that round-trips (e.g. 0.1, 1e-7, 2.0).
        let _ = write!(out, "{x:?}");
    }
}

fn neg(a: Expr) -> Expr {
    match a {
        Expr::Num(0.0) => Expr::Num(0.0),
        Expr::Neg(inner) => *inner,
        a => Expr::Neg(Box::new(a)),
    }
}

fn add(a: Expr, b: Expr) -> Expr {
    if a.is_zero() {
        b
    } else if b.is_zero() {
        a
    } else {
        Expr::Add(Box::new(a), Box::new(b))
    }
}

fn sub(a: Expr, b: Expr) -> Expr {
    if b.is_zero() {
        a
    } else if a.is_zero() {
        neg(b)
    } else {
        Expr::Sub(Box::new(a), Box::new(b))
    }
}

fn mul(a: Expr, b: Expr) -> Expr {
    if a.is_zero() || b.is_zero() {
        Expr::Num(0.0)
    } else if a.is_one() {
        b
    } else if b.is_one() {
        a
    } else {
        Expr::Mul(Box::new(a), Box::new(b))
    }
}

fn div(a: Expr, b: Expr) -> Expr {
    if a.is_zero() {
        Expr::Num(0.0)
    } else if b.is_one() {
        a
    } else {
        Expr::Div(Box::new(a), Box::new(b))
    }
}

fn call(f: Func, a: Expr) -> Expr {
    Expr::Call(f, Box::new(a))
}
