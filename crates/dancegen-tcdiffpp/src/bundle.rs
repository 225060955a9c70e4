//! A trained group model on disk: `dancegen bundle --group RUN` writes it from a finished
//! `tcdiffpp_group` training run.
//!
//! ```text
//! model.toml             kind = "tcdiffpp", name, fps, [model] (GroupModelConfig)
//! denoiser.safetensors   the group denoiser (its normaliser statistics inside)
//! normalizer.json        mean/std of one dancer's 151 channels (for reference; the weights
//!                        carry the same statistics)
//! MODEL_CARD.md
//! ```

use std::path::{Path, PathBuf};

use dancegen_nn::burn::tensor::Device;
use dancegen_nn::diffusion::Schedule;
use dancegen_nn::edge151::DIMS;
use dancegen_nn::weights::{self, Layout};
use serde::{Deserialize, Serialize};

use crate::config::GroupModelConfig;
use crate::denoiser::GroupDenoiser;

/// `model.toml`'s `kind`.
pub const KIND: &str = "tcdiffpp";

/// File names inside a bundle.
pub mod files {
    pub const MODEL_TOML: &str = "model.toml";
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
    pub model: GroupModelConfig,
}

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

/// A loaded group model.
pub struct GroupModel {
    pub dir: PathBuf,
    pub config: BundleConfig,
    pub net: GroupDenoiser,
    /// EDGE's 1000-step cosine schedule the denoiser was trained on.
    pub schedule: Schedule,
}

impl GroupModel {
    /// Reads the bundle in `dir` onto `device` (a plain inference device).
    pub fn load(dir: &Path, device: &Device) -> Result<Self, BundleError> {
        let p = dir.join(files::MODEL_TOML);
        let text = std::fs::read_to_string(&p)
            .map_err(|e| invalid(&p, format!("{e} (is it a model directory?)")))?;
        let config: BundleConfig = toml::from_str(&text).map_err(|e| invalid(&p, e.message()))?;
        if config.kind != KIND {
            return Err(invalid(
                &p,
                format!("kind {:?} is not a group model ({KIND:?})", config.kind),
            ));
        }
        config
            .model
            .denoiser
            .check()
            .map_err(|e| invalid(&p, format!("[model.denoiser] {e}")))?;
        config
            .model
            .sampling
            .check()
            .map_err(|e| invalid(&p, format!("[model.sampling] {e}")))?;
        let w = config.model.window();
        if w < 2 || !w.is_multiple_of(2) {
            return Err(invalid(
                &p,
                format!("window {w}: must be an even number ≥ 2"),
            ));
        }
        let dp = dir.join(files::DENOISER);
        if !dp.is_file() {
            return Err(invalid(
                &dp,
                "missing model file (is the model directory complete?)",
            ));
        }
        // The statistics are placeholders here; the weights file holds the trained ones.
        let init = config
            .model
            .denoiser
            .init(&[0.0; DIMS], &[1.0; DIMS], device);
        let net = weights::load(init, &dp, Layout::Burn).map_err(|e| invalid(&dp, e.reason()))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            config,
            net,
            schedule: Schedule::edge(),
        })
    }
}
