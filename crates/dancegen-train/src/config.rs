//! The training configuration: one TOML file, every key checked.
//!
//! Unknown keys are errors (`deny_unknown_fields`): a misspelt `warmup_step` silently falling
//! back to its default would train a different model than the file says. Relative paths are
//! resolved against the config file's directory, so a config works from any working directory;
//! the copy written to `RUN_DIR/config.toml` holds them absolute, so `--resume` needs only the run
//! directory.
//!
//! ```toml
//! [run]
//! dir = "../../target/runs/motion_vqvae_salsa"
//! seed = 42
//! steps = 300
//! checkpoint_every = 100
//! log_every = 25
//!
//! [data]
//! paths = ["../../../shared/data/cmu-salsa/60_01_scaled.bvh"]
//! representation = "lodge139"
//! window = 64
//! stride = 4
//! batch_size = 16
//! normalizer = "mean_std"
//!
//! [model]
//! kind = "motion_autoencoder"
//! # every other key belongs to the model kind's own config
//!
//! [optimizer]
//! kind = "adan"
//! lr = 4e-4
//! weight_decay = 0.02
//! betas = [0.02, 0.08, 0.01]
//! grad_clip_norm = 1.0
//!
//! [schedule]
//! warmup_steps = 20
//! decay = "cosine"
//!
//! [ema]
//! decay = 0.9999
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::TrainError;

/// The whole file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    pub run: RunConfig,
    pub data: DataConfig,
    /// `kind` plus the model's own keys, handed to the [`crate::TrainTask`] of that kind.
    pub model: toml::Table,
    pub optimizer: OptimizerConfig,
    #[serde(default)]
    pub schedule: ScheduleConfig,
    /// Absent = no EMA of the weights.
    #[serde(default)]
    pub ema: Option<EmaConfig>,
}

/// `[run]`: where, how long, how often.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// The run directory (relative to the config file).
    pub dir: PathBuf,
    /// Seeds the model initialisation, the data order and every step's random numbers.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Optimizer steps in total.
    pub steps: u64,
    /// A checkpoint every N steps (and at the end).
    #[serde(default = "default_checkpoint_every")]
    pub checkpoint_every: u64,
    /// A plain log line (and a CSV row) every N steps.
    #[serde(default = "default_log_every")]
    pub log_every: u64,
    /// Checkpoints kept on disk (the oldest are removed); 0 keeps all.
    #[serde(default = "default_keep_checkpoints")]
    pub keep_checkpoints: usize,
}

fn default_seed() -> u64 {
    0
}
fn default_checkpoint_every() -> u64 {
    1000
}
fn default_log_every() -> u64 {
    50
}
fn default_keep_checkpoints() -> usize {
    3
}

/// `[model]` keys that hold paths (resolved like `[data] paths`).
pub const MODEL_PATH_KEYS: &[&str] = &["vqvae", "hfsq", "vq", "mmr", "init_from"];

/// Per-frame vector the motion files are converted to (`dancegen_motion::repr`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Representation {
    /// EDGE 151 (anchors.md C.2).
    Edge151,
    /// LODGE 139 (anchors.md C.3).
    Lodge139,
    /// HumanML3D-style 263 (anchors.md C.6); one frame shorter than the motion.
    Humanml263,
    /// Duet pairs (`dancegen_motion::repr::duet`): per frame the follower's 151 values
    /// (relative to its leader) then the leader's 220 features; needs `[data] leader`.
    Duet,
    /// Groups of 2–5 dancers (`dancegen dataset build --pairing group`): every directory under
    /// `[data] paths` is one clip of `dancer_<k>.npz` files, a frame is `[5 × 151]` EDGE-151
    /// (dancer `k` in slot `k`, absent dancers zero). Windows reach the task raw; the task
    /// sorts, re-bases and normalises them (the normaliser is one dancer's 151 channels).
    Group,
    /// SoulNet's split vector `[body 263 | hands 360 | face 52]` = 675 per frame
    /// (`dancegen_motion::repr::holistic::split`, the face as ARKit weights) of the SMPL-H 52
    /// motion made of the clip's body and its hands and face from `[data] holistic` (written by
    /// `dancegen dataset build --holistic`); one frame shorter than the motion.
    Holistic,
}

