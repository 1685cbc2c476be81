//! # railmbs-models
//!
//! The model description language of railmbs. A vehicle, a mechanism or a
//! scenario is described once in a RON file; this crate reads it, resolves
//! identifiers and expressions, and validates it with errors that name the file,
//! the element and the RON line and column. The result is a [`Model`] (or a
//! [`Scenario`]) that both engines — the numeric-iterative `runtime` and the
//! symbolic `codegen` — consume.

mod error;
pub mod expr;
mod load;
mod locate;
mod methods;
pub mod model;
pub mod parser;
mod raw;
pub mod scenario;

pub use error::{ModelError, ModelErrors};
pub use expr::{Expr, Func};
pub use load::{load_model, parse_model};
pub use model::*;
pub use parser::{ParseError, ParseErrorKind, parse_expr, parse_expr_with};
pub use scenario::*;
pub use scenario::{load_scenario, parse_scenario};
