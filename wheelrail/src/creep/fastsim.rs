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
#[derive(Debug, Clone, Copy)]
pub struct Fastsim {
    strips: usize,
    elements: usize,
    bound: TractionBound,
    layout: FastsimLayout,
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
        Ok(Self {
            strips,
            elements,
            bound: TractionBound::Parabolic,
            layout: FastsimLayout::Strips,
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
    fn eval_strips(&self, p: &ContactPatch, c: &Creepages, fl: &Flexibilities) -> CreepForces {
        let m = self.strips;
        let n = self.elements;
        let dy = 2.0 * p.b / m as f64;
        let nf = n as f64;
        let strip_half = |j: usize| {
            let eta = -1.0 + (j as f64 + 0.5) * 2.0 / m as f64;
            p.a * (1.0 - eta * eta).max(0.0).sqrt()
        };
        // Normalisation: discrete integral of p_n equals N.
        let gk = match self.bound {
            TractionBound::Parabolic => {
                // Midpoint rule of ∫(aⱼ² − x²)dx over n elements = (4/3)aⱼ³(1 + 1/(2n²)).
                let s: f64 = (0..m).map(|j| strip_half(j).powi(3)).sum::<f64>()
                    * (4.0 / 3.0)
                    * (1.0 + 0.5 / (nf * nf))
                    * dy;
                p.mu * p.n / s
            }
            TractionBound::Elliptic => {
                let mut s = 0.0;
                for j in 0..m {
                    let aj = strip_half(j);
                    let h = 2.0 * aj / nf;
                    let mut acc = 0.0;
                    for i in 0..n {
                        let x = aj - (i as f64 + 0.5) * h;
                        acc += (aj * aj - x * x).max(0.0).sqrt();
                    }
                    s += acc * h;
                }
                p.mu * p.n / (s * dy)
            }
        };
        let wx_rate_xi = c.xi * fl.inv_l1;
        let wy0 = c.eta * fl.inv_l2;
        let cs = c.phi * fl.inv_l3;
        let (mut fx, mut fy, mut mz) = (0.0, 0.0, 0.0);
        for j in 0..m {
            let y = -p.b + (j as f64 + 0.5) * dy;
            let aj = strip_half(j);
            let h = 2.0 * aj / nf;
            let wxr = wx_rate_xi - c.phi * y * fl.inv_l3;
            // Leading edge to the first element centre: half an element.
            let mut x = aj - 0.5 * h;
            let mut px = wxr * 0.5 * h;
            let mut py = (wy0 + cs * (aj - 0.25 * h)) * 0.5 * h;
            let (mut sx, mut sy, mut sm) = (0.0, 0.0, 0.0);
            for i in 0..n {
                if i > 0 {
                    px += wxr * h;
                    py += (wy0 + cs * (x - 0.5 * h)) * h;
                    x -= h;
                }
                let q = (aj * aj - x * x).max(0.0);
                let g = match self.bound {
                    TractionBound::Parabolic => gk * q,
                    TractionBound::Elliptic => gk * q.sqrt(),
                };
                let t2 = px * px + py * py;
                if t2 > g * g {
                    let s = g / t2.sqrt();
                    px *= s;
                    py *= s;
                }
                sx += px;
                sy += py;
                sm += x * py;
            }
            let w = h * dy;
            fx += sx * w;
            fy += sy * w;
            mz += (sm - y * sx) * w;
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
            FastsimLayout::Strips => self.eval_strips(p, c, &fl),
            FastsimLayout::UniformGrid { scale } => self.eval_grid(p, c, &fl, scale),
        })
    }
}
