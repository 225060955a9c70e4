//! Rig presets: the bone names animators' tools expect, for the files they import
//! (`.bvh`, `.fbx`, `.glb`).
//!
//! Every preset is the SMPL 24 skeleton ([`Skeleton::smpl24`]) under another naming: the same
//! hierarchy, the same rest offsets (SMPL's T-pose, identity rest rotations) and therefore the
//! same local rotations and the same joint world positions in every frame. A preset only
//! renames, so no rotation needs converting; fitting the dance onto a character with its own
//! proportions and rest pose is retargeting (`--character`), not a preset.
//!
//! | SMPL (`smpl`) | Mixamo (`mixamo`) | UE5 Mannequin (`ue5`) | VRM 1.0 humanoid (`vrm`) |
//! |---|---|---|---|
//! | root | mixamorig:Hips | pelvis | hips |
//! | lhip / lknee / lankle / ltoes | mixamorig:LeftUpLeg / LeftLeg / LeftFoot / LeftToeBase | thigh_l / calf_l / foot_l / ball_l | leftUpperLeg / leftLowerLeg / leftFoot / leftToes |
//! | belly / spine / chest | mixamorig:Spine / Spine1 / Spine2 | spine_01 / spine_03 / spine_05 | spine / chest / upperChest |
//! | neck / head | mixamorig:Neck / Head | neck_01 / head | neck / head |
//! | linshoulder / lshoulder / lelbow / lwrist | mixamorig:LeftShoulder / LeftArm / LeftForeArm / LeftHand | clavicle_l / upperarm_l / lowerarm_l / hand_l | leftShoulder / leftUpperArm / leftLowerArm / leftHand |
//! | lhand | mixamorig:LeftHandMiddle1 | middle_metacarpal_l | leftMiddleProximal |
//!
//! and mirrored for the right side ("left" is the dancer's own left in every convention).
//! SMPL's `lhand` is the end of the hand, which no preset has as such; each takes the bone
//! that sits there, the middle finger's base. The UE5 Mannequin's five spine bones and two
//! neck bones get SMPL's three and one (spine_01/03/05, neck_01); its `root` bone at the feet
//! is not added: the pelvis is the root and carries the motion's translation, as in Mixamo
//! files. Sources: Mixamo's rig as downloaded from mixamo.com (`mixamorig:` prefix), Epic's
//! UE5 Manny/Quinn skeleton, the VRM 1.0 specification's humanoid bone list
//! (`VRMC_vrm/humanoid.md`).

use dancegen_motion::skeleton::{SMPL24_NAMES, SMPL24_OFFSETS, SMPL24_PARENTS, Skeleton};

/// A naming of the SMPL 24 skeleton (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Rig {
    /// dancegen's own names (EDGE's spelling of SMPL's joints).
    #[default]
    Smpl,
    /// Adobe Mixamo (`mixamorig:Hips`, …): Blender add-ons, Unity and Unreal retargeters
    /// recognise it.
    Mixamo,
    /// Unreal Engine 5 Mannequin (`pelvis`, `thigh_l`, …).
    Ue5,
    /// VRM 1.0 humanoid bone names (`hips`, `leftUpperLeg`, …), as UniVRM and three-vrm map.
    Vrm,
}

/// Text in front of every Mixamo bone name.
pub const MIXAMO_PREFIX: &str = "mixamorig:";

/// Mixamo names in SMPL 24 order, without [`MIXAMO_PREFIX`].
const MIXAMO_NAMES: [&str; 24] = [
    "Hips",
    "LeftUpLeg",
    "RightUpLeg",
    "Spine",
    "LeftLeg",
    "RightLeg",
    "Spine1",
    "LeftFoot",
    "RightFoot",
    "Spine2",
    "LeftToeBase",
    "RightToeBase",
    "Neck",
    "LeftShoulder",
    "RightShoulder",
    "Head",
    "LeftArm",
    "RightArm",
    "LeftForeArm",
    "RightForeArm",
    "LeftHand",
    "RightHand",
    "LeftHandMiddle1",
    "RightHandMiddle1",
];

/// UE5 Mannequin names in SMPL 24 order.
const UE5_NAMES: [&str; 24] = [
    "pelvis",
    "thigh_l",
    "thigh_r",
    "spine_01",
    "calf_l",
    "calf_r",
    "spine_03",
    "foot_l",
    "foot_r",
    "spine_05",
    "ball_l",
    "ball_r",
    "neck_01",
    "clavicle_l",
    "clavicle_r",
    "head",
    "upperarm_l",
    "upperarm_r",
    "lowerarm_l",
    "lowerarm_r",
    "hand_l",
    "hand_r",
    "middle_metacarpal_l",
    "middle_metacarpal_r",
];

/// VRM 1.0 humanoid bone names in SMPL 24 order.
const VRM_NAMES: [&str; 24] = [
    "hips",
    "leftUpperLeg",
    "rightUpperLeg",
    "spine",
    "leftLowerLeg",
    "rightLowerLeg",
    "chest",
    "leftFoot",
    "rightFoot",
    "upperChest",
    "leftToes",
    "rightToes",
    "neck",
    "leftShoulder",
    "rightShoulder",
    "head",
    "leftUpperArm",
    "rightUpperArm",
    "leftLowerArm",
    "rightLowerArm",
    "leftHand",
    "rightHand",
    "leftMiddleProximal",
    "rightMiddleProximal",
];

