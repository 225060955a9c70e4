//! FBX 7.4 binary (`.fbx`) export of animated skeletons with a simple skinned body — the format
//! Maya, MotionBuilder, Unity, Unreal and Blender all import — written natively (no FBX SDK, no
//! Blender), with `fbxcel`'s binary writer doing the byte-level encoding.
//!
//! The scene mirrors [`crate::gltf`]'s: per dancer a skeleton of one `LimbNode` per joint, the
//! same capsule body (`capsule_mesh.rs`) skinned to it, and one animation that moves all
//! dancers together.
//!
//! # Conventions (stated once; everything below follows from them)
//! - **Axes: Y-up, right-handed**, as [`dancegen_motion::conventions`]: `GlobalSettings` says
//!   `UpAxis = 1 (+Y)`, `FrontAxis = 2 (+Z)`, `CoordAxis = 0 (+X)`, all signs `+1` — the FBX
//!   SDK's `FbxAxisSystem::MayaYUp`. Nothing is converted.
//! - **Units: metres, declared as such.** FBX's native unit is the centimetre; the file keeps
//!   dancegen's metres unchanged and says so with `UnitScaleFactor = 100` (centimetres per file
//!   unit, also `OriginalUnitScaleFactor`). Readers then scale correctly: ufbx reports
//!   `unit_meters = 1`, Blender imports at scale 1 (its global scale is `UnitScaleFactor / 100`
//!   for a metric scene), Unity's "Convert Units" gives 1 unit = 1 m. (assimp's exporter writes
//!   metres but declares centimetres, so readers shrink its figures 100×; ecosystem.md §0.)
//! - **Time: KTime**, 46,186,158,000 ticks per second (FBX SDK `FbxTime`; ufbx
//!   `metadata.ktime_second`). Frame `f` is keyed at `round(f · 46186158000 / fps)`; the stack,
//!   the take and `TimeSpanStart/Stop` run from frame 0 to frame `T − 1`. `TimeMode` is the FBX
//!   SDK's `FbxTime::EMode` for the standard rates (30 fps → 6 `eFrames30`, 24 → 11, 60 → 3, …,
//!   [`time_mode`]) and 14 (`eCustom`) otherwise; `CustomFrameRate` always holds the rate.
//! - **Rotations: `Lcl Rotation` Euler angles in degrees with `RotationOrder` 0 (`eEulerXYZ`)**,
//!   which means `R = Rz · Ry · Rx` on column vectors (X applied first). Each joint's local
//!   axis-angle rotation is converted exactly (in `f64`, stored as the `f32` key values FBX
//!   curves hold) and made continuous over time — no ±360° jumps, no switching between the two
//!   Euler triples of one rotation — because FBX interpolates each angle separately
//!   (`fbx/euler.rs`). Keys are LINEAR (`KeyAttrFlags` = `eInterpolationLinear`, 0x4). Every
//!   key is exact; *between* keys an Euler curve only approximates the shortest rotation, worst
//!   near XYZ gimbal lock (Euler Y = ±90°, which a spin about the vertical axis passes twice a
//!   turn). Importers that resample to quaternions at the keys (Blender, Unity's default
//!   "Resample Curves") are unaffected.
//! - **Root translation:** each dancer's root joint (joint 0) carries a `T` curve node with
//!   `root_translation` — the **pelvis world position** of [`dancegen_motion::conventions`] — which
//!   *replaces* its rest `Lcl Translation` (`offsets()[0]`). Its parent is the dancer's `Null`
//!   at the origin with identity transform, so in every frame joint 0 is exactly at
//!   `root_translation[t]` and every other joint where [`dancegen_motion::forward_kinematics`] puts it:
//!   joint `j` has the static `Lcl Translation = offsets()[j]` and the animated rotation.
//! - **Rest / bind pose:** rest rotations are identity, so joint `j`'s rest world transform is
//!   the translation to its rest position (`offsets()[0]` plus the cumulative offsets). The
//!   `BindPose` lists those matrices (and identity for the `Null` and the mesh); each joint's
//!   skin `Cluster` has `TransformLink` = that matrix and `Transform` = its inverse (the mesh
//!   sits at the origin), the vertices of the capsules it moves (weight 1) in `Indexes`.
//!
//! # Layout
//! Per dancer `d`: a `Null` model (named `armature` for a single dancer, `dancer{d}` for a
//! group; Blender turns it into the armature object), under it the joint `LimbNode` models
//! (named after the joints; `dancer{d}/<joint>` for a group, as [`crate::gltf`] names them)
//! each with a `Skeleton` node attribute, and the mesh model (`body`, `dancer{d}/body`) with
//! its `Geometry`, `Material` (colour as [`crate::gltf`]: [`crate::gltf::GlbOptions::base_color`]
//! for dancer 0, [`crate::gltf::EXTRA_DANCER_COLORS`] after), a `Skin` deformer with one `Cluster`
//! per joint, and a `BindPose`. Per joint an `R` curve node (three curves, `d|X`, `d|Y`, `d|Z`)
//! on `Lcl Rotation`, and on the root a `T` node on `Lcl Translation`. All dancers share one
//! `AnimationStack` ([`FbxOptions::animation_name`]) and its one `AnimationLayer`.
//!
//! Output is deterministic: object ids are counters, and the header's time stamps are fixed
//! (the `FileId`/`CreationTime`/footer triple is the one the FBX SDK accepts, see `tree.rs`), so
//! the same motion always gives the same bytes.

