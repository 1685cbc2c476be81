//! A strip-theory creep law in the spirit of FaStrip (Sichani, Enblom, Berg
//! 2016, "An alternative to FASTSIM for tangential solution of the wheel–rail
//! contact", VSD 54): Kalker's strip theory for the creepages, with its
//! linear limit calibrated to Kalker's linear theory, and spin carried into
//! the strips through FASTSIM's flexibility. **It is this project's own
//! derivation, not FaStrip's published formulas** (the paper was not
//! available when it was written); how close it comes to FaStrip's accuracy
//! is measured against CONTACT's exact theory and CONTACT's FaStrip in the
//! tests (`tests/integration/exact_theory.rs`).
//!
//! **Strips.** The ellipse is cut across `y` into strips at `y = b sin θ`
//! with `θ` equally spaced (midpoint rule in `θ`: exact for the even
//! weights `cos²θ`, `cos⁴θ` of the linear forces, O(1/n²) for the odd
//! `cos³θ` of the load, so the full-sliding force is `μN` within 1.1e-4 at
//! 10 strips). A strip has half-length `l = a cos θ` and Hertz pressure
//! `p = p₀(y)√(1 − x²/l²)`, `p₀(y) = p₀ cos θ`, `p₀ = 3N/(2πab)`.
//!
//! **One strip** (Carter's two-dimensional solution, extended to lateral
//! creepage by Kalker's strip theory, 1967): with the normalized creepages
//! `s = (s_x, s_y)`, `s_x = (2 G C11/(π² μ p₀(y)))·ξ(y)`,
//! `s_y = (2 G C22/(π² μ p₀(y)))·η(y)` (Carter's `ξ_c = 2(1 − ν)μp₀/G` is
//! the case `C11 = π²/(4(1 − ν))`, Kalker's limit for `a/b → 0`: with
//! Kalker's `C11`, `C22` the small-creepage limit is Kalker's linear theory
//! for every `a/b`), the adhesion zone at the leading edge has half-length
//! `l' = l(1 − |s|)` (none for `|s| ≥ 1`), the force per unit width is
//! `μ p₀(y)(π/2) l (1 − (l'/l)²)` along `−s/|s|`, and its centre lies at
//! `x̄ = −l'²/(l + l')` (behind the centre: the traction grows towards the
//! trailing edge).
//!
//! **Spin.** Its longitudinal rigid slip `−φy` is constant along a strip and
//! enters `ξ(y) = ξ − κφy`; its lateral slip `φx` is not, and enters as the
//! lateral creepage that gives the strip FASTSIM's linear lateral force from
//! spin (flexibility `L3 = πa√(a/b)/(4 C23 G)`, force `(2/3)l³φ/L3` per
//! unit width): `η(y) = η + (4/3)(C23/C22)√(b/a) l² φ/a`. The two
//! calibration factors, `κ` on the longitudinal spin slip and `λ` on the
//! lateral force's lever arm `x̄`, make the linear limit Kalker's in all
//! four coefficients (`C11`, `C22`, `C23` both ways, `C33`):
//! `λ = (3π/4)(C23/C22)√(b/a)`, `κ = (4/C11)(a/b)(C33 + (64λ/(45π)) C23 √(a/b))`.
//!
//! **Simplifications** (stated, measured in the tests): one slip direction
//! per strip (the exact theory's slip turns along a strip under spin); spin's
//! lateral part saturates like a creepage; Kalker's coefficients by table
//! interpolation ([`crate::kalker`]). Cost: a square root and a division per
//! strip.

use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, validate};
use crate::kalker::KalkerCoefficients;
use std::f64::consts::PI;

/// Default number of strips of [`StripTheory`] (`strip` on the command line).
pub const STRIP_THEORY_STRIPS: usize = 10;

/// Largest number of strips accepted.
const MAX_STRIPS: usize = 100_000;

/// The strip-theory law (module documentation) with a fixed number of strips.
#[derive(Debug, Clone)]
pub struct StripTheory {
    /// Per strip: (sin θ, cos θ) at its centre.
    strips: Vec<(f64, f64)>,
    /// Δθ = π / strips.
    d_theta: f64,
}

