//! Stochastic irregularities from published power spectral densities (PSD),
//! generated as a sum of harmonics with random phases.
//!
//! All PSDs here are **one-sided in the angular wavenumber** Ω (rad/m): the
//! variance of the irregularity over a band is ∫ S(Ω) dΩ, S in m²/(rad/m). (A PSD
//! per cyclic wavenumber f = Ω/2π, in m²/(1/m), is 2π S.)
//!
//! **ERRI / ORE B176** (ORE B176 RP1, 1989; as used e.g. in GENSYS `TRC_IPSD`,
//! whose tabulated "ORE B176 high level" values at 50 m and 10 m wavelength
//! this formula reproduces to 4 digits):
//! - vertical level and alignment: S(Ω) = A Ωc² / ((Ω² + Ωr²)(Ω² + Ωc²));
//! - cross-level, as an angle over the half contact distance b:
//!   S(Ω) = (A_v/b²) Ωc² Ω² / ((Ω² + Ωr²)(Ω² + Ωc²)(Ω² + Ωs²)); here as a rail
//!   height difference over 2b, i.e. multiplied by (2b)², which removes b;
//! - Ωc = 0.8246, Ωr = 0.0206, Ωs = 0.4380 rad/m; low level A_v = 5.9233e-7,
//!   A_a = 3.3651e-7 m·rad; high level A_v = 1.0800e-6, A_a = 6.1250e-7 m·rad.
//!
//! **FRA classes 1–6** (Hamid & Yang, "Analytical descriptions of track geometry
//! variations", DOT/FRA/ORD-83/03.1, 1983, as tabulated in Garg & Dukkipati,
//! *Dynamics of Railway Vehicle Systems*, 1984):
//! - vertical profile: S(Ω) = k A_v Ωc² / (Ω² (Ω² + Ωc²));
//! - alignment: S(Ω) = k A_a Ωc² / (Ω² (Ω² + Ωc²));
//! - k = 0.25, Ωc = 0.8245 rad/m, A in cm²·rad/m (converted here to m²):
//!   A_v = 1.2107, 1.0181, 0.6816, 0.5376, 0.2095, 0.0339 and
//!   A_a = 3.3634, 1.2107, 0.4128, 0.3027, 0.0762, 0.0339 for classes 1…6.
//!
//! Gauge spectra (and FRA cross-level) are not provided: their published forms
//! could not be confirmed from two sources; asking for them is an error.

use std::f64::consts::PI;

use crate::alignment::{GL8_W, GL8_X};
use crate::error::{TrackError, check_param, invalid};
use crate::irregularity::{Component, MeasuredIrregularity, RailDeviation, interpolate, interval};
use std::sync::OnceLock;

/// ORE B176 Ωc, rad/m.
pub const ERRI_OMEGA_C: f64 = 0.8246;
/// ORE B176 Ωr, rad/m.
pub const ERRI_OMEGA_R: f64 = 0.0206;
/// ORE B176 Ωs, rad/m.
pub const ERRI_OMEGA_S: f64 = 0.4380;
/// ORE B176 A_v (low, high), m·rad.
pub const ERRI_A_V: [f64; 2] = [5.9233e-7, 1.0800e-6];
/// ORE B176 A_a (low, high), m·rad.
pub const ERRI_A_A: [f64; 2] = [3.3651e-7, 6.1250e-7];
/// FRA k.
pub const FRA_K: f64 = 0.25;
/// FRA Ωc, rad/m.
pub const FRA_OMEGA_C: f64 = 0.8245;
/// FRA A_v for classes 1..6, cm²·rad/m.
pub const FRA_A_V: [f64; 6] = [1.2107, 1.0181, 0.6816, 0.5376, 0.2095, 0.0339];
/// FRA A_a for classes 1..6, cm²·rad/m.
pub const FRA_A_A: [f64; 6] = [3.3634, 1.2107, 0.4128, 0.3027, 0.0762, 0.0339];

