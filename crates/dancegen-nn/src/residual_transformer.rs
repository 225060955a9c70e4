//! MoMask's residual transformer, as SoulNet uses it for the higher levels of its part tokens
//! (holistic.md §1.3): level `j` of every position is predicted from the summed embeddings of
//! that position's levels `< j`, a level embedding, the condition token and (our addition, see
//! [`crate::masked`]) the part embedding and per-time condition.
//!
//! Each input level has its own token embedding and each target level its own head. MoMask
//! ties the two (`output += output + bias`, which doubles the logits: holistic.md §1.3); this
//! one keeps them separate and has no doubling.
//!
//! Sampling ([`ResidualTransformer::sample`]) fills levels `1..Q` one after the other, each in one
//! pass, with classifier-free guidance, top-k filtering and temperature (SoulNet's `gen_m2m`
//! defaults: guidance 5, temperature 0.8).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Embedding, EmbeddingConfig, Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::attention::AttnMasks;
use crate::masked::{gumbel_top_k, part_context};
use crate::mlp::Activation;
use crate::rng::SplitMix64;
use crate::transformer::{EncoderLayer, EncoderLayerConfig};

/// Configuration of [`ResidualTransformer`].
#[derive(Config, Debug)]
pub struct ResidualTransformerConfig {
    pub vocab: usize,
    /// Quantizer levels `Q` (the transformer predicts levels `1..Q`).
    pub levels: usize,
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    pub d_cond: usize,
    #[config(default = 0.1)]
    pub dropout: f64,
    #[config(default = 1)]
    pub parts: usize,
    #[config(default = 0)]
    pub d_frame: usize,
}

#[derive(Module, Debug)]
pub struct ResidualTransformer {
    /// Input embedding of levels `0..Q−1`.
    pub tok_emb: Vec<Embedding>,
    /// Which level is predicted (`Q − 1` entries).
    pub level_emb: Embedding,
    pub cond_proj: Linear,
    pub part_emb: Option<Embedding>,
    pub frame_proj: Option<Linear>,
    pub layers: Vec<EncoderLayer>,
    /// Head of levels `1..Q`.
    pub heads: Vec<Linear>,
    pub vocab: usize,
    pub parts: usize,
}

impl ResidualTransformerConfig {
    pub fn init(&self, device: &Device) -> ResidualTransformer {
        assert!(self.levels >= 2, "a residual transformer needs two levels");
        let n = self.levels - 1;
        ResidualTransformer {
            tok_emb: (0..n)
                .map(|_| EmbeddingConfig::new(self.vocab, self.d_model).init(device))
                .collect(),
            level_emb: EmbeddingConfig::new(n, self.d_model).init(device),
            cond_proj: LinearConfig::new(self.d_cond, self.d_model).init(device),
            part_emb: (self.parts > 1)
                .then(|| EmbeddingConfig::new(self.parts, self.d_model).init(device)),
            frame_proj: (self.d_frame > 0)
                .then(|| LinearConfig::new(self.d_frame, self.d_model).init(device)),
            layers: (0..self.n_layers)
                .map(|_| {
                    EncoderLayerConfig::new(self.d_model, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .with_activation(Activation::Gelu)
                        .init(device)
                })
                .collect(),
            heads: (0..n)
                .map(|_| LinearConfig::new(self.d_model, self.vocab).init(device))
                .collect(),
            vocab: self.vocab,
            parts: self.parts.max(1),
        }
    }
}

/// Residual sampling settings (SoulNet `gen_m2m.py`).
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualSampling {
    pub cond_scale: f64,
    pub temperature: f64,
    pub topk_filter_thres: f64,
    pub seed: u64,
}

impl Default for ResidualSampling {
    fn default() -> Self {
        Self {
            cond_scale: 5.0,
            temperature: 0.8,
            topk_filter_thres: 0.9,
            seed: 0,
        }
    }
}

impl ResidualTransformer {
    /// Quantizer levels `Q`.
    pub fn levels(&self) -> usize {
        self.heads.len() + 1
    }

    /// Logits `[B, L, vocab]` of level `level` (1..Q) from `tokens` `[B, L, ≥ level]` (levels
    /// `< level` are read).
    pub fn forward(
        &self,
        tokens: Tensor<3, Int>,
        level: usize,
        cond: Tensor<2>,
        frame: Option<Tensor<3>>,
    ) -> Tensor<3> {
        let [b, l, _] = tokens.dims();
        assert!(
            (1..self.levels()).contains(&level),
            "level {level} is not predicted by a {}-level residual transformer",
            self.levels()
        );
        let device = tokens.device();
        let d = self.cond_proj.weight.dims()[1];
        let mut x = part_context(
            self.parts,
            self.part_emb.as_ref(),
            self.frame_proj.as_ref(),
            frame,
            [b, l, d],
            &device,
        );
        for q in 0..level {
            let ids = tokens.clone().narrow(2, q, 1).reshape([b, l]);
            x = x + self.tok_emb[q].forward(ids);
        }
        let lid =
            Tensor::<2, Int>::from_data(TensorData::new(vec![(level - 1) as i64], [1, 1]), &device);
        x = x + self.level_emb.forward(lid);
        let c = self.cond_proj.forward(cond).reshape([b, 1, d]);
        let mut h = Tensor::cat(vec![c, x], 1);
        for layer in &self.layers {
            h = layer.forward(h, &AttnMasks::default(), None);
        }
        self.heads[level - 1].forward(h.narrow(1, 1, l))
    }

