//! Which character bone each SMPL joint drives.
//!
//! # Order of evidence
//! 1. A VRM humanoid table (`extensions.VRMC_vrm.humanoid.humanBones`, VRM 1.0, or
//!    `extensions.VRM.humanoid.humanBones`, VRM 0.x) is the author's own statement, so it is used
//!    as is.
//! 2. Otherwise bone names propose candidates (`names.rs`; SMPL's names have their own table,
//!    used when the skin has SMPL's sided collar, elbow and knee) among the skin joints that
//!    carry no mesh, and the hierarchy decides:
//!    - a limb is upper → lower → end with each a descendant of the one before, the shallowest
//!      consistent candidates winning (so `upper_arm.L` beats its twist segment
//!      `upper_arm.L.001`); a missing middle name is the node right below the upper bone on the
//!      way to the end, a missing upper name the lower bone's parent;
//!    - an end bone (foot, hand) that is not below its limb but sits, at rest, where the limb
//!      ends is an IK-style bone (RobotExpressive's feet hang from the armature root): it is
//!      mapped as **detached** and its translation is animated too, so it follows the shin;
//!    - a forearm without a hand bone whose children are palm or finger bones (RobotExpressive
//!      again) gets a **hand group**: its child joints turn together with SMPL's wrist;
//!    - the hips are the lowest common ancestor of both upper legs and the head (a bone named
//!      `Hips` that the legs do not hang from, as in RobotExpressive, becomes spine);
//!    - the chest is the lowest common ancestor of both upper arms; every bone between hips and
//!      chest is spine, between chest and head neck, between chest and an upper arm collar.
//!
//! # Spine distribution
//! SMPL has three spine joints (belly, spine, chest). With `n` character spine bones, bone `i`
//! (0-based, bottom up) follows SMPL spine joint `⌈3(i+1)/n⌉ − 1`: one bone follows the chest,
//! two follow spine and chest, three map one to one, five (UE5) follow belly, spine, spine,
//! chest, chest. The top one always follows the chest because the arms and the neck hang from
//! it. Every neck bone follows SMPL's neck, every collar bone SMPL's collar.
//!
//! # Aims
//! Each mapped bone records where it points at rest (another mapped bone, or the end of its own
//! bone) and which SMPL joint the matching SMPL bone points to; the retargeter turns the
//! character's rest pose onto SMPL's with them (`retarget.rs`).

use serde_json::Value;

use super::names::{self, NameTable, Part, Side};
use super::scene::NodeTree;
use dancegen_motion::vec3::{norm, scale, sub};

/// Where the bone map came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Convention {
    /// `extensions.VRMC_vrm.humanoid` (VRM 1.0).
    Vrm1,
    /// `extensions.VRM.humanoid` (VRM 0.x).
    Vrm0,
    /// SMPL joint names.
    SmplNames,
    /// Mixamo, Unreal, VRM-style, Blender or similar bone names.
    BoneNames,
}

/// A point on the character's skeleton.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Site {
    /// The origin of a node.
    Node(usize),
    /// Where a node's bone ends: the position most of its child nodes share (the palms of
    /// RobotExpressive's forearm), else its middle-finger child, else the mean of its
    /// non-thumb children.
    EndOf(usize),
}

/// Where a mapped bone points at rest, to be turned onto SMPL's rest pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aim {
    /// No direction of its own (head, toes, hand groups): it keeps its parent's alignment.
    None,
    /// The bone (this node → `target`) is turned onto SMPL's bone (`smpl` joint of this bone →
    /// SMPL joint `source`).
    Full { target: Site, source: usize },
    /// Like `Full` but only about the vertical axis (feet: both rest poses stand with flat
    /// feet, however differently the foot bones are drawn).
    Heading { target: Site, source: usize },
    /// The hips: the left-right hip axis first, then the trunk's up direction.
    Hips,
}

/// One character bone the dance drives.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedBone {
    /// Node index in the character file.
    pub node: usize,
    /// SMPL 24 joint whose world rotation it follows.
    pub smpl: usize,
    pub aim: Aim,
    /// For an IK-style bone not parented to its limb: the node whose motion it follows (its
    /// translation is animated too).
    pub detached_from: Option<usize>,
    /// Index (in [`BoneMap::bones`]) of the mapped bone it continues, whose alignment it
    /// starts from.
    pub chain_parent: Option<usize>,
}

/// The mapping from SMPL 24 joints to character bones.
#[derive(Debug, Clone, PartialEq)]
pub struct BoneMap {
    pub convention: Convention,
    /// Every driven bone, each after its chain parent; `bones[0]` is the hips.
    pub bones: Vec<MappedBone>,
    /// The character point of each SMPL joint, where there is one.
    pub sites: [Option<Site>; 24],
}