/// A published irregularity spectrum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum PsdModel {
    /// ERRI (ORE B176) low level.
    ErriLow,
    /// ERRI (ORE B176) high level.
    ErriHigh,
    /// FRA track class 1..=6 (6 is the best).
    Fra(u8),
}

/// One-sided PSD S(Ω) of `component` at angular wavenumber `omega` (rad/m, > 0),
/// m²/(rad/m).
pub fn psd(model: PsdModel, component: Component, omega: f64) -> Result<f64, TrackError> {
    check_param("wavenumber Ω", omega, true)?;
    let o2 = omega * omega;
    match model {
        PsdModel::ErriLow | PsdModel::ErriHigh => {
            let lvl = usize::from(model == PsdModel::ErriHigh);
            let (c2, r2, s2) = (
                ERRI_OMEGA_C * ERRI_OMEGA_C,
                ERRI_OMEGA_R * ERRI_OMEGA_R,
                ERRI_OMEGA_S * ERRI_OMEGA_S,
            );
            let base = c2 / ((o2 + r2) * (o2 + c2));
            match component {
                Component::Vertical => Ok(ERRI_A_V[lvl] * base),
                Component::Lateral => Ok(ERRI_A_A[lvl] * base),
                Component::CrossLevel => Ok(4.0 * ERRI_A_V[lvl] * base * o2 / (o2 + s2)),
                Component::Gauge => Err(invalid(
                    "PSD component",
                    "the ERRI (ORE B176) gauge spectrum is not provided",
                )),
            }
        }
        PsdModel::Fra(class) => {
            if !(1..=6).contains(&class) {
                return Err(invalid("FRA track class", format!("{class} must be 1..=6")));
            }
            let i = usize::from(class - 1);
            let c2 = FRA_OMEGA_C * FRA_OMEGA_C;
            let base = FRA_K * c2 / (o2 * (o2 + c2)) * 1e-4; // cm² → m²
            match component {
                Component::Vertical => Ok(FRA_A_V[i] * base),
                Component::Lateral => Ok(FRA_A_A[i] * base),
                Component::Gauge | Component::CrossLevel => Err(invalid(
                    "PSD component",
                    "FRA gauge and cross-level spectra are not provided",
                )),
            }
        }
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014): a small, seedable, portable PRNG.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Seeds the generator.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// What to generate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StochasticSpec {
    /// The spectrum.
    pub model: PsdModel,
    /// The component it drives.
    pub component: Component,
    /// Shortest wavelength of the band, m.
    pub wavelength_min: f64,
    /// Longest wavelength of the band, m.
    pub wavelength_max: f64,
    /// Number of harmonics N. The realization repeats after 2π/ΔΩ =
    /// N·λmin·λmax/(λmax − λmin) m; choose N so that this exceeds the track.
    pub harmonics: usize,
    /// PRNG seed of the phases.
    pub seed: u64,
    /// Start of the extent, m.
    pub start: f64,
    /// End of the extent, m.
    pub end: f64,
    /// Length of the sin² fade-in after `start` and fade-out before `end`, m
    /// (0: switched on and off abruptly).
    pub fade: f64,
}

/// A generated realization Σ a_k cos(Ω_k s + φ_k).
///
/// The band [2π/λmax, 2π/λmin] is cut into N equal bins of width ΔΩ; Ω_k is the
/// bin centre and a_k = √(2 ∫_bin S dΩ) (8-point Gauss–Legendre per bin), so the
/// mean square Σ a_k²/2 equals the integral of the PSD over the band. Phases
/// φ_k are uniform in [0, 2π) from [`SplitMix64`].
#[derive(Debug, Clone, PartialEq)]
pub struct StochasticIrregularity {
    component: Component,
    omega: Vec<f64>,
    amplitude: Vec<f64>,
    phase: Vec<f64>,
    start: f64,
    end: f64,
    fade: f64,
}

