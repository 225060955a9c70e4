//! FineDance raw 315 and LODGE's 319 (`li-ronghui/FineDance`, `li-ronghui/LODGE:data/code/preprocess.py`;
//! anchors.md C.3).
//!
//! **315** (`motion/*.npy`, shape `(T, 315)`), 30 fps, Y-up, metres:
//!
//! | dims | content |
//! |---|---|
//! | 0..3 | root (pelvis) position |
//! | 3..135 | 22 × 6D body joints, SMPL-X order 0–21 (= SMPL 0–21) |
//! | 135..225 | 15 × 6D left-hand joints (SMPL-X 25–39: index, middle, pinky, ring, thumb × 3) |
//! | 225..315 | 15 × 6D right-hand joints (SMPL-X 40–54) |
//!
//! i.e. SMPL-X without jaw/eyes (22–24). 6D = pytorch3d first two rows.
//!
//! **319** = `[contacts 4, 315]` after LODGE's grounding, contacts as in [`super::Lodge139`].
//!
//! Conversion to SMPL 24 ([`FineDanceMotion::to_smpl24`]): joints 0–21 are copied, SMPL's
//! `lhand`/`rhand` (22, 23) — which SMPL-X does not have; its fingers hang off the wrists
//! instead — are set to identity, and the 30 finger rotations are dropped (available via
//! [`FineDanceMotion::hands_6d`]). Encoding from SMPL 24 writes identity fingers.

use super::lodge139::{BODY_JOINTS, IDENTITY_6D, Lodge139, decode_rows, push_6d};
use super::{ReprError, SmplMotion, check_fps, frames_of};
use crate::conventions::CANONICAL_FPS;
use crate::rotation::Mat3;
use std::path::Path;

/// Number of finger joints in FineDance (15 per hand).
pub const HAND_JOINTS: usize = 30;

/// A FineDance motion as stored, `(T, 315)`.
#[derive(Debug, Clone, PartialEq)]
pub struct FineDanceMotion {
    pub fps: f32,
    /// `(T, 315)` row-major, see module docs.
    pub data: Vec<f32>,
}

impl FineDanceMotion {
    /// Reads a FineDance `motion/*.npy` of shape `(T, 315)` (30 fps).
    pub fn from_npy(path: impl AsRef<Path>) -> Result<Self, ReprError> {
        let path = path.as_ref();
        let arr = dancegen_io::read_npy(path)?;
        if arr.shape.len() != 2 || arr.shape[1] != FineDance315::DIMS {
            return Err(ReprError::Invalid(format!(
                "{}: shape {:?}, expected (T, 315)",
                path.display(),
                arr.shape
            )));
        }
        Ok(FineDanceMotion {
            fps: CANONICAL_FPS as f32,
            data: arr.data.iter().map(|&v| v as f32).collect(),
        })
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.data.len() / FineDance315::DIMS
    }

    /// SMPL 24 motion: body 0–21, identity 22/23, fingers dropped (module docs).
    pub fn to_smpl24(&self) -> Result<SmplMotion, ReprError> {
        let mut m = FineDance315::decode(&self.data)?;
        m.fps = self.fps;
        Ok(m)
    }

    /// SMPL-H 52 motion with its real fingers: FineDance's joint order is SMPL-H's (body 0–21,
    /// left hand 22–36, right hand 37–51, each index, middle, pinky, ring, thumb), so every 6D
    /// rotation maps to the same-numbered SMPL-H joint.
    pub fn to_smplh52(&self) -> Result<super::holistic::HolisticMotion, ReprError> {
        let t = frames_of(
            "FineDanceMotion::to_smplh52",
            &self.data,
            FineDance315::DIMS,
        )?;
        let mut poses = Vec::with_capacity(t * super::holistic::JOINTS * 3);
        let mut trans = Vec::with_capacity(t * 3);
        for row in self.data.chunks_exact(FineDance315::DIMS) {
            trans.extend_from_slice(&row[..3]);
            for d in row[3..].chunks_exact(6) {
                let d: [f64; 6] = std::array::from_fn(|i| d[i] as f64);
                poses.extend(Mat3::from_6d(&d).to_axis_angle().map(|v| v as f32));
            }
        }
        Ok(super::holistic::HolisticMotion {
            fps: self.fps,
            poses,
            trans,
            face: None,
        })
    }

    /// Finger 6D rotations `(T, 30, 6)` (left 15 then right 15).
    pub fn hands_6d(&self) -> Vec<f32> {
        self.data
            .chunks_exact(FineDance315::DIMS)
            .flat_map(|r| r[3 + BODY_JOINTS * 6..].iter().copied())
            .collect()
    }
}