impl BoneMap {
    /// The hips node.
    pub fn hips(&self) -> usize {
        self.bones[0].node
    }

    /// The main node driven by SMPL joint `j` (the first, bottom up, when several are).
    pub fn node_for(&self, j: usize) -> Option<usize> {
        self.bones.iter().find(|b| b.smpl == j).map(|b| b.node)
    }

    /// All nodes driven by SMPL joint `j`.
    pub fn nodes_for(&self, j: usize) -> Vec<usize> {
        self.bones
            .iter()
            .filter(|b| b.smpl == j)
            .map(|b| b.node)
            .collect()
    }
}

/// SMPL 24 joint indices used here.
pub(crate) mod smpl {
    pub const ROOT: usize = 0;
    pub const HIP: [usize; 2] = [1, 2];
    pub const BELLY: usize = 3;
    pub const KNEE: [usize; 2] = [4, 5];
    pub const SPINE: usize = 6;
    pub const ANKLE: [usize; 2] = [7, 8];
    pub const CHEST: usize = 9;
    pub const TOES: [usize; 2] = [10, 11];
    pub const NECK: usize = 12;
    pub const COLLAR: [usize; 2] = [13, 14];
    pub const HEAD: usize = 15;
    pub const SHOULDER: [usize; 2] = [16, 17];
    pub const ELBOW: [usize; 2] = [18, 19];
    pub const WRIST: [usize; 2] = [20, 21];
    pub const HAND: [usize; 2] = [22, 23];
}

/// The end of a limb.
#[derive(Debug, Clone, PartialEq)]
enum End {
    Bone { node: usize, detached: bool },
    Group(Vec<usize>),
}

#[derive(Debug, Clone, PartialEq)]
struct Limb {
    upper: usize,
    lower: usize,
    end: End,
}

/// The skeleton's humanoid parts, before they become [`MappedBone`]s.
#[derive(Debug, Clone)]
struct Found {
    root: usize,
    spine: Vec<usize>,
    neck: Vec<usize>,
    head: usize,
    legs: [Limb; 2],
    toes: [Option<usize>; 2],
    arms: [Limb; 2],
    collars: [Vec<usize>; 2],
}

/// VRM's side prefixes, left then right (side index 0 is always the left).
const SIDE_WORD: [&str; 2] = ["left", "right"];

/// Maps the character's bones; `Err` lists the SMPL joints (with their meaning) not found.
pub(crate) fn match_bones(json: &Value, tree: &NodeTree) -> Result<BoneMap, Vec<String>> {
    let ext = json.get("extensions");
    let vrm1 = ext
        .and_then(|e| e.pointer("/VRMC_vrm/humanoid/humanBones"))
        .and_then(Value::as_object)
        .map(|o| {
            o.iter()
                .filter_map(|(k, v)| Some((k.clone(), v.get("node")?.as_u64()? as usize)))
                .collect::<Vec<_>>()
        });
    let vrm0 = ext
        .and_then(|e| e.pointer("/VRM/humanoid/humanBones"))
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(|b| {
                    Some((
                        b.get("bone")?.as_str()?.to_string(),
                        b.get("node")?.as_i64().filter(|&n| n >= 0)? as usize,
                    ))
                })
                .collect::<Vec<_>>()
        });
    let (convention, found) = if let Some(table) = vrm1.filter(|t| !t.is_empty()) {
        (Convention::Vrm1, from_vrm(tree, &table)?)
    } else if let Some(table) = vrm0.filter(|t| !t.is_empty()) {
        (Convention::Vrm0, from_vrm(tree, &table)?)
    } else {
        let joint_names = (0..tree.len())
            .filter(|&k| tree.is_joint[k])
            .map(|k| tree.names[k].as_str());
        if names::looks_like_smpl(joint_names) {
            (Convention::SmplNames, from_names(tree, NameTable::Smpl)?)
        } else {
            (Convention::BoneNames, from_names(tree, NameTable::Generic)?)
        }
    };
    Ok(build(convention, tree, &found))
}

