//! Synthetic ARKit face curves driven by the music (issue 19).
//!
//! Not captured faces: there is no face dance data here. The curves follow simple, stated rules
//! so that the face is a learnable function of the music plus noise:
//!
//! - **Mood** (one per clip): valence from the song's mode (major against minor third over the
//!   strongest pitch class of the clip's mean chroma) and its mean energy. It sets the smile
//!   (with cheek and eye squint) or the frown.
//! - **Energy** (onset strength smoothed over ±0.25 s, scaled to the clip): jaw opening
//!   (exertion), brows lowered in intense passages.
//! - **Beats**: a breath pulse on each beat (jaw, and lips pushed out in loud passages).
//! - **Accents** (onset peaks in the clip's top fifth): eyebrows raised, decaying over 0.3 s.
//! - **Blinks**: a Poisson process at 17 per minute (fewer in loud passages), plus a blink on a
//!   strong beat with probability 0.15; a blink takes 5 frames at 30 fps, at least 0.3 s apart.
//! - **Gaze**: a saccade to a new small direction every 0.8–2.5 s.

use dancegen_motion::face::arkit::{ARKIT_COUNT, arkit_index};
use dancegen_motion::rng::SplitMix64;

use super::signal::{quantile, smooth, unit_scale};

/// Blinks per minute at rest (adults in conversation blink 15–20 times a minute).
const BLINKS_PER_MINUTE: f32 = 17.0;
/// Blink shape at 30 fps (closing, closed, opening).
const BLINK: [f32; 5] = [0.5, 1.0, 1.0, 0.6, 0.2];
/// Shortest gap between blinks, seconds.
const BLINK_GAP_S: f32 = 0.3;
/// Chance of a blink on a strong beat.
const BEAT_BLINK_P: f64 = 0.15;
/// Decay time of beat and accent pulses, seconds.
const PULSE_TAU_S: f32 = 0.12;
const ACCENT_TAU_S: f32 = 0.3;
/// Saccade interval range, seconds, and largest gaze weight.
const SACCADE_S: (f32, f32) = (0.8, 2.5);
const GAZE_MAX: f32 = 0.35;

/// Music inputs of the face, at the motion's frame rate.
#[derive(Debug, Clone, Copy)]
pub struct FaceInputs<'a> {
    pub fps: f32,
    pub frames: usize,
    /// `(T,)` onset strength (any scale).
    pub onset: &'a [f32],
    /// `(T, 12)` chroma, or empty when unknown (valence then comes from energy alone).
    pub chroma: &'a [f32],
    /// Beat frames, ascending.
    pub beats: &'a [usize],
    pub seed: u64,
}

/// The synthetic face of one clip.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticFace {
    /// `(T, 52)` ARKit weights in [0, 1], in [`dancegen_motion::face::ARKIT_NAMES`] order.
    pub weights: Vec<f32>,
    /// The clip's valence in [−1, 1] (the mood label).
    pub valence: f32,
}

/// The clip's valence from its chroma and mean energy (see the module documentation).
pub fn valence(chroma: &[f32], mean_energy: f32) -> f32 {
    let mode = if chroma.len() >= 12 {
        let mut mean = [0.0f32; 12];
        let n = chroma.len() / 12;
        for row in chroma.chunks_exact(12) {
            for (m, v) in mean.iter_mut().zip(row) {
                *m += v / n as f32;
            }
        }
        let tonic = (0..12)
            .max_by(|&a, &b| mean[a].total_cmp(&mean[b]))
            .unwrap_or(0);
        let (major, minor) = (mean[(tonic + 4) % 12], mean[(tonic + 3) % 12]);
        (major - minor) / (major + minor + 1e-6)
    } else {
        0.0
    };
    (0.7 * (1.5 * mode).clamp(-1.0, 1.0) + 0.3 * (2.0 * mean_energy - 1.0)).clamp(-1.0, 1.0)
}

fn idx(name: &str) -> usize {
    arkit_index(name).unwrap_or_else(|| panic!("{name} is an ARKit name"))
}

