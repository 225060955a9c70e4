//! An EDGE-sized denoiser on burn-flex, timed the same way as `bench/nn_denoiser.py` times
//! PyTorch (run both with `bash bench/nn.sh`, which prints the ratios).
//!
//! Model (EDGE, anchors D.1): Linear 151 → 512, 8 FiLM decoder layers (d 512, 8 heads, FF 1024,
//! GELU, rotary on the self-attention query/key input), cross-attention to 150 music tokens of
//! width 512, Linear 512 → 151; the FiLM vector is the conditioning vector plus the timestep
//! embedding (sinusoidal → Linear 512 → 2048 → Mish → Linear 2048 → 512). Cases: forward at
//! batch 1 and 8; one training step (forward, MSE, backward, AdamW) at batch 1 and 8; EDGE's
//! sampler on 150 frames at batch 1 (DDIM 50 steps, eta 1, guidance w = 2: two forwards per
//! step). Each case: warm-up, then `DANCEGEN_BENCH_REPS` (default 5) timed runs; prints one JSON
//! line per case with the median and min in ms.

use std::time::Instant;

use dancegen_nn::attention::AttnMasks;
use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::nn::{Linear, LinearConfig};
use dancegen_nn::burn::optim::{AdamWConfig, GradientsParams};
use dancegen_nn::burn::tensor::Int;
use dancegen_nn::burn::tensor::{Device, Distribution, Tensor};
use dancegen_nn::device;
use dancegen_nn::diffusion::{
    Conditioning, Denoiser as DenoiserTrait, SampleOptions, Schedule, sample,
};
use dancegen_nn::pos_encoding::{Rotary, RotaryTables};
use dancegen_nn::timestep::{TimestepMlp, TimestepMlpConfig};
use dancegen_nn::transformer::{DecoderContext, FilmDecoderLayer, FilmDecoderLayerConfig};

const FRAMES: usize = 150;
const D_MOTION: usize = 151;
const D: usize = 512;

#[derive(Module, Debug)]
struct Denoiser {
    time: TimestepMlp,
    time_cond: Linear,
    input: Linear,
    layers: Vec<FilmDecoderLayer>,
    output: Linear,
}

impl Denoiser {
    fn new(device: &Device) -> Self {
        Denoiser {
            time: TimestepMlpConfig::new(D).init(device),
            time_cond: LinearConfig::new(4 * D, D).init(device),
            input: LinearConfig::new(D_MOTION, D).init(device),
            layers: (0..8)
                .map(|_| FilmDecoderLayerConfig::new(D, 8, 1024).init(device))
                .collect(),
            output: LinearConfig::new(D, D_MOTION).init(device),
        }
    }

    fn forward(
        &self,
        x: Tensor<3>,
        t: &[f32],
        memory: Tensor<3>,
        cond: Tensor<2>,
        rotary: &RotaryTables,
    ) -> Tensor<3> {
        let cond = cond + self.time_cond.forward(self.time.forward(t, &x.device()));
        let none = AttnMasks::default();
        let ctx = DecoderContext {
            memory,
            cond: cond.unsqueeze_dim(1),
            self_masks: &none,
            cross_masks: &none,
            rotary: Some(rotary),
        };
        let mut h = self.input.forward(x);
        for l in &self.layers {
            h = l.forward(h, &ctx);
        }
        self.output.forward(h)
    }
}

/// The music condition of the sampler case.
struct Music {
    memory: Tensor<3>,
    cond: Tensor<2>,
}

/// The denoiser as the sampler sees it. The null condition is zeros (a stand-in for EDGE's
/// learned null embedding at the same cost).
struct Sampling<'a> {
    net: &'a Denoiser,
    rotary: &'a RotaryTables,
}

impl DenoiserTrait for Sampling<'_> {
    type Cond = Music;

    fn predict_x0(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        c: Conditioning<'_, Music>,
    ) -> Tensor<3> {
        let t: Vec<f32> = t
            .into_data()
            .convert::<f32>()
            .try_into_vec::<f32>()
            .unwrap();
        let b = x_t.dims()[0];
        let dev = x_t.device();
        let (memory, cond) = match c {
            Conditioning::Full(m) => (m.memory.clone(), m.cond.clone()),
            _ => (
                Tensor::zeros([b, FRAMES, D], &dev),
                Tensor::zeros([b, D], &dev),
            ),
        };
        self.net.forward(x_t, &t, memory, cond, self.rotary)
    }
}

fn inputs(b: usize, dev: &Device) -> (Tensor<3>, Tensor<3>, Tensor<2>) {
    let n = Distribution::Normal(0.0, 1.0);
    (
        Tensor::random([b, FRAMES, D_MOTION], n, dev),
        Tensor::random([b, FRAMES, D], n, dev),
        Tensor::random([b, D], n, dev),
    )
}

fn time(name: &str, reps: usize, mut f: impl FnMut()) {
    f();
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

fn main() {
    let reps: usize = std::env::var("DANCEGEN_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let only = std::env::args().nth(1).filter(|a| !a.starts_with('-'));
    let want = |c: &str| only.as_deref().is_none_or(|o| c.contains(o));

    let dev = device::inference();
    dev.seed(0);
    let rotary = Rotary::new(D).tables(0, FRAMES, &dev);
    let model = Denoiser::new(&dev);
    for b in [1, 8] {
        let case = format!("forward_b{b}");
        if want(&case) {
            let (x, m, c) = inputs(b, &dev);
            time(&case, reps, || {
                let y = model.forward(x.clone(), &[500.0; 8][..b], m.clone(), c.clone(), &rotary);
                let _ = y.into_data();
            });
        }
    }

    if want("ddim50_b1") {
        let (_, memory, cond) = inputs(1, &dev);
        let music = Music { memory, cond };
        let schedule = Schedule::edge();
        let sampler = Sampling {
            net: &model,
            rotary: &rotary,
        };
        time("ddim50_b1", reps.min(3), || {
            let x = sample(
                &sampler,
                &schedule,
                [1, FRAMES, D_MOTION],
                Some(&music),
                &SampleOptions::edge(0),
                &dev,
            );
            let _ = x.into_data();
        });
    }

    let tdev = device::training();
    tdev.seed(0);
    let rotary = Rotary::new(D).tables(0, FRAMES, &tdev);
    for b in [1, 8] {
        let case = format!("train_step_b{b}");
        if !want(&case) {
            continue;
        }
        let mut model = Some(Denoiser::new(&tdev));
        let mut optim = AdamWConfig::new().init();
        let (x, m, c) = inputs(b, &tdev);
        let target =
            Tensor::<3>::random([b, FRAMES, D_MOTION], Distribution::Normal(0.0, 1.0), &tdev);
        time(&case, reps, || {
            let net = model.take().unwrap();
            let y = net.forward(x.clone(), &[500.0; 8][..b], m.clone(), c.clone(), &rotary);
            let loss = (y - target.clone()).powf_scalar(2.0).mean();
            let grads = GradientsParams::from_grads(loss.backward(), &net);
            model = Some(optim.step(1e-4, net, grads));
        });
    }
}
