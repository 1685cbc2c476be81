//! Every creep law against Kalker's exact theory, computed by CONTACT
//! (E.A.H. Vollebregt, Apache-2.0) for 240 Hertzian cases: five ellipses from
//! a/b = 2.5 (tread) to 0.2 (flange), longitudinal, lateral, combined
//! creepage and spin from 0.1 to 5 times the creepage of full sliding, and
//! creepage with spin (`tests/data/contact/hertz_creep.csv`; its README says
//! how it was made). The same file holds CONTACT's own FASTSIM and FaStrip
//! for the same cases, which tie our FASTSIM to CONTACT's and give the error
//! level of the published approximate methods on this case set.
//!
//! Error measure, as the tables: |(ΔFx, ΔFy)|/(μN), mean and maximum
//! over the cases. The tolerances are stated at each law.

use railmbs_wheelrail::creep::{
    ContactPatch, CreepForces, CreepLaw, CreepLawSpec, Creepages, Fastsim, FastsimLayout,
    TractionBound,
};
use std::collections::HashMap;

/// One case of the reference file: inputs, CONTACT's exact forces, and the
/// forces of CONTACT's approximate methods by their column prefix.
struct Case {
    patch: ContactPatch,
    creep: Creepages,
    exact: CreepForces,
    contact: HashMap<String, CreepForces>,
}

fn cases() -> Vec<Case> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/contact/hertz_creep.csv"
    );
    let mut rd = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .expect("tests/data/contact/hertz_creep.csv");
    let hdr: Vec<String> = rd.headers().unwrap().iter().map(str::to_string).collect();
    let col = |name: &str| hdr.iter().position(|h| h == name).expect(name);
    let prefixes: Vec<String> = hdr
        .iter()
        .filter_map(|h| h.strip_suffix(".Fx").map(str::to_string))
        .collect();
    rd.records()
        .map(|r| {
            let r = r.unwrap();
            let v = |name: &str| -> f64 { r[col(name)].parse().unwrap() };
            let forces = |p: &str| CreepForces {
                fx: v(&format!("{p}Fx")),
                fy: v(&format!("{p}Fy")),
                mz: v(&format!("{p}Mz")),
            };
            Case {
                patch: ContactPatch {
                    a: v("a"),
                    b: v("b"),
                    g: v("G"),
                    nu: v("nu"),
                    mu: v("mu"),
                    n: v("N"),
                },
                creep: Creepages {
                    xi: v("xi"),
                    eta: v("eta"),
                    phi: v("phi"),
                },
                exact: forces(""),
                contact: prefixes
                    .iter()
                    .map(|p| (p.clone(), forces(&format!("{p}."))))
                    .collect(),
            }
        })
        .collect()
}

/// |(ΔFx, ΔFy)|/(μN).
fn err(f: &CreepForces, r: &CreepForces, p: &ContactPatch) -> f64 {
    (f.fx - r.fx).hypot(f.fy - r.fy) / (p.mu * p.n)
}

/// Mean and maximum of `err` over the cases, with the case of the maximum
/// (1-based, as the file's `case` column).
fn stats(errs: &[f64]) -> (f64, f64, usize) {
    let (mut max, mut at) = (0.0, 0);
    for (k, &e) in errs.iter().enumerate() {
        if e > max {
            (max, at) = (e, k + 1);
        }
    }
    (errs.iter().sum::<f64>() / errs.len() as f64, max, at)
}

fn law_errors(law: &dyn CreepLaw, cases: &[Case]) -> Vec<f64> {
    cases
        .iter()
        .map(|c| err(&law.forces(&c.patch, &c.creep).unwrap(), &c.exact, &c.patch))
        .collect()
}

/// The file is what its README says: 240 cases, CONTACT's normal solution
/// carried the prescribed load (checked when generated), and Coulomb's limit
/// holds for the exact forces, |F| ≤ μN (within the 4 printed digits).
#[test]
fn reference_file_is_sound() {
    let cs = cases();
    assert_eq!(cs.len(), 240);
    for (k, c) in cs.iter().enumerate() {
        let f = c.exact.fx.hypot(c.exact.fy) / (c.patch.mu * c.patch.n);
        assert!(f <= 1.0 + 5e-4, "case {}: |F|/μN = {f}", k + 1);
    }
}

