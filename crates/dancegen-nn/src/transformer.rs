//! Transformer layers.
//!
//! - [`EncoderLayer`]: PyTorch `nn.TransformerEncoderLayer` semantics (post-norm by default,
//!   `norm_first` for pre-norm), optional rotary on the self-attention query/key input as in
//!   EDGE's music encoder.
//! - [`FilmDecoderLayer`]: EDGE's `FiLMTransformerDecoderLayer` (norm-first): self-attention,
//!   cross-attention to the conditioning tokens, feed-forward, each branch FiLM-modulated by the
//!   conditioning vector before its residual add:
//!   `x += film_k(c)(branch_k(norm_k(x)))`. Lodge, Lodge++ and TCDiff++ reuse it.
//!
//! Parameter names: `self_attn`, `cross_attn`, `ff.linear1/linear2`, `norm1..3`, `film1..3`.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Dropout, DropoutConfig, LayerNorm, LayerNormConfig};
use burn::tensor::{Device, Tensor};

use crate::attention::{AttnMasks, MultiHeadAttention, MultiHeadAttentionConfig, ProjectedKv};
use crate::film::{Film, FilmConfig};
use crate::mlp::{Activation, Mlp, MlpConfig};
use crate::pos_encoding::RotaryTables;

/// PyTorch's LayerNorm epsilon.
pub const LAYER_NORM_EPS: f64 = 1e-5;

/// Configuration of [`EncoderLayer`].
#[derive(Config, Debug)]
pub struct EncoderLayerConfig {
    pub d_model: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    #[config(default = 0.0)]
    pub dropout: f64,
    #[config(default = "Activation::Gelu")]
    pub activation: Activation,
    /// Pre-norm (`true`) or PyTorch's default post-norm.
    #[config(default = false)]
    pub norm_first: bool,
}

/// One Transformer encoder layer.
#[derive(Module, Debug)]
pub struct EncoderLayer {
    pub self_attn: MultiHeadAttention,
    pub ff: Mlp,
    pub norm1: LayerNorm,
    pub norm2: LayerNorm,
    pub dropout1: Dropout,
    pub dropout2: Dropout,
    pub norm_first: bool,
}

fn layer_norm(d: usize, device: &Device) -> LayerNorm {
    LayerNormConfig::new(d)
        .with_epsilon(LAYER_NORM_EPS)
        .init(device)
}

impl EncoderLayerConfig {
    pub fn init(&self, device: &Device) -> EncoderLayer {
        EncoderLayer {
            self_attn: MultiHeadAttentionConfig::new(self.d_model, self.n_heads).init(device),
            ff: MlpConfig::new(self.d_model, self.d_ff, self.d_model)
                .with_activation(self.activation)
                .with_dropout(self.dropout)
                .init(device),
            norm1: layer_norm(self.d_model, device),
            norm2: layer_norm(self.d_model, device),
            dropout1: DropoutConfig::new(self.dropout).init(),
            dropout2: DropoutConfig::new(self.dropout).init(),
            norm_first: self.norm_first,
        }
    }
}

impl EncoderLayer {
    /// `rotary`: tables for the frames of `x` (EDGE's music encoder), or `None`.
    pub fn forward(
        &self,
        x: Tensor<3>,
        masks: &AttnMasks,
        rotary: Option<&RotaryTables>,
    ) -> Tensor<3> {
        let sa = |h: Tensor<3>| {
            let qk = rotary.map_or(h.clone(), |r| r.rotate(h.clone()));
            self.dropout1
                .forward(self.self_attn.forward(qk.clone(), qk, h, masks))
        };
        if self.norm_first {
            let x = x.clone() + sa(self.norm1.forward(x));
            x.clone()
                + self
                    .dropout2
                    .forward(self.ff.forward(self.norm2.forward(x)))
        } else {
            let x = self.norm1.forward(x.clone() + sa(x));
            self.norm2
                .forward(x.clone() + self.dropout2.forward(self.ff.forward(x)))
        }
    }
}

