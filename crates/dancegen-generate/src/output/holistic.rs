//! The files of a holistic dance: body, fingers and face ([`HolisticParts`]).
//!
//! Kept out of `output.rs` because every other dance is written from its SMPL 24 bodies
//! through `dancegen_formats::dispatch`, while a holistic dance is written from its SMPL-H 52
//! rotations and its ARKit face, which those single-body writers do not take. `output.rs` only
//! routes every non-preview file of a holistic dance here.
//!
//! | file | holds |
//! |---|---|
//! | `.npy` | world joints `(T, 52, 3)` float32, metres, Y-up, SMPL-H order (22 body joints, 15 left-hand, 15 right-hand finger joints): forward kinematics of the poses and pelvis on the parts' skeleton |
//! | `.json` | the single-dancer document (`fps`, `up`, `units`, `joint_names`, `parents`, `shape`, `positions`, the SMPL 24 body's `smpl_poses_axis_angle` and `pelvis_trans`) for the 52 joints, plus `smplh_poses_axis_angle` (`T × 156`) and `face`: `{"names": [52 camelCase ARKit names], "weights": [[52 per frame], …]}` |
//! | `.glb` | 52 bones in the skin and a head mesh with the 52 ARKit morph targets, played through a `weights` channel ([`write_glb_with_face`]) |
//! | `.fbx` | 52 bones in the skin; no face (the FBX writer has no blend shapes) |
//! | `.bvh` | 52 joints, centimetres, as the single-dancer BVH |
//! | `.npz` | AMASS-style SMPL-H: `poses` `(T, 156)`, `trans`, `betas`, `gender` `"neutral"`, `mocap_framerate` |
//! | `.csv` | the face as Live Link Face CSV |
//!
//! Bone names: the 22 body joints as the single-dancer files name them — the `--rig` preset's
//! names in `.bvh`, `.glb` and `.fbx`, SMPL's (EDGE spelling) in `.json` — and the 30 finger
//! joints by their SMPL-X names (`left_index1` … `right_thumb3`) in every rig, since the presets
//! name the body only. Previews (`.gif`, `.mp4`) and a `--character` `.glb` show the SMPL 24
//! body only (`output.rs`).

use std::path::Path;

use dancegen_formats::bvh::{BvhWriteOptions, write_bvh_file};
use dancegen_formats::bvh_motion::skeleton_motion_to_bvh;
use dancegen_formats::dispatch::LoadedMotion;
use dancegen_formats::fbx::{FbxOptions, write_fbx};
use dancegen_formats::gltf::{DancerAnimation, FaceAnimation, GlbOptions, write_glb_with_face};
use dancegen_formats::livelink_csv;
use dancegen_formats::rig::Rig;
use dancegen_formats::smpl_npz::{BODY_JOINTS, SMPLH_JOINTS, SmplNpzOptions, write_smplh_npz_with};
use dancegen_motion::face::ARKIT_NAMES;
use dancegen_motion::fk::fk_axis_angle_f32;
use dancegen_motion::repr::motion::SmplMotion;
use dancegen_motion::skeleton::{SMPLH52_NAMES, SMPLH52_PARENTS, Skeleton};

use super::{OutputFormat, about_dest};
use crate::error::GenerateError;
use crate::record::DanceRecord;
use crate::system::HolisticParts;

/// The head joint of SMPL-H 52 (the face rides on it).
const HEAD: usize = 15;

/// Writes `parts` (whose body is `motion`, the dance's one dancer) as `format` to `tmp`, the
/// staging copy of `dest`. Previews are not written here.
pub(super) fn write(
    tmp: &Path,
    dest: &Path,
    format: OutputFormat,
    rig: Rig,
    parts: &HolisticParts,
    motion: &LoadedMotion,
    record: &DanceRecord,
) -> Result<(), GenerateError> {
    let bad = |reason: String| GenerateError::Output {
        path: dest.to_path_buf(),
        reason,
    };
    let LoadedMotion::Smpl(body) = motion else {
        return Err(bad(format!(
            "a holistic dance has one dancer, and this file would hold a {}",
            motion.kind()
        )));
    };
    let frames = check(parts, body).map_err(|e| bad(format!("holistic dance: {e}")))?;
    let fps = body.fps;
    let here = |e: &dyn std::fmt::Display| about_dest(e, tmp, dest);
    let dancer = DancerAnimation {
        local_rotations_axis_angle: &parts.poses,
        root_translation: &parts.trans,
    };
    match format {
        OutputFormat::Npy => {
            let joints = fk_axis_angle_f32(&parts.skeleton, &parts.poses, &parts.trans)
                .map_err(|e| bad(e.to_string()))?;
            dancegen_io::write_npy_f32(tmp, &[frames, SMPLH_JOINTS, 3], &joints)
                .map_err(|e| here(&e))
        }
        OutputFormat::Json => write_json(tmp, parts, body, frames).map_err(|e| here(&e)),
        OutputFormat::Glb => {
            let face = FaceAnimation {
                weights: &parts.face,
                head_joint: HEAD,
            };
            let skeleton = named(parts, rig).map_err(|e| bad(e.to_string()))?;
            write_glb_with_face(tmp, &skeleton, dancer, face, fps, &GlbOptions::default())
                .map_err(|e| here(&e))
        }
        OutputFormat::Fbx => {
            let skeleton = named(parts, rig).map_err(|e| bad(e.to_string()))?;
            write_fbx(tmp, &skeleton, &[dancer], fps, &FbxOptions::default()).map_err(|e| here(&e))
        }
        OutputFormat::Bvh => {
            let skeleton = named(parts, rig).map_err(|e| bad(e.to_string()))?;
            let b = skeleton_motion_to_bvh(&skeleton, &parts.poses, &parts.trans, f64::from(fps))
                .map_err(|e| bad(e.to_string()))?;
            write_bvh_file(tmp, &b, &BvhWriteOptions::default()).map_err(|e| here(&e))
        }
        OutputFormat::Npz => write_smplh_npz_with(
            tmp,
            &parts.poses,
            &parts.trans,
            fps,
            Some(parts.face.as_slice()),
            Some(&record.to_json()),
            &SmplNpzOptions::default(),
        )
        .map_err(|e| here(&e)),
        OutputFormat::Csv => livelink_csv::write_file(&parts.face, tmp).map_err(|e| here(&e)),
        OutputFormat::Gif | OutputFormat::Mp4 => Err(bad(
            "a preview shows the body and is drawn by the preview writer".into(),
        )),
    }
}

