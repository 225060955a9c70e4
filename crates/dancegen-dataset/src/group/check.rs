//! Rejection of composed group samples (group.md §4.6–4.7).

use dancegen_metrics::FRAME_LEN;
use dancegen_metrics::foot_skating::foot_skating_ratio;
use dancegen_metrics::group::{CapsuleRadii, bodies_intersect};
use dancegen_refine::formation::MIN_SEPARATION_M;

/// A composition may add at most this much to a dancer's foot-skating ratio (LODGE's ratio of
/// sliding contact frames, [`foot_skating_ratio`]) over the same warped motion before it was
/// placed; more and the model would learn sliding (group.md §4.6). Our choice.
pub(crate) const MAX_ADDED_SKATING: f64 = 0.10;

/// A joint more than this far below the floor (metres) is a body through the floor.
pub(crate) const FLOOR_TOLERANCE_M: f64 = 0.05;
/// Share of frames that may have a joint under the floor: each member is grounded on its
/// support foot as the solo set is, and floor work (breaking) or a mocap session's tilted
/// floor puts a few frames lower; more than this is a grounding failure. Our choice.
pub(crate) const MAX_UNDER_FLOOR_SHARE: f64 = 0.02;

/// Why a sample was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Reject {
    /// Non-partners' roots closer than [`MIN_SEPARATION_M`].
    TooClose,
    /// Non-partners' capsule bodies intersect.
    Capsules,
    /// The placement made a dancer's feet slide ([`MAX_ADDED_SKATING`]).
    Skating,
    /// A body under the floor.
    Floor,
    /// No formation, segment or warp fitted.
    NoFit,
}

impl Reject {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Reject::TooClose => "roots closer than 0.45 m",
            Reject::Capsules => "capsule bodies intersect",
            Reject::Skating => "feet slide",
            Reject::Floor => "body under the floor",
            Reject::NoFit => "no formation, segment or warp fitted",
        }
    }
}

fn partners(a: usize, b: usize, pairs: &[[usize; 2]]) -> bool {
    pairs
        .iter()
        .any(|p| (p[0] == a && p[1] == b) || (p[0] == b && p[1] == a))
}

/// Checks a placed scene: `joints[d]` is dancer `d`'s flat `(T, 24, 3)` world joints (floor at
/// y = 0), `unplaced_skating[d]` the skating ratio of the same motion before placement.
pub(crate) fn check_scene(
    joints: &[Vec<f64>],
    partner_pairs: &[[usize; 2]],
    unplaced_skating: &[f64],
) -> Result<(), Reject> {
    let n = joints.len();
    let frames = joints
        .iter()
        .map(|j| j.len() / FRAME_LEN)
        .min()
        .unwrap_or(0);
    let radii = CapsuleRadii::default();
    for a in 0..n {
        for b in a + 1..n {
            if partners(a, b, partner_pairs) {
                continue;
            }
            for t in 0..frames {
                let (pa, pb) = (&joints[a][t * FRAME_LEN..], &joints[b][t * FRAME_LEN..]);
                if (pa[0] - pb[0]).hypot(pa[2] - pb[2]) < MIN_SEPARATION_M {
                    return Err(Reject::TooClose);
                }
            }
            if (0..frames).any(|t| bodies_intersect(&joints[a], &joints[b], t, &radii)) {
                return Err(Reject::Capsules);
            }
        }
    }
    for j in joints {
        let under = j
            .chunks_exact(FRAME_LEN)
            .filter(|f| f.iter().skip(1).step_by(3).any(|&y| y < -FLOOR_TOLERANCE_M))
            .count();
        if under as f64 > MAX_UNDER_FLOOR_SHARE * frames.max(1) as f64 {
            return Err(Reject::Floor);
        }
    }
    for (j, &before) in joints.iter().zip(unplaced_skating) {
        if skating(j) > before + MAX_ADDED_SKATING {
            return Err(Reject::Skating);
        }
    }
    Ok(())
}

/// LODGE's foot-skating ratio of world joints; a clip without a foot contact counts as 0.
pub(crate) fn skating(joints: &[f64]) -> f64 {
    let r = foot_skating_ratio(joints, 24).ratio();
    if r.is_nan() { 0.0 } else { r }
}
