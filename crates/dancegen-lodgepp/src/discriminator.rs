//! The Multi-Genre Discriminator (paper §3.4.4 after MNET; D.2): a transformer encoder over
//! `[motion tokens; music tokens]`, mean-pooled, a shared MLP and one logit head per genre; the
//! logit of the window's own genre is the score. Trained with the hinge loss.

use dancegen_nn::attention::AttnMasks;
use dancegen_nn::burn;
use dancegen_nn::mlp::{Mlp, MlpConfig};
use dancegen_nn::pos_encoding::sinusoidal;
use dancegen_nn::transformer::{EncoderLayer, EncoderLayerConfig};

use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::choreo_gpt::MUSIC_DIMS;
use crate::config::DiscriminatorConfig;
use crate::layout::DIMS;

/// See the module documentation.
#[derive(Module, Debug)]
pub struct GenreDiscriminator {
    pub motion_in: Linear,
    pub music_in: Linear,
    pub layers: Vec<EncoderLayer>,
    pub shared: Mlp,
    /// `d → genres`: row `g` is genre `g`'s head.
    pub heads: Linear,
}

impl DiscriminatorConfig {
    pub fn init(&self, genres: usize, device: &Device) -> GenreDiscriminator {
        let d = self.d_model;
        GenreDiscriminator {
            motion_in: LinearConfig::new(DIMS, d).init(device),
            music_in: LinearConfig::new(MUSIC_DIMS, d).init(device),
            layers: (0..self.depth)
                .map(|_| {
                    EncoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_norm_first(true)
                        .init(device)
                })
                .collect(),
            shared: MlpConfig::new(d, self.d_ff, d).init(device),
            heads: LinearConfig::new(d, genres.max(1)).init(device),
        }
    }
}

impl GenreDiscriminator {
    /// Scores `[B, 1]` of windows `motion` `[B, T, 151]` with `music` `[B, T, 35]` as genre
    /// `genre[b]`.
    pub fn forward(&self, motion: Tensor<3>, music: Tensor<3>, genre: &[usize]) -> Tensor<2> {
        let [b, t, _] = motion.dims();
        let device = motion.device();
        let m = self.motion_in.forward(motion);
        let d = m.dims()[2];
        let pos = sinusoidal(0, t, d, &device).unsqueeze::<3>();
        let mut h = Tensor::cat(vec![m + pos.clone(), self.music_in.forward(music) + pos], 1);
        let masks = AttnMasks::default();
        for l in &self.layers {
            h = l.forward(h, &masks, None);
        }
        let pooled = self.shared.forward(h.mean_dim(1).reshape([b, d]));
        let logits = self.heads.forward(pooled);
        let idx: Vec<i64> = genre.iter().map(|&g| g as i64).collect();
        let idx = Tensor::<2, Int>::from_data(TensorData::new(idx, [b, 1]), &device);
        logits.gather(1, idx)
    }
}
