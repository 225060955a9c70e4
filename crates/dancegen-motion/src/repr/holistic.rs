//! SoulNet's holistic body + hands (+ face) vectors, 623 and 723 (anchors.md C.6).
//!
//! # What anchors.md C.6 states (`xjli360/SoulDance-Official:README.md`)
//! A HumanTOMATO / HumanML3D-style **623**-dim vector for the **52** SMPL-H joints (22 body +
//! 30 finger joints): root rotation velocity (1), root linear velocity (2), root y (1), ric
//! 51 × 3 (153), rot 51 × 6 (306), local velocity 52 × 3 (156), foot contact (4); plus a
//! **100**-dim FLAME face vector (expression/jaw, EMAGE-style) = **723**; 30 fps.
//!
//! # Our layout
//! Exactly the generalised HumanML3D encoder of [`super::humanml263`] run on 52 joints (the
//! same code, [`super::humanml263::RicLayout`] `{ joints: 52 }`), per frame `t < T − 1`:
//!
//! | dims | content |
//! |---|---|
//! | 0 | root rotation velocity (half the yaw step, `asin(y)`) |
//! | 1..3 | root linear velocity x, z |
//! | 3 | root y |
//! | 4..157 | ric: joints 1–51 relative to the root's x, z, heading-rotated (51 × 3) |
//! | 157..463 | rot: joints 1–51 local rotations, continuous 6D = first two columns (51 × 6) |
//! | 463..619 | local velocity, joints 0–51 (52 × 3) |
//! | 619..623 | foot contacts l-ankle 7, l-toe 10, r-ankle 8, r-toe 11 |
//! | 623..723 | (723 only) the caller's 100 face parameters of frame `t`, passed through |
//!
//! The block sizes and their order are C.6's. **Assumptions** (SoulDance's code and data are
//! under an EULA and not public, so none of these can be checked):
//! - joint order = SMPL-H 52 as in FineDance / [`crate::skeleton::SMPLH52_NAMES`] (body 0–21,
//!   left hand 22–36, right hand 37–51, each index, middle, pinky, ring, thumb × 3);
//! - canonicalisation, heading smoothing, 6D convention, contact joints and the 0.002 m²
//!   per-frame threshold are HumanML3D's, with the same differences as our 263 (true local
//!   rotations instead of HumanML3D's IK, no skeleton uniformisation, motion's own frame rate);
//! - the face block is appended **after** the 623 body/hand dims, frame `t`'s parameters on
//!   output row `t` (the last input frame's face is dropped, like its pose); its internal split
//!   (how many expression vs jaw values) is not interpreted — the 100 numbers pass through
//!   bit-exactly;
//! - the 30 finger joints' rest offsets: when no SMPL-H model is available we use our own
//!   [`Skeleton::smplh52_approx`] (its finger geometry is an anthropometric approximation, not
//!   SMPL-H's). Use [`Holistic623::encode_with`] with [`Skeleton::smplh52`] and real rest
//!   joints when you have them; decode with the same skeleton.

pub mod split;

use super::humanml263::{
    RicLayout, decode_ric_joints, decode_ric_rotations, dims_for_joints, encode_ric,
};
use super::{ReprError, frames_of};
use crate::fk::fk_axis_angle_f64;
use crate::rotation::{Mat3, Quat};
use crate::skeleton::{SMPLH52_PARENTS, Skeleton};

/// Joints of the holistic representation (SMPL-H 52).
pub const JOINTS: usize = 52;
/// FLAME face parameters per frame in [`Holistic723`].
pub const FACE_DIMS: usize = 100;
/// The block layout of the 623 part.
pub const LAYOUT: RicLayout = RicLayout { joints: JOINTS };

/// The 623-dim body + hands vector; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct Holistic623;

/// The 723-dim body + hands + face vector; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct Holistic723;

/// A decoded holistic motion.
#[derive(Debug, Clone, PartialEq)]
pub struct HolisticMotion {
    pub fps: f32,
    /// `(T, 52, 3)` local axis-angle (SMPL-H order; root = world orientation).
    pub poses: Vec<f32>,
    /// `(T, 3)` pelvis world position, metres, Y-up.
    pub trans: Vec<f32>,
    /// `(T, 100)` face parameters ([`Holistic723`] only).
    pub face: Option<Vec<f32>>,
}

