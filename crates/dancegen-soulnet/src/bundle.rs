//! A trained holistic model on disk: `dancegen bundle --holistic` writes it from the three
//! training runs (part autoencoder, MMR, generator).
//!
//! ```text
//! model.toml                kind = "soulnet", name, fps, [vq] [mmr] [generator] [sampling]
//! vq.safetensors            the part autoencoder (HRVQ-VAE)
//! mmr.safetensors           the music and motion encoders
//! generator.safetensors     masked + residual transformers
//! normalizer.json           mean/std of the 675 training values
//! MODEL_CARD.md
//! ```

use std::path::{Path, PathBuf};

use dancegen_nn::burn::tensor::Device;
use dancegen_nn::part_autoencoder::PartAutoencoder;
use dancegen_nn::retrieval::MusicMotionRetrieval;
use dancegen_nn::weights::{self, Layout};
use serde::{Deserialize, Serialize};

use crate::config::{GeneratorTable, MmrTable, SamplingDefaults, VqTable};
use crate::generator::PartGenerator;
use crate::layout::TOTAL_DIMS;

/// `model.toml`'s `kind`.
pub const KIND: &str = "soulnet";

/// File names inside a bundle.
pub mod files {
    pub const MODEL_TOML: &str = "model.toml";
    pub const VQ: &str = "vq.safetensors";
    pub const MMR: &str = "mmr.safetensors";
    pub const GENERATOR: &str = "generator.safetensors";
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
    pub vq: VqTable,
    pub mmr: MmrTable,
    pub generator: GeneratorTable,
    #[serde(default)]
    pub sampling: SamplingDefaults,
}

impl BundleConfig {
    pub fn validate(&self) -> Result<(), String> {
        if self.kind != KIND {
            return Err(format!(
                "kind {:?} is not a holistic model ({KIND:?})",
                self.kind
            ));
        }
        self.vq.validate()?;
        self.mmr.validate()?;
        self.generator.validate()?;
        let s = &self.sampling;
        if s.overlap_tokens >= self.generator.window_tokens {
            return Err(format!(
                "[sampling] overlap_tokens {} must be below [generator] window_tokens {}",
                s.overlap_tokens, self.generator.window_tokens
            ));
        }
        if s.steps == 0 {
            return Err("[sampling] steps must be at least 1".into());
        }
        Ok(())
    }

    /// The generator's networks (MMR latent as the clip condition).
    pub fn init_generator(&self, device: &Device) -> PartGenerator {
        PartGenerator::init(&self.generator, &self.vq, self.mmr.latent_dim, device)
    }
}

/// `normalizer.json` (the mean / std of the 675 training values).
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

/// A loaded holistic model.
pub struct HolisticModel {
    pub dir: PathBuf,
    pub config: BundleConfig,
    pub vq: PartAutoencoder,
    pub mmr: MusicMotionRetrieval,
    pub generator: PartGenerator,
    pub norm: MeanStd,
}

impl HolisticModel {
    /// Reads the bundle in `dir` onto `device` (a plain inference device).
    pub fn load(dir: &Path, device: &Device) -> Result<Self, BundleError> {
        let p = dir.join(files::MODEL_TOML);
        let text = std::fs::read_to_string(&p)
            .map_err(|e| invalid(&p, format!("{e} (is it a model directory?)")))?;
        let config: BundleConfig = toml::from_str(&text).map_err(|e| invalid(&p, e.message()))?;
        config.validate().map_err(|r| invalid(&p, r))?;
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
        let vp = need(files::VQ)?;
        let vq = weights::load(config.vq.autoencoder().init(device), &vp, Layout::Burn)
            .map_err(|e| invalid(&vp, e.reason()))?;
        let mp = need(files::MMR)?;
        let mmr = weights::load(config.mmr.retrieval().init(device), &mp, Layout::Burn)
            .map_err(|e| invalid(&mp, e.reason()))?;
        let gp = need(files::GENERATOR)?;
        let generator = weights::load(config.init_generator(device), &gp, Layout::Burn)
            .map_err(|e| invalid(&gp, e.reason()))?;
        let np = need(files::NORMALIZER)?;
        let norm = MeanStd::load(&np, TOTAL_DIMS).map_err(|e| invalid(&np, e))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            config,
            vq,
            mmr,
            generator,
            norm,
        })
    }
}
