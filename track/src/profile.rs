//! Piecewise-linear functions of arc length: vertical grade (giving z(s) and
//! pitch), design gauge widening.

use crate::error::{TrackError, check_param, finite, invalid};

/// A piecewise-linear function y(x) through knots with strictly increasing x,
/// constant beyond the first and last knot, with its exact integral.
#[derive(Debug, Clone, PartialEq)]
pub struct PiecewiseLinear {
    x: Vec<f64>,
    y: Vec<f64>,
    /// ∫ from x[0] to x[i] of y.
    cumulative: Vec<f64>,
}

impl PiecewiseLinear {
    /// Builds from knots; `name` is used in error messages.
    pub fn new(name: &str, knots: &[(f64, f64)]) -> Result<Self, TrackError> {
        if knots.is_empty() {
            return Err(invalid(name, "needs at least one knot"));
        }
        let mut x = Vec::with_capacity(knots.len());
        let mut y = Vec::with_capacity(knots.len());
        for (i, &(xi, yi)) in knots.iter().enumerate() {
            check_param(&format!("{name} knot {i} position"), xi, false)?;
            check_param(&format!("{name} knot {i} value"), yi, false)?;
            if let Some(&prev) = x.last()
                && xi <= prev
            {
                return Err(invalid(
                    format!("{name} knot {i}"),
                    format!("position {xi} m is not greater than the previous {prev} m"),
                ));
            }
            x.push(xi);
            y.push(yi);
        }
        let mut cumulative = vec![0.0; x.len()];
        for i in 1..x.len() {
            cumulative[i] = cumulative[i - 1] + 0.5 * (y[i] + y[i - 1]) * (x[i] - x[i - 1]);
        }
        Ok(PiecewiseLinear { x, y, cumulative })
    }

    /// A constant function.
    pub fn constant(value: f64) -> Self {
        PiecewiseLinear {
            x: vec![0.0],
            y: vec![value],
            cumulative: vec![0.0],
        }
    }

    fn segment(&self, x: f64) -> usize {
        self.x.partition_point(|&k| k <= x).saturating_sub(1)
    }

    /// Value and slope dy/dx at `x` (slope 0 outside the knots; at a knot the
    /// slope of the segment to the right).
    pub fn value_slope(&self, x: f64) -> (f64, f64) {
        let n = self.x.len();
        if x <= self.x[0] {
            return (
                self.y[0],
                if n > 1 && x == self.x[0] {
                    self.slope_of(0)
                } else {
                    0.0
                },
            );
        }
        if x >= self.x[n - 1] {
            return (self.y[n - 1], 0.0);
        }
        let i = self.segment(x);
        let k = self.slope_of(i);
        (self.y[i] + k * (x - self.x[i]), k)
    }

    fn slope_of(&self, i: usize) -> f64 {
        (self.y[i + 1] - self.y[i]) / (self.x[i + 1] - self.x[i])
    }

    /// ∫ from `x[0]` to `x` of y (negative for x < `x[0]`).
    pub fn integral(&self, x: f64) -> f64 {
        let n = self.x.len();
        if x <= self.x[0] {
            return self.y[0] * (x - self.x[0]);
        }
        if x >= self.x[n - 1] {
            return self.cumulative[n - 1] + self.y[n - 1] * (x - self.x[n - 1]);
        }
        let i = self.segment(x);
        let (yx, _) = self.value_slope(x);
        self.cumulative[i] + 0.5 * (self.y[i] + yx) * (x - self.x[i])
    }
}

/// Vertical profile: the grade g = dz/ds (m/m) is piecewise linear in s (a
/// constant grade per stretch, joined by parabolic vertical curves where the
/// grade ramps), so z(s) is piecewise quadratic with continuous slope.
///
/// `s` is the plan arc length; the 3-D path is longer by the factor √(1+g²)
/// (0.08 % at 4 %), which the track frame accounts for in its velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct VerticalProfile {
    grade: PiecewiseLinear,
    z0: f64,
}

/// Height and grade of the centre line at one arc position.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VerticalPoint {
    /// Rail-top level of the centre line, m.
    pub z: f64,
    /// Grade g = dz/ds, m/m.
    pub grade: f64,
    /// dg/ds (vertical curvature), 1/m.
    pub grade_rate: f64,
}

impl VerticalProfile {
    /// Level track at height 0.
    pub fn level() -> Self {
        VerticalProfile {
            grade: PiecewiseLinear::constant(0.0),
            z0: 0.0,
        }
    }

    /// A constant grade (m/m, positive uphill) with z(0) = 0.
    pub fn constant_grade(grade: f64) -> Result<Self, TrackError> {
        check_param("grade", grade, false)?;
        Ok(VerticalProfile {
            grade: PiecewiseLinear::constant(grade),
            z0: 0.0,
        })
    }

    /// Grade knots (s m, grade m/m) joined linearly, and the height `z0` (m) at
    /// s = 0. A vertical curve of radius Rv between grades g1 and g2 is the pair
    /// of knots (s1, g1), (s1 + Rv·|g2 − g1|, g2).
    pub fn from_grade_knots(knots: &[(f64, f64)], z0: f64) -> Result<Self, TrackError> {
        check_param("vertical profile z0", z0, false)?;
        Ok(VerticalProfile {
            grade: PiecewiseLinear::new("vertical grade", knots)?,
            z0,
        })
    }

    /// Height, grade and its rate at `s` (m).
    pub fn point(&self, s: f64) -> Result<VerticalPoint, TrackError> {
        finite("arc position s", s)?;
        let (g, gr) = self.grade.value_slope(s);
        Ok(VerticalPoint {
            z: self.z0 + self.grade.integral(s) - self.grade.integral(0.0),
            grade: g,
            grade_rate: gr,
        })
    }
}
