//! Compile time versus run time of a generated-like plugin source.
//!
//! Generates ~20 000 lines of straight-line f64 arithmetic (like CSE-optimized equations of
//! motion: products, sums, some sin/cos, values passed between parts through a host-owned
//! work array), either split into functions of ~500 lines or as one huge function with the
//! same statements, and compiles it with [`build_plugin`] into a fresh temporary cache for
//! each combination of opt-level and codegen-units. Then it loads each library and times the
//! exported `eval`, and checks that every build computes bit-identical results.
//!
//! ```text
//! cargo run --release -p railmbs-build-support --example compile_time -- \
//!     [--lines 20000] [--chunk 500] [--opt 1,2,3] [--cgu 1,2,16] [--layout split,huge] \
//!     [--write DIR]   # also write the sources to DIR/split.rs, DIR/huge.rs
//! ```

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use railmbs_build_support::{BuildOptions, build_plugin, write_source};

/// Number of inputs `x` (generalized coordinates, velocities, parameters).
const NX: usize = 64;
/// Values each part hands on to later parts through the work array.
const OUT_PER_PART: usize = 16;

// Every statement maps values in [-1, 1] into [-1, 1] (inputs are in [0.1, 0.73]), so the
// results stay finite and comparable bit for bit across builds.

/// Small deterministic generator (64-bit LCG, Knuth's MMIX constants).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self, n: usize) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 33) as usize) % n
    }
}

/// Plugin source: `eval(x, nx, w, nw)`; `split` puts each part in its own function.
fn generate(lines: usize, chunk: usize, split: bool) -> (String, usize) {
    let parts = lines.div_ceil(chunk);
    let nw = parts * OUT_PER_PART;
    let mut rng = Lcg(0x5eed);
    let mut bodies = Vec::with_capacity(parts);
    for p in 0..parts {
        let mut b = String::new();
        let n = chunk.min(lines - p * chunk);
        for i in 0..n {
            let operand = |rng: &mut Lcg| -> String {
                match rng.next(10) {
                    0..=1 => format!("x[{}]", rng.next(NX)),
                    2 if p > 0 => format!("w[{}]", rng.next(p * OUT_PER_PART)),
                    _ if i > 0 => format!("t{}", i - 1 - rng.next(i.min(40))),
                    _ => format!("x[{}]", rng.next(NX)),
                }
            };
            let (a, c, d) = (operand(&mut rng), operand(&mut rng), operand(&mut rng));
            let k = (rng.next(1000) as f64 + 1.0) * 1e-3;
            let e = match rng.next(12) {
                0 => format!("({a} * {k:?} + {c}).sin()"),
                1 => format!("({a} - {c} * {k:?}).cos()"),
                2..=4 => format!("({a} * {c} + {d}) * 0.5"),
                5..=7 => format!("({a} * {k:?} - {c} * {d}) * 0.5"),
                8 | 9 => format!("({a} + {c} * {k:?}) * 0.5"),
                _ => format!("({a} - {c}) * {d} * 0.5"),
            };
            writeln!(b, "    let t{i}: f64 = {e};").unwrap();
        }
        for j in 0..OUT_PER_PART {
            writeln!(b, "    w[{}] = t{};", p * OUT_PER_PART + j, n - 1 - j % n).unwrap();
        }
        bodies.push(b);
    }
    let mut s = String::from("// generated-like benchmark source\n");
    if split {
        for (p, b) in bodies.iter().enumerate() {
            writeln!(
                s,
                "#[inline(never)]\nfn part{p}(x: &[f64; {NX}], w: &mut [f64; {nw}]) {{\n{b}}}"
            )
            .unwrap();
        }
    }
    writeln!(
        s,
        "/// # Safety\n/// x: {NX} values, w: {nw} values.\n#[no_mangle]\n\
         pub unsafe extern \"C\" fn eval(x: *const f64, nx: usize, w: *mut f64, nw: usize) -> i32 {{\n\
         if x.is_null() || w.is_null() || nx != {NX} || nw != {nw} {{ return 1; }}\n\
         let x = unsafe {{ &*(x as *const [f64; {NX}]) }};\n\
         let w = unsafe {{ &mut *(w as *mut [f64; {nw}]) }};"
    )
    .unwrap();
    for (p, b) in bodies.iter().enumerate() {
        if split {
            writeln!(s, "    part{p}(x, w);").unwrap();
        } else {
            // Same statements, one scope per part so the names stay unique.
            writeln!(s, "    {{\n{b}    }}").unwrap();
        }
    }
    s.push_str("    0\n}\n");
    (s, nw)
}

