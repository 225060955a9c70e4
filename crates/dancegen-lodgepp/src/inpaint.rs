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
use crate::layout::{DIMS, ROOT_HEIGHT, ROOT_HORIZONTAL};
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

/// A made run `[a, b)` and where the generated root's floor position missed the known one
/// (generated − known): at `a − 1`, at root-known frames inside the run (a keyframe's mark, a
/// path) and at `b`, in frame order.
#[derive(Clone, Debug, Default, PartialEq)]
struct Run {
    a: usize,
    b: usize,
    misses: Vec<(usize, [f32; 2])>,
}

/// Frames over which a generated run eases into the values known on some of its frames (a
/// keyframe's pose): the difference at the known frame fades out (smoothstep) over this many
/// frames on each side, or is interpolated between two known frames closer than twice it.
pub const EASE_FRAMES: usize = 20;

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
        let mut runs: Vec<Run> = Vec::new();
        for (wi, w) in plan.iter().enumerate() {
            let len = n.min(total - w.start);
            let frame = |f: usize| w.start + f.min(len - 1);
            let origin = ROOT_HORIZONTAL.map(|c| buf[w.start * DIMS + c]);
            let head = w.writes.start - w.start;
            let window_root_known =
                all_known_root || (w.start..w.start + len).all(|g| known.root_known(g));
            let mut prims = WindowPrimitives::empty(n);
            let mut cue_v = vec![0f32; n * DIMS];
            let mut cue_m = vec![0f32; n * DIMS];
            for f in 0..len {
                let g = w.start + f;
                // Frames this window makes are cued in what is known of them (kept joints, a
                // keyframe's pose); the frames around them in everything.
                let in_run = w.writes.contains(&g);
                let with_root = f < head || window_root_known;
                let mut raw = buf[g * DIMS..(g + 1) * DIMS].to_vec();
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    raw[c] -= origin[k];
                }
                let norm: Vec<f32> = (0..DIMS).map(|c| (raw[c] - shift[c]) / scale[c]).collect();
                let full = !in_run && (0..DIMS).all(|c| done[g * DIMS + c] > 0.0);
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
                SeamBlend::Quintic,
            );
            for f in x.chunks_mut(DIMS) {
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    f[c] += origin[k];
                }
            }
            let rel = w.writes.start - w.start..w.writes.end - w.start;
            ease_into_known(&mut x[..span * DIMS], rel, |f, c| {
                let i = (w.start + f) * DIMS + c;
                (done[i] > 0.0).then_some(buf[i])
            });
            let miss = |g: usize| {
                let i = g * DIMS;
                let at = (g - w.start) * DIMS;
                ROOT_HORIZONTAL.map(|c| x[at + c] - buf[i + c])
            };
            let (a, b) = (w.writes.start, w.writes.end);
            if a == 0 || !needs[a - 1] {
                let mut run = Run {
                    a,
                    b,
                    misses: Vec::new(),
                };
                if a > w.start && known.root_known(a - 1) {
                    run.misses.push((a - 1, miss(a - 1)));
                }
                runs.push(run);
            }
            let run = runs.last_mut().expect("a run is open");
            run.b = b;
            for g in w.writes.clone().filter(|&g| known.root_known(g)) {
                run.misses.push((g, miss(g)));
            }
            if (b == total || !needs[b]) && b < w.start + len && known.root_known(b) {
                run.misses.push((b, miss(b)));
            }
            for g in w.writes.clone() {
                for c in 0..DIMS {
                    let i = g * DIMS + c;
                    if done[i] <= 0.0 {
                        buf[i] = x[(g - w.start) * DIMS + c];
                    }
                }
            }
            for g in w.writes.clone() {
                done[g * DIMS..(g + 1) * DIMS].fill(1.0);
            }
        }
        let largest = join_runs(&mut buf, known, &runs);
        if opts.foot_lock {
            let lock = FootLock {
                root: true,
                ik: opts.foot_ik,
                rule: opts.foot_lock_rule,
                max_travel_m: f64::INFINITY,
            };
            lock_feet_in_runs(&mut buf, known, &runs, lock);
        }
        for r in &runs {
            hand_over_root(&mut buf, known, r.a, r.b);
        }
        Ok(Inpainted {
            frames: buf,
            windows: plan.len(),
            largest_join_correction_m: largest,
        })
    }
}

