//! The model configuration: the three networks' tables (`[model]` of the training configs,
//! `[vq]` / `[mmr]` / `[generator]` of a bundle's `model.toml`) and the sampling defaults.
//!
//! SoulNet's sizes (holistic.md §1.2–1.3: width 512, 512 codes × 512, 6 levels; transformers
//! 6 + 6 layers, d = 512) do not train in two hours on two cores; the defaults here are ours and
//! `docs/holistic-eval.md` measures them.

use dancegen_nn::conv::ConvCodecConfig;
use dancegen_nn::loss::Distance;
use dancegen_nn::masked::{MaskedSampling, MaskedTransformerConfig};
use dancegen_nn::part_autoencoder::{PartAutoencoderConfig, PartQuantizerConfig};
use dancegen_nn::quant::hrvq::HierarchicalRvqConfig;
use dancegen_nn::quant::rvq::ResidualVqConfig;
use dancegen_nn::quant::vq::EmaVqConfig;
use dancegen_nn::residual_transformer::{ResidualSampling, ResidualTransformerConfig};
use dancegen_nn::retrieval::{MusicMotionRetrievalConfig, SequenceEncoderConfig};
use serde::{Deserialize, Serialize};

use crate::layout::{MUSIC_DIMS, PART_DIMS, TOTAL_DIMS};

/// Which quantizer (the ablation of SoulNet's Tables 2–3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QuantizerKind {
    /// Body → hands → face links at every residual level (SoulNet).
    Hrvq,
    /// Three independent residual stacks.
    Rvq,
    /// One codebook per part.
    Vq,
}

/// The part autoencoder (`kind = "soulnet_vq"`): one conv encoder per part, the quantizer, one
/// decoder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VqTable {
    #[serde(default = "d_quantizer")]
    pub quantizer: QuantizerKind,
    /// Residual levels (hrvq, rvq).
    #[serde(default = "d_levels")]
    pub num_quantizers: usize,
    #[serde(default = "d_codes")]
    pub nb_code: usize,
    /// One part's latent width.
    #[serde(default = "d_code_dim")]
    pub code_dim: usize,
    /// EMA decay of the codebooks.
    #[serde(default = "d_mu")]
    pub mu: f64,
    #[serde(default = "d_dropout")]
    pub quantize_dropout_prob: f64,
    /// Conv channels.
    #[serde(default = "d_width")]
    pub width: usize,
    /// Residual blocks per stage.
    #[serde(default = "d_depth")]
    pub depth: usize,
    /// ×2 downsamplings (2: one token per 4 frames).
    #[serde(default = "d_down")]
    pub down_t: usize,
    #[serde(default = "d_dilation")]
    pub dilation_growth_rate: usize,
    #[serde(default = "d_recon")]
    pub recon: Distance,
    /// Body, hands, face (equal, as the released code).
    #[serde(default = "d_part_weights")]
    pub part_weights: [f64; 3],
    #[serde(default = "d_velocity")]
    pub velocity_weight: f64,
    /// Training only: weight of the second differences' distance (not in SoulNet; 0 = off).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub acceleration_weight: f64,
    /// Training only: weight of the body's foot velocity loss in m/s
    /// ([`crate::body_feet::BodyFeet`]; not in SoulNet; 0 = off).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub foot_velocity_weight: f64,
    #[serde(default = "d_commit")]
    pub commit_weight: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
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

impl VqTable {
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
        PartAutoencoderConfig::new(PART_DIMS, codec, quantizer)
            .with_recon(self.recon)
            .with_part_weights(self.part_weights)
            .with_velocity_weight(self.velocity_weight)
            .with_acceleration_weight(self.acceleration_weight)
            .with_commit_weight(self.commit_weight)
    }

    /// Whether `other`'s weights fit this autoencoder, and its tokens mean the same (the loss
    /// weights and the EMA decay may differ).
    pub fn same_architecture(&self, other: &VqTable) -> bool {
        (
            self.quantizer,
            self.num_quantizers,
            self.nb_code,
            self.code_dim,
            self.width,
            self.depth,
            self.down_t,
            self.dilation_growth_rate,
        ) == (
            other.quantizer,
            other.num_quantizers,
            other.nb_code,
            other.code_dim,
            other.width,
            other.depth,
            other.down_t,
            other.dilation_growth_rate,
        )
    }

    /// Token levels per position (1 for `vq`).
    pub fn levels(&self) -> usize {
        match self.quantizer {
            QuantizerKind::Vq => 1,
            _ => self.num_quantizers,
        }
    }

    /// Motion frames per token.
    pub fn frames_per_token(&self) -> usize {
        1 << self.down_t
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.num_quantizers == 0 || self.nb_code == 0 || self.code_dim == 0 {
            return Err("[vq] num_quantizers, nb_code and code_dim must be positive".into());
        }
        for (name, w) in [
            ("acceleration_weight", self.acceleration_weight),
            ("foot_velocity_weight", self.foot_velocity_weight),
        ] {
            if !(w.is_finite() && w >= 0.0) {
                return Err(format!("[vq] {name} {w} must be a finite value ≥ 0"));
            }
        }
        Ok(())
    }
}

