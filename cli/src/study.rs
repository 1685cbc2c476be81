//! `umsim study STUDY.ron [--jobs N] [-o DIR]`: runs a parameter study (the
//! format is documented in the `railmbs-study` crate) on a local pool,
//! appending each case's row to `DIR/results.csv` as it finishes and
//! resuming where an earlier run stopped; `--list` lists the cases, `--case
//! INDEX` runs one case into `DIR/cases/<id>.csv` (for job arrays) and
//! `--collect` gathers those files into the table.

use railmbs_study::{
    CaseOptions, CaseResult, PoolOptions, ResultStore, Study, StudyEngine, StudyError,
};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The environment variable `--case` without an index reads (Slurm job arrays).
pub const TASK_ID_VARIABLE: &str = "SLURM_ARRAY_TASK_ID";

/// Arguments of `umsim study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (RON; see `cargo doc -p railmbs-study`).
    pub study: PathBuf,
    /// Threads of the local pool (default: one per core).
    #[arg(long, short = 'j', default_value_t = 0)]
    pub jobs: usize,
    /// Output folder: results.csv, cases/ (per-case files), series/ (time
    /// series). Default: out/NAME, NAME the study file name without .ron.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// List the cases (index, id, inputs) and exit.
    #[arg(long, conflicts_with_all = ["case", "collect"])]
    pub list: bool,
    /// Run only the case INDEX (0-based) and write DIR/cases/ID.csv (ID the case id); without
    /// INDEX, the index is $SLURM_ARRAY_TASK_ID (a Slurm job array
    /// `--array=0-N`). A case whose file exists is not run again.
    #[arg(long, value_name = "INDEX", num_args = 0..=1, conflicts_with = "collect")]
    pub case: Option<Option<usize>>,
    /// Gather the per-case files of DIR/cases/ into DIR/results.csv.
    #[arg(long)]
    pub collect: bool,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `umsim study`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let study = Study::load(&args.study)?;
    let dir = args.output.clone().unwrap_or_else(|| {
        let stem = args.study.file_stem().unwrap_or_default();
        Path::new("out").join(stem)
    });
    if args.list {
        print!("{}", case_list(&study));
        return Ok(());
    }
    let results = dir.join("results.csv");
    if args.collect {
        let mut store = ResultStore::open(&results, study.result_header())?;
        let added = railmbs_study::collect_case_files(&study, &dir, &mut store)?;
        let missing: Vec<String> = study
            .cases()
            .iter()
            .filter(|c| !store.finished().contains(&c.id))
            .map(|c| c.index.to_string())
            .collect();
        println!(
            "collected {added} case file(s) into {}; {} of {} cases in the table",
            results.display(),
            study.cases().len() - missing.len(),
            study.cases().len()
        );
        if !missing.is_empty() {
            println!("missing cases (index): {}", missing.join(" "));
        }
        return Ok(());
    }
    if let Some(index) = args.case {
        return run_one(args, &study, &dir, index);
    }
    run_all(args, &study, &dir, &results)
}

/// The case table of `--list`.
fn case_list(study: &Study) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = write!(out, "{:>6}  {:<16}", "index", "case_id");
    for v in &study.variables {
        let _ = write!(out, "  {v:>14}");
    }
    let _ = writeln!(out);
    for c in study.cases() {
        let _ = write!(out, "{:>6}  {:<16}", c.index, c.id);
        for x in c.input_texts() {
            let _ = write!(out, "  {x:>14}");
        }
        let _ = writeln!(out);
    }
    out
}

