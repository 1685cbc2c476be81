//! Mueller's method as Pogorelov 2005, Sect. 4.2 gives it: values worked out
//! by hand from the paper's formula, the saturation limit μN, independence of
//! spin and of the ellipse, pure sliding at the flange contact of a two-point
//! contact, and the recognition of that contact (`ContactMode::of_wheel`).

use crate::common;

use common::*;
use railmbs_wheelrail::creep::{
    ContactMode, ContactPatch, CreepError, CreepLaw, CreepLawSpec, Creepages, FLANGE_CONTACT_ANGLE,
    MUELLER_MAX_LOAD, Mueller,
};

fn patch(n: f64) -> ContactPatch {
    ContactPatch { n, ..tread_patch() }
}

fn creep(xi: f64, eta: f64, phi: f64) -> Creepages {
    Creepages { xi, eta, phi }
}

/// The slope 1000·k_c(P) at P = 100 kN and 50 kN, by hand:
/// k_c(100) = 100·(235 + 100·(2.4 − 1.0)) = 37 500 kN,
/// k_c(50) = 50·(235 + 50·(2.4 − 0.5)) = 16 500 kN (the paper's P is the load
/// in kN, P = 0.001 N). At ρ = 1e-7 the saturation factor differs from 1 by
/// (k_c ρ/(μP))²/2 < 1e-7: tolerance 1e-6 relative.
#[test]
fn small_creepage_slope_is_the_papers_polynomial() {
    let law = Mueller::default();
    for (n, slope) in [(100e3, 37_500e3), (50e3, 16_500e3)] {
        assert!((Mueller::slope(n) / slope - 1.0).abs() < 1e-12);
        let rho = 1e-7;
        // 3-4-5 split of the resultant creepage: Fx = −ξ F_xy, Fy = −η F_xy.
        let f = law
            .forces(&patch(n), &creep(0.6 * rho, -0.8 * rho, 0.0))
            .unwrap();
        assert!((f.fx / (-0.6 * rho * slope) - 1.0).abs() < 1e-6, "{f:?}");
        assert!((f.fy / (0.8 * rho * slope) - 1.0).abs() < 1e-6, "{f:?}");
        assert_eq!(f.mz, 0.0);
    }
}

/// A mid-range value by hand with m = 2: N = 100 kN, μ = 0.3, ρ = 0.001:
/// k_c ρ = 37.5 kN, u = 37.5/(0.3·100) = 1.25, |F| = 37 500 N/√(1 + 1.5625)
/// = 23 426.1 N; with m = 3, |F| = 37 500/(1 + 1.953125)^(1/3) = 26 137.9 N.
/// Tolerance 0.1 N (the hand values' last digit).
#[test]
fn transition_by_hand() {
    let p = patch(100e3);
    for (m, expected) in [(2.0, 23_426.06), (3.0, 26_137.90)] {
        let f = Mueller::new(m)
            .unwrap()
            .forces(&p, &creep(0.0, 1e-3, 0.0))
            .unwrap();
        assert!((-f.fy - expected).abs() < 0.1, "m = {m}: {f:?}");
        assert_eq!(f.fx, 0.0);
    }
}

/// Spin and the ellipse's semi-axes do not enter (the paper: "forces do not
/// depend on the spin"); the resultant saturates towards μN from below.
#[test]
fn no_spin_no_ellipse_and_saturation() {
    let law = Mueller::default();
    let base = law.forces(&patch(80e3), &creep(2e-3, 1e-3, 0.0)).unwrap();
    let spun = law.forces(&patch(80e3), &creep(2e-3, 1e-3, 5.0)).unwrap();
    assert_eq!(base, spun);
    let other = ContactPatch {
        a: 3e-3,
        b: 9e-3,
        ..patch(80e3)
    };
    assert_eq!(base, law.forces(&other, &creep(2e-3, 1e-3, 0.0)).unwrap());
    let mu_n = 0.3 * 80e3;
    let mut last = 0.0;
    for k in 0..40 {
        let eta = 1e-5 * 1.3_f64.powi(k);
        let f = law.forces(&patch(80e3), &creep(0.0, eta, 0.0)).unwrap();
        assert!(-f.fy > last && -f.fy < mu_n, "{eta}: {f:?}");
        last = -f.fy;
    }
    // ρ = 1e-5·1.3³⁹ ≈ 0.278: u = 2.904e7·0.278/24 000 ≈ 336,
    // |F| = μN/√(1 + 1/u²) = μN(1 − 4.4e-6).
    assert!(last > mu_n * (1.0 - 5e-6) && last < mu_n * (1.0 - 4e-6));
}

