//! The canonical capsule body of SMPL 24: a signed-distance stand-in for the SMPL mesh.
//!
//! The SMPL / SMPL-X meshes are not available to this project, so self-penetration (Lodge++'s
//! penetration guidance and metric, anchors.md A.7) is measured on a body made of capsules around
//! the SMPL 24 bones. This module is the one definition of that body and of capsule geometry in
//! the workspace; the metrics crate and the differentiable guidance both read it.
//!
//! # Geometry
//!
//! A [`Capsule`] is the set of points within `radius_m` of a segment. The segment lies on the
//! line through joints `joint_a` (`A`) and `joint_b` (`B`) of the frame:
//! `P(s) = A + s · (B − A)`, `s ∈ [start, end]`. `start = 0, end = 1` is the bone itself;
//! `end > 1` extends the capsule past `B` (hands past the SMPL hand joint, which sits at the
//! knuckles); `start == end` is a sphere (the head: a sphere on the neck → head line, above the
//! head joint, which SMPL places at the base of the skull). Everything is plain data — joint
//! indices, two line parameters and a radius in metres — so a tensor implementation can gather
//! the joints and evaluate the same formula ([`capsule_endpoints`], [`signed_distance`]).
//!
//! # Radii
//!
//! Approximate adult values (both sexes pooled, rounded to 5 mm), derived from the means of the
//! 2012 Anthropometric Survey of U.S. Army Personnel (ANSUR II; Gordon et al., NATICK/TR-15/007,
//! 2014), the same kind of data NASA-STD-3000 vol. I §3 tabulates. They are approximations of
//! an average body, not measurements of SMPL's mean shape, and not fitted to any data set:
//!
//! - **Limbs** (near-circular cross-sections): circumference / 2π at mid-segment. Upper arm:
//!   biceps circumference ≈ 0.32 m → 0.05 m. Forearm: ≈ 0.27 m below the elbow, ≈ 0.17 m at
//!   the wrist → 0.04 m. Thigh: ≈ 0.55 m
//!   at mid-thigh → 0.08 m. Shin: calf ≈ 0.38 m, ankle ≈ 0.23 m → 0.05 m. Foot: ankle to 1.3 ×
//!   ankle → toe-joint distance, half the foot height → 0.035 m. Neck: ≈ 0.37 m → 0.06 m.
//!   Head: circumference ≈ 0.56 m → 0.09 m.
//! - **Hand** (flat: ≈ 0.085 m broad, ≈ 0.03 m thick at the knuckles, ≈ 0.04 m at the thenar):
//!   half the **thickness** → 0.02 m, not circumference / 2π (≈ 0.035 m), which would make two
//!   palms pressed together (claps, clasped hands) overlap by several centimetres. Extended to
//!   1.6 × the wrist → hand-joint distance (the SMPL hand joint sits near the knuckles), i.e.
//!   to the middle of the fingers.
//! - **Trunk** (elliptical, wider than deep): half the **depth**, so the capsule stays inside
//!   the body sideways and a capsule "penetration" is a real one; a forearm that only grazes
//!   the flank is missed rather than a relaxed arm hanging beside the ribs being counted.
//!   Chest depth ≈ 0.25 m → 0.12 m; waist/abdominal depth ≈ 0.22 m → 0.11 m; pelvis (hip
//!   joints to hip joints, plus radius ≈ half the hip breadth of ≈ 0.35 m) → 0.10 m; the upper
//!   chest between the shoulders → 0.09 m; the collar/shoulder region → 0.06 m.
//!
//! Capsules overlap each other at the joints (as the mesh is continuous there); only
//! [`penetration_targets`] decides which overlaps count.

/// Body region of a capsule (for the exclusion rule and for reports).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BodyPart {
    Torso,
    Head,
    /// Collar → shoulder joint: where an arm attaches to the trunk.
    Shoulder,
    UpperArm,
    Forearm,
    Hand,
    Thigh,
    Shin,
    Foot,
}

