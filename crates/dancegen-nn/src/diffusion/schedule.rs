//! Gaussian diffusion schedules and the x0-prediction training loss.
//!
//! Follows EDGE (`model/utils.py::make_beta_schedule`, `model/diffusion.py`; anchors D.1), which
//! Lodge and TCDiff++ copy: T = 1000, cosine schedule (Nichol & Dhariwal 2021, s = 0.008, β
//! clipped to ≤ 0.999) or the linear one `linspace(√1e−4, √2e−2, T)²`. EDGE stores the tables
//! in float32; here every table is f64 (the coefficients are cast once per step when they
//! multiply a tensor), so schedule values near t = 0 and t = T − 1 keep their precision.

use burn::tensor::{Device, Int, Tensor, TensorData};

use super::noise::SeededNoise;
use super::{Conditioning, Denoiser};

/// EDGE's number of diffusion steps (anchors D.1, Lodge D.2, TCDiff++ D.4).
pub const EDGE_TIMESTEPS: usize = 1000;
/// Offset `s` of the cosine schedule (Nichol & Dhariwal 2021, EDGE `cosine_s`).
pub const COSINE_S: f64 = 8e-3;
/// Upper clip of β in the cosine schedule (Nichol & Dhariwal 2021; EDGE).
pub const COSINE_MAX_BETA: f64 = 0.999;
/// End points of the linear schedule (DDPM, Ho et al. 2020; EDGE `linear_start/linear_end`).
pub const LINEAR_START: f64 = 1e-4;
pub const LINEAR_END: f64 = 2e-2;
/// Lower clamp of the posterior variance before its log (EDGE: the variance is 0 at t = 0).
pub const POSTERIOR_VARIANCE_FLOOR: f64 = 1e-20;
/// EDGE's classifier-free condition dropout probability (anchors D.1; Lodge, TCDiff++ too).
pub const EDGE_COND_DROP: f64 = 0.25;

/// Which β schedule.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BetaSchedule {
    /// `ᾱ(t) = cos²((t/T + s)/(1 + s) · π/2) / ᾱ(0)`, `β_t = min(1 − ᾱ(t+1)/ᾱ(t), 0.999)`.
    Cosine,
    /// `β = linspace(√1e−4, √2e−2, T)²`.
    Linear,
}

/// β and every table derived from it, indexed by the 0-based timestep `t ∈ 0..T`.
#[derive(Clone, Debug)]
pub struct Schedule {
    pub betas: Vec<f64>,
    pub alphas_cumprod: Vec<f64>,
    pub alphas_cumprod_prev: Vec<f64>,
    pub sqrt_alphas_cumprod: Vec<f64>,
    pub sqrt_one_minus_alphas_cumprod: Vec<f64>,
    pub sqrt_recip_alphas_cumprod: Vec<f64>,
    pub sqrt_recipm1_alphas_cumprod: Vec<f64>,
    /// `β_t (1 − ᾱ_{t−1}) / (1 − ᾱ_t)`: variance of q(x_{t−1} | x_t, x0).
    pub posterior_variance: Vec<f64>,
    pub posterior_log_variance_clipped: Vec<f64>,
    /// Posterior mean `= coef1 · x0 + coef2 · x_t`.
    pub posterior_mean_coef1: Vec<f64>,
    pub posterior_mean_coef2: Vec<f64>,
}

impl Schedule {
    /// EDGE's default: cosine, T = 1000.
    pub fn edge() -> Self {
        Self::new(BetaSchedule::Cosine, EDGE_TIMESTEPS)
    }

    pub fn new(kind: BetaSchedule, timesteps: usize) -> Self {
        assert!(
            timesteps >= 2,
            "a diffusion schedule needs at least 2 steps"
        );
        let n = timesteps as f64;
        let betas: Vec<f64> = match kind {
            BetaSchedule::Cosine => {
                let f = |i: usize| {
                    let a =
                        (i as f64 / n + COSINE_S) / (1.0 + COSINE_S) * std::f64::consts::FRAC_PI_2;
                    a.cos().powi(2)
                };
                let f0 = f(0);
                (0..timesteps)
                    .map(|i| (1.0 - (f(i + 1) / f0) / (f(i) / f0)).clamp(0.0, COSINE_MAX_BETA))
                    .collect()
            }
            BetaSchedule::Linear => {
                let (a, b) = (LINEAR_START.sqrt(), LINEAR_END.sqrt());
                (0..timesteps)
                    .map(|i| (a + (b - a) * i as f64 / (n - 1.0)).powi(2))
                    .collect()
            }
        };
        Self::from_betas(betas)
    }

