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

/// The learned gate of [`Prediction::LearnedSkip`]: x̂0 = output + `Σ_k g_k(t) ⊙ (G_k ∗ x_t)`,
/// where `G_k` smooths each channel along the window's frames with a Gaussian of `σ_k` frames
/// (`σ = 0`: the input itself) and `g_k = Linear(time features → 151)`, zero at the start,
/// masked off the channels that take no skip.
///
/// Why a bank of smoothings: a per-channel scalar gate cannot tell the motion from the noise,
/// which have the same channels; it passes both, and the noise became jitter (v11,
/// docs/group-collapse.md §17). The motion is smooth over frames and the noise is not, so the
/// best linear estimate of x0 from x_t is a low-pass filter whose width grows with the noise
/// level. A learned mix of a few fixed widths lets the gate approach it.
#[derive(Module, Debug)]
pub struct SkipGate {
    pub gate: Linear,
    /// Per smoothing, 1 where a token channel takes it: not the integrated root x/y, and not
    /// the root rotation's 6D channels in the smoothings (σ > 0) when they are kept sharp.
    #[module(skip)]
    skipped: Vec<Vec<f32>>,
    /// `σ_k` in frames.
    #[module(skip)]
    sigmas: Vec<f64>,
}

impl SkipGate {
    /// `time_dims`: the width of the timestep features it reads; `sigmas`: the smoothing
    /// widths in frames (at least one); `smooth_root_rotation`: whether the smoothings
    /// (σ > 0) carry the root rotation's 6D channels too. With them, v12's dancers tipped
    /// over in fast turns under a formation; without them, not (docs/group-collapse.md §20).
    pub fn new(
        time_dims: usize,
        root_integrated: bool,
        sigmas: &[f64],
        smooth_root_rotation: bool,
        device: &Device,
    ) -> Self {
        assert!(
            !sigmas.is_empty(),
            "a skip needs at least one smoothing width"
        );
        let root_rotation =
            dancegen_nn::edge151::rot6d(0, 0)..dancegen_nn::edge151::rot6d(0, 5) + 1;
        Self {
            gate: LinearConfig::new(time_dims, sigmas.len() * DIMS)
                .with_initializer(Initializer::Zeros)
                .init(device),
            skipped: sigmas
                .iter()
                .map(|&sigma| {
                    (0..DIMS)
                        .map(|c| {
                            let integrated = root_integrated && ROOT_HORIZONTAL.contains(&c);
                            let sharp =
                                sigma > 0.0 && !smooth_root_rotation && root_rotation.contains(&c);
                            f32::from(u8::from(!(integrated || sharp)))
                        })
                        .collect()
                })
                .collect(),
            sigmas: sigmas.to_vec(),
        }
    }

    /// x̂0 tokens `[B, T·N, 151]` from the output tokens, the input tokens `x_t` (frame-major,
    /// [`crate::layout`]) and the timestep features `[B, time_dims]` of the batch.
    pub fn apply(&self, out: Tensor<3>, x_t: Tensor<3>, time: Tensor<2>) -> Tensor<3> {
        let [b, k, c] = out.dims();
        debug_assert_eq!(c, DIMS);
        let frames = k / crate::layout::N_MAX;
        let device = out.device();
        let gates = self.gate.forward(time).reshape([b, self.sigmas.len(), c]);
        let window = crate::layout::from_tokens(x_t);
        let mut x0 = out;
        for (i, &sigma) in self.sigmas.iter().enumerate() {
            let smoothed = if sigma > 0.0 {
                let kernel = Tensor::<2>::from_data(
                    TensorData::new(gaussian_rows(frames, sigma), [frames, frames]),
                    &device,
                );
                kernel.unsqueeze::<3>().matmul(window.clone())
            } else {
                window.clone()
            };
            let mask = Tensor::<3>::from_data(
                TensorData::new(self.skipped[i].clone(), [1, 1, c]),
                &device,
            );
            let g = gates.clone().narrow(1, i, 1) * mask;
            x0 = x0 + crate::layout::to_tokens(smoothed) * g;
        }
        x0
    }
}

