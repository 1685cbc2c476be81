//! The contact solve at one state: both wheels' contacts on rigid rails
//! (Hertzian normal force from the approach, creep forces by the law), the
//! elastic rails' solve called per side, and the last solution kept for the
//! outputs, the Jacobian and the accepted step that ask for the same state.

use super::WheelRailContact;
use super::kinematics::{ContactKinematics, PointKinematics};
use crate::forces::{ForceContext, ForceJacobian};
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_wheelrail::creep::{ContactMode, ContactPatch, CreepForces, Creepages};
use railmbs_wheelrail::elastic_rail::CreepStart;
use railmbs_wheelrail::kalker::KalkerCoefficients;

/// One solved contact.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ContactState {
    /// Point of application (on the rail surface), SC0, m.
    pub(super) point: Vector3<f64>,
    /// Contact frame in SC0.
    pub(super) ex: Vector3<f64>,
    pub(super) ey: Vector3<f64>,
    pub(super) n: Vector3<f64>,
    /// Normal force, N.
    pub(super) normal: f64,
    /// dN/dδ, N/m.
    pub(super) normal_stiffness: f64,
    pub(super) creepages: Creepages,
    pub(super) forces: CreepForces,
    /// Linear creep coefficients f11 = G a b C11, f22 = G a b C22 (N), times the
    /// saturation ratio (|F| / linear |F|, ≤ 1), for the Jacobian.
    pub(super) f11: f64,
    pub(super) f22: f64,
    /// Rolling speed, m/s.
    pub(super) speed: f64,
    /// Contact angle, rad; lateral position of the contact on the rail (track
    /// frame, m).
    pub(super) angle: f64,
    pub(super) rail_y: f64,
    /// Rolling radius of the wheel at the contact, m.
    pub(super) rolling_radius: f64,
    /// Power dissipated at the contact, W: the creep forces against the
    /// creepages, −V (F_x ξ + F_y η + M_z φ) (the forces act on the wheel and
    /// oppose the slip), plus the normal damper's force times the approach
    /// rate (rigid rails).
    pub(super) dissipation: f64,
    /// Elastic energy of the Hertz contact, (2/5) N δ (N ∝ δ^{3/2}), J.
    pub(super) elastic_energy: f64,
    /// Area of the contact patch, m² (π a b for a Hertz ellipse).
    pub(super) area: f64,
}

/// Most contacts (patches) of one wheel an element keeps: two for Hertz (the
/// tread and flange regions), any up to this many for the non-elliptic
/// contact.
pub(super) const MAX_CONTACTS: usize = 4;

impl ContactState {
    /// Total force on the wheel, SC0, N.
    pub(super) fn force(&self) -> Vector3<f64> {
        self.n * self.normal + self.ex * self.forces.fx + self.ey * self.forces.fy
    }
}

/// Both wheels at one state.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct WheelsetState {
    /// Per side (left, right): contacts (up to [`MAX_CONTACTS`]) and how many.
    pub(super) contacts: [[ContactState; MAX_CONTACTS]; 2],
    pub(super) count: [usize; 2],
    /// Track frame axes in SC0 (columns x, y, z).
    pub(super) track_axes: Matrix3<f64>,
    /// Elastic rails: per rail (left, right) the displacement (d_y, d_z), m,
    /// in the track frame; zero for rigid rails.
    pub(super) rail_d: [[f64; 2]; 2],
    /// Elastic rails: per rail the creep forces the rail's outer iterations
    /// converged to (where the next step's iterations start).
    pub(super) rail_creep: [CreepStart; 2],
}

impl WheelsetState {
    /// The contacts of side 0 (left) or 1 (right).
    pub(super) fn side(&self, side: usize) -> &[ContactState] {
        &self.contacts[side][..self.count[side]]
    }

    /// Adds a loaded contact to side 0 (left) or 1 (right).
    pub(super) fn push(&mut self, side: usize, contact: ContactState) {
        self.contacts[side][self.count[side]] = contact;
        self.count[side] += 1;
    }
}

