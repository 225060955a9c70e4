//! Fusion Projection (paper §4.1, Fig. 3): one MLP over the stacked features of all dancers of
//! a frame, `[B, T, N_MAX · d]`, so the network sees the group at once and can tell dancers
//! apart ("dancer ambiguity").
//!
//! Released shape: `Linear(N·d → h) → ReLU → Linear(h → h) → ReLU → Linear(h → N·d)`, no
//! residual, `h = 2·d` (group.md §1 row 3). The released weights depend on N, so it trains
//! one model per dancer count (P6); here N is fixed at [`N_MAX`] and empty slots are zero on
//! the way in and masked on the way out, so one model serves 2–5 dancers.

use dancegen_nn::burn;

use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

use crate::layout::{N_MAX, from_tokens};
use dancegen_nn::host_linear;

#[derive(Module, Debug)]
pub struct FusionProjection {
    pub linear1: Linear,
    pub linear2: Linear,
    pub linear3: Linear,
}

impl FusionProjection {
    pub fn new(d: usize, hidden: usize, device: &Device) -> Self {
        Self {
            linear1: LinearConfig::new(N_MAX * d, hidden).init(device),
            linear2: LinearConfig::new(hidden, hidden).init(device),
            linear3: LinearConfig::new(hidden, N_MAX * d).init(device),
        }
    }

    /// Tokens `[B, T·N_MAX, d]` with `mask` `[B, T·N_MAX, 1]` (1 on active slots) → the same
    /// shape, empty slots zero.
    pub fn forward(&self, tokens: Tensor<3>, mask: Tensor<3>) -> Tensor<3> {
        let [b, k, d] = tokens.dims();
        let stacked = from_tokens(tokens * mask.clone());
        let h = relu(host_linear::forward(&self.linear1, stacked));
        let h = relu(host_linear::forward(&self.linear2, h));
        host_linear::forward(&self.linear3, h).reshape([b, k, d]) * mask
    }
}
