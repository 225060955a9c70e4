//! The canonical conventions of dancegen, stated once.
//!
//! Every motion inside the crate (and every tensor handed to a model) uses these conventions.
//! Importers (AIST++, FineDance, BVH, …) convert *into* them and exporters convert *out of*
//! them, so the middle of the pipeline never has to guess. The published systems we reproduce
//! disagree on almost every one of these choices (anchors.md C.1–C.4), which is why they are
//! written down here instead of being implied by code.
//!
//! # Space
//! - **Y-up, right-handed, metres.** This is the frame of the SMPL rest pose and of AIST++,
//!   FineDance and the EDGE offsets table (anchors.md C.3, C.4). In the SMPL rest pose the body
//!   faces **+Z** and its left side is **+X** (the left hip offset has x > 0, the toes z > 0).
//!   EDGE renders and trains in Z-up; that is an edge conversion, see [`yup_to_zup_point`] and
//!   [`yup_to_zup_root_quat`] (anchors.md C.2). AIST++ stores centimetres and a per-sequence
//!   scale; its importer turns them into metres (shared data README).
//! - **The floor is y = 0**, where the joints of a resting foot are: the lowest foot joint
//!   (ankles 7/8, toes 10/11) of a planted foot has height 0, as LODGE's and EDGE's grounding
//!   put it (the SMPL toe joint sits at the ball of the foot, a few centimetres above the
//!   sole, so a mesh foot sinks that much; the capsule body's foot likewise). Retargeting
//!   (`dancegen_formats::dispatch::convert_motion` to SMPL 24) and the training sets put each take's
//!   resting feet there ([`crate::repr::motion::planted_floor_height`]); generated motion is
//!   grounded the same way. Raw imports that keep their recording's world frame (AIST++
//!   `.pkl`, SMPL `.npz`) are left where they are.
//!
//! # Time
//! - The frame rate is **stored with every motion**, never assumed. Models use
//!   [`CANONICAL_FPS`] = 30; AIST++ raw data is [`AISTPP_RAW_FPS`] = 60 and EDGE downsamples by
//!   taking every second frame (anchors.md C.2).
//!
//! # Rotations
//! - Rotation matrices act on **column vectors**: `v' = R v`. Composition `R_a · R_b` applies
//!   `R_b` first.
//! - Quaternions are **real-first `(w, x, y, z)`** (pytorch3d, anchors.md C.2), Hamilton product.
//! - Axis-angle is the **Rodrigues vector**: unit axis times angle in radians (SMPL `poses`).
//! - 6D is pytorch3d `matrix_to_rotation_6d`: the **first two rows** of the matrix, row-major
//!   `[R00, R01, R02, R10, R11, R12]`; decoding is Gram-Schmidt on those rows
//!   (anchors.md C.2). This is *not* the column layout of Zhou et al. / mmpose.
//! - Euler angles only appear at the BVH edge: a channel order such as `"ZXY"` means
//!   `R = Rz · Rx · Ry` (see [`crate::rotation::Mat3::from_euler`]).
//!
//! # Skeleton and pose
//! - Local joint rotations are **relative to the parent joint's frame**; the root's local
//!   rotation is its world orientation.
//! - **Root translation = pelvis (joint 0) world position**, in metres. Forward kinematics places
//!   joint 0 exactly at the translation (anchors.md C.4). AIST++'s `smpl_trans` is *not* that:
//!   its world joints are `(FK(poses) + pelvis_rest) · smpl_scaling + smpl_trans`, so its importer
//!   must add the rest pelvis position and apply the scale (shared data README).
//! - Offsets are parent-relative rest-pose bone vectors in the Y-up frame (anchors.md C.4).

use crate::rotation::{Mat3, Quat};
use std::f64::consts::FRAC_1_SQRT_2;

/// Index of the up axis in `[x, y, z]` (Y-up).
pub const UP_AXIS: usize = 1;
/// The up direction as a vector.
pub const UP: [f64; 3] = [0.0, 1.0, 0.0];
/// Forward direction of the SMPL rest pose (+Z).
pub const REST_FORWARD: [f64; 3] = [0.0, 0.0, 1.0];
/// Body-left direction of the SMPL rest pose (+X).
pub const REST_LEFT: [f64; 3] = [1.0, 0.0, 0.0];
/// Length unit: positions are in metres, so one unit is one metre.
pub const METRES_PER_UNIT: f64 = 1.0;

/// Frame rate models are trained and sampled at (EDGE, LODGE, … all use 30 fps).
pub const CANONICAL_FPS: f64 = 30.0;
/// Frame rate of the raw AIST++ SMPL fits.
pub const AISTPP_RAW_FPS: f64 = 60.0;

