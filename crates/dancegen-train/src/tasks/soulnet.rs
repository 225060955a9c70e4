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

use crate::config::{Representation, TrainConfig};
use crate::data::Batch;
use crate::files;
use crate::task::{Losses, TrainTask};

/// `[model] kind` of the part autoencoder.
pub const KIND: &str = "soulnet_vq";
/// `[model] kind` of the retrieval model.
pub const MMR: &str = "soulnet_mmr";
/// `[model] kind` of the generator.
pub const MAGM: &str = "soulnet_magm";

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

/// See the module documentation.
#[derive(Clone, Debug)]
pub struct SoulnetVqTask {
    pub table: VqTable,
}

impl SoulnetVqTask {
    pub fn from_config(config: &TrainConfig) -> Result<Self, String> {
        require_holistic(config, KIND)?;
        let table: VqTable = toml::Value::Table(config.model_params())
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
        Ok(Self { table })
    }
}

impl TrainTask for SoulnetVqTask {
    type Model = PartAutoencoder;

    fn kind(&self) -> &'static str {
        KIND
    }

    fn init(&self, device: &Device) -> PartAutoencoder {
        self.table.autoencoder().init(device)
    }

    fn loss(&self, model: &PartAutoencoder, batch: &Batch) -> Losses {
        let l = model.loss(batch.motion.clone());
        let [body, hands, face] = l.recon_parts;
        let mut parts = vec![
            ("body", body),
            ("hands", hands),
            ("face", face),
            ("velocity", l.velocity),
            ("commit", l.commit),
        ];
        if let Some(p) = l.quant.perplexity {
            parts.push(("perplexity", p));
        }
        Losses {
            total: l.total,
            parts,
        }
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
    /// The finished `soulnet_vq` run (relative to the config file).
    pub vq: PathBuf,
    /// The finished `soulnet_mmr` run.
    pub mmr: PathBuf,
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
        for p in [&mut table.vq, &mut table.mmr] {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
        table
            .generator
            .validate()
            .map_err(|r| r.replace("[generator]", "[model.generator]"))?;
        let dev = device::inference();
        let (vq_table, vq) = load_run(&table.vq, KIND, |t: &VqTable| t.autoencoder().init(&dev))?;
        let (mmr_table, mmr) = load_run(&table.mmr, MMR, |t: &MmrTable| t.retrieval().init(&dev))?;
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
            let (_, v) = load_run(&table.vq, KIND, |t: &VqTable| t.autoencoder().init(&tdev))?;
            let (_, m) = load_run(&table.mmr, MMR, |t: &MmrTable| {
                let mut t = t.clone();
                t.dropout = 0.0;
                t.retrieval().init(&tdev)
            })?;
            Some((v.no_grad(), m.no_grad()))
        } else {
            None
        };
        table.vq_table = Some(vq_table);
        table.mmr_table = Some(mmr_table);
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
}

impl TrainTask for SoulnetMagmTask {
    type Model = PartGenerator;

    fn kind(&self) -> &'static str {
        MAGM
    }

    fn init(&self, device: &Device) -> PartGenerator {
        let vq = self.vq_table();
        let d = self.table.mmr_table.as_ref().expect("set").latent_dim;
        PartGenerator {
            masked: self.table.generator.masked(vq, d).init(device),
            residual: self.table.generator.residual(vq, d).map(|c| c.init(device)),
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

    let err = |p: &Path, reason: String| crate::TrainError::Config {
        path: p.to_path_buf(),
        reason,
    };
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

fn save<M>(m: &M, p: &Path, storage: weights::Storage) -> Result<(), String>
where
    M: dancegen_nn::burn::module::Module + dancegen_nn::burn::store::ModuleSnapshot,
{
    weights::save_as(m, p, Layout::Burn, &[], storage).map_err(|e| e.to_string())
}
