//! Retargeting a humanoid BVH to SMPL 24, for three joint-naming conventions.
//!
//! # Source conventions
//! A convention ([`SourceConvention`]) is a joint map (one row per SMPL joint), a rest-alignment
//! rule, a height-normalisation rule and whether frame 0 may be a reference T-pose.
//! [`detect_convention`] picks the first of [`CONVENTIONS`] whose joint names are all present
//! (names may carry the prefix in front of the root's `Hips`, e.g. `Neo_Hips` → `Neo_`);
//! otherwise [`BvhMotionError::UnknownSkeleton`] lists the names found and, per convention,
//! the names missing.
//!
//! | SMPL | Poser/Daz ([`POSER_TO_SMPL`]) | cgspeed ([`CGSPEED_TO_SMPL`]) | Unity humanoid ([`UNITY_TO_SMPL`]) |
//! |---|---|---|---|
//! | root | `hip` | `Hips` | `Hips` |
//! | lhip / lknee / lankle | `lThigh` / `lShin` / `lFoot` | `LeftUpLeg` / `LeftLeg` / `LeftFoot` | same as cgspeed |
//! | ltoes | – (identity) | `LeftToeBase` | `LeftToeBase` |
//! | belly / spine / chest | `abdomen` / `chest` / `chest` | `LowerBack` / `Spine` / `Spine1` | `Spine` / `Spine1` / `Spine2` |
//! | neck / head | `neck` / `head` | `Neck1` / `Head` | `Neck` / `Head` |
//! | linshoulder / lshoulder | `lCollar` / `lShldr` | `LeftShoulder` / `LeftArm` | same as cgspeed |
//! | lelbow / lwrist | `lForeArm` / `lHand` | `LeftForeArm` / `LeftFingerBase` | `LeftForeArm` / `LeftHand` |
//! | lhand | – (identity) | – | – |
//!
//! and mirrored for the right side. Not used: Poser `lButtock`, fingers, eyes; cgspeed
//! `LHipJoint` (always zero), `Neck` (the lower neck, folded into SMPL `neck`'s local rotation),
//! `LeftHand` (CMU's forearm-twist `lwrist`, folded into SMPL `lwrist`), the finger and thumb
//! joints. The cgspeed `LeftFingerBase` is CMU's `lhand`, the joint that bends the hand, so it
//! drives SMPL `lwrist` (its bone points to `LeftHandIndex1`). The cgspeed `Spine1` is where
//! the neck and collars branch, so SMPL `chest` takes it and SMPL `neck` the upper neck `Neck1`.
//! The three Unity spine joints map one to one.
//!
//! # Method
//! 1. **Joint map**: each SMPL joint takes its world rotation from one source joint (or none:
//!    local identity, it follows its parent).
//! 2. **Height normalisation**: source lengths are multiplied by `metres_per_unit`.
//!    - Poser ([`HeightRule::HeadToAnkleRest`]): `SMPL rest head-to-ankle / source rest
//!      head-to-ankle` (head joint height minus left ankle height, all channels zero). SMPL's is
//!      1.514 m; the salsa files' ≈ 1.10.
//!    - cgspeed and Unity ([`HeightRule::LegLength`]): `SMPL leg / source leg`, leg = the
//!      hip→knee and knee→ankle bone lengths added, mean of both sides (SMPL 0.818 m). Bone
//!      lengths do not depend on the rest pose, which matters because the Unity files' rest pose
//!      is whatever pose the FBX was bound in (85_04: crouched, head 31 cm above the ankle). The
//!      cgspeed skeletons have long legs for their head height (leg / head-to-ankle 0.64, SMPL
//!      0.54), so scaling them by head height would leave SMPL's feet ≈ 14 cm above the floor
//!      when the source stands; scaling by the leg puts them on it and keeps strides consistent
//!      with SMPL's legs (the price: the upper body, ≈ 17 cm shorter than SMPL's to the
//!      shoulders, is where the position error is).
//! 3. **Rest-pose alignment**: for every SMPL joint `j` a constant `A_j` with
//!    `W_j(t) = R_src(t) · A_j` (world rotations; a BVH's world rotations are identity in its
//!    rest pose, so `A_j` is SMPL joint `j`'s world rotation when the source is at rest).
//!    - Poser ([`RestAlignment::BoneOnly`]): both rest poses are T-poses facing +Z, but bone
//!      directions differ slightly. For every SMPL joint with a mapped bone (its main child),
//!      `A_j` is the smallest rotation taking the SMPL rest bone direction to the source rest
//!      bone direction, so that `W_j d_smpl = R_src(t) d_src`: every mapped bone points where
//!      the source bone points. Joints without a mapped bone (root, head) use `A = I`.
//!    - cgspeed and Unity ([`RestAlignment::Transported`]): the source rest pose need not be a
//!      T-pose facing +Z (the Unity files face −Z, 85_04 rests crouched), so the twist about each
//!      bone must come from the body, not from the world axes. The root's `A` is the rotation
//!      taking SMPL's hip axis (`rhip`→`lhip`) onto the source's and, second, SMPL's hip-centre →
//!      `belly` direction into the plane of the source's; SMPL `chest` likewise takes its bone
//!      (→ `neck`) first and the `rshoulder`→`lshoulder` axis second. Every other joint with a
//!      mapped bone starts from its SMPL parent's `A` and adds the smallest rotation taking that
//!      parent-aligned bone to the source bone (the parent's twist is carried down the chain, so
//!      e.g. a bent rest knee is unbent about its hinge); joints without one use the parent's
//!      `A`. Mapped bones again point exactly along the source bones.
//!
//!    Local rotations are `W_parent^T · W_j` (root: `W_0`).
//! 4. **Translation**: SMPL's hip centre (mean of `lhip`, `rhip`) is placed on the source's hip
//!    centre (mean of the source joints driving `lhip`, `rhip`, scaled):
//!    `trans = c_src − W_0 · c_smpl_rest`, the pelvis world position in metres (crate
//!    convention). The source root is not the SMPL pelvis.
//! 5. **Frame rate**: every `stride`-th source frame, `stride = round(src_fps / target_fps)`
//!    (120 → 30 fps: every 4th frame), starting at source frame 0, or at frame 1 when frame 0 is
//!    a reference T-pose (below).
//!
//! # The cgspeed reference frame
//! The cgspeed BVH conversions start with one T-pose frame that is not part of the take
//! (shared data README). [`has_reference_tpose`] drops frame 0 when all of these hold: the
//! convention is cgspeed; the file has ≥ 2 frames; frame 0's root rotation is the identity
//! (within [`TPOSE_ROOT_MAX_DEG`]); frame 0 is a T-pose (upper arms along the hip axis outwards
//! within [`TPOSE_ARM_MAX_DEG`], thighs straight down within [`TPOSE_LEG_MAX_DEG`]); and frame 1
//! is far from it (some joint's world rotation changes by more than [`TPOSE_JUMP_MIN_DEG`]).
//! The rule does not depend on file names, and a take that genuinely starts in such a pose
//! keeps its frame 0 unless the next frame jumps away from it.
//!
//! SMPL keeps its own bone lengths, so joint positions differ from the source's by the
//! proportion mismatch (e.g. the salsa shins are ≈ 6 cm longer than SMPL's after height
//! normalisation); [`retarget_report`] measures it.

