//! Modes of a linearized system ([`super::linear`]): eigenvalues λ of A by
//! faer's general (real, non-symmetric) eigendecomposition, with frequency,
//! damping ratio and the mode shape in the system coordinates, named by
//! the coordinates that dominate it; root loci over the running speed and
//! the linear critical speed.
//!
//! For λ = σ + iω: damped frequency f = ω/2π, natural frequency
//! fₙ = |λ|/2π, damping ratio ζ = −σ/|λ| (negative: unstable). Of each
//! complex-conjugate pair the one with ω > 0 is kept. Eigenvalues with
//! |λ| below [`ZERO_EIGENVALUE`] (the wheels' spin angles and other
//! coordinates nothing depends on: pure integrators) are reported apart.

use super::linear::Linearization;
use super::{CoordinateInfo, CoordinateKind};

use crate::system::SimError;
use railmbs_models::Axis;

/// |λ| below which an eigenvalue counts as zero, 1/s: a coordinate nothing
/// depends on (a spin angle) gives λ = 0 up to the rounding of the
/// difference Jacobian, ~1e-9 1/s for Vehicle 1; the slowest physical
/// motion of a vehicle (the speed hold's creep of a coasting car, 0.01 1/s)
/// is far above.
pub const ZERO_EIGENVALUE: f64 = 1e-6;

/// One mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Real part σ of λ, 1/s.
    pub re: f64,
    /// Imaginary part ω ≥ 0 of λ, rad/s.
    pub im: f64,
    /// Damped frequency ω/2π, Hz.
    pub frequency: f64,
    /// Natural frequency |λ|/2π, Hz.
    pub natural_frequency: f64,
    /// Damping ratio −σ/|λ| (1 for a real negative λ, −1 for a real
    /// positive one).
    pub damping_ratio: f64,
    /// The dominant coordinates: `Bogie1.WS1.ws yaw/lateral`, bodies in
    /// order of amplitude.
    pub name: String,
    /// Complex amplitude (re, im) of every system coordinate (m, rad, or
    /// the element state's unit), scaled so that the dominant one (by
    /// kinetic energy, Mᵢᵢ |δqᵢ|²) is 1 + 0i.
    pub shape: Vec<(f64, f64)>,
    /// Share of the mode's kinetic energy (Σ Mᵢᵢ |δqᵢ|²) in lateral and yaw
    /// coordinates, 0 to 1: hunting and the lateral modes have most.
    pub lateral_share: f64,
}

impl Mode {
    /// Whether it oscillates (ω > 0) mainly laterally and in yaw (at least
    /// half of its kinetic energy): the candidates of hunting.
    pub fn is_lateral(&self) -> bool {
        self.im > 0.0 && self.lateral_share >= 0.5
    }
}

/// The modes of a linearization.
#[derive(Debug, Clone, PartialEq)]
pub struct Modes {
    /// Non-zero eigenvalues, sorted by natural frequency.
    pub modes: Vec<Mode>,
    /// Zero eigenvalues, named by their dominant coordinates.
    pub zero_modes: Vec<String>,
}

impl Modes {
    /// The least damped lateral (hunting candidate) mode.
    pub fn least_damped_lateral(&self) -> Option<&Mode> {
        self.modes
            .iter()
            .filter(|m| m.is_lateral())
            .min_by(|a, b| a.damping_ratio.total_cmp(&b.damping_ratio))
    }
}

