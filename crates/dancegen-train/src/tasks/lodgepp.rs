//! The three networks of Lodge++ (`dancegen_lodgepp`), each trained as its own run on EDGE-151
//! windows with a mean/std normaliser:
//! - `lodgepp_vqvae`: the motion autoencoder over the 42 main-joint channels
//!   (`[model]` = the `motion_autoencoder` table);
//! - `lodgepp_gpt`: the choreography GPT on the tokens of a trained VQ-VAE run
//!   (`[model] vqvae = "<run dir>"`, `[model.gpt]` = `ChoreoGptConfig`);
//! - `lodgepp_pddm`: the primitive-based diffusion model with its genre discriminator
//!   (`[model.pddm]`, `[model.discriminator]` or `discriminator = false`, `[model.weights]`,
//!   `[model.dropout]`, `[model.shift]` κ / p of the residual shifting).
//!
//! The genre list comes from the data set manifest (`[data] manifest`).

use std::path::{Path, PathBuf};

use dancegen_lodgepp::choreo_gpt::ChoreoGpt;
use dancegen_lodgepp::config::{ChoreoGptConfig, PddmTable, TOKEN_FRAMES};
use dancegen_lodgepp::layout::MAIN_DIMS;
use dancegen_lodgepp::training::{self, PddmTrainModel};
use dancegen_nn::autoencoder::MotionAutoencoder;
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::device;
use dancegen_nn::diffusion::pddm::ResidualShift;
use dancegen_nn::weights::{self, Layout};
use serde::{Deserialize, Serialize};

use crate::config::{NormalizerKind, TrainConfig};
use crate::data::{Batch, GenreManifest, Normalizer};
use crate::task::{Losses, TrainTask};
use crate::tasks::motion_autoencoder::{MotionAutoencoderTask, autoencoder_losses};
use crate::{TrainError, files};

pub const VQVAE: &str = "lodgepp_vqvae";
pub const GPT: &str = "lodgepp_gpt";
pub const PDDM: &str = "lodgepp_pddm";

/// The genres of `[data] manifest` (required by the genre-conditioned networks).
fn genres(config: &TrainConfig, path: &Path) -> Result<Vec<String>, String> {
    let m = config.data.manifest.as_ref().ok_or_else(|| {
        format!(
            "{}: [data] manifest is required (the genres come from a `dancegen dataset build` manifest)",
            path.display()
        )
    })?;
    let g = GenreManifest::load(m).map_err(|e| e.to_string())?;
    if g.genres.is_empty() {
        return Err(format!("{}: the manifest lists no genres", m.display()));
    }
    Ok(g.genres)
}

fn batch_genres(batch: &Batch) -> Vec<usize> {
    batch
        .genre
        .clone()
        .expect("every clip of a Lodge++ data set has a genre (checked when the task is built)")
}

fn batch_music(batch: &Batch) -> dancegen_nn::burn::tensor::Tensor<3> {
    batch
        .music
        .clone()
        .expect("[data.music] is required (checked when the task is built)")
}

fn require_music_and_mean_std(config: &TrainConfig) -> Result<(), String> {
    match &config.data.music {
        Some(m) if m.dims == dancegen_lodgepp::choreo_gpt::MUSIC_DIMS => {}
        Some(m) => {
            return Err(format!(
                "[data.music] dims = {}, Lodge++ reads the 35 EDGE features",
                m.dims
            ));
        }
        None => return Err("[data.music] is required".into()),
    }
    if config.data.normalizer != NormalizerKind::MeanStd {
        return Err("[data] normalizer must be \"mean_std\" for Lodge++".into());
    }
    Ok(())
}

/// `lodgepp_vqvae`.
#[derive(Clone, Debug)]
pub struct VqvaeTask {
    inner: MotionAutoencoderTask,
}

impl VqvaeTask {
    pub fn from_config(config: &TrainConfig) -> Result<Self, String> {
        Ok(Self {
            inner: MotionAutoencoderTask::from_table(
                config.model_params(),
                MAIN_DIMS,
                config.data.window,
            )?,
        })
    }
}

impl TrainTask for VqvaeTask {
    type Model = MotionAutoencoder;

    fn kind(&self) -> &'static str {
        VQVAE
    }

    fn init(&self, device: &Device) -> MotionAutoencoder {
        self.inner.init(device)
    }

    fn loss(&self, model: &MotionAutoencoder, batch: &Batch) -> Losses {
        autoencoder_losses(model, training::main_joints(batch.motion.clone()))
    }

    fn model_config(&self) -> toml::Table {
        self.inner.model_config()
    }
}

