//! Group-formation geometry: where dancers stand on the stage and how they get from one place
//! to the next.
//!
//! Pure geometry, no models: templates ([`shapes`]), the user's keyframed formation file
//! ([`keyframes`]), slot assignment between formations ([`assign`]) and collision-free
//! transitions ([`transition`]), all on minimum-jerk paths ([`min_jerk`]). The group
//! composition generator (group.md §4) and the group system's trajectory control both build on
//! it, so the stage frame is stated here once.
//!
//! # Stage frame (the product's contract)
//! - The world is Y-up, metres, 30 fps ([`dancegen_motion::conventions`]). A stage position is
//!   `[x, z]`: world x and world z, with the origin at the stage centre.
//! - The audience looks from +Z towards −Z, so **x runs to the audience's right** and **+z is
//!   downstage** (towards the audience); "upstage" is −z.
//! - A dancer facing the audience faces +Z, the SMPL rest forward
//!   ([`dancegen_motion::conventions::REST_FORWARD`]), so an unrotated body already faces the audience.
//! - "Left to right as the audience sees them" is ascending x ([`order_left_to_right`]).
//!
//! group.md §4.2 writes the stage as Z-up with y upstage; this module uses the world's own
//! Y-up axes instead, so a stage position is a root translation with its height dropped.
//!
//! Trajectories are dancer-major: `trajectories[d][t]` is dancer `d` at frame `t`.

pub mod assign;
pub mod keyframes;
mod keyframes_error;
mod keyframes_json;
pub mod min_jerk;
pub mod shapes;
pub mod transition;

/// Non-partner dancers whose roots come closer than this collide (issue #17; group.md §4.7
/// rejection rule and the collision-TIF definition, P10). Partner pairs are exempt there, but
/// this module has no notion of partners: every pair must keep it.
pub const MIN_SEPARATION_M: f64 = 0.45;

/// Slack on [`MIN_SEPARATION_M`] for floating-point rounding, so a formation built at exactly
/// 0.45 m spacing (e.g. `0.1 + 0.35`) is not rejected for being 1e-17 m short. Far below any
/// distance a dancer could perceive.
pub const SEPARATION_SLACK_M: f64 = 1e-9;

/// A position on the stage, `[x, z]` in metres (stage frame in the module docs).
pub type StagePos = [f64; 2];

/// Euclidean distance between two stage positions.
#[inline]
pub fn distance(a: StagePos, b: StagePos) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Whether two dancers `distance` metres apart collide ([`MIN_SEPARATION_M`] less the
/// rounding slack).
#[inline]
pub fn too_close(distance: f64) -> bool {
    distance < MIN_SEPARATION_M - SEPARATION_SLACK_M
}

/// Dancer indices as the audience sees them from left to right: ascending x, ties broken by
/// ascending z (upstage first) and then by index, so the order is deterministic even for a
/// column. NaN coordinates sort after every number (`f64::total_cmp`) instead of panicking.
pub fn order_left_to_right(positions: &[StagePos]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..positions.len()).collect();
    order.sort_by(|&i, &j| {
        let (p, q) = (positions[i], positions[j]);
        p[0].total_cmp(&q[0])
            .then(p[1].total_cmp(&q[1]))
            .then(i.cmp(&j))
    });
    order
}

/// The closest two dancers of one formation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// The lower dancer index.
    pub a: usize,
    /// The higher dancer index.
    pub b: usize,
    /// Their distance in metres.
    pub distance: f64,
}

/// Where a group's closest approach over time happens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestApproach {
    /// The frame of the closest approach (the first such frame on ties).
    pub frame: usize,
    /// The two dancers and their distance there.
    pub pair: Pair,
}

/// The closest pair of one formation (the first in `(a, b)` order on ties); `None` for fewer
/// than two dancers. Pairs with a NaN distance are never the closest: validate positions first.
pub fn closest_pair(positions: &[StagePos]) -> Option<Pair> {
    let mut best: Option<Pair> = None;
    for a in 0..positions.len() {
        for b in a + 1..positions.len() {
            let d = distance(positions[a], positions[b]);
            if !d.is_nan() && best.is_none_or(|p| d < p.distance) {
                best = Some(Pair { a, b, distance: d });
            }
        }
    }
    best
}

/// The closest approach of any two dancers over trajectories `trajectories[d][t]`; frames are
/// counted up to the shortest trajectory. `None` for fewer than two dancers or no frames.
pub fn min_pairwise_distance(trajectories: &[Vec<StagePos>]) -> Option<ClosestApproach> {
    let frames = trajectories.iter().map(Vec::len).min()?;
    let mut best: Option<ClosestApproach> = None;
    let mut frame_positions = Vec::with_capacity(trajectories.len());
    for frame in 0..frames {
        frame_positions.clear();
        frame_positions.extend(trajectories.iter().map(|path| path[frame]));
        if let Some(pair) = closest_pair(&frame_positions)
            && best.is_none_or(|b| pair.distance < b.pair.distance)
        {
            best = Some(ClosestApproach { frame, pair });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_to_right_is_ascending_x_then_upstage_then_index() {
        let positions = [[1.0, 0.0], [-1.0, 0.0], [0.0, 0.5], [0.0, -0.5], [0.0, 0.5]];
        assert_eq!(order_left_to_right(&positions), vec![1, 3, 2, 4, 0]);
        assert!(order_left_to_right(&[]).is_empty());
        // NaN does not panic and sorts last.
        assert_eq!(
            order_left_to_right(&[[f64::NAN, 0.0], [0.0, 0.0]]),
            vec![1, 0]
        );
    }

    #[test]
    fn closest_pair_and_approach_name_the_place() {
        assert_eq!(closest_pair(&[[0.0, 0.0]]), None);
        let p = closest_pair(&[[0.0, 0.0], [3.0, 0.0], [3.0, 0.5]]).unwrap();
        assert_eq!((p.a, p.b), (1, 2));
        assert!((p.distance - 0.5).abs() < 1e-15);

        let trajectories = vec![
            vec![[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]],
            vec![[2.0, 0.0], [0.3, 0.4], [1.0, 0.0]],
            vec![[-2.0, 0.0], [-2.0, 0.0]],
        ];
        let c = min_pairwise_distance(&trajectories).unwrap();
        assert_eq!(c.frame, 1);
        assert_eq!((c.pair.a, c.pair.b), (0, 1));
        assert!((c.pair.distance - 0.5).abs() < 1e-15);
        assert_eq!(min_pairwise_distance(&[vec![[0.0, 0.0]]]), None);
        assert_eq!(min_pairwise_distance(&[]), None);
    }

    #[test]
    fn separation_threshold_tolerates_rounding_only() {
        assert!(!too_close(0.45));
        assert!(!too_close(0.1 + 0.35 - 1e-12));
        assert!(too_close(0.449));
    }
}
