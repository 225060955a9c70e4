//! HumanML3D-style 263-dim body vector for the SMPL 22-joint body (the body part of SoulNet's
//! HumanTOMATO-style 623 / 723, anchors.md C.6; layout and steps of
//! `EricGuo5513/HumanML3D:motion_representation.ipynb` `process_file` / `recover_from_ric`).
//!
//! Canonicalisation of the whole clip (world joints from FK, joints 0–21, Y-up):
//! 1. floor: subtract the minimum y over all joints and frames;
//! 2. subtract frame 0's root x, z;
//! 3. rotate about Y so frame 0 faces +Z: across = (r_hip − l_hip) + (r_shoulder − l_shoulder)
//!    (joints 2, 1, 17, 16), forward = up × across.
//!
//! Per-frame heading `r_rot[t]`: the Y rotation taking forward (same rule, Gaussian-smoothed over
//! time with σ = 20 frames, scipy `gaussian_filter1d` mode `nearest`) to +Z, made
//! sign-continuous over time (`qfix`).
//!
//! Per frame `t < T − 1` (the output has **T − 1** frames):
//!
//! | dims | content |
//! |---|---|
//! | 0 | root rotation velocity: `asin(y)` of `r_rot[t+1] · r_rot[t]⁻¹` (half the yaw step) |
//! | 1..3 | root linear velocity x, z: `r_rot[t+1] (p₀[t+1] − p₀[t])` |
//! | 3 | root y |
//! | 4..67 | ric: joints 1–21 relative to the root's x, z, rotated by `r_rot[t]` (21 × 3) |
//! | 67..193 | rot: joints 1–21 local rotations as **continuous 6D = first two columns** (HumanML3D `quaternion_to_cont6d_np`; *not* EDGE's rows) (21 × 6) |
//! | 193..259 | local velocity: `r_rot[t] (p_j[t+1] − p_j[t])`, joints 0–21 (22 × 3) |
//! | 259..263 | foot contacts l-ankle 7, l-toe 10, r-ankle 8, r-toe 11: squared displacement per frame < 0.002 m² |
//!
//! Differences from HumanML3D: no skeleton "uniformisation" (the EDGE SMPL offsets are used as
//! they are), and `rot` holds the **true SMPL local rotations** instead of HumanML3D's
//! twist-free IK; HumanML3D runs at 20 fps, here the motion's own rate is kept (the 0.002
//! threshold is per frame).
//!
//! The building blocks ([`dims_for_joints`], [`RicLayout`] and the crate-internal encoder /
//! decoder) are generic over the joint count; [`super::holistic`] uses them for the 52-joint
//! SoulNet 623 / 723.

use super::motion::{POSE_DIMS, SMPL_JOINTS};
use super::{ReprError, SmplMotion, frames_of};
use crate::rigid_fit::fit_rotation;
use crate::rot6d_track::decode_6d_track;
use crate::rotation::{Mat3, Quat};
use crate::skeleton::{SMPL24_OFFSETS, SMPL24_PARENTS};

/// Body joints of the representation (SMPL 0–21).
pub const JOINTS: usize = 22;
/// HumanML3D's foot-contact threshold on the squared per-frame displacement (m²).
pub const CONTACT_SQ_THRESHOLD: f64 = 0.002;
/// σ (frames) of the heading smoothing.
pub const HEADING_SIGMA: f64 = 20.0;

/// The HumanML3D-style 263-dim representation; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct HumanMl263;

/// Encoder output with the intermediate quantities, for checks and visualisation.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanMl263Parts {
    /// `(T − 1, 263)`.
    pub data: Vec<f32>,
    /// `(T, 22, 3)` canonicalised world joints (steps 1–3).
    pub positions: Vec<f64>,
    /// `(T,)` heading quaternions `r_rot`.
    pub heading: Vec<Quat>,
}

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: V3) -> V3 {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt().max(1e-12);
    [a[0] / n, a[1] / n, a[2] / n]
}

/// `qbetween_np(v, +Z)`: shortest rotation taking `v` to +Z.
fn qbetween_to_z(v: V3) -> Quat {
    let t = [0.0, 0.0, 1.0];
    let c = cross(v, t);
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    Quat::new(n + v[2], c[0], c[1], c[2]).normalize()
}

