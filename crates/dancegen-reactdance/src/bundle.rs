//! A trained duet model on disk: `dancegen bundle --duet` writes it from the two training runs.
//!
//! ```text
//! model.toml             kind = "reactdance", name, [autoencoder] [denoiser] [sampling]
//! hfsq.safetensors       the HFSQ autoencoder
//! denoiser.safetensors   the latent diffusion transformer
//! normalizer.json        mean/std of the 371 training channels (follower 151 | leader 220)
//! MODEL_CARD.md
//! ```

use std::path::{Path, PathBuf};

use dancegen_nn::burn::tensor::Device;
use dancegen_nn::weights::{self, Layout};
use serde::{Deserialize, Serialize};

use crate::autoencoder::HfsqAutoencoder;
use crate::config::{DenoiserConfig, HfsqAutoencoderConfig, SamplingDefaults};
use crate::denoiser::LatentDenoiser;
use crate::training::PAIR_DIMS;

/// `model.toml`'s `kind`.
pub const KIND: &str = "reactdance";

/// File names inside a bundle.
pub mod files {
    pub const MODEL_TOML: &str = "model.toml";
    pub const HFSQ: &str = "hfsq.safetensors";
    pub const DENOISER: &str = "denoiser.safetensors";
    pub const NORMALIZER: &str = "normalizer.json";
    pub const CARD: &str = "MODEL_CARD.md";
}

/// `model.toml`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BundleConfig {
    pub kind: String,
    pub name: String,
    pub fps: f64,
    /// σ (frames) of the leader frame the follower is expressed in
    /// (`dancegen_motion::repr::duet::leader_frames`; 0 = each frame's own heading). Must be
    /// the value the model was trained with (`[data] heading_sigma`).
    #[serde(default)]
    pub heading_sigma: f64,
    pub autoencoder: HfsqAutoencoderConfig,
    pub denoiser: DenoiserConfig,
    #[serde(default)]
    pub sampling: SamplingDefaults,
}

impl BundleConfig {
    /// Reads and checks a bundle's `model.toml`.
    pub fn load(p: &Path) -> Result<Self, BundleError> {
        let text = std::fs::read_to_string(p)
            .map_err(|e| invalid(p, format!("{e} (is it a model directory?)")))?;
        let config: BundleConfig = toml::from_str(&text).map_err(|e| invalid(p, e.message()))?;
        if config.kind != KIND {
            return Err(invalid(
                p,
                format!("kind {:?} is not a duet model ({KIND:?})", config.kind),
            ));
        }
        config
            .autoencoder
            .validate()
            .and_then(|_| config.denoiser.validate())
            .and_then(|_| config.sampling.validate())
            .map_err(|r| invalid(p, r))?;
        Ok(config)
    }
}

/// `normalizer.json` (mean / std of the 371 training channels).
pub use dancegen_motion::repr::normalizer::MeanStdNormalizer as MeanStd;

/// What can go wrong reading a bundle (always names the file).
#[derive(Debug, thiserror::Error)]
#[error("{}: {reason}", path.display())]
pub struct BundleError {
    pub path: PathBuf,
    pub reason: String,
}

fn invalid(path: &Path, reason: impl ToString) -> BundleError {
    BundleError {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// A loaded duet model.
pub struct DuetModel {
    pub dir: PathBuf,
    pub config: BundleConfig,
    pub autoencoder: HfsqAutoencoder,
    pub denoiser: LatentDenoiser,
    pub norm: MeanStd,
}

impl DuetModel {
    /// Reads the bundle in `dir` onto `device` (a plain inference device).
    pub fn load(dir: &Path, device: &Device) -> Result<Self, BundleError> {
        let config = BundleConfig::load(&dir.join(files::MODEL_TOML))?;
        let need = |name: &str| -> Result<PathBuf, BundleError> {
            let f = dir.join(name);
            if f.is_file() {
                Ok(f)
            } else {
                Err(invalid(
                    &f,
                    "missing model file (is the model directory complete?)",
                ))
            }
        };
        let hp = need(files::HFSQ)?;
        let autoencoder = weights::load(config.autoencoder.init(device), &hp, Layout::Burn)
            .map_err(|e| invalid(&hp, e.reason()))?;
        let dp = need(files::DENOISER)?;
        let denoiser = weights::load(
            config.denoiser.init(
                config.autoencoder.latent_dim(),
                config.autoencoder.frames_per_token(),
                device,
            ),
            &dp,
            Layout::Burn,
        )
        .map_err(|e| invalid(&dp, e.reason()))?;
        let np = need(files::NORMALIZER)?;
        let norm = MeanStd::load(&np, PAIR_DIMS).map_err(|e| invalid(&np, e))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            config,
            autoencoder,
            denoiser,
            norm,
        })
    }
}
