//! Quantizers: VQ with EMA codebook and dead-code reset, residual VQ, SoulNet hierarchical RVQ,
//! FSQ, grouped hierarchical residual FSQ (ReactDance).
//!
//! | module | quantizer | source |
//! |---|---|---|
//! | [`vq`] | [`vq::EmaVq`] | T2M-GPT `QuantizeEMAReset` (`Mael-zys/T2M-GPT:models/quantize_cnn.py`), Lodge++ (anchors D.3) |
//! | [`rvq`] | [`rvq::ResidualVq`] | MoMask `ResidualVQ` (`EricGuo5513/momask-codes:models/vq/residual_vq.py`) |
//! | [`hrvq`] | [`hrvq::HierarchicalRvq`] | SoulNet `HiResidualVQ` (`xjli360/SoulDance-Official:models/vq/residual_hvq.py`, anchors D.6) |
//! | [`fsq`] | [`fsq::Fsq`] | Mentzer et al. 2023, "Finite Scalar Quantization: VQ-VAE Made Simple" |
//! | [`hfsq`] | [`hfsq::Hfsq`] | ReactDance (arXiv 2505.05589) section "HFSQ" (anchors D.5) |
//!
//! Every quantizer takes `[B, T, D]` latents and returns a [`QuantOutput`]. Training behaviour
//! (EMA codebook updates, quantize-dropout, HFSQ masking) happens only when the input lives on an
//! autodiff device (Burn 0.22's convention, as `Dropout`): for deterministic inference run a
//! model built on [`crate::device::inference`] or its [`burn::module::Module::valid`] copy.
//! Random draws use Burn's device RNG (`Device::seed` makes them reproducible).

pub mod fsq;
pub mod hfsq;
pub mod hrvq;
pub mod rvq;
pub mod vq;

use burn::module::Module;
use burn::tensor::{Device, Distribution, Int, Tensor};

/// What a quantizer returns.
#[derive(Debug, Clone)]
pub struct QuantOutput {
    /// Straight-through quantized latents `[B, T, D]` (forward value = the codes, gradient =
    /// identity to the input where the quantizer defines one).
    pub quantized: Tensor<3>,
    /// Code indices `[B, T', Q]` (layout documented per quantizer; −1 marks a dropped level).
    pub indices: Tensor<3, Int>,
    /// Commitment loss (zero for the FSQ family, which has none).
    pub commit_loss: Tensor<1>,
    /// Codebook perplexity `exp(−Σ p log p)` of this batch, where defined.
    pub perplexity: Option<Tensor<1>>,
    /// The quantized contribution of each residual level `[B, T, D]` (residual quantizers).
    pub levels: Vec<Tensor<3>>,
}

/// One uniform draw in `[0, 1)` from the device RNG.
pub(crate) fn uniform(device: &Device) -> f64 {
    let v: f32 = Tensor::<1>::random([1], Distribution::Uniform(0.0, 1.0), device)
        .into_data()
        .try_to_vec::<f32>()
        .expect("f32")[0];
    f64::from(v)
}

/// Whether a quantizer input asks for training behaviour (autodiff device).
pub(crate) fn is_training(x: &Tensor<3>) -> bool {
    x.device().is_autodiff()
}

/// Configuration of [`Quantizer`]: which quantizer the motion autoencoder uses.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum QuantizerConfig {
    Vq(vq::EmaVqConfig),
    Rvq(rvq::ResidualVqConfig),
    Hrvq(hrvq::HierarchicalRvqConfig),
    Fsq(fsq::FsqConfig),
    Hfsq(hfsq::HfsqConfig),
}

impl QuantizerConfig {
    pub fn init(&self, device: &Device) -> Quantizer {
        match self {
            QuantizerConfig::Vq(c) => Quantizer::Vq(c.init(device)),
            QuantizerConfig::Rvq(c) => Quantizer::Rvq(c.init(device)),
            QuantizerConfig::Hrvq(c) => Quantizer::Hrvq(c.init(device)),
            QuantizerConfig::Fsq(c) => Quantizer::Fsq(c.init(device)),
            QuantizerConfig::Hfsq(c) => Quantizer::Hfsq(c.init(device)),
        }
    }

    /// Channels of the latent the quantizer takes.
    pub fn dim(&self) -> usize {
        match self {
            QuantizerConfig::Vq(c) => c.code_dim,
            QuantizerConfig::Rvq(c) => c.vq.code_dim,
            QuantizerConfig::Hrvq(c) => 3 * c.vq.code_dim,
            QuantizerConfig::Fsq(c) => c.input_dim(),
            QuantizerConfig::Hfsq(c) => c.dim,
        }
    }
}

/// Any of the quantizers, chosen by [`QuantizerConfig`].
#[derive(Module, Debug)]
pub enum Quantizer {
    Vq(vq::EmaVq),
    Rvq(rvq::ResidualVq),
    Hrvq(hrvq::HierarchicalRvq),
    Fsq(fsq::Fsq),
    Hfsq(hfsq::Hfsq),
}

impl Quantizer {
    /// `[B, T, D]` latents → [`QuantOutput`].
    pub fn forward(&self, x: Tensor<3>) -> QuantOutput {
        match self {
            Quantizer::Vq(q) => q.forward(x),
            Quantizer::Rvq(q) => q.forward(x),
            Quantizer::Hrvq(q) => q.forward(x),
            Quantizer::Fsq(q) => q.forward(x),
            Quantizer::Hfsq(q) => q.forward(x),
        }
    }

