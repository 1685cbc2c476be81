//! The strip-theory law ([`StripTheory`]) in its limits: Kalker's linear
//! theory at small creepage (Kalker 1990, Table E.3, through
//! [`KalkerLinear`]), Coulomb's μN at full sliding, and zero force without
//! creepage. Its accuracy against the exact theory is in `exact_theory.rs`.

use crate::common::tread_patch;
use railmbs_wheelrail::creep::{
    ContactPatch, CreepLaw, CreepLawSpec, Creepages, KalkerLinear, StripTheory,
};

fn flange_patch() -> ContactPatch {
    ContactPatch {
        a: 2e-3,
        b: 5e-3,
        n: 20e3,
        ..tread_patch()
    }
}

fn long_patch() -> ContactPatch {
    ContactPatch {
        a: 8e-3,
        b: 3.2e-3,
        n: 100e3,
        ..tread_patch()
    }
}

/// At 1e-9 creepage (1e-6 of sliding) every one of the four coefficients
/// C11, C22, C23 (both ways) and C33 is Kalker's: the law is calibrated on
/// them. The θ-midpoint rule integrates the even weights (cos²θ for C11,
/// C22, cos⁴θ for C23 from spin, cos²θ sin²θ for C33) exactly, the odd
/// cos³θ of Mz(η) with an error O(1/n²) (relative 2e-4 at 10 strips);
/// tolerance 1e-3 of the largest linear term from 10 strips on.
#[test]
fn linear_limit_is_kalkers() {
    let eps = 1e-9;
    for p in [tread_patch(), flange_patch(), long_patch()] {
        for n in [10, 40] {
            let law = StripTheory::new(n).unwrap();
            for c in [
                Creepages {
                    xi: eps,
                    eta: 0.0,
                    phi: 0.0,
                },
                Creepages {
                    xi: 0.0,
                    eta: eps,
                    phi: 0.0,
                },
                Creepages {
                    xi: 0.0,
                    eta: 0.0,
                    phi: eps / p.a,
                },
            ] {
                let f = law.forces(&p, &c).unwrap();
                let k = KalkerLinear.forces(&p, &c).unwrap();
                let scale = k.fx.abs().max(k.fy.abs()).max(k.mz.abs() / p.a);
                for (what, x, y, s) in [
                    ("Fx", f.fx, k.fx, scale),
                    ("Fy", f.fy, k.fy, scale),
                    ("Mz", f.mz, k.mz, scale * p.a),
                ] {
                    assert!(
                        (x - y).abs() <= 1e-3 * s,
                        "{n} strips {c:?} {what}: {x} vs {y}"
                    );
                }
            }
        }
    }
}

/// Far beyond sliding, without spin, every strip slides: |F| = μN up to
/// the θ-midpoint rule's error on the pressure's odd weight cos³θ,
/// O(1/n²): 1.1e-4 at 10 strips, 7e-6 at 40 (tolerances 2e-4 and 1.5e-5),
/// along Kalker's normalized creepage direction (C11 ξ, C22 η), the law's
/// stated simplification.
#[test]
fn full_sliding_is_coulomb() {
    for (n, tol) in [(10, 2e-4), (40, 1.5e-5)] {
        for p in [tread_patch(), flange_patch(), long_patch()] {
            let law = StripTheory::new(n).unwrap();
            for (xi, eta) in [(1.0, 0.0), (0.0, -1.0), (0.3, 0.4), (-2.0, 0.5)] {
                let f = law.forces(&p, &Creepages { xi, eta, phi: 0.0 }).unwrap();
                let mag = f.fx.hypot(f.fy);
                assert!(
                    (mag - p.mu * p.n).abs() <= tol * p.mu * p.n,
                    "{n}: {xi} {eta}: {mag}"
                );
                assert!(f.fx * xi <= 0.0 && f.fy * eta <= 0.0, "{f:?}");
            }
        }
    }
}

/// No creepage, no force; no load or no friction, no force; and the law
/// is reached through its spec text.
#[test]
fn zero_cases_and_spec() {
    let law = "strip:12".parse::<CreepLawSpec>().unwrap().build().unwrap();
    assert_eq!(law.name(), "strip");
    let zero = Creepages {
        xi: 0.0,
        eta: 0.0,
        phi: 0.0,
    };
    let f = law.forces(&tread_patch(), &zero).unwrap();
    assert_eq!((f.fx, f.fy, f.mz), (0.0, 0.0, 0.0));
    let c = Creepages {
        xi: 1e-3,
        eta: 0.0,
        phi: 0.2,
    };
    for p in [
        ContactPatch {
            n: 0.0,
            ..tread_patch()
        },
        ContactPatch {
            mu: 0.0,
            ..tread_patch()
        },
    ] {
        let f = law.forces(&p, &c).unwrap();
        assert_eq!((f.fx, f.fy, f.mz), (0.0, 0.0, 0.0));
    }
    assert!(StripTheory::new(0).is_err());
    assert_eq!(
        "strip".parse::<CreepLawSpec>().unwrap().to_string(),
        "strip:strips=10"
    );
}