/// A trained VQ-VAE run directory: its model on the inference device.
pub fn load_vqvae(run: &Path) -> Result<MotionAutoencoder, String> {
    let toml_path = run.join(files::MODEL_TOML);
    let text = std::fs::read_to_string(&toml_path).map_err(|e| {
        format!(
            "{}: {e} (is it a finished lodgepp_vqvae run?)",
            toml_path.display()
        )
    })?;
    let t: toml::Table =
        toml::from_str(&text).map_err(|e| format!("{}: {e}", toml_path.display()))?;
    if t.get("kind").and_then(|k| k.as_str()) != Some(VQVAE) {
        return Err(format!("{}: not a {VQVAE} model", toml_path.display()));
    }
    let window = t.get("window").and_then(|w| w.as_integer()).unwrap_or(128) as usize;
    let cfg = t
        .get("config")
        .and_then(|c| c.as_table())
        .cloned()
        .ok_or_else(|| format!("{}: no [config]", toml_path.display()))?;
    let task = MotionAutoencoderTask::from_table(cfg, MAIN_DIMS, window)?;
    let dev = device::inference();
    weights::load(task.init(&dev), &run.join(files::WEIGHTS), Layout::Burn)
        .map_err(|e| e.to_string())
}

/// `[model]` of `lodgepp_gpt`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GptTable {
    /// The VQ-VAE run directory.
    vqvae: PathBuf,
    #[serde(default)]
    gpt: ChoreoGptConfig,
    /// Filled in from the manifest (written to `model.toml`).
    #[serde(default)]
    genres: Vec<String>,
}

/// `lodgepp_gpt`.
#[derive(Clone, Debug)]
pub struct GptTask {
    table: GptTable,
    codes: usize,
    vqvae: MotionAutoencoder,
}

impl GptTask {
    pub fn from_config(config: &TrainConfig, path: &Path) -> Result<Self, String> {
        require_music_and_mean_std(config)?;
        let mut table: GptTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        // `TrainConfig::parse` made `vqvae` absolute (relative to the config file).
        if table.vqvae.is_relative() {
            table.vqvae = path.parent().unwrap_or(Path::new(".")).join(&table.vqvae);
        }
        table.genres = genres(config, path)?;
        let w = config.data.window;
        if w != table.gpt.window_tokens * TOKEN_FRAMES {
            return Err(format!(
                "[data] window {w} must be gpt.window_tokens × 4 = {}",
                table.gpt.window_tokens * TOKEN_FRAMES
            ));
        }
        let vqvae = load_vqvae(&table.vqvae)?;
        let codes = vqvae
            .quantizer
            .codebook_size()
            .ok_or("the VQ-VAE's quantizer has no single codebook (use kind = \"vq\")")?;
        Ok(Self {
            table,
            codes,
            vqvae,
        })
    }
}

impl TrainTask for GptTask {
    type Model = ChoreoGpt;

    fn kind(&self) -> &'static str {
        GPT
    }

    fn init(&self, device: &Device) -> ChoreoGpt {
        self.table
            .gpt
            .init(self.codes, self.table.genres.len(), device)
    }

    fn loss(&self, model: &ChoreoGpt, batch: &Batch) -> Losses {
        let tokens = training::tokens(&self.vqvae, batch.motion.clone(), &device::inference());
        let (ce, acc) = training::gpt_loss(model, tokens, batch_music(batch), &batch_genres(batch));
        Losses {
            total: ce.clone(),
            parts: vec![("cross_entropy", ce), ("accuracy", acc)],
        }
    }

    fn model_config(&self) -> toml::Table {
        let mut t = toml::Table::try_from(&self.table).expect("serialises");
        t.insert("codes".into(), toml::Value::Integer(self.codes as i64));
        t
    }
}

/// `lodgepp_pddm`.
#[derive(Clone, Debug)]
pub struct PddmTask {
    pub table: PddmTable,
    shift: ResidualShift,
}

impl PddmTask {
    pub fn from_config(config: &TrainConfig, path: &Path) -> Result<Self, String> {
        require_music_and_mean_std(config)?;
        let mut table: PddmTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        table.genres = genres(config, path)?;
        if config.data.window != table.pddm.window {
            return Err(format!(
                "[data] window {} differs from pddm.window {}",
                config.data.window, table.pddm.window
            ));
        }
        let shift = table.shift.schedule();
        Ok(Self { table, shift })
    }
}

/// A `lodgepp_pddm` run's checkpoint with the run's own task and training windows, on the
/// inference device: what the diagnostic probes (`examples/pddm_*_probe.rs`) start from.
pub struct PddmCheckpoint {
    pub task: PddmTask,
    pub data: crate::data::WindowDataset,
    pub model: PddmTrainModel,
}

