//! Synthetic finger motion that depends on the body and the music (issue 19).
//!
//! It is **not** mocap: no real finger dance data can be had here. It is built so that the
//! hands are a learnable function of the body and the music, plus a little noise, which is what
//! the hierarchical quantiser (body → hands) and the generator need to have something to learn:
//!
//! 1. **When** the hand changes shape: on beats (the song's), where that hand's wrist moves
//!    faster than its median (an accent); otherwise the shape is held, but at most 4 beats.
//!    The new shape is reached over 6 frames and lands on the beat (it starts 3 frames before).
//! 2. **Which** shape ([`super::hand_poses::POSES`]): scored from the body's pose at the beat —
//!    wrist height between pelvis and head, arm extension, wrist speed — and the music's energy,
//!    by the rules of [`pose_scores`] (raised and open in high energy → spread; extended → flat
//!    or point; tense and fast → fist or claw; calm → relaxed, cupped or graceful), with Gumbel
//!    noise (scale [`CHOICE_NOISE`]) so that the choice is a distribution, not a lookup.
//! 3. **Continuous layer**: finger tension follows the wrist's speed (more flexion when the
//!    hand moves fast), the fingertip joints lag it by 2 frames (follow-through), and a slow
//!    wobble of ±0.03 of the range per finger keeps held shapes alive.

use dancegen_motion::rng::SplitMix64;

use super::hand_poses::{FINGERS, HAND_JOINTS, POSES, left_hand_axis_angles, mirror_hand};
use super::signal::{gumbel, point_speed, quantile, smooth, smoothstep, unit_scale, wobble};

/// SMPL 24 joints used: pelvis, head, shoulders, wrists.
const PELVIS: usize = 0;
const HEAD: usize = 15;
const SHOULDER: [usize; 2] = [16, 17];
const WRIST: [usize; 2] = [20, 21];
const BODY_JOINTS: usize = 24;

/// Frames over which a new shape is reached, and how many of them come before the beat.
const TRANSITION_FRAMES: usize = 6;
const LEAD_FRAMES: usize = 3;
/// A shape is held at most this many beats.
const MAX_HOLD_BEATS: usize = 4;
/// Scale of the Gumbel noise on the pose scores.
pub const CHOICE_NOISE: f32 = 0.3;
/// Extra flexion (fraction of the range) at the clip's fastest wrist speed, around the median.
const TENSION: f32 = 0.12;
/// Follow-through delay of the fingertip joints, frames.
const TIP_LAG: usize = 2;
/// Peak of the per-finger wobble (fraction of the range), and its band (Hz).
const WOBBLE: f32 = 0.03;
const WOBBLE_HZ: (f32, f32) = (0.2, 0.9);

/// What the pose choice sees at a beat, all roughly in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandContext {
    /// Wrist height: 0 at the pelvis, 1 at the head (may exceed both).
    pub height: f32,
    /// Shoulder-to-wrist distance over the clip's 95th percentile.
    pub extension: f32,
    /// Wrist speed over the clip's 95th percentile.
    pub speed: f32,
    /// Music energy (onset strength, smoothed) over the clip's 95th percentile.
    pub energy: f32,
}

/// Score of every pose in [`POSES`] order for a context (higher = likelier).
pub fn pose_scores(c: &HandContext) -> [f32; POSES.len()] {
    let (h, x, s, e) = (c.height, c.extension, c.speed, c.energy);
    let raised = (h - 1.0).max(0.0);
    [
        1.0 - e - 0.8 * s,                                // relaxed
        1.2 * x + 0.3 * s - 0.3,                          // flat
        1.5 * raised + 0.8 * e + 0.6 * x - 0.5,           // spread
        1.2 * e + 0.6 * s - x,                            // fist
        1.2 * x + 0.5 * s + 0.3 * e - 0.2 - 0.7 * raised, // point
        0.8 * (h - 0.8) + 0.4 * e - 0.4,                  // peace
        0.7 - e - x,                                      // pinch
        0.8 - 0.8 * x - 0.3 * e,                          // cupped
        1.5 * e + 0.4 * s - 0.9,                          // claw
        0.5 - 1.2 * e + 0.5 * h,                          // graceful
    ]
}

/// Synthetic fingers for one clip.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticHands {
    /// `(T, 30, 3)` local axis-angle of SMPL-H joints 22–51 (left hand, then right hand).
    pub axis_angles: Vec<f32>,
    /// `(T, 2)` the pose id each hand is heading for (left, right).
    pub targets: Vec<u8>,
}

/// Inputs of the synthesis, all at one frame rate.
#[derive(Debug, Clone, Copy)]
pub struct SynthInputs<'a> {
    pub fps: f32,
    /// `(T, 24, 3)` SMPL 24 world joints, metres, Y-up.
    pub joints: &'a [f32],
    /// `(T,)` music onset strength (any scale).
    pub onset: &'a [f32],
    /// Beat frames of the song, ascending.
    pub beats: &'a [usize],
    pub seed: u64,
}

