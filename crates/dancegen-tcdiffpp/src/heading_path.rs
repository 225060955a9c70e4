//! Our option ([`crate::config::DenoiserConfig::heading_integrated`]), not the paper's: each
//! dancer's root rotation in x̂0 is split into its heading (the turn about the vertical) and
//! the rest, its tilt. The heading is x̂0's own, optionally smoothed **as an angle** over the
//! window's frames, plus a learned turn integrated from per-frame turns, as
//! [`crate::root_path`] does for the root x/y. The tilt is x̂0's own, optionally smoothed in
//! the heading's frame.
//!
//! Why: with the learned skip over smoothings of x_t, the root rotation's two 6D rows were
//! averaged across fast turns. Averaging two headings half a turn apart shrinks the rows
//! towards zero; normalising them back (the 6D → matrix Gram–Schmidt) then follows whatever
//! error is left, and the body tipped over (docs/group-collapse.md §20). Taking the root
//! rotation out of the smoothings stopped the tipping but left the root rotation reading its
//! input's noise: the body jittered with it, mostly in its tilt (§20, v13; §21). Here a fast
//! turn stays a turn and the frame-to-frame noise goes.
//!
//! Per dancer and frame, with `R` the root rotation of x̂0 and `h` the unit horizontal
//! direction of its first column (the pelvis's side axis, which stays horizontal for an
//! upright body):
//! - the tilt `T = R_z(−∠h) · R`, smoothed with the Gaussian rows of `σ` frames of the learned
//!   skip ([`crate::prediction::gaussian_rows`]) and orthonormalised again. Neighbouring
//!   frames' `T` differ by their tilt alone, even in a fast turn, so the mean does not shrink;
//! - the heading `(G_σ ∗ θ)[t] + Φ[t] − mean_τ(Φ[τ])`: `θ` is the unwrapped angle of `h` (each
//!   frame's turn taken the short way round), `Φ[t] = Σ_{τ ≤ t} TURN_SCALE · ω[τ]` and `ω` a
//!   linear head on the last hidden state, starting at zero;
//! - `R' = R_z(heading) · T`, written back as its first two rows (pytorch3d 6D).
//!
//! With σ = 0 and an untrained head, `R'` is `R` orthonormalised.

use dancegen_nn::burn;
use dancegen_nn::edge151::{DIMS, Denormalize, ROT6D_START};

use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::{Device, Tensor, TensorData};

