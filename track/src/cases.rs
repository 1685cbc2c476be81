//! Track cases: data plus documented choices.
//!
//! Public sources (Pogorelov 2005; `../shared/reference/README.md`) give only
//! the headline data of the Manchester benchmark track cases; everything else
//! here (transition lengths, lead-in, dip length, sinusoid wavelength and
//! amplitude) is our choice, stated per case. All use standard gauge 1.435 m,
//! 2e0 = 1.5 m and rail inclination 1:40.

use crate::alignment::{Alignment, Direction, Section};
use crate::error::TrackError;
use crate::irregularity::{
    Component, Dip, DipShape, GaugeWidening, Irregularities, Irregularity, Rail, Sinusoid,
};
use crate::psd::{PsdModel, StochasticIrregularity, StochasticSpec};
use crate::track::Track;

/// Track case 1: curve radius, m.
pub const TC1_RADIUS: f64 = 150.0;
/// Track case 1: cant, m.
pub const TC1_CANT: f64 = 0.100;
/// Track case 1: straight lead-in, m (our choice: a Manchester Vehicle 1 whose
/// body centre starts at [`TC1_BODY_START`] has all wheelsets on the straight).
pub const TC1_LEAD_IN: f64 = 25.0;
/// Track case 1: clothoid transitions with linear cant ramps, m (our choice:
/// cant rate 2 mm/m, curvature rate 1/(150·50) 1/m²).
pub const TC1_TRANSITION: f64 = 50.0;
/// Track case 1: circular curve length, m (our choice: longer than the
/// vehicle's 21.56 m wheelbase so that steady curving is reached).
pub const TC1_CURVE: f64 = 50.0;
/// Track case 1: straight after the leaving transition, m (our choice).
pub const TC1_RUN_OUT: f64 = 100.0;
/// Track case 1: dip depth, m (the benchmark's 20 mm).
pub const TC1_DIP_DEPTH: f64 = 0.020;
/// Track case 1: dip length, m (our choice: 5 m ramps down and up, 4 mm/m),
/// centred on the end of the leaving transition.
pub const TC1_DIP_LENGTH: f64 = 10.0;
/// Track case 1: running speed, m/s.
pub const TC1_SPEED: f64 = 4.4;
/// Track case 1: simulated time, s.
pub const TC1_DURATION: f64 = 42.0;
/// Track case 1: suggested arc position of Vehicle 1's body centre at t = 0, m
/// (rear wheelset at 0.22 m; it passes the dip's end at about 40.9 s).
pub const TC1_BODY_START: f64 = 11.0;

/// Manchester benchmark track case 1: right curve R = 150 m with 100 mm cant,
/// reached and left by 50 m clothoids with linear cant ramps after a 25 m
/// straight lead-in, followed by a 100 m straight; a single linear (V-shaped)
/// dip of 20 mm, 10 m long, in the outer (left) rail, centred on the end of the
/// leaving transition (s = 175 m). Total length 275 m.
pub fn manchester_tc1() -> Result<Track, TrackError> {
    let dir = Direction::Right;
    let alignment = Alignment::new(vec![
        Section::straight(TC1_LEAD_IN),
        Section::entry_transition(TC1_TRANSITION, TC1_RADIUS, dir).with_cant(0.0, TC1_CANT),
        Section::curve(TC1_CURVE, TC1_RADIUS, dir).with_cant(TC1_CANT, TC1_CANT),
        Section::exit_transition(TC1_TRANSITION, TC1_RADIUS, dir).with_cant(TC1_CANT, 0.0),
        Section::straight(TC1_RUN_OUT),
    ])?;
    let end_of_transition = TC1_LEAD_IN + 2.0 * TC1_TRANSITION + TC1_CURVE;
    let dip = Dip::new(
        Rail::Left,
        end_of_transition - 0.5 * TC1_DIP_LENGTH,
        TC1_DIP_LENGTH,
        TC1_DIP_DEPTH,
        DipShape::Linear,
    )?;
    Ok(Track::new(alignment)?
        .with_irregularities(Irregularities::new().with(Irregularity::Dip(dip))))
}

/// Track case 3: gauge widening, m (the benchmark's 25.4 mm).
pub const TC3_GAUGE_WIDENING: f64 = 0.0254;
/// Track case 3: lateral sinusoid wavelength, m (our choice).
pub const TC3_WAVELENGTH: f64 = 25.0;
/// Track case 3: lateral sinusoid amplitude, m (our choice; 10 mm peak to peak).
pub const TC3_AMPLITUDE: f64 = 0.005;
/// Track case 3: start of the sinusoid, m (our choice).
pub const TC3_START: f64 = 50.0;
/// Track case 3: number of whole wavelengths (our choice).
pub const TC3_WAVES: f64 = 20.0;
/// Track case 3: running speed, m/s.
pub const TC3_SPEED: f64 = 22.5;

