//! Rust source of a plugin: straight-line code of the CSE'd programs, split into
//! functions of bounded size, and the exported functions of the flat `extern "C"`
//! interface. The interface's types, version and CPU-feature list are not written here:
//! they are the text of `railmbs_plugin_abi` ([`railmbs_plugin_abi::SOURCE`]), pasted
//! verbatim into the plugin, whose exported functions are checked against its signatures
//! when the plugin compiles.
//!
//! Programs (each CSE'd over all its outputs together):
//! - `dyn`: M (nonzero upper-triangle entries), k, Q_g;
//! - `kin`: body kinematics and the nonzero entries of the Jacobians Γ;
//! - `all`: both of the above together (one simulation step with force elements);
//! - `con`: constraints g and the nonzero entries of G (when the model has cut joints).

use crate::derive::Derived;
use proc_macro2::{Literal, TokenStream};
use quote::{format_ident, quote};
use railmbs_cas::Func as CasFunc;
use railmbs_cas::{Instr, OpCounts, Operand, Program, SymbolKind};

/// Where one program output goes: buffer and flat index (column-major for
/// matrices); a mass entry off the diagonal goes to both triangles.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Target {
    Mass { row: usize, col: usize },
    Bias(usize),
    Gravity(usize),
    Kinematics(usize),
    Jacobian(usize),
    Constraint(usize),
    ConstraintJacobian(usize),
}

/// One program with its output targets.
pub(crate) struct Unit {
    pub name: &'static str,
    pub program: Program,
    pub targets: Vec<Target>,
    /// Instructions of `program` computed by one `sin_cos_batch` call
    /// ([`Program::batch_sin_cos`]).
    pub trig_batch: std::ops::Range<usize>,
    /// Lanes of the vector operations ([`Program::pack_lanes`]); 1 for none.
    pub lanes: usize,
    /// First instructions of the packs (each `lanes` instructions computed as one vector).
    pub packs: Vec<usize>,
    /// Ranges each function must hold whole: the packs and the batch ([`railmbs_cas::Packed::together`]).
    pub together: Vec<std::ops::Range<usize>>,
}

impl Unit {
    fn new(
        name: &'static str,
        ctx: &railmbs_cas::Context,
        outputs: &[railmbs_cas::ExprId],
        targets: Vec<Target>,
        n: usize,
        lanes: usize,
    ) -> Unit {
        let (program, trig_batch) = Program::compile(ctx, outputs).batch_sin_cos();
        let seeds = mass_row_seeds(&program, &targets, n, lanes);
        let packed = program.pack_lanes(&seeds, lanes, std::slice::from_ref(&trig_batch));
        let together = packed.together();
        Unit {
            name,
            targets,
            trig_batch: packed.keep[0].clone(),
            lanes: packed.width,
            packs: packed.packs,
            program: packed.program,
            together,
        }
    }
}

/// Seeds for [`Program::pack_lanes`]: the upper-triangle mass entries M(r, c … c+lanes−1) of
/// one row and a block of adjacent columns, whose mirrored entries M(c … c+lanes−1, r) are
/// adjacent in the column-major buffer. Rows go from the first, where the column recursions
/// M_rc = M_(r+1)c + … end, so that one seed grows down a whole block of columns. Blocks are
/// tried at every alignment, the one ending at the last column first (the longest columns
/// fill whole blocks): a column whose entries are lowered differently (a chain's last link,
/// whose composite moment is half a segment, say) stops a tree, and the packer keeps only
/// trees that pay.
fn mass_row_seeds(program: &Program, targets: &[Target], n: usize, lanes: usize) -> Vec<Vec<u32>> {
    if lanes < 2 || n < lanes + 1 {
        return Vec::new();
    }
    let mut entry = vec![None; n * n];
    for (out, target) in program.outputs.iter().zip(targets) {
        if let (Operand::Tmp(k), Target::Mass { row, col }) = (out, target) {
            entry[row * n + col] = Some(*k);
        }
    }
    let mut seeds = Vec::new();
    for shift in 0..lanes {
        for row in 0..n {
            let mut end = n - shift;
            while end >= lanes && end - lanes > row {
                let seed: Option<Vec<u32>> =
                    (end - lanes..end).map(|c| entry[row * n + c]).collect();
                seeds.extend(seed);
                end -= lanes;
            }
        }
    }
    seeds
}

/// Statistics for `umgen`.
#[derive(Debug, Clone, Default)]
pub struct EmitStats {
    /// Operation count of the unshared expression trees of all outputs.
    pub ops_tree: OpCounts,
    /// Operations of the emitted programs (after CSE), summed over programs.
    pub ops_cse: OpCounts,
    /// Instructions of the `dyn` program (M, k, Q_g) alone.
    pub dyn_instructions: usize,
    /// Lines of generated source.
    pub source_lines: usize,
    /// Functions emitted.
    pub functions: usize,
    /// Time of common-subexpression elimination (building the programs).
    pub cse_time: std::time::Duration,
    /// Time of writing and formatting the Rust source.
    pub format_time: std::time::Duration,
}

