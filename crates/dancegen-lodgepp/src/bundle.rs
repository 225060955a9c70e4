//! A trained Lodge++ model on disk: one directory with `model.toml` (configs, genres, sampling
//! defaults), the weights of the three networks as safetensors, the two normalisers and the
//! key-motion library. `dancegen bundle` writes it from three training runs.
//!
//! ```text
//! model.toml            kind = "lodgepp", genres, [vqvae] [gpt] [pddm] [sampling]
//! vqvae.safetensors     vqvae_normalizer.json
//! gpt.safetensors
//! pddm.safetensors      normalizer.json
//! library.npz           key-motion library (clips, keys)
//! MODEL_CARD.md
//! ```

use std::path::{Path, PathBuf};

use dancegen_nn::autoencoder::{MotionAutoencoder, MotionAutoencoderConfig};
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::weights::{self, Layout};
use serde::{Deserialize, Serialize};

use crate::choreo_gpt::ChoreoGpt;
use crate::config::{ChoreoGptConfig, PddmTable};
use crate::denoiser::PddmDenoiser;
use crate::layout::DIMS;
use crate::library::PrimitiveLibrary;

/// `model.toml`'s `kind`.
pub const KIND: &str = "lodgepp";

/// File names inside a bundle.
pub mod files {
    pub const MODEL_TOML: &str = "model.toml";
    pub const VQVAE: &str = "vqvae.safetensors";
    pub const VQVAE_NORMALIZER: &str = "vqvae_normalizer.json";
    pub const GPT: &str = "gpt.safetensors";
    pub const PDDM: &str = "pddm.safetensors";
    pub const NORMALIZER: &str = "normalizer.json";
    pub const LIBRARY: &str = "library.npz";
    pub const CARD: &str = "MODEL_CARD.md";
}

/// Sampling defaults a bundle ships with (the CLI overrides them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplingDefaults {
    pub steps: usize,
    pub guidance: f64,
    /// GPT decoding: Lodge++ decodes greedily (D.3); sampling from the top k makes `--seed`
    /// change the choreography too (`gpt_top_k = 1` is greedy).
    pub gpt_top_k: usize,
    pub gpt_temperature: f64,
    pub penetration_scale: f64,
    pub penetration_iterations: usize,
    /// Final denoising steps the penetration guidance acts on.
    pub penetration_steps: usize,
    /// Largest shift (frames) of a key motion onto the nearest music beat.
    pub max_beat_shift: usize,
    /// Keep planted feet in place: root lock, then leg IK (`dancegen_lodgepp::planted_feet`;
    /// not part of Lodge++).
    pub foot_lock: bool,
    /// When a foot counts as planted for the foot lock (absent in older bundles: `either`).
    pub foot_lock_rule: crate::planted_feet::PlantedRule,
    /// The foot lock's second pass, leg IK on planted feet
    /// ([`crate::planted_feet::pin_planted_feet_with`]); `false` keeps the root lock only.
    /// Absent in older bundles: `true`, both passes, as they were tuned with.
    pub foot_ik: bool,
    /// Final denoising steps the Foot Refine Block acts on (absent: every step, as Lodge++).
    pub foot_refine_steps: Option<usize>,
    /// Channels the Foot Refine Block's refinement is added to (absent: `all`, as Lodge++).
    pub foot_refine_scope: crate::foot_refine::FootRefineScope,
}

impl Default for SamplingDefaults {
    fn default() -> Self {
        Self {
            steps: 50,
            guidance: 2.0,
            gpt_top_k: 5,
            gpt_temperature: 1.0,
            penetration_scale: 0.02,
            penetration_iterations: 2,
            penetration_steps: 10,
            max_beat_shift: 6,
            foot_lock: true,
            foot_lock_rule: crate::planted_feet::PlantedRule::Either,
            foot_ik: true,
            foot_refine_steps: None,
            foot_refine_scope: crate::foot_refine::FootRefineScope::All,
        }
    }
}

/// `[gpt]` of `model.toml`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GptSection {
    pub gpt: ChoreoGptConfig,
    pub codes: usize,
}

/// `model.toml`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundleConfig {
    pub kind: String,
    pub name: String,
    pub fps: f64,
    pub genres: Vec<String>,
    pub default_genre: String,
    /// The VQ-VAE's `MotionAutoencoderConfig` (42 channels).
    pub vqvae: MotionAutoencoderConfig,
    pub gpt: GptSection,
    pub pddm: PddmTable,
    #[serde(default)]
    pub sampling: SamplingDefaults,
}

