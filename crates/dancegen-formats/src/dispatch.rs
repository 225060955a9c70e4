//! One entry point per direction for every motion file format the project reads and writes,
//! chosen by file extension. Importers convert to the canonical conventions
//! ([`dancegen_motion::conventions`]) here and nowhere else; exporters convert back at the edge.
//!
//! | extension | read | write |
//! |---|---|---|
//! | `.pkl` | AIST++ motion (`smpl_poses`, `smpl_trans`, `smpl_scaling`), AIOZ-GDance group | – |
//! | `.bvh` | any skeleton | SMPL 24 (centimetres) or the file's own skeleton |
//! | `.npz` | AMASS-style SMPL (`poses`, `trans`, `mocap_framerate`), EDGE-style (`smpl_poses`, `smpl_trans`) | both |
//! | `.npy` | FineDance `(T, 315)`, joints `(T, J, 3)` | world joints `(T, J, 3)` float32 |
//! | `.glb` | the dances dancegen writes (any rig; every dancer of a group) | animated skeleton + skinned capsule mesh; every dancer of a group |
//! | `.fbx` | – | the same scene as `.glb`, FBX 7.4 binary (Y-up, metres); every dancer of a group |
//! | `.json` | – | joints, skeleton and (for SMPL) poses |

use std::path::{Path, PathBuf};

use crate::aistpp;
use crate::body_check;
use crate::bvh::{self, Bvh, BvhReadOptions, BvhWriteOptions};
use crate::bvh_motion::{self, bvh_world_positions};
use crate::fbx::{self, FbxOptions};
use crate::gltf::{self, DancerAnimation, GlbOptions};
use crate::retarget;
use crate::rig::Rig;
use crate::smpl_npz::SmplNpzOptions;
use dancegen_motion::repr::ReprError;
use dancegen_motion::repr::finedance::FineDanceMotion;
use dancegen_motion::repr::motion::SmplMotion;
use dancegen_motion::skeleton::Skeleton;

/// A motion file that could not be read, converted or written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct FormatError {
    pub path: PathBuf,
    pub reason: String,
}

/// The error about `path`; a reason that already starts with the path (a write error from
/// `dancegen-io` names its file) is not prefixed twice.
fn err(path: &Path, reason: impl std::fmt::Display) -> FormatError {
    let reason = reason.to_string();
    let named = format!("{}: ", path.display());
    FormatError {
        path: path.to_path_buf(),
        reason: reason
            .strip_prefix(&named)
            .map_or(reason.clone(), str::to_string),
    }
}

/// A motion as read from a file, before any conversion the user asked for.
#[derive(Debug, Clone)]
pub enum LoadedMotion {
    /// SMPL 24 local rotations + pelvis trajectory (AIST++, SMPL/EDGE npz, FineDance).
    Smpl(SmplMotion),
    /// Several dancers of one group recording (AIOZ-GDance).
    Group(Vec<SmplMotion>),
    /// A BVH with its own skeleton, in the file's units.
    Bvh(Bvh),
    /// World joint positions only: `(T, J, 3)`, or `(N, T, J, 3)` for `dancers = N > 1` (the
    /// `.npy` that `generate --dancers N` writes), dancer after dancer.
    Joints {
        fps: f32,
        dancers: usize,
        joints: usize,
        positions: Vec<f32>,
    },
}

impl LoadedMotion {
    pub fn fps(&self) -> f32 {
        match self {
            LoadedMotion::Smpl(m) => m.fps,
            LoadedMotion::Group(g) => g.first().map_or(0.0, |m| m.fps),
            LoadedMotion::Bvh(b) => b.nominal_fps() as f32,
            LoadedMotion::Joints { fps, .. } => *fps,
        }
    }

