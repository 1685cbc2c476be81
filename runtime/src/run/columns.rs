//! The output columns of a run: which quantities, their names (the CSV
//! header) and their values at an output row.

use super::grid::{Row, RowView};
use super::{RowColumns, RunError};
use crate::equations::Parts;
use crate::model_system::ModelSystem;
use crate::system::SimError;
use crate::track_inputs::RunningSpeed;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{Model, OutputSpec};
use std::path::Path;

/// Column layout of the output file.
pub(crate) struct Columns {
    pub(crate) header: Vec<String>,
    /// The running speed law, when the run is on a track: the columns `s[m]`
    /// (arc position of the vehicle's reference point) and `v[m/s]` (its
    /// running speed) follow `time`.
    arc: Option<RunningSpeed>,
    coordinates: bool,
    velocities: bool,
    bodies: Vec<usize>,
    /// The selected force elements (indices into the system's elements).
    forces: Vec<usize>,
    /// (body, point in the body's frame) of each accelerometer.
    accelerometers: Vec<(usize, Vector3<f64>)>,
    need_kinematics: bool,
}

fn select(
    names: &[String],
    wanted: &[String],
    what: &str,
    file: &Path,
) -> Result<Vec<usize>, RunError> {
    if wanted.iter().any(|w| w == "*") {
        return Ok((0..names.len()).collect());
    }
    wanted
        .iter()
        .map(|w| {
            names
                .iter()
                .position(|n| n == w)
                .ok_or_else(|| RunError::Setup {
                    file: file.to_path_buf(),
                    message: format!("output: no {what} named \"{w}\""),
                })
        })
        .collect()
}

pub(crate) fn columns(
    model: &Model,
    system: &ModelSystem,
    spec: &OutputSpec,
    file: &Path,
    arc: Option<RunningSpeed>,
) -> Result<Columns, RunError> {
    let mut header = vec!["time".to_string()];
    if arc.is_some() {
        header.extend(ARC_COLUMNS.map(String::from));
    }
    if spec.coordinates {
        header.extend(model.coordinates.iter().map(|c| c.name.clone()));
        header.extend(system.state_names());
    }
    if spec.velocities {
        header.extend(model.coordinates.iter().map(|c| format!("{}.v", c.name)));
        header.extend(system.state_names().iter().map(|c| format!("{c}.v")));
    }
    let body_names: Vec<String> = model.bodies.iter().map(|b| b.name.clone()).collect();
    let bodies = select(&body_names, &spec.bodies, "body", file)?;
    for &b in &bodies {
        let n = &body_names[b];
        for s in [
            "x[m]",
            "y[m]",
            "z[m]",
            "rx[rad]",
            "ry[rad]",
            "rz[rad]",
            "vx[m/s]",
            "vy[m/s]",
            "vz[m/s]",
            "wx[rad/s]",
            "wy[rad/s]",
            "wz[rad/s]",
        ] {
            header.push(format!("{n}.{s}"));
        }
    }
    let force_names: Vec<String> = model.forces.iter().map(|f| f.name.clone()).collect();
    let mut accelerometers = Vec::new();
    for a in &spec.accelerometers {
        let b = select(&body_names, std::slice::from_ref(&a.body), "body", file).map_err(|_| {
            RunError::Setup {
                file: file.to_path_buf(),
                message: format!(
                    "output: accelerometer \"{}\" is on \"{}\", which is no body of the model",
                    a.name, a.body
                ),
            }
        })?[0];
        accelerometers.push((b, Vector3::from(a.point)));
    }
    let mut forces = Vec::new();
    for e in select(&force_names, &spec.forces, "force element", file)? {
        let names = system.forces()[e].output_names();
        for s in &names {
            header.push(format!("{}.{s}", force_names[e]));
        }
        forces.push(e);
    }
    for a in &spec.accelerometers {
        for c in ["ax[m/s2]", "ay[m/s2]", "az[m/s2]"] {
            header.push(format!("{}.{c}", a.name));
        }
    }
    Ok(Columns {
        header,
        arc,
        coordinates: spec.coordinates,
        velocities: spec.velocities,
        need_kinematics: !bodies.is_empty() || !forces.is_empty(),
        accelerometers,
        bodies,
        forces,
    })
}

