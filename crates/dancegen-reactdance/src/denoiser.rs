//! The latent diffusion transformer (paper §"Overall Architecture", stage 2): predicts the
//! clean hierarchical latent x̂0 from a noised one, the leader motion (cross-attention) and
//! the music (FiLM).
//!
//! - Input: `Linear(C → d)` of the noised latent plus the phase-aligned encoding
//!   ([`phase_aligned`], BLC's per-block phase reset).
//! - Leader: the leader's features of the `2^down_t` frames of each token, concatenated,
//!   `Linear → d` + the same phase encoding, then `leader_layers` transformer encoder layers:
//!   the cross-attention memory. The null condition is a learned token.
//! - Music: the EDGE-35 features of each token's frames, concatenated, LayerNorm (MFCCs are
//!   in the hundreds) and `Linear → d`: a FiLM vector **per token**, added to the timestep's.
//!   The null condition is a learned vector.
//! - `n_layers` FiLM decoder layers ([`FilmDecoderLayer`], shared with Lodge++ / EDGE), then
//!   `Linear(d → C)`.
//!
//! - Optional (`leader_film`, ours): the encoded leader token of the same time is also a FiLM
//!   vector, `Linear(d → d)`, added to the music's, so the follower token at time `n` is
//!   modulated by the leader at `n` without having to find it by attention.
//!
//! The leader and the music are dropped together (the paper's null embedding `∅` replaces
//! `(c, M_L)`).

use dancegen_nn::attention::{AttnMasks, ProjectedKv};
use dancegen_nn::burn;
use dancegen_nn::diffusion::{Conditioning, Denoiser};
use dancegen_nn::mask::AttnMask;
use dancegen_nn::pos_encoding::phase_aligned;
use dancegen_nn::timestep::{TimestepMlp, TimestepMlpConfig};
use dancegen_nn::transformer::{
    DecoderContext, EncoderLayer, EncoderLayerConfig, FilmDecoderLayer, FilmDecoderLayerConfig,
};