impl PddmCheckpoint {
    /// Reads the run directory `run` (its `config.toml`, `normalizer.json` and data) and the
    /// weights `checkpoint`.
    pub fn load(run: &Path, checkpoint: &Path) -> Result<Self, String> {
        let s = |e: &dyn std::fmt::Display| e.to_string();
        let config = crate::run_config(run).map_err(|e| s(&e))?;
        let task = PddmTask::from_config(&config, &run.join("config.toml"))?;
        let normalizer = Normalizer::load(&run.join("normalizer.json")).map_err(|e| s(&e))?;
        let clips = crate::data::WindowDataset::read_clips(&config.data).map_err(|e| s(&e))?;
        let data = crate::data::WindowDataset::new(clips, &config.data, &normalizer, 5)
            .map_err(|e| s(&e))?;
        let dev = device::inference();
        let model = weights::load(
            task.init_with_data(&dev, &normalizer),
            checkpoint,
            Layout::Burn,
        )
        .map_err(|e| format!("{}: {e}", checkpoint.display()))?;
        Ok(Self { task, data, model })
    }
}

impl TrainTask for PddmTask {
    type Model = PddmTrainModel;

    fn kind(&self) -> &'static str {
        PDDM
    }

    fn init(&self, device: &Device) -> PddmTrainModel {
        let d = dancegen_lodgepp::layout::DIMS;
        self.table.init(&vec![0.0; d], &vec![1.0; d], device)
    }

    fn init_with_data(&self, device: &Device, normalizer: &Normalizer) -> PddmTrainModel {
        match normalizer {
            Normalizer::MeanStd { mean, std } => self.table.init(mean, std, device),
            _ => unreachable!("mean_std checked when the task is built"),
        }
    }

    fn loss(&self, model: &PddmTrainModel, batch: &Batch) -> Losses {
        let l = training::pddm_loss(
            model,
            self.table.pddm.canonical_heading,
            batch.motion.clone(),
            batch_music(batch),
            &batch_genres(batch),
            &self.shift,
            &self.table.weights,
            &self.table.dropout,
            batch.seed,
        );
        Losses {
            total: l.total,
            parts: l.parts,
        }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("serialises")
    }
}

/// Errors of building a task, with the config path.
pub fn config_error(path: &Path, reason: String) -> TrainError {
    TrainError::Config {
        path: path.to_path_buf(),
        reason,
    }
}

