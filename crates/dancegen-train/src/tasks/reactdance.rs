//! The two networks of the duet system (`dancegen_reactdance`), each its own run on windows of
//! the `duet` representation (follower relative to its leader, then the leader; mean/std
//! normaliser) with the EDGE-35 music:
//! - `reactdance_hfsq`: the HFSQ autoencoder (`[model.autoencoder]`);
//! - `reactdance_ldm`: the latent diffusion transformer on a finished autoencoder run
//!   (`[model] hfsq = "<run dir>"`, `[model.denoiser]`, `[model.weights]`). Dense sliding
//!   windows are `[data] window = block_tokens × 2^down_t` with a small `[data] stride`.

use std::path::{Path, PathBuf};

use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::device;
use dancegen_nn::diffusion::{BetaSchedule, Schedule};
use dancegen_nn::weights::{self, Layout};
use dancegen_reactdance::autoencoder::HfsqAutoencoder;
use dancegen_reactdance::config::{
    DenoiserConfig, HfsqAutoencoderConfig, LatentLossWeights, MUSIC_DIMS,
};
use dancegen_reactdance::denoiser::LatentDenoiser;
use dancegen_reactdance::training::{self, follower};
use serde::{Deserialize, Serialize};

use crate::config::{NormalizerKind, Representation, TrainConfig};
use crate::data::Batch;
use crate::files;
use crate::task::{Losses, TrainTask};

pub const HFSQ: &str = "reactdance_hfsq";
pub const LDM: &str = "reactdance_ldm";

fn require_duet(config: &TrainConfig, music: bool) -> Result<(), String> {
    if config.data.representation != Representation::Duet {
        return Err("[data] representation must be \"duet\" for the duet system".into());
    }
    if config.data.normalizer != NormalizerKind::MeanStd {
        return Err("[data] normalizer must be \"mean_std\" for the duet system".into());
    }
    if music {
        match &config.data.music {
            Some(m) if m.dims == MUSIC_DIMS => {}
            Some(m) => {
                return Err(format!(
                    "[data.music] dims = {}, the duet system reads the 35 EDGE features",
                    m.dims
                ));
            }
            None => return Err("[data.music] is required".into()),
        }
    }
    Ok(())
}

/// `[model]` of `reactdance_hfsq`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HfsqTable {
    #[serde(default)]
    pub autoencoder: HfsqAutoencoderConfig,
}

/// `reactdance_hfsq`.
#[derive(Clone, Debug)]
pub struct HfsqTask {
    pub table: HfsqTable,
}

impl HfsqTask {
    pub fn from_config(config: &TrainConfig) -> Result<Self, String> {
        require_duet(config, false)?;
        let table: HfsqTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        table.autoencoder.validate()?;
        let f = table.autoencoder.frames_per_token();
        if !config.data.window.is_multiple_of(f) {
            return Err(format!(
                "[data] window {} must be a multiple of 2^down_t = {f}",
                config.data.window
            ));
        }
        Ok(Self { table })
    }
}

impl TrainTask for HfsqTask {
    type Model = HfsqAutoencoder;

    fn kind(&self) -> &'static str {
        HFSQ
    }

    fn init(&self, device: &Device) -> HfsqAutoencoder {
        self.table.autoencoder.init(device)
    }

    fn loss(&self, model: &HfsqAutoencoder, batch: &Batch) -> Losses {
        let (_, l) = model.loss(follower(&batch.motion), &self.table.autoencoder);
        Losses {
            total: l.total,
            parts: vec![
                ("position", l.position),
                ("velocity", l.velocity),
                ("acceleration", l.acceleration),
                ("latent", l.latent),
            ],
        }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("serialises")
    }
}

/// A finished `reactdance_hfsq` run: its configuration and weights on `device`.
pub fn load_hfsq(
    run: &Path,
    device: &Device,
) -> Result<(HfsqAutoencoderConfig, HfsqAutoencoder), String> {
    let p = run.join(files::MODEL_TOML);
    let text = std::fs::read_to_string(&p)
        .map_err(|e| format!("{}: {e} (is it a finished {HFSQ} run?)", p.display()))?;
    let t: toml::Table = toml::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))?;
    if t.get("kind").and_then(|k| k.as_str()) != Some(HFSQ) {
        return Err(format!("{}: not a {HFSQ} model", p.display()));
    }
    let table: HfsqTable = t
        .get("config")
        .cloned()
        .ok_or_else(|| format!("{}: no [config]", p.display()))?
        .try_into()
        .map_err(|e: toml::de::Error| format!("{}: {}", p.display(), e.message()))?;
    let ae = weights::load(
        table.autoencoder.init(device),
        &run.join(files::WEIGHTS),
        Layout::Burn,
    )
    .map_err(|e| e.to_string())?;
    Ok((table.autoencoder, ae))
}

