//! EDGE's 151-dim motion vector (`Stanford-TML/EDGE:dataset/dance_dataset.py`, anchors.md C.2).
//!
//! Per frame, 30 fps, **Z-up**:
//!
//! | dims | content |
//! |---|---|
//! | 0..4 | foot contacts (0/1): left ankle 7, right ankle 8, left toe 10, right toe 11 — 1 where the per-frame displacement norm < 0.01 m; the last frame is always 1 |
//! | 4..7 | root (pelvis) position, Y-up `(x, y, z)` → Z-up `(x, −z, y)` |
//! | 7..151 | 24 × 6D (pytorch3d: first two **rows** of the rotation matrix), SMPL 24 order; the root rotation is left-multiplied by the +90°-about-X quaternion `(√½, √½, 0, 0)`, the other joints are unchanged local rotations |
//!
//! Decoding drops the contacts (see [`Edge151::contacts`]) and converts back to the canonical
//! Y-up [`SmplMotion`]. Note: EDGE's root translation is AIST++ `smpl_trans / scaling`
//! (see `AistppMotion::to_smpl_motion_edge` in `dancegen-formats`).

use super::motion::{EDGE_CONTACT_VELOCITY, POSE_DIMS, SMPL_JOINTS, contacts_velocity};
use super::{ReprError, SmplMotion, check_fps, frames_of};
use crate::conventions::{
    CANONICAL_FPS, yup_to_zup_point, yup_to_zup_root_mat, zup_to_yup_point, zup_to_yup_root_mat,
};
use crate::rot6d_track::decode_6d_track;
use crate::rotation::Mat3;
use std::ops::Range;

/// The EDGE 151-dim representation; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct Edge151;

impl Edge151 {
    /// Values per frame.
    pub const DIMS: usize = 151;
    /// Contact labels.
    pub const CONTACTS: Range<usize> = 0..4;
    /// Root position (Z-up).
    pub const ROOT: Range<usize> = 4..7;
    /// 24 × 6D rotations.
    pub const ROT6D: Range<usize> = 7..151;

    /// Encodes a 30-fps motion to `(T, 151)`.
    pub fn encode(m: &SmplMotion) -> Result<Vec<f32>, ReprError> {
        check_fps("Edge151::encode", m.fps, CANONICAL_FPS as f32)?;
        let t = m.validate()?;
        let joints = m.joints_world()?;
        let contacts = contacts_velocity(&joints, EDGE_CONTACT_VELOCITY);
        let mut out = Vec::with_capacity(t * Self::DIMS);
        for f in 0..t {
            out.extend_from_slice(&contacts[f * 4..f * 4 + 4]);
            let p = &m.trans[f * 3..f * 3 + 3];
            let z = yup_to_zup_point([p[0], p[1], p[2]].map(f64::from));
            out.extend(z.map(|v| v as f32));
            for j in 0..SMPL_JOINTS {
                let mut r = Mat3::from_axis_angle(m.joint_aa(f, j).map(f64::from));
                if j == 0 {
                    r = yup_to_zup_root_mat(&r);
                }
                out.extend(r.to_6d().map(|v| v as f32));
            }
        }
        Ok(out)
    }

    /// Decodes `(T, 151)` to a Y-up 30-fps motion (contacts are ignored).
    ///
    /// Each joint's 6D track is decoded as one ([`decode_6d_track`]): proper rotations, as in
    /// real data, decode exactly as Gram–Schmidt gives them; a generated run whose rows shrank
    /// towards the origin is bridged instead of flipping in one frame (logged when it happens).
    pub fn decode(data: &[f32]) -> Result<SmplMotion, ReprError> {
        let t = frames_of("Edge151::decode", data, Self::DIMS)?;
        let start = Self::ROT6D.start;
        let mut bridged = 0;
        let tracks: Vec<Vec<Mat3>> = (0..SMPL_JOINTS)
            .map(|j| {
                let track: Vec<[f64; 6]> = data
                    .chunks_exact(Self::DIMS)
                    .map(|row| std::array::from_fn(|i| f64::from(row[start + 6 * j + i])))
                    .collect();
                let (r, n) = decode_6d_track(&track);
                bridged += n;
                r
            })
            .collect();
        if bridged > 0 {
            tracing::info!(
                joint_frames = bridged,
                "bridged joint rotations whose 6D rows had shrunk below {}",
                crate::rot6d_track::MIN_ROW_LENGTH
            );
        }
        let mut poses = Vec::with_capacity(t * POSE_DIMS);
        let mut trans = Vec::with_capacity(t * 3);
        for (f, row) in data.chunks_exact(Self::DIMS).enumerate() {
            let r = &row[Self::ROOT];
            trans.extend(zup_to_yup_point([r[0], r[1], r[2]].map(f64::from)).map(|v| v as f32));
            for (j, track) in tracks.iter().enumerate() {
                let mut r = track[f];
                if j == 0 {
                    r = zup_to_yup_root_mat(&r);
                }
                poses.extend(r.to_axis_angle().map(|v| v as f32));
            }
        }
        SmplMotion::new(CANONICAL_FPS as f32, poses, trans)
    }

    /// The contact columns `(T, 4)` of a `(T, 151)` array.
    pub fn contacts(data: &[f32]) -> Result<Vec<f32>, ReprError> {
        frames_of("Edge151::contacts", data, Self::DIMS)?;
        Ok(data
            .chunks_exact(Self::DIMS)
            .flat_map(|r| r[Self::CONTACTS].iter().copied())
            .collect())
    }
}
