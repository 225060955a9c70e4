//! Footwork Adaptor (paper §4.2, Eq. 9–11): the lower body is regenerated from the raw
//! prediction under the control of the root's own velocity, so feet move with the travel.
//!
//! Released form (group.md §1 row 7, anchors D.4): three ConcatSquashLinear layers
//! `151 → h → h → 151` with leaky ReLU between them; `CSL(x, c) = W x ⊙ σ(G c) + B c`; the
//! context `c` is the per-frame root displacement (Z-up x/y, the first frame 0), taken from
//! the raw prediction; the adaptor's output replaces the 6D rotations of joints
//! [`LOWER_BODY`] only, so root, contacts and upper body stay the decoder's. It runs inside the
//! denoiser, on x̂0 at every step.
//!
//! Our option ([`crate::config::DenoiserConfig::footwork_residual`]): the adaptor's output is
//! added to the decoder's lower-body rotations instead of replacing them, and its last layer
//! starts at zero, so it begins as the identity and learns a correction.

use dancegen_nn::burn;
use dancegen_nn::edge151::{DIMS, ROOT_HORIZONTAL, rot6d};

use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::activation::leaky_relu;
use burn::tensor::{Device, Tensor, TensorData};

use crate::layout::N_MAX;
use dancegen_nn::{host_linear, vector_math};

/// SMPL joints whose rotations the adaptor replaces (released `model.py`: hips, spine1, knees,
/// ankles, feet; the pelvis orientation is not among them).
pub const LOWER_BODY: [usize; 9] = [1, 2, 3, 4, 5, 7, 8, 10, 11];
/// Slope of the leaky ReLUs (PyTorch's default, as in the released adaptor).
pub const LEAKY_SLOPE: f64 = 0.01;
/// Width of the context: root displacement x/y.
pub const CONTEXT_DIMS: usize = 2;

/// `W x ⊙ σ(G c) + B c` (Luo & Hu 2021, `ConcatSquashLinear`).
#[derive(Module, Debug)]
pub struct ConcatSquashLinear {
    pub layer: Linear,
    pub hyper_gate: Linear,
    pub hyper_bias: Linear,
}

impl ConcatSquashLinear {
    pub fn new(d_in: usize, d_out: usize, d_ctx: usize, device: &Device) -> Self {
        Self {
            layer: LinearConfig::new(d_in, d_out).init(device),
            hyper_gate: LinearConfig::new(d_ctx, d_out).init(device),
            hyper_bias: LinearConfig::new(d_ctx, d_out)
                .with_bias(false)
                .init(device),
        }
    }

    /// A layer whose output starts at zero (its `W` and `B` are zero; the gate is not).
    pub fn silent(d_in: usize, d_out: usize, d_ctx: usize, device: &Device) -> Self {
        Self {
            layer: LinearConfig::new(d_in, d_out)
                .with_initializer(Initializer::Zeros)
                .init(device),
            hyper_gate: LinearConfig::new(d_ctx, d_out).init(device),
            hyper_bias: LinearConfig::new(d_ctx, d_out)
                .with_bias(false)
                .with_initializer(Initializer::Zeros)
                .init(device),
        }
    }

    pub fn forward(&self, x: Tensor<3>, ctx: Tensor<3>) -> Tensor<3> {
        let gate = vector_math::sigmoid_tensor(host_linear::forward(&self.hyper_gate, ctx.clone()));
        host_linear::forward(&self.layer, x) * gate + host_linear::forward(&self.hyper_bias, ctx)
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct FootworkAdaptor {
    pub csl1: ConcatSquashLinear,
    pub csl2: ConcatSquashLinear,
    pub csl3: ConcatSquashLinear,
    /// `x + FA(x)` on the lower body instead of `FA(x)`.
    #[module(skip)]
    pub residual: bool,
}

/// Channels of the replaced rotations.
pub fn lower_body_channels() -> Vec<usize> {
    LOWER_BODY
        .iter()
        .flat_map(|&j| (0..6).map(move |k| rot6d(j, k)))
        .collect()
}

impl FootworkAdaptor {
    pub fn new(hidden: usize, residual: bool, device: &Device) -> Self {
        Self {
            csl1: ConcatSquashLinear::new(DIMS, hidden, CONTEXT_DIMS, device),
            csl2: ConcatSquashLinear::new(hidden, hidden, CONTEXT_DIMS, device),
            csl3: if residual {
                ConcatSquashLinear::silent(hidden, DIMS, CONTEXT_DIMS, device)
            } else {
                ConcatSquashLinear::new(hidden, DIMS, CONTEXT_DIMS, device)
            },
            residual,
        }
    }

    /// Root displacement context `[B, T·N_MAX, 2]` of raw-prediction tokens `[B, T·N_MAX, 151]`
    /// (per dancer along frames; zero at frame 0).
    pub fn context(tokens: Tensor<3>) -> Tensor<3> {
        let [b, k, _] = tokens.dims();
        let t = k / N_MAX;
        let root = tokens.narrow(2, ROOT_HORIZONTAL[0], CONTEXT_DIMS).reshape([
            b,
            t,
            N_MAX * CONTEXT_DIMS,
        ]);
        if t < 2 {
            return Tensor::zeros([b, k, CONTEXT_DIMS], &root.device());
        }
        let d = root.clone().narrow(1, 1, t - 1) - root.clone().narrow(1, 0, t - 1);
        let zero = Tensor::zeros([b, 1, N_MAX * CONTEXT_DIMS], &root.device());
        Tensor::cat(vec![zero, d], 1).reshape([b, k, CONTEXT_DIMS])
    }

    /// The final x̂0 tokens: `raw`'s, with the lower-body rotations the adaptor's (Eq. 11), or
    /// `raw`'s plus the adaptor's when residual.
    pub fn forward(&self, raw: Tensor<3>) -> Tensor<3> {
        let ctx = Self::context(raw.clone());
        let h = leaky_relu(self.csl1.forward(raw.clone(), ctx.clone()), LEAKY_SLOPE);
        let h = leaky_relu(self.csl2.forward(h, ctx.clone()), LEAKY_SLOPE);
        let adapted = self.csl3.forward(h, ctx);
        let [b, k, c] = raw.dims();
        let device = raw.device();
        let mut sel = vec![0f32; c];
        for ch in lower_body_channels() {
            sel[ch] = 1.0;
        }
        let sel = Tensor::<1>::from_data(TensorData::new(sel, [c]), &device)
            .reshape([1, 1, c])
            .expand([b, k, c]);
        if self.residual {
            return raw + adapted * sel;
        }
        let keep = sel.clone().neg() + 1.0;
        raw * keep + adapted * sel
    }
}
