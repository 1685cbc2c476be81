//! Mass and inertia checks of a body: mass positive, inertia tensor positive
//! definite and physically realizable.

use super::super::*;

impl Cx<'_> {
    /// Mass positive; inertia positive definite and physically realizable
    /// (principal moments satisfy the triangle inequality), with default parameters.
    pub(super) fn check_mass(&mut self, w: &Where, mass: &Expr, inertia: &[Expr; 6]) {
        let Some(d) = self.defaults.clone() else {
            return;
        };
        let i = inertia.each_ref().map(|e| e.eval(&d, 0.0));
        for (field, message) in mass_problems(mass.eval(&d, 0.0), i) {
            self.err(w, Some(field), None, message);
        }
    }
}

/// What is wrong with a body of mass `m` (kg) and inertia `i` (kg m²: ixx,
/// iyy, izz, ixy, ixz, iyz): (field, message) for a mass that is not
/// positive, an inertia tensor that is not positive definite or whose
/// principal moments violate the triangle inequality (no rigid body has
/// them). Non-finite values are left to the callers' own finiteness checks.
pub(crate) fn mass_problems(m: f64, i: [f64; 6]) -> Vec<(&'static str, String)> {
    let mut problems = Vec::new();
    if m.is_finite() && m <= 0.0 {
        problems.push(("mass", format!("mass must be positive, got {m}")));
    }
    if i.iter().any(|x| !x.is_finite()) {
        return problems;
    }
    let (ixx, iyy, izz) = (i[0], i[1], i[2]);
    // Relative slack for rounding in the parameters' expressions.
    let slack = 1e-9 * (ixx.abs() + iyy.abs() + izz.abs());
    for (a, b, c, na, nb, nc) in [
        (ixx, iyy, izz, "ixx", "iyy", "izz"),
        (iyy, izz, ixx, "iyy", "izz", "ixx"),
        (izz, ixx, iyy, "izz", "ixx", "iyy"),
    ] {
        if a + b < c - slack {
            problems.push((
                "inertia",
                format!(
                    "inertia violates the triangle inequality: {na} + {nb} = {} < {nc} = {c}",
                    a + b
                ),
            ));
            return problems;
        }
    }
    let ev = sym3_eigenvalues([[ixx, i[3], i[4]], [i[3], iyy, i[5]], [i[4], i[5], izz]]);
    if ev.iter().any(|&l| l <= 0.0) {
        problems.push((
            "inertia",
            format!("inertia tensor is not positive definite: principal moments {ev:?} kg m²"),
        ));
        return problems;
    }
    let [a, b, c] = ev;
    if a + b < c - slack || b + c < a - slack || c + a < b - slack {
        problems.push((
            "inertia",
            format!(
                "inertia violates the triangle inequality for its principal moments {ev:?} kg m²"
            ),
        ));
    }
    problems
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending (closed form, O. K. Smith,
/// "Eigenvalues of a symmetric 3 × 3 matrix", CACM 4(4), 1961).
fn sym3_eigenvalues(a: [[f64; 3]; 3]) -> [f64; 3] {
    let p1 = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
    let mut ev = if p1 == 0.0 {
        [a[0][0], a[1][1], a[2][2]]
    } else {
        let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
        let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let b = |i: usize, j: usize| (a[i][j] - if i == j { q } else { 0.0 }) / p;
        let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(2, 1))
            - b(0, 1) * (b(1, 0) * b(2, 2) - b(1, 2) * b(2, 0))
            + b(0, 2) * (b(1, 0) * b(2, 1) - b(1, 1) * b(2, 0));
        let r = (det / 2.0).clamp(-1.0, 1.0);
        let phi = r.acos() / 3.0;
        let e1 = q + 2.0 * p * phi.cos();
        let e3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
        [e1, 3.0 * q - e1 - e3, e3]
    };
    ev.sort_by(f64::total_cmp);
    ev
}
