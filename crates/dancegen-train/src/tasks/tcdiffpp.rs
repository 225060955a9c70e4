//! The group system's denoiser (`dancegen_tcdiffpp`, kind `tcdiffpp_group`), trained on the
//! `group` representation (`dancegen dataset build --pairing group`) with the EDGE-35 music.
//!
//! Windows arrive raw; each is brought into the network's coordinates here
//! ([`dancegen_tcdiffpp::window::training_window`]: slots left to right, roots relative to the
//! frame-0 centroid, normalised with the statistics the model carries) and gets its swap code,
//! then [`dancegen_tcdiffpp::losses::group_loss`] gives the objective.

use dancegen_nn::burn::tensor::{Device, Tensor, TensorData};
use dancegen_nn::diffusion::Schedule;
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
}

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
        let cfg: GroupModelConfig = toml::Value::Table(config.model_params())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model]: {}", e.message()))?;
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
        })
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

    fn init_with_data(&self, device: &Device, normalizer: &Normalizer) -> GroupDenoiser {
        let (m, s) = stats(normalizer);
        self.config.denoiser.init(&m, &s, device)
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