/// The planted-feet pass over a made run and the frames around it
/// ([`crate::planted_feet`]): the root lock (`root`; not for a dancer whose root path is
/// given) and the leg IK (`ik`).
#[derive(Clone, Copy, Debug)]
pub struct FootLock {
    pub root: bool,
    pub ik: bool,
    pub rule: crate::planted_feet::PlantedRule,
    /// The IK leaves a contact run alone whose foot strays farther than this (metres;
    /// [`crate::planted_feet::pin_planted_feet_within`]); `f64::INFINITY`: no bound.
    pub max_travel_m: f64,
}

/// Known frames on each side of a made run that [`join_made_runs`] blends it into.
pub const JOIN_CONTEXT: usize = 8;

/// Joins a dance that another sampler made whole in one pass (`generated`, raw EDGE-151
/// frames `[T, 151]` in the same world as `known`, e.g. a duet's follower) to what `known`
/// keeps, with the treatment the windows of [`SoloModel::inpaint_hooked`] get: each made run
/// is blended into the kept frames around it (root onto the kept path at its start,
/// rotations and height with their velocity, [`SeamBlend::Hermite`]), its root path ramped
/// to meet the kept one at its end, the planted feet of the run locked (`lock`, as the
/// windows' are), the root velocity handed over at both ends, partly known frames eased
/// into, and the root moved onto floor positions known inside a run (the misses there
/// interpolated, [`join_runs`]). Returns the frames (known values exact) and the largest root move that joined a run.
pub fn join_made_runs(
    generated: &[f32],
    known: &KnownFrames,
    lock: Option<FootLock>,
) -> (Vec<f32>, f32) {
    let total = known.frames();
    assert_eq!(
        generated.len(),
        total * DIMS,
        "one generated frame per known one"
    );
    let needs: Vec<bool> = (0..total).map(|f| known.needs(f)).collect();
    let mut buf = known.values.clone();
    let mut runs = Vec::new();
    let mut f = 0;
    while f < total {
        if !needs[f] {
            f += 1;
            continue;
        }
        let a = f;
        while f < total && needs[f] {
            f += 1;
        }
        let b = f;
        let (head, tail) = (a.min(JOIN_CONTEXT), (total - b).min(JOIN_CONTEXT));
        let (lo, hi) = (a - head, b + tail);
        let mut x = generated[lo * DIMS..hi * DIMS].to_vec();
        x[..head * DIMS].copy_from_slice(&known.values[lo * DIMS..a * DIMS]);
        x[(b - lo) * DIMS..].copy_from_slice(&known.values[b * DIMS..hi * DIMS]);
        // Without frames before it, the run keeps its own floor position (the seam
        // treatment would start it at the origin).
        let start = ROOT_HORIZONTAL.map(|c| x[c]);
        anchor_windows_blended(
            &mut x,
            hi - lo,
            &[CuedFrames { head, tail }],
            SeamBlend::Quintic,
        );
        if head == 0 {
            for row in x[..(b - lo) * DIMS].chunks_mut(DIMS) {
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    row[c] += start[k];
                }
            }
        }
        ease_into_known(&mut x, head..b - lo, |g, c| {
            let i = (lo + g) * DIMS + c;
            (known.mask[i] > 0.0).then_some(known.values[i])
        });
        let mut misses = Vec::new();
        if a > 0 && known.root_known(a - 1) {
            misses.push((a - 1, [0.0, 0.0]));
        }
        // Root positions known inside the run (a keyframe's mark, a path): where the run's
        // root missed them, so that the frames between and after follow them.
        for g in (a..b).filter(|&g| known.root_known(g)) {
            let at = (g - lo) * DIMS;
            misses.push((
                g,
                ROOT_HORIZONTAL.map(|c| x[at + c] - known.values[g * DIMS + c]),
            ));
        }
        if b < total && known.root_known(b) && b - a >= 2 {
            // Where the run's own root was heading at the kept frame after it.
            let r = |g: usize| ROOT_HORIZONTAL.map(|c| x[(g - lo) * DIMS + c]);
            let (p1, p2) = (r(b - 1), r(b - 2));
            let want = ROOT_HORIZONTAL.map(|c| known.values[b * DIMS + c]);
            misses.push((b, [0, 1].map(|k| 2.0 * p1[k] - p2[k] - want[k])));
        }
        for g in a..b {
            for c in 0..DIMS {
                let i = g * DIMS + c;
                if known.mask[i] <= 0.0 {
                    buf[i] = x[(g - lo) * DIMS + c];
                }
            }
        }
        runs.push(Run { a, b, misses });
    }
    let largest = join_runs(&mut buf, known, &runs);
    if let Some(lock) = lock {
        lock_feet_in_runs(&mut buf, known, &runs, lock);
    }
    for r in &runs {
        hand_over_root(&mut buf, known, r.a, r.b);
    }
    (buf, largest)
}