/// FineDance raw 315; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct FineDance315;

impl FineDance315 {
    /// Values per frame.
    pub const DIMS: usize = 3 + (BODY_JOINTS + HAND_JOINTS) * 6;

    /// Encodes a 30-fps SMPL 24 motion to `(T, 315)` with identity fingers (no grounding).
    pub fn encode(m: &SmplMotion) -> Result<Vec<f32>, ReprError> {
        check_fps("FineDance315::encode", m.fps, CANONICAL_FPS as f32)?;
        let t = m.validate()?;
        let mut out = Vec::with_capacity(t * Self::DIMS);
        for f in 0..t {
            out.extend_from_slice(&m.trans[f * 3..f * 3 + 3]);
            push_6d(&mut out, m, f, BODY_JOINTS);
            for _ in 0..HAND_JOINTS {
                out.extend_from_slice(&IDENTITY_6D);
            }
        }
        Ok(out)
    }

    /// Encodes an SMPL-H 52 motion (`poses` `(T, 52, 3)` axis-angle, `trans` `(T, 3)`) to
    /// `(T, 315)` with its fingers (the inverse of [`FineDanceMotion::to_smplh52`]).
    pub fn encode_smplh52(poses: &[f32], trans: &[f32]) -> Result<Vec<f32>, ReprError> {
        let joints = super::holistic::JOINTS;
        let t = frames_of("FineDance315::encode_smplh52 poses", poses, joints * 3)?;
        if frames_of("FineDance315::encode_smplh52 trans", trans, 3)? != t {
            return Err(ReprError::FrameMismatch {
                what: "FineDance315::encode_smplh52",
                poses: t,
                trans: trans.len() / 3,
            });
        }
        let mut out = Vec::with_capacity(t * Self::DIMS);
        for f in 0..t {
            out.extend_from_slice(&trans[f * 3..f * 3 + 3]);
            for a in poses[f * joints * 3..(f + 1) * joints * 3].chunks_exact(3) {
                let r = Mat3::from_axis_angle([a[0] as f64, a[1] as f64, a[2] as f64]);
                out.extend(r.to_6d().map(|v| v as f32));
            }
        }
        Ok(out)
    }

    /// Decodes `(T, 315)` to SMPL 24 (see module docs).
    pub fn decode(data: &[f32]) -> Result<SmplMotion, ReprError> {
        frames_of("FineDance315::decode", data, Self::DIMS)?;
        decode_rows(data, Self::DIMS, 0, BODY_JOINTS)
    }
}

/// LODGE's 319 = height contacts 4 + FineDance 315 (grounded); see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct FineDance319;

impl FineDance319 {
    /// Values per frame.
    pub const DIMS: usize = 4 + FineDance315::DIMS;

    /// Grounds (LODGE rule) and encodes a FineDance motion, keeping its finger rotations.
    pub fn encode_finedance(m: &FineDanceMotion) -> Result<Vec<f32>, ReprError> {
        let smpl = m.to_smpl24()?;
        let (g, contacts) = Lodge139::grounded_with_contacts(&smpl)?;
        let dy = g.trans.get(1).copied().unwrap_or(0.0) - smpl.trans.get(1).copied().unwrap_or(0.0);
        let mut out = Vec::with_capacity(m.frames() * Self::DIMS);
        for (f, row) in m.data.chunks_exact(FineDance315::DIMS).enumerate() {
            out.extend_from_slice(&contacts[f * 4..f * 4 + 4]);
            out.extend_from_slice(&[row[0], row[1] + dy, row[2]]);
            out.extend_from_slice(&row[3..]);
        }
        Ok(out)
    }

    /// Grounds (LODGE rule) and encodes a 30-fps SMPL 24 motion with identity fingers.
    pub fn encode(m: &SmplMotion) -> Result<Vec<f32>, ReprError> {
        check_fps("FineDance319::encode", m.fps, CANONICAL_FPS as f32)?;
        let (g, contacts) = Lodge139::grounded_with_contacts(m)?;
        let body = FineDance315::encode(&g)?;
        let mut out = Vec::with_capacity(g.frames() * Self::DIMS);
        for (f, row) in body.chunks_exact(FineDance315::DIMS).enumerate() {
            out.extend_from_slice(&contacts[f * 4..f * 4 + 4]);
            out.extend_from_slice(row);
        }
        Ok(out)
    }

    /// Decodes `(T, 319)` to SMPL 24 (contacts and fingers dropped).
    pub fn decode(data: &[f32]) -> Result<SmplMotion, ReprError> {
        frames_of("FineDance319::decode", data, Self::DIMS)?;
        decode_rows(data, Self::DIMS, 4, BODY_JOINTS)
    }
}