use std::fmt;

use crate::bvh::Bvh;
use crate::bvh_motion::{BvhMotionError, bvh_world_transforms, smpl_fk_f64};
use dancegen_motion::conventions::UP;
use dancegen_motion::rotation::Mat3;
use dancegen_motion::skeleton::{SMPL24_NAMES, Skeleton};
use dancegen_motion::vec3::{cross, dot, norm, scale, sub};

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

/// cgspeed / MotionBuilder-friendly (CMU 05, 55_01 conversions, 31 joints) → SMPL 24, in SMPL
/// joint order. The neck and head are not compared by position: cgspeed's `Neck1` sits
/// ≈ 10 cm above the collar line, SMPL's `neck` ≈ 20 cm above `chest`.
#[rustfmt::skip]
pub const CGSPEED_TO_SMPL: [JointMapEntry; 24] = [
    e(Some("Hips"), None, None),                                                   // root
    e(Some("LeftUpLeg"), Some(Joint("LeftLeg")), Some("LeftUpLeg")),               // lhip
    e(Some("RightUpLeg"), Some(Joint("RightLeg")), Some("RightUpLeg")),            // rhip
    e(Some("LowerBack"), Some(Joint("Spine")), None),                              // belly
    e(Some("LeftLeg"), Some(Joint("LeftFoot")), Some("LeftLeg")),                  // lknee
    e(Some("RightLeg"), Some(Joint("RightFoot")), Some("RightLeg")),               // rknee
    e(Some("Spine"), Some(Joint("Spine1")), None),                                 // spine
    e(Some("LeftFoot"), Some(Joint("LeftToeBase")), Some("LeftFoot")),             // lankle
    e(Some("RightFoot"), Some(Joint("RightToeBase")), Some("RightFoot")),          // rankle
    e(Some("Spine1"), Some(Joint("Neck1")), None),                                 // chest
    e(Some("LeftToeBase"), None, Some("LeftToeBase")),                             // ltoes
    e(Some("RightToeBase"), None, Some("RightToeBase")),                           // rtoes
    e(Some("Neck1"), Some(Joint("Head")), None),                                   // neck
    e(Some("LeftShoulder"), Some(Joint("LeftArm")), None),                         // linshoulder
    e(Some("RightShoulder"), Some(Joint("RightArm")), None),                       // rinshoulder
    e(Some("Head"), None, None),                                                   // head
    e(Some("LeftArm"), Some(Joint("LeftForeArm")), Some("LeftArm")),               // lshoulder
    e(Some("RightArm"), Some(Joint("RightForeArm")), Some("RightArm")),            // rshoulder
    e(Some("LeftForeArm"), Some(Joint("LeftHand")), Some("LeftForeArm")),          // lelbow
    e(Some("RightForeArm"), Some(Joint("RightHand")), Some("RightForeArm")),       // relbow
    e(Some("LeftFingerBase"), Some(Joint("LeftHandIndex1")), Some("LeftHand")),    // lwrist
    e(Some("RightFingerBase"), Some(Joint("RightHandIndex1")), Some("RightHand")), // rwrist
    e(None, None, None),                                                           // lhand
    e(None, None, None),                                                           // rhand
];

