//! The group system's denoiser (`dancegen_tcdiffpp`, kind `tcdiffpp_group`), trained on the
//! `group` representation (`dancegen dataset build --pairing group`) with the EDGE-35 music.
//!
//! Windows arrive raw; each is brought into the network's coordinates here
//! ([`dancegen_tcdiffpp::window::training_window`]: slots left to right, roots relative to the
//! frame-0 centroid, normalised with the statistics the model carries) and gets its swap code,
//! then [`dancegen_tcdiffpp::losses::group_loss`] gives the objective.

use std::path::{Path, PathBuf};

use dancegen_nn::burn::tensor::{Device, Tensor, TensorData};
use dancegen_nn::diffusion::Schedule;
use dancegen_nn::weights;
use dancegen_tcdiffpp::config::GroupModelConfig;
use dancegen_tcdiffpp::denoiser::{GroupDenoiser, MUSIC_DIMS};
use dancegen_tcdiffpp::layout::GROUP_DIMS;
use dancegen_tcdiffpp::losses::{GroupBatch, group_loss};
use dancegen_tcdiffpp::window::training_window;

use crate::config::{Representation, TrainConfig};
use crate::data::{Batch, Normalizer};
use crate::task::{Losses, TrainTask};

pub const KIND: &str = "tcdiffpp_group";

/// `tcdiffpp_group`.
#[derive(Clone, Debug)]
pub struct GroupTask {
    pub config: GroupModelConfig,
    schedule: Schedule,
    /// `[model] init_from`: a run's weights (a `model.safetensors`, or a run or checkpoint
    /// folder holding one) to start from. Tensors of the same name and shape are taken; the
    /// modules this architecture adds keep their fresh initialisation (a warm start, e.g. the
    /// integrated root added to a trained network).
    pub init_from: Option<PathBuf>,
    /// `[model] init_fresh`: modules of [`FRESH_MODULES`] that start fresh even where
    /// `init_from` has them (e.g. a footwork adaptor trained to replace the lower body, when
    /// this run's adds to it).
    pub init_fresh: Vec<String>,
}

/// The modules `[model] init_fresh` may name.
pub const FRESH_MODULES: [&str; 4] = ["footwork", "fusion", "output", "root_path"];

impl GroupTask {
    pub fn from_config(config: &TrainConfig) -> Result<Self, String> {
        if config.data.representation != Representation::Group {
            return Err("[data] representation must be \"group\" for the group system".into());
        }
        match &config.data.music {
            Some(m) if m.dims == MUSIC_DIMS => {}
            Some(m) => {
                return Err(format!(
                    "[data.music] dims = {}, the group system reads the 35 EDGE features",
                    m.dims
                ));
            }
            None => return Err("[data.music] is required".into()),
        }
        let mut params = config.model_params();
        let init_from = match params.remove("init_from") {
            None => None,
            Some(toml::Value::String(p)) => Some(weights_file(Path::new(&p))),
            Some(v) => return Err(format!("[model] init_from must be a path, not {v}")),
        };
        let init_fresh = match params.remove("init_fresh") {
            None => Vec::new(),
            Some(toml::Value::Array(names)) => names
                .into_iter()
                .map(|n| match n {
                    toml::Value::String(n) if FRESH_MODULES.contains(&n.as_str()) => Ok(n),
                    other => Err(format!(
                        "[model] init_fresh: {other} is not one of {}",
                        FRESH_MODULES.join(", ")
                    )),
                })
                .collect::<Result<_, _>>()?,
            Some(v) => return Err(format!("[model] init_fresh must be a list, not {v}")),
        };
        if !init_fresh.is_empty() && init_from.is_none() {
            return Err("[model] init_fresh needs init_from".into());
        }
        let cfg: GroupModelConfig = toml::Value::Table(params)
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
        cfg.denoiser
            .check()
            .map_err(|e| format!("[model.denoiser] {e}"))?;
        cfg.training
            .check()
            .map_err(|e| format!("[model.training] {e}"))?;
        if config.data.window != cfg.window() {
            return Err(format!(
                "[data] window = {} but the model's window is {} frames",
                config.data.window,
                cfg.window()
            ));
        }
        Ok(Self {
            config: cfg,
            schedule: Schedule::edge(),
            init_from,
            init_fresh,
        })
    }
}

/// `p` itself, or the weights file in the run or checkpoint folder `p`.
fn weights_file(p: &Path) -> PathBuf {
    if p.is_dir() {
        p.join(crate::files::WEIGHTS)
    } else {
        p.to_path_buf()
    }
}

/// The normaliser's 151 per-channel `(mean, std)`.
fn stats(n: &Normalizer) -> (Vec<f64>, Vec<f64>) {
    match n {
        Normalizer::MeanStd { mean, std } if mean.len() == dancegen_nn::edge151::DIMS => {
            (mean.clone(), std.clone())
        }
        _ => (
            vec![0.0; dancegen_nn::edge151::DIMS],
            vec![1.0; dancegen_nn::edge151::DIMS],
        ),
    }
}

impl TrainTask for GroupTask {
    type Model = GroupDenoiser;

