//! 1D convolutional residual encoder/decoder with temporal down/up-sampling (T2M-GPT/MoMask).
//!
//! Source: `Mael-zys/T2M-GPT:models/encdec.py` and `models/resnet.py` (also
//! `EricGuo5513/momask-codes:models/vq/encdec.py`, the same modules); Lodge++'s VQ-VAE uses them
//! with `down_t 2, stride_t 2, width 1024, depth 3, dilation growth 3, code_dim 1024`
//! (anchors D.3, [`ConvCodecConfig::lodgepp`]).
//!
//! - [`ConvEncoder`]: `Conv1d(in, width, 3, pad 1)` + ReLU, then `down_t` × [`Conv1d(width,
//!   width, 2·stride_t, stride stride_t, pad stride_t/2)`, [`Resnet1D`]], then
//!   `Conv1d(width, code_dim, 3, pad 1)`: `T` frames → `T / stride_t^down_t`.
//! - [`ConvDecoder`]: `Conv1d(code_dim, width, 3)` + ReLU, `down_t` × [[`Resnet1D`] (reversed
//!   dilations), nearest upsample ×2, `Conv1d(width, width, 3)`], `Conv1d(width, width, 3)` +
//!   ReLU, `Conv1d(width, out, 3)`.
//! - [`Resnet1D`]: `depth` blocks `x + conv2(relu(conv1(relu(x))))`, `conv1 = Conv1d(w, w, 3,
//!   dilation d, pad d)`, `conv2 = Conv1d(w, w, 1)`, dilations `growth^i` for `i = 0..depth`.
//!   T2M-GPT's `Resnet1D` defaults to `reverse_dilation=True` and its encoder does not override
//!   it, so the encoder's dilations run `growth^(depth−1) … 1` too unless
//!   [`ConvCodecConfig::encoder_reverse_dilation`] is false.
//!
//! The API is batch-first `[B, T, C]`; inside, tensors are `[B, C, T]` as Burn's `Conv1d` wants.
//! Parameter names are descriptive (`conv_in`, `down.i.conv`, `down.i.resnet.blocks.j.conv1`, …)
//! rather than T2M-GPT's `nn.Sequential` indices; `tools/parity/quant.py` builds the reference
//! with the same names.

use burn::config::Config;
use burn::module::Module;
use burn::nn::PaddingConfig1d;
use burn::nn::conv::{Conv1d, Conv1dConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

/// Configuration of [`ConvEncoder`] / [`ConvDecoder`] (T2M-GPT `Encoder`/`Decoder` arguments).
#[derive(Config, Debug)]
pub struct ConvCodecConfig {
    /// Motion features per frame (encoder input).
    pub input_dim: usize,
    /// Decoder output features per frame (usually `input_dim`).
    pub output_dim: usize,
    /// Hidden channels.
    #[config(default = 512)]
    pub width: usize,
    /// Residual blocks per [`Resnet1D`].
    #[config(default = 3)]
    pub depth: usize,
    /// Number of down-sampling (encoder) / up-sampling (decoder) stages.
    #[config(default = 2)]
    pub down_t: usize,
    /// Temporal stride of each encoder down-sampling conv (the decoder always upsamples ×2).
    #[config(default = 2)]
    pub stride_t: usize,
    #[config(default = 3)]
    pub dilation_growth_rate: usize,
    /// Latent channels.
    #[config(default = 512)]
    pub code_dim: usize,
    /// T2M-GPT: the encoder's `Resnet1D` keeps its default `reverse_dilation=True`.
    #[config(default = true)]
    pub encoder_reverse_dilation: bool,
}

impl ConvCodecConfig {
    /// Lodge++'s VQ-VAE codec (anchors D.3) for `dim`-d motion (139 for FineDance).
    pub fn lodgepp(dim: usize) -> Self {
        ConvCodecConfig::new(dim, dim)
            .with_width(1024)
            .with_depth(3)
            .with_down_t(2)
            .with_stride_t(2)
            .with_dilation_growth_rate(3)
            .with_code_dim(1024)
    }

    /// Frames of latent per input frames (`stride_t^down_t`).
    pub fn downsampling(&self) -> usize {
        self.stride_t.pow(self.down_t as u32)
    }

    pub fn init_encoder(&self, device: &Device) -> ConvEncoder {
        let (k, s) = (2 * self.stride_t, self.stride_t);
        ConvEncoder {
            conv_in: conv(self.input_dim, self.width, 3, 1, 1, 1, device),
            down: (0..self.down_t)
                .map(|_| DownBlock {
                    conv: conv(self.width, self.width, k, s, s / 2, 1, device),
                    resnet: self.resnet(self.encoder_reverse_dilation, device),
                })
                .collect(),
            conv_out: conv(self.width, self.code_dim, 3, 1, 1, 1, device),
        }
    }

    pub fn init_decoder(&self, device: &Device) -> ConvDecoder {
        ConvDecoder {
            conv_in: conv(self.code_dim, self.width, 3, 1, 1, 1, device),
            up: (0..self.down_t)
                .map(|_| UpBlock {
                    resnet: self.resnet(true, device),
                    conv: conv(self.width, self.width, 3, 1, 1, 1, device),
                })
                .collect(),
            conv_mid: conv(self.width, self.width, 3, 1, 1, 1, device),
            conv_out: conv(self.width, self.output_dim, 3, 1, 1, 1, device),
        }
    }

    fn resnet(&self, reverse: bool, device: &Device) -> Resnet1D {
        let mut dil: Vec<usize> = (0..self.depth)
            .map(|i| self.dilation_growth_rate.pow(i as u32))
            .collect();
        if reverse {
            dil.reverse();
        }
        Resnet1D {
            blocks: dil
                .into_iter()
                .map(|d| ResBlock {
                    conv1: conv(self.width, self.width, 3, 1, d, d, device),
                    conv2: conv(self.width, self.width, 1, 1, 0, 1, device),
                })
                .collect(),
        }
    }
}

fn conv(
    c_in: usize,
    c_out: usize,
    k: usize,
    stride: usize,
    pad: usize,
    dilation: usize,
    device: &Device,
) -> Conv1d {
    Conv1dConfig::new(c_in, c_out, k)
        .with_stride(stride)
        .with_dilation(dilation)
        .with_padding(PaddingConfig1d::Explicit(pad, pad))
        .init(device)
}

/// T2M-GPT `ResConv1DBlock` without norm: `x + conv2(relu(conv1(relu(x))))`.
#[derive(Module, Debug)]
pub struct ResBlock {
    pub conv1: Conv1d,
    pub conv2: Conv1d,
}

impl ResBlock {
    /// `[B, C, T]` → `[B, C, T]`.
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        let h = self
            .conv2
            .forward(relu(self.conv1.forward(relu(x.clone()))));
        x + h
    }
}

