//! Music features → dance: the whole Lodge++ inference (paper Fig. 2) and the two ablation
//! samplers the evaluation compares it with.
//!
//! - [`Sampler::Lodgepp`]: GPT tokens for the whole song → VQ decoder → coarse dance → motion
//!   beats → key motions retrieved from the library and moved onto the nearest music beats,
//!   boundary primitives at every window edge → all PDDM windows denoised in one batch →
//!   windows concatenated, each placed where the previous one ends.
//! - [`Sampler::Autoregressive`] ("without the global network"): no primitives; window after
//!   window, each continuing the last 4 frames of the previous one (inpainting).
//! - [`Sampler::Edge`]: EDGE's long-form sampling (D.1) with the same network and no
//!   primitives: windows overlapping by half, denoised in one batch, window `i`'s first half
//!   overwritten by window `i − 1`'s second half after every step.

use dancegen_nn::burn;
use dancegen_nn::diffusion::longform::{ChannelLayout, stitch};
use dancegen_nn::diffusion::pddm::ResidualShift;
use dancegen_nn::gpt::SamplingOptions;
use dancegen_nn::progress::{Cancelled, DENOISING, NoHook, StepHook};

use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::bundle::SoloModel;
use crate::choreo_gpt::MUSIC_DIMS;
use crate::config::{BOUNDARY_FRAMES, PRIMITIVE_FRAMES, TOKEN_FRAMES};
use crate::denoiser::PddmCond;
use crate::heading::{self, Stats};
use crate::layout::{self, DIMS, MAIN_DIMS, ROOT_HORIZONTAL, main_channels};
use crate::library::{key_of, relative_root, retrieval_channels};
use crate::penetration::{CapsulePairs, PenetrationGuidance, guide};
use crate::primitives::{WindowPrimitives, align_to_music, key_centres, motion_beats, speed};
use crate::rotation_tracks::bridge_short_rows;
use crate::sampler::{HardCues, PddmSampleOptions, sample_windows_hooked};
use crate::seams::{CuedFrames, SeamCorrection, anchor_windows};
use dancegen_motion::smoothing::{Ends, gaussian_smooth};

/// Which long-form sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    Lodgepp,
    Autoregressive,
    Edge,
}

/// Everything a generation run can change.
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    pub genre: usize,
    pub seed: u64,
    pub steps: usize,
    pub guidance: f64,
    pub sampler: Sampler,
    pub refine: bool,
    /// Final denoising steps the Foot Refine Block acts on (`None`: all).
    pub refine_last_steps: Option<usize>,
    /// Channels the Foot Refine Block's refinement is added to.
    pub refine_scope: crate::foot_refine::FootRefineScope,
    pub penetration: Option<(PenetrationGuidance, usize)>,
    pub gpt: SamplingOptions,
    pub max_beat_shift: usize,
    /// Post-processing: the root stops gliding over planted feet
    /// ([`crate::planted_feet::lock_planted_feet_with`]), then, with [`Self::foot_ik`], leg IK
    /// pins them.
    pub foot_lock: bool,
    /// When a foot counts as planted for the foot lock.
    pub foot_lock_rule: crate::planted_feet::PlantedRule,
    /// With the foot lock, also pin planted feet by leg IK (else the root lock alone).
    pub foot_ik: bool,
}

impl GenerateOptions {
    /// The bundle's defaults for `genre` and `seed`.
    pub fn defaults(model: &SoloModel, genre: usize, seed: u64) -> Self {
        let s = &model.config.sampling;
        Self {
            genre,
            seed,
            steps: s.steps,
            guidance: s.guidance,
            sampler: Sampler::Lodgepp,
            refine: true,
            refine_last_steps: s.foot_refine_steps,
            refine_scope: s.foot_refine_scope,
            penetration: Some((
                PenetrationGuidance {
                    scale: s.penetration_scale,
                    iterations: s.penetration_iterations,
                },
                s.penetration_steps,
            )),
            gpt: SamplingOptions {
                greedy: s.gpt_top_k <= 1,
                temperature: s.gpt_temperature,
                top_k: Some(s.gpt_top_k.max(1)),
                seed,
            },
            max_beat_shift: s.max_beat_shift,
            foot_lock: s.foot_lock,
            foot_lock_rule: s.foot_lock_rule,
            foot_ik: s.foot_ik,
        }
    }
}