impl WheelRailContact {
    /// `f` of [`Self::solve_new`]'s result, or of the stored result for the
    /// same time and wheelset kinematics (the axle's and, for independently
    /// rotating wheels, the wheels', whose spin alone changes the creep
    /// forces). `f` sees the stored state in place: the state (about 1 kB)
    /// is not copied out for every force, output and Jacobian call.
    pub(super) fn solved<R>(
        &self,
        ctx: &ForceContext,
        f: impl FnOnce(&WheelsetState) -> R,
    ) -> Result<R, SimError> {
        let body = [
            ctx.bodies[self.spec.wheelset],
            ctx.bodies[self.wheel_body(0)],
            ctx.bodies[self.wheel_body(1)],
        ];
        let Ok(mut last) = self.last.lock() else {
            let mut state = WheelsetState::default();
            self.solve_into(ctx, &mut state)?;
            return Ok(f(&state));
        };
        if let Some((t, k, state)) = last.as_ref()
            && *t == ctx.t
            && *k == body
        {
            return Ok(f(state));
        }
        // Solved in the kept slot itself (no copy of the state), marked as
        // solved for no time (NaN) until the solve has succeeded.
        let (t, k, state) = last.get_or_insert_with(|| (f64::NAN, body, WheelsetState::default()));
        *t = f64::NAN;
        self.solve_into(ctx, state)?;
        (*t, *k) = (ctx.t, body);
        Ok(f(state))
    }

    /// Solves both wheels' contacts at the context's state into `state`
    /// (whatever it held before).
    fn solve_into(&self, ctx: &ForceContext, state: &mut WheelsetState) -> Result<(), SimError> {
        let Some(b) = &self.bound else {
            return Err(self.err(
                "no track: a wheel–rail element needs the scenario's track (`track: (file: …)`)",
            ));
        };
        let t = ctx.t;
        let sides = self.sides(ctx, b)?;
        state.count = [0; 2];
        state.track_axes = sides[0].axes;
        state.rail_d = Default::default();
        state.rail_creep = Default::default();
        match self.c.rail {
            None if self.c.non_elliptic.is_some() => {
                for geo in &sides {
                    self.solve_non_elliptic_side(geo, state)?;
                }
            }
            None => {
                let sets = [self.lookup(&sides[0], 0.0)?, self.lookup(&sides[1], 0.0)?];
                for (side, geo) in sides.iter().enumerate() {
                    // Normal forces of both contacts first: whether the wheel
                    // is in two-point contact decides the flange contact's
                    // creep law (ContactMode).
                    let mut loaded: [Option<(ContactKinematics, f64, f64)>; 2] = [None, None];
                    for (slot, c) in loaded.iter_mut().zip(&sets[side]) {
                        let Some(k) = self.kinematics(geo, c, [0.0; 2])? else {
                            continue;
                        };
                        let elastic = k
                            .shape
                            .normal_force(k.approach)
                            .map_err(|e| self.diverged(t, format!("Hertz: {e}")))?;
                        let normal = (elastic + self.c.normal_damping * k.approach_rate).max(0.0);
                        if normal == 0.0 {
                            continue;
                        }
                        *slot = Some((k, elastic, normal));
                    }
                    let angle = |i: usize| loaded[i].as_ref().map_or(0.0, |(k, ..)| k.angle);
                    let modes = ContactMode::of_wheel(
                        [angle(0), angle(1)],
                        [loaded[0].is_some(), loaded[1].is_some()],
                    );
                    for (slot, mode) in loaded.iter().zip(modes) {
                        let Some((k, elastic, normal)) = slot else {
                            continue;
                        };
                        let (elastic, normal) = (*elastic, *normal);
                        let stiffness = if elastic > 0.0 {
                            k.shape.stiffness(k.approach)
                        } else {
                            0.0
                        };
                        let hertz = k
                            .shape
                            .contact(normal)
                            .map_err(|e| self.diverged(t, format!("Hertz: {e}")))?;
                        let patch = self.patch(hertz.a, hertz.b, normal);
                        let forces = b
                            .law
                            .forces_in_contact(&patch, &k.creepages, k.speed, mode)
                            .map_err(|e| self.diverged(t, format!("creep forces: {e}")))?;
                        let damper_power = (normal - elastic) * k.approach_rate;
                        let st = self.contact_state(
                            k,
                            &patch,
                            (normal, stiffness),
                            forces,
                            (damper_power, 0.4 * elastic * k.approach),
                        )?;
                        state.push(side, st);
                    }
                }
            }
            Some(support) => {
                let (h, d_prev, creep) = self.rail_reference(t);
                for (side, geo) in sides.iter().enumerate() {
                    let start = (h, d_prev[side], &creep[side]);
                    self.solve_elastic_side(geo, &support, start, state)?;
                }
            }
        }
        Ok(())
    }

