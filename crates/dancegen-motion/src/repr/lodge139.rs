//! LODGE's 139-dim body vector (`li-ronghui/LODGE:data/code/preprocess.py`, anchors.md C.3).
//!
//! Per frame, 30 fps, **Y-up**, metres, motion first put on the ground with LODGE's rule
//! ([`GroundMode::FirstFrameToes`]: frame-0 toe heights, mean if within 2 cm else min):
//!
//! | dims | content |
//! |---|---|
//! | 0..4 | height contacts (0/1): left ankle 7, right ankle 8 (`y < 0.12`), left toe 10, right toe 11 (`y < 0.05`) |
//! | 4..7 | root (pelvis) position `(x, y, z)` |
//! | 7..139 | 22 × 6D (pytorch3d first two rows), body joints 0–21 of SMPL-X order (= SMPL 0–21) |
//!
//! It is the first 139 dims of FineDance's 319 ([`super::FineDance319`]). Decoding sets the SMPL
//! hand joints 22, 23 to identity.
//!
//! Difference from LODGE: grounding and contacts use FK on the EDGE SMPL 24 skeleton (C.4);
//! LODGE uses its neutral SMPL-X rest joints (C.3), whose feet sit a few millimetres
//! differently, so a contact label right at a threshold can differ.

use super::motion::{GroundMode, LODGE_CONTACT_HEIGHT, POSE_DIMS, SMPL_JOINTS, contacts_height};
use super::{ReprError, SmplMotion, check_fps, frames_of};
use crate::conventions::CANONICAL_FPS;
use crate::rotation::Mat3;
use std::ops::Range;

/// The LODGE 139-dim representation; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct Lodge139;

/// Number of body joints (SMPL / SMPL-X 0–21).
pub const BODY_JOINTS: usize = 22;
/// 6D of the identity rotation.
pub const IDENTITY_6D: [f32; 6] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

impl Lodge139 {
    /// Values per frame.
    pub const DIMS: usize = 139;
    /// Contact labels.
    pub const CONTACTS: Range<usize> = 0..4;
    /// Root position (Y-up).
    pub const ROOT: Range<usize> = 4..7;
    /// 22 × 6D rotations.
    pub const ROT6D: Range<usize> = 7..139;

    /// Grounds a copy of `m` the LODGE way and returns it with its `(T, 4)` height contacts.
    pub fn grounded_with_contacts(m: &SmplMotion) -> Result<(SmplMotion, Vec<f32>), ReprError> {
        let mut g = m.clone();
        g.put_on_ground_with(GroundMode::FirstFrameToes)?;
        let (ankle, toe) = LODGE_CONTACT_HEIGHT;
        let contacts = contacts_height(&g.joints_world()?, ankle, toe);
        Ok((g, contacts))
    }

    /// Encodes a 30-fps motion to `(T, 139)` (grounded, see module docs).
    pub fn encode(m: &SmplMotion) -> Result<Vec<f32>, ReprError> {
        check_fps("Lodge139::encode", m.fps, CANONICAL_FPS as f32)?;
        let t = m.validate()?;
        let (g, contacts) = Self::grounded_with_contacts(m)?;
        let mut out = Vec::with_capacity(t * Self::DIMS);
        for f in 0..t {
            out.extend_from_slice(&contacts[f * 4..f * 4 + 4]);
            out.extend_from_slice(&g.trans[f * 3..f * 3 + 3]);
            push_6d(&mut out, &g, f, BODY_JOINTS);
        }
        Ok(out)
    }

    /// Decodes `(T, 139)` to a 30-fps motion (hands 22, 23 identity, contacts ignored).
    pub fn decode(data: &[f32]) -> Result<SmplMotion, ReprError> {
        frames_of("Lodge139::decode", data, Self::DIMS)?;
        decode_rows(data, Self::DIMS, 4, BODY_JOINTS)
    }
}

/// Appends the 6D of joints `0..n` of frame `f`.
pub(crate) fn push_6d(out: &mut Vec<f32>, m: &SmplMotion, f: usize, n: usize) {
    for j in 0..n {
        let r = Mat3::from_axis_angle(m.joint_aa(f, j).map(f64::from));
        out.extend(r.to_6d().map(|v| v as f32));
    }
}

/// Decodes rows of `width` values holding root `[root_at, root_at + 3)` followed by `n_body`
/// 6D rotations (SMPL 0..n_body); SMPL joints from `n_body` to 23 become identity.
pub(crate) fn decode_rows(
    data: &[f32],
    width: usize,
    root_at: usize,
    n_body: usize,
) -> Result<SmplMotion, ReprError> {
    let t = data.len() / width;
    let mut poses = Vec::with_capacity(t * POSE_DIMS);
    let mut trans = Vec::with_capacity(t * 3);
    for row in data.chunks_exact(width) {
        trans.extend_from_slice(&row[root_at..root_at + 3]);
        let rot = &row[root_at + 3..root_at + 3 + n_body * 6];
        for d in rot.chunks_exact(6) {
            let d: [f64; 6] = std::array::from_fn(|i| d[i] as f64);
            poses.extend(Mat3::from_6d(&d).to_axis_angle().map(|v| v as f32));
        }
        poses.extend(std::iter::repeat_n(0.0, (SMPL_JOINTS - n_body) * 3));
    }
    SmplMotion::new(CANONICAL_FPS as f32, poses, trans)
}
