//! The Group Dance Decoder plus the Footwork Adaptor (paper §4.1–4.2, Fig. 2): x̂0 of a group
//! window from its noised version, the music, the swap mode and the formation-control flags.
//!
//! Per token (frame-major, [`crate::layout`]):
//! 1. `Linear([x_t; control] → d)`: the EDGE-151 frame of one dancer plus a flag that is 1
//!    where its root x/y is the clean, requested path (formation control, the TCDiff v1
//!    injection with a flag so partial control is unambiguous; group.md §1 row 12 "Proposal").
//! 2. Plus the dancer positioning embedding ([`dancegen_nn::pos_encoding::dancer_positions`]: the
//!    temporal code of the token's frame plus the rank code of its slot, Eq. 8). Added before
//!    the Fusion Projection, as the paper says (the released code adds it after).
//! 3. [`FusionProjection`] over each frame's dancers.
//! 4. `n_layers` Sequence Decoder layers: EDGE's FiLM transformer decoder layer or
//!    [`CrossMambaLayer`]. Self-attention runs over all `T · N_MAX` tokens with empty slots as
//!    key padding; the memory is `[swap token ‖ music tokens]`; the FiLM vector is timestep +
//!    pooled music + swap embedding (§4.1: "T, M and S … injected into FiLM"). Empty slots are
//!    zeroed after every layer, so they never leak into the causal scan or the fusion.
//! 5. `Linear(d → 151)` = raw motion x̂r, then the [`FootworkAdaptor`] replaces the lower body.
//!
//! The music is EDGE's 35 librosa features per frame (paper §3.2 says 35-d; the released code
//! uses 438-d at 60 fps, B.2), `Linear → d` plus `music_layers` encoder layers.
//! Our choice: the timestep reaches the network through FiLM only (EDGE also appends two time
//! tokens to the memory), so the memory is the same at every step and its keys and values are
//! projected once per sampling run.
//! Classifier-free guidance drops the music (a learned null token); the swap mode and the
//! control flags are structure, never dropped.

use dancegen_nn::attention::{AttnMasks, ProjectedKv};
use dancegen_nn::burn;
use dancegen_nn::diffusion::{Conditioning, Denoiser, separate_guidance_branches};
use dancegen_nn::edge151::{DIMS, Denormalize};
use dancegen_nn::pos_encoding::{dancer_positions, sinusoidal};
use dancegen_nn::timestep::{TimestepMlp, TimestepMlpConfig};
use dancegen_nn::transformer::{
    DecoderContext, EncoderLayer, EncoderLayerConfig, FilmDecoderLayer, FilmDecoderLayerConfig,
};

use burn::module::{Module, Param};
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::config::{DenoiserConfig, SequenceMixer};
use crate::cross_mamba::CrossMambaLayer;
use crate::footwork::FootworkAdaptor;
use crate::fusion::FusionProjection;
use crate::heading_path::HeadingPath;
use crate::layout::{N_MAX, from_tokens, to_tokens, token_mask, token_padding};
use crate::prediction::{Prediction, SkipGate, VelocitySkip};
use crate::root_path::RootPath;
use crate::swap::SwapEmbedding;
use dancegen_nn::host_linear;

/// EDGE's music features per frame (`dancegen_music` EDGE-35).
pub const MUSIC_DIMS: usize = 35;

/// What one batch of group windows is conditioned on.
#[derive(Clone, Debug)]
pub struct GroupCond {
    /// `[B, T, 35]`.
    pub music: Tensor<3>,
    /// Active dancers per element (2..=N_MAX), in slots `0..n`.
    pub dancers: Vec<usize>,
    /// Swap codes `[B, N_MAX²]` ([`crate::swap::swap_code`]).
    pub swap: Tensor<2>,
    /// `[B, T, N_MAX]`: 1 where the slot's root x/y in `x_t` is the clean requested path.
    pub control: Tensor<3>,
}

