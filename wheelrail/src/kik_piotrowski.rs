//! Non-elliptic wheel–rail contact by the modified Kik–Piotrowski method
//! (Kik & Piotrowski 1996; Piotrowski & Kik 2008; the "modified KP" that
//! Pogorelov 2005, Sect. 4.3, item 4 lists among UM's contact models).
//!
//! **Input.** The undeformed vertical gap `g(y)` between a wheel and its rail
//! at `x = 0`, sampled across the profiles ([`GapSample`], from
//! [`crate::geometry::ContactGeometry::gap_samples`]), and the wheel's
//! vertical approach `δ_z` (m, the rigid wheel's descent below the height
//! where it first touches at `g = 0`).
//!
//! **Patches.** Every run of samples with `δ_z − g > 0` (the rigid
//! interpenetration) is one patch, so a wheel may have several (tread and
//! flange). In a patch, with `γ` the contact angle at its deepest sample
//! (gap `g_min`), the normal approach is `δ₀ = (δ_z − g_min) cos γ`, the
//! lateral coordinate in the tangent plane `s = (y − y_min)/cos γ`, and the
//! normal gap `(g − g_min) cos γ`. The **virtual penetration** replaces `δ₀`
//! by `εδ₀` (penetration-reduction factor `ε`, default 0.55 as in Piotrowski
//! & Kik 2008 and UM): the contact is where
//! `h(x, s) = εδ₀ − (g(s) − g_min) cos γ − A(s) x² > 0`, with the wheel's
//! curvature in the rolling direction `2A = cos γ / r(s)` (Meusnier; the rail
//! is straight). A strip at `s` thus has half-length
//! `l(s) = √(h(0, s)/A(s))`.
//!
//! **Pressure.** Semi-elliptic along each strip with an amplitude that follows
//! the virtual penetration: `p(x, s) = p₀ √(h(x, s)/h₀)`,
//! `h₀ = max h(0, s) = εδ₀`, i.e. `p = p₀ √(h(0,s)/h₀) √(1 − x²/l²)`.
//! For constant curvatures this is Hertz's distribution on the virtual
//! ellipse (exactly Hertz's for a sphere with `ε = 1/2`).
//! **This form is this module's reading of KP's pressure** (the papers were
//! not available when it was written; it is the form that reduces to Hertz),
//! and is tested against CONTACT, not against KP's own numbers.
//!
//! **Normal load.** As KP: the elastic half-space (Boussinesq) displacement
//! at the point of largest penetration equals the full approach `δ₀`:
//! `δ₀ = (2(1 − ν²)/(πE)) ∫∫ p(x, s)/ρ dx ds` (two bodies of the same
//! material, `ρ` the distance to that point), which fixes `p₀`; the normal
//! force is `N = ∫∫ p dx ds`. The integral over a strip of width `w` uses
//! the exact lateral average of `1/ρ` over the strip
//! (`(1/w)[asinh((d + w/2)/|x|) − asinh((d − w/2)/|x|)]`, `d` the strip's
//! lateral distance), so the strip through the singular point needs no
//! special case; along `x` a Gauss rule in `θ`, `x = l sin θ`.
//!
//! **Tangential forces.** By strips on the non-elliptic patch with the strip
//! solution of [`crate::creep::StripTheory`] (one home:
//! `creep::StripSolution`), each strip with its own half-length and peak
//! pressure, calibrated on the patch's equivalent ellipse (half-width `b_e`
//! of the patch, `a_e = area/(π b_e)`, so that the linear limit is Kalker's
//! for an ellipse of the same area).
//!
//! **Simplifications** (stated): the gap is taken at `x = 0` with the
//! longitudinal curvature of the wheel only (no yaw); each patch is planar at
//! its deepest point's contact angle; the vertical force of a patch is
//! `N cos γ` (normal force only, as for the frictionless normal problem); a
//! run of interpenetration whose reduced region falls apart stays one patch
//! (its deepest point's); strips are the gap samples (their lateral spacing,
//! e.g. 0.1 mm, is the strip width).
//!
//! **Accuracy** (tests in `tests/integration/kik_piotrowski.rs`): exact for
//! a sphere with ε = 1/2; for constant curvatures with ε = 0.55 semi-axes
//! within 20 %, area within 11 %, peak pressure within 10 % of Hertz for
//! B/A from 0.2 to 5; against CONTACT for S1002/UIC60: area within 8 % and
//! peak pressure within 9 % on the tread, 18 % and 19 % at the flange root,
//! but +50 % and −33 % on the flange flank, where the curvature across the
//! patch is ~100 times that along it and the virtual-penetration ellipse's
//! axis ratio `√(A/B)` is far from Hertz's (no correction of it here).
//!
//! **Cost** (criterion, `benches/kik_piotrowski.rs`): per wheel, tens to a
//! few hundred times Hertz with the 10-strip law, growing with the number of
//! strips (the Boussinesq sum is 8 kernel evaluations per strip); the gap
//! sampling across the whole profile costs as much again.

