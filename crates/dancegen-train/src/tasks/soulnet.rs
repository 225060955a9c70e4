//! SoulNet's part autoencoder (`dancegen_nn::part_autoencoder`, the HRVQ-VAE of issue 19) on
//! holistic windows `[body 263 | hands 360 | face 52]` (`representation = "holistic"`).
//!
//! `[model]` keys (defaults in brackets; SoulNet's own values in `holistic.md` §1.2 are width
//! 512, depth 3, 512 codes × 512, 6 levels, which do not fit this machine's budget):
//!
//! ```toml
//! kind = "soulnet_vq"
//! quantizer = "hrvq"        # "hrvq" (linked) | "rvq" (independent stacks) | "vq" (one level)
//! num_quantizers = 6        # residual levels (hrvq, rvq) [6]
//! nb_code = 512             # codes per codebook [512]
//! code_dim = 128            # one part's latent width [128]
//! mu = 0.99                 # EMA decay [0.99]
//! quantize_dropout_prob = 0.2   # [0.2]
//! width = 256               # conv channels [256]
//! depth = 2                 # residual blocks per stage [2]
//! down_t = 2                # ×2 downsamplings [2]
//! dilation_growth_rate = 3  # [3]
//! recon = "smooth_l1"       # "l1" | "l2" | "smooth_l1" [smooth_l1, as SoulNet]
//! part_weights = [1.0, 1.0, 1.0]   # body, hands, face [equal, as the released code]
//! velocity_weight = 0.5     # [0.5]
//! commit_weight = 0.02      # [0.02]
//! ```

use dancegen_nn::burn::tensor::Device;
use dancegen_nn::conv::ConvCodecConfig;
use dancegen_nn::loss::Distance;
use dancegen_nn::part_autoencoder::{PartAutoencoder, PartAutoencoderConfig, PartQuantizerConfig};
use dancegen_nn::quant::hrvq::HierarchicalRvqConfig;
use dancegen_nn::quant::rvq::ResidualVqConfig;
use dancegen_nn::quant::vq::EmaVqConfig;
use serde::{Deserialize, Serialize};

use crate::config::{Representation, TrainConfig};
use crate::data::Batch;
use crate::task::{Losses, TrainTask};

/// `[model] kind`.
pub const KIND: &str = "soulnet_vq";

/// The split layout's part widths with the 52 ARKit weights as the face.
pub const PARTS: [usize; 3] = [263, 360, 52];

/// Which quantizer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QuantizerKind {
    Hrvq,
    Rvq,
    Vq,
}

/// The `[model]` table (see the module documentation).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SoulnetVqTable {
    #[serde(default = "d_quantizer")]
    pub quantizer: QuantizerKind,
    #[serde(default = "d_levels")]
    pub num_quantizers: usize,
    #[serde(default = "d_codes")]
    pub nb_code: usize,
    #[serde(default = "d_code_dim")]
    pub code_dim: usize,
    #[serde(default = "d_mu")]
    pub mu: f64,
    #[serde(default = "d_dropout")]
    pub quantize_dropout_prob: f64,
    #[serde(default = "d_width")]
    pub width: usize,
    #[serde(default = "d_depth")]
    pub depth: usize,
    #[serde(default = "d_down")]
    pub down_t: usize,
    #[serde(default = "d_dilation")]
    pub dilation_growth_rate: usize,
    #[serde(default = "d_recon")]
    pub recon: Distance,
    #[serde(default = "d_part_weights")]
    pub part_weights: [f64; 3],
    #[serde(default = "d_velocity")]
    pub velocity_weight: f64,
    #[serde(default = "d_commit")]
    pub commit_weight: f64,
}

fn d_quantizer() -> QuantizerKind {
    QuantizerKind::Hrvq
}
fn d_levels() -> usize {
    6
}
fn d_codes() -> usize {
    512
}
fn d_code_dim() -> usize {
    128
}
fn d_mu() -> f64 {
    0.99
}
fn d_dropout() -> f64 {
    0.2
}
fn d_width() -> usize {
    256
}
fn d_depth() -> usize {
    2
}
fn d_down() -> usize {
    2
}
fn d_dilation() -> usize {
    3
}
fn d_recon() -> Distance {
    Distance::SmoothL1
}
fn d_part_weights() -> [f64; 3] {
    [1.0; 3]
}
fn d_velocity() -> f64 {
    0.5
}
fn d_commit() -> f64 {
    0.02
}

impl SoulnetVqTable {
    /// The autoencoder this table describes.
    pub fn autoencoder(&self) -> PartAutoencoderConfig {
        let vq = EmaVqConfig::new(self.nb_code, self.code_dim).with_mu(self.mu);
        let quantizer = match self.quantizer {
            QuantizerKind::Hrvq => PartQuantizerConfig::Hrvq(
                HierarchicalRvqConfig::new(vq)
                    .with_num_quantizers(self.num_quantizers)
                    .with_quantize_dropout_prob(self.quantize_dropout_prob),
            ),
            QuantizerKind::Rvq => PartQuantizerConfig::Rvq(
                ResidualVqConfig::new(vq)
                    .with_num_quantizers(self.num_quantizers)
                    .with_quantize_dropout_prob(self.quantize_dropout_prob),
            ),
            QuantizerKind::Vq => PartQuantizerConfig::Vq(vq),
        };
        let codec = ConvCodecConfig::new(0, 0)
            .with_width(self.width)
            .with_depth(self.depth)
            .with_down_t(self.down_t)
            .with_stride_t(2)
            .with_dilation_growth_rate(self.dilation_growth_rate)
            .with_code_dim(self.code_dim);
        PartAutoencoderConfig::new(PARTS, codec, quantizer)
            .with_recon(self.recon)
            .with_part_weights(self.part_weights)
            .with_velocity_weight(self.velocity_weight)
            .with_commit_weight(self.commit_weight)
    }
}

/// See the module documentation.
#[derive(Clone, Debug)]
pub struct SoulnetVqTask {
    pub table: SoulnetVqTable,
}

impl SoulnetVqTask {
    pub fn from_config(config: &TrainConfig) -> Result<Self, String> {
        if config.data.representation != Representation::Holistic {
            return Err("[data] representation must be \"holistic\" for soulnet_vq".into());
        }
        let table: SoulnetVqTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        let down = 1usize << table.down_t;
        if !config.data.window.is_multiple_of(down) {
            return Err(format!(
                "[data] window {} must be a multiple of 2^down_t = {down}",
                config.data.window
            ));
        }
        if table.num_quantizers == 0 || table.nb_code == 0 || table.code_dim == 0 {
            return Err("[model] num_quantizers, nb_code and code_dim must be positive".into());
        }
        Ok(Self { table })
    }
}

impl TrainTask for SoulnetVqTask {
    type Model = PartAutoencoder;

    fn kind(&self) -> &'static str {
        KIND
    }

    fn init(&self, device: &Device) -> PartAutoencoder {
        self.table.autoencoder().init(device)
    }

    fn loss(&self, model: &PartAutoencoder, batch: &Batch) -> Losses {
        let l = model.loss(batch.motion.clone());
        let [body, hands, face] = l.recon_parts;
        let mut parts = vec![
            ("body", body),
            ("hands", hands),
            ("face", face),
            ("velocity", l.velocity),
            ("commit", l.commit),
        ];
        if let Some(p) = l.quant.perplexity {
            parts.push(("perplexity", p));
        }
        Losses {
            total: l.total,
            parts,
        }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("a serialisable table")
    }
}
