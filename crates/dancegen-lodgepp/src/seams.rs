//! Continuity where a window's generated frames meet its hard cues (not part of Lodge++).
//!
//! The sampler writes the shared boundary frames into every window after each step. Lodge++
//! relies on the network continuing them; the small shipped model does not. It sees positions
//! only through rotary attention, so it has no notion of "window frame 0". Measured on the
//! bundled model: its generated root sat ~1.2 m from the cued frames four frames into every
//! window, and joint jerk at the seams was 4-6x the rest of the dance. So, per window:
//! - Root, horizontal: the generated frames are translated onto the path the cued frames set
//!   (exact for the dance: horizontal position is translation-invariant). The cued frames'
//!   velocity then hands over to the generated one over [`BLEND_FRAMES`].
//! - Root height: cued at both ends, so it gets a linear ramp between the two seam offsets.
//! - Joint rotations: the generated rotation next to each seam is turned onto the
//!   continuation of the cued ones, and the turn fades out over [`BLEND_FRAMES`] along the
//!   geodesic.
//!
//! [`anchor_windows`] reports the root corrections, so the evaluation can show how large they
//! are.

use dancegen_motion::rotation::Mat3;

use crate::layout::{DIMS, ROOT_HEIGHT, ROOT_HORIZONTAL, rot6d};

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
    anchor_windows_blended(windows, n, cues, SeamBlend::Fade)
}

/// How the generated rotations next to a seam are turned onto the cued ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeamBlend {
    /// The turn that lands the first generated frame one cued step on, faded out by a raised
    /// cosine over [`BLEND_FRAMES`]: the position continues the cues, the velocity right
    /// after the seam is still the network's (the Lodge++ sampler's windows, whose generated
    /// frames were trained to meet these cues).
    Fade,
    /// The same turn plus the difference of the angular velocities, faded out by cubic
    /// Hermite curves over [`BLEND_FRAMES`], so that both the rotation and its velocity
    /// continue the cued frames (editing: the kept frames come from another dance, and the
    /// network's velocity at a join can be half theirs; with [`SeamBlend::Fade`] the joins of
    /// a regenerated range had a boundary-jerk ratio of 2-5).
    Hermite,
    /// [`SeamBlend::Hermite`] plus the difference of the angular accelerations, faded out by
    /// quintic Hermite curves, so that the acceleration continues the cued frames too: a jump
    /// of acceleration at a join is a spike of jerk, the quantity the boundary-jerk ratio
    /// measures.
    Quintic,
}

