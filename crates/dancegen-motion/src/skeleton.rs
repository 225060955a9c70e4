//! Kinematic trees: joint names, parents and rest-pose offsets, plus the SMPL-family tables.
//!
//! A [`Skeleton`] is validated on construction (one root at index 0, every parent listed before
//! its children, unique names, finite offsets) so forward kinematics can walk the joints in index
//! order without checks. Offsets are parent-relative rest-pose bone vectors in the Y-up metre
//! frame of [`crate::conventions`].

use std::collections::HashMap;

/// Why a skeleton description was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkeletonError {
    #[error("skeleton has no joints")]
    Empty,
    #[error("length mismatch: {names} names, {parents} parents, {offsets} offsets")]
    LengthMismatch {
        names: usize,
        parents: usize,
        offsets: usize,
    },
    #[error(
        "joint {joint} ({name}) has parent {parent}, which is not an earlier joint; \
         parents must be listed before their children and joint 0 must be the root"
    )]
    ParentNotBefore {
        joint: usize,
        name: String,
        parent: i64,
    },
    #[error("joint {joint} ({name}) has no parent, but only joint 0 may be the root")]
    MultipleRoots { joint: usize, name: String },
    #[error("duplicate joint name {name:?} at indices {first} and {second}")]
    DuplicateName {
        name: String,
        first: usize,
        second: usize,
    },
    #[error("joint {joint} ({name}) has a non-finite offset {offset:?}")]
    NonFiniteOffset {
        joint: usize,
        name: String,
        offset: [f64; 3],
    },
    #[error("expected {expected} rest joints, got {got}")]
    RestJointCount { expected: usize, got: usize },
}

/// A validated kinematic tree.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    names: Vec<String>,
    parents: Vec<Option<usize>>,
    offsets: Vec<[f64; 3]>,
}

impl Skeleton {
    /// Builds and validates a skeleton.
    ///
    /// `offsets[j]` is joint `j`'s rest position relative to its parent. `offsets[0]` is the
    /// root's rest position in the body frame; forward kinematics ignores it (the root goes to
    /// the root translation, [`crate::conventions`]) but importers can use it to convert
    /// translations that were defined relative to the rest pelvis (AIST++, LODGE's SMPL-X FK).
    pub fn new(
        names: Vec<String>,
        parents: Vec<Option<usize>>,
        offsets: Vec<[f64; 3]>,
    ) -> Result<Self, SkeletonError> {
        if names.len() != parents.len() || names.len() != offsets.len() {
            return Err(SkeletonError::LengthMismatch {
                names: names.len(),
                parents: parents.len(),
                offsets: offsets.len(),
            });
        }
        if names.is_empty() {
            return Err(SkeletonError::Empty);
        }
        let mut seen: HashMap<&str, usize> = HashMap::with_capacity(names.len());
        for (j, name) in names.iter().enumerate() {
            if let Some(first) = seen.insert(name.as_str(), j) {
                return Err(SkeletonError::DuplicateName {
                    name: name.clone(),
                    first,
                    second: j,
                });
            }
            match parents[j] {
                None if j != 0 => {
                    return Err(SkeletonError::MultipleRoots {
                        joint: j,
                        name: name.clone(),
                    });
                }
                Some(p) if p >= j => {
                    return Err(SkeletonError::ParentNotBefore {
                        joint: j,
                        name: name.clone(),
                        parent: p as i64,
                    });
                }
                _ => {}
            }
            if offsets[j].iter().any(|v| !v.is_finite()) {
                return Err(SkeletonError::NonFiniteOffset {
                    joint: j,
                    name: name.clone(),
                    offset: offsets[j],
                });
            }
        }
        Ok(Skeleton {
            names,
            parents,
            offsets,
        })
    }

