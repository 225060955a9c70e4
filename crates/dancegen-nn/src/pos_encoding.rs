//! Positional encodings.
//!
//! - [`sinusoidal`]: the Transformer table, `pe[p, 2i] = sin(p·ω_i)`, `pe[p, 2i+1] = cos(p·ω_i)`,
//!   `ω_i = 10000^(−2i/d)` (EDGE/Lodge `PositionalEncoding`, TCDiff++ temporal PE).
//! - [`Rotary`]: rotary position embedding as EDGE uses it (`rotary-embedding-torch`,
//!   `RotaryEmbedding(dim = latent_dim)` applied to the full-width query/key input before the
//!   projections): frequencies `θ^(−2i/d)`, each frequency repeated for an **interleaved** pair
//!   of channels `(2i, 2i+1)`, rotation `x·cos + rotate_half(x)·sin` with
//!   `rotate_half(a, b) = (−b, a)` per pair.
//! - [`phase_aligned`]: ReactDance's Blocked-Local-Context encoding, the phase `φ = (p mod T)/T`
//!   restarting every block of `T` frames: `[sin(π·k·φ), cos(π·k·φ)]` for `k = 1 … d/2`. The
//!   paper writes the `k = 1` pair (`sin(π(i mod T)/T) ⊕ cos(π(i mod T)/T)`); higher `k` extend
//!   it to `d` channels (our choice, the code is unreleased).
//! - [`LearnedPositions`]: a learned table (GPT block positions).
//! - [`dancer_positions`]: TCDiff++'s dancer positioning embedding for frame-major group
//!   tokens: a sinusoidal code of each dancer's rank (out of `max_dancers`) added to the
//!   temporal encoding of its frame.

use burn::config::Config;
use burn::module::{Module, Param};
use burn::tensor::{Device, Distribution, Tensor, TensorData};

/// `[positions, d]` sinusoidal table for positions `start .. start + positions`.
pub fn sinusoidal(start: usize, positions: usize, d: usize, device: &Device) -> Tensor<2> {
    let mut data = vec![0f32; positions * d];
    for p in 0..positions {
        let pos = (start + p) as f64;
        for i in 0..d.div_ceil(2) {
            let w = (-(2.0 * i as f64) * (10000f64).ln() / d as f64).exp();
            data[p * d + 2 * i] = (pos * w).sin() as f32;
            if 2 * i + 1 < d {
                data[p * d + 2 * i + 1] = (pos * w).cos() as f32;
            }
        }
    }
    Tensor::from_data(TensorData::new(data, [positions, d]), device)
}

/// `[positions, d]` phase-aligned table of frames `start ..` with blocks of `block` frames.
pub fn phase_aligned(
    start: usize,
    positions: usize,
    block: usize,
    d: usize,
    device: &Device,
) -> Tensor<2> {
    assert!(
        block > 0 && d.is_multiple_of(2),
        "phase-aligned PE: block > 0, even d"
    );
    let mut data = vec![0f32; positions * d];
    for p in 0..positions {
        let phase = ((start + p) % block) as f64 / block as f64;
        for k in 0..d / 2 {
            let a = std::f64::consts::PI * (k + 1) as f64 * phase;
            data[p * d + 2 * k] = a.sin() as f32;
            data[p * d + 2 * k + 1] = a.cos() as f32;
        }
    }
    Tensor::from_data(TensorData::new(data, [positions, d]), device)
}

/// Rotary position embedding over the last dimension of `[B, T, d]` inputs.
#[derive(Clone, Debug)]
pub struct Rotary {
    pub dim: usize,
    pub theta: f64,
}

impl Rotary {
    /// EDGE: `RotaryEmbedding(dim = latent_dim)`, θ = 10000.
    pub fn new(dim: usize) -> Self {
        assert!(dim.is_multiple_of(2), "rotary dim must be even");
        Self {
            dim,
            theta: 10000.0,
        }
    }

