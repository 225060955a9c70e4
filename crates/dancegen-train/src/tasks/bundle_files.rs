//! The steps every `dancegen bundle` assembler shares: read a finished run's `[config]`, check
//! and copy its normaliser, write the bundle's `model.toml` (all atomically, each error naming its file).

use std::path::Path;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::data::Normalizer;
use crate::{TrainError, files};

/// A configuration error naming `p`.
pub(crate) fn config_error(p: &Path, reason: String) -> TrainError {
    TrainError::Config {
        path: p.to_path_buf(),
        reason,
    }
}

/// The `[config]` of the finished run in `run` whose `model.toml` has `kind`.
pub fn finished_run_config<T: DeserializeOwned>(run: &Path, kind: &str) -> Result<T, TrainError> {
    let mp = run.join(files::MODEL_TOML);
    let text = std::fs::read_to_string(&mp).map_err(|e| TrainError::io(&mp, e))?;
    let t: toml::Table = toml::from_str(&text).map_err(|e| config_error(&mp, e.to_string()))?;
    if t.get("kind").and_then(|k| k.as_str()) != Some(kind) {
        return Err(config_error(&mp, format!("not a finished {kind} run")));
    }
    t.get("config")
        .cloned()
        .ok_or_else(|| config_error(&mp, "no [config]".into()))?
        .try_into()
        .map_err(|e: toml::de::Error| config_error(&mp, e.message().to_string()))
}

/// Whether the normaliser file `theirs` maps values as `ours` does, so that weights trained with
/// it read data normalised by `ours` in the same units. Within 1e-4: the same data set gives the
/// same statistics up to the decimal printing of `normalizer.json`.
pub fn normalizer_matches(ours: &Normalizer, theirs: &Path) -> Result<bool, TrainError> {
    Ok(Normalizer::load(theirs)?.approx_eq(ours, 1e-4))
}

/// Copies the run's `normalizer.json` to `dst`.
pub fn copy_normalizer(run: &Path, dst: &Path) -> Result<(), TrainError> {
    let np = run.join(files::NORMALIZER);
    let bytes = std::fs::read(&np).map_err(|e| TrainError::io(&np, e))?;
    dancegen_io::write_atomic(dst, |w| w.write_all(&bytes)).map_err(|e| TrainError::io(dst, e))
}

/// Writes `config` as pretty TOML to `dst`.
pub fn write_model_toml<T: Serialize>(config: &T, dst: &Path) -> Result<(), TrainError> {
    let text = toml::to_string_pretty(config).expect("config serialises");
    dancegen_io::write_atomic(dst, |w| w.write_all(text.as_bytes()))
        .map_err(|e| TrainError::io(dst, e))
}
