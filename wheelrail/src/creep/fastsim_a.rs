//! FastSim_A: a semi-analytic FASTSIM (D. Yu. Pogorelov's FastSim_A,
//! Pogorelov 2005, Sect. 4.3): each strip of the contact ellipse is solved in
//! closed form, so the cost is proportional to the number of strips only.
//!
//! On a strip at lateral position `y` with half-length `a_y = a√(1 − y²/b²)`,
//! with the parabolic traction bound `g(x) = K (a_y² − x²)` and the rigid slip
//! of the simplified theory `w(x) = (A, B + 2Cx)`, `A = ξ/L1 − φy/L3`,
//! `B = η/L2`, `C = φ/(2L3)`:
//!
//! - **Adhesion zone** (from the leading edge): the exact solution of FASTSIM's
//!   differential equation `dp/d(−x) = w` is `p = (a_y − x)·(A, B + C(a_y + x))`
//!   (Pogorelov 2005, Eq. 20). With `t = a_y + x` the traction reaches the
//!   bound where `A² + (B + Ct)² = K²t²` (Eq. 21), a quadratic in `t` solved in
//!   closed form; the adhesion zone is `t* ≤ t ≤ 2a_y`, and its force and
//!   moment are polynomial integrals (the paper's `dFxa`, `dFya`).
//! - **Sliding zone** (`−a_y ≤ x ≤ x*`): the traction is on the bound,
//!   `p = g·e`. The exact direction obeys `dθ/d(−x) = |w| sin(θ_w − θ)/g`
//!   (FASTSIM's scaling onto the bound; Pogorelov 2005, Eqs. 24–25 and 28),
//!   which has no closed-form solution. It is approximated by the direction of
//!   the adhesion solution continued into the sliding zone, `e ≈ d/|d|`,
//!   `d = (A, B + C(a_y + x))` (the paper's approximation, Eq. 26): the
//!   traction keeps turning as the accumulated elastic displacement would.
//!   This is exact for zero spin (then `d ∥ w` is constant and never turns, and
//!   FastSim_A equals FASTSIM with infinitely many elements: property 1 of
//!   Pogorelov 2005, Sect. 4.3), and
//!   compared with the rigid-slip direction `w/|w|` (tried first) it reduces the
//!   error against fine FASTSIM at tread-contact spin from 15–30 % to 1–4 %. The force is
//!   integrated in closed form (as the paper does, its `dFxs0`, `dFys0`):
//!   with `u = B + C(a_y + x)` the integrands are
//!   `polynomial(u)/√(A² + u²)`, and `∫ uᵏ/√(A² + u²) du` (k ≤ 4) are elementary
//!   (one logarithm, two square roots and two divisions per strip). Where the
//!   direction turns little over the zone (`|C|ℓ ≤ 0.4|d|`, `d` at the zone's
//!   midpoint) — always for zero spin — a second-order Taylor expansion of the
//!   direction about the midpoint is integrated instead (this crate's own):
//!   cheaper, free of the
//!   closed form's cancellation as `C → 0`, and within 5.4e-4 of the closed
//!   form at the switching threshold (unit test), exact for zero spin.
//!
//! **Improving the sliding zone** ([`SlidingZone`], selected with
//! [`FastsimA::with_sliding`]). Both corrections add `∫ (p − g e₀) dt` over the
//! sliding zone to the closed form above (`e₀` the continuation direction),
//! evaluated with a fixed Gauss rule of `n` nodes per zone (cost proportional
//! to the number of strips; no correction for zero spin, which stays exact).
//! With `t = a_y + x` the ODE's right-hand side along `e₀` reduces to
//! `dθ/d(−x) = −AC/(K r t)`, `r = |d|`, singular like `1/t` at the trailing
//! edge where `g → 0`.
//!
//! - [`SlidingZone::Picard`]: one Picard step from the continuation direction,
//!   `θ₁(t) = θ₀(t*) − (AC/K)∫ₜ^{t*} dt'/(t' r(t'))`, the integral in closed form
//!   (a logarithm per node): the improved approximation `e¹` at the end of
//!   Pogorelov 2005, Sect. 4.3 (Eq. 25 with Eq. 26 on its right-hand side),
//!   for which the paper reports about half the error of Eq. 26 on its Fig. 25
//!   case. Measured here, it does **not** help at tread spin:
//!   the step diverges logarithmically towards the trailing edge, where the
//!   true direction relaxes onto the rigid slip instead (error 6.3 % of the
//!   force against 4.2 % for the continuation, with 8–16 nodes, on the grid of
//!   `fastsim_a_against_fine_fastsim`; flange spin: mean error 16 % against 37 %).
//! - [`SlidingZone::Integrated`] (this project's own, not in the paper;
//!   [`FastsimA::integrated`],
//!   [`INTEGRATED_NODES`] = 8 nodes): the traction is stepped from `t*` through
//!   the nodes. A step first tries FASTSIM's exact elastic update
//!   `p + ∫ w d(−x)`; if that stays within the bound the point has re-adhered
//!   (at large spin `w` turns and the traction leaves the bound, which no
//!   single-zone model captures). Otherwise the point slides and the direction
//!   follows the ODE in `τ = ln(t*/t)`, `dθ/dτ = λ sin(θ_w − θ)`,
//!   `λ = |w|/(K(2a_y − t))` — the variable `τ` removes the trailing-edge
//!   singularity — solved over the step with `λ`, `θ_w` frozen at the step's
//!   midpoint: `tan(ψ/2) = tan(ψ₀/2)·e^(−λΔτ)`, `ψ = θ − θ_w`.
//!
//! Measured against FASTSIM with 4000 elements per strip (same 20 strips;
//! tests `fastsim_a_against_fine_fastsim`, `fastsim_a_integrated_other_ellipses`;
//! errors relative to the total tangential force):
//!
//! | sliding zone | tread spin, `|φ|a ≤ 0.0018` | flange spin, `|φ|a` 0.009–0.021: max / mean |
//! |---|---|---|
//! | continuation (default) | 4.2 % | 124 % / 37 % |
//! | Picard step, 8 nodes | 6.3 % | 132 % / 16 % |
//! | integrated, 4 / 8 / 16 nodes | 0.82 / 0.29 / 0.08 % | 18 / 8.9 / 1.6 % ; 6.0 / 2.2 / 0.5 % |
//!
//! (a = 6 mm, b = 4 mm; flange-spin maxima where spin and lateral creepage
//! nearly cancel the resultant). On a wide ellipse (a/b = 0.5) at `|φ|a = 0.02`
//! the integrated zone with 8 nodes is off by up to 0.047 μN (0.39 μN for the
//! continuation) and needs 32 nodes for 2 %. For comparison FASTSIM 20 × 20 /
//! 20 × 40 elements: 1.2 / 0.64 % at tread spin, 12 / 6.5 % max at flange spin.
//! Cost (criterion bench `creep`, 64 tread cases, one core, shared machine):
//! continuation with 10 strips about 5.5 million evaluations per second, the
//! integrated zone (8 nodes) about 0.45 million — no cheaper than FASTSIM of
//! similar accuracy — hence not the default; the Picard step about 0.33 million.
//!
//! Relation to Pogorelov 2005, Sect. 4.3: the adhesion zone is the paper's
//! exact strip solution (Eqs. 20–21), the default sliding zone
//! ([`SlidingZone::Continuation`]) its approximation of Eq. 26 with the
//! closed-form integral, [`SlidingZone::Picard`] its improved approximation;
//! [`SlidingZone::Integrated`] and the Taylor branch are this crate's own. The
//! paper compares it with FASTSIM in tread-contact conditions (Figs. 20–22;
//! Fig. 20's largest spin, 0.5 1/m with a = 8.4 mm, is `φa ≈ 0.004`). The
//! default continuation's error grows with spin: against FASTSIM with 2000–4000
//! elements per strip (same strips) it is at most 4.2 % of the total force for
//! `|φ|·a ≤ 0.002` (tread contact), up to 7.5 % at `|φ|·a ≈ 0.004`, 4 % on
//! CONTACT's FASTSIM example (`φa = 0.005`), and tens of percent for
//! flange-contact spin (`|φ|·a ≈ 0.01–0.02`, table above), where FASTSIM
//! itself is far from the exact theory.
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
    /// The strips of the unit ellipse.
    strips: Strips,
    /// Treatment of the sliding zones.
    sliding: SlidingZone,
    /// Gauss nodes on [0, 1] for the sliding-zone corrections, in decreasing
    /// order (empty for [`SlidingZone::Continuation`]).
    nodes: Vec<Node>,
}

