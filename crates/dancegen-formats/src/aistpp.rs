//! Loaders for AIST++ motion / keypoint pickles and AIOZ-GDance group pickles
//! (`reference/anchors.md` C.1 and C.5), on top of the safe [`crate::pickle`] reader.
//!
//! Values are returned as stored (AIST++ `smpl_trans` in centimetres, scaled by `smpl_scaling`);
//! unit conversion is explicit ([`AistppMotion::trans_metres`]).

use std::path::{Path, PathBuf};

use crate::pickle::{self, NdArray, PickleError, PickleValue};
use dancegen_motion::repr::ReprError;
use dancegen_motion::repr::group::GroupMotion;
use dancegen_motion::repr::motion::{AISTPP_PELVIS_REST, SmplMotion};

/// AIST++ frame rate.
pub const AISTPP_FPS: u32 = 60;
/// AIOZ-GDance frame rate.
pub const GDANCE_FPS: u32 = 30;
/// Number of SMPL pose parameters per frame (24 joints × axis-angle).
pub const SMPL_POSE_DIMS: usize = 72;
/// COCO keypoints in AIST++ `keypoints3d`.
pub const COCO_JOINTS: usize = 17;

/// Errors of the AIST++ / GDance loaders; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum AistppError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Pickle {
        path: PathBuf,
        #[source]
        source: PickleError,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
}

/// One AIST++ SMPL motion (`motions/*.pkl`).
#[derive(Debug, Clone, PartialEq)]
pub struct AistppMotion {
    /// `smpl_poses`, frames × 72 axis-angle (radians), row-major.
    pub poses: Vec<f32>,
    /// `smpl_trans`, frames × 3, as stored (centimetres, i.e. metres × `scaling`).
    pub trans: Vec<f32>,
    /// `smpl_scaling`.
    pub scaling: f32,
    /// `smpl_loss`, when present.
    pub loss: Option<f64>,
    /// Always [`AISTPP_FPS`].
    pub fps: u32,
}

impl AistppMotion {
    pub fn frames(&self) -> usize {
        self.trans.len() / 3
    }

    /// Root translation in metres (generic SMPL scale): `smpl_trans / smpl_scaling` (anchors C.1).
    pub fn trans_metres(&self) -> Vec<f32> {
        self.trans.iter().map(|&t| t / self.scaling).collect()
    }

    /// The motion with the pelvis at its true world position:
    /// `trans = smpl_trans / smpl_scaling + AISTPP_PELVIS_REST` (60 fps).
    pub fn to_smpl_motion(&self) -> SmplMotion {
        let mut out = self.to_smpl_motion_edge();
        for t in out.trans.chunks_exact_mut(3) {
            for (v, o) in t.iter_mut().zip(AISTPP_PELVIS_REST) {
                *v += o;
            }
        }
        out
    }

    /// The motion the way EDGE reads it (`data/slice.py`, anchors.md C.1): root translation
    /// `smpl_trans / smpl_scaling`, i.e. **without** the rest-pelvis offset, so the skeleton sits
    /// ~24 cm lower than the real dancer. Use this to reproduce EDGE's 151-dim vectors bit for bit.
    pub fn to_smpl_motion_edge(&self) -> SmplMotion {
        SmplMotion {
            fps: self.fps as f32,
            poses: self.poses.clone(),
            trans: self.trans_metres(),
        }
    }
}

/// AIST++ 3D keypoints (`keypoints3d/*.pkl`), COCO-17, centimetres.
#[derive(Debug, Clone, PartialEq)]
pub struct AistppKeypoints {
    /// frames × 17 × 3, row-major (raw triangulation; may contain NaN for missing joints).
    pub keypoints3d: Vec<f64>,
    /// frames × 17 × 3, row-major (optimised).
    pub keypoints3d_optim: Vec<f64>,
    pub fps: u32,
}

impl AistppKeypoints {
    pub fn frames(&self) -> usize {
        self.keypoints3d_optim.len() / (COCO_JOINTS * 3)
    }
}

/// One AIOZ-GDance group sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct GDanceMotion {
    pub persons: usize,
    pub frames: usize,
    /// `smpl_poses`, persons × frames × 72, row-major.
    pub poses: Vec<f32>,
    /// `root_trans`, persons × frames × 3, row-major, as stored.
    pub root_trans: Vec<f32>,
    /// `smpl_betas` (shape, data) when present.
    pub betas: Option<(Vec<usize>, Vec<f32>)>,
    /// Always [`GDANCE_FPS`].
    pub fps: u32,
}

