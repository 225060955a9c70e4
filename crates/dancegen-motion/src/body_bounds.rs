//! What a motion must be to be read as one body dancing: finite, near the origin, and with
//! bones that keep their length.
//!
//! Every motion reader runs this on the world joint positions it produced, so a file with a
//! joint at 1e30 m, or joints that are not one skeleton (two people interleaved, random
//! numbers of the right shape), is refused with the file, the frame and the joint instead of
//! being danced, scored or rendered. The bounds are deliberately loose: they catch what is
//! not a body, not a body moving badly (noisy generated joints must still be scored).

/// The farthest a joint may be from the origin, metres. A dance floor is tens of metres; even
/// a motion that walks for an hour (5 km at a brisk pace) stays inside. Beyond it, values are
/// garbage (1e30 from a bad export) and would overflow the float32 maths downstream.
pub const MAX_JOINT_DISTANCE_M: f64 = 10_000.0;

/// The most a bone's length may differ in one frame from its median over the motion, metres.
/// A body's bones keep their length, and motion computed from rotations (SMPL, BVH without
/// joint translations) keeps it exactly. Joint positions predicted directly are noisier: the
/// reference metric fixtures' noisy generated clips change a bone by up to 0.29 m
/// (`shared/fixtures/metrics/inputs/generated/gen04_R3_noise_*`), and must still be scored;
/// AIST++'s keypoints triangulated from video change one by up to 0.28 m
/// (`python3 tools/bone_stretch.py`). A change of more than a metre (about half a body
/// height) is no longer one body.
pub const MAX_BONE_STRETCH_M: f64 = 1.0;

/// A motion refused by [`check_body`]: where, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyError {
    /// 0-based frame.
    pub frame: usize,
    /// 0-based joint index.
    pub joint: usize,
    /// The joint's name when the skeleton has names.
    pub joint_name: Option<String>,
    pub problem: String,
}

impl std::fmt::Display for BodyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.joint_name {
            Some(name) => write!(
                f,
                "frame {}, joint {} ({name}): {}",
                self.frame, self.joint, self.problem
            ),
            None => write!(
                f,
                "frame {}, joint {}: {}",
                self.frame, self.joint, self.problem
            ),
        }
    }
}

impl std::error::Error for BodyError {}

/// How [`check_body`] reads the positions it is given.
#[derive(Clone, Copy, Debug)]
pub struct BodyUnits {
    /// File units per metre (1 for metres, 100 for a centimetre BVH). The bounds are in metres.
    pub per_metre: f64,
}

impl BodyUnits {
    pub const METRES: BodyUnits = BodyUnits { per_metre: 1.0 };
}