    /// The `(cos, sin)` tables for frames at positions `start .. start + t`, computed once per
    /// forward pass and shared by every layer.
    pub fn tables(&self, start: usize, t: usize, device: &Device) -> RotaryTables {
        let d = self.dim;
        let mut c = vec![0f32; t * d];
        let mut s = vec![0f32; t * d];
        for p in 0..t {
            for i in 0..d / 2 {
                let f = self.theta.powf(-(2.0 * i as f64) / d as f64);
                let a = (start + p) as f64 * f;
                for k in 0..2 {
                    c[p * d + 2 * i + k] = a.cos() as f32;
                    s[p * d + 2 * i + k] = a.sin() as f32;
                }
            }
        }
        RotaryTables {
            cos: Tensor::<2>::from_data(TensorData::new(c, [t, d]), device).unsqueeze(),
            sin: Tensor::<2>::from_data(TensorData::new(s, [t, d]), device).unsqueeze(),
        }
    }

    /// Rotates `x` `[B, T, d]` whose frames sit at positions `start ..`.
    pub fn rotate(&self, x: Tensor<3>, start: usize) -> Tensor<3> {
        let t = x.dims()[1];
        self.tables(start, t, &x.device()).rotate(x)
    }
}

/// Precomputed rotary tables `[1, T, d]` (pairs interleaved).
#[derive(Clone, Debug)]
pub struct RotaryTables {
    pub cos: Tensor<3>,
    pub sin: Tensor<3>,
}

impl RotaryTables {
    /// `x·cos + rotate_half(x)·sin` for `x` `[B, T, d]`.
    pub fn rotate(&self, x: Tensor<3>) -> Tensor<3> {
        let [b, t, d] = x.dims();
        assert_eq!(
            [t, d],
            [self.cos.dims()[1], self.cos.dims()[2]],
            "rotary tables vs input [T, d]"
        );
        let pairs = x.clone().reshape([b, t, d / 2, 2]);
        let first = pairs.clone().narrow(3, 0, 1);
        let second = pairs.narrow(3, 1, 1);
        let half = Tensor::cat(vec![second.neg(), first], 3).reshape([b, t, d]);
        x * self.cos.clone() + half * self.sin.clone()
    }
}

/// Configuration of [`LearnedPositions`].
#[derive(Config, Debug)]
pub struct LearnedPositionsConfig {
    pub max_positions: usize,
    pub d: usize,
}

/// A learned `[max_positions, d]` position table (normal init, σ = 0.02 as GPT-2).
#[derive(Module, Debug)]
pub struct LearnedPositions {
    pub weight: Param<Tensor<2>>,
}

impl LearnedPositionsConfig {
    pub fn init(&self, device: &Device) -> LearnedPositions {
        LearnedPositions {
            weight: Param::from_tensor(Tensor::random(
                [self.max_positions, self.d],
                Distribution::Normal(0.0, 0.02),
                device,
            )),
        }
    }
}

impl LearnedPositions {
    /// Rows `start .. start + t` as `[1, t, d]`.
    pub fn forward(&self, start: usize, t: usize) -> Tensor<3> {
        let [max, _] = self.weight.dims();
        assert!(
            start + t <= max,
            "positions {start}..{} exceed the table of {max}",
            start + t
        );
        self.weight.val().narrow(0, start, t).unsqueeze()
    }
}