    pub fn kind(&self) -> &'static str {
        match self {
            LoadedMotion::Smpl(_) => "SMPL 24 motion",
            LoadedMotion::Group(_) => "group motion",
            LoadedMotion::Bvh(_) => "BVH motion",
            LoadedMotion::Joints { .. } => "joint positions",
        }
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Frame rate assumed for `.npy` inputs, which do not store one (FineDance is 30 fps).
pub const NPY_DEFAULT_FPS: f32 = 30.0;

/// Largest source frame rate [`LoadOptions::source_fps`] accepts: no motion capture a dance
/// comes from runs faster (optical systems record dance at 60-480 fps).
pub const MAX_SOURCE_FPS: f64 = 1000.0;

/// How [`load_motion_file_with`] reads a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// The rate the file was really sampled at, whatever its header says: the frames stay the
    /// same, their times change (a BVH whose header says 120 fps for a 60 fps capture plays
    /// at half speed with `Some(60.0)`). In `(0, MAX_SOURCE_FPS]`.
    pub source_fps: Option<f64>,
    /// How the user gives the rate, named in the error of a file whose header has no usable
    /// rate: a command-line flag (`--source-fps N`, `--leader-fps N`) or another way.
    pub rate_hint: &'static str,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            source_fps: None,
            rate_hint: "--source-fps N",
        }
    }
}

/// Checks a source frame rate given by the user: `Err` says what is wrong with it.
pub fn check_source_fps(fps: f64) -> Result<f64, String> {
    if fps.is_finite() && fps > 0.0 && fps <= MAX_SOURCE_FPS {
        Ok(fps)
    } else {
        Err(format!(
            "{fps} is not a frame rate: give the rate the motion was captured at, \
             above 0 and at most {MAX_SOURCE_FPS} fps"
        ))
    }
}

/// The error of a file whose stored rate is missing or unusable: `why`, then how to give it.
fn no_rate(why: &str, hint: &str) -> String {
    format!("{why}; the file's frame rate is unknown: give the rate it was captured at ({hint})")
}

/// Reads any supported motion file (see the module table) at the rate stored in it.
pub fn load_motion_file(path: &Path) -> Result<LoadedMotion, FormatError> {
    load_motion_file_with(path, &LoadOptions::default())
}

/// Reads any supported motion file, at [`LoadOptions::source_fps`] when it is given. A motion
/// that is not one body (a value that is not finite, a joint beyond
/// [`dancegen_motion::body_bounds::MAX_JOINT_DISTANCE_M`], a bone that stretches past
/// [`dancegen_motion::body_bounds::MAX_BONE_STRETCH_M`]) is refused, naming the frame and joint.
pub fn load_motion_file_with(path: &Path, opts: &LoadOptions) -> Result<LoadedMotion, FormatError> {
    if let Some(fps) = opts.source_fps {
        check_source_fps(fps).map_err(|e| err(path, format!("the given rate: {e}")))?;
    }
    if !path.exists() {
        return Err(err(path, "no such file"));
    }
    let fps = opts.source_fps;
    let ext = extension(path);
    let mut loaded = match ext.as_str() {
        "pkl" => load_pickle(path)?,
        "bvh" => {
            let read = BvhReadOptions {
                frame_time: fps.map(|f| 1.0 / f),
                ..BvhReadOptions::default()
            };
            let b = bvh::read_bvh(path, &read).map_err(|e| match e.kind {
                bvh::BvhErrorKind::BadFrameTime { .. }
                | bvh::BvhErrorKind::MissingFrameTime { .. } => {
                    err(path, no_rate(&e.kind.to_string(), opts.rate_hint))
                }
                _ => err(path, e.kind),
            })?;
            LoadedMotion::Bvh(b)
        }
        "npz" => {
            let read = SmplNpzOptions {
                fps: fps.map(|f| f as f32),
                ..SmplNpzOptions::default()
            };
            crate::smpl_npz::read_smpl_npz(path, &read)
                .map(|n| LoadedMotion::Smpl(n.motion))
                .map_err(|e| match e {
                    ReprError::NoRate { why, .. } => err(path, no_rate(&why, opts.rate_hint)),
                    other => err(path, other),
                })?
        }
        "npy" => load_npy(path)?,
        "glb" | "fbx" => {
            let read = if ext == "glb" {
                crate::glb_in::read_dance_glb(path)
            } else {
                crate::fbx_in::read_dance_fbx(path)
            };
            let mut dancers = read.map_err(|e| err(path, e))?;
            if dancers.len() == 1 {
                LoadedMotion::Smpl(dancers.remove(0))
            } else {
                LoadedMotion::Group(dancers)
            }
        }
        other => {
            return Err(err(
                path,
                format!(
                    "unknown motion format '.{other}' (use .pkl, .bvh, .npz, .npy, .glb or .fbx)"
                ),
            ));
        }
    };
    if let Some(f) = fps {
        let f = f as f32;
        match &mut loaded {
            LoadedMotion::Smpl(m) => m.fps = f,
            LoadedMotion::Group(g) => g.iter_mut().for_each(|m| m.fps = f),
            LoadedMotion::Joints { fps, .. } => *fps = f,
            // Read with the given frame time above.
            LoadedMotion::Bvh(_) => {}
        }
    }
    check_loaded(&loaded).map_err(|e| err(path, e))?;
    Ok(loaded)
}