use crate::creep::{ContactPatch, CreepError, CreepForces, Creepages, StripSolution, validate};
use crate::geometry::GapSample;
use std::f64::consts::PI;

/// Default penetration-reduction factor ε (Piotrowski & Kik 2008; UM).
pub const PENETRATION_REDUCTION: f64 = 0.55;

/// Gauss–Legendre nodes and weights on [0, 1] (8 points) for the `θ` rule.
const GL8: [(f64, f64); 8] = [
    (0.019_855_071_751_231_856, 0.050_614_268_145_188_13),
    (0.101_666_761_293_186_63, 0.111_190_517_226_687_24),
    (0.237_233_795_041_835_5, 0.156_853_322_938_943_64),
    (0.408_282_678_752_175_1, 0.181_341_891_689_181),
    (0.591_717_321_247_825, 0.181_341_891_689_181),
    (0.762_766_204_958_164_5, 0.156_853_322_938_943_64),
    (0.898_333_238_706_813_4, 0.111_190_517_226_687_24),
    (0.980_144_928_248_768_2, 0.050_614_268_145_188_13),
];

/// Errors of the Kik–Piotrowski contact: which input is wrong and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KikPiotrowskiError {
    /// An invalid input value.
    #[error("Kik–Piotrowski contact: invalid {what}: {message}")]
    Invalid {
        /// Which input.
        what: &'static str,
        /// What is wrong.
        message: String,
    },
    /// No vertical approach gives the requested vertical force.
    #[error("Kik–Piotrowski contact: no approach up to 10 mm carries the vertical force {0} N")]
    NoSolution(f64),
}

fn invalid(what: &'static str, message: impl Into<String>) -> KikPiotrowskiError {
    KikPiotrowskiError::Invalid {
        what,
        message: message.into(),
    }
}

/// Settings of the method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KikPiotrowski {
    /// Penetration-reduction factor ε (–), in (0, 1]; default
    /// [`PENETRATION_REDUCTION`].
    pub penetration_reduction: f64,
    /// Young's modulus `E` of wheel and rail (Pa).
    pub young: f64,
    /// Poisson ratio `ν` of wheel and rail (–).
    pub poisson: f64,
}

impl Default for KikPiotrowski {
    /// ε = 0.55, steel (E = 210 GPa, ν = 0.28).
    fn default() -> Self {
        Self {
            penetration_reduction: PENETRATION_REDUCTION,
            young: 2.1e11,
            poisson: 0.28,
        }
    }
}

/// One strip of a [`Patch`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Strip {
    /// Lateral position in the patch's tangent plane from its reference point (m).
    pub s: f64,
    /// Width (m).
    pub width: f64,
    /// Half-length in the rolling direction (m).
    pub half_length: f64,
    /// Peak pressure of the strip, at `x = 0` (Pa).
    pub pressure: f64,
}

