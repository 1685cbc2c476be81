//! Kalker's FASTSIM (J.J. Kalker, "A fast algorithm for the simplified theory of
//! rolling contact", Vehicle System Dynamics 11 (1982) 1–13), written from its
//! published description.
//!
//! Simplified theory: the surface displacement is `u = L p` (flexibilities `L1`,
//! `L2`, `L3` for the ξ, η and φ parts). Material rolls through the contact from
//! the leading edge `x = a(y)` to the trailing edge `x = −a(y)`; in adhesion the
//! traction grows by the rigid slip `w = (ξ/L1 − φy/L3, η/L2 + φx/L3)` per unit
//! length, `p(x − h) = p(x) + ∫ w dx`, and where `|p|` would exceed the traction
//! bound `g = μ p_n(x, y)` it is scaled back onto it (sliding, traction opposite
//! to the slip). Forces are the integrals of `p`; they act on the rail, so the
//! force on the wheel is their negative.
//!
//! Two discretisations:
//! - [`FastsimLayout::Strips`] (default): `m` strips of equal width, each cut
//!   into `n` equal elements spanning its exact length; tractions at element
//!   centres (the first half an element from the leading edge), midpoint-rule
//!   integration. With this placement the adhesion solution, linear in `x`, is
//!   integrated exactly, so the small-creepage limit is Kalker's linear theory
//!   up to the strip quadrature in `y` (< 1 % for 10 strips). The normal pressure
//!   is scaled so that its discrete integral is exactly `N` (hence the saturated
//!   force is exactly `μN`).
//! - [`FastsimLayout::UniformGrid`]: CONTACT's layout — a uniform grid of
//!   `elements × strips` cells over the potential contact `[−s a, s a] × [−s b, s b]`
//!   (`s` = 1.1 in CONTACT's examples), cells in contact where their centre lies
//!   in the ellipse, analytic pressure at the centre, traction at a cell =
//!   bounded (traction of the upstream cell + rigid slip × cell length).

use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, Flexibilities, validate};

/// Normal pressure distribution that, times `μ`, bounds the traction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TractionBound {
    /// `p_n = 2N/(πab)·(1 − x²/a² − y²/b²)` (Kalker's choice for FASTSIM).
    #[default]
    Parabolic,
    /// Hertz: `p_n = 3N/(2πab)·√(1 − x²/a² − y²/b²)`.
    Elliptic,
}

/// Discretisation of FASTSIM (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum FastsimLayout {
    /// Equal-width strips, each with `elements` equal elements over its length.
    #[default]
    Strips,
    /// CONTACT's uniform grid over the potential contact area scaled by `scale`
    /// (≥ 1) in both directions.
    UniformGrid {
        /// Potential-contact scale factor (CONTACT's SCALE), ≥ 1.
        scale: f64,
    },
}

/// Kalker's FASTSIM with `strips` × `elements`.
#[derive(Debug, Clone)]
pub struct Fastsim {
    strips: usize,
    elements: usize,
    bound: TractionBound,
    layout: FastsimLayout,
    /// Per strip: (η = y/b at the strip centre, √(1 − η²) = a_y/a).
    strip_geom: Vec<(f64, f64)>,
    /// Discrete integral of (1 − x² − η²) over the unit ellipse (a = b = 1) by
    /// the strip layout's midpoint rule, and of √(1 − x² − η²); the pressure
    /// integrals for semi-axes a, b are these times a·b.
    norm_parabolic: f64,
    norm_elliptic: f64,
}

/// Largest number of strips or elements per strip accepted.
const MAX_DIVISIONS: usize = 100_000;

