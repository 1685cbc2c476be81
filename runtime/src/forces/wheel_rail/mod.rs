//! Wheel–rail contact of one wheelset on the scenario's track (Pogorelov 2005,
//! Sect. 4; docs/design.md "Wheel–rail contact").
//!
//! Per evaluation, for a wheelset body whose track-following frame sits at arc
//! position s:
//!
//! 1. the wheelset's pose relative to the design track frame at s: lateral
//!    shift y, height z, yaw ψ (of the axle about the frame's z) and roll φ
//!    (positive lifts the left wheel); the spin never enters;
//! 2. the rails' deviations at s (irregularities, gauge widening): each rail is
//!    shifted rigidly, laterally by Δyₖ and vertically by Δzₖ, so wheel k sees
//!    the wheelset at lateral shift y − Δyₖ over a nominal rail and its gap
//!    grows by z − r₀ − Δzₖ;
//! 3. the contacts of each wheel from the contact table: the deepest point of
//!    the tread region and of the flange region of the wheel profile
//!    ([`railmbs_wheelrail::geometry::ContactTable::lookup_regions`]), so one-
//!    and two-point contact come out of one continuous description (the
//!    single deepest point jumps at the flange root of S1002 on UIC60, which
//!    would make the forces jump and the integration chatter); the contact
//!    angle is the gap's lateral slope. Vertical penetration p = −gap,
//!    normal approach δ = p cos δ_c (δ_c the contact angle), Hertzian normal
//!    force N = (δ/δ₁)^{3/2} (plus optional damping along the normal, never
//!    pulling);
//! 4. the contact frame: normal n in the track's cross-section plane tilted
//!    by δ_c towards the track centre, rolling direction eₓ = a × n (a the axle
//!    direction), eᵧ = n × eₓ; creepages from the material velocity of the
//!    wheel at the contact point (the rails are at rest) divided by the rolling
//!    speed V = |v·eₓ| of the wheelset centre;
//! 5. the Hertz ellipse and the creep forces by the chosen law; on the wheel:
//!    N n + Fx eₓ + Fy eᵧ at the contact point and the spin moment Mz n.
//!
//! **Elastic rails** (`rail: Elastic(ky, cy, kz, cz)`, Pogorelov 2005, Sect. 4.2):
//! each rail head is massless and moves laterally and vertically, by
//! d = (d_y, d_z) in the track's cross-section, against a spring–damper to
//! ground. At every force evaluation and for each rail,
//! [`railmbs_wheelrail::elastic_rail::solve`] finds d in equilibrium with
//! that wheel's contacts (inner Newton iterations on d for the normal forces,
//! outer iterations for the creep forces; one- and two-point contact): the
//! contacts come from the same table with the wheelset shifted by −d_y over
//! the rail and the gap closed by d_z, and the rail's velocity enters the
//! lateral creepage. The damper's rate is backward Euler,
//! ḋ = (d − d_prev)/(t − t_prev), from the rail displacement d_prev of the
//! latest accepted step before t (the element's state, changed only in
//! [`ForceElement::accept_step`], never inside Newton iterations or by
//! rejected steps); without an accepted step before t (the start of a run)
//! the rails are in static equilibrium. The outer iterations start from the
//! creep forces of that same accepted step
//! ([`railmbs_wheelrail::elastic_rail::solve_from`]), which halves their
//! number without changing the solution. The contact has no damper of its own
//! along the normal then (`normal_damping` must be 0: the rail dampers act
//! in series with the Hertz spring). The Jacobian uses the Hertz stiffness in
//! series with the support's K + C/h along the normal. Outputs per rail:
//! `L.rail_dy`, `L.rail_dz` (m, track frame, +y left, +z up).
//!
//! **Independently rotating wheels** (`wheels: Some(("WheelL", "WheelR"))`):
//! each wheel is its own body turning on the axle (the `wheelset` body, which
//! then has no spin). The contact geometry still follows the axle's pose;
//! each wheel's contact forces act on its own body and its creepages come
//! from that body's velocity and angular velocity, so each wheel rolls at its
//! own speed and no longitudinal creep couples the two.
//!
//! **Conicity override** (the classical quasi-linear analysis: modes and
//! linear critical speed as a function of the equivalent conicity λ,
//! `umsim modes --conicity`; [`TrackBinding::conicity`]): the contact table
//! is looked up at the lateral shift y' = s y instead of y, with
//! s = λ / λ₀ and λ₀ the table's own central conicity
//! ([`railmbs_wheelrail::geometry::ContactTable::central_conicity`]: ½ dΔr/dy
//! of the exact rigid contact at the centre, over the table's nodes at
//! ±dy, the roll following; the small-amplitude limit of EN 15302's
//! equivalent conicity), and each contact's rail point is moved
//! by y − y' so that it lies, relative to the wheelset, where the profiles'
//! contact at y' lies. Every derivative of the contact geometry with
//! respect to the shift is then the profiles' times s: the rolling radius
//! difference's slope is 2λ, and the contact angles' slope (the
//! gravitational stiffness, the spin's change), the roll that follows the
//! shift and the contacts' travel across the wheel are scaled alike; the
//! centred values (contact angle δ₀, rolling radius r₀, contact distance
//! 2e, the Hertz ellipses and Kalker's coefficients) are the profiles'.
//! So Wickens' contact parameters keep their real ratios to λ (ε/λ for the
//! contact angles, σ/λ for the roll; Wickens 1965, "The dynamic stability
//! of railway vehicle wheelsets and bogies having profiled wheels", Int.
//! J. Solids Struct. 1). Why this and not the cone (constant contact angle,
//! no gravitational stiffness): for circular-arc profiles (wheel radius
//! R_w, rail R_r) a shift y turns the line of the profiles' centres by
//! y/(R_w − R_r), so λ ≈ δ₀ R_w/(R_w − R_r) and the contact angle's slope
//! 1/(R_w − R_r) both grow with the conformity, the way wear raises the
//! conicity (Polach & Nicklisch, "Wheel/rail contact geometry parameters in
//! regard to vehicle behaviour and their alteration with wear", Wear 2016);
//! the cone drops the gravitational stiffness that, less the spin's part,
//! sets the wheelset's critical speed (tests/tests/integration/wickens.rs:
//! without it the critical speed is 24 % off). The simplifications: that
//! family's roll follows the shift at ≈ tan δ₀/e rather than scaled (the
//! roll rate adds r₀ φ̇/V, about 1.5 % of the lateral creepage); and the
//! gap changes s times faster with the shift than the (unscaled) contact
//! angle's tangent says, which makes the normal force non-conservative by
//! (s − 1) N sin δ₀ per unit of tan δ₀ in the stiff vertical–lateral coupling of the contact
//! (the fast contact modes; the quasi-static lateral stiffness is the
//! profiles' times s, as above). For linear analyses: large shifts reach
//! the table's edge or the flange s times sooner.
//!
//! The rails' reactions go to ground (the track is not a body of the model).
//! Outputs per wheel follow the usual assessment conventions: Q the vertical
//! wheel load and Y the lateral force of the wheel on the rail, positive
//! towards the field side, both in the track frame; ΣY the track-shifting force
//! of the wheelset (lateral force on the track, positive to the left).
//!
//! The element's code, by topic: `preparation.rs` (constants, binding to the
//! track, profiles and contact tables), `kinematics.rs` (wheelset pose,
//! contact geometry and creepages), `solve.rs` (the contact solve at one
//! state, rigid rails), `elastic.rs` (the elastic rails' solve),
//! `assessment.rs` (outputs, wheel loads and their limits); here the element
//! itself, its elastic rails' state (the accepted steps' rail displacements)
//! and its [`ForceElement`] implementation.

