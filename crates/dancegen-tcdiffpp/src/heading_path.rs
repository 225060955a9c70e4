//! Our option ([`crate::config::DenoiserConfig::heading_integrated`]), not the paper's: each
//! dancer's heading (the root rotation's turn about the vertical) in x̂0 is integrated from
//! per-frame turns and placed at the window's mean heading of x̂0, as [`crate::root_path`]
//! does for the root x/y. The rest of the root rotation (its tilt) is x̂0's own.
//!
//! Why: with the learned skip over smoothings of x_t, the root rotation's two 6D rows were
//! averaged across fast turns. Averaging two headings half a turn apart shrinks the rows
//! towards zero; normalising them back (the 6D → matrix Gram–Schmidt) then follows whatever
//! error is left, and the body tipped over (docs/group-collapse.md §20). Taking the root
//! rotation out of the smoothings stopped the tipping but left the heading reading its input's
//! noise: the whole body jittered with it (§20, v13). Here a frame's noise moves the heading by
//! one small turn, not a jump, and the placement is a circular mean over the window's frames.
//!
//! `heading[t] = ∠ mean_τ(h[τ]) + Φ[t] − mean_τ(Φ[τ])`, `Φ[t] = Σ_{τ ≤ t} TURN_SCALE · ω[τ]`,
//! where `h` is the unit heading of x̂0's root rotation (the horizontal direction of its first
//! column, the pelvis's side axis, which stays horizontal for an upright body) and `ω` a linear
//! head on the last hidden state. The head starts at zero: an untrained head holds each dancer
//! at the window's mean heading.
//!
//! The root rotation's rows (pytorch3d 6D: the first two rows of the matrix) are written back
//! orthonormalised (Gram–Schmidt, as every reader of the 6D does anyway) and turned by the
//! difference between the integrated heading and their own: `R' = R_z(heading − ∠h) · R`.

use dancegen_nn::burn;
use dancegen_nn::edge151::{DIMS, Denormalize, ROT6D_START};

use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::{Device, Tensor};

use crate::layout::N_MAX;
use dancegen_nn::host_linear;

/// Radians per unit of the turn head: a dancer turns up to about 0.2 rad (12°) a frame in a
/// fast spin at 30 fps, so the head's outputs are of order one.
pub const TURN_SCALE: f64 = 0.05;

/// Added under the square roots of the norms: empty slots have zero rows.
const EPS: f64 = 1e-8;

/// See the module documentation.
#[derive(Module, Debug)]
pub struct HeadingPath {
    pub turn: Linear,
}

/// A 2-vector field `[…, 2]` split into its two components `[…, 1]`.
fn xy(v: Tensor<4>) -> (Tensor<4>, Tensor<4>) {
    (v.clone().narrow(3, 0, 1), v.narrow(3, 1, 1))
}

fn unit(v: Tensor<4>) -> Tensor<4> {
    let n = (v.clone().powf_scalar(2.0).sum_dim(3) + EPS).sqrt();
    v / n
}

impl HeadingPath {
    pub fn new(d_model: usize, device: &Device) -> Self {
        Self {
            turn: LinearConfig::new(d_model, 1)
                .with_initializer(Initializer::Zeros)
                .init(device),
        }
    }

