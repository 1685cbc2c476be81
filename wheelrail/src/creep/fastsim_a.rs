//! FastSim_A: a semi-analytic FASTSIM (after D. Yu. Pogorelov's FastSim_A, seed
//! paper Sect. 4.3): each strip of the contact ellipse is solved in closed form,
//! so the cost is proportional to the number of strips only.
//!
//! On a strip at lateral position `y` with half-length `a_y = a√(1 − y²/b²)`,
//! with the parabolic traction bound `g(x) = K (a_y² − x²)` and the rigid slip
//! of the simplified theory `w(x) = (A, B + 2Cx)`, `A = ξ/L1 − φy/L3`,
//! `B = η/L2`, `C = φ/(2L3)`:
//!
//! - **Adhesion zone** (from the leading edge): the exact solution of FASTSIM's
//!   differential equation `dp/d(−x) = w` is `p = (a_y − x)·(A, B + C(a_y + x))`.
//!   With `t = a_y + x` the traction reaches the bound where
//!   `A² + (B + Ct)² = K²t²`, a quadratic in `t` solved in closed form; the
//!   adhesion zone is `t* ≤ t ≤ 2a_y`, and its force and moment are polynomial
//!   integrals.
//! - **Sliding zone** (`−a_y ≤ x ≤ x*`): the traction is on the bound,
//!   `p = g·e`. The exact direction obeys `dθ/d(−x) = |w| sin(θ_w − θ)/g`
//!   (FASTSIM's scaling onto the bound), which has no closed-form solution. It is
//!   approximated by the direction of the adhesion solution continued into the
//!   sliding zone, `e ≈ d/|d|`, `d = (A, B + C(a_y + x))`: the traction keeps
//!   turning as the accumulated elastic displacement would. This is exact for
//!   zero spin (then `d ∥ w` is constant and never turns, and FastSim_A equals
//!   FASTSIM with infinitely many elements: property 1 of the seed paper), and
//!   compared with the rigid-slip direction `w/|w|` (tried first) it reduces the
//!   error against fine FASTSIM at tread-contact spin from 15–30 % to 1–4 %. The force is
//!   integrated in closed form: with `u = B + C(a_y + x)` the integrands are
//!   `polynomial(u)/√(A² + u²)`, and `∫ uᵏ/√(A² + u²) du` (k ≤ 4) are elementary
//!   (one logarithm, two square roots and two divisions per strip). Where the
//!   direction turns little over the zone (`|C|ℓ ≤ 0.4|d|`, `d` at the zone's
//!   midpoint) — always for zero spin — a second-order Taylor expansion of the
//!   direction about the midpoint is integrated instead: cheaper, free of the
//!   closed form's cancellation as `C → 0`, and within 5.4e-4 of the closed
//!   form at the switching threshold (unit test), exact for zero spin.
//!
//! Deviation from the seed paper: its Sect. 4.3 text (Eqs. 20–21, 26 and the
//! improved Picard-step approximation) could not be retrieved with the project's
//! search tool; the adhesion zone above is the exact strip solution the paper
//! describes, the sliding-zone direction is this module's own approximation, and
//! no Picard-step correction is applied. The error grows with spin: against
//! FASTSIM with 2000–4000 elements per strip (same strips) it is at most 4.2 %
//! of the total force for `|φ|·a ≤ 0.002` (tread contact; test
//! `fastsim_a_against_fine_fastsim`), up to 7.5 % at `|φ|·a ≈ 0.004`, 4 % on
//! CONTACT's FASTSIM example (`φa = 0.005`), and 15–70 % for flange-contact spin
//! (`|φ|·a ≈ 0.01–0.02`), where FASTSIM itself is far from the exact theory.
//!
//! Strips: `m` strips of equal width at their centre lines, the same layout as
//! [`super::Fastsim`]'s strip layout, with `K` scaled so that the strips carry
//! exactly `N` (the saturated force is exactly `μN`).

use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, Flexibilities, validate};

/// Largest number of strips accepted.
const MAX_STRIPS: usize = 100_000;

