//! Models from text and from the bundled library (`models/`).

use crate::paths::{model_files, model_path};
use railmbs_models::{Model, ModelErrors};
use std::path::Path;

/// The file a model parsed from text is said to come from: errors name it,
/// and relative paths in the text would resolve against its folder.
pub const TEXT_FILE: &str = "models/mechanisms/x.ron";

/// A model from text, or the loader's errors (located in [`TEXT_FILE`]).
pub fn try_parse(text: &str) -> Result<Model, ModelErrors> {
    railmbs_models::parse_model(text, Path::new(TEXT_FILE))
}

/// A model from text; panics with the loader's message.
pub fn parse(text: &str) -> Model {
    try_parse(text).unwrap_or_else(|e| panic!("{e}"))
}

/// Loads `models/mechanisms/<name>.ron`.
pub fn mechanism(name: &str) -> Model {
    load(&model_path(&format!("mechanisms/{name}.ron")))
}

/// Every bundled mechanism model (`models/mechanisms/*.ron`), by file name.
pub fn all_mechanisms() -> Vec<Model> {
    model_files("mechanisms").iter().map(|p| load(p)).collect()
}

/// Every bundled vehicle model (`models/vehicles/*.ron`, by file name; the
/// subsystem component files in subfolders are covered through the
/// vehicles), then the component wheelset with independently rotating wheels,
/// which no vehicle uses yet, the coupler models of trains
/// (`models/vehicles/couplers/*.ron`) and the freight car
/// (`models/vehicles/freight/freight_car.ron`).
pub fn all_vehicles() -> Vec<Model> {
    let mut paths = model_files("vehicles");
    paths.push(model_path("vehicles/components/wheelset_s1002_irw.ron"));
    paths.extend(model_files("vehicles/couplers"));
    paths.push(model_path("vehicles/freight/freight_car.ron"));
    paths.iter().map(|p| load(p)).collect()
}

fn load(path: &Path) -> Model {
    railmbs_models::load_model(path).unwrap_or_else(|e| panic!("{e}"))
}