/// Side of the body (SMPL's left is +X in the rest pose, [`crate::conventions`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    Centre,
    Left,
    Right,
}

/// One capsule of the body: points within `radius_m` of `P(s) = J[joint_a] + s·(J[joint_b] −
/// J[joint_a])`, `s ∈ [start, end]` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub name: &'static str,
    /// SMPL 24 joint index of `A`.
    pub joint_a: usize,
    /// SMPL 24 joint index of `B`.
    pub joint_b: usize,
    /// Segment start on the `A → B` line (0 = at `A`).
    pub start: f64,
    /// Segment end on the `A → B` line (1 = at `B`; `start == end` is a sphere).
    pub end: f64,
    /// Radius in metres.
    pub radius_m: f64,
    pub part: BodyPart,
    pub side: Side,
}

/// Table-row constructor: one positional row per capsule keeps [`CAPSULES`] readable.
#[allow(clippy::too_many_arguments)]
const fn cap(
    name: &'static str,
    joint_a: usize,
    joint_b: usize,
    start: f64,
    end: f64,
    radius_m: f64,
    part: BodyPart,
    side: Side,
) -> Capsule {
    Capsule {
        name,
        joint_a,
        joint_b,
        start,
        end,
        radius_m,
        part,
        side,
    }
}

use crate::vec3::{dot, lerp, sub};
use BodyPart::*;
use Side::*;

/// Number of capsules in [`CAPSULES`].
pub const NUM_CAPSULES: usize = 21;

/// The capsule body of SMPL 24 (joint indices: 0 pelvis, 1/2 hips, 3/6/9 spine1–3, 4/5 knees,
/// 7/8 ankles, 10/11 feet, 12 neck, 13/14 collars, 15 head, 16/17 shoulders, 18/19 elbows,
/// 20/21 wrists, 22/23 hands; left before right). Radii: module docs.
#[rustfmt::skip]
pub const CAPSULES: [Capsule; NUM_CAPSULES] = [
    cap("pelvis",         1,  2, 0.0, 1.0, 0.100, Torso,    Centre),
    cap("lower_back",     0,  3, 0.0, 1.0, 0.110, Torso,    Centre),
    cap("abdomen",        3,  6, 0.0, 1.0, 0.110, Torso,    Centre),
    cap("chest",          6,  9, 0.0, 1.0, 0.120, Torso,    Centre),
    cap("upper_chest",    9, 12, 0.0, 1.0, 0.090, Torso,    Centre),
    cap("neck",          12, 15, 0.0, 1.0, 0.060, Head,     Centre),
    cap("head",          12, 15, 1.8, 1.8, 0.090, Head,     Centre),
    cap("left_collar",   13, 16, 0.0, 1.0, 0.060, Shoulder, Left),
    cap("right_collar",  14, 17, 0.0, 1.0, 0.060, Shoulder, Right),
    cap("left_upper_arm",  16, 18, 0.0, 1.0, 0.050, UpperArm, Left),
    cap("right_upper_arm", 17, 19, 0.0, 1.0, 0.050, UpperArm, Right),
    cap("left_forearm",  18, 20, 0.0, 1.0, 0.040, Forearm,  Left),
    cap("right_forearm", 19, 21, 0.0, 1.0, 0.040, Forearm,  Right),
    cap("left_hand",     20, 22, 0.0, 1.6, 0.020, Hand,     Left),
    cap("right_hand",    21, 23, 0.0, 1.6, 0.020, Hand,     Right),
    cap("left_thigh",     1,  4, 0.0, 1.0, 0.080, Thigh,    Left),
    cap("right_thigh",    2,  5, 0.0, 1.0, 0.080, Thigh,    Right),
    cap("left_shin",      4,  7, 0.0, 1.0, 0.050, Shin,     Left),
    cap("right_shin",     5,  8, 0.0, 1.0, 0.050, Shin,     Right),
    cap("left_foot",      7, 10, 0.0, 1.3, 0.035, Foot,     Left),
    cap("right_foot",     8, 11, 0.0, 1.3, 0.035, Foot,     Right),
];

