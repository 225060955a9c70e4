//! Selective state-space layer (Mamba v1, Gu & Dao 2023, "Mamba: Linear-time sequence modeling
//! with selective state spaces", arXiv 2312.00752), the sequence mixer of TCDiff++'s Sequence
//! Decoder (`Da1yuqin/TCDiffpp:mamba_addon/modules/mamba_simple.py`, anchors D.4).
//!
//! Per frame `t` of `x` `[B, T, d_model]`:
//! 1. `in_proj` (no bias) → `x, z`, each `d_inner = expand · d_model` wide;
//! 2. causal depthwise `conv1d` over time (kernel `d_conv`, left padding `d_conv − 1`) + SiLU;
//! 3. `x_proj` (no bias) → `(dt, B, C)` of widths `(dt_rank, d_state, d_state)`;
//!    `Δ = softplus(dt_proj(dt))` (the bias of `dt_proj` is the Δ bias of the CUDA kernel);
//! 4. selective scan with `A = −exp(A_log)` `[d_inner, d_state]`:
//!    `h_t = exp(Δ_t A) ⊙ h_{t−1} + Δ_t B_t x_t`, `y_t = C_t · h_t + D ⊙ x_t` (the paper's ZOH for
//!    `A`, the Euler step for `B`, as in the reference `selective_scan_ref`);
//! 5. `out_proj(y ⊙ SiLU(z))` (no bias).
//!
//! Two scans compute the same function: [`selective_scan_sequential`] (one step per frame, the
//! correctness reference) and [`selective_scan_chunked`] (closed-form within chunks, a short
//! sequential carry between chunks). The per-step loop is fine forward but its backward costs
//! O(T²) memory traffic in Burn (every per-step slice's backward materialises a full-size
//! gradient; `../shared/reference/rust-ml-stack.md` §1), so [`Mamba::forward`] uses the chunked
//! scan by default ([`Scan`]); `benches/ssm_scan.rs` measures both.
//!
//! Parameter names are the reference's (`in_proj`, `conv1d`, `x_proj`, `dt_proj`, `A_log`, `D`,
//! `out_proj`), so a PyTorch state dict loads with [`crate::weights::load`] in
//! [`crate::weights::Layout::PyTorch`].
//!
//! Left out: TCDiff++'s linear cross-attention to the music tokens that its decoder adds before
//! `out_proj` (a separate block, not part of Mamba), and the recurrent single-step inference path
//! with a conv/SSM state cache (not needed by a diffusion decoder, which sees whole windows).

// `A_log`, `D`: the reference's parameter names, also in the code `derive(Module)` generates.
#![allow(non_snake_case)]

use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::conv::{Conv1d, Conv1dConfig};
use burn::nn::{Initializer, LayerNorm, LayerNormConfig, Linear, LinearConfig, PaddingConfig1d};
use burn::tensor::activation::{silu, softplus};
use burn::tensor::{Device, Distribution, Tensor, TensorData};

/// Mamba v1 defaults (`mamba_simple.py` `Mamba.__init__`, used unchanged by TCDiff++):
/// state size per channel.
pub const D_STATE: usize = 16;
/// Kernel of the causal depthwise convolution (`mamba_simple.py` `d_conv=4`).
pub const D_CONV: usize = 4;
/// `d_inner = EXPAND · d_model` (`mamba_simple.py` `expand=2`).
pub const EXPAND: usize = 2;
/// Smallest initial Δ (`mamba_simple.py` `dt_min=0.001`).
pub const DT_MIN: f64 = 0.001;
/// Largest initial Δ (`mamba_simple.py` `dt_max=0.1`).
pub const DT_MAX: f64 = 0.1;
/// Floor of the sampled initial Δ (`mamba_simple.py` `dt_init_floor=1e-4`).
pub const DT_INIT_FLOOR: f64 = 1e-4;