/// How FastSim_A obtains the traction direction in the sliding zone of each
/// strip (see the module documentation for the measured errors).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SlidingZone {
    /// The adhesion-continuation direction, integrated in closed form: the
    /// paper's FastSim_A (Pogorelov 2005, Eq. 26); fastest; the default.
    #[default]
    Continuation,
    /// One Picard step of the direction ODE from the continuation direction,
    /// the improved approximation of Pogorelov 2005, Sect. 4.3, with `nodes`
    /// Gauss nodes per zone (measured: no better than
    /// [`Self::Continuation`] at tread spin; kept for comparison).
    Picard {
        /// Gauss nodes per sliding zone, 1..=32.
        nodes: usize,
    },
    /// The sliding zone integrated node to node (`nodes` Gauss nodes per zone;
    /// this project's own, not in Pogorelov 2005):
    /// exact elastic steps where the traction falls below the bound
    /// (re-adhesion), the closed-form solution of the direction ODE with
    /// frozen coefficients where it slides.
    Integrated {
        /// Gauss nodes per sliding zone, 1..=32.
        nodes: usize,
    },
}

/// A Gauss node `s` on [0, 1] with weight `w` and `dtau = ln(s_prev/s)`, the
/// step in `τ = ln(t*/t)` from the previous (larger) node or from 1, and
/// the step's midpoint in `τ`.
#[derive(Debug, Clone, Copy)]
struct Node {
    s: f64,
    w: f64,
    dtau: f64,
    /// Geometric midpoint √(s_prev s) of the step.
    smid: f64,
}

