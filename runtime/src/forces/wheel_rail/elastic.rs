//! The massless elastic rails (Pogorelov 2005, Sect. 4.2): one side's rail
//! displacement and contact forces in equilibrium, solved by
//! [`railmbs_wheelrail::elastic_rail::solve_from`] over the contact table's
//! geometry ([`TableRail`]). Where the backward-Euler rate starts from (the
//! rails at the latest accepted step) is the element's state, kept in
//! `mod.rs` with [`crate::forces::ForceElement::accept_step`].

use super::WheelRailContact;
use super::kinematics::Side;
use super::solve::WheelsetState;
use crate::system::SimError;
use railmbs_wheelrail::creep::Creepages;
use railmbs_wheelrail::elastic_rail::{
    self, ContactMaterial, CreepStart, ElasticRailError, ElasticRailSettings, RailContact,
    RailContactGeometry, RailSupport,
};

/// The contact geometry of one wheel on its elastic rail for
/// [`elastic_rail::solve`]: the table's region contacts with the wheelset
/// shifted by −d_y over the rail and the gap closed by d_z.
struct TableRail<'a> {
    el: &'a WheelRailContact,
    s: &'a Side<'a>,
}

impl RailContactGeometry for TableRail<'_> {
    fn contacts_at(
        &self,
        d: [f64; 2],
        out: &mut [RailContact; elastic_rail::MAX_CONTACTS],
    ) -> Result<usize, ElasticRailError> {
        let geo = |e: SimError| ElasticRailError::Geometry {
            index: 0,
            what: e.to_string(),
        };
        let slots = self.el.lookup(self.s, d[0]).map_err(geo)?;
        for (o, c) in out.iter_mut().zip(&slots) {
            *o = match self.el.kinematics(self.s, c, d).map_err(geo)? {
                Some(k) => RailContact {
                    approach: k.approach,
                    normal: k.normal_2d,
                    hertz: k.shape,
                    creepages: k.creepages,
                },
                // Open (or a boundary point without load): no force; any
                // valid shape will do.
                None => {
                    let (sd, cd) = c.contact_angle.sin_cos();
                    RailContact {
                        approach: 0.0,
                        normal: [-self.s.sign * sd, cd],
                        hertz: self.el.placeholder_shape.ok_or_else(|| {
                            ElasticRailError::Parameter("no Hertz shape for an open contact".into())
                        })?,
                        creepages: Creepages::default(),
                    }
                }
            };
        }
        Ok(2)
    }
}

impl WheelRailContact {
    /// One side on its massless elastic rail (Pogorelov 2005, Sect. 4.2, via
    /// [`elastic_rail::solve_from`]): the rail displacement and the normal
    /// and creep forces in equilibrium, written into `state`; `start` is
    /// (h, d_prev, creep) of [`Self::rail_reference`] for this rail.
    pub(super) fn solve_elastic_side(
        &self,
        s: &Side,
        support: &RailSupport,
        start: (f64, [f64; 2], &CreepStart),
        state: &mut WheelsetState,
    ) -> Result<(), SimError> {
        let (h, d_prev, creep_start) = start;
        let t = s.ctx.t;
        let material = ContactMaterial {
            g: self.c.shear,
            nu: self.c.poisson,
            mu: self.c.mu,
        };
        let settings = ElasticRailSettings {
            h,
            v_roll: s.speed,
            // 1 µN against wheel loads of tens of kN: what the integrator
            // resolves at tolerances down to 1e-14 m against the 1e8 N/m
            // support (the solver raises it to the rounding of its terms on
            // tiny steps).
            force_tol: 1e-6,
            rel_tol: 1e-8,
            max_inner: 50,
            max_outer: 200,
        };
        let side_name = ["left", "right"][s.side];
        let sol = elastic_rail::solve_from(
            support,
            &material,
            &TableRail { el: self, s },
            s.b.law.as_ref(),
            d_prev,
            creep_start,
            &settings,
        )
        .map_err(|e| self.diverged(t, format!("{side_name} rail: {e}")))?;
        let d = sol.displacement;
        // The support's effective stiffness over the step, K + C/h (the
        // backward-Euler damper; the lateral one where it acted).
        let cy = if sol.lateral_damped { support.cy } else { 0.0 };
        let keff = if h.is_finite() {
            [support.ky + cy / h, support.kz + support.cz / h]
        } else {
            [support.ky, support.kz]
        };
        state.rail_d[s.side] = d;
        state.rail_creep[s.side] = CreepStart {
            forces: sol.contacts.map(|c| c.creep),
            slope: sol.contacts.map(|c| c.lateral_slope),
        };
        let slots = self.lookup(s, d[0])?;
        for (i, c) in slots.iter().enumerate().take(sol.n_contacts) {
            let r = &sol.contacts[i];
            if r.normal_force <= 0.0 {
                continue;
            }
            let Some(mut k) = self.kinematics(s, c, d)? else {
                continue;
            };
            // The rail's own velocity in the lateral creepage, as the solver
            // used it: Δη = −(ḋ·t)/V, t = (n_z, −n_y) in the cross-section.
            let [ny, nz] = r.normal;
            k.creepages.eta -= (sol.velocity[0] * nz - sol.velocity[1] * ny) / s.speed;
            // Hertz spring in series with the rail support along the normal:
            // 1/k = 1/k_H + nᵀ K_eff⁻¹ n.
            let k_hertz = k.shape.stiffness(r.approach);
            let compliance = ny * ny / keff[0] + nz * nz / keff[1];
            let stiffness = if k_hertz > 0.0 {
                k_hertz / (1.0 + k_hertz * compliance)
            } else {
                0.0
            };
            let patch = self.patch(r.a, r.b, r.normal_force);
            // The rail supports' dampers are not counted in the contact's
            // dissipation (they act between rail and ground).
            let st = self.contact_state(
                &k,
                &patch,
                (r.normal_force, stiffness),
                r.creep,
                (0.0, 0.4 * r.normal_force * r.approach),
            )?;
            state.push(s.side, st);
        }
        Ok(())
    }
}
