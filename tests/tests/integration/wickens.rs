//! The hunting mode of the full model against the classical analytic linear
//! models of a single wheelset: Wickens' wheelset on lateral and yaw springs
//! (Wickens 1965; as Knothe & Stichel, "Rail Vehicle Dynamics", Springer
//! 2017, and Garg & Dukkipati, "Dynamics of Railway Vehicle Systems",
//! Academic Press 1984, write it in their chapters on the wheelset's
//! lateral dynamics) and the free wheelset's
//! kinematic oscillation (Klingel 1883), both through `umsim modes`' path
//! ([`scenario_modes`]).
//!
//! The analytic models' parameters are computed here, independently of the
//! simulator, from the same profiles and dimensions: the rigid contact
//! geometry by `railmbs_wheelrail::geometry` (rolling radius difference,
//! contact angles, contact positions), the contact ellipse by Hertz
//! (`railmbs_wheelrail::hertz`) at the static wheel load, Kalker's
//! coefficients from his table (`railmbs_wheelrail::kalker`).

use nalgebra::Matrix4;
use railmbs_models::{CreepLawSpec, ForceKind, InitialStateKind, Model, Scenario};
use railmbs_runtime::NumericEquations;
use railmbs_runtime::analysis::modes::Mode;
use railmbs_runtime::analysis::speed::{at_conicity, at_speed, scenario_modes};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_testkit::*;
use railmbs_wheelrail::geometry::{ContactGeometry, RigidContact, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::hertz::{HertzShape, effective_modulus, wheel_rail_curvatures};
use railmbs_wheelrail::kalker::KalkerCoefficients;
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

/// Steel, the WheelRail element's defaults: E (Pa), ν.
const YOUNG: f64 = 2.1e11;
const POISSON: f64 = 0.28;
const GRAVITY: f64 = 9.81;

/// The linear contact parameters of a wheelset at its central position
/// (y = 0), per wheel, from the profiles (S1002 on UIC60 1:40, Vehicle 1's
/// wheelset: r0 = 0.46 m, back to back 1.360 m, gauge 1.435 m).
#[derive(Debug)]
pub(super) struct WheelsetContact {
    /// Rolling radius at the contact, m.
    pub(super) r0: f64,
    /// Half the lateral distance of the contact points on the wheels, m.
    pub(super) e: f64,
    /// Equivalent conicity of the linearization, ½ dΔr/dy (–).
    pub(super) conicity: f64,
    /// Contact angle δ0 (rad) and d(δ_L − δ_R)/dy (1/m).
    pub(super) delta0: f64,
    pub(super) d_delta: f64,
    /// d(tan δ_L − tan δ_R)/dy, 1/m.
    pub(super) d_tan_delta: f64,
    /// The rigid wheelset's roll per lateral shift, dθ/dy (rad/m).
    pub(super) d_roll: f64,
    /// Kalker's coefficients and the ellipse's semi-axes at the static load.
    kalker: KalkerCoefficients,
    a: f64,
    b: f64,
    /// Shear modulus, Pa.
    g: f64,
}

impl WheelsetContact {
    /// f11 = G a b C11, f22 = G a b C22 (N), f23 = G (ab)^{3/2} C23 (N m),
    /// f33 = G (ab)² C33 (N m²): Kalker's linear theory (Kalker 1967).
    pub(super) fn coefficients(&self) -> (f64, f64, f64, f64) {
        let c2 = self.a * self.b;
        let gc2 = self.g * c2;
        (
            gc2 * self.kalker.c11,
            gc2 * self.kalker.c22,
            gc2 * c2.sqrt() * self.kalker.c23,
            gc2 * c2 * self.kalker.c33,
        )
    }
}

/// The rigid contact geometry of a wheelset with the bundled wheel profile
/// `wheel` (a file in `models/profiles`) and nominal rolling radius `r0`
/// (m), back to back 1.360 m, on UIC60 1:40 rails at gauge 1.435 m (the
/// WheelRail element's and the straight track's defaults).
pub(super) fn contact_geometry_of(wheel: &str, r0: f64) -> ContactGeometry {
    let profiles = model_path("profiles");
    let s = ProfileSettings::default();
    let wheel = Profile::read(&profiles.join(wheel), ProfileKind::Wheel, &s).unwrap();
    let rail = Profile::read(&profiles.join("MBench_UIC60_v3.ban"), ProfileKind::Rail, &s).unwrap();
    ContactGeometry::new(
        &Wheelset::new(wheel.clone(), wheel, r0, 1.360),
        &Track::new(rail.clone(), rail, 1.435),
        SearchSettings::default(),
    )
    .unwrap()
}

fn contact_geometry() -> ContactGeometry {
    contact_geometry_of("MBench_S1002_v3.prw", 0.46)
}

/// The parameters at y = 0 under the vertical wheel load `q` (N): slopes by
/// central differences of the rigid contact over ±`h` (m), small enough
/// for the profile pair's linear range around the centre, large enough to
/// span several grid points of the profiles' splines.
fn wheelset_contact(q: f64, h: f64) -> WheelsetContact {
    wheelset_contact_on(&contact_geometry(), q, h)
}

/// As [`wheelset_contact`] on the contact geometry `geo`.
pub(super) fn wheelset_contact_on(geo: &ContactGeometry, q: f64, h: f64) -> WheelsetContact {
    let at = |y: f64| -> RigidContact { geo.rigid(y).unwrap() };
    let (c, plus, minus) = (at(0.0), at(h), at(-h));
    let left = |r: &RigidContact| *r.sides[0].deepest();
    let right = |r: &RigidContact| *r.sides[1].deepest();
    let slope = |f: &dyn Fn(&RigidContact) -> f64| (f(&plus) - f(&minus)) / (2.0 * h);
    let cl = left(&c);
    let delta0 = cl.contact_angle;
    // Normal load from the vertical load: N cos δ0 = Q.
    let normal = q / delta0.cos();
    let (curv_a, curv_b) = wheel_rail_curvatures(
        1.0 / cl.wheel_longitudinal_curvature,
        cl.wheel_transverse_curvature,
        cl.rail_transverse_curvature,
    );
    let hertz = HertzShape::with_modulus(curv_a, curv_b, effective_modulus(YOUNG, POISSON))
        .unwrap()
        .contact(normal)
        .unwrap();
    WheelsetContact {
        r0: cl.rolling_radius,
        e: 0.5 * (cl.wheel_y - right(&c).wheel_y),
        conicity: 0.5 * slope(&|r| r.rolling_radius_difference()),
        delta0,
        d_delta: slope(&|r| left(r).contact_angle - right(r).contact_angle),
        d_tan_delta: slope(&|r| left(r).contact_angle.tan() - right(r).contact_angle.tan()),
        d_roll: slope(&|r| r.roll),
        kalker: KalkerCoefficients::interpolate_ab(hertz.a, hertz.b, POISSON).unwrap(),
        a: hertz.a,
        b: hertz.b,
        g: YOUNG / (2.0 * (1.0 + POISSON)),
    }
}

/// The wheelset's inertia and suspension: mass m (kg), yaw inertia Iz
/// (kg m²), lateral stiffness and damping of the whole suspension ky (N/m),
/// cy (N s/m), yaw stiffness and damping kψ (N m/rad), cψ (N m s/rad),
/// vertical wheel load Q (N).
#[derive(Debug, Clone, Copy)]
struct Suspension {
    m: f64,
    iz: f64,
    ky: f64,
    cy: f64,
    kpsi: f64,
    cpsi: f64,
    q: f64,
}

/// The state matrix of the linear wheelset at speed `v` (m/s), state
/// (y, ψ, ẏ, ψ̇). Wickens' equations (in the form of
/// Knothe & Stichel 2017 and Garg & Dukkipati 1984) with the per-wheel creep coefficients
/// f11, f22 and the spin terms f23, f33 of Kalker's linear theory:
///
/// ```text
/// m ÿ  = −(ky + kg − ks) y − cy ẏ − 2 f22 (ẏ/V − ψ) − 2 f23 ψ̇/V
/// Iz ψ̈ = −kψ ψ − cψ ψ̇ − 2 f11 e (λ y/r0 + e ψ̇/V) + 2 f23 (ẏ/V − ψ) − 2 f33 ψ̇/V
/// ```
///
/// Longitudinal creepage ξ = ∓(λ y/r0 + e ψ̇/V) (left/right: rolling radii
/// r0 ± λ y, contact points at ±e), lateral creepage η = ẏ/V − ψ, spin
/// φ = ψ̇/V ∓ sin δ/r0 on each wheel (the wheel's angular velocity on the
/// contact normal, which leans by δ towards the track centre). The normal
/// forces' lateral components give the gravitational stiffness
/// kg = Q d(tan δ_L − tan δ_R)/dy; the equilibrium spin's lateral forces
/// ±f23 sin δ/r0 change with the contact angles and oppose it:
/// ks = f23 cos δ0 d(δ_L − δ_R)/dy / r0 (the reduction of the gravitational stiffness
/// by spin creep that Wickens pointed out).
/// The spin moment's change with the contact angles, f33 cos δ0 dΔδ/dy / r0,
/// is kept in the yaw row.
///
/// `spin`: whether the f23, f33 terms (and ks) are kept (Wickens' original
/// model has f11, f22 and kg only).
fn wickens_matrix(v: f64, w: &WheelsetContact, s: &Suspension, spin: bool) -> Matrix4<f64> {
    let (f11, f22, f23, f33) = w.coefficients();
    let (f23, f33) = if spin { (f23, f33) } else { (0.0, 0.0) };
    let (e, r0, lam) = (w.e, w.r0, w.conicity);
    let kg = s.q * w.d_tan_delta;
    let ks = f23 * w.delta0.cos() * w.d_delta / r0;
    let kms = f33 * w.delta0.cos() * w.d_delta / r0;
    // Rows of M ẍ = −K x − C ẋ in (y, ψ).
    let k = [
        [s.ky + kg - ks, -2.0 * f22],
        [2.0 * f11 * e * lam / r0 - kms, s.kpsi + 2.0 * f23],
    ];
    let c = [
        [s.cy + 2.0 * f22 / v, 2.0 * f23 / v],
        [
            -2.0 * f23 / v,
            s.cpsi + 2.0 * f11 * e * e / v + 2.0 * f33 / v,
        ],
    ];
    let mass = [s.m, s.iz];
    let mut a = Matrix4::zeros();
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    for i in 0..2 {
        for j in 0..2 {
            a[(2 + i, j)] = -k[i][j] / mass[i];
            a[(2 + i, 2 + j)] = -c[i][j] / mass[i];
        }
    }
    a
}

/// The oscillating eigenvalues (σ, ω > 0) of `a`, least damped first.
fn oscillating(a: &Matrix4<f64>) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = a
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im > 1e-9)
        .map(|l| (l.re, l.im))
        .collect();
    out.sort_by(|x, y| (-x.0 / x.0.hypot(x.1)).total_cmp(&(-y.0 / y.0.hypot(y.1))));
    out
}