mod assessment;
mod elastic;
mod kinematics;
mod non_elliptic;
mod preparation;
mod solve;
mod table_cache;

pub use assessment::{nadal_limit, prudhomme_limit};
pub use kinematics::MIN_ROLLING_SPEED;
pub use preparation::{ContactTableCache, PreparedContact, TrackBinding};

use super::{ForceContext, ForceElement, ForceJacobian, Wrench, add_force, add_moment};
use crate::equations::BodyKinematics;
use crate::system::SimError;
use preparation::{Bound, Constants};
use railmbs_models::WheelRail;
use railmbs_wheelrail::elastic_rail::CreepStart;
use railmbs_wheelrail::hertz::HertzShape;
use solve::WheelsetState;

/// The elastic rails at an accepted step: time (s), displacements (left,
/// right; (d_y, d_z) each, m) and creep forces.
type RailRecord = (f64, [[f64; 2]; 2], [CreepStart; 2]);

/// The wheel–rail element of one wheelset.
pub struct WheelRailContact {
    name: String,
    spec: WheelRail,
    c: Constants,
    bound: Option<Bound>,
    /// The last solved state and what it was solved for (time and the
    /// wheelset's kinematics): the accept-step hook, the outputs and the
    /// Jacobian usually ask again for the state the last force evaluation
    /// saw, and the contact solution is the costly part of a step.
    /// The kinematics are the wheelset's and each wheel's body's (the same
    /// body thrice for a solid wheelset).
    last: std::sync::Mutex<Option<(f64, [BodyKinematics; 3], WheelsetState)>>,
    /// The time (its bits), arc position and design track frame of the
    /// wheelset's track-following frame last asked for (see
    /// `design_frame`); cleared when the track is bound.
    frame_at: std::sync::Mutex<Option<(u64, f64, railmbs_track::TrackFrame)>>,
    /// Elastic rails: the rails at the last accepted step. Only
    /// [`ForceElement::accept_step`] changes it; every evaluation until the
    /// next accepted step (Newton iterations, Jacobians, the output rows of
    /// the step, which the runner evaluates before accepting it) starts from
    /// it.
    rail_accepted: Option<RailRecord>,
    /// A valid Hertz shape for contacts without load (elastic rails).
    placeholder_shape: Option<HertzShape>,
}

