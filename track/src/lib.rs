//! # railmbs-track
//!
//! Track geometry as pure functions, validated against analytic results:
//!
//! - [`alignment`]: straights, clothoid transitions and circular curves (left or
//!   right) with linear cant ramps and continuity checks; position, heading,
//!   curvature at arc length s;
//! - [`profile`]: vertical profile (grade, vertical curves) and piecewise-linear
//!   functions of s (design gauge widening);
//! - [`track`]: the [`Track`] (alignment + vertical profile + rail distance 2e0,
//!   gauge, rail inclination, irregularities) and the **track-following frame**
//!   [`TrackFrame`] (pose, velocity, angular velocity and their rates) for the
//!   rheonomic joints of vehicle models; balancing speed and cant deficiency;
//! - [`speed`]: running-speed laws s(t) (constant, tabulated v(t), or your own);
//! - [`irregularity`]: dips, sinusoids, gauge widening, measured (CSV) and
//!   their sum per rail;
//! - [`psd`]: stochastic irregularities from the ERRI (ORE B176) and FRA PSDs;
//! - [`cases`]: the track cases of the Manchester benchmark and others;
//! - [`spec`]: serde descriptions of tracks (for RON scenario files).
//!
//! Conventions (docs/design.md): SI units; SC0 x forward along the start of the
//! track, y left, z up; s is the plan arc length; signed curvature κ > 0 turns
//! left; signed cant h = z(left rail) − z(right rail).

pub mod alignment;
pub mod cases;
pub mod error;
pub mod irregularity;
pub mod profile;
pub mod psd;
pub mod spec;
pub mod speed;
pub mod track;

pub use alignment::{Alignment, AlignmentPoint, Direction, PlanPose, Section, SectionKind};
pub use error::TrackError;
pub use irregularity::{
    Component, Dip, DipShape, GaugeWidening, Irregularities, Irregularity, MeasuredIrregularity,
    Rail, RailDeviation, Sinusoid,
};
pub use profile::{PiecewiseLinear, VerticalPoint, VerticalProfile};
pub use psd::{PsdModel, SampledIrregularity, StochasticIrregularity, StochasticSpec};
pub use spec::{IrregularitySpec, SectionSpec, TrackCase, TrackDescription, TrackSpec};
pub use speed::{ArcMotion, ConstantSpeed, SpeedLaw, SpeedTable};
pub use track::{
    FRAME_INPUTS, STANDARD_GAUGE, STANDARD_GRAVITY, STANDARD_RAIL_DISTANCE, Track, TrackFrame,
    TrackPoint, balancing_speed, cant_angle, cant_deficiency, uncompensated_lateral_acceleration,
};