/// Eases the made frames `run` of a window (`x`, raw frames) into the values known on some
/// of them, channel by channel (not the root's floor position, which [`join_runs`] moves):
/// the difference between the known value and the generated one at each such frame is added
/// around it, fading out over [`EASE_FRAMES`] (smoothstep, so the motion's own velocity is
/// kept at the known frame and at the fade's end), interpolated between two such frames that
/// are close, and zero at the run's ends where it meets fully known frames (already joined by
/// the seam blend).
fn ease_into_known(
    x: &mut [f32],
    run: std::ops::Range<usize>,
    known: impl Fn(usize, usize) -> Option<f32>,
) {
    let span = x.len() / DIMS;
    let reach = EASE_FRAMES as f32;
    let smooth = |u: f32| {
        let u = u.clamp(0.0, 1.0);
        u * u * (3.0 - 2.0 * u)
    };
    for c in (0..DIMS).filter(|c| !ROOT_HORIZONTAL.contains(c)) {
        // The difference is taken against what the generated motion does across the known
        // frames (a line between the frames on either side of each block of them): a hard
        // cue on a lone frame makes the network put that frame right and leave its
        // neighbours where they were, so the frame's own value says nothing.
        let is_known: Vec<bool> = (0..span).map(|f| known(f, c).is_some()).collect();
        let mut points: Vec<(usize, f32)> = Vec::new();
        let mut f = run.start;
        while f < run.end {
            if !is_known[f] {
                f += 1;
                continue;
            }
            let p = f;
            while f < run.end && is_known[f] {
                f += 1;
            }
            let q = f;
            let lo = p.checked_sub(1).map(|g| x[g * DIMS + c]);
            let hi = (q < span).then(|| x[q * DIMS + c]);
            for g in p..q {
                let line = match (lo, hi) {
                    (Some(a), Some(b)) => a + (b - a) * (g + 1 - p) as f32 / (q + 1 - p) as f32,
                    (Some(a), None) => a,
                    (None, Some(b)) => b,
                    (None, None) => x[g * DIMS + c],
                };
                points.push((g, known(g, c).expect("a known frame") - line));
            }
        }
        if points.is_empty() || points.len() == run.len() {
            continue;
        }
        if run.start > 0 {
            points.insert(0, (run.start - 1, 0.0));
        }
        if run.end < span {
            points.push((run.end, 0.0));
        }
        let mut offset = vec![0f32; span];
        for f in run.clone().filter(|&f| known(f, c).is_none()) {
            let next = points.partition_point(|p| p.0 < f);
            let before = next.checked_sub(1).map(|i| points[i]);
            let after = points.get(next).copied();
            offset[f] = match (before, after) {
                (Some((f0, d0)), Some((f1, d1))) if (f1 - f0) as f32 <= 2.0 * reach => {
                    d0 + (d1 - d0) * smooth((f - f0) as f32 / (f1 - f0) as f32)
                }
                _ => {
                    let fade = |p: Option<(usize, f32)>| {
                        p.map_or(0.0, |(g, d)| d * smooth(1.0 - g.abs_diff(f) as f32 / reach))
                    };
                    fade(before) + fade(after)
                }
            };
        }
        for f in run.clone() {
            match known(f, c) {
                Some(v) => x[f * DIMS + c] = v,
                None => x[f * DIMS + c] += offset[f],
            }
        }
    }
}