impl HolisticMotion {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.trans.len() / 3
    }

    /// World joints `(T, 52, 3)` by FK on `skeleton` (52 joints).
    pub fn joints_world_with(&self, skeleton: &Skeleton) -> Result<Vec<f32>, ReprError> {
        let poses: Vec<f64> = self.poses.iter().map(|&v| v as f64).collect();
        let trans: Vec<f64> = self.trans.iter().map(|&v| v as f64).collect();
        Ok(fk_axis_angle_f64(skeleton, &poses, &trans)?
            .into_iter()
            .map(|v| v as f32)
            .collect())
    }
}

/// Encoder output with the intermediate quantities, for checks and visualisation.
#[derive(Debug, Clone, PartialEq)]
pub struct HolisticParts {
    /// `(T − 1, 623)` or `(T − 1, 723)`.
    pub data: Vec<f32>,
    /// `(T, 52, 3)` canonicalised world joints.
    pub positions: Vec<f64>,
    /// `(T,)` heading quaternions.
    pub heading: Vec<Quat>,
}

fn check_skeleton(skeleton: &Skeleton) -> Result<(), ReprError> {
    if skeleton.parent_indices() != SMPLH52_PARENTS {
        return Err(ReprError::Invalid(format!(
            "holistic representation needs an SMPL-H 52 skeleton, got {} joints with other parents",
            skeleton.len()
        )));
    }
    Ok(())
}

/// Shared encoder: checks shapes, runs FK in `f64` and the generalised HumanML3D encoder.
fn encode_623(
    skeleton: &Skeleton,
    poses: &[f32],
    trans: &[f32],
    fps: f32,
) -> Result<HolisticParts, ReprError> {
    check_skeleton(skeleton)?;
    let t = frames_of("Holistic623 poses", poses, JOINTS * 3)?;
    let tt = frames_of("Holistic623 trans", trans, 3)?;
    if t != tt {
        return Err(ReprError::FrameMismatch {
            what: "Holistic623",
            poses: t,
            trans: tt,
        });
    }
    if !fps.is_finite() || fps <= 0.0 {
        return Err(ReprError::Invalid(format!("fps {fps} is not positive")));
    }
    if t < 2 {
        return Err(ReprError::Invalid(
            "Holistic623 needs at least 2 frames".into(),
        ));
    }
    let p64: Vec<f64> = poses.iter().map(|&v| v as f64).collect();
    let t64: Vec<f64> = trans.iter().map(|&v| v as f64).collect();
    let world = fk_axis_angle_f64(skeleton, &p64, &t64)?;
    let (data, positions, heading) = encode_ric(JOINTS, world, |f, k| {
        let o = (f * JOINTS + k) * 3;
        Mat3::from_axis_angle([p64[o], p64[o + 1], p64[o + 2]])
    });
    Ok(HolisticParts {
        data,
        positions,
        heading,
    })
}

impl Holistic623 {
    /// Values per frame (C.6).
    pub const DIMS: usize = dims_for_joints(JOINTS);

    /// Encodes `poses` `(T, 52, 3)` local axis-angle and `trans` `(T, 3)` pelvis positions
    /// (T ≥ 2) on [`Skeleton::smplh52_approx`] to `(T − 1, 623)`. `fps` is validated only
    /// (the per-frame quantities are at the motion's own rate).
    pub fn encode(poses: &[f32], trans: &[f32], fps: f32) -> Result<Vec<f32>, ReprError> {
        Ok(Self::encode_with(&Skeleton::smplh52_approx(), poses, trans, fps)?.data)
    }

    /// [`Holistic623::encode`] on a caller-chosen SMPL-H 52 skeleton, with intermediates.
    pub fn encode_with(
        skeleton: &Skeleton,
        poses: &[f32],
        trans: &[f32],
        fps: f32,
    ) -> Result<HolisticParts, ReprError> {
        encode_623(skeleton, poses, trans, fps)
    }

    /// `recover_from_ric` for 52 joints: `(T', 52, 3)` world joints from `(T', 623)`, in the
    /// frame whose initial heading is the identity (canonical positions rotated by
    /// `heading[0]`).
    pub fn decode_joints(data: &[f32]) -> Result<Vec<f32>, ReprError> {
        decode_ric_joints("Holistic623::decode_joints", data, JOINTS)
    }

