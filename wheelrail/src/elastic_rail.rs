//! Massless elastic rail (Pogorelov 2005, Sect. 4.2): the rail head of one rail is a
//! massless body that moves laterally and vertically against springs and
//! dampers to ground, and is in quasi-static equilibrium with the wheel–rail
//! contact forces at every instant.
//!
//! In the cross-section plane of the rail (y lateral, z up, as the track frame)
//! the rail displacement `d = (d_y, d_z)` satisfies
//!
//! ```text
//! k_y d_y + c_y ḋ_y = −Σᵢ F_y,i        (lateral equilibrium)
//! k_z d_z + c_z ḋ_z = −Σᵢ F_z,i        (vertical equilibrium)
//! ```
//!
//! (the lateral damper `c_y` in every contact mode by default, or in
//! two-point contact only, as in the paper: [`LateralDamping`]),
//! where `Fᵢ = Nᵢ nᵢ + Tᵢ tᵢ` is the force of contact `i` on the wheel (normal
//! force `Nᵢ` along the normal `nᵢ` from rail to wheel, lateral creep force `Tᵢ`
//! along the in-plane tangent `tᵢ = (n_z, −n_y)`, i.e. `eᵧ` of the contact
//! frame); the rail receives `−Fᵢ`. The damping rate is discretised over the
//! caller's time step, `ḋ ≈ (d − d_prev)/h` (backward Euler; `h = ∞` gives the
//! static problem).
//!
//! The normal force of each contact follows Hertz, `Nᵢ = (δᵢ/δ₁)^{3/2}` with the
//! approach `δᵢ(d)` from the contact geometry at the displaced rail (one- or
//! two-point contact). Solution as in the paper:
//!
//! - **inner iterations**: with the creep forces fixed, Newton on the 2×2
//!   equilibrium for `d` (Jacobian `K + C/h + Σ (dN/dδ)·nnᵀ`), which gives the
//!   rail deformation and the normal forces;
//! - **outer iterations**: with the new normal forces, the contact ellipses and
//!   the creep forces are recomputed (the rail's own velocity enters the lateral
//!   creepage), and the inner problem is solved again, until the normal and
//!   creep forces change by less than the tolerance.
//!
//! With damping over a finite step the rail's velocity `(d − d_prev)/h` makes
//! the lateral creep force a damper on the rail, of rate `f₂₂/V` (N·s/m, f₂₂
//! Kalker's lateral creep coefficient): frozen during the inner iterations,
//! the outer iterations diverge as soon as `f₂₂/(V h)` exceeds the support's
//! `k_y + c_y/h` (e.g. 300 kN·s/m of creep damping at 30 m/s against 100
//! kN·s/m of rail damping). So the inner iterations carry the creep force to
//! first order in `d`: `Tᵢ(d) ≈ Tᵢ(d_k) + gᵢ tᵢ·(d − d_k)`, `gᵢ = f₂₂,ᵢ/(V h)`
//! from Kalker's coefficient (scaled by the saturation |F|/|F_linear| of the
//! law's actual force), `d_k` the displacement of the last outer iteration.
//! The converged solution is the same (the outer iterations stop when the
//! creep forces at `d` no longer change); only the convergence is helped.
//! (The scaled coefficient is at least the law's tangent, so the iterations
//! contract monotonically, slowly in partial saturation; the law's exact
//! tangent converges faster there but overshoots between the two saturated
//! branches when the creepage is small, as at standstill.)
//!
//! The inner Newton step uses the contact normals (`dδ/dd = n`); where it
//! does not lower the residual (the normal is not the approach's true
//! gradient, e.g. a flange contact moving across the profiles' regions) it is
//! retried once with a finite-difference Jacobian of the residual. The force
//! tolerance is raised to the rounding of the residual's terms where those
//! are huge (on tiny steps C/h and f₂₂/(V h)).
//!
//! The contact geometry is supplied through [`RailContactGeometry`] — "the
//! contact geometry at a given rail displacement": [`ProfileRailContacts`]
//! implements it from the wheel and rail profiles ([`crate::geometry`], one- and
//! two-point contact), [`LinearizedContacts`] to first order from the contacts
//! at zero displacement.

use crate::creep::{ContactMode, ContactPatch, CreepForces, CreepLaw, Creepages};
use crate::geometry::{Contact, ContactGeometry};
use crate::hertz::HertzShape;
use crate::kalker::KalkerCoefficients;

/// Most contacts per wheel (tread and flange).
pub const MAX_CONTACTS: usize = 2;

