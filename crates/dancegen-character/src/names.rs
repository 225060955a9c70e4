//! What a bone name says: which part of the body and which side.
//!
//! Rigs from different tools spell the same bone very differently (`mixamorig:LeftUpLeg`,
//! `thigh_l`, `J_Bip_L_UpperLeg`, `UpperLeg.L`, `upper_arm.L`, `Bip01 L Thigh`). A name is split
//! into lower-case words (at separators, lower→upper case changes and letter↔digit changes),
//! exporter prefixes and namespaces are dropped, the side is read from a `left`/`right`/`l`/`r`
//! word, and the remaining words, joined, are looked up in a synonym table. Names only propose
//! candidates; the hierarchy decides (see `bone_map.rs`), because one word means different bones
//! in different conventions — Mixamo's `LeftArm` is the upper arm, its `LeftLeg` the shin, and
//! SMPL's `left_shoulder` the upper arm while everyone else's shoulder is the collar bone. SMPL
//! names therefore have their own table, used when a file is recognisably SMPL-named.

/// Side of the body a bone name declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    Left,
    Right,
    Center,
}

/// Part of the body a bone name declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Part {
    Hips,
    Spine,
    Neck,
    Head,
    UpperLeg,
    LowerLeg,
    Foot,
    Toes,
    Collar,
    UpperArm,
    LowerArm,
    Hand,
    /// Fingers, palm and metacarpal bones (and SMPL's hand end joint): never driven by the
    /// dance, but they tell where a hand points.
    Finger,
}

/// Which synonym table to read names with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameTable {
    /// Mixamo, Unreal, VRM bone names, Blender/Rigify, 3ds Max Biped, …
    Generic,
    /// SMPL's own joint names (`left_collar`, `left_shoulder` = upper arm, `left_foot` = toes),
    /// including dancegen's short spelling (`linshoulder`, `lshoulder`, …).
    Smpl,
}

/// Words that are exporter prefixes or rig furniture, not anatomy.
const NOISE: &[&str] = &[
    "mixamorig",
    "mixamo",
    "j",
    "bip",
    "biped",
    "valve",
    "def",
    "org",
    "cc",
    "base",
    "armature",
    "rig",
    "jnt",
    "joint",
    "bn",
    "avg",
    "m",
    "f",
    "c",
];

/// Words that make a node not a body bone (end markers, twist and helper bones, IK controls,
/// VRM's adjustment and secondary bones, face parts).
const EXCLUDE: &[&str] = &[
    "end",
    "nub",
    "tip",
    "top",
    "twist",
    "roll",
    "pole",
    "ik",
    "target",
    "ctrl",
    "control",
    "helper",
    "null",
    "mch",
    "jiggle",
    "sec",
    "adj",
    "corrective",
    "socket",
    "weapon",
    "prop",
    "attach",
    "goal",
    "dummy",
    "eye",
    "jaw",
    "tongue",
    "hair",
    "breast",
    "bust",
    "skirt",
    "tail",
    "ear",
    "cape",
];

const FINGER_WORDS: &[&str] = &[
    "thumb",
    "index",
    "middle",
    "ring",
    "pinky",
    "little",
    "finger",
    "fingers",
    "palm",
    "metacarpal",
    "carpal",
];

/// Splits a name into lower-case words, dropping digits, namespaces (`ns:` or `ns|`) and the
/// [`NOISE`] words.
pub fn words(name: &str) -> Vec<String> {
    let local = name.rsplit([':', '|']).next().unwrap_or(name);
    let chars: Vec<char> = local.chars().collect();
    let mut raw: Vec<String> = Vec::new();
    let mut cur = String::new();
    for (i, &c) in chars.iter().enumerate() {
        if !c.is_alphanumeric() {
            if !cur.is_empty() {
                raw.push(std::mem::take(&mut cur));
            }
            continue;
        }
        if let Some(&p) = i.checked_sub(1).and_then(|j| chars.get(j))
            && !cur.is_empty()
        {
            let next_lower = chars.get(i + 1).is_some_and(|n| n.is_lowercase());
            let boundary = (p.is_lowercase() && c.is_uppercase())
                || (p.is_alphabetic() != c.is_alphabetic())
                || (p.is_uppercase() && c.is_uppercase() && next_lower);
            if boundary {
                raw.push(std::mem::take(&mut cur));
            }
        }
        cur.extend(c.to_lowercase());
    }
    if !cur.is_empty() {
        raw.push(cur);
    }
    raw.into_iter()
        .filter(|w| !w.chars().all(|c| c.is_ascii_digit()) && !NOISE.contains(&w.as_str()))
        .collect()
}

