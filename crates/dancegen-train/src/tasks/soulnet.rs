//! The three networks of the holistic system (`dancegen_soulnet`, SoulNet), each its own run on
//! holistic windows `[body 263 | hands 360 | face 52]` (`representation = "holistic"`):
//! - `soulnet_vq`: the part autoencoder (HRVQ-VAE; `quantizer = "rvq" | "vq"` for the ablation),
//!   `[model]` = [`VqTable`];
//! - `soulnet_mmr`: the music–motion retrieval encoders, `[model]` = [`MmrTable`], needs
//!   `[data.music]` (35 features);
//! - `soulnet_magm`: the masked + residual transformers on the tokens of a finished
//!   `soulnet_vq` run, conditioned by a finished `soulnet_mmr` run's music encoder:
//!   `[model] vq = "<run>"`, `mmr = "<run>"`, `[model.generator]` = [`GeneratorTable`].
//!
//! `dancegen bundle --holistic-vq --holistic-mmr --holistic-generator` joins the three runs into
//! a model directory ([`assemble_holistic_bundle`]).
//!
//! SoulNet's own sizes (holistic.md §1.2: width 512, depth 3, 512 codes × 512, 6 levels) do not
//! fit this machine's budget; `configs/soulnet_small_*.toml` are the shipped model's.

use std::path::{Path, PathBuf};

use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::tensor::{Device, Tensor};
use dancegen_nn::device;
use dancegen_nn::part_autoencoder::PartAutoencoder;
use dancegen_nn::retrieval::MusicMotionRetrieval;
use dancegen_nn::weights::{self, Layout};
use dancegen_soulnet::config::{GeneratorTable, MmrTable};
use dancegen_soulnet::generator::{Condition, PartGenerator, mmr_alignment_loss, music_tokens};
use dancegen_soulnet::layout::MUSIC_DIMS;
use serde::{Deserialize, Serialize};

pub use dancegen_soulnet::config::{QuantizerKind, VqTable};
/// The `soulnet_vq` `[model]` table (kept under its first name).
pub type SoulnetVqTable = VqTable;

use super::run_feet::{RunFeet, run_dir_of};
use super::soulnet_sources as sources;
use crate::config::{Representation, TrainConfig};
use crate::data::{Batch, Normalizer};
use crate::files;
use crate::task::{Losses, TrainTask};
use dancegen_soulnet::body_feet::BodyFeet;

/// The `[model] kind`s of the three holistic runs (defined with the run readers).
pub use super::soulnet_sources::{KIND, MAGM, MMR};

/// The split layout's part widths with the 52 ARKit weights as the face.
pub const PARTS: [usize; 3] = dancegen_soulnet::layout::PART_DIMS;

fn require_holistic(config: &TrainConfig, kind: &str) -> Result<(), String> {
    if config.data.representation != Representation::Holistic {
        return Err(format!(
            "[data] representation must be \"holistic\" for {kind}"
        ));
    }
    Ok(())
}

fn require_music(config: &TrainConfig, kind: &str) -> Result<(), String> {
    match &config.data.music {
        Some(m) if m.dims == MUSIC_DIMS => Ok(()),
        Some(m) => Err(format!(
            "[data.music] dims = {}, {kind} reads the {MUSIC_DIMS} EDGE features",
            m.dims
        )),
        None => Err(format!("[data.music] is required for {kind}")),
    }
}

fn batch_music(batch: &Batch) -> Tensor<3> {
    batch
        .music
        .clone()
        .expect("[data.music] is required (checked when the task is built)")
}