impl StripTheory {
    /// The law with `strips` strips (1..=100 000).
    pub fn new(strips: usize) -> Result<Self, CreepError> {
        if strips == 0 || strips > MAX_STRIPS {
            return Err(CreepError::Parameter(format!(
                "strip theory: number of strips must be in 1..={MAX_STRIPS}, got {strips}"
            )));
        }
        let d_theta = PI / strips as f64;
        Ok(Self {
            strips: (0..strips)
                .map(|i| {
                    let t = -0.5 * PI + (i as f64 + 0.5) * d_theta;
                    (t.sin(), t.cos())
                })
                .collect(),
            d_theta,
        })
    }

    /// Number of strips.
    pub fn strips(&self) -> usize {
        self.strips.len()
    }
}

impl CreepLaw for StripTheory {
    fn name(&self) -> &'static str {
        "strip"
    }

    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        let k = validate(p, c)?;
        if p.n == 0.0 || p.mu == 0.0 {
            return Ok(CreepForces::default());
        }
        let (a, b) = (p.a, p.b);
        let sol = StripSolution::new(a, b, p.g, &k, c);
        let mu_p0 = p.mu * 3.0 * p.n / (2.0 * PI * a * b);
        let w0 = b * self.d_theta;
        let mut f = CreepForces::default();
        for &(s, co) in &self.strips {
            // Hertz strip: y = b sin θ, l = a cos θ, p₀(y) = p₀ cos θ, width b cos θ Δθ.
            sol.add_strip(&mut f, c, b * s, a * co, mu_p0 * co, w0 * co);
        }
        Ok(f)
    }
}

/// The strip solution of the module documentation for one patch: the
/// calibration constants from the semi-axes `a`, `b` (m) of the patch's
/// ellipse (for a non-elliptic patch, its equivalent ellipse: the linear
/// limit is then Kalker's for that ellipse), and the per-strip force. The one
/// home of the strip solution: [`StripTheory`] cuts a Hertz ellipse into
/// strips, [`crate::kik_piotrowski`] a non-elliptic patch.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StripSolution {
    /// 2 G C11/π², 2 G C22/π² (Pa): times the creepage over μp₀(y) they give `s`.
    cx: f64,
    cy: f64,
    /// λ of the lateral lever arm.
    lambda: f64,
    /// κφ (1/m): the longitudinal spin slip per unit y.
    kphi: f64,
    /// Lateral creepage from spin per l² (1/m²).
    spin_eta: f64,
}

impl StripSolution {
    /// Constants for the ellipse `a`, `b` (m), shear modulus `g` (Pa),
    /// Kalker's coefficients `k` of that ellipse and the creepages `c`.
    #[inline]
    pub(crate) fn new(a: f64, b: f64, g: f64, k: &KalkerCoefficients, c: &Creepages) -> Self {
        let rba = (b / a).sqrt();
        let lambda = 0.75 * PI * k.c23 / k.c22 * rba;
        let kappa = 4.0 / k.c11 * (a / b) * (k.c33 + 64.0 * lambda / (45.0 * PI) * k.c23 / rba);
        Self {
            cx: 2.0 * g * k.c11 / (PI * PI),
            cy: 2.0 * g * k.c22 / (PI * PI),
            lambda,
            kphi: kappa * c.phi,
            // (4/3)(C23/C22)√(b/a) φ/a
            spin_eta: 4.0 / 3.0 * k.c23 / k.c22 * rba * c.phi / a,
        }
    }

    /// Adds to `f` the force of one strip at lateral position `y` (m, from
    /// the point the creepages `c` refer to), half-length `l` (m), peak
    /// pressure times friction `mu_p0` (Pa, > 0) and width `w` (m): μp₀(π/2)lw(1 − α²)
    /// along −s/|s| (module documentation), its moment about that point.
    #[inline]
    pub(crate) fn add_strip(
        &self,
        f: &mut CreepForces,
        c: &Creepages,
        y: f64,
        l: f64,
        mu_p0: f64,
        w: f64,
    ) {
        let inv = 1.0 / mu_p0;
        let sx = self.cx * inv * (c.xi - self.kphi * y);
        let sy = self.cy * inv * (c.eta + self.spin_eta * l * l);
        let sn = sx.hypot(sy);
        if sn == 0.0 {
            return;
        }
        let alpha = (1.0 - sn).max(0.0);
        let force = mu_p0 * 0.5 * PI * l * w * (1.0 - alpha * alpha) / sn;
        let (sfx, sfy) = (-force * sx, -force * sy);
        let xbar = -self.lambda * l * alpha * alpha / (1.0 + alpha);
        f.fx += sfx;
        f.fy += sfy;
        f.mz += xbar * sfy - y * sfx;
    }
}