/// Reads a VRM humanoid table (`(bone name, node)` pairs).
fn from_vrm(tree: &NodeTree, table: &[(String, usize)]) -> Result<Found, Vec<String>> {
    let get = |name: &str| {
        table
            .iter()
            .find(|(b, _)| b == name)
            .map(|&(_, n)| n)
            .filter(|&n| n < tree.len())
    };
    let mut missing = Vec::new();
    let mut need = |name: &str, what: String| {
        let n = get(name);
        if n.is_none() {
            missing.push(what);
        }
        n.unwrap_or(0)
    };
    let root = need("hips", "root (hips)".into());
    let head = need("head", "head (head)".into());
    let spine_bone = need("spine", "spine (spine)".into());
    let mut legs = Vec::new();
    let mut arms = Vec::new();
    for (s, cap) in SIDE_WORD.iter().enumerate() {
        legs.push((
            need(&format!("{cap}UpperLeg"), missing_name(smpl::HIP[s])),
            need(&format!("{cap}LowerLeg"), missing_name(smpl::KNEE[s])),
            need(&format!("{cap}Foot"), missing_name(smpl::ANKLE[s])),
        ));
        arms.push((
            need(&format!("{cap}UpperArm"), missing_name(smpl::SHOULDER[s])),
            need(&format!("{cap}LowerArm"), missing_name(smpl::ELBOW[s])),
            need(&format!("{cap}Hand"), missing_name(smpl::WRIST[s])),
        ));
    }
    if !missing.is_empty() {
        return Err(missing);
    }
    let mut spine = vec![spine_bone];
    spine.extend(get("chest"));
    spine.extend(get("upperChest"));
    let limb = |(u, l, e): (usize, usize, usize)| Limb {
        upper: u,
        lower: l,
        end: End::Bone {
            node: e,
            detached: !tree.is_ancestor(l, e),
        },
    };
    Ok(Found {
        root,
        spine,
        neck: get("neck").into_iter().collect(),
        head,
        legs: [limb(legs[0]), limb(legs[1])],
        toes: [get("leftToes"), get("rightToes")],
        arms: [limb(arms[0]), limb(arms[1])],
        collars: [
            get("leftShoulder").into_iter().collect(),
            get("rightShoulder").into_iter().collect(),
        ],
    })
}

/// "lhip (left upper leg)": an SMPL joint with what it means on a body.
pub(crate) fn missing_name(j: usize) -> String {
    let what = match j {
        0 => "hips: the bone both legs and the spine hang from",
        1 => "left upper leg",
        2 => "right upper leg",
        4 => "left lower leg",
        5 => "right lower leg",
        7 => "left foot",
        8 => "right foot",
        9 => "chest: a spine bone between the hips and the arms",
        15 => "head",
        16 => "left upper arm",
        17 => "right upper arm",
        18 => "left forearm",
        19 => "right forearm",
        20 => "left hand",
        21 => "right hand",
        _ => "",
    };
    format!("{} ({what})", dancegen_motion::skeleton::SMPL24_NAMES[j])
}

