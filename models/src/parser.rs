//! Parser of expression text: `+ - * / ^`, parentheses, functions
//! (`sin cos tan sqrt abs exp ln atan`), the constant `pi`, numbers
//! (`1`, `1.5`, `1e-3`, `.5`), identifiers (letters, digits, `_` and `.`,
//! starting with a letter or `_`, e.g. `WS1.r0`) and time `t`.
//!
//! Grammar (precedence from loose to tight; `^` is right-associative and
//! binds tighter than unary minus, so `-x^2 = -(x^2)` and `2^-1 = 0.5`):
//! ```text
//! sum     := product (('+' | '-') product)*
//! product := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary ('^' unary)?
//! primary := number | 'pi' | 't' | identifier | function '(' sum ')' | '(' sum ')'
//! ```

use crate::expr::{Expr, Func};
use std::fmt;

/// What went wrong in an expression.
#[derive(Debug, Clone, PartialEq)]
pub enum ParseErrorKind {
    /// Malformed text: what was expected and what was found instead.
    Syntax {
        /// What the parser expected there, e.g. `a number`.
        expected: String,
        /// What it found instead: the character (or number text) in quotes, or
        /// `the end of the expression`.
        found: String,
    },
    /// An identifier that is not a parameter of the model.
    UnknownIdentifier(String),
    /// `t` where the value must not depend on time.
    TimeNotAllowed,
}

/// An error in expression text, with the 1-based column (in characters) where it was found.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    /// The whole expression text.
    pub text: String,
    /// 1-based character column within `text`.
    pub column: usize,
    /// What went wrong.
    pub kind: ParseErrorKind,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // A long expression is quoted around the column only.
        const QUOTE: usize = 60;
        let chars: Vec<char> = self.text.chars().collect();
        if chars.len() <= 2 * QUOTE {
            write!(f, "in expression \"{}\"", self.text)?;
        } else {
            let at = self.column.saturating_sub(1).min(chars.len());
            let (a, b) = (at.saturating_sub(QUOTE), (at + QUOTE).min(chars.len()));
            let part: String = chars[a..b].iter().collect();
            let (pre, post) = (
                if a > 0 { "…" } else { "" },
                if b < chars.len() { "…" } else { "" },
            );
            write!(
                f,
                "in expression \"{pre}{part}{post}\" ({} characters)",
                chars.len()
            )?;
        }
        write!(f, " at column {}: ", self.column)?;
        match &self.kind {
            ParseErrorKind::Syntax { expected, found } => {
                write!(f, "expected {expected}, found {found}")
            }
            ParseErrorKind::UnknownIdentifier(name) => write!(f, "unknown identifier \"{name}\""),
            ParseErrorKind::TimeNotAllowed => {
                write!(
                    f,
                    "time `t` is not allowed here (the value must be constant in time)"
                )
            }
        }
    }
}

impl std::error::Error for ParseError {}

/// Names with a fixed meaning in expressions, which cannot name parameters.
pub fn is_reserved_name(name: &str) -> bool {
    name == "t" || name == "pi" || Func::from_name(name).is_some()
}

/// True if `name` is a valid identifier: a letter or `_`, then letters, digits, `_` or `.`.
pub fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    match chars.next() {
        Some(c) if c.is_ascii_alphabetic() || c == '_' => {}
        _ => return false,
    }
    !name.ends_with('.') && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.')
}

/// Parses `text`, resolving identifiers to `Param(i)` with `names[i] == identifier`.
/// `t` is accepted only if `allow_time`.
pub fn parse_expr(text: &str, names: &[String], allow_time: bool) -> Result<Expr, ParseError> {
    parse_expr_with(text, allow_time, |id| names.iter().position(|n| n == id))
}

/// Parses `text`, resolving identifiers with `resolve` (parameter index or `None`).
pub fn parse_expr_with(
    text: &str,
    allow_time: bool,
    resolve: impl FnMut(&str) -> Option<usize>,
) -> Result<Expr, ParseError> {
    parse_expr_vars(text, allow_time, &[], resolve)
}

