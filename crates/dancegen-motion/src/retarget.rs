//! Retargeting a Poser/Daz-named humanoid BVH (the CMU salsa files) to SMPL 24.
//!
//! # Method
//! 1. **Joint map** ([`POSER_TO_SMPL`]): each SMPL joint takes its world rotation from one
//!    source joint (or, for the leaves `ltoes`, `rtoes`, `lhand`, `rhand`, none: local identity):
//!    `root`←`hip`, `lhip`←`lThigh`, `lknee`←`lShin`, `lankle`←`lFoot`, `belly`←`abdomen`,
//!    `spine`←`chest`, `chest`←`chest`, `neck`←`neck`, `head`←`head`,
//!    `linshoulder`←`lCollar`, `lshoulder`←`lShldr`, `lelbow`←`lForeArm`, `lwrist`←`lHand`, and
//!    mirrored for the right side. `lButtock`/`rButtock`, fingers and eyes are not used.
//! 2. **Height normalisation**: source lengths are multiplied by
//!    `metres_per_unit = SMPL rest head-to-ankle / source rest head-to-ankle` (head joint height
//!    minus left ankle height, all channels zero). SMPL's is 1.514 m; the salsa files' ≈ 1.10.
//! 3. **Rest-pose alignment**: both rest poses are T-poses facing +Z, but bone directions differ
//!    slightly. For every SMPL joint with a mapped bone (its main child), `A_j` is the smallest
//!    rotation taking the SMPL rest bone direction to the source rest bone direction; the SMPL
//!    world rotation is `W_j(t) = R_src(t) · A_j`, so that `W_j d_smpl = R_src(t) d_src`: every
//!    mapped bone points where the source bone points. Joints without a mapped bone (root, head)
//!    use `A = I`. Local rotations are `W_parent^T · W_j` (root: `W_0`).
//! 4. **Translation**: SMPL's hip centre (mean of `lhip`, `rhip`) is placed on the source's hip
//!    centre (mean of `lThigh`, `rThigh`, scaled): `trans = c_src − W_0 · c_smpl_rest`, the pelvis
//!    world position in metres (crate convention). The Poser `hip` root is not the SMPL pelvis.
//! 5. **Frame rate**: every `stride`-th source frame, `stride = round(src_fps / target_fps)`
//!    (120 → 30 fps: every 4th frame).
//!
//! SMPL keeps its own bone lengths, so joint positions differ from the source's by the
//! proportion mismatch (e.g. the salsa shins are ≈ 6 cm longer than SMPL's after height
//! normalisation); [`retarget_report`] measures it.

use std::fmt;

use crate::bvh::Bvh;
use crate::bvh_motion::{BvhMotionError, bvh_world_transforms, smpl_fk_f64};
use crate::rotation::Mat3;
use crate::skeleton::{SMPL24_NAMES, Skeleton};
use crate::vec3::{norm, sub};

/// Where a bone of the source ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoneEnd {
    /// At this joint.
    Joint(&'static str),
    /// At the `End Site` of the rotation source joint.
    EndSite,
}

/// One row of the joint map, indexed by SMPL joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JointMapEntry {
    /// Source joint whose world rotation drives this SMPL joint; `None` = local identity.
    pub rotation_from: Option<&'static str>,
    /// End of the source bone matched to this SMPL joint's main child bone (rest alignment);
    /// `None` = no alignment (`A = I`).
    pub bone_to: Option<BoneEnd>,
    /// Source joint at the same anatomical place, for the position error; `None` = not compared.
    pub position_of: Option<&'static str>,
}

const fn e(
    rotation_from: Option<&'static str>,
    bone_to: Option<BoneEnd>,
    position_of: Option<&'static str>,
) -> JointMapEntry {
    JointMapEntry {
        rotation_from,
        bone_to,
        position_of,
    }
}

use BoneEnd::{EndSite, Joint};

