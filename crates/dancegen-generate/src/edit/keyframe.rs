//! `--keyframe POSE@T`: a pose the dancer reaches at a time of the song.
//!
//! POSE is a motion file `convert` reads; its first frame is the pose, or frame `N` (from 0, the
//! file's own frames) with `POSE:N`. T is seconds from the song's start, as the `t` of a
//! FORMATION.json or `--path` keyframe.

use std::path::{Path, PathBuf};

use dancegen_motion::repr::motion::POSE_DIMS;

use super::given::GivenMotion;
use crate::error::GenerateError;

/// One `--keyframe`: the pose and when it is reached.
#[derive(Clone, Debug)]
pub struct KeyframePose {
    /// As the user wrote it (`pose.npz:3@4.5`), for messages.
    pub spec: String,
    /// Seconds from the song's start.
    pub t: f64,
    /// SMPL 24 local rotations (72 axis-angle values), the root's being its world orientation.
    pub pose: Vec<f32>,
    /// The pelvis position, Y-up metres, in the pose file's world with its floor at y = 0.
    pub trans: [f32; 3],
}

/// `POSE[:FRAME]@T` split into the file, the frame (0 when not given) and the time, or what
/// is wrong with it.
pub fn parse_keyframe_spec(spec: &str) -> Result<(PathBuf, usize, f64), String> {
    let bad = |why: &str| format!("--keyframe {spec}: {why} (write POSE@T or POSE:FRAME@T)");
    let (pose, t) = spec
        .rsplit_once('@')
        .ok_or_else(|| bad("no @T, the time in seconds"))?;
    let t: f64 = t
        .trim()
        .parse()
        .ok()
        .filter(|t: &f64| t.is_finite() && *t >= 0.0)
        .ok_or_else(|| bad(&format!("{t:?} is not a time in seconds from 0")))?;
    let (file, frame) = match pose.rsplit_once(':') {
        Some((file, n)) if !file.is_empty() && !n.is_empty() && !n.contains(['/', '\\']) => {
            let frame = n
                .trim()
                .parse()
                .map_err(|_| bad(&format!("{n:?} is not a frame number")))?;
            (file, frame)
        }
        _ => (pose, 0),
    };
    if file.is_empty() {
        return Err(bad("no POSE file"));
    }
    Ok((PathBuf::from(file), frame, t))
}

impl KeyframePose {
    /// Reads `--keyframe SPEC`: the file, its frame, the time. A frame the file does not have
    /// is an error naming the file and how many frames it has.
    pub fn load(spec: &str) -> Result<Self, GenerateError> {
        let (path, frame, t) = parse_keyframe_spec(spec).map_err(GenerateError::Invalid)?;
        Self::from_file(spec, &path, frame, t)
    }

    fn from_file(spec: &str, path: &Path, frame: usize, t: f64) -> Result<Self, GenerateError> {
        let mut m = GivenMotion::load_frames(path, "a --keyframe pose")
            .map_err(|e| GenerateError::Invalid(format!("--keyframe {spec}: {e}")))?
            .motion;
        // Heights over the file's own floor (where its planted feet are; the lowest foot of a
        // one-frame file), so that a pose from another capture stands on the dance's floor.
        m.put_feet_on_floor().map_err(|e| {
            GenerateError::Invalid(format!("--keyframe {spec}: {}: {e}", path.display()))
        })?;
        if frame >= m.frames() {
            return Err(GenerateError::Invalid(format!(
                "--keyframe {spec}: {} has no frame {frame}; it has {} (0 to {})",
                path.display(),
                m.frames(),
                m.frames().saturating_sub(1)
            )));
        }
        Ok(KeyframePose {
            spec: spec.to_string(),
            t,
            pose: m.poses[frame * POSE_DIMS..(frame + 1) * POSE_DIMS].to_vec(),
            trans: [0, 1, 2].map(|c| m.trans[frame * 3 + c]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_split_into_file_frame_and_time() {
        assert_eq!(
            parse_keyframe_spec("pose.npz@4.5").unwrap(),
            (PathBuf::from("pose.npz"), 0, 4.5)
        );
        assert_eq!(
            parse_keyframe_spec("dir/take.bvh:120@10").unwrap(),
            (PathBuf::from("dir/take.bvh"), 120, 10.0)
        );
        // A colon in a directory name is part of the file.
        assert_eq!(
            parse_keyframe_spec("C:/poses/a.npz@1").unwrap(),
            (PathBuf::from("C:/poses/a.npz"), 0, 1.0)
        );
        for (bad, words) in [
            ("pose.npz", "no @T"),
            ("pose.npz@-1", "not a time"),
            ("pose.npz@x", "not a time"),
            ("pose.npz:a@1", "not a frame number"),
            ("@3", "no POSE file"),
        ] {
            let e = parse_keyframe_spec(bad).unwrap_err();
            assert!(e.contains("--keyframe") && e.contains(words), "{bad}: {e}");
        }
    }
}
