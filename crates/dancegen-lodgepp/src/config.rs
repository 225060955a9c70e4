//! The configuration of each network, read from TOML (`[model]` of a training config, and the
//! bundle's `model.toml`). Every field has a default, so a config names only what it changes;
//! unknown keys are errors (a misspelt key must not silently train the default).
//!
//! Defaults are the small configuration that trains on this project's 2-core CPU. The paper's
//! sizes are in `configs/lodgepp_*_paper.toml` (anchors D.2/D.3: VQ-VAE width 1024, codebook
//! 1024 × 1024; GPT embed 512; denoiser 8 layers × 512).

use dancegen_nn::diffusion::pddm::{ResidualShift, ResidualShiftConfig};
use serde::{Deserialize, Serialize};

/// Lodge++'s PDDM / local-diffusion window (D.3: 128 frames, 4-frame shared boundaries).
pub const LODGEPP_WINDOW: usize = 128;
/// Frames at each window end taken from the boundary primitive (paper §3.4.6).
pub const BOUNDARY_FRAMES: usize = 4;
/// Length of one dance primitive (paper §3.3: "8-frame key motions").
pub const PRIMITIVE_FRAMES: usize = 8;
/// VQ-VAE temporal downsampling (D.3: `down_t 2, stride_t 2`).
pub const TOKEN_FRAMES: usize = 4;

/// The global choreography GPT (D.3): a music encoder (Linear 35 → `music_d`, then
/// `music_layers` transformer encoder layers), per-token music summaries added to the token
/// embeddings, and a genre embedding.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChoreoGptConfig {
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    /// D.3: Linear(35 → 36) + 3-layer encoder, 6 heads.
    pub music_d: usize,
    pub music_layers: usize,
    pub music_heads: usize,
    /// Tokens per generation window (D.3: 128 = 512 frames).
    pub window_tokens: usize,
    /// Tokens of the previous window that seed the next (D.3: 4).
    pub overlap_tokens: usize,
    pub dropout: f64,
}

impl Default for ChoreoGptConfig {
    fn default() -> Self {
        Self {
            d_model: 256,
            n_layers: 4,
            n_heads: 8,
            music_d: 36,
            music_layers: 3,
            music_heads: 6,
            window_tokens: 128,
            overlap_tokens: 4,
            dropout: 0.1,
        }
    }
}

/// The PDDM denoiser (paper Fig. 5): FiLM transformer decoder over `[d_t; d_p; mask]` with
/// cross-attention to the encoded music and a genre token, then the Foot Refine Block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PddmConfig {
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    pub music_layers: usize,
    pub dropout: f64,
    /// Build the Foot Refine Block (paper §3.4.4).
    pub foot_refine: bool,
    /// Frames per window.
    pub window: usize,
    /// Train and sample every window in its own heading frame (`crate::heading`; an experiment,
    /// not in the paper, measured not to cure the upside-down v3 bodies). Off in older bundles.
    pub canonical_heading: bool,
    /// Predict x̂0 through a noise-dependent skip of the input ([`crate::denoiser::X0Skip`]):
    /// at low noise the network only corrects its input instead of rebuilding every pose through
    /// the transformer. Not in Lodge++, which predicts x̂0 directly (issue 41: the shipped
    /// network, asked for x̂0 from nearly clean windows, returned them at 62 % of their speed).
    /// Off in older bundles.
    pub x0_skip: bool,
}

impl Default for PddmConfig {
    fn default() -> Self {
        Self {
            d_model: 256,
            n_layers: 4,
            n_heads: 8,
            d_ff: 512,
            music_layers: 2,
            dropout: 0.1,
            foot_refine: true,
            window: LODGEPP_WINDOW,
            canonical_heading: false,
            x0_skip: false,
        }
    }
}

/// The multi-genre discriminator (D.2: transformer over `[motion tokens; music tokens]`,
/// mean-pooled, a shared MLP and one head per genre).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DiscriminatorConfig {
    pub d_model: usize,
    pub depth: usize,
    pub n_heads: usize,
    pub d_ff: usize,
}

impl Default for DiscriminatorConfig {
    fn default() -> Self {
        Self {
            d_model: 128,
            depth: 2,
            n_heads: 4,
            d_ff: 256,
        }
    }
}

/// Loss weights of the PDDM (paper eq. 21). The paper gives no values; these follow Lodge's
/// local stage (D.2: λ_FK 1, λ_foot 20 on normalised data; generator adversarial term 0.01)
/// scaled to metre-valued joint losses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PddmLossWeights {
    pub joint: f64,
    pub velocity: f64,
    pub acceleration: f64,
    pub contact: f64,
    /// Generator's hinge term (D.2: 0.01).
    pub genre: f64,
    /// Discriminator's hinge loss (D.2: λ_dis 0.1).
    pub discriminator: f64,
    /// Weight of the main decoder's own x̂0 loss next to the refined one (deep supervision: it
    /// keeps the main output usable when the refine block is switched off for the ablation).
    pub main_output: f64,
    /// Weight of the root's up-axis term (`training::root_up_loss`; not in the paper,
    /// issue 16). 0 (the default, and every shipped model) leaves it out.
    pub root_up: f64,
}

impl Default for PddmLossWeights {
    fn default() -> Self {
        Self {
            joint: 1.0,
            velocity: 10.0,
            acceleration: 10.0,
            contact: 10.0,
            genre: 0.01,
            discriminator: 0.1,
            main_output: 0.5,
            root_up: 0.0,
        }
    }
}

/// How often training shows the PDDM which primitives (so one network serves the full system,
/// the autoregressive-inpainting ablation and the EDGE-style sampler).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrimitiveDropout {
    /// Share of windows trained with no primitives at all.
    pub none: f64,
    /// Share trained with the boundary primitives only (no key motions).
    pub boundaries_only: f64,
    /// Classifier-free condition dropout of music + genre (D.2: 0.25).
    pub condition: f64,
}

impl Default for PrimitiveDropout {
    fn default() -> Self {
        Self {
            none: 0.1,
            boundaries_only: 0.15,
            condition: 0.25,
        }
    }
}

/// Residual-shifting hyper-parameters in `[model.shift]` (defaults: Lodge++'s T = 50 with
/// ResShift's κ and p, see `dancegen_nn::diffusion::pddm`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShiftTable {
    pub steps: usize,
    pub kappa: f64,
    pub p: f64,
}

impl Default for ShiftTable {
    fn default() -> Self {
        let c = ResidualShiftConfig::lodgepp();
        Self {
            steps: c.steps,
            kappa: c.kappa,
            p: c.p,
        }
    }
}

impl ShiftTable {
    pub fn schedule(&self) -> ResidualShift {
        ResidualShiftConfig {
            steps: self.steps,
            kappa: self.kappa,
            p: self.p,
            ..ResidualShiftConfig::lodgepp()
        }
        .init()
    }
}

/// `[model]` of `lodgepp_pddm`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PddmTable {
    #[serde(default)]
    pub pddm: PddmConfig,
    /// `false` trains without the genre discriminator.
    #[serde(default = "yes")]
    pub use_discriminator: bool,
    #[serde(default)]
    pub discriminator: DiscriminatorConfig,
    #[serde(default)]
    pub weights: PddmLossWeights,
    #[serde(default)]
    pub dropout: PrimitiveDropout,
    #[serde(default)]
    pub shift: ShiftTable,
    #[serde(default)]
    pub genres: Vec<String>,
}

fn yes() -> bool {
    true
}