/// One contact patch of a wheel.
#[derive(Debug, Clone, PartialEq)]
pub struct Patch {
    /// Strips across the patch, in the order of the gap samples.
    pub strips: Vec<Strip>,
    /// Reference point (the deepest sample): lateral position of the rail point in the
    /// track frame (m).
    pub rail_y: f64,
    /// Height of the rail point of the reference point (m, rail profile
    /// convention, as [`crate::geometry::Contact::rail_z`]).
    pub rail_z: f64,
    /// Wheel profile coordinate of the reference point (m).
    pub wheel_u: f64,
    /// Contact angle at the reference point (rad).
    pub contact_angle: f64,
    /// Rolling radius at the reference point (m).
    pub rolling_radius: f64,
    /// Normal approach `δ₀` (m, not reduced).
    pub approach: f64,
    /// Normal force (N).
    pub normal_force: f64,
    /// Largest pressure `p₀` (Pa).
    pub max_pressure: f64,
    /// Area (m²).
    pub area: f64,
}

impl Patch {
    /// Vertical force of the patch (N): `N cos γ`.
    pub fn vertical_force(&self) -> f64 {
        self.normal_force * self.contact_angle.cos()
    }

    /// Lateral extent of the patch in its tangent plane (m).
    pub fn width(&self) -> f64 {
        self.strips.iter().map(|s| s.width).sum()
    }

    /// Largest half-length of a strip (m).
    pub fn max_half_length(&self) -> f64 {
        self.strips
            .iter()
            .map(|s| s.half_length)
            .fold(0.0, f64::max)
    }

    /// The equivalent ellipse (m): `b_e` half the lateral extent,
    /// `a_e = area/(π b_e)`.
    pub fn equivalent_ellipse(&self) -> (f64, f64) {
        let b = 0.5 * self.width();
        (self.area / (PI * b), b)
    }

    /// Tangential forces on the wheel (N, N·m about the reference point, the
    /// contact frame and sign convention of [`crate::creep`]) for the
    /// creepages `c` (spin about the reference point), shear modulus `g` (Pa),
    /// Poisson ratio `nu` and friction coefficient `mu`, by strips
    /// (module documentation).
    pub fn creep_forces(
        &self,
        g: f64,
        nu: f64,
        mu: f64,
        c: &Creepages,
    ) -> Result<CreepForces, CreepError> {
        let (a, b) = self.equivalent_ellipse();
        let cp = ContactPatch {
            a,
            b,
            g,
            nu,
            mu,
            n: self.normal_force,
        };
        let k = validate(&cp, c)?;
        if self.normal_force == 0.0 || mu == 0.0 {
            return Ok(CreepForces::default());
        }
        let sol = StripSolution::new(a, b, g, &k, c);
        let mut f = CreepForces::default();
        for st in &self.strips {
            if st.pressure > 0.0 {
                sol.add_strip(&mut f, c, st.s, st.half_length, mu * st.pressure, st.width);
            }
        }
        Ok(f)
    }
}

impl KikPiotrowski {
    fn validate(&self) -> Result<(), KikPiotrowskiError> {
        let e = self.penetration_reduction;
        if !(e.is_finite() && e > 0.0 && e <= 1.0) {
            return Err(invalid(
                "penetration reduction",
                format!("must be in (0, 1], got {}", crate::readable(e)),
            ));
        }
        if !(self.young.is_finite() && self.young > 0.0) {
            return Err(invalid(
                "Young's modulus",
                format!(
                    "must be positive and finite, got {} Pa",
                    crate::readable(self.young)
                ),
            ));
        }
        if !(self.poisson.is_finite() && (0.0..0.5).contains(&self.poisson)) {
            return Err(invalid(
                "Poisson ratio",
                format!("must be in [0, 0.5), got {}", crate::readable(self.poisson)),
            ));
        }
        Ok(())
    }

