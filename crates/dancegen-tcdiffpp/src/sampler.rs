//! Long group dances: windows of `W` frames at a stride of `W / 2`, two ways (issue #17 asks
//! for both, measured against each other in `docs/group-eval.md`).
//!
//! - [`LongSampler::Lgds`] (paper §4.4, Eq. 19): windows one after another. Window `w > 0`
//!   starts from the previous window's second half noised to the first step (Eq. 19's
//!   `x̂_T^[75:150]`) followed by fresh noise, and that half is imposed on its first `W / 2`
//!   frames after every step: clean, as the released `lgds_ddim_sample` does, or re-noised to
//!   the step's level (EDGE inpainting), [`PrefixMode`]. Unlike the released code, window 0 is
//!   kept (group.md §5 P4), so the dance starts with the song.
//! - [`LongSampler::Parallel`]: every window in one batch; after every step each window's first
//!   half is overwritten by the previous window's second half (EDGE `long_ddim_sample`), then
//!   EDGE's stitching cross-fades positions and slerps rotations over the overlaps.
//!
//! Window coordinates: the network works with roots relative to the group's frame-0 centroid
//! and slots sorted left to right at frame 0 ([`crate::layout`]). LGDS re-sorts the slots at
//! every window (by the prefix's first frame) and re-bases the prefix, so every window looks
//! like a training window, then maps the result back to the dance's own dancer order and
//! stage position. The parallel sampler cannot re-sort (all windows move at once), so its
//! slots keep the dance's frame-0 order throughout.
//!
//! Formation control: requested root paths (raw Z-up metres, per frame and dancer, `None` =
//! free) become, in window coordinates, a clean cue on those root channels plus the control
//! flags the network was trained with. The swap code of a window is the permutation from the
//! requested order at its first frame to the one at its last when every dancer is given at
//! both; otherwise the identity (keep the order).

use dancegen_nn::burn;
use dancegen_nn::diffusion::longform::{ChannelLayout, stitch};
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_nn::diffusion::{
    Cue, CueActivity, Guidance, SampleOptions, Schedule, Solver, Spacing, WeightSchedule,
    sample_with,
};
use dancegen_nn::edge151::{DIMS, ROOT_HORIZONTAL, ROT6D_START};
use dancegen_nn::progress::{Cancelled, StepHook};

use burn::tensor::{Device, Tensor, TensorData};

use crate::config::{LongSampler, PrefixMode};
use crate::denoiser::{GroupCond, GroupDenoiser, MUSIC_DIMS, PreparedGroupDenoiser};
use crate::known::GroupKnown;
use crate::layout::{GROUP_DIMS, N_MAX, STAGE_X, centroid, channel, left_to_right, shift_roots};
use crate::swap::{identity_code, swap_code};

/// A requested root position: raw Z-up `(x, y)` metres.
pub type RootXy = [f32; 2];

/// One long group dance to sample.
pub struct GroupRequest<'a> {
    /// EDGE-35 features `[frames, 35]`, flat.
    pub music: &'a [f32],
    pub frames: usize,
    pub dancers: usize,
    /// Requested root paths, `control[f · N_MAX + s]`.
    pub control: Option<&'a [Option<RootXy>]>,
    /// What an edit keeps ([`crate::known`]); sampled window by window (LGDS) whatever
    /// [`GroupSampleOptions::sampler`] says.
    pub known: Option<GroupKnown<'a>>,
}

/// Sampling choices.
#[derive(Clone, Debug)]
pub struct GroupSampleOptions {
    pub steps: usize,
    pub eta: f64,
    pub spacing: Spacing,
    pub solver: Solver,
    pub guidance: f64,
    pub sampler: LongSampler,
    pub prefix: PrefixMode,
    pub seed: u64,
}

/// Number of windows of `window` frames at stride `window / 2` that cover `frames`.
pub fn window_count(frames: usize, window: usize) -> usize {
    let half = window / 2;
    if frames <= window {
        1
    } else {
        1 + (frames - window).div_ceil(half)
    }
}

/// The model's per-channel `(scale, shift)`, repeated for every slot.
fn group_stats(net: &GroupDenoiser) -> (Vec<f32>, Vec<f32>) {
    let (scale, shift) = net.denorm.host();
    (scale.repeat(N_MAX), shift.repeat(N_MAX))
}