/// Gauss nodes per sliding zone of [`FastsimA::integrated`].
pub const INTEGRATED_NODES: usize = 8;

/// Gauss–Legendre nodes and weights on [0, 1] (Newton iteration on the
/// Legendre polynomial from the Chebyshev guesses; converges to rounding).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let nf = n as f64;
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_n(x) and P_n'(x) by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let kf = k as f64;
                    let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
                    p0 = p1;
                    p1 = p2;
                }
                let pn = if n == 0 { 1.0 } else { p1 };
                let pm = if n == 1 { 1.0 } else { p0 };
                dp = nf * (x * pn - pm) / (x * x - 1.0);
                let dx = pn / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            (0.5 * (1.0 - x), 0.5 * w)
        })
        .collect()
}

/// Integrals over one strip (traction on the rail, before the sign flip).
#[derive(Debug, Clone, Copy, Default)]
struct StripSums {
    fx: f64,
    fy: f64,
    mz: f64,
}

/// The strips of a unit ellipse cut across the lateral axis, as FastSim_A
/// and FastSim_SA integrate over them.
#[derive(Debug, Clone)]
pub(super) struct Strips {
    /// Per strip: (η = y/b at the strip centre, √(1 − η²) = a_y/a).
    pub(super) geom: Vec<(f64, f64)>,
    /// Σ (4/3)(1 − η²)^(3/2)·Δη: the strips' bound integral for a = b = 1
    /// (→ π/2 as the strips get finer).
    pub(super) norm: f64,
    /// Strip width for b = 1: Δη = 2/strips.
    pub(super) d_eta: f64,
}

impl Strips {
    /// `strips` strips of equal width.
    pub(super) fn new(strips: usize) -> Strips {
        let mf = strips as f64;
        let geom: Vec<(f64, f64)> = (0..strips)
            .map(|j| {
                let e = -1.0 + (j as f64 + 0.5) * 2.0 / mf;
                (e, (1.0 - e * e).max(0.0).sqrt())
            })
            .collect();
        let norm = geom.iter().map(|&(_, s)| s * s * s).sum::<f64>() * (4.0 / 3.0) * 2.0 / mf;
        Strips {
            geom,
            norm,
            d_eta: 2.0 / mf,
        }
    }
}

impl FastsimA {
    /// FastSim_A with `strips` strips.
    pub fn new(strips: usize) -> Result<Self, CreepError> {
        if strips == 0 || strips > MAX_STRIPS {
            return Err(CreepError::Parameter(format!(
                "FastSim_A number of strips must be in 1..={MAX_STRIPS}, got {strips}"
            )));
        }
        Ok(Self {
            strips: Strips::new(strips),
            sliding: SlidingZone::Continuation,
            nodes: Vec::new(),
        })
    }

