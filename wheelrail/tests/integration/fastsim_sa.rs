//! FastSim_SA (Pogorelov 2005, Sect. 4.3, Fig. 24) against FASTSIM with many
//! elements (the same strips: FastSim_SA's sliding zone is FASTSIM's own
//! march, its adhesion zone the exact strip solution, so both converge to the
//! same limit), against FastSim_A at zero spin (both exact there), Kalker's
//! linear theory at small creepage and Coulomb's μN at large creepage.

use crate::common;

use common::*;
use railmbs_wheelrail::creep::{
    ContactPatch, CreepForces, CreepLaw, CreepLawSpec, Creepages, Fastsim, FastsimA, FastsimSa,
    KalkerLinear,
};

/// |F − F_ref| / (μN): the error measure of the tables.
fn err_mu_n(a: &CreepForces, r: &CreepForces, p: &ContactPatch) -> f64 {
    (a.fx - r.fx).hypot(a.fy - r.fy) / (p.mu * p.n)
}

/// Tread and flange spin cases (a = 6 mm: |φ|a up to 0.0018 and 0.021).
fn cases() -> Vec<Creepages> {
    let mut v = Vec::new();
    for xi in [0.0, 3e-4, 1e-3, -3e-3, 1e-2] {
        for eta in [0.0, -5e-4, 1e-3, 3e-3, -1e-2] {
            for phi in [0.0, 0.1, -0.3, 1.5, -2.5, 3.5] {
                if xi != 0.0 || eta != 0.0 || phi != 0.0 {
                    v.push(Creepages { xi, eta, phi });
                }
            }
        }
    }
    v
}

/// At zero spin the direction never turns: FastSim_SA's sliding elements
/// carry the bound's exact integral and FastSim_A's closed form is exact, so
/// they agree to rounding (1e-10 μN) for any number of elements, even 2.
#[test]
fn zero_spin_equals_fastsim_a() {
    let p = tread_patch();
    let fsa = FastsimA::new(20).unwrap();
    for n in [2, 10, 50] {
        let sa = FastsimSa::new(20, n).unwrap();
        for c in cases().into_iter().filter(|c| c.phi == 0.0) {
            let e = err_mu_n(
                &sa.forces(&p, &c).unwrap(),
                &fsa.forces(&p, &c).unwrap(),
                &p,
            );
            assert!(e < 1e-10, "n {n} {c:?}: {e}");
        }
    }
}

/// Against FASTSIM with 4000 elements (20 strips), over tread and flange
/// spin: with as many elements both march the sliding zone alike and differ
/// only in the adhesion zone (exact against FASTSIM's midpoint rule, whose
/// error for the linear adhesion traction is zero and for the bound
/// O(1/n²) ≈ 1e-7): FastSim_SA with 4000 elements must agree to 1e-6 μN
/// (measured 2.4e-8); with 100 and 20
/// elements it carries FASTSIM's discretisation error of its sliding zone
/// only, bounded here by that of FASTSIM itself with as many elements (plus
/// 1e-3 μN for the different quadrature of the bound).
#[test]
fn converges_to_fine_fastsim() {
    let p = tread_patch();
    let fine = Fastsim::new(20, 4000).unwrap();
    let sa_fine = FastsimSa::new(20, 4000).unwrap();
    let mut worst = [0.0_f64; 3];
    let mut worst_fastsim = [0.0_f64; 2];
    let mut mean = [0.0_f64; 3];
    let cs = cases();
    for c in &cs {
        let r = fine.forces(&p, c).unwrap();
        let e = err_mu_n(&sa_fine.forces(&p, c).unwrap(), &r, &p);
        assert!(e < 1e-6, "{c:?}: {e}");
        worst[0] = worst[0].max(e);
        mean[0] += e;
        for (k, n) in [100, 20].into_iter().enumerate() {
            let sa = FastsimSa::new(20, n).unwrap();
            let fs = Fastsim::new(20, n).unwrap();
            let e = err_mu_n(&sa.forces(&p, c).unwrap(), &r, &p);
            let ef = err_mu_n(&fs.forces(&p, c).unwrap(), &r, &p);
            worst[k + 1] = worst[k + 1].max(e);
            mean[k + 1] += e;
            worst_fastsim[k] = worst_fastsim[k].max(ef);
        }
    }
    for (k, n) in [100.0, 20.0].into_iter().enumerate() {
        assert!(
            worst[k + 1] <= worst_fastsim[k] + 1e-3,
            "n {n}: {worst:?} vs {worst_fastsim:?}"
        );
    }
    let m = cs.len() as f64;
    eprintln!(
        "FastSim_SA vs FASTSIM 20×4000 over {} cases, |ΔF|/μN: n = 4000 max {:.2e} mean {:.2e}; \
         n = 100 max {:.2e} mean {:.2e} (FASTSIM 20×100 max {:.2e}); n = 20 max {:.2e} mean {:.2e} \
         (FASTSIM 20×20 max {:.2e})",
        cs.len(),
        worst[0],
        mean[0] / m,
        worst[1],
        mean[1] / m,
        worst_fastsim[0],
        worst[2],
        mean[2] / m,
        worst_fastsim[1]
    );
}

/// Small creepage: the adhesion zone covers the strips, the exact solution
/// integrates to Kalker's linear theory up to the strip quadrature in y (as
/// FastSim_A: 2 % for 10 strips, see `creep::linear_limit_matches_kalker`);
/// large creepage: exactly μN (the sliding elements carry the bound's exact
/// integral), opposing the creepage.
#[test]
fn linear_limit_and_saturation() {
    let p = tread_patch();
    let sa = FastsimSa::new(10, 10).unwrap();
    let eps = 1e-7;
    for (c, lin_fx) in [
        (
            Creepages {
                xi: eps,
                eta: 0.0,
                phi: 0.0,
            },
            true,
        ),
        (
            Creepages {
                xi: 0.0,
                eta: eps,
                phi: 0.0,
            },
            false,
        ),
    ] {
        let f = sa.forces(&p, &c).unwrap();
        let l = KalkerLinear.forces(&p, &c).unwrap();
        let (a, b) = if lin_fx { (f.fx, l.fx) } else { (f.fy, l.fy) };
        assert!((a / b - 1.0).abs() < 0.02, "{c:?}: {a} vs {b}");
    }
    let mu_n = p.mu * p.n;
    for c in [
        Creepages {
            xi: 0.2,
            eta: 0.0,
            phi: 0.0,
        },
        Creepages {
            xi: -0.1,
            eta: 0.1,
            phi: 0.0,
        },
        Creepages {
            xi: 0.0,
            eta: -0.3,
            phi: 0.0,
        },
    ] {
        let f = sa.forces(&p, &c).unwrap();
        let t = f.fx.hypot(f.fy);
        assert!((t / mu_n - 1.0).abs() < 1e-12, "{c:?}: {t} vs {mu_n}");
        assert!(f.fx * c.xi <= 0.0 && f.fy * c.eta <= 0.0);
    }
    // Through the spec, as model files and `umsim creep` build it.
    let spec: CreepLawSpec = "fastsim-sa:nx=10,ny=10".parse().unwrap();
    let c = Creepages {
        xi: 1e-3,
        eta: 2e-3,
        phi: 1.0,
    };
    assert_eq!(
        spec.build().unwrap().forces(&p, &c).unwrap(),
        sa.forces(&p, &c).unwrap()
    );
    assert!(FastsimSa::new(0, 10).is_err() && FastsimSa::new(10, 0).is_err());
}
