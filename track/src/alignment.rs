//! Horizontal alignment: a chain of straights, clothoid transitions and circular
//! curves, each with a linear cant ramp.
//!
//! Conventions (docs/design.md): SC0 has x forward along the start of the track, y to
//! the left, z up. `s` is the arc length of the horizontal (plan) centre line, m.
//! The heading ψ(s) is the angle from SC0's x axis to the tangent, positive
//! counter-clockwise seen from above, rad. The **signed curvature** κ = dψ/ds is
//! positive for a curve to the left and negative for a curve to the right, 1/m.
//! The **signed cant** h is the height of the left rail above the right rail,
//! m: a right curve carries h > 0 (its outer rail is the left one), a left curve
//! h < 0. [`Section::with_cant`] takes the cant magnitude and gives it the sign of
//! the section's curve, so users never deal with the sign by hand.

use crate::error::{TrackError, check_param, finite, invalid};

/// Direction of a curve as seen in the direction of increasing `s`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Direction {
    /// Curving to the left (κ > 0).
    Left,
    /// Curving to the right (κ < 0).
    Right,
}

impl Direction {
    /// +1 for left, −1 for right.
    pub fn sign(self) -> f64 {
        match self {
            Direction::Left => 1.0,
            Direction::Right => -1.0,
        }
    }
}

/// Signed curvature (1/m) of a curve of radius `radius` (m) in `direction`.
pub fn signed_curvature(radius: f64, direction: Direction) -> f64 {
    direction.sign() / radius
}

/// The geometric kind of a section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SectionKind {
    /// κ = 0.
    Straight,
    /// κ linear in arc length from `curvature_start` to `curvature_end`.
    Clothoid,
    /// Constant κ ≠ 0.
    Curve,
}

/// One section of the alignment with its cant ramp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Kind of geometry.
    pub kind: SectionKind,
    /// Plan length, m (> 0).
    pub length: f64,
    /// Signed curvature at the start, 1/m.
    pub curvature_start: f64,
    /// Signed curvature at the end, 1/m.
    pub curvature_end: f64,
    /// Signed cant (left rail above right rail) at the start, m.
    pub cant_start: f64,
    /// Signed cant at the end, m; linear in s in between.
    pub cant_end: f64,
}

impl Section {
    /// A straight of `length` m without cant.
    pub fn straight(length: f64) -> Self {
        Section {
            kind: SectionKind::Straight,
            length,
            curvature_start: 0.0,
            curvature_end: 0.0,
            cant_start: 0.0,
            cant_end: 0.0,
        }
    }

    /// A circular curve of `length` m and `radius` m to the left or right,
    /// without cant.
    pub fn curve(length: f64, radius: f64, direction: Direction) -> Self {
        let k = signed_curvature(radius, direction);
        Section {
            kind: SectionKind::Curve,
            length,
            curvature_start: k,
            curvature_end: k,
            cant_start: 0.0,
            cant_end: 0.0,
        }
    }

    /// A clothoid of `length` m whose signed curvature goes linearly from
    /// `curvature_start` to `curvature_end` (1/m), without cant.
    pub fn clothoid(length: f64, curvature_start: f64, curvature_end: f64) -> Self {
        Section {
            kind: SectionKind::Clothoid,
            length,
            curvature_start,
            curvature_end,
            cant_start: 0.0,
            cant_end: 0.0,
        }
    }

    /// A clothoid entering a curve of `radius` m from a straight (κ: 0 → ±1/R).
    pub fn entry_transition(length: f64, radius: f64, direction: Direction) -> Self {
        Self::clothoid(length, 0.0, signed_curvature(radius, direction))
    }

    /// A clothoid leaving a curve of `radius` m into a straight (κ: ±1/R → 0).
    pub fn exit_transition(length: f64, radius: f64, direction: Direction) -> Self {
        Self::clothoid(length, signed_curvature(radius, direction), 0.0)
    }

