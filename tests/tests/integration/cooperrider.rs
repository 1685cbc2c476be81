//! Cooperrider's two-axle bogie (`models/vehicles/cooperrider_bogie.ron`:
//! N. K. Cooperrider, "The hunting behavior of conventional railway trucks",
//! ASME J. Eng. Industry 94 (1972) 752–762, with the parameters of the DTU
//! implementation DYTSI, on 1:20 conical wheels) through `umsim modes`' path
//! ([`scenario_modes`]) against the classical linear bogie model: two
//! wheelsets in lateral and yaw with Wickens' creep, spin and gravitational
//! terms ([`super::wickens`]), a frame in lateral, yaw and roll, linear
//! springs and dampers: the degrees of freedom of Cooperrider's "more
//! complex" model (7), written here from the elements of the model file.
//!
//! The linear model's contact parameters are computed here from the
//! profiles, independently of the simulator (as in [`super::wickens`]): the
//! rigid contact geometry, Hertz at the static wheel load, Kalker's table.
//!
//! What this is not: the reproduction of a published critical speed. The
//! parameter table of Cooperrider 1972 (or of Kaas-Petersen, "Chaos in a
//! railway bogie", Acta Mechanica 61 (1986) 89–107, which corrects its
//! misprints) could not be retrieved here; the one published number found,
//! a Hopf bifurcation of the Kaas-Petersen equations at v ≈ 68.66 (R. Seydel's
//! example collection, bifurcation.de/exd10, after B. Hassard's worksheet,
//! which itself lists inconsistencies in the parameter values), goes with a
//! constant creep coefficient G·π·a·b = 6.563 MN for both directions, no spin
//! and parameters not all known here, so it is not asserted.

use nalgebra::DMatrix;
use railmbs_models::{InitialStateKind, Model, Scenario};
use railmbs_runtime::NumericEquations;
use railmbs_runtime::analysis::modes::{Mode, zero_crossing};
use railmbs_runtime::analysis::speed::{at_speed, scenario_modes};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_testkit::*;

use super::wickens::{
    WheelsetContact, contact_geometry_of, frequency_and_damping, param, wheelset_contact_on,
};

const GRAVITY: f64 = 9.81;

/// The bundled scenario and its model (Kalker's linear creep law, steady
/// state solved at every speed).
fn bogie() -> (Scenario, Model) {
    let mut s =
        railmbs_models::load_scenario(&model_path("scenarios/cooperrider_bogie.ron")).unwrap();
    s.initial_kind = InitialStateKind::Equilibrium;
    let model = railmbs_models::load_model(&s.model).unwrap();
    (s, model)
}

/// The bogie's parameters as the model file has them (SI units; the names
/// of `cooperrider_bogie.ron`).
struct Bogie {
    mw: f64,
    iwx: f64,
    iwy: f64,
    iwz: f64,
    mf: f64,
    ifx: f64,
    ifz: f64,
    b: f64,
    d1: f64,
    d2: f64,
    h1: f64,
    h2: f64,
    k1: f64,
    k2: f64,
    k3: f64,
    k4: f64,
    k5: f64,
    c1: f64,
    c2: f64,
    /// Primary vertical preload per axlebox (frame and half the car body), N.
    fp: f64,
    /// Secondary vertical preload per side (half the car body's half), N.
    fs: f64,
}

impl Bogie {
    fn of(model: &Model, s: &Scenario) -> Bogie {
        let p = |n: &str| param(model, s, n);
        Bogie {
            mw: p("mw"),
            iwx: p("Iwx"),
            iwy: p("Iwy"),
            iwz: p("Iwz"),
            mf: p("mf"),
            ifx: p("Ifx"),
            ifz: p("Ifz"),
            b: p("b"),
            d1: p("d1"),
            d2: p("d2"),
            h1: p("h1"),
            h2: p("h2"),
            k1: p("k1"),
            k2: p("k2"),
            k3: p("k3"),
            k4: p("k4"),
            k5: p("k5"),
            c1: p("D1"),
            c2: p("D2"),
            fp: (p("mc") / 2.0 + p("mf")) * GRAVITY / 4.0,
            fs: p("mc") * GRAVITY / 4.0,
        }
    }

    /// Static vertical load of one wheel, N.
    fn wheel_load(&self) -> f64 {
        (2.0 * self.fp + self.mw * GRAVITY) / 2.0
    }
}

/// Coordinates of the linear model: lateral y and yaw ψ of the leading and
/// trailing wheelsets, lateral, yaw and roll of the frame.
const Y1: usize = 0;
const P1: usize = 1;
const Y2: usize = 2;
const P2: usize = 3;
const YF: usize = 4;
const PF: usize = 5;
const RF: usize = 6;
const N: usize = 7;

