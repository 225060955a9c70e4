//! The holistic (SoulNet) system's generation on burn-flex, timed the same way as
//! `bench/holistic_sampler.py` times the PyTorch re-implementation (run both with
//! `bash bench/holistic.sh`, which prints the ratio).
//!
//! Model: the shipped small configuration with random weights: `model.toml` of
//! `HOLISTIC_MODEL` (default `models/soulnet-small`) when it exists, otherwise the training
//! configs `configs/soulnet_small_{vq,mmr,generator}.toml` with
//! [`SamplingDefaults::for_window`] (as `dancegen bundle --holistic` writes them). The Python
//! side reads the same files. Random codebooks; normaliser mean 0, std 1 (the inverse still
//! runs). Both sides print every network's parameter count to stderr; they must agree.
//!
//! Work: [`dancegen_soulnet::pipeline::generate`] on 1800 frames (60 s at 30 fps) of random
//! music features (envelope, 20 MFCC, 12 chroma, peak and beat one-hots in their usual ranges):
//! 450 tokens per part in windows of `window_tokens` overlapping by `overlap_tokens`
//! ([`window_starts`]); per window the MMR music encoder once, the masked transformer's
//! `steps` iterations with one forward each of a batch of 2 (the conditional and the
//! unconditional row of classifier-free guidance), the residual transformer's `levels − 1`
//! levels with one batch-2 forward each; then the part autoencoder's conv decoder over all 450
//! tokens and the normaliser's inverse.
//! The forward counts and batch sizes are computed from [`window_starts`] and the sampling
//! settings the way `MaskedTransformer::sample_with` and `ResidualTransformer::sample` run them
//! (as of commit 8f8f102; the masked loop never ends early: every step re-masks at least one
//! free token) and printed in the JSON line; the Python side counts its calls and records
//! their shapes, and `bench/holistic.sh` checks that they agree. Update [`counts`] if the
//! samplers change how they call the networks.
//!
//! Case: `holistic_1800f`. A warm-up run with 2 steps, then `DANCEGEN_BENCH_REPS` (default 3)
//! timed runs; one JSON line with the median and min in ms. An optional first argument keeps
//! only the cases whose name contains it.

use std::path::PathBuf;
use std::time::Instant;

/// The `dancegen` binary's allocator (`crates/dancegen-cli/src/main.rs`).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use dancegen_nn::burn::module::{Module, RunningState};
use dancegen_nn::burn::tensor::{Device, Distribution, Tensor};
use dancegen_nn::device;
use dancegen_nn::part_autoencoder::PartQuantizer;
use dancegen_nn::progress::NoHook;
use dancegen_nn::quant::vq::EmaVq;
use dancegen_nn::rng::SplitMix64;
use dancegen_soulnet::bundle::{BundleConfig, HolisticModel, KIND, MeanStd};
use dancegen_soulnet::config::{GeneratorTable, MmrTable, SamplingDefaults, VqTable};
use dancegen_soulnet::layout::{MUSIC_DIMS, TOTAL_DIMS};
use dancegen_soulnet::pipeline::{GenerateOptions, generate, window_starts};