/// Poser/Daz (CMU salsa) → SMPL 24 joint map, in SMPL joint order.
pub const POSER_TO_SMPL: [JointMapEntry; 24] = [
    e(Some("hip"), None, None),                                  // root
    e(Some("lThigh"), Some(Joint("lShin")), Some("lThigh")),     // lhip
    e(Some("rThigh"), Some(Joint("rShin")), Some("rThigh")),     // rhip
    e(Some("abdomen"), Some(Joint("chest")), None),              // belly
    e(Some("lShin"), Some(Joint("lFoot")), Some("lShin")),       // lknee
    e(Some("rShin"), Some(Joint("rFoot")), Some("rShin")),       // rknee
    e(Some("chest"), Some(Joint("neck")), None),                 // spine
    e(Some("lFoot"), Some(EndSite), Some("lFoot")),              // lankle
    e(Some("rFoot"), Some(EndSite), Some("rFoot")),              // rankle
    e(Some("chest"), Some(Joint("neck")), None),                 // chest
    e(None, None, None),                                         // ltoes
    e(None, None, None),                                         // rtoes
    e(Some("neck"), Some(Joint("head")), Some("neck")),          // neck
    e(Some("lCollar"), Some(Joint("lShldr")), None),             // linshoulder
    e(Some("rCollar"), Some(Joint("rShldr")), None),             // rinshoulder
    e(Some("head"), None, Some("head")),                         // head
    e(Some("lShldr"), Some(Joint("lForeArm")), Some("lShldr")),  // lshoulder
    e(Some("rShldr"), Some(Joint("rForeArm")), Some("rShldr")),  // rshoulder
    e(Some("lForeArm"), Some(Joint("lHand")), Some("lForeArm")), // lelbow
    e(Some("rForeArm"), Some(Joint("rHand")), Some("rForeArm")), // relbow
    e(Some("lHand"), Some(Joint("lMid1")), Some("lHand")),       // lwrist
    e(Some("rHand"), Some(Joint("rMid1")), Some("rHand")),       // rwrist
    e(None, None, None),                                         // lhand
    e(None, None, None),                                         // rhand
];

/// Main child of each SMPL joint used for the rest alignment (bone direction).
const SMPL_MAIN_CHILD: [Option<usize>; 24] = [
    None,
    Some(4),
    Some(5),
    Some(6),
    Some(7),
    Some(8),
    Some(9),
    Some(10),
    Some(11),
    Some(12),
    None,
    None,
    Some(15),
    Some(16),
    Some(17),
    None,
    Some(18),
    Some(19),
    Some(20),
    Some(21),
    Some(22),
    Some(23),
    None,
    None,
];

/// SMPL motion retargeted from a BVH.
#[derive(Debug, Clone, PartialEq)]
pub struct RetargetOutput {
    /// `frames × 72` axis-angle, SMPL order.
    pub poses: Vec<f32>,
    /// `frames × 3` pelvis world position, metres.
    pub trans: Vec<f32>,
    pub frames: usize,
    /// Output frame rate, `source fps / stride`.
    pub fps: f64,
    /// Source frames per output frame.
    pub stride: usize,
    /// Height normalisation: metres per source unit.
    pub metres_per_unit: f64,
}

/// A bone length in both skeletons, metres (source after height normalisation).
#[derive(Debug, Clone, PartialEq)]
pub struct BoneLength {
    pub name: &'static str,
    pub source_m: f64,
    pub smpl_m: f64,
}

/// Quality of a retarget.
#[derive(Debug, Clone, PartialEq)]
pub struct RetargetReport {
    pub frames: usize,
    pub metres_per_unit: f64,
    /// Mean over frames and compared joints of the SMPL FK ↔ source joint distance, cm.
    pub mean_error_cm: f64,
    pub max_error_cm: f64,
    /// Same distance in the rest pose (all rotations zero), cm: the part due to proportions.
    pub rest_mean_error_cm: f64,
    /// Mean angle (degrees) between each aligned SMPL bone (joint → main child, from FK) and the
    /// source bone it was aligned to; ≈ 0 by construction, so it checks the rotation chain
    /// independently of proportions.
    pub mean_bone_angle_deg: f64,
    /// `(SMPL joint name, mean error cm)` for every compared joint.
    pub per_joint_error_cm: Vec<(&'static str, f64)>,
    pub bone_lengths: Vec<BoneLength>,
}

impl fmt::Display for RetargetReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} frames, {:.4} m/unit, mean joint error {:.2} cm (max {:.2}, rest pose {:.2})",
            self.frames,
            self.metres_per_unit,
            self.mean_error_cm,
            self.max_error_cm,
            self.rest_mean_error_cm
        )?;
        writeln!(
            f,
            "  mean bone direction error {:.4}°",
            self.mean_bone_angle_deg
        )?;
        for (n, v) in &self.per_joint_error_cm {
            writeln!(f, "  {n:<10} {v:6.2} cm")?;
        }
        for b in &self.bone_lengths {
            writeln!(
                f,
                "  bone {:<10} source {:.3} m, SMPL {:.3} m",
                b.name, b.source_m, b.smpl_m
            )?;
        }
        Ok(())
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

fn idx(bvh: &Bvh, name: &str) -> Result<usize, BvhMotionError> {
    bvh.joint_index(name)
        .ok_or_else(|| BvhMotionError::MissingJoint(name.to_owned()))
}

/// Rest-pose (all channels zero) world positions of the source, file units.
fn source_rest(bvh: &Bvh) -> Result<Vec<[f64; 3]>, BvhMotionError> {
    let mut rest = bvh.clone();
    rest.frames = 1;
    rest.data = vec![0.0; bvh.num_channels()];
    Ok(bvh_world_transforms(&rest, 1.0)?.1)
}