    /// FastSim_A with `strips` strips and the integrated sliding zones
    /// ([`SlidingZone::Integrated`] with [`INTEGRATED_NODES`] nodes).
    pub fn integrated(strips: usize) -> Result<Self, CreepError> {
        Self::new(strips)?.with_sliding(SlidingZone::Integrated {
            nodes: INTEGRATED_NODES,
        })
    }

    /// The same law with another treatment of the sliding zones.
    pub fn with_sliding(mut self, sliding: SlidingZone) -> Result<Self, CreepError> {
        self.nodes = match sliding {
            SlidingZone::Continuation => Vec::new(),
            SlidingZone::Picard { nodes } | SlidingZone::Integrated { nodes } => {
                if !(1..=32).contains(&nodes) {
                    return Err(CreepError::Parameter(format!(
                        "FastSim_A sliding-zone Gauss nodes must be in 1..=32, got {nodes}"
                    )));
                }
                let mut g = gauss_legendre(nodes);
                g.sort_by(|a, b| b.0.total_cmp(&a.0));
                let mut prev = 1.0;
                g.iter()
                    .map(|&(s, w)| {
                        let n = Node {
                            s,
                            w,
                            dtau: (prev / s).ln(),
                            smid: (prev * s).sqrt(),
                        };
                        prev = s;
                        n
                    })
                    .collect()
            }
        };
        self.sliding = sliding;
        Ok(self)
    }

    /// The treatment of the sliding zones.
    pub fn sliding(&self) -> SlidingZone {
        self.sliding
    }

