//! Diagnostic (issue 43): how much of its noise does the group denoiser let through, and how
//! much does its prediction move? For training windows of a group data set (with their own
//! music and dancer counts, in the network's coordinates exactly as `GroupTask::loss` builds
//! them), at several noise levels `t`, two noises give `x_t¹` and `x_t²` from the same clean
//! window and the network predicts `x̂0¹` and `x̂0²` (no formation control, music kept).
//! Printed per level, over the active dancers' channels in normalised units:
//! - **noise reach**: RMS(`x̂0¹ − x̂0²`). A model that uses its noise gives different dances
//!   for different noises at high `t`; near 0 there means every seed gets the same dance;
//! - **error**: RMS(`x̂0 − x0`);
//! - **motion**: mean over channels of the prediction's standard deviation over the window's
//!   frames, against the clean window's (`truth`). A prediction that barely moves while the
//!   truth moves has collapsed towards a mean pose;
//! - the same three for the 6D joint rotations alone (the pose, without the roots).
//!
//!     cargo run --release -p dancegen-train --example group_noise_probe -- MODEL_DIR CONFIG.toml [BATCHES]
//!
//! `CONFIG.toml` is a group training config (`configs/tcdiffpp_small.toml`); its `[data]` is
//! read; windows are normalised by the model's own statistics, as in training.

use std::path::PathBuf;

use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::device;
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_nn::edge151::{DIMS, ROT6D_START};
use dancegen_tcdiffpp::bundle::GroupModel;
use dancegen_tcdiffpp::denoiser::GroupCond;
use dancegen_tcdiffpp::layout::{GROUP_DIMS, N_MAX};
use dancegen_tcdiffpp::losses::control_tensors;
use dancegen_tcdiffpp::window::training_window;
use dancegen_train::data::DataPosition;
use dancegen_train::{Normalizer, TrainConfig, WindowDataset};

/// Noise levels of EDGE's 1000-step schedule probed, high to low.
const LEVELS: [usize; 7] = [999, 900, 750, 500, 250, 100, 10];

fn host(x: Tensor<3>) -> Vec<f32> {
    x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
}

/// Accumulated sums of one level: noise reach, error, prediction motion, truth motion, each
/// over all active channels and over the rotation channels alone.
#[derive(Default, Clone)]
struct Sums {
    reach: [f64; 2],
    error: [f64; 2],
    motion: [f64; 2],
    truth: [f64; 2],
    count: [f64; 2],
    channels: [f64; 2],
}

fn main() {
    if let Err(e) = probe() {
        eprintln!("group_noise_probe: {e}");
        std::process::exit(1);
    }
}

