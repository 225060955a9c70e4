//! Residual VQ with quantize-dropout: MoMask `ResidualVQ`
//! (`EricGuo5513/momask-codes:models/vq/residual_vq.py`; SoulNet's body stack, anchors D.6).
//!
//! `num_quantizers` [`EmaVq`] layers; layer `i` quantizes the residual
//! `r_i = x − Σ_{j<i} sg(q_j)` and the output is `Σ q_i` (each `q_i` straight-through on its
//! residual). In training, with probability `quantize_dropout_prob`, a level
//! `s ∈ [cutoff, num_quantizers)` is drawn and layers `> s` are skipped (their indices −1).
//! Commitment loss and perplexity are averaged over the layers that ran. Indices `[B, T, Q]`.

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, Int, Tensor};

use super::vq::{EmaVq, EmaVqConfig};
use super::{QuantOutput, is_training, uniform};

/// Configuration of [`ResidualVq`].
#[derive(Config, Debug)]
pub struct ResidualVqConfig {
    /// Each layer's quantizer.
    pub vq: EmaVqConfig,
    #[config(default = 6)]
    pub num_quantizers: usize,
    /// MoMask `quantize_dropout_prob` (0.2 in MoMask/SoulNet training).
    #[config(default = 0.2)]
    pub quantize_dropout_prob: f64,
    /// Layers `≤ cutoff` are never dropped.
    #[config(default = 0)]
    pub quantize_dropout_cutoff_index: usize,
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct ResidualVq {
    pub layers: Vec<EmaVq>,
    #[module(skip)]
    pub quantize_dropout_prob: f64,
    #[module(skip)]
    pub quantize_dropout_cutoff_index: usize,
}

impl ResidualVqConfig {
    pub fn init(&self, device: &Device) -> ResidualVq {
        ResidualVq {
            layers: (0..self.num_quantizers)
                .map(|_| self.vq.init(device))
                .collect(),
            quantize_dropout_prob: self.quantize_dropout_prob,
            quantize_dropout_cutoff_index: self.quantize_dropout_cutoff_index,
        }
    }
}

/// The last level kept this call (`num_quantizers − 1` = all), MoMask's
/// `start_drop_quantize_index` logic.
pub(crate) fn dropout_last_kept(
    training: bool,
    prob: f64,
    cutoff: usize,
    num_quant: usize,
    device: &Device,
) -> usize {
    if training && prob > 0.0 && uniform(device) < prob && cutoff < num_quant {
        let span = num_quant - cutoff;
        let s = cutoff + ((uniform(device) * span as f64) as usize).min(span - 1);
        s.min(num_quant - 1)
    } else {
        num_quant - 1
    }
}

impl ResidualVq {
    /// `[B, T, d]` → [`QuantOutput`] with indices `[B, T, Q]`.
    pub fn forward(&self, x: Tensor<3>) -> QuantOutput {
        self.forward_keep(x.clone(), None)
    }

    /// As [`forward`](Self::forward), with the number of levels to run forced to `keep`
    /// (MoMask's `force_dropout_index = keep − 1`) when given.
    pub fn forward_keep(&self, x: Tensor<3>, keep: Option<usize>) -> QuantOutput {
        let [b, t, _] = x.dims();
        let device = x.device();
        let q = self.layers.len();
        let last = match keep {
            Some(k) => k.clamp(1, q) - 1,
            None => dropout_last_kept(
                is_training(&x),
                self.quantize_dropout_prob,
                self.quantize_dropout_cutoff_index,
                q,
                &device,
            ),
        };
        let mut residual = x.clone();
        let mut out = x.zeros_like();
        let mut indices = Vec::with_capacity(q);
        let mut losses = Vec::new();
        let mut perps = Vec::new();
        let mut levels = Vec::new();
        for (i, layer) in self.layers.iter().enumerate() {
            if i > last {
                indices.push(Tensor::<3, Int>::full([b, t, 1], -1, &device));
                continue;
            }
            let o = layer.forward(residual.clone());
            residual = residual - o.quantized.clone().detach();
            out = out + o.quantized.clone();
            indices.push(o.indices);
            losses.push(o.commit_loss);
            perps.extend(o.perplexity);
            levels.push(o.quantized);
        }
        let n = losses.len() as f64;
        let commit_loss = losses.into_iter().reduce(|a, b| a + b).unwrap() / n;
        let np = perps.len() as f64;
        let perplexity = perps.into_iter().reduce(|a, b| a + b).map(|p| p / np);
        QuantOutput {
            quantized: out,
            indices: Tensor::cat(indices, 2),
            commit_loss,
            perplexity,
            levels,
        }
    }

    /// Indices `[B, T, Q']` (`Q' ≤ Q`, −1 = dropped) → `Σ` codes `[B, T, d]`.
    pub fn decode_indices(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let qn = indices.dims()[2];
        let mut out: Option<Tensor<3>> = None;
        for (i, layer) in self.layers.iter().enumerate().take(qn) {
            let c = layer.decode_indices(indices.clone().narrow(2, i, 1));
            out = Some(match out {
                Some(o) => o + c,
                None => c,
            });
        }
        out.expect("at least one level of indices")
    }
}