/// One window for [`SoloModel::sample_cued_window`]: its music `[n, 35]`, primitives and hard
/// cues `[n, 151]` (normalised, window-relative root), and whether the cues apply.
pub(crate) struct CuedWindow {
    pub music: Vec<f32>,
    pub prims: WindowPrimitives,
    pub cue_v: Vec<f32>,
    pub cue_m: Vec<f32>,
    pub cued: bool,
}

/// A generated dance: raw EDGE-151 frames (Z-up, absolute root) and what was done.
pub struct GeneratedDance {
    /// `[frames, 151]`.
    pub frames: Vec<f32>,
    pub n_frames: usize,
    pub windows: usize,
    /// Key motions placed (Lodge++ sampler).
    pub key_motions: usize,
    /// Largest root corrections at the cue seams, metres (`seams` module).
    pub seam_correction: SeamCorrection,
    /// Frames whose root orientation flip was repaired ([`crate::root_flips`]).
    pub root_flips_repaired: usize,
    /// Joint-frames whose shrunken 6D rows were bridged ([`crate::rotation_tracks`]).
    pub rotations_bridged: usize,
}

impl SoloModel {
    /// Normalised frames `[T, 151]` → raw, in place (window-relative root: no mean added).
    pub(crate) fn to_raw(&self, frames: &mut [f32]) {
        let (scale, shift) = self.pddm.denorm.host();
        for f in frames.chunks_mut(DIMS) {
            for c in 0..DIMS {
                f[c] = f[c] * scale[c] + shift[c];
            }
        }
    }

    /// The denormaliser's `(scale, shift)` when the PDDM works in per-window heading frames
    /// (`crate::heading`), else `None`.
    pub(crate) fn heading_stats(&self) -> Option<(Vec<f32>, Vec<f32>)> {
        self.config
            .pddm
            .pddm
            .canonical_heading
            .then(|| self.pddm.denorm.host())
    }

    pub(crate) fn shift(&self) -> ResidualShift {
        self.config.pddm.shift.schedule()
    }

    /// Dance for `music` `[frames, 35]` (30 fps EDGE features) with music beats at
    /// `beat_frames`.
    pub fn generate(
        &self,
        music: &[f32],
        beat_frames: &[usize],
        opts: &GenerateOptions,
        device: &Device,
        grad_device: &Device,
    ) -> GeneratedDance {
        self.generate_hooked(music, beat_frames, opts, device, grad_device, &NoHook)
            .expect("NoHook never cancels")
    }

    /// [`SoloModel::generate`], telling `hook` of every GPT token
    /// ([`crate::choreo_gpt::CHOREOGRAPHY`], Lodge++ sampler only) and every denoising step
    /// (`DENOISING`, counted over all windows for the autoregressive sampler), and stopping
    /// with [`Cancelled`] when it answers `Break`.
    pub fn generate_hooked(
        &self,
        music: &[f32],
        beat_frames: &[usize],
        opts: &GenerateOptions,
        device: &Device,
        grad_device: &Device,
        hook: &dyn StepHook,
    ) -> Result<GeneratedDance, Cancelled> {
        let frames = music.len() / MUSIC_DIMS;
        assert!(frames > 0, "no music frames");
        let n = self.config.pddm.pddm.window;
        // Windows come back normalised; the root's horizontal channels have no mean (they are
        // window-relative), so raw windows can be anchored and placed in metres.
        // Ill-defined 6D runs are bridged first, so the seams read proper rotations.
        let bridged = std::cell::Cell::new(0);
        let anchored = |mut w: Vec<f32>, cues: Vec<CuedFrames>| {
            self.to_raw(&mut w);
            bridged.set(bridged.get() + bridge_short_rows(&mut w, n));
            let c = anchor_windows(&mut w, n, &cues);
            (w, c)
        };
        let (mut out, nwin, key_motions, seam_correction) = match opts.sampler {
            Sampler::Lodgepp => {
                let (w, k) =
                    self.lodgepp(music, beat_frames, frames, opts, device, grad_device, hook)?;
                let l = w.len() / (n * DIMS);
                let (w, c) = anchored(w, shared_boundary_cues(l));
                (place_windows(&w, n, n), l, k, c)
            }
            Sampler::Autoregressive => {
                let w = self.autoregressive(music, frames, opts, device, grad_device, hook)?;
                let l = w.len() / (n * DIMS);
                let cues = (0..l)
                    .map(|i| CuedFrames {
                        head: if i == 0 { 0 } else { BOUNDARY_FRAMES },
                        tail: 0,
                    })
                    .collect();
                let (w, c) = anchored(w, cues);
                (place_windows(&w, n, n - BOUNDARY_FRAMES), l, 0, c)
            }
            Sampler::Edge => {
                let (mut placed, l) = self.edge(music, frames, opts, device, grad_device, hook)?;
                // Overlapping windows, already placed: one track per joint.
                let t = placed.len() / DIMS;
                bridged.set(bridge_short_rows(&mut placed, t.max(1)));
                (placed, l, 0, SeamCorrection::default())
            }
        };
        out.truncate(frames * DIMS);
        let rotations_bridged = bridged.get();
        if rotations_bridged > 0 {
            tracing::info!(
                joint_frames = rotations_bridged,
                "bridged generated joint rotations whose 6D rows had shrunk below {}",
                dancegen_motion::rot6d_track::MIN_ROW_LENGTH
            );
        }
        let root_flips_repaired = crate::root_flips::repair_root_flips(&mut out);
        if root_flips_repaired > 0 {
            tracing::info!(
                frames = root_flips_repaired,
                "repaired one- to three-frame flips of the root orientation"
            );
        }
        if opts.foot_lock {
            crate::planted_feet::lock_planted_feet_with(&mut out, opts.foot_lock_rule);
            if opts.foot_ik {
                let ik = crate::planted_feet::pin_planted_feet_with(&mut out, opts.foot_lock_rule);
                tracing::debug!(
                    adjusted = ik.adjusted,
                    unreached_m = ik.max_unreached_m,
                    "leg IK on planted feet"
                );
            }
        }
        keep_on_stage(&mut out, STAGE_HALF_SIZE, STAGE_SMOOTHING_FRAMES);
        Ok(GeneratedDance {
            n_frames: out.len() / DIMS,
            frames: out,
            windows: nwin,
            key_motions,
            seam_correction,
            root_flips_repaired,
            rotations_bridged,
        })
    }

