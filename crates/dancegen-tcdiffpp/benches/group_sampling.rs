//! The group model's long sampling on burn-flex, timed the same way as
//! `bench/group_denoiser.py` times the PyTorch re-implementation (run both with
//! `bash bench/group.sh`, which prints the ratios).
//!
//! Model: the shipped small configuration, `configs/tcdiffpp_small.toml` `[model.denoiser]`
//! read at run time over [`DenoiserConfig::default`] (as the Python side does; today they are
//! equal: d 128, 4 FiLM decoder layers, 4 heads, FF 512, 2 music layers, cross-attention),
//! random weights, identity normaliser. Both sides print the parameter count to stderr.
//! Sampler: [`dancegen_tcdiffpp::sampler::generate`] with the default sampling
//! ([`SamplingConfig::default`]: DDIM 6 steps, eta 1, guidance 2, i.e. one forward of the
//! conditional and one of the null branch per step; clean LGDS prefix; `GROUP_BENCH_STEPS` and
//! `GROUP_BENCH_GUIDANCE` override steps and guidance, as bench/group.sh does with the shipped
//! model's), 5 dancers, 1800
//! frames (60 s at 30 fps) = 23 windows of 150 frames at stride 75, random music features.
//!
//! Cases: `lgds_5x1800f` (windows one after another) and `parallel_5x1800f` (all 23 windows
//! as one batch, [`LongSampler::Parallel`]). Each case: a warm-up run with 2 steps, then
//! `DANCEGEN_BENCH_REPS` (default 3) timed runs; one JSON line per case with the median and
//! min in ms. An optional first argument keeps only the cases whose name contains it.

use std::time::Instant;

/// The `dancegen` binary's allocator (`crates/dancegen-cli/src/main.rs`).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::device;
use dancegen_nn::diffusion::{Schedule, SeededNoise};
use dancegen_nn::edge151::DIMS;
use dancegen_nn::progress::NoHook;
use dancegen_tcdiffpp::config::{DenoiserConfig, LongSampler, SamplingConfig, WINDOW_FRAMES};
use dancegen_tcdiffpp::denoiser::{GroupDenoiser, MUSIC_DIMS};
use dancegen_tcdiffpp::layout::GROUP_DIMS;
use dancegen_tcdiffpp::sampler::{GroupRequest, GroupSampleOptions, generate, window_count};

const FRAMES: usize = 1800;
const DANCERS: usize = 5;

fn denoiser_config() -> DenoiserConfig {
    let path = format!(
        "{}/../../configs/tcdiffpp_small.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {path}: {e}"));
    let doc: toml::Table = toml::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let table = doc
        .get("model")
        .and_then(|m| m.get("denoiser"))
        .cloned()
        .unwrap_or_else(|| panic!("{path}: no [model.denoiser]"));
    table
        .try_into()
        .unwrap_or_else(|e| panic!("{path} [model.denoiser]: {e}"))
}

fn env_usize(key: &str, default: usize) -> usize {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

struct Bench {
    net: GroupDenoiser,
    schedule: Schedule,
    music: Vec<f32>,
    dev: Device,
}

impl Bench {
    fn run(&self, steps: usize, guidance: f64, sampler: LongSampler) {
        let defaults = SamplingConfig::default();
        let opts = GroupSampleOptions {
            steps,
            eta: defaults.eta,
            spacing: defaults.spacing,
            solver: defaults.solver,
            guidance,
            sampler,
            prefix: defaults.prefix,
            seed: 0,
        };
        let req = GroupRequest {
            music: &self.music,
            frames: FRAMES,
            dancers: DANCERS,
            control: None,
            known: None,
        };
        let out = generate(
            &self.net,
            &self.schedule,
            WINDOW_FRAMES,
            &req,
            &opts,
            &self.dev,
            &NoHook,
        )
        .expect("NoHook never cancels");
        assert_eq!(out.len(), FRAMES * GROUP_DIMS);
    }
}

fn main() {
    let reps = env_usize("DANCEGEN_BENCH_REPS", 3);
    let only = std::env::args().nth(1).filter(|a| !a.starts_with('-'));
    let want = |c: &str| only.as_deref().is_none_or(|o| c.contains(o));
    let dev = device::inference();
    dev.seed(0);
    let cfg = denoiser_config();
    let net = cfg.init(&[0.0; DIMS], &[1.0; DIMS], &dev);
    eprintln!(
        "burn-flex group denoiser parameters: {} ({} windows of {WINDOW_FRAMES} frames)",
        net.num_params(),
        window_count(FRAMES, WINDOW_FRAMES)
    );
    let mut rng = SeededNoise::new(0);
    let music: Vec<f32> = (0..FRAMES * MUSIC_DIMS)
        .map(|_| rng.normal() as f32)
        .collect();
    let bench = Bench {
        net,
        schedule: Schedule::edge(),
        music,
        dev,
    };
    let steps = env_usize("GROUP_BENCH_STEPS", SamplingConfig::default().steps);
    let guidance = std::env::var("GROUP_BENCH_GUIDANCE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SamplingConfig::default().guidance);
    for (name, sampler) in [
        ("lgds_5x1800f", LongSampler::Lgds),
        ("parallel_5x1800f", LongSampler::Parallel),
    ] {
        if !want(name) {
            continue;
        }
        bench.run(2, guidance, sampler);
        let mut ms: Vec<f64> = (0..reps)
            .map(|_| {
                let t = Instant::now();
                bench.run(steps, guidance, sampler);
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        println!(
            "{{\"impl\": \"burn-flex\", \"case\": \"{name}\", \"steps\": {steps}, \"median_ms\": {:.2}, \"min_ms\": {:.2}, \"reps\": {reps}}}",
            ms[ms.len() / 2],
            ms[0]
        );
    }
}