/// Known frames on each side of a run that the foot lock sees with it.
pub const FOOT_LOCK_CONTEXT: usize = 30;

/// Frames over which the leg IK of [`lock_feet_in_runs`] fades in from a kept frame next to a
/// made run: a third of a second at 30 fps. Without the fade the IK pinned a foot planted across
/// a join to a place the kept frames' foot is not, and the leg jumped there in one frame: a
/// group edit with a model whose dancers step (tcdiffpp v15: 8-14 s of a 3-dancer dance of
/// feelings.ogg 30-54 s made new) jerked 1.3-2.0 times as much at its joins as elsewhere;
/// 0.5-0.8 without the foot lock, 0.4-0.8 with this fade (docs/group-collapse.md §21).
pub const IK_FADE_FRAMES: usize = 10;

/// The IK's weight on the made frame `d` frames after (or before) a kept one (`d = 0`: the
/// run's first or last frame): 0 there, rising to 1 at [`IK_FADE_FRAMES`] (smootherstep: no
/// step of velocity or acceleration where it starts).
fn ik_fade(d: usize) -> f32 {
    let u = (d as f32 / IK_FADE_FRAMES as f32).min(1.0);
    u * u * u * (u * (6.0 * u - 15.0) + 10.0)
}

/// The whole-dance sampler's foot lock (root lock, then leg IK) on each made run, with
/// [`FOOT_LOCK_CONTEXT`] known frames on each side so that its feet continue the planted
/// ones there. Only the run's frames are written back. Known root positions stay: the root
/// path the lock moved is joined to them again as in [`join_runs`] before the legs are
/// pinned on it.
fn lock_feet_in_runs(buf: &mut [f32], known: &KnownFrames, runs: &[Run], lock: FootLock) {
    let total = buf.len() / DIMS;
    for r in runs {
        let (a, b) = (r.a, r.b);
        let lo = a.saturating_sub(FOOT_LOCK_CONTEXT);
        let hi = (b + FOOT_LOCK_CONTEXT).min(total);
        let mut seg = buf[lo * DIMS..hi * DIMS].to_vec();
        if lock.root {
            crate::planted_feet::lock_planted_feet_with(&mut seg, lock.rule);
        }
        let moved = |seg: &[f32], g: usize| {
            ROOT_HORIZONTAL.map(|c| seg[(g - lo) * DIMS + c] - buf[g * DIMS + c])
        };
        let mut misses = Vec::new();
        if a > lo {
            misses.push((a - 1, moved(&seg, a - 1)));
        }
        for g in (a..b).filter(|&g| known.root_known(g)) {
            misses.push((g, moved(&seg, g)));
            for &c in &ROOT_HORIZONTAL {
                seg[(g - lo) * DIMS + c] = buf[g * DIMS + c];
            }
        }
        if b < hi {
            misses.push((b, moved(&seg, b)));
        }
        buf[a * DIMS..b * DIMS].copy_from_slice(&seg[(a - lo) * DIMS..(b - lo) * DIMS]);
        join_runs(buf, known, &[Run { a, b, misses }]);
        // The legs are pinned on the root path as it now is, known parts included. The IK's
        // change fades in from each kept end of the run ([`IK_FADE_FRAMES`]): it may pin a
        // foot planted across a join where the kept frames do not have it, and the kept
        // frames' legs are not changed.
        if lock.ik {
            let mut seg = buf[lo * DIMS..hi * DIMS].to_vec();
            crate::planted_feet::pin_planted_feet_within(&mut seg, lock.rule, lock.max_travel_m);
            for g in a..b {
                let from_kept = [(a > 0).then(|| g - a), (b < total).then(|| b - 1 - g)]
                    .into_iter()
                    .flatten()
                    .min();
                let w = from_kept.map_or(1.0, ik_fade);
                for c in 0..DIMS {
                    let i = g * DIMS + c;
                    buf[i] += w * (seg[(g - lo) * DIMS + c] - buf[i]);
                }
            }
        }
        // The lock moved known channels of the run too (a keyframe's legs): back to their
        // values, eased in as the sampler's output was.
        ease_into_known(&mut buf[lo * DIMS..hi * DIMS], a - lo..b - lo, |f, c| {
            let i = (lo + f) * DIMS + c;
            (known.mask[i] > 0.0).then_some(known.values[i])
        });
    }
}