/// `soulnet_vq`: the part autoencoder, from scratch or (`[model] init_from`) from a finished
/// `soulnet_vq` run or a holistic bundle, optionally training its decoder alone
/// (`decoders_only`), so that a generator trained on its tokens stays valid. With
/// `foot_velocity_weight > 0` the body's foot velocities
/// ([`dancegen_soulnet::body_feet::BodyFeet`]) join the loss.
#[derive(Debug)]
pub struct SoulnetVqTask {
    pub table: VqTable,
    /// The autoencoder to start from (absolute, or relative to the working directory once
    /// built; the config gives it relative to the config file).
    pub init_from: Option<PathBuf>,
    /// Train the decoder only: the encoders and quantizer keep `init_from`'s weights.
    pub decoders_only: bool,
    fps: f64,
    /// `init_from` on the inference device, whose codes the decoder learns from when
    /// `decoders_only`.
    frozen: Option<PartAutoencoder>,
    feet: RunFeet<BodyFeet>,
}

/// The `[model]` keys of `soulnet_vq` that are not the autoencoder's [`VqTable`].
const START_KEYS: [&str; 2] = ["init_from", "decoders_only"];

impl SoulnetVqTask {
    /// `path` is the config file (relative paths in it are relative to its folder).
    pub fn from_config(config: &TrainConfig, path: &Path) -> Result<Self, String> {
        require_holistic(config, KIND)?;
        let mut params = config.model_params();
        let init_from = match params.remove(START_KEYS[0]) {
            None => None,
            Some(toml::Value::String(p)) => {
                let p = PathBuf::from(p);
                Some(if p.is_relative() {
                    path.parent().unwrap_or(Path::new(".")).join(p)
                } else {
                    p
                })
            }
            Some(v) => return Err(format!("[model] init_from must be a path, not {v}")),
        };
        let decoders_only = match params.remove(START_KEYS[1]) {
            None => false,
            Some(toml::Value::Boolean(b)) => b,
            Some(v) => {
                return Err(format!(
                    "[model] decoders_only must be true or false, not {v}"
                ));
            }
        };
        let table: VqTable = toml::Value::Table(params)
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        let down = table.frames_per_token();
        if !config.data.window.is_multiple_of(down) {
            return Err(format!(
                "[data] window {} must be a multiple of 2^down_t = {down}",
                config.data.window
            ));
        }
        table.validate().map_err(|r| r.replace("[vq]", "[model]"))?;
        if decoders_only && init_from.is_none() {
            return Err("[model] decoders_only needs init_from (the autoencoder to keep)".into());
        }
        let frozen = match (&init_from, decoders_only) {
            (Some(from), true) => Some(read_vq_weights(from, &table, &device::inference())?.0),
            _ => None,
        };
        Ok(Self {
            table,
            init_from,
            decoders_only,
            fps: f64::from(config.data.fps),
            frozen,
            feet: RunFeet::new(run_dir_of(config, path), BodyFeet::new),
        })
    }
}

/// The part autoencoder in `from` (a `soulnet_vq` run or a holistic model) if its
/// architecture is `table`'s, and the path of its normaliser.
fn read_vq_weights(
    from: &Path,
    table: &VqTable,
    device: &Device,
) -> Result<(PartAutoencoder, PathBuf), String> {
    let (theirs, ae, norm_path) = sources::part_autoencoder(from, device)?;
    if !theirs.same_architecture(table) {
        return Err(format!(
            "{}: its part autoencoder's architecture is not this run's [model]",
            from.display()
        ));
    }
    Ok((ae, norm_path))
}

impl TrainTask for SoulnetVqTask {
    type Model = PartAutoencoder;

