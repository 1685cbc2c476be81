//! Small symbolic 3-vectors and 3×3 matrices for kinematics: elementary rotations and their
//! products, matrix–vector products, cross and dot products.
//!
//! Convention: `rot_x(a)`, `rot_y(a)`, `rot_z(a)` are the direction cosine matrices of a frame
//! rotated by the angle `a` (rad, right-handed) about the x, y, z axis of its parent frame:
//! they map coordinates in the rotated frame to coordinates in the parent frame
//! (`r_parent = A · r_body`), as in the recursive kinematics of Pogorelov 2005, Sect. 2.1.

use crate::graph::{Context, ExprId, ONE, ZERO};

/// A symbolic 3-vector.
pub type Vec3 = [ExprId; 3];
/// A symbolic 3×3 matrix, row-major (`m[row][column]`).
pub type Mat3 = [[ExprId; 3]; 3];

/// The 3×3 identity matrix.
pub const IDENTITY: Mat3 = [[ONE, ZERO, ZERO], [ZERO, ONE, ZERO], [ZERO, ZERO, ONE]];

impl Context {
    /// Rotation about x by `a` (rad): `[[1,0,0],[0,c,−s],[0,s,c]]`.
    pub fn rot_x(&mut self, a: ExprId) -> Mat3 {
        let (s, c) = (self.sin(a), self.cos(a));
        let ms = self.neg(s);
        [[ONE, ZERO, ZERO], [ZERO, c, ms], [ZERO, s, c]]
    }

    /// Rotation about y by `a` (rad): `[[c,0,s],[0,1,0],[−s,0,c]]`.
    pub fn rot_y(&mut self, a: ExprId) -> Mat3 {
        let (s, c) = (self.sin(a), self.cos(a));
        let ms = self.neg(s);
        [[c, ZERO, s], [ZERO, ONE, ZERO], [ms, ZERO, c]]
    }

    /// Rotation about z by `a` (rad): `[[c,−s,0],[s,c,0],[0,0,1]]`.
    pub fn rot_z(&mut self, a: ExprId) -> Mat3 {
        let (s, c) = (self.sin(a), self.cos(a));
        let ms = self.neg(s);
        [[c, ms, ZERO], [s, c, ZERO], [ZERO, ZERO, ONE]]
    }

    /// Matrix product `a·b`.
    pub fn mat_mul(&mut self, a: &Mat3, b: &Mat3) -> Mat3 {
        let mut out = [[ZERO; 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, e) in row.iter_mut().enumerate() {
                let col = [b[0][j], b[1][j], b[2][j]];
                *e = self.dot(&a[i], &col);
            }
        }
        out
    }

    /// Transpose (the inverse of a rotation matrix).
    pub fn transpose(&self, a: &Mat3) -> Mat3 {
        let mut out = [[ZERO; 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, e) in row.iter_mut().enumerate() {
                *e = a[j][i];
            }
        }
        out
    }

    /// Matrix–vector product `a·v`.
    pub fn mat_vec(&mut self, a: &Mat3, v: &Vec3) -> Vec3 {
        [self.dot(&a[0], v), self.dot(&a[1], v), self.dot(&a[2], v)]
    }

    /// `aᵀ·v` (for a rotation matrix: parent-frame vector to body-frame coordinates).
    pub fn mat_t_vec(&mut self, a: &Mat3, v: &Vec3) -> Vec3 {
        let t = self.transpose(a);
        self.mat_vec(&t, v)
    }

    /// Dot product.
    pub fn dot(&mut self, a: &Vec3, b: &Vec3) -> ExprId {
        let p = [
            self.mul(a[0], b[0]),
            self.mul(a[1], b[1]),
            self.mul(a[2], b[2]),
        ];
        self.add_many(&p)
    }

    /// Cross product `a × b`.
    pub fn cross(&mut self, a: &Vec3, b: &Vec3) -> Vec3 {
        let mut out = [ZERO; 3];
        for (i, e) in out.iter_mut().enumerate() {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let p = self.mul(a[j], b[k]);
            let q = self.mul(a[k], b[j]);
            *e = self.sub(p, q);
        }
        out
    }

    /// Sum of vectors.
    pub fn vec_add(&mut self, a: &Vec3, b: &Vec3) -> Vec3 {
        [
            self.add(a[0], b[0]),
            self.add(a[1], b[1]),
            self.add(a[2], b[2]),
        ]
    }

    /// `c·a` for a vector.
    pub fn vec_scale(&mut self, c: ExprId, a: &Vec3) -> Vec3 {
        [self.mul(c, a[0]), self.mul(c, a[1]), self.mul(c, a[2])]
    }
}
