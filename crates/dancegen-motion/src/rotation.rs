//! Rotations: quaternions, 3×3 matrices, axis-angle, the 6D representation and Euler angles.
//!
//! Every representation follows [`crate::conventions`]: matrices act on column vectors
//! (`v' = R v`), quaternions are real-first `(w, x, y, z)` like pytorch3d, axis-angle is the
//! Rodrigues vector (unit axis × angle in radians) and 6D is the first two **rows** of the matrix
//! (pytorch3d `matrix_to_rotation_6d`, anchors.md C.2). Scalars are `f64`; the batched helpers at
//! the bottom take and return flat `f32` slices because that is what representation code and
//! model tensors use.

use std::f64::consts::PI;

use crate::vec3::{cross, dot, norm, scale};

/// Below this angle (radians) the trigonometric ratios are replaced by their Taylor series, so
/// that `sin θ / θ` and friends never divide by a tiny number. At 1e-4 the first dropped term is
/// of order θ⁴/120 ≈ 1e-18, below `f64` resolution.
const SMALL_ANGLE: f64 = 1e-4;

/// A unit quaternion `w + xi + yj + zk`, stored real-first (pytorch3d order, anchors.md C.2).
///
/// `q` and `-q` are the same rotation; functions that return quaternions do not canonicalise the
/// sign unless they say so.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quat {
    pub w: f64,
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// A 3×3 rotation matrix, row-major: `self.0[row][col]`. It acts on column vectors, `v' = R v`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mat3(pub [[f64; 3]; 3]);

/// Error for malformed Euler channel orders.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid Euler order {order:?}: expected three distinct axes from X, Y, Z (e.g. \"ZXY\")")]
pub struct EulerOrderError {
    pub order: String,
}

/// Normalises like `torch.nn.functional.normalize` (divide by `max(|v|, eps)`), so a zero input
/// gives a zero output instead of NaN, matching what pytorch3d's 6D decoder would produce.
#[inline]
fn normalize_eps(v: [f64; 3]) -> [f64; 3] {
    let n = dot(v, v).sqrt().max(1e-12);
    [v[0] / n, v[1] / n, v[2] / n]
}

