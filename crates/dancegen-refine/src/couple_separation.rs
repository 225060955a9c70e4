//! Keeps two dancers from passing through each other: a smooth horizontal offset of one of them.
//!
//! A generator that places a dancer relative to a partner (the duet follower in its leader's
//! frame) makes centimetre errors in that placement, and at partner-dance distances (pelvis to
//! pelvis 0.9–1.0 m in the CMU salsa takes) they put a trunk, head or leg through the partner.
//! [`separation_offsets`] finds a smooth track of horizontal offsets for the `mover` that takes
//! its body out of the `fixed` dancer's, on the canonical capsule body
//! ([`dancegen_motion::capsule_body::CAPSULES`]).
//!
//! **Our method; ReactDance has no collision handling** (its relative-orientation and contact
//! losses only shape training).
//!
//! - **Hands are exempt** ([`BodyPart::Hand`], on both dancers): partners hold hands and rest a
//!   hand on the other's back or shoulder, so a hand capsule touching the partner is contact, not
//!   penetration. Every other pair (trunk, head, shoulders, arms, legs, feet) counts.
//! - Each round, the deepest overlap of every frame (two radii + [`SeparationConfig::margin_m`]
//!   − axis distance) gives a push of that depth, horizontal, from the fixed dancer's closest
//!   axis point towards the mover's: the smallest move that clears the pair. Where that
//!   direction points towards the partner (an arm round the partner's back, limbs interlocked)
//!   or is vertical, the push is along the pelvis-to-pelvis line instead, so the mover steps
//!   back rather than through, and neighbouring frames do not push opposite ways. The pushes
//!   are Gaussian-smoothed (σ = `sigma_frames`, cut at 3σ, ends held) and added to the offset
//!   track, so the correction never jumps and stays within 3σ of the frames that need it.
//!   Smoothing lowers a peak, so rounds repeat until no capsule pair penetrates or `max_rounds`
//!   is reached.
//! - Only the horizontal root position changes: poses, heights (floor contact) and the fixed
//!   dancer are kept.
//!
//! A **group** ([`group_separation_offsets`] with [`SeparationConfig::group`]) is stricter: its
//! dancers are not partners and never hold hands, so hands count like every other capsule, and
//! two pelvises closer than [`crate::formation::MIN_SEPARATION_M`] horizontally are pushed apart
//! along the line between them even where no capsules touch (the group collision rule of the
//! metrics, group.md P10), so a dancer never stands in another's personal space.

use dancegen_motion::capsule_body::{
    BodyPart, CAPSULES, Capsule, capsule_endpoints, frame_joints, segment_closest_points,
};
use dancegen_motion::smoothing::{Ends, gaussian_smooth};
use dancegen_motion::vec3::{dot, sub};

/// How [`separation_offsets`] works (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeparationConfig {
    /// Gap (metres) the pushes aim for beyond touching, so the smoothed track still clears.
    pub margin_m: f64,
    /// Gaussian σ of the offset track, in frames.
    pub sigma_frames: f64,
    /// Upper bound on push-and-smooth rounds.
    pub max_rounds: usize,
    /// Whether hand capsules are separated too; `false` for a couple (module docs).
    pub separate_hands: bool,
    /// Pelvises closer than this horizontally (metres) are pushed apart as well, to this
    /// distance plus the margin; `None` for a couple, whose partners stand close.
    pub min_root_distance_m: Option<f64>,
}

impl Default for SeparationConfig {
    /// Our choices, not tuned on the evaluation clips: 1 cm margin; σ = 3 frames (0.1 s at
    /// 30 fps), short enough to follow a partner's step, long enough that a one-frame push
    /// becomes a sway; 12 rounds. Each round moves a brief overlap only by the kernel's share of
    /// its push, so an overlap of a few frames is reduced rather than removed: the rounds bound
    /// how fast the follower may be moved. Real couples have brief capsule overlaps too (an arm
    /// round the partner), so removing every one is not the aim.
    fn default() -> Self {
        Self {
            margin_m: 0.01,
            sigma_frames: 3.0,
            max_rounds: 12,
            separate_hands: false,
            min_root_distance_m: None,
        }
    }
}