/// Synthesises both hands (see the module documentation).
pub fn synthesize_hands(inp: &SynthInputs) -> SyntheticHands {
    let t = inp.joints.len() / (BODY_JOINTS * 3);
    if t == 0 {
        return SyntheticHands {
            axis_angles: Vec::new(),
            targets: Vec::new(),
        };
    }
    let mut rng = SplitMix64(inp.seed ^ 0x68616e6473); // "hands"
    let energy = unit_scale(&smooth(
        &inp.onset[..t.min(inp.onset.len())],
        (inp.fps / 4.0) as usize,
    ));
    let energy_at = |f: usize| energy.get(f).copied().unwrap_or(0.0);
    let j = |f: usize, k: usize| {
        let o = (f * BODY_JOINTS + k) * 3;
        [inp.joints[o], inp.joints[o + 1], inp.joints[o + 2]]
    };
    let dist = |a: [f32; 3], b: [f32; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut axis_angles = vec![0.0f32; t * 2 * HAND_JOINTS * 3];
    let mut targets = vec![0u8; t * 2];
    for hand in 0..2 {
        let speed = smooth(
            &point_speed(inp.joints, BODY_JOINTS, WRIST[hand], inp.fps),
            1,
        );
        let speed_top = quantile(&speed, 0.95).max(1e-6);
        let speed_median = quantile(&speed, 0.5);
        let reach: Vec<f32> = (0..t)
            .map(|f| dist(j(f, WRIST[hand]), j(f, SHOULDER[hand])))
            .collect();
        let reach_top = quantile(&reach, 0.95).max(1e-6);
        // Target pose per frame: decided at beats, starting LEAD_FRAMES before them.
        let mut target = vec![usize::MAX; t];
        let mut current = pose_choice(
            &context(
                0, &speed, speed_top, &reach, reach_top, &energy_at, &j, hand,
            ),
            &mut rng,
        );
        let mut held = 0usize;
        let mut changes: Vec<(usize, usize)> = vec![(0, current)];
        for &b in inp.beats.iter().filter(|&&b| b < t) {
            held += 1;
            if speed[b] > speed_median || held >= MAX_HOLD_BEATS {
                let c = context(
                    b, &speed, speed_top, &reach, reach_top, &energy_at, &j, hand,
                );
                let next = pose_choice(&c, &mut rng);
                held = 0;
                if next != current {
                    current = next;
                    changes.push((b.saturating_sub(LEAD_FRAMES), next));
                }
            }
        }
        // Per-frame flexion: smoothstep from the previous shape to each new one.
        let mut flex = vec![[[0.0f32; 3]; FINGERS]; t];
        let mut spread = vec![[0.0f32; FINGERS]; t];
        for (k, &(start, pose)) in changes.iter().enumerate() {
            let end = changes.get(k + 1).map_or(t, |c| c.0);
            let from = if k == 0 { pose } else { changes[k - 1].1 };
            for f in start..end.max(start).min(t) {
                let a = if k == 0 {
                    1.0
                } else {
                    smoothstep((f - start) as f32 / TRANSITION_FRAMES as f32)
                };
                let (p, q) = (&POSES[from], &POSES[pose]);
                let lerp = |x: f32, y: f32| x + a * (y - x);
                for fi in 0..FINGERS {
                    flex[f][fi] = std::array::from_fn(|s| lerp(p.flex[fi][s], q.flex[fi][s]));
                    spread[f][fi] = lerp(p.spread[fi], q.spread[fi]);
                }
                target[f] = pose;
            }
        }
        // Continuous layer: tension from the wrist speed (tips delayed), per-finger wobble.
        let wobbles: Vec<Vec<f32>> = (0..FINGERS)
            .map(|_| wobble(&mut rng, t, inp.fps, WOBBLE_HZ.0, WOBBLE_HZ.1, WOBBLE / 2.0))
            .collect();
        let tension = |f: usize| TENSION * ((speed[f] - speed_median) / speed_top).clamp(-0.5, 1.0);
        for f in 0..t {
            let mut fl = flex[f];
            for fi in 0..FINGERS {
                for (s, v) in fl[fi].iter_mut().enumerate() {
                    let lagged = if s == 2 { f.saturating_sub(TIP_LAG) } else { f };
                    *v = (*v + tension(lagged) + wobbles[fi][f]).clamp(0.0, 1.0);
                }
            }
            let left = left_hand_axis_angles(&fl, &spread[f]);
            let aa = if hand == 0 { left } else { mirror_hand(&left) };
            let o = (f * 2 + hand) * HAND_JOINTS * 3;
            for (i, a) in aa.iter().enumerate() {
                axis_angles[o + i * 3..o + i * 3 + 3].copy_from_slice(a);
            }
            targets[f * 2 + hand] = target[f] as u8;
        }
    }
    SyntheticHands {
        axis_angles,
        targets,
    }
}

#[allow(clippy::too_many_arguments)]
fn context(
    f: usize,
    speed: &[f32],
    speed_top: f32,
    reach: &[f32],
    reach_top: f32,
    energy_at: &dyn Fn(usize) -> f32,
    j: &dyn Fn(usize, usize) -> [f32; 3],
    hand: usize,
) -> HandContext {
    let (pelvis, head, wrist) = (j(f, PELVIS)[1], j(f, HEAD)[1], j(f, WRIST[hand])[1]);
    HandContext {
        height: (wrist - pelvis) / (head - pelvis).max(0.1),
        extension: reach[f] / reach_top,
        speed: speed[f] / speed_top,
        energy: energy_at(f),
    }
}

fn pose_choice(c: &HandContext, rng: &mut SplitMix64) -> usize {
    let s = pose_scores(c);
    (0..s.len())
        .map(|i| (i, s[i] + CHOICE_NOISE * gumbel(rng)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
        .expect("poses")
}
