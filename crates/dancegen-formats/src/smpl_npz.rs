//! SMPL motions in numpy `.npz` files: AMASS-style (`poses`, `trans`, `betas`,
//! `mocap_framerate`) and EDGE-style (`smpl_poses`, `smpl_trans`, `full_pose`).
//!
//! # Translation conventions (read this before touching the maths)
//!
//! [`SmplMotion::trans`] is the **pelvis (joint 0) world position**, Y-up ([`dancegen_motion::conventions`]).
//! Neither file layout stores that:
//!
//! - **AMASS `trans`** is the SMPL model's `transl` parameter. SMPL rotates the body about the
//!   rest pelvis `J0(betas)` and then adds `transl`, so in the file's world frame
//!   `pelvis = trans + J0`, with `J0` *not* rotated by the root orientation nor by the file's
//!   up-axis change (the Z-up of AMASS is baked into the root orientation). AMASS files are
//!   **Z-up** ([`UpAxis::Z`], the default); [`UpAxis::Y`] reads/writes Y-up SMPL files (e.g.
//!   AIST++ re-exports) with the same `transl` meaning.
//! - **EDGE `smpl_trans`** (`Stanford-TML/EDGE` `render_sample` pickles, anchors.md D.1) is the
//!   root position in EDGE's Z-up model space. EDGE trains on AIST++ `smpl_trans /
//!   smpl_scaling` = the SMPL `transl` in **Y-up**, rotated to Z-up (C.1, C.2), and its FK puts
//!   the root exactly there. So `smpl_trans = Z(pelvis − J0)` where `Z` is
//!   [`yup_to_zup_point`]: `J0` is subtracted *before* the rotation, unlike AMASS. `smpl_poses`
//!   carries the root orientation in Z-up (left-multiplied by [`dancegen_motion::conventions::YUP_TO_ZUP_MAT`])
//!   and `full_pose` is EDGE's FK of those, `Z(joints − J0)`.
//!
//! `J0` depends on the body shape (`betas`), which needs the SMPL model we do not ship. We use
//! the AIST++/EDGE rest pelvis [`AISTPP_PELVIS_REST`] `(-0.0021, -0.2444, 0.0282)` m for every
//! file ([`SmplNpzOptions::pelvis_rest`] overrides it). For a file with non-zero `betas` the
//! pelvis is therefore off by the (few mm to ~2 cm) difference between its true `J0` and ours;
//! the joint rotations are unaffected. Written files carry `betas = zeros(10)` so our `J0` is
//! the right one for them up to the mean-shape-vs-AIST++ difference.
//!
//! # Poses
//!
//! `poses` may be `(T, 72)` (SMPL 24), `(T, 156)` (SMPL-H 52: 22 body + 30 finger joints, the
//! AMASS SMPL-H release), `(T, 165)` (SMPL-X 55: 22 body, jaw, 2 eyes, 30 fingers) or `(T, 66)`
//! (body only). Joints 0..21 are the same in all of them and are copied. SMPL 24's joints 22/23
//! (`lhand`/`rhand`, a rigid hand segment) do not exist in SMPL-H/X, whose wrists carry finger
//! chains instead, so they are set to the **identity** rotation; finger, jaw and eye rotations
//! are dropped.
//!
//! [`write_smplh_npz`] writes the SMPL-H form, `(T, 156)`, with the fingers (a holistic dance),
//! plus `gender = "neutral"` as AMASS's SMPL-H files carry a gender.
//!
//! # Frame rate
//!
//! AMASS: `mocap_framerate` (SMPL-H) or `mocap_frame_rate` (SMPL-X), a scalar; required. EDGE
//! pickles carry no rate and EDGE samples at 30 fps, so EDGE-style files default to 30 unless
//! they have an `fps` (which our writer adds) or `mocap_framerate` member.

use std::path::Path;

use dancegen_io::npy::{NpyArray, NpyData};
use dancegen_io::npz::{read_npz_members, write_npz};

use dancegen_motion::conventions::{
    yup_to_zup_point, yup_to_zup_root_axis_angle, zup_to_yup_point, zup_to_yup_root_axis_angle,
};
use dancegen_motion::repr::ReprError;
use dancegen_motion::repr::motion::{AISTPP_PELVIS_REST, POSE_DIMS, SMPL_JOINTS, SmplMotion};