fn forward(p: &[f64], joints: usize, t: usize) -> V3 {
    let j = |k: usize| {
        let o = (t * joints + k) * 3;
        [p[o], p[o + 1], p[o + 2]]
    };
    let across = normalize(
        sub(j(2), j(1))
            .iter()
            .zip(sub(j(17), j(16)))
            .map(|(a, b)| a + b)
            .collect::<Vec<_>>()
            .try_into()
            .unwrap_or([0.0; 3]),
    );
    cross([0.0, 1.0, 0.0], across)
}

/// scipy `gaussian_filter1d(x, sigma, mode='nearest', truncate=4)` on a sequence of vectors.
fn gaussian_smooth(x: &[V3], sigma: f64) -> Vec<V3> {
    let r = (4.0 * sigma + 0.5) as i64;
    let w: Vec<f64> = (-r..=r)
        .map(|i| (-0.5 * (i as f64 / sigma).powi(2)).exp())
        .collect();
    let s: f64 = w.iter().sum();
    let n = x.len() as i64;
    (0..n)
        .map(|t| {
            let mut acc = [0.0; 3];
            for (k, wk) in w.iter().enumerate() {
                let idx = (t + k as i64 - r).clamp(0, n - 1) as usize;
                for c in 0..3 {
                    acc[c] += wk / s * x[idx][c];
                }
            }
            acc
        })
        .collect()
}

impl HumanMl263 {
    /// Values per frame.
    pub const DIMS: usize = dims_for_joints(JOINTS);

    /// Encodes to `(T − 1, 263)`.
    pub fn encode(m: &SmplMotion) -> Result<Vec<f32>, ReprError> {
        Ok(Self::encode_parts(m)?.data)
    }

    /// Encodes and returns the intermediate quantities too.
    pub fn encode_parts(m: &SmplMotion) -> Result<HumanMl263Parts, ReprError> {
        let t = m.validate()?;
        if t < 2 {
            return Err(ReprError::Invalid(
                "HumanMl263 needs at least 2 frames".into(),
            ));
        }
        let j24 = m.joints_world()?;
        let p: Vec<f64> = j24
            .chunks_exact(SMPL_JOINTS * 3)
            .flat_map(|f| f[..JOINTS * 3].iter().map(|&v| v as f64))
            .collect();
        let (data, positions, heading) = encode_ric(JOINTS, p, |f, k| {
            Mat3::from_axis_angle(m.joint_aa(f, k).map(f64::from))
        });
        Ok(HumanMl263Parts {
            data,
            positions,
            heading,
        })
    }

    /// HumanML3D `recover_from_ric`: world joints `(T', 22, 3)` from `(T', 263)`, in the frame
    /// whose initial heading is the identity (i.e. the canonical positions rotated by
    /// `heading[0]`).
    pub fn decode_joints(data: &[f32]) -> Result<Vec<f32>, ReprError> {
        decode_ric_joints("HumanMl263::decode_joints", data, JOINTS)
    }

    /// Decodes to an SMPL motion at `fps`: root position from [`HumanMl263::decode_joints`], root
    /// rotation solved from the decoded pelvis, hip and belly joints (exact for SMPL-offset
    /// data), joints 1–21 from the 6D, hands 22, 23 identity.
    pub fn decode(data: &[f32], fps: f32) -> Result<SmplMotion, ReprError> {
        let joints = Self::decode_joints(data)?;
        let (aa, trans) = decode_ric_rotations(data, &joints, JOINTS, &SMPL24_OFFSETS);
        let mut poses = Vec::with_capacity(trans.len() / 3 * POSE_DIMS);
        for f in aa.chunks_exact(JOINTS * 3) {
            poses.extend_from_slice(f);
            poses.extend([0.0; 6]);
        }
        SmplMotion::new(fps, poses, trans)
    }
}

/// Values per frame of the HumanML3D layout generalised to `joints` joints (root 4, ric
/// 3·(J − 1), rot 6·(J − 1), local velocity 3·J, contacts 4): `12·J − 1`, i.e. 263 for the
/// 22-joint body and 623 for the 52-joint SMPL-H body + hands ([`super::holistic`]).
pub const fn dims_for_joints(joints: usize) -> usize {
    12 * joints - 1
}

