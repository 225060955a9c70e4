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
use dancegen_reactdance::autoencoder::{HfsqAutoencoder, LossOptions};
use dancegen_reactdance::config::{
    DenoiserConfig, HfsqAutoencoderConfig, LatentLossWeights, MUSIC_DIMS,
};
use dancegen_reactdance::denoiser::LatentDenoiser;
use dancegen_reactdance::follower_feet::FollowerFeet;
use dancegen_reactdance::training::{self, follower};
use serde::{Deserialize, Serialize};

use super::run_feet::{RunFeet, run_dir_of};
use crate::config::{NormalizerKind, Representation, TrainConfig};
use crate::data::{Batch, Normalizer};
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
    /// Start from this autoencoder instead of random weights: a finished `reactdance_hfsq` run
    /// or a duet bundle (relative to the config file). Its architecture and its normaliser
    /// must be this run's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_from: Option<PathBuf>,
    /// Train the decoders only (the encoders and quantizers keep `init_from`'s weights), so a
    /// latent model trained on that autoencoder stays valid. Needs `init_from`.
    #[serde(default)]
    pub decoders_only: bool,
}

/// `reactdance_hfsq`.
#[derive(Debug)]
pub struct HfsqTask {
    pub table: HfsqTable,
    /// The run directory: its `normalizer.json` is read for the foot velocity loss.
    feet: RunFeet<FollowerFeet>,
    /// `init_from` on the inference device, whose encoders give the latent when
    /// `decoders_only`.
    frozen: Option<HfsqAutoencoder>,
}

impl HfsqTask {
    pub fn from_config(config: &TrainConfig, path: &Path) -> Result<Self, String> {
        require_duet(config, false)?;
        let mut table: HfsqTable = toml::Value::Table(config.model_params())
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
        let base = path.parent().unwrap_or(Path::new("."));
        if let Some(from) = &mut table.init_from
            && from.is_relative()
        {
            *from = base.join(&*from);
        }
        if table.decoders_only && table.init_from.is_none() {
            return Err("[model] decoders_only needs init_from (the autoencoder to keep)".into());
        }
        let run_dir = run_dir_of(config, path);
        let frozen = match (&table.init_from, table.decoders_only) {
            (Some(from), true) => {
                Some(read_hfsq_weights(from, &table.autoencoder, &device::inference())?.0)
            }
            _ => None,
        };
        Ok(Self {
            table,
            feet: RunFeet::new(run_dir, FollowerFeet::new),
            frozen,
        })
    }