/// How the per-dimension statistics map the data.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalizerKind {
    /// `(x − mean) / std`, as T2M-GPT / MoMask train their VQ-VAEs.
    MeanStd,
    /// EDGE / LODGE MinMax to `[−1, 1]` (anchors.md C.2).
    MinMax,
    /// Raw values.
    None,
}

/// `[data]`: motion files cut into windows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataConfig {
    /// Motion files or directories (every `.bvh`, `.pkl`, `.npz`, `.npy` inside, sorted).
    pub paths: Vec<PathBuf>,
    pub representation: Representation,
    /// Frame rate the motion is resampled to before encoding (EDGE / LODGE: 30).
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// Frames per window (EDGE: 150, Lodge local: 256, Lodge++ VQ-VAE: 128).
    pub window: usize,
    /// Frames between window starts (EDGE: 15 = 0.5 s at 30 fps; dense sliding windows: 1–4).
    pub stride: usize,
    pub batch_size: usize,
    #[serde(default = "default_normalizer")]
    pub normalizer: NormalizerKind,
    /// Per-frame music features aligned with the motion.
    #[serde(default)]
    pub music: Option<MusicConfig>,
    /// A `dancegen dataset build` manifest: each clip's genre (by motion file stem), used by
    /// genre-conditioned models. Clips it does not list get no genre.
    #[serde(default)]
    pub manifest: Option<PathBuf>,
    /// Duet data: directory of each clip's leader, `<dir>/<motion file stem>.npz` (written by
    /// `dancegen dataset build --pairing duet` as `leader/`). Required by `representation =
    /// "duet"`.
    #[serde(default)]
    pub leader: Option<PathBuf>,
    /// Duet data: Gaussian σ (frames) of the leader frame's heading
    /// (`dancegen_motion::repr::duet::leader_frames`); 0 = each frame's own heading.
    #[serde(default)]
    pub heading_sigma: f64,
    /// Holistic data: directory of each clip's hands and face, `<dir>/<motion file stem>.npz`
    /// (`hands` `(T, 30, 3)`, `face` `(T, 52)`; `dancegen dataset build --holistic` writes
    /// `holistic/`). Required by `representation = "holistic"`.
    #[serde(default)]
    pub holistic: Option<PathBuf>,
    /// `normalizer = "mean_std"`: the smallest standard deviation a channel is scaled by
    /// (0 = none, the channel's own std unless below [`crate::data::MIN_STD`]). Channels that
    /// barely move in the data, such as the SMPL hand joints of retargeted BVH (6D std down to
    /// 5e-6), otherwise come out of the normaliser as rare values of 30 to 70 that dominate the
    /// x0 loss and the denoiser's input tokens. Group task only.
    #[serde(default)]
    pub std_floor: f64,
}

fn default_fps() -> f32 {
    30.0
}
fn default_normalizer() -> NormalizerKind {
    NormalizerKind::MeanStd
}

/// `[data.music]`: `<dir>/<motion file stem>.npy`, `(T, dims)` at the motion's frame rate (e.g.
/// written by `dancegen features`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MusicConfig {
    pub dir: PathBuf,
    pub dims: usize,
}

/// Which update rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OptimizerKind {
    /// Burn's AdamW (decoupled weight decay, Loshchilov & Hutter 2019).
    Adamw,
    /// Adan exactly as EDGE trains with it (`Stanford-TML/EDGE:model/adan.py`).
    Adan,
    /// Adan as the paper authors' implementation (`sail-sg/Adan`), Burn's `AdanConfig`.
    AdanOfficial,
}

