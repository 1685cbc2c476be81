//! `umgen`: the railmbs plugin generator.

use clap::Parser;

fn main() {
    let args = railmbs_cli::umgen::Args::parse();
    if let Err(e) = railmbs_cli::umgen::run(&args) {
        eprintln!("umgen: error: {e}");
        std::process::exit(1);
    }
}