    /// [`Self::eval_lanes`], compiled for AVX2 where the CPU has it (found
    /// at run time): four lanes per vector instruction instead of SSE2's
    /// two. The same IEEE operations in the same order either way (Rust
    /// never contracts or reassociates floating-point arithmetic, and AVX2
    /// brings no fused multiply–add), so the forces are bit for bit the
    /// same (test `avx2_path_is_bit_identical`).
    #[inline]
    fn eval(&self, p: &ContactPatch, c: &Creepages, fl: &Flexibilities) -> CreepForces {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.eval_avx2(p, c, fl) };
        }
        self.eval_lanes(p, c, fl)
    }

    /// [`Self::eval_lanes`] with AVX2 enabled.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn eval_avx2(&self, p: &ContactPatch, c: &Creepages, fl: &Flexibilities) -> CreepForces {
        self.eval_lanes(p, c, fl)
    }

    /// Strips are processed in chunks of `LANES`: branch-free passes over the
    /// lanes (adhesion boundaries; then adhesion zones and the Taylor branch of
    /// the sliding zones) let the compiler overlap or vectorise the independent
    /// square roots and divisions of the strips; sliding zones whose direction
    /// turns much take the closed form (with a logarithm) in a last pass.
    #[inline(always)]
    fn eval_lanes(&self, p: &ContactPatch, c: &Creepages, fl: &Flexibilities) -> CreepForces {
        let dy = self.strips.d_eta * p.b;
        // Bound g = K(aⱼ² − x²) with K such that the strips carry exactly μN.
        let kk = p.mu * p.n / (self.strips.norm * p.a * p.a * p.a * p.b);
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
        let n8 = self.strips.geom.len() / 8 * 8;
        for chunk in self.strips.geom[..n8].chunks(8) {
            let (x, y, m) = chunk_sums::<8>(chunk, &k);
            fx += x;
            fy += y;
            mz += m;
        }
        // Sliding-zone corrections (none for zero spin, where the
        // continuation direction is exact).
        let correct = !self.nodes.is_empty() && cc != 0.0;
        if correct {
            for chunk in self.strips.geom[..n8].chunks(8) {
                let (x, y, m) = chunk_corrections::<8>(chunk, &k, self.sliding, &self.nodes);
                fx += x;
                fy += y;
                mz += m;
            }
        }
        for chunk in self.strips.geom[n8..].chunks(2) {
            let (x, y, m) = chunk_sums::<2>(chunk, &k);
            fx += x;
            fy += y;
            mz += m;
            if correct {
                let (x, y, m) = chunk_corrections::<2>(chunk, &k, self.sliding, &self.nodes);
                fx += x;
                fy += y;
                mz += m;
            }
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

/// Per-evaluation constants of the strips: semi-axes `a`, `b` (m), the
/// bound's `K`, `B = η/L2`, `C = φ/(2L3)`, `α = K² − C²`, `BC`.
pub(super) struct StripConsts {
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) kk: f64,
    pub(super) bb: f64,
    pub(super) cc: f64,
    pub(super) alpha: f64,
    pub(super) bc: f64,
    /// ξ/L1 and φ/L3.
    pub(super) wx: f64,
    pub(super) wphi: f64,
}

/// `t* = aⱼ + x*` of a strip's adhesion boundary (0 ≤ t* ≤ 2aⱼ; the sliding
/// zone is `0 ≤ t ≤ t*`), for `A` = `a_` and half-length `aj_`.
#[inline(always)]
pub(super) fn adhesion_boundary(a_: f64, aj_: f64, k: &StripConsts) -> f64 {
    let StripConsts { bb, alpha, bc, .. } = *k;
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
    t.max(0.0).min(len)
}

/// Force and moment of a strip's adhesion zone `x* ≤ x ≤ aⱼ` (traction on
/// the rail, times 1/Δy), `p = (aⱼ − x)(A, B + C(aⱼ + x))` (Pogorelov 2005,
/// Eq. 20) integrated exactly; `a_` = A, `aj_` = aⱼ, `y_` the strip's `y`,
/// `tstar` = aⱼ + x*.
#[inline(always)]
pub(super) fn adhesion_zone(
    a_: f64,
    aj_: f64,
    y_: f64,
    tstar: f64,
    bb: f64,
    cc: f64,
) -> (f64, f64, f64) {
    let xs = tstar - aj_;
    let sl = 2.0 * aj_ - tstar;
    let a2 = aj_ * aj_;
    let cub = sl * (a2 + aj_ * xs + xs * xs) * (1.0 / 3.0); // (aⱼ³ − x*³)/3
    let i0 = 0.5 * sl * sl; // ∫(aⱼ − x)
    let i_par = sl * a2 - cub; // ∫(aⱼ² − x²)
    let ix_lin = aj_ * sl * tstar * 0.5 - cub; // ∫x(aⱼ − x)
    let ix_par = a2 * sl * tstar * 0.5 - sl * tstar * (a2 + xs * xs) * 0.25; // ∫x(aⱼ² − x²)
    let afx = a_ * i0;
    let afy = bb * i0 + cc * i_par;
    let amz = bb * ix_lin + cc * ix_par - y_ * afx;
    (afx, afy, amz)
}

/// Sliding-zone corrections (traction on the rail, times 1/Δy) of up to
/// `LANES` strips: [`SlidingZone::Integrated`] with the lanes stepped together
/// (independent dependency chains overlap), [`SlidingZone::Picard`] per strip.
#[inline(always)]
fn chunk_corrections<const LANES: usize>(
    chunk: &[(f64, f64)],
    k: &StripConsts,
    sliding: SlidingZone,
    nodes: &[Node],
) -> (f64, f64, f64) {
    let StripConsts { kk, bb, cc, .. } = *k;
    // Dummy lanes (beyond the chunk, or without a sliding zone) get finite
    // values and weight 0.
    let mut aj = [1.0; LANES];
    let mut y = [0.0; LANES];
    let mut aa = [1.0; LANES];
    let mut ts = [1.0; LANES];
    let mut on = [0.0; LANES];
    for (l, &(e, sj)) in chunk.iter().enumerate() {
        let (yl, ajl) = (e * k.b, k.a * sj);
        let al = k.wx - k.wphi * yl;
        let t = adhesion_boundary(al, ajl, k);
        if t > 0.0 {
            (y[l], aj[l], aa[l], ts[l], on[l]) = (yl, ajl, al, t, 1.0);
        }
    }
    if on.iter().all(|&o| o == 0.0) {
        return (0.0, 0.0, 0.0);
    }
    let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
    if let SlidingZone::Picard { .. } = sliding {
        for l in 0..LANES {
            if on[l] > 0.0 {
                let s = picard_correction(aa[l], bb, cc, kk, aj[l], y[l], ts[l], nodes);
                fx += s.fx;
                fy += s.fy;
                mz += s.mz;
            }
        }
        return (fx, fy, mz);
    }
    // Integrated: state p at the previous node, per lane.
    let mut px = [0.0; LANES];
    let mut py = [0.0; LANES];
    let mut tp = [0.0; LANES];
    for l in 0..LANES {
        // At t*: on the bound along the adhesion solution d = (A, B + Ct*).
        let u = bb + cc * ts[l];
        let r2 = aa[l] * aa[l] + u * u;
        let inv = if r2 > 0.0 { 1.0 / r2.sqrt() } else { 0.0 };
        let g = kk * ts[l] * (2.0 * aj[l] - ts[l]);
        px[l] = g * aa[l] * inv;
        py[l] = g * u * inv;
        tp[l] = ts[l];
    }
    let mut sx = [0.0; LANES];
    let mut sy = [0.0; LANES];
    let mut sm = [0.0; LANES];
    for nd in nodes {
        for l in 0..LANES {
            let (a_, aj_, t_prev) = (aa[l], aj[l], tp[l]);
            let t = ts[l] * nd.s;
            let (ox, oy) = (px[l], py[l]);
            let (x, yy) = integrated_step(
                a_,
                bb,
                cc,
                kk,
                aj_,
                t_prev,
                t,
                ts[l] * nd.smid,
                nd.dtau,
                ox,
                oy,
            );
            px[l] = x;
            py[l] = yy;
            tp[l] = t;
            // Correction against the continuation direction e₀ = d/|d|.
            let g = kk * t * (2.0 * aj_ - t);
            let u = bb + cc * t;
            let r2 = a_ * a_ + u * u;
            let inv = if r2 > 0.0 { 1.0 / r2.sqrt() } else { 0.0 };
            let wg = nd.w * ts[l] * on[l];
            let (dx, dy) = ((x - g * a_ * inv) * wg, (yy - g * u * inv) * wg);
            sx[l] += dx;
            sy[l] += dy;
            sm[l] += (t - aj_) * dy - y[l] * dx;
        }
    }
    for l in 0..LANES {
        fx += sx[l];
        fy += sy[l];
        mz += sm[l];
    }
    (fx, fy, mz)
}

/// Integrated sliding zone `0 ≤ t ≤ t*` (`t = aⱼ + x`, material moving to
/// decreasing `t`): the traction `p` is stepped from `t*` (on the bound, along
/// the adhesion solution) through the Gauss nodes `t_k` in decreasing order.
/// Each step first tries the exact elastic update `p + ∫ w d(−x)` (FASTSIM's
/// adhesion rule); if that stays within the bound `g(t_k)` the point has
/// re-adhered. Otherwise it slides: `|p| = g` and the direction obeys
/// `dθ/dτ = λ sin(θ_w − θ)` in `τ = ln(t*/t)`, `λ = |w|/(K(2aⱼ − t))` (the
/// ODE `dθ/d(−x) = |w| sin(θ_w − θ)/g` with `g = K t(2aⱼ − t)`: the variable
/// `τ` removes the trailing-edge singularity), solved over the step with `λ`
/// and `θ_w` frozen at the step's geometric midpoint:
/// `tan(ψ/2) = tan(ψ₀/2)·e^(−λΔτ)`, `ψ = θ − θ_w`. The caller
/// accumulates `∫ (p − g e₀) dt` and its moment by the Gauss rule (`e₀` the
/// continuation direction, whose integral is in closed form).
///
/// One step from `t_prev` to `t < t_prev` (midpoint `tm`, `dtau =
/// ln(t_prev/t)`), traction `(px, py)` before; returns the traction after.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn integrated_step(
    aa: f64,
    bb: f64,
    cc: f64,
    kk: f64,
    aj: f64,
    t_prev: f64,
    t: f64,
    tm: f64,
    dtau: f64,
    px: f64,
    py: f64,
) -> (f64, f64) {
    let g = kk * t * (2.0 * aj - t);
    // Elastic trial: p + ∫ w d(−x), w = (A, B + 2C(t − aⱼ)), exact.
    let h = t_prev - t;
    let qx = px + aa * h;
    let qy = py + bb * h + cc * ((t_prev - aj) * (t_prev - aj) - (t - aj) * (t - aj));
    let q2 = qx * qx + qy * qy;
    // Sliding: relax the direction towards the rigid slip at the midpoint.
    let p2 = px * px + py * py;
    let inv_pn = if p2 > 0.0 { 1.0 / p2.sqrt() } else { 0.0 };
    let (ex, ey) = (px * inv_pn, py * inv_pn);
    let wy = bb + 2.0 * cc * (tm - aj);
    let w2 = aa * aa + wy * wy;
    let wn = w2.sqrt();
    let inv_wn = if wn > 0.0 { 1.0 / wn } else { 0.0 };
    let (ux, uy) = (aa * inv_wn, wy * inv_wn);
    let lam = wn / (kk * (2.0 * aj - tm));
    let f = exp_neg(lam * dtau);
    // ψ from θ_w: cos ψ = e·u, sin ψ = u × e; tan(ψ/2) scaled by f.
    let c = ex * ux + ey * uy;
    let ss = (ux * ey - uy * ex) * f;
    let pp = 1.0 + c;
    let den = pp * pp + ss * ss;
    let ok = den > 0.0 && wn > 0.0;
    let g_den = if ok { g / den } else { 0.0 };
    let (c2, s2) = ((pp * pp - ss * ss) * g_den, 2.0 * ss * pp * g_den);
    let (rx, ry) = if ok {
        (c2 * ux - s2 * uy, c2 * uy + s2 * ux)
    } else {
        (g * ex, g * ey)
    };
    if q2 <= g * g {
        // Adhesion (re-adhered).
        (qx, qy)
    } else if px * qx + py * qy <= 0.0 {
        // The step reversed the traction through adhesion (rare): slide
        // along the trial direction.
        let k = g / q2.sqrt();
        (k * qx, k * qy)
    } else {
        (rx, ry)
    }
}

