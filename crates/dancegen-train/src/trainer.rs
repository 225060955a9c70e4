//! The training loop, checkpoints and exact resume.
//!
//! Exactness: everything a step depends on is either saved or a pure function of the step
//! number. The checkpoint holds the weights, the EMA weights, the optimizer state (Burn's
//! record, with every parameter's [`ParamId`](dancegen_nn::burn::module::ParamId) under its path
//! so a rebuilt model matches it), the data position and the step; the learning rate is
//! [`lr_at`] of the step; and the backend's random generator is reseeded from `(seed, step)`
//! before every step, so dropout or a quantizer's code reset draws the same numbers whether or
//! not the run was interrupted.
//!
//! Burn-flex's generator is process-global, so a run holds [`RNG_LOCK`] throughout: two runs in
//! one process (tests) take turns instead of interleaving their draws.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use dancegen_nn::burn;
use dancegen_nn::weights::{self, Layout};

use burn::module::Module;
use burn::optim::{GradientsParams, ModuleOptimizer};
use burn::tensor::Device;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::config::TrainConfig;
use crate::data::{DataPosition, Normalizer, WindowDataset, derive_seed};
use crate::log::{LogRow, TrainLog};
use crate::optim::{build_optimizer, clip_global_norm, global_norm, lr_at};
use crate::params::{Ema, param_ids, set_param_ids, sync_running_states};
use crate::task::TrainTask;
use crate::{TrainError, files};

/// Serialises runs within a process (see the module documentation).
pub static RNG_LOCK: Mutex<()> = Mutex::new(());

/// Stream ids of [`derive_seed`].
const INIT_STREAM: u64 = 2;
const STEP_STREAM: u64 = 3;

/// Version of the checkpoint layout in `state.json`.
pub const CHECKPOINT_FORMAT: u32 = 1;

/// How a session runs (not part of the config: it does not change the result).
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// No progress bar and no log lines.
    pub quiet: bool,
    /// Stop after this step (checkpointing there), as if interrupted; `--resume` continues.
    pub stop_at: Option<u64>,
}

/// What a session did.
#[derive(Clone, Debug)]
pub struct RunSummary {
    pub run_dir: PathBuf,
    /// Step reached (total steps done, including earlier sessions).
    pub step: u64,
    pub start_step: u64,
    pub last_loss: f64,
    /// Steps per second over this session.
    pub steps_per_s: f64,
    /// Whether the run reached `[run] steps` (and wrote the final model).
    pub finished: bool,
}

/// `checkpoints/step_N/state.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointState {
    pub format: u32,
    pub kind: String,
    pub step: u64,
    pub data: DataPosition,
    pub seed: u64,
    pub ema: bool,
    /// `path → ParamId` of the trained model (the optimizer record is keyed by id).
    pub param_ids: std::collections::BTreeMap<String, u64>,
}

/// Starts a new run in `config.run.dir` (which must not hold one already).
pub fn train<T: TrainTask>(
    task: &T,
    config: &TrainConfig,
    opts: &RunOptions,
) -> Result<RunSummary, TrainError> {
    let dir = &config.run.dir;
    if dir.join(files::CONFIG).exists() {
        return Err(TrainError::Run {
            path: dir.clone(),
            reason: "already holds a run; continue it with --resume or choose another [run] dir"
                .into(),
        });
    }
    run(task, config, None, opts)
}

/// Continues the run in `run_dir` from its latest checkpoint.
pub fn resume<T: TrainTask>(
    task: &T,
    run_dir: &Path,
    opts: &RunOptions,
) -> Result<RunSummary, TrainError> {
    let config = run_config(run_dir)?;
    let ckpt = latest_checkpoint(run_dir)?;
    run(task, &config, Some(ckpt), opts)
}