/// Copies the three trained runs into one Lodge++ model directory (`dancegen_lodgepp::bundle`)
/// and builds its key-motion library from the PDDM run's training data. Returns the library's
/// clip count.
pub fn assemble_bundle(
    vqvae_run: &Path,
    gpt_run: &Path,
    pddm_run: &Path,
    out: &Path,
    name: &str,
    default_genre: Option<&str>,
) -> Result<usize, TrainError> {
    use dancegen_lodgepp::bundle::{self, BundleConfig, GptSection, SamplingDefaults};
    use dancegen_lodgepp::library::PrimitiveLibrary;
    use dancegen_nn::autoencoder::MotionAutoencoderConfig;

    let read_model_toml = |run: &Path, kind: &str| -> Result<toml::Table, TrainError> {
        let p = run.join(files::MODEL_TOML);
        let text = std::fs::read_to_string(&p).map_err(|e| TrainError::io(&p, e))?;
        let t: toml::Table = toml::from_str(&text).map_err(|e| config_error(&p, e.to_string()))?;
        if t.get("kind").and_then(|k| k.as_str()) != Some(kind) {
            return Err(config_error(&p, format!("not a finished {kind} run")));
        }
        t.get("config")
            .and_then(|c| c.as_table())
            .cloned()
            .ok_or_else(|| config_error(&p, "no [config]".into()))
    };
    let vq_cfg = read_model_toml(vqvae_run, VQVAE)?;
    let vq_task = MotionAutoencoderTask::from_table(vq_cfg, MAIN_DIMS, 128)
        .map_err(|r| config_error(vqvae_run, r))?;
    let vqvae: MotionAutoencoderConfig = vq_task.config.clone();
    let gpt_cfg = read_model_toml(gpt_run, GPT)?;
    let gpt: ChoreoGptConfig = gpt_cfg
        .get("gpt")
        .cloned()
        .unwrap_or(toml::Value::Table(Default::default()))
        .try_into()
        .map_err(|e: toml::de::Error| config_error(gpt_run, e.to_string()))?;
    let codes = gpt_cfg
        .get("codes")
        .and_then(|c| c.as_integer())
        .ok_or_else(|| config_error(gpt_run, "model.toml has no codes".into()))?
        as usize;
    let gpt_genres: Vec<String> = gpt_cfg
        .get("genres")
        .cloned()
        .and_then(|g| g.try_into().ok())
        .unwrap_or_default();
    let pddm_cfg = read_model_toml(pddm_run, PDDM)?;
    let pddm: PddmTable = toml::Value::Table(pddm_cfg)
        .try_into()
        .map_err(|e: toml::de::Error| config_error(pddm_run, e.to_string()))?;
    if gpt_genres != pddm.genres {
        return Err(config_error(
            gpt_run,
            format!(
                "the GPT's genres {gpt_genres:?} differ from the PDDM's {:?}",
                pddm.genres
            ),
        ));
    }
    let default_genre = default_genre
        .map(str::to_string)
        .unwrap_or_else(|| pddm.genres[0].clone());
    let run_pddm = pddm.clone();
    let config = BundleConfig {
        kind: bundle::KIND.into(),
        name: name.into(),
        fps: 30.0,
        genres: pddm.genres.clone(),
        default_genre,
        vqvae,
        gpt: GptSection { gpt, codes },
        // The bundle carries the denoiser only: the discriminator is a training-time critic.
        pddm: PddmTable {
            use_discriminator: false,
            ..pddm
        },
        sampling: SamplingDefaults::default(),
    };

    // The library: the PDDM run's training motion in its normalised units.
    let run_config = crate::trainer::run_config(pddm_run)?;
    let normalizer = Normalizer::load(&pddm_run.join(files::NORMALIZER))?;
    let mut clips = crate::data::WindowDataset::read_clips(&run_config.data)?;
    for c in &mut clips {
        normalizer
            .transform(&mut c.motion)
            .map_err(|reason| TrainError::Data {
                path: c.source.clone(),
                reason,
            })?;
    }
    // Each clip tagged with its take's genre, an index into the manifest's genres, which are
    // the PDDM run's (and so the bundle's) genres.
    let library = PrimitiveLibrary::build(clips.iter().map(|c| (c.motion.as_slice(), c.genre)));

    std::fs::create_dir_all(out).map_err(|e| TrainError::io(out, e))?;
    let copy = |from: PathBuf, to: &str| -> Result<(), TrainError> {
        let dst = out.join(to);
        let bytes = std::fs::read(&from).map_err(|e| TrainError::io(&from, e))?;
        dancegen_io::write_atomic(&dst, |w| w.write_all(&bytes))
            .map_err(|e| TrainError::io(&dst, e))
    };
    // Weights are re-saved in half precision (weights::Storage::F16) at half the size. The
    // rounding (≤ 2^-11 relative) is enough to change which tokens the GPT's top-k sampling
    // draws, so a seed gives another dance than the F32 weights would; docs/solo-eval.md
    // measures the shipped (F16) bundle.
    let dev = device::inference();
    // A weights error names the file it is about (a run's weights or the bundle file written).
    let half =
        |to: &str, save: &dyn Fn(&Path) -> Result<(), weights::WeightsError>| save(&out.join(to));
    let vq_model = weights::load(
        vq_task.init(&dev),
        &vqvae_run.join(files::WEIGHTS),
        Layout::Burn,
    )?;
    let gpt_model = weights::load(
        config.gpt.gpt.init(codes, config.genres.len(), &dev),
        &gpt_run.join(files::WEIGHTS),
        Layout::Burn,
    )?;
    let Normalizer::MeanStd { mean, std } = &normalizer else {
        return Err(config_error(
            pddm_run,
            "the PDDM run's normaliser is not mean_std".into(),
        ));
    };
    let mut pddm_model = weights::load(
        run_pddm.init(mean, std, &dev),
        &pddm_run.join(files::WEIGHTS),
        Layout::Burn,
    )?;
    pddm_model.discriminator = None;
    let f16 = weights::Storage::F16;
    half(bundle::files::VQVAE, &|p| {
        weights::save_as(&vq_model, p, Layout::Burn, &[], f16)
    })?;
    half(bundle::files::GPT, &|p| {
        weights::save_as(&gpt_model, p, Layout::Burn, &[], f16)
    })?;
    half(bundle::files::PDDM, &|p| {
        weights::save_as(&pddm_model, p, Layout::Burn, &[], f16)
    })?;
    copy(
        vqvae_run.join(files::NORMALIZER),
        bundle::files::VQVAE_NORMALIZER,
    )?;
    copy(pddm_run.join(files::NORMALIZER), bundle::files::NORMALIZER)?;
    let lp = out.join(bundle::files::LIBRARY);
    library
        .save(&lp)
        .map_err(|e| TrainError::io(&lp, std::io::Error::other(e.to_string())))?;
    let text = toml::to_string_pretty(&config).expect("config serialises");
    let mp = out.join(bundle::files::MODEL_TOML);
    dancegen_io::write_atomic(&mp, |w| w.write_all(text.as_bytes()))
        .map_err(|e| TrainError::io(&mp, e))?;
    Ok(library.len())
}