/// Identity of the generated plugin.
pub struct PluginHeader<'a> {
    /// Name of the model.
    pub model_name: &'a str,
    /// Its structural hash (`Model::structural_hash`), checked by the loader.
    pub model_hash: &'a str,
    /// Its coordinate names, in order.
    pub coordinate_names: Vec<String>,
    /// Its parameter names, in order.
    pub parameter_names: Vec<String>,
    /// Names of the runtime inputs (`<body>.<component>` of each track-following frame;
    /// 3 numbers each in u: value, rate, acceleration).
    pub input_names: Vec<String>,
    /// Parameters fixed at generation time, with their values (the plugin still
    /// takes the full parameter vector; the host refuses other values for these).
    pub fixed: Vec<(usize, f64)>,
}

pub(crate) fn units(d: &Derived, lanes: usize) -> Vec<Unit> {
    let n = d.dof;
    let nb6 = 6 * d.bodies;
    let mut dyn_out = Vec::new();
    let mut dyn_t = Vec::new();
    for (e, &(row, col)) in d.mass.iter().zip(&d.mass_index) {
        dyn_out.push(*e);
        dyn_t.push(Target::Mass { row, col });
    }
    for (i, e) in d.bias.iter().enumerate() {
        dyn_out.push(*e);
        dyn_t.push(Target::Bias(i));
    }
    for (i, e) in d.gravity.iter().enumerate() {
        dyn_out.push(*e);
        dyn_t.push(Target::Gravity(i));
    }
    let mut kin_out = Vec::new();
    let mut kin_t = Vec::new();
    for (i, e) in d.kinematics.iter().enumerate() {
        kin_out.push(*e);
        kin_t.push(Target::Kinematics(i));
    }
    for (e, &(r, c)) in d.jacobians.iter().zip(&d.jacobian_index) {
        kin_out.push(*e);
        kin_t.push(Target::Jacobian(c * nb6 + r));
    }
    let mut all_out = dyn_out.clone();
    all_out.extend_from_slice(&kin_out);
    let mut all_t = dyn_t.clone();
    all_t.extend_from_slice(&kin_t);
    let mut units = vec![
        Unit::new("dyn", &d.ctx, &dyn_out, dyn_t, n, lanes),
        Unit::new("kin", &d.ctx, &kin_out, kin_t, n, lanes),
        Unit::new("all", &d.ctx, &all_out, all_t, n, lanes),
    ];
    if !d.constraints.is_empty() {
        let nc = d.constraints.len();
        let mut out = Vec::new();
        let mut t = Vec::new();
        for (i, e) in d.constraints.iter().enumerate() {
            out.push(*e);
            t.push(Target::Constraint(i));
        }
        for (e, &(r, c)) in d
            .constraint_jacobian
            .iter()
            .zip(&d.constraint_jacobian_index)
        {
            out.push(*e);
            t.push(Target::ConstraintJacobian(c * nc + r));
        }
        units.push(Unit::new("con", &d.ctx, &out, t, n, lanes));
    }
    units
}