/// `[model]` of `reactdance_ldm`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LdmTable {
    /// The autoencoder run directory.
    pub hfsq: PathBuf,
    #[serde(default)]
    pub denoiser: DenoiserConfig,
    #[serde(default)]
    pub weights: LatentLossWeights,
    /// Filled in from the autoencoder run (written to `model.toml`).
    #[serde(default)]
    pub autoencoder: HfsqAutoencoderConfig,
}

/// `reactdance_ldm`.
pub struct LdmTask {
    pub table: LdmTable,
    schedule: Schedule,
    ae_target: HfsqAutoencoder,
    ae_decode: HfsqAutoencoder,
}

impl LdmTask {
    pub fn from_config(config: &TrainConfig, path: &Path) -> Result<Self, String> {
        require_duet(config, true)?;
        let mut table: LdmTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        if table.hfsq.is_relative() {
            table.hfsq = path.parent().unwrap_or(Path::new(".")).join(&table.hfsq);
        }
        table.denoiser.validate()?;
        let (ae_cfg, ae_target) = load_hfsq(&table.hfsq, &device::inference())?;
        let window = table.denoiser.block_tokens * ae_cfg.frames_per_token();
        if config.data.window != window {
            return Err(format!(
                "[data] window {} must be denoiser.block_tokens × 2^down_t = {window}",
                config.data.window
            ));
        }
        let (_, ae_decode) = load_hfsq(&table.hfsq, &device::training())?;
        table.autoencoder = ae_cfg;
        Ok(Self {
            schedule: Schedule::new(BetaSchedule::Cosine, table.denoiser.timesteps),
            table,
            ae_target,
            ae_decode: ae_decode.no_grad(),
        })
    }
}

impl TrainTask for LdmTask {
    type Model = LatentDenoiser;

    fn kind(&self) -> &'static str {
        LDM
    }

    fn init(&self, device: &Device) -> LatentDenoiser {
        let ae = &self.table.autoencoder;
        self.table
            .denoiser
            .init(ae.latent_dim(), ae.frames_per_token(), device)
    }

    fn loss(&self, model: &LatentDenoiser, batch: &Batch) -> Losses {
        let l = training::ldm_loss(
            model,
            &self.ae_target,
            &self.ae_decode,
            batch.motion.clone(),
            batch
                .music
                .clone()
                .expect("[data.music] is required (checked when the task is built)"),
            &self.schedule,
            &self.table.weights,
            self.table.autoencoder.down_t,
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

/// Writes a duet model directory (`dancegen_reactdance::bundle`) from a finished autoencoder
/// run and a finished diffusion run trained on it. Weights are stored in half precision.
pub fn assemble_duet_bundle(
    hfsq_run: &Path,
    ldm_run: &Path,
    out: &Path,
    name: &str,
) -> Result<(), crate::TrainError> {
    use dancegen_reactdance::bundle::{BundleConfig, KIND, files as bundle_files};
    use dancegen_reactdance::config::SamplingDefaults;

    let err = |p: &Path, reason: String| crate::TrainError::Config {
        path: p.to_path_buf(),
        reason,
    };
    let table: LdmTable = super::bundle_files::finished_run_config(ldm_run, LDM)?;
    let dev = device::inference();
    let (ae_cfg, ae) = load_hfsq(hfsq_run, &dev).map_err(|r| err(hfsq_run, r))?;
    if ae_cfg != table.autoencoder {
        return Err(err(
            hfsq_run,
            format!(
                "the diffusion run {} was trained on another autoencoder configuration",
                ldm_run.display()
            ),
        ));
    }
    let net = weights::load(
        table
            .denoiser
            .init(ae_cfg.latent_dim(), ae_cfg.frames_per_token(), &dev),
        &ldm_run.join(files::WEIGHTS),
        Layout::Burn,
    )?;
    std::fs::create_dir_all(out).map_err(|e| crate::TrainError::io(out, e))?;
    let f16 = weights::Storage::F16;
    let hp = out.join(bundle_files::HFSQ);
    weights::save_as(&ae, &hp, Layout::Burn, &[], f16)?;
    let dp = out.join(bundle_files::DENOISER);
    weights::save_as(&net, &dp, Layout::Burn, &[], f16)?;
    super::bundle_files::copy_normalizer(ldm_run, &out.join(bundle_files::NORMALIZER))?;
    let run = crate::trainer::run_config(ldm_run)?;
    let config = BundleConfig {
        kind: KIND.into(),
        name: name.into(),
        fps: 30.0,
        heading_sigma: run.data.heading_sigma,
        autoencoder: ae_cfg,
        denoiser: table.denoiser,
        sampling: SamplingDefaults::default(),
    };
    super::bundle_files::write_model_toml(&config, &out.join(bundle_files::MODEL_TOML))
}
