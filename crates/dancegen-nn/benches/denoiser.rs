//! An EDGE-sized denoiser on burn-flex, timed the same way as `bench/nn_denoiser.py` times
//! PyTorch (run both with `bash bench/nn.sh`, which prints the ratios).
//!
//! Model (EDGE, anchors D.1): Linear 151 → 512, 8 FiLM decoder layers (d 512, 8 heads, FF 1024,
//! GELU, rotary on the self-attention query/key input), cross-attention to 150 music tokens of
//! width 512, Linear 512 → 151. Cases: forward at batch 1 and 8; one training step (forward,
//! MSE, backward, AdamW) at batch 1 and 8. Each case: warm-up, then `DANCEGEN_BENCH_REPS`
//! (default 5) timed runs; prints one JSON line per case with the median and min in ms.

use std::time::Instant;

use dancegen_nn::attention::AttnMasks;
use dancegen_nn::burn::module::Module;
use dancegen_nn::burn::nn::{Linear, LinearConfig};
use dancegen_nn::burn::optim::{AdamWConfig, GradientsParams};
use dancegen_nn::burn::tensor::{Device, Distribution, Tensor};
use dancegen_nn::device;
use dancegen_nn::pos_encoding::{Rotary, RotaryTables};
use dancegen_nn::transformer::{DecoderContext, FilmDecoderLayer, FilmDecoderLayerConfig};

const FRAMES: usize = 150;
const D_MOTION: usize = 151;
const D: usize = 512;

#[derive(Module, Debug)]
struct Denoiser {
    input: Linear,
    layers: Vec<FilmDecoderLayer>,
    output: Linear,
}

impl Denoiser {
    fn new(device: &Device) -> Self {
        Denoiser {
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
        memory: Tensor<3>,
        cond: Tensor<2>,
        rotary: &RotaryTables,
    ) -> Tensor<3> {
        let none = AttnMasks::default();
        let ctx = DecoderContext {
            memory,
            cond,
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
                let y = model.forward(x.clone(), m.clone(), c.clone(), &rotary);
                let _ = y.into_data();
            });
        }
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
            let y = net.forward(x.clone(), m.clone(), c.clone(), &rotary);
            let loss = (y - target.clone()).powf_scalar(2.0).mean();
            let grads = GradientsParams::from_grads(loss.backward(), &net);
            model = Some(optim.step(1e-4, net, grads));
        });
    }
}
