//! Point–plane contact with Coulomb friction (Pogorelov 2005, Sect. 3.3).
//!
//! Points fixed to one body touch a plane fixed to another body (or the
//! ground). For a point P, the plane through O with outward unit normal n
//! (both moving with the plane's body), the penetration is δ = −n·(P − O) and
//! its rate δ̇ = −n·v_r, v_r the velocity of P relative to the plane's point
//! under P. While δ > 0:
//!
//! * normal force N = max(0, c δ + d δ̇) along n: viscoelastic, no adhesion;
//! * tangential force, Coulomb friction:
//!   - sticking: P is tied to an anchor point A fixed in the plane by a
//!     spring–damper, F_t = −(c_t s_t + d_t v_t) with s_t, v_t the tangential
//!     parts of P − A and v_r, as long as |F_t| ≤ μ0 N;
//!   - sliding: F_t = −μ N v_t/|v_t| (the direction regularized below
//!     [`V_REG`]).
//!
//! The mode and anchor of each point change only in
//! [`ForceElement::accept_step`] (never during Newton iterations or rejected
//! steps), as for the bipolar friction elements ([`super::nonlinear`]): a
//! sticking point whose trial force exceeds μ0 N is held at the limit μ0 N for
//! the rest of the step and slides from the next one; a sliding point whose
//! tangential velocity has reversed or fallen below [`V_STICK`] at the end of a
//! step sticks again, with the anchor placed so that the sticking force equals
//! the sliding force it replaces. A point that comes into contact starts
//! sliding (sticking at once if its tangential speed is below `V_STICK`).

use super::nonlinear::{V_REG, V_STICK};
use super::{
    Attachment, ForceContext, ForceElement, ForceJacobian, PairMatrix, Wrench, add_force,
    eval_scalar, eval_vector, point_twist_map,
};
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{BodyRef, Expr};

/// Normal stiffness c (N/m) and damping d (N s/m) that make a mass m (kg)
/// resting on a linear contact vibrate at `frequency` (Hz) with the damping
/// ratio ζ: c = 4π² f² m, d = 2ζ √(m c).
///
/// # Errors
/// When f or m is not positive and finite, or ζ is negative or not finite.
pub fn contact_stiffness_damping(
    frequency: f64,
    damping_ratio: f64,
    mass: f64,
) -> Result<(f64, f64), SimError> {
    if !(frequency > 0.0 && frequency.is_finite()) {
        return Err(SimError::Other(format!(
            "contact frequency must be positive and finite, got {frequency} Hz"
        )));
    }
    if !(mass > 0.0 && mass.is_finite()) {
        return Err(SimError::Other(format!(
            "contact mass must be positive and finite, got {mass} kg"
        )));
    }
    if !(damping_ratio >= 0.0 && damping_ratio.is_finite()) {
        return Err(SimError::Other(format!(
            "contact damping ratio must be non-negative and finite, got {damping_ratio}"
        )));
    }
    let c = 4.0 * std::f64::consts::PI.powi(2) * frequency * frequency * mass;
    Ok((c, 2.0 * damping_ratio * (mass * c).sqrt()))
}

/// State of one contact point (changes only in `accept_step`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactMode {
    /// Not in contact at the last accepted step.
    Free,
    /// Sticking to the anchor, given in the plane body's frame (m).
    Stick {
        /// Anchor point in the plane body's frame, m.
        anchor: Vector3<f64>,
    },
    /// Sliding; `dir` the unit sliding direction (SC0) at the last accepted
    /// step; `established` once the sliding speed has reached [`V_STICK`].
    Slide {
        /// Unit sliding direction in SC0 (dimensionless).
        dir: Vector3<f64>,
        /// Whether the sliding speed has reached [`V_STICK`].
        established: bool,
    },
}