    fn loss_options(&self) -> LossOptions {
        let feet =
            (self.table.autoencoder.foot_velocity_weight > 0.0).then(|| self.feet.get().clone());
        LossOptions {
            feet,
            frozen_latent: self.frozen.clone(),
            ..LossOptions::default()
        }
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

    fn check_data(&self, normalizer: &Normalizer) -> Result<(), String> {
        match &self.table.init_from {
            None => Ok(()),
            Some(from) => load_initial_hfsq(
                from,
                &self.table.autoencoder,
                normalizer,
                &device::inference(),
            )
            .map(|_| ())
            .map_err(|e| format!("[model] init_from: {e}")),
        }
    }

    fn init_with_data(&self, device: &Device, normalizer: &Normalizer) -> HfsqAutoencoder {
        match &self.table.init_from {
            None => self.init(device),
            // Checked by `check_data` before this is called.
            Some(from) => load_initial_hfsq(from, &self.table.autoencoder, normalizer, device)
                .unwrap_or_else(|e| panic!("[model] init_from: {e}")),
        }
    }

    fn loss(&self, model: &HfsqAutoencoder, batch: &Batch) -> Losses {
        let (_, l) = model.loss_with(
            follower(&batch.motion),
            &self.table.autoencoder,
            &self.loss_options(),
        );
        let mut parts = vec![
            ("position", l.position),
            ("velocity", l.velocity),
            ("acceleration", l.acceleration),
            ("latent", l.latent),
        ];
        if let Some(f) = l.foot_velocity {
            parts.push(("foot_velocity", f));
        }
        Losses {
            total: l.total,
            parts,
        }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("serialises")
    }
}

/// The autoencoder an `init_from` names (a `reactdance_hfsq` run or a duet bundle), checked
/// against this run's architecture and normaliser.
fn load_initial_hfsq(
    from: &Path,
    cfg: &HfsqAutoencoderConfig,
    normalizer: &Normalizer,
    device: &Device,
) -> Result<HfsqAutoencoder, String> {
    let (ae, norm_path) = read_hfsq_weights(from, cfg, device)?;
    if !super::bundle_files::normalizer_matches(normalizer, &norm_path)
        .map_err(|e| e.to_string())?
    {
        return Err(format!(
            "{}: trained with another normaliser than this run's data gives (rebuild the same \
             data set, or train from scratch)",
            norm_path.display()
        ));
    }
    Ok(ae)
}

/// The weights of the autoencoder in `from` (a `reactdance_hfsq` run or a duet bundle) if its
/// architecture is `cfg`'s, and the path of its normaliser.
fn read_hfsq_weights(
    from: &Path,
    cfg: &HfsqAutoencoderConfig,
    device: &Device,
) -> Result<(HfsqAutoencoder, PathBuf), String> {
    use dancegen_reactdance::bundle::files as bundle_files;
    let bundle = from.join(bundle_files::HFSQ);
    let (their_cfg, weights_path, norm_path) = if bundle.is_file() {
        let b =
            dancegen_reactdance::bundle::BundleConfig::load(&from.join(bundle_files::MODEL_TOML))
                .map_err(|e| e.to_string())?;
        (b.autoencoder, bundle, from.join(bundle_files::NORMALIZER))
    } else {
        let (c, _) = load_hfsq(from, &device::inference())?;
        (c, from.join(files::WEIGHTS), from.join(files::NORMALIZER))
    };
    if !their_cfg.same_architecture(cfg) {
        return Err(format!(
            "{}: its autoencoder architecture is not this run's [model.autoencoder]",
            from.display()
        ));
    }
    let ae = weights::load(cfg.init(device), &weights_path, Layout::Burn)
        .map_err(|e| format!("{}: {e}", weights_path.display()))?;
    Ok((ae, norm_path))
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
    feet: RunFeet<FollowerFeet>,
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
            feet: RunFeet::new(run_dir_of(config, path), FollowerFeet::new),
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
            (self.table.weights.foot_velocity > 0.0).then(|| self.feet.get()),
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
///
/// `ldm_run` may also be a duet model directory: its latent model, normaliser and `[sampling]`
/// are kept and its autoencoder is replaced by `hfsq_run`'s, which must have the same
/// architecture and normaliser (a decoder fine-tuned with `[model] decoders_only`, say).
pub fn assemble_duet_bundle(
    hfsq_run: &Path,
    ldm_run: &Path,
    out: &Path,
    name: &str,
) -> Result<(), crate::TrainError> {
    use dancegen_reactdance::bundle::{BundleConfig, KIND};
    use dancegen_reactdance::config::SamplingDefaults;

    let err = super::bundle_files::config_error;
    if ldm_run
        .join(dancegen_reactdance::bundle::files::DENOISER)
        .is_file()
    {
        return replace_bundle_autoencoder(hfsq_run, ldm_run, out, name);
    }
    let table: LdmTable = super::bundle_files::finished_run_config(ldm_run, LDM)?;
    let dev = device::inference();
    let (ae_cfg, ae) = load_hfsq(hfsq_run, &dev).map_err(|r| err(hfsq_run, r))?;
    if !ae_cfg.same_architecture(&table.autoencoder) {
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
    write_duet_bundle(&ae, &net, ldm_run, &config, out)
}

/// Writes a duet model directory: both networks in half precision, the normaliser of the run or
/// bundle `normalizer_from`, and `config` as `model.toml`.
fn write_duet_bundle(
    ae: &HfsqAutoencoder,
    net: &LatentDenoiser,
    normalizer_from: &Path,
    config: &dancegen_reactdance::bundle::BundleConfig,
    out: &Path,
) -> Result<(), crate::TrainError> {
    use dancegen_reactdance::bundle::files as bundle_files;
    std::fs::create_dir_all(out).map_err(|e| crate::TrainError::io(out, e))?;
    let f16 = weights::Storage::F16;
    weights::save_as(ae, &out.join(bundle_files::HFSQ), Layout::Burn, &[], f16)?;
    weights::save_as(
        net,
        &out.join(bundle_files::DENOISER),
        Layout::Burn,
        &[],
        f16,
    )?;
    super::bundle_files::copy_normalizer(normalizer_from, &out.join(bundle_files::NORMALIZER))?;
    super::bundle_files::write_model_toml(config, &out.join(bundle_files::MODEL_TOML))
}

/// [`assemble_duet_bundle`] from a duet model directory `bundle` and an autoencoder run.
fn replace_bundle_autoencoder(
    hfsq_run: &Path,
    bundle: &Path,
    out: &Path,
    name: &str,
) -> Result<(), crate::TrainError> {
    use dancegen_reactdance::bundle::{BundleConfig, files as bundle_files};

    let err = super::bundle_files::config_error;
    let mt = bundle.join(bundle_files::MODEL_TOML);
    let mut config = BundleConfig::load(&mt).map_err(|e| err(&mt, e.reason))?;
    let dev = device::inference();
    let (ae_cfg, ae) = load_hfsq(hfsq_run, &dev).map_err(|r| err(hfsq_run, r))?;
    if !ae_cfg.same_architecture(&config.autoencoder) {
        return Err(err(
            hfsq_run,
            format!(
                "its autoencoder architecture is not the one {} was trained on",
                bundle.display()
            ),
        ));
    }
    let ours = Normalizer::load(&hfsq_run.join(files::NORMALIZER))?;
    if !super::bundle_files::normalizer_matches(&ours, &bundle.join(bundle_files::NORMALIZER))? {
        return Err(err(
            hfsq_run,
            format!(
                "trained with another normaliser than {}'s",
                bundle.display()
            ),
        ));
    }
    let denoiser = weights::load(
        config
            .denoiser
            .init(ae_cfg.latent_dim(), ae_cfg.frames_per_token(), &dev),
        &bundle.join(bundle_files::DENOISER),
        Layout::Burn,
    )?;
    config.name = name.into();
    config.autoencoder = ae_cfg;
    write_duet_bundle(&ae, &denoiser, bundle, &config, out)
}