/// Unity humanoid with Mixamo-style names (CMU 85 via keijiro/CMUMocap, 22 joints, `Neo_`
/// prefix in the files) → SMPL 24, in SMPL joint order. Its end sites have zero length, so
/// toes, hands and head have no bone to align.
#[rustfmt::skip]
pub const UNITY_TO_SMPL: [JointMapEntry; 24] = [
    e(Some("Hips"), None, None),                                             // root
    e(Some("LeftUpLeg"), Some(Joint("LeftLeg")), Some("LeftUpLeg")),         // lhip
    e(Some("RightUpLeg"), Some(Joint("RightLeg")), Some("RightUpLeg")),      // rhip
    e(Some("Spine"), Some(Joint("Spine1")), None),                           // belly
    e(Some("LeftLeg"), Some(Joint("LeftFoot")), Some("LeftLeg")),            // lknee
    e(Some("RightLeg"), Some(Joint("RightFoot")), Some("RightLeg")),         // rknee
    e(Some("Spine1"), Some(Joint("Spine2")), None),                          // spine
    e(Some("LeftFoot"), Some(Joint("LeftToeBase")), Some("LeftFoot")),       // lankle
    e(Some("RightFoot"), Some(Joint("RightToeBase")), Some("RightFoot")),    // rankle
    e(Some("Spine2"), Some(Joint("Neck")), None),                            // chest
    e(Some("LeftToeBase"), None, Some("LeftToeBase")),                       // ltoes
    e(Some("RightToeBase"), None, Some("RightToeBase")),                     // rtoes
    e(Some("Neck"), Some(Joint("Head")), None),                              // neck
    e(Some("LeftShoulder"), Some(Joint("LeftArm")), None),                   // linshoulder
    e(Some("RightShoulder"), Some(Joint("RightArm")), None),                 // rinshoulder
    e(Some("Head"), None, None),                                             // head
    e(Some("LeftArm"), Some(Joint("LeftForeArm")), Some("LeftArm")),         // lshoulder
    e(Some("RightArm"), Some(Joint("RightForeArm")), Some("RightArm")),      // rshoulder
    e(Some("LeftForeArm"), Some(Joint("LeftHand")), Some("LeftForeArm")),    // lelbow
    e(Some("RightForeArm"), Some(Joint("RightHand")), Some("RightForeArm")), // relbow
    e(Some("LeftHand"), None, Some("LeftHand")),                             // lwrist
    e(Some("RightHand"), None, Some("RightHand")),                           // rwrist
    e(None, None, None),                                                     // lhand
    e(None, None, None),                                                     // rhand
];

/// How the constant rest alignments `A_j` are built (module documentation, step 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestAlignment {
    /// Smallest rotation per mapped bone, `A = I` elsewhere: for T-poses facing +Z.
    BoneOnly,
    /// Root and chest from two body axes, the rest carried down the chains: any rest pose.
    Transported,
}

/// How `metres_per_unit` is found (module documentation, step 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightRule {
    /// SMPL / source rest-pose head-to-left-ankle height.
    HeadToAnkleRest,
    /// SMPL / source leg length (hip→knee→ankle bone lengths, mean of both sides).
    LegLength,
}

/// A source skeleton's naming convention and how to retarget it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SourceConvention {
    pub name: &'static str,
    pub map: [JointMapEntry; 24],
    pub alignment: RestAlignment,
    pub height: HeightRule,
    /// Frame 0 may be a reference T-pose to drop ([`has_reference_tpose`]).
    pub reference_tpose: bool,
}

/// The CMU salsa files' Poser/Daz names.
pub const POSER: SourceConvention = SourceConvention {
    name: "Poser/Daz",
    map: POSER_TO_SMPL,
    alignment: RestAlignment::BoneOnly,
    height: HeightRule::HeadToAnkleRest,
    reference_tpose: false,
};

/// Bruce Hahne's cgspeed "MotionBuilder-friendly" CMU conversion.
pub const CGSPEED: SourceConvention = SourceConvention {
    name: "cgspeed/MotionBuilder",
    map: CGSPEED_TO_SMPL,
    alignment: RestAlignment::Transported,
    height: HeightRule::LegLength,
    reference_tpose: true,
};

/// Unity humanoid / Mixamo-style names (`Spine`, `Spine1`, `Spine2`, no `LowerBack`).
pub const UNITY_HUMANOID: SourceConvention = SourceConvention {
    name: "Unity humanoid",
    map: UNITY_TO_SMPL,
    alignment: RestAlignment::Transported,
    height: HeightRule::LegLength,
    reference_tpose: false,
};