/// Eigenvalues and mode shapes of `lin` (coordinates `names` in system
/// order).
///
/// # Errors
/// The eigensolver's failure to converge.
pub fn modes(lin: &Linearization, names: &[CoordinateInfo]) -> Result<Modes, SimError> {
    let m = lin.a.nrows();
    let a = faer::Mat::<f64>::from_fn(m, m, |i, j| lin.a[(i, j)]);
    let evd = a
        .eigen()
        .map_err(|e| SimError::Other(format!("eigendecomposition: {e:?}")))?;
    let (s, u) = (evd.S().column_vector(), evd.U());
    let mut modes = Vec::new();
    let mut zero_modes = Vec::new();
    // Coordinates weigh by √Mᵢᵢ: a mode is named by where its kinetic
    // energy is (element states, without inertia, weigh 1 when nothing
    // else moves).
    let inertial = lin.mass_diagonal.iter().any(|&m| m > 0.0);
    let weight = |i: usize| {
        let m = lin.mass_diagonal[i];
        if inertial { m.max(0.0).sqrt() } else { 1.0 }
    };
    for k in 0..m {
        let lambda = s[k];
        let (re, im) = (lambda.re, lambda.im);
        let norm = re.hypot(im);
        if im < 0.0 {
            continue;
        }
        let re_x: Vec<f64> = (0..m).map(|i| u[(i, k)].re).collect();
        let im_x: Vec<f64> = (0..m).map(|i| u[(i, k)].im).collect();
        let mut shape = lin.coordinate_amplitudes(&re_x, &im_x);
        // Scale: the dominant coordinate (by energy) 1 + 0i.
        let (dominant, _) = shape.iter().enumerate().fold((0, 0.0), |best, (i, c)| {
            let mag = c.0.hypot(c.1) * weight(i);
            if mag > best.1 { (i, mag) } else { best }
        });
        let (dr, di) = shape[dominant];
        let d2 = dr * dr + di * di;
        if d2 > 0.0 {
            for c in &mut shape {
                // c / d
                *c = ((c.0 * dr + c.1 * di) / d2, (c.1 * dr - c.0 * di) / d2);
            }
        }
        let name = mode_name(&shape, names, &weight);
        if norm < ZERO_EIGENVALUE {
            zero_modes.push(name);
            continue;
        }
        let total: f64 = shape
            .iter()
            .enumerate()
            .map(|(i, c)| (c.0 * c.0 + c.1 * c.1) * weight(i).powi(2))
            .sum();
        let lateral: f64 = shape
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                matches!(
                    names[*i].kind,
                    CoordinateKind::Translation(Axis::Y) | CoordinateKind::Rotation(Axis::Z)
                )
            })
            .map(|(i, c)| (c.0 * c.0 + c.1 * c.1) * weight(i).powi(2))
            .sum();
        modes.push(Mode {
            re,
            im,
            frequency: im / (2.0 * std::f64::consts::PI),
            natural_frequency: norm / (2.0 * std::f64::consts::PI),
            damping_ratio: -re / norm,
            name,
            shape,
            lateral_share: if total > 0.0 { lateral / total } else { 0.0 },
        });
    }
    modes.sort_by(|a, b| a.natural_frequency.total_cmp(&b.natural_frequency));
    Ok(Modes { modes, zero_modes })
}

/// `Body motion/motion, Body motion`: the coordinates with at least half
/// the largest weighed amplitude (√(Mᵢᵢ) |δqᵢ|), grouped by body in order
/// of amplitude (at most three bodies).
fn mode_name(
    shape: &[(f64, f64)],
    names: &[CoordinateInfo],
    weight: &dyn Fn(usize) -> f64,
) -> String {
    let mags: Vec<f64> = shape
        .iter()
        .enumerate()
        .map(|(i, c)| c.0.hypot(c.1) * weight(i))
        .collect();
    let top = mags.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut order: Vec<usize> = (0..shape.len()).filter(|&i| mags[i] >= 0.5 * top).collect();
    order.sort_by(|&a, &b| mags[b].total_cmp(&mags[a]));
    let mut groups: Vec<(String, Vec<&'static str>)> = Vec::new();
    for i in order {
        let owner = &names[i].owner;
        let motion = names[i].kind.motion();
        match groups.iter_mut().find(|(o, _)| o == owner) {
            Some((_, motions)) => {
                if !motions.contains(&motion) {
                    motions.push(motion);
                }
            }
            None => groups.push((owner.clone(), vec![motion])),
        }
    }
    let more = groups.len() > 3;
    let mut text = groups
        .iter()
        .take(3)
        .map(|(o, m)| format!("{o} {}", m.join("/")))
        .collect::<Vec<_>>()
        .join(", ");
    if more {
        text.push_str(", …");
    }
    text
}

/// The speed at which `damping(v)` (samples sorted by speed) first crosses
/// zero from positive to negative, interpolated linearly between the two
/// samples around it; `None` if it never does.
pub fn zero_crossing(samples: &[(f64, f64)]) -> Option<f64> {
    samples.windows(2).find_map(|w| {
        let ((v0, z0), (v1, z1)) = (w[0], w[1]);
        (z0 > 0.0 && z1 <= 0.0).then(|| v0 + (v1 - v0) * z0 / (z0 - z1))
    })
}
