//! Symbolic mass matrix M and inertia-force vector k of a planar N-link chain (N = 10, 30),
//! derived by the direct method (not the composite-body method codegen uses), then CSE.
//!
//! Link i (0-based) hangs from the end of link i−1 by a revolute joint with relative angle
//! q[i]; its absolute angle is φᵢ = q₀ + … + qᵢ. Parameters: length lᵢ = p[3i], mass
//! mᵢ = p[3i+1], central inertia Iᵢ = p[3i+2]. Centre of link i:
//! rᵢ = Σ_{j<i} lⱼ·(cos φⱼ, sin φⱼ) + ½lᵢ·(cos φᵢ, sin φᵢ).
//! Jacobians Jᵢ = ∂rᵢ/∂q by `diff`, Jωᵢ,ₖ = 1 for k ≤ i.
//! M = Σᵢ mᵢ·JᵢᵀJᵢ + Iᵢ·JωᵢᵀJωᵢ (upper triangle), and
//! k = Σᵢ mᵢ·Jᵢᵀ·(J̇ᵢ v) with J̇ᵢ v = Σₖ ∂(Jᵢ v)/∂qₖ · vₖ (Coriolis and centrifugal terms).
//!
//! Run: `cargo bench -p railmbs-cas --bench chain`. Prints node and operation counts once.

#![allow(clippy::needless_range_loop)] // index loops read like the matrix formulas

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_cas::{Context, ExprId, Program, Symbol};

struct Derived {
    ctx: Context,
    outputs: Vec<ExprId>,
}

fn derive(n: usize) -> Derived {
    let mut c = Context::new();
    let q: Vec<ExprId> = (0..n as u32).map(|i| c.q(i)).collect();
    let v: Vec<ExprId> = (0..n as u32).map(|i| c.v(i)).collect();
    let l: Vec<ExprId> = (0..n as u32).map(|i| c.p(3 * i)).collect();
    let m: Vec<ExprId> = (0..n as u32).map(|i| c.p(3 * i + 1)).collect();
    let inertia: Vec<ExprId> = (0..n as u32).map(|i| c.p(3 * i + 2)).collect();
    let qs: Vec<Symbol> = (0..n as u32).map(Symbol::q).collect();

    // absolute angles and their sines/cosines
    let phi: Vec<ExprId> = (0..n).map(|i| c.add_many(&q[..=i])).collect();
    let cs: Vec<(ExprId, ExprId)> = phi.iter().map(|&f| (c.cos(f), c.sin(f))).collect();
    // centres of mass
    let mut centres = Vec::with_capacity(n);
    for i in 0..n {
        let mut xs = Vec::with_capacity(i + 1);
        let mut ys = Vec::with_capacity(i + 1);
        for j in 0..=i {
            let a = c.mul(l[j], cs[j].0);
            let b = c.mul(l[j], cs[j].1);
            let w = if j == i { 0.5 } else { 1.0 };
            xs.push((a, w));
            ys.push((b, w));
        }
        centres.push((c.sum(0.0, &xs), c.sum(0.0, &ys)));
    }
    // translational Jacobians J[i] = [(∂x/∂q_k, ∂y/∂q_k)]_k
    let jac: Vec<Vec<(ExprId, ExprId)>> = centres
        .iter()
        .map(|&(x, y)| qs.iter().map(|&s| (c.diff(x, s), c.diff(y, s))).collect())
        .collect();

    let mut outputs = Vec::new();
    // mass matrix, upper triangle row by row
    for a in 0..n {
        for b in a..n {
            let mut terms = Vec::new();
            for i in a.max(b)..n {
                let (xa, ya) = jac[i][a];
                let (xb, yb) = jac[i][b];
                let p1 = c.mul(xa, xb);
                let p2 = c.mul(ya, yb);
                let dot = c.add(p1, p2);
                terms.push((c.mul(m[i], dot), 1.0));
                // Jω entries are 1 for a, b ≤ i
                terms.push((inertia[i], 1.0));
            }
            outputs.push(c.sum(0.0, &terms));
        }
    }
    // velocity-dependent inertia forces
    let mut bias = Vec::with_capacity(n);
    for row in &jac {
        let vx: Vec<(ExprId, f64)> = Vec::new();
        let (mut vxs, mut vys) = (vx.clone(), vx);
        for (k, &(jx, jy)) in row.iter().enumerate() {
            vxs.push((c.mul(jx, v[k]), 1.0));
            vys.push((c.mul(jy, v[k]), 1.0));
        }
        let (vxe, vye) = (c.sum(0.0, &vxs), c.sum(0.0, &vys));
        let mut axs = Vec::new();
        let mut ays = Vec::new();
        for (k, &s) in qs.iter().enumerate() {
            let dx = c.diff(vxe, s);
            let dy = c.diff(vye, s);
            axs.push((c.mul(dx, v[k]), 1.0));
            ays.push((c.mul(dy, v[k]), 1.0));
        }
        bias.push((c.sum(0.0, &axs), c.sum(0.0, &ays)));
    }
    for a in 0..n {
        let mut terms = Vec::new();
        for i in a..n {
            let (jx, jy) = jac[i][a];
            let p1 = c.mul(jx, bias[i].0);
            let p2 = c.mul(jy, bias[i].1);
            let dot = c.add(p1, p2);
            terms.push((c.mul(m[i], dot), 1.0));
        }
        outputs.push(c.sum(0.0, &terms));
    }
    Derived { ctx: c, outputs }
}