const FRAMES: usize = 1800;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `[model]` (or `[model.<sub>]`) of a training config, without its `kind`.
fn config_table<T: serde::de::DeserializeOwned>(file: &str, sub: Option<&str>) -> T {
    let path = repo().join("configs").join(file);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    let doc: toml::Table =
        toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut model = doc
        .get("model")
        .and_then(|m| m.as_table())
        .cloned()
        .unwrap_or_else(|| panic!("{}: no [model]", path.display()));
    model.remove("kind");
    let table = match sub {
        Some(s) => model
            .get(s)
            .cloned()
            .unwrap_or_else(|| panic!("{}: no [model.{s}]", path.display())),
        None => toml::Value::Table(model),
    };
    table
        .try_into()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The shipped model's `model.toml` when it exists, otherwise what the training configs
/// would bundle.
fn bundle_config() -> (BundleConfig, String) {
    let dir = std::env::var_os("HOLISTIC_MODEL")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("models/soulnet-small"));
    let toml_path = dir.join("model.toml");
    let (config, source) = if toml_path.is_file() {
        let text = std::fs::read_to_string(&toml_path).expect("model.toml");
        let c: BundleConfig =
            toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", toml_path.display()));
        (c, toml_path.display().to_string())
    } else {
        let vq: VqTable = config_table("soulnet_small_vq.toml", None);
        let mmr: MmrTable = config_table("soulnet_small_mmr.toml", None);
        let generator: GeneratorTable =
            config_table("soulnet_small_generator.toml", Some("generator"));
        let c = BundleConfig {
            kind: KIND.into(),
            name: "holistic-bench".into(),
            fps: 30.0,
            vq,
            mmr,
            sampling: SamplingDefaults::for_window(generator.window_tokens),
            generator,
        };
        (c, "configs/soulnet_small_{vq,mmr,generator}.toml".into())
    };
    config
        .validate()
        .unwrap_or_else(|e| panic!("{source}: {e}"));
    (config, source)
}