impl Quat {
    pub const IDENTITY: Quat = Quat {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    pub const fn new(w: f64, x: f64, y: f64, z: f64) -> Self {
        Quat { w, x, y, z }
    }

    /// The conjugate, which is the inverse for unit quaternions.
    #[inline]
    pub fn conjugate(self) -> Quat {
        Quat {
            w: self.w,
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }

    #[inline]
    pub fn dot(self, rhs: Quat) -> f64 {
        self.w * rhs.w + self.x * rhs.x + self.y * rhs.y + self.z * rhs.z
    }

    #[inline]
    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }

    /// Scales to unit length; the zero quaternion becomes the identity rather than NaN.
    #[inline]
    pub fn normalize(self) -> Quat {
        let n = self.norm();
        if n < 1e-300 {
            return Quat::IDENTITY;
        }
        Quat {
            w: self.w / n,
            x: self.x / n,
            y: self.y / n,
            z: self.z / n,
        }
    }

    /// Returns the sign representative with `w >= 0` (rotation angle in `[0, π]`).
    #[inline]
    pub fn canonical(self) -> Quat {
        if self.w < 0.0 { -self } else { self }
    }

    /// Rotates a vector, `q v q*`, without building the matrix.
    #[inline]
    pub fn rotate(self, v: [f64; 3]) -> [f64; 3] {
        let u = [self.x, self.y, self.z];
        let t = cross(u, v);
        let t = [2.0 * t[0], 2.0 * t[1], 2.0 * t[2]];
        let c = cross(u, t);
        [
            v[0] + self.w * t[0] + c[0],
            v[1] + self.w * t[1] + c[1],
            v[2] + self.w * t[2] + c[2],
        ]
    }

    /// From a Rodrigues vector. Uses the Taylor series of `sin(θ/2)/θ` near zero so tiny
    /// rotations keep full precision.
    pub fn from_axis_angle(v: [f64; 3]) -> Quat {
        let theta2 = dot(v, v);
        let theta = theta2.sqrt();
        let (w, k) = if theta < SMALL_ANGLE {
            (1.0 - theta2 / 8.0, 0.5 - theta2 / 48.0)
        } else {
            let half = 0.5 * theta;
            (half.cos(), half.sin() / theta)
        };
        Quat {
            w,
            x: v[0] * k,
            y: v[1] * k,
            z: v[2] * k,
        }
    }

    /// To a Rodrigues vector with angle in `[0, π]`. Uses `θ = 2·atan2(|xyz|, w)`, which stays
    /// accurate both near 0 (where `acos(w)` loses half the digits) and near π (where `w → 0`).
    pub fn to_axis_angle(self) -> [f64; 3] {
        let q = self.canonical();
        let n2 = q.x * q.x + q.y * q.y + q.z * q.z;
        let n = n2.sqrt();
        let k = if n < 0.5 * SMALL_ANGLE * q.w.abs().max(1e-300) {
            // θ/n = 2·atan(n/w)/n ≈ (2/w)·(1 − n²/(3w²)).
            let w = q.w;
            (2.0 / w) * (1.0 - n2 / (3.0 * w * w))
        } else {
            2.0 * n.atan2(q.w) / n
        };
        [q.x * k, q.y * k, q.z * k]
    }

    /// Rotation matrix (column-vector convention).
    pub fn to_mat3(self) -> Mat3 {
        let Quat { w, x, y, z } = self;
        Mat3([
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ])
    }

    /// Spherical linear interpolation along the shortest arc (`b` is negated when `a·b < 0`).
    /// `t = 0` gives `a`, `t = 1` gives `b` (or `-b`, the same rotation). Nearly parallel inputs
    /// fall back to normalised linear interpolation, where slerp's `1/sin Ω` is ill-conditioned.
    pub fn slerp(a: Quat, b: Quat, t: f64) -> Quat {
        let mut b = b;
        let mut d = a.dot(b);
        if d < 0.0 {
            b = -b;
            d = -d;
        }
        let (s0, s1) = if d > 0.9995 {
            (1.0 - t, t)
        } else {
            let omega = d.min(1.0).acos();
            let so = omega.sin();
            (((1.0 - t) * omega).sin() / so, (t * omega).sin() / so)
        };
        Quat {
            w: s0 * a.w + s1 * b.w,
            x: s0 * a.x + s1 * b.x,
            y: s0 * a.y + s1 * b.y,
            z: s0 * a.z + s1 * b.z,
        }
        .normalize()
    }
}

/// Hamilton product `a ⊗ b`: the rotation that applies `b` first, then `a`.
impl std::ops::Mul for Quat {
    type Output = Quat;
    #[inline]
    fn mul(self, b: Quat) -> Quat {
        let a = self;
        Quat {
            w: a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
            x: a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            y: a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            z: a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
        }
    }
}

/// Negation: the same rotation, opposite sign representative.
impl std::ops::Neg for Quat {
    type Output = Quat;
    #[inline]
    fn neg(self) -> Quat {
        Quat {
            w: -self.w,
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// Matrix product, same as [`Mat3::mul`].
impl std::ops::Mul for Mat3 {
    type Output = Mat3;
    #[inline]
    fn mul(self, rhs: Mat3) -> Mat3 {
        Mat3::mul(&self, &rhs)
    }
}

impl Mat3 {
    pub const IDENTITY: Mat3 = Mat3([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);

    /// The smallest rotation taking direction `from` to direction `to` (identity if either is
    /// zero; a half turn about an axis perpendicular to `from` if they are opposite).
    pub fn between(from: [f64; 3], to: [f64; 3]) -> Mat3 {
        let (nf, nt) = (norm(from), norm(to));
        if nf < 1e-12 || nt < 1e-12 {
            return Mat3::IDENTITY;
        }
        let c = cross(from, to);
        let s = norm(c);
        let angle = s.atan2(dot(from, to));
        if s < 1e-12 {
            if angle.abs() < 1e-6 {
                return Mat3::IDENTITY;
            }
            let helper = if from[0].abs() < 0.9 * nf {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let axis = cross(from, helper);
            return Mat3::from_axis_angle(scale(axis, PI / norm(axis)));
        }
        Mat3::from_axis_angle(scale(c, angle / s))
    }

    /// Matrix product `self · rhs` (apply `rhs` first, then `self`, to column vectors).
    #[inline]
    pub fn mul(&self, rhs: &Mat3) -> Mat3 {
        let a = &self.0;
        let b = &rhs.0;
        let mut r = [[0.0; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                *cell = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
            }
        }
        Mat3(r)
    }

    /// `R v` for a column vector `v`.
    #[inline]
    pub fn mul_vec(&self, v: [f64; 3]) -> [f64; 3] {
        let m = &self.0;
        [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
    }

    #[inline]
    pub fn transpose(&self) -> Mat3 {
        let m = &self.0;
        Mat3([
            [m[0][0], m[1][0], m[2][0]],
            [m[0][1], m[1][1], m[2][1]],
            [m[0][2], m[1][2], m[2][2]],
        ])
    }

    pub fn determinant(&self) -> f64 {
        dot(self.0[0], cross(self.0[1], self.0[2]))
    }

    /// Rotation by `angle` radians about the X (0), Y (1) or Z (2) axis, right-handed.
    ///
    /// # Panics
    /// If `axis > 2`.
    pub fn from_axis_rotation(axis: usize, angle: f64) -> Mat3 {
        let (s, c) = angle.sin_cos();
        match axis {
            0 => Mat3([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]),
            1 => Mat3([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]),
            2 => Mat3([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]),
            _ => panic!("axis index {axis} out of range 0..3"),
        }
    }

    /// Rodrigues' formula `R = I + A·K + B·K²` with `K = [v]×` (un-normalised), `A = sin θ/θ`,
    /// `B = (1 − cos θ)/θ²`; both ratios switch to Taylor series near θ = 0.
    #[inline]
    pub fn from_axis_angle(v: [f64; 3]) -> Mat3 {
        let (x, y, z) = (v[0], v[1], v[2]);
        let theta2 = x * x + y * y + z * z;
        let (a, b) = if theta2 < SMALL_ANGLE * SMALL_ANGLE {
            (1.0 - theta2 / 6.0, 0.5 - theta2 / 24.0)
        } else {
            let theta = theta2.sqrt();
            let (s, c) = theta.sin_cos();
            (s / theta, (1.0 - c) / theta2)
        };
        // K² = v vᵀ − θ² I.
        Mat3([
            [
                1.0 + b * (x * x - theta2),
                b * x * y - a * z,
                b * x * z + a * y,
            ],
            [
                b * x * y + a * z,
                1.0 + b * (y * y - theta2),
                b * y * z - a * x,
            ],
            [
                b * x * z - a * y,
                b * y * z + a * x,
                1.0 + b * (z * z - theta2),
            ],
        ])
    }

    /// Rodrigues vector with angle in `[0, π]`, via [`Mat3::to_quat`] (Shepperd), which is
    /// stable near π where the `(R − Rᵀ)/2 sin θ` formula breaks down.
    pub fn to_axis_angle(&self) -> [f64; 3] {
        self.to_quat().to_axis_angle()
    }

    pub fn from_quat(q: Quat) -> Mat3 {
        q.to_mat3()
    }

    /// Shepperd's method: pick the largest of `w², x², y², z²` to divide by, so the result is
    /// accurate for every rotation. Returns the `w >= 0` representative, normalised.
    pub fn to_quat(&self) -> Quat {
        let m = &self.0;
        let tr = m[0][0] + m[1][1] + m[2][2];
        let q = if tr >= m[0][0] && tr >= m[1][1] && tr >= m[2][2] {
            let s = 2.0 * (1.0 + tr).max(0.0).sqrt();
            Quat::new(
                0.25 * s,
                (m[2][1] - m[1][2]) / s,
                (m[0][2] - m[2][0]) / s,
                (m[1][0] - m[0][1]) / s,
            )
        } else if m[0][0] >= m[1][1] && m[0][0] >= m[2][2] {
            let s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).max(0.0).sqrt();
            Quat::new(
                (m[2][1] - m[1][2]) / s,
                0.25 * s,
                (m[0][1] + m[1][0]) / s,
                (m[0][2] + m[2][0]) / s,
            )
        } else if m[1][1] >= m[2][2] {
            let s = 2.0 * (1.0 - m[0][0] + m[1][1] - m[2][2]).max(0.0).sqrt();
            Quat::new(
                (m[0][2] - m[2][0]) / s,
                (m[0][1] + m[1][0]) / s,
                0.25 * s,
                (m[1][2] + m[2][1]) / s,
            )
        } else {
            let s = 2.0 * (1.0 - m[0][0] - m[1][1] + m[2][2]).max(0.0).sqrt();
            Quat::new(
                (m[1][0] - m[0][1]) / s,
                (m[0][2] + m[2][0]) / s,
                (m[1][2] + m[2][1]) / s,
                0.25 * s,
            )
        };
        q.normalize().canonical()
    }

    /// pytorch3d `matrix_to_rotation_6d`: the first two **rows**, row-major
    /// `[R00, R01, R02, R10, R11, R12]` (anchors.md C.2; not the column layout of Zhou et al.).
    #[inline]
    pub fn to_6d(&self) -> [f64; 6] {
        let m = &self.0;
        [m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2]]
    }

    /// pytorch3d `rotation_6d_to_matrix`: Gram-Schmidt on the two rows, third row = `b1 × b2`
    /// (anchors.md C.2). Any 6 numbers give a proper rotation (zero rows give zeros, like torch).
    #[inline]
    pub fn from_6d(d: &[f64; 6]) -> Mat3 {
        let b1 = normalize_eps([d[0], d[1], d[2]]);
        let a2 = [d[3], d[4], d[5]];
        let p = dot(b1, a2);
        let b2 = normalize_eps([a2[0] - p * b1[0], a2[1] - p * b1[1], a2[2] - p * b1[2]]);
        Mat3([b1, b2, cross(b1, b2)])
    }

    /// Composes `R = R_{order[0]}(angles[0]) · R_{order[1]}(angles[1]) · R_{order[2]}(angles[2])`
    /// (radians), the BVH meaning of a channel list: `"ZXY"` with `[z, x, y]` is `Rz·Rx·Ry`
    /// applied to column vectors, i.e. intrinsic Z then X then Y.
    pub fn from_euler(order: &str, angles: [f64; 3]) -> Result<Mat3, EulerOrderError> {
        let axes = parse_euler_order(order)?;
        let mut r = Mat3::from_axis_rotation(axes[0], angles[0]);
        r = r.mul(&Mat3::from_axis_rotation(axes[1], angles[1]));
        r = r.mul(&Mat3::from_axis_rotation(axes[2], angles[2]));
        Ok(r)
    }

    /// Inverse of [`Mat3::from_euler`]: angles (radians) in the same order as the channel
    /// string, middle angle in `[−π/2, π/2]`. At gimbal lock (middle angle ±π/2) the last
    /// angle is set to 0 and the first absorbs the combined rotation.
    pub fn to_euler(&self, order: &str) -> Result<[f64; 3], EulerOrderError> {
        let [a, b, c] = parse_euler_order(order)?;
        let m = &self.0;
        // Sign of the permutation (a, b, c): +1 for XYZ, YZX, ZXY; −1 for the others.
        let s = if (b + 3 - a) % 3 == 1 { 1.0 } else { -1.0 };
        let sin_mid = (s * m[a][c]).clamp(-1.0, 1.0);
        let cos_mid = (m[a][a] * m[a][a] + m[a][b] * m[a][b]).sqrt();
        let mid = sin_mid.atan2(cos_mid);
        if cos_mid > 1e-9 {
            let first = (-s * m[b][c]).atan2(m[c][c]);
            let last = (-s * m[a][b]).atan2(m[a][a]);
            Ok([first, mid, last])
        } else {
            let first = (s * m[c][b]).atan2(m[b][b]);
            Ok([first, mid, 0.0])
        }
    }
}

/// Parses a channel order such as `"ZXY"` (case-insensitive) into axis indices.
fn parse_euler_order(order: &str) -> Result<[usize; 3], EulerOrderError> {
    let err = || EulerOrderError {
        order: order.to_owned(),
    };
    let bytes = order.as_bytes();
    if bytes.len() != 3 {
        return Err(err());
    }
    let mut axes = [0usize; 3];
    for (slot, &ch) in axes.iter_mut().zip(bytes) {
        *slot = match ch.to_ascii_uppercase() {
            b'X' => 0,
            b'Y' => 1,
            b'Z' => 2,
            _ => return Err(err()),
        };
    }
    if axes[0] == axes[1] || axes[1] == axes[2] || axes[0] == axes[2] {
        return Err(err());
    }
    Ok(axes)
}

/// Wraps an angle into `(−π, π]`.
pub fn wrap_angle(a: f64) -> f64 {
    let r = (a + PI).rem_euclid(2.0 * PI) - PI;
    if r <= -PI { r + 2.0 * PI } else { r }
}

// ---------------------------------------------------------------------------------------------
// Batched helpers over flat f32 slices (one rotation after another, no padding).
// ---------------------------------------------------------------------------------------------

fn check_len(len: usize, width: usize, what: &str) {
    assert!(
        len.is_multiple_of(width),
        "{what}: slice length {len} is not a multiple of {width}"
    );
}

#[inline]
fn aa3(c: &[f32]) -> [f64; 3] {
    [c[0] as f64, c[1] as f64, c[2] as f64]
}

/// `(N·3)` axis-angle → `(N·6)` pytorch3d 6D.
///
/// # Panics
/// If the length is not a multiple of 3.
pub fn axis_angle_to_6d(aa: &[f32]) -> Vec<f32> {
    check_len(aa.len(), 3, "axis_angle_to_6d");
    let mut out = Vec::with_capacity(aa.len() * 2);
    for c in aa.chunks_exact(3) {
        out.extend(Mat3::from_axis_angle(aa3(c)).to_6d().map(|v| v as f32));
    }
    out
}

/// `(N·6)` pytorch3d 6D → `(N·3)` axis-angle (angle in `[0, π]`).
///
/// # Panics
/// If the length is not a multiple of 6.
pub fn rot6d_to_axis_angle(d6: &[f32]) -> Vec<f32> {
    check_len(d6.len(), 6, "rot6d_to_axis_angle");
    let mut out = Vec::with_capacity(d6.len() / 2);
    for c in d6.chunks_exact(6) {
        let d: [f64; 6] = std::array::from_fn(|i| c[i] as f64);
        out.extend(Mat3::from_6d(&d).to_axis_angle().map(|v| v as f32));
    }
    out
}

/// `(N·3)` axis-angle → `(N·9)` row-major matrices.
///
/// # Panics
/// If the length is not a multiple of 3.
pub fn axis_angle_to_matrix(aa: &[f32]) -> Vec<f32> {
    check_len(aa.len(), 3, "axis_angle_to_matrix");
    let mut out = Vec::with_capacity(aa.len() * 3);
    for c in aa.chunks_exact(3) {
        let m = Mat3::from_axis_angle(aa3(c));
        out.extend(m.0.iter().flatten().map(|&v| v as f32));
    }
    out
}

/// `(N·9)` row-major matrices → `(N·6)` pytorch3d 6D (first two rows).
///
/// # Panics
/// If the length is not a multiple of 9.
pub fn matrix_to_6d(m: &[f32]) -> Vec<f32> {
    check_len(m.len(), 9, "matrix_to_6d");
    let mut out = Vec::with_capacity(m.len() / 9 * 6);
    for c in m.chunks_exact(9) {
        out.extend_from_slice(&c[..6]);
    }
    out
}

/// `(N·6)` pytorch3d 6D → `(N·9)` row-major matrices (Gram-Schmidt on rows).
///
/// # Panics
/// If the length is not a multiple of 6.
pub fn rot6d_to_matrix(d6: &[f32]) -> Vec<f32> {
    check_len(d6.len(), 6, "rot6d_to_matrix");
    let mut out = Vec::with_capacity(d6.len() / 6 * 9);
    for c in d6.chunks_exact(6) {
        let d: [f64; 6] = std::array::from_fn(|i| c[i] as f64);
        out.extend(Mat3::from_6d(&d).0.iter().flatten().map(|&v| v as f32));
    }
    out
}

/// `(N·3)` axis-angle → `(N·4)` quaternions `(w, x, y, z)`.
///
/// # Panics
/// If the length is not a multiple of 3.
pub fn axis_angle_to_quat(aa: &[f32]) -> Vec<f32> {
    check_len(aa.len(), 3, "axis_angle_to_quat");
    let mut out = Vec::with_capacity(aa.len() / 3 * 4);
    for c in aa.chunks_exact(3) {
        let q = Quat::from_axis_angle(aa3(c));
        out.extend([q.w, q.x, q.y, q.z].map(|v| v as f32));
    }
    out
}

/// `(N·4)` quaternions `(w, x, y, z)` → `(N·3)` axis-angle (angle in `[0, π]`). Inputs need not
/// be normalised.
///
/// # Panics
/// If the length is not a multiple of 4.
pub fn quat_to_axis_angle(q: &[f32]) -> Vec<f32> {
    check_len(q.len(), 4, "quat_to_axis_angle");
    let mut out = Vec::with_capacity(q.len() / 4 * 3);
    for c in q.chunks_exact(4) {
        let q = Quat::new(c[0] as f64, c[1] as f64, c[2] as f64, c[3] as f64).normalize();
        out.extend(q.to_axis_angle().map(|v| v as f32));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::vec3;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn between_turns_one_direction_onto_another_even_the_opposite_one() {
        for (a, b) in [
            ([1.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            ([0.3, -0.2, 0.9], [-0.3, 0.2, -0.9]),
            ([0.0, 0.0, 1.0], [0.0, 0.0, 3.0]),
        ] {
            let r = Mat3::between(a, b);
            let got = r.mul_vec(a);
            let want = vec3::scale(b, vec3::norm(a) / vec3::norm(b));
            assert!(
                vec3::norm(vec3::sub(got, want)) < 1e-9,
                "{a:?} → {b:?}: {got:?}"
            );
        }
    }

    /// Deterministic LCG (Numerical Recipes constants) so tests need no `rand` dependency.
    struct Lcg(u64);
    impl Lcg {
        fn next_f64(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn sym(&mut self) -> f64 {
            2.0 * self.next_f64() - 1.0
        }
        fn quat(&mut self) -> Quat {
            loop {
                let q = Quat::new(self.sym(), self.sym(), self.sym(), self.sym());
                let n = q.norm();
                if n > 0.1 && n <= 1.0 {
                    return q.normalize();
                }
            }
        }
    }

    fn mat_close(a: &Mat3, b: &Mat3, tol: f64) -> bool {
        (0..3).all(|i| (0..3).all(|j| (a.0[i][j] - b.0[i][j]).abs() < tol))
    }

    fn vec_close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < tol)
    }

    #[test]
    fn known_quarter_turns() {
        // +90° about X maps Y to Z, about Y maps Z to X, about Z maps X to Y (right-handed).
        let cases = [
            ([FRAC_PI_2, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            ([0.0, FRAC_PI_2, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
            ([0.0, 0.0, FRAC_PI_2], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ];
        for (axis, (aa, v, expected)) in cases.into_iter().enumerate() {
            let m = Mat3::from_axis_angle(aa);
            assert!(vec_close(m.mul_vec(v), expected, 1e-12));
            assert!(vec_close(
                Quat::from_axis_angle(aa).rotate(v),
                expected,
                1e-12
            ));
            assert!(mat_close(
                &m,
                &Mat3::from_axis_rotation(axis, FRAC_PI_2),
                1e-12
            ));
        }
        // Quaternion for +90° about X is (√½, √½, 0, 0) — the EDGE root rotation of C.2.
        let q = Quat::from_axis_angle([FRAC_PI_2, 0.0, 0.0]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q.w - h).abs() < 1e-12 && (q.x - h).abs() < 1e-12);
    }

    #[test]
    fn random_round_trips() {
        let mut rng = Lcg(42);
        for _ in 0..2000 {
            let q = rng.quat().canonical();
            let m = q.to_mat3();
            assert!((m.determinant() - 1.0).abs() < 1e-12);
            assert!(mat_close(&m.mul(&m.transpose()), &Mat3::IDENTITY, 1e-12));
            let q2 = m.to_quat();
            assert!((q.dot(q2).abs() - 1.0).abs() < 1e-12);
            let aa = q.to_axis_angle();
            assert!(mat_close(&Mat3::from_axis_angle(aa), &m, 1e-12));
            assert!(mat_close(&Quat::from_axis_angle(aa).to_mat3(), &m, 1e-12));
            assert!(vec_close(m.to_axis_angle(), aa, 1e-9));
            assert!(mat_close(&Mat3::from_6d(&m.to_6d()), &m, 1e-12));
            let v = [rng.sym(), rng.sym(), rng.sym()];
            assert!(vec_close(q.rotate(v), m.mul_vec(v), 1e-12));
            // Composition agrees between quaternions and matrices.
            let p = rng.quat();
            assert!(mat_close(&(p * q).to_mat3(), &p.to_mat3().mul(&m), 1e-12));
            assert!(mat_close(
                &(q * q.conjugate()).to_mat3(),
                &Mat3::IDENTITY,
                1e-12
            ));
        }
    }

    #[test]
    fn six_d_is_first_two_rows() {
        let m = Mat3::from_euler("ZXY", [0.3, -0.7, 1.1]).unwrap();
        let d = m.to_6d();
        assert_eq!(
            d,
            [
                m.0[0][0], m.0[0][1], m.0[0][2], m.0[1][0], m.0[1][1], m.0[1][2]
            ]
        );
        // A hand-written example: 90° about Z has rows (0,−1,0), (1,0,0), (0,0,1).
        let rz = Mat3::from_axis_angle([0.0, 0.0, FRAC_PI_2]);
        let d = rz.to_6d();
        let expected = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0];
        assert!(d.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-12));
        // Gram-Schmidt: a scaled, skewed second row decodes to the same matrix.
        let noisy = [
            2.0 * d[0],
            2.0 * d[1],
            2.0 * d[2],
            d[3] + 0.3 * d[0],
            d[4] + 0.3 * d[1],
            d[5],
        ];
        assert!(mat_close(&Mat3::from_6d(&noisy), &rz, 1e-12));
    }

    #[test]
    fn euler_all_orders_round_trip() {
        let mut rng = Lcg(7);
        for order in ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"] {
            let axes = parse_euler_order(order).unwrap();
            for _ in 0..300 {
                let ang = [
                    rng.sym() * PI,
                    rng.sym() * FRAC_PI_2 * 0.999,
                    rng.sym() * PI,
                ];
                let m = Mat3::from_euler(order, ang).unwrap();
                let manual = Mat3::from_axis_rotation(axes[0], ang[0])
                    .mul(&Mat3::from_axis_rotation(axes[1], ang[1]))
                    .mul(&Mat3::from_axis_rotation(axes[2], ang[2]));
                assert!(mat_close(&m, &manual, 1e-12));
                let back = m.to_euler(order).unwrap();
                for k in 0..3 {
                    assert!(
                        wrap_angle(back[k] - ang[k]).abs() < 1e-9,
                        "{order} {ang:?} {back:?}"
                    );
                }
            }
            // Gimbal lock: the angles differ but the matrix must be reproduced.
            for mid in [FRAC_PI_2, -FRAC_PI_2] {
                let m = Mat3::from_euler(order, [0.4, mid, -0.9]).unwrap();
                let back = m.to_euler(order).unwrap();
                assert!(
                    mat_close(&Mat3::from_euler(order, back).unwrap(), &m, 1e-9),
                    "{order}"
                );
            }
        }
        assert!(Mat3::from_euler("ZZY", [0.0; 3]).is_err());
        assert!(Mat3::from_euler("XY", [0.0; 3]).is_err());
        assert!(Mat3::from_euler("zxy", [0.0; 3]).is_ok());
    }

    #[test]
    fn slerp_endpoints_and_midpoint() {
        let a = Quat::IDENTITY;
        let b = Quat::from_axis_angle([0.0, 0.0, FRAC_PI_2]);
        assert!((Quat::slerp(a, b, 0.0).dot(a) - 1.0).abs() < 1e-12);
        assert!((Quat::slerp(a, b, 1.0).dot(b) - 1.0).abs() < 1e-12);
        let mid = Quat::slerp(a, b, 0.5).to_axis_angle();
        assert!(vec_close(mid, [0.0, 0.0, FRAC_PI_2 / 2.0], 1e-12));
        // Shortest path: using −b must give the same rotations.
        let mid_neg = Quat::slerp(a, -b, 0.5).to_axis_angle();
        assert!(vec_close(mid_neg, mid, 1e-12));
        // Nearly identical inputs take the lerp branch and stay unit.
        let c = Quat::from_axis_angle([1e-6, 0.0, 0.0]);
        assert!((Quat::slerp(a, c, 0.5).norm() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn axis_angle_near_zero() {
        for &t in &[0.0, 1e-12, 1e-8, 5e-5, 2e-4] {
            let v = [t * 0.6, -t * 0.8, 0.0];
            let back = Quat::from_axis_angle(v).to_axis_angle();
            assert!(vec_close(back, v, 1e-15 + 1e-10 * t), "{t}: {back:?}");
            let back = Mat3::from_axis_angle(v).to_axis_angle();
            assert!(vec_close(back, v, 1e-15 + 1e-8 * t), "{t}: {back:?}");
            // Matrix skew part is ≈ [v]× for tiny angles.
            let m = Mat3::from_axis_angle(v);
            assert!((m.0[1][0] - v[2]).abs() < 1e-15 + t * t);
            assert!((m.0[0][2] - v[1]).abs() < 1e-15 + t * t);
        }
    }

    #[test]
    fn axis_angle_near_pi() {
        let axis = [0.48, -0.6, 0.64]; // unit
        for &eps in &[0.0, 1e-10, 1e-6, 1e-3] {
            let theta = PI - eps;
            let v = axis.map(|a| a * theta);
            let m = Mat3::from_axis_angle(v);
            let back = m.to_axis_angle();
            // At exactly π the sign of the axis is arbitrary; both describe the same rotation.
            let ok =
                vec_close(back, v, 1e-7) || (eps == 0.0 && vec_close(back, v.map(|x| -x), 1e-7));
            assert!(ok, "eps {eps}: {back:?} vs {v:?}");
            assert!(mat_close(&Mat3::from_axis_angle(back), &m, 1e-12));
            let qb = Quat::from_axis_angle(v).to_axis_angle();
            assert!(mat_close(&Mat3::from_axis_angle(qb), &m, 1e-12));
        }
    }

    #[test]
    fn batched_helpers() {
        let mut rng = Lcg(3);
        let aa: Vec<f32> = (0..30).map(|_| (rng.sym() * 2.0) as f32).collect();
        let d6 = axis_angle_to_6d(&aa);
        assert_eq!(d6.len(), 60);
        let mats = axis_angle_to_matrix(&aa);
        assert_eq!(matrix_to_6d(&mats), d6);
        let back_m = rot6d_to_matrix(&d6);
        assert!(back_m.iter().zip(&mats).all(|(a, b)| (a - b).abs() < 1e-5));
        let back = rot6d_to_axis_angle(&d6);
        let via_q = quat_to_axis_angle(&axis_angle_to_quat(&aa));
        for (i, c) in aa.chunks_exact(3).enumerate() {
            let m0 = Mat3::from_axis_angle(aa3(c));
            let m1 = Mat3::from_axis_angle(aa3(&back[3 * i..]));
            let m2 = Mat3::from_axis_angle(aa3(&via_q[3 * i..]));
            assert!(mat_close(&m0, &m1, 1e-5) && mat_close(&m0, &m2, 1e-5));
        }
    }
}