/// `wheelset_on_springs_critical.ron` (the soft primary suspension: 0.5
/// MN/m longitudinal and lateral per axlebox) at constant speed, with the
/// creep law `law`.
fn soft_wheelset(law: Option<CreepLawSpec<railmbs_models::Expr>>) -> (Scenario, Model) {
    let mut s =
        railmbs_models::load_scenario(&model_path("scenarios/wheelset_on_springs_critical.ron"))
            .unwrap();
    s.initial_kind = InitialStateKind::Equilibrium;
    let mut model = railmbs_models::load_model(&s.model).unwrap();
    if let Some(law) = law {
        for f in &mut model.forces {
            if let ForceKind::WheelRail(w) = &mut f.kind {
                w.creep = law.clone();
            }
        }
    }
    (s, model)
}

pub(super) fn param(model: &Model, s: &Scenario, name: &str) -> f64 {
    s.parameter_values(model).unwrap()[model.parameter_index(name).unwrap()]
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

/// Wickens' parameters of `wheelset_on_springs.ron` with the scenario's
/// overrides: the suspension of two axleboxes at ±b1, the static wheel
/// load from the wheelset's weight and the axlebox preloads.
fn suspension(model: &Model, s: &Scenario) -> Suspension {
    let p = |n: &str| param(model, s, n);
    let (b1, m) = (p("b1"), p("m"));
    Suspension {
        m,
        iz: p("Izz"),
        ky: 2.0 * p("ky"),
        cy: 2.0 * p("cy"),
        kpsi: 2.0 * p("kx") * b1 * b1,
        cpsi: 2.0 * p("cx") * b1 * b1,
        q: 0.5 * (m * GRAVITY + 2.0 * p("axlebox_load")),
    }
}

/// Frequency (Hz) and damping ratio of an eigenvalue (σ, ω).
pub(super) fn frequency_and_damping((re, im): (f64, f64)) -> (f64, f64) {
    (im / (2.0 * std::f64::consts::PI), -re / re.hypot(im))
}

/// The wheelset on soft springs (`wheelset_on_springs_critical.ron` at
/// constant speeds from 20 to 70 m/s, Kalker's linear creep law: the law
/// whose derivative at zero creepage Wickens' model uses) hunts as
/// Wickens' linear wheelset with Kalker's spin terms (see
/// [`wickens_matrix`]): same frequency, damping ratio and linear critical
/// speed.
///
/// What the 2-DOF model neglects and the full 6-DOF model has: the wheel
/// loads' transfer as the contact points move across the profiles (on
/// S1002/UIC60 1:40 near the centre a contact moves 4.6 mm on the wheel per
/// mm of shift: ΔQ ≈ 3e5 N/m · y), the ellipses' and spin coefficients'
/// change along the profiles (f23 by 0.8 % per 0.1 mm), the roll that
/// follows the shift (0.033 rad/m, adding r0 θ̇ = 1.5 % to the lateral
/// creepage), the elastic (Hertz) contact, the suspension's vertical and
/// roll coupling. Each changes the net lateral stiffness kg − ks
/// (1.32e6 − 1.08e6 N/m: gravitational less spin, a difference of two
/// large terms) by a few per cent, which moves the weakly damped hunting
/// mode's real part by up to 0.3 1/s against ω ≈ 11–35 rad/s. Hence the
/// tolerances: frequency 1.5 % (found ≤ 0.7 %), damping ratio 0.012
/// absolute (found ≤ 0.009), linear critical speed 4 % (found 2.4 %:
/// 52.7 m/s analytic, 51.4 m/s full). Wickens' model without the spin
/// terms misses the critical speed by 24 % (63.5 m/s; the check that the spin terms
/// matter, and that the comparison can fail).
#[test]
fn wheelset_on_springs_hunts_as_wickens_linear_wheelset() {
    let (s, model) = soft_wheelset(Some(CreepLawSpec::Kalker));
    let susp = suspension(&model, &s);
    // Slopes over ±0.1 mm: the profile pair's contact jumps between 0.1 and
    // 0.2 mm off centre (contact angle 0.026 → 0.065 rad); the model's
    // contact table (grid 0.1 mm) interpolates over the same points.
    let w = wheelset_contact(susp.q, 1e-4);
    let speeds = [20.0, 30.0, 40.0, 50.0, 60.0, 70.0];
    let (mut full_zeta, mut wickens_zeta, mut plain_zeta) = (vec![], vec![], vec![]);
    for v in speeds {
        let full = full_hunting(&s, &model, v);
        let an = oscillating(&wickens_matrix(v, &w, &susp, true));
        let (f, zeta) = frequency_and_damping(an[0]);
        println!(
            "V = {v} m/s: full {:.4} Hz, ζ = {:.4}; Wickens {f:.4} Hz, ζ = {zeta:.4}",
            full.frequency, full.damping_ratio
        );
        assert!(
            (full.frequency - f).abs() < 0.015 * f,
            "at {v} m/s: {} Hz, Wickens {f} Hz",
            full.frequency
        );
        assert!(
            (full.damping_ratio - zeta).abs() < 0.012,
            "at {v} m/s: ζ = {}, Wickens {zeta}",
            full.damping_ratio
        );
        full_zeta.push((v, full.damping_ratio));
        wickens_zeta.push((v, zeta));
        let plain = oscillating(&wickens_matrix(v, &w, &susp, false));
        plain_zeta.push((v, frequency_and_damping(plain[0]).1));
    }
    let crossing = railmbs_runtime::analysis::modes::zero_crossing;
    let (full_vc, wickens_vc) = (
        crossing(&full_zeta).unwrap(),
        crossing(&wickens_zeta).unwrap(),
    );
    println!("linear critical speed: full {full_vc:.2} m/s, Wickens {wickens_vc:.2} m/s");
    assert!(
        (full_vc - wickens_vc).abs() < 0.04 * wickens_vc,
        "critical speed {full_vc} m/s, Wickens {wickens_vc} m/s"
    );
    let plain_vc = crossing(&plain_zeta).unwrap_or(f64::INFINITY);
    println!("Wickens without spin terms: {plain_vc:.2} m/s");
    assert!(
        (plain_vc - full_vc).abs() > 0.1 * full_vc,
        "without spin terms {plain_vc} m/s"
    );
}

/// The wheelset of `wheelset_on_springs_critical.ron` with Kalker's linear
/// law, its lateral and yaw suspension removed (ky = cy = cx = 0) and held
/// longitudinally by a 1 kN/m spring per axlebox, centred (see
/// [`a_free_wheelset_oscillates_at_klingels_kinematic_frequency`]).
fn free_wheelset() -> (Scenario, Model) {
    let (mut s, model) = soft_wheelset(Some(CreepLawSpec::Kalker));
    for (name, value) in [
        ("kx", "1e3"),
        ("ky", "0"),
        ("cx", "0"),
        ("cy", "0"),
        ("y0", "0"),
    ] {
        s.set_parameter(name, value);
    }
    (s, model)
}

/// The free wheelset's kinematic oscillation: Klingel's frequency
/// f = V/(2π) √(λ/(r0 e)) (Klingel 1883)
/// is the limit of the hunting mode's frequency as V → 0, where the creep
/// forces (∝ f22, f11, independent of V) dominate inertia (∝ V²) and the
/// net gravitational stiffness. λ, r0, e from the profiles as above.
///
/// The wheelset is `wheelset_on_springs.ron` with its lateral and yaw
/// suspension removed (ky = cy = cx = 0) and held longitudinally by a
/// 1 kN/m spring per axlebox (its yaw stiffness 2 kN m/rad is 0.06 % of
/// the creep forces' 2 f11 e λ/r0 = 3.3e6 N m/rad): a wheelset free also
/// longitudinally (`free_wheelset.ron`) has no steady state at constant
/// speed, as its spin creep leaves a rolling resistance of 0.13 N that
/// nothing balances (`umsim modes` says so). The wheel loads are those of
/// Vehicle 1 (54.5 kN).
///
/// Tolerance 0.5 %: the full model's frequency lies 0.29 % below
/// Klingel's at every speed from 1 to 10 m/s (a constant ratio, so not the
/// creep compliance or inertia, which vanish as V → 0: the kinematic ratio
/// λ/(r0 e) as the full model sees it, through its contact table
/// interpolated on a 0.1 mm × 2 mrad grid in shift and roll and its roll
/// following the shift, differs by 0.6 % from the rigid contact's central
/// difference here); Wickens' model with the same parameters lies within
/// 0.02 % of Klingel at these speeds.
#[test]
fn a_free_wheelset_oscillates_at_klingels_kinematic_frequency() {
    let (s, model) = free_wheelset();
    let susp = suspension(&model, &s);
    let w = wheelset_contact(susp.q, 1e-4);
    for v in [1.0, 2.0, 5.0, 10.0] {
        let full = full_hunting(&s, &model, v);
        let klingel = v / (2.0 * std::f64::consts::PI) * (w.conicity / (w.r0 * w.e)).sqrt();
        let (wickens, _) =
            frequency_and_damping(oscillating(&wickens_matrix(v, &w, &susp, true))[0]);
        println!(
            "V = {v} m/s: full {:.5} Hz ({}), Wickens {wickens:.5} Hz, Klingel {klingel:.5} Hz",
            full.frequency, full.name
        );
        assert!(
            (full.frequency - klingel).abs() < 5e-3 * klingel,
            "at {v} m/s: {} Hz, Klingel {klingel} Hz",
            full.frequency
        );
        // Nearly undamped: the kinematic oscillation neither grows nor decays
        // (ζ = 0 in Klingel's limit).
        assert!(full.damping_ratio.abs() < 0.01, "{full:?}");
    }
}

/// The conicity override (`umsim modes --conicity`; the wheel–rail
/// element's "Conicity override": the contact geometry looked up at the
/// shift s y, s = λ/λ₀): the free wheelset of
/// [`a_free_wheelset_oscillates_at_klingels_kinematic_frequency`] at the
/// equivalent conicities 0.05, 0.1, 0.2 and 0.3 oscillates at Klingel's
/// f = V/(2π) √(λ/(r0 e)) with λ the override itself (r0, e from the
/// profiles' rigid contact as above: the override keeps them).
///
/// Klingel's formula neglects the wheelset's roll; the override scales the
/// roll that follows the shift by s with everything else, and the contacts
/// r0 below the axle then move laterally by r0 θ̇ besides ẏ: the kinematic
/// relation ẏ (1 + r0 s dθ/dy) = V ψ lowers the frequency by
/// (1 + r0 s dθ/dy)^(−1/2) (0.33 % at λ = 0.05, 1.3 % at λ = 0.2 here;
/// dθ/dy from the rigid contact). With it the full model lies a constant
/// +0.45 % above at every conicity and speed (speed-independent, so
/// kinematic: the table's interpolation of the rolling radii against the
/// rigid contact's central difference, as in the unscaled test, which
/// sees the same offset once the roll is counted). Tolerance 0.6 %.
#[test]
fn a_free_wheelset_at_an_overridden_conicity_oscillates_at_klingels_frequency() {
    let (s, model) = free_wheelset();
    let susp = suspension(&model, &s);
    let w = wheelset_contact(susp.q, 1e-4);
    println!(
        "the profiles' own conicity (rigid contact, ±0.1 mm): {:.5}",
        w.conicity
    );
    for lambda in [0.05, 0.1, 0.2, 0.3] {
        let scaled = at_conicity(&s, lambda);
        for v in [2.0, 5.0] {
            let full = full_hunting(&scaled, &model, v);
            // The roll that follows the shift (θ = s dθ/dy y) moves the
            // contacts, r0 below the axle, laterally by r0 θ (a rotation
            // about x of the point z = −r0): the kinematic relation is
            // ẏ (1 + r0 s dθ/dy) = V ψ, and Klingel's ω² divides by that.
            let roll = 1.0 + w.r0 * (lambda / w.conicity) * w.d_roll;
            let klingel = v / (2.0 * std::f64::consts::PI) * (lambda / (w.r0 * w.e * roll)).sqrt();
            println!(
                "λ = {lambda}, V = {v} m/s: full {:.5} Hz, Klingel with the roll {klingel:.5} Hz ({:+.3} %)",
                full.frequency,
                100.0 * (full.frequency / klingel - 1.0)
            );
            assert!(
                (full.frequency - klingel).abs() < 6e-3 * klingel,
                "λ = {lambda}, {v} m/s: {} Hz, Klingel {klingel} Hz",
                full.frequency
            );
            assert!(full.damping_ratio.abs() < 0.01, "{full:?}");
        }
    }
}

/// The wheelset on soft springs of
/// [`wheelset_on_springs_hunts_as_wickens_linear_wheelset`] at the
/// overridden equivalent conicity 0.1 (s = λ/λ_profiles = 0.88) hunts as
/// Wickens' linear wheelset with λ the override and the contact angles'
/// slopes (hence the gravitational stiffness and the spin terms) scaled by
/// s, as the override defines them; frequency, damping ratio and critical
/// speed, with the tolerances of the unscaled comparison (frequency 1.5 %,
/// damping ratio 0.012, critical speed 4 %: the residual there is the net
/// lateral stiffness kg − ks, a difference of two large terms, as the
/// 6-DOF model sees it against the 2-DOF model, and at s ≤ 1 it is no
/// larger).
///
/// At λ = 0.2 (s = 1.75) only the frequency is held to Wickens' (1.5 %,
/// found 1.2 %) and the critical speed must fall (Wickens: V_c ∝ 1/√λ for
/// the dominant creep terms): a check that the override moves it. The
/// damping ratio (0.008 to 0.013 below Wickens') and the critical speed
/// (38.4 against 40.3 m/s, 4.9 %) are printed, not held: the residual
/// grows with s (the roll that follows the shift, scaled by s, adds
/// r0 s dθ/dy ẏ to the contacts' lateral velocity, which Wickens' model
/// omits; see the free wheelset's test), a limit of the comparison, not
/// of the override, which the free wheelset's kinematic test checks
/// exactly.
#[test]
fn wheelset_on_springs_at_an_overridden_conicity_hunts_as_wickens_wheelset() {
    let (mut s, model) = soft_wheelset(Some(CreepLawSpec::Kalker));
    // The equilibrium's guess centred: the scenario's 3 mm start (for its
    // decelerating run) is, scaled by s ≈ 2 at λ = 0.3, beyond the
    // profiles' tread (the Newton solve then does not reach the centre).
    s.set_parameter("y0", "0");
    let susp = suspension(&model, &s);
    let real = wheelset_contact(susp.q, 1e-4);
    let mut critical = Vec::new();
    for (lambda, speeds) in [
        (0.1, [40.0, 50.0, 60.0, 70.0, 80.0]),
        (0.2, [24.0, 32.0, 40.0, 48.0, 56.0]),
    ] {
        let ratio = lambda / real.conicity;
        let w = WheelsetContact {
            conicity: lambda,
            d_delta: real.d_delta * ratio,
            d_tan_delta: real.d_tan_delta * ratio,
            ..wheelset_contact(susp.q, 1e-4)
        };
        let scaled = at_conicity(&s, lambda);
        let (mut full_zeta, mut wickens_zeta) = (vec![], vec![]);
        for v in speeds {
            let full = full_hunting(&scaled, &model, v);
            let (f, zeta) =
                frequency_and_damping(oscillating(&wickens_matrix(v, &w, &susp, true))[0]);
            println!(
                "λ = {lambda}, V = {v} m/s: full {:.4} Hz, ζ = {:.4}; Wickens {f:.4} Hz, ζ = {zeta:.4}",
                full.frequency, full.damping_ratio
            );
            assert!(
                (full.frequency - f).abs() < 0.015 * f,
                "λ = {lambda}, {v} m/s: {} Hz, Wickens {f} Hz",
                full.frequency
            );
            assert!(
                lambda > 0.15 || (full.damping_ratio - zeta).abs() < 0.012,
                "λ = {lambda}, {v} m/s: ζ = {}, Wickens {zeta}",
                full.damping_ratio
            );
            full_zeta.push((v, full.damping_ratio));
            wickens_zeta.push((v, zeta));
        }
        let crossing = railmbs_runtime::analysis::modes::zero_crossing;
        let (full_vc, wickens_vc) = (
            crossing(&full_zeta).unwrap_or_else(|| panic!("λ = {lambda}: {full_zeta:?}")),
            crossing(&wickens_zeta).unwrap_or_else(|| panic!("λ = {lambda}: {wickens_zeta:?}")),
        );
        println!(
            "λ = {lambda}: linear critical speed full {full_vc:.2} m/s, Wickens {wickens_vc:.2} m/s"
        );
        assert!(
            lambda > 0.15 || (full_vc - wickens_vc).abs() < 0.04 * wickens_vc,
            "λ = {lambda}: critical speed {full_vc} m/s, Wickens {wickens_vc} m/s"
        );
        critical.push(full_vc);
    }
    assert!(critical[1] < 0.8 * critical[0], "{critical:?}");
}