/// T2M-GPT `Resnet1D`: a stack of dilated [`ResBlock`]s.
#[derive(Module, Debug)]
pub struct Resnet1D {
    pub blocks: Vec<ResBlock>,
}

impl Resnet1D {
    /// `[B, C, T]` → `[B, C, T]`.
    pub fn forward(&self, mut x: Tensor<3>) -> Tensor<3> {
        for b in &self.blocks {
            x = b.forward(x);
        }
        x
    }

    /// Dilation of each block, in order.
    pub fn dilations(&self) -> Vec<usize> {
        self.blocks.iter().map(|b| b.conv1.dilation).collect()
    }
}

/// Strided conv + [`Resnet1D`].
#[derive(Module, Debug)]
pub struct DownBlock {
    pub conv: Conv1d,
    pub resnet: Resnet1D,
}

/// [`Resnet1D`] + nearest ×2 upsampling + conv.
#[derive(Module, Debug)]
pub struct UpBlock {
    pub resnet: Resnet1D,
    pub conv: Conv1d,
}

/// T2M-GPT `Encoder` (see the module documentation).
#[derive(Module, Debug)]
pub struct ConvEncoder {
    pub conv_in: Conv1d,
    pub down: Vec<DownBlock>,
    pub conv_out: Conv1d,
}

impl ConvEncoder {
    /// `[B, T, input_dim]` → `[B, T / stride_t^down_t, code_dim]`.
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        let mut h = relu(self.conv_in.forward(x.swap_dims(1, 2)));
        for d in &self.down {
            h = d.resnet.forward(d.conv.forward(h));
        }
        self.conv_out.forward(h).swap_dims(1, 2)
    }
}

/// T2M-GPT `Decoder` (see the module documentation).
#[derive(Module, Debug)]
pub struct ConvDecoder {
    pub conv_in: Conv1d,
    pub up: Vec<UpBlock>,
    pub conv_mid: Conv1d,
    pub conv_out: Conv1d,
}

/// `nn.Upsample(scale_factor=2, mode='nearest')` on `[B, C, T]`: every frame repeated twice.
pub fn upsample_nearest2(x: Tensor<3>) -> Tensor<3> {
    let [b, c, t] = x.dims();
    x.unsqueeze_dim::<4>(3)
        .repeat_dim(3, 2)
        .reshape([b, c, 2 * t])
}

impl ConvDecoder {
    /// `[B, T', code_dim]` → `[B, T' · 2^down_t, output_dim]`.
    pub fn forward(&self, z: Tensor<3>) -> Tensor<3> {
        let mut h = relu(self.conv_in.forward(z.swap_dims(1, 2)));
        for u in &self.up {
            h = u.conv.forward(upsample_nearest2(u.resnet.forward(h)));
        }
        let h = relu(self.conv_mid.forward(h));
        self.conv_out.forward(h).swap_dims(1, 2)
    }
}