/// Manchester benchmark track case 3: straight track of `length` m (≥ 600 m;
/// 1000 m covers 44 s at 22.5 m/s), gauge widened by 25.4 mm throughout
/// (±12.7 mm per rail), and a lateral (alignment) sinusoid of 25 m wavelength and
/// 5 mm amplitude over 20 whole wavelengths from s = 50 m (starting and ending
/// at zero deviation).
pub fn manchester_tc3(length: f64) -> Result<Track, TrackError> {
    let end = TC3_START + TC3_WAVES * TC3_WAVELENGTH;
    if length.is_nan() || length < end + 50.0 {
        return Err(crate::error::invalid(
            "track case 3 length",
            format!("{length} m must be at least {} m", end + 50.0),
        ));
    }
    let alignment = Alignment::new(vec![Section::straight(length)])?;
    let irr = Irregularities::new()
        .with(Irregularity::GaugeWidening(GaugeWidening::constant(
            TC3_GAUGE_WIDENING,
        )?))
        .with(Irregularity::Sinusoid(Sinusoid::new(
            Component::Lateral,
            TC3_WAVELENGTH,
            TC3_AMPLITUDE,
            TC3_START,
            end,
        )?));
    Ok(Track::new(alignment)?.with_irregularities(irr))
}

/// High-speed curve: radius, m.
pub const HS_RADIUS: f64 = 1200.0;
/// High-speed curve: cant, m (our choice).
pub const HS_CANT: f64 = 0.150;
/// High-speed curve: transitions, m (our choice: cant rate 0.75 mm/m).
pub const HS_TRANSITION: f64 = 200.0;
/// High-speed curve: curve length, m (our choice).
pub const HS_CURVE: f64 = 600.0;
/// High-speed curve: suggested speed, m/s (162 km/h): a_q = v²/R − g h/2e0 ≈
/// 0.71 m/s², cant deficiency ≈ 109 mm; the balancing speed is ≈ 34.4 m/s.
pub const HS_SPEED: f64 = 45.0;

/// A left curve of 1200 m radius with 150 mm cant for high speed: 100 m
/// straight, 200 m clothoid with cant ramp, 600 m curve, 200 m clothoid, 200 m
/// straight (1300 m).
pub fn high_speed_curve() -> Result<Track, TrackError> {
    let dir = Direction::Left;
    let alignment = Alignment::new(vec![
        Section::straight(100.0),
        Section::entry_transition(HS_TRANSITION, HS_RADIUS, dir).with_cant(0.0, HS_CANT),
        Section::curve(HS_CURVE, HS_RADIUS, dir).with_cant(HS_CANT, HS_CANT),
        Section::exit_transition(HS_TRANSITION, HS_RADIUS, dir).with_cant(HS_CANT, 0.0),
        Section::straight(200.0),
    ])?;
    Track::new(alignment)
}

/// Straight track of `length` m with a stochastic lateral (alignment)
/// irregularity: ERRI (ORE B176) low level, wavelengths 3–100 m, as many
/// harmonics as keep the realization from repeating on the track (at least
/// 500, repeat length ≥ 1.5 km), phases from `seed`, from s = 50 m to
/// `length` − 50 m with 20 m fades, tabulated every 0.05 m (our choices; for
/// the 55 m/s run of Vehicle 1).
pub fn straight_lateral_irregularity(length: f64, seed: u64) -> Result<Track, TrackError> {
    if length.is_nan() || length <= 200.0 {
        return Err(crate::error::invalid(
            "straight track length",
            format!("{length} m must exceed 200 m"),
        ));
    }
    let alignment = Alignment::new(vec![Section::straight(length)])?;
    // Enough harmonics that the realization does not repeat on the track:
    // repeat length N·λmin·λmax/(λmax − λmin) ≥ length, and at least 500.
    let harmonics = ((length * (100.0 - 3.0) / 300.0).ceil() as usize).max(500);
    let irr = StochasticIrregularity::generate(&StochasticSpec {
        model: PsdModel::ErriLow,
        component: Component::Lateral,
        wavelength_min: 3.0,
        wavelength_max: 100.0,
        harmonics,
        seed,
        start: 50.0,
        end: length - 50.0,
        fade: 20.0,
    })?;
    // Tabulated every 5 cm for speed (~55 ns instead of ~100 µs per evaluation):
    // the interpolation error is below (π·0.05/3)²/2 = 0.14 % of the 3 m
    // harmonics' amplitude.
    let table = irr.sampled_lazily(0.05)?;
    Ok(Track::new(alignment)?
        .with_irregularities(Irregularities::new().with(Irregularity::Sampled(table))))
}
