//! Self-penetration of a solo dancer on the capsule body (our stand-in for Lodge++'s metric).
//!
//! Lodge++ reports a penetration ratio in the style of ProHMR: penetrated vertices over all
//! vertices of the posed SMPL-X mesh, with an SDF (COAP) body (anchors.md A.7: paper only, not in
//! the public code). This project has neither the SMPL-X mesh nor COAP, so this module measures
//! the same idea on the capsule body of [`dancegen_motion::capsule_body`]: **an approximation,
//! not the paper's number.** Values are not comparable with the paper's table; they compare
//! motions with each other under one fixed body.
//!
//! The measured points are the samples of [`dancegen_motion::capsule_body::hand_arm_points`] on the forearm and hand axes
//! (the parts penetration guidance moves), each the centre of a cross-section sphere of the
//! arm's radius. A sample is *penetrating* when that sphere reaches more than
//! [`PENETRATION_TOLERANCE_M`] into any capsule the exclusion rule tests it against
//! ([`dancegen_motion::capsule_body::is_target`]: trunk, neck, head, thighs, the other arm),
//! i.e. when the deepest point of the arm's surface there has signed distance below
//! `−PENETRATION_TOLERANCE_M`.

use dancegen_motion::capsule_body::{frame_joints, hand_arm_points};

use crate::{FeatureError, frame_count};

/// How far (metres) an arm's surface may reach into another capsule before it counts as
/// penetration: 1 cm, the precision of the approximate radii (module docs of
/// [`dancegen_motion::capsule_body`]) and the inflation Duolando uses to call meshes "in
/// contact" (anchors.md A.7), so skin contact is not counted as penetration.
pub const PENETRATION_TOLERANCE_M: f64 = 0.01;

/// Samples per forearm / hand capsule used by `dancegen eval` (32 points per frame; the hand
/// capsule is ≈ 14 cm long, so samples are ≈ 2 cm apart there and ≈ 4 cm on the forearm).
pub const DEFAULT_SAMPLES_PER_SEGMENT: usize = 8;

/// Share (percent) of forearm/hand samples, over all frames, that penetrate another part of
/// the body by more than [`PENETRATION_TOLERANCE_M`] (module docs). `joints` is a flat
/// `(T, 24, 3)` Y-up metre array; `samples_per_segment` ≥ 1 points per capsule
/// ([`DEFAULT_SAMPLES_PER_SEGMENT`]). `None` for zero frames or zero samples.
pub fn capsule_penetration_ratio(
    joints: &[f64],
    samples_per_segment: usize,
) -> Result<Option<f64>, FeatureError> {
    let frames = frame_count(joints)?;
    let (mut inside, mut total) = (0usize, 0usize);
    for t in 0..frames {
        let j = frame_joints(joints, t);
        for p in hand_arm_points(&j, samples_per_segment) {
            total += 1;
            if p.max_depth(&j) > PENETRATION_TOLERANCE_M {
                inside += 1;
            }
        }
    }
    Ok((total > 0).then(|| 100.0 * inside as f64 / total as f64))
}

/// Per frame, the summed penetration depth (metres) of the forearm/hand samples: Σ over samples
/// of `max(0, depth)`, without the tolerance, so the curve is continuous (for plots and for
/// checking the guidance). Same inputs as [`capsule_penetration_ratio`].
pub fn capsule_penetration_depth(
    joints: &[f64],
    samples_per_segment: usize,
) -> Result<Vec<f64>, FeatureError> {
    let frames = frame_count(joints)?;
    Ok((0..frames)
        .map(|t| {
            let j = frame_joints(joints, t);
            hand_arm_points(&j, samples_per_segment)
                .iter()
                .map(|p| p.max_depth(&j).max(0.0))
                .sum()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::skeleton::Skeleton;

    fn flat(frames: &[[[f64; 3]; 24]]) -> Vec<f64> {
        frames.iter().flatten().flatten().copied().collect()
    }

    /// SMPL rest pose (a T-pose) from the skeleton table.
    fn t_pose() -> [[f64; 3]; 24] {
        let r = Skeleton::smpl24().rest_positions();
        std::array::from_fn(|j| r[j])
    }

    /// T-pose with the left forearm bent at the elbow so it points at the chest: elbow stays,
    /// wrist and hand placed on the line from the elbow through the spine3 joint.
    fn forearm_into_torso() -> [[f64; 3]; 24] {
        let mut j = t_pose();
        let (elbow, chest) = (j[18], j[9]);
        let d = [
            chest[0] - elbow[0],
            chest[1] - elbow[1],
            chest[2] - elbow[2],
        ];
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let u = d.map(|v| v / n);
        // Forearm 0.265 m, hand joint 0.088 m further (SMPL rest lengths).
        j[20] = [0, 1, 2].map(|c| elbow[c] + 0.265 * u[c]);
        j[22] = [0, 1, 2].map(|c| elbow[c] + 0.353 * u[c]);
        j
    }

    #[test]
    fn t_pose_has_no_penetration() {
        let j = flat(&[t_pose(); 5]);
        assert_eq!(capsule_penetration_ratio(&j, 8).unwrap(), Some(0.0));
        assert!(
            capsule_penetration_depth(&j, 8)
                .unwrap()
                .iter()
                .all(|&d| d == 0.0)
        );
    }

    #[test]
    fn forearm_through_torso_penetrates() {
        let bent = forearm_into_torso();
        let j = flat(&[t_pose(), bent, bent, t_pose()]);
        let r = capsule_penetration_ratio(&j, 8).unwrap().unwrap();
        // Half the frames are bent; in them part of the left arm's 16 of 32 samples is inside.
        assert!(r > 0.0 && r < 50.0, "{r}");
        let d = capsule_penetration_depth(&j, 8).unwrap();
        assert_eq!(d[0], 0.0);
        assert_eq!(d[3], 0.0);
        assert!(d[1] > 0.1 && d[1] == d[2], "{d:?}");
        // Only the bent frames count: one bent frame alone has twice the ratio.
        let one = capsule_penetration_ratio(&flat(&[bent, t_pose()]), 8)
            .unwrap()
            .unwrap();
        assert!((one - r).abs() < 1e-9);
        let all = capsule_penetration_ratio(&flat(&[bent]), 8)
            .unwrap()
            .unwrap();
        assert!((all - 2.0 * r).abs() < 1e-9, "{all} vs {r}");
    }

    #[test]
    fn bad_input_and_empty() {
        assert!(capsule_penetration_ratio(&[0.0; 71], 8).is_err());
        assert_eq!(capsule_penetration_ratio(&[], 8).unwrap(), None);
        assert_eq!(
            capsule_penetration_ratio(&flat(&[t_pose()]), 0).unwrap(),
            None
        );
        assert!(capsule_penetration_depth(&[], 8).unwrap().is_empty());
    }
}