impl SeparationConfig {
    /// The group's rule (module docs): hands count and pelvises keep
    /// [`crate::formation::MIN_SEPARATION_M`]. Our choices, checked in docs/group-eval.md: a
    /// 5 cm margin rather than 1 cm, because the group metrics' collision body
    /// (`dancegen_metrics::group::CapsuleRadii`: shins 0.07 m, forearms 0.05 m, hands 0.04 m)
    /// is thicker than this module's by up to 2 cm a capsule, so two shins that clear here by
    /// less than 4 cm still touch there; and 30 rounds rather than 12, since each round clears
    /// a one-frame overlap only by the kernel's peak share (about 13 % at σ = 3).
    pub fn group() -> Self {
        Self {
            margin_m: 0.05,
            max_rounds: 30,
            separate_hands: true,
            min_root_distance_m: Some(crate::formation::MIN_SEPARATION_M),
            ..Self::default()
        }
    }
}

/// The deepest overlap of two posed bodies in one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    /// Two radii + margin − axis distance (metres); above the margin, the capsules penetrate.
    pub depth_m: f64,
    /// Unit horizontal `(x, z)` direction that moves the mover away from the fixed dancer.
    pub away: [f64; 2],
}

/// Pelvises closer than this (metres, horizontally) give no direction to step back along.
const PELVIS_AXIS_MIN_M: f64 = 0.05;

/// Whether a capsule takes part in a couple's separation (module docs: hands are exempt).
pub fn is_separated(capsule: &Capsule) -> bool {
    capsule.part != BodyPart::Hand
}

/// Horizontal unit vector of `v`, or `None` if `v` is (nearly) vertical.
fn horizontal_unit(v: [f64; 3]) -> Option<[f64; 2]> {
    let n = v[0].hypot(v[2]);
    (n > 1e-6).then(|| [v[0] / n, v[2] / n])
}

/// A separated capsule posed in one frame, with the sphere that holds it (for a cheap reject).
#[derive(Clone, Copy)]
struct Posed {
    a: [f64; 3],
    b: [f64; 3],
    radius: f64,
    centre: [f64; 3],
    /// Radius of the enclosing sphere around `centre`: half the axis plus the capsule radius.
    bound: f64,
}

/// The separated capsules of one posed body (hands too if `hands`).
fn posed(joints: &[[f64; 3]; 24], hands: bool) -> Vec<Posed> {
    CAPSULES
        .iter()
        .filter(|c| hands || is_separated(c))
        .map(|c| {
            let (a, b) = capsule_endpoints(joints, c);
            let axis = sub(b, a);
            Posed {
                a,
                b,
                radius: c.radius_m,
                centre: [
                    0.5 * (a[0] + b[0]),
                    0.5 * (a[1] + b[1]),
                    0.5 * (a[2] + b[2]),
                ],
                bound: 0.5 * dot(axis, axis).sqrt() + c.radius_m,
            }
        })
        .collect()
}

/// The deepest overlap (with `margin_m`) between the separated capsules of `mover` and `fixed`
/// in one frame under a couple's rule (hands exempt), or `None` if every pair is at least
/// `margin_m` apart.
pub fn deepest_overlap(
    mover: &[[f64; 3]; 24],
    fixed: &[[f64; 3]; 24],
    margin_m: f64,
) -> Option<Overlap> {
    deepest_overlap_under(
        mover,
        fixed,
        &SeparationConfig {
            margin_m,
            ..SeparationConfig::default()
        },
    )
}

/// [`deepest_overlap`] under `config`'s rule: its margin, hands if it separates them, and its
/// pelvis distance, whose shortfall counts as an overlap along the pelvis-to-pelvis line.
pub fn deepest_overlap_under(
    mover: &[[f64; 3]; 24],
    fixed: &[[f64; 3]; 24],
    config: &SeparationConfig,
) -> Option<Overlap> {
    let margin_m = config.margin_m;
    let hands = config.separate_hands;
    let (pm_caps, pf_caps) = (posed(mover, hands), posed(fixed, hands));
    let mut best: Option<(f64, [f64; 3], [f64; 3])> = None;
    for cm in &pm_caps {
        for cf in &pf_caps {
            let c = sub(cm.centre, cf.centre);
            let far = cm.bound + cf.bound + margin_m;
            if dot(c, c) >= far * far {
                continue;
            }
            let reach = cm.radius + cf.radius + margin_m;
            let (pm, pf) = segment_closest_points(cm.a, cm.b, cf.a, cf.b);
            let d = sub(pm, pf);
            let dist_sq = dot(d, d);
            if dist_sq >= reach * reach {
                continue;
            }
            let depth = reach - dist_sq.sqrt();
            if best.is_none_or(|(b, _, _)| depth > b) {
                best = Some((depth, pm, pf));
            }
        }
    }
    let pelvis = sub(mover[0], fixed[0]);
    let pelvis_distance = pelvis[0].hypot(pelvis[2]);
    let axis = (pelvis_distance >= PELVIS_AXIS_MIN_M)
        .then(|| horizontal_unit(pelvis))
        .flatten();
    if let Some(min) = config.min_root_distance_m {
        let depth_m = min + margin_m - pelvis_distance;
        if depth_m > 0.0 && best.is_none_or(|(b, _, _)| depth_m >= b) {
            return Some(Overlap {
                depth_m,
                away: axis.unwrap_or([1.0, 0.0]),
            });
        }
    }
    let (depth_m, pm, pf) = best?;
    let away = match (horizontal_unit(sub(pm, pf)), axis) {
        // An arm reaching round the partner's back: its closest-point push points through
        // the partner, and neighbouring frames push opposite ways; step back instead.
        (Some(c), Some(a)) if c[0] * a[0] + c[1] * a[1] < 0.0 => a,
        (Some(c), _) => c,
        (None, Some(a)) => a,
        (None, None) => [1.0, 0.0],
    };
    Some(Overlap { depth_m, away })
}