/// Parses `text` where the identifiers `vars[i]` are the local variables
/// `Var(i)` (they shadow parameters of the same name) and the others resolve
/// with `resolve`.
pub fn parse_expr_vars(
    text: &str,
    allow_time: bool,
    vars: &[&str],
    resolve: impl FnMut(&str) -> Option<usize>,
) -> Result<Expr, ParseError> {
    let mut p = Parser {
        text,
        chars: text.chars().collect(),
        pos: 0,
        depth: 0,
        operators: 0,
        allow_time,
        vars,
        resolve,
    };
    p.skip_ws();
    let e = p.sum()?;
    p.skip_ws();
    if p.pos < p.chars.len() {
        return Err(p.syntax("an operator or the end of the expression"));
    }
    Ok(e)
}

struct Parser<'a, R> {
    text: &'a str,
    chars: Vec<char>,
    pos: usize,
    /// Current nesting depth of `unary` (every recursion passes through it).
    depth: usize,
    /// Binary operators read so far.
    operators: usize,
    allow_time: bool,
    vars: &'a [&'a str],
    resolve: R,
}

/// Deepest nesting of parentheses, signs and powers accepted, so that
/// pathological text gives an error instead of overflowing the stack.
const MAX_DEPTH: usize = 200;

/// Most binary operators in one expression. A chain `1+1+…` nests one level
/// per operator in the expression tree, which later passes (evaluation,
/// differentiation, code generation) walk recursively: 100 000 terms overflow
/// the stack. Model expressions have tens of operators.
const MAX_OPERATORS: usize = 1000;

