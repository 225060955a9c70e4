//! GPT over codebook tokens with a conditioning prefix (Lodge++'s choreography network, T2M-GPT),
//! with greedy / top-k / temperature sampling through a KV cache.
//!
//! The sequence is `[prefix (Tc tokens of width d_model); token embeddings]`, learned
//! positions, `n_layers` GPT-2 blocks (pre-norm causal self-attention + GELU MLP, residuals),
//! final LayerNorm and a linear head. The logits at sequence position `Tc − 1 + i` predict token
//! `i`, so [`Gpt::forward`] returns `[B, T, vocab]` aligned with the tokens it is given. The
//! system that uses the GPT builds the prefix (music encoder, genre token).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Embedding, EmbeddingConfig, LayerNorm, LayerNormConfig, Linear, LinearConfig};
use burn::tensor::activation::softmax;
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::attention::{AttnMasks, MultiHeadAttention, MultiHeadAttentionConfig};
use crate::mask::AttnMask;
use crate::mlp::{Mlp, MlpConfig};
use crate::pos_encoding::{LearnedPositions, LearnedPositionsConfig};
use crate::rng::SplitMix64;
use crate::transformer::LAYER_NORM_EPS;

/// Configuration of [`Gpt`].
#[derive(Config, Debug)]
pub struct GptConfig {
    pub vocab: usize,
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    /// Longest prefix + token sequence (the position table's size).
    pub max_len: usize,
    #[config(default = 4)]
    pub ff_mult: usize,
    #[config(default = 0.0)]
    pub dropout: f64,
}

/// One GPT-2 block: `x += attn(ln1(x))`, `x += mlp(ln2(x))`.
#[derive(Module, Debug)]
pub struct GptBlock {
    pub ln1: LayerNorm,
    pub attn: MultiHeadAttention,
    pub ln2: LayerNorm,
    pub mlp: Mlp,
}

/// Causal transformer over tokens.
#[derive(Module, Debug)]
pub struct Gpt {
    pub tok_emb: Embedding,
    pub pos_emb: LearnedPositions,
    pub blocks: Vec<GptBlock>,
    pub ln_f: LayerNorm,
    pub head: Linear,
}

impl GptConfig {
    pub fn init(&self, device: &Device) -> Gpt {
        let d = self.d_model;
        let ln = || {
            LayerNormConfig::new(d)
                .with_epsilon(LAYER_NORM_EPS)
                .init(device)
        };
        Gpt {
            tok_emb: EmbeddingConfig::new(self.vocab, d).init(device),
            pos_emb: LearnedPositionsConfig::new(self.max_len, d).init(device),
            blocks: (0..self.n_layers)
                .map(|_| GptBlock {
                    ln1: ln(),
                    attn: MultiHeadAttentionConfig::new(d, self.n_heads)
                        .with_dropout(self.dropout)
                        .init(device),
                    ln2: ln(),
                    mlp: MlpConfig::new(d, self.ff_mult * d, d)
                        .with_dropout(self.dropout)
                        .init(device),
                })
                .collect(),
            ln_f: ln(),
            head: LinearConfig::new(d, self.vocab).init(device),
        }
    }
}

/// Per-layer keys and values `[B, H, T, dh]` of the positions seen so far.
#[derive(Debug, Default)]
pub struct KvCache {
    layers: Vec<(Tensor<4>, Tensor<4>)>,
    len: usize,
}

impl KvCache {
    /// Positions cached.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// How to pick the next token.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplingOptions {
    /// Argmax (Lodge++ decodes greedily, top-1).
    pub greedy: bool,
    pub temperature: f64,
    /// Keep only the `k` most likely tokens (`None` = all).
    pub top_k: Option<usize>,
    pub seed: u64,
}

impl Default for SamplingOptions {
    fn default() -> Self {
        Self {
            greedy: true,
            temperature: 1.0,
            top_k: None,
            seed: 0,
        }
    }
}

impl Gpt {
    /// Hidden states of `x` `[B, T, d]` at positions `start ..`, extending `cache` if given.
    fn run(&self, x: Tensor<3>, start: usize, mut cache: Option<&mut KvCache>) -> Tensor<3> {
        let [_, t, _] = x.dims();
        let mut h = x + self.pos_emb.forward(start, t);
        let device = h.device();
        let keys = start + t;
        let masks = AttnMasks {
            attn: AttnMask::Causal.tensor(t, keys, &device),
            key_padding: None,
        };
        for (i, block) in self.blocks.iter().enumerate() {
            let a = block.ln1.forward(h.clone());
            let q = block.attn.split_heads(block.attn.q_proj.forward(a.clone()));
            let mut k = block.attn.split_heads(block.attn.k_proj.forward(a.clone()));
            let mut v = block.attn.split_heads(block.attn.v_proj.forward(a));
            if let Some(c) = cache.as_deref_mut() {
                if let Some((pk, pv)) = c.layers.get(i) {
                    k = Tensor::cat(vec![pk.clone(), k], 2);
                    v = Tensor::cat(vec![pv.clone(), v], 2);
                }
                if i < c.layers.len() {
                    c.layers[i] = (k.clone(), v.clone());
                } else {
                    c.layers.push((k.clone(), v.clone()));
                }
            }
            h = h.clone() + block.attn.attend(q, k, v, &masks);
            h = h.clone() + block.mlp.forward(block.ln2.forward(h));
        }
        if let Some(c) = cache {
            c.len = keys;
        }
        self.ln_f.forward(h)
    }