/// The body check ([`body_check`]) of `m` as read; `Err` says which dancer (of a group),
/// frame and joint, and why.
fn check_loaded(m: &LoadedMotion) -> Result<(), String> {
    match m {
        LoadedMotion::Smpl(s) => {
            body_check::smpl_joints(&s.joints_world().map_err(|e| e.to_string())?)
        }
        LoadedMotion::Group(dancers) => {
            for (d, s) in dancers.iter().enumerate() {
                let joints = s.joints_world().map_err(|e| e.to_string())?;
                body_check::smpl_joints(&joints).map_err(|e| format!("dancer {d}, {e}"))?;
            }
            Ok(())
        }
        LoadedMotion::Bvh(b) => body_check::bvh(b),
        LoadedMotion::Joints {
            dancers,
            joints,
            positions,
            ..
        } => {
            let per_dancer = positions.len() / (*dancers).max(1);
            for (d, p) in positions.chunks(per_dancer.max(1)).enumerate() {
                body_check::joint_array(p, *joints).map_err(|e| {
                    if *dancers > 1 {
                        format!("dancer {d}, {e}")
                    } else {
                        e
                    }
                })?;
            }
            Ok(())
        }
    }
}

fn load_pickle(path: &Path) -> Result<LoadedMotion, FormatError> {
    // AIST++ motion first; a group file has `root_trans` instead of `smpl_trans`.
    match aistpp::load_motion(path) {
        Ok(m) => Ok(LoadedMotion::Smpl(m.to_smpl_motion())),
        Err(first) => match aistpp::load_gdance(path) {
            Ok(g) => {
                let group = g.to_group_motion().map_err(|e| err(path, e))?;
                Ok(LoadedMotion::Group(group.dancers))
            }
            Err(_) => Err(err(
                path,
                format!("not an AIST++ or AIOZ-GDance motion pickle: {first}"),
            )),
        },
    }
}

fn load_npy(path: &Path) -> Result<LoadedMotion, FormatError> {
    let a = dancegen_io::read_npy(path).map_err(|e| err(path, e))?;
    match a.shape.as_slice() {
        [_, 315] => FineDanceMotion::from_npy(path)
            .and_then(|m| m.to_smpl24())
            .map(LoadedMotion::Smpl)
            .map_err(|e| err(path, e)),
        [t, j, 3] if *t > 0 && *j > 0 => Ok(joints_npy(&a.data, 1, *j)),
        [n, t, j, 3] if *n > 0 && *t > 0 && *j > 0 => Ok(joints_npy(&a.data, *n, *j)),
        shape => Err(err(
            path,
            format!(
                "array of shape {shape:?} is neither FineDance (T, 315), joints (T, J, 3) nor a \
                 group's joints (N, T, J, 3)"
            ),
        )),
    }
}

fn joints_npy(data: &[f64], dancers: usize, joints: usize) -> LoadedMotion {
    // Finite values, near the origin, one body: checked with every format's motion, in
    // `load_motion_file_with`.
    let positions: Vec<f32> = data.iter().map(|&v| v as f32).collect();
    LoadedMotion::Joints {
        fps: NPY_DEFAULT_FPS,
        dancers,
        joints,
        positions,
    }
}