    /// The contact patch for the creep law: semi-axes `a`, `b` (m), normal
    /// force `n` (N).
    pub(super) fn patch(&self, a: f64, b: f64, n: f64) -> ContactPatch {
        ContactPatch {
            a,
            b,
            g: self.c.shear,
            nu: self.c.poisson,
            mu: self.c.mu,
            n,
        }
    }

    /// The solved contact: normal force `normal` (N) with dN/dδ `stiffness`
    /// (N/m) and the creep forces.
    pub(super) fn contact_state(
        &self,
        k: &PointKinematics,
        patch: &ContactPatch,
        (normal, stiffness): (f64, f64),
        forces: CreepForces,
        (damper_power, elastic_energy): (f64, f64),
    ) -> Result<ContactState, SimError> {
        // Linear creep coefficients (Kalker), scaled by the saturation of the
        // actual forces, for the approximate Jacobian (Pogorelov 2005, Sect. 6).
        let (f11, f22) = KalkerCoefficients::saturated_slopes(
            patch.a,
            patch.b,
            self.c.shear,
            self.c.poisson,
            k.creepages.xi,
            k.creepages.eta,
            forces.fx,
            forces.fy,
        )
        .ok_or_else(|| self.err("Poisson ratio outside Kalker's table"))?;
        Ok(ContactState {
            point: k.point,
            ex: k.ex,
            ey: k.ey,
            n: k.n,
            normal,
            normal_stiffness: stiffness * k.cos_angle,
            creepages: k.creepages,
            forces,
            f11,
            f22,
            speed: k.speed,
            angle: k.angle,
            rail_y: k.rail_y,
            rolling_radius: k.rolling_radius,
            dissipation: -k.speed
                * (forces.fx * k.creepages.xi
                    + forces.fy * k.creepages.eta
                    + forces.mz * k.creepages.phi)
                + damper_power,
            elastic_energy,
            area: std::f64::consts::PI * patch.a * patch.b,
        })
    }

    /// Adds the solved contacts' approximate stiffness and damping (Pogorelov
    /// 2005, Sect. 6) at the context's state to `jac`: the Hertz stiffness
    /// along the normal, the linear creep coefficients over the rolling speed
    /// along the rolling and lateral directions, the normal damper.
    pub(super) fn add_contact_jacobian(
        &self,
        ctx: &ForceContext,
        jac: &mut ForceJacobian,
    ) -> Result<(), SimError> {
        self.solved(ctx, |state| {
            for side in 0..2 {
                for c in state.side(side) {
                    // f = N n + Fx eₓ + Fy eᵧ on the wheel at the contact point;
                    // d = wheel point − rail point (at rest): ∂N/∂d = −k n,
                    // ∂F/∂ḋ ≈ −(f11/V) eₓeₓᵀ − (f22/V) eᵧeᵧᵀ − c_n nnᵀ.
                    let nn = c.n * c.n.transpose();
                    let kq = -c.normal_stiffness * nn;
                    let kv = -(c.f11 / c.speed) * (c.ex * c.ex.transpose())
                        - (c.f22 / c.speed) * (c.ey * c.ey.transpose())
                        - self.c.normal_damping * nn;
                    jac.add_point_pair(
                        None,
                        &c.point,
                        Some(self.wheel_body(side)),
                        &c.point,
                        &kq,
                        &kv,
                    );
                }
            }
        })
    }
}