/// Body joints shared by SMPL, SMPL-H and SMPL-X (pelvis .. right wrist).
pub const BODY_JOINTS: usize = 22;
/// Number of zero `betas` written to AMASS-style files.
pub const WRITTEN_BETAS: usize = 10;
/// SMPL-H joints: 22 body, 15 left-hand and 15 right-hand finger joints.
pub const SMPLH_JOINTS: usize = 52;
/// `gender` of the SMPL-H files we write: no body is fitted, so the neutral model's.
pub const WRITTEN_GENDER: &str = "neutral";
/// Frame rate assumed for EDGE-style files without a rate member (EDGE samples at 30 fps).
pub const EDGE_FPS: f32 = 30.0;

/// Up axis of the world frame of an AMASS-style file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UpAxis {
    /// Y-up, our canonical frame (AIST++-style exports).
    Y,
    /// Z-up (AMASS).
    #[default]
    Z,
}

/// Which key layout a file uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SmplNpzLayout {
    /// `poses`, `trans`, `betas`, `mocap_framerate` / `mocap_frame_rate`.
    Amass,
    /// `smpl_poses`, `smpl_trans` (+ `full_pose`), EDGE's output pickle keys.
    Edge,
}

/// How translations and axes are interpreted, see the module documentation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmplNpzOptions {
    /// World up axis of AMASS-style files (EDGE-style files are always Z-up).
    pub up: UpAxis,
    /// Rest pelvis `J0` in metres (Y-up model coordinates) linking `transl` to the pelvis.
    pub pelvis_rest: [f32; 3],
    /// Frame rate to use instead of the file's rate member (or of its absence), for a file
    /// whose stored rate is wrong or missing.
    pub fps: Option<f32>,
}

impl Default for SmplNpzOptions {
    fn default() -> Self {
        SmplNpzOptions {
            up: UpAxis::Z,
            pelvis_rest: AISTPP_PELVIS_REST,
            fps: None,
        }
    }
}

/// A motion read from an SMPL `.npz`.
#[derive(Debug, Clone, PartialEq)]
pub struct SmplNpz {
    pub motion: SmplMotion,
    /// `betas` as stored (empty if absent). Not applied: see the module documentation.
    pub betas: Vec<f32>,
    pub layout: SmplNpzLayout,
    /// Joints per frame in the file's `poses` (24, 52, 55 or 22).
    pub source_joints: usize,
}

const WANTED: [&str; 10] = [
    "poses",
    "trans",
    "betas",
    "mocap_framerate",
    "mocap_frame_rate",
    "smpl_poses",
    "smpl_trans",
    "fps",
    "smpl_betas",
    "smpl_scaling",
];