/// Options of [`convert_motion`].
#[derive(Clone, Debug, Default)]
pub struct ConvertOptions {
    /// Target frame rate (`None` keeps the input's).
    pub fps: Option<f32>,
    /// Retarget a BVH to SMPL 24.
    pub to_smpl24: bool,
    /// Which dancer of a group file to keep. Single-person formats need one; `.glb` and `.fbx`
    /// keep all dancers unless this picks one.
    pub dancer: Option<usize>,
    /// Style of `.npz` output.
    pub npz_style: NpzStyle,
    /// Text stored in an AMASS-style `.npz` as its
    /// [`crate::smpl_npz::RECORD_MEMBER`] (what made the dance, for `generate --edit`).
    pub npz_record: Option<String>,
    /// Bone names of `.bvh`, `.glb` and `.fbx` output ([`Rig`]; joint positions do not change).
    /// `.npy`, `.npz` and `.json` keep SMPL's order and names, which research tools expect.
    pub rig: Rig,
}

/// `.npz` output flavour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NpzStyle {
    /// AMASS-style SMPL: `poses`, `trans` (SMPL `transl`), `betas`, `mocap_framerate`.
    #[default]
    Amass,
    /// EDGE's output keys: `smpl_poses`, `smpl_trans`.
    Edge,
}

/// Applies `--to smpl24`, `--dancer` and `--fps` to a loaded motion.
pub fn convert_motion(
    path: &Path,
    m: LoadedMotion,
    opts: &ConvertOptions,
) -> Result<LoadedMotion, FormatError> {
    let m = match (m, opts.to_smpl24) {
        (LoadedMotion::Bvh(b), true) if is_smpl_bvh(&b) => {
            // Already an SMPL 24 skeleton (e.g. written by `convert`): read the rotations back.
            let (poses, trans) = bvh_motion::bvh_to_smpl(&b).map_err(|e| err(path, e))?;
            let motion =
                SmplMotion::new(b.nominal_fps() as f32, poses, trans).map_err(|e| err(path, e))?;
            LoadedMotion::Smpl(motion)
        }
        (LoadedMotion::Bvh(b), true) => {
            // Keep the source rate unless asked otherwise; retargeting then subsamples.
            let target = opts.fps.map_or(b.nominal_fps(), f64::from);
            // The convention is picked by joint names; a cgspeed reference T-pose frame 0 is
            // dropped there, so every caller gets dance frames only.
            let out = retarget::retarget_to_smpl(&b, target).map_err(|e| err(path, e))?;
            if out.first_frame > 0 {
                tracing::info!(
                    "{}: dropped frame 0, the {} reference T-pose (not part of the take)",
                    path.display(),
                    out.source.convention.name
                );
            }
            let report = retarget::retarget_report(&b, &out).map_err(|e| err(path, e))?;
            tracing::info!(
                "{}: retargeted {} skeleton to SMPL 24: {report}",
                path.display(),
                out.source.convention.name
            );
            let mut motion =
                SmplMotion::new(out.fps as f32, out.poses, out.trans).map_err(|e| err(path, e))?;
            // The source's floor is not SMPL's: the hips are placed on the source's hips and
            // SMPL's legs are longer or shorter than the source's (the salsa takes' SMPL feet
            // rest ≈ 10 cm up). Put the resting feet on y = 0, the crate's floor.
            let lifted = motion.put_feet_on_floor().map_err(|e| err(path, e))?;
            tracing::info!(
                "{}: floor put at y = 0 (resting feet were at {lifted:+.3} m)",
                path.display()
            );
            LoadedMotion::Smpl(motion)
        }
        (LoadedMotion::Joints { .. }, true) => {
            return Err(err(
                path,
                "joint positions only, no rotations to retarget (SMPL .npz, .bvh, .fbx and .glb \
                 have them)",
            ));
        }
        (m, _) => m,
    };
    let m = match (m, opts.dancer) {
        (LoadedMotion::Group(g), Some(d)) => {
            let n = g.len();
            LoadedMotion::Smpl(
                g.into_iter()
                    .nth(d)
                    .ok_or_else(|| err(path, format!("--dancer {d}: the file has {n} dancers")))?,
            )
        }
        (
            LoadedMotion::Joints {
                fps,
                dancers,
                joints,
                positions,
            },
            Some(d),
        ) if dancers > 1 => {
            if d >= dancers {
                return Err(err(
                    path,
                    format!("--dancer {d}: the file has {dancers} dancers"),
                ));
            }
            let per = positions.len() / dancers;
            LoadedMotion::Joints {
                fps,
                dancers: 1,
                joints,
                positions: positions[d * per..(d + 1) * per].to_vec(),
            }
        }
        (m, _) => m,
    };
    let Some(fps) = opts.fps else {
        return Ok(m);
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(err(path, format!("invalid target frame rate {fps}")));
    }
    Ok(match m {
        LoadedMotion::Smpl(s) => LoadedMotion::Smpl(s.resample_fps(fps)),
        LoadedMotion::Group(g) => {
            LoadedMotion::Group(g.into_iter().map(|s| s.resample_fps(fps)).collect())
        }
        LoadedMotion::Bvh(b) => LoadedMotion::Bvh(bvh_stride(path, b, fps)?),
        LoadedMotion::Joints {
            fps: src,
            dancers,
            joints,
            positions,
        } => LoadedMotion::Joints {
            fps,
            dancers,
            joints,
            positions: positions
                .chunks(positions.len() / dancers.max(1))
                .flat_map(|one| resample_linear(one, joints * 3, src, fps))
                .collect(),
        },
    })
}

