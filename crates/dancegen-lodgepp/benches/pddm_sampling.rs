//! Lodge++'s PDDM reverse process on burn-flex, timed the same way as `bench/solo_pddm.py` times
//! the PyTorch re-implementation (run both with `bash bench/solo.sh`, which prints the ratios).
//!
//! Model: the shipped small configuration, read from `configs/lodgepp_small_pddm.toml` `[model]`
//! at run time (as `bench/solo_pddm.py` does; on 2026-11-22: d 192, 3 FiLM decoder layers,
//! 6 heads, FF 384, 2 music encoder layers, 128-frame windows, Foot Refine Block on), random
//! weights, identity normaliser, 10 genres. Both sides print their parameter count to stderr.
//! Sampler: [`dancegen_lodgepp::sampler::sample_windows`], 50 residual-shift steps, guidance 2 (one
//! batched forward of `[cond; uncond]` = 2B windows per step), refine on, hard cues on the 4
//! boundary frames at each window end (as the pipeline writes them). Batch = 128-frame windows:
//! 8 for 1024 frames (34 s), 71 for 5 minutes (9000 frames).
//!
//! Cases (`pddm50_cfg_1024f_b8`, `pddm50_cfg_5min_b71`: penetration guidance off, the PyTorch
//! side has none; `pddm50_cfg_pene10_1024f_b8`: with the shipped penetration guidance on the last
//! 10 steps, Rust only). Each case: a 2-step warm-up at its batch size, then
//! `DANCEGEN_BENCH_REPS` (default 3) timed runs (`DANCEGEN_BENCH_REPS_LONG`, default 1, for the
//! 5-minute case); one JSON line per case with the median and min in ms. An optional first
//! argument keeps only the cases whose name contains it.

use std::time::Instant;

/// The `dancegen` binary's allocator (`crates/dancegen-cli/src/main.rs`). With the system
/// allocator the sampler's multi-megabyte activations go back to the kernel after every op, and
/// this bench measured ~35 % slower than `dancegen generate` doing the same sampling.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use dancegen_lodgepp::config::{BOUNDARY_FRAMES, PddmTable};
use dancegen_lodgepp::denoiser::{PddmCond, PddmDenoiser};
use dancegen_lodgepp::layout::DIMS;
use dancegen_lodgepp::penetration::PenetrationGuidance;
use dancegen_lodgepp::sampler::{HardCues, PddmSampleOptions, sample_windows};
use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::tensor::{Device, Distribution, Tensor, TensorData};
use dancegen_nn::diffusion::pddm::ResidualShift;

/// EDGE-35 music features per frame.
const MUSIC_DIMS: usize = 35;
const GENRES: usize = 10;
/// Shipped defaults (`SamplingDefaults` of the bundle): 50 steps, w = 2, penetration on the
/// last 10 steps.
const STEPS: usize = 50;
const GUIDANCE: f64 = 2.0;
const PENETRATION_STEPS: usize = 10;

/// `[model]` of the shipped config (its `kind` key belongs to the trainer).
fn shipped_table() -> PddmTable {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/lodgepp_small_pddm.toml"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {path}: {e}"));
    let mut doc: toml::Table = toml::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut model = match doc.remove("model") {
        Some(toml::Value::Table(t)) => t,
        _ => panic!("{path}: no [model] table"),
    };
    model.remove("kind");
    let mut table: PddmTable = toml::Value::Table(model)
        .try_into()
        .unwrap_or_else(|e| panic!("{path} [model]: {e}"));
    if table.genres.is_empty() {
        table.genres = (0..GENRES).map(|g| format!("genre{g}")).collect();
    }
    // Sampling never touches the discriminator.
    table.use_discriminator = false;
    table
}