/// Point–plane contact of any number of points; see the module docs.
#[derive(Debug, Clone)]
pub struct PointPlane {
    name: String,
    points: Vec<Attachment>,
    plane_body: Option<usize>,
    origin_expr: [Expr; 3],
    normal_expr: [Expr; 3],
    /// Point–Z-surface variant: the height f(x, y) and its slopes f_x, f_y
    /// (expressions in the local variables x, y and the parameters).
    surface: Option<[Expr; 3]>,
    coeff_expr: [Expr; 6],
    /// Plane point and unit normal in the plane body's frame.
    origin: Vector3<f64>,
    normal: Vector3<f64>,
    /// Normal stiffness, N/m.
    pub c: f64,
    /// Normal damping, N s/m: the normal force is
    /// max(0, c δ + d δ̇) with δ the penetration (m).
    pub d: f64,
    /// Tangential stiffness of the sticking anchor, N/m.
    pub ct: f64,
    /// Tangential damping of the sticking anchor, N s/m.
    pub dt: f64,
    /// Static friction coefficient (dimensionless): the sticking anchor
    /// holds while its force is at most μ_static times the normal force.
    pub mu_static: f64,
    /// Sliding friction coefficient (dimensionless): the tangential force
    /// while sliding is μ times the normal force.
    pub mu: f64,
    /// One per point.
    pub modes: Vec<ContactMode>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tangential {
    Stick,
    /// Trial sticking force beyond μ0 N, held at the limit: unit direction.
    Saturated(Vector3<f64>),
    /// Sliding: regularized unit velocity direction, |v_t|.
    Slide(Vector3<f64>, f64),
}

/// Everything about one point in contact at a state.
struct PointEval {
    p: Vector3<f64>,
    n: Vector3<f64>,
    /// Penetration, m.
    delta: f64,
    /// Its rate δ̇ = −n·v_r, m/s.
    delta_rate: f64,
    /// N.
    normal_force: f64,
    /// Tangential force on the point's body, N (SC0).
    ft: Vector3<f64>,
    /// Trial sticking force (Stick mode), N.
    trial: Vector3<f64>,
    /// Tangential relative velocity, m/s.
    vt: Vector3<f64>,
    branch: Tangential,
}

impl PointPlane {
    /// From the model's `PointPlane` spec (`railmbs_models::forces::PointPlane`).
    pub fn new(name: String, spec: &railmbs_models::forces::PointPlane) -> Self {
        let railmbs_models::forces::PointPlane {
            body,
            points,
            plane_body,
            origin,
            normal,
            surface,
            stiffness,
            damping,
            tangential_stiffness,
            tangential_damping,
            mu_static,
            mu,
        } = spec;
        Self {
            name,
            points: points.iter().map(|p| Attachment::new(*body, p)).collect(),
            plane_body: match plane_body {
                BodyRef::Ground => None,
                BodyRef::Body(i) => Some(*i),
            },
            origin_expr: origin.clone(),
            normal_expr: normal.clone(),
            surface: surface
                .as_ref()
                .map(|f| [f.clone(), f.var_derivative(0), f.var_derivative(1)]),
            coeff_expr: [
                stiffness.clone(),
                damping.clone(),
                tangential_stiffness.clone(),
                tangential_damping.clone(),
                mu_static.clone(),
                mu.clone(),
            ],
            origin: Vector3::zeros(),
            normal: Vector3::z(),
            c: 0.0,
            d: 0.0,
            ct: 0.0,
            dt: 0.0,
            mu_static: 0.0,
            mu: 0.0,
            modes: vec![ContactMode::Free; points.len()],
        }
    }

    /// Plane point, normal, rotation and kinematics helpers in SC0.
    fn plane(&self, ctx: &ForceContext) -> (Vector3<f64>, Vector3<f64>, Matrix3<f64>) {
        match self.plane_body {
            Some(b) => {
                let k = &ctx.bodies[b];
                (
                    k.point_position(&self.origin),
                    k.rotation * self.normal,
                    k.rotation,
                )
            }
            None => (self.origin, self.normal, Matrix3::identity()),
        }
    }

