//! SoulNet's hierarchical residual VQ, body → hands → face: `HiResidualVQ`
//! (`xjli360/SoulDance-Official:models/vq/residual_hvq.py`, anchors D.6).
//!
//! The input `[B, T, 3d]` is the three part latents `[body | hands | face]` along channels.
//! Three stacks of `num_quantizers` [`EmaVq`] layers; at each residual level `i`:
//!
//! - `q_b = VQ_b,i(r_b)`, `r_b −= sg(q_b)`;
//! - `q_h = VQ_h,i(conv1d_k3([L(q_b); r_h]))`, `r_h −= sg(q_h)`;
//! - `q_f = VQ_f,i(conv1d_k3([L(q_h); r_f]))`, `r_f −= sg(q_f)`;
//!
//! with **one** `Linear(d, d)` `L` (`transformation.linear`) and **one**
//! `Conv1d(2d, d, 3, pad 1)` (`conv1d`) shared by both links. The reference's
//! `TransformationLayer` applies the Linear per frame and then `reshape`s the `[B·T, d]` result
//! to `[B, d, T]` **without** a transpose; this port reproduces that reinterpretation exactly so
//! SoulNet checkpoints behave the same. Outputs: `[Σq_b | Σq_h | Σq_f]` `[B, T, 3d]`; indices
//! `[B, 3T, Q]` (per level the three parts' `[B, T]` indices concatenated along time, as the
//! reference's `torch.cat(..., dim=-1)`); commitment and perplexity = the three parts' sum,
//! averaged over levels that ran. Quantize-dropout as [`super::rvq`].

use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::{Conv1d, Conv1dConfig};
use burn::nn::{Linear, LinearConfig, PaddingConfig1d};
use burn::tensor::{Device, Int, Tensor};

use super::rvq::dropout_last_kept;
use super::vq::{EmaVq, EmaVqConfig};
use super::{QuantOutput, is_training};

/// Configuration of [`HierarchicalRvq`].
#[derive(Config, Debug)]
pub struct HierarchicalRvqConfig {
    /// Every layer's quantizer (`code_dim` = `d`, one part's width).
    pub vq: EmaVqConfig,
    #[config(default = 6)]
    pub num_quantizers: usize,
    #[config(default = 0.2)]
    pub quantize_dropout_prob: f64,
    #[config(default = 0)]
    pub quantize_dropout_cutoff_index: usize,
}

/// SoulNet `TransformationLayer`.
#[derive(Module, Debug)]
pub struct Transformation {
    pub linear: Linear,
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct HierarchicalRvq {
    pub layers_body: Vec<EmaVq>,
    pub layers_hands: Vec<EmaVq>,
    pub layers_face: Vec<EmaVq>,
    pub transformation: Transformation,
    pub conv1d: Conv1d,
    #[module(skip)]
    pub quantize_dropout_prob: f64,
    #[module(skip)]
    pub quantize_dropout_cutoff_index: usize,
}

impl HierarchicalRvqConfig {
    pub fn init(&self, device: &Device) -> HierarchicalRvq {
        let d = self.vq.code_dim;
        let stack = || {
            (0..self.num_quantizers)
                .map(|_| self.vq.init(device))
                .collect()
        };
        HierarchicalRvq {
            layers_body: stack(),
            layers_hands: stack(),
            layers_face: stack(),
            transformation: Transformation {
                linear: LinearConfig::new(d, d).init(device),
            },
            conv1d: Conv1dConfig::new(2 * d, d, 3)
                .with_padding(PaddingConfig1d::Explicit(1, 1))
                .init(device),
            quantize_dropout_prob: self.quantize_dropout_prob,
            quantize_dropout_cutoff_index: self.quantize_dropout_cutoff_index,
        }
    }
}

impl HierarchicalRvq {
    /// `conv1d([L(q_prev); residual])` on `[B, T, d]` tensors, with the reference's reshape.
    pub fn link(&self, q_prev: Tensor<3>, residual: Tensor<3>) -> Tensor<3> {
        let [b, t, d] = q_prev.dims();
        let lin = self
            .transformation
            .linear
            .forward(q_prev)
            .reshape([b, d, t]);
        let cat = Tensor::cat(vec![lin, residual.swap_dims(1, 2)], 1);
        self.conv1d.forward(cat).swap_dims(1, 2)
    }

