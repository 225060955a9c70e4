//! Training infrastructure shared by dancegen's four dance systems: windowed motion data sets,
//! AdamW and Adan, warm-up + decay schedules, global-norm gradient clipping, an EMA of the
//! weights, checkpoints with exact resume, progress and logs.
//!
//! A system plugs in through [`TrainTask`] (its model and loss); [`train`] / [`resume`] do the
//! rest. A run directory holds:
//!
//! | path | content |
//! |---|---|
//! | `config.toml` | the resolved configuration (defaults filled in, paths absolute) |
//! | `checkpoints/step_N/` | `model.safetensors`, `ema.safetensors`, `optimizer.bpk` (Burn's optimizer record), `state.json` (step, data position, parameter ids) |
//! | `model.safetensors` + `model.toml` + `normalizer.json` | the trained model (the project's model format) |
//! | `log.csv`, `loss.png` | step, loss, learning rate, gradient norm, steps/s; the loss curve |
//!
//! Every file is written atomically (temporary file + rename; a checkpoint directory is renamed
//! into place once complete).

use std::path::{Path, PathBuf};

pub mod config;
pub mod data;
pub mod log;
pub mod optim;
pub mod params;
pub mod task;
pub mod tasks;
pub mod trainer;

pub use config::TrainConfig;
pub use data::{Batch, Normalizer, WindowDataset};
pub use task::{Losses, TrainTask};
pub use trainer::{RunOptions, RunSummary, resume, run_config, train};

/// File names inside a run directory.
pub mod files {
    pub const CONFIG: &str = "config.toml";
    pub const CHECKPOINTS: &str = "checkpoints";
    pub const WEIGHTS: &str = "model.safetensors";
    pub const EMA: &str = "ema.safetensors";
    pub const OPTIMIZER: &str = "optimizer.bpk";
    pub const STATE: &str = "state.json";
    pub const MODEL_TOML: &str = "model.toml";
    pub const NORMALIZER: &str = "normalizer.json";
    pub const LOG: &str = "log.csv";
    pub const LOSS_PNG: &str = "loss.png";
}

/// Why a run could not start, continue or finish. Each names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    #[error("{path}: {reason}")]
    Config { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    Data { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    Run { path: PathBuf, reason: String },
    #[error("{path}: corrupt or incompatible checkpoint: {reason}")]
    Checkpoint { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    Io { path: PathBuf, reason: String },
    #[error(transparent)]
    Weights(#[from] dancegen_nn::weights::WeightsError),
}

impl TrainError {
    pub(crate) fn io(path: &Path, e: impl std::fmt::Display) -> Self {
        TrainError::Io {
            path: path.to_path_buf(),
            reason: e.to_string(),
        }
    }
}