/// Random condition for `b` windows of `n` frames: music, genres, primitives on 8-frame
/// stretches at both ends and in the middle (mask 1 there), and hard cues on the 4 boundary
/// frames at each end.
fn inputs(b: usize, n: usize, dev: &Device) -> (PddmCond, HardCues) {
    let normal = Distribution::Normal(0.0, 1.0);
    let mut mask = vec![0f32; b * n];
    let mut cue = vec![0f32; b * n * DIMS];
    for w in 0..b {
        for f in (0..8).chain(n / 2 - 4..n / 2 + 4).chain(n - 8..n) {
            mask[w * n + f] = 1.0;
        }
        for f in (0..BOUNDARY_FRAMES).chain(n - BOUNDARY_FRAMES..n) {
            let row = (w * n + f) * DIMS;
            cue[row..row + DIMS].iter_mut().for_each(|v| *v = 1.0);
        }
    }
    let mask = Tensor::<3>::from_data(TensorData::new(mask, [b, n, 1]), dev);
    let primitives = Tensor::<3>::random([b, n, DIMS], normal, dev) * mask.clone();
    let cond = PddmCond {
        music: Tensor::random([b, n, MUSIC_DIMS], normal, dev),
        genre: (0..b).map(|w| w % GENRES).collect(),
        primitives: primitives.clone(),
        mask,
        music_encoded: None,
    };
    let cues = HardCues {
        values: primitives,
        mask: Tensor::from_data(TensorData::new(cue, [b, n, DIMS]), dev),
    };
    (cond, cues)
}

fn time(name: &str, reps: usize, mut warm_up: impl FnMut(), mut f: impl FnMut()) {
    warm_up();
    let mut ms: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    println!(
        "{{\"impl\": \"burn-flex\", \"case\": \"{name}\", \"median_ms\": {:.2}, \"min_ms\": {:.2}, \"reps\": {reps}}}",
        ms[ms.len() / 2],
        ms[0]
    );
}

struct Bench<'a> {
    net: &'a PddmDenoiser,
    shift: &'a ResidualShift,
    dev: &'a Device,
    grad: &'a Device,
}

impl Bench<'_> {
    fn run(&self, cond: &PddmCond, cues: &HardCues, opts: &PddmSampleOptions) {
        let x = sample_windows(
            self.net,
            self.shift,
            cond,
            Some(cues),
            opts,
            self.dev,
            self.grad,
        );
        let _ = x.into_data();
    }
}

fn env_usize(key: &str, default: usize) -> usize {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let reps = env_usize("DANCEGEN_BENCH_REPS", 3);
    let reps_long = env_usize("DANCEGEN_BENCH_REPS_LONG", 1);
    let only = std::env::args().nth(1).filter(|a| !a.starts_with('-'));
    let want = |c: &str| only.as_deref().is_none_or(|o| c.contains(o));

    let dev = dancegen_lodgepp::inference_device();
    dev.seed(0);
    let grad = dev.clone().autodiff();
    let table = shipped_table();
    let n = table.pddm.window;
    let net = table.init(&[0.0; DIMS], &[1.0; DIMS], &dev).denoiser;
    let shift = table.shift.schedule();
    // Same count as `bench/solo_pddm.py` prints (its normaliser is 302 buffer values, here
    // 302 frozen parameters).
    eprintln!("burn-flex PDDM parameters: {}", net.num_params());
    let bench = Bench {
        net: &net,
        shift: &shift,
        dev: &dev,
        grad: &grad,
    };
    let opts = |steps: usize, penetration: bool| PddmSampleOptions {
        steps,
        guidance: GUIDANCE,
        refine: true,
        refine_last_steps: None,
        refine_scope: Default::default(),
        penetration: penetration.then(|| (PenetrationGuidance::default(), PENETRATION_STEPS)),
        seed: 0,
    };

    let cases = [
        ("pddm50_cfg_1024f_b8", 1024usize.div_ceil(n), false, reps),
        (
            "pddm50_cfg_5min_b71",
            9000usize.div_ceil(n),
            false,
            reps_long,
        ),
        (
            "pddm50_cfg_pene10_1024f_b8",
            1024usize.div_ceil(n),
            true,
            reps,
        ),
    ];
    for (name, b, penetration, r) in cases {
        if !want(name) {
            continue;
        }
        let (cond, cues) = inputs(b, n, &dev);
        // Warm-up: 2 steps (t = 50, 25); with penetration on, both run the guidance too.
        let warm = opts(2, penetration);
        let full = opts(STEPS, penetration);
        time(
            name,
            r,
            || bench.run(&cond, &cues, &warm),
            || bench.run(&cond, &cues, &full),
        );
    }
}