/// Finds the humanoid parts from bone names and the hierarchy.
fn from_names(tree: &NodeTree, table: NameTable) -> Result<Found, Vec<String>> {
    let class: Vec<Option<(Part, Side)>> = (0..tree.len())
        .map(|k| {
            if tree.is_joint[k] && !tree.has_content[k] {
                names::classify(&tree.names[k], table)
            } else {
                None
            }
        })
        .collect();
    let cands = |part: Part, side: Side| -> Vec<usize> {
        let mut v: Vec<usize> = (0..tree.len())
            .filter(|&k| class[k] == Some((part, side)))
            .collect();
        v.sort_by_key(|&k| (tree.depth[k], k));
        v
    };
    let sides = [Side::Left, Side::Right];
    let mut missing = Vec::new();
    let mut legs = Vec::new();
    let mut arms = Vec::new();
    for (s, &side) in sides.iter().enumerate() {
        let leg = find_limb(
            tree,
            &cands(Part::UpperLeg, side),
            &cands(Part::LowerLeg, side),
            &cands(Part::Foot, side),
            false,
        );
        let arm = find_limb(
            tree,
            &cands(Part::UpperArm, side),
            &cands(Part::LowerArm, side),
            &cands(Part::Hand, side),
            true,
        );
        for (found, joints) in [
            (&leg, [smpl::HIP[s], smpl::KNEE[s], smpl::ANKLE[s]]),
            (&arm, [smpl::SHOULDER[s], smpl::ELBOW[s], smpl::WRIST[s]]),
        ] {
            if found.0.is_none() {
                missing.push(missing_name(joints[0]));
            }
            if found.1.is_none() {
                missing.push(missing_name(joints[1]));
            }
            if found.2.is_none() {
                missing.push(missing_name(joints[2]));
            }
        }
        legs.push(leg);
        arms.push(arm);
    }
    let thighs = [legs[0].0, legs[1].0];
    let pelvis = match thighs {
        [Some(a), Some(b)] => tree.lca(a, b),
        _ => None,
    };
    let heads = cands(Part::Head, Side::Center);
    let head = match pelvis {
        Some(p) => heads.iter().copied().find(|&h| tree.lca(p, h).is_some()),
        None => heads.first().copied(),
    }
    .or_else(|| {
        // A neck whose child is unnamed: that child is the head.
        cands(Part::Neck, Side::Center).iter().find_map(|&n| {
            tree.children[n]
                .iter()
                .copied()
                .find(|&c| tree.is_joint[c] && !tree.has_content[c])
        })
    });
    if head.is_none() {
        missing.push(missing_name(smpl::HEAD));
    }
    let root = match (pelvis, head) {
        (Some(p), Some(h)) => tree.lca(p, h),
        _ => None,
    };
    if root.is_none() && pelvis.is_some() && head.is_some() {
        missing.push(missing_name(smpl::ROOT));
    }
    let uppers = [arms[0].0, arms[1].0];
    let chest = match (uppers, root, head) {
        ([Some(a), Some(b)], Some(r), Some(h)) => tree
            .lca(a, b)
            .and_then(|c| {
                if tree.is_ancestor(c, h) {
                    Some(c)
                } else {
                    tree.lca(c, h)
                }
            })
            .filter(|&c| tree.is_ancestor(r, c)),
        _ => None,
    };
    if chest.is_none() && uppers.iter().all(Option::is_some) && root.is_some() {
        missing.push(missing_name(smpl::CHEST));
    }
    if !missing.is_empty() {
        return Err(missing);
    }
    let (root, head, chest) = (root.unwrap_or(0), head.unwrap_or(0), chest.unwrap_or(0));
    let limb = |(u, l, e): (Option<usize>, Option<usize>, Option<End>)| Limb {
        upper: u.unwrap_or(0),
        lower: l.unwrap_or(0),
        end: e.unwrap_or(End::Group(Vec::new())),
    };
    let legs: Vec<Limb> = legs.into_iter().map(limb).collect();
    let arms: Vec<Limb> = arms.into_iter().map(limb).collect();
    let mut spine = tree.between(root, chest);
    spine.push(chest);
    let toes = [0, 1].map(|s| {
        let foot = match legs[s].end {
            End::Bone { node, .. } => node,
            End::Group(_) => return None,
        };
        cands(Part::Toes, sides[s])
            .into_iter()
            .find(|&t| tree.is_ancestor(foot, t))
    });
    Ok(Found {
        root,
        spine,
        neck: tree.between(chest, head),
        head,
        toes,
        collars: [
            tree.between(chest, arms[0].upper),
            tree.between(chest, arms[1].upper),
        ],
        legs: [legs[0].clone(), legs[1].clone()],
        arms: [arms[0].clone(), arms[1].clone()],
    })
}

/// Picks upper → lower → end for one limb (see the module docs). Returns what it found.
fn find_limb(
    tree: &NodeTree,
    uppers: &[usize],
    lowers: &[usize],
    ends: &[usize],
    arm: bool,
) -> (Option<usize>, Option<usize>, Option<End>) {
    let fallback_uppers: Vec<usize>;
    let uppers = if uppers.is_empty() {
        fallback_uppers = lowers.iter().filter_map(|&l| tree.parents[l]).collect();
        &fallback_uppers
    } else {
        uppers
    };
    let mut partial = (uppers.first().copied(), None, None);
    for &u in uppers {
        let lower = lowers
            .iter()
            .copied()
            .find(|&l| tree.is_ancestor(u, l))
            .or_else(|| {
                ends.iter()
                    .copied()
                    .find(|&e| tree.is_ancestor(u, e))
                    .and_then(|e| tree.between(u, e).first().copied())
            });
        let Some(l) = lower else { continue };
        let end = ends
            .iter()
            .copied()
            .find(|&e| tree.is_ancestor(l, e))
            .map(|node| End::Bone {
                node,
                detached: false,
            })
            .or_else(|| {
                let tip = end_point(tree, l)?;
                let reach = norm(sub(tip, tree.rest_position(l)));
                ends.iter()
                    .copied()
                    .find(|&e| {
                        !tree.is_ancestor(e, l)
                            && norm(sub(tree.rest_position(e), tip)) <= DETACHED_TOLERANCE * reach
                    })
                    .map(|node| End::Bone {
                        node,
                        detached: true,
                    })
            })
            .or_else(|| {
                // Nothing marks where the lower limb ends: an exporter that writes no leaf
                // bones (Blender's glTF exporter; the robot exported again from Blender lost
                // its `LowerLeg.L_end`). An IK-style end named for this limb counts when the
                // limb runs on nearly straight to it at rest (the hip-to-foot distance is
                // within [`STRAIGHT_AT_REST`] of thigh plus knee-to-foot) and it is no
                // farther from the knee than twice the thigh: the robot's shin is 1.5 thighs.
                if end_point(tree, l).is_some() {
                    return None;
                }
                let (pu, pl) = (tree.rest_position(u), tree.rest_position(l));
                let upper = norm(sub(pl, pu));
                ends.iter()
                    .copied()
                    .find(|&e| {
                        let pe = tree.rest_position(e);
                        let lower = norm(sub(pe, pl));
                        !tree.is_ancestor(e, l)
                            && !tree.is_ancestor(u, e)
                            && lower <= 2.0 * upper
                            && norm(sub(pe, pu)) >= STRAIGHT_AT_REST * (upper + lower)
                    })
                    .map(|node| End::Bone {
                        node,
                        detached: true,
                    })
            })
            .or_else(|| {
                let kids: Vec<usize> = tree.children[l]
                    .iter()
                    .copied()
                    .filter(|&c| tree.is_joint[c] && !tree.has_content[c])
                    .collect();
                match (arm, kids.first()) {
                    (_, None) => None,
                    (true, Some(_)) => Some(End::Group(kids)),
                    (false, Some(&c)) => Some(End::Bone {
                        node: c,
                        detached: false,
                    }),
                }
            });
        match end {
            Some(e) => return (Some(u), Some(l), Some(e)),
            None => partial = (Some(u), Some(l), None),
        }
    }
    partial
}