/// FastSim_A with a given number of strips.
#[derive(Debug, Clone)]
pub struct FastsimA {
    /// Per strip: (η = y/b at the strip centre, √(1 − η²) = a_y/a).
    strip_geom: Vec<(f64, f64)>,
    /// Σ (4/3)(1 − η²)^(3/2)·Δη: the strips' bound integral for a = b = 1.
    norm: f64,
    /// Strip width for b = 1: Δη = 2/m.
    d_eta: f64,
}

/// Integrals over one strip (traction on the rail, before the sign flip).
#[derive(Debug, Clone, Copy, Default)]
struct StripSums {
    fx: f64,
    fy: f64,
    mz: f64,
}

impl FastsimA {
    /// FastSim_A with `strips` strips.
    pub fn new(strips: usize) -> Result<Self, CreepError> {
        if strips == 0 || strips > MAX_STRIPS {
            return Err(CreepError::Parameter(format!(
                "FastSim_A number of strips must be in 1..={MAX_STRIPS}, got {strips}"
            )));
        }
        let mf = strips as f64;
        let strip_geom: Vec<(f64, f64)> = (0..strips)
            .map(|j| {
                let e = -1.0 + (j as f64 + 0.5) * 2.0 / mf;
                (e, (1.0 - e * e).max(0.0).sqrt())
            })
            .collect();
        let norm = strip_geom.iter().map(|&(_, s)| s * s * s).sum::<f64>() * (4.0 / 3.0) * 2.0 / mf;
        Ok(Self {
            strip_geom,
            norm,
            d_eta: 2.0 / mf,
        })
    }

    /// Strips are processed in chunks of `LANES`: branch-free passes over the
    /// lanes (adhesion boundaries; then adhesion zones and the Taylor branch of
    /// the sliding zones) let the compiler overlap or vectorise the independent
    /// square roots and divisions of the strips; sliding zones whose direction
    /// turns much take the closed form (with a logarithm) in a last pass.
    #[inline]
    fn eval(&self, p: &ContactPatch, c: &Creepages, fl: &Flexibilities) -> CreepForces {
        let dy = self.d_eta * p.b;
        // Bound g = K(aⱼ² − x²) with K such that the strips carry exactly μN.
        let kk = p.mu * p.n / (self.norm * p.a * p.a * p.a * p.b);
        let bb = c.eta * fl.inv_l2;
        let cc = 0.5 * c.phi * fl.inv_l3;
        let alpha = kk * kk - cc * cc;
        let bc = bb * cc;
        let k = StripConsts {
            a: p.a,
            b: p.b,
            kk,
            bb,
            cc,
            alpha,
            bc,
            wx: c.xi * fl.inv_l1,
            wphi: c.phi * fl.inv_l3,
        };
        // Full chunks of 8 lanes, the rest in chunks of 2 (a dummy lane of zero
        // length if odd): every lane computed is a strip.
        let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
        let n8 = self.strip_geom.len() / 8 * 8;
        for chunk in self.strip_geom[..n8].chunks(8) {
            let (x, y, m) = chunk_sums::<8>(chunk, &k);
            fx += x;
            fy += y;
            mz += m;
        }
        for chunk in self.strip_geom[n8..].chunks(2) {
            let (x, y, m) = chunk_sums::<2>(chunk, &k);
            fx += x;
            fy += y;
            mz += m;
        }
        CreepForces {
            fx: -fx * dy,
            fy: -fy * dy,
            mz: -mz * dy,
        }
    }
}

/// ∫ uᵏ/√(A² + u²) du between u1 and u2 for k = 0..4.
struct Antiderivs {
    j: [f64; 5],
}

/// `u + √(A²+u²)` as a fraction `(num, den)`, cancellation-free for negative
/// `u` (`A²/(r − u)`).
#[inline]
fn log_arg(u: f64, r: f64, a2: f64) -> (f64, f64) {
    if u >= 0.0 { (u + r, 1.0) } else { (a2, r - u) }
}