/// Checks that the parts are one SMPL-H 52 motion of `body`'s length and rate with finite
/// values; returns the frame count.
fn check(parts: &HolisticParts, body: &SmplMotion) -> Result<usize, String> {
    if parts.skeleton.parent_indices() != SMPLH52_PARENTS {
        return Err(format!(
            "the skeleton has {} joints and is not SMPL-H 52's tree",
            parts.skeleton.len()
        ));
    }
    if !parts.trans.len().is_multiple_of(3) {
        return Err(format!(
            "{} pelvis values is not a whole number of frames",
            parts.trans.len()
        ));
    }
    let frames = parts.trans.len() / 3;
    if parts.poses.len() != frames * SMPLH_JOINTS * 3 {
        return Err(format!(
            "{} pose values for {frames} frames of {SMPLH_JOINTS} joints",
            parts.poses.len()
        ));
    }
    if body.frames() != frames || parts.face.frames() != frames {
        return Err(format!(
            "the body has {} frames, the fingers {frames} and the face {}",
            body.frames(),
            parts.face.frames()
        ));
    }
    if parts.face.fps != body.fps {
        return Err(format!(
            "the face is at {} fps and the body at {}",
            parts.face.fps, body.fps
        ));
    }
    if let Some(i) = parts.poses.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "frame {} joint {} has a non-finite rotation",
            i / (SMPLH_JOINTS * 3),
            i / 3 % SMPLH_JOINTS
        ));
    }
    if let Some(i) = parts.trans.iter().position(|v| !v.is_finite()) {
        return Err(format!("frame {} has a non-finite pelvis position", i / 3));
    }
    Ok(frames)
}

/// Bone names: the body's 22 joints as `rig` names them, then the 30 finger joints by their
/// SMPL-X names (SMPL-H order: index, middle, pinky, ring, thumb × 3, left hand then right).
pub(super) fn bone_names(rig: Rig) -> Vec<String> {
    rig.joint_names()
        .into_iter()
        .take(BODY_JOINTS)
        .chain(SMPLH52_NAMES[BODY_JOINTS..].iter().map(|n| n.to_string()))
        .collect()
}

/// The parts' skeleton (rest offsets, tree) under [`bone_names`].
fn named(
    parts: &HolisticParts,
    rig: Rig,
) -> Result<Skeleton, dancegen_motion::skeleton::SkeletonError> {
    Skeleton::new(
        bone_names(rig),
        parts.skeleton.parents().to_vec(),
        parts.skeleton.offsets().to_vec(),
    )
}

fn write_json(
    out: &Path,
    parts: &HolisticParts,
    body: &SmplMotion,
    frames: usize,
) -> Result<(), dancegen_io::atomic::WriteError> {
    let positions =
        fk_axis_angle_f32(&parts.skeleton, &parts.poses, &parts.trans).map_err(|e| {
            dancegen_io::atomic::WriteError {
                path: out.to_path_buf(),
                reason: e.to_string(),
            }
        })?;
    let weights: Vec<&[f32]> = (0..frames).map(|f| parts.face.frame(f)).collect();
    let mut v = serde_json::json!({
        "fps": body.fps,
        "up": "y",
        "units": "metres",
        "joint_names": bone_names(Rig::Smpl),
        "parents": parts.skeleton.parents(),
        "shape": [frames, SMPLH_JOINTS, 3],
        "positions": positions,
        "smpl_poses_axis_angle": body.poses,
        "pelvis_trans": body.trans,
        "smplh_poses_axis_angle": parts.poses,
        "face": {
            "names": &ARKIT_NAMES[..],
            "weights": weights,
        },
    });
    if let Some(flame) = &parts.flame {
        let per_frame = flame.len() / frames.max(1);
        let rows: Vec<&[f32]> = flame.chunks_exact(per_frame.max(1)).collect();
        v["flame"] = serde_json::json!(rows);
    }
    dancegen_io::write_atomic(out, |w| {
        serde_json::to_writer(&mut *w, &v).map_err(std::io::Error::other)
    })
}

#[cfg(test)]
mod tests;