/// Errors of the elastic-rail solution.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElasticRailError {
    /// Bad support or solver parameter.
    #[error("elastic rail: {0}")]
    Parameter(String),
    /// The geometry reported something unusable.
    #[error("elastic rail: contact {index}: {what}")]
    Geometry {
        /// Contact index.
        index: usize,
        /// What is wrong.
        what: String,
    },
    /// A creep law or Hertz failed.
    #[error("elastic rail: contact {index}: {message}")]
    Contact {
        /// Contact index.
        index: usize,
        /// The underlying error's message.
        message: String,
    },
    /// No convergence.
    #[error(
        "elastic rail: {kind} iterations did not converge in {iterations} (residual {residual:e})"
    )]
    NoConvergence {
        /// `inner` or `outer`.
        kind: &'static str,
        /// Iterations made.
        iterations: usize,
        /// Last residual (N for inner, relative for outer).
        residual: f64,
    },
}

/// Stiffness and damping of the rail support at the contact, per rail.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RailSupport {
    /// Lateral stiffness, N/m (> 0).
    pub ky: f64,
    /// Lateral damping, N·s/m (≥ 0).
    pub cy: f64,
    /// Vertical stiffness, N/m (> 0).
    pub kz: f64,
    /// Vertical damping, N·s/m (≥ 0).
    pub cz: f64,
    /// When the lateral damping `cy` acts.
    pub lateral_damping: LateralDamping,
}

/// When the rail's lateral damper acts.
///
/// The default is [`Self::Always`], not the paper's rule: without the
/// lateral damper the creep force is the rail's only lateral damper (rate
/// `f₂₂/V` through the rail's velocity in the creepage), and at low speed
/// under a lateral load the outer iterations can fail to settle (the bundled
/// test `elastic_rails_balance_a_lateral_axle_force`, a wheelset at
/// standstill pushed against the rails with 20 kN, stops with "outer
/// iterations did not converge"; falling back to the damped solution there
/// makes the force switch between the two and the integrator's step
/// collapse).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LateralDamping {
    /// In two-point contact only, as in Pogorelov 2005, Sect. 4.2 ("lateral
    /// dissipation is taken into account for two-point contact mode only"):
    /// the equilibrium is solved without the lateral damper, and again with
    /// it if that equilibrium has two loaded contacts (so a wheel whose
    /// flange just touches gets the damped solution even if the damper then
    /// keeps the flange off).
    TwoPointContact,
    /// In every contact mode (the default).
    #[default]
    Always,
}

/// Geometry of one wheel–rail contact at a given rail displacement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RailContact {
    /// Approach (geometric overlap of the undeformed surfaces along the normal),
    /// m; no contact if ≤ 0.
    pub approach: f64,
    /// Unit normal from rail into wheel, `(n_y, n_z)` in the rail cross-section.
    pub normal: [f64; 2],
    /// Hertz shape from the contact's curvatures and materials.
    pub hertz: HertzShape,
    /// Creepages for a rigid rail at rest (the rail's own velocity is added by
    /// the solver).
    pub creepages: Creepages,
}

/// "Contact geometry at a given rail displacement": writes the contacts (at
/// most [`MAX_CONTACTS`]) of the wheel on the rail displaced by `d = (d_y, d_z)`
/// (m) and returns how many there are.
pub trait RailContactGeometry {
    /// Contacts at rail displacement `d`.
    fn contacts_at(
        &self,
        d: [f64; 2],
        out: &mut [RailContact; MAX_CONTACTS],
    ) -> Result<usize, ElasticRailError>;
}

/// First-order contact geometry: the contacts at zero rail displacement, with
/// the approach changing as `δ(d) = δ₀ + n·d` (moving the rail along its normal
/// into the wheel increases the overlap) and normals, curvatures and creepages
/// kept — adequate for rail displacements small against the profile radii.
#[derive(Debug, Clone)]
pub struct LinearizedContacts {
    /// The contacts at `d = 0`.
    pub contacts: Vec<RailContact>,
}

impl RailContactGeometry for LinearizedContacts {
    fn contacts_at(
        &self,
        d: [f64; 2],
        out: &mut [RailContact; MAX_CONTACTS],
    ) -> Result<usize, ElasticRailError> {
        let n = self.contacts.len().min(MAX_CONTACTS);
        for (o, c) in out.iter_mut().zip(&self.contacts[..n]) {
            *o = RailContact {
                approach: c.approach + c.normal[0] * d[0] + c.normal[1] * d[1],
                ..*c
            };
        }
        Ok(n)
    }
}