/// Horizontal `(x, z)` offsets (metres), one per frame of `mover`, that keep its body out of
/// `fixed`'s (module docs). Both are flat `(T, 24, 3)` world joints in metres, Y up; frames past
/// the shorter of the two get no offset. A mover already clear of the fixed dancer gets zeros.
pub fn separation_offsets(
    mover: &[f64],
    fixed: &[f64],
    config: &SeparationConfig,
) -> Vec<[f64; 2]> {
    let t_mover = mover.len() / 72;
    let t = t_mover.min(fixed.len() / 72);
    let fixed_frames: Vec<[[f64; 3]; 24]> = (0..t).map(|f| frame_joints(fixed, f)).collect();
    let mover_frames: Vec<[[f64; 3]; 24]> = (0..t).map(|f| frame_joints(mover, f)).collect();
    let mut offsets = vec![[0.0f64; 2]; t_mover];
    // Frames to examine: all at first, then those the last round moved (the others keep their
    // verdict: clear).
    let mut examine = vec![true; t];
    for _ in 0..config.max_rounds {
        let mut penetrating = false;
        let pushes: Vec<[f64; 2]> = (0..t)
            .map(|f| {
                if !examine[f] {
                    return [0.0, 0.0];
                }
                let [ox, oz] = offsets[f];
                let moved = mover_frames[f].map(|[x, y, z]| [x + ox, y, z + oz]);
                match deepest_overlap_under(&moved, &fixed_frames[f], config) {
                    Some(o) => {
                        penetrating |= o.depth_m > config.margin_m;
                        [o.away[0] * o.depth_m, o.away[1] * o.depth_m]
                    }
                    None => [0.0, 0.0],
                }
            })
            .collect();
        if !penetrating {
            break;
        }
        examine.fill(false);
        for c in 0..2 {
            let push: Vec<f64> = pushes.iter().map(|p| p[c]).collect();
            for (f, v) in gaussian_smooth(&push, config.sigma_frames, Ends::Hold)
                .into_iter()
                .enumerate()
            {
                if v != 0.0 {
                    offsets[f][c] += v;
                    examine[f] = true;
                }
            }
        }
    }
    offsets
}

/// Sweeps of [`group_separation_offsets`] over all pairs: a push out of one neighbour can put
/// a dancer into another, so the pairs are visited twice.
pub const GROUP_SWEEPS: usize = 2;