/// Start offsets of the blocks of the generalised layout for `joints` joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RicLayout {
    pub joints: usize,
}

impl RicLayout {
    /// Values per frame, [`dims_for_joints`].
    pub const fn dims(self) -> usize {
        dims_for_joints(self.joints)
    }
    /// First ric value (after root rot velocity 1, linear velocity 2, root y 1).
    pub const fn ric(self) -> usize {
        4
    }
    /// First 6D rotation value.
    pub const fn rot(self) -> usize {
        4 + 3 * (self.joints - 1)
    }
    /// First local-velocity value.
    pub const fn vel(self) -> usize {
        4 + 9 * (self.joints - 1)
    }
    /// First foot-contact value (4 contacts follow).
    pub const fn contacts(self) -> usize {
        4 + 9 * (self.joints - 1) + 3 * self.joints
    }
}

/// The generalised encoder (module docs, steps 1–3 and the per-frame table) for `joints`
/// joints whose 0–21 are the SMPL body: `p` is `(T, J, 3)` world joints (T ≥ 2), `local(f, k)`
/// joint `k`'s local rotation at frame `f`. Returns `(data (T − 1, 12J − 1), canonical positions
/// (T, J, 3), heading (T,))`.
pub(crate) fn encode_ric(
    joints: usize,
    mut p: Vec<f64>,
    local: impl Fn(usize, usize) -> Mat3,
) -> (Vec<f32>, Vec<f64>, Vec<Quat>) {
    let t = p.len() / (joints * 3);
    let dims = dims_for_joints(joints);
    // 1. floor, 2. frame-0 root xz at origin, 3. face +Z at frame 0.
    let floor = p
        .iter()
        .skip(1)
        .step_by(3)
        .copied()
        .fold(f64::INFINITY, f64::min);
    let (x0, z0) = (p[0], p[2]);
    for v in p.chunks_exact_mut(3) {
        v[0] -= x0;
        v[1] -= floor;
        v[2] -= z0;
    }
    let q_init = qbetween_to_z(normalize(forward(&p, joints, 0)));
    for v in p.chunks_exact_mut(3) {
        let r = q_init.rotate([v[0], v[1], v[2]]);
        v.copy_from_slice(&r);
    }
    let fwd: Vec<V3> = (0..t).map(|f| forward(&p, joints, f)).collect();
    let mut heading: Vec<Quat> = gaussian_smooth(&fwd, HEADING_SIGMA)
        .into_iter()
        .map(|v| qbetween_to_z(normalize(v)))
        .collect();
    // HumanML3D `qfix`: sign-continuous quaternions, so `asin(y)` of the step has the
    // right sign when the heading passes through −Z.
    for f in 1..t {
        if heading[f].dot(heading[f - 1]) < 0.0 {
            heading[f] = -heading[f];
        }
    }
    let pj = |f: usize, k: usize| -> V3 {
        let o = (f * joints + k) * 3;
        [p[o], p[o + 1], p[o + 2]]
    };
    let mut data = Vec::with_capacity(t.saturating_sub(1) * dims);
    for f in 0..t.saturating_sub(1) {
        let (r0, r1) = (heading[f], heading[f + 1]);
        let rv = r1 * r0.conjugate();
        data.push(rv.y.clamp(-1.0, 1.0).asin() as f32);
        let v = r1.rotate(sub(pj(f + 1, 0), pj(f, 0)));
        data.extend([v[0] as f32, v[2] as f32]);
        let root = pj(f, 0);
        data.push(root[1] as f32);
        for k in 1..joints {
            let q = pj(f, k);
            let ric = r0.rotate([q[0] - root[0], q[1], q[2] - root[2]]);
            data.extend(ric.map(|v| v as f32));
        }
        for k in 1..joints {
            data.extend(local(f, k).transpose().to_6d().map(|v| v as f32));
        }
        for k in 0..joints {
            let lv = r0.rotate(sub(pj(f + 1, k), pj(f, k)));
            data.extend(lv.map(|v| v as f32));
        }
        for k in [7, 10, 8, 11] {
            let d = sub(pj(f + 1, k), pj(f, k));
            let sq = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            data.push(if sq < CONTACT_SQ_THRESHOLD { 1.0 } else { 0.0 });
        }
    }
    (data, p, heading)
}