fn music_window(music: &[f32], frames: usize, start: usize, window: usize) -> Vec<f32> {
    (start..start + window)
        .flat_map(|f| {
            let f = f.min(frames.saturating_sub(1));
            music[f * MUSIC_DIMS..(f + 1) * MUSIC_DIMS].iter().copied()
        })
        .collect()
}

/// Generates a whole dance: raw frames `[frames, N_MAX·151]` (flat; Z-up, metres, roots on
/// the stage; slots `n..` zero). Deterministic given `opts.seed`.
pub fn generate(
    net: &GroupDenoiser,
    schedule: &Schedule,
    window: usize,
    req: &GroupRequest,
    opts: &GroupSampleOptions,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Vec<f32>, Cancelled> {
    assert!((2..=N_MAX).contains(&req.dancers), "2..={N_MAX} dancers");
    assert!(window.is_multiple_of(2) && window >= 2, "even window");
    let sampler = if req.known.is_some() {
        LongSampler::Lgds
    } else {
        opts.sampler
    };
    // A formation that gives every dancer at frame 0 in another order than left to right is
    // danced in sorted slots (as every training window was) and handed back in its order.
    let order = requested_order(req);
    let sorted_control = order.as_ref().map(|perm| {
        let c = req.control.expect("an order comes from the control");
        let mut p = c.to_vec();
        for (src, dst) in c.chunks_exact(N_MAX).zip(p.chunks_exact_mut(N_MAX)) {
            for (s, &d) in perm.iter().enumerate() {
                dst[s] = src[d];
            }
        }
        p
    });
    let sorted_req = GroupRequest {
        control: sorted_control.as_deref().or(req.control),
        ..*req
    };
    let mut out = match sampler {
        LongSampler::Lgds => lgds(net, schedule, window, &sorted_req, opts, device, hook)?,
        LongSampler::Parallel => parallel(net, schedule, window, &sorted_req, opts, device, hook)?,
    };
    out.truncate(req.frames * GROUP_DIMS);
    Ok(match order {
        Some(perm) => permute(&out, &perm, true),
        None => out,
    })
}

/// The slot order (`perm[slot] = dancer`) that sorts the dancers left to right by their
/// requested stage x at frame 0, when the request gives every dancer there, is not an edit
/// (whose known frames LGDS sorts itself) and is not sorted already.
///
/// Why: the network only ever saw slots sorted left to right at frame 0 (TCDiff++ Eq. 5-7;
/// its positioning embedding is the slot's rank). A formation listing its dancers right to
/// left put a right-hand dancer in the left-hand slot; the x0 networks that ignored their
/// input did not care, a network that reads its input flailed its limbs (joints moving 1.4 m
/// in a frame; docs/group-collapse.md §19).
fn requested_order(req: &GroupRequest) -> Option<Vec<usize>> {
    if req.known.is_some() {
        return None;
    }
    let c = req.control?;
    let x: Vec<f32> = (0..req.dancers)
        .map(|d| c[d].map(|p| p[0]))
        .collect::<Option<_>>()?;
    let perm = left_to_right(&x);
    perm.iter()
        .enumerate()
        .any(|(s, &d)| s != d)
        .then_some(perm)
}

fn sample_options(
    opts: &GroupSampleOptions,
    seed: u64,
    cues: Vec<Cue>,
    init: Option<Tensor<3>>,
) -> SampleOptions {
    SampleOptions {
        method: opts.solver.method(opts.steps, opts.eta, opts.spacing),
        // Mean/std-normalised data is not confined to [−1, 1] (EDGE's min-max range).
        clip_x0: None,
        guidance: if (opts.guidance - 1.0).abs() < 1e-9 {
            Guidance::Conditional
        } else {
            Guidance::Scale(opts.guidance)
        },
        weight_schedule: WeightSchedule::Constant,
        cues,
        long_form: false,
        seed,
        init,
    }
}

/// The requested roots of frames `start..start + window` in window coordinates
/// (normalised, minus `origin`), slots permuted by `perm` (`perm[slot] = dancer`).
struct WindowControl {
    /// `[W, N_MAX]` flags.
    flags: Vec<f32>,
    /// `[W, N_MAX·151]` values (root channels only) and mask.
    values: Vec<f32>,
    mask: Vec<f32>,
    swap: Vec<f32>,
}

#[allow(clippy::too_many_arguments)]
fn window_control(
    req: &GroupRequest,
    start: usize,
    window: usize,
    perm: &[usize],
    origin: [f32; 2],
    scale: &[f32],
) -> WindowControl {
    let n = req.dancers;
    let mut flags = vec![0f32; window * N_MAX];
    let mut values = vec![0f32; window * GROUP_DIMS];
    let mut mask = vec![0f32; window * GROUP_DIMS];
    let at = |f: usize, d: usize| -> Option<RootXy> {
        let c = req.control?;
        if f >= req.frames {
            return None;
        }
        c[f * N_MAX + d]
    };
    for w in 0..window {
        for (s, &d) in perm.iter().enumerate() {
            if let Some(p) = at(start + w, d) {
                flags[w * N_MAX + s] = 1.0;
                for (k, &ch) in ROOT_HORIZONTAL.iter().enumerate() {
                    let i = w * GROUP_DIMS + channel(s, ch);
                    values[i] = p[k] / scale[ch] - origin[k];
                    mask[i] = 1.0;
                }
            }
        }
    }
    let last = (start + window).min(req.frames) - 1;
    let first: Option<Vec<RootXy>> = perm.iter().map(|&d| at(start, d)).collect();
    let end: Option<Vec<RootXy>> = perm.iter().map(|&d| at(last, d)).collect();
    let swap = match (first, end) {
        (Some(_), Some(end)) => swap_code(&end.iter().map(|p| p[0]).collect::<Vec<_>>()),
        _ => identity_code(n),
    };
    WindowControl {
        flags,
        values,
        mask,
        swap,
    }
}

/// Slot order sorting the first `n` slots of one group frame left to right (stage x).
pub(crate) fn sorted_slots(frame: &[f32], n: usize) -> Vec<usize> {
    let x: Vec<f32> = (0..n).map(|s| frame[channel(s, STAGE_X)]).collect();
    left_to_right(&x)
}

/// `frames` `[T, N_MAX·151]` with slot `s` taken from dancer `perm[s]` (`inverse = false`) or
/// dancer `perm[s]` taken from slot `s` (`inverse = true`).
pub(crate) fn permute(frames: &[f32], perm: &[usize], inverse: bool) -> Vec<f32> {
    let mut out = frames.to_vec();
    for (src, dst) in frames
        .chunks_exact(GROUP_DIMS)
        .zip(out.chunks_exact_mut(GROUP_DIMS))
    {
        for (s, &d) in perm.iter().enumerate() {
            let (from, to) = if inverse { (s, d) } else { (d, s) };
            dst[to * DIMS..(to + 1) * DIMS].copy_from_slice(&src[from * DIMS..(from + 1) * DIMS]);
        }
    }
    out
}

fn to_tensor(v: Vec<f32>, shape: [usize; 3], device: &Device) -> Tensor<3> {
    Tensor::from_data(TensorData::new(v, shape), device)
}

fn host(x: Tensor<3>) -> Vec<f32> {
    x.into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .expect("f32 tensor")
}

/// Where window 0's frame-0 centroid sits (normalised): the requested centroid when every
/// dancer is given at frame 0, else the stage centre.
fn first_origin(req: &GroupRequest, scale: &[f32]) -> [f32; 2] {
    let given: Option<Vec<RootXy>> = req
        .control
        .and_then(|c| (0..req.dancers).map(|d| c[d]).collect());
    match given {
        Some(p) => {
            let n = p.len() as f32;
            let mut c = [0f32; 2];
            for q in &p {
                c[0] += q[0] / n;
                c[1] += q[1] / n;
            }
            [
                c[0] / scale[ROOT_HORIZONTAL[0]],
                c[1] / scale[ROOT_HORIZONTAL[1]],
            ]
        }
        None => [0.0, 0.0],
    }
}

fn lgds(
    net: &GroupDenoiser,
    schedule: &Schedule,
    window: usize,
    req: &GroupRequest,
    opts: &GroupSampleOptions,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Vec<f32>, Cancelled> {
    let n = req.dancers;
    let half = window / 2;
    let windows = window_count(req.frames, window);
    let (scale, shift) = group_stats(net);
    let mut rng = SeededNoise::new(opts.seed);
    // Normalised frames with global (stage) roots, in the dance's own dancer order.
    let mut out: Vec<f32> = Vec::with_capacity((window + (windows - 1) * half) * GROUP_DIMS);
    let identity: Vec<usize> = (0..n).collect();
    for w in 0..windows {
        let start = w * half;
        let made = if w == 0 {
            0
        } else {
            req.known
                .map_or(half, |k| seam_before_known(&k, start, half, req.frames, n))
        };
        if let Some(k) = &req.known
            && (start + made..start + window).all(|g| g >= req.frames || k.frame_known(g, n))
        {
            // Nothing to make: the known frames, normalised, as a sampled window would give.
            out.truncate((start + made) * GROUP_DIMS);
            for g in start + made..start + window {
                out.extend(k.normalised(g.min(req.frames - 1), n, &scale, &shift));
            }
            continue;
        }
        let (perm, origin, prefix) = if w == 0 {
            match req.known.filter(|k| (0..n).all(|d| k.root_known(0, d))) {
                // Known first positions: slots and origin from them, as in training.
                Some(k) => {
                    let first = k.normalised(0, n, &scale, &shift);
                    (sorted_slots(&first, n), centroid(&first, n), None)
                }
                None => (identity.clone(), first_origin(req, &scale), None),
            }
        } else {
            // The window's prefix: the frames before what it makes (all of the previous
            // window's second half, or less before a known frame, [`seam_before_known`]).
            out.truncate((start + made) * GROUP_DIMS);
            let tail = &out[start * GROUP_DIMS..];
            let perm = sorted_slots(&tail[..GROUP_DIMS], n);
            let origin = centroid(&tail[..GROUP_DIMS], n);
            let mut p = permute(tail, &perm, false);
            shift_roots(&mut p, n, [-origin[0], -origin[1]]);
            (perm, origin, Some(p))
        };
        let mut ctrl = window_control(req, start, window, &perm, origin, &scale);
        let known_cue = req
            .known
            .map(|k| k.window_cue(start, window, made, &perm, origin, &scale, &shift));
        if let Some(k) = &known_cue {
            for (f, kf) in ctrl.flags.iter_mut().zip(&k.flags) {
                *f = f.max(*kf);
            }
        }
        let music = music_window(req.music, req.frames, start, window);
        let cond = GroupCond {
            music: to_tensor(music, [1, window, MUSIC_DIMS], device),
            dancers: vec![n],
            swap: Tensor::from_data(
                TensorData::new(ctrl.swap.clone(), [1, ctrl.swap.len()]),
                device,
            ),
            control: to_tensor(ctrl.flags.clone(), [1, window, N_MAX], device),
        };
        let shape = [1, window, GROUP_DIMS];
        let mut cues = Vec::new();
        let mut init = None;
        if let Some(p) = &prefix {
            let mut value = p.clone();
            value.resize(window * GROUP_DIMS, 0.0);
            let mut mask = vec![0f32; window * GROUP_DIMS];
            for f in 0..made {
                for s in 0..n {
                    for c in 0..DIMS {
                        mask[f * GROUP_DIMS + channel(s, c)] = 1.0;
                    }
                }
            }
            let value = to_tensor(value, shape, device);
            let mask = to_tensor(mask, shape, device);
            // Eq. 19: the prefix noised to the first step, fresh noise after it.
            let first_t = schedule.timesteps() - 1;
            let noised = schedule.q_sample(value.clone(), &[first_t], rng.tensor(shape, device));
            let fresh = rng.tensor(shape, device);
            init = Some(noised * mask.clone() + fresh * (mask.clone().neg() + 1.0));
            cues.push(Cue {
                value,
                mask,
                noised: opts.prefix == PrefixMode::Renoised,
                activity: CueActivity::Hard,
            });
        }
        let known_mask = known_cue.as_ref().map(|k| k.mask.clone());
        if let Some(k) = known_cue.filter(|k| k.mask.iter().any(|&m| m > 0.0)) {
            cues.push(Cue {
                value: to_tensor(k.values, shape, device),
                mask: to_tensor(k.mask, shape, device),
                noised: opts.prefix == PrefixMode::Renoised,
                activity: CueActivity::Hard,
            });
        }
        if ctrl.mask.iter().any(|&m| m > 0.0) {
            cues.push(Cue {
                value: to_tensor(ctrl.values, shape, device),
                mask: to_tensor(ctrl.mask.clone(), shape, device),
                noised: false,
                activity: CueActivity::Hard,
            });
        }
        let guided = (opts.guidance - 1.0).abs() >= 1e-9;
        let model = PreparedGroupDenoiser::new(net, cond.clone(), guided);
        let so = sample_options(opts, opts.seed.wrapping_add(w as u64 + 1), cues, init);
        let x = host(sample_with(
            &model,
            schedule,
            shape,
            Some(&cond),
            &so,
            device,
            hook,
            &|x| x,
        )?);
        let mut x = x;
        if prefix.is_some() {
            let cued =
                |i: usize| ctrl.mask[i] > 0.0 || known_mask.as_ref().is_some_and(|m| m[i] > 0.0);
            continue_free_roots(&mut x, window, made, n, &cued);
        }
        let mut x = permute(&x, &perm, true);
        shift_roots(&mut x, n, origin);
        out.extend_from_slice(&x[made * GROUP_DIMS..]);
    }
    denormalise(&mut out, &scale, &shift, n);
    Ok(out)
}

/// Frames between an LGDS seam and a known frame after it that the window making that frame
/// also makes (2/3 s at 30 fps). A keyframe just after a seam was seen only by the window that
/// starts there, which had to bend the dance to it within a few frames of the previous
/// window's frames: with the x0-skip network (tcdiffpp v15) a keyframe at a seam jerked 2.4
/// times as much in the frames around it as elsewhere (feelings.ogg 30-54 s, 3 dancers).
pub const KNOWN_LEAD_FRAMES: usize = 20;

/// How many of its first frames an LGDS window `start..start + 2·half` takes from the
/// previous window (`half`, the paper's), fewer when a frame with a known channel comes within
/// [`KNOWN_LEAD_FRAMES`] after the seam and the frame before the seam has none (a keyframe, or
/// the kept frames after a remade range, not joints kept all through): then the seam moves to
/// that many frames before it, so the window that sees the known frame also makes the approach.
fn seam_before_known(k: &GroupKnown, start: usize, half: usize, frames: usize, n: usize) -> usize {
    let seam = start + half;
    let any_known = |g: usize| g < frames && (0..n).any(|d| k.any_known(g, d));
    if seam == 0 || seam >= frames || any_known(seam - 1) {
        return half;
    }
    match (seam..seam + KNOWN_LEAD_FRAMES).find(|&g| any_known(g)) {
        Some(g) => half - (KNOWN_LEAD_FRAMES - (g - seam)).min(half - 1),
        None => half,
    }
}

/// Continues each free dancer's root across an LGDS window's seam: its made frames
/// `made..window` of `x` (normalised, window coordinates, `[W, N_MAX·151]`) are shifted so that
/// the first of them follows the prefix's last with the made part's own first step (no jump,
/// no change of velocity at the seam). A dancer with a cued root on a made frame (a formation,
/// an edit's known root) gets that shift only before its first cued frame, fading to none
/// there, so the cued roots stay as cued; with a cue on the first two made frames, nothing.
/// (Left wholly as it was, a group edit whose remade range ends in kept frames jumped a dancer
/// 0.2-0.32 m at the seam before them with tcdiffpp v15: feelings.ogg 30-54 s, 8-14 s remade.)
///
/// Why: the prefix is imposed on the window's first half, but the network places the made
/// frames' root itself (with `root_integrated`, at the window mean of its own root output), and
/// its placement of the prefix need not be the imposed one. Unshifted, the shipped model's
/// dancers jumped 0.2-0.4 m at every window seam of a 20 s dance (feelings.ogg 30-50 s, 3
/// dancers, `--sampler lgds`): the sampler a formation with free dancers uses.
fn continue_free_roots(
    x: &mut [f32],
    window: usize,
    made: usize,
    n: usize,
    cued: &dyn Fn(usize) -> bool,
) {
    if made == 0 || made + 2 > window {
        return;
    }
    for s in 0..n {
        let idx = |f: usize, ch: usize| f * GROUP_DIMS + channel(s, ch);
        let first_cue =
            (made..window).find(|&f| ROOT_HORIZONTAL.iter().any(|&ch| cued(idx(f, ch))));
        if first_cue.is_some_and(|c| c <= made + 1) {
            continue;
        }
        let weight = |f: usize| match first_cue {
            None => 1.0,
            Some(c) if f < c => (c - f) as f32 / (c - made) as f32,
            Some(_) => 0.0,
        };
        for &ch in &ROOT_HORIZONTAL {
            let (last, first, next) =
                (x[idx(made - 1, ch)], x[idx(made, ch)], x[idx(made + 1, ch)]);
            let shift = last + (next - first) - first;
            for f in made..window {
                x[idx(f, ch)] += shift * weight(f);
            }
        }
    }
}

/// Normalised → raw, in place; slots `n..` set to zero.
fn denormalise(frames: &mut [f32], scale: &[f32], shift: &[f32], n: usize) {
    for f in frames.chunks_exact_mut(GROUP_DIMS) {
        for (c, v) in f.iter_mut().enumerate() {
            *v = if c / DIMS < n {
                *v * scale[c] + shift[c]
            } else {
                0.0
            };
        }
    }
}

/// EDGE's overwrite for centroid-relative group windows: window `i`'s first half becomes
/// window `i − 1`'s second half, re-based so the group's centroid at its first frame is 0.
pub fn overwrite_first_halves_rebased(
    x: &[f32],
    windows: usize,
    window: usize,
    n: usize,
) -> Vec<f32> {
    let half = window / 2;
    let mut out = x.to_vec();
    for w in 1..windows {
        let src = &x[((w - 1) * window + half) * GROUP_DIMS..w * window * GROUP_DIMS];
        let origin = centroid(&src[..GROUP_DIMS], n);
        let mut p = src.to_vec();
        shift_roots(&mut p, n, [-origin[0], -origin[1]]);
        out[w * window * GROUP_DIMS..(w * window + half) * GROUP_DIMS].copy_from_slice(&p);
    }
    out
}

fn parallel(
    net: &GroupDenoiser,
    schedule: &Schedule,
    window: usize,
    req: &GroupRequest,
    opts: &GroupSampleOptions,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Vec<f32>, Cancelled> {
    let n = req.dancers;
    let half = window / 2;
    let l = window_count(req.frames, window);
    let (scale, shift) = group_stats(net);
    let identity: Vec<usize> = (0..n).collect();
    let mut music = Vec::with_capacity(l * window * MUSIC_DIMS);
    let mut flags = Vec::new();
    let mut values = Vec::new();
    let mut mask = Vec::new();
    let mut swap = Vec::new();
    let mut origins = Vec::with_capacity(l);
    for w in 0..l {
        let start = w * half;
        music.extend(music_window(req.music, req.frames, start, window));
        // A window's origin is known in advance only where the whole group is requested at
        // its first frame; elsewhere its control is dropped (module docs).
        let known: Option<Vec<RootXy>> = req.control.and_then(|c| {
            (0..n)
                .map(|d| {
                    if start < req.frames {
                        c[start * N_MAX + d]
                    } else {
                        None
                    }
                })
                .collect()
        });
        let origin = match &known {
            Some(_) => {
                let sub = GroupRequest {
                    control: req.control.map(|c| &c[start * N_MAX..]),
                    ..*req
                };
                first_origin(&sub, &scale)
            }
            None => [0.0, 0.0],
        };
        let ctrl = window_control(req, start, window, &identity, origin, &scale);
        if known.is_some() {
            flags.extend(ctrl.flags);
            values.extend(ctrl.values);
            mask.extend(ctrl.mask);
        } else {
            flags.extend(vec![0f32; window * N_MAX]);
            values.extend(vec![0f32; window * GROUP_DIMS]);
            mask.extend(vec![0f32; window * GROUP_DIMS]);
        }
        swap.extend(ctrl.swap);
        origins.push(known.map(|_| origin));
    }
    let cond = GroupCond {
        music: to_tensor(music, [l, window, MUSIC_DIMS], device),
        dancers: vec![n; l],
        swap: Tensor::from_data(TensorData::new(swap, [l, N_MAX * N_MAX]), device),
        control: to_tensor(flags, [l, window, N_MAX], device),
    };
    let shape = [l, window, GROUP_DIMS];
    let mut cues = Vec::new();
    if mask.iter().any(|&m| m > 0.0) {
        cues.push(Cue {
            value: to_tensor(values, shape, device),
            mask: to_tensor(mask, shape, device),
            noised: false,
            activity: CueActivity::Hard,
        });
    }
    let guided = (opts.guidance - 1.0).abs() >= 1e-9;
    let model = PreparedGroupDenoiser::new(net, cond.clone(), guided);
    let so = sample_options(opts, opts.seed, cues, None);
    let rebase = |x: Tensor<3>| {
        let h = host(x);
        to_tensor(
            overwrite_first_halves_rebased(&h, l, window, n),
            shape,
            device,
        )
    };
    let mut win = host(sample_with(
        &model,
        schedule,
        shape,
        Some(&cond),
        &so,
        device,
        hook,
        &rebase,
    )?);
    // Place: window w's frame 0 is window w − 1's frame `half` (or its requested origin).
    for w in 0..l {
        let origin = match (w, origins[w]) {
            (_, Some(o)) => o,
            (0, None) => [0.0, 0.0],
            (_, None) => {
                let prev = ((w - 1) * window + half) * GROUP_DIMS;
                centroid(&win[prev..prev + GROUP_DIMS], n)
            }
        };
        shift_roots(
            &mut win[w * window * GROUP_DIMS..(w + 1) * window * GROUP_DIMS],
            n,
            origin,
        );
    }
    denormalise(&mut win, &scale, &shift, n);
    let layout = ChannelLayout {
        rot6d: (0..n)
            .map(|s| channel(s, ROT6D_START)..channel(s, DIMS))
            .collect(),
    };
    let stitched = stitch(to_tensor(win, shape, device), &layout);
    let mut out = stitched
        .into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .expect("f32");
    denormalise(&mut out, &[1.0; GROUP_DIMS], &[0.0; GROUP_DIMS], n);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mask over `frames` frames of 2 dancers: `known(f)` gives the channels of dancer 0
    /// known at frame f.
    fn mask(frames: usize, known: impl Fn(usize) -> std::ops::Range<usize>) -> Vec<f32> {
        let mut m = vec![0f32; frames * GROUP_DIMS];
        for f in 0..frames {
            for c in known(f) {
                m[f * GROUP_DIMS + channel(0, c)] = 1.0;
            }
        }
        m
    }

    #[test]
    fn a_made_root_continues_the_prefix_and_fades_into_a_cued_one() {
        // One dancer standing at x = 0 in the prefix (frames 0-9); the made frames (10-29) stand
        // at x = 1, and frame 20's root is cued there.
        let (window, made) = (30, 10);
        let x_ch = channel(0, ROOT_HORIZONTAL[0]);
        let mut x = vec![0f32; window * GROUP_DIMS];
        for f in made..window {
            x[f * GROUP_DIMS + x_ch] = 1.0;
        }
        let cue = |i: usize| i == 20 * GROUP_DIMS + x_ch;
        continue_free_roots(&mut x, window, made, 1, &cue);
        let root: Vec<f32> = (0..window).map(|f| x[f * GROUP_DIMS + x_ch]).collect();
        assert_eq!(root[made], 0.0, "{root:?}");
        for f in made..20 {
            // A straight approach: 0.1 per frame, no jump at the seam.
            assert!((root[f + 1] - root[f] - 0.1).abs() < 1e-6, "{root:?}");
        }
        assert!(root[20..].iter().all(|&r| r == 1.0), "{root:?}");
        // Uncued, the whole made part moves onto the prefix.
        let mut y = vec![0f32; window * GROUP_DIMS];
        for f in made..window {
            y[f * GROUP_DIMS + x_ch] = 1.0;
        }
        continue_free_roots(&mut y, window, made, 1, &|_| false);
        assert!((0..window).all(|f| y[f * GROUP_DIMS + x_ch] == 0.0));
    }

    #[test]
    fn a_seam_moves_before_a_known_frame_just_after_it() {
        let (frames, half, start) = (450, 75, 150);
        let seam = start + half;
        let values = vec![0f32; frames * GROUP_DIMS];
        let made = |m: &[f32]| {
            let k = GroupKnown {
                values: &values,
                mask: m,
            };
            seam_before_known(&k, start, half, frames, 2)
        };
        // A keyframe at the seam or a few frames after it: the window starts making
        // KNOWN_LEAD_FRAMES before it.
        for after in [0, 5, KNOWN_LEAD_FRAMES - 1] {
            let m = mask(frames, |f| if f == seam + after { 0..DIMS } else { 0..0 });
            assert_eq!(
                made(&m),
                half - (KNOWN_LEAD_FRAMES - after),
                "after {after}"
            );
        }
        // Farther away, none at all, or joints known all through (kept arms): the paper's
        // half.
        let far = mask(frames, |f| {
            if f == seam + KNOWN_LEAD_FRAMES {
                0..DIMS
            } else {
                0..0
            }
        });
        assert_eq!(made(&far), half);
        assert_eq!(made(&mask(frames, |_| 0..0)), half);
        assert_eq!(made(&mask(frames, |_| ROT6D_START..ROT6D_START + 6)), half);
    }
}
