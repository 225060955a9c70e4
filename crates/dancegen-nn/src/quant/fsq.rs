//! Finite scalar quantization (Mentzer, Minnen, Agustsson, Tschannen 2023, "Finite Scalar
//! Quantization: VQ-VAE Made Simple", appendix code; as in `lucidrains/vector-quantize-pytorch`
//! `FSQ`).
//!
//! For `L_i` levels in dimension `i`:
//! - bound: `half = (L − 1)(1 + ε)/2` (ε = 1e−3), `offset = 0.5` for even `L` else 0,
//!   `shift = atanh(offset / half)`, `bound(z) = tanh(z + shift)·half − offset`;
//! - quantize: `round_ste(bound(z)) / ⌊L/2⌋` — codes normalised to `[−1, 1]`, rounding
//!   straight-through (`z + sg(round(z) − z)`, round half to even as `torch.round`);
//! - index: `Σ_i (ẑ_i·⌊L_i/2⌋ + ⌊L_i/2⌋)·basis_i` with `basis = cumprod([1, L_0, …])`, and back
//!   `((idx // basis) % L − ⌊L/2⌋) / ⌊L/2⌋`.
//!
//! With [`FsqConfig::dim`] different from the number of levels, `project_in`/`project_out`
//! Linears map the latent to and from the FSQ dimensions (vector-quantize-pytorch). No
//! commitment loss (zero) and no training-only behaviour. Indices `[B, T, 1]`.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

use super::QuantOutput;

/// Configuration of [`Fsq`].
#[derive(Config, Debug)]
pub struct FsqConfig {
    /// Levels per dimension, e.g. `[8, 5, 5, 5]` (FSQ paper: ~2^10 codes).
    pub levels: Vec<usize>,
    /// Latent width if it differs from `levels.len()` (adds in/out projections).
    #[config(default = "None")]
    pub dim: Option<usize>,
}

impl FsqConfig {
    /// Latent width the quantizer takes.
    pub fn input_dim(&self) -> usize {
        self.dim.unwrap_or(self.levels.len())
    }

    /// Number of distinct codes `Π L_i`.
    pub fn codebook_size(&self) -> usize {
        self.levels.iter().product()
    }

    pub fn init(&self, device: &Device) -> Fsq {
        let n = self.levels.len();
        let proj = self.dim.filter(|&d| d != n);
        Fsq {
            project_in: proj.map(|d| LinearConfig::new(d, n).init(device)),
            project_out: proj.map(|d| LinearConfig::new(n, d).init(device)),
            levels: self.levels.clone(),
        }
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct Fsq {
    pub project_in: Option<Linear>,
    pub project_out: Option<Linear>,
    #[module(skip)]
    pub levels: Vec<usize>,
}

fn row(v: &[f64], device: &Device) -> Tensor<3> {
    let data: Vec<f32> = v.iter().map(|&x| x as f32).collect();
    Tensor::<1>::from_data(TensorData::new(data, [v.len()]), device).reshape([1, 1, v.len()])
}

/// `z + sg(round(z) − z)`.
pub fn round_ste<const D: usize>(z: Tensor<D>) -> Tensor<D> {
    z.clone() + (z.clone().round() - z).detach()
}

impl Fsq {
    pub fn codebook_size(&self) -> usize {
        self.levels.iter().product()
    }

    fn half_width(&self) -> Vec<f64> {
        self.levels.iter().map(|&l| (l / 2) as f64).collect()
    }

    fn basis(&self) -> Vec<i64> {
        let mut b = Vec::with_capacity(self.levels.len());
        let mut acc = 1i64;
        for &l in &self.levels {
            b.push(acc);
            acc *= l as i64;
        }
        b
    }

    /// `bound(z)` on `[B, T, n]`.
    pub fn bound(&self, z: Tensor<3>) -> Tensor<3> {
        let eps = 1e-3;
        let device = z.device();
        let half: Vec<f64> = self
            .levels
            .iter()
            .map(|&l| (l as f64 - 1.0) * (1.0 + eps) / 2.0)
            .collect();
        let offset: Vec<f64> = self
            .levels
            .iter()
            .map(|&l| if l % 2 == 0 { 0.5 } else { 0.0 })
            .collect();
        let shift: Vec<f64> = offset
            .iter()
            .zip(&half)
            .map(|(o, h)| (o / h).atanh())
            .collect();
        (z + row(&shift, &device)).tanh() * row(&half, &device) - row(&offset, &device)
    }

    /// Normalised codes `[B, T, n]` in `[−1, 1]`, straight-through.
    pub fn quantize(&self, z: Tensor<3>) -> Tensor<3> {
        let device = z.device();
        round_ste(self.bound(z)) / row(&self.half_width(), &device)
    }

    /// Normalised codes `[B, T, n]` → indices `[B, T, 1]`.
    pub fn codes_to_indices(&self, codes: Tensor<3>) -> Tensor<3, Int> {
        let device = codes.device();
        let hw = row(&self.half_width(), &device);
        let basis: Vec<f64> = self.basis().iter().map(|&b| b as f64).collect();
        let shifted = (codes.detach() * hw.clone() + hw).round();
        (shifted * row(&basis, &device)).sum_dim(2).round().int()
    }

    /// Indices `[B, T, 1]` → normalised codes `[B, T, n]`.
    pub fn indices_to_codes(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let [b, t, _] = indices.dims();
        let n = self.levels.len();
        let device = indices.device();
        let ints = |v: Vec<i64>| {
            Tensor::<1, Int>::from_data(TensorData::new(v, [n]), &device)
                .reshape([1, 1, n])
                .expand([b, t, n])
        };
        let basis = ints(self.basis());
        let levels = ints(self.levels.iter().map(|&l| l as i64).collect());
        let idx = indices.expand([b, t, n]);
        let nc = (idx / basis).remainder(levels).float();
        let hw = row(&self.half_width(), &device);
        (nc - hw.clone()) / hw
    }

    /// `[B, T, dim]` → [`QuantOutput`] with indices `[B, T, 1]`.
    pub fn forward(&self, x: Tensor<3>) -> QuantOutput {
        let device = x.device();
        let z = match &self.project_in {
            Some(p) => p.forward(x),
            None => x,
        };
        let codes = self.quantize(z);
        let indices = self.codes_to_indices(codes.clone());
        let out = match &self.project_out {
            Some(p) => p.forward(codes),
            None => codes,
        };
        QuantOutput {
            quantized: out.clone(),
            indices,
            commit_loss: Tensor::zeros([1], &device),
            perplexity: None,
            levels: vec![out],
        }
    }

    /// Indices `[B, T, 1]` → quantized latents `[B, T, dim]` (after `project_out`).
    pub fn decode_indices(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let codes = self.indices_to_codes(indices);
        match &self.project_out {
            Some(p) => p.forward(codes),
            None => codes,
        }
    }
}