fn list(arg: &str) -> Vec<String> {
    arg.split(',').map(str::to_owned).collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut lines = 20_000usize;
    let mut chunk = 500usize;
    let mut opts = vec!["1".to_owned(), "2".into(), "3".into()];
    let mut cgus = vec!["1".to_owned(), "2".into(), "16".into()];
    let mut layouts = vec!["split".to_owned(), "huge".into()];
    let mut write = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let v = args.next().ok_or(format!("{a} needs a value"))?;
        match a.as_str() {
            "--lines" => lines = v.parse()?,
            "--chunk" => chunk = v.parse()?,
            "--opt" => opts = list(&v),
            "--cgu" => cgus = list(&v),
            "--layout" => layouts = list(&v),
            "--write" => write = Some(std::path::PathBuf::from(v)),
            _ => return Err(format!("unknown argument {a}").into()),
        }
    }
    if lines == 0 || chunk == 0 {
        return Err("--lines and --chunk must be positive".into());
    }
    println!("{lines} lines, parts of {chunk} lines");
    println!(
        "| layout | opt-level | codegen-units | compile wall [s] | compile CPU [s] | eval [µs] | size [KiB] |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut reference: Option<Vec<f64>> = None;
    for layout in &layouts {
        let split = match layout.as_str() {
            "split" => true,
            "huge" => false,
            _ => return Err(format!("unknown layout {layout}").into()),
        };
        let (src, nw) = generate(lines, chunk, split);
        if let Some(dir) = &write {
            let p = write_source(dir, &format!("{layout}.rs"), &src)?;
            println!("wrote {}", p.display());
        }
        for opt in &opts {
            for cgu in &cgus {
                let cache = tempfile::tempdir()?;
                let mut o = BuildOptions::new(0).with_cache_dir(cache.path());
                o.opt_level = opt.parse()?;
                o.codegen_units = cgu.parse()?;
                let cpu0 = children_cpu_seconds();
                let out = build_plugin(&src, &o)?;
                let cpu = children_cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
                let size = std::fs::metadata(&out.path)?.len() as f64 / 1024.0;
                let (per_call, w) = time_eval(&out.path, nw)?;
                if let Some(r) = &reference {
                    let same = r.iter().zip(&w).all(|(a, b)| a.to_bits() == b.to_bits());
                    if !same {
                        return Err(format!("{layout} O{opt} cgu{cgu}: results differ").into());
                    }
                } else {
                    if !w.iter().all(|v| v.is_finite()) {
                        return Err("generated code produced non-finite values".into());
                    }
                    reference = Some(w);
                }
                println!(
                    "| {layout} | {opt} | {cgu} | {:.2} | {} | {:.1} | {size:.0} |",
                    out.compile_time.unwrap_or_default().as_secs_f64(),
                    cpu.map_or("n/a".to_owned(), |c| format!("{c:.2}")),
                    per_call.as_secs_f64() * 1e6
                );
            }
        }
    }
    Ok(())
}

/// User + system CPU time of all waited-for child processes (rustc and the linker), from
/// `/proc/self/stat` fields 16 and 17 (`cutime`, `cstime`, in clock ticks of 1/100 s, the
/// Linux USER_HZ); `None` where that file does not exist. Unlike wall time, it does not
/// depend on how busy the machine is, but it does not show the gain from parallel codegen.
fn children_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may contain spaces: split after it.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3, so fields 16 and 17 are at indices 13 and 14.
    let ticks: f64 = f.get(13)?.parse::<f64>().ok()? + f.get(14)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Best-of-60 time per `eval` call, and the work array after one call.
fn time_eval(
    path: &std::path::Path,
    nw: usize,
) -> Result<(Duration, Vec<f64>), Box<dyn std::error::Error>> {
    type Eval = unsafe extern "C" fn(*const f64, usize, *mut f64, usize) -> i32;
    // SAFETY: the library was just built from `generate`'s source, which exports `eval`
    // with this signature; its initialisers are Rust std's only.
    let lib = unsafe { libloading::Library::new(path)? };
    let eval = unsafe { *lib.get::<Eval>(b"eval")? };
    let x: Vec<f64> = (0..NX).map(|i| 0.1 + 0.01 * i as f64).collect();
    let mut w = vec![0.0; nw];
    // SAFETY: x and w have the lengths eval checks.
    let rc = unsafe { eval(x.as_ptr(), NX, w.as_mut_ptr(), nw) };
    if rc != 0 {
        return Err("eval rejected its arguments".into());
    }
    let result = w.clone();
    // Many short batches, best one: robust against other processes on a busy machine.
    let reps = 50;
    let mut best = Duration::MAX;
    for _ in 0..60 {
        let t = Instant::now();
        for _ in 0..reps {
            // SAFETY: as above.
            unsafe { eval(std::hint::black_box(x.as_ptr()), NX, w.as_mut_ptr(), nw) };
        }
        best = best.min(t.elapsed() / reps);
    }
    // Rust cdylibs are never unloaded (docs/design.md).
    std::mem::forget(lib);
    Ok((best, result))
}
