//! Batched forward kinematics.
//!
//! The rule is EDGE's (anchors.md C.4), written with matrices acting on column vectors:
//! `p[0] = root translation`, `R_world[0] = R_local[0]`, and for `j > 0`
//! `p[j] = R_world[parent] · offset[j] + p[parent]`, `R_world[j] = R_world[parent] · R_local[j]`.
//! The root translation is the pelvis world position ([`crate::conventions`]); data sets that
//! define translation differently (AIST++ adds the rest pelvis and a scale, shared data README)
//! are converted by their importers, not here.
//!
//! Arithmetic is `f64` whatever the storage type, so `f32` and `f64` entry points agree to `f32`
//! rounding. Frames are independent, so they are processed in parallel chunks with one scratch
//! buffer per chunk (no per-frame allocation). Because a skeleton lists parents before children,
//! one pass in index order suffices. Leaf rotations cannot move any joint, so with axis-angle
//! input their Rodrigues conversion is skipped unless world rotations are requested.

use crate::rotation::Mat3;
use crate::skeleton::Skeleton;
use rayon::prelude::*;

/// Frames per parallel work item: large enough to amortise scheduling and the scratch buffer,
/// small enough to balance across threads for short clips.
const CHUNK_FRAMES: usize = 256;

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// Storage scalar accepted by the FK entry points (`f32` or `f64`).
pub trait Real: Copy + Send + Sync + sealed::Sealed {
    fn to_f64(self) -> f64;
    fn from_f64(v: f64) -> Self;
}

impl Real for f32 {
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Real for f64 {
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// Per-frame local joint rotations, flat and frame-major.
#[derive(Debug, Clone, Copy)]
pub enum LocalRotations<'a, T> {
    /// `(T, J, 3)` Rodrigues vectors (SMPL `poses`).
    AxisAngle(&'a [T]),
    /// `(T, J, 3, 3)` row-major rotation matrices.
    Matrix(&'a [T]),
}

impl<T> LocalRotations<'_, T> {
    fn data(&self) -> &[T] {
        match self {
            LocalRotations::AxisAngle(s) | LocalRotations::Matrix(s) => s,
        }
    }

    fn width(&self) -> usize {
        match self {
            LocalRotations::AxisAngle(_) => 3,
            LocalRotations::Matrix(_) => 9,
        }
    }
}

/// Shape errors of the FK inputs and outputs.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FkError {
    #[error(
        "rotation slice has {len} values, not a multiple of {joints} joints × {width} values per joint"
    )]
    RotationShape {
        len: usize,
        joints: usize,
        width: usize,
    },
    #[error(
        "{rotation_frames} frames of rotations but {translation_values} translation values (expected {expected})"
    )]
    TranslationShape {
        rotation_frames: usize,
        translation_values: usize,
        expected: usize,
    },
    #[error("{what} output buffer has {got} values, expected {expected}")]
    OutputShape {
        what: &'static str,
        got: usize,
        expected: usize,
    },
}

/// Result of [`forward_kinematics`].
#[derive(Debug, Clone, PartialEq)]
pub struct FkOutput<T> {
    pub frames: usize,
    pub joints: usize,
    /// `(T, J, 3)` world joint positions.
    pub positions: Vec<T>,
    /// `(T, J, 3, 3)` row-major world rotations, when requested.
    pub world_rotations: Option<Vec<T>>,
}

/// Runs FK over all frames and allocates the outputs. `root_translation` is `(T, 3)`.
pub fn forward_kinematics<T: Real>(
    skeleton: &Skeleton,
    rotations: LocalRotations<'_, T>,
    root_translation: &[T],
    with_world_rotations: bool,
) -> Result<FkOutput<T>, FkError> {
    let joints = skeleton.len();
    let frames = frame_count(skeleton, &rotations, root_translation)?;
    let mut positions = vec![T::from_f64(0.0); frames * joints * 3];
    let mut world = with_world_rotations.then(|| vec![T::from_f64(0.0); frames * joints * 9]);
    forward_kinematics_into(
        skeleton,
        rotations,
        root_translation,
        &mut positions,
        world.as_deref_mut(),
    )?;
    Ok(FkOutput {
        frames,
        joints,
        positions,
        world_rotations: world,
    })
}

