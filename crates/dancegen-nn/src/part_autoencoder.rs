//! SoulNet's part autoencoder (the HRVQ-VAE, `xjli360/SoulDance-Official:models/vq/model.py`,
//! `../shared/reference/holistic.md` §1.2): one conv encoder per part of the split vector
//! `[body 263 | hands 360 | face F]`, a quantizer over the three part latents, and **one** conv
//! decoder from the concatenated part codes `[Σq_body | Σq_hands | Σq_face]` to the whole vector.
//!
//! The quantizer is the only thing the ablation of the paper's Tables 2–3 changes, so the
//! encoders and the decoder are the same for all three kinds ([`PartQuantizerConfig`]):
//! - `hrvq`: [`HierarchicalRvq`], body → hands → face links at every residual level;
//! - `rvq`: three independent [`ResidualVq`] stacks, one per part (no links);
//! - `vq`: three independent single-level [`EmaVq`] codebooks.
//!
//! Indices are `[B, 3T', Q]` for all three: per level the three parts' `[B, T']` indices
//! concatenated along time (the reference's layout; `Q = 1` for `vq`).
//!
//! Loss: `Σ_p w_p · (D_p / D) · recon_p + velocity_weight · velocity + acceleration_weight ·
//! acceleration + commit_weight · commit` (the acceleration term is ours, 0 by default: the
//! released code has none).
//! With the default part weights `w = (1, 1, 1)` the recon term is the mean over every value,
//! which is what the released code trains (it weights the parts equally per value; the paper's
//! α, β, γ are not given). SoulNet's extra 0.5 × SmoothL1 on "positions" `[4:157]` is not
//! reproduced: in the split layout that slice takes in 90 rotation values (holistic.md §1.2).

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, Int, Tensor};

use crate::conv::{ConvCodecConfig, ConvDecoder, ConvEncoder};
use crate::loss::{self, Distance};
use crate::quant::QuantOutput;
use crate::quant::hrvq::{HierarchicalRvq, HierarchicalRvqConfig};
use crate::quant::rvq::{ResidualVq, ResidualVqConfig};
use crate::quant::vq::{EmaVq, EmaVqConfig};

/// Parts of the holistic vector: body, hands, face.
pub const PARTS: usize = 3;

/// The quantizer kind (serde tag `kind = "hrvq" | "rvq" | "vq"`); every kind quantizes `d`-wide
/// part latents.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PartQuantizerConfig {
    Hrvq(HierarchicalRvqConfig),
    Rvq(ResidualVqConfig),
    Vq(EmaVqConfig),
}

impl PartQuantizerConfig {
    /// One part's latent width `d`.
    pub fn part_dim(&self) -> usize {
        match self {
            PartQuantizerConfig::Hrvq(c) => c.vq.code_dim,
            PartQuantizerConfig::Rvq(c) => c.vq.code_dim,
            PartQuantizerConfig::Vq(c) => c.code_dim,
        }
    }
}

/// The part quantizer. One per model, so the size gap between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Module, Debug)]
pub enum PartQuantizer {
    Hrvq(HierarchicalRvq),
    Rvq(Vec<ResidualVq>),
    Vq(Vec<EmaVq>),
}

/// Configuration of [`PartAutoencoder`].
#[derive(Config, Debug)]
pub struct PartAutoencoderConfig {
    /// Values per frame of each part, `[263, 360, F]` for SoulNet's split layout.
    pub parts: [usize; PARTS],
    /// Shared encoder/decoder shape; its `input_dim`, `output_dim` and `code_dim` are replaced
    /// per part (`code_dim` = the quantizer's part width).
    pub codec: ConvCodecConfig,
    pub quantizer: PartQuantizerConfig,
    #[config(default = "Distance::SmoothL1")]
    pub recon: Distance,
    /// Per-part reconstruction weights (α, β, γ).
    #[config(default = "[1.0, 1.0, 1.0]")]
    pub part_weights: [f64; PARTS],
    #[config(default = 0.5)]
    pub velocity_weight: f64,
    /// Weight of the second differences' distance (not in SoulNet; against a decoder's jitter).
    #[config(default = 0.0)]
    pub acceleration_weight: f64,
    #[config(default = 0.02)]
    pub commit_weight: f64,
}