/// [`anchor_windows`] with the rotation blend chosen.
pub fn anchor_windows_blended(
    windows: &mut [f32],
    n: usize,
    cues: &[CuedFrames],
    blend: SeamBlend,
) -> SeamCorrection {
    let mut worst = SeamCorrection::default();
    for (w, cue) in cues.iter().enumerate() {
        let win = &mut windows[w * n * DIMS..(w + 1) * n * DIMS];
        let (head, tail) = (cue.head.min(n), cue.tail.min(n));
        if head + tail >= n {
            continue;
        }
        // Horizontal: the generated frames are shifted onto the path of the cued frames, and
        // the cued frames' velocity hands over to the generated one over BLEND_FRAMES.
        for &c in &ROOT_HORIZONTAL {
            let at = |f: usize| win[f * DIMS + c];
            if head == 0 {
                let shift = -at(0);
                for f in 0..n {
                    win[f * DIMS + c] += shift;
                }
                worst.horizontal = worst.horizontal.max(shift.abs());
                continue;
            }
            let (cue, gen_first) = (head - 1, head);
            let v_cue = if cue >= 1 { at(cue) - at(cue - 1) } else { 0.0 };
            let v_gen = if gen_first + 1 < n {
                at(gen_first + 1) - at(gen_first)
            } else {
                0.0
            };
            let shift = at(cue) + v_cue - at(gen_first);
            let mut extra = 0.0;
            for (k, f) in (gen_first..n).enumerate() {
                if k > 0 && k < BLEND_FRAMES {
                    extra += (v_cue - v_gen) * fade(k);
                }
                win[f * DIMS + c] += shift + extra;
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
        blend_rotation_seams(win, n, head, tail, blend);
    }
    worst
}

/// Generated frames over which a seam's offset fades out: two primitives (16 frames, 0.53 s).
/// The jerk of a raised-cosine fade falls with the cube of its length, and the model's
/// mismatch with the cues is what it fades. Chosen on the training songs (issue 41 part 5,
/// `tools/solo_sampling_validation.sh`, 12 dances, the foot lock without leg IK): 8 / 12 / 16 /
/// 24 frames gave a boundary-jerk ratio of 1.51 / 1.29 / 1.22 / 1.10, FID_k 118.6 / 117.6 /
/// 116.3 / 111.5 and the largest frame step 0.42 / 0.42 / 0.42 / 0.53 m; 16 is the longest
/// that adds no jump. Shorter blends keep more of the pose the model reaches just after the
/// cue; 8 (one primitive) was the first choice.
pub const BLEND_FRAMES: usize = 16;

/// Raised-cosine weight of generated frame `k` after a seam: 1 at the seam, 0 from
/// [`BLEND_FRAMES`] on, flat at both ends.
fn fade(k: usize) -> f32 {
    if k >= BLEND_FRAMES {
        return 0.0;
    }
    0.5 + 0.5 * (std::f32::consts::PI * k as f32 / BLEND_FRAMES as f32).cos()
}

/// Quintic Hermite weights at `u = k / len`: value 1 (first), slope 1 per frame (second) and
/// curvature 1 per frame² (third) at the seam, each with the other two derivatives 0 there;
/// all three reach 0 with zero slope and curvature at `u = 1`.
pub(crate) fn quintic(u: f64, len: f64) -> (f64, f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3, u4, u5) = (u * u, u.powi(3), u.powi(4), u.powi(5));
    (
        1.0 - 10.0 * u3 + 15.0 * u4 - 6.0 * u5,
        len * (u - 6.0 * u3 + 8.0 * u4 - 3.0 * u5),
        len * len * (0.5 * u2 - 1.5 * u3 + 1.5 * u4 - 0.5 * u5),
    )
}

/// Cubic Hermite weights at `u = k / len`: the first has value 1 and slope 0 at the seam
/// (`h00`), the second value 0 and slope 1 per frame (`len · h10`); both reach 0 with zero
/// slope at `u = 1`.
fn hermite(u: f64, len: f64) -> (f64, f64) {
    let u = u.clamp(0.0, 1.0);
    let (u2, u3) = (u * u, u * u * u);
    (2.0 * u3 - 3.0 * u2 + 1.0, len * (u3 - 2.0 * u2 + u))
}

fn rotation(win: &[f32], f: usize, j: usize) -> Mat3 {
    let c = rot6d(j, 0);
    let d: [f64; 6] = std::array::from_fn(|k| f64::from(win[f * DIMS + c + k]));
    Mat3::from_6d(&d)
}

fn set_rotation(win: &mut [f32], f: usize, j: usize, r: &Mat3) {
    let c = rot6d(j, 0);
    for (k, v) in r.to_6d().iter().enumerate() {
        win[f * DIMS + c + k] = *v as f32;
    }
}

/// Every joint's generated rotations next to a seam are turned towards the continuation of the
/// cued rotations (the cued frames' last rotation advanced by their own last step), the turn
/// fading out over [`BLEND_FRAMES`]. Turning along the geodesic keeps every frame a rotation;
/// blending 6D vectors linearly can pass near degenerate ones when the two sides disagree.
fn blend_rotation_seams(win: &mut [f32], n: usize, head: usize, tail: usize, blend: SeamBlend) {
    let (first, last) = (head, n - tail - 1);
    // (cued frame next to the seam, the cued frames before it if any (nearest first),
    // generated frames outward)
    let mut seams: Vec<(usize, Vec<usize>, Vec<usize>)> = Vec::new();
    if head > 0 {
        let before = (0..head - 1).rev().take(2).collect();
        seams.push((
            head - 1,
            before,
            (first..=last).take(BLEND_FRAMES).collect(),
        ));
    }
    if tail > 0 {
        let c = n - tail;
        let before = (c + 1..n).take(2).collect();
        seams.push((c, before, (first..=last).rev().take(BLEND_FRAMES).collect()));
    }
    for j in 0..24 {
        for (cue, before, frames) in &seams {
            let rc = rotation(win, *cue, j);
            let step_of = |a: &Mat3, b: usize| a.mul(&rotation(win, b, j).transpose());
            let step = before.first().map_or(Mat3::IDENTITY, |&b| step_of(&rc, b));
            let target = step.mul(&rc);
            let offset = target.mul(&rotation(win, frames[0], j).transpose());
            let aa = offset.to_axis_angle();
            // Hermite: the velocity mismatch, cued step minus generated step (both in the
            // direction away from the cue, as rotation vectors), also faded in.
            let dv = match (blend, frames.get(1)) {
                (SeamBlend::Hermite | SeamBlend::Quintic, Some(&g1)) => {
                    let cued = step.to_axis_angle();
                    let made = rotation(win, g1, j)
                        .mul(&rotation(win, frames[0], j).transpose())
                        .to_axis_angle();
                    [cued[0] - made[0], cued[1] - made[1], cued[2] - made[2]]
                }
                _ => [0.0; 3],
            };
            // Quintic: the acceleration mismatch, the cued frames' change of step minus the
            // generated frames' (rotation vectors per frame²).
            let da = match (blend, before.get(1), frames.get(1), frames.get(2)) {
                (SeamBlend::Quintic, Some(&b2), Some(&g1), Some(&g2)) => {
                    let b1 = before[0];
                    let older = rotation(win, b1, j).mul(&rotation(win, b2, j).transpose());
                    let (s1, s0) = (step.to_axis_angle(), older.to_axis_angle());
                    let r = |f: usize| rotation(win, f, j);
                    let m1 = r(g1).mul(&r(frames[0]).transpose()).to_axis_angle();
                    let m2 = r(g2).mul(&r(g1).transpose()).to_axis_angle();
                    std::array::from_fn(|i| (s1[i] - s0[i]) - (m2[i] - m1[i]))
                }
                _ => [0.0; 3],
            };
            let len = frames.len().max(1) as f64;
            for (k, &f) in frames.iter().enumerate() {
                let (w, wv, wa) = match blend {
                    SeamBlend::Fade => (f64::from(fade(k)), 0.0, 0.0),
                    SeamBlend::Hermite => {
                        let (w, wv) = hermite(k as f64 / len, len);
                        (w, wv, 0.0)
                    }
                    SeamBlend::Quintic => quintic(k as f64 / len, len),
                };
                let turn = Mat3::from_axis_angle(std::array::from_fn(|i| {
                    aa[i] * w + dv[i] * wv + da[i] * wa
                }));
                let r = turn.mul(&rotation(win, f, j));
                set_rotation(win, f, j, &r);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Joint whose rotation turns steadily in [`walking`].
    const TURNING: usize = 2;

    /// A window whose root walks 0.1 per frame in x and bobs in height, every joint at rest
    /// except [`TURNING`], which turns 0.05 rad per frame about z.
    fn walking(n: usize) -> Vec<f32> {
        let mut w = vec![0f32; n * DIMS];
        for f in 0..n {
            w[f * DIMS + ROOT_HORIZONTAL[0]] = 0.1 * f as f32;
            w[f * DIMS + ROOT_HORIZONTAL[1]] = -0.05 * f as f32;
            w[f * DIMS + ROOT_HEIGHT] = 1.0 + 0.005 * (f as f32 * 0.7).sin();
            for j in 0..24 {
                let angle = if j == TURNING { 0.05 * f as f64 } else { 0.0 };
                set_rotation(&mut w, f, j, &Mat3::from_axis_angle([0.0, 0.0, angle]));
            }
        }
        w
    }

    fn rotations_close(a: &[f32], b: &[f32], f: usize, tol: f32) -> bool {
        (7..DIMS).all(|c| (a[f * DIMS + c] - b[f * DIMS + c]).abs() < tol)
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
            for ch in [ROOT_HORIZONTAL[0], ROOT_HORIZONTAL[1]] {
                let (got, want) = (w[f * DIMS + ch], truth[f * DIMS + ch]);
                assert!(
                    (got - want).abs() < 1e-4,
                    "frame {f} channel {ch}: {got} vs {want}"
                );
            }
            // A steady turn continues across the seams: nothing to correct.
            assert!(
                rotations_close(&w, &truth, f, 1e-5),
                "frame {f} rotations moved"
            );
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
    fn a_rotation_jump_at_a_seam_fades_out_along_the_geodesic() {
        let n = 64;
        let truth = walking(n);
        let mut w = truth.clone();
        // The generated frames turn joint 5 by an extra 0.8 rad about x.
        let extra = Mat3::from_axis_angle([0.8, 0.0, 0.0]);
        for f in 4..n - 4 {
            set_rotation(&mut w, f, 5, &extra.mul(&rotation(&truth, f, 5)));
        }
        let jumped = w.clone();
        anchor_windows(&mut w, n, &[CuedFrames { head: 4, tail: 4 }]);
        // At both seams the generated frame continues the cued ones (the joint is at rest).
        for f in [4, n - 5] {
            assert!(
                rotations_close(&w, &truth, f, 1e-5),
                "frame {f} not continued"
            );
        }
        // Between the fades the model's pose is kept; cued frames are untouched.
        for f in 4 + BLEND_FRAMES..n - 4 - BLEND_FRAMES {
            assert!(rotations_close(&w, &jumped, f, 1e-6), "frame {f} changed");
        }
        for f in (0..4).chain(n - 4..n) {
            assert!(
                rotations_close(&w, &truth, f, 1e-7),
                "cued frame {f} changed"
            );
        }
        // Inside a fade every frame is still a rotation, and the turn shrinks steadily.
        let angle = |f: usize| {
            let a = rotation(&w, f, 5)
                .mul(&rotation(&truth, f, 5).transpose())
                .to_axis_angle();
            (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
        };
        for f in 5..4 + BLEND_FRAMES {
            assert!(angle(f) >= angle(f - 1) - 1e-6, "frame {f}");
            assert!((rotation(&w, f, 5).determinant() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn the_root_velocity_hands_over_at_a_seam() {
        let n = 32;
        let mut w = walking(n);
        // The generated frames walk 0.3 per frame instead of the cued 0.1.
        for f in 4..n {
            w[f * DIMS + ROOT_HORIZONTAL[0]] = 5.0 + 0.3 * (f - 4) as f32;
        }
        anchor_windows(&mut w, n, &[CuedFrames { head: 4, tail: 4 }]);
        let x = |f: usize| w[f * DIMS + ROOT_HORIZONTAL[0]];
        assert!(
            (x(4) - x(3) - 0.1).abs() < 1e-5,
            "first step keeps the cued speed"
        );
        for f in 5..4 + BLEND_FRAMES {
            let (a, b) = (x(f - 1) - x(f - 2), x(f) - x(f - 1));
            assert!(
                b >= a - 1e-5 && b <= 0.3 + 1e-5,
                "frame {f}: step {b} after {a}"
            );
        }
        for f in 4 + BLEND_FRAMES..n {
            assert!(
                (x(f) - x(f - 1) - 0.3).abs() < 1e-5,
                "frame {f}: generated speed"
            );
        }
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