    /// Decodes to a motion on [`Skeleton::smplh52_approx`] (root rotation solved from the
    /// decoded pelvis, hips and belly; joints 1–51 from the 6D).
    pub fn decode(data: &[f32], fps: f32) -> Result<HolisticMotion, ReprError> {
        Self::decode_with(&Skeleton::smplh52_approx(), data, fps)
    }

    /// [`Holistic623::decode`] for a caller-chosen SMPL-H 52 skeleton (its rest offsets of
    /// joints 1–3 define the root rotation).
    pub fn decode_with(
        skeleton: &Skeleton,
        data: &[f32],
        fps: f32,
    ) -> Result<HolisticMotion, ReprError> {
        check_skeleton(skeleton)?;
        let joints = Self::decode_joints(data)?;
        let (poses, trans) = decode_ric_rotations(data, &joints, JOINTS, skeleton.offsets());
        Ok(HolisticMotion {
            fps,
            poses,
            trans,
            face: None,
        })
    }
}

impl Holistic723 {
    /// Values per frame: 623 + 100 face parameters (C.6).
    pub const DIMS: usize = Holistic623::DIMS + FACE_DIMS;

    /// [`Holistic623::encode`] with `face` `(T, 100)` appended per output row (frame `t`'s
    /// parameters on row `t`; zeros when `None`).
    pub fn encode(
        poses: &[f32],
        trans: &[f32],
        face: Option<&[f32]>,
        fps: f32,
    ) -> Result<Vec<f32>, ReprError> {
        Ok(Self::encode_with(&Skeleton::smplh52_approx(), poses, trans, face, fps)?.data)
    }

    /// [`Holistic723::encode`] on a caller-chosen SMPL-H 52 skeleton, with intermediates.
    pub fn encode_with(
        skeleton: &Skeleton,
        poses: &[f32],
        trans: &[f32],
        face: Option<&[f32]>,
        fps: f32,
    ) -> Result<HolisticParts, ReprError> {
        let mut parts = encode_623(skeleton, poses, trans, fps)?;
        let t = trans.len() / 3;
        if let Some(face) = face {
            let tf = frames_of("Holistic723 face", face, FACE_DIMS)?;
            if tf != t {
                return Err(ReprError::FrameMismatch {
                    what: "Holistic723 face",
                    poses: t,
                    trans: tf,
                });
            }
        }
        let mut data = Vec::with_capacity((t - 1) * Self::DIMS);
        for (f, row) in parts.data.chunks_exact(Holistic623::DIMS).enumerate() {
            data.extend_from_slice(row);
            match face {
                Some(face) => data.extend_from_slice(&face[f * FACE_DIMS..(f + 1) * FACE_DIMS]),
                None => data.extend([0.0; FACE_DIMS]),
            }
        }
        parts.data = data;
        Ok(parts)
    }

    /// Splits `(T', 723)` into the `(T', 623)` body/hand part and the `(T', 100)` face part.
    pub fn split(data: &[f32]) -> Result<(Vec<f32>, Vec<f32>), ReprError> {
        let t = frames_of("Holistic723", data, Self::DIMS)?;
        let mut body = Vec::with_capacity(t * Holistic623::DIMS);
        let mut face = Vec::with_capacity(t * FACE_DIMS);
        for row in data.chunks_exact(Self::DIMS) {
            body.extend_from_slice(&row[..Holistic623::DIMS]);
            face.extend_from_slice(&row[Holistic623::DIMS..]);
        }
        Ok((body, face))
    }

    /// `(T', 52, 3)` world joints, as [`Holistic623::decode_joints`].
    pub fn decode_joints(data: &[f32]) -> Result<Vec<f32>, ReprError> {
        Holistic623::decode_joints(&Self::split(data)?.0)
    }

    /// Decodes on [`Skeleton::smplh52_approx`]; `face` holds the `(T', 100)` parameters.
    pub fn decode(data: &[f32], fps: f32) -> Result<HolisticMotion, ReprError> {
        Self::decode_with(&Skeleton::smplh52_approx(), data, fps)
    }

    /// [`Holistic723::decode`] for a caller-chosen SMPL-H 52 skeleton.
    pub fn decode_with(
        skeleton: &Skeleton,
        data: &[f32],
        fps: f32,
    ) -> Result<HolisticMotion, ReprError> {
        let (body, face) = Self::split(data)?;
        let mut m = Holistic623::decode_with(skeleton, &body, fps)?;
        m.face = Some(face);
        Ok(m)
    }
}
