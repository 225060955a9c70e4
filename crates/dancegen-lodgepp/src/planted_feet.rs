//! Post-processing of planted feet on generated raw frames `[T, 151]`: the root stops gliding
//! with the support foot ([`lock_planted_feet`], `dancegen_refine::foot_lock`), then leg IK
//! pins every planted ankle and toe ([`pin_planted_feet`], `dancegen_refine::foot_ik`).
//! Neither is part of Lodge++; `--no-foot-lock` switches both off.
//!
//! Which feet are planted is a [`PlantedRule`] over two signals: the model's contact channel
//! (EDGE's label: the joint hardly moves) and nearness to the floor (within the contact heights
//! the Foot Refine Block uses — LODGE's labels, ankle 12 cm, toe 5 cm — of the height the
//! supporting foot stands at, [`GroundMode::SupportFeet`], the floor `dancegen generate` puts
//! the dance on). [`PlantedRule::Either`] was the first rule; it pins too much for dance
//! footwork: in the 29 real salsa/AIST++ clips of the solo set a foot is within those heights
//! in 76 % of frames while moving at 0.98 m/s on average (issue 16, docs/solo-data-v2.md).

use dancegen_motion::repr::motion::{GroundMode, SmplMotion};
use dancegen_motion::rotation::Mat3;
use dancegen_nn::loss::FkSkeleton;
use dancegen_refine::foot_ik::{self, FootIkReport, LegContacts, SMPL_LEGS, Stepping};
use dancegen_refine::foot_lock::{Axes, PLANTED, height_contacts, leashed, planted_feet_offsets};

use crate::foot_refine::CONTACT_HEIGHT;
use crate::kinematics::{host_skeleton, joints_host};
use crate::layout::{CONTACTS, DIMS, FEET, ROOT_HORIZONTAL, ROT6D_START};
use dancegen_motion::smoothing::{Ends, gaussian_smooth};

/// Frames over which the IK fades in before and out after a contact (0.13 s at 30 fps: a
/// foot lands and lifts within about that).
pub const IK_BLEND_FRAMES: usize = 4;

/// Gaussian σ (frames) of the root lock's correction. Unsmoothed, the correction changes its
/// slope whenever the support foot changes, which doubled the mean joint acceleration (40 vs
/// 28 m/s² on the held-out song, seed 0; real takes 12-18). Smoothed over σ = 1.5-3 frames
/// it was 22-23 m/s², and FSR rose from 6.5 % to 6.9-7.2 %: the leg IK takes up what the root
/// no longer removes.
pub const ROOT_LOCK_SMOOTHING_FRAMES: f64 = 2.0;

/// When a foot counts as planted (defined with the root lock it feeds).
pub use dancegen_refine::foot_lock::PlantedRule;

/// Both passes: root lock, then leg IK ([`PlantedRule::Either`]).
pub fn clean_planted_feet(frames: &mut [f32]) -> FootIkReport {
    clean_planted_feet_with(frames, PlantedRule::Either)
}

/// Both passes with a chosen [`PlantedRule`].
pub fn clean_planted_feet_with(frames: &mut [f32], rule: PlantedRule) -> FootIkReport {
    lock_planted_feet_with(frames, rule);
    pin_planted_feet_with(frames, rule)
}

/// Moves the root's horizontal path so the support foot does not glide (the correction
/// smoothed over [`ROOT_LOCK_SMOOTHING_FRAMES`]; [`PlantedRule::Either`]).
pub fn lock_planted_feet(frames: &mut [f32]) {
    lock_planted_feet_with(frames, PlantedRule::Either)
}

/// [`lock_planted_feet`] with a chosen [`PlantedRule`].
pub fn lock_planted_feet_with(frames: &mut [f32], rule: PlantedRule) {
    lock_planted_feet_leashed(frames, rule, None);
}

/// [`lock_planted_feet_with`] on a leash of `leash_frames` (`None`: none).
pub fn lock_planted_feet_leashed(frames: &mut [f32], rule: PlantedRule, leash_frames: Option<f64>) {
    let Some((feet, contact)) = feet_and_contacts(frames, rule) else {
        return;
    };
    // Z-up: the root's horizontal channels are x and y.
    let mut offsets = planted_feet_offsets(&feet, &contact, FEET.len(), Axes::Z_UP);
    if let Some(l) = leash_frames {
        offsets = leashed(&offsets, l);
    }
    for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
        let o: Vec<f64> = offsets.iter().map(|o| f64::from(o[k])).collect();
        for (f, v) in gaussian_smooth(&o, ROOT_LOCK_SMOOTHING_FRAMES, Ends::OddReflect)
            .into_iter()
            .enumerate()
        {
            frames[f * DIMS + c] += v as f32;
        }
    }
}

/// Leg IK: every planted ankle and toe holds the mean place of its contact run; the hips',
/// knees' and ankles' 6D channels change, nothing else ([`PlantedRule::Either`]).
pub fn pin_planted_feet(frames: &mut [f32]) -> FootIkReport {
    pin_planted_feet_with(frames, PlantedRule::Either)
}

/// [`pin_planted_feet`] with a chosen [`PlantedRule`].
pub fn pin_planted_feet_with(frames: &mut [f32], rule: PlantedRule) -> FootIkReport {
    pin_planted_feet_within(frames, rule, f64::INFINITY)
}