impl Columns {
    /// Appends the values of the columns after `time` and `s[m]` at a state.
    pub(crate) fn values(
        &self,
        system: &mut ModelSystem,
        row: RowView,
        values: &mut Vec<f64>,
    ) -> Result<(), RunError> {
        let (t, q, v) = (row.t, row.q, row.v);
        if self.coordinates {
            values.extend_from_slice(q);
        }
        if self.velocities {
            values.extend_from_slice(v);
        }
        if self.need_kinematics {
            let eval = system.evaluate(t, q, v, Parts::KINEMATICS)?;
            for &b in &self.bodies {
                let k = &eval.bodies[b];
                values.extend(k.position.iter());
                values.extend(xyz_angles(&k.rotation).iter());
                values.extend(k.velocity.iter());
                values.extend(k.angular_velocity.iter());
            }
            // Only the selected elements' outputs are evaluated.
            system.force_outputs_of(t, &self.forces, values);
        }
        if !self.accelerometers.is_empty() {
            accelerations(system, row, &self.accelerometers, values)?;
        }
        Ok(())
    }
}

/// Appends the accelerations (m/s², in the body's frame, gravity not
/// included) of the accelerometer points at an output row. The point's
/// velocity v_P(t, q, q̇) is differentiated along the motion by a central
/// difference over (t ± ε, q ± ε q̇, q̇ ± ε q̈): exact for the rheonomic
/// track-frame inputs as well, O(ε²) truncation, rounding ~1e-16·|v|/ε.
fn accelerations(
    system: &mut ModelSystem,
    row: RowView,
    points: &[(usize, Vector3<f64>)],
    values: &mut Vec<f64>,
) -> Result<(), RunError> {
    let eps = 1e-5;
    let shifted = |sign: f64| -> (Vec<f64>, Vec<f64>) {
        (
            row.q
                .iter()
                .zip(row.v)
                .map(|(q, v)| q + sign * eps * v)
                .collect(),
            row.v
                .iter()
                .zip(row.a)
                .map(|(v, a)| v + sign * eps * a)
                .collect(),
        )
    };
    let mut at = |sign: f64| -> Result<Vec<Vector3<f64>>, RunError> {
        let (q, v) = shifted(sign);
        let e = system.evaluate(row.t + sign * eps, &q, &v, Parts::KINEMATICS)?;
        Ok(points
            .iter()
            .map(|(b, p)| e.bodies[*b].point_velocity(p))
            .collect())
    };
    let (plus, minus) = (at(1.0)?, at(-1.0)?);
    let e = system.evaluate(row.t, row.q, row.v, Parts::KINEMATICS)?;
    for ((b, _), (vp, vm)) in points.iter().zip(plus.iter().zip(&minus)) {
        let a = e.bodies[*b].rotation.transpose() * ((vp - vm) / (2.0 * eps));
        values.extend(a.iter());
    }
    Ok(())
}

/// Cardan angles of a rotation matrix for the sequence x, y, z of the moving
/// frame (A = Rx(a) Ry(b) Rz(c)), rad.
pub fn xyz_angles(a: &Matrix3<f64>) -> Vector3<f64> {
    let b = a[(0, 2)].clamp(-1.0, 1.0).asin();
    let x = (-a[(1, 2)]).atan2(a[(2, 2)]);
    let z = (-a[(0, 1)]).atan2(a[(0, 0)]);
    Vector3::new(x, b, z)
}

/// A single vehicle's columns: `time`, `s[m]` on a track, then the
/// columns of [`Columns::values`].
impl RowColumns<ModelSystem> for Columns {
    fn header(&self) -> &[String] {
        &self.header
    }

    fn values(
        &self,
        system: &mut ModelSystem,
        row: &Row,
        values: &mut Vec<f64>,
    ) -> Result<(), RunError> {
        if let Some(arc) = &self.arc {
            values.extend(arc_motion(arc, row.t)?);
        }
        self.values(system, row.slice(0..row.q.len()), values)
    }
}

/// The columns of a run on a track after `time`: arc position and running
/// speed of the reference point.
pub(crate) const ARC_COLUMNS: [&str; 2] = ["s[m]", "v[m/s]"];

/// Arc position s(t) (m) and running speed v(t) (m/s) of a speed law.
pub(crate) fn arc_motion(arc: &RunningSpeed, t: f64) -> Result<[f64; 2], RunError> {
    use railmbs_track::SpeedLaw;
    arc.motion(t)
        .map(|m| [m.s, m.s_dot])
        .map_err(|e| RunError::Sim(SimError::Other(e.to_string())))
}
