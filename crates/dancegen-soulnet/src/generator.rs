//! The music-aligned generator (SoulNet's MAGM, holistic.md §1.3): a masked transformer over the
//! base tokens of the three parts and a residual transformer for the higher levels, both
//! conditioned on the window's MMR music embedding (prefix token) and, by default, the music
//! features of each token's frames (`dancegen_nn::masked` explains why).

use dancegen_nn::burn;

use burn::module::Module;
use burn::tensor::{Device, Int, Tensor, TensorData};
use dancegen_nn::loss::masked_cross_entropy;
use dancegen_nn::masked::{MaskedTransformer, corrupt};
use dancegen_nn::residual_transformer::ResidualTransformer;
use dancegen_nn::rng::SplitMix64;

use crate::config::{GeneratorTable, VqTable};

/// See the module documentation.
#[derive(Module, Debug)]
pub struct PartGenerator {
    pub masked: MaskedTransformer,
    /// Absent for a one-level quantizer.
    pub residual: Option<ResidualTransformer>,
}

/// The condition of a batch of windows.
#[derive(Clone, Debug)]
pub struct Condition {
    /// `[B, d_cond]` MMR music embedding.
    pub clip: Tensor<2>,
    /// `[B, T', frames_per_token · 35]`, when the generator hears the frames.
    pub frames: Option<Tensor<3>>,
}

impl Condition {
    /// Rows whose `keep` is false lose their music (classifier-free guidance training).
    pub fn dropped(self, keep: &[bool]) -> Self {
        let device = self.clip.device();
        let b = keep.len();
        let k: Vec<f32> = keep.iter().map(|&k| f32::from(u8::from(k))).collect();
        let k = Tensor::<1>::from_data(TensorData::new(k, [b]), &device);
        Condition {
            clip: self.clip * k.clone().reshape([b, 1]),
            frames: self.frames.map(|f| f * k.reshape([b, 1, 1])),
        }
    }
}

/// SoulNet's training-time alignment (holistic.md §1.4): the generator's base tokens, drawn by
/// Gumbel-softmax at `tau` where the loss is taken (the true codes elsewhere), are decoded by the
/// frozen part autoencoder (true higher levels) and the frozen MMR's motion encoder must find
/// the window's own music among the batch's (filtered InfoNCE). Differentiable in the logits.
///
/// The release decodes with the body codebook only and a wrong reshape (§1.4); here each part
/// uses its own base codebook. Gumbel noise comes from `seed` (resumable).
#[allow(clippy::too_many_arguments)]
pub fn mmr_alignment_loss(
    l: &GeneratorLoss,
    indices: &[i64],
    [b, len, q]: [usize; 3],
    vq: &dancegen_nn::part_autoencoder::PartAutoencoder,
    mmr: &dancegen_nn::retrieval::MusicMotionRetrieval,
    music: Tensor<3>,
    tau: f64,
    seed: u64,
) -> Tensor<1> {
    let device = l.logits.device();
    let k = l.logits.dims()[2];
    let mut rng = SplitMix64(seed);
    let gumbel: Vec<f32> = (0..b * len * k)
        .map(|_| {
            let u = rng.next_f64().clamp(1e-20, 1.0 - 1e-12);
            -(-u.ln()).ln() as f32
        })
        .collect();
    let g = Tensor::<3>::from_data(TensorData::new(gumbel, [b, len, k]), &device);
    let soft = burn::tensor::activation::softmax((l.logits.clone() + g) / tau.max(1e-3), 2);
    let w = l.weight.clone().reshape([b, len, 1]);
    let onehot = l.targets.clone().one_hot::<3>(k).float();
    let base = soft * w.clone() + onehot * (w.neg() + 1.0);
    let idx = Tensor::<3, Int>::from_data(TensorData::new(indices.to_vec(), [b, len, q]), &device);
    let motion = vq.decoder.forward(vq.soft_codes(base, idx));
    mmr.loss(motion, music)
}

/// The music of `[B, T'·fpt, 35]` frames as `[B, T', fpt·35]` per-token features.
pub fn music_tokens(music: Tensor<3>, frames_per_token: usize) -> Tensor<3> {
    let [b, f, d] = music.dims();
    music.reshape([b, f / frames_per_token, frames_per_token * d])
}

/// The losses of one batch.
pub struct GeneratorLoss {
    pub total: Tensor<1>,
    pub masked: Tensor<1>,
    /// Zero for a one-level quantizer.
    pub residual: Tensor<1>,
    /// The masked transformer's logits `[B, L, K]` on the corrupted input, …
    pub logits: Tensor<3>,
    /// … where the loss was taken (`[B, L]`, 1 = corrupted position) …
    pub weight: Tensor<2>,
    /// … and the true base codes `[B, L]` (for the training-time MMR loss).
    pub targets: Tensor<2, Int>,
}

impl PartGenerator {
    /// The untrained networks of `table` over `vq`'s tokens, conditioned by `d_cond` values
    /// per clip (the MMR's latent size).
    pub fn init(table: &GeneratorTable, vq: &VqTable, d_cond: usize, device: &Device) -> Self {
        Self {
            masked: table.masked(vq, d_cond).init(device),
            residual: table.residual(vq, d_cond).map(|c| c.init(device)),
        }
    }

    /// Loss on ground-truth `indices` `[B, 3T', Q]` (host ids, from the frozen autoencoder):
    /// MoMask's corruption and cross-entropy on the base level, and the cross-entropy of one
    /// residual level drawn per batch. `seed` drives the corruption, the level and the
    /// condition dropout (so a resumed run repeats them).
    pub fn loss(
        &self,
        indices: &[i64],
        [b, l, q]: [usize; 3],
        cond: Condition,
        cond_drop_prob: f64,
        seed: u64,
        device: &Device,
    ) -> GeneratorLoss {
        let mut rng = SplitMix64(seed);
        let keep: Vec<bool> = (0..b).map(|_| rng.next_f64() >= cond_drop_prob).collect();
        let cond = cond.dropped(&keep);
        let base: Vec<i64> = (0..b * l).map(|p| indices[p * q]).collect();
        let c = corrupt(&base, l, self.masked.vocab, &mut rng);
        let input = Tensor::<2, Int>::from_data(TensorData::new(c.input, [b, l]), device);
        let target = Tensor::<2, Int>::from_data(TensorData::new(base, [b, l]), device);
        let weight = Tensor::<2>::from_data(TensorData::new(c.weight, [b, l]), device);
        let logits = self
            .masked
            .forward_with(input, cond.clip.clone(), cond.frames.clone());
        let masked = masked_cross_entropy(logits.clone(), target.clone(), weight.clone());
        let residual = match &self.residual {
            Some(r) => {
                let level = 1 + (rng.next_f64() * (q - 1) as f64) as usize % (q - 1);
                let all = Tensor::<3, Int>::from_data(
                    TensorData::new(indices.to_vec(), [b, l, q]),
                    device,
                );
                let target = all.clone().narrow(2, level, 1).reshape([b, l]);
                let logits = r.forward(all, level, cond.clip, cond.frames);
                masked_cross_entropy(logits, target, Tensor::ones([b, l], device))
            }
            None => Tensor::zeros([1], device),
        };
        GeneratorLoss {
            total: masked.clone() + residual.clone(),
            masked,
            residual,
            logits,
            weight,
            targets: target,
        }
    }
}