/// Frames over which a run's root motion is handed over to the kept frames'.
pub const VELOCITY_HANDOVER_FRAMES: usize = 16;

/// Makes the root continue the kept frames where the made run `[a, b)` meets them: at an end
/// with three kept frames next to it, the run's root (each channel the kept frames know: the
/// floor position, the height) is offset so that its position, velocity and acceleration
/// there continue the kept frames' (the offset of a quintic Hermite curve over
/// [`VELOCITY_HANDOVER_FRAMES`], which vanishes with its first two derivatives at the far
/// end). [`join_runs`] has already made the positions meet; a jump of velocity or
/// acceleration left at a join is a spike of jerk.
fn hand_over_root(buf: &mut [f32], known: &KnownFrames, a: usize, b: usize) {
    let total = buf.len() / DIMS;
    let len = (b - a).min(VELOCITY_HANDOVER_FRAMES);
    if len < 3 {
        return;
    }
    let channels: Vec<usize> = ROOT_HORIZONTAL
        .iter()
        .copied()
        .chain([ROOT_HEIGHT])
        .collect();
    let kept = |f: usize, c: usize| known.mask[f * DIMS + c] > 0.0;
    // (the kept frames outward from the join, the run's frames outward from it)
    let mut ends: Vec<([usize; 3], Vec<usize>)> = Vec::new();
    if a >= 3 {
        ends.push(([a - 1, a - 2, a - 3], (a..a + len).collect()));
    }
    if b + 3 <= total {
        ends.push(([b, b + 1, b + 2], (b - len..b).rev().collect()));
    }
    for (k3, run) in ends {
        for &c in &channels {
            if !k3.iter().all(|&f| kept(f, c)) || kept(run[0], c) {
                continue;
            }
            let x = |f: usize| f64::from(buf[f * DIMS + c]);
            let (p1, p2, p3) = (x(k3[0]), x(k3[1]), x(k3[2]));
            let (v, acc) = (p1 - p2, p1 - 2.0 * p2 + p3);
            let (g0, g1, g2) = (x(run[0]), x(run[1]), x(run[2]));
            // Near the join the offset is d0 + d1·k + d2·k²/2: its first step is d1 + d2/2,
            // its second difference d2.
            let d0 = p1 + v + acc - g0;
            let d2 = acc - (g2 - 2.0 * g1 + g0);
            let d1 = v + 2.0 * acc - (g1 - g0) - d2 / 2.0;
            for (k, &f) in run.iter().enumerate() {
                let (w, wv, wa) = crate::seams::quintic(k as f64 / len as f64, len as f64);
                buf[f * DIMS + c] += (d0 * w + d1 * wv + d2 * wa) as f32;
            }
        }
    }
}

