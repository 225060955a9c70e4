//! A dancer's motion given to a job: a dance to edit, a motion to continue, joints to keep, a
//! keyframe pose. Any format `convert` reads, as SMPL 24 at the generator's 30 fps.

use std::path::Path;

use dancegen_formats::dispatch::{
    ConvertOptions, LoadOptions, LoadedMotion, convert_motion, load_motion_file_with,
};
use dancegen_motion::repr::SmplMotion;

use crate::error::GenerateError;
use crate::song::FPS;

/// One dancer's motion given to a job (a leader, a dance to edit, a motion to continue): SMPL 24
/// at 30 fps, with the name messages use for it (its file).
#[derive(Clone, Debug)]
pub struct GivenMotion {
    pub label: String,
    pub motion: SmplMotion,
}

impl GivenMotion {
    /// `path` as one dancer at 30 fps, or an error naming the file and `what` it is for. Any
    /// format `convert` reads; a humanoid BVH is retargeted. `source_fps` overrides the file's
    /// rate; a file without a usable rate is refused with `rate_hint` as the way to give one.
    pub fn load(
        path: &Path,
        what: &str,
        source_fps: Option<f64>,
        rate_hint: &'static str,
    ) -> Result<Self, GenerateError> {
        Self::load_as(path, what, source_fps, rate_hint, Some(FPS as f32))
    }

    /// `path`'s frames as they are in the file, not resampled (its rate does not matter: a
    /// pose, for `--keyframe`).
    pub fn load_frames(path: &Path, what: &str) -> Result<Self, GenerateError> {
        Self::load_as(path, what, Some(f64::from(FPS)), "", None)
    }

    fn load_as(
        path: &Path,
        what: &str,
        source_fps: Option<f64>,
        rate_hint: &'static str,
        fps: Option<f32>,
    ) -> Result<Self, GenerateError> {
        let invalid = |why: String| GenerateError::Invalid(format!("{}: {why}", path.display()));
        let read = LoadOptions {
            source_fps,
            rate_hint,
        };
        let loaded = load_motion_file_with(path, &read)?;
        let opts = ConvertOptions {
            to_smpl24: true,
            fps,
            ..Default::default()
        };
        // The conversion's error already names the file.
        let m = match convert_motion(path, loaded, &opts).map_err(|e| {
            GenerateError::Invalid(format!(
                "{e} ({what} must be one humanoid dancer that retargets to SMPL 24)"
            ))
        })? {
            LoadedMotion::Smpl(m) => m,
            LoadedMotion::Group(g) => {
                return Err(invalid(format!(
                    "{} dancers; {what} must be one dancer",
                    g.len()
                )));
            }
            other => {
                return Err(invalid(format!(
                    "a {} has no joint rotations for {what} (give SMPL motion or a humanoid BVH)",
                    other.kind()
                )));
            }
        };
        if m.poses.iter().chain(&m.trans).any(|v| !v.is_finite()) {
            return Err(invalid("the motion holds NaN or infinite values".into()));
        }
        Ok(Self {
            label: path.display().to_string(),
            motion: m,
        })
    }

    pub fn seconds(&self) -> f64 {
        self.motion.frames() as f64 / f64::from(FPS)
    }
}