/// Reads a run's configuration (`RUN_DIR/config.toml`).
pub fn run_config(run_dir: &Path) -> Result<TrainConfig, TrainError> {
    let p = run_dir.join(files::CONFIG);
    if !p.is_file() {
        return Err(TrainError::Run {
            path: run_dir.to_path_buf(),
            reason: format!("not a run directory (no {})", files::CONFIG),
        });
    }
    TrainConfig::load(&p)
}

/// The checkpoint directory with the highest step.
pub fn latest_checkpoint(run_dir: &Path) -> Result<PathBuf, TrainError> {
    let dir = run_dir.join(files::CHECKPOINTS);
    let mut best: Option<(u64, PathBuf)> = None;
    for e in std::fs::read_dir(&dir).map_err(|e| TrainError::io(&dir, e))? {
        let p = e.map_err(|e| TrainError::io(&dir, e))?.path();
        if let Some(n) = checkpoint_step(&p)
            && best.as_ref().is_none_or(|(b, _)| n > *b)
        {
            best = Some((n, p));
        }
    }
    best.map(|(_, p)| p).ok_or_else(|| TrainError::Run {
        path: dir,
        reason: "no checkpoint to resume from".into(),
    })
}

fn checkpoint_step(p: &Path) -> Option<u64> {
    p.file_name()?.to_str()?.strip_prefix("step_")?.parse().ok()
}