/// Moves the frames of each generated run whose root was not known onto the known path:
/// by the misses measured around and inside it, linearly interpolated between the nearest
/// two (the nearest one alone before the first and after the last). Returns the largest
/// move.
fn join_runs(buf: &mut [f32], known: &KnownFrames, runs: &[Run]) -> f32 {
    let mut largest = 0f32;
    for r in runs.iter().filter(|r| !r.misses.is_empty()) {
        let m = &r.misses;
        for g in (r.a..r.b).filter(|&g| !known.root_known(g)) {
            let next = m.partition_point(|p| p.0 < g);
            let d = match (next.checked_sub(1).map(|i| m[i]), m.get(next)) {
                (Some((f0, d0)), Some(&(f1, d1))) => {
                    let u = (g - f0) as f32 / (f1 - f0) as f32;
                    [0, 1].map(|k| d0[k] + (d1[k] - d0[k]) * u)
                }
                (Some((_, d)), None) | (None, Some(&(_, d))) => d,
                (None, None) => unreachable!("misses is not empty"),
            };
            for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                buf[g * DIMS + c] -= d[k];
                largest = largest.max(d[k].abs());
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
        let run = Run {
            a: 1,
            b: 5,
            misses: vec![(0, [0.0, 0.0]), (5, [5.0, -5.0])],
        };
        let largest = join_runs(&mut buf, &known, &[run]);
        let x: Vec<f32> = (0..t).map(|g| buf[g * DIMS + ROOT_HORIZONTAL[0]]).collect();
        assert_eq!(x, vec![0.0, -1.0, -2.0, -3.0, -4.0, 0.0]);
        assert_eq!(largest, 4.0);
    }

    #[test]
    fn join_runs_passes_through_a_known_mark_inside_the_run() {
        let t = 11;
        let mut buf = vec![0f32; t * DIMS];
        let mut mask = vec![0f32; t * DIMS];
        mask[..DIMS].fill(1.0);
        for &c in &ROOT_HORIZONTAL {
            mask[5 * DIMS + c] = 1.0;
        }
        let known = KnownFrames {
            values: buf.clone(),
            mask,
        };
        let run = Run {
            a: 1,
            b: t,
            misses: vec![(0, [0.0, 0.0]), (5, [2.5, 0.0])],
        };
        join_runs(&mut buf, &known, &[run]);
        let x: Vec<f32> = (0..t).map(|g| buf[g * DIMS + ROOT_HORIZONTAL[0]]).collect();
        // Ramped to the mark, the mark itself left to the splice, then held after it.
        assert_eq!(
            x,
            [
                0.0, -0.5, -1.0, -1.5, -2.0, 0.0, -2.5, -2.5, -2.5, -2.5, -2.5
            ]
        );
    }

    #[test]
    fn a_run_eases_into_a_value_known_on_one_frame_and_keeps_its_ends() {
        let span = 120;
        let c = 40;
        let mut x = vec![0f32; span * DIMS];
        for f in 0..span {
            x[f * DIMS + c] = f as f32 * 0.01;
        }
        let original = x.clone();
        ease_into_known(&mut x, 10..110, |f, ch| (f == 60 && ch == c).then_some(3.0));
        let v = |f: usize| x[f * DIMS + c];
        assert_eq!(v(60), 3.0);
        let d = |f: usize| v(f) - original[f * DIMS + c];
        // The difference against the line through the neighbours (0.60), in full next to the
        // keyframe and fading with zero slope at both ends of the reach.
        assert!((d(59) - d(61)).abs() < 1e-5 && (d(59) - 2.4 * 0.99275).abs() < 1e-3);
        assert!(d(60 - EASE_FRAMES).abs() < 1e-6 && d(60 + EASE_FRAMES).abs() < 1e-6);
        assert!(d(60 - EASE_FRAMES + 1) > 0.0 && d(60 - EASE_FRAMES + 1) < 0.03);
        // The generated motion's own velocity carries through the keyframe.
        assert!(((v(61) - v(59)) / 2.0 - 0.01).abs() < 1e-4);
        // Outside the run, and in the other channels, nothing moved.
        assert_eq!(x[..10 * DIMS], original[..10 * DIMS]);
        assert_eq!(x[110 * DIMS..], original[110 * DIMS..]);
        assert!((0..span).all(|f| x[f * DIMS + c + 1] == original[f * DIMS + c + 1]));
    }

    #[test]
    fn a_value_known_near_the_runs_edge_is_interpolated_from_the_edge_not_cut_off() {
        let span = 40;
        let c = 40;
        let mut x = vec![0f32; span * DIMS];
        ease_into_known(&mut x, 5..35, |f, ch| (f == 10 && ch == c).then_some(1.0));
        let v: Vec<f32> = (0..span).map(|f| x[f * DIMS + c]).collect();
        assert_eq!(v[4], 0.0, "the fully known frame before the run");
        assert_eq!(v[10], 1.0);
        // Smoothstep from 0 at frame 4 to 1 at frame 10: rising, no jump at the edge.
        assert!(v[5] > 0.0 && v[5] < 0.1 && v[5..=10].windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn a_whole_generated_dance_is_joined_to_the_kept_frames_without_a_step() {
        // Kept: frames 0..20 and 60..80, walking along x at 1 cm a frame. Generated: the same
        // walk 0.5 m off and at 2 cm a frame.
        let t = 80;
        let mut known = vec![0f32; t * DIMS];
        let mut generated = vec![0f32; t * DIMS];
        let mut mask = vec![0f32; t * DIMS];
        for f in 0..t {
            known[f * DIMS + ROOT_HORIZONTAL[0]] = 0.01 * f as f32;
            generated[f * DIMS + ROOT_HORIZONTAL[0]] = 0.5 + 0.02 * f as f32;
            if !(20..60).contains(&f) {
                mask[f * DIMS..(f + 1) * DIMS].fill(1.0);
            }
        }
        let known = KnownFrames {
            values: known,
            mask,
        };
        let (out, largest) = join_made_runs(&generated, &known, None);
        let x: Vec<f32> = (0..t).map(|f| out[f * DIMS + ROOT_HORIZONTAL[0]]).collect();
        for f in (0..20).chain(60..80) {
            assert_eq!(
                x[f],
                known.values[f * DIMS + ROOT_HORIZONTAL[0]],
                "kept frame {f}"
            );
        }
        let steps: Vec<f32> = x.windows(2).map(|w| w[1] - w[0]).collect();
        let worst = steps.iter().fold(0f32, |m, s| m.max(s.abs()));
        assert!(worst < 0.05, "a root step of {worst} m (steps {steps:?})");
        assert!(
            largest > 0.0 && largest < 0.5,
            "largest join move {largest}"
        );
    }

    #[test]
    fn a_whole_made_dance_follows_root_positions_known_inside_it_and_after_them() {
        // Nothing kept whole; the floor position known on frames 20..40 (a path) at x = 2 m.
        // The made dance stands at x = 0: it must be on the path there and stay by it after,
        // not step back to its own place.
        let t = 60;
        let generated = vec![0f32; t * DIMS];
        let mut values = vec![0f32; t * DIMS];
        let mut mask = vec![0f32; t * DIMS];
        for f in 20..40 {
            for c in ROOT_HORIZONTAL {
                mask[f * DIMS + c] = 1.0;
            }
            values[f * DIMS + ROOT_HORIZONTAL[0]] = 2.0;
        }
        let (out, _) = join_made_runs(&generated, &KnownFrames { values, mask }, None);
        let x: Vec<f32> = (0..t).map(|f| out[f * DIMS + ROOT_HORIZONTAL[0]]).collect();
        assert!(x[20..40].iter().all(|&v| v == 2.0), "{x:?}");
        let worst = x
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0f32, f32::max);
        assert!(worst < 1e-6, "a root step of {worst} m: {x:?}");
    }

    /// One standing frame: every contact label on, the root 0.9 m up, every joint at rest but
    /// the left knee (SMPL 4), bent `bend` rad about x.
    fn standing(bend: f32) -> Vec<f32> {
        let mut f = vec![0f32; DIMS];
        f[..4].fill(1.0);
        f[ROOT_HEIGHT] = 0.9;
        for j in 0..24 {
            let (c, s) = if j == 4 {
                (bend.cos(), bend.sin())
            } else {
                (1.0, 0.0)
            };
            let at = dancegen_nn::edge151::rot6d(j, 0);
            f[at..at + 6].copy_from_slice(&[1.0, 0.0, 0.0, 0.0, c, -s]);
        }
        f
    }

    #[test]
    fn the_leg_ik_fades_in_from_the_kept_frames() {
        // Kept: frames 0..20 and 40..60 standing straight, feet planted. Made: the same with
        // the left knee bent, so its planted foot is elsewhere. The IK pins the made frames'
        // planted foot where the kept frames have it, but from nothing at the run's first and
        // last frames: a leg that jumped there in one frame was a spike of jerk at the join.
        let t = 60;
        let generated: Vec<f32> = (0..t).flat_map(|_| standing(0.4)).collect();
        let mut values = generated.clone();
        let mut mask = vec![0f32; t * DIMS];
        for f in (0..20).chain(40..60) {
            values[f * DIMS..(f + 1) * DIMS].copy_from_slice(&standing(0.0));
            mask[f * DIMS..(f + 1) * DIMS].fill(1.0);
        }
        let known = KnownFrames { values, mask };
        let lock = FootLock {
            root: false,
            ik: true,
            rule: crate::planted_feet::PlantedRule::Either,
            max_travel_m: f64::INFINITY,
        };
        let (plain, _) = join_made_runs(&generated, &known, None);
        let (locked, _) = join_made_runs(&generated, &known, Some(lock));
        let frame = |x: &[f32], f: usize| x[f * DIMS..(f + 1) * DIMS].to_vec();
        for f in [20, 39] {
            assert_eq!(frame(&locked, f), frame(&plain, f), "frame {f}");
        }
        let moved = |f: usize| {
            frame(&locked, f)
                .iter()
                .zip(frame(&plain, f))
                .map(|(a, b)| (a - b).abs())
                .fold(0f32, f32::max)
        };
        assert!(moved(30) > 1e-3, "the IK pins the planted foot mid-run");
        assert!(
            moved(21) < moved(25),
            "and fades in: {} then {}",
            moved(21),
            moved(25)
        );
    }

    #[test]
    fn the_root_is_handed_over_with_its_velocity_and_acceleration() {
        // Kept: frames 0..10 accelerate along x (x = 0.001 f²); made: 10..60 at rest at the
        // kept path's end.
        let t = 60;
        let mut buf = vec![0f32; t * DIMS];
        let mut mask = vec![0f32; t * DIMS];
        for f in 0..t {
            let x = 0.001 * (f.min(9) * f.min(9)) as f32;
            buf[f * DIMS + ROOT_HORIZONTAL[0]] = x;
            if f < 10 {
                mask[f * DIMS..(f + 1) * DIMS].fill(1.0);
            }
        }
        let known = KnownFrames {
            values: buf.clone(),
            mask,
        };
        hand_over_root(&mut buf, &known, 10, t);
        let x: Vec<f64> = (0..t)
            .map(|f| f64::from(buf[f * DIMS + ROOT_HORIZONTAL[0]]))
            .collect();
        assert!((0..10).all(|f| x[f] == f64::from(known.values[f * DIMS + ROOT_HORIZONTAL[0]])));
        // Velocity and acceleration go on through the join: its first step and second
        // difference are the kept path's continued, and the third differences there (jerk)
        // are of the order of the hand-over's own, which brings the run to rest (the old
        // hand-over, a velocity fix alone, left a jerk seven times that here: 0.019).
        let (step, second) = (x[10] - x[9], x[11] - 2.0 * x[10] + x[9]);
        assert!((step - 0.019).abs() < 2e-4, "step {step} into the run");
        assert!(
            (second - 0.002).abs() < 1e-3,
            "second difference {second} at the join"
        );
        let jerk = |f: usize| (x[f + 3] - 3.0 * x[f + 2] + 3.0 * x[f + 1] - x[f]).abs();
        let at_join = (6..10).map(jerk).fold(0.0, f64::max);
        let blend = (10..10 + VELOCITY_HANDOVER_FRAMES - 3)
            .map(jerk)
            .fold(0.0, f64::max);
        assert!(
            at_join <= 1.5 * blend,
            "third difference {at_join} at the join, {blend} after"
        );
        // Past the hand-over the run is where it was.
        assert!((VELOCITY_HANDOVER_FRAMES + 10..t).all(|f| (x[f] - 0.081).abs() < 1e-6));
    }
}