/// How far (as a fraction of the lower limb's length) an IK-style foot or hand may sit from
/// where the limb ends and still count as that limb's end: FBX2glTF places RobotExpressive's
/// feet exactly at the shin ends, 10 % leaves room for rounding and small offsets without ever
/// reaching the next joint.
const DETACHED_TOLERANCE: f64 = 0.1;

/// How straight a limb with no marked end must be at rest for an IK-style end to count as
/// its end (upper-to-end distance over the sum of the two segments): a T- or A-pose limb is
/// straight (the robot's legs: 0.98), a bent one is not taken for one.
const STRAIGHT_AT_REST: f64 = 0.9;

/// Rest world position of [`Site::EndOf`]`(k)`; `None` for a node without child nodes.
pub(crate) fn end_point(tree: &NodeTree, k: usize) -> Option<[f64; 3]> {
    let kids: Vec<usize> = tree.children[k]
        .iter()
        .copied()
        .filter(|&c| !tree.has_content[c])
        .collect();
    let first = *kids.first()?;
    if kids.len() == 1 {
        return Some(tree.rest_position(first));
    }
    let base = tree.rest_position(k);
    // The position most children share (palms of one hand start at one point).
    let mut best = (0, first);
    for &c in &kids {
        let p = tree.rest_position(c);
        let eps = 0.05 * norm(sub(p, base)).max(1e-12);
        let count = kids
            .iter()
            .filter(|&&o| norm(sub(tree.rest_position(o), p)) <= eps)
            .count();
        if count > best.0 {
            best = (count, c);
        }
    }
    if best.0 > 1 {
        return Some(tree.rest_position(best.1));
    }
    let named = |word: &str| {
        kids.iter()
            .copied()
            .find(|&c| names::words(&tree.names[c]).iter().any(|w| w == word))
    };
    if let Some(m) = named("middle") {
        return Some(tree.rest_position(m));
    }
    let no_thumb: Vec<usize> = kids
        .iter()
        .copied()
        .filter(|&c| !names::words(&tree.names[c]).iter().any(|w| w == "thumb"))
        .collect();
    let pick = if no_thumb.is_empty() {
        &kids
    } else {
        &no_thumb
    };
    let sum = pick.iter().fold([0.0; 3], |a, &c| {
        let p = tree.rest_position(c);
        [a[0] + p[0], a[1] + p[1], a[2] + p[2]]
    });
    Some(scale(sum, 1.0 / pick.len() as f64))
}

/// Rest world position of a site.
pub(crate) fn site_position(tree: &NodeTree, site: Site) -> Option<[f64; 3]> {
    match site {
        Site::Node(k) => Some(tree.rest_position(k)),
        Site::EndOf(k) => end_point(tree, k),
    }
}

