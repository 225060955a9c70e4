//! A dancer's motion given to a job: a dance to edit, a motion to continue, joints to keep, a
//! keyframe pose. Any format `convert` reads, as SMPL 24 at the generator's 30 fps.

use std::path::{Path, PathBuf};

use dancegen_formats::dispatch::{
    ConvertOptions, LoadOptions, LoadedMotion, convert_motion, load_motion_file_with,
};
use dancegen_motion::repr::SmplMotion;

use crate::error::GenerateError;
use crate::song::FPS;

/// Motion given to a job (a leader, a dance to edit, a motion to continue): SMPL 24 at 30 fps,
/// with the name messages use for it (its file). One dancer, or a group's dancers (a group
/// dance to edit or continue).
#[derive(Clone, Debug)]
pub struct GivenMotion {
    pub label: String,
    /// The dancer (a group's first).
    pub motion: SmplMotion,
    /// Every dancer of a group, in order; empty for one dancer.
    pub group: Vec<SmplMotion>,
    /// The fingers and face of a holistic dance dancegen wrote (its `.npz` holds them), frame
    /// for frame with `motion`.
    pub holistic: Option<HolisticGiven>,
}

/// The fingers and face of a given dance: SMPL-H 52 local rotations `(T, 156)` (the body's
/// first 22 joints as in `motion`) and the 52 ARKit weights `(T, 52)`, at 30 fps.
#[derive(Clone, Debug)]
pub struct HolisticGiven {
    pub poses: Vec<f32>,
    pub face: Vec<f32>,
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
        Self::load_as(path, what, source_fps, rate_hint, Some(FPS as f32), false)
    }

    /// [`Self::load`], where a group is welcome too (a dance to edit or a motion to continue
    /// or keep joints from): a file holding several dancers, or one of the `NAME_K.npz` files
    /// a group dance wrote (its record names the group: every `NAME_K.npz` beside it is
    /// read).
    pub fn load_dance(
        path: &Path,
        what: &str,
        source_fps: Option<f64>,
        rate_hint: &'static str,
    ) -> Result<Self, GenerateError> {
        let path = &dance_file(path);
        let record = crate::record::DanceRecord::read(path)?;
        let Some(r) = record.filter(|r| r.system == "group" && r.dancers > 1) else {
            return Self::load_as(path, what, source_fps, rate_hint, Some(FPS as f32), true);
        };
        let files = group_files(path, r.dancer, r.dancers)?;
        let dancers = files
            .iter()
            .map(|f| Self::load(f, what, source_fps, rate_hint))
            .collect::<Result<Vec<_>, _>>()?;
        let stem = files[0].with_file_name(
            files[0]
                .file_name()
                .map(|n| n.to_string_lossy().replacen("_0.npz", "_K.npz", 1))
                .unwrap_or_default(),
        );
        Self::of_group(stem.display().to_string(), dancers)
    }

    /// `path`'s frames as they are in the file, not resampled (its rate does not matter: a
    /// pose, for `--keyframe`).
    pub fn load_frames(path: &Path, what: &str) -> Result<Self, GenerateError> {
        Self::load_as(path, what, Some(f64::from(FPS)), "", None, false)
    }

    fn load_as(
        path: &Path,
        what: &str,
        source_fps: Option<f64>,
        rate_hint: &'static str,
        fps: Option<f32>,
        group: bool,
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
            LoadedMotion::Group(g) if group && g.len() > 1 => {
                let label = path.display().to_string();
                let dancers = g
                    .into_iter()
                    .enumerate()
                    .map(|(k, m)| Self::checked(format!("{label} (dancer {k})"), m))
                    .collect::<Result<Vec<_>, _>>()?;
                return Self::of_group(label, dancers);
            }
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
        let mut given = Self::checked(path.display().to_string(), m)?;
        if group {
            given.holistic = holistic_of(path, &given.motion)?;
        }
        Ok(given)
    }

    /// `m` under `label`, refused when it holds NaN or infinite values.
    fn checked(label: String, m: SmplMotion) -> Result<Self, GenerateError> {
        if m.poses.iter().chain(&m.trans).any(|v| !v.is_finite()) {
            return Err(GenerateError::Invalid(format!(
                "{label}: the motion holds NaN or infinite values"
            )));
        }
        Ok(Self::one(label, m))
    }

    /// One dancer's motion.
    pub fn one(label: String, motion: SmplMotion) -> Self {
        Self {
            label,
            motion,
            group: Vec::new(),
            holistic: None,
        }
    }

    /// A group's dancers (at least two, the same length), under one label.
    pub fn of_group(label: String, dancers: Vec<GivenMotion>) -> Result<Self, GenerateError> {
        let Some(first) = dancers.first() else {
            return Err(GenerateError::Invalid(format!("{label}: no dancer")));
        };
        if let Some(d) = dancers
            .iter()
            .find(|d| d.motion.frames() != first.motion.frames())
        {
            return Err(GenerateError::Invalid(format!(
                "{label}: {} has {} frames and {} has {}; a group's dancers dance the same \
                 frames",
                first.label,
                first.motion.frames(),
                d.label,
                d.motion.frames()
            )));
        }
        Ok(Self {
            label,
            motion: first.motion.clone(),
            group: dancers.into_iter().map(|d| d.motion).collect(),
            holistic: None,
        })
    }

    /// Dancers this motion holds.
    pub fn dancers(&self) -> usize {
        self.group.len().max(1)
    }

    /// Dancer `d`'s motion as a one-dancer given motion.
    pub fn dancer(&self, d: usize) -> Self {
        let motion = if self.group.is_empty() {
            self.motion.clone()
        } else {
            self.group[d].clone()
        };
        Self::one(format!("{} (dancer {d})", self.label), motion)
    }

    pub fn seconds(&self) -> f64 {
        self.motion.frames() as f64 / f64::from(FPS)
    }
}