#[inline]
fn sqrt_integrals(a2: f64, u1: f64, u2: f64) -> Antiderivs {
    let r1 = (a2 + u1 * u1).sqrt();
    let r2 = (a2 + u2 * u2).sqrt();
    // J0 = asinh(u2/|A|) − asinh(u1/|A|) = ln(s2/s1), one division.
    let (n1, d1) = log_arg(u1, r1, a2);
    let (n2, d2) = log_arg(u2, r2, a2);
    let j0 = ((n2 * d1) / (d2 * n1)).ln();
    let j1 = r2 - r1;
    let j2 = 0.5 * ((u2 * r2 - u1 * r1) - a2 * j0);
    let j3 = (r2 * r2 * r2 - r1 * r1 * r1) * (1.0 / 3.0) - a2 * j1;
    let j4 = 0.25 * ((u2 * u2 * u2 * r2 - u1 * u1 * u1 * r1) - 3.0 * a2 * j2);
    Antiderivs {
        j: [j0, j1, j2, j3, j4],
    }
}

/// Per-evaluation constants of the strips.
struct StripConsts {
    a: f64,
    b: f64,
    kk: f64,
    bb: f64,
    cc: f64,
    alpha: f64,
    bc: f64,
    /// ξ/L1 and φ/L3.
    wx: f64,
    wphi: f64,
}

/// Force and moment sums (traction on the rail, times 1/Δy) of up to `LANES`
/// strips processed together.
#[inline(always)]
fn chunk_sums<const LANES: usize>(chunk: &[(f64, f64)], k: &StripConsts) -> (f64, f64, f64) {
    let StripConsts {
        kk,
        bb,
        cc,
        alpha,
        bc,
        ..
    } = *k;
    // 1/C for the closed-form sliding zones (only used where C ≠ 0).
    let inv_cc = 1.0 / cc;
    let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
    let mut aj = [0.0; LANES];
    let mut y = [0.0; LANES];
    let mut aa = [0.0; LANES];
    for (l, &(e, sj)) in chunk.iter().enumerate() {
        y[l] = e * k.b;
        aj[l] = k.a * sj;
        aa[l] = k.wx - k.wphi * y[l];
    }
    let mut sx = [0.0; LANES];
    let mut sy = [0.0; LANES];
    let mut sm = [0.0; LANES];
    let mut xs_l = [0.0; LANES];
    let mut closed = [false; LANES];
    // Pass 1: adhesion boundaries of all lanes (independent roots).
    let mut ts = [0.0; LANES];
    for l in 0..LANES {
        let (a_, aj_) = (aa[l], aj[l]);
        let len = 2.0 * aj_;
        let w0 = a_ * a_ + bb * bb;
        // Adhesion boundary: Q(t) = α t² − 2BC t − (A² + B²) = 0, the
        // cancellation-free root; sliding from the leading edge if
        // Q(2aⱼ) < 0, no adhesion boundary if there is no slip at all.
        let q_lead = alpha * len * len - 2.0 * bc * len - w0;
        let d = (bc * bc + alpha * w0).max(0.0).sqrt();
        let pos = bc > 0.0;
        let num = if pos { bc + d } else { w0 };
        let den = if pos { alpha } else { d - bc };

        let root = num / den;
        let t = if q_lead < 0.0 {
            len
        } else if w0 == 0.0 {
            0.0
        } else {
            root
        };
        let tstar = t.max(0.0).min(len);
        ts[l] = tstar;
    }
    // Pass 2: zone integrals.
    for l in 0..LANES {
        let (a_, aj_, y_) = (aa[l], aj[l], y[l]);
        let len = 2.0 * aj_;
        let tstar = ts[l];
        let xs = tstar - aj_;
        let sl = len - tstar;
        xs_l[l] = xs;
        // Adhesion zone x* ≤ x ≤ aⱼ: p = (aⱼ − x)(A, B + C(aⱼ + x)).
        let a2 = aj_ * aj_;
        let cub = sl * (a2 + aj_ * xs + xs * xs) * (1.0 / 3.0); // (aⱼ³ − x*³)/3
        let i0 = 0.5 * sl * sl; // ∫(aⱼ − x)
        let i_par = sl * a2 - cub; // ∫(aⱼ² − x²)
        let ix_lin = aj_ * sl * tstar * 0.5 - cub; // ∫x(aⱼ − x)
        let ix_par = a2 * sl * tstar * 0.5 - sl * tstar * (a2 + xs * xs) * 0.25; // ∫x(aⱼ² − x²)
        let afx = a_ * i0;
        let afy = bb * i0 + cc * i_par;
        let amz = bb * ix_lin + cc * ix_par - y_ * afx;
        // Sliding zone −aⱼ ≤ x ≤ x*: direction d = (A, B' + C x) with
        // B' = B + C aⱼ (the adhesion solution continued).
        let ell = tstar;
        let b2 = bb + cc * aj_;
        let xm = 0.5 * (xs - aj_);
        let u = b2 + cc * xm;
        let w2 = a_ * a_ + u * u;
        let turn = cc * ell;
        let taylor = turn * turn <= 0.16 * w2;
        let (tfx, tfy, tmz) = sliding_taylor(a_, y_, a2, xm, u, w2, cc, kk, ell);
        let (tfx, tfy, tmz) = if taylor {
            (tfx, tfy, tmz)
        } else {
            (0.0, 0.0, 0.0)
        };
        closed[l] = !taylor && ell > 0.0;
        sx[l] = afx + tfx;
        sy[l] = afy + tfy;
        sm[l] = amz + tmz;
    }
    for l in 0..chunk.len() {
        if closed[l] {
            let s = sliding_closed(
                aj[l],
                y[l],
                aa[l],
                bb + cc * aj[l],
                cc,
                inv_cc,
                kk,
                -aj[l],
                xs_l[l],
            );
            sx[l] += s.fx;
            sy[l] += s.fy;
            sm[l] += s.mz;
        }
        fx += sx[l];
        fy += sy[l];
        mz += sm[l];
    }
    (fx, fy, mz)
}