/// Reads an AMASS- or EDGE-style SMPL `.npz` (layout detected from the keys) into Y-up
/// pelvis-position form.
pub fn read_smpl_npz(path: &Path, opts: &SmplNpzOptions) -> Result<SmplNpz, ReprError> {
    let members = read_npz_members(path, &WANTED)?;
    let bad = |reason: String| ReprError::Invalid(format!("{}: {reason}", path.display()));
    let get = |name: &str| members.iter().find(|(n, _)| n == name).map(|(_, a)| a);
    let (layout, poses, trans) = match (get("poses"), get("trans")) {
        (Some(p), Some(t)) => (SmplNpzLayout::Amass, p, t),
        _ => match (get("smpl_poses"), get("smpl_trans")) {
            (Some(p), Some(t)) => (SmplNpzLayout::Edge, p, t),
            _ => {
                return Err(bad(
                    "no SMPL motion: expected `poses` + `trans` (AMASS) or `smpl_poses` + \
                     `smpl_trans` (EDGE)"
                        .into(),
                ));
            }
        },
    };
    let (pname, tname) = match layout {
        SmplNpzLayout::Amass => ("poses", "trans"),
        SmplNpzLayout::Edge => ("smpl_poses", "smpl_trans"),
    };
    if get("smpl_scaling").is_some_and(|s| s.data.iter().any(|&v| v != 1.0)) {
        return Err(bad(
            "has `smpl_scaling` != 1 (raw AIST++ layout); use the AIST++ importer".into(),
        ));
    }

    let t = match trans.shape.as_slice() {
        [t, 3] => *t,
        s => return Err(bad(format!("`{tname}` has shape {s:?}, expected (T, 3)"))),
    };
    let (pt, width) = match poses.shape.as_slice() {
        [pt, w] => (*pt, *w),
        [pt, j, 3] => (*pt, j * 3),
        s => return Err(bad(format!("`{pname}` has shape {s:?}, expected (T, J·3)"))),
    };
    if pt != t {
        return Err(bad(format!(
            "`{pname}` has {pt} frames but `{tname}` has {t}"
        )));
    }
    let source_joints = width / 3;
    if !matches!(width, 66 | 72 | 156 | 165) {
        return Err(bad(format!(
            "`{pname}` has {width} values per frame; expected 72 (SMPL), 156 (SMPL-H), \
             165 (SMPL-X) or 66 (body)"
        )));
    }
    let copied = if width == POSE_DIMS {
        POSE_DIMS
    } else {
        BODY_JOINTS * 3
    };

    let fps = match opts.fps {
        Some(f) if f.is_finite() && f > 0.0 => f,
        Some(f) => return Err(bad(format!("the given frame rate {f} is not positive"))),
        None => fps_of(&get, layout).map_err(|why| ReprError::NoRate {
            path: path.to_path_buf(),
            why,
        })?,
    };
    let z = match layout {
        SmplNpzLayout::Amass => opts.up == UpAxis::Z,
        SmplNpzLayout::Edge => true,
    };
    let j0 = opts.pelvis_rest.map(f64::from);

    let mut out_poses = vec![0.0f32; t * POSE_DIMS];
    let mut out_trans = Vec::with_capacity(t * 3);
    for f in 0..t {
        let src = &poses.data[f * width..f * width + copied];
        let dst = &mut out_poses[f * POSE_DIMS..f * POSE_DIMS + copied];
        for (d, s) in dst.iter_mut().zip(src) {
            *d = *s as f32;
        }
        if z {
            let root = zup_to_yup_root_axis_angle([src[0], src[1], src[2]]);
            for (d, s) in dst[..3].iter_mut().zip(root) {
                *d = s as f32;
            }
        }
        let tr = [
            trans.data[f * 3],
            trans.data[f * 3 + 1],
            trans.data[f * 3 + 2],
        ];
        let pelvis = match (layout, z) {
            (SmplNpzLayout::Amass, true) => {
                zup_to_yup_point([tr[0] + j0[0], tr[1] + j0[1], tr[2] + j0[2]])
            }
            (SmplNpzLayout::Edge, _) => {
                let p = zup_to_yup_point(tr);
                [p[0] + j0[0], p[1] + j0[1], p[2] + j0[2]]
            }
            (SmplNpzLayout::Amass, false) => [tr[0] + j0[0], tr[1] + j0[1], tr[2] + j0[2]],
        };
        out_trans.extend(pelvis.map(|v| v as f32));
    }
    let betas = get("betas")
        .or_else(|| get("smpl_betas"))
        .map(|b| b.data.iter().map(|&v| v as f32).collect())
        .unwrap_or_default();
    let motion = SmplMotion::new(fps, out_poses, out_trans)
        .map_err(|e| bad(format!("invalid motion: {e}")))?;
    Ok(SmplNpz {
        motion,
        betas,
        layout,
        source_joints,
    })
}

fn fps_of<'a>(
    get: &impl Fn(&str) -> Option<&'a NpyArray>,
    layout: SmplNpzLayout,
) -> Result<f32, String> {
    let keys: &[&str] = match layout {
        SmplNpzLayout::Amass => &["mocap_framerate", "mocap_frame_rate", "fps"],
        SmplNpzLayout::Edge => &["fps", "mocap_framerate", "mocap_frame_rate"],
    };
    for k in keys {
        if let Some(a) = get(k) {
            return match a.data.as_slice() {
                [v] if v.is_finite() && *v > 0.0 => Ok(*v as f32),
                d => Err(format!("`{k}` is {d:?}, expected one positive number")),
            };
        }
    }
    match layout {
        SmplNpzLayout::Edge => Ok(EDGE_FPS),
        SmplNpzLayout::Amass => Err("no `mocap_framerate` / `mocap_frame_rate` member".into()),
    }
}

/// Root axis-angle and SMPL `transl` of a frame in an AMASS-style file's frame, from the root
/// rotation `aa` and the pelvis world position `pelvis` (Y-up).
fn amass_frame(aa: &[f32], pelvis: &[f32], opts: &SmplNpzOptions) -> ([f64; 3], [f64; 3]) {
    let aa = [aa[0], aa[1], aa[2]].map(f64::from);
    let p = [pelvis[0], pelvis[1], pelvis[2]].map(f64::from);
    let j0 = opts.pelvis_rest.map(f64::from);
    match opts.up {
        UpAxis::Y => (aa, [p[0] - j0[0], p[1] - j0[1], p[2] - j0[2]]),
        UpAxis::Z => {
            let pz = yup_to_zup_point(p);
            (
                yup_to_zup_root_axis_angle(aa),
                [pz[0] - j0[0], pz[1] - j0[1], pz[2] - j0[2]],
            )
        }
    }
}