/// The state matrix of the linear bogie at speed `v` (m/s), state (q, q̇)
/// with q = (y1, ψ1, y2, ψ2, yf, ψf, φf): M q̈ + C q̇ + K q = 0.
///
/// - Wheelsets: Wickens' creep, spin and gravitational terms per wheelset
///   ([`super::wickens`]' rows, the spin terms with the contact angle taken
///   relative to the wheelset); the roll that follows the shift (θ = σ y,
///   σ from the rigid contact) adds r0 σ ẏ to the lateral creepage, σ² Iwx
///   to the lateral inertia, the gyroscopic yaw moment Iwy (V/r0) σ ẏ, and
///   turns the primary vertical springs (per side k3 at ±d1) into a
///   coupling of the wheelset's shift to the frame's roll.
/// - Primary suspension per side: lateral k1 between the axle centre and
///   the frame at the axle's height (h1 below the frame's centre: the
///   frame's roll moves that point by +h1 φf), longitudinal k2 at ±d1
///   (yaw stiffness 2 k2 d1²), vertical k3 at ±d1.
/// - Secondary suspension per side to the fixed car body: lateral k4, D2 at
///   h2 above the frame's centre (moved by −h2 φf), vertical k5, D1 at ±d2.
/// - Preloads, as the `Linear6` elements define them: the primary ones act
///   along the frame's vertical axis, so the frame's roll tilts them (a
///   lateral force Fp φf on each axlebox, its reaction on the frame); the
///   secondary ones act vertically at h2 above the frame's centre (a roll
///   moment 2 Fs h2 φf).
fn bogie_matrix(v: f64, w: &WheelsetContact, p: &Bogie) -> DMatrix<f64> {
    let (f11, f22, f23, f33) = w.coefficients();
    let (e, r0, lam, sigma) = (w.e, w.r0, w.conicity, w.d_roll);
    let q = p.wheel_load();
    let kg = q * w.d_tan_delta;
    // Spin follows the contact angle relative to the wheelset (the angle
    // between the axle and the contact normal), δ − θ: on a cone it does
    // not change (d(δL − δR)/dy = 2σ), so neither do the spin forces.
    let d_delta = w.d_delta - 2.0 * sigma;
    let ks = f23 * w.delta0.cos() * d_delta / r0;
    let kms = f33 * w.delta0.cos() * d_delta / r0;
    // Gyroscopic: the spin's angular momentum Iwy Ω along the axle, turned
    // by the roll rate σ ẏ, needs the yaw moment Iwy Ω σ ẏ.
    let gyro = p.iwy * v / r0 * sigma;
    let mut m = DMatrix::<f64>::zeros(N, N);
    let mut k = DMatrix::<f64>::zeros(N, N);
    let mut c = DMatrix::<f64>::zeros(N, N);
    // A spring (damper) of rate `rate` on the deflection g·q adds
    // rate g gᵀ to K (C).
    let add = |mat: &mut DMatrix<f64>, rate: f64, g: &[(usize, f64)]| {
        for &(i, gi) in g {
            for &(j, gj) in g {
                mat[(i, j)] += rate * gi * gj;
            }
        }
    };
    for (y, psi, x) in [(Y1, P1, p.b), (Y2, P2, -p.b)] {
        m[(y, y)] = p.mw + p.iwx * sigma * sigma;
        m[(psi, psi)] = p.iwz;
        // Creep (Wickens), with the roll's r0 σ ẏ in the lateral creepage.
        let lat = 1.0 + r0 * sigma;
        k[(y, y)] += kg - ks;
        k[(y, psi)] += -2.0 * f22;
        k[(psi, y)] += 2.0 * f11 * e * lam / r0 - kms;
        k[(psi, psi)] += 2.0 * f23;
        c[(y, y)] += 2.0 * f22 * lat / v;
        c[(y, psi)] += 2.0 * f23 / v;
        c[(psi, y)] += -2.0 * f23 * lat / v + gyro;
        c[(psi, psi)] += 2.0 * f11 * e * e / v + 2.0 * f33 / v;
        // Primary lateral, both sides: y − yf − x ψf − h1 φf.
        add(
            &mut k,
            2.0 * p.k1,
            &[(y, 1.0), (YF, -1.0), (PF, -x), (RF, -p.h1)],
        );
        // Primary longitudinal: ±d1 (ψ − ψf).
        add(&mut k, 2.0 * p.k2 * p.d1 * p.d1, &[(psi, 1.0), (PF, -1.0)]);
        // Primary vertical: ±d1 (φf − σ y).
        add(&mut k, 2.0 * p.k3 * p.d1 * p.d1, &[(RF, 1.0), (y, -sigma)]);
        // The primary preloads tilted by the frame's roll: +Fp φf on the
        // wheelset per axlebox, the reaction on the frame.
        k[(y, RF)] += -2.0 * p.fp;
        k[(YF, RF)] += 2.0 * p.fp;
    }
    m[(YF, YF)] = p.mf;
    m[(PF, PF)] = p.ifz;
    m[(RF, RF)] = p.ifx;
    // Secondary lateral, both sides: yf − h2 φf.
    add(&mut k, 2.0 * p.k4, &[(YF, 1.0), (RF, -p.h2)]);
    add(&mut c, 2.0 * p.c2, &[(YF, 1.0), (RF, -p.h2)]);
    // Secondary vertical: ±d2 φf; the car body's load above the frame.
    add(&mut k, 2.0 * p.k5 * p.d2 * p.d2, &[(RF, 1.0)]);
    add(&mut c, 2.0 * p.c1 * p.d2 * p.d2, &[(RF, 1.0)]);
    k[(RF, RF)] -= 2.0 * p.fs * p.h2;
    let mi = m.try_inverse().unwrap();
    let mut a = DMatrix::<f64>::zeros(2 * N, 2 * N);
    a.view_mut((0, N), (N, N))
        .copy_from(&DMatrix::identity(N, N));
    a.view_mut((N, 0), (N, N)).copy_from(&(-&mi * k));
    a.view_mut((N, N), (N, N)).copy_from(&(-&mi * c));
    a
}

