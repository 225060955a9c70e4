//! Canonical heading of a PDDM window: the whole window turned about the vertical (Z-up) axis
//! so that its first frame faces +X.
//!
//! Why: a data set whose takes face every direction (the CMU dance takes turn and whirl, and
//! mirroring doubles the headings) gives the root orientation's 6D values a near-zero mean and a
//! ring-shaped distribution; in the window's own heading frame that ring collapses to one mode.
//! It was built as the suspected cure for the upside-down bodies of the v3 PDDM, and measured
//! **not** to cure them (docs/solo-data-v2.md, "Fourth round": the PDDM barely learns the root
//! orientation with or without it). It is an experiment, not part of the Lodge++ paper; a
//! model opts in with `canonical_heading = true` in `[model.pddm]`, and the samplers then turn
//! each window's cues into its frame and the result back.
//!
//! Frames are normalised EDGE-151 with window-relative root x/y (`crate::layout`); the turn is
//! done in raw units (`raw = n · scale + shift`, the denormaliser's statistics), since the
//! normaliser scales each channel on its own.

use crate::layout::{DIMS, ROOT_HORIZONTAL, ROT6D_START};
use crate::primitives::WindowPrimitives;

/// The denormaliser's statistics on the host, `(scale, shift)` per channel.
pub struct Stats<'a> {
    pub scale: &'a [f32],
    pub shift: &'a [f32],
}

impl Stats<'_> {
    fn raw(&self, f: &[f32], c: usize) -> f32 {
        f[c] * self.scale[c] + self.shift[c]
    }

    fn set(&self, f: &mut [f32], c: usize, raw: f32) {
        f[c] = (raw - self.shift[c]) / self.scale[c];
    }
}

/// Heading (radians, about +Z from +X) of one normalised frame: the direction of the body's
/// forward axis (SMPL local +Z) in the horizontal plane. The 6D holds the first two rows of the
/// root matrix `R`, and `R · (0, 0, 1)` is its third column, so the forward's x, y are `R[0][2]`
/// and `R[1][2]`.
pub fn heading(frame: &[f32], stats: &Stats) -> f32 {
    let x = stats.raw(frame, ROT6D_START + 2);
    let y = stats.raw(frame, ROT6D_START + 5);
    y.atan2(x)
}

/// Turns normalised frames `[T, 151]` by `angle` about +Z: the root's orientation (`R ← Rz R`,
/// on the two stored rows) and its window-relative horizontal position. Joint-local rotations,
/// height and contacts do not change.
pub fn turn(frames: &mut [f32], angle: f32, stats: &Stats) {
    let (s, c) = angle.sin_cos();
    let [px, py] = ROOT_HORIZONTAL;
    for f in frames.chunks_mut(DIMS) {
        let (x, y) = (stats.raw(f, px), stats.raw(f, py));
        stats.set(f, px, c * x - s * y);
        stats.set(f, py, s * x + c * y);
        // Row 0' = c · row 0 − s · row 1, row 1' = s · row 0 + c · row 1 (Rz's first two rows).
        for k in 0..3 {
            let (r0, r1) = (
                stats.raw(f, ROT6D_START + k),
                stats.raw(f, ROT6D_START + 3 + k),
            );
            stats.set(f, ROT6D_START + k, c * r0 - s * r1);
            stats.set(f, ROT6D_START + 3 + k, s * r0 + c * r1);
        }
    }
}

/// Turns every window of `windows` (`[B, T, 151]` normalised) so its frame 0 faces +X; returns
/// the turn each window got (negated heading).
pub fn canonicalise(windows: &mut [f32], frames: usize, stats: &Stats) -> Vec<f32> {
    windows
        .chunks_mut(frames * DIMS)
        .map(|w| {
            let angle = -heading(&w[..DIMS], stats);
            turn(w, angle, stats);
            angle
        })
        .collect()
}