    /// `[B, T, 3d]` → [`QuantOutput`] (`quantized` `[B, T, 3d]`, indices `[B, 3T, Q]`).
    pub fn forward(&self, x: Tensor<3>) -> QuantOutput {
        self.forward_keep(x.clone(), None)
    }

    /// As [`forward`](Self::forward) with the number of levels forced to `keep` when given.
    pub fn forward_keep(&self, x: Tensor<3>, keep: Option<usize>) -> QuantOutput {
        let [b, t, d3] = x.dims();
        let d = d3 / 3;
        let device = x.device();
        let q = self.layers_body.len();
        let last = match keep {
            Some(k) => k.clamp(1, q) - 1,
            None => dropout_last_kept(
                is_training(&x),
                self.quantize_dropout_prob,
                self.quantize_dropout_cutoff_index,
                q,
                &device,
            ),
        };
        let mut r_b = x.clone().narrow(2, 0, d);
        let mut r_h = x.clone().narrow(2, d, d);
        let mut r_f = x.clone().narrow(2, 2 * d, d);
        let (mut o_b, mut o_h, mut o_f) = (r_b.zeros_like(), r_h.zeros_like(), r_f.zeros_like());
        let mut indices = Vec::with_capacity(q);
        let mut losses = Vec::new();
        let mut perps = Vec::new();
        let mut levels = Vec::new();
        for i in 0..q {
            if i > last {
                indices.push(Tensor::<3, Int>::full([b, 3 * t, 1], -1, &device));
                continue;
            }
            let qb = self.layers_body[i].forward(r_b.clone());
            r_b = r_b - qb.quantized.clone().detach();
            o_b = o_b + qb.quantized.clone();
            let qh = self.layers_hands[i].forward(self.link(qb.quantized.clone(), r_h.clone()));
            r_h = r_h - qh.quantized.clone().detach();
            o_h = o_h + qh.quantized.clone();
            let qf = self.layers_face[i].forward(self.link(qh.quantized.clone(), r_f.clone()));
            r_f = r_f - qf.quantized.clone().detach();
            o_f = o_f + qf.quantized.clone();
            indices.push(Tensor::cat(vec![qb.indices, qh.indices, qf.indices], 1));
            losses.push(qb.commit_loss + qh.commit_loss + qf.commit_loss);
            if let (Some(a), Some(bb), Some(c)) = (qb.perplexity, qh.perplexity, qf.perplexity) {
                perps.push(a + bb + c);
            }
            levels.push(Tensor::cat(
                vec![qb.quantized, qh.quantized, qf.quantized],
                2,
            ));
        }
        let n = losses.len() as f64;
        let np = perps.len() as f64;
        QuantOutput {
            quantized: Tensor::cat(vec![o_b, o_h, o_f], 2),
            indices: Tensor::cat(indices, 2),
            commit_loss: losses.into_iter().reduce(|a, b| a + b).unwrap() / n,
            perplexity: perps.into_iter().reduce(|a, b| a + b).map(|p| p / np),
            levels,
        }
    }

    /// Indices `[B, 3T, Q']` → `[Σ body | Σ hands | Σ face]` codes `[B, T, 3d]` (the
    /// reference's `get_codebook_entry`).
    pub fn decode_indices(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let [_, t3, qn] = indices.dims();
        let t = t3 / 3;
        let part = |stack: &[EmaVq], p: usize| {
            let ind = indices.clone().narrow(1, p * t, t);
            (0..qn.min(stack.len()))
                .map(|i| stack[i].decode_indices(ind.clone().narrow(2, i, 1)))
                .reduce(|a, b| a + b)
                .expect("at least one level")
        };
        Tensor::cat(
            vec![
                part(&self.layers_body, 0),
                part(&self.layers_hands, 1),
                part(&self.layers_face, 2),
            ],
            2,
        )
    }
}