/// Dancer positioning embedding (TCDiff++ paper §4.1, Eq. 8) for **frame-major** group tokens
/// (token `k` = frame `k / N`, dancer slot `k % N`, the layout of TCDiff++'s `p_losses`,
/// `../shared/reference/group.md` "Corrections"): row `k` is the sinusoidal code of frame
/// `k / N` plus the sinusoidal code of slot `k % N`'s rank `ranks[k % N]`, a fixed row of a
/// `max_dancers`-row table. Output `[frames · N, d]`.
///
/// Deterministic, unlike the released `Tem_ID_Encoder`, which re-draws the identities on every
/// forward and indexes them as if the tokens were dancer-major (group.md §5 P1).
pub fn dancer_positions(
    ranks: &[usize],
    frames: usize,
    d: usize,
    max_dancers: usize,
    device: &Device,
) -> Tensor<2> {
    assert!(
        ranks.iter().all(|&s| s < max_dancers),
        "dancer rank out of range"
    );
    let n = ranks.len();
    let time = sinusoidal(0, frames, d, device);
    let ids = sinusoidal(0, max_dancers, d, device);
    let idx: Vec<i64> = ranks.iter().map(|&r| r as i64).collect();
    let id_rows = ids.select(
        0,
        Tensor::<1, burn::tensor::Int>::from_data(TensorData::new(idx, [n]), device),
    );
    let time = time.unsqueeze_dim::<3>(1).expand([frames, n, d]);
    (time + id_rows.unsqueeze::<3>().expand([frames, n, d])).reshape([frames * n, d])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(t: Tensor<2>) -> Vec<Vec<f32>> {
        let [n, d] = t.dims();
        let v: Vec<f32> = t.into_data().try_into_vec::<f32>().unwrap();
        (0..n).map(|i| v[i * d..(i + 1) * d].to_vec()).collect()
    }

    #[test]
    fn phase_aligned_restarts_every_block() {
        let dev = crate::device::inference();
        let r = rows(phase_aligned(0, 12, 4, 6, &dev));
        for p in 0..12 {
            assert_eq!(r[p], r[p % 4], "frame {p} must equal frame {}", p % 4);
        }
        // The paper's pair: sin(π φ), cos(π φ) with φ = (p mod T)/T.
        let phi = 3.0 / 4.0 * std::f64::consts::PI;
        assert!((f64::from(r[3][0]) - phi.sin()).abs() < 1e-6);
        assert!((f64::from(r[3][1]) - phi.cos()).abs() < 1e-6);
        // A block start offset continues the phase.
        assert_eq!(rows(phase_aligned(5, 1, 4, 6, &dev))[0], r[1]);
    }

    #[test]
    fn dancer_positions_are_frame_major() {
        let dev = crate::device::inference();
        let t = dancer_positions(&[3, 0], 5, 8, 5, &dev);
        assert_eq!(t.dims(), [10, 8]);
        let r = rows(t);
        let time = rows(sinusoidal(0, 5, 8, &dev));
        let ids = rows(sinusoidal(0, 5, 8, &dev));
        for f in 0..5 {
            for c in 0..8 {
                // Token 2f is (frame f, slot 0 of rank 3), token 2f + 1 is (frame f, slot 1).
                assert!((r[2 * f][c] - (time[f][c] + ids[3][c])).abs() < 1e-6);
                assert!((r[2 * f + 1][c] - (time[f][c] + ids[0][c])).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn rotary_preserves_norms_and_relative_angles() {
        let dev = crate::device::inference();
        let rot = Rotary::new(8);
        let x = Tensor::<3>::random([1, 6, 8], Distribution::Normal(0.0, 1.0), &dev);
        let y = rot.rotate(x.clone(), 0);
        let n = |t: Tensor<3>| t.powf_scalar(2.0).sum().into_scalar::<f32>();
        assert!((n(x.clone()) - n(y)).abs() < 1e-4);
        // q·k depends only on the position difference: shift both by 3 frames.
        let q = x.clone().narrow(1, 0, 1);
        let k = x.narrow(1, 1, 1);
        let dot = |a: Tensor<3>, b: Tensor<3>| (a * b).sum().into_scalar::<f32>();
        let d0 = dot(rot.rotate(q.clone(), 2), rot.rotate(k.clone(), 4));
        let d1 = dot(rot.rotate(q, 5), rot.rotate(k, 7));
        assert!((d0 - d1).abs() < 1e-4, "{d0} vs {d1}");
    }
}