use burn::module::{Module, Param};
use burn::nn::{LayerNorm, LayerNormConfig, Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::config::{DenoiserConfig, leader_token_dim, music_token_dim};

/// The condition of a batch of blocks.
#[derive(Clone, Debug)]
pub struct DuetCond {
    /// Normalised leader features, each token's frames concatenated: `[B, N, 220·f]`.
    pub leader: Tensor<3>,
    /// EDGE-35 music features, each token's frames concatenated: `[B, N, 35·f]`.
    pub music: Tensor<3>,
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct LatentDenoiser {
    pub input: Linear,
    pub time: TimestepMlp,
    pub time_cond: Linear,
    pub leader_in: Linear,
    pub leader_layers: Vec<EncoderLayer>,
    pub null_leader: Param<Tensor<3>>,
    pub music_norm: LayerNorm,
    pub music_in: Linear,
    pub null_music: Param<Tensor<3>>,
    /// The per-token leader FiLM (`DenoiserConfig::leader_film`); `None` in the paper's design.
    pub leader_film: Option<Linear>,
    pub layers: Vec<FilmDecoderLayer>,
    pub output: Linear,
    #[module(skip)]
    pub d_model: usize,
    #[module(skip)]
    pub block_tokens: usize,
    #[module(skip)]
    pub causal: bool,
}

impl DenoiserConfig {
    /// A fresh network for a `latent_dim`-channel latent of `frames_per_token` frames a token.
    pub fn init(
        &self,
        latent_dim: usize,
        frames_per_token: usize,
        device: &Device,
    ) -> LatentDenoiser {
        let d = self.d_model;
        let music = music_token_dim(frames_per_token);
        LatentDenoiser {
            input: LinearConfig::new(latent_dim, d).init(device),
            time: TimestepMlpConfig::new(d).init(device),
            time_cond: LinearConfig::new(4 * d, d).init(device),
            leader_in: LinearConfig::new(leader_token_dim(frames_per_token), d).init(device),
            leader_layers: (0..self.leader_layers)
                .map(|_| {
                    EncoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .init(device)
                })
                .collect(),
            null_leader: Param::from_tensor(Tensor::zeros([1, 1, d], device)),
            music_norm: LayerNormConfig::new(music).init(device),
            music_in: LinearConfig::new(music, d).init(device),
            null_music: Param::from_tensor(Tensor::zeros([1, 1, d], device)),
            leader_film: self
                .leader_film
                .then(|| LinearConfig::new(d, d).init(device)),
            layers: (0..self.n_layers)
                .map(|_| {
                    FilmDecoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .init(device)
                })
                .collect(),
            output: LinearConfig::new(d, latent_dim).init(device),
            d_model: d,
            block_tokens: self.block_tokens,
            causal: self.causal,
        }
    }
}

/// The step-invariant part of a condition ([`LatentDenoiser::prepare`]).
#[derive(Clone, Debug)]
pub struct PreparedCond {
    /// Cross-attention tokens `[B, N, d]`.
    pub memory: Tensor<3>,
    /// Each decoder layer's key/value projections of `memory` (inference only).
    pub memory_kv: Option<Vec<ProjectedKv>>,
    /// Per-token FiLM vectors `[B, N, d]`: the music's, plus the leader's with `leader_film`
    /// (or the null vector `[B, 1, d]`).
    pub music: Tensor<3>,
}

/// Attention masks of one call: blocks batched (`None`) or a whole sequence whose blocks a
/// block-diagonal mask separates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Every batch element is one block (or a training window): phase from position 0.
    Batched,
    /// One long sequence per batch element; attention restricted to blocks of `block_tokens`
    /// (BLC's block-diagonal periodic mask). Same output as [`Layout::Batched`] on the blocks.
    Sequence,
}

impl LatentDenoiser {
    fn positions(&self, n: usize, device: &Device) -> Tensor<3> {
        phase_aligned(0, n, self.block_tokens, self.d_model, device).unsqueeze::<3>()
    }

    fn masks(&self, n: usize, layout: Layout, device: &Device) -> (AttnMasks, AttnMasks) {
        let self_mask = match (layout, self.causal) {
            (Layout::Batched, false) => None,
            (Layout::Batched, true) => AttnMask::Causal.tensor(n, n, device),
            (Layout::Sequence, false) => AttnMask::BlockDiagonal {
                block: self.block_tokens,
            }
            .tensor(n, n, device),
            (Layout::Sequence, true) => AttnMask::PeriodicBlockCausal {
                block: self.block_tokens,
            }
            .tensor(n, n, device),
        };
        let cross = match layout {
            Layout::Batched => None,
            Layout::Sequence => AttnMask::BlockDiagonal {
                block: self.block_tokens,
            }
            .tensor(n, n, device),
        };
        (
            AttnMasks {
                attn: self_mask,
                key_padding: None,
            },
            AttnMasks {
                attn: cross,
                key_padding: None,
            },
        )
    }

    /// Memory and music FiLM of `c`; `keep[b]`: element `b` sees the condition. `project`:
    /// also each layer's cross-attention K/V (for repeated calls at inference).
    pub fn prepare(
        &self,
        c: &DuetCond,
        keep: &[bool],
        layout: Layout,
        project: bool,
    ) -> PreparedCond {
        let [b, n, _] = c.leader.dims();
        assert_eq!(keep.len(), b, "one keep flag per batch element");
        let device = c.leader.device();
        let d = self.d_model;
        let k: Vec<f32> = keep.iter().map(|&k| f32::from(u8::from(k))).collect();
        let k = Tensor::<1>::from_data(TensorData::new(k, [b]), &device).reshape([b, 1, 1]);
        let mix = |cond: Tensor<3>, null: Tensor<3>| -> Tensor<3> {
            if keep.iter().all(|&k| k) {
                cond
            } else if keep.iter().all(|&k| !k) {
                null
            } else {
                cond * k.clone() + null * (k.clone().neg() + 1.0)
            }
        };
        let null_leader = self.null_leader.val().expand([b, n, d]);
        let memory = if keep.iter().all(|&k| !k) {
            null_leader
        } else {
            let mut h = self.leader_in.forward(c.leader.clone()) + self.positions(n, &device);
            let enc_masks = AttnMasks {
                attn: match layout {
                    Layout::Batched => None,
                    Layout::Sequence => AttnMask::BlockDiagonal {
                        block: self.block_tokens,
                    }
                    .tensor(n, n, &device),
                },
                key_padding: None,
            };
            for l in &self.leader_layers {
                h = l.forward(h, &enc_masks, None);
            }
            mix(h, null_leader)
        };
        let null_music = self.null_music.val().expand([b, n, d]);
        let music = if keep.iter().all(|&k| !k) {
            self.null_music.val().expand([b, 1, d])
        } else {
            let m = self
                .music_in
                .forward(self.music_norm.forward(c.music.clone()));
            mix(m, null_music)
        };
        let music = match &self.leader_film {
            None => music,
            // The null branch: one vector for every token, like the null music.
            Some(film) if keep.iter().all(|&k| !k) => {
                music + film.forward(self.null_leader.val().expand([b, 1, d]))
            }
            Some(film) => music + film.forward(memory.clone()),
        };
        let memory_kv = project.then(|| {
            self.layers
                .iter()
                .map(|l| l.cross_kv(memory.clone()))
                .collect()
        });
        PreparedCond {
            memory,
            memory_kv,
            music,
        }
    }

    /// x̂0 `[B, N, C]` of `x_t` at 0-based timesteps `t`.
    pub fn forward_prepared(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        p: &PreparedCond,
        layout: Layout,
    ) -> Tensor<3> {
        let n = x_t.dims()[1];
        let device = x_t.device();
        let time = self
            .time_cond
            .forward(self.time.forward(t, &device))
            .unsqueeze_dim::<3>(1);
        let (self_masks, cross_masks) = self.masks(n, layout, &device);
        let ctx = DecoderContext {
            memory: p.memory.clone(),
            cond: p.music.clone() + time,
            self_masks: &self_masks,
            cross_masks: &cross_masks,
            rotary: None,
        };
        let mut h = self.input.forward(x_t) + self.positions(n, &device);
        for (i, l) in self.layers.iter().enumerate() {
            h = l.forward_with_kv(h, &ctx, p.memory_kv.as_ref().map(|kv| &kv[i]));
        }
        self.output.forward(h)
    }

    /// x̂0 with per-element condition dropout (training).
    pub fn forward(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        cond: &DuetCond,
        keep: &[bool],
        layout: Layout,
    ) -> Tensor<3> {
        let p = self.prepare(cond, keep, layout, false);
        self.forward_prepared(x_t, t, &p, layout)
    }
}

/// The denoiser as the shared sampler sees it: the conditional and the null branch prepared
/// once per run (the leader encoder, the music FiLM and every layer's cross-attention K/V do
/// not change between steps).
pub struct PreparedDenoiser<'a> {
    pub net: &'a LatentDenoiser,
    pub full: PreparedCond,
    pub null: Option<PreparedCond>,
    pub layout: Layout,
}

impl<'a> PreparedDenoiser<'a> {
    pub fn new(net: &'a LatentDenoiser, c: &DuetCond, guided: bool, layout: Layout) -> Self {
        let b = c.leader.dims()[0];
        Self {
            net,
            full: net.prepare(c, &vec![true; b], layout, true),
            null: guided.then(|| net.prepare(c, &vec![false; b], layout, true)),
            layout,
        }
    }
}

impl Denoiser for PreparedDenoiser<'_> {
    type Cond = DuetCond;

    fn predict_x0(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        cond: Conditioning<'_, DuetCond>,
    ) -> Tensor<3> {
        let t: Vec<f32> = t
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .expect("timesteps");
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
        self.net.forward_prepared(x_t, &t, p, self.layout)
    }
}