fn probe() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    // `--untrained`: the same architecture, freshly initialised (with the model's statistics),
    // as the baseline of how much of its input an untrained network passes through.
    let untrained = args.iter().any(|a| a == "--untrained");
    let args: Vec<&String> = args.iter().filter(|a| *a != "--untrained").collect();
    let (model_dir, config, batches) = match &args[..] {
        [_, m, c] => (m, c, 4usize),
        [_, m, c, n] => (
            m,
            c,
            n.parse()
                .map_err(|_| format!("BATCHES: not a number: {n}"))?,
        ),
        _ => {
            return Err(
                "usage: group_noise_probe MODEL_DIR CONFIG.toml [BATCHES] [--untrained]".into(),
            );
        }
    };
    let dev = device::inference();
    let model_dir = PathBuf::from(model_dir);
    let mut model = GroupModel::load(&model_dir, &dev).map_err(|e| e.to_string())?;
    if untrained {
        let (scale, shift) = model.net.denorm.host();
        let mean: Vec<f64> = shift.iter().map(|&v| v as f64).collect();
        let std: Vec<f64> = scale.iter().map(|&v| v as f64).collect();
        model.net = model.config.model.denoiser.init(&mean, &std, &dev);
    }
    let config = TrainConfig::load(&PathBuf::from(config)).map_err(|e| e.to_string())?;
    let clips = WindowDataset::read_clips(&config.data).map_err(|e| e.to_string())?;
    // As the trainer does for group runs: raw windows, normalised per window by the task.
    let raw_windows = Normalizer::None { dims: GROUP_DIMS };
    let data =
        WindowDataset::new(clips, &config.data, &raw_windows, 5).map_err(|e| e.to_string())?;
    let net = &model.net;
    let (scale, shift) = net.denorm.host();
    eprintln!(
        "the model's statistics: scale {:?}…, shift {:?}…",
        &scale[..6],
        &shift[..6]
    );
    let mut sums = vec![Sums::default(); LEVELS.len()];
    for cursor in 0..batches {
        let (batch, _) = data.batch(DataPosition { epoch: 7, cursor }, &dev);
        let [b, t, dims] = batch.motion.dims();
        if dims != GROUP_DIMS {
            return Err(format!("{dims} channels: not group windows"));
        }
        let dancers = batch
            .dancers
            .clone()
            .ok_or("the data has no dancer counts")?;
        let raw = host(batch.motion.clone());
        let (mut x0, mut swap) = (Vec::new(), Vec::new());
        for (i, &n) in dancers.iter().enumerate() {
            let (x, s) = training_window(
                &raw[i * t * GROUP_DIMS..(i + 1) * t * GROUP_DIMS],
                t,
                n,
                &scale,
                &shift,
            );
            x0.extend(x);
            swap.extend(s);
        }
        let sw = swap.len() / b;
        let x0_t = Tensor::<3>::from_data(TensorData::new(x0.clone(), [b, t, GROUP_DIMS]), &dev);
        let flags = vec![0f32; b * t * N_MAX];
        let (control, _) = control_tensors(&flags, b, t, &dev);
        let cond = GroupCond {
            music: batch.music.clone().ok_or("the data has no music")?,
            dancers: dancers.clone(),
            swap: Tensor::from_data(TensorData::new(swap, [b, sw]), &dev),
            control,
        };
        let keep = vec![true; b];
        let mut rng = SeededNoise::new(11 + cursor as u64);
        for (li, &level) in LEVELS.iter().enumerate() {
            let steps = vec![level; b];
            let tf = vec![level as f32; b];
            let mut preds = Vec::new();
            for _ in 0..2 {
                let noise = rng.tensor([b, t, GROUP_DIMS], &dev);
                let x_t = model.schedule.q_sample(x0_t.clone(), &steps, noise);
                preds.push(host(net.forward(x_t, &tf, &cond, &keep)));
            }
            let s = &mut sums[li];
            for (i, &n) in dancers.iter().enumerate() {
                for slot in 0..n {
                    for ch in 0..DIMS {
                        let kind = usize::from(ch >= ROT6D_START);
                        let at = |v: &[f32], f: usize| {
                            v[(i * t + f) * GROUP_DIMS + slot * DIMS + ch] as f64
                        };
                        let (mut m_p, mut m_g) = (0.0, 0.0);
                        for f in 0..t {
                            m_p += at(&preds[0], f);
                            m_g += at(&x0, f);
                        }
                        m_p /= t as f64;
                        m_g /= t as f64;
                        let (mut v_p, mut v_g) = (0.0, 0.0);
                        for f in 0..t {
                            let (p1, p2, g) = (at(&preds[0], f), at(&preds[1], f), at(&x0, f));
                            for k in [0usize, 1] {
                                if k == 1 && kind == 0 {
                                    continue;
                                }
                                s.reach[k] += (p1 - p2).powi(2);
                                s.error[k] += (p1 - g).powi(2);
                                s.count[k] += 1.0;
                            }
                            v_p += (p1 - m_p).powi(2);
                            v_g += (g - m_g).powi(2);
                        }
                        for k in [0usize, 1] {
                            if k == 1 && kind == 0 {
                                continue;
                            }
                            s.motion[k] += (v_p / t as f64).sqrt();
                            s.truth[k] += (v_g / t as f64).sqrt();
                            s.channels[k] += 1.0;
                        }
                    }
                }
            }
        }
    }
    println!(
        "| t | noise reach | error | motion (truth) | rotations: noise reach | error | motion (truth) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (li, s) in sums.iter().enumerate() {
        let rms = |a: f64, n: f64| (a / n).sqrt();
        println!(
            "| {} | {:.3} | {:.3} | {:.3} ({:.3}) | {:.3} | {:.3} | {:.3} ({:.3}) |",
            LEVELS[li],
            rms(s.reach[0], s.count[0]),
            rms(s.error[0], s.count[0]),
            s.motion[0] / s.channels[0],
            s.truth[0] / s.channels[0],
            rms(s.reach[1], s.count[1]),
            rms(s.error[1], s.count[1]),
            s.motion[1] / s.channels[1],
            s.truth[1] / s.channels[1],
        );
    }
    Ok(())
}