/// Removes the side word and returns the side.
fn take_side(words: &mut Vec<String>) -> Side {
    let mut side = Side::Center;
    words.retain(|w| match w.as_str() {
        "left" | "l" | "lft" => {
            side = Side::Left;
            false
        }
        "right" | "r" | "rt" | "rgt" => {
            side = Side::Right;
            false
        }
        _ => true,
    });
    if side == Side::Center
        && let Some(first) = words.first_mut()
    {
        for (prefix, s) in [("left", Side::Left), ("right", Side::Right)] {
            if first.len() > prefix.len() && first.starts_with(prefix) {
                *first = first[prefix.len()..].to_string();
                side = s;
                break;
            }
        }
    }
    side
}

/// The part and side a bone name declares under `table`, or `None` for names that are not
/// (driven) body bones.
pub fn classify(name: &str, table: NameTable) -> Option<(Part, Side)> {
    // dancegen's short names (`lhip`, `linshoulder`) are read in SMPL's official spelling; the
    // official spelling is looked up once, never again (`neck` is both).
    let name = match table {
        NameTable::Smpl => dancegen_spelling(name).unwrap_or(name),
        NameTable::Generic => name,
    };
    let mut w = words(name);
    if w.iter().any(|x| EXCLUDE.contains(&x.as_str())) {
        return None;
    }
    let side = take_side(&mut w);
    if w.iter().any(|x| FINGER_WORDS.contains(&x.as_str())) {
        return Some((Part::Finger, side));
    }
    let core: String = w.concat();
    let part = match table {
        NameTable::Generic => generic_part(&core, side)?,
        NameTable::Smpl => smpl_part(&core, side)?,
    };
    Some((part, side))
}

fn generic_part(core: &str, side: Side) -> Option<Part> {
    let sided = side != Side::Center;
    let part = match core {
        "upleg" | "upperleg" | "thigh" | "uleg" | "upperthigh" | "femur" => Part::UpperLeg,
        "hip" if sided => Part::UpperLeg,
        "leg" | "lowerleg" | "calf" | "shin" | "knee" | "loleg" | "lleg" | "lowleg" | "shank" => {
            Part::LowerLeg
        }
        "foot" | "ankle" => Part::Foot,
        "toe" | "toes" | "toebase" | "ball" => Part::Toes,
        "shoulder" | "clavicle" | "collar" | "collarbone" | "clav" | "inshoulder" => Part::Collar,
        "arm" | "upperarm" | "uparm" | "humerus" => Part::UpperArm,
        "forearm" | "lowerarm" | "loarm" | "elbow" | "lowarm" => Part::LowerArm,
        "hand" | "wrist" => Part::Hand,
        "hips" | "hip" | "pelvis" if !sided => Part::Hips,
        "spine" | "abdomen" | "torso" | "belly" | "waist" | "chest" | "upperchest" | "back"
        | "lowerback" | "upperback" | "stomach"
            if !sided =>
        {
            Part::Spine
        }
        "neck" if !sided => Part::Neck,
        "head" if !sided => Part::Head,
        _ => return None,
    };
    Some(part)
}

fn smpl_part(core: &str, side: Side) -> Option<Part> {
    let sided = side != Side::Center;
    let part = match core {
        "hip" if sided => Part::UpperLeg,
        "knee" if sided => Part::LowerLeg,
        "ankle" if sided => Part::Foot,
        "foot" | "toes" if sided => Part::Toes,
        "collar" | "inshoulder" if sided => Part::Collar,
        "shoulder" if sided => Part::UpperArm,
        "elbow" if sided => Part::LowerArm,
        "wrist" if sided => Part::Hand,
        "hand" if sided => Part::Finger,
        "pelvis" | "root" | "hips" if !sided => Part::Hips,
        "spine" | "belly" | "chest" if !sided => Part::Spine,
        "neck" if !sided => Part::Neck,
        "head" if !sided => Part::Head,
        _ => return None,
    };
    Some(part)
}

/// dancegen's short SMPL names ([`dancegen_motion::skeleton::SMPL24_NAMES`]) in SMPL's official spelling.
fn dancegen_spelling(name: &str) -> Option<&'static str> {
    let local = name.rsplit([':', '|']).next().unwrap_or(name);
    let i = dancegen_motion::skeleton::SMPL24_NAMES
        .iter()
        .position(|n| n.eq_ignore_ascii_case(local))?;
    smpl_official_name(i)
}

/// SMPL joint `i`'s name as the model files spell it: the 22 body joints SMPL, SMPL-H and
/// SMPL-X share ([`dancegen_motion::skeleton::SMPLX55_NAMES`]), then SMPL's own hand joints.
pub fn smpl_official_name(i: usize) -> Option<&'static str> {
    /// SMPL's joints 22 and 23 (SMPL-H/X put fingers and the jaw there instead).
    const SMPL_HANDS: [&str; 2] = ["left_hand", "right_hand"];
    match i {
        0..22 => Some(dancegen_motion::skeleton::SMPLX55_NAMES[i]),
        22..24 => Some(SMPL_HANDS[i - 22]),
        _ => None,
    }
}