/// Largest `|Σ Δ·A|` one chunk of [`selective_scan_chunked`] may span. The chunk state is
/// `exp(S_t − m) ⊙ cumsum_s(exp(m − S_s) ⊙ Δ_s B_s x_s)` with `S` the cumulative `Δ·A` and `m`
/// half the chunk's total, so the two exponentials stay within `exp(±RANGE/2)`. f32 `exp`
/// overflows beyond 88 and loses precision to subnormals below −87; 60 leaves `exp(30) ≈ 1e13`
/// of head room for the inputs' own magnitude. (The rounding error does not grow with the
/// range: each summed term is scaled back by at most 1, so it stays `≈ ε · L · max|ΔBx|`.)
pub const CHUNK_LOG_RANGE: f32 = 60.0;
/// Longest chunk. Only reached when Δ is small (at the initial Δ ≤ 0.1 with `A` down to −16 the
/// log range already caps chunks at 37 frames); it bounds the zero padding of the last chunk.
/// Not tuned: 512 frames make 8 carry steps at this length, already cheap next to the
/// `[B, T, d_inner, d_state]` passes.
pub const MAX_CHUNK: usize = 64;

/// Which selective-scan implementation [`Mamba::forward`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Scan {
    /// One step per frame: the reference recurrence. O(T²) backward in Burn.
    Sequential,
    /// Closed form within chunks (chunk length from [`CHUNK_LOG_RANGE`]), carry between chunks.
    /// The default: its backward is 2-37× faster than the per-step loop's on the bench shapes.
    /// Forward on CPU the two trade places (chunked 1.3× faster at d_model 64 × 512 frames, 3×
    /// slower at d_model 128 × 512 frames, one thread, `benches/ssm_scan.rs`): CPU inference at
    /// large `d_inner · T` may prefer [`Scan::Sequential`]. On a GPU the chunked scan's ~T/L
    /// times fewer op launches should matter more (not measured here).
    #[default]
    Chunked,
}

/// Configuration of [`Mamba`]; defaults are Mamba v1's, as TCDiff++ uses them (anchors D.4).
#[derive(Config, Debug)]
pub struct MambaConfig {
    pub d_model: usize,
    #[config(default = "D_STATE")]
    pub d_state: usize,
    #[config(default = "D_CONV")]
    pub d_conv: usize,
    #[config(default = "EXPAND")]
    pub expand: usize,
    /// Width of the low-rank Δ projection; default `⌈d_model / 16⌉` (`dt_rank="auto"`).
    #[config(default = "None")]
    pub dt_rank: Option<usize>,
    #[config(default = "DT_MIN")]
    pub dt_min: f64,
    #[config(default = "DT_MAX")]
    pub dt_max: f64,
    #[config(default = "DT_INIT_FLOOR")]
    pub dt_init_floor: f64,
    #[config(default = "Scan::Chunked")]
    pub scan: Scan,
}

/// Mamba v1 selective state-space layer (see the module docs).
#[derive(Module, Debug)]
pub struct Mamba {
    /// `d_model → 2·d_inner`, no bias.
    pub in_proj: Linear,
    /// Depthwise causal convolution, weight `[d_inner, 1, d_conv]`, with bias.
    pub conv1d: Conv1d,
    /// `d_inner → dt_rank + 2·d_state`, no bias.
    pub x_proj: Linear,
    /// `dt_rank → d_inner`, with bias (the Δ bias).
    pub dt_proj: Linear,
    /// `[d_inner, d_state]`, `A = −exp(A_log)`.
    pub A_log: Param<Tensor<2>>,
    /// `[d_inner]` skip connection.
    pub D: Param<Tensor<1>>,
    /// `d_inner → d_model`, no bias.
    pub out_proj: Linear,
    pub d_inner: usize,
    pub d_state: usize,
    pub dt_rank: usize,
    #[module(skip)]
    pub scan: Scan,
}

impl MambaConfig {
    pub fn dt_rank(&self) -> usize {
        self.dt_rank.unwrap_or(self.d_model.div_ceil(16))
    }

