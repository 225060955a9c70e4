//! Diagnostic (issue 41): where does a PDDM checkpoint lose the dance's speed? For training
//! windows with their own music, genre and primitives (the trainer's "full" primitives: the
//! boundary frames and the key motions around the motion beats), prints the mean FK joint speed
//! (m/s), the mean horizontal root speed and the mean jerk (m/s³) of (a) the ground truth,
//! (b) the x0 the network predicts from `q_sample` at several noise levels, main decoder and
//! Foot Refine Block apart, and (c) sampled windows at several guidance weights, with and
//! without the block. Speeds below the truth's at low noise mean the denoiser itself damps the
//! motion; speeds that fall only when sampling mean the reverse process does.
//!
//!     cargo run --release -p dancegen-train --example pddm_speed_probe -- RUN_DIR CHECKPOINT.safetensors [BATCHES]

use std::path::PathBuf;

use dancegen_lodgepp::denoiser::PddmCond;
use dancegen_lodgepp::kinematics::joints;
use dancegen_lodgepp::layout::{DIMS, main_channels};
use dancegen_lodgepp::primitives::{PrimitiveMode, training_primitives};
use dancegen_lodgepp::sampler::{FootRefineScope, PddmSampleOptions, sample_windows};
use dancegen_lodgepp::training::root_relative;
use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::device;
use dancegen_nn::diffusion::Conditioning;
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_nn::loss::FkSkeleton;
use dancegen_train::data::DataPosition;
use dancegen_train::tasks::lodgepp::PddmCheckpoint;

const FPS: f64 = 30.0;

/// Mean joint speed, mean horizontal root speed and mean jerk of FK joints `[B, T, 24, 3]`.
fn kinematics(j: Tensor<4>) -> [f64; 3] {
    let [b, t, n, _] = j.dims();
    let v: Vec<f32> = j.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
    let at = |i: usize, f: usize, k: usize, c: usize| v[((i * t + f) * n + k) * 3 + c] as f64;
    let (mut speed, mut root, mut jerk) = (0f64, 0f64, 0f64);
    for i in 0..b {
        for f in 0..t - 1 {
            for k in 0..n {
                let d: f64 = (0..3)
                    .map(|c| (at(i, f + 1, k, c) - at(i, f, k, c)).powi(2))
                    .sum();
                speed += d.sqrt();
            }
            let (dx, dz) = (
                at(i, f + 1, 0, 0) - at(i, f, 0, 0),
                at(i, f + 1, 0, 2) - at(i, f, 0, 2),
            );
            root += (dx * dx + dz * dz).sqrt();
        }
        for f in 0..t - 3 {
            for k in 0..n {
                let d: f64 = (0..3)
                    .map(|c| {
                        at(i, f + 3, k, c) - 3.0 * at(i, f + 2, k, c) + 3.0 * at(i, f + 1, k, c)
                            - at(i, f, k, c)
                    })
                    .map(|x| x * x)
                    .sum();
                jerk += d.sqrt();
            }
        }
    }
    [
        FPS * speed / (b * (t - 1) * n) as f64,
        FPS * root / (b * (t - 1)) as f64,
        FPS.powi(3) * jerk / (b * (t - 3) * n) as f64,
    ]
}

fn main() {
    if let Err(e) = probe() {
        eprintln!("pddm_speed_probe: {e}");
        std::process::exit(1);
    }
}

fn probe() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let (run, ck, batches) = match &args[..] {
        [_, run, ck] => (run, ck, 2usize),
        [_, run, ck, n] => (
            run,
            ck,
            n.parse()
                .map_err(|_| format!("BATCHES: not a number: {n}"))?,
        ),
        _ => return Err("usage: pddm_speed_probe RUN_DIR CHECKPOINT.safetensors [BATCHES]".into()),
    };
    let (run, ck) = (PathBuf::from(run), PathBuf::from(ck));
    let PddmCheckpoint { task, data, model } = PddmCheckpoint::load(&run, &ck)?;
    let dev = device::inference();
    let net = &model.denoiser;
    let skel = FkSkeleton::smpl24();
    let fk = |x: Tensor<3>| kinematics(joints(net.denorm.apply(x), &skel));
    let shift_s = task.table.shift.schedule();
    let mut rows: Vec<(String, [f64; 3])> = Vec::new();
    let mut add = |label: String, k: [f64; 3]| match rows.iter_mut().find(|(l, _)| *l == label) {
        Some((_, acc)) => (0..3).for_each(|i| acc[i] += k[i] / batches as f64),
        None => rows.push((label, k.map(|v| v / batches as f64))),
    };
    for cursor in 0..batches {
        let (batch, _) = data.batch(DataPosition { epoch: 3, cursor }, &dev);
        let x = root_relative(batch.motion.clone());
        let [b, t, d] = x.dims();
        let host: Vec<f32> = x
            .clone()
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .unwrap();
        let (mut prim, mut mask) = (Vec::new(), Vec::new());
        for w in host.chunks(t * DIMS) {
            let p = training_primitives(w, PrimitiveMode::Full, &main_channels());
            prim.extend(p.values);
            mask.extend(p.mask);
        }
        let cond = PddmCond {
            music: batch.music.clone().ok_or("the run's data has no music")?,
            genre: batch.genre.clone().ok_or("the run's data has no genres")?,
            primitives: Tensor::from_data(TensorData::new(prim, [b, t, d]), &dev),
            mask: Tensor::from_data(TensorData::new(mask, [b, t, 1]), &dev),
            music_encoded: None,
        };
        add("ground truth".into(), fk(x.clone()));
        let mut rng = SeededNoise::new(1 + cursor as u64);
        for step in [1usize, 5, 10, 25, 40, 50] {
            let d_t = shift_s.q_sample(
                x.clone(),
                cond.primitives.clone(),
                &vec![step; b],
                rng.tensor([b, t, d], &dev),
            );
            let out = net.forward(
                d_t,
                &vec![(step - 1) as f32; b],
                Conditioning::Dropout {
                    cond: &cond,
                    keep: &vec![true; b],
                },
                true,
            );
            add(format!("x0 from t={step}, main decoder"), fk(out.main));
            add(format!("x0 from t={step}, refined"), fk(out.refined));
        }
        for g in [1.0, 2.0, 4.0] {
            for (name, refine, scope) in [
                ("no block", false, FootRefineScope::All),
                ("block on legs", true, FootRefineScope::Legs),
                ("block on all", true, FootRefineScope::All),
            ] {
                let opts = PddmSampleOptions {
                    steps: 50,
                    guidance: g,
                    refine,
                    refine_last_steps: None,
                    refine_scope: scope,
                    penetration: None,
                    seed: 3 + cursor as u64,
                };
                let out =
                    sample_windows(net, &shift_s, &cond, None, &opts, &dev, &device::training());
                add(format!("sampled, guidance {g}, {name}"), fk(out));
            }
        }
    }
    println!("| windows | joint speed (m/s) | root speed (m/s) | jerk (m/s³) |");
    println!("|---|---|---|---|");
    for (label, [a, r, j]) in rows {
        println!("| {label} | {a:.3} | {r:.3} | {j:.0} |");
    }
    Ok(())
}
