//! Root continuity where a window's generated frames meet its hard cues.
//!
//! The sampler writes the shared boundary frames into every window after each step, but the
//! network's root position for the frames it generates is only as good as its training: the
//! denoiser sees positions through rotary attention alone, so it has no absolute notion of
//! "window frame 0", and the small shipped model places its generated root with an offset from
//! the cued frames (measured on the first bundled model: ~1.2 m horizontal jumps four frames
//! into every window, and height steps of ~5 cm). The root's horizontal position is
//! translation-invariant, so a constant shift of a window's generated frames onto the path its
//! cued frames set is exact for the dance; height has cues at both ends and gets a linear ramp
//! between the two seam offsets. Rotations are not touched. [`anchor_windows`] reports the
//! corrections so the evaluation can show how large they are.

use crate::layout::{DIMS, ROOT_HEIGHT, ROOT_HORIZONTAL};

/// How many leading and trailing frames of a window were hard cues. The trailing cues never
/// include the root's horizontal position (see [`crate::pipeline`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CuedFrames {
    pub head: usize,
    pub tail: usize,
}

/// Largest corrections applied, in the windows' own (normalised) units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SeamCorrection {
    /// Largest horizontal shift of a window's generated frames.
    pub horizontal: f32,
    /// Largest height offset at a seam.
    pub height: f32,
}

/// Where frame `g` (generated) should sit next to the cued frame `c = g ∓ 1`: one step on from
/// `c`, the step being the mean of the motion's step on either side of the seam.
fn expected(x: impl Fn(usize) -> f32, c: usize, g: usize, n: usize) -> f32 {
    let forward = g > c;
    // The step inside the cued part (0 when it is a single frame) and inside the generated part.
    let cue_step = match forward {
        true if c >= 1 => x(c) - x(c - 1),
        false if c + 1 < n => x(c + 1) - x(c),
        _ => 0.0,
    };
    let gen_step = match forward {
        true if g + 1 < n => x(g + 1) - x(g),
        false if g >= 1 => x(g) - x(g - 1),
        _ => 0.0,
    };
    let step = 0.5 * (cue_step + gen_step);
    if forward { x(c) + step } else { x(c) - step }
}