    fn kind(&self) -> &'static str {
        KIND
    }

    fn init(&self, device: &Device) -> PartAutoencoder {
        self.table.autoencoder().init(device)
    }

    fn check_data(&self, normalizer: &Normalizer) -> Result<(), String> {
        let Some(from) = &self.init_from else {
            return Ok(());
        };
        let (_, norm_path) = read_vq_weights(from, &self.table, &device::inference())
            .map_err(|e| format!("[model] init_from: {e}"))?;
        let same = super::bundle_files::normalizer_matches(normalizer, &norm_path)
            .map_err(|e| format!("[model] init_from: {e}"))?;
        if !same {
            return Err(format!(
                "[model] init_from: {} was trained with another normaliser than this run's data \
                 gives (rebuild the same data set, or train from scratch)",
                norm_path.display()
            ));
        }
        Ok(())
    }

    fn init_with_data(&self, device: &Device, _normalizer: &Normalizer) -> PartAutoencoder {
        match &self.init_from {
            None => self.init(device),
            // Checked by `check_data` before this is called.
            Some(from) => {
                read_vq_weights(from, &self.table, device)
                    .unwrap_or_else(|e| panic!("[model] init_from: {e}"))
                    .0
            }
        }
    }

    fn loss(&self, model: &PartAutoencoder, batch: &Batch) -> Losses {
        let l = model.loss_with(batch.motion.clone(), self.frozen.as_ref());
        let [body, hands, face] = l.recon_parts;
        let mut total = l.total;
        let mut parts = vec![
            ("body", body),
            ("hands", hands),
            ("face", face),
            ("velocity", l.velocity),
            ("acceleration", l.acceleration),
            ("commit", l.commit),
        ];
        if let Some(p) = l.quant.perplexity {
            parts.push(("perplexity", p));
        }
        if self.table.foot_velocity_weight > 0.0 {
            let f = self
                .feet
                .get()
                .velocity_loss(l.reconstruction, batch.motion.clone(), self.fps);
            total = total + f.clone() * self.table.foot_velocity_weight;
            parts.push(("foot_velocity", f));
        }
        Losses { total, parts }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("a serialisable table")
    }
}

/// `soulnet_mmr`.
#[derive(Clone, Debug)]
pub struct SoulnetMmrTask {
    pub table: MmrTable,
}

impl SoulnetMmrTask {
    pub fn from_config(config: &TrainConfig) -> Result<Self, String> {
        require_holistic(config, MMR)?;
        require_music(config, MMR)?;
        let table: MmrTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        table
            .validate()
            .map_err(|r| r.replace("[mmr]", "[model]"))?;
        Ok(Self { table })
    }
}

impl TrainTask for SoulnetMmrTask {
    type Model = MusicMotionRetrieval;

    fn kind(&self) -> &'static str {
        MMR
    }

    fn init(&self, device: &Device) -> MusicMotionRetrieval {
        self.table.retrieval().init(device)
    }

    fn loss(&self, model: &MusicMotionRetrieval, batch: &Batch) -> Losses {
        let l = model.loss(batch.motion.clone(), batch_music(batch));
        Losses {
            total: l.clone(),
            parts: vec![("info_nce", l)],
        }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("a serialisable table")
    }
}

/// `[model]` of `soulnet_magm`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagmTable {
    /// The part autoencoder whose tokens the generator learns: a finished `soulnet_vq` run or
    /// a holistic model directory (relative to the config file).
    pub vq: PathBuf,
    /// The music encoder's source: a finished `soulnet_mmr` run or a holistic model directory.
    pub mmr: PathBuf,
    /// The generator to start from (a finished `soulnet_magm` run or a holistic model with the
    /// same `[generator]` table): training continues from its weights under this run's
    /// optimiser and schedule. Absent: from scratch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_from: Option<PathBuf>,
    #[serde(default)]
    pub generator: GeneratorTable,
    /// Weight of SoulNet's training-time MMR alignment loss (its code: 0.5; 0 = off).
    #[serde(default)]
    pub mmr_loss_weight: f64,
    /// Gumbel-softmax temperature of that loss's token draws (the paper anneals it, the code
    /// uses 0.01; ours: 0.5).
    #[serde(default = "d_gumbel_tau")]
    pub mmr_gumbel_tau: f64,
    /// Filled from the two runs when the task is built (whatever a config says here is
    /// replaced), so the run's `model.toml` records what the generator was trained on and the
    /// bundle can check it.
    #[serde(default)]
    pub vq_table: Option<VqTable>,
    #[serde(default)]
    pub mmr_table: Option<MmrTable>,
}