/// The turn that brings each window into its heading frame: from its primitives' frame 0 when
/// that frame is cued (as in training, where frame 0 is the ground truth's), else from
/// `fallback[w]`, a heading the sampler knows for that frame (the coarse dance's, or 0 for a
/// free window).
pub fn window_turns(prims: &[WindowPrimitives], fallback: &[f32], stats: &Stats) -> Vec<f32> {
    prims
        .iter()
        .zip(fallback)
        .map(|(p, &h)| {
            if p.mask[0] > 0.0 {
                -heading(&p.values[..DIMS], stats)
            } else {
                -h
            }
        })
        .collect()
}

/// Turns the cued frames of every window's primitives (mask 1) and of its hard cues
/// (`cues` `[l, n, 151]`, frames with any channel cued in `cue_mask`) by `turns[w]`. Frames
/// without a cue stay zero, as the network saw them in training.
pub fn turn_cues(
    prims: &mut [WindowPrimitives],
    cues: &mut [f32],
    cue_mask: &[f32],
    turns: &[f32],
    stats: &Stats,
) {
    let n = prims.first().map_or(0, |p| p.mask.len());
    for (w, (p, &a)) in prims.iter_mut().zip(turns).enumerate() {
        for (f, &m) in p.mask.iter().enumerate() {
            if m > 0.0 {
                turn(&mut p.values[f * DIMS..(f + 1) * DIMS], a, stats);
            }
        }
        for f in 0..n {
            let at = (w * n + f) * DIMS;
            if cue_mask[at..at + DIMS].iter().any(|&m| m > 0.0) {
                turn(&mut cues[at..at + DIMS], a, stats);
            }
        }
    }
}

/// Turns window `w` of `windows` `[l, n, 151]` by `turns[w]`.
pub fn turn_windows(windows: &mut [f32], n: usize, turns: &[f32], stats: &Stats) {
    for (w, &a) in windows.chunks_mut(n * DIMS).zip(turns) {
        turn(w, a, stats);
    }
}