/// Contact geometry from the wheel and rail profiles ([`ContactGeometry`]) for
/// one wheel of a wheelset at lateral shift `y` (m), roll `roll` (rad) and
/// height `z` (m, the geometry's vertical wheelset coordinate: the vertical gap
/// at a contact is `gap + z`), on its rail displaced elastically by `d`:
///
/// - the rail moved laterally by `d_y` is the wheelset moved by `−d_y`
///   relative to that rail (the other side is not used);
/// - the rail lowered by `−d_z` opens the vertical gap by `−d_z`;
/// - the approach along the normal is the vertical overlap times `cos δ`
///   (`δ` the contact angle), the normal `n = (∓sin δ, cos δ)` (left/right wheel:
///   the normal force on the wheel points towards the track centre for `δ > 0`);
/// - the Hertz shape from the contact's curvatures (rail rolling-direction
///   curvature 0) and the material `e` (Pa), `nu`; the creepages from the
///   caller's `creepages` function of the contact (kinematics are not geometry).
pub struct ProfileRailContacts<'g, F> {
    /// The wheelset–track contact geometry.
    pub geometry: &'g ContactGeometry,
    /// 0 = left wheel/rail, 1 = right.
    pub side: usize,
    /// Wheelset lateral shift, m.
    pub y: f64,
    /// Wheelset roll, rad.
    pub roll: f64,
    /// Wheelset height, m.
    pub z: f64,
    /// Young's modulus of wheel and rail, Pa.
    pub e: f64,
    /// Poisson ratio.
    pub nu: f64,
    /// Creepages of a contact (rigid rail at rest).
    pub creepages: F,
}

impl<F: Fn(&Contact) -> Creepages> RailContactGeometry for ProfileRailContacts<'_, F> {
    fn contacts_at(
        &self,
        d: [f64; 2],
        out: &mut [RailContact; MAX_CONTACTS],
    ) -> Result<usize, ElasticRailError> {
        let geo_err = |index: usize, what: String| ElasticRailError::Geometry { index, what };
        if self.side > 1 {
            return Err(geo_err(
                0,
                format!("side must be 0 or 1, got {}", self.side),
            ));
        }
        let sets = self
            .geometry
            .contacts(self.y - d[0], self.roll)
            .map_err(|e| geo_err(0, e.to_string()))?;
        let set = &sets[self.side];
        let sign = if self.side == 0 { -1.0 } else { 1.0 };
        let n = set.count.min(MAX_CONTACTS);
        for (i, (o, c)) in out.iter_mut().zip(&set.contacts[..n]).enumerate() {
            let (sd, cd) = c.contact_angle.sin_cos();
            let (ca, cb) = (
                0.5 * c.wheel_longitudinal_curvature,
                0.5 * (c.wheel_transverse_curvature + c.rail_transverse_curvature),
            );
            let hertz = HertzShape::new(ca, cb, self.e, self.nu)
                .map_err(|e| geo_err(i, format!("{e} (conformal contact is not Hertzian)")))?;
            *o = RailContact {
                approach: -(c.gap + self.z - d[1]) * cd,
                normal: [sign * sd, cd],
                hertz,
                creepages: (self.creepages)(c),
            };
        }
        Ok(n)
    }
}

/// Material and friction data of the contacts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactMaterial {
    /// Shear modulus, Pa.
    pub g: f64,
    /// Poisson ratio, –.
    pub nu: f64,
    /// Coefficient of friction, –.
    pub mu: f64,
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticRailSettings {
    /// Time step for the damping rate `ḋ = (d − d_prev)/h`, s; `f64::INFINITY`
    /// for the static problem.
    pub h: f64,
    /// Rolling speed `V` (m/s): converts the rail velocity into creepage, and
    /// is the speed of laws whose friction depends on it.
    pub v_roll: f64,
    /// Inner tolerance on the force residual, N.
    pub force_tol: f64,
    /// Outer tolerance, relative change of normal and creep forces.
    pub rel_tol: f64,
    /// Iteration limits.
    pub max_inner: usize,
    /// Outer iteration limit.
    pub max_outer: usize,
}

impl Default for ElasticRailSettings {
    fn default() -> Self {
        Self {
            h: f64::INFINITY,
            v_roll: 1.0,
            force_tol: 1e-6,
            rel_tol: 1e-9,
            max_inner: 50,
            max_outer: 50,
        }
    }
}

/// Result for one contact.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactResult {
    /// Normal force on the wheel, N.
    pub normal_force: f64,
    /// Unit normal (rail → wheel), `(n_y, n_z)`.
    pub normal: [f64; 2],
    /// Creep forces on the wheel in the contact frame.
    pub creep: CreepForces,
    /// Semi-axes of the contact ellipse, m.
    pub a: f64,
    /// Lateral semi-axis, m.
    pub b: f64,
    /// Approach at equilibrium, m.
    pub approach: f64,
    /// Slope −∂T/∂η of the lateral creep force used by the last outer
    /// iteration, N (see [`CreepStart`]).
    pub lateral_slope: f64,
}

