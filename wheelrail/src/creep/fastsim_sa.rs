//! FastSim_SA (Pogorelov 2005, Sect. 4.3, Fig. 24): FASTSIM with the
//! analytic solution in the adhesion zone only. Each strip's adhesion zone,
//! from the leading edge to the point `x*` where the elastic traction reaches
//! the bound, is FastSim_A's exact strip solution (Pogorelov 2005, Eqs.
//! 20–21: `p = (aⱼ − x)(A, B + C(aⱼ + x))`, boundary from the quadratic in
//! closed form) integrated exactly; the rest of the strip, `−aⱼ ≤ x ≤ x*`, is
//! FASTSIM's discretisation: equal elements no longer than a FASTSIM element
//! of `n` per strip (`2aⱼ/n`), the traction stepped from `x*` element centre
//! by element centre with the exact rigid-slip increment `∫ w dx` and scaled
//! back onto the bound where it exceeds it (Kalker's rule, so re-adhesion in
//! the sliding zone is kept, as in FASTSIM). Strips are marched four at a
//! time, interleaved, as [`super::Fastsim`] does.
//!
//! Same notation, strips and parabolic bound as [`super::FastsimA`] (module
//! `fastsim_a`): `m` strips of equal width at their centre lines, bound
//! `g = K(aⱼ² − x²)` with `K` such that the strips carry exactly `N`. In
//! the sliding zone the bound of an element is its mean over the element,
//! `K(aⱼ² − x_c² − h²/12)` (`x_c` the centre), rather than FASTSIM's centre
//! value, so that sliding elements carry the bound's exact integral and a
//! fully sliding contact exactly `μN` (the centre value would give
//! `μN(1 + 1/(2n²))`); the two differ by `O(h²)`, as the midpoint rule does.
//!
//! As `n → ∞` it converges to FASTSIM with as many elements and the same
//! strips (the adhesion zone is exact; the sliding zone is FASTSIM's own
//! march), and at zero spin it is exact for any `n` up to the bound's
//! quadrature (the direction does not turn): see the integration tests
//! `fastsim_sa`. Its cost is that of FASTSIM over the sliding zone only:
//! the fewer elements slide, the larger the gain (Pogorelov 2005, Fig. 24).
//! Measured (criterion bench `creep`, group `fig24`: 10 strips, 64
//! running-surface cases, one core of a shared 2-core machine), the time of
//! FASTSIM over FastSim_SA with `n` elements per strip: 0.82 (n = 5), 1.45
//! (10), 1.99 (20), 2.99 (40), 3.44 (60), 3.85 (80), 3.90 (100); the paper's
//! Fig. 24 rises to about 5 at n = 100. On the 64 tread cases of group
//! `creep` (creepages to 6e-3, mostly sliding) 10 × 10 costs as FASTSIM's
//! (2.2 million evaluations per second each).

use super::fastsim_a::{StripConsts, Strips, adhesion_boundary, adhesion_zone};
use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, Flexibilities, validate};

/// Largest number of strips or elements per strip accepted.
const MAX_DIVISIONS: usize = 100_000;

/// FastSim_SA with `strips` strips and FASTSIM elements of `2aⱼ/elements` in
/// the sliding zones.
#[derive(Debug, Clone)]
pub struct FastsimSa {
    /// The strips of the unit ellipse.
    strips: Strips,
    /// FASTSIM elements per strip, `n`.
    elements: usize,
}

impl FastsimSa {
    /// FastSim_SA with `strips` strips and `elements` FASTSIM elements per
    /// strip (both in 1..=100 000).
    pub fn new(strips: usize, elements: usize) -> Result<Self, CreepError> {
        for (what, v) in [("strips", strips), ("elements", elements)] {
            if v == 0 || v > MAX_DIVISIONS {
                return Err(CreepError::Parameter(format!(
                    "FastSim_SA number of {what} must be in 1..={MAX_DIVISIONS}, got {v}"
                )));
            }
        }
        Ok(Self {
            strips: Strips::new(strips),
            elements,
        })
    }

