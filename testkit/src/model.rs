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

/// The text of a generated open chain of `n` links (for chains longer than
/// the bundled ones, tests and benches of the articulated-body method).
///
/// `spatial == false`: the planar chain of `models/tools/gen_chains.py`
/// (1 kg, 1 m links, centre of mass at mid-link, Izz = Ixx = 1/12,
/// Iyy = 1e-4 kg m², revolute joints about z, gravity 9.81 m/s² along −y,
/// q0(0) = 0.5 rad). `spatial == true`: the same links with joint axes
/// cycling z, x, y, the centre of mass off the link axis (0.05, −0.5,
/// 0.02) m and a full inertia tensor (products of inertia nonzero), every
/// joint starting at 0.3 sin(i) rad: a chain whose motion is not planar.
pub fn chain_text(n: usize, spatial: bool) -> String {
    let mut s = format!(
        "Model(\n    name: \"{}chain{n}\",\n    description: \"generated chain of {n} links\",\n    \
         gravity: (0, -9.81, 0),\n    bodies: [\n",
        if spatial { "spatial_" } else { "" }
    );
    for i in 0..n {
        let parent = if i == 0 {
            "ground".to_string()
        } else {
            format!("link{}", i - 1)
        };
        let at = if i == 0 { "(0, 0, 0)" } else { "(0, -0.5, 0)" };
        let (axis, inertia, init, com) = if spatial {
            (
                ["Z", "X", "Y"][i % 3],
                "(ixx: 0.09, iyy: 0.02, izz: 0.08, ixy: 0.004, ixz: -0.002, iyz: 0.003)",
                0.3 * (i as f64).sin(),
                "(0.05, -0.5, 0.02)",
            )
        } else {
            (
                "Z",
                "(ixx: \"1/12\", iyy: 1e-4, izz: \"1/12\")",
                if i == 0 { 0.5 } else { 0.0 },
                "(0, -0.5, 0)",
            )
        };
        s += &format!(
            "        Body(name: \"link{i}\", mass: 1.0, inertia: {inertia},\n            \
             joint: Revolute(parent: \"{parent}\", at: {at}, axis: {axis}, coord: \"q{i}\", \
             init: {init}, vel: 0.0, to_com: {com})),\n"
        );
    }
    s += "    ],\n)\n";
    s
}

/// The generated chain of [`chain_text`], parsed.
pub fn chain(n: usize, spatial: bool) -> Model {
    parse(&chain_text(n, spatial))
}
