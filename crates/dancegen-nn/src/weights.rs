//! Model weights in safetensors: load with every problem named, save atomically.
//!
//! Two layouts: [`Layout::Burn`] (our own checkpoints, Burn's `[in, out]` Linear weights and
//! `gamma/beta` norms) and [`Layout::PyTorch`] (a PyTorch state dict: `[out, in]` Linear
//! weights, `weight/bias` norms), converted by burn-store's adapters.

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::store::{
    ApplyResult, BurnToPyTorchAdapter, FloatCastAdapter, HalfPrecisionAdapter, ModuleAdapter,
    ModuleSnapshot, PyTorchToBurnAdapter, SafetensorsStore,
};
use burn::tensor::DType;

/// How the tensors in a file are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Burn,
    PyTorch,
}

/// How a saved file stores float weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    F32,
    /// Half precision for the layers burn-store's `HalfPrecisionAdapter` lists (linear,
    /// embedding, convolution and normalisation weights); custom parameters (normaliser
    /// statistics, learned null tokens, codebooks) stay F32. Halves a shipped model's size;
    /// loading widens everything back to F32.
    F16,
}

/// A checkpoint that cannot be loaded or saved.
/// Shown as `path: reason`.
#[derive(Debug)]
pub enum WeightsError {
    Read {
        path: PathBuf,
        reason: String,
    },
    Missing {
        path: PathBuf,
        tensors: Vec<String>,
    },
    Mismatch {
        path: PathBuf,
        problems: Vec<String>,
    },
    Unused {
        path: PathBuf,
        tensors: Vec<String>,
    },
    Write {
        path: PathBuf,
        reason: String,
    },
}

impl std::fmt::Display for WeightsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path().display(), self.reason())
    }
}

impl std::error::Error for WeightsError {}

impl WeightsError {
    /// The checkpoint file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Read { path, .. }
            | Self::Missing { path, .. }
            | Self::Mismatch { path, .. }
            | Self::Unused { path, .. }
            | Self::Write { path, .. } => path,
        }
    }

    /// What went wrong, without the file name: for callers whose own error already names the
    /// file, so a message does not repeat the path.
    pub fn reason(&self) -> String {
        match self {
            Self::Read { reason, .. } | Self::Write { reason, .. } => reason.clone(),
            Self::Missing { tensors, .. } => {
                format!("missing tensors the model needs: {}", tensors.join(", "))
            }
            Self::Mismatch { problems, .. } => {
                format!("tensors that do not fit the model: {}", problems.join("; "))
            }
            Self::Unused { tensors, .. } => {
                format!("tensors the model does not have: {}", tensors.join(", "))
            }
        }
    }
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
    // Any float width in the file (F16 bundles, F64 exports) becomes the models' F32.
    let widen = FloatCastAdapter::to(DType::F32);
    let mut store = SafetensorsStore::from_file(path).allow_partial(true);
    store = match layout {
        Layout::PyTorch => store.with_from_adapter(PyTorchToBurnAdapter.chain(widen)),
        Layout::Burn => store.with_from_adapter(widen),
    };
    let result = model
        .load_from(&mut store)
        .map_err(|e| read(e.to_string()))?;
    check(&result, path)?;
    Ok(model)
}

/// What a warm start ([`load_warm`]) took from its file and what it left.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WarmStart {
    /// The model's tensors the file did not have: they keep their fresh initialisation.
    pub fresh: Vec<String>,
    /// The file's tensors the model does not have: ignored.
    pub unused: Vec<String>,
}

