//! A creep-force curve: lateral force against lateral creepage by any law.
//!
//! The law is named as on the command line (`umsim creep --method`), here
//! FastSim_A with 20 strips; the contact patch is Hertz's for a 0.46 m wheel on
//! a rail of 0.3 m crown radius under 100 kN (Johnson 1985, Sect. 4.2). At small
//! creepage the force follows Kalker's linear theory, F_y = −G a b C₂₂ η
//! (Kalker 1990, Table E.3); at large creepage it saturates at μN.
//!
//! ```sh
//! cargo run --release -p railmbs-examples --example creep_curve [LAW]
//! ```

use railmbs_wheelrail::creep::{ContactPatch, CreepLaw, CreepLawSpec, Creepages, KalkerLinear};
use railmbs_wheelrail::hertz::{HertzShape, wheel_rail_curvatures};
use std::error::Error;

fn main() -> Result<(), Box<dyn Error>> {
    let law: CreepLawSpec = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "fastsim-a:20".into())
        .parse()?;
    let creep = law.build()?;

    // Hertz patch: wheel radius 0.46 m, flat wheel tread, rail crown 0.3 m.
    let (e, nu, n) = (2.1e11, 0.28, 100e3);
    let (curv_a, curv_b) = wheel_rail_curvatures(0.46, 0.0, 1.0 / 0.3);
    let hertz = HertzShape::new(curv_a, curv_b, e, nu)?.contact(n)?;
    let patch = ContactPatch {
        a: hertz.a,
        b: hertz.b,
        g: e / (2.0 * (1.0 + nu)),
        nu,
        mu: 0.3,
        n,
    };
    println!(
        "law {law}; patch a = {:.2} mm, b = {:.2} mm",
        1e3 * patch.a,
        1e3 * patch.b
    );
    println!("{:>10} {:>12} {:>12}", "eta [-]", "Fy [N]", "Fy/(mu N)");
    let linear = KalkerLinear;
    for k in 0..=20 {
        let eta = 2e-4 * k as f64;
        let c = Creepages {
            xi: 0.0,
            eta,
            phi: 0.0,
        };
        let f = creep.forces(&patch, &c)?;
        println!(
            "{eta:>10.4} {:>12.1} {:>12.4}",
            f.fy,
            f.fy / (patch.mu * patch.n)
        );
        // Bounded by Coulomb's limit everywhere.
        if f.fy.abs() > patch.mu * patch.n * (1.0 + 1e-9) {
            return Err(format!("|Fy| = {} N above μN at η = {eta}", f.fy.abs()).into());
        }
    }
    // At η = 1e-6 every law is in its linear range: within 1 % of Kalker's slope.
    let small = Creepages {
        xi: 0.0,
        eta: 1e-6,
        phi: 0.0,
    };
    let (f, f_lin) = (
        creep.forces(&patch, &small)?,
        linear.forces(&patch, &small)?,
    );
    if (f.fy - f_lin.fy).abs() > 0.01 * f_lin.fy.abs() {
        return Err(format!("Fy = {} N at η = 1e-6, linear theory {} N", f.fy, f_lin.fy).into());
    }
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}
