//! The Mamba variant of the Sequence Decoder layer (paper §4.1 "Sequence Decoder"; released
//! `FiLMMambaDecoderLayer`, group.md §1 row 4, anchors D.4):
//! `self-attention → FiLM → CrossMamba → FiLM → feed-forward → FiLM`, each branch pre-normed
//! and added to the residual, like [`dancegen_nn::transformer::FilmDecoderLayer`] with the
//! cross-attention branch replaced.
//!
//! `CrossMamba` = Mamba v1 (`dancegen_nn::ssm`) whose gated output gets a linear
//! cross-attention to the memory added through `c_linear (d → d_inner)` just before
//! `out_proj` — the released slow path. The fused fast path drops that term (P5); we always
//! add it. The scan is causal over all `T · N` frame-major tokens, as released.
//!
//! Linear cross-attention (Shen et al. 2021, "Efficient Attention", the released
//! `LinearCrossAttention`): per head, `softmax` over the features of each query and over the
//! sequence of the keys, `out = Q (Kᵀ V)`, linear in both lengths.

use dancegen_nn::attention::{MultiHeadAttention, MultiHeadAttentionConfig};
use dancegen_nn::burn;
use dancegen_nn::film::{Film, FilmConfig};
use dancegen_nn::mlp::{Activation, Mlp, MlpConfig};
use dancegen_nn::ssm::{
    Mamba, MambaConfig, Scan, selective_scan_chunked, selective_scan_sequential,
};
use dancegen_nn::transformer::{DecoderContext, LAYER_NORM_EPS};

use burn::module::Module;
use burn::nn::{Dropout, DropoutConfig, LayerNorm, LayerNormConfig, Linear, LinearConfig};
use burn::tensor::activation::{silu, softmax};
use burn::tensor::{Device, Tensor};

/// See the module documentation.
#[derive(Module, Debug)]
pub struct LinearCrossAttention {
    pub q_proj: Linear,
    pub k_proj: Linear,
    pub v_proj: Linear,
    #[module(skip)]
    pub n_heads: usize,
}

impl LinearCrossAttention {
    pub fn new(d: usize, n_heads: usize, device: &Device) -> Self {
        Self {
            q_proj: LinearConfig::new(d, d).init(device),
            k_proj: LinearConfig::new(d, d).init(device),
            v_proj: LinearConfig::new(d, d).init(device),
            n_heads,
        }
    }

    fn heads(&self, x: Tensor<3>) -> Tensor<4> {
        let [b, t, d] = x.dims();
        x.reshape([b, t, self.n_heads, d / self.n_heads])
            .swap_dims(1, 2)
    }

    /// `x` `[B, T, d]` attends to `memory` `[B, M, d]` → `[B, T, d]`.
    pub fn forward(&self, x: Tensor<3>, memory: Tensor<3>) -> Tensor<3> {
        let [b, t, d] = x.dims();
        let q = softmax(self.heads(self.q_proj.forward(x)), 3);
        let k = softmax(self.heads(self.k_proj.forward(memory.clone())), 2);
        let v = self.heads(self.v_proj.forward(memory));
        let context = k.swap_dims(2, 3).matmul(v);
        q.matmul(context).swap_dims(1, 2).reshape([b, t, d])
    }
}

/// Mamba plus the linear cross-attention term.
#[derive(Module, Debug)]
pub struct CrossMamba {
    pub mamba: Mamba,
    pub cross: LinearCrossAttention,
    pub c_linear: Linear,
}

impl CrossMamba {
    pub fn new(d: usize, n_heads: usize, device: &Device) -> Self {
        let mamba = MambaConfig::new(d).init(device);
        let d_inner = mamba.d_inner;
        Self {
            mamba,
            cross: LinearCrossAttention::new(d, n_heads, device),
            c_linear: LinearConfig::new(d, d_inner).init(device),
        }
    }

    pub fn forward(&self, x: Tensor<3>, memory: Tensor<3>) -> Tensor<3> {
        let (inputs, z) = self.mamba.scan_inputs(x.clone());
        let y = match self.mamba.scan {
            Scan::Sequential => selective_scan_sequential(inputs),
            Scan::Chunked => selective_scan_chunked(inputs, None),
        };
        let y = y * silu(z) + self.c_linear.forward(self.cross.forward(x, memory));
        self.mamba.out_proj.forward(y)
    }
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct CrossMambaLayer {
    pub self_attn: MultiHeadAttention,
    pub mixer: CrossMamba,
    pub ff: Mlp,
    pub norm1: LayerNorm,
    pub norm2: LayerNorm,
    pub norm3: LayerNorm,
    pub film1: Film,
    pub film2: Film,
    pub film3: Film,
    pub dropout1: Dropout,
    pub dropout2: Dropout,
    pub dropout3: Dropout,
}

impl CrossMambaLayer {
    pub fn new(d: usize, n_heads: usize, d_ff: usize, dropout: f64, device: &Device) -> Self {
        let norm = || {
            LayerNormConfig::new(d)
                .with_epsilon(LAYER_NORM_EPS)
                .init(device)
        };
        Self {
            self_attn: MultiHeadAttentionConfig::new(d, n_heads).init(device),
            mixer: CrossMamba::new(d, n_heads, device),
            ff: MlpConfig::new(d, d_ff, d)
                .with_activation(Activation::Gelu)
                .with_dropout(dropout)
                .init(device),
            norm1: norm(),
            norm2: norm(),
            norm3: norm(),
            film1: FilmConfig::new(d).init(device),
            film2: FilmConfig::new(d).init(device),
            film3: FilmConfig::new(d).init(device),
            dropout1: DropoutConfig::new(dropout).init(),
            dropout2: DropoutConfig::new(dropout).init(),
            dropout3: DropoutConfig::new(dropout).init(),
        }
    }

    /// Same context as the transformer layer; `ctx.cross_masks` is unused (the linear
    /// attention has no mask, and the memory never has padding).
    pub fn forward(&self, x: Tensor<3>, ctx: &DecoderContext) -> Tensor<3> {
        let h = self.norm1.forward(x.clone());
        let sa =
            self.dropout1.forward(
                self.self_attn
                    .forward(h.clone(), h.clone(), h, ctx.self_masks),
            );
        let x = x + self.film1.modulate(sa, ctx.cond.clone());
        let h = self.norm2.forward(x.clone());
        let m = self
            .dropout2
            .forward(self.mixer.forward(h, ctx.memory.clone()));
        let x = x + self.film2.modulate(m, ctx.cond.clone());
        let ff = self
            .dropout3
            .forward(self.ff.forward(self.norm3.forward(x.clone())));
        x + self.film3.modulate(ff, ctx.cond.clone())
    }
}
