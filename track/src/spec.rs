//! Serializable track descriptions (for RON scenario files) and their
//! validation into a [`Track`].
//!
//! ```ron
//! Custom((
//!     sections: [
//!         Straight(length: 25.0),
//!         Transition(length: 50.0, direction: Right, radius_end: Some(150.0), cant_end: 0.1),
//!         Curve(length: 50.0, radius: 150.0, direction: Right, cant: 0.1),
//!         Transition(length: 50.0, direction: Right, radius_start: Some(150.0), cant_start: 0.1),
//!         Straight(length: 100.0),
//!     ],
//!     irregularities: [
//!         Dip(rail: Left, start: 170.0, length: 10.0, depth: 0.02, shape: Linear),
//!     ],
//! ))
//! ```
//! or a named case: `Case(ManchesterTc1)`.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::alignment::{Alignment, Direction, Section};
use crate::cases;
use crate::error::{TrackError, invalid};
use crate::irregularity::{
    Component, Dip, DipShape, GaugeWidening, Irregularities, Irregularity, MeasuredIrregularity,
    Rail, Sinusoid,
};
use crate::profile::VerticalProfile;
use crate::psd::{PsdModel, StochasticIrregularity, StochasticSpec};
use crate::track::{RAIL_INCLINATION_1_40, STANDARD_GAUGE, STANDARD_RAIL_DISTANCE, Track};

/// A track: a named case or a custom description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum TrackDescription {
    /// One of the documented track cases of [`crate::cases`].
    Case(TrackCase),
    /// A custom track.
    Custom(TrackSpec),
}

/// The track cases of [`crate::cases`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum TrackCase {
    /// [`cases::manchester_tc1`].
    ManchesterTc1,
    /// [`cases::manchester_tc3`] of `length` m.
    ManchesterTc3 {
        /// Track length, m.
        length: f64,
    },
    /// [`cases::high_speed_curve`].
    HighSpeedCurve,
    /// [`cases::straight_lateral_irregularity`].
    StraightLateralIrregularity {
        /// Track length, m.
        length: f64,
        /// PRNG seed.
        seed: u64,
    },
}

/// One section. Radii in m, cants are magnitudes in m (the outer rail is
/// raised), lengths in m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SectionSpec {
    /// A straight; `cant` is signed (left rail above right rail), default 0.
    Straight {
        /// Length, m.
        length: f64,
        /// Signed cant, m.
        #[serde(default)]
        cant: f64,
    },
    /// A circular curve.
    Curve {
        /// Length, m.
        length: f64,
        /// Radius, m.
        radius: f64,
        /// Left or right.
        direction: Direction,
        /// Cant magnitude, m.
        #[serde(default)]
        cant: f64,
    },
    /// A clothoid between two radii (None: straight).
    Transition {
        /// Length, m.
        length: f64,
        /// Left or right.
        direction: Direction,
        /// Radius at the start, m (None: infinite).
        #[serde(default)]
        radius_start: Option<f64>,
        /// Radius at the end, m (None: infinite).
        #[serde(default)]
        radius_end: Option<f64>,
        /// Cant magnitude at the start, m.
        #[serde(default)]
        cant_start: f64,
        /// Cant magnitude at the end, m.
        #[serde(default)]
        cant_end: f64,
    },
}