/// Writes an AMASS-style SMPL `.npz` (float64, like AMASS): `poses` (T, 72), `trans` (T, 3) =
/// SMPL `transl` (pelvis − `J0`, in the `opts.up` frame), `betas` zeros(10),
/// `mocap_framerate` scalar.
pub fn write_smpl_npz(path: &Path, m: &SmplMotion, opts: &SmplNpzOptions) -> Result<(), ReprError> {
    write_smpl_npz_recorded(path, m, opts, None)
}

/// The member that holds what made a dance ([`write_smpl_npz_recorded`]): one unicode string,
/// which numpy reads as `np.load(f)["dancegen"].item()` and other readers ignore.
pub const RECORD_MEMBER: &str = "dancegen";

/// [`write_smpl_npz`] plus, when given, `record` (text, e.g. JSON) as [`RECORD_MEMBER`].
pub fn write_smpl_npz_recorded(
    path: &Path,
    m: &SmplMotion,
    opts: &SmplNpzOptions,
    record: Option<&str>,
) -> Result<(), ReprError> {
    m.validate()?;
    write_amass(
        path, &m.poses, POSE_DIMS, &m.trans, m.fps, None, record, None, opts,
    )
}

/// The [`RECORD_MEMBER`] of an `.npz`, `None` when the file has none.
pub fn read_record(path: &Path) -> Result<Option<String>, ReprError> {
    dancegen_io::npz::read_npz_text(path, RECORD_MEMBER)
        .map_err(|e| ReprError::Invalid(e.to_string()))
}

/// Writes an AMASS-style SMPL-H `.npz`, the keys of AMASS's SMPL-H release (float64):
/// `poses` (T, 156) = 52 local axis-angle rotations in SMPL-H order (22 body joints, 15
/// left-hand, 15 right-hand finger joints) with the root orientation in the `opts.up` frame,
/// `trans` (T, 3) = SMPL `transl` as [`write_smpl_npz`] writes it (the `J0` caveat of the module
/// documentation applies), `betas` zeros(10), `gender` `"neutral"` ([`WRITTEN_GENDER`], a 0-d
/// unicode array as AMASS stores it) and `mocap_framerate`.
///
/// `poses` is `(T, 52, 3)`, `trans` `(T, 3)` the pelvis world position (metres, Y-up).
/// [`read_smpl_npz`] reads the body of such a file back.
pub fn write_smplh_npz(
    path: &Path,
    poses: &[f32],
    trans: &[f32],
    fps: f32,
    opts: &SmplNpzOptions,
) -> Result<(), ReprError> {
    write_smplh_npz_with(path, poses, trans, fps, None, None, opts)
}

/// The member of an SMPL-H `.npz` that holds the face ([`write_smplh_npz_with`]): `(T, 52)`
/// ARKit blendshape weights in `[0, 1]`, float32. Ours; AMASS readers ignore it.
pub const FACE_MEMBER: &str = "face_arkit52";

/// [`write_smplh_npz`] plus, when given, the face as [`FACE_MEMBER`] (`(T, 52)`) and `record`
/// as [`RECORD_MEMBER`], so that the dance can be edited with its fingers and face.
pub fn write_smplh_npz_with(
    path: &Path,
    poses: &[f32],
    trans: &[f32],
    fps: f32,
    face: Option<&[f32]>,
    record: Option<&str>,
    opts: &SmplNpzOptions,
) -> Result<(), ReprError> {
    let width = SMPLH_JOINTS * 3;
    let t = dancegen_motion::repr::frames_of("SMPL-H poses", poses, width)?;
    let tt = dancegen_motion::repr::frames_of("SMPL-H trans", trans, 3)?;
    if t != tt {
        return Err(ReprError::FrameMismatch {
            what: "SMPL-H motion",
            poses: t,
            trans: tt,
        });
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(ReprError::Invalid(format!("fps {fps} is not positive")));
    }
    if let Some(f) = face
        && f.len() != t * FACE_WEIGHTS
    {
        return Err(ReprError::Invalid(format!(
            "the face has {} values for {t} frames of {FACE_WEIGHTS} weights",
            f.len()
        )));
    }
    write_amass(
        path,
        poses,
        width,
        trans,
        fps,
        Some(WRITTEN_GENDER),
        record,
        face,
        opts,
    )
}

/// ARKit weights per frame in [`FACE_MEMBER`].
pub const FACE_WEIGHTS: usize = 52;