impl StochasticIrregularity {
    /// Generates a realization.
    pub fn generate(spec: &StochasticSpec) -> Result<Self, TrackError> {
        check_param("shortest wavelength", spec.wavelength_min, true)?;
        check_param("longest wavelength", spec.wavelength_max, true)?;
        check_param("stochastic irregularity start", spec.start, false)?;
        check_param("stochastic irregularity end", spec.end, false)?;
        check_param("stochastic irregularity fade", spec.fade, false)?;
        if spec.wavelength_max <= spec.wavelength_min {
            return Err(invalid(
                "wavelength band",
                format!(
                    "longest {} m must exceed shortest {} m",
                    spec.wavelength_max, spec.wavelength_min
                ),
            ));
        }
        if spec.harmonics == 0 || spec.harmonics > 1_000_000 {
            return Err(invalid(
                "number of harmonics",
                format!("{} must be in 1..=1000000", spec.harmonics),
            ));
        }
        if spec.end <= spec.start {
            return Err(invalid(
                "stochastic irregularity extent",
                format!("end {} m must be after start {} m", spec.end, spec.start),
            ));
        }
        if spec.fade < 0.0 || 2.0 * spec.fade > spec.end - spec.start {
            return Err(invalid(
                "stochastic irregularity fade",
                format!("{} m must be in [0, (end − start)/2]", spec.fade),
            ));
        }
        // Fails early on an unsupported component.
        psd(spec.model, spec.component, 1.0)?;
        let o1 = 2.0 * PI / spec.wavelength_max;
        let o2 = 2.0 * PI / spec.wavelength_min;
        let n = spec.harmonics;
        let d = (o2 - o1) / n as f64;
        let mut rng = SplitMix64::new(spec.seed);
        let mut omega = Vec::with_capacity(n);
        let mut amplitude = Vec::with_capacity(n);
        let mut phase = Vec::with_capacity(n);
        for k in 0..n {
            let c = o1 + (k as f64 + 0.5) * d;
            let mut integral = 0.0;
            for j in 0..4 {
                for sgn in [-1.0, 1.0] {
                    integral +=
                        GL8_W[j] * psd(spec.model, spec.component, c + sgn * GL8_X[j] * 0.5 * d)?;
                }
            }
            integral *= 0.5 * d;
            omega.push(c);
            amplitude.push((2.0 * integral).sqrt());
            phase.push(2.0 * PI * rng.next_f64());
        }
        Ok(StochasticIrregularity {
            component: spec.component,
            omega,
            amplitude,
            phase,
            start: spec.start,
            end: spec.end,
            fade: spec.fade,
        })
    }

    /// The driven component.
    pub fn component(&self) -> Component {
        self.component
    }

    /// Wavenumbers Ω_k (rad/m), amplitudes a_k (m) and phases φ_k (rad).
    pub fn harmonics(&self) -> (&[f64], &[f64], &[f64]) {
        (&self.omega, &self.amplitude, &self.phase)
    }

    /// Mean square Σ a_k²/2 of the unfaded signal, m².
    pub fn variance(&self) -> f64 {
        self.amplitude.iter().map(|a| 0.5 * a * a).sum()
    }

    /// The unfaded signal and its s-derivative at `s` (ignores the extent).
    pub fn signal(&self, s: f64) -> (f64, f64) {
        let (mut v, mut dv) = (0.0, 0.0);
        for k in 0..self.omega.len() {
            let (sn, cs) = (self.omega[k] * s + self.phase[k]).sin_cos();
            v += self.amplitude[k] * cs;
            dv -= self.amplitude[k] * self.omega[k] * sn;
        }
        (v, dv)
    }