/// Loads what `path` has of `model` (a training run started from another run's weights, whose
/// architecture may add or drop modules): tensors of the same name and shape are taken, the
/// rest keep `model`'s initialisation and are listed. A tensor of the same name and another
/// shape is an error, as in [`load`].
pub fn load_warm<M: Module + ModuleSnapshot>(
    mut model: M,
    path: &Path,
) -> Result<(M, WarmStart), WeightsError> {
    if !path.is_file() {
        return Err(WeightsError::Read {
            path: path.to_path_buf(),
            reason: "no such file".into(),
        });
    }
    let mut store = SafetensorsStore::from_file(path)
        .allow_partial(true)
        .with_from_adapter(FloatCastAdapter::to(DType::F32));
    let result = model
        .load_from(&mut store)
        .map_err(|e| WeightsError::Read {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    if !result.errors.is_empty() {
        return Err(WeightsError::Mismatch {
            path: path.to_path_buf(),
            problems: result.errors.iter().map(|e| format!("{e}")).collect(),
        });
    }
    let mut fresh: Vec<String> = result.missing.iter().map(|(p, _)| p.clone()).collect();
    let mut unused = result.unused.clone();
    fresh.sort();
    unused.sort();
    Ok((model, WarmStart { fresh, unused }))
}

/// Tensor names are sorted, so a message is the same from run to run.
fn check(r: &ApplyResult, path: &Path) -> Result<(), WeightsError> {
    let path = path.to_path_buf();
    let sorted = |mut v: Vec<String>| {
        v.sort();
        v
    };
    if !r.errors.is_empty() {
        return Err(WeightsError::Mismatch {
            path,
            problems: r.errors.iter().map(|e| format!("{e}")).collect(),
        });
    }
    if !r.missing.is_empty() {
        return Err(WeightsError::Missing {
            path,
            tensors: sorted(r.missing.iter().map(|(p, _)| p.clone()).collect()),
        });
    }
    if !r.unused.is_empty() {
        return Err(WeightsError::Unused {
            path,
            tensors: sorted(r.unused.clone()),
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
    save_as(model, path, layout, metadata, Storage::F32)
}

/// [`save`] with the float storage chosen.
pub fn save_as<M: Module + ModuleSnapshot>(
    model: &M,
    path: &Path,
    layout: Layout,
    metadata: &[(&str, &str)],
    storage: Storage,
) -> Result<(), WeightsError> {
    let write = |reason: String| WeightsError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let mut store = SafetensorsStore::from_bytes(None);
    for (k, v) in metadata {
        store = store.metadata(*k, *v);
    }
    store = match (layout, storage) {
        (Layout::Burn, Storage::F32) => store,
        (Layout::Burn, Storage::F16) => store.with_to_adapter(HalfPrecisionAdapter::new()),
        (Layout::PyTorch, Storage::F32) => store.with_to_adapter(BurnToPyTorchAdapter),
        (Layout::PyTorch, Storage::F16) => {
            store.with_to_adapter(BurnToPyTorchAdapter.chain(HalfPrecisionAdapter::new()))
        }
    };
    model
        .save_into(&mut store)
        .map_err(|e| write(e.to_string()))?;
    let bytes = store.get_bytes().map_err(|e| write(e.to_string()))?;
    dancegen_io::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| write(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::module::Param;
    use burn::nn::{Linear, LinearConfig};
    use burn::tensor::{Tensor, TensorData};

    #[derive(Module, Debug)]
    struct Net {
        linear: Linear,
        stats: Param<Tensor<1>>,
    }

    fn net(seed_shift: f32) -> Net {
        let device = crate::device::inference();
        let mut linear = LinearConfig::new(64, 64).init(&device);
        let w: Vec<f32> = (0..64 * 64)
            .map(|i| ((i as f32) * 0.37 + seed_shift).sin())
            .collect();
        linear.weight =
            Param::from_tensor(Tensor::from_data(TensorData::new(w, [64, 64]), &device));
        let stats = Param::from_tensor(Tensor::from_data(
            TensorData::new(vec![0.602_286_96f32, 0.887_855_3, 1e-5], [3]),
            &device,
        ));
        Net { linear, stats }
    }

    fn values(t: Tensor<1>) -> Vec<f32> {
        t.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn half_precision_storage_halves_layers_and_keeps_custom_parameters_exact() {
        let dir = tempfile::tempdir().unwrap();
        let (full, half) = (
            dir.path().join("f32.safetensors"),
            dir.path().join("f16.safetensors"),
        );
        let model = net(0.0);
        save(&model, &full, Layout::Burn, &[]).unwrap();
        save_as(&model, &half, Layout::Burn, &[], Storage::F16).unwrap();
        let size = |p: &Path| std::fs::metadata(p).unwrap().len();
        assert!(
            size(&half) * 10 < size(&full) * 6,
            "{} vs {}",
            size(&half),
            size(&full)
        );

        let loaded = load(net(1.0), &half, Layout::Burn).unwrap();
        assert_eq!(values(loaded.stats.val()), values(model.stats.val()));
        let a = values(loaded.linear.weight.val().reshape([64 * 64]));
        let b = values(model.linear.weight.val().reshape([64 * 64]));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0f32, f32::max);
        assert!(
            worst > 0.0 && worst < 1e-3,
            "f16 rounding of values in [-1, 1]: {worst}"
        );
        // F32 files still load bit-exactly.
        let exact = load(net(1.0), &full, Layout::Burn).unwrap();
        assert_eq!(values(exact.linear.weight.val().reshape([64 * 64])), b);
    }

    #[derive(Module, Debug)]
    struct Grown {
        linear: Linear,
        extra: Linear,
    }

    #[test]
    fn a_warm_start_takes_what_fits_and_lists_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("old.safetensors");
        let old = net(0.0);
        save(&old, &file, Layout::Burn, &[]).unwrap();
        let device = crate::device::inference();
        let grown = Grown {
            linear: LinearConfig::new(64, 64).init(&device),
            extra: LinearConfig::new(4, 2).init(&device),
        };
        let extra_before = values(grown.extra.weight.val().reshape([8]));
        let (warm, report) = load_warm(grown, &file).unwrap();
        assert_eq!(
            values(warm.linear.weight.val().reshape([64 * 64])),
            values(old.linear.weight.val().reshape([64 * 64]))
        );
        assert_eq!(values(warm.extra.weight.val().reshape([8])), extra_before);
        assert_eq!(report.fresh, vec!["extra.bias", "extra.weight"]);
        assert_eq!(report.unused, vec!["stats"]);

        // Same name, another shape: refused, naming the tensor.
        let wrong = Grown {
            linear: LinearConfig::new(64, 32).init(&device),
            extra: LinearConfig::new(4, 2).init(&device),
        };
        let err = load_warm(wrong, &file).unwrap_err().to_string();
        assert!(err.contains("linear.weight"), "{err}");
        assert!(load_warm(net(0.0), &dir.path().join("none")).is_err());
    }
}