    fn plane_velocity(&self, ctx: &ForceContext, p: &Vector3<f64>) -> Vector3<f64> {
        match self.plane_body {
            Some(b) => {
                let k = &ctx.bodies[b];
                k.velocity + k.angular_velocity.cross(&(p - k.position))
            }
            None => Vector3::zeros(),
        }
    }

    /// Anchor (plane frame) to SC0 and back.
    fn to_world(&self, ctx: &ForceContext, a: &Vector3<f64>) -> Vector3<f64> {
        match self.plane_body {
            Some(b) => ctx.bodies[b].point_position(a),
            None => *a,
        }
    }

    fn to_plane(&self, ctx: &ForceContext, p: &Vector3<f64>) -> Vector3<f64> {
        match self.plane_body {
            Some(b) => ctx.bodies[b].rotation.transpose() * (p - ctx.bodies[b].position),
            None => *p,
        }
    }

    /// The plane the point `p` (SC0) touches: a point of it and its unit
    /// outward normal (SC0). For a Z-surface, the tangent plane at the
    /// surface point above or below p: with (x, y, z) the position of p in the
    /// surface frame (plane body's frame shifted to `origin`), the surface
    /// point (x, y, f(x, y)) and the normal (−f_x, −f_y, 1)/√(1 + f_x² + f_y²).
    /// The penetration −n·(p − o) = (f − z)/√(1 + f_x² + f_y²) is then the
    /// distance to the tangent plane: exact for planar surfaces, to second
    /// order in the slope change over the gap for curved ones.
    fn contact_plane(&self, ctx: &ForceContext, p: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let Some([f, fx, fy]) = &self.surface else {
            let (o, n, _) = self.plane(ctx);
            return (o, n);
        };
        let local = self.to_plane(ctx, p) - self.origin;
        let xy = [local.x, local.y];
        let z = f.eval_vars(ctx.params, ctx.t, &xy);
        // A slope undefined where the height is defined is a kink (abs at 0,
        // whose derivative x/|x| is 0/0 there): it counts as zero, the mean of
        // a symmetric kink's two sides.
        let slope = |e: &Expr| {
            let v = e.eval_vars(ctx.params, ctx.t, &xy);
            if v.is_finite() { v } else { 0.0 }
        };
        let (sx, sy) = (slope(fx), slope(fy));
        let n_local = Vector3::new(-sx, -sy, 1.0).normalize();
        let o_local = self.origin + Vector3::new(local.x, local.y, z);
        match self.plane_body {
            Some(b) => (
                ctx.bodies[b].point_position(&o_local),
                ctx.bodies[b].rotation * n_local,
            ),
            None => (o_local, n_local),
        }
    }

    /// The contact of point k, or None when it does not penetrate.
    fn evaluate(&self, ctx: &ForceContext, k: usize) -> Option<PointEval> {
        let att = &self.points[k];
        let p = att.position(ctx);
        let (o, n) = self.contact_plane(ctx, &p);
        if !(o.iter().chain(n.iter()).all(|x| x.is_finite())) {
            // Outside a surface's domain; `apply` reports it as an error.
            return None;
        }
        let delta = -n.dot(&(p - o));
        if delta <= 0.0 {
            return None;
        }
        let vr = att.velocity(ctx) - self.plane_velocity(ctx, &p);
        let delta_rate = -n.dot(&vr);
        let normal_force = (self.c * delta + self.d * delta_rate).max(0.0);
        let vt = vr - n * n.dot(&vr);
        let limit0 = self.mu_static * normal_force;
        let mut trial = Vector3::zeros();
        let (ft, branch) = match self.modes[k] {
            ContactMode::Stick { anchor } => {
                let s = p - self.to_world(ctx, &anchor);
                let st = s - n * n.dot(&s);
                trial = -(self.ct * st + self.dt * vt);
                let m = trial.norm();
                if m <= limit0 {
                    (trial, Tangential::Stick)
                } else {
                    let u = trial / m;
                    (limit0 * u, Tangential::Saturated(u))
                }
            }
            ContactMode::Slide { .. } | ContactMode::Free => {
                let speed = vt.norm();
                let w = vt / speed.max(V_REG);
                (-self.mu * normal_force * w, Tangential::Slide(w, speed))
            }
        };
        Some(PointEval {
            p,
            n,
            delta,
            delta_rate,
            normal_force,
            ft,
            trial,
            vt,
            branch,
        })
    }

