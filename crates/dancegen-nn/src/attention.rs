//! Multi-head attention with masks: self-attention (EDGE/Lodge decoders, GPT) and
//! cross-attention (music tokens in EDGE/Lodge, the leader in ReactDance).
//!
//! Separate `q_proj`/`k_proj`/`v_proj`/`out_proj` Linear layers (PyTorch `[out, in]` weights in a
//! checkpoint). Queries, keys and values come in separately so that a rotary encoding can be
//! applied to the query/key input only, as EDGE does (`rotary(x)` for q and k, plain `x` for v).
//! The scaled dot product runs in Burn's fused `attention` op (flash-style tiling on long
//! sequences in burn-flex) when training, and in [`crate::host_attention`] at inference; dropout is applied to the output, not to the attention weights, which
//! the fused op does not expose.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Dropout, DropoutConfig, Linear, LinearConfig};
use burn::tensor::module::attention;
use burn::tensor::ops::AttentionModuleOptions;
use burn::tensor::{Bool, Tensor};

use crate::host_attention::{self, HostKv};
use crate::host_linear;
use std::sync::Arc;

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

/// Projected keys and values `[B, Tk, d_model]` (before the head split), with a host copy
/// for inference.
#[derive(Clone, Debug)]
pub struct ProjectedKv {
    pub k: Tensor<3>,
    pub v: Tensor<3>,
    host: Option<Arc<HostKv>>,
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
        let q = host_linear::forward(&self.q_proj, query);
        let k = host_linear::forward(&self.k_proj, key);
        let v = host_linear::forward(&self.v_proj, value);
        if host_attention::eligible(&q) {
            let kv = HostKv::new(k, v);
            return self.host(q, &kv, masks);
        }
        let (q, k, v) = (
            self.split_heads(q),
            self.split_heads(k),
            self.split_heads(v),
        );
        self.attend(q, k, v, masks)
    }

    /// The key/value projections of a context that stays the same over many calls (the music of
    /// a diffusion sampler's every step), for [`Self::forward_projected`].
    pub fn project_kv(&self, key: Tensor<3>, value: Tensor<3>) -> ProjectedKv {
        let k = host_linear::forward(&self.k_proj, key);
        let v = host_linear::forward(&self.v_proj, value);
        let host =
            host_attention::eligible(&k).then(|| Arc::new(HostKv::new(k.clone(), v.clone())));
        ProjectedKv { k, v, host }
    }

    /// [`Self::forward`] with the keys and values already projected.
    pub fn forward_projected(
        &self,
        query: Tensor<3>,
        kv: &ProjectedKv,
        masks: &AttnMasks,
    ) -> Tensor<3> {
        let q = host_linear::forward(&self.q_proj, query);
        if let Some(host) = &kv.host
            && host_attention::eligible(&q)
        {
            return self.host(q, host, masks);
        }
        let (q, k, v) = (
            self.split_heads(q),
            self.split_heads(kv.k.clone()),
            self.split_heads(kv.v.clone()),
        );
        self.attend(q, k, v, masks)
    }

    /// Inference: [`host_attention`], then the output projection.
    fn host(&self, q: Tensor<3>, kv: &HostKv, masks: &AttnMasks) -> Tensor<3> {
        let out = host_attention::attention(
            q,
            kv,
            self.n_heads,
            masks.attn.as_ref(),
            masks.key_padding.as_ref(),
        );
        self.dropout
            .forward(host_linear::forward(&self.out_proj, out))
    }

    /// Attention on already projected, head-split `q` `[B, H, Tq, dh]`, `k`/`v` `[B, H, Tk, dh]`
    /// (the KV-cache path), followed by the output projection.
    pub fn attend(&self, q: Tensor<4>, k: Tensor<4>, v: Tensor<4>, masks: &AttnMasks) -> Tensor<3> {
        let [b, h, tq, dh] = q.dims();
        let tk = k.dims()[2];
        let mask = combined_mask(masks, b, h, tq, tk);
        let out = attention(q, k, v, mask, None, AttentionModuleOptions::default());
        let out = out.swap_dims(1, 2).reshape([b, tq, h * dh]);
        self.dropout
            .forward(host_linear::forward(&self.out_proj, out))
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
