//! Joint sets users name: `--keep-joints` and `--keyframe-joints` (`upper`, `lower`, `arms`,
//! `legs`, or SMPL joint names).

use dancegen_motion::skeleton::SMPL24_PARENTS;

/// SMPL 24 joints of the named sets.
const LEGS: [usize; 8] = [1, 2, 4, 5, 7, 8, 10, 11];
const ARMS: [usize; 10] = [13, 14, 16, 17, 18, 19, 20, 21, 22, 23];
const SPINE_AND_HEAD: [usize; 4] = [3, 6, 9, 12];
const HEAD: usize = 15;

/// The legs' joints as a mask (hips, knees, ankles, feet).
pub fn legs_mask() -> u32 {
    LEGS.iter().fold(0, |m, &j| m | 1 << j)
}

/// Long names of the SMPL 24 joints that differ from SMPL-X's (whose first 22 are the body's,
/// `dancegen_motion::skeleton::SMPLX55_NAMES`): SMPL's last two are the hands.
const SMPL_HANDS: [&str; 2] = ["left_hand", "right_hand"];

/// Joint `j`'s long name (`left_knee`), as SMPL-X and most tools write it.
fn long_name(j: usize) -> &'static str {
    match j {
        22 | 23 => SMPL_HANDS[j - 22],
        _ => dancegen_motion::skeleton::SMPLX55_NAMES[j],
    }
}

/// The joints (bit mask) and whether the root position goes with them for a joint set given
/// to `flag` (`--keep-joints`, `--keyframe-joints`; named in errors): `upper`, `lower` (legs,
/// pelvis rotation and root position), `arms`, `legs`, `all`, or SMPL joint names separated
/// by commas (`left_knee` or `lknee`; `pelvis`/`root` is the pelvis rotation).
pub fn parse_joint_set(flag: &str, spec: &str) -> Result<(u32, bool), String> {
    let bits = |js: &[usize]| js.iter().fold(0u32, |m, &j| m | 1 << j);
    match spec.trim() {
        "lower" => return Ok((bits(&LEGS) | 1, true)),
        "legs" => return Ok((bits(&LEGS), false)),
        "arms" => return Ok((bits(&ARMS), false)),
        "upper" => return Ok((bits(&ARMS) | bits(&SPINE_AND_HEAD) | 1 << HEAD, false)),
        "all" => return Ok((super::ALL_JOINTS, true)),
        _ => {}
    }
    let short = dancegen_motion::skeleton::SMPL24_NAMES;
    let mut mask = 0u32;
    for name in spec.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let j = (0..24)
            .position(|j| long_name(j).eq_ignore_ascii_case(name))
            .or_else(|| short.iter().position(|n| n.eq_ignore_ascii_case(name)))
            .ok_or_else(|| {
                format!(
                    "{flag}: {name:?} is not a joint of the SMPL 24 skeleton (use upper, \
                     lower, arms, legs, all, or names such as {})",
                    (0..24).map(long_name).collect::<Vec<_>>().join(", ")
                )
            })?;
        mask |= 1 << j;
    }
    if mask == 0 {
        return Err(format!(
            "{flag}: name a set (upper, lower, arms, legs, all) or joints"
        ));
    }
    Ok((mask, false))
}

/// `mask` with every joint's ancestors up to the pelvis: the joints whose rotations place
/// `mask`'s joints in the world (a wrist is where the pelvis, spine, collar, shoulder and elbow
/// rotations put it).
pub fn with_ancestors(mask: u32) -> u32 {
    let mut out = mask;
    for (j, &parent) in SMPL24_PARENTS.iter().enumerate() {
        if mask & (1 << j) == 0 {
            continue;
        }
        let mut p = parent;
        while p >= 0 {
            out |= 1 << p;
            p = SMPL24_PARENTS[p as usize];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_sets_and_names_parse_and_unknown_names_are_refused() {
        let (lower, root) = parse_joint_set("--keep-joints", "lower").unwrap();
        assert!(root && lower & 1 != 0 && lower & (1 << 4) != 0 && lower & (1 << 20) == 0);
        let (legs, root) = parse_joint_set("--keep-joints", "legs").unwrap();
        assert!(!root && legs & 1 == 0 && legs.count_ones() == 8);
        let (upper, _) = parse_joint_set("--keep-joints", "upper").unwrap();
        assert_eq!(upper & legs, 0);
        assert_eq!(
            (upper | legs | 1).count_ones(),
            24,
            "upper + legs + pelvis is everything"
        );
        assert_eq!(
            parse_joint_set("--keep-joints", "left_knee, rknee").unwrap(),
            ((1 << 4) | (1 << 5), false)
        );
        let e = parse_joint_set("--keyframe-joints", "left_knee,tail").unwrap_err();
        assert!(
            e.contains("--keyframe-joints") && e.contains("\"tail\"") && e.contains("SMPL 24"),
            "{e}"
        );
        assert!(parse_joint_set("--keep-joints", " , ").is_err());
    }

    #[test]
    fn a_wrist_is_placed_by_its_chain_from_the_pelvis() {
        let (wrist, _) = parse_joint_set("--keyframe-joints", "right_wrist").unwrap();
        let chain = with_ancestors(wrist);
        // pelvis, spine1-3, right collar, shoulder, elbow, wrist
        let want = [0, 3, 6, 9, 14, 17, 19, 21];
        assert_eq!(chain, want.iter().fold(0, |m, &j| m | 1 << j));
        assert_eq!(with_ancestors(1), 1);
    }
}