fn d_gumbel_tau() -> f64 {
    0.5
}

/// A finished run's `[config]` table and weights, loaded onto `device`.
fn load_run<T: for<'de> Deserialize<'de>, M>(
    run: &Path,
    kind: &str,
    init: impl Fn(&T) -> M,
) -> Result<(T, M), String>
where
    M: dancegen_nn::burn::module::Module + dancegen_nn::burn::store::ModuleSnapshot,
{
    let table: T =
        super::bundle_files::finished_run_config(run, kind).map_err(|e| e.to_string())?;
    let model = weights::load(init(&table), &run.join(files::WEIGHTS), Layout::Burn)
        .map_err(|e| e.to_string())?;
    Ok((table, model))
}

/// `soulnet_magm`.
pub struct SoulnetMagmTask {
    pub table: MagmTable,
    vq: PartAutoencoder,
    mmr: MusicMotionRetrieval,
    /// Frozen copies on the training device for the MMR loss (gradients flow through them to
    /// the generator, never into them); the MMR without dropout.
    aligned: Option<(PartAutoencoder, MusicMotionRetrieval)>,
}

impl SoulnetMagmTask {
    pub fn from_config(config: &TrainConfig, path: &Path) -> Result<Self, String> {
        require_holistic(config, MAGM)?;
        require_music(config, MAGM)?;
        let mut table: MagmTable = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        for p in [&mut table.vq, &mut table.mmr]
            .into_iter()
            .chain(table.init_from.as_mut())
        {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
        table
            .generator
            .validate()
            .map_err(|r| r.replace("[generator]", "[model.generator]"))?;
        let dev = device::inference();
        let (vq_table, vq, _) = sources::part_autoencoder(&table.vq, &dev)?;
        let (mmr_table, mmr) = sources::retrieval(&table.mmr, None, &dev)?;
        let window = table.generator.window_tokens * vq_table.frames_per_token();
        if config.data.window != window {
            return Err(format!(
                "[data] window {} must be generator.window_tokens × 2^down_t = {window}",
                config.data.window
            ));
        }
        if !(table.mmr_loss_weight >= 0.0 && table.mmr_gumbel_tau > 0.0) {
            return Err("[model] mmr_loss_weight must be ≥ 0 and mmr_gumbel_tau > 0".into());
        }
        let aligned = if table.mmr_loss_weight > 0.0 {
            let tdev = device::training();
            let (_, v, _) = sources::part_autoencoder(&table.vq, &tdev)?;
            // The MMR without dropout.
            let (_, m) = sources::retrieval(&table.mmr, Some(0.0), &tdev)?;
            Some((v.no_grad(), m.no_grad()))
        } else {
            None
        };
        table.vq_table = Some(vq_table);
        table.mmr_table = Some(mmr_table);
        if let Some(from) = &table.init_from {
            // Fail here, not after the data is read: the generator must be this run's.
            sources::generator(from, &table.generator, || Self::build(&table, &dev))
                .map_err(|e| format!("[model] init_from: {e}"))?;
        }
        Ok(Self {
            table,
            vq,
            mmr,
            aligned,
        })
    }

    fn vq_table(&self) -> &VqTable {
        self.table.vq_table.as_ref().expect("set in from_config")
    }

    /// The empty generator of `table` (its `vq_table` and `mmr_table` filled).
    fn build(table: &MagmTable, device: &Device) -> PartGenerator {
        let vq = table.vq_table.as_ref().expect("set in from_config");
        let d = table
            .mmr_table
            .as_ref()
            .expect("set in from_config")
            .latent_dim;
        PartGenerator::init(&table.generator, vq, d, device)
    }
}

impl TrainTask for SoulnetMagmTask {
    type Model = PartGenerator;

    fn kind(&self) -> &'static str {
        MAGM
    }