/// Moves the generated frames of every window `[l, n, 151]` (normalised, window-relative
/// root) onto the root path its cued frames set (module docs). `cues[w]` describes window `w`.
/// A window without head cues has its root path started at 0 (its own first frame), the
/// convention of the representation.
pub fn anchor_windows(windows: &mut [f32], n: usize, cues: &[CuedFrames]) -> SeamCorrection {
    let mut worst = SeamCorrection::default();
    for (w, cue) in cues.iter().enumerate() {
        let win = &mut windows[w * n * DIMS..(w + 1) * n * DIMS];
        let (head, tail) = (cue.head.min(n), cue.tail.min(n));
        if head + tail >= n {
            continue;
        }
        // Horizontal: one shift for the generated frames.
        for &c in &ROOT_HORIZONTAL {
            let at = |f: usize| win[f * DIMS + c];
            let shift = if head == 0 {
                -at(0)
            } else {
                expected(at, head - 1, head, n) - at(head)
            };
            for f in head..n {
                win[f * DIMS + c] += shift;
            }
            worst.horizontal = worst.horizontal.max(shift.abs());
        }
        // Height: offsets at the head and tail seams, linearly blended across the window.
        let at = |f: usize| win[f * DIMS + ROOT_HEIGHT];
        let first = head;
        let last = n - tail - 1;
        let off_head = if head > 0 {
            expected(at, head - 1, first, n) - at(first)
        } else {
            0.0
        };
        let off_tail = if tail > 0 {
            expected(at, n - tail, last, n) - at(last)
        } else {
            0.0
        };
        let span = (last - first).max(1) as f32;
        for f in first..=last {
            let a = (f - first) as f32 / span;
            win[f * DIMS + ROOT_HEIGHT] += off_head * (1.0 - a) + off_tail * a;
        }
        worst.height = worst.height.max(off_head.abs()).max(off_tail.abs());
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window whose root walks 0.1 per frame in x and bobs in height, then has its generated
    /// frames (from `head`) displaced.
    fn walking(n: usize) -> Vec<f32> {
        let mut w = vec![0f32; n * DIMS];
        for f in 0..n {
            w[f * DIMS + ROOT_HORIZONTAL[0]] = 0.1 * f as f32;
            w[f * DIMS + ROOT_HORIZONTAL[1]] = -0.05 * f as f32;
            w[f * DIMS + ROOT_HEIGHT] = 1.0 + 0.005 * (f as f32 * 0.7).sin();
            w[f * DIMS + 20] = f as f32; // a rotation channel: must stay as it is
        }
        w
    }

    #[test]
    fn a_shifted_window_continues_its_cued_frames() {
        let n = 32;
        let truth = walking(n);
        let mut w = truth.clone();
        for f in 4..n {
            w[f * DIMS + ROOT_HORIZONTAL[0]] -= 2.0;
            w[f * DIMS + ROOT_HORIZONTAL[1]] += 0.5;
        }
        for f in 4..n - 4 {
            // A height error drifting linearly from +0.3 to +0.2 across the generated part (the
            // seam estimate borrows the generated step, so a steep drift would bias it).
            let a = (f - 4) as f32 / (n - 9) as f32;
            w[f * DIMS + ROOT_HEIGHT] += 0.3 * (1.0 - a) + 0.2 * a;
        }
        let c = anchor_windows(&mut w, n, &[CuedFrames { head: 4, tail: 4 }]);
        for f in 0..n {
            for ch in [ROOT_HORIZONTAL[0], ROOT_HORIZONTAL[1], 20] {
                let (got, want) = (w[f * DIMS + ch], truth[f * DIMS + ch]);
                assert!(
                    (got - want).abs() < 1e-4,
                    "frame {f} channel {ch}: {got} vs {want}"
                );
            }
            let (got, want) = (w[f * DIMS + ROOT_HEIGHT], truth[f * DIMS + ROOT_HEIGHT]);
            // The seam estimate averages the steps on both sides: exact up to the bob's curvature.
            assert!(
                (got - want).abs() < 5e-3,
                "frame {f} height: {got} vs {want}"
            );
        }
        assert!((c.horizontal - 2.0).abs() < 1e-4, "{c:?}");
        assert!((c.height - 0.3).abs() < 5e-3, "{c:?}");
    }

    #[test]
    fn a_window_without_head_cues_starts_at_the_origin() {
        let n = 16;
        let mut w = walking(n);
        for f in 0..n {
            w[f * DIMS + ROOT_HORIZONTAL[0]] += 3.0;
        }
        let before_height: Vec<f32> = (0..n).map(|f| w[f * DIMS + ROOT_HEIGHT]).collect();
        anchor_windows(&mut w, n, &[CuedFrames { head: 0, tail: 0 }]);
        assert_eq!(w[ROOT_HORIZONTAL[0]], 0.0);
        assert!((w[(n - 1) * DIMS + ROOT_HORIZONTAL[0]] - 0.1 * (n - 1) as f32).abs() < 1e-5);
        let after_height: Vec<f32> = (0..n).map(|f| w[f * DIMS + ROOT_HEIGHT]).collect();
        assert_eq!(before_height, after_height, "no cue, no height change");
    }

    #[test]
    fn continuous_windows_are_left_alone() {
        let n = 24;
        let truth = walking(n);
        let mut w = [truth.clone(), truth.clone()].concat();
        let cues = [
            CuedFrames { head: 0, tail: 4 },
            CuedFrames { head: 4, tail: 0 },
        ];
        let c = anchor_windows(&mut w, n, &cues);
        assert!(c.horizontal < 1e-5 && c.height < 5e-3, "{c:?}");
    }
}