/// The flange contact of a two-point contact slides: |F| = μN exactly along
/// −(ξ, η), even at a creepage where the formula is far from saturated; the
/// tread contact of the same wheel keeps the formula.
#[test]
fn flange_contact_of_two_point_contact_slides() {
    let law = Mueller::default();
    let p = patch(40e3);
    let c = creep(3e-4, -4e-4, 20.0);
    let flange = law
        .forces_in_contact(&p, &c, 30.0, ContactMode::TwoPointFlange)
        .unwrap();
    let mu_n = 0.3 * 40e3;
    assert!(
        (flange.fx - (-0.6 * mu_n)).abs() < 1e-9 * mu_n,
        "{flange:?}"
    );
    assert!((flange.fy - 0.8 * mu_n).abs() < 1e-9 * mu_n, "{flange:?}");
    assert_eq!(flange.mz, 0.0);
    let tread = law
        .forces_in_contact(&p, &c, 30.0, ContactMode::TwoPointTread)
        .unwrap();
    assert_eq!(tread, law.forces(&p, &c).unwrap());
    assert!(tread.fx.hypot(tread.fy) < 0.9 * mu_n);
    // No creepage, no direction: no force.
    let none = law
        .forces_in_contact(&p, &creep(0.0, 0.0, 3.0), 30.0, ContactMode::TwoPointFlange)
        .unwrap();
    assert_eq!((none.fx, none.fy), (0.0, 0.0));
    // Through the spec, as model files and `umsim creep` build it.
    let built = "mueller".parse::<CreepLawSpec>().unwrap().build().unwrap();
    assert_eq!(
        built
            .forces_in_contact(&p, &c, 30.0, ContactMode::TwoPointFlange)
            .unwrap(),
        flange
    );
}

/// Which contact is the flange: in two-point contact the one of larger
/// |contact angle|, if at least FLANGE_CONTACT_ANGLE (20°).
#[test]
fn flange_contact_recognition() {
    use ContactMode::*;
    assert!((FLANGE_CONTACT_ANGLE - 20f64.to_radians()).abs() < 1e-15);
    assert_eq!(
        ContactMode::of_wheel([0.03, 1.2], [true, true]),
        [TwoPointTread, TwoPointFlange]
    );
    assert_eq!(
        ContactMode::of_wheel([-1.1, 0.05], [true, true]),
        [TwoPointFlange, TwoPointTread]
    );
    assert_eq!(
        ContactMode::of_wheel([0.03, 1.2], [false, true]),
        [Single, Single]
    );
    assert_eq!(
        ContactMode::of_wheel([0.03, 1.2], [true, false]),
        [Single, Single]
    );
    // Two tread contacts (both below 20°): neither slides.
    assert_eq!(
        ContactMode::of_wheel([0.02, 0.3], [true, true]),
        [TwoPointTread, TwoPointTread]
    );
}

/// The load range: the slope polynomial is zero at MUELLER_MAX_LOAD
/// (P = 314.679 2 kN, by the quadratic formula) and loads from there on are
/// refused with an error naming N. The constant is rounded to 0.01 N; the
/// slope falls by 1 225 N per newton of load there, so the rounding leaves
/// about 4 N: tolerance 20 N against slopes of 1e7 N.
#[test]
fn load_beyond_the_fit_is_refused() {
    assert!(Mueller::slope(MUELLER_MAX_LOAD).abs() < 20.0);
    assert!(Mueller::slope(0.99 * MUELLER_MAX_LOAD) > 0.0);
    let e = Mueller::default()
        .forces(&patch(350e3), &creep(1e-3, 0.0, 0.0))
        .unwrap_err();
    assert!(matches!(e, CreepError::Input { name: "N", .. }), "{e}");
    assert!(e.to_string().contains("314.68 kN"), "{e}");
    assert!(Mueller::new(-1.0).is_err());
    // No load: no force (and no error).
    let f = Mueller::default()
        .forces(&patch(0.0), &creep(1e-3, 0.0, 0.0))
        .unwrap();
    assert_eq!((f.fx, f.fy), (0.0, 0.0));
}