/// Indices into [`CAPSULES`] of the capsules whose points the penetration metric and guidance
/// sample and move: left/right forearm and hand.
pub const ARM_SOURCES: [usize; 4] = [11, 12, 13, 14];

/// Whether capsule `target` is tested against points of capsule `source` (a forearm or hand,
/// [`ARM_SOURCES`]). Kinematic neighbours never count: the own arm (upper arm, forearm, hand)
/// and the collar/shoulder region it hangs from overlap it by construction at the joints. The
/// targets are the trunk, neck and head, both thighs, and the other arm including its collar.
/// Shins and feet are not targets (hands reach them only in floor work, where contact is
/// intended and a few centimetres of capsule error would read as penetration).
pub fn is_target(source: usize, target: usize) -> bool {
    let (s, t) = (&CAPSULES[source], &CAPSULES[target]);
    let own_arm = matches!(t.part, Shoulder | UpperArm | Forearm | Hand) && t.side == s.side;
    match t.part {
        Torso | Head | Thigh => true,
        Shoulder | UpperArm | Forearm | Hand => !own_arm,
        Shin | Foot => false,
    }
}

/// The capsules tested against points of `source` ([`is_target`]), as indices into [`CAPSULES`].
pub fn penetration_targets(source: usize) -> Vec<usize> {
    (0..NUM_CAPSULES)
        .filter(|&t| is_target(source, t))
        .collect()
}

/// Every `(source, target)` pair the penetration measures test, sources from [`ARM_SOURCES`]:
/// the flat list a batched implementation gathers.
pub fn penetration_pairs() -> Vec<(usize, usize)> {
    ARM_SOURCES
        .iter()
        .flat_map(|&s| penetration_targets(s).into_iter().map(move |t| (s, t)))
        .collect()
}

/// Joint `j` of frame `t` of a flat `(T, 24, 3)` array.
#[inline]
pub fn joint(joints: &[f64], t: usize, j: usize) -> [f64; 3] {
    let o = (t * 24 + j) * 3;
    [joints[o], joints[o + 1], joints[o + 2]]
}

/// The 24 joints of frame `t` of a flat `(T, 24, 3)` array.
pub fn frame_joints(joints: &[f64], t: usize) -> [[f64; 3]; 24] {
    std::array::from_fn(|j| joint(joints, t, j))
}

/// World endpoints `(P(start), P(end))` of `capsule` for one frame's 24 joints.
pub fn capsule_endpoints(joints: &[[f64; 3]; 24], capsule: &Capsule) -> ([f64; 3], [f64; 3]) {
    let (a, b) = (joints[capsule.joint_a], joints[capsule.joint_b]);
    (lerp(a, b, capsule.start), lerp(a, b, capsule.end))
}

/// Squared distance from `p` to the segment `a–b` (a point if `a == b`).
pub fn point_segment_distance_sq(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let s = if len2 > 1e-24 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = sub(p, lerp(a, b, s));
    dot(d, d)
}

/// Squared distance between segments `p1–q1` and `p2–q2` (degenerate segments are points).
pub fn segment_distance_sq(p1: [f64; 3], q1: [f64; 3], p2: [f64; 3], q2: [f64; 3]) -> f64 {
    let (c1, c2) = segment_closest_points(p1, q1, p2, q2);
    let d = sub(c1, c2);
    dot(d, d)
}

