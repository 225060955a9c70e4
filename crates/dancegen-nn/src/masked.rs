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
//!
//! Two extensions for SoulNet's part tokens (issue 19), both off by default so the plain model
//! stays MoMask's (and its PyTorch parity):
//! - `parts > 1`: the sequence is `parts` blocks of `T` tokens (`[body | hands | face]`, the
//!   HRVQ layout). Positions are then the time index inside a block, and a learned part
//!   embedding tells the blocks apart. SoulNet's code uses positions over the whole
//!   concatenation and no part embedding, which leaves "same time, other part" to be learned
//!   from the position alone; ours ties the three parts of one moment together explicitly.
//! - `d_frame > 0`: a per-time-step condition `[B, T, d_frame]` (music features of the frames
//!   under each token) is projected and added to every part's token at that time. SoulNet
//!   conditions on one music embedding per 5-s clip only, which cannot follow the beat
//!   (holistic.md §1.3); the clip embedding stays as the prefix token.
//!
//! Inpainting ([`MaskedTransformer::sample_with`]): positions given in `known` keep their token
//! from the start and are never re-masked; the schedule counts the free positions only. The
//! long-form sampler joins windows this way.

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
    /// Blocks of tokens in one sequence (see the module documentation; 1 = MoMask).
    #[config(default = 1)]
    pub parts: usize,
    /// Width of the per-time-step condition (0 = none).
    #[config(default = 0)]
    pub d_frame: usize,
}

#[derive(Module, Debug)]
pub struct MaskedTransformer {
    pub tok_emb: Embedding,
    pub cond_proj: Linear,
    pub layers: Vec<EncoderLayer>,
    pub head: Linear,
    pub vocab: usize,
    /// Present when `parts > 1`.
    pub part_emb: Option<Embedding>,
    /// Present when `d_frame > 0`.
    pub frame_proj: Option<Linear>,
    pub parts: usize,
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
            part_emb: (self.parts > 1)
                .then(|| EmbeddingConfig::new(self.parts, self.d_model).init(device)),
            frame_proj: (self.d_frame > 0)
                .then(|| LinearConfig::new(self.d_frame, self.d_model).init(device)),
            parts: self.parts.max(1),
        }
    }
}

