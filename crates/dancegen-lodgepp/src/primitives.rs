//! Dance primitives (paper §3.3–3.4): 8-frame key motions at motion beats (speed minima of
//! the coarse dance) moved onto the nearest music beats, plus the 8 frames around every PDDM
//! window boundary (the last 4 frames of one window and the first 4 of the next).
//!
//! Everything here is host-side bookkeeping on normalised `[T, C]` arrays; the same placement
//! rules build the primitives of a training window (from its ground truth) and of a song (from
//! the generated coarse dance and retrieved library clips).

use crate::config::{BOUNDARY_FRAMES, PRIMITIVE_FRAMES};
use crate::layout::{DIMS, ROOT_HORIZONTAL};

/// Key motions keep this many frames from a window's ends (D.3 retrieves between frames 30 and
/// 90 of a 128-frame window; we allow more of the window).
pub const KEY_MARGIN: usize = 12;
/// Minimum frames between two key motions of one window (D.3: 30).
pub const KEY_SPACING: usize = 24;
/// Gaussian smoothing of the speed curve before finding minima (frames).
const SPEED_SIGMA: f64 = 2.0;

/// Frame-to-frame speed of `x` `[T, C]` over `channels` (L2 norm of the difference; frame 0
/// copies frame 1), Gaussian-smoothed.
pub fn speed(x: &[f32], c: usize, channels: &[usize]) -> Vec<f64> {
    let t = x.len() / c;
    let mut s = vec![0.0; t];
    for f in 1..t {
        s[f] = channels
            .iter()
            .map(|&k| f64::from(x[f * c + k] - x[(f - 1) * c + k]).powi(2))
            .sum::<f64>()
            .sqrt();
    }
    if t > 1 {
        s[0] = s[1];
    }
    smooth(&s, SPEED_SIGMA)
}

fn smooth(x: &[f64], sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as i64;
    let w: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let n = x.len() as i64;
    (0..n)
        .map(|i| {
            let (mut acc, mut norm) = (0.0, 0.0);
            for (k, wk) in (-r..=r).zip(&w) {
                let j = (i + k).clamp(0, n - 1) as usize;
                acc += wk * x[j];
                norm += wk;
            }
            acc / norm
        })
        .collect()
}

/// Motion beats: strict local minima of `speed`.
pub fn motion_beats(speed: &[f64]) -> Vec<usize> {
    (1..speed.len().saturating_sub(1))
        .filter(|&i| speed[i] < speed[i - 1] && speed[i] <= speed[i + 1])
        .collect()
}

/// Key-motion centres for one window of `len` frames: the `candidates` (frames in the window)
/// kept greedily in order when they leave [`KEY_MARGIN`] to the ends and [`KEY_SPACING`] to the
/// previous one.
pub fn key_centres(candidates: &[usize], len: usize) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for &c in candidates {
        if c < KEY_MARGIN || c + KEY_MARGIN > len {
            continue;
        }
        if out.last().is_some_and(|&p| c < p + KEY_SPACING) {
            continue;
        }
        out.push(c);
    }
    out
}

/// For each motion beat, the nearest music beat (frames), if within `max_shift` frames.
pub fn align_to_music(motion: &[usize], music: &[usize], max_shift: usize) -> Vec<(usize, usize)> {
    motion
        .iter()
        .filter_map(|&m| {
            music
                .iter()
                .min_by_key(|&&b| b.abs_diff(m))
                .filter(|&&b| b.abs_diff(m) <= max_shift)
                .map(|&b| (m, b))
        })
        .collect()
}

/// The primitives of one window: `values` `[len, 151]` (zero away from primitives) and the
/// per-frame mask.
#[derive(Clone, Debug)]
pub struct WindowPrimitives {
    pub values: Vec<f32>,
    pub mask: Vec<f32>,
}