/// `SMPL rest head-to-ankle / source rest head-to-ankle` (`head` minus `lFoot` height).
pub fn height_normalisation(bvh: &Bvh) -> Result<f64, BvhMotionError> {
    let rest = source_rest(bvh)?;
    let h = rest[idx(bvh, "head")?][1] - rest[idx(bvh, "lFoot")?][1];
    let smpl = Skeleton::smpl24().rest_positions();
    let hs = smpl[15][1] - smpl[7][1];
    if !(h.is_finite() && h > 0.0) {
        return Err(BvhMotionError::Units(h));
    }
    Ok(hs / h)
}

/// Retargets a Poser/Daz-named BVH (CMU salsa) to SMPL 24 at about `target_fps` (see the module
/// documentation).
pub fn retarget_poser_to_smpl(
    bvh: &Bvh,
    target_fps: f64,
) -> Result<RetargetOutput, BvhMotionError> {
    if !(target_fps.is_finite() && target_fps > 0.0) {
        return Err(BvhMotionError::Fps(target_fps));
    }
    let src_fps = bvh.nominal_fps();
    let stride = ((src_fps / target_fps).round() as usize).max(1);
    let mpu = height_normalisation(bvh)?;
    let skel = Skeleton::smpl24();
    let smpl_rest = skel.rest_positions();
    let src_rest = source_rest(bvh)?;

    // Rotation sources and rest alignments.
    let mut rot_src: [Option<usize>; 24] = [None; 24];
    let mut align_m = [Mat3::IDENTITY; 24];
    for (j, m) in POSER_TO_SMPL.iter().enumerate() {
        let Some(name) = m.rotation_from else {
            continue;
        };
        let s = idx(bvh, name)?;
        rot_src[j] = Some(s);
        if let (Some(end), Some(c)) = (m.bone_to, SMPL_MAIN_CHILD[j]) {
            let d_src = match end {
                Joint(n) => sub(src_rest[idx(bvh, n)?], src_rest[s]),
                EndSite => bvh.joints[s]
                    .end_site
                    .ok_or_else(|| BvhMotionError::MissingJoint(format!("{name} End Site")))?,
            };
            let d_smpl = sub(smpl_rest[c], smpl_rest[j]);
            align_m[j] = Mat3::between(d_smpl, d_src);
        }
    }
    let (lt, rt) = (idx(bvh, "lThigh")?, idx(bvh, "rThigh")?);
    let c_smpl = [0, 1, 2].map(|a| 0.5 * (smpl_rest[1][a] + smpl_rest[2][a]) - smpl_rest[0][a]);

    let (rots, poss) = bvh_world_transforms(bvh, mpu)?;
    let nj = bvh.joints.len();
    let out_frames: Vec<usize> = (0..bvh.frames).step_by(stride).collect();
    let mut poses = Vec::with_capacity(out_frames.len() * 72);
    let mut trans = Vec::with_capacity(out_frames.len() * 3);
    let parents = skel.parents();
    let mut world = [Mat3::IDENTITY; 24];
    for &f in &out_frames {
        let r = &rots[f * nj..(f + 1) * nj];
        let p = &poss[f * nj..(f + 1) * nj];
        for j in 0..24 {
            world[j] = match (rot_src[j], parents[j]) {
                (Some(s), _) => r[s].mul(&align_m[j]),
                (None, Some(pj)) => world[pj],
                (None, None) => Mat3::IDENTITY,
            };
            let local = match parents[j] {
                Some(pj) => world[pj].transpose().mul(&world[j]),
                None => world[j],
            };
            poses.extend(local.to_axis_angle().map(|v| v as f32));
        }
        let c_src = [0, 1, 2].map(|a| 0.5 * (p[lt][a] + p[rt][a]));
        let off = world[0].mul_vec(c_smpl);
        trans.extend(sub(c_src, off).map(|v| v as f32));
    }
    Ok(RetargetOutput {
        frames: out_frames.len(),
        poses,
        trans,
        fps: src_fps / stride as f64,
        stride,
        metres_per_unit: mpu,
    })
}

