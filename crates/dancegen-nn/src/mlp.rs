//! Feed-forward blocks and norms.

use crate::host_linear;
use burn::config::Config;
use burn::module::Module;
use burn::nn::{Dropout, DropoutConfig, Linear, LinearConfig};
use burn::tensor::Tensor;
use burn::tensor::activation::{relu, silu};

/// Activation of an [`Mlp`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// Exact (erf) GELU, PyTorch's `F.gelu` default (EDGE, Lodge).
    #[default]
    Gelu,
    Relu,
    Mish,
    Silu,
}

impl Activation {
    pub fn apply<const D: usize>(self, x: Tensor<D>) -> Tensor<D> {
        match self {
            // Burn's erf and Mish are scalar libm; without autodiff the vectorised ones run.
            Activation::Gelu => crate::vector_math::gelu_tensor(x),
            Activation::Relu => relu(x),
            Activation::Mish => crate::vector_math::mish_tensor(x),
            Activation::Silu => silu(x),
        }
    }
}

/// Configuration of [`Mlp`].
#[derive(Config, Debug)]
pub struct MlpConfig {
    pub d_in: usize,
    pub d_hidden: usize,
    pub d_out: usize,
    #[config(default = "Activation::Gelu")]
    pub activation: Activation,
    #[config(default = 0.0)]
    pub dropout: f64,
}

/// `linear2(dropout(act(linear1(x))))` — the Transformer feed-forward block.
#[derive(Module, Debug)]
pub struct Mlp {
    pub linear1: Linear,
    pub linear2: Linear,
    pub dropout: Dropout,
    #[module(skip)]
    pub activation: Activation,
}

impl MlpConfig {
    pub fn init(&self, device: &burn::tensor::Device) -> Mlp {
        Mlp {
            linear1: LinearConfig::new(self.d_in, self.d_hidden).init(device),
            linear2: LinearConfig::new(self.d_hidden, self.d_out).init(device),
            dropout: DropoutConfig::new(self.dropout).init(),
            activation: self.activation,
        }
    }
}

impl Mlp {
    pub fn forward<const D: usize>(&self, x: Tensor<D>) -> Tensor<D> {
        let h = self
            .activation
            .apply(host_linear::forward(&self.linear1, x));
        host_linear::forward(&self.linear2, self.dropout.forward(h))
    }
}