    pub fn init(&self, device: &Device) -> Mamba {
        let d_inner = self.expand * self.d_model;
        let dt_rank = self.dt_rank();
        let n = self.d_state;
        let lin = |i, o, bias| LinearConfig::new(i, o).with_bias(bias).init(device);
        // dt_proj: weights uniform ±dt_rank^−½ ("dt_init=random", dt_scale 1); bias = softplus⁻¹
        // of Δ drawn log-uniformly in [dt_min, dt_max], floored (mamba_simple.py), so the initial
        // Δ spans the time scales the paper's S4D initialisation intends.
        let std = (dt_rank as f64).powf(-0.5);
        let mut dt_proj = LinearConfig::new(dt_rank, d_inner)
            .with_initializer(Initializer::Uniform {
                min: -std,
                max: std,
            })
            .init(device);
        let u: Vec<f32> = Tensor::<1>::random([d_inner], Distribution::Uniform(0.0, 1.0), device)
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .expect("f32 data");
        let (lo, hi) = (self.dt_min.ln(), self.dt_max.ln());
        let inv_softplus: Vec<f32> = u
            .iter()
            .map(|&r| {
                let dt = (f64::from(r) * (hi - lo) + lo)
                    .exp()
                    .max(self.dt_init_floor);
                (dt + (-(-dt).exp_m1()).ln()) as f32
            })
            .collect();
        dt_proj.bias = Some(Param::from_tensor(Tensor::from_data(
            TensorData::new(inv_softplus, [d_inner]),
            device,
        )));
        // S4D-real: A[i, n] = −(n + 1), stored as its log (Gu et al. 2022, "On the
        // parameterization and initialization of diagonal state space models").
        let a_log: Vec<f32> = (0..d_inner)
            .flat_map(|_| (1..=n).map(|k| (k as f32).ln()))
            .collect();
        Mamba {
            in_proj: lin(self.d_model, 2 * d_inner, false),
            conv1d: Conv1dConfig::new(d_inner, d_inner, self.d_conv)
                .with_groups(d_inner)
                .with_padding(PaddingConfig1d::Explicit(self.d_conv - 1, 0))
                .init(device),
            x_proj: lin(d_inner, dt_rank + 2 * n, false),
            dt_proj,
            A_log: Param::from_tensor(Tensor::from_data(
                TensorData::new(a_log, [d_inner, n]),
                device,
            )),
            D: Param::from_tensor(Tensor::ones([d_inner], device)),
            out_proj: lin(d_inner, self.d_model, false),
            d_inner,
            d_state: n,
            dt_rank,
            scan: self.scan,
        }
    }
}

/// The inputs of one selective scan (all batch-first).
#[derive(Clone, Debug)]
pub struct ScanInputs {
    /// `u` `[B, T, d_inner]`: the convolved, activated input.
    pub u: Tensor<3>,
    /// `Δ` `[B, T, d_inner]`, positive.
    pub delta: Tensor<3>,
    /// `A` `[d_inner, d_state]`, negative.
    pub a: Tensor<2>,
    /// `B` `[B, T, d_state]`.
    pub b: Tensor<3>,
    /// `C` `[B, T, d_state]`.
    pub c: Tensor<3>,
    /// `D` `[d_inner]`.
    pub d: Tensor<1>,
}

impl Mamba {
    /// `x` `[B, T, d_model]` → `[B, T, d_model]`, causal in time.
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        self.forward_with(x, self.scan)
    }

    /// [`Self::forward`] with an explicit scan implementation.
    pub fn forward_with(&self, x: Tensor<3>, scan: Scan) -> Tensor<3> {
        let (inputs, z) = self.scan_inputs(x);
        let y = match scan {
            Scan::Sequential => selective_scan_sequential(inputs),
            Scan::Chunked => selective_scan_chunked(inputs, None),
        };
        self.out_proj.forward(y * silu(z))
    }

    /// Steps 1–3 of the module docs: the scan's inputs and the gate `z` `[B, T, d_inner]`.
    pub fn scan_inputs(&self, x: Tensor<3>) -> (ScanInputs, Tensor<3>) {
        let [bs, t, _] = x.dims();
        let (di, n, r) = (self.d_inner, self.d_state, self.dt_rank);
        let xz = self.in_proj.forward(x);
        let z = xz.clone().narrow(2, di, di);
        // Conv1d is channels-first; the explicit (d_conv − 1, 0) padding keeps it causal and
        // the output T frames long.
        let u = silu(
            self.conv1d
                .forward(xz.narrow(2, 0, di).swap_dims(1, 2))
                .swap_dims(1, 2),
        );
        let dbc = self.x_proj.forward(u.clone());
        let dt = dbc.clone().narrow(2, 0, r);
        let b = dbc.clone().narrow(2, r, n);
        let c = dbc.narrow(2, r + n, n);
        let delta = softplus(self.dt_proj.forward(dt), 1.0);
        debug_assert_eq!(delta.dims(), [bs, t, di]);
        let inputs = ScanInputs {
            u,
            delta,
            a: self.A_log.val().exp().neg(),
            b,
            c,
            d: self.D.val(),
        };
        (inputs, z)
    }
}