/// Configuration of [`FilmDecoderLayer`].
#[derive(Config, Debug)]
pub struct FilmDecoderLayerConfig {
    pub d_model: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    /// Width of the cross-attention tokens (default `d_model`).
    #[config(default = "None")]
    pub d_context: Option<usize>,
    #[config(default = 0.0)]
    pub dropout: f64,
    #[config(default = "Activation::Gelu")]
    pub activation: Activation,
}

/// EDGE's FiLM Transformer decoder layer (norm-first).
#[derive(Module, Debug)]
pub struct FilmDecoderLayer {
    pub self_attn: MultiHeadAttention,
    pub cross_attn: MultiHeadAttention,
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

impl FilmDecoderLayerConfig {
    pub fn init(&self, device: &Device) -> FilmDecoderLayer {
        let d = self.d_model;
        FilmDecoderLayer {
            self_attn: MultiHeadAttentionConfig::new(d, self.n_heads).init(device),
            cross_attn: MultiHeadAttentionConfig::new(d, self.n_heads)
                .with_d_context(self.d_context)
                .init(device),
            ff: MlpConfig::new(d, self.d_ff, d)
                .with_activation(self.activation)
                .with_dropout(self.dropout)
                .init(device),
            norm1: layer_norm(d, device),
            norm2: layer_norm(d, device),
            norm3: layer_norm(d, device),
            film1: FilmConfig::new(d).init(device),
            film2: FilmConfig::new(d).init(device),
            film3: FilmConfig::new(d).init(device),
            dropout1: DropoutConfig::new(self.dropout).init(),
            dropout2: DropoutConfig::new(self.dropout).init(),
            dropout3: DropoutConfig::new(self.dropout).init(),
        }
    }
}

/// Inputs of a [`FilmDecoderLayer`] besides the sequence.
pub struct DecoderContext<'a> {
    /// Cross-attention tokens `[B, Tm, d_context]`.
    pub memory: Tensor<3>,
    /// FiLM conditioning `[B, 1, d_model]` (one vector per sequence, EDGE) or `[B, T, d_model]`
    /// (one per frame, ReactDance's music).
    pub cond: Tensor<3>,
    pub self_masks: &'a AttnMasks,
    pub cross_masks: &'a AttnMasks,
    /// Rotary tables for the self-attention query/key input (EDGE), `[1, T, d_model]`.
    pub rotary: Option<&'a RotaryTables>,
}

impl FilmDecoderLayer {
    pub fn forward(&self, x: Tensor<3>, ctx: &DecoderContext) -> Tensor<3> {
        self.forward_with_kv(x, ctx, None)
    }

    /// The cross-attention keys and values of `memory`, to reuse over calls that share it
    /// ([`Self::forward_with_kv`]).
    pub fn cross_kv(&self, memory: Tensor<3>) -> ProjectedKv {
        self.cross_attn.project_kv(memory.clone(), memory)
    }

    /// [`Self::forward`]; `kv`, when given, must be [`Self::cross_kv`] of `ctx.memory`.
    pub fn forward_with_kv(
        &self,
        x: Tensor<3>,
        ctx: &DecoderContext,
        kv: Option<&ProjectedKv>,
    ) -> Tensor<3> {
        let h = self.norm1.forward(x.clone());
        let qk = ctx.rotary.map_or(h.clone(), |r| r.rotate(h.clone()));
        let sa = self
            .dropout1
            .forward(self.self_attn.forward(qk.clone(), qk, h, ctx.self_masks));
        let x = x + self.film1.modulate(sa, ctx.cond.clone());

        let h = self.norm2.forward(x.clone());
        let ca = match kv {
            Some(kv) => self.cross_attn.forward_projected(h, kv, ctx.cross_masks),
            None => {
                self.cross_attn
                    .forward(h, ctx.memory.clone(), ctx.memory.clone(), ctx.cross_masks)
            }
        };
        let ca = self.dropout2.forward(ca);
        let x = x + self.film2.modulate(ca, ctx.cond.clone());

        let ff = self
            .dropout3
            .forward(self.ff.forward(self.norm3.forward(x.clone())));
        x + self.film3.modulate(ff, ctx.cond.clone())
    }
}