impl Fastsim {
    /// FASTSIM with `strips` strips of `elements` elements each, parabolic bound,
    /// strip layout.
    pub fn new(strips: usize, elements: usize) -> Result<Self, CreepError> {
        for (what, v) in [("strips", strips), ("elements", elements)] {
            if v == 0 || v > MAX_DIVISIONS {
                return Err(CreepError::Parameter(format!(
                    "FASTSIM number of {what} must be in 1..={MAX_DIVISIONS}, got {v}"
                )));
            }
        }
        let mf = strips as f64;
        let nf = elements as f64;
        let strip_geom: Vec<(f64, f64)> = (0..strips)
            .map(|j| {
                let e = -1.0 + (j as f64 + 0.5) * 2.0 / mf;
                (e, (1.0 - e * e).max(0.0).sqrt())
            })
            .collect();
        let dy = 2.0 / mf;
        // Midpoint rule of ∫(s² − x²)dx over n elements = (4/3)s³(1 + 1/(2n²)).
        let norm_parabolic = strip_geom.iter().map(|&(_, sj)| sj * sj * sj).sum::<f64>()
            * (4.0 / 3.0)
            * (1.0 + 0.5 / (nf * nf))
            * dy;
        let mut norm_elliptic = 0.0;
        for &(_, sj) in &strip_geom {
            let h = 2.0 * sj / nf;
            let acc: f64 = (0..elements)
                .map(|i| {
                    let x = sj - (i as f64 + 0.5) * h;
                    (sj * sj - x * x).max(0.0).sqrt()
                })
                .sum();
            norm_elliptic += acc * h * dy;
        }
        Ok(Self {
            strips,
            elements,
            bound: TractionBound::Parabolic,
            layout: FastsimLayout::Strips,
            strip_geom,
            norm_parabolic,
            norm_elliptic,
        })
    }

    /// Same with another traction bound.
    pub fn with_bound(mut self, bound: TractionBound) -> Self {
        self.bound = bound;
        self
    }

    /// Same with another layout (for the uniform grid: `strips` cells in `y`,
    /// `elements` cells in `x`).
    pub fn with_layout(mut self, layout: FastsimLayout) -> Result<Self, CreepError> {
        if let FastsimLayout::UniformGrid { scale } = layout
            && !(scale.is_finite() && scale >= 1.0)
        {
            return Err(CreepError::Parameter(format!(
                "FASTSIM grid scale must be ≥ 1, got {scale}"
            )));
        }
        self.layout = layout;
        Ok(self)
    }

    /// Strip layout; inputs already validated, `N > 0`, `μ > 0`.
    #[inline]
    fn eval_strips<const ELLIPTIC: bool>(
        &self,
        p: &ContactPatch,
        c: &Creepages,
        fl: &Flexibilities,
    ) -> CreepForces {
        let n = self.elements;
        let dy = 2.0 * p.b / self.strips as f64;
        let nf = n as f64;
        // Normalisation: the discrete integral of p_n equals N; p_n = gk/μ·(aⱼ² − x²)
        // (parabolic) or gk/μ·√(aⱼ² − x²) (elliptic); the unit-ellipse sums scale
        // with a·b·a² resp. a·b·a.
        let gk = if ELLIPTIC {
            p.mu * p.n / (self.norm_elliptic * p.a * p.a * p.b)
        } else {
            p.mu * p.n / (self.norm_parabolic * p.a * p.a * p.a * p.b)
        };
        let wx_xi = c.xi * fl.inv_l1;
        let wy0 = c.eta * fl.inv_l2;
        let cs = c.phi * fl.inv_l3;
        // Strips are processed LANES at a time, interleaved, so that the
        // loop-carried dependency of each strip (traction → bound → traction)
        // overlaps with the others; saturation is branch-free.
        const LANES: usize = 4;
        let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
        for chunk in self.strip_geom.chunks(LANES) {
            let mut y = [0.0; LANES];
            let mut a2 = [0.0; LANES];
            let mut h = [0.0; LANES];
            let mut wxh = [0.0; LANES];
            let mut csh2 = [0.0; LANES];
            let mut x = [0.0; LANES];
            let mut px = [0.0; LANES];
            let mut py = [0.0; LANES];
            let mut dpy = [0.0; LANES];
            for (l, &(e, sj)) in chunk.iter().enumerate() {
                y[l] = e * p.b;
                let aj = p.a * sj;
                a2[l] = aj * aj;
                h[l] = 2.0 * aj / nf;
                wxh[l] = (wx_xi - c.phi * y[l] * fl.inv_l3) * h[l];
                csh2[l] = cs * h[l] * h[l];
                // Leading edge to the first element centre: half an element.
                x[l] = aj - 0.5 * h[l];
                px[l] = 0.5 * wxh[l];
                py[l] = (wy0 + cs * (aj - 0.25 * h[l])) * 0.5 * h[l];
                // Slip increment per element: (wy0 + cs·(x − h/2))·h.
                dpy[l] = (wy0 + cs * (x[l] - 0.5 * h[l])) * h[l];
            }
            let mut sx = [0.0; LANES];
            let mut sy = [0.0; LANES];
            let mut sm = [0.0; LANES];
            for _ in 0..n {
                for l in 0..LANES {
                    let q = a2[l] - x[l] * x[l];
                    let g = if ELLIPTIC {
                        gk * q.max(0.0).sqrt()
                    } else {
                        gk * q
                    };
                    let t2 = px[l] * px[l] + py[l] * py[l];
                    // min ignores the NaN of 0/0 (lane unused or zero traction).
                    let s = (g / t2.sqrt()).min(1.0);
                    px[l] *= s;
                    py[l] *= s;
                    sx[l] += px[l];
                    sy[l] += py[l];
                    sm[l] += x[l] * py[l];
                    px[l] += wxh[l];
                    py[l] += dpy[l];
                    dpy[l] -= csh2[l];
                    x[l] -= h[l];
                }
            }
            for l in 0..chunk.len() {
                let w = h[l] * dy;
                fx += sx[l] * w;
                fy += sy[l] * w;
                mz += (sm[l] - y[l] * sx[l]) * w;
            }
        }
        CreepForces {
            fx: -fx,
            fy: -fy,
            mz: -mz,
        }
    }