/// Checks `positions` (`frames × parents.len() × 3`, row-major) of one body: every value
/// finite, every joint within [`MAX_JOINT_DISTANCE_M`] of the origin, and every bone (a joint
/// and its parent; `parents[j] < 0` for a root) within [`MAX_BONE_STRETCH_M`] of its median
/// length. `parents` may be `None` when the skeleton is unknown (a joint array of an unknown
/// layout): then only the first two checks apply. `names`, when given, name the joint in the
/// error. The first problem found, in frame order, is returned.
pub fn check_body<T: Copy + Into<f64>>(
    positions: &[T],
    joints: usize,
    parents: Option<&[i32]>,
    names: Option<&[&str]>,
    units: BodyUnits,
) -> Result<(), BodyError> {
    if joints == 0 {
        return Ok(());
    }
    let at = |frame: usize, joint: usize, problem: String| BodyError {
        frame,
        joint,
        joint_name: names.and_then(|n| n.get(joint)).map(|s| s.to_string()),
        problem,
    };
    let max_distance = MAX_JOINT_DISTANCE_M * units.per_metre;
    for (i, p) in positions.chunks_exact(3).enumerate() {
        let (x, y, z) = (p[0].into(), p[1].into(), p[2].into());
        let (frame, joint) = (i / joints, i % joints);
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(at(
                frame,
                joint,
                format!("position [{x}, {y}, {z}] is not finite"),
            ));
        }
        let distance = distance_from_origin([x, y, z]);
        if distance > max_distance {
            return Err(at(
                frame,
                joint,
                format!(
                    "is {:.4e} m from the origin; a dance stays within {MAX_JOINT_DISTANCE_M} m \
                     (MAX_JOINT_DISTANCE_M)",
                    distance / units.per_metre
                ),
            ));
        }
    }
    let Some(parents) = parents else {
        return Ok(());
    };
    let frames = positions.len() / (3 * joints);
    let point = |frame: usize, joint: usize| -> [f64; 3] {
        let o = (frame * joints + joint) * 3;
        [
            positions[o].into(),
            positions[o + 1].into(),
            positions[o + 2].into(),
        ]
    };
    let max_stretch = MAX_BONE_STRETCH_M * units.per_metre;
    let mut lengths = Vec::with_capacity(frames);
    let mut worst: Option<(usize, usize, f64, f64)> = None;
    for (joint, &parent) in parents.iter().enumerate().take(joints) {
        let Ok(parent) = usize::try_from(parent) else {
            continue;
        };
        if parent >= joints {
            continue;
        }
        lengths.clear();
        lengths.extend((0..frames).map(|f| {
            let (a, b) = (point(f, joint), point(f, parent));
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        }));
        let median = median_of(&lengths);
        if let Some(frame) = lengths
            .iter()
            .position(|&l| (l - median).abs() > max_stretch)
            && worst.is_none_or(|(f, ..)| frame < f)
        {
            worst = Some((frame, joint, lengths[frame], median));
        }
    }
    match worst {
        Some((frame, joint, length, median)) => Err(at(
            frame,
            joint,
            format!(
                "the bone to its parent is {:.3} m long here and {:.3} m in most frames; a \
                 body's bones change by at most {MAX_BONE_STRETCH_M} m (MAX_BONE_STRETCH_M), so \
                 this is not one body",
                length / units.per_metre,
                median / units.per_metre
            ),
        )),
        None => Ok(()),
    }
}

/// `|p|` without overflow for finite coordinates (1e200 squared is infinite in f64).
pub fn distance_from_origin(p: [f64; 3]) -> f64 {
    if !p.iter().all(|v| v.is_finite()) {
        // NaN when any coordinate is NaN, infinity otherwise.
        return p.iter().map(|v| v.abs()).sum();
    }
    let largest = p.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if largest == 0.0 {
        return 0.0;
    }
    largest * p.iter().map(|v| (v / largest).powi(2)).sum::<f64>().sqrt()
}

