//! Where a holistic training run takes a network it starts from or trains against: a finished
//! run of that network's kind, or a holistic model directory (`dancegen bundle`'s output). The
//! runs that made a shipped model are not kept with it; reading the model itself lets its
//! decoder or its generator be trained further without them.

use std::path::{Path, PathBuf};

use dancegen_nn::burn::tensor::Device;
use dancegen_nn::part_autoencoder::PartAutoencoder;
use dancegen_nn::retrieval::MusicMotionRetrieval;
use dancegen_nn::weights::{self, Layout};
use dancegen_soulnet::bundle::{BundleConfig, KIND as BUNDLE_KIND, files as bundle_files};
use dancegen_soulnet::config::{GeneratorTable, MmrTable, VqTable};
use dancegen_soulnet::generator::PartGenerator;

use crate::files;

/// `[model] kind` of the part autoencoder.
pub const KIND: &str = "soulnet_vq";
/// `[model] kind` of the retrieval model.
pub const MMR: &str = "soulnet_mmr";
/// `[model] kind` of the generator.
pub const MAGM: &str = "soulnet_magm";

/// The holistic model in `dir`, or `None` when `dir` holds no holistic model's `model.toml`
/// (a run directory, say).
pub fn holistic_model(dir: &Path) -> Result<Option<BundleConfig>, String> {
    let p = dir.join(bundle_files::MODEL_TOML);
    let Ok(text) = std::fs::read_to_string(&p) else {
        return Ok(None);
    };
    let t: toml::Table =
        toml::from_str(&text).map_err(|e| format!("{}: {}", p.display(), e.message()))?;
    if t.get("kind").and_then(|k| k.as_str()) != Some(BUNDLE_KIND) {
        return Ok(None);
    }
    toml::Value::Table(t)
        .try_into()
        .map(Some)
        .map_err(|e: toml::de::Error| format!("{}: {}", p.display(), e.message()))
}

/// A network's configuration, weights file and normaliser in `from`: the model's own section
/// when `from` is a holistic model, else the finished run of `kind`.
fn locate<T: serde::de::DeserializeOwned>(
    from: &Path,
    kind: &str,
    section: impl Fn(BundleConfig) -> T,
    bundle_weights: &str,
) -> Result<(T, PathBuf, PathBuf), String> {
    match holistic_model(from)? {
        Some(b) => Ok((
            section(b),
            from.join(bundle_weights),
            from.join(bundle_files::NORMALIZER),
        )),
        None => {
            let t = super::bundle_files::finished_run_config(from, kind).map_err(|e| {
                format!("{e} (expected a finished {kind} run or a holistic model directory)")
            })?;
            Ok((t, from.join(files::WEIGHTS), from.join(files::NORMALIZER)))
        }
    }
}

fn load<M>(model: M, path: &Path) -> Result<M, String>
where
    M: dancegen_nn::burn::module::Module + dancegen_nn::burn::store::ModuleSnapshot,
{
    weights::load(model, path, Layout::Burn).map_err(|e| format!("{}: {e}", path.display()))
}

/// The part autoencoder in `from` (a `soulnet_vq` run or a holistic model), its table and the
/// path of the normaliser it was trained with.
pub fn part_autoencoder(
    from: &Path,
    device: &Device,
) -> Result<(VqTable, PartAutoencoder, PathBuf), String> {
    let (table, w, norm) = locate(from, KIND, |b| b.vq, bundle_files::VQ)?;
    let ae = load(table.autoencoder().init(device), &w)?;
    Ok((table, ae, norm))
}

/// The music–motion retrieval model in `from` (a `soulnet_mmr` run or a holistic model), built
/// with `dropout` instead of its table's when given.
pub fn retrieval(
    from: &Path,
    dropout: Option<f64>,
    device: &Device,
) -> Result<(MmrTable, MusicMotionRetrieval), String> {
    let (table, w, _) = locate(from, MMR, |b| b.mmr, bundle_files::MMR)?;
    let mut built = table.clone();
    if let Some(d) = dropout {
        built.dropout = d;
    }
    let m = load(built.retrieval().init(device), &w)?;
    Ok((table, m))
}

/// The generator in `from` (a `soulnet_magm` run or a holistic model), if its table is
/// `expected`; `init` builds the empty network of that table.
pub fn generator(
    from: &Path,
    expected: &GeneratorTable,
    init: impl FnOnce() -> PartGenerator,
) -> Result<PartGenerator, String> {
    let (GeneratorOf(table), w, _) = locate(
        from,
        MAGM,
        |b| GeneratorOf(b.generator),
        bundle_files::GENERATOR,
    )?;
    if &table != expected {
        return Err(format!(
            "{}: its generator's [generator] table differs from this run's [model.generator]",
            from.display()
        ));
    }
    load(init(), &w)
}

/// A run's or a model's generator table: a `soulnet_magm` run keeps it under `[generator]` of
/// its `[config]`, a model under its own `[generator]`.
struct GeneratorOf(GeneratorTable);

impl<'de> serde::Deserialize<'de> for GeneratorOf {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        struct Run {
            #[serde(default)]
            generator: GeneratorTable,
        }
        Run::deserialize(d).map(|r| GeneratorOf(r.generator))
    }
}