impl GDanceMotion {
    /// Splits the sequence into dancers.
    pub fn to_group_motion(&self) -> Result<GroupMotion, ReprError> {
        let dancers = (0..self.persons)
            .map(|p| {
                let poses = self
                    .person_poses(p)
                    .ok_or_else(|| ReprError::Invalid(format!("dancer {p} missing")))?;
                let trans = self
                    .person_trans(p)
                    .ok_or_else(|| ReprError::Invalid(format!("dancer {p} missing")))?;
                SmplMotion::new(self.fps as f32, poses.to_vec(), trans.to_vec())
            })
            .collect::<Result<_, _>>()?;
        Ok(GroupMotion { dancers })
    }

    /// Poses of one dancer (frames × 72).
    pub fn person_poses(&self, p: usize) -> Option<&[f32]> {
        let n = self.frames * SMPL_POSE_DIMS;
        self.poses
            .get(p.checked_mul(n)?..p.checked_add(1)?.checked_mul(n)?)
    }

    /// Root translation of one dancer (frames × 3).
    pub fn person_trans(&self, p: usize) -> Option<&[f32]> {
        let n = self.frames * 3;
        self.root_trans
            .get(p.checked_mul(n)?..p.checked_add(1)?.checked_mul(n)?)
    }
}

fn read_pickle(path: &Path) -> Result<PickleValue, AistppError> {
    let bytes = std::fs::read(path).map_err(|source| AistppError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_pickle(path, &bytes)
}

fn parse_pickle(path: &Path, bytes: &[u8]) -> Result<PickleValue, AistppError> {
    let v = pickle::parse(bytes).map_err(|source| AistppError::Pickle {
        path: path.to_path_buf(),
        source,
    })?;
    if !matches!(v, PickleValue::Dict(_)) {
        return Err(format_err(
            path,
            format!("expected a dict at top level, found {}", v.type_name()),
        ));
    }
    Ok(v)
}

fn format_err(path: &Path, message: String) -> AistppError {
    AistppError::Format {
        path: path.to_path_buf(),
        message,
    }
}

fn array<'v>(path: &Path, root: &'v PickleValue, key: &str) -> Result<&'v NdArray, AistppError> {
    match root.get(key) {
        Some(PickleValue::NdArray(a)) => Ok(a),
        Some(other) => Err(format_err(
            path,
            format!(
                "key {key:?} is a {}, expected a numpy array",
                other.type_name()
            ),
        )),
        None => Err(format_err(path, format!("missing key {key:?}"))),
    }
}

/// Checks `a.shape` against `expected` (`None` = any size) and returns the concrete shape.
fn check_shape(
    path: &Path,
    key: &str,
    a: &NdArray,
    expected: &[Option<usize>],
) -> Result<Vec<usize>, AistppError> {
    let ok = a.shape.len() == expected.len()
        && a.shape
            .iter()
            .zip(expected)
            .all(|(s, e)| e.is_none_or(|e| e == *s));
    if ok {
        Ok(a.shape.clone())
    } else {
        let exp: Vec<String> = expected
            .iter()
            .map(|e| e.map_or_else(|| "N".to_string(), |e| e.to_string()))
            .collect();
        Err(format_err(
            path,
            format!(
                "key {key:?} has shape {:?}, expected ({})",
                a.shape,
                exp.join(", ")
            ),
        ))
    }
}

fn is_numeric(a: &NdArray) -> bool {
    !matches!(a.data, pickle::ArrayData::Bool(_))
}

fn numeric<'v>(path: &Path, root: &'v PickleValue, key: &str) -> Result<&'v NdArray, AistppError> {
    let a = array(path, root, key)?;
    if is_numeric(a) {
        Ok(a)
    } else {
        Err(format_err(path, format!("key {key:?} is a bool array")))
    }
}

/// Loads an AIST++ `motions/*.pkl` (`smpl_poses` (N, 72), `smpl_trans` (N, 3), `smpl_scaling` (1,),
/// optional `smpl_loss`).
pub fn load_motion(path: impl AsRef<Path>) -> Result<AistppMotion, AistppError> {
    let path = path.as_ref();
    let root = read_pickle(path)?;
    motion_from_value(path, &root)
}