    /// Inputs validated, `N > 0`, `μ > 0`.
    fn eval(&self, p: &ContactPatch, c: &Creepages, fl: &Flexibilities) -> CreepForces {
        let kk = p.mu * p.n / (self.strips.norm * p.a * p.a * p.a * p.b);
        let bb = c.eta * fl.inv_l2;
        let cc = 0.5 * c.phi * fl.inv_l3;
        let k = StripConsts {
            a: p.a,
            b: p.b,
            kk,
            bb,
            cc,
            alpha: kk * kk - cc * cc,
            bc: bb * cc,
            wx: c.xi * fl.inv_l1,
            wphi: c.phi * fl.inv_l3,
        };
        let nf = self.elements as f64;
        let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
        // Strips LANES at a time, interleaved (as FASTSIM): the sliding
        // march of each strip is a loop-carried dependency (traction → bound
        // → traction); lanes past their own element count get weight 0.
        const LANES: usize = 4;
        for chunk in self.strips.geom.chunks(LANES) {
            let mut y = [0.0; LANES];
            let mut a2 = [0.0; LANES];
            let mut a_ = [0.0; LANES];
            let mut count = [0usize; LANES];
            let mut h = [0.0; LANES];
            let mut x = [0.0; LANES];
            let mut px = [0.0; LANES];
            let mut py = [0.0; LANES];
            for (l, &(e, sj)) in chunk.iter().enumerate() {
                y[l] = e * k.b;
                let aj = k.a * sj;
                a2[l] = aj * aj;
                a_[l] = k.wx - k.wphi * y[l];
                let tstar = adhesion_boundary(a_[l], aj, &k);
                let (afx, afy, amz) = adhesion_zone(a_[l], aj, y[l], tstar, bb, cc);
                fx += afx;
                fy += afy;
                mz += amz;
                if tstar > 0.0 {
                    // Sliding zone −aⱼ ≤ x ≤ x*: elements of h ≤ 2aⱼ/n.
                    let c = (nf * tstar / (2.0 * aj)).ceil().max(1.0);
                    count[l] = c as usize;
                    h[l] = tstar / c;
                    // The adhesion solution at x* (on the bound; zero if the
                    // strip slides from the leading edge), stepped elastically
                    // half an element to the first centre.
                    let lead = 2.0 * aj - tstar;
                    let xs = tstar - aj;
                    let xn = xs - 0.5 * h[l];
                    px[l] = lead * a_[l] + a_[l] * 0.5 * h[l];
                    py[l] = lead * (bb + cc * tstar) + bb * 0.5 * h[l] + cc * (xs * xs - xn * xn);
                    x[l] = xn;
                }
            }
            let steps = count.iter().copied().max().unwrap_or(0);
            let mut sx = [0.0; LANES];
            let mut sy = [0.0; LANES];
            let mut sm = [0.0; LANES];
            for i in 0..steps {
                for l in 0..LANES {
                    let on = if i < count[l] { 1.0 } else { 0.0 };
                    // Bound: its mean over the element, K(aⱼ² − x_c² − h²/12),
                    // so that sliding elements carry its exact integral.
                    let g = kk * (a2[l] - x[l] * x[l] - h[l] * h[l] * (1.0 / 12.0));
                    let t2 = px[l] * px[l] + py[l] * py[l];
                    // min ignores the NaN of 0/0 (zero traction).
                    let sc = (g / t2.sqrt()).min(1.0);
                    px[l] *= sc;
                    py[l] *= sc;
                    let w = h[l] * on;
                    sx[l] += px[l] * w;
                    sy[l] += py[l] * w;
                    sm[l] += x[l] * py[l] * w;
                    // Elastic step to the next centre: p += ∫ w d(−x),
                    // w = (A, B + 2Cx), exact.
                    let xn = x[l] - h[l];
                    px[l] += a_[l] * h[l];
                    py[l] += bb * h[l] + cc * (x[l] * x[l] - xn * xn);
                    x[l] = xn;
                }
            }
            for l in 0..chunk.len() {
                fx += sx[l];
                fy += sy[l];
                mz += sm[l] - y[l] * sx[l];
            }
        }
        let dy = self.strips.d_eta * p.b;
        CreepForces {
            fx: -fx * dy,
            fy: -fy * dy,
            mz: -mz * dy,
        }
    }
}

impl CreepLaw for FastsimSa {
    fn name(&self) -> &'static str {
        "fastsim-sa"
    }

    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        let k = validate(p, c)?;
        if p.n == 0.0 || p.mu == 0.0 {
            return Ok(CreepForces::default());
        }
        let fl = Flexibilities::new(p, &k);
        Ok(self.eval(p, c, &fl))
    }
}