    fn init(&self, device: &Device) -> PartGenerator {
        Self::build(&self.table, device)
    }

    /// The tokens are the autoencoder's only if the data is normalised as it was trained.
    fn check_data(&self, normalizer: &Normalizer) -> Result<(), String> {
        let (_, _, norm_path) = sources::part_autoencoder(&self.table.vq, &device::inference())
            .map_err(|e| format!("[model] vq: {e}"))?;
        let same = super::bundle_files::normalizer_matches(normalizer, &norm_path)
            .map_err(|e| format!("[model] vq: {e}"))?;
        if !same {
            return Err(format!(
                "[model] vq: {} was trained with another normaliser than this run's data gives \
                 (the tokens would not be its tokens; use the data set it was trained on)",
                norm_path.display()
            ));
        }
        Ok(())
    }

    fn init_with_data(&self, device: &Device, _normalizer: &Normalizer) -> PartGenerator {
        match &self.table.init_from {
            None => self.init(device),
            // Read once in `from_config`, so this does not fail.
            Some(from) => sources::generator(from, &self.table.generator, || self.init(device))
                .unwrap_or_else(|e| panic!("[model] init_from: {e}")),
        }
    }

    fn loss(&self, model: &PartGenerator, batch: &Batch) -> Losses {
        let device = batch.motion.device();
        let inf = device::inference();
        // The frozen networks run on the inference device; only their outputs cross over.
        let motion = Tensor::<3>::from_data(batch.motion.clone().into_data(), &inf);
        let idx = self.vq.encode(motion);
        let dims = idx.dims();
        let ids: Vec<i64> = idx
            .into_data()
            .convert::<i64>()
            .try_into_vec::<i64>()
            .expect("int indices");
        let music = batch_music(batch);
        let music_inf = Tensor::<3>::from_data(music.clone().into_data(), &inf);
        let clip = self.mmr.music.forward(music_inf, None).into_data();
        let fpt = self.vq_table().frames_per_token();
        let cond = Condition {
            clip: Tensor::<2>::from_data(clip, &device),
            frames: (self.table.generator.d_frame(fpt) > 0).then(|| music_tokens(music, fpt)),
        };
        let l = model.loss(
            &ids,
            dims,
            cond,
            self.table.generator.cond_drop_prob,
            batch.seed,
            &device,
        );
        let mut parts = vec![
            ("masked_ce", l.masked.clone()),
            ("residual_ce", l.residual.clone()),
        ];
        let mut total = l.total.clone();
        if let Some((vq, mmr)) = &self.aligned {
            let a = mmr_alignment_loss(
                &l,
                &ids,
                dims,
                vq,
                mmr,
                batch_music(batch),
                self.table.mmr_gumbel_tau,
                batch.seed ^ 0x004D_4D52,
            );
            total = total + a.clone() * self.table.mmr_loss_weight;
            parts.push(("mmr", a));
        }
        Losses { total, parts }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.table).expect("a serialisable table")
    }
}

