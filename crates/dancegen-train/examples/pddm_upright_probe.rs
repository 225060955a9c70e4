//! Diagnostic (issue 16): does a PDDM checkpoint keep training windows upright, (a) as an x0
//! prediction from the training forward at several noise levels and (b) when sampled from noise
//! with a training window's own music and genre? Prints mean raw root height and the share of
//! frames whose root "up" axis (row 0 × row 1 of the root matrix, its Y) points down, and the
//! mean angle between that axis and world up.
//!
//!     cargo run --release -p dancegen-train --example pddm_upright_probe -- RUN_DIR CHECKPOINT.safetensors

use std::path::PathBuf;

use dancegen_lodgepp::denoiser::PddmCond;
use dancegen_lodgepp::sampler::{PddmSampleOptions, sample_windows};
use dancegen_lodgepp::training::root_relative;
use dancegen_nn::burn::tensor::Tensor;
use dancegen_nn::device;
use dancegen_nn::diffusion::Conditioning;
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_train::data::DataPosition;
use dancegen_train::tasks::lodgepp::PddmCheckpoint;

fn report(label: &str, x: Tensor<3>, scale: &[f32], shift: &[f32]) {
    let v: Vec<f32> = x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
    let (mut h, mut down, mut n, mut tilt) = (0f64, 0usize, 0usize, 0f64);
    for f in v.chunks(151) {
        let r = |c: usize| f[c] * scale[c] + shift[c];
        h += r(6) as f64;
        let (a, b) = ([r(7), r(8), r(9)], [r(10), r(11), r(12)]);
        // Row 2 = row 0 × row 1; its middle entry is the body's up (local Y) along world Z.
        let row2 = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        if row2[1] < 0.0 {
            down += 1;
        }
        // Angle between the body's up and world up (Gram–Schmidt's row 2 is the unit cross).
        let norm = row2.iter().map(|v| (v * v) as f64).sum::<f64>().sqrt();
        if norm > 0.0 {
            tilt += (row2[1] as f64 / norm).clamp(-1.0, 1.0).acos().to_degrees();
        }
        n += 1;
    }
    println!(
        "{label}: mean height {:.3}, up-axis down {:.2}, mean tilt {:.1} deg",
        h / n as f64,
        down as f64 / n as f64,
        tilt / n as f64
    );
}

fn main() {
    if let Err(e) = probe() {
        eprintln!("pddm_upright_probe: {e}");
        std::process::exit(1);
    }
}

fn probe() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let [_, run, ck] = &args[..] else {
        return Err("usage: pddm_upright_probe RUN_DIR CHECKPOINT.safetensors".into());
    };
    let (run, ck) = (PathBuf::from(run), PathBuf::from(ck));
    let PddmCheckpoint { task, data, model } = PddmCheckpoint::load(&run, &ck)?;
    let dev = device::inference();
    let net = &model.denoiser;
    let (scale, shift) = net.denorm.host();
    let (batch, _) = data.batch(
        DataPosition {
            epoch: 3,
            cursor: 0,
        },
        &dev,
    );
    let mut x = root_relative(batch.motion.clone());
    let [b, t, d] = x.dims();
    if task.table.pddm.canonical_heading {
        let mut h: Vec<f32> = x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
        dancegen_lodgepp::heading::canonicalise(
            &mut h,
            t,
            &dancegen_lodgepp::heading::Stats {
                scale: &scale,
                shift: &shift,
            },
        );
        x = Tensor::from_data(
            dancegen_nn::burn::tensor::TensorData::new(h, [b, t, d]),
            &dev,
        );
    }
    report("ground truth", x.clone(), &scale, &shift);
    let music = batch.music.clone().ok_or("the run's data has no music")?;
    let genre = batch.genre.clone().ok_or("the run's data has no genres")?;
    let cond = PddmCond {
        music: music.clone(),
        genre: genre.clone(),
        primitives: Tensor::zeros([b, t, d], &dev),
        mask: Tensor::zeros([b, t, 1], &dev),
        music_encoded: None,
    };
    let shift_s = task.table.shift.schedule();
    let mut rng = SeededNoise::new(1);
    for step in [1usize, 10, 25, 40, 50] {
        let steps = vec![step; b];
        let d_t = shift_s.q_sample(
            x.clone(),
            cond.primitives.clone(),
            &steps,
            rng.tensor([b, t, d], &dev),
        );
        let tf = vec![(step - 1) as f32; b];
        let keep = vec![true; b];
        let out = net.forward(
            d_t,
            &tf,
            Conditioning::Dropout {
                cond: &cond,
                keep: &keep,
            },
            false,
        );
        report(
            &format!("x0 from t={step}"),
            out.refined.clone(),
            &scale,
            &shift,
        );
        if step == 1 {
            let p: Vec<f32> = out
                .refined
                .into_data()
                .convert::<f32>()
                .try_to_vec::<f32>()
                .unwrap();
            let g: Vec<f32> = x
                .clone()
                .into_data()
                .convert::<f32>()
                .try_to_vec::<f32>()
                .unwrap();
            let hi: usize = std::env::var("HI")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(13);
            for c in (4..hi).step_by(if hi > 13 { 5 } else { 1 }) {
                let (mut pg, mut gg, mut pp, mut e) = (0f64, 0f64, 0f64, 0f64);
                for (a, b) in p.chunks(151).zip(g.chunks(151)) {
                    let (a, b) = (a[c] as f64, b[c] as f64);
                    pg += a * b;
                    gg += b * b;
                    pp += a * a;
                    e += (a - b).powi(2);
                }
                let n = (p.len() / 151) as f64;
                println!(
                    "  channel {c}: corr {:.2}, mse {:.3}, pred rms {:.2}, gt rms {:.2}",
                    pg / (pp * gg).sqrt(),
                    e / n,
                    (pp / n).sqrt(),
                    (gg / n).sqrt()
                );
            }
        }
    }
    for g in [1.0, 2.0] {
        let opts = PddmSampleOptions {
            steps: 50,
            guidance: g,
            refine: true,
            refine_last_steps: None,
            refine_scope: Default::default(),
            penetration: None,
            seed: 3,
        };
        let s = sample_windows(net, &shift_s, &cond, None, &opts, &dev, &device::training());
        report(&format!("sampled, guidance {g}"), s, &scale, &shift);
    }
    Ok(())
}