/// Conventions in detection order. cgspeed comes before Unity: both use `LeftUpLeg`, `Spine`,
/// `Spine1`, ...; cgspeed alone has `LowerBack` and `Neck1`, Unity alone `Spine2`.
pub const CONVENTIONS: [&SourceConvention; 3] = [&POSER, &CGSPEED, &UNITY_HUMANOID];

/// Largest frame-0 root rotation of a cgspeed reference T-pose, degrees: the converter writes
/// exact zeros (05_*: `0 0 0`; 55_01: ≤ 1e-5°), real capture never has an unrotated root.
pub const TPOSE_ROOT_MAX_DEG: f64 = 0.01;
/// Largest angle between a reference T-pose's upper arm and the hip axis (outwards), degrees:
/// 8° in every cgspeed file (arms slightly below horizontal).
pub const TPOSE_ARM_MAX_DEG: f64 = 20.0;
/// Largest angle between a reference T-pose's thigh and straight down, degrees: 1° measured.
pub const TPOSE_LEG_MAX_DEG: f64 = 10.0;
/// Smallest largest-joint rotation change from the reference frame 0 to frame 1, degrees:
/// 83–180° in the cgspeed files, while consecutive dance frames (120 fps) change by ≤ 16°.
pub const TPOSE_JUMP_MIN_DEG: f64 = 30.0;

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

/// SMPL joints used by the rules below.
const SMPL_LHIP: usize = 1;
const SMPL_RHIP: usize = 2;
const SMPL_BELLY: usize = 3;
const SMPL_LKNEE: usize = 4;
const SMPL_RKNEE: usize = 5;
const SMPL_LANKLE: usize = 7;
const SMPL_RANKLE: usize = 8;
const SMPL_CHEST: usize = 9;
const SMPL_HEAD: usize = 15;
const SMPL_LSHOULDER: usize = 16;
const SMPL_RSHOULDER: usize = 17;
const SMPL_LELBOW: usize = 18;
const SMPL_RELBOW: usize = 19;

/// A convention found in a file, with the prefix its joint names carry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DetectedConvention {
    pub convention: &'static SourceConvention,
    /// Text in front of every convention name (the root's name before `Hips`, e.g. `Neo_`).
    pub prefix: String,
}

impl DetectedConvention {
    /// A convention used without detection and without a prefix.
    pub fn exact(convention: &'static SourceConvention) -> Self {
        DetectedConvention {
            convention,
            prefix: String::new(),
        }
    }

    fn full_name(&self, name: &str) -> String {
        format!("{}{name}", self.prefix)
    }

    fn idx(&self, bvh: &Bvh, name: &str) -> Result<usize, BvhMotionError> {
        let full = self.full_name(name);
        bvh.joint_index(&full)
            .ok_or(BvhMotionError::MissingJoint(full))
    }

    /// Source joint driving SMPL joint `j`.
    fn rot_idx(&self, bvh: &Bvh, j: usize) -> Result<usize, BvhMotionError> {
        let name = self.convention.map[j].rotation_from.ok_or_else(|| {
            BvhMotionError::MissingJoint(format!("source of SMPL {}", SMPL24_NAMES[j]))
        })?;
        self.idx(bvh, name)
    }

    /// Source joint at the place of SMPL joint `j`.
    fn pos_idx(&self, bvh: &Bvh, j: usize) -> Result<usize, BvhMotionError> {
        let name = self.convention.map[j].position_of.ok_or_else(|| {
            BvhMotionError::MissingJoint(format!("joint at SMPL {}", SMPL24_NAMES[j]))
        })?;
        self.idx(bvh, name)
    }
}

/// Every joint name a convention's map needs, each once, in map order.
fn required_names(c: &SourceConvention) -> Vec<&'static str> {
    let mut names: Vec<&'static str> = Vec::new();
    for m in &c.map {
        let end = match m.bone_to {
            Some(Joint(n)) => Some(n),
            _ => None,
        };
        for n in [m.rotation_from, end, m.position_of].into_iter().flatten() {
            if !names.contains(&n) {
                names.push(n);
            }
        }
    }
    names
}

/// Picks the retargeting convention of a BVH by its joint names (module documentation).
pub fn detect_convention(bvh: &Bvh) -> Result<DetectedConvention, BvhMotionError> {
    let root = bvh.joints.first().map_or("", |j| j.name.as_str());
    let prefix = root.strip_suffix("Hips").unwrap_or("").to_owned();
    let mut missing = Vec::with_capacity(CONVENTIONS.len());
    for &c in &CONVENTIONS {
        let det = DetectedConvention {
            convention: c,
            prefix: prefix.clone(),
        };
        let lacks: Vec<String> = required_names(c)
            .into_iter()
            .map(|n| det.full_name(n))
            .filter(|n| bvh.joint_index(n).is_none())
            .collect();
        if lacks.is_empty() {
            return Ok(det);
        }
        missing.push((c.name, lacks));
    }
    Err(BvhMotionError::UnknownSkeleton {
        found: bvh.joints.iter().map(|j| j.name.clone()).collect(),
        missing,
    })
}

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
    /// Source frame of output frame 0: 1 when a reference T-pose frame 0 was dropped.
    pub first_frame: usize,
    /// Height normalisation: metres per source unit.
    pub metres_per_unit: f64,
    /// The source convention the retarget used.
    pub source: DetectedConvention,
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
    /// Same distance in the rest pose, cm: the part due to proportions. Poser: SMPL's rest pose
    /// against the source's (both T-poses), hip centres aligned; other conventions: the
    /// retargeted source rest pose against the source rest pose.
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

fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
    (dot(a, b) / (norm(a) * norm(b)))
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// Angle of a rotation matrix, degrees.
fn rotation_angle_deg(m: &Mat3) -> f64 {
    norm(m.to_axis_angle()).to_degrees()
}

/// The BVH at rest (all channels zero), one frame.
fn rest_bvh(bvh: &Bvh) -> Bvh {
    let mut rest = bvh.clone();
    rest.frames = 1;
    rest.data = vec![0.0; bvh.num_channels()];
    rest
}

/// Rest-pose (all channels zero) world positions of the source, file units.
fn source_rest(bvh: &Bvh) -> Result<Vec<[f64; 3]>, BvhMotionError> {
    Ok(bvh_world_transforms(&rest_bvh(bvh), 1.0)?.1)
}

/// Metres per source unit for a detected convention (module documentation, step 2).
fn height_normalisation_for(bvh: &Bvh, det: &DetectedConvention) -> Result<f64, BvhMotionError> {
    let rest = source_rest(bvh)?;
    let smpl = Skeleton::smpl24().rest_positions();
    let (src, target) = match det.convention.height {
        HeightRule::HeadToAnkleRest => {
            let h = rest[det.rot_idx(bvh, SMPL_HEAD)?][1] - rest[det.rot_idx(bvh, SMPL_LANKLE)?][1];
            (h, smpl[SMPL_HEAD][1] - smpl[SMPL_LANKLE][1])
        }
        HeightRule::LegLength => {
            let mut src = 0.0;
            let mut target = 0.0;
            for (hip, knee, ankle) in [
                (SMPL_LHIP, SMPL_LKNEE, SMPL_LANKLE),
                (SMPL_RHIP, SMPL_RKNEE, SMPL_RANKLE),
            ] {
                let (h, k, a) = (
                    det.pos_idx(bvh, hip)?,
                    det.pos_idx(bvh, knee)?,
                    det.pos_idx(bvh, ankle)?,
                );
                src += 0.5 * (dist(rest[h], rest[k]) + dist(rest[k], rest[a]));
                target += 0.5 * (dist(smpl[hip], smpl[knee]) + dist(smpl[knee], smpl[ankle]));
            }
            (src, target)
        }
    };
    if !(src.is_finite() && src > 0.0) {
        return Err(BvhMotionError::Units(src));
    }
    Ok(target / src)
}

/// Metres per source unit: the rule of the file's convention ([`detect_convention`]); for the
/// Poser names `SMPL rest head-to-ankle / source rest head-to-ankle` (`head` minus `lFoot`
/// height).
pub fn height_normalisation(bvh: &Bvh) -> Result<f64, BvhMotionError> {
    height_normalisation_for(bvh, &detect_convention(bvh)?)
}

/// Whether frame 0 of `bvh` is a reference T-pose to drop (module documentation, "The cgspeed
/// reference frame").
pub fn has_reference_tpose(bvh: &Bvh, det: &DetectedConvention) -> Result<bool, BvhMotionError> {
    if !det.convention.reference_tpose || bvh.frames < 2 {
        return Ok(false);
    }
    let nc = bvh.num_channels();
    let mut two = bvh.clone();
    two.frames = 2;
    two.data = bvh
        .data
        .get(..2 * nc)
        .map(<[f64]>::to_vec)
        .ok_or(BvhMotionError::Shape {
            what: "BVH motion data",
            got: bvh.data.len(),
            per_frame: nc,
            frames: bvh.frames,
        })?;
    let (rots, poss) = bvh_world_transforms(&two, 1.0)?;
    let nj = bvh.joints.len();
    let root = det.rot_idx(bvh, 0)?;
    if rotation_angle_deg(&rots[root]) > TPOSE_ROOT_MAX_DEG {
        return Ok(false);
    }
    let left = sub(
        poss[det.rot_idx(bvh, SMPL_LHIP)?],
        poss[det.rot_idx(bvh, SMPL_RHIP)?],
    );
    for (shoulder, elbow, outwards) in [
        (SMPL_LSHOULDER, SMPL_LELBOW, left),
        (SMPL_RSHOULDER, SMPL_RELBOW, scale(left, -1.0)),
    ] {
        let arm = sub(
            poss[det.rot_idx(bvh, elbow)?],
            poss[det.rot_idx(bvh, shoulder)?],
        );
        if angle_deg(arm, outwards) > TPOSE_ARM_MAX_DEG {
            return Ok(false);
        }
    }
    for (hip, knee) in [(SMPL_LHIP, SMPL_LKNEE), (SMPL_RHIP, SMPL_RKNEE)] {
        let thigh = sub(poss[det.rot_idx(bvh, knee)?], poss[det.rot_idx(bvh, hip)?]);
        if angle_deg(thigh, scale(UP, -1.0)) > TPOSE_LEG_MAX_DEG {
            return Ok(false);
        }
    }
    let jump = (0..nj)
        .map(|j| rotation_angle_deg(&rots[j].transpose().mul(&rots[nj + j])))
        .fold(0.0, f64::max);
    Ok(jump > TPOSE_JUMP_MIN_DEG)
}