/// [`separation_offsets`] for a group: horizontal offsets per dancer and frame that keep every
/// pair's bodies apart. Dancer 0 stays; each later dancer is moved out of every earlier one in
/// turn (on the joints as already moved), over [`GROUP_SWEEPS`] sweeps. `dancers[d]` are flat
/// `(T, 24, 3)` world joints in metres, Y up.
pub fn group_separation_offsets(
    dancers: &[Vec<f64>],
    config: &SeparationConfig,
) -> Vec<Vec<[f64; 2]>> {
    let mut moved: Vec<Vec<f64>> = dancers.to_vec();
    let mut total: Vec<Vec<[f64; 2]>> = dancers
        .iter()
        .map(|d| vec![[0.0; 2]; d.len() / 72])
        .collect();
    for _ in 0..GROUP_SWEEPS {
        for b in 1..dancers.len() {
            for a in 0..b {
                let off = separation_offsets(&moved[b], &moved[a], config);
                for (f, o) in off.iter().enumerate() {
                    if o[0] == 0.0 && o[1] == 0.0 {
                        continue;
                    }
                    for p in moved[b][f * 72..(f + 1) * 72].chunks_exact_mut(3) {
                        p[0] += o[0];
                        p[2] += o[1];
                    }
                    total[b][f][0] += o[0];
                    total[b][f][1] += o[1];
                }
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::skeleton::Skeleton;

    /// The SMPL rest pose (T-pose, arms along ±X) standing at `(x, z)`, `frames` times, flat.
    fn rest_at(x: f64, z: f64, frames: usize) -> Vec<f64> {
        let rest = Skeleton::smpl24().rest_positions();
        let mut v = Vec::new();
        for _ in 0..frames {
            for p in &rest {
                v.extend([p[0] + x, p[1] + 1.0, p[2] + z]);
            }
        }
        v
    }

    fn shifted(joints: &[f64], off: &[[f64; 2]]) -> Vec<f64> {
        let mut out = joints.to_vec();
        for (f, o) in off.iter().enumerate() {
            for j in 0..24 {
                out[(f * 24 + j) * 3] += o[0];
                out[(f * 24 + j) * 3 + 2] += o[1];
            }
        }
        out
    }

    fn penetrating_frames(mover: &[f64], fixed: &[f64]) -> usize {
        (0..mover.len() / 72)
            .filter(|&f| {
                deepest_overlap(&frame_joints(mover, f), &frame_joints(fixed, f), 0.0).is_some()
            })
            .count()
    }

    #[test]
    fn a_dancer_clear_of_the_partner_is_not_moved() {
        let (m, f) = (rest_at(0.0, 1.0, 20), rest_at(0.0, 0.0, 20));
        let off = separation_offsets(&m, &f, &SeparationConfig::default());
        assert_eq!(off.len(), 20);
        assert!(off.iter().all(|o| *o == [0.0, 0.0]));
    }

    #[test]
    fn overlapping_bodies_are_pushed_apart_along_the_line_between_them() {
        // Face to face 0.15 m apart along Z: the trunks interpenetrate.
        let (m, f) = (rest_at(0.0, 0.15, 30), rest_at(0.0, 0.0, 30));
        assert_eq!(penetrating_frames(&m, &f), 30);
        let off = separation_offsets(&m, &f, &SeparationConfig::default());
        assert_eq!(penetrating_frames(&shifted(&m, &off), &f), 0);
        for o in &off {
            // Away from the partner (+Z), not sideways, and not much further than needed: the
            // trunks are 0.24 m thick together.
            // (The SMPL rest pose is not exactly symmetric: a little X.)
            assert!(o[1] > 0.05 && o[1] < 0.3 && o[0].abs() < 0.01, "{o:?}");
        }
    }

    #[test]
    fn hands_may_touch() {
        // Side by side along X in the T-pose: the mover's right hand (−X) meets the fixed
        // dancer's left hand (+X). Wrists are 0.25 m apart, so only the hand capsules (which
        // reach 0.6 × the wrist–hand bone past the hand joint) overlap.
        let rest = Skeleton::smpl24().rest_positions();
        let gap = 2.0 * rest[20][0] + 0.25;
        let (m, f) = (rest_at(gap, 0.0, 5), rest_at(0.0, 0.0, 5));
        let hand_l = &CAPSULES[13];
        let hand_r = &CAPSULES[14];
        assert_eq!((hand_l.part, hand_r.part), (BodyPart::Hand, BodyPart::Hand));
        let (a0, a1) = capsule_endpoints(&frame_joints(&m, 0), hand_r);
        let (b0, b1) = capsule_endpoints(&frame_joints(&f, 0), hand_l);
        let d = dancegen_motion::capsule_body::segment_distance_sq(a0, a1, b0, b1).sqrt();
        assert!(
            d < hand_l.radius_m + hand_r.radius_m,
            "hands should touch: {d}"
        );
        let off = separation_offsets(&m, &f, &SeparationConfig::default());
        assert!(off.iter().all(|o| *o == [0.0, 0.0]));
    }

    #[test]
    fn a_brief_collision_gets_a_smooth_local_sway() {
        // 60 frames 1 m apart, except frames 28–31 where the mover stands 0.2 m away.
        let t = 60;
        let mut m = rest_at(0.0, 1.0, t);
        let close = rest_at(0.0, 0.2, 4);
        m[28 * 72..32 * 72].copy_from_slice(&close);
        let f = rest_at(0.0, 0.0, t);
        let off = separation_offsets(&m, &f, &SeparationConfig::default());
        assert_eq!(penetrating_frames(&shifted(&m, &off), &f), 0);
        // Local: nothing beyond 3σ (9 frames) of the collision; smooth: the frame-to-frame change stays a fraction of the
        // peak instead of a one-frame jump.
        assert!(off[..19].iter().chain(&off[41..]).all(|o| *o == [0.0, 0.0]));
        let peak = off.iter().map(|o| o[1]).fold(0.0, f64::max);
        let step = off
            .windows(2)
            .map(|w| (w[1][1] - w[0][1]).abs())
            .fold(0.0, f64::max);
        assert!(peak > 0.02 && step < 0.5 * peak, "peak {peak} step {step}");
    }

    #[test]
    fn an_arm_round_the_partners_back_steps_back_instead_of_through() {
        // The mover 0.6 m in front (+Z) of the fixed dancer, its left arm reaching 0.2 m
        // behind the fixed dancer's chest: the closest-point push would point further back
        // (−Z, through the partner); the mover steps back along +Z instead.
        let mut m = frame_joints(&rest_at(0.0, 0.6, 1), 0);
        let f = frame_joints(&rest_at(0.0, 0.0, 1), 0);
        let chest = f[9];
        m[18] = [chest[0] + 0.1, chest[1], chest[2] - 0.1];
        m[20] = [chest[0], chest[1], chest[2] - 0.2];
        m[22] = [chest[0] - 0.05, chest[1], chest[2] - 0.22];
        let o = deepest_overlap(&m, &f, 0.0).expect("the arm is in the chest");
        assert!(o.away[1] > 0.99, "{o:?}");
    }

    /// Smallest horizontal pelvis distance over the frames of two flat clips.
    fn closest_pelvises(a: &[f64], b: &[f64]) -> f64 {
        (0..a.len() / 72)
            .map(|f| {
                let (p, q) = (frame_joints(a, f)[0], frame_joints(b, f)[0]);
                (p[0] - q[0]).hypot(p[2] - q[2])
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_group_keeps_pelvises_apart_where_no_capsules_touch() {
        // Front to back 0.3 m apart along Z: the trunks clear (0.24 m thick together), so a
        // couple is left alone, but the pelvises are closer than the group's 0.45 m.
        let (m, f) = (rest_at(0.0, 0.3, 20), rest_at(0.0, 0.0, 20));
        let couple = separation_offsets(&m, &f, &SeparationConfig::default());
        assert!(couple.iter().all(|o| *o == [0.0, 0.0]), "{:?}", couple[0]);
        let group = SeparationConfig::group();
        let off = separation_offsets(&m, &f, &group);
        let d = closest_pelvises(&shifted(&m, &off), &f);
        let min = crate::formation::MIN_SEPARATION_M;
        assert!(d >= min && d < min + 2.0 * group.margin_m, "{d}");
        assert!(
            off.iter().all(|o| o[1] > 0.0 && o[0].abs() < 0.01),
            "{:?}",
            off[0]
        );
    }

    #[test]
    fn a_group_separates_hands_a_couple_may_join() {
        // The hands-may-touch placement: a couple keeps it, a group moves the dancers apart.
        let rest = Skeleton::smpl24().rest_positions();
        let gap = 2.0 * rest[20][0] + 0.25;
        let (m, f) = (rest_at(gap, 0.0, 5), rest_at(0.0, 0.0, 5));
        let group = SeparationConfig::group();
        let off = separation_offsets(&m, &f, &group);
        let moved = shifted(&m, &off);
        assert!(off.iter().all(|o| o[0] > 0.0), "{:?}", off[0]);
        for k in 0..5 {
            assert!(
                deepest_overlap_under(
                    &frame_joints(&moved, k),
                    &frame_joints(&f, k),
                    &SeparationConfig {
                        margin_m: 0.0,
                        ..group
                    }
                )
                .is_none()
            );
        }
    }

    #[test]
    fn coincident_bodies_push_along_x_and_near_ones_along_their_closest_points() {
        let mut a = frame_joints(&rest_at(0.0, 0.0, 1), 0);
        let b = a;
        // Identical bodies: the closest points coincide; pelvis to pelvis is zero too.
        let o = deepest_overlap(&a, &b, 0.0).expect("same body overlaps");
        assert_eq!(o.away, [1.0, 0.0]);
        for j in &mut a {
            j[2] += 0.01;
        }
        let o = deepest_overlap(&a, &b, 0.0).expect("still overlapping");
        assert!(o.away[1] > 0.99, "{o:?}");
    }
}
