//! Model weights in safetensors: load with every problem named, save atomically.
//!
//! Two layouts: [`Layout::Burn`] (our own checkpoints, Burn's `[in, out]` Linear weights and
//! `gamma/beta` norms) and [`Layout::PyTorch`] (a PyTorch state dict: `[out, in]` Linear
//! weights, `weight/bias` norms), converted by burn-store's adapters.

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::store::{
    ApplyResult, BurnToPyTorchAdapter, ModuleSnapshot, PyTorchToBurnAdapter, SafetensorsStore,
};

/// How the tensors in a file are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Burn,
    PyTorch,
}

/// A checkpoint that cannot be loaded or saved.
#[derive(Debug, thiserror::Error)]
pub enum WeightsError {
    #[error("{path}: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error("{path}: missing tensors the model needs: {}", .tensors.join(", "))]
    Missing { path: PathBuf, tensors: Vec<String> },
    #[error("{path}: tensors that do not fit the model: {}", .problems.join("; "))]
    Mismatch {
        path: PathBuf,
        problems: Vec<String>,
    },
    #[error("{path}: tensors the model does not have: {}", .tensors.join(", "))]
    Unused { path: PathBuf, tensors: Vec<String> },
    #[error("{path}: {reason}")]
    Write { path: PathBuf, reason: String },
}

/// Loads `path` into `model`. Every missing, misshapen or unexpected tensor is an error that
/// names it; nothing is applied partially on error (the caller's model is consumed and only
/// returned on success).
pub fn load<M: Module + ModuleSnapshot>(
    mut model: M,
    path: &Path,
    layout: Layout,
) -> Result<M, WeightsError> {
    let read = |reason: String| WeightsError::Read {
        path: path.to_path_buf(),
        reason,
    };
    if !path.is_file() {
        return Err(read("no such file".into()));
    }
    let mut store = SafetensorsStore::from_file(path).allow_partial(true);
    if layout == Layout::PyTorch {
        store = store.with_from_adapter(PyTorchToBurnAdapter);
    }
    let result = model
        .load_from(&mut store)
        .map_err(|e| read(e.to_string()))?;
    check(&result, path)?;
    Ok(model)
}

fn check(r: &ApplyResult, path: &Path) -> Result<(), WeightsError> {
    let path = path.to_path_buf();
    if !r.errors.is_empty() {
        return Err(WeightsError::Mismatch {
            path,
            problems: r.errors.iter().map(|e| format!("{e}")).collect(),
        });
    }
    if !r.missing.is_empty() {
        return Err(WeightsError::Missing {
            path,
            tensors: r.missing.iter().map(|(p, _)| p.clone()).collect(),
        });
    }
    if !r.unused.is_empty() {
        return Err(WeightsError::Unused {
            path,
            tensors: r.unused.clone(),
        });
    }
    Ok(())
}

/// Saves `model` to `path` (temporary file + rename: an interrupted save never leaves a torn
/// checkpoint), with string `metadata` in the safetensors header.
pub fn save<M: Module + ModuleSnapshot>(
    model: &M,
    path: &Path,
    layout: Layout,
    metadata: &[(&str, &str)],
) -> Result<(), WeightsError> {
    let write = |reason: String| WeightsError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let mut store = SafetensorsStore::from_bytes(None);
    for (k, v) in metadata {
        store = store.metadata(*k, *v);
    }
    if layout == Layout::PyTorch {
        store = store.with_to_adapter(BurnToPyTorchAdapter);
    }
    model
        .save_into(&mut store)
        .map_err(|e| write(e.to_string()))?;
    let bytes = store.get_bytes().map_err(|e| write(e.to_string()))?;
    dancegen_io::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| write(e.to_string()))
}