    /// The patches of a wheel for the vertical approach `approach` (m) on the
    /// gap samples `samples` (ordered along the profile); none where the
    /// wheel does not touch.
    pub fn patches(
        &self,
        samples: &[GapSample],
        approach: f64,
    ) -> Result<Vec<Patch>, KikPiotrowskiError> {
        self.validate()?;
        if !approach.is_finite() {
            return Err(invalid(
                "approach",
                format!("must be finite, got {approach}"),
            ));
        }
        for (i, s) in samples.iter().enumerate() {
            let v = [s.rail_y, s.gap, s.rolling_radius, s.contact_angle];
            if v.iter().any(|x| !x.is_finite()) || s.rolling_radius <= 0.0 {
                return Err(invalid(
                    "gap sample",
                    format!(
                        "sample {i} (wheel u = {} m) is not finite or has a non-positive radius",
                        crate::readable(s.wheel_u)
                    ),
                ));
            }
        }
        let mut out = Vec::new();
        let mut i = 0;
        while i < samples.len() {
            if approach - samples[i].gap <= 0.0 {
                i += 1;
                continue;
            }
            let start = i;
            while i < samples.len() && approach - samples[i].gap > 0.0 {
                i += 1;
            }
            if let Some(p) = self.patch(&samples[start..i], approach) {
                out.push(p);
            }
        }
        Ok(out)
    }