mod euler;
mod scene;
mod sections;
mod tree;

use crate::gltf::DancerAnimation;
use crate::scene_input::{SceneInputError, check_scene};
use dancegen_motion::skeleton::Skeleton;
use std::path::{Path, PathBuf};

/// FBX time ticks per second (FBX SDK `FbxTime`, since FBX 7; ufbx `ktime_second`).
pub const KTIME_PER_SECOND: i64 = 46_186_158_000;

/// Centimetres per file unit written as `UnitScaleFactor`: the file's numbers are metres.
pub const UNIT_SCALE_FACTOR: f64 = 100.0;

/// Appearance and naming of the exported figure: the same capsule body, colours and animation
/// name as the `.glb` ([`crate::gltf::GlbOptions`]), so both files show the same figure.
pub type FbxOptions = crate::gltf::GlbOptions;

/// Why the inputs cannot be exported as FBX.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FbxInputError {
    /// What every scene format checks ([`crate::scene_input`]).
    #[error(transparent)]
    Scene(#[from] SceneInputError),
    #[error(
        "{frames} frames at {fps} fps do not fit FBX time (1/46186158000 s ticks in 64 bits, \
         strictly increasing)"
    )]
    TimeOutOfRange { frames: usize, fps: f32 },
    /// A name FBX cannot hold (NUL characters).
    #[error("bad options: {0}")]
    Options(String),
    #[error("the mesh or skeleton is too large for FBX's 32-bit indices ({0})")]
    TooLarge(String),
    /// The binary encoder failed (it writes to memory, so this is not expected).
    #[error("FBX encoding failed: {0}")]
    Encode(String),
}