/// Whether a set of names reads as SMPL's: a sided collar, elbow and knee, which no other
/// common convention has together.
pub fn looks_like_smpl<'a>(names: impl IntoIterator<Item = &'a str>) -> bool {
    let mut seen = [false; 3];
    for n in names {
        let n = dancegen_spelling(n).unwrap_or(n);
        let mut w = words(n);
        if take_side(&mut w) == Side::Center {
            continue;
        }
        match w.concat().as_str() {
            "collar" | "inshoulder" => seen[0] = true,
            "elbow" => seen[1] = true,
            "knee" => seen[2] = true,
            _ => {}
        }
    }
    seen.iter().all(|&s| s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use Part::*;
    use Side::*;

    fn g(name: &str) -> Option<(Part, Side)> {
        classify(name, NameTable::Generic)
    }

    #[test]
    fn splits_words() {
        assert_eq!(words("mixamorig:LeftUpLeg"), ["left", "up", "leg"]);
        assert_eq!(words("J_Bip_L_UpperLeg"), ["l", "upper", "leg"]);
        assert_eq!(words("spine_01"), ["spine"]);
        assert_eq!(words("HeadTop_End"), ["head", "top", "end"]);
        assert_eq!(words("ValveBiped.Bip01_L_Thigh"), ["l", "thigh"]);
        assert_eq!(words("LeftFootIKTarget"), ["left", "foot", "ik", "target"]);
    }

    #[test]
    fn generic_conventions() {
        // Mixamo
        assert_eq!(g("mixamorig:Hips"), Some((Hips, Center)));
        assert_eq!(g("mixamorig:LeftUpLeg"), Some((UpperLeg, Left)));
        assert_eq!(g("mixamorig:RightLeg"), Some((LowerLeg, Right)));
        assert_eq!(g("mixamorig:LeftToeBase"), Some((Toes, Left)));
        assert_eq!(g("mixamorig:Spine2"), Some((Spine, Center)));
        assert_eq!(g("mixamorig:LeftShoulder"), Some((Collar, Left)));
        assert_eq!(g("mixamorig:LeftArm"), Some((UpperArm, Left)));
        assert_eq!(g("mixamorig:LeftForeArm"), Some((LowerArm, Left)));
        assert_eq!(g("mixamorig:LeftHandIndex1"), Some((Finger, Left)));
        assert_eq!(g("mixamorig:LeftToe_End"), None);
        // Unreal
        assert_eq!(g("pelvis"), Some((Hips, Center)));
        assert_eq!(g("thigh_l"), Some((UpperLeg, Left)));
        assert_eq!(g("calf_r"), Some((LowerLeg, Right)));
        assert_eq!(g("ball_l"), Some((Toes, Left)));
        assert_eq!(g("clavicle_l"), Some((Collar, Left)));
        assert_eq!(g("lowerarm_r"), Some((LowerArm, Right)));
        assert_eq!(g("upperarm_twist_01_l"), None);
        assert_eq!(g("neck_01"), Some((Neck, Center)));
        // VRM names
        assert_eq!(g("leftUpperLeg"), Some((UpperLeg, Left)));
        assert_eq!(g("J_Bip_R_LowerArm"), Some((LowerArm, Right)));
        assert_eq!(g("J_Bip_C_UpperChest"), Some((Spine, Center)));
        assert_eq!(g("J_Sec_Hair1_01"), None);
        // Blender
        assert_eq!(g("UpperArm.L"), Some((UpperArm, Left)));
        assert_eq!(g("upper_arm.R"), Some((UpperArm, Right)));
        assert_eq!(g("shin.L"), Some((LowerLeg, Left)));
        assert_eq!(g("LowerLeg.L_end"), None);
        assert_eq!(g("Palm2.L"), Some((Finger, Left)));
        assert_eq!(g("Bip01 L Thigh"), Some((UpperLeg, Left)));
        assert_eq!(g("PoleTarget.L"), None);
    }

    #[test]
    fn smpl_names() {
        let s = |n| classify(n, NameTable::Smpl);
        assert_eq!(s("left_shoulder"), Some((UpperArm, Left)));
        assert_eq!(s("left_collar"), Some((Collar, Left)));
        assert_eq!(s("right_foot"), Some((Toes, Right)));
        assert_eq!(s("lshoulder"), Some((UpperArm, Left)));
        assert_eq!(s("linshoulder"), Some((Collar, Left)));
        assert_eq!(s("rtoes"), Some((Toes, Right)));
        assert_eq!(s("root"), Some((Hips, Center)));
        assert_eq!(s("m_avg_L_Elbow"), Some((LowerArm, Left)));
        assert_eq!(s("neck"), Some((Neck, Center)));
        assert_eq!(s("head"), Some((Head, Center)));
        assert!(looks_like_smpl(dancegen_motion::skeleton::SMPL24_NAMES));
        assert!(looks_like_smpl((0..24).filter_map(smpl_official_name)));
        assert!(!looks_like_smpl([
            "mixamorig:LeftShoulder",
            "mixamorig:LeftLeg"
        ]));
    }
}
