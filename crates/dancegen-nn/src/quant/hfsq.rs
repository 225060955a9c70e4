//! Grouped hierarchical residual FSQ (ReactDance, arXiv 2505.05589, section "HFSQ"; an earlier
//! version calls it GRFSQ; anchors D.5 — the paper has no code, so the FSQ levels, group count
//! and masking probabilities are configuration, not published constants).
//!
//! The latent `[B, T, D]` is split into `G` groups of `n = D/G` channels. Each group is
//! quantized by `R` residual FSQ levels ([`super::fsq`], the same `levels` for all):
//! `e_{g,0} = x_g`, `v̂_{g,r} = FSQ(e_{g,r} / s_r)`, `e_{g,r+1} = e_{g,r} − s_r·sg(v̂_{g,r})` with
//! `s_r = (L − 1)^{−r}` per dimension (residual FSQ's scales, `lucidrains/vector-quantize-pytorch`
//! `ResidualFSQ`). Level `r`'s output is `[s_r·v̂_{0,r} | … | s_r·v̂_{G−1,r}]`
//! ([`QuantOutput::levels`]) and the quantized latent is their sum.
//!
//! Training only (autodiff input), as regularisers for the latent diffusion that follows:
//! - residual masking, with probability [`HfsqConfig::residual_mask_prob`]: a level `k ∈ [1, R)`
//!   is drawn and levels `≥ k` are zeroed, and Gaussian noise of std
//!   [`HfsqConfig::residual_noise_std`] is added to the base level;
//! - code masking: each dimension of each level's code is zeroed with probability
//!   [`HfsqConfig::code_mask_prob`].
//!
//! Indices `[B, T, G·R]`, entry `g·R + r` = FSQ index of group `g`, level `r`. No commitment loss.

use burn::config::Config;
use burn::module::Module;
use burn::tensor::{Device, Distribution, Int, Tensor, TensorData};

use super::fsq::{Fsq, FsqConfig};
use super::{QuantOutput, is_training, uniform};

/// Configuration of [`Hfsq`].
#[derive(Config, Debug)]
pub struct HfsqConfig {
    /// Latent width `D` (a multiple of `groups`, `D / groups = levels.len()`).
    pub dim: usize,
    /// FSQ levels of each group's dimensions.
    pub levels: Vec<usize>,
    /// Groups `G`.
    #[config(default = 1)]
    pub groups: usize,
    /// Residual levels `R`.
    #[config(default = 2)]
    pub num_levels: usize,
    #[config(default = 0.0)]
    pub residual_mask_prob: f64,
    #[config(default = 0.0)]
    pub residual_noise_std: f64,
    #[config(default = 0.0)]
    pub code_mask_prob: f64,
}