impl PartAutoencoderConfig {
    pub fn init(&self, device: &Device) -> PartAutoencoder {
        let d = self.quantizer.part_dim();
        let total: usize = self.parts.iter().sum();
        let encoders = self
            .parts
            .iter()
            .map(|&w| {
                let mut c = self.codec.clone();
                c.input_dim = w;
                c.output_dim = w;
                c.code_dim = d;
                c.init_encoder(device)
            })
            .collect();
        let mut dec = self.codec.clone();
        dec.input_dim = total;
        dec.output_dim = total;
        dec.code_dim = PARTS * d;
        let quantizer = match &self.quantizer {
            PartQuantizerConfig::Hrvq(c) => PartQuantizer::Hrvq(c.init(device)),
            PartQuantizerConfig::Rvq(c) => {
                PartQuantizer::Rvq((0..PARTS).map(|_| c.init(device)).collect())
            }
            PartQuantizerConfig::Vq(c) => {
                PartQuantizer::Vq((0..PARTS).map(|_| c.init(device)).collect())
            }
        };
        PartAutoencoder {
            encoders,
            quantizer,
            decoder: dec.init_decoder(device),
            parts: self.parts.to_vec(),
            recon: self.recon,
            part_weights: self.part_weights.to_vec(),
            velocity_weight: self.velocity_weight,
            acceleration_weight: self.acceleration_weight,
            commit_weight: self.commit_weight,
        }
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct PartAutoencoder {
    pub encoders: Vec<ConvEncoder>,
    pub quantizer: PartQuantizer,
    pub decoder: ConvDecoder,
    #[module(skip)]
    pub parts: Vec<usize>,
    #[module(skip)]
    pub recon: Distance,
    #[module(skip)]
    pub part_weights: Vec<f64>,
    #[module(skip)]
    pub velocity_weight: f64,
    #[module(skip)]
    pub acceleration_weight: f64,
    #[module(skip)]
    pub commit_weight: f64,
}

/// [`PartAutoencoder::loss`]'s terms (each `[1]`).
#[derive(Debug, Clone)]
pub struct PartAutoencoderLoss {
    pub total: Tensor<1>,
    /// Per part, in the autoencoder's distance.
    pub recon_parts: [Tensor<1>; PARTS],
    pub velocity: Tensor<1>,
    pub acceleration: Tensor<1>,
    pub commit: Tensor<1>,
    /// `[B, T, D]`.
    pub reconstruction: Tensor<3>,
    pub quant: QuantOutput,
}

impl PartAutoencoder {
    fn part_offsets(&self) -> [usize; PARTS] {
        [0, self.parts[0], self.parts[0] + self.parts[1]]
    }

    /// The three part latents `[B, T', d]` of `[B, T, D]`.
    fn encode_parts(&self, x: Tensor<3>) -> Vec<Tensor<3>> {
        let off = self.part_offsets();
        (0..PARTS)
            .map(|p| self.encoders[p].forward(x.clone().narrow(2, off[p], self.parts[p])))
            .collect()
    }

    /// Quantizes the part latents (see the module documentation for the index layout).
    fn quantize(&self, z: Vec<Tensor<3>>) -> QuantOutput {
        match &self.quantizer {
            PartQuantizer::Hrvq(q) => q.forward(Tensor::cat(z, 2)),
            PartQuantizer::Rvq(qs) => {
                let outs = qs.iter().zip(z).map(|(q, z)| q.forward(z)).collect();
                join_parts(outs)
            }
            PartQuantizer::Vq(qs) => {
                let outs = qs.iter().zip(z).map(|(q, z)| q.forward(z)).collect();
                join_parts(outs)
            }
        }
    }

    /// `[B, T, D]` (T a multiple of the downsampling) → reconstruction and quantizer output.
    pub fn forward(&self, x: Tensor<3>) -> (Tensor<3>, QuantOutput) {
        let quant = self.quantize(self.encode_parts(x));
        (self.decoder.forward(quant.quantized.clone()), quant)
    }

    /// Code indices `[B, 3T', Q]` of `[B, T, D]`.
    pub fn encode(&self, x: Tensor<3>) -> Tensor<3, Int> {
        self.quantize(self.encode_parts(x)).indices
    }

    /// The summed part codes `[B, T', 3d]` of indices `[B, 3T', Q']` (negative = dropped level).
    pub fn codes(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let [_, t3, qn] = indices.dims();
        let t = t3 / PARTS;
        let part = |p: usize| indices.clone().narrow(1, p * t, t);
        match &self.quantizer {
            PartQuantizer::Hrvq(q) => q.decode_indices(indices),
            PartQuantizer::Rvq(qs) => Tensor::cat(
                (0..PARTS).map(|p| qs[p].decode_indices(part(p))).collect(),
                2,
            ),
            PartQuantizer::Vq(qs) => Tensor::cat(
                (0..PARTS)
                    .map(|p| qs[p].decode_indices(part(p).narrow(2, 0, qn.min(1))))
                    .collect(),
                2,
            ),
        }
    }

    /// Motion `[B, T, D]` from code indices.
    pub fn decode(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        self.decoder.forward(self.codes(indices))
    }

    /// The three parts' base-level codebooks `[K, d]` (body, hands, face).
    pub fn base_codebooks(&self) -> [Tensor<2>; PARTS] {
        match &self.quantizer {
            PartQuantizer::Hrvq(q) => [
                q.layers_body[0].codebook.value_sync(),
                q.layers_hands[0].codebook.value_sync(),
                q.layers_face[0].codebook.value_sync(),
            ],
            PartQuantizer::Rvq(qs) => {
                std::array::from_fn(|p| qs[p].layers[0].codebook.value_sync())
            }
            PartQuantizer::Vq(qs) => std::array::from_fn(|p| qs[p].codebook.value_sync()),
        }
    }

    /// Summed part codes `[B, T', 3d]` with the base level given as a distribution over the
    /// codes, `base` `[B, 3T', K]` (each row sums to 1; one-hot gives [`Self::codes`]), and the
    /// higher levels from `indices` `[B, 3T', Q]` (their level 0 is ignored). Differentiable in
    /// `base`: SoulNet's training-time MMR loss decodes the generator's Gumbel-softmax draws
    /// through it (holistic.md §1.4, where the release decodes with the body codebook only).
    pub fn soft_codes(&self, base: Tensor<3>, indices: Tensor<3, Int>) -> Tensor<3> {
        let [b, t3, _] = base.dims();
        let t = t3 / PARTS;
        let books = self.base_codebooks();
        let soft = Tensor::cat(
            (0..PARTS)
                .map(|p| {
                    let book = books[p].clone();
                    let [k, d] = book.dims();
                    base.clone()
                        .narrow(1, p * t, t)
                        .reshape([b * t, k])
                        .matmul(book)
                        .reshape([b, t, d])
                })
                .collect(),
            2,
        );
        let [_, _, q] = indices.dims();
        if q < 2 {
            return soft;
        }
        let device = indices.device();
        let dropped = Tensor::<3, Int>::full([b, t3, 1], -1, &device);
        let higher = Tensor::cat(vec![dropped, indices.narrow(2, 1, q - 1)], 2);
        soft + self.codes(higher)
    }

    /// Training loss of a batch `[B, T, D]` (see the module documentation).
    pub fn loss(&self, x: Tensor<3>) -> PartAutoencoderLoss {
        self.loss_with(x, None)
    }

    /// [`Self::loss`], or with `frozen` (an autoencoder of the same shape on
    /// `crate::device::inference()`) the loss of this model's decoder alone on the codes that
    /// `frozen` gives `x`, without a commitment term: fine-tuning a decoder under a trained
    /// generator, whose tokens must keep their meaning. The frozen codes are computed off the
    /// autodiff graph (tracked work whose outputs are detached is never freed by Burn's autodiff).
    pub fn loss_with(&self, x: Tensor<3>, frozen: Option<&PartAutoencoder>) -> PartAutoencoderLoss {
        let (reconstruction, quant) = match frozen {
            None => self.forward(x.clone()),
            Some(f) => {
                let device = x.device();
                let xi = x.clone().detach().to_device(&crate::device::inference());
                let mut quant = f.quantize(f.encode_parts(xi));
                quant.quantized = quant.quantized.to_device(&device);
                quant.indices = quant.indices.to_device(&device);
                quant.commit_loss = Tensor::zeros([1], &device);
                quant.perplexity = quant.perplexity.map(|p| p.to_device(&device));
                quant.levels = quant
                    .levels
                    .into_iter()
                    .map(|l| l.to_device(&device))
                    .collect();
                (self.decoder.forward(quant.quantized.clone()), quant)
            }
        };
        let off = self.part_offsets();
        let total_dims: usize = self.parts.iter().sum();
        let recon_parts: [Tensor<1>; PARTS] = std::array::from_fn(|p| {
            loss::reconstruction(
                reconstruction.clone().narrow(2, off[p], self.parts[p]),
                x.clone().narrow(2, off[p], self.parts[p]),
                self.recon,
            )
        });
        let recon = (0..PARTS)
            .map(|p| {
                recon_parts[p].clone()
                    * (self.part_weights[p] * self.parts[p] as f64 / total_dims as f64)
            })
            .reduce(|a, b| a + b)
            .expect("three parts");
        let velocity = loss::velocity(reconstruction.clone(), x.clone(), self.recon);
        let acceleration = loss::acceleration(reconstruction.clone(), x, self.recon);
        let commit = quant.commit_loss.clone();
        let total = recon
            + velocity.clone() * self.velocity_weight
            + acceleration.clone() * self.acceleration_weight
            + commit.clone() * self.commit_weight;
        PartAutoencoderLoss {
            total,
            recon_parts,
            velocity,
            acceleration,
            commit,
            reconstruction,
            quant,
        }
    }
}

/// Three independent parts' outputs as one: codes along channels, indices along time, commit
/// and perplexity summed (as [`HierarchicalRvq`] sums its parts').
fn join_parts(outs: Vec<QuantOutput>) -> QuantOutput {
    let quantized = Tensor::cat(outs.iter().map(|o| o.quantized.clone()).collect(), 2);
    let indices = Tensor::cat(outs.iter().map(|o| o.indices.clone()).collect(), 1);
    let commit_loss = outs
        .iter()
        .map(|o| o.commit_loss.clone())
        .reduce(|a, b| a + b)
        .expect("three parts");
    let perplexity = outs
        .iter()
        .map(|o| o.perplexity.clone())
        .collect::<Option<Vec<_>>>()
        .and_then(|v| v.into_iter().reduce(|a, b| a + b));
    let levels = match outs.iter().map(|o| o.levels.len()).min() {
        Some(n) => (0..n)
            .map(|l| Tensor::cat(outs.iter().map(|o| o.levels[l].clone()).collect(), 2))
            .collect(),
        None => Vec::new(),
    };
    QuantOutput {
        quantized,
        indices,
        commit_loss,
        perplexity,
        levels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device;
    use burn::tensor::Distribution;

    fn config(kind: &str) -> PartAutoencoderConfig {
        let vq = EmaVqConfig::new(16, 8);
        let quantizer = match kind {
            "hrvq" => {
                PartQuantizerConfig::Hrvq(HierarchicalRvqConfig::new(vq).with_num_quantizers(3))
            }
            "rvq" => PartQuantizerConfig::Rvq(ResidualVqConfig::new(vq).with_num_quantizers(3)),
            _ => PartQuantizerConfig::Vq(vq),
        };
        let codec = ConvCodecConfig::new(0, 0)
            .with_width(16)
            .with_depth(1)
            .with_code_dim(8);
        PartAutoencoderConfig::new([5, 7, 3], codec, quantizer)
    }

    #[test]
    fn every_kind_has_the_same_shapes_and_decodes_its_own_indices() {
        let dev = device::inference();
        dev.seed(1);
        for (kind, q) in [("hrvq", 3), ("rvq", 3), ("vq", 1)] {
            let ae = config(kind).init(&dev);
            let x = Tensor::<3>::random([2, 16, 15], Distribution::Normal(0.0, 1.0), &dev);
            let (rec, quant) = ae.forward(x.clone());
            assert_eq!(rec.dims(), [2, 16, 15], "{kind}");
            assert_eq!(quant.quantized.dims(), [2, 4, 24], "{kind}");
            let idx = ae.encode(x);
            assert_eq!(idx.dims(), [2, 12, q], "{kind}");
            // Decoding the indices gives back the quantized codes and the reconstruction.
            let codes = ae.codes(idx.clone());
            let diff = (codes - quant.quantized).abs().max().into_scalar::<f32>();
            assert!(diff < 1e-5, "{kind}: codes differ by {diff}");
            let diff = (ae.decode(idx.clone()) - rec)
                .abs()
                .max()
                .into_scalar::<f32>();
            assert!(diff < 1e-4, "{kind}: decode differs by {diff}");
            // The base level as a one-hot distribution gives the same codes.
            let base = idx.clone().narrow(2, 0, 1).reshape([2, 12]);
            let onehot = base.one_hot::<3>(16).float();
            let diff = (ae.soft_codes(onehot, idx.clone()) - ae.codes(idx))
                .abs()
                .max()
                .into_scalar::<f32>();
            assert!(diff < 1e-5, "{kind}: soft codes differ by {diff}");
        }
    }

    #[test]
    fn loss_weights_parts_by_width_and_trains() {
        use burn::optim::{AdamWConfig, GradientsParams};
        let dev = device::training();
        dev.seed(2);
        let mut ae = config("hrvq").init(&dev);
        let x = Tensor::<3>::random([4, 16, 15], Distribution::Normal(0.0, 1.0), &dev);
        let l = ae.loss(x.clone());
        // With equal part weights, the recon term is the mean over all values.
        let overall = loss::reconstruction(l.reconstruction.clone(), x.clone(), Distance::SmoothL1);
        let parts: f32 = (0..PARTS)
            .map(|p| l.recon_parts[p].clone().into_scalar::<f32>() * [5.0, 7.0, 3.0][p] / 15.0)
            .sum();
        assert!((overall.into_scalar::<f32>() - parts).abs() < 1e-5);
        let first = l.total.clone().into_scalar::<f32>();
        let mut opt = AdamWConfig::new().with_weight_decay(0.0).init();
        let mut last = first;
        for _ in 0..60 {
            let l = ae.loss(x.clone());
            last = l.total.clone().into_scalar::<f32>();
            let g = GradientsParams::from_grads(l.total.backward(), &ae);
            ae = opt.step(3e-3, ae, g);
        }
        assert!(last < 0.8 * first, "loss {first} -> {last}");
    }
}