/// EDGE's long-form overwrite for windows in their own heading frames (the counterpart of
/// `pipeline::overwrite_first_halves_relative`): window `i`'s first `n − half` frames become
/// window `i − 1`'s last ones, re-based to root x/y 0 and turned to face +X at their first
/// frame. `x` is `[l, n, 151]`.
pub fn overwrite_first_halves_turned(x: &mut [f32], n: usize, half: usize, stats: &Stats) {
    let l = x.len() / (n * DIMS);
    for i in 1..l {
        let mut src = x[((i - 1) * n + half) * DIMS..i * n * DIMS].to_vec();
        for &c in &ROOT_HORIZONTAL {
            let o = src[c];
            for f in src.chunks_mut(DIMS) {
                f[c] -= o;
            }
        }
        let a = -heading(&src[..DIMS], stats);
        turn(&mut src, a, stats);
        x[i * n * DIMS..i * n * DIMS + src.len()].copy_from_slice(&src);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::rotation::Mat3;

    /// Different scale and shift per channel (root x/y unshifted, as the denormaliser's), so a turn
    /// done in normalised units instead of raw ones would fail the tests.
    fn uneven_stats() -> (Vec<f32>, Vec<f32>) {
        let scale: Vec<f32> = (0..DIMS).map(|c| 0.5 + 0.01 * c as f32).collect();
        let shift: Vec<f32> = (0..DIMS)
            .map(|c| {
                if ROOT_HORIZONTAL.contains(&c) {
                    0.0
                } else {
                    0.1 * (c % 7) as f32 - 0.3
                }
            })
            .collect();
        (scale, shift)
    }

    /// A normalised frame whose root is `Rz(yaw) · Rx(+90°)` (an upright body facing `yaw`)
    /// at horizontal position `(x, y)`.
    fn frame(yaw: f64, x: f32, y: f32, stats: &Stats) -> Vec<f32> {
        let r = Mat3::from_axis_rotation(2, yaw)
            .mul(&Mat3::from_axis_rotation(0, std::f64::consts::FRAC_PI_2));
        let mut f = vec![0f32; DIMS];
        for (k, v) in r.to_6d().iter().enumerate() {
            stats.set(&mut f, ROT6D_START + k, *v as f32);
        }
        stats.set(&mut f, ROOT_HORIZONTAL[0], x);
        stats.set(&mut f, ROOT_HORIZONTAL[1], y);
        f
    }

    #[test]
    fn turning_by_an_angle_adds_it_to_the_heading_and_rotates_the_path() {
        let (scale, shift) = uneven_stats();
        let stats = Stats {
            scale: &scale,
            shift: &shift,
        };
        let mut f = frame(0.3, 1.0, 0.0, &stats);
        let h0 = heading(&f, &stats);
        turn(&mut f, 0.5, &stats);
        let h1 = heading(&f, &stats);
        assert!((h1 - h0 - 0.5).abs() < 1e-5, "{h0} → {h1}");
        let expect = frame(0.8, 0.5f32.cos(), 0.5f32.sin(), &stats);
        for (a, b) in f.iter().zip(&expect) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }

    #[test]
    fn canonical_windows_face_plus_x_and_turn_back_exactly() {
        let (scale, shift) = uneven_stats();
        let stats = Stats {
            scale: &scale,
            shift: &shift,
        };
        let mut w: Vec<f32> = [2.5, 2.7, 3.0]
            .iter()
            .enumerate()
            .flat_map(|(i, &yaw)| frame(yaw, 0.1 * i as f32, -0.2 * i as f32, &stats))
            .collect();
        w.extend(frame(-1.0, 0.0, 0.0, &stats));
        let orig = w.clone();
        let angles = canonicalise(&mut w, 2, &stats);
        assert_eq!(angles.len(), 2);
        for win in w.chunks(2 * DIMS) {
            assert!(heading(&win[..DIMS], &stats).abs() < 1e-5);
        }
        for (win, &a) in w.chunks_mut(2 * DIMS).zip(&angles) {
            turn(win, -a, &stats);
        }
        for (a, b) in w.iter().zip(&orig) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
    }

    #[test]
    fn edge_overwrite_copies_the_previous_half_in_its_own_heading_frame() {
        let (scale, shift) = uneven_stats();
        let stats = Stats {
            scale: &scale,
            shift: &shift,
        };
        let (n, half) = (4, 2);
        // Two windows turning and walking; the second one's first half is to be overwritten.
        let mut x: Vec<f32> = (0..2 * n)
            .flat_map(|f| frame(0.4 * f as f32 as f64, 0.3 * f as f32, 0.1, &stats))
            .collect();
        let orig = x.clone();
        overwrite_first_halves_turned(&mut x, n, half, &stats);
        let second = &x[n * DIMS..];
        assert!(heading(&second[..DIMS], &stats).abs() < 1e-5);
        assert!(second[ROOT_HORIZONTAL[0]].abs() < 1e-6);
        // Turned back by the previous window's heading at `half`, the copy is that window's
        // second half moved to the origin.
        let mut copy = second[..half * DIMS].to_vec();
        turn(&mut copy, heading(&orig[half * DIMS..], &stats), &stats);
        for (f, got) in copy.chunks(DIMS).enumerate() {
            let want = &orig[(half + f) * DIMS..(half + f + 1) * DIMS];
            for c in (ROT6D_START..ROT6D_START + 6).chain(ROOT_HORIZONTAL) {
                let w = if ROOT_HORIZONTAL.contains(&c) {
                    want[c] - orig[half * DIMS + c]
                } else {
                    want[c]
                };
                assert!(
                    (got[c] - w).abs() < 1e-4,
                    "frame {f} channel {c}: {} vs {w}",
                    got[c]
                );
            }
        }
        // The first window and the second's own second half are untouched.
        assert_eq!(&x[..n * DIMS], &orig[..n * DIMS]);
        assert_eq!(&x[(n + half) * DIMS..], &orig[(n + half) * DIMS..]);
    }
}