    /// Window (fade) and its derivative.
    fn window(&self, s: f64) -> (f64, f64) {
        if s < self.start || s > self.end {
            return (0.0, 0.0);
        }
        if self.fade > 0.0 {
            let h = 0.5 * PI / self.fade;
            let (u, sign) = if s - self.start < self.fade {
                (s - self.start, 1.0)
            } else if self.end - s < self.fade {
                (self.end - s, -1.0)
            } else {
                return (1.0, 0.0);
            };
            let (sn, cs) = (h * u).sin_cos();
            return (sn * sn, sign * 2.0 * sn * cs * h);
        }
        (1.0, 0.0)
    }

    pub(crate) fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        let (w, dw) = self.window(s);
        if w == 0.0 && dw == 0.0 {
            return Default::default();
        }
        let (v, dv) = self.signal(s);
        (
            RailDeviation::from_component(self.component, w * v),
            RailDeviation::from_component(self.component, dw * v + w * dv),
        )
    }

    /// Samples the realization (with its fade) every `ds` m over its extent into
    /// a table, for fast evaluation by linear interpolation. The interpolation
    /// error at wavelength λ is at most (π ds/λ)²/2 of that harmonic's amplitude
    /// (1.2 % at ds = λ/20).
    pub fn sampled(&self, ds: f64) -> Result<MeasuredIrregularity, TrackError> {
        self.sampled_in(ds, true)
    }

    /// [`Self::sampled`], summing samples in blocks (`blocks`) or one at a
    /// time: the same table bit for bit (tested).
    fn sampled_in(&self, ds: f64, blocks: bool) -> Result<MeasuredIrregularity, TrackError> {
        let s = self.sample_positions(ds)?;
        let v = self.sample_values(ds, 0, s.len() - 1, blocks);
        MeasuredIrregularity::from_samples(s, v)
    }

    /// The table of [`Self::sampled`], its values computed a chunk of
    /// [`CHUNK`] samples at a time when a run first needs them: a short run
    /// on a long track samples only the stretch it covers. Interpolates to
    /// the same numbers bit for bit (tested).
    ///
    /// # Errors
    /// As [`Self::sampled`]: a bad step, too many samples, or fewer than two.
    pub fn sampled_lazily(&self, ds: f64) -> Result<SampledIrregularity, TrackError> {
        let s = self.sample_positions(ds)?;
        let chunks = (s.len() - 2) / CHUNK + 1;
        Ok(SampledIrregularity {
            source: self.clone(),
            ds,
            s,
            chunks: (0..chunks).map(|_| OnceLock::new()).collect(),
        })
    }

    /// The sample positions of the table every `ds` m: start + i ds up to
    /// the extent's end (the last one clamped to it), at least two.
    fn sample_positions(&self, ds: f64) -> Result<Vec<f64>, TrackError> {
        check_param("sampling step", ds, true)?;
        let n = ((self.end - self.start) / ds).ceil() as usize;
        if n > 50_000_000 {
            return Err(invalid(
                "sampling step",
                format!("{ds} m gives too many samples"),
            ));
        }
        let mut s: Vec<f64> = Vec::with_capacity(n + 1);
        for i in 0..=n {
            let x = self.sample_position(ds, i);
            if let Some(&last) = s.last()
                && x <= last
            {
                break;
            }
            s.push(x);
        }
        if s.len() < 2 {
            return Err(invalid(
                "measured irregularity",
                "needs at least two samples",
            ));
        }
        Ok(s)
    }

    /// Position of sample `i` of the table every `ds` m, m.
    fn sample_position(&self, ds: f64, i: usize) -> f64 {
        (self.start + i as f64 * ds).min(self.end)
    }

    /// The faded values of samples `from..=to` (`from` a multiple of
    /// [`RESEED`], `to` a sample of [`Self::sample_positions`]): each the
    /// same bit for bit whatever the range it is computed in.
    fn sample_values(&self, ds: f64, from: usize, to: usize, blocks: bool) -> Vec<RailDeviation> {
        debug_assert!(from.is_multiple_of(RESEED));
        let mut v = Vec::with_capacity(to + 1 - from);
        let m = self.omega.len();
        let mut zr = vec![0.0; m];
        let mut zi = vec![0.0; m];
        let mut wr = vec![0.0; m];
        let mut wi = vec![0.0; m];
        for k in 0..m {
            let (sn, cs) = (self.omega[k] * ds).sin_cos();
            wr[k] = cs;
            wi[k] = sn;
        }
        let at = |i: usize| self.sample_position(ds, i);
        let seed = |x: f64, zr: &mut [f64], zi: &mut [f64]| {
            for k in 0..m {
                let (sn, cs) = (self.omega[k] * x + self.phase[k]).sin_cos();
                zr[k] = cs;
                zi[k] = sn;
            }
        };
        let push = |v: &mut Vec<RailDeviation>, x: f64, signal: f64| {
            let (w, _) = self.window(x);
            v.push(RailDeviation::from_component(self.component, w * signal));
        };
        let mut i = from;
        // Whole blocks, none reaching the end of the extent (where a
        // sample is clamped and seeded exactly).
        while blocks && m > 0 && i + BLOCK - 1 <= to && at(i + BLOCK - 1) < self.end {
            if i.is_multiple_of(RESEED) {
                seed(at(i), &mut zr, &mut zi);
            }
            let mut sums = [0.0; BLOCK];
            for k in 0..m {
                let (mut r, mut im) = (zr[k], zi[k]);
                for (j, sum) in sums.iter_mut().enumerate() {
                    let term = self.amplitude[k] * r;
                    *sum = if k == 0 { term } else { *sum + term };
                    if j + 1 < BLOCK {
                        let next = r * wr[k] - im * wi[k];
                        im = r * wi[k] + im * wr[k];
                        r = next;
                    }
                }
                // Advance to the next block's first sample.
                zr[k] = r * wr[k] - im * wi[k];
                zi[k] = r * wi[k] + im * wr[k];
            }
            for (j, &sum) in sums.iter().enumerate() {
                push(&mut v, at(i + j), sum);
            }
            i += BLOCK;
        }
        // The rest one at a time.
        for i in i..=to {
            let x = at(i);
            if i.is_multiple_of(RESEED) || x == self.end {
                seed(x, &mut zr, &mut zi);
            }
            let mut signal = 0.0;
            for (k, (a, z)) in self.amplitude.iter().zip(&zr).enumerate() {
                let term = a * z;
                signal = if k == 0 { term } else { signal + term };
            }
            push(&mut v, x, signal);
            for k in 0..m {
                let r = zr[k] * wr[k] - zi[k] * wi[k];
                zi[k] = zr[k] * wi[k] + zi[k] * wr[k];
                zr[k] = r;
            }
        }
        v
    }
}