/// CPU time of the current thread in ns (Linux `/proc/thread-self/schedstat`), if available:
/// less sensitive than wall time to other processes on a loaded machine.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn report(n: usize) {
    let d = derive(n);
    let prog = Program::compile(&d.ctx, &d.outputs);
    let tree = d.ctx.tree_op_counts(&d.outputs);
    let after = prog.op_counts();
    println!(
        "chain N={n}: {} outputs, {} DAG nodes",
        d.outputs.len(),
        d.ctx.len()
    );
    println!("  operations before CSE (tree): {tree}");
    println!(
        "  operations after CSE:         {after} in {} instructions",
        prog.instrs.len()
    );
    // Mean over repeated runs of wall time and of this thread's CPU time; each phase is timed
    // over all its runs at once (the CPU clock advances in scheduler ticks).
    let runs = 20;
    let time = |f: &mut dyn FnMut()| {
        let (t0, c0) = (Instant::now(), thread_cpu_ns());
        for _ in 0..runs {
            f();
        }
        let wall = t0.elapsed().as_secs_f64() * 1e3 / runs as f64;
        let cpu = match (c0, thread_cpu_ns()) {
            (Some(a), Some(b)) => format!("{:.2}", (b - a) as f64 * 1e-6 / runs as f64),
            _ => "n/a".to_string(),
        };
        (wall, cpu)
    };
    let (wd, cd) = time(&mut || {
        black_box(derive(n).outputs.len());
    });
    let (wc, cc) = time(&mut || {
        black_box(Program::compile(&d.ctx, &d.outputs).instrs.len());
    });
    let t = Instant::now();
    let sp = prog.split(2000).expect("chunk size is positive");
    println!(
        "  split into chunks of <= 2000 instructions: {} chunks, {} scratch slots, {:.2} ms",
        sp.chunks.len(),
        sp.n_slots,
        t.elapsed().as_secs_f64() * 1e3
    );
    println!(
        "  mean of {runs}: derive M,k {wd:.2} ms wall / {cd} ms CPU; CSE {wc:.2} ms wall / {cc} ms CPU"
    );
}

fn bench(cr: &mut Criterion) {
    for n in [10usize, 30] {
        report(n);
        cr.bench_function(&format!("chain{n}/derive_M_k"), |b| {
            b.iter(|| black_box(derive(black_box(n)).outputs.len()))
        });
        cr.bench_function(&format!("chain{n}/derive_M_k_and_cse"), |b| {
            b.iter(|| {
                let d = derive(black_box(n));
                black_box(Program::compile(&d.ctx, &d.outputs).instrs.len())
            })
        });
        let d = derive(n);
        cr.bench_function(&format!("chain{n}/cse_only"), |b| {
            b.iter(|| black_box(Program::compile(&d.ctx, &d.outputs).instrs.len()))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