    /// Music `[frames, 35]` cut into `count` windows of `n` frames starting every `advance`
    /// frames (the last frame repeated past the end).
    pub(crate) fn music_windows(
        music: &[f32],
        frames: usize,
        n: usize,
        advance: usize,
        count: usize,
    ) -> Vec<f32> {
        let mut out = Vec::with_capacity(count * n * MUSIC_DIMS);
        for w in 0..count {
            for f in 0..n {
                let src = (w * advance + f).min(frames - 1);
                out.extend_from_slice(&music[src * MUSIC_DIMS..(src + 1) * MUSIC_DIMS]);
            }
        }
        out
    }

    pub(crate) fn cond(
        &self,
        music: Vec<f32>,
        prims: &[WindowPrimitives],
        genre: usize,
        device: &Device,
    ) -> PddmCond {
        let b = prims.len();
        let n = prims[0].mask.len();
        let values: Vec<f32> = prims
            .iter()
            .flat_map(|p| p.values.iter().copied())
            .collect();
        let mask: Vec<f32> = prims.iter().flat_map(|p| p.mask.iter().copied()).collect();
        PddmCond {
            music: Tensor::from_data(TensorData::new(music, [b, n, MUSIC_DIMS]), device),
            genre: vec![genre; b],
            primitives: Tensor::from_data(TensorData::new(values, [b, n, DIMS]), device),
            mask: Tensor::from_data(TensorData::new(mask, [b, n, 1]), device),
            music_encoded: None,
        }
    }

    pub(crate) fn sample_opts(&self, opts: &GenerateOptions, seed: u64) -> PddmSampleOptions {
        PddmSampleOptions {
            steps: opts.steps,
            guidance: opts.guidance,
            refine: opts.refine,
            refine_last_steps: opts.refine_last_steps,
            refine_scope: opts.refine_scope,
            penetration: opts.penetration,
            seed,
        }
    }