/// Synthesises the face of one clip (see the module documentation).
pub fn synthesize_face(inp: &FaceInputs) -> SyntheticFace {
    let t = inp.frames;
    let fps = inp.fps;
    let mut rng = SplitMix64(inp.seed ^ 0x66616365); // "face"
    let mut onset = inp.onset[..t.min(inp.onset.len())].to_vec();
    onset.resize(t, 0.0);
    let energy = unit_scale(&smooth(&onset, (fps / 4.0) as usize));
    let mean_energy = energy.iter().sum::<f32>() / t.max(1) as f32;
    let v = valence(inp.chroma, mean_energy);
    // Pulses: beats (breath) and accents (onset peaks in the clip's top fifth).
    let decay = |tau: f32| (-1.0 / (tau * fps)).exp();
    let mut beat_pulse = vec![0.0f32; t];
    let mut accent = vec![0.0f32; t];
    let is_beat: Vec<bool> = {
        let mut b = vec![false; t];
        for &f in inp.beats.iter().filter(|&&f| f < t) {
            b[f] = true;
        }
        b
    };
    let top = quantile(&onset, 0.8);
    let (db, da) = (decay(PULSE_TAU_S), decay(ACCENT_TAU_S));
    for f in 0..t {
        let prev = |x: &[f32]| if f > 0 { x[f - 1] } else { 0.0 };
        beat_pulse[f] = if is_beat[f] {
            1.0
        } else {
            prev(&beat_pulse) * db
        };
        let peak = f > 0 && f + 1 < t && onset[f] > onset[f - 1] && onset[f] >= onset[f + 1];
        accent[f] = if peak && onset[f] > top && top > 0.0 {
            1.0f32.max(prev(&accent) * da)
        } else {
            prev(&accent) * da
        };
    }
    // Blinks.
    let mut blink = vec![0.0f32; t];
    let mut next_free = 0usize;
    let gap = (BLINK_GAP_S * fps) as usize;
    let per_frame = BLINKS_PER_MINUTE / 60.0 / fps;
    let blink_len = ((BLINK.len() as f32) * fps / 30.0).round().max(2.0) as usize;
    for f in 0..t {
        if f < next_free {
            continue;
        }
        let p = per_frame * (1.0 - 0.4 * energy[f]);
        let strong_beat = is_beat[f] && energy[f] > 0.5;
        let go = (rng.next_f64() as f32) < p || (strong_beat && rng.next_f64() < BEAT_BLINK_P);
        if go {
            for k in 0..blink_len.min(t - f) {
                let s = BLINK[k * BLINK.len() / blink_len];
                blink[f + k] = blink[f + k].max(s);
            }
            next_free = f + blink_len + gap;
        }
    }
    // Gaze: piecewise-constant targets, each reached over 3 frames.
    let mut gaze = vec![[0.0f32; 2]; t];
    let mut f0 = 0usize;
    let mut from = [0.0f32; 2];
    while f0 < t {
        let to = [
            GAZE_MAX * (2.0 * rng.next_f64() as f32 - 1.0),
            GAZE_MAX * 0.6 * (2.0 * rng.next_f64() as f32 - 1.0),
        ];
        let span =
            ((SACCADE_S.0 + (SACCADE_S.1 - SACCADE_S.0) * rng.next_f64() as f32) * fps) as usize;
        for (k, g) in gaze.iter_mut().skip(f0).take(span.max(1)).enumerate() {
            let a = (k as f32 / 3.0).min(1.0);
            *g = [
                from[0] + a * (to[0] - from[0]),
                from[1] + a * (to[1] - from[1]),
            ];
        }
        from = to;
        f0 += span.max(1);
    }
    let mut w = vec![0.0f32; t * ARKIT_COUNT];
    let smile = (0.15 + 0.45 * v).max(0.0);
    let frown = (-0.5 * v).max(0.0);
    for f in 0..t {
        let row = &mut w[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT];
        let e = energy[f];
        let mut set = |name: &str, value: f32| row[idx(name)] = value.clamp(0.0, 1.0);
        set("eyeBlinkLeft", blink[f]);
        set("eyeBlinkRight", blink[f]);
        set("jawOpen", 0.04 + 0.18 * e + 0.08 * beat_pulse[f]);
        let s = smile * (0.8 + 0.35 * e);
        set("mouthSmileLeft", s);
        set("mouthSmileRight", s * 0.95);
        set("cheekSquintLeft", 0.5 * s);
        set("cheekSquintRight", 0.5 * s * 0.95);
        set("eyeSquintLeft", 0.3 * s);
        set("eyeSquintRight", 0.3 * s);
        set("mouthFrownLeft", frown * (0.5 + 0.5 * e));
        set("mouthFrownRight", frown * (0.5 + 0.5 * e));
        set("browInnerUp", 0.08 + 0.5 * accent[f]);
        set("browOuterUpLeft", 0.35 * accent[f]);
        set("browOuterUpRight", 0.35 * accent[f]);
        let intense = ((e - 0.6) * 1.5).max(0.0) * if v < 0.0 { 1.0 } else { 0.4 };
        set("browDownLeft", intense);
        set("browDownRight", intense);
        let breath = if e > 0.6 { 0.3 * beat_pulse[f] } else { 0.0 };
        set("mouthPucker", breath);
        set("mouthFunnel", 0.5 * breath);
        // Gaze: yaw > 0 looks to the dancer's left (left eye out, right eye in).
        let [yaw, pitch] = gaze[f];
        set("eyeLookOutLeft", yaw);
        set("eyeLookInRight", yaw);
        set("eyeLookInLeft", -yaw);
        set("eyeLookOutRight", -yaw);
        set("eyeLookUpLeft", pitch);
        set("eyeLookUpRight", pitch);
        set("eyeLookDownLeft", -pitch);
        set("eyeLookDownRight", -pitch);
    }
    SyntheticFace {
        weights: w,
        valence: v,
    }
}
