//! The non-elliptic contact of a wheel on rigid rails (`contact:
//! KikPiotrowski(..)`, [`railmbs_wheelrail::kik_piotrowski`]): at every
//! evaluation the undeformed gap across the wheel's profile is sampled
//! where the wheel comes close to its rail
//! ([`ContactGeometry::gap_samples_below`](railmbs_wheelrail::geometry::ContactGeometry::gap_samples_below),
//! at the strip width), the patches come from the virtual penetration of
//! the wheel at its vertical approach δ_z = −z (z the side's height of the
//! axle above its nominal radius, the rail's vertical irregularity taken
//! off: the gap at height z is gap + z), and each patch is one contact:
//!
//! - its point, frame and creepages at the patch's reference point (the
//!   deepest sample: rail point, contact angle, rolling radius), as the Hertz
//!   contact's at its contact point (yaw lead and all);
//! - its normal force N from the approach over the patch (Boussinesq), plus
//!   the normal damper's c_n δ̇ (never pulling); with the damper the strips'
//!   pressures are scaled by the total over the elastic force, so that the
//!   tangential problem sees the load the patch carries, as the Hertz
//!   contact's ellipse does;
//! - its tangential forces by the strip solution on the patch's own strips
//!   ([`Patch::creep_forces`]);
//! - for the approximate Jacobian (Pogorelov 2005, Sect. 6), dN/dδ₀ =
//!   (3/2) N/δ₀ (N ∝ δ₀^{3/2} as for Hertz; the Jacobian only steers the
//!   Newton iterations) and the linear creep coefficients of the patch's
//!   equivalent ellipse; the elastic energy (2/5) N δ₀ likewise.
//!
//! The contact table is not used for the forces (only for Nadal's limit and
//! the checks of the lateral range). Simplifications are those of the
//! library method (its module documentation); the reference point of a patch
//! moves by whole samples, so the contact angle of a patch steps by the
//! profiles' curvature times the strip width (about 1e-4 rad on the tread at
//! 0.1 mm).

use super::WheelRailContact;
use super::kinematics::Side;
use super::solve::{MAX_CONTACTS, WheelsetState};
use crate::system::SimError;
use railmbs_wheelrail::geometry::Contact;
use railmbs_wheelrail::kik_piotrowski::Patch;

impl WheelRailContact {
    /// The patches of one side's wheel on its rigid rail, solved and pushed
    /// onto `state`.
    pub(super) fn solve_non_elliptic_side(
        &self,
        s: &Side,
        state: &mut WheelsetState,
    ) -> Result<(), SimError> {
        let t = s.ctx.t;
        let (Some((kp, width)), Some(geometry)) = (&self.c.non_elliptic, &s.b.geometry) else {
            return Err(self.err("the non-elliptic contact is not prepared"));
        };
        let approach = -s.z;
        let samples = geometry
            .gap_samples_below(s.side, s.y, s.roll, *width, approach)
            .map_err(|e| self.diverged(t, format!("gap samples: {e}")))?;
        let patches = kp
            .patches(&samples, approach)
            .map_err(|e| self.diverged(t, e.to_string()))?;
        if patches.len() > MAX_CONTACTS {
            return Err(self.diverged(
                t,
                format!(
                    "{} contact patches on the {} wheel, more than the {MAX_CONTACTS} an \
                     element keeps",
                    patches.len(),
                    if s.side == 0 { "left" } else { "right" }
                ),
            ));
        }
        for patch in patches {
            let c = Contact {
                wheel_u: patch.wheel_u,
                rail_y: patch.rail_y,
                rail_z: patch.rail_z,
                contact_angle: patch.contact_angle,
                rolling_radius: patch.rolling_radius,
                ..Contact::default()
            };
            let k = self.point_kinematics(s, &c, [0.0; 2])?;
            let elastic = patch.normal_force;
            let normal = (elastic + self.c.normal_damping * k.approach_rate).max(0.0);
            if normal == 0.0 {
                continue;
            }
            let loaded = if normal == elastic {
                patch
            } else {
                scaled(patch, normal / elastic)
            };
            let forces = loaded
                .creep_forces(self.c.shear, self.c.poisson, self.c.mu, &k.creepages)
                .map_err(|e| self.diverged(t, format!("creep forces: {e}")))?;
            let (a, b) = loaded.equivalent_ellipse();
            let cp = self.patch(a, b, normal);
            let delta = loaded.approach;
            let stiffness = if elastic > 0.0 && delta > 0.0 {
                1.5 * elastic / delta
            } else {
                0.0
            };
            let damper_power = (normal - elastic) * k.approach_rate;
            let mut st = self.contact_state(
                &k,
                &cp,
                (normal, stiffness),
                forces,
                (damper_power, 0.4 * elastic * delta),
            )?;
            st.area = loaded.area;
            state.push(s.side, st);
        }
        Ok(())
    }
}

/// `patch` with its strips' pressures and its normal force times `factor`.
fn scaled(mut patch: Patch, factor: f64) -> Patch {
    for st in &mut patch.strips {
        st.pressure *= factor;
    }
    patch.normal_force *= factor;
    patch.max_pressure *= factor;
    patch
}