/// The holistic model directory from the three finished runs.
pub fn assemble_holistic_bundle(
    vq_run: &Path,
    mmr_run: &Path,
    generator_run: &Path,
    out: &Path,
    name: &str,
) -> Result<(), crate::TrainError> {
    use dancegen_soulnet::bundle::{BundleConfig, KIND as BUNDLE_KIND, files as bundle_files};
    use dancegen_soulnet::config::SamplingDefaults;

    let err = super::bundle_files::config_error;
    let magm: MagmTable = super::bundle_files::finished_run_config(generator_run, MAGM)?;
    let dev = device::inference();
    let (vq_table, vq) = load_run(vq_run, KIND, |t: &VqTable| t.autoencoder().init(&dev))
        .map_err(|r| err(vq_run, r))?;
    let (mmr_table, mmr) = load_run(mmr_run, MMR, |t: &MmrTable| t.retrieval().init(&dev))
        .map_err(|r| err(mmr_run, r))?;
    if magm.vq_table.as_ref() != Some(&vq_table) || magm.mmr_table.as_ref() != Some(&mmr_table) {
        return Err(err(
            generator_run,
            format!(
                "the generator run was trained on another autoencoder or MMR configuration than {} and {}",
                vq_run.display(),
                mmr_run.display()
            ),
        ));
    }
    let config = BundleConfig {
        kind: BUNDLE_KIND.into(),
        name: name.into(),
        fps: 30.0,
        vq: vq_table,
        mmr: mmr_table,
        sampling: SamplingDefaults::for_window(magm.generator.window_tokens),
        generator: magm.generator,
    };
    let generator = weights::load(
        config.init_generator(&dev),
        &generator_run.join(files::WEIGHTS),
        Layout::Burn,
    )?;
    // Every network saw the data through one normaliser (the same data set gives the same
    // statistics); a run on other data would silently shift the inputs.
    let norm = |run: &Path| std::fs::read(run.join(files::NORMALIZER)).ok();
    for run in [mmr_run, generator_run] {
        if norm(run) != norm(vq_run) {
            return Err(err(
                &run.join(files::NORMALIZER),
                format!(
                    "differs from {}: the runs were trained on different data",
                    vq_run.join(files::NORMALIZER).display()
                ),
            ));
        }
    }
    std::fs::create_dir_all(out).map_err(|e| crate::TrainError::io(out, e))?;
    let f16 = weights::Storage::F16;
    for (file, result) in [
        (
            bundle_files::VQ,
            save(&vq, &out.join(bundle_files::VQ), f16),
        ),
        (
            bundle_files::MMR,
            save(&mmr, &out.join(bundle_files::MMR), f16),
        ),
        (
            bundle_files::GENERATOR,
            save(&generator, &out.join(bundle_files::GENERATOR), f16),
        ),
    ] {
        result.map_err(|e| err(&out.join(file), e))?;
    }
    // The autoencoder's normaliser is the one every network saw.
    super::bundle_files::copy_normalizer(vq_run, &out.join(bundle_files::NORMALIZER))?;
    super::bundle_files::write_model_toml(&config, &out.join(bundle_files::MODEL_TOML))
}

/// The finished runs that replace networks of a holistic model ([`replace_in_holistic_model`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Replacements<'a> {
    /// A `soulnet_vq` run of the same architecture: a decoder fine-tuned with `[model]
    /// decoders_only`, say, so the generator's tokens keep their meaning.
    pub vq: Option<&'a Path>,
    /// A `soulnet_magm` run trained on the model's tokens and MMR (`[model] vq` and `mmr` the
    /// model, or runs of the same architecture): its generator and `[generator]` table.
    pub generator: Option<&'a Path>,
}