/// Orthonormal frame (columns) with `primary` first and `secondary`'s perpendicular part second.
fn frame(primary: [f64; 3], secondary: [f64; 3], what: &str) -> Result<Mat3, BvhMotionError> {
    let n1 = norm(primary);
    let s_perp = sub(
        secondary,
        scale(primary, dot(secondary, primary) / (n1 * n1)),
    );
    let n2 = norm(s_perp);
    // Degenerate below 1e-6 relative: parallel or zero-length axes cannot define a frame.
    if !(n1 > 1e-9 && n2 > 1e-6 * n1.max(norm(secondary))) {
        return Err(BvhMotionError::RestPose(format!(
            "{what}: the two axes are parallel or of zero length"
        )));
    }
    let a = scale(primary, 1.0 / n1);
    let b = scale(s_perp, 1.0 / n2);
    let c = cross(a, b);
    Ok(Mat3([
        [a[0], b[0], c[0]],
        [a[1], b[1], c[1]],
        [a[2], b[2], c[2]],
    ]))
}

/// The rotation taking SMPL's `(primary, secondary)` axes onto the source's.
fn two_axis(
    smpl: ([f64; 3], [f64; 3]),
    src: ([f64; 3], [f64; 3]),
    what: &str,
) -> Result<Mat3, BvhMotionError> {
    let fs = frame(smpl.0, smpl.1, what)?;
    let fd = frame(src.0, src.1, what)?;
    Ok(fd.mul(&fs.transpose()))
}

/// Rotation sources and rest alignments `A_j` (module documentation, step 3).
fn alignments(
    bvh: &Bvh,
    det: &DetectedConvention,
) -> Result<([Option<usize>; 24], [Mat3; 24]), BvhMotionError> {
    let map = &det.convention.map;
    let skel = Skeleton::smpl24();
    let smpl_rest = skel.rest_positions();
    let src_rest = source_rest(bvh)?;
    let mut rot_src: [Option<usize>; 24] = [None; 24];
    let mut align_m = [Mat3::IDENTITY; 24];
    // Source rest bone of SMPL joint `j` (from its rotation source `s`), if mapped.
    let bone = |j: usize, s: usize| -> Result<Option<[f64; 3]>, BvhMotionError> {
        let (Some(end), Some(_)) = (map[j].bone_to, SMPL_MAIN_CHILD[j]) else {
            return Ok(None);
        };
        Ok(Some(match end {
            Joint(n) => sub(src_rest[det.idx(bvh, n)?], src_rest[s]),
            EndSite => bvh.joints[s].end_site.ok_or_else(|| {
                BvhMotionError::MissingJoint(format!("{} End Site", bvh.joints[s].name))
            })?,
        }))
    };
    let smpl_bone = |j: usize| SMPL_MAIN_CHILD[j].map(|c| sub(smpl_rest[c], smpl_rest[j]));
    for (j, m) in map.iter().enumerate() {
        if let Some(name) = m.rotation_from {
            rot_src[j] = Some(det.idx(bvh, name)?);
        }
    }
    match det.convention.alignment {
        RestAlignment::BoneOnly => {
            for j in 0..24 {
                let Some(s) = rot_src[j] else { continue };
                if let (Some(d_src), Some(d_smpl)) = (bone(j, s)?, smpl_bone(j)) {
                    align_m[j] = Mat3::between(d_smpl, d_src);
                }
            }
        }
        RestAlignment::Transported => {
            let parents = skel.parents();
            let hip_centre =
                |p: &[[f64; 3]], l: usize, r: usize| [0, 1, 2].map(|a| 0.5 * (p[l][a] + p[r][a]));
            let (sl, sr) = (det.rot_idx(bvh, SMPL_LHIP)?, det.rot_idx(bvh, SMPL_RHIP)?);
            let smpl_c = hip_centre(&smpl_rest, SMPL_LHIP, SMPL_RHIP);
            let src_c = hip_centre(&src_rest, sl, sr);
            align_m[0] = two_axis(
                (
                    sub(smpl_rest[SMPL_LHIP], smpl_rest[SMPL_RHIP]),
                    sub(smpl_rest[SMPL_BELLY], smpl_c),
                ),
                (
                    sub(src_rest[sl], src_rest[sr]),
                    sub(src_rest[det.rot_idx(bvh, SMPL_BELLY)?], src_c),
                ),
                "pelvis (hip axis, hip centre to spine)",
            )?;
            for j in 1..24 {
                let q_parent = parents[j].map_or(Mat3::IDENTITY, |p| align_m[p]);
                let d = match rot_src[j] {
                    Some(s) => bone(j, s)?.zip(smpl_bone(j)),
                    None => None,
                };
                align_m[j] = match d {
                    Some((d_src, d_smpl)) => {
                        if !(norm(d_src).is_finite() && norm(d_src) > 0.0) {
                            return Err(BvhMotionError::RestPose(format!(
                                "the bone of {} (SMPL {}) has zero length",
                                bvh.joints[rot_src[j].unwrap_or(0)].name,
                                SMPL24_NAMES[j]
                            )));
                        }
                        if j == SMPL_CHEST {
                            let (ls, rs) = (
                                det.rot_idx(bvh, SMPL_LSHOULDER)?,
                                det.rot_idx(bvh, SMPL_RSHOULDER)?,
                            );
                            two_axis(
                                (
                                    d_smpl,
                                    sub(smpl_rest[SMPL_LSHOULDER], smpl_rest[SMPL_RSHOULDER]),
                                ),
                                (d_src, sub(src_rest[ls], src_rest[rs])),
                                "chest (spine to neck, shoulder axis)",
                            )?
                        } else {
                            Mat3::between(q_parent.mul_vec(d_smpl), d_src).mul(&q_parent)
                        }
                    }
                    None => q_parent,
                };
            }
        }
    }
    Ok((rot_src, align_m))
}