/// `[optimizer]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimizerConfig {
    pub kind: OptimizerKind,
    /// Peak learning rate (after warm-up).
    pub lr: f64,
    #[serde(default)]
    pub weight_decay: f64,
    /// AdamW: `(β1, β2)` (default 0.9, 0.999). Adan: `(β1, β2, β3)` in the paper's convention,
    /// the weight of the *new* value (EDGE: 0.02, 0.08, 0.01).
    #[serde(default)]
    pub betas: Option<Vec<f64>>,
    #[serde(default = "default_eps")]
    pub eps: f64,
    /// Clip the global L2 norm of all gradients to this (`torch.nn.utils.clip_grad_norm_`).
    #[serde(default)]
    pub grad_clip_norm: Option<f64>,
}

fn default_eps() -> f64 {
    1e-8
}

/// Shape of the learning rate after warm-up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Decay {
    #[default]
    Constant,
    Linear,
    Cosine,
}

/// `[schedule]`: linear warm-up from 0, then decay to `min_lr` at the last step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ScheduleConfig {
    #[serde(default)]
    pub warmup_steps: u64,
    #[serde(default)]
    pub decay: Decay,
    #[serde(default)]
    pub min_lr: f64,
}

/// `[ema]`: `ema ← decay·ema + (1 − decay)·θ` every `every` steps (EDGE: 0.9999, every step).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmaConfig {
    pub decay: f64,
    #[serde(default = "default_ema_every")]
    pub every: u64,
    /// Until this step the average is a copy of the model. Averaging from step 0 keeps
    /// `decay^steps` of the random initialisation in the result (16 % for 0.998 over 900 steps),
    /// which spoils short runs; long runs (EDGE's millions of samples) do not notice.
    #[serde(default)]
    pub start: u64,
}

fn default_ema_every() -> u64 {
    1
}

