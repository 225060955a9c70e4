//! The Global Choreography Network's sequence model (paper §3.3.2, D.3): a GPT over VQ-VAE
//! dance tokens, conditioned on the music and the genre.
//!
//! The input at token position `i` is the sum of three vectors: the embedding of the previous
//! token (a BOS token at `i = 0`), the music of the token's 4 frames (Linear 35 → `music_d`, a
//! small transformer encoder over the frames, the 4 frames' vectors concatenated and
//! projected), and the genre embedding. The logits at position `i` predict token `i`, so one
//! window trains with teacher forcing and generation feeds its own picks back. Lodge++ attends
//! to a genre style token in every block; adding the genre embedding at every position is our
//! simpler equivalent.
//!
//! Long songs: windows of `window_tokens`, each seeded with the last `overlap_tokens` of the
//! previous one (D.3: 128 tokens, 4 overlap).

use dancegen_nn::attention::AttnMasks;
use dancegen_nn::burn;
use dancegen_nn::gpt::{Gpt, GptConfig, KvCache, SamplingOptions, pick};
use dancegen_nn::pos_encoding::sinusoidal;
use dancegen_nn::progress::{self, Cancelled, StepHook};
use dancegen_nn::rng::SplitMix64;
use dancegen_nn::transformer::{EncoderLayer, EncoderLayerConfig};

use burn::module::Module;
use burn::nn::{Embedding, EmbeddingConfig, Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

/// The part name of the GPT's token generation in progress reports.
pub const CHOREOGRAPHY: &str = "choreography";

use crate::config::{ChoreoGptConfig, TOKEN_FRAMES};

/// Per-frame music features (EDGE 35).
pub const MUSIC_DIMS: usize = dancegen_music::features::EDGE35_DIM;

/// Music frames → one vector per token.
#[derive(Module, Debug)]
pub struct MusicTokenEncoder {
    pub input: Linear,
    pub layers: Vec<EncoderLayer>,
    pub to_token: Linear,
}

impl MusicTokenEncoder {
    /// `[B, 4·T', 35]` → `[B, T', d]`.
    pub fn forward(&self, music: Tensor<3>) -> Tensor<3> {
        let [b, f, _] = music.dims();
        assert!(
            f.is_multiple_of(TOKEN_FRAMES),
            "music frames {f} not a multiple of {TOKEN_FRAMES}"
        );
        let h = self.input.forward(music);
        let d = h.dims()[2];
        let pos = sinusoidal(0, f, d, &h.device()).unsqueeze::<3>();
        let mut h = h + pos;
        let masks = AttnMasks::default();
        for l in &self.layers {
            h = l.forward(h, &masks, None);
        }
        self.to_token
            .forward(h.reshape([b, f / TOKEN_FRAMES, TOKEN_FRAMES * d]))
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct ChoreoGpt {
    pub music: MusicTokenEncoder,
    pub genre: Embedding,
    pub gpt: Gpt,
    /// Codebook size; token `codes` is BOS.
    pub codes: usize,
}

impl ChoreoGptConfig {
    pub fn init(&self, codes: usize, genres: usize, device: &Device) -> ChoreoGpt {
        let d = self.d_model;
        ChoreoGpt {
            music: MusicTokenEncoder {
                input: LinearConfig::new(MUSIC_DIMS, self.music_d).init(device),
                layers: (0..self.music_layers)
                    .map(|_| {
                        EncoderLayerConfig::new(self.music_d, self.music_heads, 2 * self.music_d)
                            .with_dropout(self.dropout)
                            .init(device)
                    })
                    .collect(),
                to_token: LinearConfig::new(TOKEN_FRAMES * self.music_d, d).init(device),
            },
            genre: EmbeddingConfig::new(genres, d).init(device),
            gpt: GptConfig::new(
                codes + 1,
                d,
                self.n_layers,
                self.n_heads,
                self.window_tokens,
            )
            .with_dropout(self.dropout)
            .init(device),
            codes,
        }
    }
}

impl ChoreoGpt {
    /// The per-position conditioning (music + genre) `[B, T', d]`.
    fn condition(&self, music: Tensor<3>, genre: Tensor<1, Int>) -> Tensor<3> {
        let m = self.music.forward(music);
        let [b, _, d] = m.dims();
        m + self.genre.forward(genre.reshape([b, 1])).reshape([b, 1, d])
    }

    /// Logits `[B, T', codes + 1]` for `tokens` `[B, T']` given `music` `[B, 4T', 35]` and
    /// `genre` `[B]` (teacher forcing).
    pub fn forward(
        &self,
        tokens: Tensor<2, Int>,
        music: Tensor<3>,
        genre: Tensor<1, Int>,
    ) -> Tensor<3> {
        let [b, t] = tokens.dims();
        let device = tokens.device();
        let bos = Tensor::<2, Int>::full([b, 1], self.codes as i64, &device);
        let prev = Tensor::cat(vec![bos, tokens.narrow(1, 0, t - 1)], 1);
        let x = self.gpt.tok_emb.forward(prev) + self.condition(music, genre);
        self.gpt.forward_embeddings(x)
    }

    /// Tokens for `music` `[1, F, 35]` (`F` a multiple of 4) of any length: windows of
    /// `window` tokens, each after the first seeded with the previous window's last `overlap`.
    /// BOS is never picked. `hook` hears of every new token (part [`CHOREOGRAPHY`]).
    pub fn generate(
        &self,
        music: Tensor<3>,
        genre: usize,
        window: usize,
        overlap: usize,
        opts: &SamplingOptions,
        hook: &dyn StepHook,
    ) -> Result<Vec<i64>, Cancelled> {
        let [_, f, _] = music.dims();
        let total = f / TOKEN_FRAMES;
        assert!(window > overlap, "GPT window must exceed its overlap");
        let device = music.device();
        let mut rng = SplitMix64(opts.seed);
        let mut out: Vec<i64> = Vec::with_capacity(total);
        let genre_t =
            Tensor::<1, Int>::from_data(TensorData::new(vec![genre as i64], [1]), &device);
        while out.len() < total {
            let seed_len = out.len().min(overlap);
            let start = out.len() - seed_len;
            let len = window.min(total - start);
            let cond = self.condition(
                music
                    .clone()
                    .narrow(1, start * TOKEN_FRAMES, len * TOKEN_FRAMES),
                genre_t.clone(),
            );
            let mut cache = KvCache::default();
            let mut prev = self.codes as i64;
            for i in 0..len {
                let tok = Tensor::<2, Int>::from_data(TensorData::new(vec![prev], [1, 1]), &device);
                let x = self.gpt.tok_emb.forward(tok) + cond.clone().narrow(1, i, 1);
                let logits = self.gpt.step(x, &mut cache);
                let next = if i < seed_len {
                    out[start + i]
                } else {
                    // BOS is a valid logit column but never a dance token.
                    let masked = logits.slice([0..1, 0..self.codes]);
                    let t = pick(masked, opts, &mut rng)[0];
                    out.push(t);
                    progress::step(hook, CHOREOGRAPHY, out.len(), total)?;
                    t
                };
                prev = next;
            }
        }
        Ok(out)
    }
}
