//! # railmbs-cas — the computer-algebra system of railmbs
//!
//! The code generator derives the equations of motion of a multibody system (recursive
//! kinematics over products of elementary rotations, mass matrices by the composite-body
//! method, Jacobians) with this crate, then compiles all outputs together into straight-line
//! code ([`Program`]) that it emits as Rust.
//!
//! ## Design
//!
//! * **Arena with hash-consing.** A [`Context`] owns every node; an [`ExprId`] is a `u32` index
//!   (`Copy`). Structurally equal nodes are stored once (open-addressing table of ids, hashed
//!   once on creation), so equal subexpressions are one node and "is it the same expression"
//!   is an id comparison. The arena is append-only: operands always have smaller ids than
//!   their users, so ascending id order is a topological order — traversals are iterative and
//!   cannot overflow the stack.
//! * **Node kinds** ([`Node`]): numbers (`f64`), symbols ([`Symbol`]: a [`SymbolKind`] —
//!   coordinate `q`, velocity `v`, parameter `p`, input `u`, time `t` — and an index, so
//!   generated code maps them to input arrays), n-ary sums `constant + Σ cᵢ·bᵢ` with numeric
//!   coefficients, n-ary products `Π bᵢ^kᵢ` with integer exponents, the functions of [`Func`]
//!   (sin, cos, tan, sqrt, exp, ln, abs) and `atan2`.
//!   Division is a product with exponent −1 (no separate node), an integer power is a
//!   one-factor product, negation is the coefficient −1 (a "scaled term" `c·b` is a one-term
//!   sum). Operands of sums and products are sorted by id, so commutative forms are equal nodes.
//! * **Numbers** are `f64`. Sums and products of numbers fold in f64 (exact whenever the
//!   result is representable: integers, dyadic fractions such as 0.5, which is what model
//!   coefficients and derivatives of integer powers produce). Division by a number folds only
//!   when the quotient is exact (checked with a fused multiply-add): `x/4 = 0.25·x`, but `x/3`
//!   keeps the factor `3⁻¹`, is evaluated as a division, and `3·(x/3) = x`,
//!   `x/3 + 2x/3 = x`; `m·l²/12` stays exact.
//!   Functions of numbers are folded only when the result is finite (`ln(-1)` stays symbolic).
//!   Non-finite values are never produced silently: [`Context::eval`], [`Program::eval`]
//!   report them as [`CasError::NonFinite`].
//!
//! * **Cost.** Building a node costs O(k log k) in its operand count k (sort, merge, one hash
//!   lookup); a node that exists already is found, not duplicated. Build long sums and
//!   products with the n-ary [`Context::sum`], [`Context::add_many`], [`Context::product`],
//!   [`Context::mul_many`]: folding them pairwise re-flattens at every step (quadratic).
//!   Ids are `u32`: a context holds at most 2³² − 1 nodes (exceeding that panics with a
//!   message; a rail vehicle model needs a few million at most).
//!
//! ## Example
//!
//! ```
//! use railmbs_cas::{Context, Program, Symbol, Values};
//!
//! let mut c = Context::new();
//! let (q, l) = (c.q(0), c.p(0));
//! let s = c.sin(q);
//! let x = c.mul(l, s); // x = l·sin q
//! let dx = c.diff(x, Symbol::q(0)); // l·cos q
//! let co = c.cos(q);
//! assert_eq!(dx, c.mul(l, co));
//! let prog = Program::compile(&c, &[x, dx]);
//! let out = prog.eval(&Values { q: &[0.0], p: &[2.0], ..Default::default() }).unwrap();
//! assert_eq!(out, vec![0.0, 2.0]);
//! ```
//!
//! ## What the simplifier does on construction
//!
//! All rules are local and cheap (cost linear in the operand count of the node being built,
//! up to sorting); there is no expansion by default ([`Context::expand`] exists for small
//! expressions).
//!
//! * constant folding of sums, products and functions of numbers;
//! * identities `x + 0`, `x·1`, `x·0 = 0`, `x⁰ = 1`, `x¹ = x`;
//! * flattening of nested products, and of nested sums of at most [`FLATTEN_LIMIT`] (8) terms:
//!   a larger sum stays one shared operand of the enclosing sum, so recursive accumulations
//!   (positions down a chain, composite-body sums) cost O(1) per step instead of re-flattening
//!   O(depth) terms; the price is that like terms inside such a sum do not meet terms outside
//!   it (a missed cancellation, never a wrong value); numeric factors of products are pulled out
//!   (`2x·3y = 6·(x·y)`), and a number times a sum is distributed (`2·(x + y) = 2x + 2y`);
//! * like terms `c₁x + c₂x = (c₁+c₂)x` and like factors `x·x = x²`, `x·x⁻¹ = 1` (so `x/x = 1`,
//!   as every CAS does, ignoring x = 0);
//! * `sin(−x) = −sin x`, `cos(−x) = cos x`, `tan(−x) = −tan x`, `|−x| = |x|`, `||x|| = |x|`,
//!   using a canonical sign of the argument ([`Context::is_negative_form`]), so `sin(a−b)` and
//!   `sin(b−a)` share one node;
//! * `√(x²) = |x|`, `(√x)^k = x^(k/2)·(√x)^(k mod 2)`, `exp(ln x) = x`, `ln(exp x) = x`;
//! * **sin² + cos² = 1** inside one sum: two terms `c·sin(u)^k·P` and `c·cos(u)^m·P'` with the
//!   same coefficient `c`, `k, m ≥ 2`, and the same remaining monomial
//!   `sin(u)^(k−2)·P = cos(u)^(m−2)·P'` are replaced by `c·(that remainder)`, repeatedly (the
//!   result may merge with other terms). This is what products of elementary rotation
//!   matrices create: `R_z(a)ᵀR_z(a)` and `RᵀR` for `R = R_z(a)R_x(b)` simplify to the
//!   identity, `m·l²·sin²q + m·l²·cos²q` to `m·l²`. When the entries are sums (three or more
//!   rotations), `RᵀR` contains squares of sums and reduces to the identity only after
//!   [`Context::expand`].
//!
//! It does **not**: expand products of sums, factor, find common denominators, apply angle
//! addition formulas, combine `c₁·sin²u·P + c₂·cos²u·P` with `c₁ ≠ c₂`, recognise
//! `1 − sin²u = cos²u`, or simplify `√` of non-squares. Two mathematically equal expressions
//! may therefore be different nodes; numeric equality is checked by evaluation.
//!
//! ## Calculus, substitution, evaluation
//!
//! [`Context::diff`] differentiates with respect to a symbol, memoized per variable for the
//! life of the context ([`Context::jacobian`] for many at once; [`Context::clear_diff_cache`]
//! frees the memo). [`Context::subs`] and [`Substitution`] replace symbols by expressions
//! (memoized). [`Context::eval`] is the
//! reference interpreter, with symbol values per kind in [`Values`].
//!
//! ## Kinematics helpers
//!
//! [`Mat3`] and [`Vec3`] are plain arrays of ids; [`Context::rot_x`], [`Context::rot_y`],
//! [`Context::rot_z`] build elementary rotation matrices (body → parent), with
//! [`Context::mat_mul`], [`Context::mat_vec`], [`Context::cross`], [`Context::dot`] for
//! recursive kinematics.
//!
//! ## Straight-line code
//!
//! [`Program::compile`] lowers a list of outputs together into instructions
//! `t_k = op(operands)` (see [`Program`] for the lowering rules: shared nodes once, value
//! numbering, powers by squaring with shared `x²`, negation folded into subtraction, one
//! division per product). [`Context::tree_op_counts`] gives the operation count of the
//! unshared tree form (saturating `u128`), [`Program::op_counts`] that of the program — the
//! "before / after CSE" numbers. [`Program::eval`] interprets the program.
//!
//! For code generation of large programs, [`Program::last_uses`] gives liveness of
//! temporaries and [`Program::split`] cuts the program into chunks of bounded size that pass
//! the temporaries they share through a scratch array (slots reused when dead);
//! [`SplitProgram::eval`] checks a split by running each chunk in isolation.
//! [`Program::sin_cos_pairs`] lists sin/cos of the same argument for `sin_cos` fusion.
//!
//! Everything is deterministic: the same sequence of constructor calls gives the same ids and
//! the same program, instruction for instruction (no dependence on hash-map iteration order),
//! so generated source can be cached by content hash.

mod calculus;
mod eval;
mod graph;
mod lanes;
mod linalg;
mod program;

pub use calculus::Substitution;
pub use eval::{CasError, Values};
pub use graph::{
    Context, Display, ExprId, FLATTEN_LIMIT, Func, Node, ONE, Symbol, SymbolKind, ZERO,
};
pub use lanes::Packed;
pub use linalg::{IDENTITY, Mat3, Vec3};
pub use program::{Chunk, Instr, OpCounts, Operand, Program, SplitProgram};