/// [`pin_planted_feet_with`] that leaves alone a contact run whose ankle or toe strays more
/// than `max_travel_m` from the run's mean place (a step or slide the contact label calls a
/// plant; pinning it bends the leg far from where the network put it and back within the
/// IK's blend).
pub fn pin_planted_feet_within(
    frames: &mut [f32],
    rule: PlantedRule,
    max_travel_m: f64,
) -> FootIkReport {
    pin(frames, rule, max_travel_m, None)
}

/// [`pin_planted_feet_within`] that cuts a run whose foot strays more than `max_travel_m`
/// into plants within that bound joined by swings of `swing_frames` frames lifted `lift_m` at
/// their middle (`dancegen_refine::foot_ik::Stepping`): for a body dragged along a path whose
/// legs do not walk it, which would otherwise slide.
pub fn pin_planted_feet_stepping(
    frames: &mut [f32],
    rule: PlantedRule,
    max_travel_m: f64,
    swing_frames: usize,
    lift_m: f64,
) -> FootIkReport {
    let stepping = Stepping {
        swing_frames,
        lift: lift_m,
        // EDGE-151 worlds are Z-up (see `feet_and_contacts`).
        up: [0.0, 0.0, 1.0],
    };
    pin(frames, rule, max_travel_m, Some(stepping))
}

fn pin(
    frames: &mut [f32],
    rule: PlantedRule,
    max_travel_m: f64,
    stepping: Option<Stepping>,
) -> FootIkReport {
    let Some((_, contact)) = feet_and_contacts(frames, rule) else {
        return FootIkReport::default();
    };
    let t = frames.len() / DIMS;
    let skeleton = host_skeleton(&FkSkeleton::smpl24());
    let j = skeleton.len();
    let mut local: Vec<Mat3> = frames
        .chunks_exact(DIMS)
        .flat_map(|f| {
            (0..j).map(move |k| {
                let d: [f64; 6] = std::array::from_fn(|i| f64::from(f[ROT6D_START + 6 * k + i]));
                Mat3::from_6d(&d)
            })
        })
        .collect();
    let root: Vec<[f64; 3]> = frames
        .chunks_exact(DIMS)
        .map(|f| std::array::from_fn(|a| f64::from(f[4 + a])))
        .collect();
    // Contact columns follow FEET: left ankle, right ankle, left toe, right toe.
    let planted = |col: usize| -> Vec<bool> {
        (0..t)
            .map(|f| contact[f * FEET.len() + col] >= PLANTED)
            .collect()
    };
    let contacts = [
        LegContacts {
            ankle: planted(0),
            toe: planted(2),
        },
        LegContacts {
            ankle: planted(1),
            toe: planted(3),
        },
    ];
    debug_assert_eq!([SMPL_LEGS[0].ankle, SMPL_LEGS[1].ankle], [FEET[0], FEET[1]]);
    debug_assert_eq!([SMPL_LEGS[0].toe, SMPL_LEGS[1].toe], [FEET[2], FEET[3]]);
    let report = foot_ik::pin_planted_feet_stepping(
        &skeleton,
        &mut local,
        &root,
        &SMPL_LEGS,
        &contacts,
        IK_BLEND_FRAMES,
        max_travel_m,
        stepping,
    );
    let changed: Vec<usize> = SMPL_LEGS
        .iter()
        .flat_map(|l| [l.hip, l.knee, l.ankle])
        .collect();
    for (f, frame) in frames.chunks_exact_mut(DIMS).enumerate() {
        for &k in &changed {
            let d = local[f * j + k].to_6d();
            for (i, v) in d.iter().enumerate() {
                frame[ROT6D_START + 6 * k + i] = *v as f32;
            }
        }
    }
    report
}

/// The feet `[T, 4, 3]` (world, metres, Z-up) and their contacts `[T, 4]` (the model's label
/// combined with nearness to the floor by `rule`), in [`FEET`] order; `None` for no frames.
fn feet_and_contacts(frames: &[f32], rule: PlantedRule) -> Option<(Vec<f32>, Vec<f32>)> {
    let t = frames.len() / DIMS;
    if t == 0 {
        return None;
    }
    let joints = joints_host(frames, &FkSkeleton::smpl24());
    let feet: Vec<f32> = (0..t)
        .flat_map(|f| {
            FEET.iter()
                .flat_map(move |&j| (0..3).map(move |a| (f, j, a)))
        })
        .map(|(f, j, a)| joints[(f * 24 + j) * 3 + a])
        .collect();
    // The floor from a Y-up view of the joints (only heights matter to it).
    let heights: Vec<f32> = joints
        .chunks_exact(3)
        .flat_map(|p| [0.0, p[2], 0.0])
        .collect();
    let floor = SmplMotion::ground_height(&heights, GroundMode::SupportFeet);
    let near = height_contacts(&feet, FEET.len(), 2, floor, &CONTACT_HEIGHT);
    let contact: Vec<f32> = frames
        .chunks_exact(DIMS)
        .flat_map(|f| f[CONTACTS].iter().copied())
        .zip(near)
        .map(|(label, low)| match rule {
            PlantedRule::Either => label.max(low),
            PlantedRule::Both => label.min(low),
        })
        .collect();
    Some((feet, contact))
}