    /// Levels `1..Q` drawn for the base tokens `base` `[B, L]`; returns `[B, L, Q]`.
    pub fn sample(
        &self,
        base: Tensor<2, Int>,
        cond: Tensor<2>,
        frame: Option<Tensor<3>>,
        opts: &ResidualSampling,
    ) -> Tensor<3, Int> {
        let [b, l] = base.dims();
        let device = base.device();
        let q = self.levels();
        let v = self.vocab;
        let mut rng = SplitMix64(opts.seed);
        let base: Vec<i64> = base
            .into_data()
            .convert::<i64>()
            .try_into_vec::<i64>()
            .expect("int tokens");
        let mut ids = vec![0i64; b * l * q];
        for p in 0..b * l {
            ids[p * q] = base[p];
        }
        let uncond = cond.zeros_like();
        let frame_uncond = frame.as_ref().map(|f| f.zeros_like());
        let keep = (((1.0 - opts.topk_filter_thres) * v as f64).ceil() as usize).clamp(1, v);
        for level in 1..q {
            let tok = Tensor::<3, Int>::from_data(TensorData::new(ids.clone(), [b, l, q]), &device);
            let logits = if opts.cond_scale == 1.0 {
                self.forward(tok, level, cond.clone(), frame.clone())
            } else {
                // Conditional and unconditional rows in one batch: one pass instead of two.
                let both = self.forward(
                    Tensor::cat(vec![tok.clone(), tok], 0),
                    level,
                    Tensor::cat(vec![cond.clone(), uncond.clone()], 0),
                    frame
                        .clone()
                        .zip(frame_uncond.clone())
                        .map(|(f, u)| Tensor::cat(vec![f, u], 0)),
                );
                let c = both.clone().narrow(0, 0, b);
                let u = both.narrow(0, b, b);
                u.clone() + (c - u) * opts.cond_scale
            };
            let raw: Vec<f32> = logits
                .into_data()
                .try_into_vec::<f32>()
                .expect("f32 logits");
            for p in 0..b * l {
                let i = gumbel_top_k(&raw[p * v..(p + 1) * v], keep, opts.temperature, &mut rng);
                ids[p * q + level] = i as i64;
            }
        }
        Tensor::from_data(TensorData::new(ids, [b, l, q]), &device)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device;
    use crate::loss::masked_cross_entropy;
    use burn::optim::{AdamWConfig, GradientsParams};

    /// Level 1 is a fixed function of level 0 (code `(c + 1) mod 4`); after training the
    /// sampler reproduces it, and level 2 (also a function of level 0) as well.
    #[test]
    fn learns_levels_that_follow_the_base_tokens() {
        let dev = device::training();
        dev.seed(9);
        let mut m = ResidualTransformerConfig::new(4, 3, 32, 1, 4, 64, 2)
            .with_dropout(0.0)
            .with_parts(2)
            .init(&dev);
        let (b, l, q) = (8, 6, 3);
        let mut rng = SplitMix64(1);
        let mut batch = || {
            let mut ids = vec![0i64; b * l * q];
            for p in 0..b * l {
                let c = (rng.next_f64() * 4.0) as i64 % 4;
                ids[p * q] = c;
                ids[p * q + 1] = (c + 1) % 4;
                ids[p * q + 2] = (c + 3) % 4;
            }
            ids
        };
        let mut opt = AdamWConfig::new().with_weight_decay(0.0).init();
        let cond = Tensor::<2>::zeros([b, 2], &dev);
        for step in 0..150 {
            let ids = batch();
            let tok = Tensor::<3, Int>::from_data(TensorData::new(ids.clone(), [b, l, q]), &dev);
            let level = 1 + step % 2;
            let target = tok.clone().narrow(2, level, 1).reshape([b, l]);
            let logits = m.forward(tok, level, cond.clone(), None);
            let loss = masked_cross_entropy(logits, target, Tensor::ones([b, l], &dev));
            let g = GradientsParams::from_grads(loss.backward(), &m);
            m = opt.step(3e-3, m, g);
        }
        let ids = batch();
        let base: Vec<i64> = (0..b * l).map(|p| ids[p * q]).collect();
        let base = Tensor::<2, Int>::from_data(TensorData::new(base, [b, l]), &dev);
        let opts = ResidualSampling {
            cond_scale: 1.0,
            temperature: 0.5,
            ..Default::default()
        };
        let out: Vec<i64> = m
            .sample(base, cond, None, &opts)
            .into_data()
            .convert::<i64>()
            .try_into_vec::<i64>()
            .unwrap();
        let right = (0..b * l)
            .filter(|&p| out[p * q + 1] == ids[p * q + 1] && out[p * q + 2] == ids[p * q + 2])
            .count();
        assert!(right * 10 >= b * l * 9, "{right} of {}", b * l);
    }
}
