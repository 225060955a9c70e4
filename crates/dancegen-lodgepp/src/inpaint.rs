//! Editing a dance: the frames and channels that are known stay, the rest is generated to go
//! with them and the music, by PDDM inpainting (the mechanism of the Lodge++ sampler's shared
//! boundary frames, generalised to any known frames).
//!
//! Each maximal run of frames with something unknown is covered by windows of the model's
//! length, one after another ([`plan_windows`]):
//! - a run that fits with [`BOUNDARY_FRAMES`] known frames on each side gets one window
//!   centred on it, so it sees known motion before and after;
//! - a longer run is generated window after window, each continuing the last
//!   [`BOUNDARY_FRAMES`] generated frames of the previous one (the autoregressive sampler's
//!   step), each writing back at most `n − 2·BOUNDARY_FRAMES` frames so that the run's last
//!   window still reaches past its end.
//!
//! In a window every known value is a hard cue and a fully known frame is also a primitive,
//! as in training. The root's horizontal position is cued only where training shows it: on
//! the frames before the run (relative to the window's first frame, the representation's
//! origin), or everywhere when it is known everywhere in the window (e.g. kept legs and
//! root). The small model does not continue its cues by itself, so each window's generated
//! frames get the Lodge++ sampler's seam treatment ([`crate::seams::anchor_windows_blended`]:
//! root moved onto the cued path, height and rotations blended into the cued frames on both
//! sides, the rotations with their velocity, [`SeamBlend::Hermite`]). After the run the network places the root itself; the run is then moved so that
//! it meets the known path there too: by a linear ramp between the mismatches measured at
//! the frames just before and just after it.
//!
//! Known values are copied into the result unchanged, so kept frames are exactly kept.

use dancegen_nn::burn;
use dancegen_nn::progress::{Cancelled, StepHook};

use burn::tensor::Device;

use crate::bundle::SoloModel;
use crate::choreo_gpt::MUSIC_DIMS;
use crate::config::BOUNDARY_FRAMES;
use crate::layout::{DIMS, ROOT_HORIZONTAL};
use crate::pipeline::{CuedWindow, GenerateOptions};
use crate::primitives::WindowPrimitives;
use crate::rotation_tracks::bridge_short_rows;
use crate::seams::{CuedFrames, SeamBlend, anchor_windows_blended};

/// What is known of a dance: raw EDGE-151 frames `[T, 151]` (Z-up, absolute root as the
/// representation stores it) and a mask of the same shape, 1 where the value is known.
#[derive(Clone, Debug, PartialEq)]
pub struct KnownFrames {
    pub values: Vec<f32>,
    pub mask: Vec<f32>,
}

impl KnownFrames {
    pub fn frames(&self) -> usize {
        self.values.len() / DIMS
    }

    fn known(&self, f: usize, c: usize) -> bool {
        self.mask[f * DIMS + c] > 0.0
    }

    /// Whether frame `f` has a channel to generate.
    pub fn needs(&self, f: usize) -> bool {
        (0..DIMS).any(|c| !self.known(f, c))
    }

    fn root_known(&self, f: usize) -> bool {
        ROOT_HORIZONTAL.iter().all(|&c| self.known(f, c))
    }
}

/// One window of an edit: it starts at frame `start` and writes back frames `writes`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EditWindow {
    pub start: usize,
    pub writes: std::ops::Range<usize>,
}

/// The windows of `n` frames that generate every frame `needs` marks, over `needs.len()`
/// frames (module documentation).
pub fn plan_windows(needs: &[bool], n: usize) -> Vec<EditWindow> {
    assert!(
        n > 2 * BOUNDARY_FRAMES,
        "windows of {n} frames are too short"
    );
    let total = needs.len();
    let mut out = Vec::new();
    let mut f = 0;
    while f < total {
        if !needs[f] {
            f += 1;
            continue;
        }
        let end = (f..total).find(|&g| !needs[g]).unwrap_or(total);
        let rest = end - f;
        let (start, writes) = if rest + 2 * BOUNDARY_FRAMES <= n {
            (f.saturating_sub((n - rest) / 2), f..end)
        } else {
            let s = f.saturating_sub(BOUNDARY_FRAMES);
            (s, f..end.min(s + n - BOUNDARY_FRAMES))
        };
        let start = start.min(total.saturating_sub(n));
        f = writes.end;
        out.push(EditWindow { start, writes });
    }
    out
}