/// Same as [`load_motion`] from bytes already in memory; `path` is only used in errors.
pub fn parse_motion(path: impl AsRef<Path>, bytes: &[u8]) -> Result<AistppMotion, AistppError> {
    let path = path.as_ref();
    let root = parse_pickle(path, bytes)?;
    motion_from_value(path, &root)
}

fn motion_from_value(path: &Path, root: &PickleValue) -> Result<AistppMotion, AistppError> {
    let poses = numeric(path, root, "smpl_poses")?;
    let shape = check_shape(path, "smpl_poses", poses, &[None, Some(SMPL_POSE_DIMS)])?;
    let n = shape[0];
    let trans = numeric(path, root, "smpl_trans")?;
    check_shape(path, "smpl_trans", trans, &[Some(n), Some(3)])?;
    let scaling = match root.get("smpl_scaling") {
        Some(v) => v.as_f64().ok_or_else(|| {
            format_err(
                path,
                format!("smpl_scaling is a {}, expected one number", v.type_name()),
            )
        })?,
        None => return Err(format_err(path, "missing key \"smpl_scaling\"".into())),
    };
    if !(scaling.is_finite() && scaling > 0.0) {
        return Err(format_err(
            path,
            format!("smpl_scaling must be positive and finite, found {scaling}"),
        ));
    }
    let loss = root.get("smpl_loss").and_then(PickleValue::as_f64);
    Ok(AistppMotion {
        poses: poses.to_f32_vec(),
        trans: trans.to_f32_vec(),
        scaling: scaling as f32,
        loss,
        fps: AISTPP_FPS,
    })
}

/// Loads an AIST++ `keypoints3d/*.pkl` (`keypoints3d`, `keypoints3d_optim`, both (N, 17, 3) cm).
pub fn load_keypoints(path: impl AsRef<Path>) -> Result<AistppKeypoints, AistppError> {
    let path = path.as_ref();
    let root = read_pickle(path)?;
    let optim = numeric(path, &root, "keypoints3d_optim")?;
    let shape = check_shape(
        path,
        "keypoints3d_optim",
        optim,
        &[None, Some(COCO_JOINTS), Some(3)],
    )?;
    let raw = numeric(path, &root, "keypoints3d")?;
    check_shape(
        path,
        "keypoints3d",
        raw,
        &[Some(shape[0]), Some(COCO_JOINTS), Some(3)],
    )?;
    Ok(AistppKeypoints {
        keypoints3d: raw.to_f64_vec(),
        keypoints3d_optim: optim.to_f64_vec(),
        fps: AISTPP_FPS,
    })
}

/// Loads an AIOZ-GDance pickle: `smpl_poses` (P, T, 72), `root_trans` (P, T, 3), optional
/// `smpl_betas` (anchors C.5). Other keys (e.g. `meta`) are ignored, but must still be made of
/// supported pickle values.
pub fn load_gdance(path: impl AsRef<Path>) -> Result<GDanceMotion, AistppError> {
    let path = path.as_ref();
    let root = read_pickle(path)?;
    let poses = numeric(path, &root, "smpl_poses")?;
    let shape = check_shape(
        path,
        "smpl_poses",
        poses,
        &[None, None, Some(SMPL_POSE_DIMS)],
    )?;
    let (persons, frames) = (shape[0], shape[1]);
    let trans = numeric(path, &root, "root_trans")?;
    check_shape(
        path,
        "root_trans",
        trans,
        &[Some(persons), Some(frames), Some(3)],
    )?;
    let betas = match root.get("smpl_betas") {
        None | Some(PickleValue::None) => None,
        Some(PickleValue::NdArray(b)) if is_numeric(b) => Some((b.shape.clone(), b.to_f32_vec())),
        Some(other) => {
            return Err(format_err(
                path,
                format!(
                    "smpl_betas is a {}, expected a numeric array",
                    other.type_name()
                ),
            ));
        }
    };
    Ok(GDanceMotion {
        persons,
        frames,
        poses: poses.to_f32_vec(),
        root_trans: trans.to_f32_vec(),
        betas,
        fps: GDANCE_FPS,
    })
}