/// Samples between exact phasor seeds of a sampled table: the phasors
/// z_k = exp(i(Ω_k x + φ_k)) are advanced by w_k = exp(iΩ_k ds) per sample
/// (a complex product instead of a sin_cos) and recomputed exactly every
/// RESEED samples, so the rounding drift stays below ~1e-13 relative.
const RESEED: usize = 256;

/// Samples summed together: each sample's sum Σ a_k Re z_k runs over k in
/// order (the same rounding as one at a time), and BLOCK of them are
/// independent chains of additions that the processor overlaps.
const BLOCK: usize = 8;

/// Samples per chunk of a [`SampledIrregularity`] (204.8 m at 0.05 m).
pub const CHUNK: usize = 4096;

const _: () = assert!(RESEED.is_multiple_of(BLOCK), "a block never spans a reseed");
const _: () = assert!(CHUNK.is_multiple_of(RESEED), "a chunk starts at a seed");

/// A stochastic irregularity tabulated every `ds` m
/// ([`StochasticIrregularity::sampled_lazily`]): the table's positions at
/// once, its values by chunks of [`CHUNK`] samples on first use (shared by
/// threads: each chunk is computed once). Evaluates as the
/// [`MeasuredIrregularity`] of [`StochasticIrregularity::sampled`], bit for
/// bit.
#[derive(Clone)]
pub struct SampledIrregularity {
    source: StochasticIrregularity,
    ds: f64,
    /// Every sample position, m, strictly increasing.
    s: Vec<f64>,
    /// Chunk c holds the values of samples c·CHUNK ..= (c+1)·CHUNK (the
    /// last one shared with the next chunk), or up to the last sample.
    chunks: Vec<OnceLock<Vec<RailDeviation>>>,
}