/// Sliding zone of length `ell` centred at `xm` by a second-order Taylor
/// expansion of the direction e(u) = (A, u)/√(A² + u²) about the midpoint
/// (`u` = direction component there, `w2 = A² + u²`, du/dx = `cc`), integrated
/// exactly against g = K(aⱼ² − x²) via the moments Mₖ = ∫ tᵏ g dt, t = x − xm.
/// Used where the direction turns little (|C|ℓ ≤ 0.4|d|); the truncation
/// error there is below 1e-3 of the zone's force (unit test below).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sliding_taylor(
    a_: f64,
    y_: f64,
    a2: f64,
    xm: f64,
    u: f64,
    w2: f64,
    cc: f64,
    kk: f64,
    ell: f64,
) -> (f64, f64, f64) {
    let inv_r = if w2 > 0.0 { 1.0 / w2.sqrt() } else { 0.0 };
    let inv_r3 = inv_r * inv_r * inv_r;
    let inv_r5 = inv_r3 * inv_r * inv_r;
    let d1x = -a_ * u * inv_r3 * cc;
    let d1y = a_ * a_ * inv_r3 * cc;
    let d2x = a_ * (2.0 * u * u - a_ * a_) * inv_r5 * cc * cc * 0.5;
    let d2y = -3.0 * a_ * a_ * u * inv_r5 * cc * cc * 0.5;
    let e0x = a_ * inv_r;
    let e0y = u * inv_r;
    let hl = 0.5 * ell;
    let h3 = hl * hl * hl * (2.0 / 3.0);
    let h5 = hl * hl * hl * hl * hl * 0.4;
    let c0 = a2 - xm * xm;
    let m0 = kk * (c0 * 2.0 * hl - h3);
    let m1 = kk * (-2.0 * xm * h3);
    let m2 = kk * (c0 * h3 - h5);
    let m3 = kk * (-2.0 * xm * h5);
    let tfx = e0x * m0 + d1x * m1 + d2x * m2;
    let tfy = e0y * m0 + d1y * m1 + d2y * m2;
    let txfy = xm * tfy + e0y * m1 + d1y * m2 + d2y * m3;
    let tmz = txfy - y_ * tfx;
    (tfx, tfy, tmz)
}