/// Generalised `recover_from_ric`: `(T', J, 3)` joints from `(T', 12J − 1)`.
pub(crate) fn decode_ric_joints(
    what: &'static str,
    data: &[f32],
    joints: usize,
) -> Result<Vec<f32>, ReprError> {
    let dims = dims_for_joints(joints);
    let t = frames_of(what, data, dims)?;
    let mut out = Vec::with_capacity(t * joints * 3);
    let mut ang = 0.0f64;
    let mut pos = [0.0f64; 3];
    for f in 0..t {
        let row = &data[f * dims..(f + 1) * dims];
        if f > 0 {
            let prev = &data[(f - 1) * dims..f * dims];
            ang += prev[0] as f64;
        }
        let q = Quat::new(ang.cos(), 0.0, ang.sin(), 0.0);
        let qi = q.conjugate();
        if f > 0 {
            let prev = &data[(f - 1) * dims..f * dims];
            let d = qi.rotate([prev[1] as f64, 0.0, prev[2] as f64]);
            pos[0] += d[0];
            pos[2] += d[2];
        }
        pos[1] = row[3] as f64;
        out.extend(pos.map(|v| v as f32));
        for k in 0..joints - 1 {
            let c = &row[4 + k * 3..7 + k * 3];
            let w = qi.rotate([c[0] as f64, c[1] as f64, c[2] as f64]);
            out.extend([(w[0] + pos[0]) as f32, w[1] as f32, (w[2] + pos[2]) as f32]);
        }
    }
    Ok(out)
}