impl GroupCond {
    /// No formation control.
    pub fn free(music: Tensor<3>, dancers: Vec<usize>, swap: Tensor<2>) -> Self {
        let [b, t, _] = music.dims();
        let control = Tensor::zeros([b, t, N_MAX], &music.device());
        Self {
            music,
            dancers,
            swap,
            control,
        }
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct GroupDenoiser {
    pub input: Linear,
    pub time: TimestepMlp,
    pub time_cond: Linear,
    pub music_in: Linear,
    pub music_layers: Vec<EncoderLayer>,
    pub music_pool: Linear,
    pub null_music: Param<Tensor<3>>,
    pub swap: Option<SwapEmbedding>,
    pub fusion: Option<FusionProjection>,
    pub attn_layers: Vec<FilmDecoderLayer>,
    pub ssm_layers: Vec<CrossMambaLayer>,
    pub output: Linear,
    pub footwork: Option<FootworkAdaptor>,
    /// The integrated root path ([`DenoiserConfig::root_integrated`]).
    pub root_path: Option<RootPath>,
    /// The normaliser the model was trained with (one per-dancer EDGE-151 normaliser).
    pub denorm: Denormalize,
    #[module(skip)]
    pub d_model: usize,
    #[module(skip)]
    pub positioning: bool,
    /// `h + FP(h)` instead of `FP(h)` ([`DenoiserConfig::fusion_residual`]).
    #[module(skip)]
    pub fusion_residual: bool,
    /// The skip from x_t of [`crate::prediction::Prediction::Velocity`]; `None` predicts x̂0.
    #[module(skip)]
    pub velocity: Option<VelocitySkip>,
    /// The learned skip of [`crate::prediction::Prediction::LearnedSkip`].
    pub skip_gate: Option<SkipGate>,
    /// The integrated heading ([`DenoiserConfig::heading_integrated`]).
    pub heading_path: Option<HeadingPath>,
}

impl DenoiserConfig {
    /// A fresh network for the data's normaliser (`mean`, `std` of one dancer's 151 channels).
    pub fn init(&self, mean: &[f64], std: &[f64], device: &Device) -> GroupDenoiser {
        let d = self.d_model;
        let (attn, ssm) = match self.mixer {
            SequenceMixer::CrossAttention => (self.n_layers, 0),
            SequenceMixer::Mamba => (0, self.n_layers),
        };
        GroupDenoiser {
            input: LinearConfig::new(DIMS + 1, d).init(device),
            time: TimestepMlpConfig::new(d).init(device),
            time_cond: LinearConfig::new(4 * d, d).init(device),
            music_in: LinearConfig::new(MUSIC_DIMS, d).init(device),
            music_layers: (0..self.music_layers)
                .map(|_| {
                    EncoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .init(device)
                })
                .collect(),
            music_pool: LinearConfig::new(d, d).init(device),
            null_music: Param::from_tensor(Tensor::zeros([1, 1, d], device)),
            swap: self.swap_mode.then(|| SwapEmbedding::new(d, device)),
            fusion: self
                .fusion_projection
                .then(|| FusionProjection::new(d, self.fusion_hidden(), device)),
            attn_layers: (0..attn)
                .map(|_| {
                    FilmDecoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .init(device)
                })
                .collect(),
            ssm_layers: (0..ssm)
                .map(|_| CrossMambaLayer::new(d, self.n_heads, self.d_ff, self.dropout, device))
                .collect(),
            output: LinearConfig::new(d, DIMS).init(device),
            footwork: self.footwork.then(|| {
                FootworkAdaptor::new(self.footwork_hidden, self.footwork_residual, device)
            }),
            root_path: self.root_integrated.then(|| RootPath::new(d, device)),
            denorm: Denormalize::from_mean_std(mean, std, device),
            d_model: d,
            positioning: self.positioning,
            fusion_residual: self.fusion_residual,
            velocity: (self.prediction == Prediction::Velocity)
                .then(|| VelocitySkip::new(self.root_integrated)),
            skip_gate: (self.prediction == Prediction::LearnedSkip).then(|| {
                SkipGate::new(
                    4 * d,
                    self.root_integrated,
                    &self.skip_smoothing,
                    self.skip_smooth_root_rotation,
                    device,
                )
            }),
            heading_path: self
                .heading_integrated
                .then(|| HeadingPath::new(d, self.root_rotation_smoothing, device)),
        }
    }
}

/// The step-invariant part of a condition.
#[derive(Clone, Debug)]
pub struct PreparedCond {
    /// `[B, M, d]`.
    pub memory: Tensor<3>,
    /// Each transformer layer's K/V of `memory` (inference only).
    pub memory_kv: Option<Vec<ProjectedKv>>,
    /// Pooled music + swap, `[B, 1, d]`.
    pub film: Tensor<3>,
}

impl GroupDenoiser {
    fn positions(&self, frames: usize, device: &Device) -> Tensor<3> {
        let d = self.d_model;
        let pe = if self.positioning {
            let ranks: Vec<usize> = (0..N_MAX).collect();
            dancer_positions(&ranks, frames, d, N_MAX, device)
        } else {
            sinusoidal(0, frames, d, device)
                .unsqueeze_dim::<3>(1)
                .expand([frames, N_MAX, d])
                .reshape([frames * N_MAX, d])
        };
        pe.unsqueeze()
    }

    /// Memory and FiLM base of `c`; `keep[b]`: element `b` hears the music. `project`: also
    /// each transformer layer's cross-attention K/V.
    pub fn prepare(&self, c: &GroupCond, keep: &[bool], project: bool) -> PreparedCond {
        let [b, t, _] = c.music.dims();
        assert_eq!(keep.len(), b, "one keep flag per batch element");
        let device = c.music.device();
        let d = self.d_model;
        let null = self.null_music.val();
        let (tokens, pooled) = if keep.iter().all(|&k| !k) {
            (null.clone().expand([b, t, d]), null.expand([b, 1, d]))
        } else {
            let mut h = self.music_in.forward(c.music.clone())
                + sinusoidal(0, t, d, &device).unsqueeze::<3>();
            let masks = AttnMasks::default();
            for l in &self.music_layers {
                h = l.forward(h, &masks, None);
            }
            let pooled = self.music_pool.forward(h.clone().mean_dim(1));
            if keep.iter().all(|&k| k) {
                (h, pooled)
            } else {
                let k: Vec<f32> = keep.iter().map(|&k| f32::from(u8::from(k))).collect();
                let k = Tensor::<1>::from_data(TensorData::new(k, [b]), &device).reshape([b, 1, 1]);
                let inv = k.clone().neg() + 1.0;
                (
                    h * k.clone() + null.clone().expand([b, t, d]) * inv.clone(),
                    pooled * k + null.expand([b, 1, d]) * inv,
                )
            }
        };
        let (memory, film) = match &self.swap {
            Some(s) => {
                let e = s.forward(c.swap.clone()).unsqueeze_dim::<3>(1);
                (Tensor::cat(vec![e.clone(), tokens], 1), pooled + e)
            }
            None => (tokens, pooled),
        };
        let memory_kv = project.then(|| {
            self.attn_layers
                .iter()
                .map(|l| l.cross_kv(memory.clone()))
                .collect()
        });
        PreparedCond {
            memory,
            memory_kv,
            film,
        }
    }

    /// x̂0 `[B, T, N_MAX·151]` of `x_t` at 0-based timesteps `t`.
    pub fn forward_prepared(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        c: &GroupCond,
        p: &PreparedCond,
    ) -> Tensor<3> {
        let [b, frames, _] = x_t.dims();
        let device = x_t.device();
        let mask = token_mask(&c.dancers, frames, &device);
        let control = c.control.clone().reshape([b, frames * N_MAX, 1]);
        let x_tokens = to_tokens(x_t);
        let h = host_linear::forward(&self.input, Tensor::cat(vec![x_tokens.clone(), control], 2));
        let mut h = (h + self.positions(frames, &device)) * mask.clone();
        if let Some(f) = &self.fusion {
            let fused = f.forward(h.clone(), mask.clone());
            h = if self.fusion_residual {
                h + fused
            } else {
                fused
            };
        }
        let time_features = self.time.forward(t, &device);
        let time = self
            .time_cond
            .forward(time_features.clone())
            .unsqueeze_dim::<3>(1);
        let self_masks = AttnMasks {
            attn: None,
            key_padding: Some(token_padding(&c.dancers, frames, &device)),
        };
        let cross_masks = AttnMasks::default();
        let ctx = DecoderContext {
            memory: p.memory.clone(),
            cond: p.film.clone() + time,
            self_masks: &self_masks,
            cross_masks: &cross_masks,
            rotary: None,
        };
        for (i, l) in self.attn_layers.iter().enumerate() {
            h = l.forward_with_kv(h, &ctx, p.memory_kv.as_ref().map(|kv| &kv[i])) * mask.clone();
        }
        for l in &self.ssm_layers {
            h = l.forward(h, &ctx) * mask.clone();
        }
        let raw = host_linear::forward(&self.output, h.clone());
        let raw = match &self.root_path {
            Some(r) => r.forward(raw, h.clone()),
            None => raw,
        };
        let out = match &self.footwork {
            Some(fa) => fa.forward(raw),
            None => raw,
        };
        let out = match (&self.velocity, &self.skip_gate) {
            (Some(v), _) => v.apply(out, x_tokens, t),
            (None, Some(g)) => g.apply(out, x_tokens, time_features),
            (None, None) => out,
        };
        let out = match &self.heading_path {
            Some(p) => p.forward(out, h, &self.denorm),
            None => out,
        };
        from_tokens(out * mask)
    }

    /// x̂0 with per-element music dropout (training).
    pub fn forward(&self, x_t: Tensor<3>, t: &[f32], c: &GroupCond, keep: &[bool]) -> Tensor<3> {
        let p = self.prepare(c, keep, false);
        self.forward_prepared(x_t, t, c, &p)
    }
}

/// The sampler's integer timesteps as the `f32`s [`GroupDenoiser::forward_prepared`] takes.
fn host_timesteps(t: Tensor<1, Int>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .expect("timesteps convert to f32")
}

/// The denoiser as the shared sampler sees it, with both branches prepared once per run.
pub struct PreparedGroupDenoiser<'a> {
    pub net: &'a GroupDenoiser,
    pub cond: GroupCond,
    pub full: PreparedCond,
    pub null: Option<PreparedCond>,
    /// Guidance's two branches stacked into one batch of `2B` (conditional first), so a
    /// guided step is one forward pass ([`Denoiser::predict_x0_guided`]).
    pub pair: Option<(GroupCond, PreparedCond)>,
}

/// Largest batch whose guidance branches are stacked into one pass. Stacking pays where the
/// batch is small (LGDS denoises one window at a time: the GEMMs get twice as tall and the
/// weights are read once); the parallel sampler's batch of every window is already tall.
/// Doubling it measured 13.9 s against 13.2 s with two calls (`bench/group.sh`,
/// parallel_5x1800f, medians of 3 rounds on 2 cores: within the run-to-run spread, so this
/// only keeps the two-call path where stacking buys nothing).
pub const STACK_GUIDANCE_MAX_BATCH: usize = 4;

impl<'a> PreparedGroupDenoiser<'a> {
    pub fn new(net: &'a GroupDenoiser, cond: GroupCond, guided: bool) -> Self {
        let b = cond.dancers.len();
        let pair = (guided && b <= STACK_GUIDANCE_MAX_BATCH).then(|| {
            let twice = GroupCond {
                music: Tensor::cat(vec![cond.music.clone(), cond.music.clone()], 0),
                dancers: [cond.dancers.clone(), cond.dancers.clone()].concat(),
                swap: Tensor::cat(vec![cond.swap.clone(), cond.swap.clone()], 0),
                control: Tensor::cat(vec![cond.control.clone(), cond.control.clone()], 0),
            };
            let keep: Vec<bool> = (0..2 * b).map(|i| i < b).collect();
            let prepared = net.prepare(&twice, &keep, true);
            (twice, prepared)
        });
        Self {
            net,
            full: net.prepare(&cond, &vec![true; b], true),
            null: guided.then(|| net.prepare(&cond, &vec![false; b], true)),
            pair,
            cond,
        }
    }
}

impl Denoiser for PreparedGroupDenoiser<'_> {
    type Cond = GroupCond;

    fn predict_x0(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        cond: Conditioning<'_, GroupCond>,
    ) -> Tensor<3> {
        let t = host_timesteps(t);
        let p = match cond {
            Conditioning::Full(_) => &self.full,
            Conditioning::Null => self
                .null
                .as_ref()
                .expect("the null branch was prepared (guided = true)"),
            Conditioning::Dropout { .. } => {
                unreachable!("condition dropout is a training-time mode")
            }
        };
        self.net.forward_prepared(x_t, &t, &self.cond, p)
    }

    fn predict_x0_guided(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        cond: &GroupCond,
    ) -> (Tensor<3>, Tensor<3>) {
        let Some((twice, prepared)) = &self.pair else {
            return separate_guidance_branches(self, x_t, t, cond);
        };
        let b = x_t.dims()[0];
        let t = host_timesteps(t);
        let both = self.net.forward_prepared(
            Tensor::cat(vec![x_t.clone(), x_t], 0),
            &[t.clone(), t].concat(),
            twice,
            prepared,
        );
        (both.clone().narrow(0, 0, b), both.narrow(0, b, b))
    }
}