    /// The coarse dance `[frames_padded, 42]` in the PDDM's normalised units.
    fn coarse_dance(
        &self,
        music: &[f32],
        frames: usize,
        opts: &GenerateOptions,
        device: &Device,
        hook: &dyn StepHook,
    ) -> Result<Vec<f32>, Cancelled> {
        let padded = frames.div_ceil(TOKEN_FRAMES) * TOKEN_FRAMES;
        let m = Self::music_windows(music, frames, padded, padded, 1);
        let mt = Tensor::<3>::from_data(TensorData::new(m, [1, padded, MUSIC_DIMS]), device);
        let g = &self.config.gpt.gpt;
        let tokens = self.gpt.generate(
            mt,
            opts.genre,
            g.window_tokens,
            g.overlap_tokens,
            &opts.gpt,
            hook,
        )?;
        let nt = tokens.len();
        let idx = Tensor::<3, Int>::from_data(TensorData::new(tokens, [1, nt, 1]), device);
        let coarse: Vec<f32> = self
            .vqvae
            .decode(idx)
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .unwrap();
        // VQ-VAE units → raw 6D → PDDM units.
        let chans = main_channels();
        let mut out = coarse;
        for f in out.chunks_mut(MAIN_DIMS) {
            for (k, &c) in chans.iter().enumerate() {
                let raw = f64::from(f[k]) * self.vqvae_norm.std[c] + self.vqvae_norm.mean[c];
                f[k] = ((raw - self.norm.mean[c]) / self.norm.std[c]) as f32;
            }
        }
        Ok(out)
    }

    /// A library clip `[8, 151]` of `genre` for the coarse frames `[start, start + 8)`, with
    /// the coarse dance's root orientation.
    fn retrieve(&self, coarse: &[f32], start: usize, genre: usize) -> Vec<f32> {
        let chans = main_channels();
        // The coarse frames laid out as PDDM frames (only the main channels set).
        let mut frames = vec![0f32; PRIMITIVE_FRAMES * DIMS];
        for f in 0..PRIMITIVE_FRAMES {
            for (k, &c) in chans.iter().enumerate() {
                frames[f * DIMS + c] = coarse[(start + f) * MAIN_DIMS + k];
            }
        }
        let key = key_of(&frames, DIMS, &retrieval_channels());
        let mut clip = self.library.nearest(&key, Some(genre)).to_vec();
        for f in 0..PRIMITIVE_FRAMES {
            for k in 0..6 {
                let c = layout::rot6d(0, k);
                clip[f * DIMS + c] = frames[f * DIMS + c];
            }
        }
        clip
    }