/// An index or a length as an unsuffixed literal (`mass[3]`, not `mass[3usize]`).
fn ix(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

/// The names generated code indexes its inputs with: one `usize` constant per coordinate
/// (`Q_…`: its index in q, and that of its velocity in v), per parameter (`P_…`) and per
/// runtime input (`U_…`: the index in u of its value; its rate and acceleration follow),
/// made from the model's names.
pub(crate) struct Names {
    coordinates: Vec<proc_macro2::Ident>,
    parameters: Vec<proc_macro2::Ident>,
    inputs: Vec<proc_macro2::Ident>,
}

impl Names {
    pub(crate) fn new(header: &PluginHeader) -> Self {
        Names {
            coordinates: constant_names("Q", &header.coordinate_names),
            parameters: constant_names("P", &header.parameter_names),
            inputs: constant_names("U", &header.input_names),
        }
    }

    /// `const Q_…: usize = i;` for every coordinate, parameter and input; the first of each
    /// group says what the group indexes (the model's own names are in the plugin's name
    /// lists).
    fn definitions(&self) -> TokenStream {
        let define = |idents: &[proc_macro2::Ident], what: &str, step| {
            let items = idents.iter().enumerate().map(|(i, id)| {
                let doc = (i == 0).then(|| quote!(#[doc = #what]));
                let i = ix(step * i);
                quote!(#doc const #id: usize = #i;)
            });
            quote!(#(#items)*)
        };
        let q = define(
            &self.coordinates,
            " Indices of the coordinates in q (and of their velocities in v), named after the \
             model's coordinates (`COORDINATE_NAMES`).",
            1,
        );
        let p = define(
            &self.parameters,
            " Indices of the parameters in p, named after the model's parameters \
             (`PARAMETER_NAMES`).",
            1,
        );
        let u = define(
            &self.inputs,
            " Indices in u of the runtime inputs, the pose components of the track-following \
             frames (`<body>.<component>`): the value, then its rate and acceleration.",
            3,
        );
        quote!(#q #p #u)
    }
}

/// `PREFIX_NAME` constants for `names`: the name's runs of ASCII letters and digits in upper
/// case, joined by underscores (`Bogie1.WS1.m` → `P_BOGIE1_WS1_M`); the index is appended
/// to a name that would repeat an earlier one (or stands alone for a name with no such run).
fn constant_names(prefix: &str, names: &[String]) -> Vec<proc_macro2::Ident> {
    let mut seen = std::collections::HashSet::new();
    names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let words: Vec<String> = name
                .split(|c: char| !c.is_ascii_alphanumeric())
                .filter(|w| !w.is_empty())
                .map(|w| w.to_ascii_uppercase())
                .collect();
            let mut id = if words.is_empty() {
                format!("{prefix}_{i}")
            } else {
                format!("{prefix}_{}", words.join("_"))
            };
            while !seen.insert(id.clone()) {
                id = format!("{id}_{i}");
            }
            format_ident!("{}", id)
        })
        .collect()
}

/// What operands are written with: the names of the inputs and the expression of a
/// temporary (a local `t_k`, or a scratch slot).
struct Cx<'a> {
    names: &'a Names,
    tmp: &'a dyn Fn(u32) -> TokenStream,
}

fn lit(x: f64) -> TokenStream {
    // Exact round-trip literal (f64 by inference: every use is an f64 operand); the sign
    // goes outside for negative numbers.
    if x < 0.0 {
        let l = Literal::f64_unsuffixed(-x);
        quote!((-#l))
    } else {
        let l = Literal::f64_unsuffixed(x);
        quote!(#l)
    }
}

fn operand(o: Operand, local: &Cx) -> TokenStream {
    match o {
        Operand::Tmp(k) => (local.tmp)(k),
        Operand::Const(c) => lit(c),
        Operand::Sym(s) => {
            let i = s.index as usize;
            match s.kind {
                SymbolKind::Coordinate => {
                    let c = &local.names.coordinates[i];
                    quote!(q[#c])
                }
                SymbolKind::Velocity => {
                    let c = &local.names.coordinates[i];
                    quote!(v[#c])
                }
                SymbolKind::Parameter => {
                    let c = &local.names.parameters[i];
                    quote!(p[#c])
                }
                SymbolKind::Input => match (local.names.inputs.get(i / 3), i % 3) {
                    (Some(c), 0) => quote!(u[#c]),
                    (Some(c), d) => {
                        let d = ix(d);
                        quote!(u[#c + #d])
                    }
                    (None, _) => {
                        let i = ix(i);
                        quote!(u[#i])
                    }
                },
                SymbolKind::Time => quote!(t),
            }
        }
    }
}

/// The operands of an instruction.
fn instr_operands(i: &Instr) -> Vec<Operand> {
    match *i {
        Instr::Add(a, b)
        | Instr::Sub(a, b)
        | Instr::Mul(a, b)
        | Instr::Div(a, b)
        | Instr::Atan2(a, b) => vec![a, b],
        Instr::Neg(a) | Instr::Call(_, a) => vec![a],
    }
}

fn instr(i: &Instr, local: &Cx) -> TokenStream {
    let o = |x: Operand| operand(x, local);
    match *i {
        Instr::Add(a, b) => {
            let (a, b) = (o(a), o(b));
            quote!(#a + #b)
        }
        Instr::Sub(a, b) => {
            let (a, b) = (o(a), o(b));
            quote!(#a - #b)
        }
        Instr::Mul(a, b) => {
            let (a, b) = (o(a), o(b));
            quote!(#a * #b)
        }
        Instr::Div(a, b) => {
            let (a, b) = (o(a), o(b));
            quote!(#a / #b)
        }
        Instr::Neg(a) => {
            let a = o(a);
            quote!(-#a)
        }
        Instr::Atan2(y, x) => {
            let (y, x) = (o(y), o(x));
            quote!(f64::atan2(#y, #x))
        }
        Instr::Call(f, a) => {
            let a = o(a);
            match f {
                CasFunc::Sin => quote!(f64::sin(#a)),
                CasFunc::Cos => quote!(f64::cos(#a)),
                CasFunc::Tan => quote!(f64::tan(#a)),
                CasFunc::Sqrt => quote!(f64::sqrt(#a)),
                CasFunc::Exp => quote!(f64::exp(#a)),
                CasFunc::Ln => quote!(f64::ln(#a)),
                CasFunc::Abs => quote!(f64::abs(#a)),
            }
        }
    }
}

/// One pack of [`Program::pack_lanes`]: lanes `start..start + w` of one operation as one
/// `F64xW` operation, then the lanes as scalars (`t_k` for later scalar users, stores and
/// scratch; unused ones cost nothing). A vector operand is the pack whose lanes the operands
/// are, if it is computed in this function (`local_pack`), else the operand repeated (a
/// splat) or gathered from scalars.
fn vector_op(
    prog: &Program,
    start: usize,
    w: usize,
    local_pack: &dyn Fn(usize) -> bool,
    local: &Cx,
) -> TokenStream {
    let ty = format_ident!("F64x{}", w);
    let lane_operands = |pos: usize| -> Vec<Operand> {
        (start..start + w)
            .map(|k| match prog.instrs[k] {
                Instr::Add(a, b) | Instr::Sub(a, b) | Instr::Mul(a, b) => [a, b][pos],
                _ => unreachable!("packs are of binary operations"),
            })
            .collect()
    };
    let vector = |ops: Vec<Operand>| -> TokenStream {
        if let Operand::Tmp(m) = ops[0]
            && local_pack(m as usize)
            && ops
                .iter()
                .enumerate()
                .all(|(l, &o)| o == Operand::Tmp(m + l as u32))
        {
            let id = format_ident!("v{}", m);
            return quote!(#id);
        }
        if ops.iter().all(|&o| o == ops[0]) {
            let o = operand(ops[0], local);
            return quote!(#ty::splat(#o));
        }
        let lanes = ops.iter().map(|&o| operand(o, local));
        quote!(#ty::new([#(#lanes),*]))
    };
    let (a, b) = (vector(lane_operands(0)), vector(lane_operands(1)));
    let lanes = &prog.instrs[start..start + w];
    let e = if lanes.iter().all(|i| matches!(i, Instr::Mul(..))) {
        quote!(#a.mul(#b))
    } else if lanes.iter().all(|i| matches!(i, Instr::Add(..))) {
        quote!(#a.add(#b))
    } else if lanes.iter().all(|i| matches!(i, Instr::Sub(..))) {
        quote!(#a.sub(#b))
    } else {
        // Additions and subtractions: a + s·b, s = ±1 per lane (exact: only the sign flips).
        let signs = lanes.iter().map(|i| {
            lit(if matches!(i, Instr::Sub(..)) {
                -1.0
            } else {
                1.0
            })
        });
        quote!(#a.add(#b.mul(#ty::new([#(#signs),*]))))
    };
    let id = format_ident!("v{}", start);
    let names = (start..start + w).map(|k| format_ident!("t{}", k));
    quote! {
        let #id = #e;
        let [#(#names),*] = #id.to_array();
    }
}

/// The stores of a pack whose lanes are the mass entries M(r, c … c+w−1) (each lane one output,
/// r < c): one vector store of the mirrored entries M(c … c+w−1, r), adjacent in the
/// column-major buffer, and scalar stores of the others; with the outputs they write. `None`
/// for any other pack.
fn mass_pack_store(
    unit: &Unit,
    start: usize,
    n: usize,
    out_of_tmp: &std::collections::HashMap<u32, Vec<usize>>,
) -> Option<(TokenStream, Vec<usize>)> {
    let w = unit.lanes;
    let lanes: Vec<(usize, usize, usize)> = (start..start + w)
        .map(|t| match out_of_tmp.get(&(t as u32)).map(Vec::as_slice) {
            Some(&[oi]) => match unit.targets[oi] {
                Target::Mass { row, col } if row < col => Some((oi, row, col)),
                _ => None,
            },
            _ => None,
        })
        .collect::<Option<_>>()?;
    let (_, row, col) = lanes[0];
    if !lanes
        .iter()
        .enumerate()
        .all(|(l, &(_, r, c))| r == row && c == col + l)
    {
        return None;
    }
    let (a, b) = (ix(row * n + col), ix(row * n + col + w));
    let v = format_ident!("v{}", start);
    let upper = lanes.iter().enumerate().map(|(l, &(_, r, c))| {
        let id = format_ident!("t{}", start + l);
        let i = ix(c * n + r);
        quote!(mass[#i] = #id;)
    });
    let tokens = quote! {
        #v.store((&mut mass[#a..#b]).try_into().expect("a block of the mass buffer"));
        #(#upper)*
    };
    Some((tokens, lanes.iter().map(|l| l.0).collect()))
}

/// The batch of sin and cos calls `range` of `prog` (all `Call(Sin | Cos, _)`): one
/// `sin_cos_batch` call over their distinct arguments, then one `let` per instruction.
fn trig_batch(prog: &Program, range: std::ops::Range<usize>, local: &Cx) -> TokenStream {
    let mut args: Vec<Operand> = Vec::new();
    let mut lets = Vec::new();
    for k in range {
        let Instr::Call(f, a) = prog.instrs[k] else {
            unreachable!("the batch holds only sin and cos calls")
        };
        let i = args.iter().position(|&x| x == a).unwrap_or_else(|| {
            args.push(a);
            args.len() - 1
        });
        let id = format_ident!("t{}", k);
        let i = ix(i);
        lets.push(match f {
            CasFunc::Sin => quote!(let #id = trig_sin[#i];),
            _ => quote!(let #id = trig_cos[#i];),
        });
    }
    // Padded with zeros to a multiple of 8 arguments: LLVM then vectorizes the whole batch
    // with no scalar remainder (30 arguments: 67 ns, padded to 32: 34 ns, AVX-512).
    let padding = args.len().next_multiple_of(8) - args.len();
    let args = args
        .iter()
        .map(|&a| operand(a, local))
        .chain((0..padding).map(|_| lit(0.0)));
    quote! {
        let (trig_sin, trig_cos) = sin_cos_batch(&[#(#args),*]);
        #(#lets)*
    }
}

/// Statements writing one program output into its buffer.
fn store(target: Target, value: TokenStream, n: usize) -> TokenStream {
    match target {
        Target::Mass { row, col } => {
            let a = ix(col * n + row);
            if row == col {
                quote!(mass[#a] = #value;)
            } else {
                let b = ix(row * n + col);
                quote!({ let x = #value; mass[#a] = x; mass[#b] = x; })
            }
        }
        Target::Bias(i) => {
            let i = ix(i);
            quote!(bias[#i] = #value;)
        }
        Target::Gravity(i) => {
            let i = ix(i);
            quote!(gravity[#i] = #value;)
        }
        Target::Kinematics(i) => {
            let i = ix(i);
            quote!(kinematics[#i] = #value;)
        }
        Target::Jacobian(i) => {
            let i = ix(i);
            quote!(jacobians[#i] = #value;)
        }
        Target::Constraint(i) => {
            let i = ix(i);
            quote!(constraints[#i] = #value;)
        }
        Target::ConstraintJacobian(i) => {
            let i = ix(i);
            quote!(constraint_jacobian[#i] = #value;)
        }
    }
}

fn buffer_name(t: Target) -> &'static str {
    match t {
        Target::Mass { .. } => "mass",
        Target::Bias(_) => "bias",
        Target::Gravity(_) => "gravity",
        Target::Kinematics(_) => "kinematics",
        Target::Jacobian(_) => "jacobians",
        Target::Constraint(_) => "constraints",
        Target::ConstraintJacobian(_) => "constraint_jacobian",
    }
}

fn buffer_len(name: &str, n: usize, nb: usize, nc: usize) -> usize {
    match name {
        "mass" => n * n,
        "bias" | "gravity" => n,
        "kinematics" => 18 * nb,
        "jacobians" => 6 * nb * n,
        "constraints" => nc,
        _ => nc * n,
    }
}

/// Emits the functions of one unit: chunk functions and a driver `eval_<name>`.
#[allow(clippy::too_many_arguments)]
fn emit_unit(
    unit: &Unit,
    names: &Names,
    n: usize,
    n_params: usize,
    n_bodies: usize,
    n_constraints: usize,
    n_inputs: usize,
    max_instrs: usize,
    functions: &mut usize,
) -> TokenStream {
    let prog = &unit.program;
    let batch = unit.trig_batch.clone();
    let w = unit.lanes;
    let split = prog
        .split_keeping(max_instrs.max(1), &unit.together)
        .expect("max_instrs is at least 1");
    // Pack starts, and the other lanes (defined by their pack's statement).
    let pack_start: std::collections::HashSet<usize> = unit.packs.iter().copied().collect();
    let in_pack: std::collections::HashSet<usize> =
        unit.packs.iter().flat_map(|&s| s + 1..s + w).collect();
    let n_slots = split.n_slots.max(1);
    let mut fns = Vec::new();
    let mut calls = Vec::new();
    // Each program output is written by the chunk that defines it (if it is a
    // temporary of that chunk) or after the last chunk from the scratch array.
    let mut out_of_tmp: std::collections::HashMap<u32, Vec<usize>> = Default::default();
    let mut writes_in_chunk: Vec<Vec<(usize, u32)>> = vec![Vec::new(); split.chunks.len()];
    let mut final_writes = Vec::new();
    for (oi, out) in prog.outputs.iter().enumerate() {
        match out {
            Operand::Tmp(k) => {
                out_of_tmp.entry(*k).or_default().push(oi);
                writes_in_chunk[split.chunk_of(*k as usize)].push((oi, *k));
            }
            other => final_writes.push((oi, *other)),
        }
    }
    // sin and cos of the same argument in one chunk, outside the batch: one
    // `sin_cos` call at the first of the two instructions.
    let mut fused_first: std::collections::HashMap<usize, (usize, usize)> = Default::default();
    let mut fused_skip: std::collections::HashSet<usize> = Default::default();
    for (si, ci) in prog.sin_cos_pairs() {
        let (si, ci) = (si as usize, ci as usize);
        if split.chunk_of(si) == split.chunk_of(ci) && !batch.contains(&si) {
            fused_first.insert(si.min(ci), (si, ci));
            fused_skip.insert(si.max(ci));
        }
    }
    let (nq, np, nu) = (n, n_params, 3 * n_inputs);
    let loaded_later: std::collections::HashSet<u32> = split
        .chunks
        .iter()
        .flat_map(|c| c.loads.iter().map(|&(t, _)| t))
        .collect();
    for (ci, chunk) in split.chunks.iter().enumerate() {
        let fname = format_ident!("{}_{}", unit.name, ci);
        let tmp = |k: u32| {
            let id = format_ident!("t{}", k);
            quote!(#id)
        };
        let local = Cx { names, tmp: &tmp };
        let loads = chunk.loads.iter().map(|&(t, s)| {
            let id = format_ident!("t{}", t);
            let s = ix(s as usize);
            quote!(let #id = unsafe { s[#s].assume_init() };)
        });
        let body = chunk
            .instrs
            .clone()
            .filter(|k| {
                !fused_skip.contains(k)
                    && (!batch.contains(k) || *k == batch.start)
                    && !in_pack.contains(k)
            })
            .map(|k| {
                if k == batch.start && !batch.is_empty() {
                    return trig_batch(prog, batch.clone(), &local);
                }
                if pack_start.contains(&k) {
                    let local_pack = |m: usize| pack_start.contains(&m) && split.chunk_of(m) == ci;
                    return vector_op(prog, k, w, &local_pack, &local);
                }
                if let Some(&(si, cj)) = fused_first.get(&k) {
                    let (sid, cid) = (format_ident!("t{}", si), format_ident!("t{}", cj));
                    let Instr::Call(_, a) = prog.instrs[k] else {
                        unreachable!("sin/cos pair")
                    };
                    let a = operand(a, &local);
                    return quote!(let (#sid, #cid) = f64::sin_cos(#a););
                }
                let id = format_ident!("t{}", k);
                let e = instr(&prog.instrs[k], &local);
                quote!(let #id = #e;)
            });
        // Outputs are written to their buffers by the chunk that defines them:
        // only temporaries a later chunk loads go through the scratch array.
        let stores = chunk
            .stores
            .iter()
            .filter(|(t, _)| loaded_later.contains(t))
            .map(|&(t, s)| {
                let id = format_ident!("t{}", t);
                let s = ix(s as usize);
                quote!(s[#s] = std::mem::MaybeUninit::new(#id);)
            });
        let mut buffers = std::collections::BTreeSet::new();
        // Packs of mass entries M(r, c … c+w−1): one vector store of the mirrored entries
        // M(c … c+w−1, r), adjacent in the column-major buffer, and scalar stores of the rest.
        let mut vector_written: std::collections::HashSet<usize> = Default::default();
        let mut vector_stores = Vec::new();
        for &start in unit.packs.iter().filter(|&&s| split.chunk_of(s) == ci) {
            if let Some((tokens, outputs)) = mass_pack_store(unit, start, n, &out_of_tmp) {
                vector_stores.push(tokens);
                vector_written.extend(outputs);
                buffers.insert("mass");
            }
        }
        let writes: Vec<TokenStream> = writes_in_chunk[ci]
            .iter()
            .filter(|(oi, _)| !vector_written.contains(oi))
            .map(|&(oi, k)| {
                let id = format_ident!("t{}", k);
                buffers.insert(buffer_name(unit.targets[oi]));
                store(unit.targets[oi], quote!(#id), n)
            })
            .collect();
        // Fixed-size views: one length check per function, then indexing by
        // constants needs no bounds checks.
        let views = buffers.iter().map(|b| {
            let id = format_ident!("{}", b);
            let len = ix(buffer_len(b, n, n_bodies, n_constraints));
            quote!(let #id: &mut [f64; #len] = (&mut *o.#id).try_into().expect("host buffer sized by the ABI");)
        });
        // Fixed-size views of the inputs the chunk reads (the others are unused).
        let mut read = [false; 4];
        for k in chunk.instrs.clone() {
            for o in instr_operands(&prog.instrs[k]) {
                if let Operand::Sym(sym) = o {
                    match sym.kind {
                        SymbolKind::Coordinate => read[0] = true,
                        SymbolKind::Velocity => read[1] = true,
                        SymbolKind::Parameter => read[2] = true,
                        SymbolKind::Input => read[3] = true,
                        SymbolKind::Time => {}
                    }
                }
            }
        }
        let input_views = [("q", nq), ("v", nq), ("p", np), ("u", nu)]
            .into_iter()
            .zip(read)
            .filter(|&(_, r)| r)
            .map(|((name, len), _)| {
                let id = format_ident!("{}", name);
                let len = ix(len);
                quote!(let #id: &[f64; #len] = #id.try_into().expect("host buffer sized by the ABI");)
            });
        let scratch = (!chunk.loads.is_empty() || !chunk.stores.is_empty()).then(|| {
            let n_slots = ix(n_slots);
            quote!(let s: &mut [std::mem::MaybeUninit<f64>; #n_slots] = s.try_into().expect("scratch sized by the generator");)
        });
        fns.push(quote! {
            #[inline(never)]
            #[allow(unused_variables)]
            fn #fname(t: f64, q: &[f64], v: &[f64], p: &[f64], u: &[f64], s: &mut [std::mem::MaybeUninit<f64>], o: &mut Out) {
                #(#input_views)*
                #scratch
                #(#views)*
                #(#loads)*
                #(#body)*
                #(#stores)*
                #(#vector_stores)*
                #(#writes)*
            }
        });
        calls.push(quote!(#fname(t, q, v, p, u, &mut s, o);));
        *functions += 1;
    }
    // Outputs that are inputs or constants (a parameter on the mass diagonal, 0 and 1 in
    // the rotation of a planar body), one block per buffer. Constant zeros are structurally
    // zero entries: the host zeroes its buffers once, and nothing else writes them.
    let slot = |k: u32| {
        let slot = ix(split.slot_of_tmp[k as usize].expect("output temporary has a slot") as usize);
        quote!(unsafe { s[#slot].assume_init() })
    };
    let from_scratch = Cx { names, tmp: &slot };
    let mut finals_by_buffer: Vec<(&'static str, Vec<TokenStream>)> = Vec::new();
    for &(oi, op) in &final_writes {
        if matches!(op, Operand::Const(c) if c.to_bits() == 0) {
            continue;
        }
        let b = buffer_name(unit.targets[oi]);
        let st = store(unit.targets[oi], operand(op, &from_scratch), n);
        match finals_by_buffer.iter_mut().find(|(name, _)| *name == b) {
            Some((_, stores)) => stores.push(st),
            None => finals_by_buffer.push((b, vec![st])),
        }
    }
    let finals = finals_by_buffer.iter().map(|(b, stores)| {
        let b = format_ident!("{}", b);
        quote!({ let #b = &mut *o.#b; #(#stores)* })
    });
    let n_slots = ix(n_slots);
    let driver = format_ident!("eval_{}", unit.name);
    *functions += 1;
    quote! {
        #(#fns)*
        #[allow(unused_variables, unused_mut)]
        fn #driver(t: f64, q: &[f64], v: &[f64], p: &[f64], u: &[f64], o: &mut Out) {
            // Scratch slots are written by the chunk that defines a value before any
            // later chunk reads them (`Program::split`), so they need no zeroing.
            let mut s = [std::mem::MaybeUninit::<f64>::uninit(); #n_slots];
            #(#calls)*
            #(#finals)*
        }
    }
}

fn c_string_list(names: &[String]) -> Literal {
    let mut bytes = Vec::new();
    for n in names {
        bytes.extend_from_slice(n.as_bytes());
        bytes.push(0);
    }
    bytes.push(0);
    Literal::byte_string(&bytes)
}

/// Generates the whole plugin source (formatted).
pub fn emit(
    d: &Derived,
    header: &PluginHeader,
    max_instrs: usize,
    lanes: usize,
) -> (String, EmitStats) {
    let n = d.dof;
    let nb = d.bodies;
    let nc = d.constraints.len();
    let np = header.parameter_names.len();
    let start = std::time::Instant::now();
    let units = units(d, lanes);
    let mut stats = EmitStats {
        cse_time: start.elapsed(),
        ..EmitStats::default()
    };
    let start = std::time::Instant::now();
    let mut all_roots: Vec<railmbs_cas::ExprId> = Vec::new();
    all_roots.extend(&d.mass);
    all_roots.extend(&d.bias);
    all_roots.extend(&d.gravity);
    all_roots.extend(&d.kinematics);
    all_roots.extend(&d.jacobians);
    all_roots.extend(&d.constraints);
    all_roots.extend(&d.constraint_jacobian);
    stats.ops_tree = d.ctx.tree_op_counts(&all_roots);
    let mut cse = OpCounts::default();
    for u in &units {
        if u.name != "all" {
            let c = u.program.op_counts();
            cse = OpCounts {
                adds: cse.adds + c.adds,
                muls: cse.muls + c.muls,
                divs: cse.divs + c.divs,
                calls: cse.calls + c.calls,
            };
        }
        if u.name == "dyn" {
            stats.dyn_instructions = u.program.instrs.len();
        }
    }
    stats.ops_cse = cse;
    let names = Names::new(header);
    let index_names = names.definitions();
    let mut functions = 0;
    let bodies: Vec<TokenStream> = units
        .iter()
        .map(|u| {
            emit_unit(
                u,
                &names,
                n,
                np,
                nb,
                nc,
                d.inputs,
                max_instrs,
                &mut functions,
            )
        })
        .collect();
    stats.functions = functions;
    let has_con = nc > 0;
    let con_call = if has_con {
        quote!(if parts & PART_CONSTRAINTS != 0 {
            eval_con(t, q, v, p, u, &mut o);
        })
    } else {
        quote!()
    };
    let hash = Literal::byte_string(format!("{}\0", header.model_hash).as_bytes());
    let name = Literal::byte_string(format!("{}\0", header.model_name).as_bytes());
    let coords = c_string_list(&header.coordinate_names);
    let params = c_string_list(&header.parameter_names);
    let ni = d.inputs;
    let nu_len = 3 * ni;
    let fixed_idx = header
        .fixed
        .iter()
        .map(|&(i, _)| Literal::u32_unsuffixed(i as u32));
    let fixed_val: Vec<TokenStream> = header.fixed.iter().map(|&(_, x)| lit(x)).collect();
    let count = |k: usize| Literal::u32_unsuffixed(u32::try_from(k).expect("a count below 2^32"));
    let (c_n, c_nb, c_nc, c_np, c_ni, c_fixed) = (
        count(n),
        count(nb),
        count(nc),
        count(np),
        count(ni),
        count(header.fixed.len()),
    );
    let nfixed = ix(header.fixed.len());
    let (mass_len, bias_len, kin_len, jac_len, cjac_len) =
        (ix(n * n), ix(n), ix(18 * nb), ix(6 * nb * n), ix(nc * n));
    // What is known now is decided now: the null checks and slices of the inputs and
    // buffers this model has.
    let mut refused = vec![
        quote!(need_dyn && (ob.mass.is_null() || ob.bias.is_null() || ob.gravity.is_null())),
        quote!(need_kin && (ob.kinematics.is_null() || ob.jacobians.is_null())),
    ];
    if has_con {
        refused.push(quote!(
            parts & PART_CONSTRAINTS != 0
                && (ob.constraints.is_null() || ob.constraint_jacobian.is_null())
        ));
    }
    let input = |name: &str, len: usize| {
        let id = format_ident!("{}", name);
        if len == 0 {
            (None, quote!(let #id: &[f64] = &[];))
        } else {
            let len = ix(len);
            (
                Some(quote!(i.#id.is_null())),
                quote!(let #id = std::slice::from_raw_parts(i.#id, #len);),
            )
        }
    };
    let mut inputs = Vec::new();
    for (name, len) in [("q", n), ("v", n), ("p", np), ("u", nu_len)] {
        let (check, slice) = input(name, len);
        refused.extend(check);
        inputs.push(slice);
    }
    let constraint_buffers = if has_con {
        let con_len = ix(nc);
        quote! {
            constraints: sl_mut(ob.constraints, #con_len),
            constraint_jacobian: sl_mut(ob.constraint_jacobian, #cjac_len),
        }
    } else {
        quote! {
            constraints: &mut [],
            constraint_jacobian: &mut [],
        }
    };
    let head = quote! {
        //! Generated by railmbs `umgen`: the equations of motion of one model as
        //! straight-line code. Do not edit; regenerate from the model file.
        #![allow(clippy::all, dead_code, non_snake_case, unused_parens)]
    };
    let tokens = quote! {
        use std::os::raw::c_char;

        struct Out<'a> {
            mass: &'a mut [f64],
            bias: &'a mut [f64],
            gravity: &'a mut [f64],
            kinematics: &'a mut [f64],
            jacobians: &'a mut [f64],
            constraints: &'a mut [f64],
            constraint_jacobian: &'a mut [f64],
        }

        static MODEL_HASH: &[u8] = #hash;
        static MODEL_NAME: &[u8] = #name;
        static COORDINATE_NAMES: &[u8] = #coords;
        static PARAMETER_NAMES: &[u8] = #params;
        static FIXED_INDICES: [u32; #nfixed] = [#(#fixed_idx),*];
        static FIXED_VALUES: [f64; #nfixed] = [#(#fixed_val),*];

        #index_names

        #(#bodies)*

        /// Target features compiled in (`COMPILED_TARGET_FEATURES`). Runs no vector
        /// instruction, so the loader may call it before knowing whether this CPU can run
        /// the rest.
        #[no_mangle]
        pub extern "C" fn railmbs_target_features() -> *const c_char {
            COMPILED_TARGET_FEATURES.as_ptr() as *const c_char
        }
        const _: TargetFeaturesFn = railmbs_target_features;

        /// Fills `info`. Safety: `info` points to a writable `PluginInfo`.
        #[no_mangle]
        pub unsafe extern "C" fn railmbs_plugin_info(info: *mut PluginInfo) {
            if info.is_null() {
                return;
            }
            *info = PluginInfo {
                abi_version: ABI_VERSION,
                dof: #c_n,
                bodies: #c_nb,
                constraints: #c_nc,
                parameters: #c_np,
                inputs: #c_ni,
                model_hash: MODEL_HASH.as_ptr() as *const c_char,
                model_name: MODEL_NAME.as_ptr() as *const c_char,
                coordinate_names: COORDINATE_NAMES.as_ptr() as *const c_char,
                parameter_names: PARAMETER_NAMES.as_ptr() as *const c_char,
                fixed_count: #c_fixed,
                fixed_indices: FIXED_INDICES.as_ptr(),
                fixed_values: FIXED_VALUES.as_ptr(),
            };
        }
        const _: InfoFn = railmbs_plugin_info;

        /// Evaluates the requested parts. Returns 0, or 1 for a null pointer.
        /// Safety: every pointer refers to a host buffer of the size stated in
        /// `railmbs_plugin_info` (M n×n, k and Q_g n, kinematics 18·nb, Γ 6·nb×n,
        /// g nc, G nc×n); unused parts may be null.
        #[no_mangle]
        pub unsafe extern "C" fn railmbs_evaluate(inputs: *const Inputs, parts: u32, outputs: *const Outputs) -> i32 {
            if inputs.is_null() || outputs.is_null() {
                return 1;
            }
            let i = &*inputs;
            let ob = &*outputs;
            unsafe fn sl_mut<'a>(p: *mut f64, n: usize) -> &'a mut [f64] {
                if n == 0 || p.is_null() { &mut [] } else { std::slice::from_raw_parts_mut(p, n) }
            }
            let need_dyn = parts & PART_DYNAMICS != 0;
            let need_kin = parts & PART_KINEMATICS != 0;
            if #((#refused))||* {
                return 1;
            }
            let t = i.t;
            #(#inputs)*
            let mut o = Out {
                mass: sl_mut(if need_dyn { ob.mass } else { std::ptr::null_mut() }, #mass_len),
                bias: sl_mut(if need_dyn { ob.bias } else { std::ptr::null_mut() }, #bias_len),
                gravity: sl_mut(if need_dyn { ob.gravity } else { std::ptr::null_mut() }, #bias_len),
                kinematics: sl_mut(if need_kin { ob.kinematics } else { std::ptr::null_mut() }, #kin_len),
                jacobians: sl_mut(if need_kin { ob.jacobians } else { std::ptr::null_mut() }, #jac_len),
                #constraint_buffers
            };
            if need_dyn && need_kin {
                eval_all(t, q, v, p, u, &mut o);
            } else if need_dyn {
                eval_dyn(t, q, v, p, u, &mut o);
            } else if need_kin {
                eval_kin(t, q, v, p, u, &mut o);
            }
            #con_call
            0
        }
        const _: EvaluateFn = railmbs_evaluate;
    };
    let unparse = |tokens: TokenStream| {
        let file: syn::File = syn::parse2(tokens).expect("generated code parses");
        prettyplease::unparse(&file)
    };
    // The header, then the interface (verbatim), then the code.
    let mut text = unparse(head);
    text.push('\n');
    text.push_str(railmbs_plugin_abi::SOURCE);
    text.push('\n');
    text.push_str(&unparse(tokens));
    text.push('\n');
    text.push_str(crate::sin_cos::SOURCE);
    text.push('\n');
    text.push_str(crate::lanes::SOURCE);
    stats.source_lines = text.lines().count();
    stats.format_time = start.elapsed();
    (text, stats)
}