/// Compares SMPL FK of `out` with the height-normalised source joints it was retargeted from
/// (the `position_of` joints of [`POSER_TO_SMPL`]), and lists bone lengths.
pub fn retarget_report(bvh: &Bvh, out: &RetargetOutput) -> Result<RetargetReport, BvhMotionError> {
    let mpu = out.metres_per_unit;
    let (rots, poss) = bvh_world_transforms(bvh, mpu)?;
    let nj = bvh.joints.len();
    let fk = smpl_fk_f64(&out.poses, &out.trans)?;
    // (SMPL joint, SMPL child, source start, source end: Some(joint) or None = end site).
    let mut aligned: Vec<(usize, usize, usize, Option<usize>)> = Vec::new();
    for (j, m) in POSER_TO_SMPL.iter().enumerate() {
        if let (Some(rf), Some(end), Some(c)) = (m.rotation_from, m.bone_to, SMPL_MAIN_CHILD[j]) {
            let e = match end {
                Joint(n) => Some(idx(bvh, n)?),
                EndSite => None,
            };
            aligned.push((j, c, idx(bvh, rf)?, e));
        }
    }
    let mut angle_sum = 0.0;
    for k in 0..out.frames {
        let f = k * out.stride;
        for &(j, c, s, e) in &aligned {
            let a = [0, 1, 2].map(|i| fk[(k * 24 + c) * 3 + i] - fk[(k * 24 + j) * 3 + i]);
            let b = match e {
                Some(e) => sub(poss[f * nj + e], poss[f * nj + s]),
                None => rots[f * nj + s].mul_vec(bvh.joints[s].end_site.unwrap_or_default()),
            };
            let cosv = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (norm(a) * norm(b));
            angle_sum += cosv.clamp(-1.0, 1.0).acos().to_degrees();
        }
    }
    let mean_bone_angle_deg = angle_sum / (out.frames * aligned.len()).max(1) as f64;
    let pairs: Vec<(usize, usize)> = POSER_TO_SMPL
        .iter()
        .enumerate()
        .filter_map(|(j, m)| m.position_of.map(|n| (j, n)))
        .map(|(j, n)| idx(bvh, n).map(|s| (j, s)))
        .collect::<Result<_, _>>()?;
    let mut per = vec![0.0; pairs.len()];
    let mut max: f64 = 0.0;
    for k in 0..out.frames {
        let f = k * out.stride;
        for (q, &(j, s)) in pairs.iter().enumerate() {
            let a = [0, 1, 2].map(|i| fk[(k * 24 + j) * 3 + i]);
            let d = dist(a, poss[f * nj + s]);
            per[q] += d;
            max = max.max(d);
        }
    }
    let denom = out.frames.max(1) as f64;
    per.iter_mut().for_each(|v| *v *= 100.0 / denom);
    let mean = per.iter().sum::<f64>() / per.len().max(1) as f64;

    // Rest pose: align the hip centres, as the retarget does.
    let src_rest: Vec<[f64; 3]> = source_rest(bvh)?
        .into_iter()
        .map(|p| p.map(|v| v * mpu))
        .collect();
    let smpl_rest = Skeleton::smpl24().rest_positions();
    let (lt, rt) = (idx(bvh, "lThigh")?, idx(bvh, "rThigh")?);
    let shift = [0, 1, 2].map(|a| {
        0.5 * (src_rest[lt][a] + src_rest[rt][a]) - 0.5 * (smpl_rest[1][a] + smpl_rest[2][a])
    });
    let rest_mean = pairs
        .iter()
        .map(|&(j, s)| dist([0, 1, 2].map(|a| smpl_rest[j][a] + shift[a]), src_rest[s]))
        .sum::<f64>()
        * 100.0
        / pairs.len().max(1) as f64;

    let bones: [(&str, usize, usize, &str, &str); 8] = [
        ("l thigh", 1, 4, "lThigh", "lShin"),
        ("r thigh", 2, 5, "rThigh", "rShin"),
        ("l shin", 4, 7, "lShin", "lFoot"),
        ("r shin", 5, 8, "rShin", "rFoot"),
        ("l upperarm", 16, 18, "lShldr", "lForeArm"),
        ("r upperarm", 17, 19, "rShldr", "rForeArm"),
        ("l forearm", 18, 20, "lForeArm", "lHand"),
        ("r forearm", 19, 21, "rForeArm", "rHand"),
    ];
    let mut bone_lengths = Vec::with_capacity(bones.len());
    for (name, a, b, sa, sb) in bones {
        bone_lengths.push(BoneLength {
            name,
            source_m: dist(src_rest[idx(bvh, sa)?], src_rest[idx(bvh, sb)?]),
            smpl_m: dist(smpl_rest[a], smpl_rest[b]),
        });
    }
    Ok(RetargetReport {
        frames: out.frames,
        metres_per_unit: mpu,
        mean_error_cm: mean,
        max_error_cm: max * 100.0,
        rest_mean_error_cm: rest_mean,
        mean_bone_angle_deg,
        per_joint_error_cm: pairs
            .iter()
            .zip(per)
            .map(|(&(j, _), v)| (SMPL24_NAMES[j], v))
            .collect(),
        bone_lengths,
    })
}
