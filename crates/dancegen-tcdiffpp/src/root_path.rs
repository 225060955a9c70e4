//! Our option ([`crate::config::DenoiserConfig::root_integrated`]), not the paper's: each
//! dancer's root x/y in x̂0 is a path integrated from per-frame steps, placed at the window
//! mean of the decoder's own root output.
//!
//! Why: the paper's decoder predicts the root position of every frame independently. Ours,
//! once it reads its input (the residual fusion), passes that input's noise into the root, and
//! the dancers jump up to 2–3 m between frames; the released `dis_loss` stops the jumps only by
//! making the network stop reading its input (docs/group-collapse.md §9–10). Here a frame's
//! noise moves the path by one small step, not by a jump: the step head is scaled by
//! [`STEP_SCALE`] and the placement is a mean over the window's frames, so per-frame noise
//! averages out of it.
//!
//! `root[t] = mean_τ(p[τ]) + S[t] − mean_τ(S[τ])`, `S[t] = Σ_{τ ≤ t} STEP_SCALE · v[τ]`, where
//! `p` is the decoder's root output and `v` a linear head on the last hidden state. The head
//! starts at zero, so an untrained head gives each dancer a still root at the mean.

use dancegen_nn::burn;
use dancegen_nn::edge151::{DIMS, ROOT_HORIZONTAL};

use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::{Device, Tensor, TensorData};

use crate::layout::N_MAX;
use dancegen_nn::host_linear;

/// Normalised root units per unit of the step head. A real dancer's root moves about 1–3 cm
/// a frame, 0.01–0.05 of the root's standard deviation in the group set, so the head's
/// outputs are of order one.
pub const STEP_SCALE: f64 = 0.05;

/// See the module documentation.
#[derive(Module, Debug)]
pub struct RootPath {
    pub step: Linear,
}

impl RootPath {
    pub fn new(d_model: usize, device: &Device) -> Self {
        Self {
            step: LinearConfig::new(d_model, ROOT_HORIZONTAL.len())
                .with_initializer(Initializer::Zeros)
                .init(device),
        }
    }

    /// `raw` tokens `[B, T·N_MAX, 151]` with their root x/y replaced by the integrated path;
    /// `hidden` is the last decoder state `[B, T·N_MAX, d]` of the same tokens.
    pub fn forward(&self, raw: Tensor<3>, hidden: Tensor<3>) -> Tensor<3> {
        let [b, k, _] = raw.dims();
        let t = k / N_MAX;
        let w = N_MAX * ROOT_HORIZONTAL.len();
        let device = raw.device();
        let placed = raw
            .clone()
            .narrow(2, ROOT_HORIZONTAL[0], ROOT_HORIZONTAL.len())
            .reshape([b, t, w])
            .mean_dim(1);
        let steps = (host_linear::forward(&self.step, hidden) * STEP_SCALE).reshape([b, t, w]);
        let summed = cumulative_sum(t, &device).expand([b, t, t]).matmul(steps);
        let path =
            (summed.clone() - summed.mean_dim(1) + placed).reshape([b, k, ROOT_HORIZONTAL.len()]);
        let [r0, r1] = [ROOT_HORIZONTAL[0], ROOT_HORIZONTAL[1]];
        debug_assert_eq!(r1, r0 + 1, "the root x/y channels are adjacent");
        Tensor::cat(
            vec![
                raw.clone().narrow(2, 0, r0),
                path,
                raw.narrow(2, r1 + 1, DIMS - r1 - 1),
            ],
            2,
        )
    }
}

/// `[1, T, T]` lower-triangular ones: `L · v` sums `v` over frames `0..=t`.
pub(crate) fn cumulative_sum(t: usize, device: &Device) -> Tensor<3> {
    let mut m = vec![0f32; t * t];
    for i in 0..t {
        m[i * t..i * t + i + 1].fill(1.0);
    }
    Tensor::from_data(TensorData::new(m, [1, t, t]), device)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::module::Param;

    fn tokens(b: usize, t: usize, f: impl Fn(usize, usize, usize) -> f32) -> Tensor<3> {
        let dev = dancegen_nn::device::inference();
        let mut v = Vec::with_capacity(b * t * N_MAX * DIMS);
        for _ in 0..b {
            for fr in 0..t {
                for s in 0..N_MAX {
                    v.extend((0..DIMS).map(|c| f(fr, s, c)));
                }
            }
        }
        Tensor::from_data(TensorData::new(v, [b, t * N_MAX, DIMS]), &dev)
    }

    #[test]
    fn an_untrained_head_places_a_still_root_at_the_mean() {
        let dev = dancegen_nn::device::inference();
        let t = 6;
        // Jittery root: +1, -1, ... around slot-dependent centres; other channels marked.
        let raw = tokens(1, t, |fr, s, c| match c {
            4 => s as f32 + if fr % 2 == 0 { 1.0 } else { -1.0 },
            5 => -(s as f32),
            _ => c as f32 + 0.5,
        });
        let hidden = Tensor::<3>::ones([1, t * N_MAX, 8], &dev);
        let out = RootPath::new(8, &dev)
            .forward(raw, hidden)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        for fr in 0..t {
            for s in 0..N_MAX {
                let tok = &out[(fr * N_MAX + s) * DIMS..(fr * N_MAX + s + 1) * DIMS];
                assert!((tok[4] - s as f32).abs() < 1e-5, "x placed at the mean");
                assert!((tok[5] + s as f32).abs() < 1e-5);
                assert_eq!(tok[3], 3.5, "other channels untouched");
                assert_eq!(tok[6], 6.5);
            }
        }
    }

    #[test]
    fn steps_integrate_into_a_path_centred_on_the_mean() {
        let dev = dancegen_nn::device::inference();
        let t = 5;
        let d = 3;
        let mut head = RootPath::new(d, &dev);
        // The head's x output is 20 × hidden[0] (so STEP_SCALE · 20 = 1 unit a frame).
        let mut w = vec![0f32; d * 2];
        w[0] = 20.0;
        head.step.weight = Param::from_tensor(Tensor::from_data(TensorData::new(w, [d, 2]), &dev));
        let raw = tokens(1, t, |_, _, c| if c == 4 { 7.0 } else { 0.0 });
        let hidden = Tensor::<3>::ones([1, t * N_MAX, d], &dev);
        let out = head
            .forward(raw, hidden)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        let x: Vec<f32> = (0..t).map(|fr| out[fr * N_MAX * DIMS + 4]).collect();
        // Cumulative sums 1..=5, mean 3, placed at 7: 5, 6, 7, 8, 9.
        for (fr, v) in x.iter().enumerate() {
            assert!((v - (5.0 + fr as f32)).abs() < 1e-4, "frame {fr}: {v}");
        }
        let y = out[4 * N_MAX * DIMS + 5];
        assert!(y.abs() < 1e-6, "no y steps: {y}");
    }
}