/// An edited dance.
pub struct Inpainted {
    /// Raw EDGE-151 frames `[T, 151]`: the known values, the generated ones elsewhere.
    pub frames: Vec<f32>,
    pub windows: usize,
    /// Largest root move (metres) that joined a generated run to the known path.
    pub largest_join_correction_m: f32,
}

impl SoloModel {
    /// Generates what `known` leaves unknown, for `music` `[T, 35]` (the same frames).
    pub fn inpaint_hooked(
        &self,
        music: &[f32],
        known: &KnownFrames,
        opts: &GenerateOptions,
        device: &Device,
        grad_device: &Device,
        hook: &dyn StepHook,
    ) -> Result<Inpainted, Cancelled> {
        let total = known.frames();
        assert_eq!(music.len(), total * MUSIC_DIMS, "music for every frame");
        let n = self.config.pddm.pddm.window;
        let needs: Vec<bool> = (0..total).map(|f| known.needs(f)).collect();
        let plan = plan_windows(&needs, n);
        let (scale, shift) = self.pddm.denorm.host();
        let all_known_root = (0..total).all(|f| known.root_known(f));
        let mut buf = known.values.clone();
        let mut done = known.mask.clone();
        // The network's own root x/y at the frames just before and after each run.
        let mut mismatch: Vec<(usize, usize, [f32; 2], [f32; 2])> = Vec::new();
        for (wi, w) in plan.iter().enumerate() {
            let len = n.min(total - w.start);
            let frame = |f: usize| w.start + f.min(len - 1);
            let origin = ROOT_HORIZONTAL.map(|c| buf[w.start * DIMS + c]);
            let head = w.writes.start - w.start;
            let mut prims = WindowPrimitives::empty(n);
            let mut cue_v = vec![0f32; n * DIMS];
            let mut cue_m = vec![0f32; n * DIMS];
            for f in 0..len {
                let g = w.start + f;
                if w.writes.contains(&g) {
                    continue;
                }
                let with_root = f < head || all_known_root;
                let mut raw = buf[g * DIMS..(g + 1) * DIMS].to_vec();
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    raw[c] -= origin[k];
                }
                let norm: Vec<f32> = (0..DIMS).map(|c| (raw[c] - shift[c]) / scale[c]).collect();
                let full = (0..DIMS).all(|c| done[g * DIMS + c] > 0.0);
                if full {
                    prims.put(f, &norm, with_root);
                }
                for c in 0..DIMS {
                    let cue =
                        done[g * DIMS + c] > 0.0 && (with_root || !ROOT_HORIZONTAL.contains(&c));
                    if cue {
                        cue_v[f * DIMS + c] = norm[c];
                        cue_m[f * DIMS + c] = 1.0;
                    }
                }
            }
            let music_window: Vec<f32> = (0..n)
                .flat_map(|f| {
                    let g = frame(f);
                    music[g * MUSIC_DIMS..(g + 1) * MUSIC_DIMS].iter().copied()
                })
                .collect();
            let window = CuedWindow {
                music: music_window,
                prims,
                cue_v,
                cue_m,
                cued: true,
            };
            let mut x =
                self.sample_cued_window(window, opts, (wi, plan.len()), device, grad_device, hook)?;
            self.to_raw(&mut x);
            bridge_short_rows(&mut x, n);
            // The small model does not continue its cues by itself (`crate::seams`): the run's
            // frames are moved onto the cued frames before and after it, as the Lodge++
            // sampler's windows are.
            let tail = (w.writes.end..w.start + len)
                .take_while(|&g| (0..DIMS).all(|c| done[g * DIMS + c] > 0.0))
                .count();
            let span = w.writes.end - w.start + tail;
            anchor_windows_blended(
                &mut x[..span * DIMS],
                span,
                &[CuedFrames { head, tail }],
                SeamBlend::Hermite,
            );
            for f in x.chunks_mut(DIMS) {
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    f[c] += origin[k];
                }
            }
            let root_at = |g: usize| ROOT_HORIZONTAL.map(|c| x[(g - w.start) * DIMS + c]);
            let known_root = |buf: &[f32], g: usize| ROOT_HORIZONTAL.map(|c| buf[g * DIMS + c]);
            let a = w.writes.start;
            let run_starts = a == 0 || !needs[a - 1];
            let b = w.writes.end;
            let run_ends = b == total || !needs[b];
            if run_starts {
                let before = (a > w.start).then(|| {
                    let (g, k) = (root_at(a - 1), known_root(&buf, a - 1));
                    [g[0] - k[0], g[1] - k[1]]
                });
                mismatch.push((a, b, before.unwrap_or([f32::NAN; 2]), [f32::NAN; 2]));
            }
            for g in w.writes.clone() {
                for c in 0..DIMS {
                    let i = g * DIMS + c;
                    if done[i] <= 0.0 {
                        buf[i] = x[(g - w.start) * DIMS + c];
                    }
                }
            }
            if let Some(last) = mismatch.last_mut() {
                last.1 = b;
                if run_ends && b < total && b < w.start + len && known.root_known(b) {
                    let (g, k) = (root_at(b), known_root(&buf, b));
                    last.3 = [g[0] - k[0], g[1] - k[1]];
                }
            }
            for g in w.writes.clone() {
                done[g * DIMS..(g + 1) * DIMS].fill(1.0);
            }
        }
        let largest = join_runs(&mut buf, known, &mismatch);
        if opts.foot_lock {
            lock_feet_in_runs(&mut buf, known, &mismatch, opts);
        }
        for &(a, b, _, _) in &mismatch {
            hand_over_root_velocity(&mut buf, known, a, b);
        }
        Ok(Inpainted {
            frames: buf,
            windows: plan.len(),
            largest_join_correction_m: largest,
        })
    }
}