/// Our FASTSIM in CONTACT's layout (40 × 40 cells over 1.05 × the ellipse,
/// parabolic bound, the flexibilities L1, L2, L3 of Kalker's coefficients)
/// is the algorithm of CONTACT's FASTSIM (M = 3, B = 3) on the same grid,
/// where one flexibility is in play: pure ξ (L1), pure η (L2, with the
/// Mz it couples to) and pure spin (L3 in both directions). With creepages
/// of two flexibilities the two programs turn the sliding traction
/// differently (Kalker's 1982 update here: the traction follows the
/// accumulated elastic traction; CONTACT's sliding direction differs, by up
/// to 0.2 μN at flange spin), so those cases are not compared. What remains
/// is CONTACT's own Kalker coefficients (its table interpolation in a/b and
/// ν, here piecewise linear in ν between 0, 0.25 and 0.5) and its 4 printed
/// digits. Measured mean 3.3e-3, max 1.4e-2; tolerance mean 5e-3, max 2e-2
/// of μN (coefficients 2 % apart move a force at half saturation by about
/// 1 % of μN).
#[test]
fn fastsim_matches_contacts_fastsim() {
    let cs = cases();
    let ours = Fastsim::new(40, 40)
        .unwrap()
        .with_layout(FastsimLayout::UniformGrid { scale: 1.05 })
        .unwrap()
        .with_bound(TractionBound::Parabolic);
    let single = |c: &Creepages| [c.xi, c.eta, c.phi].iter().filter(|v| **v != 0.0).count() == 1;
    let errs: Vec<f64> = cs
        .iter()
        .filter(|c| single(&c.creep))
        .map(|c| {
            err(
                &ours.forces(&c.patch, &c.creep).unwrap(),
                &c.contact["contact-fastsim"],
                &c.patch,
            )
        })
        .collect();
    assert_eq!(errs.len(), 90);
    let (mean, max, at) = stats(&errs);
    eprintln!(
        "fastsim 40x40 grid vs CONTACT's FASTSIM, {} single-creepage cases: mean {mean:.4} max {max:.4} (their {at}th)",
        errs.len()
    );
    assert!(mean < 5e-3 && max < 2e-2, "mean {mean} max {max} at {at}");
}

