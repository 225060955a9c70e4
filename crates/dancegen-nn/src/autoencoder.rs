//! Motion autoencoder: conv encoder → quantizer → conv decoder (T2M-GPT/MoMask `VQVAE`,
//! `Mael-zys/T2M-GPT:models/vqvae.py`; Lodge++'s VQ-VAE, anchors D.3; SoulNet's HRVQ-VAE, D.6;
//! ReactDance's HFSQ autoencoder, D.5).
//!
//! Loss (T2M-GPT `train_vq.py`): `recon(x̂, x) + velocity_weight · recon(Δx̂, Δx) +
//! commit_weight · commit`, the distances from [`crate::loss`] (L1 by default; Lodge++: vel 0.2,
//! commit 0.02; MoMask: vel 0.5, commit 0.02).

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, Int, Tensor};

use crate::conv::{ConvCodecConfig, ConvDecoder, ConvEncoder};
use crate::loss::{self, Distance};
use crate::quant::{QuantOutput, Quantizer, QuantizerConfig};

/// Configuration of [`MotionAutoencoder`] (serde: readable from TOML/JSON; the quantizer is
/// tagged by `kind = "vq" | "rvq" | "hrvq" | "fsq" | "hfsq"`).
#[derive(Config, Debug)]
pub struct MotionAutoencoderConfig {
    /// Encoder/decoder; `code_dim` must equal the quantizer's input width.
    pub codec: ConvCodecConfig,
    pub quantizer: QuantizerConfig,
    #[config(default = "Distance::L1")]
    pub recon: Distance,
    #[config(default = 0.5)]
    pub velocity_weight: f64,
    #[config(default = 0.02)]
    pub commit_weight: f64,
}

impl MotionAutoencoderConfig {
    pub fn init(&self, device: &Device) -> MotionAutoencoder {
        assert_eq!(
            self.codec.code_dim,
            self.quantizer.dim(),
            "autoencoder: codec code_dim must equal the quantizer's width"
        );
        MotionAutoencoder {
            encoder: self.codec.init_encoder(device),
            quantizer: self.quantizer.init(device),
            decoder: self.codec.init_decoder(device),
            recon: self.recon,
            velocity_weight: self.velocity_weight,
            commit_weight: self.commit_weight,
        }
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct MotionAutoencoder {
    pub encoder: ConvEncoder,
    pub quantizer: Quantizer,
    pub decoder: ConvDecoder,
    #[module(skip)]
    pub recon: Distance,
    #[module(skip)]
    pub velocity_weight: f64,
    #[module(skip)]
    pub commit_weight: f64,
}

/// [`MotionAutoencoder::forward`]'s result.
#[derive(Debug, Clone)]
pub struct AutoencoderOutput {
    /// `[B, T, C]`.
    pub reconstruction: Tensor<3>,
    pub quant: QuantOutput,
}

/// [`MotionAutoencoder::loss`]'s terms (each `[1]`).
#[derive(Debug, Clone)]
pub struct AutoencoderLoss {
    pub total: Tensor<1>,
    pub recon: Tensor<1>,
    pub velocity: Tensor<1>,
    pub commit: Tensor<1>,
    pub output: AutoencoderOutput,
}

impl MotionAutoencoder {
    /// `[B, T, C]` (T a multiple of the downsampling factor) → reconstruction + quantizer output.
    pub fn forward(&self, x: Tensor<3>) -> AutoencoderOutput {
        let z = self.encoder.forward(x);
        let quant = self.quantizer.forward(z);
        let reconstruction = self.decoder.forward(quant.quantized.clone());
        AutoencoderOutput {
            reconstruction,
            quant,
        }
    }

    /// Code indices of a motion `[B, T, C]` (see [`QuantOutput::indices`]).
    pub fn encode(&self, x: Tensor<3>) -> Tensor<3, Int> {
        self.quantizer.forward(self.encoder.forward(x)).indices
    }

    /// Motion `[B, T, C]` from code indices.
    pub fn decode(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        self.decoder.forward(self.quantizer.decode_indices(indices))
    }

    /// Training loss of a batch `[B, T, C]` (see the module documentation).
    pub fn loss(&self, x: Tensor<3>) -> AutoencoderLoss {
        let output = self.forward(x.clone());
        let recon = loss::reconstruction(output.reconstruction.clone(), x.clone(), self.recon);
        let velocity = loss::velocity(output.reconstruction.clone(), x, self.recon);
        let commit = output.quant.commit_loss.clone();
        let total = recon.clone()
            + velocity.clone() * self.velocity_weight
            + commit.clone() * self.commit_weight;
        AutoencoderLoss {
            total,
            recon,
            velocity,
            commit,
            output,
        }
    }
}