/// Where the outer iterations start: per contact (index as the geometry
/// reports them) the creep forces (N; the lateral one along tᵢ) and the slope
/// −∂T/∂η of the lateral one (N), e.g. from the solution of the previous time
/// step; zero for a cold start. The solution does not depend on it (to the
/// tolerances), only the number of outer iterations does.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CreepStart {
    /// Creep forces on the wheel, N.
    pub forces: [CreepForces; MAX_CONTACTS],
    /// −∂T/∂η, N.
    pub slope: [f64; MAX_CONTACTS],
}

/// Solution of the elastic-rail problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticRailSolution {
    /// Rail displacement `(d_y, d_z)`, m.
    pub displacement: [f64; 2],
    /// Rail velocity `(ḋ_y, ḋ_z)`, m/s (zero for the static problem).
    pub velocity: [f64; 2],
    /// Number of contacts.
    pub n_contacts: usize,
    /// Per contact.
    pub contacts: [ContactResult; MAX_CONTACTS],
    /// Total force of the contacts on the wheel, `(F_y, F_z)` in the rail
    /// cross-section, N (equal and opposite to the support force on the rail).
    pub wheel_force: [f64; 2],
    /// Inner iterations, summed over outer iterations.
    pub inner_iterations: usize,
    /// Outer iterations.
    pub outer_iterations: usize,
    /// Whether the lateral damper `cy` acted (see [`LateralDamping`]).
    pub lateral_damped: bool,
}

/// Solves the equilibrium of a massless elastic rail under one wheel, starting
/// from the previous displacement `d_prev` (m) and no creep forces.
pub fn solve(
    support: &RailSupport,
    material: &ContactMaterial,
    geometry: &dyn RailContactGeometry,
    law: &dyn CreepLaw,
    d_prev: [f64; 2],
    settings: &ElasticRailSettings,
) -> Result<ElasticRailSolution, ElasticRailError> {
    solve_from(
        support,
        material,
        geometry,
        law,
        d_prev,
        &CreepStart::default(),
        settings,
    )
}

/// [`solve`] with the outer iterations started from `start` (e.g. the
/// previous step's creep forces: fewer outer iterations). The lateral damper
/// acts as [`RailSupport::lateral_damping`] says.
pub fn solve_from(
    support: &RailSupport,
    material: &ContactMaterial,
    geometry: &dyn RailContactGeometry,
    law: &dyn CreepLaw,
    d_prev: [f64; 2],
    start: &CreepStart,
    settings: &ElasticRailSettings,
) -> Result<ElasticRailSolution, ElasticRailError> {
    let solve = |damped| {
        solve_damped(
            support, material, geometry, law, d_prev, start, settings, damped,
        )
    };
    match support.lateral_damping {
        LateralDamping::Always => solve(true),
        LateralDamping::TwoPointContact => {
            let free = solve(false)?;
            let loaded = free.contacts[..free.n_contacts]
                .iter()
                .filter(|c| c.normal_force > 0.0)
                .count();
            if support.cy > 0.0 && loaded == MAX_CONTACTS {
                solve(true)
            } else {
                Ok(free)
            }
        }
    }
}