impl WindowPrimitives {
    pub fn empty(len: usize) -> Self {
        Self {
            values: vec![0.0; len * DIMS],
            mask: vec![0.0; len],
        }
    }

    /// Writes `clip` `[k, 151]` at frames `start..start + k`; the root's horizontal position
    /// is left out (zero) when `keep_root_horizontal` is false.
    pub fn put(&mut self, start: usize, clip: &[f32], keep_root_horizontal: bool) {
        let k = clip.len() / DIMS;
        for f in 0..k {
            let dst = (start + f) * DIMS;
            self.values[dst..dst + DIMS].copy_from_slice(&clip[f * DIMS..(f + 1) * DIMS]);
            if !keep_root_horizontal {
                for &c in &ROOT_HORIZONTAL {
                    self.values[dst + c] = 0.0;
                }
            }
            self.mask[start + f] = 1.0;
        }
    }
}

/// Which primitives a training window shows the network.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimitiveMode {
    None,
    BoundariesOnly,
    Full,
}

/// A training window's primitives from its ground truth `x` `[len, 151]` (normalised, root
/// horizontal already relative to frame 0): the first [`BOUNDARY_FRAMES`] frames (with root),
/// the last ones (without root horizontal), and key motions around the motion beats of
/// `channels` (without root horizontal).
pub fn training_primitives(x: &[f32], mode: PrimitiveMode, channels: &[usize]) -> WindowPrimitives {
    let len = x.len() / DIMS;
    let mut p = WindowPrimitives::empty(len);
    if mode == PrimitiveMode::None {
        return p;
    }
    let b = BOUNDARY_FRAMES;
    p.put(0, &x[..b * DIMS], true);
    p.put(len - b, &x[(len - b) * DIMS..], false);
    if mode == PrimitiveMode::Full {
        let beats = motion_beats(&speed(x, DIMS, channels));
        let half = PRIMITIVE_FRAMES / 2;
        for c in key_centres(&beats, len) {
            p.put(c - half, &x[(c - half) * DIMS..(c + half) * DIMS], false);
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minima_of_a_cosine_speed_are_its_troughs() {
        let s: Vec<f64> = (0..100)
            .map(|i| 1.0 + (i as f64 * std::f64::consts::TAU / 24.0).cos())
            .collect();
        let b = motion_beats(&s);
        assert_eq!(b, vec![12, 36, 60, 84]);
    }

    #[test]
    fn key_centres_respect_margin_and_spacing() {
        let c = key_centres(&[5, 20, 30, 50, 60, 120], 128);
        assert_eq!(c, vec![20, 50]);
    }

    #[test]
    fn alignment_picks_nearest_music_beat_within_reach() {
        let a = align_to_music(&[10, 40, 100], &[12, 30, 60], 6);
        assert_eq!(a, vec![(10, 12)]);
    }

    #[test]
    fn training_primitives_mask_boundaries_and_keys() {
        let len = 64;
        // One channel swinging with period 32 frames: speed minima at its extremes.
        let mut x = vec![0f32; len * DIMS];
        for f in 0..len {
            x[f * DIMS + 10] = (f as f32 * std::f32::consts::TAU / 32.0).sin();
            x[f * DIMS + 4] = f as f32;
        }
        let p = training_primitives(&x, PrimitiveMode::Full, &[10]);
        assert!(p.mask[..4].iter().all(|&m| m == 1.0));
        assert!(p.mask[60..].iter().all(|&m| m == 1.0));
        let keys: usize = p.mask[4..60].iter().map(|&m| m as usize).sum();
        assert_eq!(keys, 8, "one key motion fits between the margins");
        // Root horizontal kept at the head, dropped at the tail.
        assert_eq!(p.values[DIMS + 4], 1.0);
        assert_eq!(p.values[61 * DIMS + 4], 0.0);
        let none = training_primitives(&x, PrimitiveMode::None, &[10]);
        assert!(none.mask.iter().all(|&m| m == 0.0));
    }
}