impl std::fmt::Debug for SampledIrregularity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SampledIrregularity")
            .field("source", &self.source)
            .field("ds", &self.ds)
            .field("samples", &self.s.len())
            .field(
                "chunks_computed",
                &self.chunks.iter().filter(|c| c.get().is_some()).count(),
            )
            .finish()
    }
}

/// Equal when sampled from the same realization at the same step (which
/// chunks were computed does not matter).
impl PartialEq for SampledIrregularity {
    fn eq(&self, other: &Self) -> bool {
        self.source == other.source && self.ds == other.ds
    }
}

impl SampledIrregularity {
    /// First and last sampled position, m.
    pub fn range(&self) -> (f64, f64) {
        (self.s[0], self.s[self.s.len() - 1])
    }

    /// Deviation and its s-derivative (m/m) at `s`, linearly interpolated
    /// (as [`MeasuredIrregularity`]); zero outside the sampled range.
    pub(crate) fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        let n = self.s.len();
        if s < self.s[0] || s > self.s[n - 1] {
            return Default::default();
        }
        let i = interval(&self.s, s);
        let c = i / CHUNK;
        let values = self.chunks[c].get_or_init(|| {
            let to = ((c + 1) * CHUNK).min(n - 1);
            self.source.sample_values(self.ds, c * CHUNK, to, true)
        });
        let j = i - c * CHUNK;
        interpolate(s, (self.s[i], self.s[i + 1]), (&values[j], &values[j + 1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irregularity::Irregularity;

    /// The blocked sum gives the table of the one-at-a-time sum bit for bit:
    /// an extent whose sample count is no multiple of the block, with a
    /// clamped last sample, across several reseeds, faded at both ends.
    #[test]
    fn blocked_sampling_is_bit_identical_to_one_at_a_time() {
        for (harmonics, end) in [(37, 263.7), (1, 70.0), (600, 130.05), (20, 1000.0)] {
            let spec = StochasticSpec {
                model: PsdModel::Fra(4),
                component: Component::Vertical,
                wavelength_min: 2.0,
                wavelength_max: 100.0,
                harmonics,
                seed: 7,
                start: 30.0,
                end,
                fade: 20.0,
            };
            let g = StochasticIrregularity::generate(&spec).unwrap();
            for ds in [0.05, 0.3] {
                let blocked = g.sampled_in(ds, true).unwrap();
                let single = g.sampled_in(ds, false).unwrap();
                assert!(
                    blocked == single,
                    "{harmonics} harmonics to {end} m, ds = {ds}"
                );
                // The lazy table, its chunks computed in a scattered order,
                // interpolates as the whole table, bit for bit, inside and
                // at the ends of the extent and outside it.
                let lazy = Irregularity::Sampled(g.sampled_lazily(ds).unwrap());
                let table = Irregularity::Measured(single);
                let points = (0..3000)
                    .map(|k| 25.0 + ((k * 7919) % 3000) as f64 / 3000.0 * (end - 20.0))
                    .chain([30.0, end, 30.0 + ds, end - 1e-9, 30.0 + 4096.0 * ds]);
                for x in points {
                    assert!(table.eval(x) == lazy.eval(x), "at {x} m");
                }
            }
        }
    }
}
