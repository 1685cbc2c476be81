//! The generated source of the simple pendulum, kept as an insta snapshot so
//! that every change of the generated code is seen and reviewed
//! (`cargo insta review`, or `INSTA_UPDATE=always` then read the diff).

#[test]
fn pendulum_plugin_source() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/mechanisms/pendulum.ron");
    let model = railmbs_models::load_model(&path).unwrap_or_else(|e| panic!("{e}"));
    // ABI version 1 spelled out: the snapshot must not change silently with it.
    let generated =
        railmbs_codegen::generate(&model, &railmbs_codegen::GenerateOptions::new(1)).unwrap();
    insta::assert_snapshot!("pendulum_plugin_source", generated.source);
}