fn env_usize(key: &str, default: usize) -> usize {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Random codebooks (a fresh EMA codebook is all zeros until training initialises it).
fn randomise_codebooks(q: &mut PartQuantizer, dev: &Device) {
    let fill = |vq: &mut EmaVq| {
        let dims = vq.codebook.value_sync().dims();
        vq.codebook = RunningState::new(Tensor::random(dims, Distribution::Normal(0.0, 1.0), dev));
    };
    match q {
        PartQuantizer::Hrvq(h) => h
            .layers_body
            .iter_mut()
            .chain(&mut h.layers_hands)
            .chain(&mut h.layers_face)
            .for_each(fill),
        PartQuantizer::Rvq(stacks) => stacks
            .iter_mut()
            .flat_map(|s| s.layers.iter_mut())
            .for_each(fill),
        PartQuantizer::Vq(v) => v.iter_mut().for_each(fill),
    }
}

/// 35 EDGE features a frame in their usual ranges: envelope [0, 1), MFCC (the first around
/// −200, the others ±20), chroma [0, 1), peak and beat one-hots (about one frame in 8 / 15).
fn music(rng: &mut SplitMix64) -> Vec<f32> {
    let mut m = Vec::with_capacity(FRAMES * MUSIC_DIMS);
    for _ in 0..FRAMES {
        m.push(rng.next_f64() as f32);
        m.push((-200.0 + 100.0 * (rng.next_f64() - 0.5)) as f32);
        m.extend((0..19).map(|_| (40.0 * (rng.next_f64() - 0.5)) as f32));
        m.extend((0..12).map(|_| rng.next_f64() as f32));
        m.push(f32::from(u8::from(rng.next_f64() < 1.0 / 8.0)));
        m.push(f32::from(u8::from(rng.next_f64() < 1.0 / 15.0)));
    }
    m
}

/// Network evaluations of one [`generate`] call, counted the way the pipeline runs them: calls
/// and the batch each runs at.
struct Counts {
    windows: usize,
    masked: usize,
    masked_batch: usize,
    residual: usize,
    residual_batch: usize,
    mmr: usize,
}

fn counts(config: &BundleConfig, sampling: &SamplingDefaults) -> Counts {
    let fpt = config.vq.frames_per_token();
    let n = FRAMES.div_ceil(fpt);
    let w = config.generator.window_tokens.min(n);
    let starts = window_starts(n, w, sampling.overlap_tokens);
    // Guidance runs the conditional and the unconditional row as one batch of 2
    // (`MaskedTransformer::sample_with`, `ResidualTransformer::sample`).
    let batch = |scale: f64| if scale == 1.0 { 1 } else { 2 };
    let mut made = 0usize;
    let mut masked = 0;
    for &s in &starts {
        // Free (to be drawn) positions of the window, all three parts.
        let free = 3 * (w - made.saturating_sub(s).min(w));
        if free > 0 {
            masked += sampling.steps.max(1);
        }
        made = s + w;
    }
    let residual_levels = config.vq.levels() - 1;
    Counts {
        windows: starts.len(),
        masked,
        masked_batch: batch(sampling.cond_scale),
        residual: starts.len() * residual_levels,
        residual_batch: batch(sampling.residual_cond_scale),
        mmr: starts.len(),
    }
}

fn main() {
    let reps = env_usize("DANCEGEN_BENCH_REPS", 3);
    let only = std::env::args().nth(1).filter(|a| !a.starts_with('-'));
    let want = |c: &str| only.as_deref().is_none_or(|o| c.contains(o));
    let dev = device::inference();
    dev.seed(0);
    let (config, source) = bundle_config();
    let mut vq = config.vq.autoencoder().init(&dev);
    randomise_codebooks(&mut vq.quantizer, &dev);
    let mmr = config.mmr.retrieval().init(&dev);
    let generator = config.init_generator(&dev);
    eprintln!(
        "burn-flex holistic parameters ({source}): masked {}, residual {}, mmr music {}, conv decoder {}",
        generator.masked.num_params(),
        generator.residual.as_ref().map_or(0, |r| r.num_params()),
        mmr.music.num_params(),
        vq.decoder.num_params(),
    );
    let sampling = config.sampling.clone();
    let c = counts(&config, &sampling);
    let fpt = config.vq.frames_per_token();
    let (n, w, q) = (
        FRAMES.div_ceil(fpt),
        config.generator.window_tokens,
        config.vq.levels(),
    );
    eprintln!(
        "burn-flex holistic work: {} windows; forwards: masked {} ([{}, {}] tokens + 1 condition), residual {} ([{}, {}, {q}]), mmr music {} ([1, {}, {MUSIC_DIMS}]), conv decoder 1 ([1, {n}, {}] -> [1, {FRAMES}, {TOTAL_DIMS}])",
        c.windows,
        c.masked,
        c.masked_batch,
        3 * w,
        c.residual,
        c.residual_batch,
        3 * w,
        c.mmr,
        w * fpt,
        3 * config.vq.code_dim,
    );
    let model = HolisticModel {
        dir: PathBuf::new(),
        config,
        vq,
        mmr,
        generator,
        norm: MeanStd {
            kind: "mean_std".into(),
            mean: vec![0.0; TOTAL_DIMS],
            std: vec![1.0; TOTAL_DIMS],
        },
    };
    let music = music(&mut SplitMix64(7));
    let run = |steps: usize| {
        let mut opts = GenerateOptions::defaults(&model, 0);
        opts.sampling.steps = steps;
        let out = generate(&model, &music, &opts, &dev, &NoHook).expect("NoHook never cancels");
        assert_eq!(out.frames, FRAMES);
        assert_eq!(out.windows, c.windows);
        assert!(out.rows.iter().all(|v| v.is_finite()));
    };
    let name = "holistic_1800f";
    if !want(name) {
        return;
    }
    run(2);
    let mut ms: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            run(sampling.steps);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    println!(
        "{{\"impl\": \"burn-flex\", \"case\": \"{name}\", \"steps\": {}, \"windows\": {}, \"masked_forwards\": {}, \"masked_batch\": {}, \"residual_forwards\": {}, \"residual_batch\": {}, \"mmr_forwards\": {}, \"median_ms\": {:.2}, \"min_ms\": {:.2}, \"reps\": {reps}}}",
        sampling.steps,
        c.windows,
        c.masked,
        c.masked_batch,
        c.residual,
        c.residual_batch,
        c.mmr,
        ms[ms.len() / 2],
        ms[0]
    );
}