    /// Sets the cant as a linear ramp of the **magnitudes** `start` → `end` (m,
    /// rail height difference); the sign follows the section's curve direction
    /// (outer rail raised). For a straight use [`Section::with_signed_cant`].
    pub fn with_cant(mut self, start: f64, end: f64) -> Self {
        let k = if self.curvature_start.abs() >= self.curvature_end.abs() {
            self.curvature_start
        } else {
            self.curvature_end
        };
        // Left curve (κ > 0): right rail raised, h = z_left − z_right < 0.
        let sign = if k > 0.0 { -1.0 } else { 1.0 };
        self.cant_start = sign * start.abs();
        self.cant_end = sign * end.abs();
        self
    }

    /// Sets the signed cant (left rail above right rail, m) at both ends.
    pub fn with_signed_cant(mut self, start: f64, end: f64) -> Self {
        self.cant_start = start;
        self.cant_end = end;
        self
    }

    /// dκ/ds, 1/m².
    pub fn curvature_rate(&self) -> f64 {
        (self.curvature_end - self.curvature_start) / self.length
    }

    /// dh/ds, m/m.
    pub fn cant_rate(&self) -> f64 {
        (self.cant_end - self.cant_start) / self.length
    }

    fn validate(&self, i: usize) -> Result<(), TrackError> {
        check_param(&format!("section {i} length"), self.length, true)?;
        check_param(
            &format!("section {i} curvature at start"),
            self.curvature_start,
            false,
        )?;
        check_param(
            &format!("section {i} curvature at end"),
            self.curvature_end,
            false,
        )?;
        check_param(
            &format!("section {i} cant at start"),
            self.cant_start,
            false,
        )?;
        check_param(&format!("section {i} cant at end"), self.cant_end, false)?;
        match self.kind {
            SectionKind::Straight => {
                if self.curvature_start != 0.0 || self.curvature_end != 0.0 {
                    return Err(invalid(
                        format!("section {i} (straight)"),
                        "curvature must be 0",
                    ));
                }
            }
            SectionKind::Curve => {
                if self.curvature_start != self.curvature_end || self.curvature_start == 0.0 {
                    return Err(invalid(
                        format!("section {i} (curve)"),
                        format!(
                            "curvature must be constant and non-zero, got {} -> {} 1/m",
                            self.curvature_start, self.curvature_end
                        ),
                    ));
                }
            }
            SectionKind::Clothoid => {
                // The plan position is integrated in sub-intervals of at most
                // 1 rad of turning (`local_position`), so the turning bounds
                // the work of every position query in the section.
                let turning = (self.curvature_start.abs()
                    + self.curvature_rate().abs() * self.length)
                    * self.length;
                if turning > MAX_CLOTHOID_TURNING {
                    return Err(invalid(
                        format!("section {i} (transition)"),
                        format!(
                            "turns by {turning:.3e} rad over its {} m (curvature {} -> {} 1/m); \
                             a transition curve turns by at most {MAX_CLOTHOID_TURNING} rad",
                            self.length, self.curvature_start, self.curvature_end
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Largest turning of a transition (clothoid) section, (|κ₀| + |κ'| L) L,
/// rad: 1000 rad is 159 full turns, far beyond any track's transition (a
/// few hundredths of a radian), and bounds the plan integration to 1000
/// sub-intervals per position query.
pub const MAX_CLOTHOID_TURNING: f64 = 1000.0;

/// Plan position and heading at the start of the alignment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlanPose {
    /// x in SC0, m.
    pub x: f64,
    /// y in SC0, m.
    pub y: f64,
    /// Heading ψ, rad.
    pub heading: f64,
}

/// Geometry of the plan centre line at one arc position.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AlignmentPoint {
    /// x in SC0, m.
    pub x: f64,
    /// y in SC0, m.
    pub y: f64,
    /// Heading ψ, rad.
    pub heading: f64,
    /// Signed curvature κ = dψ/ds, 1/m.
    pub curvature: f64,
    /// dκ/ds, 1/m².
    pub curvature_rate: f64,
    /// Signed cant h (left rail above right rail), m.
    pub cant: f64,
    /// dh/ds, m/m.
    pub cant_rate: f64,
    /// Index of the section containing s.
    pub section: usize,
}

/// Tolerance for curvature continuity at joints, 1/m (a radius of 10⁹ m).
pub const CURVATURE_JOINT_TOLERANCE: f64 = 1e-9;
/// Tolerance for cant continuity at joints, m.
pub const CANT_JOINT_TOLERANCE: f64 = 1e-9;

/// A validated chain of sections with the start pose of each precomputed.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    sections: Vec<Section>,
    /// Start arc position and plan pose of each section.
    starts: Vec<(f64, PlanPose)>,
    length: f64,
}

impl Alignment {
    /// Builds an alignment starting at the SC0 origin heading along x, checking
    /// that curvature and cant are continuous at every joint.
    pub fn new(sections: Vec<Section>) -> Result<Self, TrackError> {
        Self::build(sections, PlanPose::default(), true)
    }

    /// As [`Alignment::new`] but allows curvature jumps at joints (a curve
    /// without transitions); cant must still be continuous.
    pub fn new_allowing_curvature_jumps(sections: Vec<Section>) -> Result<Self, TrackError> {
        Self::build(sections, PlanPose::default(), false)
    }

    /// As [`Alignment::new`] from a given start pose.
    pub fn with_start(sections: Vec<Section>, start: PlanPose) -> Result<Self, TrackError> {
        Self::build(sections, start, true)
    }

    fn build(
        sections: Vec<Section>,
        start: PlanPose,
        strict_curvature: bool,
    ) -> Result<Self, TrackError> {
        if sections.is_empty() {
            return Err(invalid("alignment", "needs at least one section"));
        }
        check_param("start x", start.x, false)?;
        check_param("start y", start.y, false)?;
        check_param("start heading", start.heading, false)?;
        let mut starts = Vec::with_capacity(sections.len());
        let mut s = 0.0;
        let mut pose = start;
        for (i, sec) in sections.iter().enumerate() {
            sec.validate(i)?;
            if i > 0 {
                let prev = &sections[i - 1];
                if strict_curvature
                    && (prev.curvature_end - sec.curvature_start).abs() > CURVATURE_JOINT_TOLERANCE
                {
                    return Err(TrackError::Discontinuity {
                        quantity: "curvature",
                        before: i - 1,
                        after: i,
                        s,
                        value_before: prev.curvature_end,
                        value_after: sec.curvature_start,
                    });
                }
                if (prev.cant_end - sec.cant_start).abs() > CANT_JOINT_TOLERANCE {
                    return Err(TrackError::Discontinuity {
                        quantity: "cant",
                        before: i - 1,
                        after: i,
                        s,
                        value_before: prev.cant_end,
                        value_after: sec.cant_start,
                    });
                }
            }
            starts.push((s, pose));
            let (dx, dy, psi) = local_position(sec, pose.heading, sec.length);
            pose = PlanPose {
                x: pose.x + dx,
                y: pose.y + dy,
                heading: psi,
            };
            s += sec.length;
        }
        Ok(Alignment {
            sections,
            starts,
            length: s,
        })
    }

    /// Total plan length, m.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The sections.
    pub fn sections(&self) -> &[Section] {
        &self.sections
    }

    /// Arc position at the start of section `i`, m.
    pub fn section_start(&self, i: usize) -> Option<f64> {
        self.starts.get(i).map(|p| p.0)
    }

    /// Arc position at the end of section `i`, m.
    pub fn section_end(&self, i: usize) -> Option<f64> {
        self.starts.get(i).map(|p| p.0 + self.sections[i].length)
    }

    /// Plan pose at the end of the alignment.
    pub fn end_pose(&self) -> PlanPose {
        let (_, p0) = self.starts[self.starts.len() - 1];
        let sec = &self.sections[self.sections.len() - 1];
        let (dx, dy, psi) = local_position(sec, p0.heading, sec.length);
        PlanPose {
            x: p0.x + dx,
            y: p0.y + dy,
            heading: psi,
        }
    }

    /// Index of the section containing `s` (the later one at a joint).
    fn locate(&self, s: f64) -> usize {
        let i = self.starts.partition_point(|p| p.0 <= s);
        i.saturating_sub(1)
    }

    /// Checks that `s` is finite and on the alignment.
    pub fn check_s(&self, s: f64) -> Result<f64, TrackError> {
        finite("arc position s", s)?;
        // A relative slack of 1e-12 lets the end point computed by summing
        // section lengths be evaluated.
        let slack = 1e-12 * self.length.max(1.0);
        if s < -slack || s > self.length + slack {
            return Err(TrackError::OutOfRange {
                s,
                start: 0.0,
                end: self.length,
            });
        }
        Ok(s.clamp(0.0, self.length))
    }

    /// Plan geometry at arc position `s` (m). No allocation.
    ///
    /// Straights and curves are closed form; clothoid positions come from
    /// 8-point Gauss–Legendre quadrature of (cos ψ, sin ψ) on sub-intervals over
    /// which ψ changes by at most 1 rad (checked against the Fresnel integrals
    /// to 1e-11 m over 200 m, including a spiral turning through 3.3 rad).
    pub fn point(&self, s: f64) -> Result<AlignmentPoint, TrackError> {
        let s = self.check_s(s)?;
        let i = self.locate(s);
        let (s0, p0) = self.starts[i];
        let sec = &self.sections[i];
        let u = (s - s0).clamp(0.0, sec.length);
        let (dx, dy, psi) = local_position(sec, p0.heading, u);
        let kr = sec.curvature_rate();
        let hr = sec.cant_rate();
        Ok(AlignmentPoint {
            x: p0.x + dx,
            y: p0.y + dy,
            heading: psi,
            curvature: sec.curvature_start + kr * u,
            curvature_rate: kr,
            cant: sec.cant_start + hr * u,
            cant_rate: hr,
            section: i,
        })
    }
}

/// sin(x)/x, accurate near 0.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

// 8-point Gauss–Legendre nodes and weights on [−1, 1] (Abramowitz & Stegun, Table 25.4),
// positive half; digits as published.
#[allow(clippy::excessive_precision)]
pub(crate) const GL8_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329_0,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
#[allow(clippy::excessive_precision)]
pub(crate) const GL8_W: [f64; 4] = [
    0.362_683_783_378_362_0,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// Displacement (dx, dy) and heading after arc length `u` from the section start
/// with start heading `psi0`.
fn local_position(sec: &Section, psi0: f64, u: f64) -> (f64, f64, f64) {
    let k0 = sec.curvature_start;
    let c = sec.curvature_rate();
    let psi = psi0 + k0 * u + 0.5 * c * u * u;
    if c == 0.0 {
        // Straight or arc: chord of length u·sinc(κu/2) at the mean heading.
        let half = 0.5 * k0 * u;
        let chord = u * sinc(half);
        let mid = psi0 + half;
        return (chord * mid.cos(), chord * mid.sin(), psi);
    }
    // Clothoid: ∫₀ᵘ (cos ψ(t), sin ψ(t)) dt, ψ(t) = ψ0 + k0 t + c t²/2.
    // Sub-intervals of length h with (|k0| + |c|u)·h ≤ 1 rad: the integrand's
    // derivatives are bounded by (|k0| + |c|u)^n, so the 8-point rule's error
    // term h^17 f^(16)/ (2^16 ...) is far below rounding.
    let rate = k0.abs() + c.abs() * u;
    let m = ((rate * u).ceil() as usize).max(1);
    let h = u / m as f64;
    let (mut sx, mut sy) = (0.0, 0.0);
    for j in 0..m {
        let mid = (j as f64 + 0.5) * h;
        for k in 0..4 {
            for sgn in [-1.0, 1.0] {
                let t = mid + sgn * GL8_X[k] * 0.5 * h;
                let p = psi0 + k0 * t + 0.5 * c * t * t;
                let (sn, cs) = p.sin_cos();
                sx += GL8_W[k] * cs;
                sy += GL8_W[k] * sn;
            }
        }
    }
    (0.5 * h * sx, 0.5 * h * sy, psi)
}