/// Axis-angle `(T, J·3)` + translation `(T, 3)` → positions `(T, J, 3)`, `f32` storage.
pub fn fk_axis_angle_f32(
    skeleton: &Skeleton,
    axis_angle: &[f32],
    root_translation: &[f32],
) -> Result<Vec<f32>, FkError> {
    forward_kinematics(
        skeleton,
        LocalRotations::AxisAngle(axis_angle),
        root_translation,
        false,
    )
    .map(|o| o.positions)
}

/// Axis-angle `(T, J·3)` + translation `(T, 3)` → positions `(T, J, 3)`, `f64` storage.
pub fn fk_axis_angle_f64(
    skeleton: &Skeleton,
    axis_angle: &[f64],
    root_translation: &[f64],
) -> Result<Vec<f64>, FkError> {
    forward_kinematics(
        skeleton,
        LocalRotations::AxisAngle(axis_angle),
        root_translation,
        false,
    )
    .map(|o| o.positions)
}

/// Runs FK into caller-provided buffers (`positions`: `T·J·3`, `world_rotations`: `T·J·9`),
/// for callers that reuse memory across clips. Returns the number of frames.
pub fn forward_kinematics_into<T: Real>(
    skeleton: &Skeleton,
    rotations: LocalRotations<'_, T>,
    root_translation: &[T],
    positions: &mut [T],
    world_rotations: Option<&mut [T]>,
) -> Result<usize, FkError> {
    let joints = skeleton.len();
    let frames = frame_count(skeleton, &rotations, root_translation)?;
    check_output("positions", positions.len(), frames * joints * 3)?;
    if let Some(w) = world_rotations.as_deref() {
        check_output("world rotations", w.len(), frames * joints * 9)?;
    }
    if frames == 0 {
        return Ok(0);
    }

    let plan = Plan {
        skeleton,
        axis_angle: matches!(rotations, LocalRotations::AxisAngle(_)),
        needed: {
            let mut needed = skeleton.has_children();
            if world_rotations.is_some() {
                needed.iter_mut().for_each(|n| *n = true);
            }
            needed
        },
    };
    let rot_stride = joints * rotations.width();
    let rot_chunks = rotations.data().par_chunks(CHUNK_FRAMES * rot_stride);
    let trans_chunks = root_translation.par_chunks(CHUNK_FRAMES * 3);
    let pos_chunks = positions.par_chunks_mut(CHUNK_FRAMES * joints * 3);
    match world_rotations {
        Some(w) => {
            let w_chunks = w.par_chunks_mut(CHUNK_FRAMES * joints * 9);
            rot_chunks
                .zip(trans_chunks)
                .zip(pos_chunks)
                .zip(w_chunks)
                .for_each(|(((r, t), p), w)| plan.run_chunk(r, t, p, Some(w)));
        }
        None => {
            rot_chunks
                .zip(trans_chunks)
                .zip(pos_chunks)
                .for_each(|((r, t), p)| plan.run_chunk(r, t, p, None));
        }
    }
    Ok(frames)
}

/// Single-frame FK in `f64`, the kernel of the batched functions. `local`, `positions` and
/// `world` all have one entry per joint.
///
/// # Panics
/// If the slice lengths differ from the skeleton's joint count.
pub fn fk_frame(
    skeleton: &Skeleton,
    local: &[Mat3],
    root_translation: [f64; 3],
    positions: &mut [[f64; 3]],
    world: &mut [Mat3],
) {
    let j = skeleton.len();
    assert!(local.len() == j && positions.len() == j && world.len() == j);
    for (k, (parent, offset)) in skeleton
        .parents()
        .iter()
        .zip(skeleton.offsets())
        .enumerate()
    {
        match *parent {
            None => {
                positions[k] = root_translation;
                world[k] = local[k];
            }
            Some(p) => {
                let d = world[p].mul_vec(*offset);
                let pp = positions[p];
                positions[k] = [pp[0] + d[0], pp[1] + d[1], pp[2] + d[2]];
                world[k] = world[p].mul(&local[k]);
            }
        }
    }
}