/// `Δ·A` `[B, T, D, N]` and `Δ·B·u` `[B, T, D, N]`.
fn discretise(s: &ScanInputs) -> (Tensor<4>, Tensor<4>) {
    let da = s.delta.clone().unsqueeze_dim::<4>(3) * s.a.clone().unsqueeze::<4>();
    let dbu = (s.delta.clone() * s.u.clone()).unsqueeze_dim::<4>(3) * s.b.clone().unsqueeze_dim(2);
    (da, dbu)
}

/// The selective scan one frame at a time, exactly the recurrence of the module docs (the
/// reference `selective_scan_ref` of `mamba_simple`): the correctness baseline. Returns `y`
/// `[B, T, d_inner]` (before the gate).
pub fn selective_scan_sequential(s: ScanInputs) -> Tensor<3> {
    let [bs, t, di] = s.u.dims();
    let n = s.a.dims()[1];
    let (da, dbu) = discretise(&s);
    let decay = da.exp();
    let mut h: Tensor<3> = Tensor::zeros([bs, di, n], &s.u.device());
    let mut ys = Vec::with_capacity(t);
    for i in 0..t {
        let step = |v: &Tensor<4>| v.clone().narrow(1, i, 1).squeeze_dim::<3>(1);
        h = step(&decay) * h + step(&dbu);
        // C_t · h_t over the state: [B, D, N] ⊙ [B, 1, N] summed over N.
        let c = s.c.clone().narrow(1, i, 1);
        ys.push((h.clone() * c).sum_dim(2).squeeze_dim::<2>(2));
    }
    Tensor::stack::<3>(ys, 1) + s.u * s.d.unsqueeze::<3>()
}

/// The chunk length [`selective_scan_chunked`] uses: the longest, at most `max_chunk`, whose
/// worst-case `|Σ Δ·A|` stays within [`CHUNK_LOG_RANGE`], then evened out over the sequence so
/// the last chunk is not mostly padding.
pub fn chunk_len(max_abs_da: f32, frames: usize, max_chunk: usize) -> usize {
    let max_chunk = max_chunk.max(1);
    let limit = if max_abs_da > 0.0 && max_abs_da.is_finite() {
        ((CHUNK_LOG_RANGE / max_abs_da).floor() as usize).clamp(1, max_chunk)
    } else if max_abs_da == 0.0 {
        max_chunk
    } else {
        1
    };
    let chunks = frames.max(1).div_ceil(limit);
    frames.max(1).div_ceil(chunks)
}