/// The `NAME_0.npz` … `NAME_{n−1}.npz` files of a group dance, from `path`, which its record
/// says is dancer `dancer` of `n`; an error names the first one missing.
fn group_files(path: &Path, dancer: usize, n: usize) -> Result<Vec<PathBuf>, GenerateError> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = format!("_{dancer}");
    let Some(stem) = name.strip_suffix(&suffix) else {
        return Err(GenerateError::Invalid(format!(
            "{}: dancer {dancer} of a {n}-dancer group, but its name does not end in {suffix} \
             as a group's files do (NAME_0.npz … NAME_{}.npz); rename the group's files back",
            path.display(),
            n - 1
        )));
    };
    let files: Vec<PathBuf> = (0..n)
        .map(|k| path.with_file_name(format!("{stem}_{k}.npz")))
        .collect();
    if let Some(missing) = files.iter().find(|f| !f.is_file()) {
        return Err(GenerateError::Invalid(format!(
            "{}: dancer {dancer} of a {n}-dancer group, and the group's file {} is missing \
             (keep the group's .npz files together)",
            path.display(),
            missing.display()
        )));
    }
    Ok(files)
}

/// The file of a dance named `path`: `path` itself, or, where `path` is a `NAME.npz` that does
/// not exist beside a `NAME_0.npz`, that file (`-o NAME.npz` of a group wrote `NAME_0.npz` …,
/// so NAME.npz names the group).
pub fn dance_file(path: &Path) -> PathBuf {
    let is_npz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
    let first = path.with_file_name(format!(
        "{}_0.npz",
        path.file_stem().unwrap_or_default().to_string_lossy()
    ));
    if is_npz && !path.exists() && first.is_file() {
        first
    } else {
        path.to_path_buf()
    }
}

/// The fingers and face of `path` when it is a holistic `.npz` dancegen wrote at 30 fps with
/// `body`'s frames (`None` otherwise: other files give the body alone).
fn holistic_of(path: &Path, body: &SmplMotion) -> Result<Option<HolisticGiven>, GenerateError> {
    let is_npz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
    if !is_npz {
        return Ok(None);
    }
    let Some(dancegen_formats::smpl_npz::SmplhFace { poses, face }) =
        dancegen_formats::smpl_npz::read_smplh_face(path)
            .map_err(|e| GenerateError::Invalid(e.to_string()))?
    else {
        return Ok(None);
    };
    let t = body.frames();
    if poses.len() != t * 156 || face.len() != t * 52 {
        // Not at the generator's rate: the body was resampled, the extras were not.
        return Ok(None);
    }
    // The file's root orientation is stored in its up-axis convention; the body joints are
    // taken as the motion reader gave them, the fingers (local rotations) as stored.
    let mut poses = poses;
    for f in 0..t {
        poses[f * 156..f * 156 + 66].copy_from_slice(&body.poses[f * 72..f * 72 + 66]);
    }
    if poses.iter().chain(&face).any(|v| !v.is_finite()) {
        return Err(GenerateError::Invalid(format!(
            "{}: its fingers or face hold NaN or infinite values",
            path.display()
        )));
    }
    Ok(Some(HolisticGiven { poses, face }))
}