/// Turns the found parts into the ordered list of driven bones.
fn build(convention: Convention, tree: &NodeTree, f: &Found) -> BoneMap {
    let mut sites: [Option<Site>; 24] = [None; 24];
    let mut bones: Vec<MappedBone> = Vec::new();
    let push = |bones: &mut Vec<MappedBone>, b: MappedBone| {
        bones.push(b);
        bones.len() - 1
    };
    let root = push(
        &mut bones,
        MappedBone {
            node: f.root,
            smpl: smpl::ROOT,
            aim: Aim::Hips,
            detached_from: None,
            chain_parent: None,
        },
    );
    sites[smpl::ROOT] = Some(Site::Node(f.root));

    // Trunk: spine bones, neck bones, head, with their SMPL joints.
    let n = f.spine.len();
    let spine_joints = [smpl::BELLY, smpl::SPINE, smpl::CHEST];
    let mut trunk: Vec<(usize, usize)> = f
        .spine
        .iter()
        .enumerate()
        .map(|(i, &node)| (node, spine_joints[(3 * (i + 1)).div_ceil(n) - 1]))
        .collect();
    trunk.extend(f.neck.iter().map(|&node| (node, smpl::NECK)));
    trunk.push((f.head, smpl::HEAD));
    let mut parent = root;
    let mut chest_bone = root;
    for (i, &(node, j)) in trunk.iter().enumerate() {
        let aim =
            trunk[i + 1..]
                .iter()
                .find(|&&(_, jj)| jj != j)
                .map_or(Aim::None, |&(next, jj)| Aim::Full {
                    target: Site::Node(next),
                    source: jj,
                });
        if sites[j].is_none() {
            sites[j] = Some(Site::Node(node));
        }
        parent = push(
            &mut bones,
            MappedBone {
                node,
                smpl: j,
                aim,
                detached_from: None,
                chain_parent: Some(parent),
            },
        );
        if i + 1 == n {
            chest_bone = parent;
        }
    }

    for s in 0..2 {
        // Leg.
        let leg = &f.legs[s];
        let (foot, foot_detached) = match &leg.end {
            End::Bone { node, detached } => (*node, *detached),
            // `find_limb` ends legs in a bone; a group would be its first member.
            End::Group(g) => (g.first().copied().unwrap_or(leg.lower), false),
        };
        sites[smpl::HIP[s]] = Some(Site::Node(leg.upper));
        sites[smpl::KNEE[s]] = Some(Site::Node(leg.lower));
        sites[smpl::ANKLE[s]] = Some(Site::Node(foot));
        let thigh = push(
            &mut bones,
            MappedBone {
                node: leg.upper,
                smpl: smpl::HIP[s],
                aim: Aim::Full {
                    target: Site::Node(leg.lower),
                    source: smpl::KNEE[s],
                },
                detached_from: None,
                chain_parent: Some(root),
            },
        );
        let shin = push(
            &mut bones,
            MappedBone {
                node: leg.lower,
                smpl: smpl::KNEE[s],
                aim: Aim::Full {
                    target: Site::Node(foot),
                    source: smpl::ANKLE[s],
                },
                detached_from: None,
                chain_parent: Some(thigh),
            },
        );
        let toe_site = match f.toes[s] {
            Some(t) => Some(Site::Node(t)),
            None => end_point(tree, foot).map(|_| Site::EndOf(foot)),
        };
        let foot_bone = push(
            &mut bones,
            MappedBone {
                node: foot,
                smpl: smpl::ANKLE[s],
                aim: toe_site.map_or(Aim::None, |target| Aim::Heading {
                    target,
                    source: smpl::TOES[s],
                }),
                detached_from: foot_detached.then_some(leg.lower),
                chain_parent: Some(shin),
            },
        );
        if let Some(t) = f.toes[s] {
            sites[smpl::TOES[s]] = Some(Site::Node(t));
            push(
                &mut bones,
                MappedBone {
                    node: t,
                    smpl: smpl::TOES[s],
                    aim: Aim::None,
                    detached_from: None,
                    chain_parent: Some(foot_bone),
                },
            );
        }

        // Arm.
        let arm = &f.arms[s];
        let mut parent = chest_bone;
        for &c in &f.collars[s] {
            if sites[smpl::COLLAR[s]].is_none() {
                sites[smpl::COLLAR[s]] = Some(Site::Node(c));
            }
            parent = push(
                &mut bones,
                MappedBone {
                    node: c,
                    smpl: smpl::COLLAR[s],
                    aim: Aim::Full {
                        target: Site::Node(arm.upper),
                        source: smpl::SHOULDER[s],
                    },
                    detached_from: None,
                    chain_parent: Some(parent),
                },
            );
        }
        let wrist_site = match &arm.end {
            End::Bone { node, .. } => Site::Node(*node),
            End::Group(_) => Site::EndOf(arm.lower),
        };
        sites[smpl::SHOULDER[s]] = Some(Site::Node(arm.upper));
        sites[smpl::ELBOW[s]] = Some(Site::Node(arm.lower));
        sites[smpl::WRIST[s]] = Some(wrist_site);
        let upper = push(
            &mut bones,
            MappedBone {
                node: arm.upper,
                smpl: smpl::SHOULDER[s],
                aim: Aim::Full {
                    target: Site::Node(arm.lower),
                    source: smpl::ELBOW[s],
                },
                detached_from: None,
                chain_parent: Some(parent),
            },
        );
        let fore = push(
            &mut bones,
            MappedBone {
                node: arm.lower,
                smpl: smpl::ELBOW[s],
                aim: Aim::Full {
                    target: wrist_site,
                    source: smpl::WRIST[s],
                },
                detached_from: None,
                chain_parent: Some(upper),
            },
        );
        match &arm.end {
            End::Bone { node, detached } => {
                let aim = if end_point(tree, *node).is_some() {
                    sites[smpl::HAND[s]] = Some(Site::EndOf(*node));
                    Aim::Full {
                        target: Site::EndOf(*node),
                        source: smpl::HAND[s],
                    }
                } else {
                    Aim::None
                };
                push(
                    &mut bones,
                    MappedBone {
                        node: *node,
                        smpl: smpl::WRIST[s],
                        aim,
                        detached_from: detached.then_some(arm.lower),
                        chain_parent: Some(fore),
                    },
                );
            }
            End::Group(kids) => {
                for &k in kids {
                    push(
                        &mut bones,
                        MappedBone {
                            node: k,
                            smpl: smpl::WRIST[s],
                            aim: Aim::None,
                            detached_from: None,
                            chain_parent: Some(fore),
                        },
                    );
                }
            }
        }
    }
    BoneMap {
        convention,
        bones,
        sites,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A Mixamo-named skeleton with a twist bone and an IK foot target, as nodes JSON.
    fn mixamo() -> Value {
        let names = [
            ("mixamorig:Hips", None, [0.0, 1.0, 0.0]),
            ("mixamorig:Spine", Some(0), [0.0, 0.1, 0.0]),
            ("mixamorig:Spine1", Some(1), [0.0, 0.1, 0.0]),
            ("mixamorig:Spine2", Some(2), [0.0, 0.1, 0.0]),
            ("mixamorig:Neck", Some(3), [0.0, 0.15, 0.0]),
            ("mixamorig:Head", Some(4), [0.0, 0.1, 0.0]),
            ("mixamorig:LeftShoulder", Some(3), [0.05, 0.1, 0.0]),
            ("mixamorig:LeftArm", Some(6), [0.1, 0.0, 0.0]),
            ("mixamorig:LeftForeArm", Some(7), [0.25, 0.0, 0.0]),
            ("mixamorig:LeftHand", Some(8), [0.25, 0.0, 0.0]),
            ("mixamorig:RightShoulder", Some(3), [-0.05, 0.1, 0.0]),
            ("mixamorig:RightArm", Some(10), [-0.1, 0.0, 0.0]),
            ("mixamorig:RightForeArm", Some(11), [-0.25, 0.0, 0.0]),
            ("mixamorig:RightHand", Some(12), [-0.25, 0.0, 0.0]),
            ("mixamorig:LeftUpLeg", Some(0), [0.1, -0.05, 0.0]),
            ("mixamorig:LeftLeg", Some(14), [0.0, -0.4, 0.0]),
            ("mixamorig:LeftFoot", Some(15), [0.0, -0.4, 0.0]),
            ("mixamorig:LeftToeBase", Some(16), [0.0, -0.05, 0.1]),
            ("mixamorig:RightUpLeg", Some(0), [-0.1, -0.05, 0.0]),
            ("mixamorig:RightLeg", Some(18), [0.0, -0.4, 0.0]),
            ("mixamorig:RightFoot", Some(19), [0.0, -0.4, 0.0]),
            ("mixamorig:RightToeBase", Some(20), [0.0, -0.05, 0.1]),
            ("mixamorig:LeftArmTwist", Some(7), [0.1, 0.0, 0.0]),
            ("LeftFootIK", None, [0.1, 0.1, 0.0]),
            ("mixamorig:LeftHandMiddle1", Some(9), [0.08, 0.0, 0.0]),
            ("mixamorig:LeftHandThumb1", Some(9), [0.03, 0.0, 0.03]),
        ];
        let mut nodes: Vec<Value> = names
            .iter()
            .map(|(n, _, t)| json!({"name": n, "translation": t}))
            .collect();
        for (i, (_, p, _)) in names.iter().enumerate() {
            if let Some(p) = p {
                let c = nodes[*p]
                    .as_object_mut()
                    .unwrap()
                    .entry("children")
                    .or_insert(json!([]));
                c.as_array_mut().unwrap().push(json!(i));
            }
        }
        nodes.push(json!({"name": "body", "mesh": 0, "skin": 0}));
        json!({"nodes": nodes, "skins": [{"joints": (0..names.len()).collect::<Vec<_>>()}]})
    }

    /// [`mixamo`] with the left foot taken out of the leg (an IK-style foot, a root node at
    /// world position `at`) and so no bone under the left shin: as Blender's glTF exporter
    /// writes the robot's legs.
    fn with_detached_left_foot(at: [f64; 3]) -> Value {
        let mut doc = mixamo();
        let nodes = doc["nodes"].as_array_mut().unwrap();
        nodes[15]["children"] = json!([]);
        nodes[16]["translation"] = json!(at);
        doc
    }

    #[test]
    fn an_ik_foot_ends_a_leg_with_no_bone_below_the_shin_when_the_leg_runs_straight_to_it() {
        // Hip at (0.1, 0.95, 0), knee 0.4 below it: the foot 0.4 below the knee, in line.
        let doc = with_detached_left_foot([0.1, 0.15, 0.0]);
        let tree = NodeTree::from_json(&doc).unwrap();
        let m = match_bones(&doc, &tree).unwrap();
        assert_eq!(m.node_for(smpl::ANKLE[0]), Some(16));
        let foot = m.bones.iter().find(|b| b.node == 16).unwrap();
        assert_eq!(foot.detached_from, Some(15), "moved with the shin");
        // The same foot 0.4 m out to the side of the knee: the leg is bent 90 degrees at rest
        // (hip to foot 0.57 m against 0.8 m of segments), so it is not taken for the leg's end.
        let doc = with_detached_left_foot([0.5, 0.55, 0.0]);
        let tree = NodeTree::from_json(&doc).unwrap();
        let missing = match_bones(&doc, &tree).unwrap_err();
        assert!(missing.iter().any(|m| m.contains("lankle")), "{missing:?}");
    }

    #[test]
    fn maps_mixamo_by_names_and_hierarchy() {
        let doc = mixamo();
        let tree = NodeTree::from_json(&doc).unwrap();
        let m = match_bones(&doc, &tree).unwrap();
        assert_eq!(m.convention, Convention::BoneNames);
        assert_eq!(m.hips(), 0);
        let expect = [
            (smpl::BELLY, 1),
            (smpl::SPINE, 2),
            (smpl::CHEST, 3),
            (smpl::NECK, 4),
            (smpl::HEAD, 5),
            (13, 6),
            (16, 7),
            (18, 8),
            (20, 9),
            (14, 10),
            (1, 14),
            (4, 15),
            (7, 16),
            (10, 17),
            (2, 18),
        ];
        for (j, node) in expect {
            assert_eq!(m.node_for(j), Some(node), "SMPL joint {j}");
        }
        // The hand points at its middle finger, not the thumb; the twist bone is not mapped.
        assert_eq!(m.sites[smpl::HAND[0]], Some(Site::EndOf(9)));
        assert!(m.bones.iter().all(|b| b.node != 22 && b.node != 23));
        // Chain parents come first.
        for (i, b) in m.bones.iter().enumerate() {
            assert!(b.chain_parent.is_none_or(|p| p < i));
        }
    }

    #[test]
    fn spine_distribution() {
        let pick = |n: usize| -> Vec<usize> {
            (0..n)
                .map(|i| [3, 6, 9][(3 * (i + 1)).div_ceil(n) - 1])
                .collect()
        };
        assert_eq!(pick(1), [9]);
        assert_eq!(pick(2), [6, 9]);
        assert_eq!(pick(3), [3, 6, 9]);
        assert_eq!(pick(5), [3, 6, 6, 9, 9]);
    }

    #[test]
    fn missing_bones_are_listed() {
        let mut doc = mixamo();
        // Rename the left forearm and hand out of recognition, and drop the head.
        for (i, new) in [(8, "bone_a"), (9, "bone_b"), (5, "bone_c")] {
            doc["nodes"][i]["name"] = json!(new);
        }
        doc["nodes"][4]["children"] = json!([]);
        let tree = NodeTree::from_json(&doc).unwrap();
        let err = match_bones(&doc, &tree).unwrap_err();
        assert_eq!(
            err,
            vec![
                "lelbow (left forearm)".to_string(),
                "lwrist (left hand)".to_string(),
                "head (head)".to_string()
            ]
        );
    }
}
