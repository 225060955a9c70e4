//! The [`TrainTask`](crate::TrainTask)s `dancegen train` knows, chosen by `[model] kind`.

use std::path::Path;

use crate::data::representation_dims;
use crate::trainer::{self, RunOptions, RunSummary};
use crate::{TrainConfig, TrainError, files};

pub mod bundle_files;
pub mod lodgepp;
pub mod motion_autoencoder;
pub mod reactdance;
mod run_feet;
pub mod soulnet;
pub mod soulnet_sources;
pub mod tcdiffpp;

pub use motion_autoencoder::MotionAutoencoderTask;

/// Every `[model] kind` with a task.
pub const KINDS: [&str; 10] = [
    motion_autoencoder::KIND,
    lodgepp::VQVAE,
    lodgepp::GPT,
    lodgepp::PDDM,
    reactdance::HFSQ,
    reactdance::LDM,
    tcdiffpp::KIND,
    soulnet::KIND,
    soulnet::MMR,
    soulnet::MAGM,
];

/// Starts a new run of the task `config` names (`config_path` for error messages).
pub fn train_config(
    config: &TrainConfig,
    config_path: &Path,
    opts: &RunOptions,
) -> Result<RunSummary, TrainError> {
    match kind(config, config_path)? {
        motion_autoencoder::KIND => {
            trainer::train(&autoencoder(config, config_path)?, config, opts)
        }
        lodgepp::VQVAE => trainer::train(
            &lodgepp::VqvaeTask::from_config(config)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        lodgepp::GPT => trainer::train(
            &lodgepp::GptTask::from_config(config, config_path)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        lodgepp::PDDM => trainer::train(
            &lodgepp::PddmTask::from_config(config, config_path)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        reactdance::HFSQ => trainer::train(
            &reactdance::HfsqTask::from_config(config, config_path)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        reactdance::LDM => trainer::train(
            &reactdance::LdmTask::from_config(config, config_path)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        tcdiffpp::KIND => trainer::train(
            &tcdiffpp::GroupTask::from_config(config)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        soulnet::KIND => trainer::train(
            &soulnet::SoulnetVqTask::from_config(config, config_path)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        soulnet::MMR => trainer::train(
            &soulnet::SoulnetMmrTask::from_config(config)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        soulnet::MAGM => trainer::train(
            &soulnet::SoulnetMagmTask::from_config(config, config_path)
                .map_err(|r| lodgepp::config_error(config_path, r))?,
            config,
            opts,
        ),
        _ => unreachable!("kind() only returns known kinds"),
    }
}

/// Continues the run in `run_dir`.
pub fn resume_run(run_dir: &Path, opts: &RunOptions) -> Result<RunSummary, TrainError> {
    let config = trainer::run_config(run_dir)?;
    let path = run_dir.join(files::CONFIG);
    match kind(&config, &path)? {
        motion_autoencoder::KIND => trainer::resume(&autoencoder(&config, &path)?, run_dir, opts),
        lodgepp::VQVAE => trainer::resume(
            &lodgepp::VqvaeTask::from_config(&config)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        lodgepp::GPT => trainer::resume(
            &lodgepp::GptTask::from_config(&config, &path)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        lodgepp::PDDM => trainer::resume(
            &lodgepp::PddmTask::from_config(&config, &path)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        reactdance::HFSQ => trainer::resume(
            &reactdance::HfsqTask::from_config(&config, &path)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        reactdance::LDM => trainer::resume(
            &reactdance::LdmTask::from_config(&config, &path)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        tcdiffpp::KIND => trainer::resume(
            &tcdiffpp::GroupTask::from_config(&config)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        soulnet::KIND => trainer::resume(
            &soulnet::SoulnetVqTask::from_config(&config, &path)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        soulnet::MMR => trainer::resume(
            &soulnet::SoulnetMmrTask::from_config(&config)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        soulnet::MAGM => trainer::resume(
            &soulnet::SoulnetMagmTask::from_config(&config, &path)
                .map_err(|r| lodgepp::config_error(&path, r))?,
            run_dir,
            opts,
        ),
        _ => unreachable!("kind() only returns known kinds"),
    }
}

fn kind<'a>(config: &'a TrainConfig, path: &Path) -> Result<&'a str, TrainError> {
    let err = |reason: String| TrainError::Config {
        path: path.to_path_buf(),
        reason,
    };
    let k = config.model_kind().map_err(err)?;
    KINDS
        .iter()
        .find(|&&known| known == k)
        .copied()
        .ok_or_else(|| {
            err(format!(
                "[model] kind {k:?} is not a model this version trains (known: {})",
                KINDS.join(", ")
            ))
        })
}

fn autoencoder(config: &TrainConfig, path: &Path) -> Result<MotionAutoencoderTask, TrainError> {
    MotionAutoencoderTask::from_table(
        config.model_params(),
        representation_dims(config.data.representation),
        config.data.window,
    )
    .map_err(|reason| TrainError::Config {
        path: path.to_path_buf(),
        reason,
    })
}
