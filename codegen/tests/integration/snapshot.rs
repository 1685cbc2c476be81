//! The generated source of the simple pendulum, kept as an insta snapshot so
//! that every change of the generated code is seen and reviewed
//! (`cargo insta review`, or `INSTA_UPDATE=always` then read the diff).

#[test]
fn pendulum_plugin_source() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/mechanisms/pendulum.ron");
    let model = railmbs_models::load_model(&path).unwrap_or_else(|e| panic!("{e}"));
    // The interface (`railmbs_plugin_abi::SOURCE`, with its ABI version) is part of the
    // source: the snapshot changes with it.
    let generated =
        railmbs_codegen::generate(&model, &railmbs_codegen::GenerateOptions::new()).unwrap();
    insta::assert_snapshot!("pendulum_plugin_source", generated.source);
}