fn checkpoint_err(path: &Path, reason: impl std::fmt::Display) -> TrainError {
    TrainError::Checkpoint {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// Builds the model the checkpoint's weights go into, with its saved parameter ids.
fn load_model<T: TrainTask>(
    task: &T,
    device: &Device,
    weights_path: &Path,
    ids: &std::collections::BTreeMap<String, u64>,
) -> Result<T::Model, TrainError> {
    let model = weights::load(task.init(device), weights_path, Layout::Burn)?;
    set_param_ids(model, ids).map_err(|e| checkpoint_err(weights_path, e))
}

/// Everything a checkpoint restores.
pub struct Checkpoint<M> {
    pub model: M,
    pub ema: Option<M>,
    pub optim: ModuleOptimizer,
    pub state: CheckpointState,
}

/// Reads the checkpoint directory `c` (`checkpoints/step_N`) of a run of `config`, building the
/// models on `device`. Every problem names the file.
pub fn load_checkpoint<T: TrainTask>(
    task: &T,
    config: &TrainConfig,
    c: &Path,
    device: &Device,
) -> Result<Checkpoint<T::Model>, TrainError> {
    let sp = c.join(files::STATE);
    let bytes = std::fs::read(&sp).map_err(|e| checkpoint_err(&sp, e))?;
    let state: CheckpointState =
        serde_json::from_slice(&bytes).map_err(|e| checkpoint_err(&sp, e))?;
    let seed = config.run.seed;
    if state.format != CHECKPOINT_FORMAT || state.kind != task.kind() || state.seed != seed {
        return Err(checkpoint_err(
            &sp,
            format!(
                "format {} / kind {:?} / seed {} does not match this run \
                 (format {CHECKPOINT_FORMAT}, kind {:?}, seed {seed})",
                state.format,
                state.kind,
                state.seed,
                task.kind()
            ),
        ));
    }
    if state.ema != config.ema.is_some() {
        return Err(checkpoint_err(
            &sp,
            "[ema] in the config and the checkpoint disagree",
        ));
    }
    let model = load_model(task, device, &c.join(files::WEIGHTS), &state.param_ids)?;
    let op = c.join(files::OPTIMIZER);
    if !op.is_file() {
        return Err(checkpoint_err(&op, "no such file"));
    }
    let optim = build_optimizer(&config.optimizer)
        .load(&op)
        .map_err(|e| checkpoint_err(&op, e))?;
    let ema = if state.ema {
        let m = load_model(task, device, &c.join(files::EMA), &state.param_ids)?;
        Some(m.set_require_grad(false))
    } else {
        None
    };
    Ok(Checkpoint {
        model,
        ema,
        optim,
        state,
    })
}

fn run<T: TrainTask>(
    task: &T,
    config: &TrainConfig,
    ckpt: Option<PathBuf>,
    opts: &RunOptions,
) -> Result<RunSummary, TrainError> {
    let _guard = RNG_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let dir = config.run.dir.clone();
    let kind = config.model_kind().map_err(|reason| TrainError::Config {
        path: dir.join(files::CONFIG),
        reason,
    })?;
    if kind != task.kind() {
        return Err(TrainError::Config {
            path: dir.join(files::CONFIG),
            reason: format!(
                "[model] kind {kind:?} but the task trains {:?}",
                task.kind()
            ),
        });
    }
    let seed = config.run.seed;
    let total = config.run.steps;

    // Data and normaliser (fitted once, then always read back).
    let clips = WindowDataset::read_clips(&config.data)?;
    let norm_path = dir.join(files::NORMALIZER);
    std::fs::create_dir_all(dir.join(files::CHECKPOINTS)).map_err(|e| TrainError::io(&dir, e))?;
    let group = config.data.representation == crate::config::Representation::Group;
    let normalizer = if ckpt.is_some() {
        Normalizer::load(&norm_path)?
    } else {
        let dims = crate::data::representation_dims(config.data.representation);
        let fitted = if group {
            // One dancer's 151 channels; the task normalises each window after re-basing it.
            crate::data::fit_group_normalizer(&clips, config.data.std_floor)
        } else {
            Normalizer::fit(config.data.normalizer, &clips, dims)
        };
        let n = fitted.map_err(|reason| TrainError::Data {
            path: config.data.paths[0].clone(),
            reason,
        })?;
        n.save(&norm_path)?;
        n
    };
    let window_norm = if group {
        Normalizer::None {
            dims: crate::data::representation_dims(config.data.representation),
        }
    } else {
        normalizer.clone()
    };
    let data = WindowDataset::new(clips, &config.data, &window_norm, seed)?;
    if ckpt.is_none() {
        task.check_data(&normalizer)
            .map_err(|reason| TrainError::Config {
                path: dir.join(files::CONFIG),
                reason,
            })?;
        // The run directory exists (and claims the run) only once the data is known to load.
        let cfg_path = dir.join(files::CONFIG);
        let toml = config.to_toml();
        dancegen_io::write_atomic(&cfg_path, |w| w.write_all(toml.as_bytes()))
            .map_err(|e| TrainError::io(&cfg_path, e))?;
    }

    // Model, optimizer, EMA, position.
    let device = dancegen_nn::device::training();
    device.seed(derive_seed(seed, INIT_STREAM, 0));
    let mut optim: ModuleOptimizer = build_optimizer(&config.optimizer);
    let (mut model, mut ema, mut step, mut pos, mut log) = match &ckpt {
        None => {
            let model = task.init_with_data(&device, &normalizer);
            let ema = config
                .ema
                .as_ref()
                .map(|e| Ema::new(task.init_with_data(&device, &normalizer), &model, e.decay));
            (model, ema, 0, DataPosition::default(), TrainLog::default())
        }
        Some(c) => {
            let ck = load_checkpoint(task, config, c, &device)?;
            optim = ck.optim;
            let ema = ck.ema.zip(config.ema.as_ref()).map(|(m, e)| Ema {
                model: m,
                decay: e.decay,
            });
            let log_path = dir.join(files::LOG);
            let log = if log_path.is_file() {
                TrainLog::load(&log_path, ck.state.step)?
            } else {
                TrainLog::default()
            };
            (ck.model, ema, ck.state.step, ck.state.data, log)
        }
    };
    let start = step;
    let end = opts.stop_at.map_or(total, |s| s.clamp(start, total));

    let pb = progress(total, start, opts.quiet);
    let t0 = Instant::now();
    let mut window = (Instant::now(), step);
    let mut last_loss = f64::NAN;
    // Steps per second over the last log window, shown on the bar.
    let mut sps_shown = 0.0;
    // Sum of the losses since the last log row (the row holds their mean).
    let mut loss_sum = 0.0;
    while step < end {
        device.seed(derive_seed(seed, STEP_STREAM, step));
        let (batch, next) = data.batch(pos, &device);
        pos = next;
        let losses = task.loss(&model, &batch);
        let grads = losses.total.backward();
        let mut gp = GradientsParams::from_grads(grads, &model);
        let grad_norm = match config.optimizer.grad_clip_norm {
            Some(max) => clip_global_norm(&model, &mut gp, max),
            None => global_norm(&model, &gp),
        };
        let lr = lr_at(step, total, config.optimizer.lr, &config.schedule);
        model = optim.step(lr, model, gp);
        sync_running_states(&model);
        step += 1;
        if let (Some(e), Some(c)) = (&mut ema, &config.ema) {
            if step <= c.start {
                e.reset(&model);
            } else if step % c.every == 0 {
                e.update(&model);
            }
        }
        last_loss = losses.total.into_scalar::<f32>() as f64;
        loss_sum += last_loss;
        pb.set_position(step);
        pb.set_message(format!("loss {last_loss:.5} · {sps_shown:.2} steps/s"));
        if step % config.run.log_every == 0 || step == end {
            let secs = window.0.elapsed().as_secs_f64();
            let window_start = window.1;
            let sps = (step - window_start) as f64 / secs.max(1e-9);
            window = (Instant::now(), step);
            sps_shown = sps;
            let mean_loss = loss_sum / (step - window_start) as f64;
            loss_sum = 0.0;
            let parts: Vec<(String, f64)> = losses
                .parts
                .into_iter()
                .map(|(n, t)| (n.to_string(), t.into_scalar::<f32>() as f64))
                .collect();
            if !opts.quiet {
                let extra: String = parts.iter().map(|(n, v)| format!(" {n} {v:.5}")).collect();
                pb.suspend(|| {
                    eprintln!(
                        "step {step}/{total} loss {mean_loss:.6}{extra} lr {lr:.3e} \
                         grad_norm {grad_norm:.4} {sps:.2} steps/s"
                    )
                });
            }
            log.rows.push(LogRow {
                step,
                loss: mean_loss,
                lr,
                grad_norm,
                steps_per_s: sps,
                parts,
            });
        }
        if step % config.run.checkpoint_every == 0 || step == end {
            let state = CheckpointState {
                format: CHECKPOINT_FORMAT,
                kind: task.kind().to_string(),
                step,
                data: pos,
                seed,
                ema: ema.is_some(),
                param_ids: param_ids(&model),
            };
            save_checkpoint(&dir, &model, ema.as_ref().map(|e| &e.model), &optim, &state)?;
            prune_checkpoints(&dir, config.run.keep_checkpoints)?;
            log.save(&dir.join(files::LOG))?;
            log.plot(
                &dir.join(files::LOSS_PNG),
                &format!("{} — loss", task.kind()),
            )?;
        }
    }
    pb.finish_and_clear();
    let finished = step == total;
    if finished {
        save_final(
            task,
            config,
            ema.as_ref().map_or(&model, |e| &e.model),
            step,
        )?;
        log.save(&dir.join(files::LOG))?;
        log.plot(
            &dir.join(files::LOSS_PNG),
            &format!("{} — loss", task.kind()),
        )?;
    }
    let secs = t0.elapsed().as_secs_f64();
    Ok(RunSummary {
        run_dir: dir,
        step,
        start_step: start,
        last_loss,
        steps_per_s: (step - start) as f64 / secs.max(1e-9),
        finished,
    })
}

fn progress(total: u64, start: u64, quiet: bool) -> ProgressBar {
    let pb = ProgressBar::new(total);
    if quiet {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    pb.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed_precise} < {eta}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb.set_position(start);
    pb
}

/// Writes `RUN_DIR/checkpoints/step_N/` (N = `state.step`) through a temporary directory renamed into place: a checkpoint
/// directory either is complete or does not exist.
pub fn save_checkpoint<M: burn::module::Module + burn::store::ModuleSnapshot>(
    dir: &Path,
    model: &M,
    ema: Option<&M>,
    optim: &ModuleOptimizer,
    state: &CheckpointState,
) -> Result<(), TrainError> {
    let root = dir.join(files::CHECKPOINTS);
    let fin = root.join(format!("step_{}", state.step));
    let tmp = root.join(format!(".step_{}.partial", state.step));
    for p in [&tmp, &fin] {
        if p.exists() {
            std::fs::remove_dir_all(p).map_err(|e| TrainError::io(p, e))?;
        }
    }
    std::fs::create_dir_all(&tmp).map_err(|e| TrainError::io(&tmp, e))?;
    let step = state.step.to_string();
    let meta = [("kind", state.kind.as_str()), ("step", step.as_str())];
    weights::save(model, &tmp.join(files::WEIGHTS), Layout::Burn, &meta)?;
    if let Some(e) = ema {
        weights::save(e, &tmp.join(files::EMA), Layout::Burn, &meta)?;
    }
    let op = tmp.join(files::OPTIMIZER);
    optim.save(&op).map_err(|e| checkpoint_err(&op, e))?;
    let sp = tmp.join(files::STATE);
    let json = serde_json::to_vec_pretty(state).expect("state serialises");
    dancegen_io::write_atomic(&sp, |w| w.write_all(&json)).map_err(|e| TrainError::io(&sp, e))?;
    std::fs::rename(&tmp, &fin).map_err(|e| TrainError::io(&fin, e))
}

/// Keeps the `keep` newest checkpoints (0 = all).
fn prune_checkpoints(dir: &Path, keep: usize) -> Result<(), TrainError> {
    if keep == 0 {
        return Ok(());
    }
    let root = dir.join(files::CHECKPOINTS);
    let mut steps: Vec<(u64, PathBuf)> = std::fs::read_dir(&root)
        .map_err(|e| TrainError::io(&root, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| checkpoint_step(&p).map(|n| (n, p)))
        .collect();
    steps.sort();
    let n = steps.len().saturating_sub(keep);
    for (_, p) in steps.into_iter().take(n) {
        std::fs::remove_dir_all(&p).map_err(|e| TrainError::io(&p, e))?;
    }
    Ok(())
}

/// The project's model format: `model.safetensors` (the EMA weights when `[ema]` is on, as EDGE
/// samples with its EMA model) + `model.toml` (kind, data conventions, model config) +
/// `normalizer.json` (written at the start of the run).
fn save_final<T: TrainTask>(
    task: &T,
    config: &TrainConfig,
    model: &T::Model,
    step: u64,
) -> Result<(), TrainError> {
    let dir = &config.run.dir;
    let step_s = step.to_string();
    let meta = [("kind", task.kind()), ("step", step_s.as_str())];
    weights::save(model, &dir.join(files::WEIGHTS), Layout::Burn, &meta)?;
    let mut t = toml::Table::new();
    t.insert("kind".into(), task.kind().into());
    t.insert(
        "representation".into(),
        toml::Value::try_from(config.data.representation).expect("enum serialises"),
    );
    t.insert("fps".into(), toml::Value::Float(config.data.fps as f64));
    t.insert(
        "window".into(),
        toml::Value::Integer(config.data.window as i64),
    );
    t.insert("steps".into(), toml::Value::Integer(step as i64));
    t.insert("ema".into(), toml::Value::Boolean(config.ema.is_some()));
    t.insert("config".into(), toml::Value::Table(task.model_config()));
    let text = toml::to_string_pretty(&t).expect("table serialises");
    let p = dir.join(files::MODEL_TOML);
    dancegen_io::write_atomic(&p, |w| w.write_all(text.as_bytes()))
        .map_err(|e| TrainError::io(&p, e))
}