impl HfsqConfig {
    pub fn init(&self, device: &Device) -> Hfsq {
        assert_eq!(
            self.dim,
            self.groups * self.levels.len(),
            "HFSQ: dim must be groups × levels.len()"
        );
        Hfsq {
            fsq: FsqConfig::new(self.levels.clone()).init(device),
            groups: self.groups,
            num_levels: self.num_levels,
            residual_mask_prob: self.residual_mask_prob,
            residual_noise_std: self.residual_noise_std,
            code_mask_prob: self.code_mask_prob,
        }
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct Hfsq {
    pub fsq: Fsq,
    #[module(skip)]
    pub groups: usize,
    #[module(skip)]
    pub num_levels: usize,
    #[module(skip)]
    pub residual_mask_prob: f64,
    #[module(skip)]
    pub residual_noise_std: f64,
    #[module(skip)]
    pub code_mask_prob: f64,
}

impl Hfsq {
    /// `s_r` as a `[1, 1, n]` row (one group's dimensions).
    pub fn scale(&self, r: usize, device: &Device) -> Tensor<3> {
        let n = self.fsq.levels.len();
        let v: Vec<f32> = self
            .fsq
            .levels
            .iter()
            .map(|&l| ((l as f64 - 1.0).powi(-(r as i32))) as f32)
            .collect();
        Tensor::<1>::from_data(TensorData::new(v, [n]), device).reshape([1, 1, n])
    }

    /// `s_r` as a `[1, 1, D]` row (every group).
    pub fn level_scale(&self, r: usize, device: &Device) -> Tensor<3> {
        Tensor::cat(vec![self.scale(r, device); self.groups], 2)
    }

    /// The `R` level outputs `s_r·v̂_r` `[B, T, D]` and the indices `[B, T, G·R]`, without the
    /// training-time masking.
    pub fn residual_levels(&self, x: Tensor<3>) -> (Vec<Tensor<3>>, Tensor<3, Int>) {
        let d = x.dims()[2];
        let device = x.device();
        let n = d / self.groups;
        let mut level_parts: Vec<Vec<Tensor<3>>> = vec![Vec::new(); self.num_levels];
        let mut indices = Vec::with_capacity(self.groups * self.num_levels);
        for g in 0..self.groups {
            let mut e = x.clone().narrow(2, g * n, n);
            for (r, parts) in level_parts.iter_mut().enumerate() {
                let s = self.scale(r, &device);
                let v = self.fsq.quantize(e.clone() / s.clone());
                indices.push(self.fsq.codes_to_indices(v.clone()));
                let c = v * s;
                e = e - c.clone().detach();
                parts.push(c);
            }
        }
        let levels = level_parts.into_iter().map(|p| Tensor::cat(p, 2)).collect();
        (levels, Tensor::cat(indices, 2))
    }

    /// Progressive masking of level outputs (see the module documentation); a no-op unless
    /// `levels` live on an autodiff device.
    pub fn mask_levels(&self, mut levels: Vec<Tensor<3>>) -> Vec<Tensor<3>> {
        let Some(first) = levels.first() else {
            return levels;
        };
        if !is_training(first) {
            return levels;
        }
        let device = first.device();
        let dims = first.dims();
        if self.num_levels > 1
            && self.residual_mask_prob > 0.0
            && uniform(&device) < self.residual_mask_prob
        {
            let span = self.num_levels - 1;
            let k = 1 + ((uniform(&device) * span as f64) as usize).min(span - 1);
            for l in levels.iter_mut().skip(k) {
                *l = l.zeros_like();
            }
            if self.residual_noise_std > 0.0 {
                let noise = Tensor::<3>::random(
                    dims,
                    Distribution::Normal(0.0, self.residual_noise_std),
                    &device,
                );
                levels[0] = levels[0].clone() + noise;
            }
        }
        if self.code_mask_prob > 0.0 {
            for l in levels.iter_mut() {
                let drop = Tensor::<3>::random(dims, Distribution::Uniform(0.0, 1.0), &device)
                    .lower_elem(self.code_mask_prob);
                *l = l.clone().mask_fill(drop, 0.0);
            }
        }
        levels
    }

    /// `[B, T, D]` → [`QuantOutput`] (indices `[B, T, G·R]`, `levels` = the `R` level outputs).
    pub fn forward(&self, x: Tensor<3>) -> QuantOutput {
        let device = x.device();
        let (levels, indices) = self.residual_levels(x);
        let levels = self.mask_levels(levels);
        let quantized = levels
            .iter()
            .cloned()
            .reduce(|a, c| a + c)
            .expect("at least one level");
        QuantOutput {
            quantized,
            indices,
            commit_loss: Tensor::zeros([1], &device),
            perplexity: None,
            levels,
        }
    }

    /// Indices `[B, T, G·R']` (`R' ≤ R` levels per group: `G·R'` columns, group-major) →
    /// quantized latent `[B, T, D]` (sum of the given levels).
    pub fn decode_indices(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let device = indices.device();
        let rl = indices.dims()[2] / self.groups;
        let groups: Vec<Tensor<3>> = (0..self.groups)
            .map(|g| {
                (0..rl)
                    .map(|r| {
                        let idx = indices.clone().narrow(2, g * rl + r, 1);
                        self.fsq.indices_to_codes(idx) * self.scale(r, &device)
                    })
                    .reduce(|a, c| a + c)
                    .expect("at least one level")
            })
            .collect();
        Tensor::cat(groups, 2)
    }
}