    /// Like [`Skeleton::new`] with parents as signed indices, `-1` for the root (the form used
    /// by SMPL/EDGE/LODGE code and by the constant tables of this module).
    pub fn from_parent_indices<S: AsRef<str>>(
        names: &[S],
        parents: &[i32],
        offsets: Vec<[f64; 3]>,
    ) -> Result<Self, SkeletonError> {
        let names: Vec<String> = names.iter().map(|s| s.as_ref().to_owned()).collect();
        let mut converted = Vec::with_capacity(parents.len());
        for (j, &p) in parents.iter().enumerate() {
            converted.push(match p {
                -1 => None,
                p if p >= 0 => Some(p as usize),
                p => {
                    return Err(SkeletonError::ParentNotBefore {
                        joint: j,
                        name: names.get(j).cloned().unwrap_or_default(),
                        parent: p as i64,
                    });
                }
            });
        }
        Skeleton::new(names, converted, offsets)
    }

    /// Builds a skeleton from absolute rest joint positions (as SMPL-family models ship them):
    /// `offset[j] = rest[j] − rest[parent[j]]`, `offset[0] = rest[0]`.
    pub fn from_rest_joints<S: AsRef<str>>(
        names: &[S],
        parents: &[i32],
        rest_joints: &[[f64; 3]],
    ) -> Result<Self, SkeletonError> {
        if rest_joints.len() != parents.len() {
            return Err(SkeletonError::RestJointCount {
                expected: parents.len(),
                got: rest_joints.len(),
            });
        }
        let offsets = parents
            .iter()
            .enumerate()
            .map(|(j, &p)| {
                if p >= 0 && (p as usize) < j {
                    let (a, b) = (rest_joints[j], rest_joints[p as usize]);
                    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
                } else {
                    rest_joints[j]
                }
            })
            .collect();
        Skeleton::from_parent_indices(names, parents, offsets)
    }

    /// The 24-joint SMPL body with EDGE's joint names and rest offsets (anchors.md C.4).
    ///
    /// Offsets as in Stanford-TML/EDGE `vis.py` (MIT licence): parent-relative, Y-up, metres,
    /// root offset zero.
    pub fn smpl24() -> Self {
        Skeleton::from_parent_indices(&SMPL24_NAMES, &SMPL24_PARENTS, SMPL24_OFFSETS.to_vec())
            .expect("built-in SMPL 24 table is valid")
    }

    /// SMPL-H 52 (22 body + 2 × 15 hand joints; FineDance's order, anchors.md C.3) from
    /// user-supplied rest joints (52 × 3, metres, Y-up). No rest pose is shipped because the
    /// SMPL-H/SMPL-X model files that define it are under a non-commercial licence.
    pub fn smplh52(rest_joints: &[[f64; 3]]) -> Result<Self, SkeletonError> {
        Skeleton::from_rest_joints(&SMPLH52_NAMES, &SMPLH52_PARENTS, rest_joints)
    }

    /// SMPL-X 55 (anchors.md C.3 parents) from user-supplied rest joints (55 × 3, metres, Y-up),
    /// e.g. LODGE's `smplx_neu_J_1.npy`. Not shipped: the SMPL-X model licence is
    /// non-commercial.
    pub fn smplx55(rest_joints: &[[f64; 3]]) -> Result<Self, SkeletonError> {
        Skeleton::from_rest_joints(&SMPLX55_NAMES, &SMPLX55_PARENTS, rest_joints)
    }