/// The selective scan in chunks of `L` frames: within a chunk, with `S_t = Σ_{s≤t} Δ_s A` (from
/// the chunk start) and the chunk state `h⁰` at its start,
/// `h_t = exp(S_t) ⊙ h⁰ + exp(S_t − m) ⊙ Σ_{s≤t} exp(m − S_s) ⊙ Δ_s B_s u_s`,
/// i.e. one cumulative sum for all chunks at once (the log-space form of the cumulative product
/// of `exp(Δ A)`; `m` = half the chunk's total, detached, only bounds the exponentials). The
/// states at chunk boundaries are then carried sequentially (`T / L` steps on `[B, D, N]`
/// states). The backward is fast because nothing slices the `[B, T, D, N]` terms per frame:
/// their gradients flow through a handful of whole-tensor ops. Same result as
/// [`selective_scan_sequential`] to f32 rounding (`tests/parity_ssm.rs`).
///
/// `max_chunk`: the longest chunk to use, default [`MAX_CHUNK`]; the length actually used is
/// shortened by [`chunk_len`] so the chunk's exponentials cannot overflow (a host read of the
/// largest `|Δ·A|`; the bound is per element, so it holds for every chunk).
pub fn selective_scan_chunked(s: ScanInputs, max_chunk: Option<usize>) -> Tensor<3> {
    let [bs, t, di] = s.u.dims();
    let n = s.a.dims()[1];
    let device = s.u.device();
    // max |Δ·A| = max_d (max_{b,t} Δ) · (max_n |A|) (both factors ≥ 0), read from the small
    // tensors rather than the [B, T, D, N] product.
    let max_abs_da = {
        let dmax = s.delta.clone().detach().max_dim(1).max_dim(0).reshape([di]);
        let amax = s.a.clone().detach().abs().max_dim(1).reshape([di]);
        (dmax * amax).max().into_scalar::<f32>()
    };
    let l = chunk_len(max_abs_da, t, max_chunk.unwrap_or(MAX_CHUNK));
    let nc = t.div_ceil(l);
    let tp = nc * l;
    // Zero Δ (so zero Δ·A and Δ·B·u) and C after the last frame: padding never feeds back into
    // real frames. Padding the [B, T, ·] inputs is cheaper than padding the [B, T, D, N] terms.
    let pad = |v: &Tensor<3>| {
        if tp > t {
            let w = v.dims()[2];
            Tensor::cat(vec![v.clone(), Tensor::zeros([bs, tp - t, w], &device)], 1)
        } else {
            v.clone()
        }
    };
    let padded = ScanInputs {
        u: pad(&s.u),
        delta: pad(&s.delta),
        a: s.a.clone(),
        b: pad(&s.b),
        c: pad(&s.c),
        d: s.d.clone(),
    };
    let (da, dbu) = discretise(&padded);
    let da = da.reshape([bs, nc, l, di, n]);
    let dbu = dbu.reshape([bs, nc, l, di, n]);

    let cum = da.cumsum(2); // S_t, ≤ 0, decreasing within each chunk
    let mid = cum.clone().narrow(2, l - 1, 1).detach().mul_scalar(0.5);
    let grow = (cum.clone() - mid).exp(); // exp(S_t − m) ∈ [exp(−RANGE/2), exp(RANGE/2)]
    let local = grow.clone() * (grow.recip() * dbu).cumsum(2);
    let decay = cum.exp(); // exp(S_t): decay of the chunk's start state

    // Carry: h⁰_{c+1} = exp(S_end,c) ⊙ h⁰_c + local_end,c.
    let decay_end = decay.clone().narrow(2, l - 1, 1).squeeze_dim::<4>(2);
    let local_end = local.clone().narrow(2, l - 1, 1).squeeze_dim::<4>(2);
    let mut h0: Tensor<3> = Tensor::zeros([bs, di, n], &device);
    let mut starts = Vec::with_capacity(nc);
    for ci in 0..nc {
        starts.push(h0.clone());
        if ci + 1 < nc {
            let at = |v: &Tensor<4>| v.clone().narrow(1, ci, 1).squeeze_dim::<3>(1);
            h0 = at(&decay_end) * h0 + at(&local_end);
        }
    }
    let starts = Tensor::stack::<4>(starts, 1).unsqueeze_dim::<5>(2); // [B, nc, 1, D, N]
    let h = local + decay * starts;

    let c = padded.c.reshape([bs, nc, l, 1, n]);
    let y = (h * c).sum_dim(4).reshape([bs, tp, di]).narrow(1, 0, t);
    y + s.u * s.d.unsqueeze::<3>()
}

/// Configuration of [`MambaBlock`].
#[derive(Config, Debug)]
pub struct MambaBlockConfig {
    pub mamba: MambaConfig,
    /// LayerNorm epsilon (PyTorch's default, as in [`crate::transformer::LAYER_NORM_EPS`]).
    #[config(default = 1e-5)]
    pub norm_eps: f64,
}

/// Pre-norm residual Mamba block, `x + mamba(norm(x))`, the form TCDiff++'s decoder layer wraps
/// its SSM in. TCDiff++'s linear cross-attention term is not included (see the module docs).
#[derive(Module, Debug)]
pub struct MambaBlock {
    pub norm: LayerNorm,
    pub mamba: Mamba,
}

impl MambaBlockConfig {
    pub fn init(&self, device: &Device) -> MambaBlock {
        MambaBlock {
            norm: LayerNormConfig::new(self.mamba.d_model)
                .with_epsilon(self.norm_eps)
                .init(device),
            mamba: self.mamba.init(device),
        }
    }
}

impl MambaBlock {
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        x.clone() + self.mamba.forward(self.norm.forward(x))
    }
}
