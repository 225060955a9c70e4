//! The formation plan of one composed group sample: where each member (a solo dancer or a
//! couple) stands on every frame, with transitions on phrase boundaries (group.md §4.3–4.4).

use dancegen_motion::rng::SplitMix64;
use dancegen_refine::formation::assign::{assign_slots, targets};
use dancegen_refine::formation::shapes::{Shape, positions};
use dancegen_refine::formation::transition::{TransitionKind, plan_transition, swap_targets};
use dancegen_refine::formation::{StagePos, order_left_to_right};

/// Slot jitter σ (metres): group.md §4.3 gives 0.05–0.1 m; we draw σ in that range per sample.
const JITTER_SIGMA_M: (f64, f64) = (0.05, 0.1);
/// Template yaw about the stage centre (group.md §4.3: ±30°).
const TEMPLATE_YAW_RAD: f64 = std::f64::consts::PI / 6.0;
/// Transitions last 2–4 beats (group.md §4.4).
const TRANSITION_BEATS: (usize, usize) = (2, 4);
/// Chance that a phrase boundary starts a transition (our choice: about every other phrase).
const TRANSITION_CHANCE: f64 = 0.6;
/// Among transitions, the share that swap two neighbours (the rest morph to a new template).
const SWAP_CHANCE: f64 = 0.35;
/// Largest translation of the whole formation in a morph (metres; our choice).
const MAX_SHIFT_M: f64 = 0.5;
/// Fastest a planned path may go (metres per second, at the minimum-jerk peak, 1.875 × the
/// mean speed): a brisk dancing walk. A transition that would be faster in 2–4 beats is
/// stretched to up to [`MAX_TRANSITION_BEATS`] or dropped. Our choice.
const MAX_PATH_SPEED_M_S: f64 = 2.0;
/// Longest a stretched transition may last.
const MAX_TRANSITION_BEATS: usize = 8;
/// Peak speed of a minimum-jerk path over its mean speed.
const MIN_JERK_PEAK: f64 = 1.875;
/// Frames per second of the plan (the data set's).
const PLAN_FPS: f64 = 30.0;

/// The paths of a sample's members and what they were made of.
#[derive(Clone, Debug)]
pub(crate) struct Plan {
    /// `paths[member][frame]`.
    pub paths: Vec<Vec<StagePos>>,
    /// Shapes in the order they are held.
    pub shapes: Vec<Shape>,
    /// Kinds of the transitions between them (`direct`, `lateral_swap`, `upstage_pass`).
    pub transitions: Vec<&'static str>,
}

/// Spacing range (metres) of a template: group.md §4.3's 0.9–1.8 m between solo dancers; a
/// couple needs about a metre more (its partners stand 0.15–2.15 m apart, median about 1 m).
pub(crate) fn spacing_range(has_couples: bool) -> (f64, f64) {
    if has_couples { (1.8, 2.6) } else { (0.9, 1.8) }
}

pub(crate) fn uniform(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.next_f64()
}