/// Number of numbers in one 6D rotation.
pub const ROT6D_LEN: usize = 6;
/// Component order of a quaternion as stored in flat arrays.
pub const QUAT_ORDER: [char; 4] = ['w', 'x', 'y', 'z'];
/// Which matrix entries (row, column) the 6D layout stores, in order.
pub const ROT6D_LAYOUT: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2)];

/// EDGE's Y-up → Z-up rotation: +90° about X, quaternion `(w, x, y, z) = (√½, √½, 0, 0)`
/// (anchors.md C.2, `Stanford-TML/EDGE:dataset/dance_dataset.py`).
pub const YUP_TO_ZUP_QUAT: Quat = Quat::new(FRAC_1_SQRT_2, FRAC_1_SQRT_2, 0.0, 0.0);

/// The matrix of [`YUP_TO_ZUP_QUAT`]: `(x, y, z) → (x, −z, y)`.
pub const YUP_TO_ZUP_MAT: Mat3 = Mat3([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]);

/// Converts a Y-up point or translation to EDGE's Z-up frame: `(x, y, z) → (x, −z, y)`.
#[inline]
pub fn yup_to_zup_point(p: [f64; 3]) -> [f64; 3] {
    [p[0], -p[2], p[1]]
}

/// Inverse of [`yup_to_zup_point`]: `(x, y, z) → (x, z, −y)`.
#[inline]
pub fn zup_to_yup_point(p: [f64; 3]) -> [f64; 3] {
    [p[0], p[2], -p[1]]
}

/// Converts a Y-up root orientation to Z-up by **left**-multiplying with the +90°-about-X
/// quaternion, as EDGE does (anchors.md C.2). Only the root changes: local joint rotations and
/// the rest offsets stay in the Y-up rest frame, so FK with the converted root yields Z-up
/// positions.
#[inline]
pub fn yup_to_zup_root_quat(q: Quat) -> Quat {
    YUP_TO_ZUP_QUAT * q
}

/// Inverse of [`yup_to_zup_root_quat`].
#[inline]
pub fn zup_to_yup_root_quat(q: Quat) -> Quat {
    YUP_TO_ZUP_QUAT.conjugate() * q
}

/// Matrix form of [`yup_to_zup_root_quat`].
#[inline]
pub fn yup_to_zup_root_mat(r: &Mat3) -> Mat3 {
    YUP_TO_ZUP_MAT.mul(r)
}

/// Matrix form of [`zup_to_yup_root_quat`].
#[inline]
pub fn zup_to_yup_root_mat(r: &Mat3) -> Mat3 {
    YUP_TO_ZUP_MAT.transpose().mul(r)
}

/// Axis-angle form of [`yup_to_zup_root_quat`] (SMPL root `poses[0..3]`).
pub fn yup_to_zup_root_axis_angle(aa: [f64; 3]) -> [f64; 3] {
    yup_to_zup_root_quat(Quat::from_axis_angle(aa)).to_axis_angle()
}

/// Axis-angle form of [`zup_to_yup_root_quat`].
pub fn zup_to_yup_root_axis_angle(aa: [f64; 3]) -> [f64; 3] {
    zup_to_yup_root_quat(Quat::from_axis_angle(aa)).to_axis_angle()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zup_matrix_matches_quaternion_and_point_map() {
        let m = YUP_TO_ZUP_QUAT.to_mat3();
        for i in 0..3 {
            for j in 0..3 {
                assert!((m.0[i][j] - YUP_TO_ZUP_MAT.0[i][j]).abs() < 1e-15);
            }
        }
        let p = [0.1, 0.2, 0.3];
        assert_eq!(yup_to_zup_point(p), [0.1, -0.3, 0.2]);
        assert_eq!(YUP_TO_ZUP_MAT.mul_vec(p), yup_to_zup_point(p));
        assert_eq!(zup_to_yup_point(yup_to_zup_point(p)), p);
        // Y-up "up" becomes Z-up "up".
        assert_eq!(yup_to_zup_point(UP), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn root_conversions_invert() {
        let aa = [0.3, -1.2, 0.5];
        let back = zup_to_yup_root_axis_angle(yup_to_zup_root_axis_angle(aa));
        assert!(aa.iter().zip(back).all(|(a, b)| (a - b).abs() < 1e-12));
        let r = Mat3::from_axis_angle(aa);
        let z = yup_to_zup_root_mat(&r);
        let q = yup_to_zup_root_quat(Quat::from_axis_angle(aa)).to_mat3();
        assert!((0..3).all(|i| (0..3).all(|j| (z.0[i][j] - q.0[i][j]).abs() < 1e-12)));
        let y = zup_to_yup_root_mat(&z);
        assert!((0..3).all(|i| (0..3).all(|j| (y.0[i][j] - r.0[i][j]).abs() < 1e-12)));
    }
}
