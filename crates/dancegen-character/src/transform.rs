//! Node transforms of a glTF character: translation/rotation/scale and general affine maps.
//!
//! glTF nodes carry either `matrix` (column-major 4×4) or `translation`/`rotation`/`scale`, and
//! exporters put real scale in the hierarchy (FBX2glTF writes a 100× or 0.01× armature node), so
//! positions go through full affine maps. Rotations of bones are composed separately, without
//! scale (see `scene.rs`), which is exact for uniform positive scales — the case of every
//! armature we know of.

use dancegen_motion::rotation::{Mat3, Quat};
use dancegen_motion::vec3::{add, cross, dot, norm};

/// A node's local transform as glTF's `T · R · S`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trs {
    pub translation: [f64; 3],
    pub rotation: Quat,
    pub scale: [f64; 3],
}

impl Trs {
    pub const IDENTITY: Trs = Trs {
        translation: [0.0; 3],
        rotation: Quat::IDENTITY,
        scale: [1.0; 3],
    };

    /// The affine map `T · R · S`.
    pub fn to_affine(&self) -> Affine {
        let r = self.rotation.to_mat3().0;
        let s = self.scale;
        let mut l = [[0.0; 3]; 3];
        for (i, row) in l.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                *cell = r[i][j] * s[j];
            }
        }
        Affine {
            linear: Mat3(l),
            translation: self.translation,
        }
    }

    /// Splits a glTF `matrix` (16 numbers, column-major) into `T · R · S`. A mirroring matrix
    /// (negative determinant) puts the sign on the x scale; shear, which TRS cannot hold, is
    /// dropped by taking the nearest rotation.
    pub fn from_column_major(m: &[f64; 16]) -> Trs {
        let col = |c: usize| [m[4 * c], m[4 * c + 1], m[4 * c + 2]];
        let (c0, c1, c2) = (col(0), col(1), col(2));
        let mut s = [norm(c0), norm(c1), norm(c2)];
        if dot(cross(c0, c1), c2) < 0.0 {
            s[0] = -s[0];
        }
        let safe = |v: f64| if v.abs() < 1e-300 { 1.0 } else { v };
        let r = Mat3([
            [c0[0] / safe(s[0]), c1[0] / safe(s[1]), c2[0] / safe(s[2])],
            [c0[1] / safe(s[0]), c1[1] / safe(s[1]), c2[1] / safe(s[2])],
            [c0[2] / safe(s[0]), c1[2] / safe(s[1]), c2[2] / safe(s[2])],
        ]);
        Trs {
            translation: [m[12], m[13], m[14]],
            rotation: r.to_quat(),
            scale: s,
        }
    }
}

/// `x ↦ linear · x + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Affine {
    pub linear: Mat3,
    pub translation: [f64; 3],
}

impl Affine {
    pub const IDENTITY: Affine = Affine {
        linear: Mat3::IDENTITY,
        translation: [0.0; 3],
    };

    /// `self · rhs` (apply `rhs` first).
    pub fn mul(&self, rhs: &Affine) -> Affine {
        Affine {
            linear: self.linear.mul(&rhs.linear),
            translation: self.point(rhs.translation),
        }
    }

    /// Maps a point.
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        add(self.linear.mul_vec(p), self.translation)
    }

    /// The inverse map, or `None` when the linear part is singular (a zero scale).
    pub fn inverse(&self) -> Option<Affine> {
        let inv = inverse3(&self.linear)?;
        let t = inv.mul_vec(self.translation);
        Some(Affine {
            linear: inv,
            translation: [-t[0], -t[1], -t[2]],
        })
    }
}

/// General 3×3 inverse by the adjugate; `None` when the determinant is (relatively) zero.
fn inverse3(m: &Mat3) -> Option<Mat3> {
    let a = &m.0;
    let det = m.determinant();
    let size = a.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    if !det.is_finite() || det.abs() <= 1e-12 * size * size * size || size == 0.0 {
        return None;
    }
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0];
    let adj = [
        [c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2)],
        [-c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2)],
        [c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1)],
    ];
    Some(Mat3(adj.map(|row| row.map(|v| v / det))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9)
    }

    #[test]
    fn matrix_round_trips_through_trs() {
        let trs = Trs {
            translation: [1.0, -2.0, 0.5],
            rotation: Quat::from_axis_angle([0.3, -0.7, 0.2]),
            scale: [0.01, 0.02, 0.03],
        };
        let a = trs.to_affine();
        let mut m = [0.0; 16];
        for c in 0..3 {
            for r in 0..3 {
                m[4 * c + r] = a.linear.0[r][c];
            }
        }
        m[12..15].copy_from_slice(&a.translation);
        m[15] = 1.0;
        let back = Trs::from_column_major(&m).to_affine();
        for p in [[1.0, 2.0, 3.0], [-0.5, 0.0, 4.0]] {
            assert!(close(a.point(p), back.point(p)));
        }
    }

    #[test]
    fn inverse_undoes_scaled_rotation() {
        let a = Trs {
            translation: [0.0, 3.0, -1.0],
            rotation: Quat::from_axis_angle([-std::f64::consts::FRAC_PI_2, 0.0, 0.0]),
            scale: [100.0, 100.0, 100.0],
        }
        .to_affine();
        let inv = a.inverse().unwrap();
        let p = [0.2, -0.4, 7.0];
        assert!(close(inv.point(a.point(p)), p));
        assert!(close(a.mul(&inv).point(p), p));
        let zero = Trs {
            scale: [0.0, 1.0, 1.0],
            ..Trs::IDENTITY
        };
        assert!(zero.to_affine().inverse().is_none());
    }
}