/// One irregularity (see [`crate::irregularity`], [`crate::psd`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum IrregularitySpec {
    /// [`Dip`].
    Dip {
        /// Rail(s).
        rail: Rail,
        /// Start, m.
        start: f64,
        /// Length, m.
        length: f64,
        /// Depth, m (positive down).
        depth: f64,
        /// Shape.
        shape: DipShape,
    },
    /// [`Sinusoid`].
    Sinusoid {
        /// Component.
        component: Component,
        /// Wavelength, m.
        wavelength: f64,
        /// Amplitude, m.
        amplitude: f64,
        /// Start, m.
        start: f64,
        /// End, m.
        end: f64,
        /// Phase at start, rad.
        #[serde(default)]
        phase: f64,
    },
    /// [`GaugeWidening`]; without `start` the widening is constant.
    GaugeWidening {
        /// Widening, m.
        widening: f64,
        /// Start of the ramp, m.
        #[serde(default)]
        start: Option<f64>,
        /// Ramp length, m.
        #[serde(default)]
        ramp: f64,
    },
    /// [`StochasticIrregularity`]; with `sample_step` (m) it is tabulated at
    /// that step for fast evaluation.
    Stochastic {
        /// Spectrum.
        model: PsdModel,
        /// Component.
        component: Component,
        /// Shortest wavelength, m.
        wavelength_min: f64,
        /// Longest wavelength, m.
        wavelength_max: f64,
        /// Number of harmonics.
        harmonics: usize,
        /// PRNG seed.
        seed: u64,
        /// Start, m.
        start: f64,
        /// End, m.
        end: f64,
        /// Fade length, m.
        #[serde(default)]
        fade: f64,
        /// Tabulation step, m.
        #[serde(default)]
        sample_step: Option<f64>,
    },
    /// [`MeasuredIrregularity`] from a CSV file (relative paths are resolved
    /// against the directory given to [`TrackDescription::build`]).
    Measured {
        /// The CSV file.
        file: PathBuf,
    },
}

/// A custom track description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackSpec {
    /// Sections in order.
    pub sections: Vec<SectionSpec>,
    /// Allow curvature jumps at joints (default false).
    #[serde(default)]
    pub allow_curvature_jumps: bool,
    /// Grade knots (s m, grade m/m); empty: level.
    #[serde(default)]
    pub grade: Vec<(f64, f64)>,
    /// Height at s = 0, m.
    #[serde(default)]
    pub z0: f64,
    /// Rail distance 2e0, m (default 1.5).
    #[serde(default = "default_rail_distance")]
    pub rail_distance: f64,
    /// Nominal gauge, m (default 1.435).
    #[serde(default = "default_gauge")]
    pub gauge: f64,
    /// Design gauge widening knots (s m, widening m); empty: none.
    #[serde(default)]
    pub gauge_widening: Vec<(f64, f64)>,
    /// Rail inclination (tangent, default 1/40).
    #[serde(default = "default_inclination")]
    pub rail_inclination: f64,
    /// Irregularities.
    #[serde(default)]
    pub irregularities: Vec<IrregularitySpec>,
}

fn default_rail_distance() -> f64 {
    STANDARD_RAIL_DISTANCE
}
fn default_gauge() -> f64 {
    STANDARD_GAUGE
}
fn default_inclination() -> f64 {
    RAIL_INCLINATION_1_40
}

fn curvature(radius: Option<f64>, direction: Direction, what: String) -> Result<f64, TrackError> {
    match radius {
        None => Ok(0.0),
        Some(r) if r.is_finite() && r > 0.0 => Ok(direction.sign() / r),
        Some(r) => Err(invalid(
            what,
            format!("radius {r} m must be finite and > 0"),
        )),
    }
}

impl SectionSpec {
    fn build(&self, i: usize) -> Result<Section, TrackError> {
        Ok(match *self {
            SectionSpec::Straight { length, cant } => {
                Section::straight(length).with_signed_cant(cant, cant)
            }
            SectionSpec::Curve {
                length,
                radius,
                direction,
                cant,
            } => {
                curvature(Some(radius), direction, format!("section {i} (curve)"))?;
                Section::curve(length, radius, direction).with_cant(cant, cant)
            }
            SectionSpec::Transition {
                length,
                direction,
                radius_start,
                radius_end,
                cant_start,
                cant_end,
            } => {
                let what = || format!("section {i} (transition)");
                let k0 = curvature(radius_start, direction, what())?;
                let k1 = curvature(radius_end, direction, what())?;
                if k0 == 0.0 && k1 == 0.0 {
                    return Err(invalid(what(), "needs radius_start or radius_end"));
                }
                for c in [cant_start, cant_end] {
                    if c < 0.0 {
                        return Err(invalid(
                            what(),
                            format!("cant {c} m must be a magnitude ≥ 0"),
                        ));
                    }
                }
                Section::clothoid(length, k0, k1).with_cant(cant_start, cant_end)
            }
        })
    }
}