/// An unknown `--rig` name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown rig '{0}' (use smpl, mixamo, ue5 or vrm)")]
pub struct UnknownRig(pub String);

impl Rig {
    pub const ALL: [Rig; 4] = [Rig::Smpl, Rig::Mixamo, Rig::Ue5, Rig::Vrm];

    /// The preset's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Rig::Smpl => "smpl",
            Rig::Mixamo => "mixamo",
            Rig::Ue5 => "ue5",
            Rig::Vrm => "vrm",
        }
    }

    /// The preset called `name` (case-insensitive).
    pub fn from_name(name: &str) -> Result<Rig, UnknownRig> {
        Rig::ALL
            .into_iter()
            .find(|r| r.name().eq_ignore_ascii_case(name.trim()))
            .ok_or_else(|| UnknownRig(name.to_string()))
    }

    /// Bone names in SMPL 24 order.
    pub fn joint_names(self) -> Vec<String> {
        match self {
            Rig::Smpl => SMPL24_NAMES.iter().map(|n| n.to_string()).collect(),
            Rig::Mixamo => MIXAMO_NAMES
                .iter()
                .map(|n| format!("{MIXAMO_PREFIX}{n}"))
                .collect(),
            Rig::Ue5 => UE5_NAMES.iter().map(|n| n.to_string()).collect(),
            Rig::Vrm => VRM_NAMES.iter().map(|n| n.to_string()).collect(),
        }
    }

    /// The SMPL 24 skeleton under this preset's names.
    pub fn skeleton(self) -> Skeleton {
        Skeleton::from_parent_indices(
            &self.joint_names(),
            &SMPL24_PARENTS,
            SMPL24_OFFSETS.to_vec(),
        )
        .expect("every preset renames the valid SMPL 24 table with 24 distinct names")
    }
}

impl std::str::FromStr for Rig {
    type Err = UnknownRig;
    fn from_str(s: &str) -> Result<Self, UnknownRig> {
        Rig::from_name(s)
    }
}

impl std::fmt::Display for Rig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// SMPL joints a dance file may lack when read back: the hands (22 and 23), where a holistic
/// skeleton has fingers instead.
const OPTIONAL_SMPL_JOINTS: [usize; 2] = [22, 23];

/// For one skin's bone names (a `dancer{d}/` prefix already removed), each SMPL joint's
/// index into `names`, under the first rig whose every body joint is there (the hands may be
/// missing); the words for a skin that is no rig's, naming it `skin {skin}`. How the `.glb`
/// and `.fbx` readers ([`crate::glb_in`], [`crate::fbx_in`]) find the dancers dancegen wrote.
pub fn smpl_joints_by_name(names: &[String], skin: usize) -> Result<Vec<Option<usize>>, String> {
    Rig::ALL
        .iter()
        .map(|rig| {
            rig.joint_names()
                .iter()
                .map(|want| names.iter().position(|n| n == want))
                .collect::<Vec<_>>()
        })
        .find(|m: &Vec<Option<usize>>| {
            m.iter()
                .enumerate()
                .all(|(k, i)| i.is_some() || OPTIONAL_SMPL_JOINTS.contains(&k))
        })
        .ok_or_else(|| {
            format!(
                "skin {skin}'s bones are not an SMPL 24 skeleton under any rig's names ({}): \
                 not a dance dancegen wrote",
                Rig::ALL.map(Rig::name).join(", ")
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn presets_rename_the_smpl_skeleton_only() {
        let smpl = Skeleton::smpl24();
        assert_eq!(Rig::Smpl.skeleton(), smpl);
        for rig in Rig::ALL {
            let s = rig.skeleton();
            assert_eq!(s.parents(), smpl.parents(), "{rig}");
            assert_eq!(s.offsets(), smpl.offsets(), "{rig}");
            let names: HashSet<&String> = s.names().iter().collect();
            assert_eq!(names.len(), 24, "{rig}: names must be distinct");
        }
        assert_eq!(Rig::Mixamo.joint_names()[0], "mixamorig:Hips");
        assert_eq!(Rig::Ue5.joint_names()[20], "hand_l");
        assert_eq!(Rig::Vrm.joint_names()[16], "leftUpperArm");
    }

    #[test]
    fn left_stays_left() {
        // Joint 1 (lhip) is at +x, the dancer's left (conventions::REST_LEFT).
        for rig in [Rig::Mixamo, Rig::Ue5, Rig::Vrm] {
            let names = rig.joint_names();
            for (j, name) in names.iter().enumerate() {
                let lower = name.to_ascii_lowercase();
                let smpl = SMPL24_NAMES[j];
                let left = lower.contains("left") || lower.ends_with("_l");
                let right = lower.contains("right") || lower.ends_with("_r");
                assert_eq!(left, smpl.starts_with('l'), "{rig}: {name} for {smpl}");
                assert_eq!(
                    right,
                    smpl.starts_with('r') && smpl != "root",
                    "{rig}: {name}"
                );
            }
        }
    }

    #[test]
    fn names_parse_and_unknown_rigs_are_listed() {
        assert_eq!(Rig::from_name("Mixamo"), Ok(Rig::Mixamo));
        assert_eq!("ue5".parse::<Rig>(), Ok(Rig::Ue5));
        let e = Rig::from_name("maya").unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown rig 'maya' (use smpl, mixamo, ue5 or vrm)"
        );
    }
}