/// Whether a BVH carries every SMPL 24 joint by name.
fn is_smpl_bvh(b: &Bvh) -> bool {
    Skeleton::smpl24()
        .names()
        .iter()
        .all(|n| b.joint_index(n).is_some())
}

/// Changes a raw BVH's frame rate by keeping every k-th frame (integer ratios only; Euler
/// channels cannot be interpolated safely — retarget with `--to smpl24` for other rates).
fn bvh_stride(path: &Path, mut b: Bvh, fps: f32) -> Result<Bvh, FormatError> {
    let ratio = b.nominal_fps() / fps as f64;
    let k = ratio.round();
    if k < 1.0 || (ratio - k).abs() > 1e-6 {
        return Err(err(
            path,
            format!(
                "a raw BVH can only be resampled by an integer factor ({:.3} fps -> {fps} fps); \
                 use --to smpl24 for other rates",
                b.nominal_fps()
            ),
        ));
    }
    let k = k as usize;
    let nc = b.num_channels();
    let frames: Vec<usize> = (0..b.frames).step_by(k).collect();
    let mut data = Vec::with_capacity(frames.len() * nc);
    for &f in &frames {
        data.extend_from_slice(&b.data[f * nc..(f + 1) * nc]);
    }
    b.data = data;
    b.frames = frames.len();
    b.frame_time *= k as f64;
    Ok(b)
}

/// Linear interpolation of per-frame vectors of `width` values from `src` to `dst` fps.
fn resample_linear(x: &[f32], width: usize, src: f32, dst: f32) -> Vec<f32> {
    let n = x.len() / width;
    if n == 0 {
        return Vec::new();
    }
    let duration = (n - 1) as f64 / src as f64;
    let m = (duration * dst as f64).floor() as usize + 1;
    let mut out = Vec::with_capacity(m * width);
    for i in 0..m {
        let t = i as f64 * src as f64 / dst as f64;
        let a = (t.floor() as usize).min(n - 1);
        let b = (a + 1).min(n - 1);
        let w = (t - a as f64) as f32;
        for c in 0..width {
            out.push(x[a * width + c] * (1.0 - w) + x[b * width + c] * w);
        }
    }
    out
}

fn single<'a>(path: &Path, m: &'a LoadedMotion) -> Result<&'a SmplMotion, FormatError> {
    match m {
        LoadedMotion::Smpl(s) => Ok(s),
        LoadedMotion::Group(g) => Err(err(
            path,
            format!(
                "the input has {} dancers; choose one with --dancer N (0-based), or write \
                 .glb, .fbx, .npy or .json, which hold them all",
                g.len()
            ),
        )),
        other => Err(err(
            path,
            format!("a {} cannot be written as SMPL data", other.kind()),
        )),
    }
}

/// The dancers of a group a multi-dancer format writes: all of them, or the one `--dancer`
/// picks (as [`convert_motion`] would, for callers that skip it).
fn group_members<'a>(
    path: &Path,
    g: &'a [SmplMotion],
    dancer: Option<usize>,
) -> Result<Vec<&'a SmplMotion>, FormatError> {
    match dancer {
        Some(d) => g.get(d).map(|s| vec![s]).ok_or_else(|| {
            err(
                path,
                format!("--dancer {d}: the file has {} dancers", g.len()),
            )
        }),
        None if g.is_empty() => Err(err(path, "the group has no dancers")),
        None => Ok(g.iter().collect()),
    }
}

