//! Expressions over identifiers (parameters) and time: the value of every numeric
//! field of a model. Parsed from text such as `"2*pi*f*t"` or `"sqrt(k/m)"`.

/// A function usable in expressions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Sqrt,
    Abs,
    Exp,
    Ln,
    Atan,
}

/// An expression tree. `Param(i)` is the identifier `Model::parameters[i]`,
/// which stays a runtime input of both engines; `Time` is `t` in seconds.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    Num(f64),
    Param(usize),
    Time,
    Neg(Box<Expr>),
    Add(Box<Expr>, Box<Expr>),
    Sub(Box<Expr>, Box<Expr>),
    Mul(Box<Expr>, Box<Expr>),
    Div(Box<Expr>, Box<Expr>),
    /// `a ^ b`.
    Pow(Box<Expr>, Box<Expr>),
    Call(Func, Box<Expr>),
}