/// Retargets a BVH to SMPL 24 at about `target_fps`, with the convention its joint names
/// match ([`detect_convention`]; see the module documentation). A cgspeed reference T-pose
/// frame 0 is dropped ([`has_reference_tpose`]; `first_frame` = 1).
pub fn retarget_to_smpl(bvh: &Bvh, target_fps: f64) -> Result<RetargetOutput, BvhMotionError> {
    let det = detect_convention(bvh)?;
    retarget_with(bvh, &det, target_fps)
}

/// Retargets a Poser/Daz-named BVH (CMU salsa) to SMPL 24 at about `target_fps` (see the module
/// documentation), without detection: every Poser joint must be present.
pub fn retarget_poser_to_smpl(
    bvh: &Bvh,
    target_fps: f64,
) -> Result<RetargetOutput, BvhMotionError> {
    retarget_with(bvh, &DetectedConvention::exact(&POSER), target_fps)
}

/// Retargets with a given convention (module documentation).
pub fn retarget_with(
    bvh: &Bvh,
    det: &DetectedConvention,
    target_fps: f64,
) -> Result<RetargetOutput, BvhMotionError> {
    if !(target_fps.is_finite() && target_fps > 0.0) {
        return Err(BvhMotionError::Fps(target_fps));
    }
    let src_fps = bvh.nominal_fps();
    let stride = ((src_fps / target_fps).round() as usize).max(1);
    let first = usize::from(has_reference_tpose(bvh, det)?);
    let mpu = height_normalisation_for(bvh, det)?;
    let (rots, poss) = bvh_world_transforms(bvh, mpu)?;
    let mut out = retarget_frames(bvh, det, &rots, &poss, (first..bvh.frames).step_by(stride))?;
    out.fps = src_fps / stride as f64;
    out.stride = stride;
    out.first_frame = first;
    out.metres_per_unit = mpu;
    Ok(out)
}

/// SMPL poses and translations of the given source frames from their world transforms
/// (`rots`, `poss`: frames × joints, already scaled). Rate fields are left for the caller.
fn retarget_frames(
    bvh: &Bvh,
    det: &DetectedConvention,
    rots: &[Mat3],
    poss: &[[f64; 3]],
    frames: impl ExactSizeIterator<Item = usize>,
) -> Result<RetargetOutput, BvhMotionError> {
    let skel = Skeleton::smpl24();
    let smpl_rest = skel.rest_positions();
    let (rot_src, align_m) = alignments(bvh, det)?;
    let (lt, rt) = (det.rot_idx(bvh, SMPL_LHIP)?, det.rot_idx(bvh, SMPL_RHIP)?);
    let c_smpl = [0, 1, 2]
        .map(|a| 0.5 * (smpl_rest[SMPL_LHIP][a] + smpl_rest[SMPL_RHIP][a]) - smpl_rest[0][a]);
    let nj = bvh.joints.len();
    let n = frames.len();
    let mut poses = Vec::with_capacity(n * 72);
    let mut trans = Vec::with_capacity(n * 3);
    let parents = skel.parents();
    let mut world = [Mat3::IDENTITY; 24];
    for f in frames {
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
        frames: n,
        poses,
        trans,
        fps: bvh.nominal_fps(),
        stride: 1,
        first_frame: 0,
        metres_per_unit: 1.0,
        source: det.clone(),
    })
}