    /// Local Jacobians (∂f/∂d, ∂f/∂ḋ) of the force f on the point's body with
    /// respect to the point's position and velocity relative to the plane.
    fn local_jacobian(&self, e: &PointEval) -> (Matrix3<f64>, Matrix3<f64>) {
        let n = e.n;
        let nn = n * n.transpose();
        let t = Matrix3::identity() - nn;
        let loaded = e.normal_force > 0.0;
        // ∂N/∂d = −c nᵀ, ∂N/∂ḋ = −d nᵀ while N > 0.
        let (cn, dn) = if loaded { (self.c, self.d) } else { (0.0, 0.0) };
        let mut kq = -cn * nn;
        let mut kv = -dn * nn;
        match e.branch {
            Tangential::Stick => {
                kq -= self.ct * t;
                kv -= self.dt * t;
            }
            Tangential::Saturated(u) => {
                let r = self.mu_static * e.normal_force / e.trial.norm();
                let pu = Matrix3::identity() - u * u.transpose();
                kq -= r * self.ct * pu * t + self.mu_static * cn * u * n.transpose();
                kv -= r * self.dt * pu * t + self.mu_static * dn * u * n.transpose();
            }
            Tangential::Slide(w, speed) => {
                kq += self.mu * cn * w * n.transpose();
                kv += self.mu * dn * w * n.transpose();
                let dw = if speed > V_REG {
                    (Matrix3::identity() - w * w.transpose()) * t / speed
                } else {
                    t / V_REG
                };
                kv -= self.mu * e.normal_force * dw;
            }
        }
        (kq, kv)
    }

    fn body(&self) -> Option<usize> {
        self.points.first().and_then(|a| a.body)
    }