/// An `.fbx` that could not be written; both variants name the path.
#[derive(Debug, thiserror::Error)]
pub enum FbxError {
    #[error("{path}: cannot export FBX: {reason}")]
    Input {
        path: PathBuf,
        reason: FbxInputError,
    },
    #[error(transparent)]
    Write(#[from] dancegen_io::atomic::WriteError),
}

/// Writes the dancers (one or more, sharing `skeleton` and one timeline) as an `.fbx` file,
/// atomically (see the module docs for the layout and conventions).
///
/// Each dancer's `local_rotations_axis_angle` is `T×J×3` (radians, parent-relative) and
/// `root_translation` is `T×3` (metres, pelvis world position); `fps` is the motion's frame rate.
pub fn write_fbx(
    path: impl AsRef<Path>,
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    opts: &FbxOptions,
) -> Result<(), FbxError> {
    let path = path.as_ref();
    let bytes = fbx_bytes(skeleton, dancers, fps, opts).map_err(|reason| FbxError::Input {
        path: path.to_path_buf(),
        reason,
    })?;
    dancegen_io::write_atomic(path, |w| w.write_all(&bytes))?;
    Ok(())
}

/// The `.fbx` file contents for [`write_fbx`].
pub fn fbx_bytes(
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    opts: &FbxOptions,
) -> Result<Vec<u8>, FbxInputError> {
    let frames = check_inputs(skeleton, dancers, fps, opts)?;
    let key_times = key_times(frames, fps)?;
    let top = scene::build(skeleton, dancers, fps, &key_times, opts)?;
    tree::encode(&top).map_err(|e| FbxInputError::Encode(e.to_string()))
}

/// `TimeMode` for a frame rate: the FBX SDK's `FbxTime::EMode` value of a standard rate
/// (`eFrames120` = 1, `eFrames100` = 2, `eFrames60` = 3, `eFrames50` = 4, `eFrames48` = 5,
/// `eFrames30` = 6, `ePAL` (25) = 10, `eFrames24` = 11, `eFrames96` = 15, `eFrames72` = 16), else
/// `eCustom` = 14 with the rate in `CustomFrameRate`. (ufbx's `ufbx_time_mode` uses the same
/// numbers.) `eFrames1000` (12) is left out: Blender's importer does not accept it.
pub fn time_mode(fps: f32) -> i32 {
    const STANDARD: [(f32, i32); 10] = [
        (120.0, 1),
        (100.0, 2),
        (60.0, 3),
        (50.0, 4),
        (48.0, 5),
        (30.0, 6),
        (25.0, 10),
        (24.0, 11),
        (96.0, 15),
        (72.0, 16),
    ];
    STANDARD
        .iter()
        .find(|(rate, _)| *rate == fps)
        .map_or(TIME_MODE_CUSTOM, |&(_, mode)| mode)
}

/// `FbxTime::eCustom`: the frame rate is `CustomFrameRate`.
const TIME_MODE_CUSTOM: i32 = 14;

/// Key time of each frame in KTime ticks, strictly increasing.
fn key_times(frames: usize, fps: f32) -> Result<Vec<i64>, FbxInputError> {
    let out_of_range = || FbxInputError::TimeOutOfRange { frames, fps };
    let ticks_per_frame = KTIME_PER_SECOND as f64 / fps as f64;
    let mut times = Vec::with_capacity(frames);
    for f in 0..frames {
        let t = (f as f64 * ticks_per_frame).round();
        // i64::MAX is not exactly representable; stay well below it.
        if !(t.is_finite() && t < 9.0e18) {
            return Err(out_of_range());
        }
        let t = t as i64;
        if times.last().is_some_and(|&prev| t <= prev) {
            return Err(out_of_range());
        }
        times.push(t);
    }
    Ok(times)
}

/// Validates all inputs and returns the frame count.
fn check_inputs(
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    opts: &FbxOptions,
) -> Result<usize, FbxInputError> {
    let joints = skeleton.len();
    let frames = check_scene(
        joints,
        dancers,
        fps,
        &opts.capsule_shape(),
        &opts.base_color,
    )?;
    if opts.animation_name.contains('\0') {
        return Err(FbxInputError::Options(
            "animation_name must not contain NUL characters".to_string(),
        ));
    }
    if let Some(name) = skeleton.names().iter().find(|n| n.contains('\0')) {
        return Err(FbxInputError::Options(format!(
            "joint name {name:?} contains a NUL character, which FBX names cannot hold"
        )));
    }
    if joints > u16::MAX as usize {
        return Err(FbxInputError::TooLarge(format!("{joints} joints")));
    }
    Ok(frames)
}