fn frame_count<T>(
    skeleton: &Skeleton,
    rotations: &LocalRotations<'_, T>,
    root_translation: &[T],
) -> Result<usize, FkError> {
    let joints = skeleton.len();
    let width = rotations.width();
    let len = rotations.data().len();
    if !len.is_multiple_of(joints * width) {
        return Err(FkError::RotationShape { len, joints, width });
    }
    let frames = len / (joints * width);
    if root_translation.len() != frames * 3 {
        return Err(FkError::TranslationShape {
            rotation_frames: frames,
            translation_values: root_translation.len(),
            expected: frames * 3,
        });
    }
    Ok(frames)
}

fn check_output(what: &'static str, got: usize, expected: usize) -> Result<(), FkError> {
    if got == expected {
        Ok(())
    } else {
        Err(FkError::OutputShape {
            what,
            got,
            expected,
        })
    }
}

/// Per-call constants shared by all chunks.
struct Plan<'s> {
    skeleton: &'s Skeleton,
    axis_angle: bool,
    /// Joints whose world rotation must be computed (parents, or all when output is requested).
    needed: Vec<bool>,
}

impl Plan<'_> {
    fn run_chunk<T: Real>(
        &self,
        rot: &[T],
        trans: &[T],
        pos_out: &mut [T],
        mut world_out: Option<&mut [T]>,
    ) {
        let joints = self.skeleton.len();
        let parents = self.skeleton.parents();
        let offsets = self.skeleton.offsets();
        let width = if self.axis_angle { 3 } else { 9 };
        // Scratch reused for every frame of the chunk.
        let mut world = vec![Mat3::IDENTITY; joints];
        let mut pos = vec![[0.0f64; 3]; joints];

        for (f, t) in trans.chunks_exact(3).enumerate() {
            let r = &rot[f * joints * width..(f + 1) * joints * width];
            for k in 0..joints {
                let local = if !self.needed[k] {
                    Mat3::IDENTITY
                } else if self.axis_angle {
                    let a = &r[k * 3..k * 3 + 3];
                    Mat3::from_axis_angle([a[0].to_f64(), a[1].to_f64(), a[2].to_f64()])
                } else {
                    let m = &r[k * 9..k * 9 + 9];
                    Mat3(std::array::from_fn(|i| {
                        std::array::from_fn(|c| m[i * 3 + c].to_f64())
                    }))
                };
                match parents[k] {
                    None => {
                        pos[k] = [t[0].to_f64(), t[1].to_f64(), t[2].to_f64()];
                        world[k] = local;
                    }
                    Some(p) => {
                        let d = world[p].mul_vec(offsets[k]);
                        let pp = pos[p];
                        pos[k] = [pp[0] + d[0], pp[1] + d[1], pp[2] + d[2]];
                        if self.needed[k] {
                            world[k] = world[p].mul(&local);
                        }
                    }
                }
            }
            let out = &mut pos_out[f * joints * 3..(f + 1) * joints * 3];
            for (o, p) in out.chunks_exact_mut(3).zip(&pos) {
                o[0] = T::from_f64(p[0]);
                o[1] = T::from_f64(p[1]);
                o[2] = T::from_f64(p[2]);
            }
            if let Some(w) = world_out.as_deref_mut() {
                let out = &mut w[f * joints * 9..(f + 1) * joints * 9];
                for (o, m) in out.chunks_exact_mut(9).zip(&world) {
                    for (dst, src) in o.iter_mut().zip(m.0.iter().flatten()) {
                        *dst = T::from_f64(*src);
                    }
                }
            }
        }
    }
}