/// The music–motion retrieval model (`kind = "soulnet_mmr"`): two TMR-style encoders.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MmrTable {
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    pub dropout: f64,
    /// SoulNet: 256.
    pub latent_dim: usize,
    /// InfoNCE temperature (paper 0.1; released code 0.7).
    pub temperature: f64,
    /// Negative filtering threshold (paper 0.8; dead code in the release).
    pub filter_threshold: f64,
}

impl Default for MmrTable {
    fn default() -> Self {
        Self {
            d_model: 128,
            n_layers: 2,
            n_heads: 4,
            d_ff: 256,
            dropout: 0.1,
            latent_dim: 256,
            temperature: 0.1,
            filter_threshold: 0.8,
        }
    }
}

impl MmrTable {
    fn encoder(&self, input_dim: usize) -> SequenceEncoderConfig {
        SequenceEncoderConfig::new(input_dim)
            .with_d_model(self.d_model)
            .with_n_layers(self.n_layers)
            .with_n_heads(self.n_heads)
            .with_d_ff(self.d_ff)
            .with_dropout(self.dropout)
            .with_latent_dim(self.latent_dim)
    }

    /// MMR over the whole holistic vector ("Align-whole") and the 35 music features.
    pub fn retrieval(&self) -> MusicMotionRetrievalConfig {
        MusicMotionRetrievalConfig::new(self.encoder(TOTAL_DIMS), self.encoder(MUSIC_DIMS))
            .with_temperature(self.temperature)
            .with_filter_threshold(self.filter_threshold)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.d_model == 0 || self.n_heads == 0 || !self.d_model.is_multiple_of(self.n_heads) {
            return Err(format!(
                "[mmr] d_model {} must be a positive multiple of n_heads {}",
                self.d_model, self.n_heads
            ));
        }
        Ok(())
    }
}

/// How the generator hears the music.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MusicConditioning {
    /// SoulNet: one MMR music embedding per window, as a prefix token.
    Clip,
    /// The prefix token and the music features of each token's frames (ours, the default).
    ClipAndFrames,
}

/// The music-aligned generator (`kind = "soulnet_magm"`): masked transformer over the base
/// tokens of the three parts + residual transformer for the higher levels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeneratorTable {
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    pub residual_layers: usize,
    pub dropout: f64,
    /// Probability of training a batch row without its music (classifier-free guidance).
    pub cond_drop_prob: f64,
    pub music: MusicConditioning,
    /// Tokens per part in one window.
    pub window_tokens: usize,
}

impl Default for GeneratorTable {
    fn default() -> Self {
        Self {
            d_model: 256,
            n_layers: 4,
            n_heads: 4,
            d_ff: 768,
            residual_layers: 3,
            dropout: 0.1,
            // SoulNet / MoMask: 0.1.
            cond_drop_prob: 0.1,
            music: MusicConditioning::ClipAndFrames,
            window_tokens: 32,
        }
    }
}

impl GeneratorTable {
    /// Per-token music width (0 when the generator hears the clip embedding only).
    pub fn d_frame(&self, frames_per_token: usize) -> usize {
        match self.music {
            MusicConditioning::Clip => 0,
            MusicConditioning::ClipAndFrames => frames_per_token * MUSIC_DIMS,
        }
    }

    pub fn masked(&self, vq: &VqTable, d_cond: usize) -> MaskedTransformerConfig {
        MaskedTransformerConfig::new(
            vq.nb_code,
            self.d_model,
            self.n_layers,
            self.n_heads,
            self.d_ff,
            d_cond,
        )
        .with_dropout(self.dropout)
        .with_parts(3)
        .with_d_frame(self.d_frame(vq.frames_per_token()))
    }

