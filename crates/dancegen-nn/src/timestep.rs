//! Diffusion timestep embedding (EDGE `SinusoidalPosEmb` + `time_mlp`):
//! `emb = [sin(t·ω_i), cos(t·ω_i)]`, `ω_i = exp(−i·ln(10000)/(half − 1))`, `i < half = d/2`,
//! then `Linear(d, 4d)` + Mish. EDGE derives the FiLM vector (`Linear(4d, d)`) and two extra
//! memory tokens (`Linear(4d, 2d)`) from it; those heads belong to the denoiser.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::activation::mish;
use burn::tensor::{Device, Tensor, TensorData};

/// `[B, d]` sinusoidal embedding of (possibly fractional) timesteps.
pub fn sinusoidal_timestep(t: &[f32], d: usize, device: &Device) -> Tensor<2> {
    assert!(
        d.is_multiple_of(2) && d >= 4,
        "timestep embedding width must be even and ≥ 4"
    );
    let half = d / 2;
    let scale = (10000f64).ln() / (half - 1) as f64;
    let mut data = vec![0f32; t.len() * d];
    for (b, &tt) in t.iter().enumerate() {
        for i in 0..half {
            let a = f64::from(tt) * (-(i as f64) * scale).exp();
            data[b * d + i] = a.sin() as f32;
            data[b * d + half + i] = a.cos() as f32;
        }
    }
    Tensor::from_data(TensorData::new(data, [t.len(), d]), device)
}

/// Configuration of [`TimestepMlp`].
#[derive(Config, Debug)]
pub struct TimestepMlpConfig {
    pub d: usize,
}

/// `time_mlp`: sinusoidal embedding → `Linear(d, 4d)` → Mish.
#[derive(Module, Debug)]
pub struct TimestepMlp {
    pub linear: Linear,
    pub d: usize,
}

impl TimestepMlpConfig {
    pub fn init(&self, device: &Device) -> TimestepMlp {
        TimestepMlp {
            linear: LinearConfig::new(self.d, 4 * self.d).init(device),
            d: self.d,
        }
    }
}

impl TimestepMlp {
    /// `[B, 4d]` for timesteps `t`.
    pub fn forward(&self, t: &[f32], device: &Device) -> Tensor<2> {
        mish(self.linear.forward(sinusoidal_timestep(t, self.d, device)))
    }
}