/// The error level of the published approximate methods on this case set,
/// as CONTACT computes them (printed, and checked in
/// [`reference_file_is_sound`]), and what each of our laws reaches. Measured
/// (mean, max of |ΔF|/(μN)) and the tolerance of each law:
/// - FASTSIM 10 × 10 (0.043, 0.23), FastSim_SA 10 × 10 (0.043, 0.23),
///   FastSim_A integrated (0.039, 0.20): FASTSIM's known error against the
///   exact theory is 5–15 % of the force over creepage, more under large
///   spin (Kalker 1982; Vollebregt 2014); CONTACT's own FASTSIM measures
///   (0.022, 0.097) here, its sliding direction being better at spin (see
///   [`fastsim_matches_contacts_fastsim`]). Tolerance (0.05, 0.25).
/// - FastSim_A continuation (0.111, 0.67): the paper's closed form is poor
///   at large spin (issue 17: 124 % against fine FASTSIM). Tolerance (0.13,
///   0.75), a guard only.
/// - Polach 1999 (0.088, 0.61): Kalker's coefficients with a closed-form
///   saturation, spin by an empirical term that misses large flange spin.
///   Tolerance (0.10, 0.70), a guard only.
/// - Strip theory (0.085, 0.45): at FaStrip's level without spin, poor with
///   spin (see [`strip_theory_at_fastrips_level_without_spin`]). Tolerance
///   (0.10, 0.50), a guard only.
/// - Kalker (linear, never saturates; at 5 × the sliding creepage it is
///   several μN off) and the Mueller laws (no spin; the paper's slope is
///   empirical, about 3 × Kalker's): sanity bounds only, the error is the
///   law's nature.
#[test]
fn every_law_against_the_exact_theory() {
    let cs = cases();
    eprintln!(
        "|ΔF|/(μN) against CONTACT's exact theory, {} cases:",
        cs.len()
    );
    let mut prefixes: Vec<&String> = cs[0].contact.keys().collect();
    prefixes.sort();
    for p in prefixes {
        let errs: Vec<f64> = cs
            .iter()
            .map(|c| err(&c.contact[p], &c.exact, &c.patch))
            .collect();
        let (mean, max, at) = stats(&errs);
        eprintln!("  {p:<45} mean {mean:.4}  max {max:.4} (case {at})");
    }
    let mut failures = Vec::new();
    for spec in CreepLawSpec::every_law() {
        let law = spec.build().unwrap();
        let (mean, max, at) = stats(&law_errors(law.as_ref(), &cs));
        let name = spec.to_string();
        eprintln!("  {name:<45} mean {mean:.4}  max {max:.4} (case {at})");
        let (tm, tx) = tolerance(&spec);
        if !(mean <= tm && max <= tx) {
            failures.push(format!(
                "{name}: mean {mean:.4} (≤ {tm}), max {max:.4} (≤ {tx}), case {at}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// (mean, max) tolerance of |ΔF|/(μN) per law; see
/// [`every_law_against_the_exact_theory`].
fn tolerance(spec: &CreepLawSpec) -> (f64, f64) {
    use railmbs_wheelrail::creep::SlidingZone;
    match spec {
        CreepLawSpec::Fastsim { .. } | CreepLawSpec::FastsimSa { .. } => (0.05, 0.25),
        CreepLawSpec::FastsimA {
            sliding: SlidingZone::Continuation,
            ..
        } => (0.13, 0.75),
        CreepLawSpec::FastsimA { .. } => (0.05, 0.25),
        CreepLawSpec::Polach { .. } => (0.10, 0.70),
        CreepLawSpec::Kalker => (1.5, 10.0),
        CreepLawSpec::Mueller { .. } | CreepLawSpec::MuellerKalkerSaturated { .. } => (0.6, 1.5),
        // Spin enters as an equivalent strip creepage (see `strip.rs`):
        // a guard here; its creepage cases are held to FaStrip's level in
        // `strip_theory_at_fastrips_level_without_spin`.
        CreepLawSpec::Strip { .. } => (0.10, 0.50),
    }
}

/// The strip law without spin, the 90 cases of pure and combined creepage:
/// strip theory with Kalker's coefficients is exact in the linear limit and
/// at full sliding, and Carter's two-dimensional solution per strip in
/// between. Measured: pure ξ or η (60 cases) mean 0.0030, max 0.0114, as
/// CONTACT's original FaStrip (0.0034, 0.0110) and better than CONTACT's
/// FASTSIM (0.0101, 0.0333); with ξ and η together (one slip direction per
/// strip, Kalker's normalized one, which at full sliding differs from the
/// rigid slip's by the ratio C11/C22) max 0.13 at a/b = 0.2. Tolerance:
/// pure creepage mean 0.005, max 0.015 (FaStrip's level); all 90 mean 0.012,
/// max 0.15.
#[test]
fn strip_theory_at_fastrips_level_without_spin() {
    let cs = cases();
    let law = railmbs_wheelrail::creep::StripTheory::new(10).unwrap();
    let no_spin: Vec<&Case> = cs.iter().filter(|c| c.creep.phi == 0.0).collect();
    let pure: Vec<&Case> = no_spin
        .iter()
        .copied()
        .filter(|c| c.creep.xi == 0.0 || c.creep.eta == 0.0)
        .collect();
    assert_eq!((no_spin.len(), pure.len()), (90, 60));
    let errs = |set: &[&Case], f: &dyn Fn(&Case) -> CreepForces| -> Vec<f64> {
        set.iter().map(|c| err(&f(c), &c.exact, &c.patch)).collect()
    };
    let ours = |c: &Case| law.forces(&c.patch, &c.creep).unwrap();
    let fastrip = |c: &Case| c.contact["contact-fastrip"];
    let (pm, px, pa) = stats(&errs(&pure, &ours));
    let (nm, nx, na) = stats(&errs(&no_spin, &ours));
    let (fm, fx, _) = stats(&errs(&pure, &fastrip));
    eprintln!(
        "strip 10, pure creepage: mean {pm:.4} max {px:.4} (CONTACT's FaStrip {fm:.4}, {fx:.4}); \
         no spin: mean {nm:.4} max {nx:.4}"
    );
    assert!(pm < 0.005 && px < 0.015, "pure: mean {pm} max {px} at {pa}");
    assert!(
        nm < 0.012 && nx < 0.15,
        "no spin: mean {nm} max {nx} at {na}"
    );
}
