//! Long-form sampling of the latent: Blocked Local Context (paper §"BLC") and, for the
//! ablation, autoregressive window-by-window sampling.
//!
//! **BLC.** The `K`-token latent is cut into `⌈K/T⌉` non-overlapping blocks of `T` tokens
//! (the training window) and every block is denoised at once. The paper states it as one
//! sequence with a block-diagonal periodic mask and a phase encoding that restarts every `T`
//! tokens; attention then never crosses a block, so the same computation is the blocks as a
//! batch with positions `0..T` each ([`crate::denoiser::Layout::Batched`]) — which costs `K·T`
//! attention scores instead of `K²`. `tests/blc.rs` checks the two agree. The last block is
//! padded by repeating the last token's condition and its padding is dropped. Continuity
//! between blocks comes from training (dense sliding windows) and the conv decoder, which
//! decodes the whole latent at once.
//!
//! **Autoregressive** (ablation): windows of `T` tokens every `T/2`; each window's first half
//! is inpainted (hard cue) with the previous window's second half.
//!
//! Guidance is LDCFG: level `r`'s channels get `x̂0 = (1 + s_r)·cond − s_r·uncond`
//! ([`Guidance::PerChannel`]); all `s_r = 0` skips the unconditional branch.
//!
//! **Editing** ([`LatentCue`]): tokens whose value is known (the latent of the frames an edit
//! keeps) are hard cues, noised to each step's level, in either sampler; the rest is generated
//! to go with them (diffusion inpainting).

use dancegen_nn::burn;
use dancegen_nn::diffusion::{
    ChannelScale, Cue, CueActivity, Guidance, Method, SampleOptions, Schedule, Spacing,
    WeightSchedule, sample_hooked,
};
use dancegen_nn::progress::{Cancelled, NoHook, StepHook};

use burn::tensor::{Device, Tensor, TensorData};

use crate::denoiser::{DuetCond, LatentDenoiser, Layout, PreparedDenoiser};

/// How a latent longer than one block is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LongForm {
    /// Blocked Local Context: all blocks in parallel.
    Blc,
    /// Window by window, each inpainted with half of the previous one.
    Autoregressive,
}

/// One sampling run.
#[derive(Clone, Debug)]
pub struct LatentSampling {
    pub steps: usize,
    /// DDIM stochasticity (EDGE: 1).
    pub eta: f64,
    /// `s_r` per level (missing levels use the last value).
    pub guidance: Vec<f64>,
    pub seed: u64,
    pub long_form: LongForm,
}

/// Known tokens of the latent being sampled (an edit): `value` `[K, C]` row-major, and
/// `known[i]` whether token `i`'s value is imposed.
#[derive(Clone, Debug, PartialEq)]
pub struct LatentCue {
    pub value: Vec<f32>,
    pub known: Vec<bool>,
}

impl LatentCue {
    /// The cue over tokens `start..start + len` as `[1, len, C]` tensors (tokens past the end
    /// repeat the last one's, as [`to_blocks`] pads), or `None` if none of them is known.
    fn window(&self, start: usize, len: usize, c: usize, device: &Device) -> Option<Cue> {
        let k = self.known.len();
        let at = |i: usize| (start + i).min(k - 1);
        if !(0..len).any(|i| self.known[at(i)]) {
            return None;
        }
        let mut value = vec![0f32; len * c];
        let mut mask = vec![0f32; len * c];
        for i in 0..len {
            let g = at(i);
            if self.known[g] {
                value[i * c..(i + 1) * c].copy_from_slice(&self.value[g * c..(g + 1) * c]);
                mask[i * c..(i + 1) * c].fill(1.0);
            }
        }
        Some(Cue {
            value: Tensor::from_data(TensorData::new(value, [1, len, c]), device),
            mask: Tensor::from_data(TensorData::new(mask, [1, len, c]), device),
            noised: true,
            activity: CueActivity::Hard,
        })
    }

    /// The cue over every block of [`to_blocks`] (`[nb, block, C]`).
    fn blocks(&self, block: usize, c: usize, device: &Device) -> Option<Cue> {
        let nb = self.known.len().div_ceil(block);
        let cue = self.window(0, nb * block, c, device)?;
        Some(Cue {
            value: cue.value.reshape([nb, block, c]),
            mask: cue.mask.reshape([nb, block, c]),
            ..cue
        })
    }
}

/// The LDCFG guidance of `levels` levels of `level_dim` channels.
pub fn level_guidance(scales: &[f64], levels: usize, level_dim: usize) -> Guidance {
    let s = |r: usize| scales.get(r).or(scales.last()).copied().unwrap_or(0.0);
    if (0..levels).all(|r| s(r) == 0.0) {
        return Guidance::Conditional;
    }
    Guidance::PerChannel {
        groups: (0..levels)
            .map(|r| ChannelScale {
                range: r * level_dim..(r + 1) * level_dim,
                s: s(r),
            })
            .collect(),
        default_s: 0.0,
    }
}

/// `x` `[1, K, C]` cut into `[⌈K/T⌉, T, C]`, the tail padded with the last token.
pub fn to_blocks(x: Tensor<3>, block: usize) -> Tensor<3> {
    let [_, k, c] = x.dims();
    let nb = k.div_ceil(block);
    let pad = nb * block - k;
    let x = if pad > 0 {
        let last = x.clone().narrow(1, k - 1, 1).expand([1, pad, c]);
        Tensor::cat(vec![x, last], 1)
    } else {
        x
    };
    x.reshape([nb, block, c])
}