/// Known frames on each side of a run that the foot lock sees with it.
pub const FOOT_LOCK_CONTEXT: usize = 30;

/// The whole-dance sampler's foot lock (root lock, then leg IK) on each made run, with
/// [`FOOT_LOCK_CONTEXT`] known frames on each side so that its feet continue the planted
/// ones there. Only the run's frames are written back; the root path the lock moved is joined
/// to the known one again as in [`join_runs`].
fn lock_feet_in_runs(
    buf: &mut [f32],
    known: &KnownFrames,
    runs: &[(usize, usize, [f32; 2], [f32; 2])],
    opts: &GenerateOptions,
) {
    let total = buf.len() / DIMS;
    for &(a, b, _, _) in runs {
        let lo = a.saturating_sub(FOOT_LOCK_CONTEXT);
        let hi = (b + FOOT_LOCK_CONTEXT).min(total);
        let mut seg = buf[lo * DIMS..hi * DIMS].to_vec();
        crate::planted_feet::lock_planted_feet_with(&mut seg, opts.foot_lock_rule);
        if opts.foot_ik {
            crate::planted_feet::pin_planted_feet_with(&mut seg, opts.foot_lock_rule);
        }
        let moved =
            |g: usize| ROOT_HORIZONTAL.map(|c| seg[(g - lo) * DIMS + c] - buf[g * DIMS + c]);
        let before = if a > lo { moved(a - 1) } else { [f32::NAN; 2] };
        let after = if b < hi { moved(b) } else { [f32::NAN; 2] };
        buf[a * DIMS..b * DIMS].copy_from_slice(&seg[(a - lo) * DIMS..(b - lo) * DIMS]);
        join_runs(buf, known, &[(a, b, before, after)]);
    }
}

/// Frames over which a run's root velocity is handed over to the kept frames'.
pub const VELOCITY_HANDOVER_FRAMES: usize = 16;

/// Makes the root's horizontal velocity continuous where the made run `[a, b)` meets kept
/// frames whose root is known: the run's first (last) frame is moved so that its step from
/// (to) the kept frame is the kept frames' own step, and the move fades out into the run over
/// [`VELOCITY_HANDOVER_FRAMES`] (weight `(1 − k/L)²`, no jump of its own). The positions at
/// the joins already meet ([`join_runs`]); this removes the kink of velocity there.
fn hand_over_root_velocity(buf: &mut [f32], known: &KnownFrames, a: usize, b: usize) {
    let total = buf.len() / DIMS;
    let root = |buf: &[f32], f: usize| ROOT_HORIZONTAL.map(|c| buf[f * DIMS + c]);
    let len = (b - a).min(VELOCITY_HANDOVER_FRAMES);
    let weight = |k: usize| {
        let u = 1.0 - k as f32 / len.max(1) as f32;
        u * u
    };
    if a >= 2 && known.root_known(a - 1) && known.root_known(a - 2) && !known.root_known(a) {
        let (p2, p1, p0) = (root(buf, a - 2), root(buf, a - 1), root(buf, a));
        let d = [0, 1].map(|i| (p1[i] - p2[i]) - (p0[i] - p1[i]));
        for k in 0..len {
            for (i, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                buf[(a + k) * DIMS + c] += d[i] * weight(k);
            }
        }
    }
    if b + 1 < total && known.root_known(b) && known.root_known(b + 1) && b > a {
        let (p0, p1, p2) = (root(buf, b - 1), root(buf, b), root(buf, b + 1));
        let d = [0, 1].map(|i| (p1[i] - p0[i]) - (p2[i] - p1[i]));
        for k in 0..len {
            for (i, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                buf[(b - 1 - k) * DIMS + c] += d[i] * weight(k);
            }
        }
    }
}

