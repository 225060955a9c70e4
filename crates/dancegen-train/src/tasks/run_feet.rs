//! Foot losses need the run's normaliser (to read the feet in metres), which the trainer writes
//! to the run directory before the first step, after the task is built: [`RunFeet`] reads it
//! on first use.

use std::path::{Path, PathBuf};

use crate::config::TrainConfig;
use crate::data::Normalizer;
use crate::files;

/// A run's feet reader, built once from `normalizer.json` in the run directory by `build`
/// (from the normaliser's mean and std).
#[derive(Debug)]
pub(crate) struct RunFeet<T> {
    run_dir: PathBuf,
    build: fn(&[f64], &[f64]) -> Result<T, String>,
    cell: std::sync::OnceLock<T>,
}

impl<T> RunFeet<T> {
    pub(crate) fn new(run_dir: PathBuf, build: fn(&[f64], &[f64]) -> Result<T, String>) -> Self {
        Self {
            run_dir,
            build,
            cell: std::sync::OnceLock::new(),
        }
    }

    pub(crate) fn get(&self) -> &T {
        self.cell.get_or_init(|| {
            let p = self.run_dir.join(files::NORMALIZER);
            let feet = match Normalizer::load(&p) {
                Ok(Normalizer::MeanStd { mean, std }) => (self.build)(&mean, &std),
                Ok(_) => Err("not a mean/std normaliser".to_string()),
                Err(e) => Err(e.to_string()),
            };
            // The trainer wrote and checked this file before the first step.
            feet.unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        })
    }
}

/// The run directory of `config` read from `path` (relative to the config file).
pub(crate) fn run_dir_of(config: &TrainConfig, path: &Path) -> PathBuf {
    if config.run.dir.is_relative() {
        path.parent()
            .unwrap_or(Path::new("."))
            .join(&config.run.dir)
    } else {
        config.run.dir.clone()
    }
}