/// `normalizer.json` / `vqvae_normalizer.json` (mean / std of the 151 EDGE channels).
pub use dancegen_motion::repr::normalizer::MeanStdNormalizer as MeanStd;

/// What can go wrong reading a bundle (always names the file).
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    #[error("{}: {reason}", path.display())]
    Invalid { path: PathBuf, reason: String },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl BundleError {
    fn io(path: &Path, source: std::io::Error) -> Self {
        if source.kind() == std::io::ErrorKind::NotFound {
            return BundleError::Invalid {
                path: path.to_path_buf(),
                reason: "missing model file (is the model directory complete?)".into(),
            };
        }
        BundleError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// A loaded Lodge++ model, ready to generate.
pub struct SoloModel {
    pub dir: PathBuf,
    pub config: BundleConfig,
    pub vqvae: MotionAutoencoder,
    pub vqvae_norm: MeanStd,
    pub gpt: ChoreoGpt,
    pub pddm: PddmDenoiser,
    pub norm: MeanStd,
    pub library: PrimitiveLibrary,
}

impl SoloModel {
    /// Reads the bundle in `dir` onto `device` (a plain inference device).
    pub fn load(dir: &Path, device: &Device) -> Result<Self, BundleError> {
        let p = dir.join(files::MODEL_TOML);
        let text = std::fs::read_to_string(&p).map_err(|e| BundleError::io(&p, e))?;
        let config: BundleConfig = toml::from_str(&text).map_err(|e| BundleError::Invalid {
            path: p.clone(),
            reason: e.message().to_string(),
        })?;
        if config.kind != KIND {
            return Err(BundleError::Invalid {
                path: p,
                reason: format!("kind {:?} is not a Lodge++ model ({KIND:?})", config.kind),
            });
        }
        if !config.genres.contains(&config.default_genre) {
            return Err(BundleError::Invalid {
                path: p,
                reason: format!("default_genre {:?} is not in genres", config.default_genre),
            });
        }
        let wload_err = |path: PathBuf| {
            move |e: weights::WeightsError| BundleError::Invalid {
                path: path.clone(),
                reason: e.reason(),
            }
        };
        let need = |name: &str| -> Result<PathBuf, BundleError> {
            let f = dir.join(name);
            if f.is_file() {
                Ok(f)
            } else {
                Err(BundleError::Invalid {
                    path: f,
                    reason: "missing model file (is the model directory complete?)".into(),
                })
            }
        };
        let vp = need(files::VQVAE)?;
        let vqvae =
            weights::load(config.vqvae.init(device), &vp, Layout::Burn).map_err(wload_err(vp))?;
        let gp = need(files::GPT)?;
        let gpt = weights::load(
            config
                .gpt
                .gpt
                .init(config.gpt.codes, config.genres.len(), device),
            &gp,
            Layout::Burn,
        )
        .map_err(wload_err(gp))?;
        let load_norm = |name: &str| -> Result<MeanStd, BundleError> {
            let p = need(name)?;
            MeanStd::load(&p, DIMS).map_err(|e| BundleError::Invalid {
                path: p.clone(),
                reason: e.to_string(),
            })
        };
        let norm = load_norm(files::NORMALIZER)?;
        let vqvae_norm = load_norm(files::VQVAE_NORMALIZER)?;
        let pp = need(files::PDDM)?;
        let mut table = config.pddm.clone();
        table.genres = config.genres.clone();
        let train_model =
            weights::load(table.init(&norm.mean, &norm.std, device), &pp, Layout::Burn)
                .map_err(wload_err(pp))?;
        let lp = need(files::LIBRARY)?;
        let library = PrimitiveLibrary::load(&lp)
            .map_err(|reason| BundleError::Invalid { path: lp, reason })?;
        Ok(Self {
            dir: dir.to_path_buf(),
            config,
            vqvae,
            vqvae_norm,
            gpt,
            pddm: train_model.denoiser,
            norm,
            library,
        })
    }

    /// Index of `genre`, or an error listing the valid ones.
    pub fn genre_index(&self, genre: &str) -> Result<usize, String> {
        self.config
            .genres
            .iter()
            .position(|g| g == genre)
            .ok_or_else(|| {
                format!(
                    "unknown genre {genre:?}; this model knows: {}",
                    self.config.genres.join(", ")
                )
            })
    }
}