    /// All tables from β (DDPM, Ho et al. 2020, eq. 4, 6, 7).
    pub fn from_betas(betas: Vec<f64>) -> Self {
        let mut alphas_cumprod = Vec::with_capacity(betas.len());
        let mut acc = 1.0;
        for b in &betas {
            acc *= 1.0 - b;
            alphas_cumprod.push(acc);
        }
        let alphas_cumprod_prev: Vec<f64> = std::iter::once(1.0)
            .chain(alphas_cumprod[..betas.len() - 1].iter().copied())
            .collect();
        let map = |f: &dyn Fn(usize) -> f64| (0..betas.len()).map(f).collect::<Vec<f64>>();
        let ac = &alphas_cumprod;
        let acp = &alphas_cumprod_prev;
        let posterior_variance = map(&|t| betas[t] * (1.0 - acp[t]) / (1.0 - ac[t]));
        Schedule {
            sqrt_alphas_cumprod: map(&|t| ac[t].sqrt()),
            sqrt_one_minus_alphas_cumprod: map(&|t| (1.0 - ac[t]).sqrt()),
            sqrt_recip_alphas_cumprod: map(&|t| (1.0 / ac[t]).sqrt()),
            sqrt_recipm1_alphas_cumprod: map(&|t| (1.0 / ac[t] - 1.0).sqrt()),
            posterior_log_variance_clipped: posterior_variance
                .iter()
                .map(|v| v.max(POSTERIOR_VARIANCE_FLOOR).ln())
                .collect(),
            posterior_mean_coef1: map(&|t| betas[t] * acp[t].sqrt() / (1.0 - ac[t])),
            posterior_mean_coef2: map(&|t| {
                (1.0 - acp[t]) * (1.0 - betas[t]).sqrt() / (1.0 - ac[t])
            }),
            posterior_variance,
            alphas_cumprod_prev: alphas_cumprod_prev.clone(),
            alphas_cumprod: alphas_cumprod.clone(),
            betas,
        }
    }

    pub fn timesteps(&self) -> usize {
        self.betas.len()
    }

    /// `q(x_t | x0)`: `√ᾱ_t · x0 + √(1 − ᾱ_t) · noise`, one `t` per batch element.
    pub fn q_sample(&self, x0: Tensor<3>, t: &[usize], noise: Tensor<3>) -> Tensor<3> {
        let dims = x0.dims();
        let device = x0.device();
        let a = per_batch(
            t.iter().map(|&t| self.sqrt_alphas_cumprod[t]),
            dims,
            &device,
        );
        let s = per_batch(
            t.iter().map(|&t| self.sqrt_one_minus_alphas_cumprod[t]),
            dims,
            &device,
        );
        x0 * a + noise * s
    }
}

/// A `[B]` list of per-sample coefficients broadcast to `dims = [B, T, C]`.
pub(crate) fn per_batch(
    values: impl Iterator<Item = f64>,
    dims: [usize; 3],
    device: &Device,
) -> Tensor<3> {
    let v: Vec<f32> = values.map(|v| v as f32).collect();
    assert_eq!(v.len(), dims[0], "one coefficient per batch element");
    Tensor::<3>::from_data(TensorData::new(v, [dims[0], 1, 1]), device).expand(dims)
}

/// `[B]` integer timesteps.
pub(crate) fn timestep_tensor(t: &[usize], device: &Device) -> Tensor<1, Int> {
    let v: Vec<i64> = t.iter().map(|&t| t as i64).collect();
    Tensor::from_data(TensorData::new(v, [t.len()]), device)
}

/// The x0-prediction training loss of EDGE `p_losses` (`L_simple`, L2): for every batch
/// element draw `t ~ U{0..T−1}` and `ε ~ N(0, I)`, noise `x0` with [`Schedule::q_sample`], and
/// compare the denoiser's x̂0 with `x0`. Each element's condition is dropped with probability
/// `cond_drop` (classifier-free guidance training, Ho & Salimans 2022; EDGE 0.25): the denoiser
/// receives [`Conditioning::Dropout`]. Returns `(loss, x̂0)` so a system can add its auxiliary
/// losses (velocity, FK, foot contact) on the same prediction.
pub fn x0_loss<M: Denoiser>(
    model: &M,
    schedule: &Schedule,
    x0: Tensor<3>,
    cond: &M::Cond,
    cond_drop: f64,
    rng: &mut SeededNoise,
) -> (Tensor<1>, Tensor<3>) {
    let dims = x0.dims();
    let device = x0.device();
    let t: Vec<usize> = (0..dims[0])
        .map(|_| rng.below(schedule.timesteps()))
        .collect();
    let keep: Vec<bool> = (0..dims[0]).map(|_| rng.uniform() >= cond_drop).collect();
    let noise = rng.tensor(dims, &device);
    let x_t = schedule.q_sample(x0.clone(), &t, noise);
    let pred = model.predict_x0(
        x_t,
        timestep_tensor(&t, &device),
        Conditioning::Dropout { cond, keep: &keep },
    );
    let loss = (pred.clone() - x0).powf_scalar(2.0).mean();
    (loss, pred)
}