/// What the tokens of a part-structured sequence add besides their embedding: positions (time
/// inside a block), the part embedding and the per-time condition, `[B, parts·T, d]`.
pub fn part_context(
    parts: usize,
    part_emb: Option<&Embedding>,
    frame_proj: Option<&Linear>,
    frame: Option<Tensor<3>>,
    [batch, len, d]: [usize; 3],
    device: &Device,
) -> Tensor<3> {
    let t = len / parts;
    let pos = sinusoidal(0, t, d, device);
    let mut ctx = Tensor::cat(vec![pos; parts], 0)
        .unsqueeze::<3>()
        .repeat_dim(0, batch);
    if let Some(e) = part_emb {
        let ids: Vec<i64> = (0..parts as i64)
            .flat_map(|p| std::iter::repeat_n(p, t))
            .collect();
        let ids = Tensor::<2, Int>::from_data(TensorData::new(ids, [1, len]), device);
        ctx = ctx + e.forward(ids);
    }
    if let (Some(proj), Some(f)) = (frame_proj, frame) {
        let f = proj.forward(f);
        ctx = ctx + Tensor::cat(vec![f; parts], 1);
    }
    ctx
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
        self.forward_with(tokens, cond, None)
    }

    /// [`Self::forward`] with the per-time condition `frame` `[B, T / parts, d_frame]` (zeros =
    /// unconditional; ignored by a model built without `d_frame`).
    pub fn forward_with(
        &self,
        tokens: Tensor<2, Int>,
        cond: Tensor<2>,
        frame: Option<Tensor<3>>,
    ) -> Tensor<3> {
        let [b, t] = tokens.dims();
        let device = tokens.device();
        let d = self.head.weight.dims()[0];
        let x = if self.parts > 1 || self.frame_proj.is_some() {
            self.tok_emb.forward(tokens)
                + part_context(
                    self.parts,
                    self.part_emb.as_ref(),
                    self.frame_proj.as_ref(),
                    frame,
                    [b, t, d],
                    &device,
                )
        } else {
            self.tok_emb.forward(tokens) + sinusoidal(0, t, d, &device).unsqueeze::<3>()
        };
        let c = self.cond_proj.forward(cond).reshape([b, 1, d]);
        let mut h = Tensor::cat(vec![c, x], 1);
        for layer in &self.layers {
            h = layer.forward(h, &AttnMasks::default(), None);
        }
        self.head.forward(h.narrow(1, 1, t))
    }

    /// Iterative masked decoding of `len` tokens per condition row.
    pub fn sample(&self, cond: Tensor<2>, len: usize, opts: &MaskedSampling) -> Tensor<2, Int> {
        self.sample_with(cond, None, len, None, opts)
    }

    /// Iterative masked decoding with a per-time condition and inpainting: `known` `[B·len]`
    /// holds a code where the token is given and a negative value where it is to be drawn.
    pub fn sample_with(
        &self,
        cond: Tensor<2>,
        frame: Option<Tensor<3>>,
        len: usize,
        known: Option<&[i64]>,
        opts: &MaskedSampling,
    ) -> Tensor<2, Int> {
        let [b, _] = cond.dims();
        let device = cond.device();
        let v = self.vocab;
        let mut rng = SplitMix64(opts.seed);
        let mut ids = vec![self.mask_id(); b * len];
        let mut scores = vec![0f64; b * len];
        let mut free = vec![len; b];
        if let Some(k) = known {
            assert_eq!(k.len(), b * len, "known tokens: one per position");
            for (p, &code) in k.iter().enumerate() {
                if code >= 0 {
                    ids[p] = code.min(v as i64 - 1);
                    scores[p] = f64::INFINITY;
                    free[p / len] -= 1;
                }
            }
        }
        let uncond = cond.zeros_like();
        let frame_uncond = frame.as_ref().map(|f| f.zeros_like());
        let steps = opts.steps.max(1);
        for s in 0..steps {
            let frac = if steps == 1 {
                0.0
            } else {
                s as f64 / (steps - 1) as f64
            };
            // Re-mask the least confident free positions of each row.
            let mut is_mask = vec![false; b * len];
            for r in 0..b {
                if free[r] == 0 {
                    continue;
                }
                let n_mask = ((frac * std::f64::consts::FRAC_PI_2).cos() * free[r] as f64)
                    .round()
                    .max(1.0) as usize;
                let mut order: Vec<usize> = (0..len).collect();
                order.sort_by(|&x, &y| scores[r * len + x].total_cmp(&scores[r * len + y]));
                for &i in order.iter().take(n_mask.min(free[r])) {
                    is_mask[r * len + i] = true;
                    ids[r * len + i] = self.mask_id();
                }
            }
            if !is_mask.iter().any(|&m| m) {
                break;
            }
            let tok = Tensor::<2, Int>::from_data(TensorData::new(ids.clone(), [b, len]), &device);
            let logits = if opts.cond_scale == 1.0 {
                self.forward_with(tok, cond.clone(), frame.clone())
            } else {
                // Conditional and unconditional rows in one batch: one pass instead of two.
                let both = self.forward_with(
                    Tensor::cat(vec![tok.clone(), tok], 0),
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
            let probs: Vec<f32> = softmax(logits.clone(), 2)
                .into_data()
                .try_into_vec::<f32>()
                .expect("f32 logits");
            let raw: Vec<f32> = logits
                .into_data()
                .try_into_vec::<f32>()
                .expect("f32 logits");
            let keep = (((1.0 - opts.topk_filter_thres) * v as f64).ceil() as usize).clamp(1, v);
            for p in 0..b * len {
                if !is_mask[p] {
                    if scores[p].is_finite() {
                        scores[p] = 1e5;
                    }
                    continue;
                }
                let row = &raw[p * v..(p + 1) * v];
                let i = gumbel_top_k(row, keep, opts.temperature, &mut rng);
                ids[p] = i as i64;
                scores[p] = f64::from(probs[p * v + i]);
            }
        }
        Tensor::from_data(TensorData::new(ids, [b, len]), &device)
    }
}

/// A code drawn from the `keep` largest `logits` by Gumbel-max at `temperature`.
pub fn gumbel_top_k(logits: &[f32], keep: usize, temperature: f64, rng: &mut SplitMix64) -> usize {
    let mut order: Vec<usize> = (0..logits.len()).collect();
    order.sort_by(|&x, &y| logits[y].total_cmp(&logits[x]));
    let mut best = (f64::NEG_INFINITY, order[0]);
    for &i in order.iter().take(keep.max(1)) {
        let u = rng.next_f64().clamp(1e-20, 1.0 - 1e-12);
        let gumbel = -(-u.ln()).ln();
        let val = f64::from(logits[i]) / temperature.max(1e-6) + gumbel;
        if val > best.0 {
            best = (val, i);
        }
    }
    best.1
}

/// SoulNet's share of the masked tokens replaced by a random code (holistic.md §1.3).
pub const RANDOM_TOKEN_SHARE: f64 = 0.1;
/// SoulNet's share of the remaining masked tokens replaced by `[MASK]`; the rest keep their
/// code (holistic.md §1.3; MoMask uses 0.88).
pub const MASK_TOKEN_SHARE: f64 = 0.7;

/// A training input made from ground-truth codes (MoMask's corruption): per row a ratio
/// `cos(π/2 · u)`, `u ~ U(0, 1)`, of the positions is chosen (at least one); of those
/// [`RANDOM_TOKEN_SHARE`] become a random code, [`MASK_TOKEN_SHARE`] of the rest `[MASK]`, the
/// others keep their code. `weight` is 1 at every chosen position (the loss is taken there).
#[derive(Clone, Debug, PartialEq)]
pub struct Corrupted {
    pub input: Vec<i64>,
    pub weight: Vec<f32>,
}

/// See [`Corrupted`]; `ids` is `[rows · len]`.
pub fn corrupt(ids: &[i64], len: usize, vocab: usize, rng: &mut SplitMix64) -> Corrupted {
    let mut input = ids.to_vec();
    let mut weight = vec![0f32; ids.len()];
    for r in 0..ids.len() / len.max(1) {
        let ratio = (rng.next_f64() * std::f64::consts::FRAC_PI_2).cos();
        let n = ((ratio * len as f64).ceil() as usize).clamp(1, len);
        // Partial Fisher-Yates: the first n of a random order.
        let mut order: Vec<usize> = (0..len).collect();
        for i in 0..n {
            let j = i + (rng.next_f64() * (len - i) as f64) as usize % (len - i);
            order.swap(i, j);
        }
        for &i in &order[..n] {
            let p = r * len + i;
            weight[p] = 1.0;
            let u = rng.next_f64();
            if u < RANDOM_TOKEN_SHARE {
                input[p] = ((rng.next_f64() * vocab as f64) as i64).min(vocab as i64 - 1);
            } else if rng.next_f64() < MASK_TOKEN_SHARE {
                input[p] = vocab as i64;
            }
        }
    }
    Corrupted { input, weight }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device;
    use burn::tensor::Distribution;

    #[test]
    fn corruption_masks_a_cosine_share_and_weights_only_those() {
        let mut rng = SplitMix64(4);
        let ids: Vec<i64> = (0..64 * 200).map(|i| (i % 7) as i64).collect();
        let c = corrupt(&ids, 64, 7, &mut rng);
        let chosen: f32 = c.weight.iter().sum();
        // E[cos(π/2 u)] = 2/π of the positions.
        let share = f64::from(chosen) / ids.len() as f64;
        assert!((share - 2.0 / std::f64::consts::PI).abs() < 0.05, "{share}");
        for ((w, got), want) in c.weight.iter().zip(&c.input).zip(&ids) {
            if *w == 0.0 {
                assert_eq!(got, want);
            }
        }
        let masked = c.input.iter().filter(|&&i| i == 7).count() as f64;
        // 0.9 · 0.7 of the chosen ones become [MASK].
        assert!((masked / f64::from(chosen) - 0.63).abs() < 0.05, "{masked}");
    }

    #[test]
    fn part_tokens_see_their_time_step_condition_and_inpainting_keeps_known_tokens() {
        let dev = device::inference();
        dev.seed(5);
        let m = MaskedTransformerConfig::new(6, 16, 1, 4, 32, 3)
            .with_dropout(0.0)
            .with_parts(3)
            .with_d_frame(2)
            .init(&dev);
        let tokens = Tensor::<2, Int>::from_data(TensorData::new(vec![6i64; 12], [1, 12]), &dev);
        let cond = Tensor::<2>::zeros([1, 3], &dev);
        let f0 = Tensor::<3>::zeros([1, 4, 2], &dev);
        let mut f1 = vec![0f32; 8];
        f1[2 * 2] = 3.0; // time step 2 only
        let f1 = Tensor::<3>::from_data(TensorData::new(f1, [1, 4, 2]), &dev);
        let a = m.forward_with(tokens.clone(), cond.clone(), Some(f0));
        let b = m.forward_with(tokens, cond.clone(), Some(f1));
        let diff: Vec<f32> = (a - b)
            .abs()
            .sum_dim(2)
            .into_data()
            .try_into_vec::<f32>()
            .unwrap();
        // Time step 2 of every part (positions 2, 6, 10) changes; attention spreads it, so
        // those positions change the most.
        for p in [2, 6, 10] {
            assert!(diff[p] > 0.0, "{diff:?}");
        }
        let known: Vec<i64> = (0..12).map(|i| if i % 4 == 0 { 1 } else { -1 }).collect();
        let frame = Tensor::<3>::random([1, 4, 2], Distribution::Normal(0.0, 1.0), &dev);
        let ids: Vec<i64> = m
            .sample_with(
                cond,
                Some(frame),
                12,
                Some(&known),
                &MaskedSampling::default(),
            )
            .into_data()
            .convert::<i64>()
            .try_into_vec::<i64>()
            .unwrap();
        for i in 0..12 {
            if i % 4 == 0 {
                assert_eq!(ids[i], 1);
            }
            assert!((0..6).contains(&ids[i]), "{ids:?}");
        }
    }
}