/// Sliding zone x1 ≤ x ≤ x2 with p = K(aj² − x²)·e, e = d/|d|, d = (A, B + 2Cx)
/// (called with the adhesion-continuation direction: B = B' and 2C = C), in
/// closed form; requires a direction that turns (2C ≠ 0); `inv2c` = 1/(2C).
#[allow(clippy::too_many_arguments)]
#[inline]
fn sliding_closed(
    aj: f64,
    y: f64,
    aa: f64,
    bb: f64,
    two_c: f64,
    inv2c: f64,
    kk: f64,
    x1: f64,
    x2: f64,
) -> StripSums {
    let a2j = aj * aj;
    // Closed form in u = B + 2Cx; x = (u − B)/(2C), dx = du/(2C).
    // g = K P(u), P = α0 + α1 u + α2 u².
    let amin = 1e-12 * (bb.abs() + two_c.abs() * aj) + f64::MIN_POSITIVE.sqrt();
    let aeff = if aa.abs() < amin { amin } else { aa.abs() };
    let a2 = aeff * aeff;
    let al2 = -inv2c * inv2c;
    let al1 = -2.0 * bb * al2;
    let al0 = a2j + bb * bb * al2;
    let u1 = bb + two_c * x1;
    let u2 = bb + two_c * x2;
    let jj = sqrt_integrals(a2, u1, u2).j;
    let ip0 = al0 * jj[0] + al1 * jj[1] + al2 * jj[2]; // ∫P/r du
    let ip1 = al0 * jj[1] + al1 * jj[2] + al2 * jj[3]; // ∫P u/r du
    let ip2 = al0 * jj[2] + al1 * jj[3] + al2 * jj[4]; // ∫P u²/r du
    let f = kk * inv2c;
    let fx = f * aa * ip0;
    let fy = f * ip1;
    // x p_y − y p_x: x u = (u² − B u)/(2C).
    let mzz = f * ((ip2 - bb * ip1) * inv2c - y * aa * ip0);
    StripSums { fx, fy, mz: mzz }
}

impl CreepLaw for FastsimA {
    fn name(&self) -> &'static str {
        "fastsim-a"
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Numerical-analysis check of the Taylor branch at its switching threshold
    /// (|C|ℓ = 0.4|d|) against the closed form: the truncation error is the
    /// third-order term, ~ (0.2)³ times O(1) derivative factors.
    #[test]
    fn taylor_branch_truncation_at_threshold() {
        let (aj, kk, xs, y) = (1.0, 1.0, 0.2, 0.3);
        let ell = xs + aj;
        let xm = 0.5 * (xs - aj);
        let mut worst = 0.0_f64;
        for k in 0..24 {
            let ang = f64::from(k) * std::f64::consts::PI / 12.0 + 0.1;
            let (a_, u) = (ang.cos(), ang.sin());
            for sgn in [-1.0, 1.0] {
                let cc = sgn * 0.4 / ell;
                let b2 = u - cc * xm;
                let w2 = a_ * a_ + u * u;
                let (tx, ty, tm) = sliding_taylor(a_, y, aj * aj, xm, u, w2, cc, kk, ell);
                let c = sliding_closed(aj, y, a_, b2, cc, 1.0 / cc, kk, -aj, xs);
                let mag = c.fx.hypot(c.fy);
                let e = (tx - c.fx).hypot(ty - c.fy) / mag;
                worst = worst.max(e);
                assert!(
                    (tm - c.mz).abs() < 2e-3 * mag,
                    "{ang} {sgn}: mz {tm} vs {}",
                    c.mz
                );
            }
        }
        eprintln!("Taylor vs closed at threshold: worst {worst:.2e}");
        assert!(worst < 1e-3, "worst {worst}");
    }
}