/// `e^(−z)` for `z ≥ 0` (NaN-free; 0 beyond `z = 700`), by `2^(−z log₂e)`
/// with the exponent split into an integer and a fraction, `2^r` by its
/// degree-7 Taylor polynomial in `r ln 2` (relative error < 1e-8 for
/// `|r| ≤ 0.5`): inline arithmetic that the lanes can share, unlike a libm call.
#[inline(always)]
fn exp_neg(z: f64) -> f64 {
    let x = -(z.min(700.0)) * std::f64::consts::LOG2_E;
    // Rounded: n ∈ [−1010, 0], r = x − n ∈ (−0.5, 0.5].
    let n = (x - 0.5) as i32;
    let r = (x - f64::from(n)) * std::f64::consts::LN_2;
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0
                        + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    p * f64::from_bits(((i64::from(n) + 1023) as u64) << 52)
}

/// Force and moment sums (traction on the rail, times 1/Δy) of up to `LANES`
/// strips processed together.
#[inline(always)]
fn chunk_sums<const LANES: usize>(chunk: &[(f64, f64)], k: &StripConsts) -> (f64, f64, f64) {
    let StripConsts { kk, bb, cc, .. } = *k;
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
        ts[l] = adhesion_boundary(aa[l], aj[l], k);
    }
    // Pass 2: zone integrals.
    for l in 0..LANES {
        let (a_, aj_, y_) = (aa[l], aj[l], y[l]);
        let tstar = ts[l];
        let xs = tstar - aj_;
        xs_l[l] = xs;
        let a2 = aj_ * aj_;
        let (afx, afy, amz) = adhesion_zone(a_, aj_, y_, tstar, bb, cc);
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

/// Picard-step correction of one sliding zone `0 ≤ t ≤ t*` (`t = aⱼ + x`):
/// `∫ g (e₁ − e₀) dt` and its moment, where `e₀ = d/|d|` is the
/// adhesion-continuation direction and `e₁` the direction after one Picard
/// step of `dθ/d(−x) = |w| sin(θ_w − θ)/g` from `θ₀`:
/// `θ₁(t) = θ₀(t*) − (AC/K)·J(t)`, `J(t) = ∫ₜ^{t*} dt'/(t' r(t'))`,
/// `r = √(A² + (B + Ct)²)` (the integrand `e₀ × w/g` reduces to
/// `−AC/(K r t)`), `J` in closed form; Gauss nodes in `t`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn picard_correction(
    aa: f64,
    bb: f64,
    cc: f64,
    kk: f64,
    aj: f64,
    y: f64,
    tstar: f64,
    nodes: &[Node],
) -> StripSums {
    if aa.abs() < 1e-150 {
        // The Picard integrand is proportional to A.
        return StripSums::default();
    }
    // ∫ dt/(t √(α + βt + γt²)) = −(1/√α) ln((2α + βt + 2√α R)/t), α = A² + B² > 0.
    let alpha = aa * aa + bb * bb;
    let sa = alpha.sqrt();
    // ln((α + BCt + √α R)/t), cancellation-free: if α + BCt < 0 use
    // (α + BCt)² − αR² = −A²C²t².
    let log_term = |t: f64, r: f64| -> f64 {
        let q = alpha + bb * cc * t;
        let v = if q >= 0.0 {
            q + sa * r
        } else {
            aa * aa * cc * cc * t * t / (sa * r - q)
        };
        (v / t).ln()
    };
    let rs = (aa * aa + (bb + cc * tstar) * (bb + cc * tstar)).sqrt();
    let ls = log_term(tstar, rs);
    let (cs, sn) = (aa / rs, (bb + cc * tstar) / rs); // e₀(t*)
    let rate = aa * cc / (kk * sa);
    let mut out = StripSums::default();
    for &Node { s, w: wq, .. } in nodes {
        let t = tstar * s;
        let u = bb + cc * t;
        let r = (aa * aa + u * u).sqrt();
        let (e0x, e0y) = (aa / r, u / r);
        // Δ = (AC/K) J(t), J = (ln-term(t) − ln-term(t*))/√α.
        let delta = rate * (log_term(t, r) - ls);
        let (sd, cd) = delta.sin_cos();
        // Rotate e₀(t*) by −Δ.
        let e1x = cs * cd + sn * sd;
        let e1y = sn * cd - cs * sd;
        let g = kk * t * (2.0 * aj - t) * wq * tstar;
        let (dx, dy) = ((e1x - e0x) * g, (e1y - e0y) * g);
        out.fx += dx;
        out.fy += dy;
        out.mz += (t - aj) * dy - y * dx;
    }
    out
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

    /// The inline `e^(−z)` against the standard library's `exp`.
    #[test]
    fn exp_neg_accuracy() {
        for k in 0..=20000 {
            let z = f64::from(k) * 0.036;
            let (a, b) = (exp_neg(z), (-z).exp());
            assert!((a - b).abs() <= 1e-7 * b + 1e-300, "{z}: {a} vs {b}");
        }
        assert_eq!(exp_neg(0.0), 1.0);
        assert!(exp_neg(1e300) >= 0.0 && exp_neg(1e300) < 1e-300);
    }

    /// The AVX2 build of the strip loop gives the SSE2 build's forces bit
    /// for bit, over creepages from full adhesion to full sliding with tread
    /// and flange spin (both sliding-zone branches), several ellipses and
    /// strip counts (odd ones take the 2-lane tail), and the integrated
    /// sliding zone.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_path_is_bit_identical() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: only one path exists");
            return;
        }
        let mut cases = 0;
        for strips in [1, 7, 10, 20, 33] {
            for law in [
                FastsimA::new(strips).unwrap(),
                FastsimA::integrated(strips).unwrap(),
            ] {
                for (a, b) in [(6e-3, 4e-3), (4e-3, 8e-3), (2e-3, 10e-3)] {
                    let p = ContactPatch {
                        a,
                        b,
                        g: 8.0e10,
                        nu: 0.28,
                        mu: 0.3,
                        n: 60e3,
                    };
                    let k = validate(&p, &Creepages::default()).unwrap();
                    let fl = Flexibilities::new(&p, &k);
                    for xi in [0.0, 1e-4, -7e-4, 3e-3, 2e-2] {
                        for eta in [0.0, -2e-4, 1e-3, -1e-2] {
                            for phi in [0.0, 0.1, -0.8, 3.0, -6.0] {
                                let c = Creepages { xi, eta, phi };
                                let x = law.eval_lanes(&p, &c, &fl);
                                // SAFETY: AVX2 is present (checked above).
                                let y = unsafe { law.eval_avx2(&p, &c, &fl) };
                                for (u, v) in [(x.fx, y.fx), (x.fy, y.fy), (x.mz, y.mz)] {
                                    assert_eq!(u.to_bits(), v.to_bits(), "{strips} {p:?} {c:?}");
                                }
                                cases += 1;
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(cases, 5 * 2 * 3 * 5 * 4 * 5);
    }

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