/// [`solve_from`] with the lateral damper on (`damped`) or off.
#[allow(clippy::too_many_arguments)]
fn solve_damped(
    support: &RailSupport,
    material: &ContactMaterial,
    geometry: &dyn RailContactGeometry,
    law: &dyn CreepLaw,
    d_prev: [f64; 2],
    start: &CreepStart,
    settings: &ElasticRailSettings,
    damped: bool,
) -> Result<ElasticRailSolution, ElasticRailError> {
    let p = |s: String| Err(ElasticRailError::Parameter(s));
    if !(support.ky.is_finite() && support.ky > 0.0 && support.kz.is_finite() && support.kz > 0.0) {
        return p(format!(
            "support stiffnesses must be positive and finite, got ky = {} N/m, kz = {} N/m",
            support.ky, support.kz
        ));
    }
    if !(support.cy.is_finite() && support.cy >= 0.0 && support.cz.is_finite() && support.cz >= 0.0)
    {
        return p(format!(
            "support damping must be non-negative and finite, got cy = {}, cz = {} N·s/m",
            support.cy, support.cz
        ));
    }
    if settings.h.is_nan() || settings.h <= 0.0 {
        return p(format!(
            "time step must be positive, got h = {} s",
            settings.h
        ));
    }
    if !(settings.v_roll.is_finite() && settings.v_roll > 0.0) {
        return p(format!(
            "rolling speed must be positive and finite, got {} m/s",
            settings.v_roll
        ));
    }
    if !d_prev.iter().all(|v| v.is_finite()) {
        return p(format!("previous rail displacement not finite: {d_prev:?}"));
    }
    // Effective stiffness with the damper over the step: K + C/h, and the
    // damper's memory term C/h·d_prev on the right-hand side.
    let cy = if damped { support.cy } else { 0.0 };
    let (ch_y, ch_z) = if settings.h.is_finite() {
        (cy / settings.h, support.cz / settings.h)
    } else {
        (0.0, 0.0)
    };
    let keff = [support.ky + ch_y, support.kz + ch_z];
    let rhs0 = [ch_y * d_prev[0], ch_z * d_prev[1]];

    let mut d = d_prev;
    let mut geo = [RailContact {
        approach: 0.0,
        normal: [0.0, 1.0],
        hertz: HertzShape::with_modulus(1.0, 1.0, 1.0).map_err(|e| ElasticRailError::Geometry {
            index: 0,
            what: e.to_string(),
        })?,
        creepages: Creepages::default(),
    }; MAX_CONTACTS];
    // Lateral creep forces (along tᵢ) in the inner iterations, to first order
    // in the rail displacement about `d_lin`: creep_t + creep_g·tᵢ·(d − d_lin).
    if !start
        .forces
        .iter()
        .flat_map(|f| [f.fx, f.fy, f.mz])
        .chain(start.slope)
        .all(|x| x.is_finite())
    {
        return p(format!("creep start not finite: {start:?}"));
    }
    let mut creep = start.forces;
    let mut creep_t = creep.map(|f| f.fy);
    let mut slope = start.slope.map(|s| s.max(0.0));
    let rate = |s: f64| {
        if settings.h.is_finite() {
            s / (settings.v_roll * settings.h)
        } else {
            0.0
        }
    };
    let mut creep_g = slope.map(rate);
    let mut d_lin = d_prev;
    let mut normal = [0.0; MAX_CONTACTS];
    let mut inner_total = 0;
    let mut n_contacts = 0;
    // The displacement whose contacts `geo` holds (the geometry is the costly
    // part: a line-search trial that is accepted is not evaluated again).
    let mut geo_d = None;
    for outer in 1..=settings.max_outer {
        // Inner: Newton on R(d) = Keff d − rhs0 + Σ Fᵢ(d) = 0.
        let mut converged = false;
        let mut residual = f64::INFINITY;
        for _ in 0..settings.max_inner {
            inner_total += 1;
            if geo_d != Some(d) {
                n_contacts = geometry.contacts_at(d, &mut geo)?;
                geo_d = Some(d);
            }
            let mut r = [keff[0] * d[0] - rhs0[0], keff[1] * d[1] - rhs0[1]];
            let mut j = [[keff[0], 0.0], [0.0, keff[1]]];
            // Size of the terms summed into r, for the rounding floor.
            let mut terms = (keff[0] * d[0]).abs().max((keff[1] * d[1]).abs())
                + rhs0[0].abs().max(rhs0[1].abs());
            for (i, c) in geo[..n_contacts].iter().enumerate() {
                check_contact(i, c)?;
                let nn = c
                    .hertz
                    .normal_force(c.approach)
                    .map_err(|e| contact_err(i, e))?;
                let kn = c.hertz.stiffness(c.approach);
                let [ny, nz] = c.normal;
                let t = [nz, -ny];
                normal[i] = nn;
                let ti = linear_creep(creep_t[i], creep_g[i], t, d, d_lin);
                r[0] += nn * ny + ti * t[0];
                r[1] += nn * nz + ti * t[1];
                terms += nn + ti.abs() + creep_g[i] * (d[0] - d_lin[0]).hypot(d[1] - d_lin[1]);
                // dFᵢ/dd = kn·n nᵀ (δ = δ₀ + n·d) + gᵢ t tᵀ.
                let g = creep_g[i];
                j[0][0] += kn * ny * ny + g * t[0] * t[0];
                j[0][1] += kn * ny * nz + g * t[0] * t[1];
                j[1][0] += kn * nz * ny + g * t[1] * t[0];
                j[1][1] += kn * nz * nz + g * t[1] * t[1];
            }
            residual = r[0].hypot(r[1]);
            // The residual cannot be resolved below the rounding of its terms
            // and of d itself through the Jacobian (on tiny steps C/h and the
            // creep damping f₂₂/(V h) make J huge).
            let j_max = j.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
            let floor = 16.0 * f64::EPSILON * (terms + j_max * d[0].abs().max(d[1].abs()));
            let tol = settings.force_tol.max(floor);
            if residual <= tol {
                converged = true;
                break;
            }
            let mut dd = newton_step(j, r);
            // Damped step: do not let an approach jump from positive far into
            // separation (Hertz is stiff at contact, zero beyond): halve the step
            // while the residual norm would grow. If the step from the contact
            // normals does not lower the residual at all (the normal is not
            // the approach's true gradient, e.g. where a flange contact moves
            // across the profiles' regions), retry once with a
            // finite-difference Jacobian of the residual.
            let r_norm = residual;
            let creep_lin = (&creep_t, &creep_g, d_lin);
            let mut accepted = false;
            for attempt in 0..2 {
                if attempt == 1 {
                    let h = 1e-9 + 1e-7 * d[0].abs().max(d[1].abs());
                    let mut jfd = [[0.0; 2]; 2];
                    for k in 0..2 {
                        let mut dk = d;
                        dk[k] += h;
                        let (rk, _) = residual_at(geometry, &mut geo, dk, keff, rhs0, creep_lin)?;
                        geo_d = Some(dk);
                        jfd[0][k] = (rk[0] - r[0]) / (dk[k] - d[k]);
                        jfd[1][k] = (rk[1] - r[1]) / (dk[k] - d[k]);
                    }
                    dd = newton_step(jfd, r);
                }
                for _ in 0..30 {
                    let trial = [d[0] + dd[0], d[1] + dd[1]];
                    let (rt, n) = residual_at(geometry, &mut geo, trial, keff, rhs0, creep_lin)?;
                    n_contacts = n;
                    geo_d = Some(trial);
                    let rt = rt[0].hypot(rt[1]);
                    if rt < r_norm || rt <= tol {
                        d = trial;
                        accepted = true;
                        break;
                    }
                    dd = [0.5 * dd[0], 0.5 * dd[1]];
                }
                if accepted {
                    break;
                }
            }
            if !accepted {
                break;
            }
        }
        if !converged {
            return Err(ElasticRailError::NoConvergence {
                kind: "inner",
                iterations: settings.max_inner,
                residual,
            });
        }
        // Outer: creep forces from the new normal forces and the rail velocity.
        let vel = rail_velocity(d, d_prev, settings.h);
        let mut change = 0.0_f64;
        let mut scale = 0.0_f64;
        // One- or two-point contact, for the laws that treat the flange
        // contact apart; the contact angle in the rail's cross-section.
        let loaded = |i: usize| i < n_contacts && normal[i] > 0.0;
        let angle = |i: usize| geo[i].normal[0].abs().atan2(geo[i].normal[1]);
        let modes = ContactMode::of_wheel([angle(0), angle(1)], [loaded(0), loaded(1)]);
        for i in 0..n_contacts {
            let c = &geo[i];
            let [ny, nz] = c.normal;
            let t = [nz, -ny];
            let (f, lateral_slope) = creep_force(
                i,
                c,
                (normal[i], modes[i]),
                material,
                law,
                vel,
                t,
                settings.v_roll,
            )?;
            change = change.max((f.fy - creep[i].fy).abs().max((f.fx - creep[i].fx).abs()));
            scale = scale.max(normal[i]);
            creep[i] = f;
            creep_t[i] = f.fy;
            slope[i] = lateral_slope;
            creep_g[i] = rate(slope[i]);
        }
        d_lin = d;
        for item in creep.iter_mut().skip(n_contacts) {
            *item = CreepForces::default();
        }
        // Converged when the creep forces did not change (relative to the load).
        let rel = if scale > 0.0 { change / scale } else { 0.0 };
        let settled = rel <= settings.rel_tol;
        if settled || outer == settings.max_outer {
            if !settled {
                return Err(ElasticRailError::NoConvergence {
                    kind: "outer",
                    iterations: outer,
                    residual: rel,
                });
            }
            let mut contacts = [ContactResult::default(); MAX_CONTACTS];
            let mut wheel_force = [0.0; 2];
            for i in 0..n_contacts {
                let c = &geo[i];
                let [ny, nz] = c.normal;
                let hc = c.hertz.contact(normal[i]).map_err(|e| contact_err(i, e))?;
                contacts[i] = ContactResult {
                    normal_force: normal[i],
                    normal: c.normal,
                    creep: creep[i],
                    a: hc.a,
                    b: hc.b,
                    approach: c.approach,
                    lateral_slope: slope[i],
                };
                wheel_force[0] += normal[i] * ny + creep[i].fy * nz;
                wheel_force[1] += normal[i] * nz - creep[i].fy * ny;
            }
            return Ok(ElasticRailSolution {
                displacement: d,
                velocity: vel,
                n_contacts,
                contacts,
                wheel_force,
                inner_iterations: inner_total,
                outer_iterations: outer,
                lateral_damped: damped,
            });
        }
    }
    Err(ElasticRailError::NoConvergence {
        kind: "outer",
        iterations: settings.max_outer,
        residual: f64::NAN,
    })
}

