//! Lodge++'s Primitive-based Dance Diffusion Model (PDDM): a residual-shifting forward process
//! that moves the clean dance `d0` toward the dance primitives `d_p` while adding noise, so
//! sampling starts from the primitives (plus noise) rather than from pure noise.
//!
//! Equations (Lodge++ paper, §3.4.1–3.4.2, eq. 7–15; the process is ResShift's, Yue et al.
//! NeurIPS 2023, the paper's refs [56, 57]), with `d_res = d_p − d0`, `t ∈ 1..=T`:
//! - (7)  `q(d_t | d_{t−1}) = N(d_{t−1} + α_t d_res, κ² α_t I)`, `α_t = η_t − η_{t−1}`
//! - (9)  `q(d_t | d0, d_p) = N(d0 + η_t d_res, κ² η_t I)`, `η_1 → 0`, `η_T → 1`
//!   (so `d_T ≈ N(d_p, κ² I)`)
//! - (13) `q(d_{t−1} | d_t, d0) = N(η_{t−1}/η_t · d_t + α_t/η_t · d0, κ² η_{t−1}/η_t · α_t I)`
//! - (14) the reverse mean replaces `d0` by the network's prediction `f_θ(d_t, d_p, c, t)`;
//!   (15) the loss is `‖f_θ − d0‖²`.
//!
//! Gap: the paper names the hyper-parameters `κ` (noise variance) and `p` (shifting
//! trajectory, "the smaller, the smoother") but gives neither their values nor the η schedule
//! itself. `p` is ResShift's exponent, so [`ResidualShiftConfig`] uses ResShift's schedule
//! `√η_t = √η_1 · b0^{β_t}`, `β_t = ((t − 1)/(T − 1))^p · (T − 1)`,
//! `b0 = exp(ln(η_T/η_1) / (2(T − 1)))`, with ResShift's defaults (κ = 2, p = 0.3,
//! η_1 = min((0.04/κ)², 0.001), η_T = 0.999) and Lodge++'s T = 50 (§4.1). The public Lodge++
//! dump (`q_sample_res`) uses a different, DDPM-table parameterisation; this module follows the
//! paper.

use burn::tensor::{Device, Tensor};

use super::noise::SeededNoise;
use super::schedule::{per_batch, timestep_tensor};
use super::{Conditioning, Denoiser};

/// PDDM diffusion steps (Lodge++ §4.1: "the diffusion time steps are configured to be 50").
pub const LODGEPP_PDDM_STEPS: usize = 50;
/// ResShift's defaults (Yue et al. 2023), used because Lodge++ does not publish its own.
pub const RESSHIFT_KAPPA: f64 = 2.0;
pub const RESSHIFT_P: f64 = 0.3;
pub const RESSHIFT_ETA_T: f64 = 0.999;

/// Hyper-parameters of the residual-shifting schedule.
#[derive(Clone, Debug, PartialEq)]
pub struct ResidualShiftConfig {
    pub steps: usize,
    pub kappa: f64,
    pub p: f64,
    pub eta_1: f64,
    pub eta_t: f64,
}

impl ResidualShiftConfig {
    /// Lodge++'s T = 50 with ResShift's κ, p, η_1, η_T (see the module doc for the gap).
    pub fn lodgepp() -> Self {
        ResidualShiftConfig {
            steps: LODGEPP_PDDM_STEPS,
            kappa: RESSHIFT_KAPPA,
            p: RESSHIFT_P,
            eta_1: (0.04 / RESSHIFT_KAPPA).powi(2).min(1e-3),
            eta_t: RESSHIFT_ETA_T,
        }
    }

    pub fn init(&self) -> ResidualShift {
        let t = self.steps;
        assert!(t >= 2, "PDDM needs at least 2 steps");
        let b0 = ((self.eta_t / self.eta_1).ln() / (2.0 * (t - 1) as f64)).exp();
        let mut eta = vec![0.0; t + 1];
        for (i, e) in eta.iter_mut().enumerate().skip(1) {
            let beta = ((i - 1) as f64 / (t - 1) as f64).powf(self.p) * (t - 1) as f64;
            *e = (self.eta_1.sqrt() * b0.powf(beta)).powi(2);
        }
        ResidualShift::from_etas(eta, self.kappa)
    }
}

/// The η table (index 0..=T, `η_0 = 0`) and κ.
#[derive(Clone, Debug)]
pub struct ResidualShift {
    pub eta: Vec<f64>,
    pub kappa: f64,
}

impl ResidualShift {
    /// From an explicit increasing `η` (`eta[0] = 0`, `eta[T] ≈ 1`).
    pub fn from_etas(eta: Vec<f64>, kappa: f64) -> Self {
        assert!(eta.len() >= 3 && eta[0] == 0.0, "η must start at η_0 = 0");
        assert!(
            eta.windows(2).all(|w| w[1] > w[0]),
            "η must increase strictly"
        );
        ResidualShift { eta, kappa }
    }

    pub fn steps(&self) -> usize {
        self.eta.len() - 1
    }