    /// The full system; returns the windows `[l, n, 151]` and the number of key motions.
    #[allow(clippy::too_many_arguments)]
    fn lodgepp(
        &self,
        music: &[f32],
        beat_frames: &[usize],
        frames: usize,
        opts: &GenerateOptions,
        device: &Device,
        grad_device: &Device,
        hook: &dyn StepHook,
    ) -> Result<(Vec<f32>, usize), Cancelled> {
        let n = self.config.pddm.pddm.window;
        let l = frames.div_ceil(n);
        let started = std::time::Instant::now();
        let coarse = self.coarse_dance(music, frames, opts, device, hook)?;
        tracing::debug!(
            "timing: coarse dance (GPT + VQ-VAE) in {:?}",
            started.elapsed()
        );
        let cf = coarse.len() / MAIN_DIMS;
        let half = PRIMITIVE_FRAMES / 2;
        // Motion beats of the coarse dance → nearest music beats.
        let beats = motion_beats(&speed(
            &coarse,
            MAIN_DIMS,
            &(0..MAIN_DIMS).collect::<Vec<_>>(),
        ));
        let aligned = align_to_music(&beats, beat_frames, opts.max_beat_shift);
        let mut prims: Vec<WindowPrimitives> = (0..l).map(|_| WindowPrimitives::empty(n)).collect();
        let mut keys = 0;
        for (w, p) in prims.iter_mut().enumerate() {
            let lo = w * n;
            let in_window: Vec<(usize, usize)> = aligned
                .iter()
                .filter(|&&(m, b)| b >= lo && b < lo + n && m >= half && m + half <= cf)
                .map(|&(m, b)| (m, b - lo))
                .collect();
            let centres = key_centres(&in_window.iter().map(|&(_, b)| b).collect::<Vec<_>>(), n);
            for c in centres {
                let (m, _) = in_window.iter().find(|&&(_, b)| b == c).copied().unwrap();
                let clip = self.retrieve(&coarse, m - half, opts.genre);
                p.put(c - half, &clip, false);
                keys += 1;
            }
        }
        // Boundary primitives: clip frames 0..4 end window w − 1, 4..8 start window w.
        let mut cue_v = vec![0f32; l * n * DIMS];
        let mut cue_m = vec![0f32; l * n * DIMS];
        let all_but_root = layout::all_but_root_horizontal();
        let mut clips: Vec<f32> = (1..l)
            .flat_map(|w| {
                let at = (w * n).min(cf - half).max(half);
                let mut clip = self.retrieve(&coarse, at - half, opts.genre);
                relative_root(&mut clip, half);
                clip
            })
            .collect();
        // The boundary frames are written over the sampler's output after every step, so the
        // penetration guidance cannot reach them there: they get the same number of guidance
        // iterations once, before sampling.
        if let (Some((g, steps)), false) = (&opts.penetration, clips.is_empty()) {
            let all = PenetrationGuidance {
                iterations: g.iterations * steps,
                ..*g
            };
            let t = Tensor::<3>::from_data(
                TensorData::new(clips, [l - 1, PRIMITIVE_FRAMES, DIMS]),
                device,
            );
            clips = host(guide(
                t,
                &self.pddm.denorm,
                &CapsulePairs::new(),
                &all,
                grad_device,
            ));
        }
        for w in 1..l {
            let clip = &clips[(w - 1) * PRIMITIVE_FRAMES * DIMS..w * PRIMITIVE_FRAMES * DIMS];
            prims[w].put(0, &clip[half * DIMS..], true);
            prims[w - 1].put(n - half, &clip[..half * DIMS], false);
            for f in 0..half {
                for c in 0..DIMS {
                    let i = ((w * n) + f) * DIMS + c;
                    cue_v[i] = clip[(half + f) * DIMS + c];
                    cue_m[i] = 1.0;
                }
                for &c in &all_but_root {
                    let i = ((w - 1) * n + n - half + f) * DIMS + c;
                    cue_v[i] = clip[f * DIMS + c];
                    cue_m[i] = 1.0;
                }
            }
        }
        // Per-window heading frames: window w turned so its frame 0 faces +X; a window without
        // a cued frame 0 (window 0) takes the coarse dance's heading there.
        let stats = self.heading_stats();
        let turns = stats.as_ref().map(|(scale, shift)| {
            let stats = Stats { scale, shift };
            let chans = main_channels();
            let fallback: Vec<f32> = (0..l)
                .map(|w| {
                    let f = (w * n).min(cf - 1);
                    let mut frame = vec![0f32; DIMS];
                    for (k, &c) in chans.iter().enumerate() {
                        frame[c] = coarse[f * MAIN_DIMS + k];
                    }
                    heading::heading(&frame, &stats)
                })
                .collect();
            let t = heading::window_turns(&prims, &fallback, &stats);
            heading::turn_cues(&mut prims, &mut cue_v, &cue_m, &t, &stats);
            t
        });
        let m = Self::music_windows(music, frames, n, n, l);
        let cond = self.cond(m, &prims, opts.genre, device);
        let cues = HardCues {
            values: Tensor::from_data(TensorData::new(cue_v, [l, n, DIMS]), device),
            mask: Tensor::from_data(TensorData::new(cue_m, [l, n, DIMS]), device),
        };
        tracing::debug!("timing: primitives ready at {:?}", started.elapsed());
        let x = sample_windows_hooked(
            &self.pddm,
            &self.shift(),
            &cond,
            Some(&cues),
            &self.sample_opts(opts, opts.seed),
            device,
            grad_device,
            hook,
        )?;
        let mut x = host(x);
        if let (Some((scale, shift)), Some(t)) = (&stats, turns) {
            let back: Vec<f32> = t.iter().map(|a| -a).collect();
            heading::turn_windows(&mut x, n, &back, &Stats { scale, shift });
        }
        tracing::debug!("timing: PDDM sampling done at {:?}", started.elapsed());
        Ok((x, keys))
    }

    /// Window after window, each starting with the previous one's last 4 frames.
    fn autoregressive(
        &self,
        music: &[f32],
        frames: usize,
        opts: &GenerateOptions,
        device: &Device,
        grad_device: &Device,
        hook: &dyn StepHook,
    ) -> Result<Vec<f32>, Cancelled> {
        let n = self.config.pddm.pddm.window;
        let adv = n - BOUNDARY_FRAMES;
        let l = frames.saturating_sub(BOUNDARY_FRAMES).div_ceil(adv).max(1);
        let mut out: Vec<f32> = Vec::with_capacity(l * n * DIMS);
        let mut prev: Option<Vec<f32>> = None;
        for w in 0..l {
            let mut p = WindowPrimitives::empty(n);
            let mut cue_v = vec![0f32; n * DIMS];
            let mut cue_m = vec![0f32; n * DIMS];
            if let Some(pw) = &prev {
                let mut head = pw[(n - BOUNDARY_FRAMES) * DIMS..].to_vec();
                relative_root(&mut head, 0);
                p.put(0, &head, true);
                cue_v[..head.len()].copy_from_slice(&head);
                cue_m[..head.len()].iter_mut().for_each(|v| *v = 1.0);
            }
            let m = Self::music_windows(&music[w * adv * MUSIC_DIMS..], frames - w * adv, n, n, 1);
            let window = CuedWindow {
                music: m,
                prims: p,
                cue_v,
                cue_m,
                cued: prev.is_some(),
            };
            let x = self.sample_cued_window(window, opts, (w, l), device, grad_device, hook)?;
            out.extend_from_slice(&x);
            prev = Some(x);
        }
        Ok(out)
    }