/// Compares SMPL FK of `out` with the height-normalised source joints it was retargeted from
/// (the `position_of` joints of the convention's map), and lists bone lengths.
pub fn retarget_report(bvh: &Bvh, out: &RetargetOutput) -> Result<RetargetReport, BvhMotionError> {
    let det = &out.source;
    let map = &det.convention.map;
    let mpu = out.metres_per_unit;
    let (rots, poss) = bvh_world_transforms(bvh, mpu)?;
    let nj = bvh.joints.len();
    let src_frame = |k: usize| out.first_frame + k * out.stride;
    if out.frames > 0 && src_frame(out.frames - 1) >= bvh.frames {
        return Err(BvhMotionError::Shape {
            what: "retargeted frames",
            got: out.frames,
            per_frame: out.stride,
            frames: bvh.frames,
        });
    }
    let fk = smpl_fk_f64(&out.poses, &out.trans)?;
    // (SMPL joint, SMPL child, source start, source end: Some(joint) or None = end site).
    // Only bones rigid in their source joint count: the end is a child or the end site. A bone
    // through another rotating joint (cgspeed `Spine1` → `Neck1` passes the lower neck) is
    // aligned at rest only and follows that joint's rotation in motion.
    let mut aligned: Vec<(usize, usize, usize, Option<usize>)> = Vec::new();
    for (j, m) in map.iter().enumerate() {
        if let (Some(rf), Some(end), Some(c)) = (m.rotation_from, m.bone_to, SMPL_MAIN_CHILD[j]) {
            let s = det.idx(bvh, rf)?;
            let e = match end {
                Joint(n) => Some(det.idx(bvh, n)?),
                EndSite => None,
            };
            if e.is_none_or(|e| bvh.joints[e].parent == Some(s)) {
                aligned.push((j, c, s, e));
            }
        }
    }
    let mut angle_sum = 0.0;
    for k in 0..out.frames {
        let f = src_frame(k);
        for &(j, c, s, e) in &aligned {
            let a = [0, 1, 2].map(|i| fk[(k * 24 + c) * 3 + i] - fk[(k * 24 + j) * 3 + i]);
            let b = match e {
                Some(e) => sub(poss[f * nj + e], poss[f * nj + s]),
                None => rots[f * nj + s].mul_vec(bvh.joints[s].end_site.unwrap_or_default()),
            };
            angle_sum += angle_deg(a, b);
        }
    }
    let mean_bone_angle_deg = angle_sum / (out.frames * aligned.len()).max(1) as f64;
    let pairs: Vec<(usize, usize)> = map
        .iter()
        .enumerate()
        .filter_map(|(j, m)| m.position_of.map(|n| (j, n)))
        .map(|(j, n)| det.idx(bvh, n).map(|s| (j, s)))
        .collect::<Result<_, _>>()?;
    let mut per = vec![0.0; pairs.len()];
    let mut max: f64 = 0.0;
    for k in 0..out.frames {
        let f = src_frame(k);
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

    let src_rest: Vec<[f64; 3]> = source_rest(bvh)?
        .into_iter()
        .map(|p| p.map(|v| v * mpu))
        .collect();
    let smpl_rest = Skeleton::smpl24().rest_positions();
    let rest_mean = match det.convention.alignment {
        RestAlignment::BoneOnly => {
            // Both rest poses are T-poses facing +Z: align the hip centres, as the retarget does.
            let (lt, rt) = (det.rot_idx(bvh, SMPL_LHIP)?, det.rot_idx(bvh, SMPL_RHIP)?);
            let shift = [0, 1, 2].map(|a| {
                0.5 * (src_rest[lt][a] + src_rest[rt][a])
                    - 0.5 * (smpl_rest[SMPL_LHIP][a] + smpl_rest[SMPL_RHIP][a])
            });
            pairs
                .iter()
                .map(|&(j, s)| dist([0, 1, 2].map(|a| smpl_rest[j][a] + shift[a]), src_rest[s]))
                .sum::<f64>()
        }
        RestAlignment::Transported => {
            // Any rest pose: retarget the source's own rest pose and compare.
            let rest = rest_bvh(bvh);
            let (r_rots, r_poss) = bvh_world_transforms(&rest, mpu)?;
            let r = retarget_frames(bvh, det, &r_rots, &r_poss, 0..1)?;
            let r_fk = smpl_fk_f64(&r.poses, &r.trans)?;
            pairs
                .iter()
                .map(|&(j, s)| dist([0, 1, 2].map(|a| r_fk[j * 3 + a]), src_rest[s]))
                .sum::<f64>()
        }
    } * 100.0
        / pairs.len().max(1) as f64;

    let bones: [(&str, usize, usize); 8] = [
        ("l thigh", SMPL_LHIP, SMPL_LKNEE),
        ("r thigh", SMPL_RHIP, SMPL_RKNEE),
        ("l shin", SMPL_LKNEE, SMPL_LANKLE),
        ("r shin", SMPL_RKNEE, SMPL_RANKLE),
        ("l upperarm", SMPL_LSHOULDER, SMPL_LELBOW),
        ("r upperarm", SMPL_RSHOULDER, SMPL_RELBOW),
        ("l forearm", SMPL_LELBOW, 20),
        ("r forearm", SMPL_RELBOW, 21),
    ];
    let mut bone_lengths = Vec::with_capacity(bones.len());
    for (name, a, b) in bones {
        bone_lengths.push(BoneLength {
            name,
            source_m: dist(
                src_rest[det.pos_idx(bvh, a)?],
                src_rest[det.pos_idx(bvh, b)?],
            ),
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