/// `base.join(rel)` with `.` and `..` removed lexically (messages then show
/// `/project/target/runs/x`, not `/project/examples/train/../../target/runs/x`).
fn lexical_join(base: &Path, rel: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = base.to_path_buf();
    for c in rel.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

impl TrainConfig {
    /// Reads, checks and resolves `path` (relative paths become absolute).
    pub fn load(path: &Path) -> Result<Self, TrainError> {
        let text = std::fs::read_to_string(path).map_err(|e| TrainError::Config {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let base = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let base = std::path::absolute(base).map_err(|e| TrainError::Config {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        Self::parse(&text, &base).map_err(|reason| TrainError::Config {
            path: path.to_path_buf(),
            reason,
        })
    }

    /// Parses TOML text, resolving relative paths against `base`.
    pub fn parse(text: &str, base: &Path) -> Result<Self, String> {
        let mut c: TrainConfig = toml::from_str(text).map_err(|e| e.to_string())?;
        let abs = |p: &Path| {
            if p.is_absolute() {
                p.to_path_buf()
            } else {
                lexical_join(base, p)
            }
        };
        c.run.dir = abs(&c.run.dir);
        c.data.paths = c.data.paths.iter().map(|p| abs(p)).collect();
        if let Some(m) = &mut c.data.music {
            m.dir = abs(&m.dir);
        }
        if let Some(m) = &mut c.data.manifest {
            *m = abs(m);
        }
        if let Some(l) = &mut c.data.leader {
            *l = abs(l);
        }
        if let Some(h) = &mut c.data.holistic {
            *h = abs(h);
        }
        // Paths inside `[model]` (e.g. the VQ-VAE run a GPT trains on) are relative to this
        // file too; resolved here so the run's own config copy (used by `--resume`) has them.
        for key in MODEL_PATH_KEYS {
            if let Some(toml::Value::String(p)) = c.model.get(*key) {
                let resolved = abs(Path::new(p)).to_string_lossy().into_owned();
                c.model
                    .insert((*key).to_string(), toml::Value::String(resolved));
            }
        }
        c.validate()?;
        Ok(c)
    }

    /// The model kind (`[model] kind`).
    pub fn model_kind(&self) -> Result<&str, String> {
        match self.model.get("kind") {
            Some(toml::Value::String(s)) => Ok(s),
            Some(other) => Err(format!(
                "[model] kind must be a string, not {}",
                other.type_str()
            )),
            None => Err("[model] needs `kind`".into()),
        }
    }

    /// The `[model]` table without `kind`: the model's own configuration.
    pub fn model_params(&self) -> toml::Table {
        let mut t = self.model.clone();
        t.remove("kind");
        t
    }

    fn validate(&self) -> Result<(), String> {
        self.model_kind()?;
        let r = &self.run;
        if r.steps == 0 {
            return Err("[run] steps must be at least 1".into());
        }
        if r.checkpoint_every == 0 || r.log_every == 0 {
            return Err("[run] checkpoint_every and log_every must be at least 1".into());
        }
        let d = &self.data;
        if d.paths.is_empty() {
            return Err("[data] paths is empty: list motion files or directories".into());
        }
        for p in &d.paths {
            if !p.exists() {
                return Err(format!("[data] paths: {}: no such file", p.display()));
            }
        }
        if d.window < 2 || d.stride == 0 || d.batch_size == 0 {
            return Err(
                "[data] window must be at least 2, stride and batch_size at least 1".into(),
            );
        }
        if !(d.fps.is_finite() && d.fps > 0.0) {
            return Err(format!("[data] fps {} is not a frame rate", d.fps));
        }
        if !(d.std_floor.is_finite() && d.std_floor >= 0.0) {
            return Err(format!(
                "[data] std_floor {} must be a standard deviation (0 or more)",
                d.std_floor
            ));
        }
        if d.std_floor > 0.0 && d.representation != Representation::Group {
            return Err("[data] std_floor is only read by representation = \"group\"".into());
        }
        match (&d.leader, d.representation) {
            (None, Representation::Duet) => {
                return Err(
                    "[data] representation = \"duet\" needs [data] leader = \"<dir>\"".into(),
                );
            }
            (Some(_), r) if r != Representation::Duet => {
                return Err(format!(
                    "[data] leader is only read by representation = \"duet\", not {r:?}"
                ));
            }
            (Some(l), _) if !l.is_dir() => {
                return Err(format!("[data] leader: {}: no such directory", l.display()));
            }
            _ => {}
        }
        if let Some(m) = &d.music {
            if !m.dir.is_dir() {
                return Err(format!(
                    "[data.music] dir: {}: no such directory",
                    m.dir.display()
                ));
            }
            if m.dims == 0 {
                return Err("[data.music] dims must be at least 1".into());
            }
        }
        let o = &self.optimizer;
        if !(o.lr.is_finite() && o.lr > 0.0) {
            return Err(format!("[optimizer] lr {} must be positive", o.lr));
        }
        if !(o.weight_decay.is_finite() && o.weight_decay >= 0.0) {
            return Err("[optimizer] weight_decay must be ≥ 0".into());
        }
        if let Some(b) = &o.betas {
            let want = if o.kind == OptimizerKind::Adamw { 2 } else { 3 };
            if b.len() != want || b.iter().any(|v| !(0.0..1.0).contains(v)) {
                return Err(format!(
                    "[optimizer] betas: {:?} optimizer needs {want} values in [0, 1)",
                    o.kind
                ));
            }
        }
        if let Some(c) = o.grad_clip_norm
            && !(c.is_finite() && c > 0.0)
        {
            return Err("[optimizer] grad_clip_norm must be positive".into());
        }
        let s = &self.schedule;
        if !(s.min_lr.is_finite() && s.min_lr >= 0.0 && s.min_lr <= o.lr) {
            return Err("[schedule] min_lr must be in [0, lr]".into());
        }
        if let Some(e) = &self.ema
            && (!(0.0..1.0).contains(&e.decay) || e.every == 0)
        {
            return Err("[ema] decay must be in [0, 1) and every at least 1".into());
        }
        Ok(())
    }

    /// The resolved configuration as TOML (what `RUN_DIR/config.toml` holds).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a parsed config serialises")
    }
}