    /// Samples one window (normalised, window-relative root) with its primitives and, when
    /// `cued`, its hard cues, in its heading frame when the model uses one (the first frame's
    /// heading when cued, else 0) and turned back. `index` is (this window, windows in the run):
    /// steps are reported over the whole run, and window `i` gets seed `opts.seed + i`. Shared by
    /// the autoregressive sampler and editing (`crate::inpaint`).
    pub(crate) fn sample_cued_window(
        &self,
        window: CuedWindow,
        opts: &GenerateOptions,
        index: (usize, usize),
        device: &Device,
        grad_device: &Device,
        hook: &dyn StepHook,
    ) -> Result<Vec<f32>, Cancelled> {
        let n = self.config.pddm.pddm.window;
        let CuedWindow {
            music,
            mut prims,
            mut cue_v,
            cue_m,
            cued,
        } = window;
        let stats = self.heading_stats();
        let turn = stats.as_ref().map(|(scale, shift)| {
            let stats = Stats { scale, shift };
            let t = heading::window_turns(std::slice::from_ref(&prims), &[0.0], &stats);
            heading::turn_cues(
                std::slice::from_mut(&mut prims),
                &mut cue_v,
                &cue_m,
                &t,
                &stats,
            );
            t[0]
        });
        let cond = self.cond(music, std::slice::from_ref(&prims), opts.genre, device);
        let cues = HardCues {
            values: Tensor::from_data(TensorData::new(cue_v, [1, n, DIMS]), device),
            mask: Tensor::from_data(TensorData::new(cue_m, [1, n, DIMS]), device),
        };
        let (w, l) = index;
        // Steps are counted over all windows, so the hook sees one run of l · steps.
        let per_window = |_: &'static str, done: usize, total: usize| {
            hook.on_step(DENOISING, w * total + done, l * total)
        };
        let mut x = host(sample_windows_hooked(
            &self.pddm,
            &self.shift(),
            &cond,
            cued.then_some(&cues),
            &self.sample_opts(opts, opts.seed.wrapping_add(w as u64)),
            device,
            grad_device,
            &per_window,
        )?);
        if let (Some((scale, shift)), Some(a)) = (&stats, turn) {
            heading::turn_windows(&mut x, n, &[-a], &Stats { scale, shift });
        }
        Ok(x)
    }

    /// EDGE-style: half-overlapping windows in one batch, first halves overwritten after every
    /// step but the last (EDGE's `long_ddim_sample`), then EDGE's final stitching: positions
    /// cross-faded and rotations slerped over each overlap (`dancegen_nn::diffusion::longform`).
    /// Returns the placed frames (raw units) and the window count.
    fn edge(
        &self,
        music: &[f32],
        frames: usize,
        opts: &GenerateOptions,
        device: &Device,
        grad_device: &Device,
        hook: &dyn StepHook,
    ) -> Result<(Vec<f32>, usize), Cancelled> {
        let n = self.config.pddm.pddm.window;
        let half = n / 2;
        let l = frames.saturating_sub(half).div_ceil(half).max(1);
        let prims: Vec<WindowPrimitives> = (0..l).map(|_| WindowPrimitives::empty(n)).collect();
        let m = Self::music_windows(music, frames, n, half, l);
        let cond = self.cond(m, &prims, opts.genre, device);
        let stats = self.heading_stats();
        let mut win = host(crate::sampler::sample_windows_with(
            &self.pddm,
            &self.shift(),
            &cond,
            &self.sample_opts(opts, opts.seed),
            device,
            grad_device,
            |x, last| match (&stats, last) {
                (_, true) => x,
                (None, false) => overwrite_first_halves_relative(x, half),
                (Some((scale, shift)), false) => {
                    let dims = x.dims();
                    let mut h = host(x);
                    heading::overwrite_first_halves_turned(
                        &mut h,
                        n,
                        half,
                        &Stats { scale, shift },
                    );
                    Tensor::from_data(TensorData::new(h, dims), device)
                }
            },
            hook,
        )?);
        // Window-relative roots → one path: window w starts where window w − 1 is at its
        // middle frame (`win` already holds window w − 1 in global coordinates), and, in
        // heading frames, faces the way window w − 1 faces there.
        for w in 1..l {
            if let Some((scale, shift)) = &stats {
                let stats = Stats { scale, shift };
                let prev = (w - 1) * n + half;
                let h = heading::heading(&win[prev * DIMS..(prev + 1) * DIMS], &stats);
                heading::turn_windows(&mut win[w * n * DIMS..(w + 1) * n * DIMS], n, &[h], &stats);
            }
            let prev = (w - 1) * n + half;
            let origin: Vec<f32> = ROOT_HORIZONTAL
                .iter()
                .map(|&c| win[prev * DIMS + c])
                .collect();
            for f in 0..n {
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    win[(w * n + f) * DIMS + c] += origin[k];
                }
            }
        }
        // Stitch in raw units (slerp needs real rotations); the result stays raw.
        self.to_raw(&mut win);
        let raw = Tensor::<3>::from_data(TensorData::new(win, [l, n, DIMS]), device);
        let out: Vec<f32> = stitch(raw, &ChannelLayout::edge151())
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .unwrap();
        Ok((out, l))
    }
}

