//! Masked-token transformer and its iterative decoding (MoMask; SoulNet's masked transformer,
//! anchors D.6).
//!
//! Network: `[cond token; token embeddings + sinusoidal positions]` through post-norm encoder
//! layers, a linear head over the codebook. Token ids `0..vocab` are codes, `vocab` is the
//! `[MASK]` id. Condition dropout (training) replaces the condition by zeros, which is also the
//! unconditional branch of classifier-free guidance.
//!
//! Decoding ([`MaskedTransformer::sample`]): start fully masked; at step `s` of `S` the number of
//! masked tokens is `max(1, round(cos(π/2 · s/(S − 1)·…) · T))` following MoMask's cosine
//! schedule over `linspace(0, 1, S)`; the least confident tokens are re-masked; logits are
//! guided `uncond + scale · (cond − uncond)`, filtered to the top `ceil((1 − thres)·V)` codes and
//! drawn by Gumbel-max at `temperature`; a token's confidence is its probability without
//! temperature, and unmasked tokens are never re-masked (confidence 1e5).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Embedding, EmbeddingConfig, Linear, LinearConfig};
use burn::tensor::activation::softmax;
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::attention::AttnMasks;
use crate::mlp::Activation;
use crate::pos_encoding::sinusoidal;
use crate::rng::SplitMix64;
use crate::transformer::{EncoderLayer, EncoderLayerConfig};

/// Configuration of [`MaskedTransformer`].
#[derive(Config, Debug)]
pub struct MaskedTransformerConfig {
    /// Codebook size (the `[MASK]` id is `vocab`).
    pub vocab: usize,
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    /// Width of the condition vector (SoulNet: 256-d MMR music feature).
    pub d_cond: usize,
    #[config(default = 0.1)]
    pub dropout: f64,
}

#[derive(Module, Debug)]
pub struct MaskedTransformer {
    pub tok_emb: Embedding,
    pub cond_proj: Linear,
    pub layers: Vec<EncoderLayer>,
    pub head: Linear,
    pub vocab: usize,
}

impl MaskedTransformerConfig {
    pub fn init(&self, device: &Device) -> MaskedTransformer {
        MaskedTransformer {
            tok_emb: EmbeddingConfig::new(self.vocab + 1, self.d_model).init(device),
            cond_proj: LinearConfig::new(self.d_cond, self.d_model).init(device),
            layers: (0..self.n_layers)
                .map(|_| {
                    EncoderLayerConfig::new(self.d_model, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .with_activation(Activation::Gelu)
                        .init(device)
                })
                .collect(),
            head: LinearConfig::new(self.d_model, self.vocab).init(device),
            vocab: self.vocab,
        }
    }
}

/// Decoding settings (SoulNet `eval_option.py` defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct MaskedSampling {
    pub steps: usize,
    pub cond_scale: f64,
    pub temperature: f64,
    /// Keep the top `ceil((1 − topk_filter_thres) · vocab)` codes.
    pub topk_filter_thres: f64,
    pub seed: u64,
}

impl Default for MaskedSampling {
    fn default() -> Self {
        Self {
            steps: 18,
            cond_scale: 4.0,
            temperature: 1.0,
            topk_filter_thres: 0.9,
            seed: 0,
        }
    }
}

impl MaskedTransformer {
    /// The `[MASK]` token id.
    pub fn mask_id(&self) -> i64 {
        self.vocab as i64
    }

    /// Logits `[B, T, vocab]` of `tokens` `[B, T]` under `cond` `[B, d_cond]` (zeros =
    /// unconditional).
    pub fn forward(&self, tokens: Tensor<2, Int>, cond: Tensor<2>) -> Tensor<3> {
        let [b, t] = tokens.dims();
        let device = tokens.device();
        let d = self.head.weight.dims()[0];
        let x = self.tok_emb.forward(tokens) + sinusoidal(0, t, d, &device).unsqueeze::<3>();
        let c = self.cond_proj.forward(cond).reshape([b, 1, d]);
        let mut h = Tensor::cat(vec![c, x], 1);
        for layer in &self.layers {
            h = layer.forward(h, &AttnMasks::default(), None);
        }
        self.head.forward(h.narrow(1, 1, t))
    }

    /// Iterative masked decoding of `len` tokens per condition row.
    pub fn sample(&self, cond: Tensor<2>, len: usize, opts: &MaskedSampling) -> Tensor<2, Int> {
        let [b, _] = cond.dims();
        let device = cond.device();
        let v = self.vocab;
        let mut rng = SplitMix64(opts.seed);
        let mut ids = vec![self.mask_id(); b * len];
        let mut scores = vec![0f64; b * len];
        let uncond = cond.zeros_like();
        let steps = opts.steps.max(1);
        for s in 0..steps {
            let frac = if steps == 1 {
                0.0
            } else {
                s as f64 / (steps - 1) as f64
            };
            let n_mask = ((frac * std::f64::consts::FRAC_PI_2).cos() * len as f64)
                .round()
                .max(1.0) as usize;
            // Re-mask the n_mask least confident positions of each row.
            let mut is_mask = vec![false; b * len];
            for r in 0..b {
                let mut order: Vec<usize> = (0..len).collect();
                order.sort_by(|&x, &y| scores[r * len + x].total_cmp(&scores[r * len + y]));
                for &i in order.iter().take(n_mask) {
                    is_mask[r * len + i] = true;
                    ids[r * len + i] = self.mask_id();
                }
            }
            let tok = Tensor::<2, Int>::from_data(TensorData::new(ids.clone(), [b, len]), &device);
            let c = self.forward(tok.clone(), cond.clone());
            let logits = if opts.cond_scale == 1.0 {
                c
            } else {
                let u = self.forward(tok, uncond.clone());
                u.clone() + (c - u) * opts.cond_scale
            };
            let probs: Vec<f32> = softmax(logits.clone(), 2)
                .into_data()
                .try_into_vec::<f32>()
                .unwrap();
            let raw: Vec<f32> = logits.into_data().try_into_vec::<f32>().unwrap();
            let keep = (((1.0 - opts.topk_filter_thres) * v as f64).ceil() as usize).clamp(1, v);
            for p in 0..b * len {
                if !is_mask[p] {
                    scores[p] = 1e5;
                    continue;
                }
                let row = &raw[p * v..(p + 1) * v];
                let mut order: Vec<usize> = (0..v).collect();
                order.sort_by(|&x, &y| row[y].total_cmp(&row[x]));
                let mut best = (f64::NEG_INFINITY, order[0]);
                for &i in order.iter().take(keep) {
                    let u = rng.next_f64().clamp(1e-20, 1.0 - 1e-12);
                    let gumbel = -(-u.ln()).ln();
                    let val = f64::from(row[i]) / opts.temperature.max(1e-6) + gumbel;
                    if val > best.0 {
                        best = (val, i);
                    }
                }
                ids[p] = best.1 as i64;
                scores[p] = f64::from(probs[p * v + best.1]);
            }
        }
        Tensor::from_data(TensorData::new(ids, [b, len]), &device)
    }
}
