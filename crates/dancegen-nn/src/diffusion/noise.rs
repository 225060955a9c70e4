//! Seeded Gaussian noise generated on the host.
//!
//! Burn's `Tensor::random` draws from a backend-global generator, so a sample would depend on
//! what else ran before it and on the backend. The sampler instead draws every noise tensor from
//! one [`SeededNoise`] (SplitMix64 + Box–Muller in f64): the same seed gives the same dance on
//! CPU and GPU, and a parity fixture can ship the exact noise it used.

use burn::tensor::{Device, Tensor, TensorData};

use crate::rng::SplitMix64;

/// Gaussian noise from the crate's [`SplitMix64`].
#[derive(Clone, Debug)]
pub struct SeededNoise {
    rng: SplitMix64,
    spare: Option<f64>,
}

impl SeededNoise {
    pub fn new(seed: u64) -> Self {
        SeededNoise {
            rng: SplitMix64(seed),
            spare: None,
        }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.rng.next_u64()
    }

    /// Uniform in the open interval (0, 1).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Uniform integer in `0..n`.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n - 1)
    }

    /// One standard normal draw (Box–Muller, both values used).
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let r = (-2.0 * self.uniform().ln()).sqrt();
        let th = 2.0 * std::f64::consts::PI * self.uniform();
        self.spare = Some(r * th.sin());
        r * th.cos()
    }

    /// A standard normal tensor of `shape`.
    pub fn tensor<const D: usize>(&mut self, shape: [usize; D], device: &Device) -> Tensor<D> {
        let n: usize = shape.iter().product();
        let v: Vec<f32> = (0..n).map(|_| self.normal() as f32).collect();
        Tensor::from_data(TensorData::new(v, shape), device)
    }
}