/// The engine of the study, saying on a terminal what it waits for.
fn engine(args: &Args, study: &Study) -> Result<StudyEngine, StudyError> {
    let terminal = !args.quiet && std::io::stderr().is_terminal();
    if terminal && study.engine == railmbs_study::EngineKind::Symbolic {
        eprint!(
            "umsim: symbolic equations of model {}: deriving, then compiling unless cached…",
            study
                .models
                .iter()
                .map(|m| format!("\"{}\"", m.name))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let start = Instant::now();
    let engine = StudyEngine::prepare(study, None);
    if terminal && study.engine == railmbs_study::EngineKind::Symbolic {
        match &engine {
            Ok(e) if e.builds().compiled == 0 => eprintln!(" cached"),
            Ok(_) => eprintln!(" compiled in {:.1} s", start.elapsed().as_secs_f64()),
            Err(_) => eprintln!(),
        }
    }
    engine
}

/// `--case [INDEX]`.
fn run_one(
    args: &Args,
    study: &Study,
    dir: &Path,
    index: Option<usize>,
) -> Result<(), Box<dyn std::error::Error>> {
    let index = match index {
        Some(k) => k,
        None => {
            let text = std::env::var(TASK_ID_VARIABLE).map_err(|_| {
                format!("--case without INDEX reads ${TASK_ID_VARIABLE}, which is not set")
            })?;
            text.trim()
                .parse()
                .map_err(|_| format!("${TASK_ID_VARIABLE} is not a case index: {text:?}"))?
        }
    };
    let case = study.cases().get(index).ok_or_else(|| {
        format!(
            "{}: no case {index} (the study has {}: 0 to {})",
            args.study.display(),
            study.cases().len(),
            study.cases().len().saturating_sub(1)
        )
    })?;
    let file = railmbs_study::case_file(dir, &case.id);
    if file.exists() {
        println!(
            "case {index} ({}) has its result already: {}",
            case.id,
            file.display()
        );
        return Ok(());
    }
    let engine = engine(args, study)?;
    let options = CaseOptions {
        series_dir: study.time_series.then(|| dir.join("series")),
        stop: Some(crate::run::interrupt_flag()),
    };
    let result = engine.run_case(study, case, &options)?;
    let path = railmbs_study::write_case_file(study, dir, &result)?;
    println!(
        "case {index} ({}): {}{} in {:.2} s; {}",
        case.id,
        result.status.name(),
        result
            .error
            .as_ref()
            .map(|e| format!(" ({e})"))
            .unwrap_or_default(),
        result.wall_time,
        path.display()
    );
    Ok(())
}

/// The whole study on the local pool.
fn run_all(
    args: &Args,
    study: &Study,
    dir: &Path,
    results: &Path,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut store = ResultStore::open(results, study.result_header())?;
    if store.dropped_partial_line() {
        eprintln!(
            "umsim: {}: dropped a partly written last line (an earlier run was killed while writing it)",
            results.display()
        );
    }
    let total = study.cases().len();
    let pending = study
        .cases()
        .iter()
        .filter(|c| !store.finished().contains(&c.id))
        .count();
    if pending < total && !args.quiet {
        eprintln!(
            "umsim: resuming: {} of {total} cases are in {} already",
            total - pending,
            results.display()
        );
    }
    let start = Instant::now();
    let engine = engine(args, study)?;
    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| {
        let bar = indicatif::ProgressBar::new(pending as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} cases, {msg}, {eta} left",
            )
            .expect("valid progress template"),
        );
        bar.set_message("0 failed");
        bar
    });
    let options = PoolOptions {
        jobs: args.jobs,
        series_dir: study.time_series.then(|| dir.join("series")),
        stop: Some(crate::run::interrupt_flag()),
    };
    let mut failed = 0;
    let summary =
        railmbs_study::run_local(study, &engine, &mut store, &options, |r: &CaseResult| {
            failed += usize::from(r.status == railmbs_study::CaseStatus::Failed);
            if let Some(b) = &bar {
                b.inc(1);
                b.set_message(format!("{failed} failed"));
            }
        });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let summary = summary?;
    let done = summary.skipped + summary.recorded;
    if summary.interrupted {
        return Err(format!(
            "interrupted: {done} of {total} cases are in {}; run the same command again to resume",
            results.display()
        )
        .into());
    }
    if !args.quiet {
        println!(
            "{} cases run ({} failed), {} skipped as finished, in {:.1} s on {} thread(s); plugin: {} derived, {} found by the index, {} compiled",
            summary.recorded,
            summary.failed,
            summary.skipped,
            start.elapsed().as_secs_f64(),
            railmbs_study::threads(args.jobs).min(pending.max(1)),
            engine.builds().derived,
            engine.builds().indexed,
            engine.builds().compiled
        );
        println!("results                {} ({done} rows)", results.display());
    }
    Ok(())
}