impl IrregularitySpec {
    fn build(&self, base: &Path) -> Result<Irregularity, TrackError> {
        Ok(match self {
            IrregularitySpec::Dip {
                rail,
                start,
                length,
                depth,
                shape,
            } => Irregularity::Dip(Dip::new(*rail, *start, *length, *depth, *shape)?),
            IrregularitySpec::Sinusoid {
                component,
                wavelength,
                amplitude,
                start,
                end,
                phase,
            } => {
                let mut s = Sinusoid::new(*component, *wavelength, *amplitude, *start, *end)?;
                if !phase.is_finite() {
                    return Err(invalid("sinusoid phase", format!("{phase} is not finite")));
                }
                s.phase = *phase;
                Irregularity::Sinusoid(s)
            }
            IrregularitySpec::GaugeWidening {
                widening,
                start,
                ramp,
            } => Irregularity::GaugeWidening(match start {
                None => GaugeWidening::constant(*widening)?,
                Some(s) => GaugeWidening::new(*s, *ramp, *widening)?,
            }),
            IrregularitySpec::Stochastic {
                model,
                component,
                wavelength_min,
                wavelength_max,
                harmonics,
                seed,
                start,
                end,
                fade,
                sample_step,
            } => {
                let g = StochasticIrregularity::generate(&StochasticSpec {
                    model: *model,
                    component: *component,
                    wavelength_min: *wavelength_min,
                    wavelength_max: *wavelength_max,
                    harmonics: *harmonics,
                    seed: *seed,
                    start: *start,
                    end: *end,
                    fade: *fade,
                })?;
                match sample_step {
                    Some(ds) => Irregularity::Sampled(g.sampled_lazily(*ds)?),
                    None => Irregularity::Stochastic(g),
                }
            }
            IrregularitySpec::Measured { file } => {
                let path = if file.is_absolute() {
                    file.clone()
                } else {
                    base.join(file)
                };
                Irregularity::Measured(MeasuredIrregularity::from_csv(path)?)
            }
        })
    }
}

impl TrackSpec {
    /// Validates and builds the track; relative CSV paths are resolved
    /// against `base`.
    pub fn build(&self, base: &Path) -> Result<Track, TrackError> {
        let sections = self
            .sections
            .iter()
            .enumerate()
            .map(|(i, s)| s.build(i))
            .collect::<Result<Vec<_>, _>>()?;
        let alignment = if self.allow_curvature_jumps {
            Alignment::new_allowing_curvature_jumps(sections)?
        } else {
            Alignment::new(sections)?
        };
        let vertical = if self.grade.is_empty() {
            VerticalProfile::level()
        } else {
            VerticalProfile::from_grade_knots(&self.grade, self.z0)?
        };
        let mut irr = Irregularities::new();
        for it in &self.irregularities {
            irr.push(it.build(base)?);
        }
        let mut t = Track::new(alignment)?
            .with_vertical(vertical)
            .with_rail_distance(self.rail_distance)?
            .with_gauge(self.gauge)?
            .with_rail_inclination(self.rail_inclination)?
            .with_irregularities(irr);
        if !self.gauge_widening.is_empty() {
            t = t.with_gauge_widening(&self.gauge_widening)?;
        }
        Ok(t)
    }
}

impl TrackDescription {
    /// Validates and builds the track; relative CSV paths are resolved
    /// against `base` (typically the directory of the scenario file).
    pub fn build(&self, base: &Path) -> Result<Track, TrackError> {
        match self {
            TrackDescription::Case(c) => match *c {
                TrackCase::ManchesterTc1 => cases::manchester_tc1(),
                TrackCase::ManchesterTc3 { length } => cases::manchester_tc3(length),
                TrackCase::HighSpeedCurve => cases::high_speed_curve(),
                TrackCase::StraightLateralIrregularity { length, seed } => {
                    cases::straight_lateral_irregularity(length, seed)
                }
            },
            TrackDescription::Custom(spec) => spec.build(base),
        }
    }
}
