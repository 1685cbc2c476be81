//! Plugin loading: a plugin is refused, with a clear message, when it was built
//! from another model, for another ABI version, or is not a plugin at all; and a
//! simulation gives the same trajectory with either engine.

use railmbs_runtime::integrate::ParkSettings;
use railmbs_runtime::{ModelSystem, NumericEquations, Plugin, PluginError};
use railmbs_testkit::*;
use std::path::PathBuf;

fn build(model: &railmbs_models::Model) -> PathBuf {
    railmbs_codegen::build_plugin(
        model,
        &railmbs_codegen::GenerateOptions::new(),
        Some(plugin_cache_dir()),
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .path
}

#[test]
fn plugin_of_another_model_is_refused() {
    let pendulum = mechanism("pendulum");
    let path = build(&pendulum);
    // Structural change: one more elementary transformation.
    let mut changed = pendulum.clone();
    changed.bodies[0].joint.push(railmbs_models::Elementary {
        kind: railmbs_models::ElementaryKind::Translation(railmbs_models::Axis::Z),
        motion: railmbs_models::Motion::Fixed(railmbs_models::Expr::Num(0.1)),
    });
    let err = Plugin::load_for(&path, &changed).unwrap_err();
    assert!(matches!(err, PluginError::ModelMismatch { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("another model") && msg.contains("umgen"),
        "{msg}"
    );
    // A different default value is not a structural change: accepted.
    let mut other_default = pendulum.clone();
    other_default.parameters[0].default = railmbs_models::Expr::Num(2.0);
    Plugin::load_for(&path, &other_default).unwrap();
    // A different model entirely.
    let err = Plugin::load_for(&path, &mechanism("double_pendulum")).unwrap_err();
    assert!(err.to_string().contains("\"pendulum\""), "{err}");
}

#[test]
fn plugin_of_another_abi_version_is_refused() {
    // The generated source with the interface's one version constant changed: what a
    // plugin of another railmbs would be.
    let model = mechanism("pendulum");
    let source = railmbs_codegen::generate(&model, &railmbs_codegen::GenerateOptions::new())
        .unwrap()
        .source;
    let abi = railmbs_runtime::plugin::ABI_VERSION;
    let line = format!("pub const ABI_VERSION: u32 = {abi};");
    assert_eq!(source.matches(&line).count(), 1, "{line}");
    let other = source.replace(
        &line,
        &format!("pub const ABI_VERSION: u32 = {};", abi + 100),
    );
    let path = railmbs_build_support::build_plugin(
        &other,
        &railmbs_build_support::BuildOptions::new(abi + 100).with_cache_dir(plugin_cache_dir()),
    )
    .unwrap()
    .path;
    let err = Plugin::load_for(&path, &model).unwrap_err();
    assert!(matches!(err, PluginError::AbiVersion { .. }), "{err}");
    assert!(err.to_string().contains("ABI version"), "{err}");
}

#[test]
fn a_file_that_is_not_a_plugin_is_refused() {
    let model = mechanism("pendulum");
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("not_a_library.so");
    std::fs::write(&text, "this is text").unwrap();
    let err = Plugin::load_for(&text, &model).unwrap_err();
    assert!(matches!(err, PluginError::NotALibrary { .. }), "{err}");
    assert!(err.to_string().contains("not_a_library.so"), "{err}");
    // A real shared library without the plugin's symbols.
    let lib = railmbs_build_support::build_plugin(
        "#[no_mangle] pub extern \"C\" fn something_else() -> i32 { 1 }",
        &railmbs_build_support::BuildOptions::new(1).with_cache_dir(plugin_cache_dir()),
    )
    .unwrap();
    let err = Plugin::load_for(&lib.path, &model).unwrap_err();
    assert!(matches!(err, PluginError::MissingSymbol { .. }), "{err}");
    assert!(err.to_string().contains("railmbs_plugin_info"), "{err}");
}

#[test]
fn the_plugin_and_the_loader_share_one_interface() {
    // The generated source holds the interface verbatim, once: the same text the loader
    // compiles as `railmbs_plugin_abi`, whose types it calls the plugin through.
    let model = mechanism("double_pendulum");
    let source = railmbs_codegen::generate(&model, &railmbs_codegen::GenerateOptions::new())
        .unwrap()
        .source;
    let abi = railmbs_runtime::plugin::abi::SOURCE;
    assert_eq!(source.matches(abi).count(), 1);
    // Nothing of the interface is written a second time around it.
    let rest = source.replace(abi, "");
    for item in [
        "struct PluginInfo",
        "struct Inputs",
        "struct Outputs",
        "ABI_VERSION: u32 =",
        "PART_DYNAMICS: u32 =",
        "\"avx512f\"",
    ] {
        assert!(
            !rest.contains(item),
            "`{item}` written outside the interface"
        );
    }
    // The exported functions are checked against the interface's signatures, which the
    // loader's symbol types are.
    for check in [
        "const _: InfoFn = railmbs_plugin_info;",
        "const _: TargetFeaturesFn = railmbs_target_features;",
        "const _: EvaluateFn = railmbs_evaluate;",
    ] {
        assert!(rest.contains(check), "{check}");
    }
    // A plugin built from it loads (the loader checks its version).
    let plugin = Plugin::load_for(&build(&model), &model).unwrap();
    assert_eq!(plugin.dof, model.coordinates.len());
}

#[test]
fn a_plugin_for_cpu_features_this_machine_lacks_is_refused() {
    // A library that reports a feature no CPU has: refused before any other of its
    // functions runs, naming the feature and the way out.
    let model = mechanism("pendulum");
    let lib = railmbs_build_support::build_plugin(
        "#[no_mangle] pub extern \"C\" fn railmbs_target_features() -> *const u8 { \
         b\"avx,no-such-feature\\0\".as_ptr() }",
        &railmbs_build_support::BuildOptions::new(1).with_cache_dir(plugin_cache_dir()),
    )
    .unwrap();
    let err = Plugin::load_for(&lib.path, &model).unwrap_err();
    match &err {
        PluginError::CpuFeatures { missing, .. } => {
            assert!(missing.contains(&"no-such-feature".to_owned()), "{err}")
        }
        other => panic!("expected CpuFeatures, got {other}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("no-such-feature") && msg.contains("--portable"),
        "{msg}"
    );
    // Every feature a generated plugin may report can be checked on this machine.
    if cfg!(target_arch = "x86_64") {
        for f in railmbs_runtime::plugin::abi::TARGET_FEATURES {
            assert!(
                railmbs_runtime::plugin::host_has_target_feature(f).is_some(),
                "the loader cannot check {f}"
            );
        }
    }
}

#[test]
fn native_and_portable_plugins_report_their_cpu_features_and_agree() {
    // The default plugin is built for this CPU and loads here; the portable one reports
    // only the baseline (no AVX); both give the same mass matrix to rounding.
    let model = mechanism("double_pendulum");
    let native = build(&model);
    let mut opts = railmbs_codegen::GenerateOptions::new();
    opts.portable = true;
    let portable = railmbs_codegen::build_plugin(&model, &opts, Some(plugin_cache_dir()))
        .unwrap()
        .path;
    assert_ne!(native, portable);
    let features = |path: &std::path::Path| Plugin::open(path).unwrap().target_features.clone();
    let (fn_native, fn_portable) = (features(&native), features(&portable));
    if cfg!(target_arch = "x86_64") {
        assert!(
            !fn_portable.iter().any(|f| f.starts_with("avx")),
            "{fn_portable:?}"
        );
        if railmbs_runtime::plugin::host_has_target_feature("avx2") == Some(true) {
            assert!(fn_native.contains(&"avx2".to_owned()), "{fn_native:?}");
        }
    }
    use railmbs_runtime::Equations;
    let params = model.default_parameter_values();
    let (q, v) = model.initial_state(&params);
    let mut masses = Vec::new();
    for path in [&native, &portable] {
        let mut eq = railmbs_runtime::PluginEquations::new(Plugin::load_for(path, &model).unwrap());
        eq.set_parameters(&params).unwrap();
        let mut out = railmbs_runtime::Evaluation::for_equations(&eq);
        eq.evaluate(
            0.0,
            q.as_slice(),
            v.as_slice(),
            railmbs_runtime::Parts::ALL,
            &mut out,
        )
        .unwrap();
        masses.push(out.mass);
    }
    for (a, b) in masses[0].iter().zip(masses[1].iter()) {
        assert!((a - b).abs() <= 1e-14 * (1.0 + a.abs()), "{a} vs {b}");
    }
}

#[test]
fn fixed_parameters_are_folded_and_other_values_refused() {
    let model = mechanism("pendulum");
    let mut opts = railmbs_codegen::GenerateOptions::new();
    opts.fixed = vec!["l".into(), "r".into()];
    let built = railmbs_codegen::build_plugin(&model, &opts, Some(plugin_cache_dir())).unwrap();
    let plugin = Plugin::load_for(&built.path, &model).unwrap();
    let mut eq = railmbs_runtime::PluginEquations::new(plugin);
    let mut params = model.default_parameter_values();
    use railmbs_runtime::Equations;
    eq.set_parameters(&params).unwrap();
    params[model.parameter_index("l").unwrap()] = 2.0;
    let err = eq.set_parameters(&params).unwrap_err().to_string();
    assert!(err.contains("\"l\"") && err.contains("fixed"), "{err}");
    let err = railmbs_codegen::build_plugin(
        &model,
        &railmbs_codegen::GenerateOptions {
            fixed: vec!["nope".into()],
            ..opts
        },
        Some(plugin_cache_dir()),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("nope"), "{err}");
}

#[test]
fn symbolic_and_numeric_engines_give_the_same_trajectories() {
    for name in [
        "double_pendulum",
        "fourbar",
        "spring_mass",
        "shaken_pendulum",
        "chain10",
    ] {
        let model = mechanism(name);
        let params = model.default_parameter_values();
        let (q0, v0) = model.initial_state(&params);
        let mut num = ModelSystem::new(
            &model,
            Box::new(NumericEquations::new(&model)),
            params.clone(),
        )
        .unwrap();
        let mut sym =
            ModelSystem::new(&model, Box::new(symbolic_engine(&model)), params.clone()).unwrap();
        // Fixed step: the engines differ only by rounding, so the states agree
        // to far below any integration error.
        let fixed = ParkSettings::fixed(1e-3);
        let (a, _) = run_park(&mut num, &fixed, &q0, &v0, 2.0);
        let (b, _) = run_park(&mut sym, &fixed, &q0, &v0, 2.0);
        for ((ta, qa, _), (tb, qb, _)) in a.iter().zip(&b) {
            assert_eq!(ta, tb);
            for (x, y) in qa.iter().zip(qb) {
                assert!(
                    (x - y).abs() < 1e-9 * (1.0 + x.abs()),
                    "{name}, t = {ta}: {x} vs {y}"
                );
            }
        }
        // Error control may pick a different step now and then (a rounding-level
        // difference in the error estimate near the acceptance threshold): the
        // end states then agree to the size of the integration error.
        let adaptive = ParkSettings::with_tolerances(1e-8, 1e-8);
        let (a, _) = run_park(&mut num, &adaptive, &q0, &v0, 2.0);
        let (b, _) = run_park(&mut sym, &adaptive, &q0, &v0, 2.0);
        let (qa, qb) = (&a.last().unwrap().1, &b.last().unwrap().1);
        for (x, y) in qa.iter().zip(qb) {
            assert!((x - y).abs() < 1e-5 * (1.0 + x.abs()), "{name}: {x} vs {y}");
        }
    }
}

#[test]
fn plugin_index_finds_a_built_plugin_without_generating_and_never_a_stale_one() {
    use railmbs_codegen::{GenerateOptions, find_or_build_plugin, input_digest};
    let cache = tempfile::tempdir().unwrap();
    let dir = || Some(cache.path().to_path_buf());
    let model = mechanism("pendulum");
    let opts = GenerateOptions::new();

    let first = find_or_build_plugin(&model, &opts, dir()).unwrap();
    assert!(!first.indexed && !first.cache_hit, "{first:?}");
    let again = find_or_build_plugin(&model, &opts, dir()).unwrap();
    assert!(again.indexed && again.cache_hit, "{again:?}");
    assert_eq!(again.path, first.path);

    // Another default value: other generator input, so not found in the
    // index; the source does not depend on it, so the library is a cache hit.
    let mut other_default = model.clone();
    other_default.parameters[0].default = railmbs_models::Expr::Num(2.0);
    assert_ne!(
        input_digest(&other_default, &opts),
        input_digest(&model, &opts)
    );
    let other = find_or_build_plugin(&other_default, &opts, dir()).unwrap();
    assert!(!other.indexed && other.cache_hit, "{other:?}");
    assert_eq!(other.path, first.path);

    // A truncated library is never handed out by the index: rebuilt.
    let bytes = std::fs::read(&first.path).unwrap();
    std::fs::write(&first.path, &bytes[..bytes.len() / 2]).unwrap();
    let rebuilt = find_or_build_plugin(&model, &opts, dir()).unwrap();
    assert!(
        !rebuilt.indexed && rebuilt.rebuilt_damaged.is_some(),
        "{rebuilt:?}"
    );
    assert_eq!(std::fs::read(&rebuilt.path).unwrap(), bytes);

    // An entry whose compiler is gone (a toolchain replaced in place) is not used.
    let index = cache.path().join("index");
    let entries: Vec<_> = std::fs::read_dir(&index)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(
        entries.len(),
        2,
        "one entry per generator input: {entries:?}"
    );
    for entry in &entries {
        let text = std::fs::read_to_string(entry).unwrap();
        let gone: String = text
            .lines()
            .map(|l| match l.strip_prefix("driver ") {
                Some(_) => "driver /nonexistent/librustc_driver-0.so".to_owned(),
                None => l.to_owned(),
            })
            .collect::<Vec<_>>()
            .join("\n");
        std::fs::write(entry, gone + "\n").unwrap();
    }
    let relooked = find_or_build_plugin(&model, &opts, dir()).unwrap();
    assert!(!relooked.indexed && relooked.cache_hit, "{relooked:?}");
    let last = find_or_build_plugin(&model, &opts, dir()).unwrap();
    assert!(last.indexed);
    // Loaded only now: truncating a loaded library (above) would crash the process.
    Plugin::load_for(&last.path, &model).unwrap();
}
