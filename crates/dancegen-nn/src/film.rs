//! FiLM conditioning (EDGE `DenseFiLM` + `featurewise_affine`): a conditioning vector `c` gives
//! per-channel `(scale, shift)` = chunks of `Linear(Mish(c))`, applied as `(scale + 1)·x + shift`
//! to every frame. EDGE/Lodge condition on one vector per sequence (timestep + pooled music,
//! `[B, 1, d]`); ReactDance injects the music this way frame by frame (`[B, T, d]`).

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::Tensor;

/// Configuration of [`Film`].
#[derive(Config, Debug)]
pub struct FilmConfig {
    /// Width of the conditioning vector and of the modulated features.
    pub d: usize,
}

/// `DenseFiLM`: `linear` maps `Mish(c)` `[B, d]` to `[B, 2d]` = (scale, shift).
#[derive(Module, Debug)]
pub struct Film {
    pub linear: Linear,
}

impl FilmConfig {
    pub fn init(&self, device: &burn::tensor::Device) -> Film {
        Film {
            linear: LinearConfig::new(self.d, 2 * self.d).init(device),
        }
    }
}

impl Film {
    /// `(scale, shift)`, each shaped like `cond`: `[B, 1, d]` (one vector per sequence) or
    /// `[B, T, d]` (one per frame).
    pub fn scale_shift(&self, cond: Tensor<3>) -> (Tensor<3>, Tensor<3>) {
        let m = crate::vector_math::mish_tensor(cond);
        let ss = self.linear.forward(m);
        let d = ss.dims()[2] / 2;
        (ss.clone().narrow(2, 0, d), ss.narrow(2, d, d))
    }

    /// `(scale + 1)·x + shift` for `x` `[B, T, d]` and `cond` `[B, 1, d]` or `[B, T, d]`.
    pub fn modulate(&self, x: Tensor<3>, cond: Tensor<3>) -> Tensor<3> {
        let (scale, shift) = self.scale_shift(cond);
        x * (scale + 1.0) + shift
    }
}
