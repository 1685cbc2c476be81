//! Records a digest of the generator's source (this crate, the computer
//! algebra, the model language and the plugin interface) and of the compiler
//! as `RAILMBS_GENERATOR_DIGEST`: the plugin index, which finds a cached
//! plugin from the model without generating its source, is keyed by it.

include!("../tools/build/source_digest.rs");

fn main() {
    println!(
        "cargo:rustc-env=RAILMBS_GENERATOR_DIGEST={}",
        source_digest(&["src", "../cas/src", "../models/src", "../plugin-abi/src"])
    );
}