fn contact_err(index: usize, e: impl std::error::Error) -> ElasticRailError {
    ElasticRailError::Contact {
        index,
        message: e.to_string(),
    }
}

fn check_contact(i: usize, c: &RailContact) -> Result<(), ElasticRailError> {
    let n2 = c.normal[0] * c.normal[0] + c.normal[1] * c.normal[1];
    if (n2 - 1.0).abs() >= 1e-9 || n2.is_nan() {
        return Err(ElasticRailError::Geometry {
            index: i,
            what: format!("normal {:?} is not a unit vector", c.normal),
        });
    }
    if !c.approach.is_finite() {
        return Err(ElasticRailError::Geometry {
            index: i,
            what: format!("approach is not finite ({})", c.approach),
        });
    }
    Ok(())
}

fn rail_velocity(d: [f64; 2], d_prev: [f64; 2], h: f64) -> [f64; 2] {
    if h.is_finite() {
        [(d[0] - d_prev[0]) / h, (d[1] - d_prev[1]) / h]
    } else {
        [0.0, 0.0]
    }
}

/// Creep forces of contact `i` for normal force `nn` in `mode`; the rail's velocity
/// `vel` moves the rail's material point, `Δη = −(vel·t)/V`. Also −∂T/∂η (N)
/// of the lateral creep force: Kalker's f₂₂ = G a b C₂₂ scaled by the
/// saturation |F|/|F_linear| (≤ 1) of the law's force; 0 without load or
/// where Kalker's table does not apply.
#[allow(clippy::too_many_arguments)]
fn creep_force(
    i: usize,
    c: &RailContact,
    (nn, mode): (f64, ContactMode),
    material: &ContactMaterial,
    law: &dyn CreepLaw,
    vel: [f64; 2],
    t: [f64; 2],
    v_roll: f64,
) -> Result<(CreepForces, f64), ElasticRailError> {
    if nn <= 0.0 {
        return Ok((CreepForces::default(), 0.0));
    }
    let hc = c.hertz.contact(nn).map_err(|e| contact_err(i, e))?;
    let patch = ContactPatch {
        a: hc.a,
        b: hc.b,
        g: material.g,
        nu: material.nu,
        mu: material.mu,
        n: nn,
    };
    let cr = Creepages {
        eta: c.creepages.eta - (vel[0] * t[0] + vel[1] * t[1]) / v_roll,
        ..c.creepages
    };
    // At the rolling speed, for laws whose friction falls with the slip
    // velocity (Polach).
    let f = law
        .forces_in_contact(&patch, &cr, v_roll, mode)
        .map_err(|e| contact_err(i, e))?;
    let lateral_slope = KalkerCoefficients::saturated_slopes(
        hc.a,
        hc.b,
        material.g,
        material.nu,
        cr.xi,
        cr.eta,
        f.fx,
        f.fy,
    )
    .map_or(0.0, |(_, f22)| f22);
    Ok((f, lateral_slope))
}