/// The median of `values` (the lower middle for an even count); 0 for none.
fn median_of(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    let mid = (v.len() - 1) / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::{SMPL24_NAMES, SMPL24_OFFSETS, SMPL24_PARENTS};

    /// `frames` frames of the SMPL rest pose (joints from the offsets), walking along x.
    fn walking(frames: usize) -> Vec<f32> {
        let mut rest = [[0.0f64; 3]; 24];
        for j in 1..24 {
            let p = SMPL24_PARENTS[j] as usize;
            for k in 0..3 {
                rest[j][k] = rest[p][k] + SMPL24_OFFSETS[j][k];
            }
        }
        let mut out = Vec::new();
        for f in 0..frames {
            for r in rest {
                out.extend([(r[0] + 0.01 * f as f64) as f32, r[1] as f32, r[2] as f32]);
            }
        }
        out
    }

    fn check(p: &[f32]) -> Result<(), BodyError> {
        check_body(
            p,
            24,
            Some(&SMPL24_PARENTS),
            Some(&SMPL24_NAMES),
            BodyUnits::METRES,
        )
    }

    #[test]
    fn distances_do_not_overflow() {
        assert_eq!(distance_from_origin([3.0, 4.0, 0.0]), 5.0);
        assert_eq!(distance_from_origin([0.0; 3]), 0.0);
        let d = distance_from_origin([1e200, 1e200, 0.0]);
        assert!((d / (std::f64::consts::SQRT_2 * 1e200) - 1.0).abs() < 1e-12);
        assert!(distance_from_origin([f64::NAN, 0.0, 0.0]).is_nan());
        assert_eq!(
            distance_from_origin([1.0, f64::NEG_INFINITY, 0.0]),
            f64::INFINITY
        );
    }

    #[test]
    fn a_body_passes() {
        assert_eq!(check(&walking(30)), Ok(()));
    }

    #[test]
    fn a_far_joint_is_named_with_its_frame() {
        let mut p = walking(30);
        p[(12 * 24 + 20) * 3 + 1] = 1e30;
        let e = check(&p).unwrap_err();
        assert_eq!((e.frame, e.joint), (12, 20));
        assert_eq!(e.joint_name.as_deref(), Some(SMPL24_NAMES[20]));
        assert!(e.to_string().contains("1.0000e30 m from the origin"), "{e}");
        // Just inside the bound passes: a whole body 9.9 km away.
        let far: Vec<f32> = walking(3)
            .iter()
            .map(|v| v + 9_900.0 / 3f32.sqrt())
            .collect();
        assert_eq!(check(&far), Ok(()));
    }

    #[test]
    fn nan_and_infinity_are_refused() {
        let mut p = walking(5);
        p[(3 * 24 + 7) * 3] = f32::NAN;
        let e = check(&p).unwrap_err();
        assert_eq!((e.frame, e.joint), (3, 7));
        assert!(e.problem.contains("not finite"));
        let mut p = walking(5);
        p[5] = f32::INFINITY;
        assert!(check(&p).is_err());
    }

    #[test]
    fn a_bone_that_stretches_past_the_tolerance_is_not_one_body() {
        // The left wrist (20) is moved 1.5 m up, 1.3 m farther from its elbow, in frame 8.
        let mut p = walking(20);
        p[(8 * 24 + 20) * 3 + 1] += 1.5;
        let e = check(&p).unwrap_err();
        assert_eq!((e.frame, e.joint), (8, 20));
        assert!(e.problem.contains("not one body"), "{e}");
        // Noise as large as the reference's noisy fixtures (0.3 m) is still a body.
        let mut p = walking(20);
        p[(8 * 24 + 20) * 3 + 1] += 0.3;
        assert_eq!(check(&p), Ok(()));
        // Without parents only the position bounds apply.
        let mut p = walking(20);
        p[(8 * 24 + 20) * 3 + 1] += 5.0;
        assert_eq!(check_body(&p, 24, None, None, BodyUnits::METRES), Ok(()));
    }

    #[test]
    fn the_first_frame_with_a_problem_is_reported() {
        let mut p = walking(20);
        p[(15 * 24 + 4) * 3] += 2.0;
        p[(6 * 24 + 18) * 3] += 2.0;
        let e = check(&p).unwrap_err();
        assert_eq!((e.frame, e.joint), (6, 18));
    }

    #[test]
    fn units_scale_the_bounds() {
        let cm: Vec<f32> = walking(10).iter().map(|v| v * 100.0).collect();
        let units = BodyUnits { per_metre: 100.0 };
        assert_eq!(
            check_body(&cm, 24, Some(&SMPL24_PARENTS), None, units),
            Ok(())
        );
        let mut bad = cm.clone();
        bad[3 * 24 * 3 + 3 * 5] += 150.0;
        let e = check_body(&bad, 24, Some(&SMPL24_PARENTS), None, units).unwrap_err();
        assert_eq!((e.frame, e.joint), (3, 5));
        assert!(e.problem.contains("m long here"), "{e}");
    }
}
