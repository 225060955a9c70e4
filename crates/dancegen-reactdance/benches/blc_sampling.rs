//! The duet model's latent sampling on burn-flex, timed the same way as
//! `bench/duet_denoiser.py` times the PyTorch re-implementation (run both with
//! `bash bench/duet.sh`, which prints the ratios).
//!
//! Model: the shipped small configuration, read at run time from
//! `configs/reactdance_small_hfsq.toml` `[model.autoencoder]` and
//! `configs/reactdance_small_ldm.toml` `[model.denoiser]` (as the Python side does), random
//! weights. Both sides print the denoiser's parameter count to stderr.
//! Sampler: [`dancegen_reactdance::blc::sample_latent`]: BLC (all blocks of 60 tokens as one
//! batch), DDIM with the shipped step count, layer-wise guidance (one batched forward of the
//! conditional and one of the null branch per step), then the HFSQ decoder over the whole
//! latent. 2000 frames = 500 tokens = 9 blocks.
//!
//! Cases: `blc_ldcfg_2000f` (compared with PyTorch), `ar_ldcfg_2000f` (the autoregressive
//! ablation, Rust only). Each case: a warm-up run with 2 steps, then `DANCEGEN_BENCH_REPS`
//! (default 3) timed runs; one JSON line per case with the median and min in ms. An optional
//! first argument keeps only the cases whose name contains it.

use std::time::Instant;

/// The `dancegen` binary's allocator (`crates/dancegen-cli/src/main.rs`).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::tensor::{Device, Distribution, Tensor};
use dancegen_nn::device;
use dancegen_nn::diffusion::{BetaSchedule, Schedule};
use dancegen_reactdance::autoencoder::HfsqAutoencoder;
use dancegen_reactdance::blc::{LatentSampling, LongForm, sample_latent};
use dancegen_reactdance::config::{
    DenoiserConfig, HfsqAutoencoderConfig, SamplingDefaults, leader_token_dim, music_token_dim,
};
use dancegen_reactdance::denoiser::{DuetCond, LatentDenoiser};

const FRAMES: usize = 2000;

fn table<T: serde::de::DeserializeOwned>(file: &str, key: &str) -> T {
    let path = format!("{}/../../configs/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {path}: {e}"));
    let doc: toml::Table = toml::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let model = doc
        .get("model")
        .and_then(|m| m.get(key))
        .cloned()
        .unwrap_or_else(|| panic!("{path}: no [model.{key}]"));
    model
        .try_into()
        .unwrap_or_else(|e| panic!("{path} [model.{key}]: {e}"))
}

fn env_usize(key: &str, default: usize) -> usize {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

struct Bench {
    ae: HfsqAutoencoder,
    net: LatentDenoiser,
    cfg: HfsqAutoencoderConfig,
    schedule: Schedule,
    cond: DuetCond,
    dev: Device,
}

impl Bench {
    fn run(&self, steps: usize, guidance: &[f64], long_form: LongForm) {
        let s = LatentSampling {
            steps,
            eta: 1.0,
            guidance: guidance.to_vec(),
            seed: 0,
            long_form,
        };
        let z = sample_latent(
            &self.net,
            &self.schedule,
            &self.cond,
            self.cfg.latent_dim(),
            self.cfg.num_levels,
            &s,
            &self.dev,
        );
        let _ = self.ae.decode(z).into_data();
    }
}

fn main() {
    let reps = env_usize("DANCEGEN_BENCH_REPS", 3);
    let only = std::env::args().nth(1).filter(|a| !a.starts_with('-'));
    let want = |c: &str| only.as_deref().is_none_or(|o| c.contains(o));
    let dev = device::inference();
    dev.seed(0);
    let cfg: HfsqAutoencoderConfig = table("reactdance_small_hfsq.toml", "autoencoder");
    let dcfg: DenoiserConfig = table("reactdance_small_ldm.toml", "denoiser");
    let f = cfg.frames_per_token();
    let k = FRAMES.div_ceil(f);
    let net = dcfg.init(cfg.latent_dim(), f, &dev);
    eprintln!("burn-flex duet denoiser parameters: {}", net.num_params());
    let normal = Distribution::Normal(0.0, 1.0);
    let bench = Bench {
        ae: cfg.init(&dev),
        net,
        schedule: Schedule::new(BetaSchedule::Cosine, dcfg.timesteps),
        cond: DuetCond {
            leader: Tensor::random([1, k, leader_token_dim(f)], normal, &dev),
            music: Tensor::random([1, k, music_token_dim(f)], normal, &dev),
        },
        cfg,
        dev,
    };
    let sampling = SamplingDefaults::default();
    for (name, long_form) in [
        ("blc_ldcfg_2000f", LongForm::Blc),
        ("ar_ldcfg_2000f", LongForm::Autoregressive),
    ] {
        if !want(name) {
            continue;
        }
        bench.run(2, &sampling.guidance, long_form);
        let mut ms: Vec<f64> = (0..reps)
            .map(|_| {
                let t = Instant::now();
                bench.run(sampling.steps, &sampling.guidance, long_form);
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        println!(
            "{{\"impl\": \"burn-flex\", \"case\": \"{name}\", \"steps\": {}, \"median_ms\": {:.2}, \"min_ms\": {:.2}, \"reps\": {reps}}}",
            sampling.steps,
            ms[ms.len() / 2],
            ms[0]
        );
    }
}