    /// Size of the single codebook a token index points into (plain VQ only: the residual and
    /// FSQ quantizers emit several indices per step).
    pub fn codebook_size(&self) -> Option<usize> {
        match self {
            Quantizer::Vq(q) => Some(q.codebook.value_sync().dims()[0]),
            _ => None,
        }
    }

    /// Indices as returned in [`QuantOutput::indices`] → quantized latents `[B, T, D]`.
    pub fn decode_indices(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        match self {
            Quantizer::Vq(q) => q.decode_indices(indices),
            Quantizer::Rvq(q) => q.decode_indices(indices),
            Quantizer::Hrvq(q) => q.decode_indices(indices),
            Quantizer::Fsq(q) => q.decode_indices(indices),
            Quantizer::Hfsq(q) => q.decode_indices(indices),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device;
    use crate::weights::{self, Layout};

    fn vals<const D: usize>(t: Tensor<D>) -> Vec<f32> {
        t.into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap()
    }

    #[test]
    fn ema_vq_state_is_saved_and_restored() {
        let dev = device::training();
        dev.seed(3);
        let cfg = vq::EmaVqConfig::new(8, 4);
        let q = cfg.init(&dev);
        let x = Tensor::<3>::random([2, 10, 4], Distribution::Normal(0.0, 1.0), &dev);
        q.forward(x.clone());
        q.forward(x * 1.5);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("vq.safetensors");
        weights::save(&q, &path, Layout::Burn, &[]).unwrap();
        let back = weights::load(cfg.init(&device::inference()), &path, Layout::Burn).unwrap();
        assert!(back.is_initialised());
        assert_eq!(
            vals(back.codebook.value_sync()),
            vals(q.codebook.value_sync())
        );
        assert_eq!(
            vals(back.code_sum.value_sync()),
            vals(q.code_sum.value_sync())
        );
        assert_eq!(
            vals(back.code_count.value_sync()),
            vals(q.code_count.value_sync())
        );
    }

    #[test]
    fn quantize_dropout_only_in_training() {
        let cfg = rvq::ResidualVqConfig::new(vq::EmaVqConfig::new(8, 4))
            .with_num_quantizers(4)
            .with_quantize_dropout_prob(1.0);
        let dev = device::training();
        dev.seed(5);
        let r = cfg.init(&dev);
        let x = Tensor::<3>::random([1, 16, 4], Distribution::Normal(0.0, 1.0), &dev);
        let mut dropped = 0;
        for _ in 0..8 {
            let idx = r.forward(x.clone()).indices;
            if idx.lower_elem(0).any().into_scalar::<bool>() {
                dropped += 1;
            }
        }
        assert!(dropped > 0, "quantize-dropout never dropped a level");
        let plain = r.valid();
        let xi = Tensor::<3>::random(
            [1, 16, 4],
            Distribution::Normal(0.0, 1.0),
            &device::inference(),
        );
        for _ in 0..4 {
            let idx = plain.forward(xi.clone()).indices;
            assert!(!idx.lower_elem(0).any().into_scalar::<bool>());
        }
    }

    #[test]
    fn hfsq_masking_only_in_training_and_inference_is_deterministic() {
        let cfg = hfsq::HfsqConfig::new(8, vec![8, 5, 5, 3])
            .with_groups(2)
            .with_num_levels(3)
            .with_residual_mask_prob(1.0)
            .with_residual_noise_std(0.1)
            .with_code_mask_prob(0.3);
        let plain = device::inference();
        let h = cfg.init(&plain);
        let x = Tensor::<3>::random([2, 6, 8], Distribution::Normal(0.0, 1.0), &plain);
        let a = vals(h.forward(x.clone()).quantized);
        let b = vals(h.forward(x.clone()).quantized);
        assert_eq!(a, b);
        let dev = device::training();
        dev.seed(9);
        let ht = cfg.init(&dev);
        let xt = Tensor::<3>::from_data(x.into_data(), &dev);
        let o = ht.forward(xt);
        assert_ne!(vals(o.quantized), a, "training masks changed nothing");
        // Levels ≥ k were dropped: the top level is all zeros.
        assert!(vals(o.levels[2].clone()).iter().all(|&v| v == 0.0));
    }

    #[test]
    fn autoencoder_config_serde_round_trip() {
        use crate::autoencoder::MotionAutoencoderConfig;
        use crate::conv::ConvCodecConfig;
        for q in [
            QuantizerConfig::Vq(vq::EmaVqConfig::new(16, 8)),
            QuantizerConfig::Fsq(fsq::FsqConfig::new(vec![8, 5, 5]).with_dim(Some(8))),
            QuantizerConfig::Hfsq(hfsq::HfsqConfig::new(8, vec![8, 5, 5, 3]).with_groups(2)),
        ] {
            let cfg = MotionAutoencoderConfig::new(
                ConvCodecConfig::new(12, 12).with_width(16).with_code_dim(8),
                q,
            );
            let json = serde_json::to_string(&cfg).unwrap();
            let back: MotionAutoencoderConfig = serde_json::from_str(&json).unwrap();
            assert_eq!(serde_json::to_string(&back).unwrap(), json);
            let m = back.init(&device::inference());
            let x = Tensor::<3>::zeros([1, 16, 12], &device::inference());
            let out = m.forward(x.clone());
            assert_eq!(out.reconstruction.dims(), [1, 16, 12]);
            let idx = m.encode(x);
            assert_eq!(m.decode(idx).dims(), [1, 16, 12]);
        }
    }
}