/// Half the side of the square (metres) the dancer's slow travel is kept in, so minutes of
/// windows placed one after another cannot walk off a 6 m stage (fast steps still reach ~1 m
/// beyond it).
pub const STAGE_HALF_SIZE: f32 = 2.0;
/// Gaussian σ (frames, 4 s at 30 fps) separating slow travel from dance steps.
pub const STAGE_SMOOTHING_FRAMES: f64 = 120.0;

/// The cues of the Lodge++ sampler's `l` windows: every inner boundary's 4 + 4 shared frames.
pub fn shared_boundary_cues(l: usize) -> Vec<CuedFrames> {
    (0..l)
        .map(|w| CuedFrames {
            head: if w > 0 { BOUNDARY_FRAMES } else { 0 },
            tail: if w + 1 < l { BOUNDARY_FRAMES } else { 0 },
        })
        .collect()
}

/// Moves the root's horizontal path (raw frames `[T, 151]`) by the part of its slow travel
/// (Gaussian-smoothed path) that lies outside the square `±half`: a smooth, low-frequency
/// correction that leaves every step's shape as generated.
pub fn keep_on_stage(frames: &mut [f32], half: f32, sigma: f64) {
    let t = frames.len() / DIMS;
    if t == 0 {
        return;
    }
    for &c in &ROOT_HORIZONTAL {
        let x: Vec<f64> = (0..t).map(|f| f64::from(frames[f * DIMS + c])).collect();
        for (f, centre) in gaussian_smooth(&x, sigma, Ends::Renormalise)
            .into_iter()
            .enumerate()
        {
            let centre = centre as f32;
            let outside = centre - centre.clamp(-half, half);
            frames[f * DIMS + c] -= outside;
        }
    }
}

pub(crate) fn host(x: Tensor<3>) -> Vec<f32> {
    x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
}

/// EDGE's long-form overwrite for window-relative roots: window `i`'s first half becomes
/// window `i − 1`'s second half, re-based so its first frame's root x/y is 0.
pub fn overwrite_first_halves_relative(x: Tensor<3>, half: usize) -> Tensor<3> {
    let [l, n, _] = x.dims();
    if l < 2 {
        return x;
    }
    let src = x.clone().narrow(0, 0, l - 1).narrow(1, half, n - half);
    let lo = ROOT_HORIZONTAL[0];
    let root = src.clone().narrow(2, lo, 2);
    let first = root.clone().narrow(1, 0, 1).expand([l - 1, n - half, 2]);
    let rebased = Tensor::cat(
        vec![
            src.clone().narrow(2, 0, lo),
            root - first,
            src.narrow(2, lo + 2, DIMS - lo - 2),
        ],
        2,
    );
    let rest = Tensor::cat(
        vec![
            rebased,
            x.clone().narrow(0, 1, l - 1).narrow(1, n - half, half),
        ],
        1,
    );
    Tensor::cat(vec![x.narrow(0, 0, 1), rest], 0)
}