    /// CONTACT-like uniform grid; inputs validated.
    fn eval_grid(
        &self,
        p: &ContactPatch,
        c: &Creepages,
        fl: &Flexibilities,
        scale: f64,
    ) -> CreepForces {
        let mx = self.elements;
        let my = self.strips;
        let dx = 2.0 * scale * p.a / mx as f64;
        let dy = 2.0 * scale * p.b / my as f64;
        let area = std::f64::consts::PI * p.a * p.b;
        let (p0, elliptic) = match self.bound {
            TractionBound::Parabolic => (2.0 * p.n / area, false),
            TractionBound::Elliptic => (1.5 * p.n / area, true),
        };
        let gk = p.mu * p0;
        let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
        for j in 0..my {
            let y = -scale * p.b + (j as f64 + 0.5) * dy;
            let wxr = c.xi * fl.inv_l1 - c.phi * y * fl.inv_l3;
            let (mut px, mut py) = (0.0, 0.0);
            for i in (0..mx).rev() {
                let x = -scale * p.a + (i as f64 + 0.5) * dx;
                let r = 1.0 - (x / p.a).powi(2) - (y / p.b).powi(2);
                if r <= 0.0 {
                    px = 0.0;
                    py = 0.0;
                    continue;
                }
                px += wxr * dx;
                py += (c.eta * fl.inv_l2 + c.phi * x * fl.inv_l3) * dx;
                let g = gk * if elliptic { r.sqrt() } else { r };
                let t2 = px * px + py * py;
                if t2 > g * g {
                    let s = g / t2.sqrt();
                    px *= s;
                    py *= s;
                }
                fx += px;
                fy += py;
                mz += x * py - y * px;
            }
        }
        let w = dx * dy;
        CreepForces {
            fx: -fx * w,
            fy: -fy * w,
            mz: -mz * w,
        }
    }
}

impl CreepLaw for Fastsim {
    fn name(&self) -> &'static str {
        "fastsim"
    }

    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        let k = validate(p, c)?;
        if p.n == 0.0 || p.mu == 0.0 {
            return Ok(CreepForces::default());
        }
        let fl = Flexibilities::new(p, &k);
        Ok(match self.layout {
            FastsimLayout::Strips => match self.bound {
                TractionBound::Parabolic => self.eval_strips::<false>(p, c, &fl),
                TractionBound::Elliptic => self.eval_strips::<true>(p, c, &fl),
            },
            FastsimLayout::UniformGrid { scale } => self.eval_grid(p, c, &fl, scale),
        })
    }
}
