//! Motion files read as dancers ready to pair: SMPL 24 at 30 fps, and their mirror images.

use std::path::{Path, PathBuf};

use dancegen_formats::dispatch::{
    ConvertOptions, LoadedMotion, convert_motion, load_motion_file_with,
};
use dancegen_motion::repr::motion::SmplMotion;

use crate::FPS;
use crate::error::DatasetError;
use crate::rates::{RateFrom, SourceRates};
use crate::song::stem;

/// World joints `(T, 24, 3)` of a motion, `source` naming it in errors.
pub(crate) fn world_joints(m: &SmplMotion, source: &Path) -> Result<Vec<f64>, DatasetError> {
    let j = m
        .joints_world()
        .map_err(|e| DatasetError::input(source, format!("forward kinematics failed: {e}")))?;
    Ok(j.into_iter().map(f64::from).collect())
}

/// One dancer's motion at 30 fps, ready to be paired.
#[derive(Clone, Debug)]
pub(crate) struct MotionUnit {
    /// Clip name (pieces get `_<k>` appended).
    pub name: String,
    /// Stem of the source file (what `--hold-out` names).
    pub stem: String,
    pub source: PathBuf,
    pub genre: String,
    pub motion: SmplMotion,
    /// The rate the source file was read at, and where it came from.
    pub source_fps: f64,
    pub rate_from: RateFrom,
}

/// Loads a motion file as SMPL 24 at 30 fps: BVH retargeted, 60 fps strided (EDGE), each dancer
/// of a group file separately (`<stem>_d<k>`).
pub(crate) fn load_units(
    path: &Path,
    genre: &str,
    rates: &SourceRates,
) -> Result<Vec<MotionUnit>, DatasetError> {
    let given = rates.rate_for(path);
    let read = dancegen_formats::dispatch::LoadOptions {
        source_fps: given,
        ..Default::default()
    };
    let loaded = load_motion_file_with(path, &read)?;
    let source_fps = f64::from(loaded.fps());
    let rate_from = if given.is_some() {
        RateFrom::Given
    } else {
        RateFrom::Header
    };
    let opts = ConvertOptions {
        to_smpl24: true,
        fps: Some(FPS as f32),
        ..Default::default()
    };
    let converted = convert_motion(path, loaded, &opts)?;
    let s = stem(path);
    let unit = |name: String, motion: SmplMotion| MotionUnit {
        name,
        stem: s.clone(),
        source: path.to_path_buf(),
        genre: genre.to_string(),
        motion,
        source_fps,
        rate_from,
    };
    match converted {
        LoadedMotion::Smpl(m) => Ok(vec![unit(s.clone(), m)]),
        LoadedMotion::Group(g) => Ok(g
            .into_iter()
            .enumerate()
            .map(|(k, m)| unit(format!("{s}_d{k}"), m))
            .collect()),
        other => Err(DatasetError::input(
            path,
            format!("a {} has no SMPL rotations to train on", other.kind()),
        )),
    }
}

/// The left–right mirror image of a unit, as its own clip (`<name>_mirror`); the stem stays,
/// so a `--hold-out` of the take covers both.
pub(crate) fn mirrored_unit(u: &MotionUnit) -> MotionUnit {
    MotionUnit {
        name: format!("{}_mirror", u.name),
        motion: u.motion.mirror(),
        ..u.clone()
    }
}