/// World joint positions `(T, J, 3)` of a motion (metres for SMPL, file units for raw BVH).
pub fn joint_positions(
    path: &Path,
    m: &LoadedMotion,
) -> Result<(Vec<usize>, Vec<f32>), FormatError> {
    match m {
        LoadedMotion::Smpl(s) => {
            let p = s.joints_world().map_err(|e| err(path, e))?;
            Ok((vec![s.frames(), 24, 3], p))
        }
        LoadedMotion::Group(g) => {
            let mut all = Vec::new();
            let t = g.first().map_or(0, |s| s.frames());
            for s in g {
                all.extend(s.joints_world().map_err(|e| err(path, e))?);
            }
            Ok((vec![g.len(), t, 24, 3], all))
        }
        LoadedMotion::Bvh(b) => {
            let (t, j, p) = bvh_world_positions(b, 1.0).map_err(|e| err(path, e))?;
            Ok((vec![t, j, 3], p.into_iter().map(|v| v as f32).collect()))
        }
        LoadedMotion::Joints {
            dancers,
            joints,
            positions,
            ..
        } => {
            let frames = positions.len() / (dancers * joints * 3).max(1);
            let shape = if *dancers > 1 {
                vec![*dancers, frames, *joints, 3]
            } else {
                vec![frames, *joints, 3]
            };
            Ok((shape, positions.clone()))
        }
    }
}

/// Writes a motion in the format given by `out`'s extension.
pub fn save_motion_file(
    out: &Path,
    m: &LoadedMotion,
    opts: &ConvertOptions,
) -> Result<(), FormatError> {
    match extension(out).as_str() {
        "npy" => {
            let (shape, data) = joint_positions(out, m)?;
            dancegen_io::write_npy_f32(out, &shape, &data).map_err(|e| err(out, e))
        }
        "bvh" => {
            let b = match m {
                LoadedMotion::Bvh(b) => {
                    no_rig_for_raw_bvh(out, opts)?;
                    b.clone()
                }
                other => {
                    let s = single(out, other)?;
                    let mut b = bvh_motion::smpl_to_bvh(&s.poses, &s.trans, s.fps as f64)
                        .map_err(|e| err(out, e))?;
                    rename_smpl_joints(&mut b, opts.rig);
                    b
                }
            };
            bvh::write_bvh_file(out, &b, &BvhWriteOptions::default()).map_err(|e| err(out, e))
        }
        "glb" => {
            let glb = GlbOptions::default();
            with_dancers(out, m, opts, ".glb", |skel, dancers, fps| {
                gltf::write_glb_multi(out, skel, dancers, fps, &glb).map_err(|e| err(out, e))
            })
        }
        "fbx" => {
            let fbx = FbxOptions::default();
            with_dancers(out, m, opts, ".fbx", |skel, dancers, fps| {
                fbx::write_fbx(out, skel, dancers, fps, &fbx).map_err(|e| err(out, e))
            })
        }
        "npz" => {
            let s = single(out, m)?;
            let r = match opts.npz_style {
                NpzStyle::Amass => crate::smpl_npz::write_smpl_npz_recorded(
                    out,
                    s,
                    &SmplNpzOptions::default(),
                    opts.npz_record.as_deref(),
                ),
                NpzStyle::Edge => {
                    crate::smpl_npz::write_edge_npz(out, s, &SmplNpzOptions::default())
                }
            };
            r.map_err(|e| err(out, e))
        }
        "json" => write_json(out, m),
        other => Err(err(
            out,
            format!("unknown output format '.{other}' (use .npy, .bvh, .glb, .fbx, .npz or .json)"),
        )),
    }
}

