//! The input checks every scene exporter (`.glb`, `.fbx`) makes before writing: the dancers'
//! arrays fit the skeleton and each other, values are finite, the frame rate and the capsule
//! body's look make sense. Each format adds only its own limits (key-time precision, index
//! sizes) in its own error type, which wraps [`SceneInputError`].

use crate::capsule_mesh::CapsuleShape;

/// One dancer's motion as every scene exporter takes it (`gltf::write_glb`, `fbx`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DancerAnimation<'a> {
    /// `T×J×3` local axis-angle rotations (radians).
    pub local_rotations_axis_angle: &'a [f32],
    /// `T×3` pelvis world positions (metres).
    pub root_translation: &'a [f32],
}

/// Why dancers cannot be exported, whatever the format.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneInputError {
    #[error("motion has no frames (a single-frame pose is fine, zero frames is not)")]
    NoFrames,
    #[error(
        "rotations have {len} values, not a multiple of {joints} joints × 3 (axis-angle, T×J×3)"
    )]
    RotationShape { len: usize, joints: usize },
    #[error("{frames} frames of rotations but {got} root translation values (expected {expected})")]
    TranslationShape {
        frames: usize,
        got: usize,
        expected: usize,
    },
    #[error("{what} value {index} is not finite ({value})")]
    NonFinite {
        what: &'static str,
        index: usize,
        value: f32,
    },
    #[error("fps must be finite and positive, got {0}")]
    BadFps(f32),
    #[error("bad options: {0}")]
    Options(String),
    #[error("no dancers to export")]
    NoDancers,
    #[error(
        "dancer {dancer} has {frames} frames but dancer 0 has {first}; dancers in one file share \
         one timeline"
    )]
    FrameCountMismatch {
        dancer: usize,
        frames: usize,
        first: usize,
    },
    /// Only used with several dancers, so the message says whose data is wrong.
    #[error("dancer {dancer}: {reason}")]
    Dancer {
        dancer: usize,
        reason: Box<SceneInputError>,
    },
}

/// Checks `dancers` on a skeleton of `joints` joints at `fps`, and the body's `shape` and
/// `base_color`; returns the frame count every dancer shares.
pub(crate) fn check_scene(
    joints: usize,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    shape: &CapsuleShape,
    base_color: &[f32; 4],
) -> Result<usize, SceneInputError> {
    if dancers.is_empty() {
        return Err(SceneInputError::NoDancers);
    }
    let many = dancers.len() > 1;
    let mut frames = 0;
    for (d, dancer) in dancers.iter().enumerate() {
        let f = check_dancer(joints, dancer).map_err(|e| {
            if many {
                SceneInputError::Dancer {
                    dancer: d,
                    reason: Box::new(e),
                }
            } else {
                e
            }
        })?;
        if d == 0 {
            frames = f;
        } else if f != frames {
            return Err(SceneInputError::FrameCountMismatch {
                dancer: d,
                frames: f,
                first: frames,
            });
        }
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(SceneInputError::BadFps(fps));
    }
    if shape.sides < 3 {
        return Err(SceneInputError::Options(format!(
            "sides must be at least 3, got {}",
            shape.sides
        )));
    }
    let positive = |v: f32| v.is_finite() && v > 0.0;
    if !positive(shape.bone_radius) || !positive(shape.taper) {
        return Err(SceneInputError::Options(format!(
            "bone_radius and taper must be finite and positive, got {} and {}",
            shape.bone_radius, shape.taper
        )));
    }
    if base_color.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(SceneInputError::Options(format!(
            "base_color components must lie in [0, 1], got {base_color:?}"
        )));
    }
    Ok(frames)
}

/// Validates one dancer's arrays and returns its frame count.
fn check_dancer(joints: usize, dancer: &DancerAnimation<'_>) -> Result<usize, SceneInputError> {
    let rot = dancer.local_rotations_axis_angle;
    let root_translation = dancer.root_translation;
    if !rot.len().is_multiple_of(joints * 3) {
        return Err(SceneInputError::RotationShape {
            len: rot.len(),
            joints,
        });
    }
    let frames = rot.len() / (joints * 3);
    if frames == 0 {
        return Err(SceneInputError::NoFrames);
    }
    if root_translation.len() != frames * 3 {
        return Err(SceneInputError::TranslationShape {
            frames,
            got: root_translation.len(),
            expected: frames * 3,
        });
    }
    check_finite("rotation", rot)?;
    check_finite("root translation", root_translation)?;
    Ok(frames)
}

fn check_finite(what: &'static str, v: &[f32]) -> Result<(), SceneInputError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(SceneInputError::NonFinite {
            what,
            index,
            value: v[index],
        }),
        None => Ok(()),
    }
}