    /// x̂0 tokens `[B, T·N_MAX, 151]` (normalised) with each dancer's root rotation turned to
    /// the integrated heading; `hidden` is the last decoder state `[B, T·N_MAX, d]` of the
    /// same tokens, `denorm` the model's normaliser.
    pub fn forward(&self, x0: Tensor<3>, hidden: Tensor<3>, denorm: &Denormalize) -> Tensor<3> {
        let [b, k, _] = x0.dims();
        let t = k / N_MAX;
        let device = x0.device();
        let scale = denorm
            .scale
            .val()
            .narrow(0, ROT6D_START, 6)
            .reshape([1, 1, 6]);
        let shift = denorm
            .shift
            .val()
            .narrow(0, ROT6D_START, 6)
            .reshape([1, 1, 6]);
        let rows = x0.clone().narrow(2, ROT6D_START, 6) * scale.clone() + shift.clone();
        // [B, T, N, 3] each, then Gram–Schmidt.
        let row = |i: usize| rows.clone().narrow(2, 3 * i, 3).reshape([b, t, N_MAX, 3]);
        let b1 = unit(row(0));
        let a2 = row(1);
        let b2 = unit(a2.clone() - b1.clone() * (b1.clone() * a2).sum_dim(3));
        // The first column's horizontal direction: (R00, R10).
        let h = unit(Tensor::cat(
            vec![b1.clone().narrow(3, 0, 1), b2.clone().narrow(3, 0, 1)],
            3,
        ));
        let mean = unit(h.clone().sum_dim(1)); // [B, 1, N, 2]
        let turns = (host_linear::forward(&self.turn, hidden) * TURN_SCALE).reshape([b, t, N_MAX]);
        let summed = crate::root_path::cumulative_sum(t, &device)
            .expand([b, t, t])
            .matmul(turns);
        let phi = (summed.clone() - summed.mean_dim(1)).reshape([b, t, N_MAX, 1]);
        let (c, s) = (phi.clone().cos(), phi.sin());
        let (mx, my) = xy(mean);
        // The integrated heading u = mean ⊗ e^{iφ}, and the turn d = u ⊗ conj(h) to apply.
        let ux = mx.clone() * c.clone() - my.clone() * s.clone();
        let uy = mx * s + my * c;
        let (hx, hy) = xy(h);
        let dc = ux.clone() * hx.clone() + uy.clone() * hy.clone();
        let ds = uy * hx - ux * hy;
        // R_z(d) · R: row 0 → dc·row0 − ds·row1, row 1 → ds·row0 + dc·row1.
        let r0 = b1.clone() * dc.clone() - b2.clone() * ds.clone();
        let r1 = b1 * ds + b2 * dc;
        let turned = Tensor::cat(vec![r0, r1], 3).reshape([b, k, 6]);
        let normalised = (turned - shift) / scale;
        Tensor::cat(
            vec![
                x0.clone().narrow(2, 0, ROT6D_START),
                normalised,
                x0.narrow(2, ROT6D_START + 6, DIMS - ROT6D_START - 6),
            ],
            2,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::module::Param;
    use burn::tensor::TensorData;

    /// Normalised tokens `[1, T·N_MAX, 151]` whose raw root rotation in frame `f` is a turn of
    /// `yaw(f, slot)` about the vertical tilted by `tilt` about the x axis, under a normaliser
    /// of scale 2 and shift 0.5; other channels hold their index.
    fn tokens(t: usize, yaw: impl Fn(usize, usize) -> f64, tilt: f64) -> (Tensor<3>, Denormalize) {
        let dev = dancegen_nn::device::inference();
        let denorm = Denormalize::from_mean_std(&[0.5; DIMS], &[2.0; DIMS], &dev);
        let mut v = Vec::new();
        for f in 0..t {
            for s in 0..N_MAX {
                let m = matrix(yaw(f, s), tilt);
                let mut tok: Vec<f32> = (0..DIMS).map(|c| c as f32).collect();
                for i in 0..6 {
                    tok[ROT6D_START + i] = ((m[i / 3][i % 3] - 0.5) / 2.0) as f32;
                }
                v.extend(tok);
            }
        }
        let x = Tensor::from_data(TensorData::new(v, [1, t * N_MAX, DIMS]), &dev);
        (x, denorm)
    }

    /// `R_z(yaw) · R_x(tilt)`.
    fn matrix(yaw: f64, tilt: f64) -> [[f64; 3]; 3] {
        let (cy, sy, ct, st) = (yaw.cos(), yaw.sin(), tilt.cos(), tilt.sin());
        [
            [cy, -sy * ct, sy * st],
            [sy, cy * ct, -cy * st],
            [0.0, st, ct],
        ]
    }

    /// The raw rows of token `k`.
    fn raw_rows(out: &[f32], k: usize) -> [f64; 6] {
        std::array::from_fn(|i| out[k * DIMS + ROT6D_START + i] as f64 * 2.0 + 0.5)
    }

    fn run(head: &HeadingPath, x: Tensor<3>, denorm: &Denormalize, d: usize) -> Vec<f32> {
        let dev = dancegen_nn::device::inference();
        let t = x.dims()[1] / N_MAX;
        let hidden = Tensor::<3>::ones([1, t * N_MAX, d], &dev);
        head.forward(x, hidden, denorm)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap()
    }

    #[test]
    fn an_untrained_head_holds_the_mean_heading_and_keeps_the_tilt() {
        let dev = dancegen_nn::device::inference();
        let t = 4;
        // Slot s: headings alternating ±0.3 rad around 0.2·s, tilted 0.1 rad.
        let yaw =
            |f: usize, s: usize| 0.2 * s as f64 + if f.is_multiple_of(2) { 0.3 } else { -0.3 };
        let (x, denorm) = tokens(t, yaw, 0.1);
        let out = run(&HeadingPath::new(3, &dev), x, &denorm, 3);
        for f in 0..t {
            for s in 0..N_MAX {
                let k = f * N_MAX + s;
                let want = matrix(0.2 * s as f64, 0.1);
                let got = raw_rows(&out, k);
                for i in 0..6 {
                    assert!(
                        (got[i] - want[i / 3][i % 3]).abs() < 1e-4,
                        "frame {f} slot {s} value {i}: {} against {}",
                        got[i],
                        want[i / 3][i % 3]
                    );
                }
                for c in (0..DIMS).filter(|c| !(ROT6D_START..ROT6D_START + 6).contains(c)) {
                    assert_eq!(out[k * DIMS + c], c as f32, "channel {c} untouched");
                }
            }
        }
    }

    #[test]
    fn turns_integrate_into_a_heading_centred_on_the_mean() {
        let dev = dancegen_nn::device::inference();
        let (t, d) = (5, 2);
        let mut head = HeadingPath::new(d, &dev);
        // ω = 20 · hidden[0], so TURN_SCALE · ω = 1 rad a frame.
        head.turn.weight = Param::from_tensor(Tensor::from_data(
            TensorData::new(vec![20.0f32, 0.0], [d, 1]),
            &dev,
        ));
        // Every frame faces 0.4 rad, whatever the frame: the mean is 0.4.
        let (x, denorm) = tokens(t, |_, _| 0.4, 0.0);
        let out = run(&head, x, &denorm, d);
        // Cumulative turns 1..=5, mean 3: headings 0.4 − 2, …, 0.4 + 2.
        for f in 0..t {
            let want = matrix(0.4 + f as f64 - 2.0, 0.0);
            let got = raw_rows(&out, f * N_MAX + 1);
            for i in 0..6 {
                assert!(
                    (got[i] - want[i / 3][i % 3]).abs() < 1e-4,
                    "frame {f} value {i}: {} against {}",
                    got[i],
                    want[i / 3][i % 3]
                );
            }
        }
    }

    #[test]
    fn headings_half_a_turn_apart_keep_an_upright_body() {
        // The failure of the smoothed skip (module docs): x̂0 rows that average headings half a
        // turn apart. Here each frame's rows are one valid rotation, so whatever the mean, the
        // written rows stay a rotation about the vertical: the third row (up) stays (0, 0, 1).
        let dev = dancegen_nn::device::inference();
        let t = 6;
        let (x, denorm) = tokens(t, |f, _| if f < 3 { 0.0 } else { 3.0 }, 0.0);
        let out = run(&HeadingPath::new(2, &dev), x, &denorm, 2);
        for k in 0..t * N_MAX {
            let r = raw_rows(&out, k);
            assert!(r[2].abs() < 1e-4 && r[5].abs() < 1e-4, "token {k}: {r:?}");
            let n0 = (r[0] * r[0] + r[1] * r[1]).sqrt();
            assert!((n0 - 1.0).abs() < 1e-4, "token {k}: row 0 is a unit vector");
        }
    }
}