/// Hands a motion to a scene exporter (`.glb`, `.fbx`) as a skeleton plus dancers sharing one
/// timeline: a raw BVH with its own skeleton, every dancer of a group (or the one `--dancer`
/// picks), or a single SMPL 24 motion. `format` names the extension in messages.
fn with_dancers(
    out: &Path,
    m: &LoadedMotion,
    opts: &ConvertOptions,
    format: &str,
    write: impl FnOnce(&Skeleton, &[DancerAnimation<'_>], f32) -> Result<(), FormatError>,
) -> Result<(), FormatError> {
    match m {
        LoadedMotion::Bvh(b) => {
            no_rig_for_raw_bvh(out, opts)?;
            let (skel, poses, trans) =
                bvh_motion::bvh_skeleton_motion(b, 1.0).map_err(|e| err(out, e))?;
            let dancer = DancerAnimation {
                local_rotations_axis_angle: &poses,
                root_translation: &trans,
            };
            write(&skel, &[dancer], b.nominal_fps() as f32)
        }
        LoadedMotion::Group(g) => {
            let chosen = group_members(out, g, opts.dancer)?;
            let dancers: Vec<DancerAnimation<'_>> = chosen
                .iter()
                .map(|s| DancerAnimation {
                    local_rotations_axis_angle: &s.poses,
                    root_translation: &s.trans,
                })
                .collect();
            let fps = chosen[0].fps;
            if let Some((d, s)) = chosen.iter().enumerate().find(|(_, s)| s.fps != fps) {
                return Err(err(
                    out,
                    format!(
                        "dancer {d} is at {} fps but dancer 0 at {fps}; one {format} \
                         animation needs one frame rate",
                        s.fps
                    ),
                ));
            }
            write(&opts.rig.skeleton(), &dancers, fps)
        }
        other => {
            let s = single(out, other)?;
            let dancer = DancerAnimation {
                local_rotations_axis_angle: &s.poses,
                root_translation: &s.trans,
            };
            write(&opts.rig.skeleton(), &[dancer], s.fps)
        }
    }
}

/// A rig preset names SMPL 24 joints; a BVH kept on its own skeleton has other joints.
fn no_rig_for_raw_bvh(out: &Path, opts: &ConvertOptions) -> Result<(), FormatError> {
    if opts.rig == Rig::Smpl {
        return Ok(());
    }
    Err(err(
        out,
        format!(
            "--rig {} renames SMPL 24 joints, and this BVH keeps its own skeleton: add --to \
             smpl24",
            opts.rig
        ),
    ))
}

/// Gives an SMPL 24 BVH (written by [`bvh_motion::smpl_to_bvh`], joints in depth-first
/// order) the bone names of `rig`.
fn rename_smpl_joints(b: &mut Bvh, rig: Rig) {
    if rig == Rig::Smpl {
        return;
    }
    let smpl = Skeleton::smpl24();
    let names = rig.joint_names();
    for joint in &mut b.joints {
        if let Some(j) = smpl.index_of(&joint.name) {
            joint.name = names[j].clone();
        }
    }
}

fn write_json(out: &Path, m: &LoadedMotion) -> Result<(), FormatError> {
    let (shape, positions) = joint_positions(out, m)?;
    let (names, parents): (Vec<String>, Vec<Option<usize>>) = match m {
        LoadedMotion::Bvh(b) => (
            b.joints.iter().map(|j| j.name.clone()).collect(),
            b.joints.iter().map(|j| j.parent).collect(),
        ),
        LoadedMotion::Joints { joints, .. } => (
            (0..*joints).map(|j| format!("joint{j}")).collect(),
            vec![None; *joints],
        ),
        _ => {
            let s = Skeleton::smpl24();
            (s.names().to_vec(), s.parents().to_vec())
        }
    };
    let units = match m {
        LoadedMotion::Bvh(_) => "file units",
        _ => "metres",
    };
    let mut v = serde_json::json!({
        "fps": m.fps(),
        "up": "y",
        "units": units,
        "joint_names": names,
        "parents": parents,
        "shape": shape,
        "positions": positions,
    });
    if let LoadedMotion::Smpl(s) = m {
        v["smpl_poses_axis_angle"] = serde_json::json!(s.poses);
        v["pelvis_trans"] = serde_json::json!(s.trans);
    }
    dancegen_io::write_atomic(out, |w| {
        serde_json::to_writer(&mut *w, &v).map_err(std::io::Error::other)
    })
    .map_err(|e| err(out, e))
}