/// Windows `[l, n, 151]` (normalised, window-relative root) → one sequence: window `w` starts
/// `advance` frames after window `w − 1` (its first `n − advance` frames repeat the previous
/// window's last ones and are skipped), placed so its first frame continues from the previous
/// window's motion (the step between the two frames before the join is carried over).
pub fn place_windows(windows: &[f32], n: usize, advance: usize) -> Vec<f32> {
    let l = windows.len() / (n * DIMS);
    let overlap = n - advance;
    let mut out: Vec<f32> = Vec::with_capacity((n + (l.saturating_sub(1)) * advance) * DIMS);
    let mut origin = [0f32; 2];
    for w in 0..l {
        let win = &windows[w * n * DIMS..(w + 1) * n * DIMS];
        let skip = if w == 0 { 0 } else { overlap };
        if w > 0 {
            // Where this window's frame 0 sits: on the already placed frame it repeats, or one
            // step after the last placed frame for disjoint windows.
            let placed = out.len() / DIMS;
            if overlap > 0 {
                let f = placed - overlap;
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    origin[k] = out[f * DIMS + c];
                }
            } else {
                let last = &out[(placed - 1) * DIMS..placed * DIMS];
                let before = &out[(placed.max(2) - 2) * DIMS..(placed.max(2) - 1) * DIMS];
                for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                    origin[k] = last[c] + (last[c] - before[c]);
                }
            }
        }
        for f in skip..n {
            let mut fr = win[f * DIMS..(f + 1) * DIMS].to_vec();
            for (k, &c) in ROOT_HORIZONTAL.iter().enumerate() {
                fr[c] += origin[k];
            }
            out.extend(fr);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_walk_stays_on_stage_and_keeps_its_steps() {
        // 5 minutes walking 1 cm per frame in x, with a 10 cm side-step wiggle.
        let t = 9000;
        let mut f = vec![0f32; t * DIMS];
        for i in 0..t {
            f[i * DIMS + 4] = i as f32 * 0.01;
            f[i * DIMS + 5] = 0.1 * (i as f32 * 0.3).sin();
        }
        let before = f.clone();
        keep_on_stage(&mut f, STAGE_HALF_SIZE, STAGE_SMOOTHING_FRAMES);
        let xs: Vec<f32> = f.chunks(DIMS).map(|r| r[4]).collect();
        assert!(
            xs.iter().all(|x| x.abs() < 3.0),
            "max {}",
            xs.iter().fold(0f32, |a, b| a.max(b.abs()))
        );
        // Small-scale motion is untouched: the side-step wiggle is the same.
        for i in 0..t {
            assert!((f[i * DIMS + 5] - before[i * DIMS + 5]).abs() < 1e-6);
        }
        // Inside the square nothing moves.
        assert_eq!(&f[..100 * DIMS], &before[..100 * DIMS]);
    }

    #[test]
    fn disjoint_windows_continue_the_root_path() {
        let n = 8;
        // Two windows walking +1 per frame in x, each relative to its own first frame.
        let mut w = vec![0f32; 2 * n * DIMS];
        for k in 0..2 {
            for f in 0..n {
                w[(k * n + f) * DIMS + 4] = f as f32;
            }
        }
        let out = place_windows(&w, n, n);
        let xs: Vec<f32> = out.chunks(DIMS).map(|f| f[4]).collect();
        assert_eq!(xs, (0..16).map(|i| i as f32).collect::<Vec<_>>());
    }

    #[test]
    fn overlapping_windows_skip_the_repeated_frames() {
        let n = 8;
        let mut w = vec![0f32; 2 * n * DIMS];
        for k in 0..2 {
            for f in 0..n {
                w[(k * n + f) * DIMS + 4] = f as f32;
                w[(k * n + f) * DIMS + 10] = (k * 4 + f) as f32;
            }
        }
        let out = place_windows(&w, n, 4);
        let xs: Vec<f32> = out.chunks(DIMS).map(|f| f[4]).collect();
        assert_eq!(xs, (0..12).map(|i| i as f32).collect::<Vec<_>>());
        let ys: Vec<f32> = out.chunks(DIMS).map(|f| f[10]).collect();
        assert_eq!(ys, (0..12).map(|i| i as f32).collect::<Vec<_>>());
    }
}