/// The rotations and face [`read_smplh_face`] reads.
#[derive(Clone, Debug)]
pub struct SmplhFace {
    /// `(T, 156)` as stored (the root orientation in the file's up-axis convention).
    pub poses: Vec<f32>,
    /// `(T, 52)` ARKit weights.
    pub face: Vec<f32>,
}

/// The full SMPL-H rotations `(T, 156)` and the face `(T, 52)` of an `.npz`
/// [`write_smplh_npz_with`] wrote, at the file's rate (with its `trans` as stored); `None` for
/// a file without the face (any other `.npz`).
pub fn read_smplh_face(path: &Path) -> Result<Option<SmplhFace>, ReprError> {
    let members = dancegen_io::npz::read_npz_members(path, &["poses", FACE_MEMBER])
        .map_err(|e| ReprError::Invalid(e.to_string()))?;
    let get = |name: &str| members.iter().find(|(n, _)| n == name).map(|(_, a)| a);
    let (Some(poses), Some(face)) = (get("poses"), get(FACE_MEMBER)) else {
        return Ok(None);
    };
    let t = face.data.len() / FACE_WEIGHTS;
    if face.shape != [t, FACE_WEIGHTS] || poses.shape != [t, SMPLH_JOINTS * 3] {
        return Err(ReprError::Invalid(format!(
            "{}: {FACE_MEMBER} {:?} and poses {:?} are not (T, {FACE_WEIGHTS}) and (T, {})",
            path.display(),
            face.shape,
            poses.shape,
            SMPLH_JOINTS * 3
        )));
    }
    let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    Ok(Some(SmplhFace {
        poses: f32s(&poses.data),
        face: f32s(&face.data),
    }))
}

/// The AMASS-style writer behind [`write_smpl_npz`] and [`write_smplh_npz`]: `poses` is
/// `(T, width)` with the root first, `trans` the `(T, 3)` pelvis, shapes already checked.
#[allow(clippy::too_many_arguments)]
fn write_amass(
    path: &Path,
    poses: &[f32],
    width: usize,
    trans: &[f32],
    fps: f32,
    gender: Option<&str>,
    record: Option<&str>,
    face: Option<&[f32]>,
    opts: &SmplNpzOptions,
) -> Result<(), ReprError> {
    let t = trans.len() / 3;
    let mut out_poses: Vec<f64> = poses.iter().map(|&v| f64::from(v)).collect();
    let mut out_trans = Vec::with_capacity(t * 3);
    for f in 0..t {
        let (root, tr) = amass_frame(&poses[f * width..], &trans[f * 3..], opts);
        out_poses[f * width..f * width + 3].copy_from_slice(&root);
        out_trans.extend(tr);
    }
    let fps = [f64::from(fps)];
    let betas = [0.0f64; WRITTEN_BETAS];
    let (poses_shape, trans_shape) = ([t, width], [t, 3]);
    let mut members: Vec<(&str, &[usize], NpyData<'_>)> = vec![
        ("poses", &poses_shape, NpyData::F64(&out_poses)),
        ("trans", &trans_shape, NpyData::F64(&out_trans)),
        ("betas", &[WRITTEN_BETAS], NpyData::F64(&betas)),
    ];
    if let Some(g) = gender {
        members.push(("gender", &[], NpyData::Str(g)));
    }
    members.push(("mocap_framerate", &[], NpyData::F64(&fps)));
    if let Some(r) = record {
        members.push((RECORD_MEMBER, &[], NpyData::Str(r)));
    }
    let face_shape = [t, FACE_WEIGHTS];
    if let Some(f) = face {
        members.push((FACE_MEMBER, &face_shape, NpyData::F32(f)));
    }
    write_npz(path, &members)?;
    Ok(())
}