    /// Elastic energy (J) and dissipated power (W) of one point in contact.
    ///
    /// The energy is ½ c δ² of the normal spring and, while the point sticks
    /// (also beyond the limit, until the breakaway is accepted), ½ c_t |s_t|²
    /// of its anchor spring (c_t s_t = −trial − d_t v_t). The power is what
    /// the balance leaves: the contact's forces do the work F·v_r on the two
    /// bodies (F = N n + F_t on the point's body, −F on the plane's at the
    /// same place), and d/dt ½ c δ² = c δ δ̇, d/dt ½ c_t |s_t|² = c_t s_t·v_t
    /// exactly (the anchor and the normal turn with the plane body), so
    /// P = (N − c δ) δ̇ − F_t·v_t − c_t s_t·v_t: d δ̇² (or −c δ δ̇ > 0 where
    /// the damper would pull and N is held at 0), plus d_t |v_t|² sticking,
    /// μ N |v_t| sliding. Held at the static limit within a step, the anchor
    /// spring may be stretched faster than the limit force works, and P is
    /// then negative until the breakaway. At a mode change (an accepted
    /// step) the anchor's energy is released (breakaway: ½ c_t |s_t|², about
    /// ½ (μ0 N)²/c_t) or stored (a new anchor carrying the sliding force:
    /// ½ (μ N)²/c_t); P does not hold these jumps.
    fn energy_and_dissipation(&self, e: &PointEval) -> (f64, f64) {
        let normal = (
            0.5 * self.c * e.delta * e.delta,
            (e.normal_force - self.c * e.delta) * e.delta_rate,
        );
        let slip = -e.ft.dot(&e.vt);
        let (energy, power) = match e.branch {
            Tangential::Stick | Tangential::Saturated(_) => {
                let cs = -e.trial - self.dt * e.vt;
                (0.5 * cs.norm_squared() / self.ct, slip - cs.dot(&e.vt))
            }
            Tangential::Slide(..) => (0.0, slip),
        };
        (normal.0 + energy, normal.1 + power)
    }
}

impl ForceElement for PointPlane {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        for p in &mut self.points {
            p.set_parameters(params, &self.name)?;
        }
        self.origin = eval_vector(&self.origin_expr, params, 0.0, &self.name)?;
        let n = eval_vector(&self.normal_expr, params, 0.0, &self.name)?;
        if n.norm() == 0.0 {
            return Err(SimError::Other(format!(
                "force element \"{}\": the plane normal is zero",
                self.name
            )));
        }
        self.normal = n.normalize();
        let names = ["c", "d", "ct", "dt", "mu0", "mu"];
        let mut v = [0.0; 6];
        for (k, e) in self.coeff_expr.iter().enumerate() {
            v[k] = eval_scalar(e, params, &self.name, names[k])?;
        }
        [self.c, self.d, self.ct, self.dt, self.mu_static, self.mu] = v;
        if !(self.c > 0.0 && self.ct > 0.0 && self.d >= 0.0 && self.dt >= 0.0) {
            return Err(SimError::Other(format!(
                "force element \"{}\": needs c > 0, ct > 0, d ≥ 0, dt ≥ 0, got {}, {}, {}, {}",
                self.name, self.c, self.ct, self.d, self.dt
            )));
        }
        if !(0.0 <= self.mu && self.mu <= self.mu_static) {
            return Err(SimError::Other(format!(
                "force element \"{}\": needs 0 ≤ mu ≤ mu0, got mu = {}, mu0 = {}",
                self.name, self.mu, self.mu_static
            )));
        }
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let body = self.body();
        for (k, att) in self.points.iter().enumerate() {
            if let Some(e) = self.evaluate(ctx, k) {
                let f = e.normal_force * e.n + e.ft;
                add_force(wrenches, ctx, body, &e.p, &f);
                add_force(wrenches, ctx, self.plane_body, &e.p, &(-f));
            } else if self.surface.is_some() {
                // No contact, or a surface undefined under the point (which
                // `evaluate` cannot tell apart): only then look again.
                let p = att.position(ctx);
                let (o, n) = self.contact_plane(ctx, &p);
                if !(o.iter().chain(n.iter()).all(|x| x.is_finite())) {
                    let local = self.to_plane(ctx, &p) - self.origin;
                    return Err(SimError::NonFinite {
                        t: ctx.t,
                        what: format!(
                            "force element \"{}\": the surface is not defined under point {k} \
                             (x = {} m, y = {} m in the surface frame)",
                            self.name, local.x, local.y
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        let mut v = Vec::new();
        for k in 0..self.points.len() {
            for q in [
                "N[N]",
                "Ftx[N]",
                "Fty[N]",
                "Ftz[N]",
                "penetration[m]",
                "mode[-]",
            ] {
                v.push(format!("{k}.{q}"));
            }
        }
        v.extend(["E[J]".to_string(), "P[W]".to_string()]);
        v
    }

    /// Per point: N, the tangential force (SC0), the penetration and the mode
    /// (0 free, 1 sticking, 2 sliding); then the elastic energy and the
    /// dissipated power of all points (`energy_and_dissipation`).
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let (mut energy, mut power) = (0.0, 0.0);
        for k in 0..self.points.len() {
            let mode = match self.modes[k] {
                ContactMode::Free => 0.0,
                ContactMode::Stick { .. } => 1.0,
                ContactMode::Slide { .. } => 2.0,
            };
            match self.evaluate(ctx, k) {
                Some(e) => {
                    let (ek, pk) = self.energy_and_dissipation(&e);
                    energy += ek;
                    power += pk;
                    out.extend([e.normal_force, e.ft.x, e.ft.y, e.ft.z, e.delta, mode]);
                }
                None => out.extend([0.0, 0.0, 0.0, 0.0, 0.0, mode]),
            }
        }
        out.extend([energy, power]);
    }

    fn remembers_accepted_steps(&self) -> bool {
        true
    }

    fn accept_step(&mut self, ctx: &ForceContext) -> Result<(), SimError> {
        for k in 0..self.points.len() {
            let Some(e) = self.evaluate(ctx, k) else {
                self.modes[k] = ContactMode::Free;
                continue;
            };
            let speed = e.vt.norm();
            // Anchor such that −c_t s_t equals the current tangential force.
            let stick_here = |this: &Self| ContactMode::Stick {
                anchor: this.to_plane(ctx, &(e.p + e.ft / this.ct)),
            };
            self.modes[k] = match (self.modes[k], e.branch) {
                // Breakaway: the point will slip against the friction force.
                (ContactMode::Stick { .. }, Tangential::Saturated(u)) => ContactMode::Slide {
                    dir: -u,
                    established: speed >= V_STICK,
                },
                (ContactMode::Stick { anchor }, _) => ContactMode::Stick { anchor },
                (ContactMode::Slide { dir, established }, _) => {
                    // Sticks again when the slip has reversed or slowed below
                    // V_STICK; right after a breakaway (slip not yet at
                    // V_STICK) only a clear reversal counts.
                    let est = established || speed >= V_STICK;
                    let along = e.vt.dot(&dir);
                    let stop = if est {
                        along <= 0.0 || speed < V_STICK
                    } else {
                        along < -V_STICK
                    };
                    if stop {
                        stick_here(self)
                    } else {
                        ContactMode::Slide {
                            dir: if speed > V_REG { e.vt / speed } else { dir },
                            established: est,
                        }
                    }
                }
                (ContactMode::Free, _) => {
                    if speed < V_STICK {
                        stick_here(self)
                    } else {
                        ContactMode::Slide {
                            dir: e.vt / speed,
                            established: true,
                        }
                    }
                }
            };
        }
        Ok(())
    }

    /// Sums the points' contributions in the twist coordinates of the two
    /// bodies, Σ Gₖᵀ K_k Gₖ with Gₖ = [−S(ρ₁ₖ), S(ρ₂ₖ)] (3 × 12,
    /// [`super::point_twist_map`]), and maps the 12×12 sums once with the body
    /// Jacobians: the same as one point pair per point, at a fraction of the cost.
    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let body = self.body();
        let mut kq12 = PairMatrix::zeros();
        let mut kv12 = PairMatrix::zeros();
        let mut any = false;
        for k in 0..self.points.len() {
            if let Some(e) = self.evaluate(ctx, k) {
                let (kq, kv) = self.local_jacobian(&e);
                // Blocks Sᵢᵀ K Sⱼ with the signs of G = [−S₁, S₂], only for
                // the sides that are bodies.
                let s1 = self
                    .plane_body
                    .map(|b| point_twist_map(&(e.p - jac.body_position(b))));
                let s2 = body.map(|b| point_twist_map(&(e.p - jac.body_position(b))));
                for (k, acc) in [(&kq, &mut kq12), (&kv, &mut kv12)] {
                    if let Some(s2) = &s2 {
                        let ks2 = k * s2;
                        let mut blk = acc.fixed_view_mut::<6, 6>(6, 6);
                        blk += s2.transpose() * ks2;
                        if let Some(s1) = &s1 {
                            let mut blk = acc.fixed_view_mut::<6, 6>(0, 6);
                            blk -= s1.transpose() * ks2;
                        }
                    }
                    if let Some(s1) = &s1 {
                        let ks1 = k * s1;
                        let mut blk = acc.fixed_view_mut::<6, 6>(0, 0);
                        blk += s1.transpose() * ks1;
                        if let Some(s2) = &s2 {
                            let mut blk = acc.fixed_view_mut::<6, 6>(6, 0);
                            blk -= s2.transpose() * ks1;
                        }
                    }
                }
                any = true;
            }
        }
        if any {
            jac.add_body_pair(self.plane_body, body, &kq12, &kv12);
        }
        Ok(())
    }
}