fn cond_blocks(c: &DuetCond, block: usize) -> DuetCond {
    DuetCond {
        leader: to_blocks(c.leader.clone(), block),
        music: to_blocks(c.music.clone(), block),
    }
}

fn cond_window(c: &DuetCond, start: usize, len: usize) -> DuetCond {
    DuetCond {
        leader: c.leader.clone().narrow(1, start, len),
        music: c.music.clone().narrow(1, start, len),
    }
}

fn options(s: &LatentSampling, guidance: Guidance, seed: u64) -> SampleOptions {
    SampleOptions {
        method: Method::Ddim {
            steps: s.steps,
            eta: s.eta,
            spacing: Spacing::Linear,
        },
        clip_x0: Some((-1.0, 1.0)),
        guidance,
        weight_schedule: WeightSchedule::Constant,
        cues: Vec::new(),
        long_form: false,
        seed,
        init: None,
    }
}

/// Samples the `[1, K, C]` latent for the condition `c` (`[1, K, ·]` each).
pub fn sample_latent(
    net: &LatentDenoiser,
    schedule: &Schedule,
    c: &DuetCond,
    latent_dim: usize,
    levels: usize,
    s: &LatentSampling,
    device: &Device,
) -> Tensor<3> {
    sample_latent_hooked(net, schedule, c, latent_dim, levels, s, device, &NoHook)
        .expect("NoHook never cancels")
}

/// [`sample_latent`], telling `hook` after every denoising step (part `DENOISING`, counted
/// over all windows for the autoregressive sampler) and stopping with [`Cancelled`] when it
/// answers `Break`.
#[allow(clippy::too_many_arguments)]
pub fn sample_latent_hooked(
    net: &LatentDenoiser,
    schedule: &Schedule,
    c: &DuetCond,
    latent_dim: usize,
    levels: usize,
    s: &LatentSampling,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Tensor<3>, Cancelled> {
    sample_latent_cued_hooked(net, schedule, c, latent_dim, levels, s, None, device, hook)
}

/// [`sample_latent_hooked`] with the tokens `cue` knows imposed (an edit).
#[allow(clippy::too_many_arguments)]
pub fn sample_latent_cued_hooked(
    net: &LatentDenoiser,
    schedule: &Schedule,
    c: &DuetCond,
    latent_dim: usize,
    levels: usize,
    s: &LatentSampling,
    cue: Option<&LatentCue>,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Tensor<3>, Cancelled> {
    let k = c.leader.dims()[1];
    if let Some(cue) = cue {
        assert_eq!(cue.known.len(), k, "one cue entry per token");
        assert_eq!(
            cue.value.len(),
            k * latent_dim,
            "a cue value per token and channel"
        );
    }
    let t = net.block_tokens;
    let guidance = level_guidance(&s.guidance, levels, latent_dim / levels);
    let guided = !matches!(guidance, Guidance::Conditional);
    if s.long_form == LongForm::Blc || k <= t {
        let blocks = cond_blocks(c, t);
        let nb = blocks.leader.dims()[0];
        let model = PreparedDenoiser::new(net, &blocks, guided, Layout::Batched);
        let mut opts = options(s, guidance, s.seed);
        opts.cues
            .extend(cue.and_then(|q| q.blocks(t, latent_dim, device)));
        let x = sample_hooked(
            &model,
            schedule,
            [nb, t, latent_dim],
            Some(&blocks),
            &opts,
            device,
            hook,
        )?;
        return Ok(x.reshape([1, nb * t, latent_dim]).narrow(1, 0, k));
    }
    // Autoregressive windows.
    let hop = t / 2;
    let mut starts: Vec<usize> = (0..)
        .map(|i| i * hop)
        .take_while(|&st| st + t < k)
        .collect();
    starts.push(k - t);
    let mut out: Option<Tensor<3>> = None;
    for (i, &st) in starts.iter().enumerate() {
        let w = cond_window(c, st, t);
        let model = PreparedDenoiser::new(net, &w, guided, Layout::Batched);
        let mut opts = options(s, guidance.clone(), s.seed.wrapping_add(i as u64));
        opts.cues
            .extend(cue.and_then(|q| q.window(st, t, latent_dim, device)));
        if let Some(prev) = &out {
            let known = prev.dims()[1] - st;
            let mut value = prev.clone().narrow(1, st, known);
            value = Tensor::cat(
                vec![value, Tensor::zeros([1, t - known, latent_dim], device)],
                1,
            );
            opts.cues.push(Cue {
                value,
                mask: Cue::frames([1, t, latent_dim], 0..known, device),
                noised: true,
                activity: CueActivity::Hard,
            });
        }
        let windows = starts.len();
        let per_window = |part: &'static str, done: usize, total: usize| {
            hook.on_step(part, i * total + done, windows * total)
        };
        let x = sample_hooked(
            &model,
            schedule,
            [1, t, latent_dim],
            Some(&w),
            &opts,
            device,
            &per_window,
        )?;
        out = Some(match out {
            None => x,
            Some(prev) => {
                let known = prev.dims()[1] - st;
                Tensor::cat(vec![prev, x.narrow(1, known, t - known)], 1)
            }
        });
    }
    Ok(out.expect("at least one window"))
}
