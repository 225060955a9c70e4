//! Multi-head attention with masks: self-attention (EDGE/Lodge decoders, GPT) and
//! cross-attention (music tokens in EDGE/Lodge, the leader in ReactDance).
//!
//! Separate `q_proj`/`k_proj`/`v_proj`/`out_proj` Linear layers (PyTorch `[out, in]` weights in a
//! checkpoint). Queries, keys and values come in separately so that a rotary encoding can be
//! applied to the query/key input only, as EDGE does (`rotary(x)` for q and k, plain `x` for v).
//! The scaled dot product runs in Burn's fused `attention` op (flash-style tiling on long
//! sequences in burn-flex); dropout is applied to the output, not to the attention weights, which
//! the fused op does not expose.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Dropout, DropoutConfig, Linear, LinearConfig};
use burn::tensor::module::attention;
use burn::tensor::ops::AttentionModuleOptions;
use burn::tensor::{Bool, Tensor};

/// Configuration of [`MultiHeadAttention`].
#[derive(Config, Debug)]
pub struct MultiHeadAttentionConfig {
    /// Model width (queries and output).
    pub d_model: usize,
    /// Heads; must divide `d_model`.
    pub n_heads: usize,
    /// Width of the key/value input (cross-attention to another stream); default `d_model`.
    #[config(default = "None")]
    pub d_context: Option<usize>,
    /// Bias in the four projections (PyTorch's default).
    #[config(default = true)]
    pub bias: bool,
    /// Dropout on the attention output.
    #[config(default = 0.0)]
    pub dropout: f64,
}

/// Multi-head scaled dot-product attention.
#[derive(Module, Debug)]
pub struct MultiHeadAttention {
    pub q_proj: Linear,
    pub k_proj: Linear,
    pub v_proj: Linear,
    pub out_proj: Linear,
    pub dropout: Dropout,
    pub n_heads: usize,
}

impl MultiHeadAttentionConfig {
    pub fn init(&self, device: &burn::tensor::Device) -> MultiHeadAttention {
        assert!(
            self.n_heads > 0 && self.d_model.is_multiple_of(self.n_heads),
            "d_model {} is not divisible by n_heads {}",
            self.d_model,
            self.n_heads
        );
        let d_ctx = self.d_context.unwrap_or(self.d_model);
        let lin = |i, o| LinearConfig::new(i, o).with_bias(self.bias).init(device);
        MultiHeadAttention {
            q_proj: lin(self.d_model, self.d_model),
            k_proj: lin(d_ctx, self.d_model),
            v_proj: lin(d_ctx, self.d_model),
            out_proj: lin(self.d_model, self.d_model),
            dropout: DropoutConfig::new(self.dropout).init(),
            n_heads: self.n_heads,
        }
    }
}

/// Optional masks of one attention call.
#[derive(Clone, Debug, Default)]
pub struct AttnMasks {
    /// `[queries, keys]`, `true` = blocked (see [`crate::mask::AttnMask`]).
    pub attn: Option<Tensor<2, Bool>>,
    /// `[batch, keys]`, `true` = padding (never attended).
    pub key_padding: Option<Tensor<2, Bool>>,
}

impl MultiHeadAttention {
    /// Attention of `query` `[B, Tq, d_model]` over `key`/`value` `[B, Tk, d_context]`.
    pub fn forward(
        &self,
        query: Tensor<3>,
        key: Tensor<3>,
        value: Tensor<3>,
        masks: &AttnMasks,
    ) -> Tensor<3> {
        let q = self.split_heads(self.q_proj.forward(query));
        let k = self.split_heads(self.k_proj.forward(key));
        let v = self.split_heads(self.v_proj.forward(value));
        self.attend(q, k, v, masks)
    }

    /// Attention on already projected, head-split `q` `[B, H, Tq, dh]`, `k`/`v` `[B, H, Tk, dh]`
    /// (the KV-cache path), followed by the output projection.
    pub fn attend(&self, q: Tensor<4>, k: Tensor<4>, v: Tensor<4>, masks: &AttnMasks) -> Tensor<3> {
        let [b, h, tq, dh] = q.dims();
        let tk = k.dims()[2];
        let mask = combined_mask(masks, b, h, tq, tk);
        let out = attention(q, k, v, mask, None, AttentionModuleOptions::default());
        let out = out.swap_dims(1, 2).reshape([b, tq, h * dh]);
        self.dropout.forward(self.out_proj.forward(out))
    }

    /// `[B, T, d]` → `[B, H, T, d / H]`.
    pub fn split_heads(&self, x: Tensor<3>) -> Tensor<4> {
        let [b, t, d] = x.dims();
        x.reshape([b, t, self.n_heads, d / self.n_heads])
            .swap_dims(1, 2)
    }
}

/// The attention and key-padding masks broadcast to `[B, H, Tq, Tk]`.
fn combined_mask(
    masks: &AttnMasks,
    b: usize,
    h: usize,
    tq: usize,
    tk: usize,
) -> Option<Tensor<4, Bool>> {
    let attn = masks.attn.clone().map(|m| {
        assert_eq!(m.dims(), [tq, tk], "attention mask shape");
        m.reshape([1, 1, tq, tk]).expand([b, h, tq, tk])
    });
    let pad = masks.key_padding.clone().map(|m| {
        assert_eq!(m.dims(), [b, tk], "key padding mask shape");
        m.reshape([b, 1, 1, tk]).expand([b, h, tq, tk])
    });
    match (attn, pad) {
        (Some(a), Some(p)) => Some(a.bool_or(p)),
        (a, p) => a.or(p),
    }
}