/// The lateral creep force of a contact at rail displacement `d`, to first
/// order about `d_lin` where it is `t0` with slope `g` along `t`.
fn linear_creep(t0: f64, g: f64, t: [f64; 2], d: [f64; 2], d_lin: [f64; 2]) -> f64 {
    t0 + g * (t[0] * (d[0] - d_lin[0]) + t[1] * (d[1] - d_lin[1]))
}

/// The Newton step −J⁻¹ r of a 2×2 system.
fn newton_step(j: [[f64; 2]; 2], r: [f64; 2]) -> [f64; 2] {
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    [
        -(j[1][1] * r[0] - j[0][1] * r[1]) / det,
        -(-j[1][0] * r[0] + j[0][0] * r[1]) / det,
    ]
}

/// The inner residual at displacement `d` and the number of contacts
/// (written into `geo`); `creep` holds the lateral creep forces, their slopes
/// and the displacement they are linearised about.
fn residual_at(
    geometry: &dyn RailContactGeometry,
    geo: &mut [RailContact; MAX_CONTACTS],
    d: [f64; 2],
    keff: [f64; 2],
    rhs0: [f64; 2],
    creep: (&[f64; MAX_CONTACTS], &[f64; MAX_CONTACTS], [f64; 2]),
) -> Result<([f64; 2], usize), ElasticRailError> {
    let (creep_t, creep_g, d_lin) = creep;
    let n = geometry.contacts_at(d, geo)?;
    let mut r = [keff[0] * d[0] - rhs0[0], keff[1] * d[1] - rhs0[1]];
    for (i, c) in geo[..n].iter().enumerate() {
        check_contact(i, c)?;
        let nn = c
            .hertz
            .normal_force(c.approach)
            .map_err(|e| contact_err(i, e))?;
        let [ny, nz] = c.normal;
        let ti = linear_creep(creep_t[i], creep_g[i], [nz, -ny], d, d_lin);
        r[0] += nn * ny + ti * nz;
        r[1] += nn * nz - ti * ny;
    }
    Ok((r, n))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::creep::FastsimA;
    use crate::hertz::wheel_rail_curvatures;

    /// A tread contact on a 1:40-inclined normal with lateral creepage, on a
    /// damped rail over a 1 ms step at 30 m/s: the outer iterations couple
    /// the creep forces with the rail's velocity.
    fn problem() -> (
        RailSupport,
        ContactMaterial,
        LinearizedContacts,
        ElasticRailSettings,
    ) {
        let (ca, cb) = wheel_rail_curvatures(0.46, 0.0, 1.0 / 0.3);
        let angle: f64 = 0.025;
        let contacts = vec![RailContact {
            approach: 0.6e-3,
            normal: [-angle.sin(), angle.cos()],
            hertz: HertzShape::new(ca, cb, 210e9, 0.3).unwrap(),
            creepages: Creepages {
                xi: 2e-4,
                eta: 1e-3,
                phi: 0.02,
            },
        }];
        let support = RailSupport {
            ky: 65e6,
            cy: 1e5,
            kz: 100e6,
            cz: 2e5,
            lateral_damping: LateralDamping::Always,
        };
        let material = ContactMaterial {
            g: 210e9 / (2.0 * 1.3),
            nu: 0.3,
            mu: 0.4,
        };
        let settings = ElasticRailSettings {
            h: 1e-3,
            v_roll: 30.0,
            ..Default::default()
        };
        (support, material, LinearizedContacts { contacts }, settings)
    }

    /// Steps in a row: one started from the previous step's creep forces
    /// (which belong to its displacement, the second's d_prev, as in time
    /// simulation) reaches the same equilibrium as from a cold start (to the
    /// tolerances: 1e-9 of the load in the creep forces, about 1e-12 m
    /// against the 65 MN/m support) in fewer outer iterations.
    #[test]
    fn a_warm_start_reaches_the_same_solution_sooner() {
        let (support, material, geo, settings) = problem();
        let law = FastsimA::new(10).unwrap();
        // 50 ms towards the steady state (the rail settles within a few ms;
        // the first step jumps from an unloaded rail).
        let mut first = solve(&support, &material, &geo, &law, [0.0; 2], &settings).unwrap();
        for _ in 0..50 {
            first = solve(
                &support,
                &material,
                &geo,
                &law,
                first.displacement,
                &settings,
            )
            .unwrap();
        }
        let d_prev = first.displacement;
        let cold = solve(&support, &material, &geo, &law, d_prev, &settings).unwrap();
        let start = CreepStart {
            forces: first.contacts.map(|c| c.creep),
            slope: first.contacts.map(|c| c.lateral_slope),
        };
        let warm = solve_from(&support, &material, &geo, &law, d_prev, &start, &settings).unwrap();
        for k in 0..2 {
            let diff = (warm.displacement[k] - cold.displacement[k]).abs();
            assert!(diff < 1e-12, "d[{k}] differs by {diff} m");
        }
        println!(
            "outer iterations: cold {}, warm {}",
            cold.outer_iterations, warm.outer_iterations
        );
        assert!(
            warm.outer_iterations < cold.outer_iterations,
            "warm {} vs cold {} outer iterations",
            warm.outer_iterations,
            cold.outer_iterations
        );
        // A start that is not finite is refused, naming it.
        let bad = CreepStart {
            slope: [f64::NAN; MAX_CONTACTS],
            ..start
        };
        let e = solve_from(&support, &material, &geo, &law, d_prev, &bad, &settings).unwrap_err();
        assert!(e.to_string().contains("creep start"), "{e}");
    }
}