/// `[frames, frames]` row-major: row `f` holds Gaussian weights of width `sigma` frames around
/// frame `f`, cut at ±3σ and at the window's ends, summing to 1.
pub fn gaussian_rows(frames: usize, sigma: f64) -> Vec<f32> {
    let reach = (3.0 * sigma).ceil() as usize;
    let mut m = vec![0f32; frames * frames];
    for f in 0..frames {
        let (lo, hi) = (f.saturating_sub(reach), (f + reach).min(frames - 1));
        let w: Vec<f64> = (lo..=hi)
            .map(|g| (-((g as f64 - f as f64) / sigma).powi(2) / 2.0).exp())
            .collect();
        let total: f64 = w.iter().sum();
        for (g, wg) in (lo..=hi).zip(w) {
            m[f * frames + g] = (wg / total) as f32;
        }
    }
    m
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
        let k = crate::layout::N_MAX;
        let out = tensor(vec![2.0; 2 * k * DIMS], [2, k, DIMS]);
        let x_t = tensor(vec![-1.0; 2 * k * DIMS], [2, k, DIMS]);
        let time = Tensor::<2>::ones([2, 8], &dev);
        let fresh = SkipGate::new(8, true, &[0.0], true, &dev);
        assert!(
            host(fresh.apply(out.clone(), x_t.clone(), time.clone()))
                .iter()
                .all(|&v| v == 2.0)
        );
        // A gate of 1 everywhere (bias 1): x̂0 = output + x_t, except the integrated root.
        let mut open = SkipGate::new(8, true, &[0.0], true, &dev);
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
    fn a_sharp_root_rotation_takes_only_the_unsmoothed_skip() {
        let dev = dancegen_nn::device::inference();
        let k = crate::layout::N_MAX * 4;
        let out = tensor(vec![2.0; k * DIMS], [1, k, DIMS]);
        let x_t = tensor(vec![-1.0; k * DIMS], [1, k, DIMS]);
        let time = Tensor::<2>::ones([1, 8], &dev);
        for smooth_root_rotation in [true, false] {
            let mut gate = SkipGate::new(8, true, &[0.0, 2.0], smooth_root_rotation, &dev);
            gate.gate.bias = Some(burn::module::Param::from_tensor(Tensor::ones(
                [2 * DIMS],
                &dev,
            )));
            // A constant input is its own smoothing: each skip adds −1 where it is taken.
            let got = host(gate.apply(out.clone(), x_t.clone(), time.clone()));
            let root_rotation =
                dancegen_nn::edge151::rot6d(0, 0)..dancegen_nn::edge151::rot6d(1, 0);
            for (i, &v) in got.iter().enumerate() {
                let c = i % DIMS;
                let want = if ROOT_HORIZONTAL.contains(&c) {
                    2.0
                } else if root_rotation.contains(&c) && !smooth_root_rotation {
                    1.0
                } else {
                    0.0
                };
                assert!((v - want).abs() < 1e-5, "channel {c}: {v} against {want}");
            }
        }
    }

    #[test]
    fn the_smoothings_keep_a_constant_and_damp_frame_to_frame_noise() {
        let frames = 40;
        for sigma in [0.5, 1.0, 2.0, 4.0] {
            let m = gaussian_rows(frames, sigma);
            for f in 0..frames {
                let row = &m[f * frames..(f + 1) * frames];
                assert!(
                    (row.iter().sum::<f32>() - 1.0).abs() < 1e-5,
                    "σ {sigma} row {f}"
                );
            }
        }
        // An alternating ±1 (noise at the frame rate) shrinks with the width; a slow wave
        // (a 2 s period at 30 fps) stays.
        let smoothed_amplitude = |sigma: f64, signal: &dyn Fn(usize) -> f32| {
            let m = gaussian_rows(frames, sigma);
            (10..30)
                .map(|f| {
                    (0..frames)
                        .map(|g| m[f * frames + g] * signal(g))
                        .sum::<f32>()
                        .abs()
                })
                .fold(0f32, f32::max)
        };
        let noise = |g: usize| if g.is_multiple_of(2) { 1.0 } else { -1.0 };
        assert!(smoothed_amplitude(1.0, &noise) < 0.02);
        assert!(smoothed_amplitude(2.0, &noise) < 0.001);
        let slow = |g: usize| (g as f32 * std::f32::consts::TAU / 60.0).sin();
        assert!(smoothed_amplitude(2.0, &slow) > 0.95);
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
