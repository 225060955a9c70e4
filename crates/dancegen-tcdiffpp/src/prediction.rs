//! What the decoder's last layer predicts, and how x̂0 is formed from it.
//!
//! The paper (and EDGE) predict x̂0 directly: the network's output is the clean window. Ours
//! never learned to read its noisy input that way: at any noise level it returned a
//! music-conditioned mean pose, so two noises gave the same dance (docs/group-collapse.md §1,
//! §11: trained longer, every variant drifted back to the mean).
//!
//! [`Prediction::Velocity`] is our option, not the paper's: the v-parameterisation of
//! Salimans & Ho (2022, "Progressive distillation", §4), `x̂0 = √ᾱ_t · x_t − √(1 − ᾱ_t) · v̂`.
//! The noisy input reaches x̂0 through a fixed skip of weight `√ᾱ_t`, so at low and middle
//! noise the sample's own trajectory (and with it the noise that made it) is carried into the
//! result instead of having to be learned; the network only corrects it. At the highest noise
//! (`ᾱ ≈ 0`) x̂0 is the network's output alone, as before.
//!
//! Sign convention: the network outputs `−v̂`, so that at `t = T − 1` its output means x̂0 as
//! an x0-predictor's does and a trained x0 network can warm-start this one.
//!
//! [`Prediction::LearnedSkip`] is our option too: x̂0 is the network's output plus `g(t) ⊙ x_t`,
//! a per-channel gate of the noise level learned from the timestep features ([`SkipGate`]).
//! It starts at zero, so a trained x0 network warm-starts it unchanged, and it learns from the
//! data how much of the input to carry at each level: near 1 where the input is nearly clean
//! (the copy the x0 network learned too slowly, docs/group-collapse.md §15), less in the
//! middle, where v's fixed `√ᾱ` carried the noise into the dance (§12, §14).
//!
//! Channels the decoder already builds from its own path (the integrated root x/y,
//! [`crate::root_path`]) take no skip: their per-frame noise is what that path keeps out.

use dancegen_nn::burn;
use dancegen_nn::diffusion::Schedule;
use dancegen_nn::edge151::{DIMS, ROOT_HORIZONTAL};

use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};

/// See the module documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Prediction {
    /// The paper's: the output is x̂0.
    #[default]
    X0,
    /// Ours: the output is `−v̂`, `x̂0 = √ᾱ x_t + √(1 − ᾱ) · output`.
    #[serde(rename = "v")]
    Velocity,
    /// Ours: x̂0 = output + `g(t) ⊙ x_t`, the gate learned ([`SkipGate`]).
    #[serde(rename = "x0_skip")]
    LearnedSkip,
}

/// The learned gate of [`Prediction::LearnedSkip`]: `Linear(time features → 151)`, zero at
/// the start, masked off the channels that take no skip.
#[derive(Module, Debug)]
pub struct SkipGate {
    pub gate: Linear,
    /// 1 where a token channel takes the skip (not the integrated root x/y).
    #[module(skip)]
    skipped: Vec<f32>,
}

impl SkipGate {
    /// `time_dims`: the width of the timestep features it reads.
    pub fn new(time_dims: usize, root_integrated: bool, device: &Device) -> Self {
        Self {
            gate: LinearConfig::new(time_dims, DIMS)
                .with_initializer(Initializer::Zeros)
                .init(device),
            skipped: (0..DIMS)
                .map(|c| f32::from(u8::from(!(root_integrated && ROOT_HORIZONTAL.contains(&c)))))
                .collect(),
        }
    }

    /// x̂0 tokens `[B, K, 151]` from the output tokens, the input tokens `x_t` and the
    /// timestep features `[B, time_dims]` of the batch.
    pub fn apply(&self, out: Tensor<3>, x_t: Tensor<3>, time: Tensor<2>) -> Tensor<3> {
        let [b, _, c] = out.dims();
        debug_assert_eq!(c, DIMS);
        let mask = Tensor::<3>::from_data(
            TensorData::new(self.skipped.clone(), [1, 1, c]),
            &out.device(),
        );
        let g = self.gate.forward(time).reshape([b, 1, c]) * mask;
        out + x_t * g
    }
}

/// The skip coefficients of [`Prediction::Velocity`] for the model's schedule.
#[derive(Clone, Debug)]
pub struct VelocitySkip {
    /// `√ᾱ_t` per 0-based timestep.
    sqrt_ac: Vec<f64>,
    /// Whether a token channel takes the skip (not the integrated root x/y).
    skipped: Vec<bool>,
}

impl VelocitySkip {
    /// For EDGE's schedule (the one every group model trains and samples with).
    pub fn new(root_integrated: bool) -> Self {
        let schedule = Schedule::edge();
        Self {
            sqrt_ac: schedule.sqrt_alphas_cumprod,
            skipped: (0..DIMS)
                .map(|c| !(root_integrated && ROOT_HORIZONTAL.contains(&c)))
                .collect(),
        }
    }

