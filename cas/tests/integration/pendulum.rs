//! The planar double pendulum (two-link arm) derived symbolically with the crate, checked
//! against the textbook closed form (M. W. Spong, S. Hutchinson, M. Vidyasagar, "Robot Modeling
//! and Control", 2006, Sect. 7.4.1, two-link planar arm with centres of mass at lc = l/2):
//!
//! M₁₁ = m₁lc₁² + m₂(l₁² + lc₂² + 2l₁lc₂ cos q₂) + I₁ + I₂
//! M₁₂ = m₂(lc₂² + l₁lc₂ cos q₂) + I₂,  M₂₂ = m₂lc₂² + I₂
//! k₁ = h(2q̇₁q̇₂ + q̇₂²),  k₂ = −h q̇₁²,  h = −m₂l₁lc₂ sin q₂
//!
//! (q₁ absolute angle of link 1, q₂ angle of link 2 relative to link 1.)

use railmbs_cas::{Context, ExprId, Program, Symbol, Values};

/// M (upper triangle, row-major) and k of a planar n-link chain by the direct method:
/// M = Σ mᵢJᵢᵀJᵢ + IᵢJωᵢᵀJωᵢ, k = Σ mᵢJᵢᵀ(J̇ᵢv). Parameters per link: l = p[3i], m = p[3i+1],
/// I = p[3i+2].
fn chain(c: &mut Context, n: usize) -> (Vec<ExprId>, Vec<ExprId>) {
    let q: Vec<ExprId> = (0..n as u32).map(|i| c.q(i)).collect();
    let v: Vec<ExprId> = (0..n as u32).map(|i| c.v(i)).collect();
    let qs: Vec<Symbol> = (0..n as u32).map(Symbol::q).collect();
    let par = |c: &mut Context, i: usize, k: u32| c.p(3 * i as u32 + k);
    let mut centres = Vec::new();
    for i in 0..n {
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        for j in 0..=i {
            let phi = c.add_many(&q[..=j]);
            let (co, s) = (c.cos(phi), c.sin(phi));
            let l = par(c, j, 0);
            let w = if j == i { 0.5 } else { 1.0 };
            xs.push((c.mul(l, co), w));
            ys.push((c.mul(l, s), w));
        }
        centres.push((c.sum(0.0, &xs), c.sum(0.0, &ys)));
    }
    let jac: Vec<Vec<(ExprId, ExprId)>> = centres
        .iter()
        .map(|&(x, y)| qs.iter().map(|&s| (c.diff(x, s), c.diff(y, s))).collect())
        .collect();
    let mut m_out = Vec::new();
    for a in 0..n {
        for b in a..n {
            let mut terms = Vec::new();
            for (i, row) in jac.iter().enumerate().skip(b) {
                let (p1, p2) = (c.mul(row[a].0, row[b].0), c.mul(row[a].1, row[b].1));
                let dot = c.add(p1, p2);
                let m = par(c, i, 1);
                let inertia = par(c, i, 2);
                terms.push(c.mul(m, dot));
                terms.push(inertia);
            }
            m_out.push(c.add_many(&terms));
        }
    }
    let mut k_out = Vec::new();
    for a in 0..n {
        let mut terms = Vec::new();
        for (i, row) in jac.iter().enumerate().skip(a) {
            let vx: Vec<ExprId> = row.iter().zip(&v).map(|(j, &vk)| c.mul(j.0, vk)).collect();
            let vy: Vec<ExprId> = row.iter().zip(&v).map(|(j, &vk)| c.mul(j.1, vk)).collect();
            let (vx, vy) = (c.add_many(&vx), c.add_many(&vy));
            let mut ax = Vec::new();
            let mut ay = Vec::new();
            for (k, &s) in qs.iter().enumerate() {
                let (dx, dy) = (c.diff(vx, s), c.diff(vy, s));
                ax.push(c.mul(dx, v[k]));
                ay.push(c.mul(dy, v[k]));
            }
            let (ax, ay) = (c.add_many(&ax), c.add_many(&ay));
            let (p1, p2) = (c.mul(row[a].0, ax), c.mul(row[a].1, ay));
            let dot = c.add(p1, p2);
            let m = par(c, i, 1);
            terms.push(c.mul(m, dot));
        }
        k_out.push(c.add_many(&terms));
    }
    (m_out, k_out)
}

#[test]
fn double_pendulum_matches_textbook() {
    let mut c = Context::new();
    let (m, k) = chain(&mut c, 2);
    // M₂₂ = I₂ + m₂l₂²/4 exactly, by the sin²+cos² rule
    let (l2, m2, i2) = (c.p(3), c.p(4), c.p(5));
    let l2sq = c.powi(l2, 2);
    let ml = c.mul(m2, l2sq);
    let want = c.sum(0.0, &[(i2, 1.0), (ml, 0.25)]);
    assert_eq!(m[2], want, "M22 = {}", c.display(m[2]));

    let mut outs = m.clone();
    outs.extend(&k);
    let prog = Program::compile(&c, &outs);
    let cases = [
        ([0.3, -0.7], [1.1, -0.4], [1.2, 3.0, 0.4, 0.8, 2.0, 0.1]),
        ([-2.0, 2.5], [-0.3, 2.2], [0.5, 1.0, 0.02, 1.5, 0.7, 0.3]),
    ];
    for (q, v, p) in cases {
        let vals = Values {
            q: &q,
            v: &v,
            p: &p,
            ..Default::default()
        };
        let got = prog.eval(&vals).unwrap();
        let dag = c.eval(&outs, &vals).unwrap();
        let (l1, m1, i1, l2, m2, i2) = (p[0], p[1], p[2], p[3], p[4], p[5]);
        let (lc1, lc2) = (l1 / 2.0, l2 / 2.0);
        let c2 = q[1].cos();
        let h = -m2 * l1 * lc2 * q[1].sin();
        let want = [
            m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2.0 * l1 * lc2 * c2) + i1 + i2,
            m2 * (lc2 * lc2 + l1 * lc2 * c2) + i2,
            m2 * lc2 * lc2 + i2,
            h * (2.0 * v[0] * v[1] + v[1] * v[1]),
            -h * v[0] * v[0],
        ];
        for i in 0..5 {
            // Different but equivalent formulas: rounding of ~30 operations on O(10) values;
            // 1e-13 relative to the largest magnitude involved (~10) is ~ 20 ε.
            let scale = 10.0;
            assert!(
                (got[i] - want[i]).abs() <= 1e-13 * scale,
                "{i}: {} vs {}",
                got[i],
                want[i]
            );
            assert!(
                (dag[i] - want[i]).abs() <= 1e-13 * scale,
                "{i}: {} vs {}",
                dag[i],
                want[i]
            );
        }
    }
}
