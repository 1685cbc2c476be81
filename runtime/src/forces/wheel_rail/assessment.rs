//! The element's outputs per wheel and the wheel loads of the EN 14363
//! assessment: Q the vertical wheel load and Y the lateral force of the wheel
//! on the rail (towards the field side), both in the track frame, Y/Q, the
//! track-shifting force ΣY, and the limits of Nadal and Prud'homme.

use super::WheelRailContact;
use super::solve::{ContactState, WheelsetState};
use crate::forces::{ForceContext, WheelLoads};
use nalgebra::Vector3;
use railmbs_track::SpeedLaw;

impl WheelRailContact {
    /// The output columns: per wheel (`L.`, `R.`) the loads, forces,
    /// creepages and contact data, then ΣY and Nadal's limit, and the rails'
    /// displacements for elastic rails, and for the non-elliptic contact
    /// each wheel's total patch area.
    pub(super) fn output_columns(&self) -> Vec<String> {
        let mut names = Vec::new();
        for side in ["L", "R"] {
            for n in [
                "Q [N]",
                "Y [N]",
                "Y/Q [-]",
                "N [N]",
                "Fx [N]",
                "Fy [N]",
                "xi [-]",
                "eta [-]",
                "spin [1/m]",
                "Tgamma [N]",
                "P [W]",
                "Eel [J]",
                "contact_angle [rad]",
                "contact_y [m]",
                "contacts [-]",
                "rolling_radius [m]",
            ] {
                names.push(format!("{side}.{n}"));
            }
        }
        names.push("SumY [N]".into());
        names.push("Nadal [-]".into());
        if self.c.rail.is_some() {
            for side in ["L", "R"] {
                for n in ["rail_dy [m]", "rail_dz [m]"] {
                    names.push(format!("{side}.{n}"));
                }
            }
        }
        if self.c.non_elliptic.is_some() {
            for side in ["L", "R"] {
                names.push(format!("{side}.patch_area [m2]"));
            }
        }
        names
    }

    /// Appends the values of [`Self::output_columns`] at the context's state.
    pub(super) fn write_outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        if self
            .solved(ctx, |state| self.write_state(state, out))
            .is_err()
        {
            // Only at an interpolated output state the steps never visited
            // (the step states themselves were solved): NaN marks the gap.
            out.extend(std::iter::repeat_n(f64::NAN, self.output_columns().len()));
        }
    }

    /// [`Self::write_outputs`] of a solved state.
    fn write_state(&self, state: &WheelsetState, out: &mut Vec<f64>) {
        let loads = Self::wheel_loads(state);
        for (side, &(q, y)) in loads.iter().enumerate() {
            let contacts = state.side(side);
            let sum = |f: &dyn Fn(&ContactState) -> f64| contacts.iter().map(f).sum::<f64>();
            // The contact carrying the largest normal force describes the wheel.
            let main = contacts
                .iter()
                .max_by(|a, b| a.normal.total_cmp(&b.normal))
                .copied()
                .unwrap_or_default();
            out.extend([
                q,
                y,
                if q > 0.0 { y / q } else { 0.0 },
                sum(&|c| c.normal),
                sum(&|c| c.forces.fx),
                sum(&|c| c.forces.fy),
                main.creepages.xi,
                main.creepages.eta,
                main.creepages.phi,
                // Wear number Tγ = |Fx ξ| + |Fy η| (N), per contact, summed.
                sum(&|c| {
                    (c.forces.fx * c.creepages.xi).abs() + (c.forces.fy * c.creepages.eta).abs()
                }),
                sum(&|c| c.dissipation),
                sum(&|c| c.elastic_energy),
                main.angle,
                main.rail_y,
                contacts.len() as f64,
                main.rolling_radius,
            ]);
        }
        // Track-shifting force: lateral force on the track, positive left =
        // Y_left − Y_right in field-side terms.
        out.push(loads[0].1 - loads[1].1);
        out.push(self.bound.as_ref().map_or(f64::NAN, |b| b.nadal));
        if self.c.rail.is_some() {
            out.extend(state.rail_d.iter().flatten());
        }
        if self.c.non_elliptic.is_some() {
            for side in 0..2 {
                out.push(state.side(side).iter().map(|c| c.area).sum());
            }
        }
    }

    /// The wheel loads for the EN 14363 assessment at the context's state:
    /// the wheelset's distance along the track, (Q, Y) per wheel and Nadal's
    /// limit; `None` if the contacts cannot be solved there.
    pub(super) fn wheel_loads_at(&self, ctx: &ForceContext) -> Option<WheelLoads> {
        let loads = self.solved(ctx, Self::wheel_loads).ok()?;
        // The distance s of the wheelset along the track.
        let distance = self
            .bound
            .as_ref()
            .and_then(|b| b.speed.motion(ctx.t).ok().map(|m| m.s + b.offset));
        Some(WheelLoads {
            distance,
            loads,
            nadal: self.bound.as_ref().map(|b| b.nadal),
        })
    }

    /// Per-side sums in the track frame: (Q, Y) with Q the vertical wheel load
    /// and Y the lateral force on the rail towards the field side, N.
    fn wheel_loads(state: &WheelsetState) -> [(f64, f64); 2] {
        [0, 1].map(|side| {
            let sign = if side == 0 { 1.0 } else { -1.0 };
            let f: Vector3<f64> = state.side(side).iter().map(|c| c.force()).sum();
            let local = state.track_axes.transpose() * f;
            // Force on the rail is −f; field side is +y on the left, −y on the right.
            (local.z, -sign * local.y)
        })
    }
}

/// Nadal's limit of Y/Q for flange angle `beta` (rad) and friction `mu`:
/// (tan β − μ)/(1 + μ tan β) (Nadal 1908).
pub fn nadal_limit(beta: f64, mu: f64) -> f64 {
    let t = beta.tan();
    (t - mu) / (1.0 + mu * t)
}

/// Prud'homme's limit of the track-shifting force ΣY (N) for axle load `p`
/// (N): α (10 kN + P/3), α = 0.85 (Prud'homme 1970, the usual factor for
/// track in service).
pub fn prudhomme_limit(p: f64) -> f64 {
    0.85 * (10e3 + p / 3.0)
}