    fn kind(&self) -> &'static str {
        KIND
    }

    fn init(&self, device: &Device) -> GroupDenoiser {
        let (m, s) = stats(&Normalizer::None { dims: 0 });
        self.config.denoiser.init(&m, &s, device)
    }

    fn check_data(&self, normalizer: &Normalizer) -> Result<(), String> {
        let Some(from) = &self.init_from else {
            return Ok(());
        };
        let (m, s) = stats(normalizer);
        let dev = dancegen_nn::device::inference();
        let (net, _) = weights::load_warm(self.config.denoiser.init(&m, &s, &dev), from)
            .map_err(|e| format!("[model] init_from: {e}"))?;
        let fresh = self.config.denoiser.init(&m, &s, &dev);
        let (theirs, ours) = (net.denorm.host(), fresh.denorm.host());
        let close = |a: &[f32], b: &[f32]| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y).abs() <= 1e-5 * (1.0 + y.abs()))
        };
        if !(close(&theirs.0, &ours.0) && close(&theirs.1, &ours.1)) {
            return Err(format!(
                "[model] init_from: {} was trained with another normaliser than this run's data \
                 gives (rebuild the same data set, or train from scratch)",
                from.display()
            ));
        }
        Ok(())
    }

    fn init_with_data(&self, device: &Device, normalizer: &Normalizer) -> GroupDenoiser {
        let (m, s) = stats(normalizer);
        let fresh = self.config.denoiser.init(&m, &s, device);
        let Some(from) = &self.init_from else {
            return fresh;
        };
        // Checked by `check_data` before this is called.
        let (mut net, report) = weights::load_warm(fresh.clone(), from)
            .unwrap_or_else(|e| panic!("[model] init_from: {e}"));
        for name in &self.init_fresh {
            match name.as_str() {
                "footwork" => net.footwork = fresh.footwork.clone(),
                "fusion" => net.fusion = fresh.fusion.clone(),
                "output" => net.output = fresh.output.clone(),
                "root_path" => net.root_path = fresh.root_path.clone(),
                other => unreachable!("{other} was checked against FRESH_MODULES"),
            }
        }
        eprintln!(
            "init_from {}: fresh {:?}{}, ignored {:?}",
            from.display(),
            report.fresh,
            if self.init_fresh.is_empty() {
                String::new()
            } else {
                format!(" and the modules {:?}", self.init_fresh)
            },
            report.unused
        );
        net
    }

    fn loss(&self, model: &GroupDenoiser, batch: &Batch) -> Losses {
        let [b, t, dims] = batch.motion.dims();
        assert_eq!(dims, GROUP_DIMS, "group windows");
        let dancers = batch
            .dancers
            .clone()
            .expect("group clips carry their dancer count (representation = \"group\")");
        let device = batch.motion.device();
        let raw = batch
            .motion
            .clone()
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .expect("f32 batch");
        let (scale, shift) = model.denorm.host();
        let mut x0 = Vec::with_capacity(raw.len());
        let mut swap = Vec::with_capacity(b * dancegen_tcdiffpp::swap::SWAP_DIMS);
        for (i, &n) in dancers.iter().enumerate() {
            let w = &raw[i * t * GROUP_DIMS..(i + 1) * t * GROUP_DIMS];
            let (x, s) = training_window(w, t, n, &scale, &shift);
            x0.extend(x);
            swap.extend(s);
        }
        let sw = swap.len() / b;
        let gb = GroupBatch {
            x0: Tensor::from_data(TensorData::new(x0, [b, t, GROUP_DIMS]), &device),
            music: batch
                .music
                .clone()
                .expect("[data.music] is required (checked when the task is built)"),
            dancers,
            swap: Tensor::from_data(TensorData::new(swap, [b, sw]), &device),
        };
        let l = group_loss(
            model,
            &self.schedule,
            &gb,
            &self.config.loss,
            &self.config.training,
            batch.seed,
        );
        Losses {
            total: l.total,
            parts: l.parts,
        }
    }

    fn model_config(&self) -> toml::Table {
        toml::Table::try_from(&self.config).expect("serialises")
    }
}

/// Writes a group model directory (`dancegen_tcdiffpp::bundle`) from a finished
/// `tcdiffpp_group` run. Weights are stored in half precision (the normaliser statistics stay
/// f32).
pub fn assemble_group_bundle(
    run: &std::path::Path,
    out: &std::path::Path,
    name: &str,
) -> Result<(), crate::TrainError> {
    use dancegen_nn::device;
    use dancegen_nn::weights::{self, Layout};
    use dancegen_tcdiffpp::bundle::{BundleConfig, KIND as BUNDLE_KIND, files as bundle_files};

    use crate::files;

    let mut config: GroupModelConfig = super::bundle_files::finished_run_config(run, KIND)?;
    // Sampling is not trained: the bundle gets this version's defaults (as the duet bundle
    // does), so a rebuilt bundle matches the shipped one.
    config.sampling = dancegen_tcdiffpp::config::SamplingConfig::default();
    let dev = device::inference();
    let d = dancegen_nn::edge151::DIMS;
    let net = weights::load(
        config.denoiser.init(&vec![0.0; d], &vec![1.0; d], &dev),
        &run.join(files::WEIGHTS),
        Layout::Burn,
    )?;
    std::fs::create_dir_all(out).map_err(|e| crate::TrainError::io(out, e))?;
    let dp = out.join(bundle_files::DENOISER);
    weights::save_as(&net, &dp, Layout::Burn, &[], weights::Storage::F16)?;
    super::bundle_files::copy_normalizer(run, &out.join(bundle_files::NORMALIZER))?;
    let bundle = BundleConfig {
        kind: BUNDLE_KIND.into(),
        name: name.into(),
        fps: 30.0,
        model: config,
    };
    super::bundle_files::write_model_toml(&bundle, &out.join(bundle_files::MODEL_TOML))
}
