//! The kinematic beats and Bailando BAS the warp aligns and the manifest records.

use dancegen_metrics::FRAME_LEN;
use dancegen_metrics::bas::{Variant, beat_align_score, clip_music_beats, try_motion_beats};

/// Kinematic beats of world joints `(T, 24, 3)`: frame indices into the `T − 1` velocity
/// samples of strict local minima of the mean joint speed smoothed by a Gaussian of σ = 5
/// frames — Bailando/FACT's "kinetic beat", computed by the metric crate's own BAS code, so the
/// warp aligns exactly the beats the BAS metric later measures. (σ = 2 and 3 were tried on the
/// salsa takes: more, noisier minima, more of them matched, but a smaller BAS gain.)
pub fn kinematic_beats(joints: &[f64]) -> Vec<usize> {
    try_motion_beats(joints, Variant::Bailando).unwrap_or_default()
}

/// Bailando's BAS of a clip's world joints against the clip's music beats (frames relative
/// to the clip start, cut as Bailando cuts them).
pub fn bas_bailando(joints: &[f64], music_beats: &[usize]) -> Option<f64> {
    let frames = joints.len() / FRAME_LEN;
    let motion = try_motion_beats(joints, Variant::Bailando).ok()?;
    let music = clip_music_beats(music_beats, frames, Variant::Bailando);
    beat_align_score(&music, &motion, Variant::Bailando)
}
