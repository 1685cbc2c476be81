//! Every bundled model and scenario file loads without errors.

use railmbs_models::*;
use railmbs_testkit::model_files;

#[test]
fn bundled_models_load() {
    let mut problems = Vec::new();
    for folder in [
        "mechanisms",
        "mechanisms/subsystems",
        "vehicles",
        "vehicles/couplers",
    ] {
        for path in model_files(folder) {
            match load_model(&path) {
                Ok(m) => {
                    let p = m.default_parameter_values();
                    assert!(p.iter().all(|x| x.is_finite()), "{}", path.display());
                }
                Err(e) => problems.push(e.to_string()),
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn bundled_scenarios_resolve() {
    let mut problems = Vec::new();
    for path in model_files("scenarios") {
        let resolve = |sc: &Scenario, model: &Model| {
            let p = sc.parameter_values(model)?;
            sc.initial_state(model, &p).map(|_| ())
        };
        let resolved = load_any_scenario(&path).and_then(|any| match any {
            AnyScenario::Single(sc) => resolve(&sc, &load_model(&sc.model)?),
            AnyScenario::Train(train) => {
                let models = train
                    .vehicles
                    .iter()
                    .map(|v| load_model(&v.model))
                    .collect::<Result<Vec<_>, _>>()?;
                let refs: Vec<&Model> = models.iter().collect();
                train.check_names(&refs)?;
                for c in &train.couplers {
                    train.resolve_coupler(c, &refs)?;
                }
                train.resolve_elements(&refs)?;
                for (k, model) in models.iter().enumerate() {
                    resolve(&train.vehicle_scenario(k, model), model)?;
                }
                Ok(())
            }
        });
        if let Err(e) = resolved {
            problems.push(e.to_string());
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