/// The holistic model in `bundle` with the networks of `runs` replaced, written to `out` (which
/// may be `bundle` itself). Everything else (the other networks, the normaliser, the sampling
/// defaults, the model card) is copied byte for byte. Each run must have been trained on data
/// normalised as the model's; nothing is written on a refusal.
pub fn replace_in_holistic_model(
    runs: Replacements<'_>,
    bundle: &Path,
    out: &Path,
    name: &str,
) -> Result<(), crate::TrainError> {
    use dancegen_soulnet::bundle::{BundleConfig, files as bundle_files};

    let err = super::bundle_files::config_error;
    if runs.vq.is_none() && runs.generator.is_none() {
        return Err(err(bundle, "no run to put into the model".into()));
    }
    let mt = bundle.join(bundle_files::MODEL_TOML);
    let text = std::fs::read_to_string(&mt).map_err(|e| crate::TrainError::io(&mt, e))?;
    let mut config: BundleConfig =
        toml::from_str(&text).map_err(|e| err(&mt, e.message().to_string()))?;
    let dev = device::inference();
    let same_normalizer = |run: &Path| -> Result<(), crate::TrainError> {
        let ours = Normalizer::load(&run.join(files::NORMALIZER))?;
        if super::bundle_files::normalizer_matches(&ours, &bundle.join(bundle_files::NORMALIZER))? {
            Ok(())
        } else {
            Err(err(
                run,
                format!(
                    "trained with another normaliser than {}'s",
                    bundle.display()
                ),
            ))
        }
    };
    let vq = match runs.vq {
        None => None,
        Some(run) => {
            let (vq_table, vq) = load_run(run, KIND, |t: &VqTable| t.autoencoder().init(&dev))
                .map_err(|r| err(run, r))?;
            if !vq_table.same_architecture(&config.vq) {
                return Err(err(
                    run,
                    format!(
                        "its part autoencoder's architecture is not the one {} was trained on",
                        bundle.display()
                    ),
                ));
            }
            same_normalizer(run)?;
            config.vq = vq_table;
            Some(vq)
        }
    };
    let generator = match runs.generator {
        None => None,
        Some(run) => {
            let magm: MagmTable = super::bundle_files::finished_run_config(run, MAGM)?;
            let on_ours = magm
                .vq_table
                .as_ref()
                .is_some_and(|t| t.same_architecture(&config.vq))
                && magm.mmr_table.as_ref() == Some(&config.mmr);
            if !on_ours {
                return Err(err(
                    run,
                    format!(
                        "the generator was trained on another autoencoder or MMR configuration \
                         than {}'s",
                        bundle.display()
                    ),
                ));
            }
            if config.sampling.overlap_tokens >= magm.generator.window_tokens {
                return Err(err(
                    run,
                    format!(
                        "its window of {} tokens is not longer than {}'s [sampling] \
                         overlap_tokens {}",
                        magm.generator.window_tokens,
                        bundle.display(),
                        config.sampling.overlap_tokens
                    ),
                ));
            }
            same_normalizer(run)?;
            config.generator = magm.generator;
            let g = weights::load(
                config.init_generator(&dev),
                &run.join(files::WEIGHTS),
                Layout::Burn,
            )?;
            Some(g)
        }
    };
    // Read everything kept before writing anything: `out` may be `bundle`.
    let mut kept = Vec::new();
    for (file, replaced) in [
        (bundle_files::VQ, vq.is_some()),
        (bundle_files::MMR, false),
        (bundle_files::GENERATOR, generator.is_some()),
        (bundle_files::NORMALIZER, false),
        (bundle_files::CARD, false),
    ] {
        if replaced {
            continue;
        }
        let p = bundle.join(file);
        match std::fs::read(&p) {
            Ok(bytes) => kept.push((file, bytes)),
            Err(e) if file == bundle_files::CARD && e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(crate::TrainError::io(&p, e)),
        }
    }
    config.name = name.into();
    std::fs::create_dir_all(out).map_err(|e| crate::TrainError::io(out, e))?;
    if let Some(vq) = &vq {
        let p = out.join(bundle_files::VQ);
        save(vq, &p, weights::Storage::F16).map_err(|e| err(&p, e))?;
    }
    if let Some(g) = &generator {
        let p = out.join(bundle_files::GENERATOR);
        save(g, &p, weights::Storage::F16).map_err(|e| err(&p, e))?;
    }
    for (file, bytes) in kept {
        let dst = out.join(file);
        dancegen_io::write_atomic(&dst, |w| std::io::Write::write_all(w, &bytes))
            .map_err(|e| crate::TrainError::io(&dst, e))?;
    }
    super::bundle_files::write_model_toml(&config, &out.join(bundle_files::MODEL_TOML))
}

fn save<M>(m: &M, p: &Path, storage: weights::Storage) -> Result<(), String>
where
    M: dancegen_nn::burn::module::Module + dancegen_nn::burn::store::ModuleSnapshot,
{
    weights::save_as(m, p, Layout::Burn, &[], storage).map_err(|e| e.to_string())
}