    /// One patch from a run of interpenetrating samples.
    fn patch(&self, run: &[GapSample], approach: f64) -> Option<Patch> {
        let deepest = run
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.gap.total_cmp(&b.1.gap))?
            .0;
        let r = run[deepest];
        let cg = r.contact_angle.cos();
        let delta0 = (approach - r.gap) * cg;
        let h0 = self.penetration_reduction * delta0;
        // Strips where the virtual penetration is positive; width from the
        // midpoints to the neighbouring samples, in the tangent plane.
        let n = run.len();
        let mut strips = Vec::new();
        for j in 0..n {
            let h = h0 - (run[j].gap - r.gap) * cg;
            if h <= 0.0 {
                continue;
            }
            let lo = if j > 0 {
                0.5 * (run[j - 1].rail_y + run[j].rail_y)
            } else {
                run[j].rail_y
            };
            let hi = if j + 1 < n {
                0.5 * (run[j + 1].rail_y + run[j].rail_y)
            } else {
                run[j].rail_y
            };
            let width = (hi - lo).abs() / cg;
            if width == 0.0 {
                continue;
            }
            let a2 = cg / (2.0 * run[j].rolling_radius);
            strips.push(Strip {
                s: (run[j].rail_y - r.rail_y) / cg,
                width,
                half_length: (h / a2).sqrt(),
                // the amplitude √(h/h₀) for now; times p₀ below
                pressure: (h / h0).sqrt(),
            });
        }
        if strips.is_empty() {
            return None;
        }
        // Boussinesq at the reference point: δ₀ = (2(1 − ν²)/(πE)) p₀ J.
        let mut j_int = 0.0;
        let mut load = 0.0;
        let mut area = 0.0;
        for st in &strips {
            let (d, w, l) = (st.s.abs(), st.width, st.half_length);
            // ∫_{−l}^{l} √(1 − x²/l²) K(x) dx, x = l sin θ, θ = (π/2)t², t ∈ [0, 1]
            // (clusters nodes at x = 0 where K has its log singularity for d < w/2).
            let mut acc = 0.0;
            for &(t, wt) in &GL8 {
                let th = 0.5 * PI * t * t;
                let (sn, cs) = th.sin_cos();
                let x = l * sn;
                let k = if x == 0.0 {
                    0.0
                } else {
                    // asinh(D₁/x) − asinh(D₂/x) as one logarithm, D₁ = d + w/2,
                    // D₂ = d − w/2 (for D₂ < 0 as asinh(D₁/x) + asinh(|D₂|/x),
                    // without cancellation)
                    let (d1, d2) = (d + 0.5 * w, d - 0.5 * w);
                    let x2 = x * x;
                    let e1 = d1 + (d1 * d1 + x2).sqrt();
                    let e2 = d2.abs() + (d2 * d2 + x2).sqrt();
                    let ratio = if d2 >= 0.0 { e1 / e2 } else { e1 * e2 / x2 };
                    ratio.ln() / w
                };
                // dx = l cos θ dθ, dθ = π t dt; both halves of the strip.
                acc += wt * cs * k * l * cs * PI * t;
            }
            j_int += st.pressure * 2.0 * acc * w;
            load += st.pressure * 0.5 * PI * l * w;
            area += 2.0 * l * w;
        }
        let nu = self.poisson;
        let p0 = delta0 * PI * self.young / (2.0 * (1.0 - nu * nu) * j_int);
        for st in &mut strips {
            st.pressure *= p0;
        }
        Some(Patch {
            strips,
            rail_y: r.rail_y,
            rail_z: r.rail_z,
            wheel_u: r.wheel_u,
            contact_angle: r.contact_angle,
            rolling_radius: r.rolling_radius,
            approach: delta0,
            normal_force: p0 * load,
            max_pressure: p0,
            area,
        })
    }

    /// The vertical approach (m) at which the patches carry the vertical force
    /// `fz` (N, > 0) together (`Σ N cos γ = fz`), and those patches: a
    /// bracketed secant iteration on `fz^(2/3)`, to a relative force error of 1e-9.
    pub fn patches_for_vertical_force(
        &self,
        samples: &[GapSample],
        fz: f64,
    ) -> Result<(f64, Vec<Patch>), KikPiotrowskiError> {
        if !(fz.is_finite() && fz > 0.0) {
            return Err(invalid(
                "vertical force",
                format!("must be positive and finite, got {} N", crate::readable(fz)),
            ));
        }
        let g_min = samples.iter().map(|s| s.gap).fold(f64::INFINITY, f64::min);
        if !g_min.is_finite() {
            return Err(invalid("gap samples", "none given"));
        }
        let force = |d: f64| -> Result<(f64, Vec<Patch>), KikPiotrowskiError> {
            let p = self.patches(samples, g_min + d)?;
            Ok((p.iter().map(Patch::vertical_force).sum(), p))
        };
        // F ~ d^{3/2}: iterate on φ(d) = F^{2/3} − fz^{2/3}, nearly linear.
        let target = fz.powf(2.0 / 3.0);
        let (mut lo, mut hi) = (0.0, 1e-5);
        let mut f_hi = force(hi)?.0.powf(2.0 / 3.0) - target;
        while f_hi < 0.0 {
            lo = hi;
            hi *= 2.0;
            if hi > 1e-2 {
                return Err(KikPiotrowskiError::NoSolution(fz));
            }
            f_hi = force(hi)?.0.powf(2.0 / 3.0) - target;
        }
        let mut f_lo = if lo == 0.0 {
            -target
        } else {
            force(lo)?.0.powf(2.0 / 3.0) - target
        };
        let mut best = force(hi)?;
        let mut d = hi;
        let mut side = 0i8;
        for _ in 0..200 {
            // regula falsi with the Illinois modification inside the bracket
            let mut x = lo - f_lo * (hi - lo) / (f_hi - f_lo);
            if !(x > lo && x < hi) {
                x = 0.5 * (lo + hi);
            }
            let r = force(x)?;
            let fx = r.0.powf(2.0 / 3.0) - target;
            d = x;
            best = r;
            if (best.0 - fz).abs() <= 1e-9 * fz || hi - lo < 1e-15 {
                break;
            }
            if fx < 0.0 {
                lo = x;
                f_lo = fx;
                if side == -1 {
                    f_hi *= 0.5;
                }
                side = -1;
            } else {
                hi = x;
                f_hi = fx;
                if side == 1 {
                    f_lo *= 0.5;
                }
                side = 1;
            }
        }
        Ok((g_min + d, best.1))
    }
}