    /// An **approximate** SMPL-H 52 skeleton of our own, for when no SMPL-H/SMPL-X model file
    /// is available (their rest joints are non-commercial and not shipped, see
    /// [`Skeleton::smplh52`]). Names and parents are [`SMPLH52_NAMES`] / [`SMPLH52_PARENTS`];
    /// offsets are [`SMPLH52_APPROX_OFFSETS`]: the body 0–21 is EDGE's SMPL 24 table
    /// ([`SMPL24_OFFSETS`], MIT) and the 30 finger joints are placed from anthropometric
    /// proportions documented on that constant. Good for synthetic tests, visualisation and
    /// representation round trips; not a substitute for a fitted SMPL-H hand.
    pub fn smplh52_approx() -> Self {
        Skeleton::from_parent_indices(
            &SMPLH52_NAMES,
            &SMPLH52_PARENTS,
            SMPLH52_APPROX_OFFSETS.to_vec(),
        )
        .expect("built-in approximate SMPL-H 52 table is valid")
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Always false for a validated skeleton; present for API symmetry with `len`.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    pub fn names(&self) -> &[String] {
        &self.names
    }

    pub fn parents(&self) -> &[Option<usize>] {
        &self.parents
    }

    pub fn offsets(&self) -> &[[f64; 3]] {
        &self.offsets
    }

    pub fn parent(&self, joint: usize) -> Option<usize> {
        self.parents[joint]
    }

    /// Index of a joint by exact name.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Parents as signed indices with `-1` for the root.
    pub fn parent_indices(&self) -> Vec<i32> {
        self.parents
            .iter()
            .map(|p| p.map_or(-1, |p| p as i32))
            .collect()
    }

    /// `true` for joints that have at least one child (leaf rotations do not move any joint).
    pub fn has_children(&self) -> Vec<bool> {
        let mut out = vec![false; self.len()];
        for p in self.parents.iter().flatten() {
            out[*p] = true;
        }
        out
    }

    /// Rest-pose joint positions with the root at the origin (cumulative offsets, `offsets[0]`
    /// ignored) — what forward kinematics returns for the identity pose and zero translation.
    pub fn rest_positions(&self) -> Vec<[f64; 3]> {
        let mut out: Vec<[f64; 3]> = Vec::with_capacity(self.len());
        for (j, parent) in self.parents.iter().enumerate() {
            out.push(match parent {
                None => [0.0; 3],
                Some(p) => {
                    let (a, o) = (out[*p], self.offsets[j]);
                    [a[0] + o[0], a[1] + o[1], a[2] + o[2]]
                }
            });
        }
        out
    }
}

/// SMPL 24 joint names in EDGE's spelling (anchors.md C.4).
pub const SMPL24_NAMES: [&str; 24] = [
    "root",
    "lhip",
    "rhip",
    "belly",
    "lknee",
    "rknee",
    "spine",
    "lankle",
    "rankle",
    "chest",
    "ltoes",
    "rtoes",
    "neck",
    "linshoulder",
    "rinshoulder",
    "head",
    "lshoulder",
    "rshoulder",
    "lelbow",
    "relbow",
    "lwrist",
    "rwrist",
    "lhand",
    "rhand",
];

/// SMPL 24 parents, `-1` = root (anchors.md C.4).
pub const SMPL24_PARENTS: [i32; 24] = [
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21,
];

// Offsets as in Stanford-TML/EDGE vis.py (MIT), copied from anchors.md C.4.
/// SMPL 24 rest offsets, parent-relative, Y-up, metres (anchors.md C.4).
#[rustfmt::skip]
pub const SMPL24_OFFSETS: [[f64; 3]; 24] = [
    [0.0, 0.0, 0.0],
    [0.05858135, -0.08228004, -0.01766408],
    [-0.06030973, -0.09051332, -0.01354254],
    [0.00443945, 0.12440352, -0.03838522],
    [0.04345142, -0.38646945, 0.008037],
    [-0.04325663, -0.38368791, -0.00484304],
    [0.00448844, 0.1379564, 0.02682033],
    [-0.01479032, -0.42687458, -0.037428],
    [0.01905555, -0.4200455, -0.03456167],
    [-0.00226458, 0.05603239, 0.00285505],
    [0.04105436, -0.06028581, 0.12204243],
    [-0.03483987, -0.06210566, 0.13032329],
    [-0.0133902, 0.21163553, -0.03346758],
    [0.07170245, 0.11399969, -0.01889817],
    [-0.08295366, 0.11247234, -0.02370739],
    [0.01011321, 0.08893734, 0.05040987],
    [0.12292141, 0.04520509, -0.019046],
    [-0.11322832, 0.04685326, -0.00847207],
    [0.2553319, -0.01564902, -0.02294649],
    [-0.26012748, -0.01436928, -0.03126873],
    [0.26570925, 0.01269811, -0.00737473],
    [-0.26910836, 0.00679372, -0.00602676],
    [0.08669055, -0.01063603, -0.01559429],
    [-0.0887537, -0.00865157, -0.01010708],
];

/// SMPL 24 left/right mirror permutation (`li-ronghui/LODGE` `SMPL_JOINTS_FLIP_PERM`,
/// anchors.md C.3): pairs 1↔2, 4↔5, 7↔8, 10↔11, 13↔14, 16↔17, 18↔19, 20↔21, 22↔23.
///
/// Mirroring a motion across the YZ plane (x → −x) takes joint `perm[j]`'s data for joint `j`,
/// negates the x of positions and the y and z components of axis-angle rotations (C.3).
pub const SMPL24_MIRROR: [usize; 24] = [
    0, 2, 1, 3, 5, 4, 6, 8, 7, 9, 11, 10, 12, 14, 13, 15, 17, 16, 19, 18, 21, 20, 23, 22,
];

/// SMPL-X 55 joint names (the `smplx` package's order; 25–39 left hand, 40–54 right hand, each
/// index, middle, pinky, ring, thumb × 3).
pub const SMPLX55_NAMES: [&str; 55] = [
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "jaw",
    "left_eye_smplhf",
    "right_eye_smplhf",
    "left_index1",
    "left_index2",
    "left_index3",
    "left_middle1",
    "left_middle2",
    "left_middle3",
    "left_pinky1",
    "left_pinky2",
    "left_pinky3",
    "left_ring1",
    "left_ring2",
    "left_ring3",
    "left_thumb1",
    "left_thumb2",
    "left_thumb3",
    "right_index1",
    "right_index2",
    "right_index3",
    "right_middle1",
    "right_middle2",
    "right_middle3",
    "right_pinky1",
    "right_pinky2",
    "right_pinky3",
    "right_ring1",
    "right_ring2",
    "right_ring3",
    "right_thumb1",
    "right_thumb2",
    "right_thumb3",
];

/// SMPL-X 55 parents, `-1` = root (anchors.md C.3, LODGE `smplx_parents`).
pub const SMPLX55_PARENTS: [i32; 55] = [
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 15, 15, 15, 20, 25,
    26, 20, 28, 29, 20, 31, 32, 20, 34, 35, 20, 37, 38, 21, 40, 41, 21, 43, 44, 21, 46, 47, 21, 49,
    50, 21, 52, 53,
];

/// SMPL-X 55 mirror permutation, derived from the names/structure: the body 0–21 as
/// [`SMPL24_MIRROR`], jaw 22 fixed, eyes 23↔24, left hand 25+k ↔ right hand 40+k (both hands
/// list fingers in the same order). Matches LODGE's `SMPLX_JOINTS_FLIP_PERM` (anchors.md C.3);
/// the test suite checks it against the names.
pub const SMPLX55_MIRROR: [usize; 55] = smplx55_mirror();

const fn smplx55_mirror() -> [usize; 55] {
    let mut m = [0usize; 55];
    let mut j = 0;
    while j < 55 {
        m[j] = if j < 22 {
            SMPL24_MIRROR[j]
        } else if j == 23 {
            24
        } else if j == 24 {
            23
        } else if j >= 25 && j < 40 {
            j + 15
        } else if j >= 40 {
            j - 15
        } else {
            j
        };
        j += 1;
    }
    m
}

/// Maps an SMPL-X index to its SMPL-H 52 index (jaw and eyes 22–24 removed), `usize::MAX` for
/// the removed joints.
const fn smplx_to_smplh(j: usize) -> usize {
    if j < 22 {
        j
    } else if j < 25 {
        usize::MAX
    } else {
        j - 3
    }
}

/// SMPL-H 52 joint names: SMPL-X without jaw and eyes (FineDance order, anchors.md C.3).
pub const SMPLH52_NAMES: [&str; 52] = smplh52_names();

const fn smplh52_names() -> [&'static str; 52] {
    let mut out = [""; 52];
    let mut j = 0;
    while j < 55 {
        let k = smplx_to_smplh(j);
        if k != usize::MAX {
            out[k] = SMPLX55_NAMES[j];
        }
        j += 1;
    }
    out
}

/// SMPL-H 52 parents, derived from [`SMPLX55_PARENTS`] by removing joints 22–24 (whose only
/// children are none) and re-indexing the hands: left-hand roots hang off the left wrist 20,
/// right-hand roots off the right wrist 21.
pub const SMPLH52_PARENTS: [i32; 52] = smplh52_parents();

const fn smplh52_parents() -> [i32; 52] {
    let mut out = [0i32; 52];
    let mut j = 0;
    while j < 55 {
        let k = smplx_to_smplh(j);
        if k != usize::MAX {
            let p = SMPLX55_PARENTS[j];
            out[k] = if p < 0 {
                -1
            } else {
                smplx_to_smplh(p as usize) as i32
            };
        }
        j += 1;
    }
    out
}

/// SMPL-H 52 mirror permutation (SMPL-X's with jaw/eyes removed): body as SMPL, left hand
/// 22+k ↔ right hand 37+k.
pub const SMPLH52_MIRROR: [usize; 52] = smplh52_mirror();

const fn smplh52_mirror() -> [usize; 52] {
    let mut out = [0usize; 52];
    let mut j = 0;
    while j < 55 {
        let k = smplx_to_smplh(j);
        if k != usize::MAX {
            out[k] = smplx_to_smplh(SMPLX55_MIRROR[j]);
        }
        j += 1;
    }
    out
}

/// Parent-relative rest offsets (Y-up, metres) of [`Skeleton::smplh52_approx`]: our own
/// approximation, **not** SMPL-H's rest joints.
///
/// - Joints 0–21: [`SMPL24_OFFSETS`] (EDGE `vis.py`, MIT) unchanged.
/// - Fingers, left hand (22–36, SMPL-H order index, middle, pinky, ring, thumb × 3), in the
///   SMPL rest T-pose: the left arm points along +X, the palm faces down (−Y), the thumb side
///   is forward (+Z). The right hand (37–51) is the exact mirror (x negated).
/// - Scale: hand length (wrist crease → middle fingertip) ≈ 0.19 m, the usual ≈ 11 % of a
///   1.7 m stature; palm (wrist → middle knuckle) 0.105 m ≈ 55 % of it, middle finger
///   0.085 m ≈ 45 %. Other fingers relative to the middle one: index 0.92, ring 0.95,
///   pinky 0.75.
/// - `*1` = wrist → MCP knuckle (the metacarpal; offsets fan across the palm from
///   z = +0.025 m for the index to z = −0.033 m for the pinky, knuckles 5 mm below the wrist
///   axis, the outer fingers' knuckles shorter along X); `*2` = proximal phalanx (0.45 of the
///   finger length), `*3` = middle phalanx (0.30). The distal phalanx (0.25) has no joint in
///   SMPL-H (no fingertips), so it does not appear. Fingers are straight along +X.
/// - Thumb: `thumb1` (CMC, base of the first metacarpal) sits 2.5 cm forward (+Z), 1.2 cm
///   down and 2.5 cm out from the wrist; `thumb2` (MCP) is the first metacarpal, 0.045 m
///   pointing out, forward and down; `thumb3` (IP) is the proximal phalanx, 0.032 m further
///   along the same direction.
#[rustfmt::skip]
pub const SMPLH52_APPROX_OFFSETS: [[f64; 3]; 52] = smplh52_approx_offsets();

const fn smplh52_approx_offsets() -> [[f64; 3]; 52] {
    // Middle-finger length and the per-finger scale; phalanx fractions 0.45 / 0.30 (/ 0.25).
    const MID: f64 = 0.085;
    const PROX: f64 = 0.45;
    const MIDP: f64 = 0.30;
    // Thumb metacarpal / proximal-phalanx direction: out (+X), forward (+Z), down (−Y),
    // normalised: (0.60, −0.30, 0.74) has norm 1.0 to 3 decimals (0.36 + 0.09 + 0.5476).
    const TD: [f64; 3] = [0.6, -0.3, 0.74];
    #[rustfmt::skip]
    const LEFT: [[f64; 3]; 15] = [
        // index: knuckle, proximal, middle phalanx (finger length 0.92 · MID)
        [0.098, -0.005, 0.025], [0.92 * MID * PROX, 0.0, 0.0], [0.92 * MID * MIDP, 0.0, 0.0],
        // middle (1.0 · MID)
        [0.105, -0.005, 0.006], [MID * PROX, 0.0, 0.0], [MID * MIDP, 0.0, 0.0],
        // pinky (0.75 · MID)
        [0.088, -0.005, -0.033], [0.75 * MID * PROX, 0.0, 0.0], [0.75 * MID * MIDP, 0.0, 0.0],
        // ring (0.95 · MID)
        [0.098, -0.005, -0.014], [0.95 * MID * PROX, 0.0, 0.0], [0.95 * MID * MIDP, 0.0, 0.0],
        // thumb: CMC, metacarpal 0.045 m, proximal phalanx 0.032 m
        [0.025, -0.012, 0.025],
        [0.045 * TD[0], 0.045 * TD[1], 0.045 * TD[2]],
        [0.032 * TD[0], 0.032 * TD[1], 0.032 * TD[2]],
    ];
    let mut out = [[0.0; 3]; 52];
    let mut j = 0;
    while j < 22 {
        out[j] = SMPL24_OFFSETS[j];
        j += 1;
    }
    let mut k = 0;
    while k < 15 {
        let o = LEFT[k];
        out[22 + k] = o;
        out[37 + k] = [-o[0], o[1], o[2]];
        k += 1;
    }
    out
}

/// Derives a mirror permutation from joint names by swapping the side prefixes `left_`↔`right_`
/// and `l`↔`r` (EDGE spelling). Names whose swapped counterpart does not exist map to
/// themselves (so `root` stays `root`). Used to check the constant tables and to mirror
/// skeletons that arrive from files (BVH `LeftArm`/`RightArm` also works via `Left`↔`Right`).
pub fn mirror_from_names<S: AsRef<str>>(names: &[S]) -> Vec<usize> {
    const PAIRS: [(&str, &str); 4] = [
        ("left_", "right_"),
        ("Left", "Right"),
        ("l", "r"),
        ("L", "R"),
    ];
    let index: HashMap<&str, usize> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_ref(), i))
        .collect();
    names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let name = name.as_ref();
            for (a, b) in PAIRS {
                for (from, to) in [(a, b), (b, a)] {
                    if let Some(rest) = name.strip_prefix(from)
                        && let Some(&k) = index.get(format!("{to}{rest}").as_str())
                    {
                        return k;
                    }
                }
            }
            i
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_tables_validate() {
        let s = Skeleton::smpl24();
        assert_eq!(s.len(), 24);
        assert_eq!(s.parent_indices(), SMPL24_PARENTS.to_vec());
        let rest = vec![[0.0; 3]; 55];
        assert_eq!(Skeleton::smplx55(&rest).unwrap().len(), 55);
        let rest = vec![[0.0; 3]; 52];
        assert_eq!(Skeleton::smplh52(&rest).unwrap().len(), 52);
        assert!(matches!(
            Skeleton::smplx55(&rest),
            Err(SkeletonError::RestJointCount {
                expected: 55,
                got: 52
            })
        ));
    }

    #[test]
    fn smplh_derivation() {
        // Body unchanged, hand roots on the wrists, fingers chained.
        assert_eq!(&SMPLH52_PARENTS[..22], &SMPLX55_PARENTS[..22]);
        assert_eq!(SMPLH52_PARENTS[22], 20);
        assert_eq!(SMPLH52_PARENTS[23], 22);
        assert_eq!(SMPLH52_PARENTS[37], 21);
        assert_eq!(SMPLH52_NAMES[22], "left_index1");
        assert_eq!(SMPLH52_NAMES[51], "right_thumb3");
        assert_eq!(mirror_from_names(&SMPLH52_NAMES), SMPLH52_MIRROR.to_vec());
    }

    #[test]
    fn mirrors_match_names() {
        assert_eq!(mirror_from_names(&SMPL24_NAMES), SMPL24_MIRROR.to_vec());
        assert_eq!(mirror_from_names(&SMPLX55_NAMES), SMPLX55_MIRROR.to_vec());
        // Structure: mirrored joints have mirrored parents.
        for (parents, mirror) in [
            (&SMPLX55_PARENTS[..], &SMPLX55_MIRROR[..]),
            (&SMPLH52_PARENTS[..], &SMPLH52_MIRROR[..]),
            (&SMPL24_PARENTS[..], &SMPL24_MIRROR[..]),
        ] {
            for j in 1..parents.len() {
                assert_eq!(parents[mirror[j]] as usize, mirror[parents[j] as usize]);
            }
        }
    }

    #[test]
    fn validation_errors() {
        let names = ["a", "b", "c"].map(String::from).to_vec();
        let off = vec![[0.0; 3]; 3];
        let err = Skeleton::new(names.clone(), vec![None, Some(2), Some(0)], off.clone());
        assert!(matches!(
            err,
            Err(SkeletonError::ParentNotBefore { joint: 1, .. })
        ));
        let err = Skeleton::new(names.clone(), vec![None, None, Some(0)], off.clone());
        assert!(matches!(
            err,
            Err(SkeletonError::MultipleRoots { joint: 1, .. })
        ));
        let err = Skeleton::new(names.clone(), vec![Some(0), Some(0), Some(0)], off.clone());
        assert!(matches!(
            err,
            Err(SkeletonError::ParentNotBefore { joint: 0, .. })
        ));
        let err = Skeleton::new(names.clone(), vec![None, Some(0)], off.clone());
        assert!(matches!(err, Err(SkeletonError::LengthMismatch { .. })));
        let dup = ["a", "b", "a"].map(String::from).to_vec();
        let err = Skeleton::new(dup, vec![None, Some(0), Some(0)], off.clone());
        assert!(matches!(
            err,
            Err(SkeletonError::DuplicateName {
                first: 0,
                second: 2,
                ..
            })
        ));
        let mut bad = off.clone();
        bad[2][1] = f64::NAN;
        let err = Skeleton::new(names.clone(), vec![None, Some(0), Some(1)], bad);
        assert!(matches!(
            err,
            Err(SkeletonError::NonFiniteOffset { joint: 2, .. })
        ));
        let err = Skeleton::from_parent_indices(&names, &[-1, -2, 0], off.clone());
        assert!(matches!(
            err,
            Err(SkeletonError::ParentNotBefore {
                joint: 1,
                parent: -2,
                ..
            })
        ));
        assert!(matches!(
            Skeleton::new(vec![], vec![], vec![]),
            Err(SkeletonError::Empty)
        ));
        // The message names the offending joint.
        let msg = Skeleton::new(names, vec![None, Some(2), Some(0)], off)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("joint 1 (b)"), "{msg}");
    }

    #[test]
    fn rest_joints_to_offsets() {
        let rest = [[0.0, 1.0, 0.0], [0.1, 0.9, 0.0], [0.1, 0.5, 0.0]];
        let s = Skeleton::from_rest_joints(&["p", "h", "k"], &[-1, 0, 1], &rest).unwrap();
        let o = s.offsets();
        assert_eq!(o[0], [0.0, 1.0, 0.0]);
        assert!((o[1][0] - 0.1).abs() < 1e-15 && (o[1][1] + 0.1).abs() < 1e-15);
        assert!((o[2][1] + 0.4).abs() < 1e-15);
        // Rest positions are relative to the root.
        let p = s.rest_positions();
        assert!((p[2][1] + 0.5).abs() < 1e-15);
    }
}