    /// `α_t = η_t − η_{t−1}`.
    pub fn alpha(&self, t: usize) -> f64 {
        self.eta[t] - self.eta[t - 1]
    }

    /// Eq. (9): `d_t = d0 + η_t (d_p − d0) + κ √η_t · noise`, one `t ∈ 1..=T` per element.
    pub fn q_sample(
        &self,
        d0: Tensor<3>,
        dp: Tensor<3>,
        t: &[usize],
        noise: Tensor<3>,
    ) -> Tensor<3> {
        let dims = d0.dims();
        let dev = d0.device();
        let eta = per_batch(t.iter().map(|&t| self.eta[t]), dims, &dev);
        let sd = per_batch(
            t.iter().map(|&t| self.kappa * self.eta[t].sqrt()),
            dims,
            &dev,
        );
        d0.clone() + (dp - d0) * eta + noise * sd
    }

    /// Eq. (13)/(14): `d_{t−1} = η_{t−1}/η_t d_t + α_t/η_t x̂0 + κ √(η_{t−1} α_t / η_t) z`
    /// (at `t = 1`, `η_0 = 0`, so the step returns x̂0).
    pub fn step(&self, d_t: Tensor<3>, x0: Tensor<3>, t: usize, noise: Tensor<3>) -> Tensor<3> {
        let (e, ep, a) = (self.eta[t], self.eta[t - 1], self.alpha(t));
        if t == 1 {
            return x0;
        }
        d_t * (ep / e) + x0 * (a / e) + noise * (self.kappa * (ep * a / e).sqrt())
    }

    /// The reverse step from `t` straight to any `s < t` (strided sampling): the posterior (13)
    /// with `η_{t−1}` replaced by `η_s` and `α_t` by `η_t − η_s`, exact because the shifted
    /// chain's increments are independent Gaussians. `s = 0` returns x̂0.
    pub fn step_to(
        &self,
        d_t: Tensor<3>,
        x0: Tensor<3>,
        t: usize,
        s: usize,
        noise: Tensor<3>,
    ) -> Tensor<3> {
        assert!(s < t && t <= self.steps(), "PDDM step {t} → {s}");
        if s == 0 {
            return x0;
        }
        let (e, es) = (self.eta[t], self.eta[s]);
        let a = e - es;
        d_t * (es / e) + x0 * (a / e) + noise * (self.kappa * (es * a / e).sqrt())
    }

    /// `n` evenly spaced steps `T = t_0 > t_1 > … > t_{n−1} ≥ 1` (all `T` when `n ≥ T`).
    pub fn strided(&self, n: usize) -> Vec<usize> {
        let big_t = self.steps();
        let n = n.clamp(1, big_t);
        let mut v: Vec<usize> = (0..n)
            .map(|i| big_t - ((i * big_t) as f64 / n as f64).round() as usize)
            .collect();
        v.dedup();
        v
    }

    /// The PDDM loss (15): `t ~ U{1..T}`, `d_t` from (9), `‖f_θ(d_t, ·, t − 1) − d0‖²`. The
    /// primitives reach the network through the system's condition type; the network receives
    /// the 0-based timestep `t − 1`.
    pub fn x0_loss<M: Denoiser>(
        &self,
        model: &M,
        d0: Tensor<3>,
        dp: Tensor<3>,
        cond: Conditioning<'_, M::Cond>,
        rng: &mut SeededNoise,
    ) -> (Tensor<1>, Tensor<3>) {
        let dims = d0.dims();
        let dev = d0.device();
        let t: Vec<usize> = (0..dims[0]).map(|_| 1 + rng.below(self.steps())).collect();
        let d_t = self.q_sample(d0.clone(), dp, &t, rng.tensor(dims, &dev));
        let t0: Vec<usize> = t.iter().map(|t| t - 1).collect();
        let pred = model.predict_x0(d_t, timestep_tensor(&t0, &dev), cond);
        ((pred.clone() - d0).powf_scalar(2.0).mean(), pred)
    }

    /// Samples from `d_T = d_p + κ √η_T z` down to `d_0` with the reverse step; x̂0 is clamped
    /// to `clip` when given. The network sees the 0-based timestep `t − 1`.
    pub fn sample<M: Denoiser>(
        &self,
        model: &M,
        dp: Tensor<3>,
        cond: Option<&M::Cond>,
        clip: Option<(f64, f64)>,
        seed: u64,
        device: &Device,
    ) -> Tensor<3> {
        let dims = dp.dims();
        let mut rng = SeededNoise::new(seed);
        let big_t = self.steps();
        let mut d = dp + rng.tensor(dims, device) * (self.kappa * self.eta[big_t].sqrt());
        for t in (1..=big_t).rev() {
            let tt = timestep_tensor(&vec![t - 1; dims[0]], device);
            let c = match cond {
                Some(c) => Conditioning::Full(c),
                None => Conditioning::Null,
            };
            let mut x0 = model.predict_x0(d.clone(), tt, c);
            if let Some((lo, hi)) = clip {
                x0 = x0.clamp(lo, hi);
            }
            let z = rng.tensor(dims, device);
            d = self.step(d, x0, t, z);
        }
        d
    }
}