    /// `None` for a one-level quantizer.
    pub fn residual(&self, vq: &VqTable, d_cond: usize) -> Option<ResidualTransformerConfig> {
        (vq.levels() > 1).then(|| {
            ResidualTransformerConfig::new(
                vq.nb_code,
                vq.levels(),
                self.d_model,
                self.residual_layers,
                self.n_heads,
                self.d_ff,
                d_cond,
            )
            .with_dropout(self.dropout)
            .with_parts(3)
            .with_d_frame(self.d_frame(vq.frames_per_token()))
        })
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.d_model == 0 || self.n_heads == 0 || !self.d_model.is_multiple_of(self.n_heads) {
            return Err(format!(
                "[generator] d_model {} must be a positive multiple of n_heads {}",
                self.d_model, self.n_heads
            ));
        }
        if self.window_tokens < 4 {
            return Err("[generator] window_tokens must be at least 4".into());
        }
        if !(0.0..1.0).contains(&self.cond_drop_prob) {
            return Err("[generator] cond_drop_prob must be in [0, 1)".into());
        }
        Ok(())
    }
}

/// Sampling defaults (`[sampling]` of `model.toml`; SoulNet `gen_m2m.py` unless noted).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplingDefaults {
    pub steps: usize,
    pub cond_scale: f64,
    pub temperature: f64,
    pub topk_filter_thres: f64,
    pub residual_cond_scale: f64,
    pub residual_temperature: f64,
    /// Tokens per part carried over from the previous window and inpainted (ours: SoulNet has
    /// no long form).
    pub overlap_tokens: usize,
    /// Post-processing (ours, not SoulNet's), with the foot lock: after the root lock, also pin
    /// each planted foot by leg IK at its contact run's mean place
    /// (`dancegen_lodgepp::planted_feet`). `false` keeps the root lock alone. Absent in older
    /// bundles: `true`, as they shipped.
    pub foot_ik: bool,
}

impl Default for SamplingDefaults {
    fn default() -> Self {
        Self {
            steps: 18,
            cond_scale: 4.0,
            temperature: 1.0,
            topk_filter_thres: 0.9,
            residual_cond_scale: 5.0,
            residual_temperature: 0.8,
            overlap_tokens: 8,
            foot_ik: true,
        }
    }
}

impl SamplingDefaults {
    /// The defaults for a generator of `window_tokens` tokens per part: a quarter of the window
    /// is carried over between windows (8 of 32).
    pub fn for_window(window_tokens: usize) -> Self {
        Self {
            overlap_tokens: (window_tokens / 4).max(1),
            ..Self::default()
        }
    }

    pub fn masked(&self, seed: u64) -> MaskedSampling {
        MaskedSampling {
            steps: self.steps,
            cond_scale: self.cond_scale,
            temperature: self.temperature,
            topk_filter_thres: self.topk_filter_thres,
            seed,
        }
    }

    pub fn residual(&self, seed: u64) -> ResidualSampling {
        ResidualSampling {
            cond_scale: self.residual_cond_scale,
            temperature: self.residual_temperature,
            topk_filter_thres: self.topk_filter_thres,
            seed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn older_bundles_keep_the_leg_ik_and_a_model_can_turn_it_off() {
        let old: SamplingDefaults = toml::from_str("steps = 12\noverlap_tokens = 4").unwrap();
        assert!(old.foot_ik, "absent: as the older bundles shipped");
        assert_eq!(old.steps, 12);
        let off: SamplingDefaults = toml::from_str("foot_ik = false").unwrap();
        assert!(!off.foot_ik);
        assert!(toml::from_str::<SamplingDefaults>("foot_ick = false").is_err());
    }

    #[test]
    fn the_training_loss_weights_are_checked_and_not_the_architecture() {
        let base: VqTable = toml::from_str("").unwrap();
        let mut tuned = base.clone();
        tuned.foot_velocity_weight = 1.0;
        tuned.acceleration_weight = 0.5;
        tuned.velocity_weight = 2.0;
        assert!(tuned.validate().is_ok());
        assert!(base.same_architecture(&tuned));
        let mut wider = base.clone();
        wider.width += 1;
        assert!(!base.same_architecture(&wider));
        tuned.foot_velocity_weight = -1.0;
        assert!(
            tuned
                .validate()
                .unwrap_err()
                .contains("foot_velocity_weight")
        );
        // Zero weights are not written, so older readers still read the table.
        assert!(!toml::to_string(&base).unwrap().contains("foot_velocity"));
    }
}