/// Moves each generated run `[a, b)` whose root was not known onto the known path: by the
/// mismatch before it at `a`, the one after it at `b`, and a linear ramp between (one of
/// them alone where the other side has no known frame). Returns the largest move.
fn join_runs(
    buf: &mut [f32],
    known: &KnownFrames,
    runs: &[(usize, usize, [f32; 2], [f32; 2])],
) -> f32 {
    let mut largest = 0f32;
    for &(a, b, before, after) in runs {
        let (before, after) = match (before[0].is_finite(), after[0].is_finite()) {
            (true, true) => (before, after),
            (true, false) => (before, before),
            (false, true) => (after, after),
            (false, false) => continue,
        };
        let span = (b - a + 1) as f32;
        for g in a..b {
            if known.root_known(g) {
                continue;
            }
            let u = (g - a + 1) as f32 / span;
            for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                let d = before[k] + (after[k] - before[k]) * u;
                buf[g * DIMS + c] -= d;
                largest = largest.max(d.abs());
            }
        }
    }
    largest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn needs(spec: &[(usize, usize)], total: usize) -> Vec<bool> {
        let mut v = vec![false; total];
        for &(a, b) in spec {
            v[a..b].fill(true);
        }
        v
    }

    #[test]
    fn a_short_range_gets_one_centred_window() {
        let plan = plan_windows(&needs(&[(300, 330)], 600), 128);
        assert_eq!(plan.len(), 1);
        let w = &plan[0];
        assert_eq!(w.writes, 300..330);
        assert_eq!(w.start, 300 - 49);
        assert!(w.start + 128 >= 330 + BOUNDARY_FRAMES);
    }

    #[test]
    fn a_long_range_is_covered_window_after_window_and_ends_inside_a_window() {
        let plan = plan_windows(&needs(&[(100, 400)], 600), 128);
        let mut covered = vec![false; 600];
        for w in &plan {
            for g in w.writes.clone() {
                assert!(!covered[g], "frame {g} written twice");
                covered[g] = true;
            }
            assert!(
                w.writes.start >= w.start + BOUNDARY_FRAMES,
                "{w:?} has a known head"
            );
            assert!(w.writes.end <= w.start + 128);
        }
        assert_eq!(covered, needs(&[(100, 400)], 600));
        let last = plan.last().unwrap();
        assert!(
            last.start + 128 >= 400 + BOUNDARY_FRAMES,
            "the last window sees past the run"
        );
    }

    #[test]
    fn ranges_at_the_ends_and_short_dances_stay_inside() {
        for (spec, total) in [
            (vec![(0, 40)], 600),
            (vec![(560, 600)], 600),
            (vec![(30, 600)], 600),
            (vec![(10, 50)], 90),
            (vec![(0, 90)], 90),
        ] {
            let want = needs(&spec, total);
            let plan = plan_windows(&want, 128);
            let mut covered = vec![false; total];
            for w in &plan {
                assert!(w.start + 128 >= w.writes.end.min(total) && w.start <= w.writes.start);
                for g in w.writes.clone() {
                    covered[g] = true;
                }
            }
            assert_eq!(covered, want, "{spec:?} of {total}");
        }
    }

    #[test]
    fn join_runs_ramps_between_the_two_mismatches() {
        let t = 6;
        let mut buf = vec![0f32; t * DIMS];
        let mut mask = vec![1f32; t * DIMS];
        for g in 1..5 {
            mask[g * DIMS..(g + 1) * DIMS].fill(0.0);
        }
        let known = KnownFrames {
            values: buf.clone(),
            mask,
        };
        let largest = join_runs(&mut buf, &known, &[(1, 5, [0.0, 0.0], [5.0, -5.0])]);
        let x: Vec<f32> = (0..t).map(|g| buf[g * DIMS + ROOT_HORIZONTAL[0]]).collect();
        assert_eq!(x, vec![0.0, -1.0, -2.0, -3.0, -4.0, 0.0]);
        assert_eq!(largest, 4.0);
    }
}