impl<R: FnMut(&str) -> Option<usize>> Parser<'_, R> {
    fn peek(&self) -> Option<char> {
        self.chars.get(self.pos).copied()
    }

    fn skip_ws(&mut self) {
        while self.peek().is_some_and(char::is_whitespace) {
            self.pos += 1;
        }
    }

    fn error_at(&self, column0: usize, kind: ParseErrorKind) -> ParseError {
        ParseError {
            text: self.text.to_string(),
            column: column0 + 1,
            kind,
        }
    }

    fn syntax(&self, expected: &str) -> ParseError {
        let found = match self.peek() {
            Some(c) => format!("'{c}'"),
            None => "the end of the expression".to_string(),
        };
        self.error_at(
            self.pos,
            ParseErrorKind::Syntax {
                expected: expected.to_string(),
                found,
            },
        )
    }

    /// Counts one binary operator, failing past [`MAX_OPERATORS`].
    fn operator(&mut self) -> Result<(), ParseError> {
        self.operators += 1;
        if self.operators > MAX_OPERATORS {
            return Err(self.syntax(&format!(
                "the end of the expression: at most {MAX_OPERATORS} operators in one expression"
            )));
        }
        Ok(())
    }

    fn eat(&mut self, c: char) -> bool {
        if self.peek() == Some(c) {
            self.pos += 1;
            self.skip_ws();
            true
        } else {
            false
        }
    }

    fn sum(&mut self) -> Result<Expr, ParseError> {
        let mut lhs = self.product()?;
        loop {
            if self.eat('+') {
                self.operator()?;
                let rhs = self.product()?;
                lhs = Expr::Add(Box::new(lhs), Box::new(rhs));
            } else if self.eat('-') {
                self.operator()?;
                let rhs = self.product()?;
                lhs = Expr::Sub(Box::new(lhs), Box::new(rhs));
            } else {
                return Ok(lhs);
            }
        }
    }

    fn product(&mut self) -> Result<Expr, ParseError> {
        let mut lhs = self.unary()?;
        loop {
            if self.eat('*') {
                self.operator()?;
                let rhs = self.unary()?;
                lhs = Expr::Mul(Box::new(lhs), Box::new(rhs));
            } else if self.eat('/') {
                self.operator()?;
                let rhs = self.unary()?;
                lhs = Expr::Div(Box::new(lhs), Box::new(rhs));
            } else {
                return Ok(lhs);
            }
        }
    }

    fn unary(&mut self) -> Result<Expr, ParseError> {
        if self.depth >= MAX_DEPTH {
            return Err(self.syntax(&format!(
                "at most {MAX_DEPTH} levels of nested parentheses, signs and powers"
            )));
        }
        self.depth += 1;
        let result = self.unary_inner();
        self.depth -= 1;
        result
    }

    fn unary_inner(&mut self) -> Result<Expr, ParseError> {
        if self.eat('-') {
            Ok(Expr::Neg(Box::new(self.unary()?)))
        } else if self.eat('+') {
            self.unary()
        } else {
            self.power()
        }
    }

    fn power(&mut self) -> Result<Expr, ParseError> {
        let base = self.primary()?;
        if self.eat('^') {
            self.operator()?;
            let exponent = self.unary()?;
            Ok(Expr::Pow(Box::new(base), Box::new(exponent)))
        } else {
            Ok(base)
        }
    }

    fn primary(&mut self) -> Result<Expr, ParseError> {
        const OPERAND: &str = "a number, an identifier, a function or '('";
        let start = self.pos;
        match self.peek() {
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(),
            Some(c) if c.is_ascii_alphabetic() || c == '_' => {
                while self
                    .peek()
                    .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.')
                {
                    self.pos += 1;
                }
                let name: String = self.chars[start..self.pos].iter().collect();
                if name.ends_with('.') {
                    self.pos -= 1;
                    return Err(self.syntax("a letter, digit or '_' after '.' in an identifier"));
                }
                self.skip_ws();
                if let Some(f) = Func::from_name(&name) {
                    if !self.eat('(') {
                        return Err(self.syntax(&format!("'(' after the function {name}")));
                    }
                    let arg = self.sum()?;
                    if !self.eat(')') {
                        return Err(self.syntax("')' closing the function's argument"));
                    }
                    return Ok(Expr::Call(f, Box::new(arg)));
                }
                match name.as_str() {
                    "pi" => Ok(Expr::Num(std::f64::consts::PI)),
                    "t" => {
                        if self.allow_time {
                            Ok(Expr::Time)
                        } else {
                            Err(self.error_at(start, ParseErrorKind::TimeNotAllowed))
                        }
                    }
                    _ if self.vars.contains(&name.as_str()) => Ok(Expr::Var(
                        self.vars.iter().position(|v| *v == name).unwrap_or(0),
                    )),
                    _ => match (self.resolve)(&name) {
                        Some(i) => Ok(Expr::Param(i)),
                        None => Err(self.error_at(start, ParseErrorKind::UnknownIdentifier(name))),
                    },
                }
            }
            Some('(') => {
                self.eat('(');
                let e = self.sum()?;
                if !self.eat(')') {
                    return Err(self.syntax("')'"));
                }
                Ok(e)
            }
            _ => Err(self.syntax(OPERAND)),
        }
    }

    fn number(&mut self) -> Result<Expr, ParseError> {
        let start = self.pos;
        let digits = |p: &mut Self| {
            let s = p.pos;
            while p.peek().is_some_and(|c| c.is_ascii_digit()) {
                p.pos += 1;
            }
            p.pos - s
        };
        let mut n = digits(self);
        if self.peek() == Some('.') {
            self.pos += 1;
            n += digits(self);
        }
        if n == 0 {
            self.pos = start;
            return Err(self.syntax("a number"));
        }
        if matches!(self.peek(), Some('e' | 'E')) {
            self.pos += 1;
            if matches!(self.peek(), Some('+' | '-')) {
                self.pos += 1;
            }
            if digits(self) == 0 {
                return Err(self.syntax("the digits of the exponent"));
            }
        }
        if self
            .peek()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.')
        {
            return Err(self.syntax("an operator after the number"));
        }
        let s: String = self.chars[start..self.pos].iter().collect();
        self.skip_ws();
        match s.parse::<f64>() {
            Ok(x) => Ok(Expr::Num(x)),
            Err(_) => Err(self.error_at(
                start,
                ParseErrorKind::Syntax {
                    expected: "a number".into(),
                    found: format!("\"{s}\""),
                },
            )),
        }
    }
}