impl std::fmt::Debug for WheelRailContact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WheelRailContact")
            .field("name", &self.name)
            .field("wheelset", &self.spec.wheelset)
            .field("bound", &self.bound.is_some())
            .finish()
    }
}

impl WheelRailContact {
    /// The element named `name` from the model's wheel–rail spec. Nothing
    /// is evaluated or checked here: the constants come with
    /// [`ForceElement::set_parameters`] and the contact table (from the
    /// profiles the model holds, read when it was loaded) with
    /// [`ForceElement::bind_track`], which report errors.
    pub fn new(name: String, spec: &WheelRail) -> Self {
        Self {
            name,
            spec: spec.clone(),
            c: Constants::default(),
            bound: None,
            last: std::sync::Mutex::new(None),
            frame_at: std::sync::Mutex::new(None),
            rail_accepted: None,
            placeholder_shape: HertzShape::with_modulus(1.0, 1.0, 1.0).ok(),
        }
    }

    fn err(&self, message: impl std::fmt::Display) -> SimError {
        SimError::Other(format!("wheel–rail element \"{}\": {message}", self.name))
    }

    fn diverged(&self, t: f64, message: impl std::fmt::Display) -> SimError {
        SimError::Diverged {
            t,
            reason: format!("wheel–rail element \"{}\": {message}", self.name),
        }
    }

    /// The body carrying wheel `side` (0 left, 1 right): the wheel's own body
    /// for independently rotating wheels, else the wheelset.
    fn wheel_body(&self, side: usize) -> usize {
        self.spec.wheels.map_or(self.spec.wheelset, |w| w[side])
    }

    /// Where the backward-Euler rate of the elastic rails starts from at time
    /// `t` (s): (h, d_prev, creep) with d_prev the rails' displacements (left,
    /// right; (d_y, d_z) each, m) at the last accepted step, h the time since
    /// it (s) and the creep forces there (where the outer iterations start).
    /// At the accepted time itself or before any accepted step (the start of
    /// a run) the rails are in static equilibrium: h = ∞.
    fn rail_reference(&self, t: f64) -> (f64, [[f64; 2]; 2], [CreepStart; 2]) {
        match self.rail_accepted {
            Some((tr, d, creep)) if tr < t => (t - tr, d, creep),
            accepted => {
                let (_, d, creep) = accepted.unwrap_or_default();
                (f64::INFINITY, d, creep)
            }
        }
    }
}

impl ForceElement for WheelRailContact {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        let c = self.constants(params)?;
        // The contact table is built from these when the track is bound.
        let geometry = |c: &Constants| (c.radius, c.flange_back_distance, c.taping_offset);
        if self.bound.is_some() && geometry(&c) != geometry(&self.c) {
            return Err(self.err(
                "the wheel radius, back-to-back distance and taping line are fixed once the \
                 contact table is built (at the start of the run)",
            ));
        }
        self.c = c;
        *self.last.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        *self.frame_at.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        self.rail_accepted = None;
        Ok(())
    }

    fn needs_track(&self) -> bool {
        true
    }

    fn rigid_contact(&self) -> Option<(f64, Vec<railmbs_wheelrail::geometry::RigidContact>)> {
        let b = self.bound.as_ref()?;
        // With a conicity override the table is looked up at s·y.
        let rigid = b.contact.table.rigid_functions();
        Some((
            b.contact.nominal_radius,
            rigid
                .iter()
                .map(|r| railmbs_wheelrail::geometry::RigidContact {
                    y: r.y / b.shift_scale,
                    ..*r
                })
                .collect(),
        ))
    }

    fn bind_track(&mut self, binding: &TrackBinding) -> Result<(), SimError> {
        self.bound = Some(self.bind(binding)?);
        *self.frame_at.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        *self.last.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        self.solved(ctx, |state| {
            for side in 0..2 {
                let body = Some(self.wheel_body(side));
                for c in state.side(side) {
                    add_force(wrenches, ctx, body, &c.point, &c.force());
                    add_moment(wrenches, body, &(c.n * c.forces.mz));
                }
            }
        })
    }

    fn output_names(&self) -> Vec<String> {
        self.output_columns()
    }

    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        self.write_outputs(ctx, out);
    }

    fn assessment_loads(&self, ctx: &ForceContext) -> Option<super::WheelLoads> {
        self.wheel_loads_at(ctx)
    }

    fn remembers_accepted_steps(&self) -> bool {
        // Elastic rails start their damper rate from the accepted step.
        self.c.rail.is_some()
    }

    fn accept_step(&mut self, ctx: &ForceContext) -> Result<(), SimError> {
        let (rail_d, rail_creep) = self.solved(ctx, |state| (state.rail_d, state.rail_creep))?;
        // Elastic rails: this step's rail displacements become the start of
        // the next step's damper rate (never changed inside Newton
        // iterations or by rejected steps).
        if self.c.rail.is_some() {
            self.rail_accepted = Some((ctx.t, rail_d, rail_creep));
        }
        Ok(())
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        self.add_contact_jacobian(ctx, jac)
    }
}