use crate::layout::N_MAX;
use crate::prediction::gaussian_rows;
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
    /// σ of the smoothing of the heading and the tilt, frames (0: none).
    #[module(skip)]
    smoothing: f64,
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
    /// `smoothing`: σ of the heading's and the tilt's smoothing in frames, 0 for none.
    pub fn new(d_model: usize, smoothing: f64, device: &Device) -> Self {
        Self {
            turn: LinearConfig::new(d_model, 1)
                .with_initializer(Initializer::Zeros)
                .init(device),
            smoothing,
        }
    }

    /// `[1, T, T]` Gaussian rows of the smoothing over `t` frames, `None` without one.
    fn smoothing_rows(&self, t: usize, device: &Device) -> Option<Tensor<3>> {
        (self.smoothing > 0.0 && t > 1).then(|| {
            Tensor::from_data(
                TensorData::new(gaussian_rows(t, self.smoothing), [1, t, t]),
                device,
            )
        })
    }

    /// x̂0 tokens `[B, T·N_MAX, 151]` (normalised) with each dancer's root rotation rebuilt
    /// from its heading and tilt (module docs); `hidden` is the last decoder state `[B, T·N_MAX, d]` of the
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
        let (hx, hy) = xy(h);
        // The heading-free rotation T = R_z(−∠h) · R: row 0 → hx·b1 + hy·b2, row 1 →
        // −hy·b1 + hx·b2. Neighbouring frames' T differ only by their tilt, even in a fast
        // turn, so smoothing them does not shrink them.
        let t0 = b1.clone() * hx.clone() + b2.clone() * hy.clone();
        let t1 = b2 * hx.clone() - b1 * hy.clone();
        let smooth = self.smoothing_rows(t, &device);
        let (t0, t1) = match &smooth {
            Some(g) => {
                let frames = |v: Tensor<4>| {
                    g.clone()
                        .expand([b, t, t])
                        .matmul(v.reshape([b, t, N_MAX * 3]))
                        .reshape([b, t, N_MAX, 3])
                };
                let s0 = unit(frames(t0));
                let s1 = frames(t1);
                let s1 = unit(s1.clone() - s0.clone() * (s0.clone() * s1).sum_dim(3));
                (s0, s1)
            }
            None => (t0, t1),
        };
        // The unwrapped angle: frame 0's, then each frame's turn the short way round.
        let first = hy.clone().narrow(1, 0, 1).atan2(hx.clone().narrow(1, 0, 1));
        let theta = if t > 1 {
            let (x0, y0) = (
                hx.clone().narrow(1, 0, t - 1),
                hy.clone().narrow(1, 0, t - 1),
            );
            let (x1, y1) = (hx.narrow(1, 1, t - 1), hy.narrow(1, 1, t - 1));
            let turns =
                (y1.clone() * x0.clone() - x1.clone() * y0.clone()).atan2(x1 * x0 + y1 * y0);
            let turns = Tensor::cat(vec![first, turns], 1).reshape([b, t, N_MAX]);
            crate::root_path::cumulative_sum(t, &device)
                .expand([b, t, t])
                .matmul(turns)
        } else {
            first.reshape([b, t, N_MAX])
        };
        let theta = match smooth {
            Some(g) => g.expand([b, t, t]).matmul(theta),
            None => theta,
        };
        let turns = (host_linear::forward(&self.turn, hidden) * TURN_SCALE).reshape([b, t, N_MAX]);
        let summed = crate::root_path::cumulative_sum(t, &device)
            .expand([b, t, t])
            .matmul(turns);
        let heading = (theta + summed.clone() - summed.mean_dim(1)).reshape([b, t, N_MAX, 1]);
        let (c, s) = (heading.clone().cos(), heading.sin());
        // R' = R_z(heading) · T: row 0 → c·t0 − s·t1, row 1 → s·t0 + c·t1.
        let r0 = t0.clone() * c.clone() - t1.clone() * s.clone();
        let r1 = t0 * s + t1 * c;
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
    /// `yaw(f, slot)` about the vertical tilted by `tilt(f)` about the x axis, under a normaliser
    /// of scale 2 and shift 0.5; other channels hold their index.
    fn tokens(
        t: usize,
        yaw: impl Fn(usize, usize) -> f64,
        tilt: impl Fn(usize) -> f64,
    ) -> (Tensor<3>, Denormalize) {
        let dev = dancegen_nn::device::inference();
        let denorm = Denormalize::from_mean_std(&[0.5; DIMS], &[2.0; DIMS], &dev);
        let mut v = Vec::new();
        for f in 0..t {
            for s in 0..N_MAX {
                let m = matrix(yaw(f, s), tilt(f));
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

    fn assert_rows(out: &[f32], k: usize, want: [[f64; 3]; 3], what: &str) {
        let got = raw_rows(out, k);
        for i in 0..6 {
            assert!(
                (got[i] - want[i / 3][i % 3]).abs() < 1e-4,
                "{what}, value {i}: {} against {}",
                got[i],
                want[i / 3][i % 3]
            );
        }
    }

    #[test]
    fn an_untrained_head_without_smoothing_keeps_the_rotation() {
        let dev = dancegen_nn::device::inference();
        let t = 4;
        // Slot s: headings alternating around 0.2·s, and across ±π in slot 4; tilted 0.1 rad.
        let yaw = |f: usize, s: usize| {
            let swing = if f.is_multiple_of(2) { 0.3 } else { -0.3 };
            if s == 4 {
                3.0 + swing
            } else {
                0.2 * s as f64 + swing
            }
        };
        let (x, denorm) = tokens(t, yaw, |_| 0.1);
        let out = run(&HeadingPath::new(3, 0.0, &dev), x, &denorm, 3);
        for f in 0..t {
            for s in 0..N_MAX {
                let k = f * N_MAX + s;
                assert_rows(
                    &out,
                    k,
                    matrix(yaw(f, s), 0.1),
                    &format!("frame {f} slot {s}"),
                );
                for c in (0..DIMS).filter(|c| !(ROT6D_START..ROT6D_START + 6).contains(c)) {
                    assert_eq!(out[k * DIMS + c], c as f32, "channel {c} untouched");
                }
            }
        }
    }

    #[test]
    fn a_turn_stays_a_turn_and_the_jitter_goes() {
        let dev = dancegen_nn::device::inference();
        let (t, sigma) = (20, 2.0);
        // A steady turn of 0.3 rad a frame through ±π, with frame-to-frame jitter of ±0.1 rad
        // on top, and a tilt jittering between 0 and 0.2 rad: the smoothing keeps the turn
        // (a linear ramp is its own smoothing away from the window's ends, ±3σ frames) and
        // the mean tilt, and removes both jitters.
        let turn = |f: usize| 2.0 + 0.3 * f as f64;
        let jitter = |f: usize| if f.is_multiple_of(2) { 0.1 } else { -0.1 };
        let tilt = |f: usize| 0.1 + jitter(f);
        let (x, denorm) = tokens(t, |f, _| turn(f) + jitter(f), tilt);
        let out = run(&HeadingPath::new(2, sigma, &dev), x, &denorm, 2);
        // Frames 6..14 see the whole ±6-frame kernel; an alternation smoothed by σ = 2 keeps
        // exp(−2π²) ≈ 3e-9 of itself; two tilts about one axis averaged as rows and
        // orthonormalised give the tilt halfway.
        for f in 6..14 {
            let got = raw_rows(&out, f * N_MAX + 2);
            let angle = got[3].atan2(got[0]);
            let want = turn(f);
            let off = (angle - want + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            assert!(
                off.abs() < 1e-3,
                "frame {f}: heading {angle} against {want}"
            );
            assert_rows(
                &out,
                f * N_MAX + 2,
                matrix(angle, 0.1),
                &format!("frame {f}"),
            );
        }
        // Without smoothing, each frame keeps its own heading and tilt.
        let (x, denorm) = tokens(t, |f, _| turn(f) + jitter(f), tilt);
        let out = run(&HeadingPath::new(2, 0.0, &dev), x, &denorm, 2);
        for f in 0..t {
            assert_rows(
                &out,
                f * N_MAX,
                matrix(turn(f) + jitter(f), tilt(f)),
                &format!("frame {f}"),
            );
        }
    }

    #[test]
    fn turns_integrate_into_a_heading_centred_on_the_mean() {
        let dev = dancegen_nn::device::inference();
        let (t, d) = (5, 2);
        let mut head = HeadingPath::new(d, 0.0, &dev);
        // ω = 20 · hidden[0], so TURN_SCALE · ω = 1 rad a frame.
        head.turn.weight = Param::from_tensor(Tensor::from_data(
            TensorData::new(vec![20.0f32, 0.0], [d, 1]),
            &dev,
        ));
        // Every frame faces 0.4 rad.
        let (x, denorm) = tokens(t, |_, _| 0.4, |_| 0.0);
        let out = run(&head, x, &denorm, d);
        // Cumulative turns 1..=5, mean 3: headings 0.4 − 2, …, 0.4 + 2.
        for f in 0..t {
            assert_rows(
                &out,
                f * N_MAX + 1,
                matrix(0.4 + f as f64 - 2.0, 0.0),
                &format!("frame {f}"),
            );
        }
    }
}