/// Writes an EDGE-style `.npz` with EDGE's output keys and units (float32, Z-up, metres):
/// `smpl_poses` (T, 72) with the root orientation in Z-up, `smpl_trans` (T, 3) =
/// `Z(pelvis − J0)`, `full_pose` (T, 24, 3) = EDGE FK positions `Z(joints − J0)`, plus `fps`
/// (a scalar EDGE does not write; EDGE outputs are 30 fps).
pub fn write_edge_npz(path: &Path, m: &SmplMotion, opts: &SmplNpzOptions) -> Result<(), ReprError> {
    let t = m.validate()?;
    let j0 = opts.pelvis_rest.map(f64::from);
    let joints = m.joints_world()?;
    let mut poses = m.poses.clone();
    let mut trans = Vec::with_capacity(t * 3);
    for f in 0..t {
        let root = yup_to_zup_root_axis_angle(m.joint_aa(f, 0).map(f64::from));
        for (d, s) in poses[f * POSE_DIMS..f * POSE_DIMS + 3].iter_mut().zip(root) {
            *d = s as f32;
        }
        let p = [m.trans[f * 3], m.trans[f * 3 + 1], m.trans[f * 3 + 2]].map(f64::from);
        trans
            .extend(yup_to_zup_point([p[0] - j0[0], p[1] - j0[1], p[2] - j0[2]]).map(|v| v as f32));
    }
    let full_pose: Vec<f32> = joints
        .chunks_exact(3)
        .flat_map(|p| {
            let p = p.iter().map(|&v| f64::from(v)).collect::<Vec<_>>();
            yup_to_zup_point([p[0] - j0[0], p[1] - j0[1], p[2] - j0[2]]).map(|v| v as f32)
        })
        .collect();
    let fps = [m.fps];
    write_npz(
        path,
        &[
            ("smpl_poses", &[t, POSE_DIMS], NpyData::F32(&poses)),
            ("smpl_trans", &[t, 3], NpyData::F32(&trans)),
            ("full_pose", &[t, SMPL_JOINTS, 3], NpyData::F32(&full_pose)),
            ("fps", &[], NpyData::F32(&fps)),
        ],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aistpp::load_motion;
    use dancegen_motion::fk::fk_axis_angle_f64;
    use dancegen_motion::skeleton::Skeleton;

    const SEQS: [&str; 3] = [
        "gBR_sBM_cAll_d04_mBR2_ch08",
        "gBR_sBM_cAll_d06_mBR2_ch06",
        "gJS_sFM_cAll_d02_mJS4_ch09",
    ];

    fn aistpp(seq: &str) -> crate::aistpp::AistppMotion {
        let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
        load_motion(shared.join(format!("data/aistpp/motions/{seq}.pkl"))).unwrap()
    }

    fn fk64(m: &SmplMotion) -> Vec<f64> {
        let p: Vec<f64> = m.poses.iter().map(|&v| v.into()).collect();
        let t: Vec<f64> = m.trans.iter().map(|&v| v.into()).collect();
        fk_axis_angle_f64(&Skeleton::smpl24(), &p, &t).unwrap()
    }

    fn max_diff<A: Copy + Into<f64>, B: Copy + Into<f64>>(a: &[A], b: &[B]) -> f64 {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .map(|(&x, &y)| (x.into() - y.into()).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn aistpp_round_trips_through_both_writers() {
        let dir = tempfile::tempdir().unwrap();
        for seq in SEQS {
            let raw = aistpp(seq);
            let m = raw.to_smpl_motion();
            let edge_m = raw.to_smpl_motion_edge();
            let want = fk64(&m);
            let z = SmplNpzOptions::default();
            let y = SmplNpzOptions { up: UpAxis::Y, ..z };
            let cases = [
                ("amass_z.npz", SmplNpzLayout::Amass, z),
                ("amass_y.npz", SmplNpzLayout::Amass, y),
                ("edge.npz", SmplNpzLayout::Edge, z),
            ];
            for (name, layout, opts) in cases {
                let p = dir.path().join(name);
                match layout {
                    SmplNpzLayout::Amass => write_smpl_npz(&p, &m, &opts).unwrap(),
                    SmplNpzLayout::Edge => write_edge_npz(&p, &m, &opts).unwrap(),
                }
                let r = read_smpl_npz(&p, &opts).unwrap();
                assert_eq!(r.layout, layout);
                assert_eq!(r.source_joints, 24);
                assert_eq!(r.motion.fps, 60.0);
                assert_eq!(r.motion.frames(), m.frames());
                let d = max_diff(&fk64(&r.motion), &want);
                assert!(d < 1e-6, "{seq} {name}: FK joints differ by {d} m");
                let members = dancegen_io::read_npz(&p).unwrap();
                let get = |k: &str| &members.iter().find(|(n, _)| n == k).unwrap().1;
                match layout {
                    SmplNpzLayout::Amass => {
                        assert_eq!(r.betas, vec![0.0; WRITTEN_BETAS]);
                        let trans = &get("trans").data;
                        if opts.up == UpAxis::Y {
                            // Y-up `transl` is exactly AIST++'s smpl_trans / smpl_scaling.
                            let d = max_diff(trans, &edge_m.trans);
                            assert!(d < 1e-6, "{seq}: transl vs AIST++ differs by {d}");
                        } else {
                            // Z-up: pelvis_zup = transl + J0 (J0 not rotated).
                            for (f, tr) in trans.chunks_exact(3).enumerate() {
                                let p = m.trans[f * 3..f * 3 + 3].iter().map(|&v| v.into());
                                let p: Vec<f64> = p.collect();
                                let pz = yup_to_zup_point([p[0], p[1], p[2]]);
                                for k in 0..3 {
                                    let j0 = f64::from(AISTPP_PELVIS_REST[k]);
                                    assert!((tr[k] + j0 - pz[k]).abs() < 1e-6);
                                }
                            }
                        }
                    }
                    SmplNpzLayout::Edge => {
                        // EDGE's smpl_trans is its training root: Z(smpl_trans / smpl_scaling).
                        let want_root: Vec<f64> = edge_m
                            .trans
                            .chunks_exact(3)
                            .flat_map(|p| yup_to_zup_point([p[0], p[1], p[2]].map(f64::from)))
                            .collect();
                        let d = max_diff(&get("smpl_trans").data, &want_root);
                        assert!(d < 1e-6, "{seq}: EDGE smpl_trans differs by {d}");
                        // full_pose = EDGE's Z-up FK of (smpl_poses, smpl_trans).
                        let sp = &get("smpl_poses").data;
                        let st = &get("smpl_trans").data;
                        let fp = fk_axis_angle_f64(&Skeleton::smpl24(), sp, st).unwrap();
                        let d = max_diff(&get("full_pose").data, &fp);
                        assert!(d < 1e-5, "{seq}: full_pose vs EDGE FK differs by {d}");
                        assert_eq!(get("full_pose").shape, vec![m.frames(), 24, 3]);
                    }
                }
            }
        }
    }

    /// An AMASS file without a rate member is refused as `NoRate` (so a caller can say how to
    /// give one), unless the rate is given; a given rate overrides a stored one.
    #[test]
    fn a_missing_rate_is_no_rate_unless_one_is_given() {
        let dir = tempfile::tempdir().unwrap();
        let t = 4;
        let poses = vec![0.0f64; t * 72];
        let trans = vec![0.0f64; t * 3];
        let write = |name: &str, rate: Option<f64>| {
            let p = dir.path().join(name);
            let (ps, ts) = ([t, 72], [t, 3]);
            let mut members = vec![
                ("poses", &ps[..], NpyData::F64(&poses)),
                ("trans", &ts[..], NpyData::F64(&trans)),
            ];
            let r = rate.map(|r| [r]);
            if let Some(r) = &r {
                members.push(("mocap_framerate", &[][..], NpyData::F64(r)));
            }
            write_npz(&p, &members).unwrap();
            p
        };
        let none = write("none.npz", None);
        match read_smpl_npz(&none, &SmplNpzOptions::default()) {
            Err(ReprError::NoRate { path, .. }) => assert_eq!(path, none),
            other => panic!("expected NoRate, got {other:?}"),
        }
        let given = SmplNpzOptions {
            fps: Some(60.0),
            ..Default::default()
        };
        assert_eq!(read_smpl_npz(&none, &given).unwrap().motion.fps, 60.0);
        let stored = write("stored.npz", Some(120.0));
        assert_eq!(read_smpl_npz(&stored, &given).unwrap().motion.fps, 60.0);
        let bad = SmplNpzOptions {
            fps: Some(0.0),
            ..Default::default()
        };
        assert!(read_smpl_npz(&stored, &bad).is_err());
    }

    #[test]
    fn smplh_and_smplx_poses_keep_body_and_zero_hands() {
        let dir = tempfile::tempdir().unwrap();
        for width in [156usize, 165, 66] {
            let t = 5;
            let poses: Vec<f64> = (0..t * width)
                .map(|i| ((i % 97) as f64 - 48.0) * 0.01)
                .collect();
            let trans: Vec<f64> = (0..t * 3).map(|i| i as f64 * 0.1).collect();
            let p = dir.path().join(format!("h{width}.npz"));
            let betas = [0.5f64; 16];
            write_npz(
                &p,
                &[
                    ("poses", &[t, width], NpyData::F64(&poses)),
                    ("trans", &[t, 3], NpyData::F64(&trans)),
                    ("betas", &[16], NpyData::F64(&betas)),
                    ("mocap_frame_rate", &[], NpyData::F64(&[120.0])),
                ],
            )
            .unwrap();
            let opts = SmplNpzOptions {
                up: UpAxis::Y,
                ..Default::default()
            };
            let r = read_smpl_npz(&p, &opts).unwrap();
            assert_eq!(r.source_joints, width / 3);
            assert_eq!(r.motion.fps, 120.0);
            assert_eq!(r.betas, vec![0.5; 16]);
            for f in 0..t {
                let got = &r.motion.poses[f * 72..(f + 1) * 72];
                let src = &poses[f * width..f * width + 66];
                assert!(max_diff(&got[..66], src) < 1e-7);
                assert!(got[66..].iter().all(|&v| v == 0.0), "SMPL 22/23 identity");
                for k in 0..3 {
                    let want = trans[f * 3 + k] + f64::from(AISTPP_PELVIS_REST[k]);
                    assert!((f64::from(r.motion.trans[f * 3 + k]) - want).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn smplh_writer_keeps_fingers_and_reads_back_the_body() {
        let dir = tempfile::tempdir().unwrap();
        let t = 6;
        let width = SMPLH_JOINTS * 3;
        let poses: Vec<f32> = (0..t * width)
            .map(|i| ((i % 89) as f32 - 44.0) * 0.01)
            .collect();
        let trans: Vec<f32> = (0..t * 3).map(|i| 0.9 + i as f32 * 0.01).collect();
        let p = dir.path().join("h.npz");
        let opts = SmplNpzOptions::default();
        write_smplh_npz(&p, &poses, &trans, 30.0, &opts).unwrap();
        let members = dancegen_io::read_npz_members(&p, &["poses", "trans", "betas"]).unwrap();
        let got = &members.iter().find(|(n, _)| n == "poses").unwrap().1;
        assert_eq!(got.shape, vec![t, width]);
        // Fingers (and every non-root joint) as given; the root turned to Z-up.
        for f in 0..t {
            let (a, b) = (f * width + 3, (f + 1) * width);
            assert!(max_diff(&got.data[a..b], &poses[a..b]) < 1e-7);
        }
        // The archive names `gender` (a unicode scalar our numeric reader skips).
        let raw = std::fs::read(&p).unwrap();
        assert!(raw.windows(10).any(|w| w == b"gender.npy"));
        assert!(raw.windows(4).any(|w| w == b"<U7'"));
        let r = read_smpl_npz(&p, &opts).unwrap();
        assert_eq!((r.source_joints, r.motion.fps), (SMPLH_JOINTS, 30.0));
        for f in 0..t {
            let body = &r.motion.poses[f * 72..f * 72 + 66];
            assert!(max_diff(body, &poses[f * width..f * width + 66]) < 1e-6);
        }
        assert!(max_diff(&r.motion.trans, &trans) < 1e-6);
        let e = write_smplh_npz(&p, &poses[..width * 2], &trans, 30.0, &opts).unwrap_err();
        assert!(e.to_string().contains("2 pose frames but 6"), "{e}");
        assert!(write_smplh_npz(&p, &poses[1..], &trans, 30.0, &opts).is_err());
        assert!(write_smplh_npz(&p, &poses, &trans, 0.0, &opts).is_err());
    }

    #[test]
    fn clear_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.npz");
        write_npz(&p, &[("foo", &[1], NpyData::F32(&[1.0]))]).unwrap();
        let e = read_smpl_npz(&p, &Default::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.npz") && e.contains("poses"), "{e}");

        let poses = vec![0.0f64; 2 * 72];
        let trans = vec![0.0f64; 2 * 3];
        write_npz(
            &p,
            &[
                ("poses", &[2, 72], NpyData::F64(&poses)),
                ("trans", &[2, 3], NpyData::F64(&trans)),
            ],
        )
        .unwrap();
        let e = read_smpl_npz(&p, &Default::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("mocap_framerate"), "{e}");

        write_npz(
            &p,
            &[
                ("poses", &[2, 69], NpyData::F64(&poses[..138])),
                ("trans", &[2, 3], NpyData::F64(&trans)),
                ("mocap_framerate", &[], NpyData::F64(&[30.0])),
            ],
        )
        .unwrap();
        let e = read_smpl_npz(&p, &Default::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("69"), "{e}");

        // EDGE-style without a rate member is 30 fps.
        write_npz(
            &p,
            &[
                ("smpl_poses", &[2, 72], NpyData::F64(&poses)),
                ("smpl_trans", &[2, 3], NpyData::F64(&trans)),
            ],
        )
        .unwrap();
        let r = read_smpl_npz(&p, &Default::default()).unwrap();
        assert_eq!((r.layout, r.motion.fps), (SmplNpzLayout::Edge, EDGE_FPS));
    }
}