/// The least damped oscillating eigenvalue (σ, ω > 0) of `a`.
fn least_damped(a: &DMatrix<f64>) -> (f64, f64) {
    a.clone()
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im > 1e-9)
        .map(|l| (l.re, l.im))
        .min_by(|x, y| (-x.0 / x.0.hypot(x.1)).total_cmp(&(-y.0 / y.0.hypot(y.1))))
        .unwrap()
}

/// The full model's least damped lateral mode at speed `v` (m/s).
fn full_hunting(s: &Scenario, model: &Model, v: f64) -> Mode {
    let s = at_speed(s, model, v);
    let one = scenario_modes(
        &s,
        model,
        Box::new(NumericEquations::new(model)),
        &ContactTableCache::new(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    one.modes.least_damped_lateral().unwrap().clone()
}

/// Cooperrider's bogie hunts as the linear bogie model
/// ([`bogie_matrix`]): the least damped lateral mode's frequency and
/// damping ratio from 30 to 80 m/s (the frame's yaw mode at 30 m/s, the
/// bogie's hunting mode above), and the linear critical speed where its
/// damping ratio crosses zero (both interpolated on the same 10 m/s grid).
///
/// What the 7-DOF model leaves out and the full model (every body 6-DOF,
/// elastic Hertz contact, the contact table) has: the wheel loads' transfer
/// as the contact points move across the cones (1 mm per mm of shift) and
/// by the gyroscopic roll moment, with it the change of the spin creep's
/// lateral forces (±0.64 kN per wheel at rest); the creep forces' tilt with
/// the contact plane and the roll rate's share e δ σ ẏ of the lateral
/// creepage (0.3 %); the contact table's interpolation (0.1 mm × 2 mrad;
/// 0.6 % on the kinematic ratio for the S1002 wheelset,
/// [`super::wickens`]); the vertical, pitch and longitudinal motions
/// (uncoupled to first order on straight track). Found: frequencies within
/// 0.3 %, damping ratios within 0.006, the critical speed 1.9 % above the
/// linear model's (52.4 against 51.4 m/s); not attributed term by term.
/// Tolerances: frequency 1 %, damping ratio 0.008, critical speed 3 %.
/// Without the gyroscopic term the linear model's critical speed drops by
/// 0.7 m/s, without the roll that follows the shift by another 0.35 m/s:
/// the comparison resolves terms of that size.
#[test]
fn cooperriders_bogie_hunts_as_the_linear_bogie_model() {
    let (s, model) = bogie();
    let p = Bogie::of(&model, &s);
    let geo = contact_geometry_of("cone_1in20.dat", param(&model, &s, "r0"));
    let w = wheelset_contact_on(&geo, p.wheel_load(), 1e-4);
    println!("{w:?}");
    let speeds = [30.0, 40.0, 50.0, 60.0, 70.0, 80.0];
    let (mut full_zeta, mut linear_zeta) = (vec![], vec![]);
    for v in speeds {
        let full = full_hunting(&s, &model, v);
        let (f, zeta) = frequency_and_damping(least_damped(&bogie_matrix(v, &w, &p)));
        println!(
            "V = {v} m/s: full {:.4} Hz, ζ = {:.4} ({}); linear {f:.4} Hz, ζ = {zeta:.4}",
            full.frequency, full.damping_ratio, full.name
        );
        assert!(
            (full.frequency - f).abs() < 0.01 * f,
            "at {v} m/s: {} Hz, linear model {f} Hz",
            full.frequency
        );
        assert!(
            (full.damping_ratio - zeta).abs() < 0.008,
            "at {v} m/s: ζ = {}, linear model {zeta}",
            full.damping_ratio
        );
        full_zeta.push((v, full.damping_ratio));
        linear_zeta.push((v, zeta));
    }
    let (full_vc, linear_vc) = (
        zero_crossing(&full_zeta).unwrap(),
        zero_crossing(&linear_zeta).unwrap(),
    );
    println!("linear critical speed: full {full_vc:.2} m/s, linear model {linear_vc:.2} m/s");
    assert!(
        (full_vc - linear_vc).abs() < 0.03 * linear_vc,
        "critical speed {full_vc} m/s, linear model {linear_vc} m/s"
    );
}