/// The closest points `(on p1–q1, on p2–q2)` of two segments (the construction of Ericson,
/// *Real-Time Collision Detection*, §5.1.9; degenerate segments are points).
pub fn segment_closest_points(
    p1: [f64; 3],
    q1: [f64; 3],
    p2: [f64; 3],
    q2: [f64; 3],
) -> ([f64; 3], [f64; 3]) {
    const EPS: f64 = 1e-12;
    let (d1, d2, r) = (sub(q1, p1), sub(q2, p2), sub(p1, p2));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    if a <= EPS && e <= EPS {
        return (p1, p2);
    }
    let (s, t);
    if a <= EPS {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = dot(d1, r);
        if e <= EPS {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > EPS {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    (lerp(p1, q1, s), lerp(p2, q2, t))
}

/// Signed distance (metres) from `point` to the surface of `capsule` posed by one frame's 24
/// joints: negative inside, `−radius_m` on the axis.
pub fn signed_distance(point: [f64; 3], joints: &[[f64; 3]; 24], capsule: &Capsule) -> f64 {
    let (a, b) = capsule_endpoints(joints, capsule);
    point_segment_distance_sq(point, a, b).sqrt() - capsule.radius_m
}

/// A sample on the axis of a forearm or hand capsule: the centre of a cross-section sphere of
/// radius `radius_m`, the arm's surface around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmSample {
    /// World position on the capsule axis.
    pub pos: [f64; 3],
    /// Radius of the capsule the sample belongs to (metres).
    pub radius_m: f64,
    /// Index into [`CAPSULES`] of that capsule (one of [`ARM_SOURCES`]).
    pub capsule: usize,
    /// Line parameter `s` of the sample on its capsule (`P(s)`, module docs).
    pub s: f64,
}

impl ArmSample {
    /// How deep the sample's cross-section sphere reaches into `target` (metres, > 0 when the
    /// arm's surface is inside it): `radius_m − signed_distance(pos, target)`.
    pub fn depth(&self, joints: &[[f64; 3]; 24], target: &Capsule) -> f64 {
        self.radius_m - signed_distance(self.pos, joints, target)
    }

    /// Deepest [`ArmSample::depth`] over the sample's [`penetration_targets`] (negative: the
    /// clearance to the nearest one).
    pub fn max_depth(&self, joints: &[[f64; 3]; 24]) -> f64 {
        (0..NUM_CAPSULES)
            .filter(|&t| is_target(self.capsule, t))
            .map(|t| self.depth(joints, &CAPSULES[t]))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// Samples on the axes of the forearm and hand capsules ([`ARM_SOURCES`], in that order) of one
/// frame: `samples_per_segment` points per capsule, evenly spaced from `start` to `end`
/// inclusive (one sample: the middle). These are the points penetration guidance moves and the
/// penetration metric counts.
pub fn hand_arm_points(joints: &[[f64; 3]; 24], samples_per_segment: usize) -> Vec<ArmSample> {
    let mut out = Vec::with_capacity(ARM_SOURCES.len() * samples_per_segment);
    for &c in &ARM_SOURCES {
        let cap = &CAPSULES[c];
        let (a, b) = (joints[cap.joint_a], joints[cap.joint_b]);
        for i in 0..samples_per_segment {
            let f = if samples_per_segment == 1 {
                0.5
            } else {
                i as f64 / (samples_per_segment - 1) as f64
            };
            let s = cap.start + f * (cap.end - cap.start);
            out.push(ArmSample {
                pos: lerp(a, b, s),
                radius_m: cap.radius_m,
                capsule: c,
                s,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Skeleton;

    fn rest() -> [[f64; 3]; 24] {
        let r = Skeleton::smpl24().rest_positions();
        std::array::from_fn(|j| r[j])
    }

    #[test]
    fn table_is_consistent() {
        for (i, c) in CAPSULES.iter().enumerate() {
            assert!(c.joint_a < 24 && c.joint_b < 24, "{}", c.name);
            assert!(c.start <= c.end && c.radius_m > 0.0 && c.radius_m < 0.2);
            let names = CAPSULES.iter().filter(|d| d.name == c.name).count();
            assert_eq!(names, 1, "{}", c.name);
            // Left/right capsules mirror each other.
            if let Some(rest) = c.name.strip_prefix("left_") {
                let r = CAPSULES
                    .iter()
                    .position(|d| d.name == format!("right_{rest}"))
                    .unwrap();
                let m = &CAPSULES[r];
                assert_eq!(r, i + 1);
                assert_eq!(crate::skeleton::SMPL24_MIRROR[c.joint_a], m.joint_a);
                assert_eq!(crate::skeleton::SMPL24_MIRROR[c.joint_b], m.joint_b);
                assert_eq!((c.start, c.end, c.radius_m), (m.start, m.end, m.radius_m));
                assert_eq!((c.side, m.side), (Side::Left, Side::Right));
            }
        }
        for &s in &ARM_SOURCES {
            assert!(matches!(
                CAPSULES[s].part,
                BodyPart::Forearm | BodyPart::Hand
            ));
        }
    }

    #[test]
    fn exclusions_follow_the_chain() {
        let names = |s: usize| -> Vec<&str> {
            penetration_targets(s)
                .into_iter()
                .map(|t| CAPSULES[t].name)
                .collect()
        };
        let lf = names(11);
        for own in ["left_collar", "left_upper_arm", "left_forearm", "left_hand"] {
            assert!(!lf.contains(&own), "{own}");
        }
        for other in [
            "chest",
            "head",
            "neck",
            "left_thigh",
            "right_thigh",
            "right_collar",
            "right_forearm",
            "right_hand",
        ] {
            assert!(lf.contains(&other), "{other}");
        }
        assert!(!lf.contains(&"left_shin") && !lf.contains(&"right_foot"));
        assert_eq!(names(13), lf);
        assert_eq!(penetration_pairs().len(), 4 * lf.len());
    }

    #[test]
    fn signed_distance_on_axis_is_minus_radius() {
        let j = rest();
        for c in &CAPSULES {
            let (a, b) = capsule_endpoints(&j, c);
            for s in [0.0, 0.3, 1.0] {
                let p = lerp(a, b, s);
                assert!((signed_distance(p, &j, c) + c.radius_m).abs() < 1e-12);
            }
        }
        // Head sphere: 1.8 × (neck → head) from the neck; a point 1 m above it is 1 m − r away.
        let head = &CAPSULES[6];
        let (c, _) = capsule_endpoints(&j, head);
        let p = [c[0], c[1] + 1.0, c[2]];
        assert!((signed_distance(p, &j, head) - (1.0 - head.radius_m)).abs() < 1e-12);
    }

    #[test]
    fn rest_pose_arms_are_clear() {
        let j = rest();
        let pts = hand_arm_points(&j, 8);
        assert_eq!(pts.len(), 32);
        for p in &pts {
            assert!(p.max_depth(&j) < 0.0, "{p:?}: {}", p.max_depth(&j));
        }
        // The hand capsule reaches past the hand joint.
        let last = pts[3 * 8 - 1];
        assert_eq!(last.capsule, 13);
        assert!((last.s - 1.6).abs() < 1e-12);
        assert!(last.pos[0] > j[22][0]);
    }

    #[test]
    fn segment_distances() {
        let d = segment_distance_sq([0.0; 3], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, 2.0, 0.0]);
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance_sq([0.0; 3], [1.0, 0.0, 0.0], [0.5, -1.0, 1.0], [0.5, 1.0, 1.0]);
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance_sq([0.0; 3], [0.0; 3], [3.0, 4.0, 0.0], [3.0, 4.0, 0.0]);
        assert!((d - 25.0).abs() < 1e-12);
        // Parallel segments, offset along their axis.
        let d = segment_distance_sq([0.0; 3], [1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [3.0, 1.0, 0.0]);
        assert!((d - 2.0).abs() < 1e-12);
        let d = point_segment_distance_sq([2.0, 1.0, 0.0], [0.0; 3], [1.0, 0.0, 0.0]);
        assert!((d - 2.0).abs() < 1e-12);
        // Point–segment agrees with the degenerate segment–segment case.
        let (p, a, b) = ([0.3, 0.7, -0.2], [0.1, 0.0, 0.0], [0.5, 1.0, 0.2]);
        let d1 = point_segment_distance_sq(p, a, b);
        let d2 = segment_distance_sq(p, p, a, b);
        assert!((d1 - d2).abs() < 1e-12);
    }
}