    /// x̂0 tokens `[B, K, 151]` from the network's output tokens and the input tokens `x_t`,
    /// for the batch's timesteps `t` (`[B]`, 0-based, as f32).
    pub fn apply(&self, out: Tensor<3>, x_t: Tensor<3>, t: &[f32]) -> Tensor<3> {
        let [b, _, c] = out.dims();
        debug_assert_eq!(c, DIMS);
        let device = out.device();
        let (mut skip, mut keep) = (Vec::with_capacity(b * c), Vec::with_capacity(b * c));
        for &step in t {
            let i = (step.round().max(0.0) as usize).min(self.sqrt_ac.len() - 1);
            let a = self.sqrt_ac[i];
            let s = (1.0 - a * a).max(0.0).sqrt();
            for &skipped in &self.skipped {
                let (k, o) = if skipped { (a, s) } else { (0.0, 1.0) };
                skip.push(k as f32);
                keep.push(o as f32);
            }
        }
        let coef = |v: Vec<f32>, device: &Device| {
            Tensor::<3>::from_data(TensorData::new(v, [b, 1, c]), device)
        };
        out * coef(keep, &device) + x_t * coef(skip, &device)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tensor(v: Vec<f32>, shape: [usize; 3]) -> Tensor<3> {
        Tensor::from_data(TensorData::new(v, shape), &dancegen_nn::device::inference())
    }

    fn host(x: Tensor<3>) -> Vec<f32> {
        x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn the_highest_noise_is_the_output_and_the_lowest_the_input() {
        let skip = VelocitySkip::new(true);
        let out = tensor(vec![2.0; 2 * DIMS], [2, 1, DIMS]);
        let x_t = tensor(vec![-1.0; 2 * DIMS], [2, 1, DIMS]);
        let x0 = host(skip.apply(out, x_t, &[999.0, 0.0]));
        // t = T − 1: ᾱ ≈ 0 (β clipped at 0.999), x̂0 = output.
        assert!(
            x0[..DIMS].iter().all(|&v| (v - 2.0).abs() < 1e-2),
            "{:?}",
            &x0[..4]
        );
        // t = 0: ᾱ ≈ 1, x̂0 ≈ x_t, except the integrated root, which is the output.
        for (c, &v) in x0[DIMS..].iter().enumerate() {
            let want = if ROOT_HORIZONTAL.contains(&c) {
                2.0
            } else {
                -1.0
            };
            assert!((v - want).abs() < 0.05, "channel {c}: {v} against {want}");
        }
    }

    #[test]
    fn a_fresh_gate_is_the_x0_network_and_the_integrated_root_takes_no_skip() {
        let dev = dancegen_nn::device::inference();
        let out = tensor(vec![2.0; 2 * DIMS], [2, 1, DIMS]);
        let x_t = tensor(vec![-1.0; 2 * DIMS], [2, 1, DIMS]);
        let time = Tensor::<2>::ones([2, 8], &dev);
        let fresh = SkipGate::new(8, true, &dev);
        assert!(
            host(fresh.apply(out.clone(), x_t.clone(), time.clone()))
                .iter()
                .all(|&v| v == 2.0)
        );
        // A gate of 1 everywhere (bias 1): x̂0 = output + x_t, except the integrated root.
        let mut open = SkipGate::new(8, true, &dev);
        open.gate.bias = Some(burn::module::Param::from_tensor(Tensor::ones([DIMS], &dev)));
        let got = host(open.apply(out, x_t, time));
        for (i, &v) in got.iter().enumerate() {
            let want = if ROOT_HORIZONTAL.contains(&(i % DIMS)) {
                2.0
            } else {
                1.0
            };
            assert_eq!(v, want, "channel {}", i % DIMS);
        }
    }

    #[test]
    fn the_combination_reconstructs_x0_from_the_true_velocity() {
        // x_t = √ᾱ x0 + √(1−ᾱ) ε and −v = √(1−ᾱ) x0 − √ᾱ ε give back x0 exactly.
        let skip = VelocitySkip::new(false);
        let s = Schedule::edge();
        let t = 400usize;
        let (a, o) = (s.sqrt_alphas_cumprod[t], s.sqrt_one_minus_alphas_cumprod[t]);
        let x0: Vec<f32> = (0..DIMS).map(|c| (c as f32 * 0.37).sin()).collect();
        let eps: Vec<f32> = (0..DIMS).map(|c| (c as f32 * 1.3).cos()).collect();
        let x_t: Vec<f32> = x0
            .iter()
            .zip(&eps)
            .map(|(x, e)| (a * *x as f64 + o * *e as f64) as f32)
            .collect();
        let neg_v: Vec<f32> = x0
            .iter()
            .zip(&eps)
            .map(|(x, e)| (o * *x as f64 - a * *e as f64) as f32)
            .collect();
        let got = host(skip.apply(
            tensor(neg_v, [1, 1, DIMS]),
            tensor(x_t, [1, 1, DIMS]),
            &[t as f32],
        ));
        for (g, w) in got.iter().zip(&x0) {
            assert!((g - w).abs() < 1e-4, "{g} against {w}");
        }
    }
}