/// Local rotations and root translation from the generalised layout: `decoded` is the output
/// of [`decode_ric_joints`] on `data`, `offsets` the skeleton's rest offsets. Joints 1–21 take
/// their rotations from the 6D block, each joint's track decoded by
/// [`crate::rot6d_track::decode_6d_track`] (proper rotations, as in real data, are unchanged;
/// runs of generated frames whose rows shrank are bridged); the root rotation is the one that best carries the body
/// so posed (forward kinematics from the root, joints 1–21) onto the decoded joint positions
/// relative to the pelvis ([`fit_rotation`]; where the data does not decide it, below
/// [`ROOT_TIE_MARGIN`], pulled toward the previous frame's root). Returns `(axis-angle (T', J, 3), trans (T', 3))`.
///
/// Why a fit over the body and not the pelvis frame alone: the frame spanned by the hips and
/// the belly (joints 1–3, 6-12 cm from the pelvis) is exact for consistent data but flips
/// when a generated frame swings one of those short vectors. That turned whole SoulNet bodies
/// around for a frame or two (a hand moving 1.4 m between two frames on the demo song, issue
/// 41). The fit is equally exact for consistent data and leans on all 21 body joints.
pub(crate) fn decode_ric_rotations(
    data: &[f32],
    decoded: &[f32],
    joints: usize,
    offsets: &[[f64; 3]],
) -> (Vec<f32>, Vec<f32>) {
    let layout = RicLayout { joints };
    let dims = layout.dims();
    let t = decoded.len() / (joints * 3);
    let mut poses = Vec::with_capacity(t * joints * 3);
    let mut trans = Vec::with_capacity(t * 3);
    // Each joint's 6D track decoded as one, so a generated track whose rows shrink through
    // the origin turns over its frames instead of flipping in one (`crate::rot6d_track`).
    let rot = layout.rot();
    let mut bridged = 0;
    let tracks: Vec<Vec<Mat3>> = (0..joints - 1)
        .map(|k| {
            let track: Vec<[f64; 6]> = (0..t)
                .map(|f| std::array::from_fn(|i| f64::from(data[f * dims + rot + 6 * k + i])))
                .collect();
            let (r, n) = decode_6d_track(&track);
            bridged += n;
            r
        })
        .collect();
    if bridged > 0 {
        tracing::info!(
            joint_frames = bridged,
            "bridged joint rotations whose 6D rows had shrunk below {}",
            crate::rot6d_track::MIN_ROW_LENGTH
        );
    }
    let mut local = vec![Mat3::IDENTITY; joints];
    let mut global = vec![Mat3::IDENTITY; BODY_FIT_JOINTS];
    let mut posed = vec![[0.0f64; 3]; BODY_FIT_JOINTS];
    let mut target = vec![[0.0f64; 3]; BODY_FIT_JOINTS];
    let mut prev_root: Option<Mat3> = None;
    for f in 0..t {
        let j = |k: usize| {
            let o = (f * joints + k) * 3;
            [decoded[o], decoded[o + 1], decoded[o + 2]].map(f64::from)
        };
        for (k, track) in tracks.iter().enumerate() {
            local[k + 1] = track[f].transpose();
        }
        // The body posed by its local rotations with the root unrotated at the origin.
        let root_pos = j(0);
        for k in 1..BODY_FIT_JOINTS {
            let parent = SMPL24_PARENTS[k] as usize;
            let o = global[parent].mul_vec(offsets[k]);
            posed[k] = std::array::from_fn(|a| posed[parent][a] + o[a]);
            global[k] = global[parent].mul(&local[k]);
            target[k] = sub(j(k), root_pos);
        }
        // Where the rotations and the positions disagree (generated frames), a whole family
        // of root rotations can fit almost equally, and the per-frame optimum wandered through
        // it: a 129° turn in one frame, 20° jitters (issue 41). Below the fit margin real
        // motion reaches, the previous frame's root pulls, the more the less the data decides.
        let fit = fit_rotation(&posed[1..], &target[1..], None, None);
        let pull = ROOT_CONTINUITY * (1.0 - fit.margin / ROOT_TIE_MARGIN);
        let root = match &prev_root {
            Some(prev) if pull > 0.0 => {
                fit_rotation(&posed[1..], &target[1..], None, Some((prev, pull))).rotation
            }
            _ => fit.rotation,
        };
        if let Some(prev) = &prev_root {
            let turn = turn_angle(prev, &root);
            if turn > FAST_ROOT_TURN {
                tracing::debug!(
                    frame = f,
                    turn_deg = turn.to_degrees(),
                    margin = fit.margin,
                    "the decoded root turned fast in one frame"
                );
            }
        }
        prev_root = Some(root);
        trans.extend(root_pos.map(|v| v as f32));
        poses.extend(root.to_axis_angle().map(|v| v as f32));
        for m in &local[1..] {
            poses.extend(m.to_axis_angle().map(|v| v as f32));
        }
    }
    (poses, trans)
}

/// Joints 0-21, the SMPL body every layout of this module starts with: the root rotation is
/// fitted on them ([`decode_ric_rotations`]).
const BODY_FIT_JOINTS: usize = 22;

/// The root fit's margin ([`crate::rigid_fit::RotationFit::margin`]) below which the data is
/// taken not to decide the root's rotation. Real motion stays above it: over the 29 real clips
/// of the holistic data set (about 30,000 frames) the smallest margin is 0.081; the shipped
/// autoencoder's reconstructions of them fall below 0.05 in 118 frames, and generated frames
/// that turned 129° in one had 0.0075. Above it the fit is exact (real data decodes exactly).
const ROOT_TIE_MARGIN: f64 = 0.05;

/// The previous frame's pull on the root at margin 0 (`k` of
/// [`crate::rigid_fit::fit_rotation`]; it falls linearly to 0 at [`ROOT_TIE_MARGIN`]). Chosen on
/// the training songs (`tools/holistic_sampling_validation.sh`, issue 41 part 8: 0.02 and 0.1
/// both removed the jumps; the smaller one is kept).
const ROOT_CONTINUITY: f64 = 0.02;

/// A root turn per frame worth a debug log line (30°: 900°/s at 30 fps).
const FAST_ROOT_TURN: f64 = std::f64::consts::PI / 6.0;

/// The angle of the rotation between `a` and `b`.
fn turn_angle(a: &Mat3, b: &Mat3) -> f64 {
    let d = a.transpose().mul(b).to_axis_angle();
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}
