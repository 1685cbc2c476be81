//! The examples in the crate documentation parse, load and resolve.

use railmbs_models::*;

/// The ```ron blocks of the crate docs, without the `//! ` prefix.
fn ron_blocks() -> Vec<String> {
    let lib = include_str!("../../src/lib.rs");
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in lib.lines() {
        let Some(body) = line.strip_prefix("//!") else {
            continue;
        };
        let body = body.strip_prefix(' ').unwrap_or(body);
        match (&mut current, body.trim()) {
            (None, "```ron") => current = Some(String::new()),
            (Some(_), "```") => blocks.extend(current.take()),
            (Some(text), _) => {
                text.push_str(body);
                text.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

#[test]
fn documented_model_and_scenario_are_valid() {
    let blocks = ron_blocks();
    assert_eq!(blocks.len(), 2, "a model and a scenario example");
    let dir = std::env::temp_dir().join(format!("railmbs-models-docs-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("mechanisms")).unwrap();
    std::fs::create_dir_all(dir.join("scenarios")).unwrap();
    let model_path = dir.join("mechanisms/double_pendulum.ron");
    std::fs::write(&model_path, &blocks[0]).unwrap();
    let model = load_model(&model_path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.bodies.len(), 5);
    assert_eq!(model.coordinates.len(), 3 + 6);
    assert_eq!(model.forces.len(), 3);
    assert_eq!(model.cut_joints.len(), 1);

    let scenario_path = dir.join("scenarios/double_pendulum.ron");
    std::fs::write(&scenario_path, &blocks[1]).unwrap();
    let sc = load_scenario(&scenario_path).unwrap_or_else(|e| panic!("{e}"));
    let loaded = load_model(&sc.model).unwrap_or_else(|e| panic!("{e}"));
    let p = sc
        .parameter_values(&loaded)
        .unwrap_or_else(|e| panic!("{e}"));
    let (q, v) = sc
        .initial_state(&loaded, &p)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(q[0], 0.3);
    assert_eq!(v[1], 1.0);
    std::fs::remove_dir_all(&dir).ok();
}