    /// Logits `[B, T, vocab]` for `tokens` `[B, T]` after `prefix` `[B, Tc, d]` (`Tc ≥ 1`):
    /// entry `i` is the distribution of token `i` given the prefix and tokens `< i`.
    pub fn forward(&self, prefix: Tensor<3>, tokens: Tensor<2, Int>) -> Tensor<3> {
        let [_, tc, _] = prefix.dims();
        assert!(tc >= 1, "the GPT needs a prefix of at least one token");
        let t = tokens.dims()[1];
        let x = Tensor::cat(vec![prefix, self.tok_emb.forward(tokens)], 1);
        let h = self.run(x, 0, None);
        self.head.forward(h.narrow(1, tc - 1, t))
    }

    /// Logits `[B, T, vocab]` at every position of an input the caller embedded itself
    /// `[B, T, d]` (e.g. token embedding + per-step music, as Bailando / Lodge++ condition their
    /// GPTs): entry `i` predicts what follows position `i`.
    pub fn forward_embeddings(&self, x: Tensor<3>) -> Tensor<3> {
        self.head.forward(self.run(x, 0, None))
    }

    /// Samples `n` tokens `[B, n]` after `prefix`, one position per step through a KV cache.
    pub fn generate(&self, prefix: Tensor<3>, n: usize, opts: &SamplingOptions) -> Tensor<2, Int> {
        let [b, tc, _] = prefix.dims();
        let device = prefix.device();
        let mut cache = KvCache::default();
        let mut rng = SplitMix64(opts.seed);
        let mut out: Vec<Vec<i64>> = vec![Vec::with_capacity(n); b];
        let mut h = self.run(prefix, 0, Some(&mut cache)).narrow(1, tc - 1, 1);
        for step in 0..n {
            let logits = self
                .head
                .forward(h)
                .reshape([b, self.head.weight.dims()[1]]);
            let next = pick(logits, opts, &mut rng);
            for (row, &tok) in out.iter_mut().zip(&next) {
                row.push(tok);
            }
            if step + 1 == n {
                break;
            }
            let tok = Tensor::<2, Int>::from_data(TensorData::new(next, [b, 1]), &device);
            h = self.run(self.tok_emb.forward(tok), cache.len(), Some(&mut cache));
        }
        let flat: Vec<i64> = out.into_iter().flatten().collect();
        Tensor::from_data(TensorData::new(flat, [b, n]), &device)
    }

    /// Logits `[B, vocab]` of the next token after feeding `x` `[B, T, d]` (embeddings or a
    /// prefix) at the cache's next positions: the building block of custom decoding loops.
    pub fn step(&self, x: Tensor<3>, cache: &mut KvCache) -> Tensor<2> {
        let [b, t, _] = x.dims();
        let h = self.run(x, cache.len(), Some(cache)).narrow(1, t - 1, 1);
        self.head
            .forward(h)
            .reshape([b, self.head.weight.dims()[1]])
    }
}

/// The next token per row of `logits` `[B, V]` (greedy, or top-k / temperature sampling from
/// `rng`): the picking rule of [`Gpt::generate`], for systems with their own decoding loop.
pub fn pick(logits: Tensor<2>, opts: &SamplingOptions, rng: &mut SplitMix64) -> Vec<i64> {
    let [b, v] = logits.dims();
    if opts.greedy {
        let idx: Vec<i64> = logits
            .argmax(1)
            .into_data()
            .convert::<i64>()
            .try_into_vec::<i64>()
            .unwrap();
        return idx;
    }
    let probs: Vec<f32> = softmax(logits / opts.temperature.max(1e-6), 1)
        .into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .unwrap();
    (0..b)
        .map(|r| {
            let row = &probs[r * v..(r + 1) * v];
            let mut order: Vec<usize> = (0..v).collect();
            order.sort_by(|&a, &c| row[c].total_cmp(&row[a]));
            order.truncate(opts.top_k.unwrap_or(v).clamp(1, v));
            let total: f64 = order.iter().map(|&i| f64::from(row[i])).sum();
            let mut u = rng.next_f64() * total;
            for &i in &order {
                u -= f64::from(row[i]);
                if u <= 0.0 {
                    return i as i64;
                }
            }
            *order.last().unwrap() as i64
        })
        .collect()
}