/// A standard normal draw (Box–Muller).
pub(crate) fn normal(rng: &mut SplitMix64) -> f64 {
    let u = rng.next_f64().max(1e-12);
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A template's slots, jittered and yawed about the centre, shifted by `shift`.
fn template(
    rng: &mut SplitMix64,
    shape: Shape,
    m: usize,
    spacing: f64,
    jitter: f64,
    shift: StagePos,
) -> Option<Vec<StagePos>> {
    let slots = positions(shape, m, spacing).ok()?;
    let yaw = uniform(rng, -TEMPLATE_YAW_RAD, TEMPLATE_YAW_RAD);
    let (s, c) = yaw.sin_cos();
    Some(
        slots
            .into_iter()
            .map(|[x, z]| {
                let (x, z) = (x + jitter * normal(rng), z + jitter * normal(rng));
                [c * x + s * z + shift[0], -s * x + c * z + shift[1]]
            })
            .collect(),
    )
}

fn too_close(slots: &[StagePos], min: f64) -> bool {
    (0..slots.len()).any(|i| {
        (i + 1..slots.len()).any(|j| dancegen_refine::formation::distance(slots[i], slots[j]) < min)
    })
}

/// Plans `m` members over `frames` frames: a template from `shapes`, then at each of
/// `phrase_starts` (frames) maybe a transition of 2–4 beats (`beat_frames` frames per beat).
/// `min_gap` is the smallest slot distance accepted. `None` if no valid first template was
/// found.
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_formation(
    rng: &mut SplitMix64,
    m: usize,
    frames: usize,
    phrase_starts: &[usize],
    beat_frames: f64,
    shapes: &[Shape],
    spacing: (f64, f64),
    min_gap: f64,
) -> Option<Plan> {
    let jitter = uniform(rng, JITTER_SIGMA_M.0, JITTER_SIGMA_M.1);
    let mut first = None;
    for _ in 0..8 {
        let shape = shapes[rng.below(shapes.len())];
        let sp = uniform(rng, spacing.0, spacing.1);
        if let Some(slots) = template(rng, shape, m, sp, jitter, [0.0, 0.0])
            && !too_close(&slots, min_gap)
        {
            first = Some((shape, slots));
            break;
        }
    }
    let (shape, slots) = first?;
    // Members take the slots in a random order.
    let mut perm: Vec<usize> = (0..m).collect();
    for i in (1..m).rev() {
        perm.swap(i, rng.below(i + 1));
    }
    let mut current: Vec<StagePos> = perm.iter().map(|&k| slots[k]).collect();
    let mut plan = Plan {
        paths: vec![Vec::with_capacity(frames); m],
        shapes: vec![shape],
        transitions: Vec::new(),
    };
    let mut t = 0usize;
    let hold = |plan: &mut Plan, at: &[StagePos], until: usize, t: &mut usize| {
        while *t < until {
            for (d, p) in at.iter().enumerate() {
                plan.paths[d].push(*p);
            }
            *t += 1;
        }
    };
    for &start in phrase_starts {
        if start < t || rng.next_f64() >= TRANSITION_CHANCE {
            continue;
        }
        let beats = TRANSITION_BEATS.0 + rng.below(TRANSITION_BEATS.1 - TRANSITION_BEATS.0 + 1);
        let len = (beats as f64 * beat_frames).round() as usize;
        if len < 2 || start + len > frames {
            continue;
        }
        let Some((kind, target, name, shape)) = next_formation(
            rng,
            &current,
            shapes,
            spacing,
            jitter,
            min_gap,
            plan.shapes[plan.shapes.len() - 1],
        ) else {
            continue;
        };
        // Stretch the transition so no path is faster than MAX_PATH_SPEED_M_S (a swap's bow
        // makes its path longer than the straight line; the bound is checked on the result).
        let far = current
            .iter()
            .zip(&target)
            .map(|(a, b)| dancegen_refine::formation::distance(*a, *b))
            .fold(0.0, f64::max);
        let needed = (MIN_JERK_PEAK * far * PLAN_FPS / MAX_PATH_SPEED_M_S).ceil() as usize;
        let len = len.max(needed);
        if len as f64 > MAX_TRANSITION_BEATS as f64 * beat_frames || start + len > frames {
            continue;
        }
        let Ok(paths) = plan_transition(&current, &target, kind, len) else {
            continue;
        };
        let step_max = paths
            .iter()
            .flat_map(|p| {
                p.windows(2)
                    .map(|w| dancegen_refine::formation::distance(w[0], w[1]))
            })
            .fold(0.0, f64::max);
        if step_max * PLAN_FPS > 1.5 * MAX_PATH_SPEED_M_S {
            continue;
        }
        hold(&mut plan, &current, start, &mut t);
        for f in 0..len {
            for (d, p) in paths.iter().enumerate() {
                plan.paths[d].push(p[f]);
            }
        }
        t += len;
        current = target;
        plan.shapes.push(shape);
        plan.transitions.push(name);
    }
    hold(&mut plan, &current, frames, &mut t);
    Some(plan)
}

/// The next formation from `current`: a swap of two neighbours (lateral or upstage pass) or a
/// morph to a new template (Hungarian assignment, maybe shifted).
#[allow(clippy::type_complexity)]
fn next_formation(
    rng: &mut SplitMix64,
    current: &[StagePos],
    shapes: &[Shape],
    spacing: (f64, f64),
    jitter: f64,
    min_gap: f64,
    shape_now: Shape,
) -> Option<(TransitionKind, Vec<StagePos>, &'static str, Shape)> {
    let m = current.len();
    // One member (a single couple) can only move; a swap needs two.
    if m >= 2 && rng.next_f64() < SWAP_CHANCE {
        let order = order_left_to_right(current);
        let k = rng.below(m - 1);
        let (a, b) = (order[k], order[k + 1]);
        let target = swap_targets(current, a, b);
        return Some(if rng.next_f64() < 0.5 {
            (
                TransitionKind::LateralSwap { a, b },
                target,
                "lateral_swap",
                shape_now,
            )
        } else {
            let (behind, front) = if rng.next_f64() < 0.5 { (a, b) } else { (b, a) };
            (
                TransitionKind::UpstagePass { behind, front },
                target,
                "upstage_pass",
                shape_now,
            )
        });
    }
    let shape = shapes[rng.below(shapes.len())];
    let sp = uniform(rng, spacing.0, spacing.1);
    let shift = [
        uniform(rng, -MAX_SHIFT_M, MAX_SHIFT_M),
        uniform(rng, -MAX_SHIFT_M, MAX_SHIFT_M),
    ];
    let slots = template(rng, shape, m, sp, jitter, shift)?;
    if too_close(&slots, min_gap) {
        return None;
    }
    let assignment = assign_slots(current, &slots).ok()?;
    Some((
        TransitionKind::Direct,
        targets(&slots, &assignment),
        "direct",
        shape,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plans_cover_every_frame_and_keep_their_gap() {
        for seed in 0..40 {
            let mut rng = SplitMix64(seed);
            let starts = [60, 120, 180, 240];
            let plan = plan_formation(
                &mut rng,
                4,
                300,
                &starts,
                15.0,
                &Shape::ALL,
                spacing_range(false),
                0.6,
            )
            .expect("a plan");
            assert_eq!(plan.paths.len(), 4);
            assert!(plan.paths.iter().all(|p| p.len() == 300));
            assert_eq!(plan.shapes.len(), plan.transitions.len() + 1);
            for t in 0..300 {
                let at: Vec<StagePos> = plan.paths.iter().map(|p| p[t]).collect();
                assert!(!too_close(&at, 0.45), "seed {seed} frame {t}: {at:?}");
            }
            // Paths are continuous and walkable: no step above 3 m/s.
            for p in &plan.paths {
                for w in p.windows(2) {
                    assert!(dancegen_refine::formation::distance(w[0], w[1]) * PLAN_FPS <= 3.0);
                }
            }
        }
    }
}
