//! The autoencoder's foot velocity loss (ours): the feet it reads from the duet features are
//! the follower's real feet in the leader frame, the loss is zero for a perfect
//! reconstruction, and decoder-only training leaves the encoders without gradients.

use dancegen_motion::repr::duet::leader_frames;
use dancegen_motion::repr::{DuetFollower, SmplMotion};
use dancegen_motion::rotation::Mat3;
use dancegen_nn::burn::module::{Module, ModuleVisitor, Param};
use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::device;
use dancegen_reactdance::autoencoder::LossOptions;
use dancegen_reactdance::config::HfsqAutoencoderConfig;
use dancegen_reactdance::follower_feet::{FOOT_JOINTS, FollowerFeet};

const T: usize = 40;

/// A dancer stepping and turning: smooth, varied joint angles and a wandering root.
fn dancer(phase: f64, turn: f64) -> SmplMotion {
    let mut poses = Vec::with_capacity(T * 72);
    let mut trans = Vec::with_capacity(T * 3);
    for f in 0..T {
        let t = f as f64 / 30.0;
        for j in 0..24 {
            let a = 0.4 * (3.0 * t + phase + j as f64).sin();
            let b = 0.3 * (2.0 * t + 0.5 * j as f64).cos();
            let c = 0.2 * (5.0 * t + phase).sin();
            let yaw = if j == 0 { turn * t } else { 0.0 };
            poses.extend([a as f32, (b + yaw) as f32, c as f32]);
        }
        trans.extend([
            (0.5 * (t + phase).sin()) as f32,
            (0.9 + 0.05 * (4.0 * t).sin()) as f32,
            (0.3 * t + phase) as f32,
        ]);
    }
    SmplMotion::new(30.0, poses, trans).unwrap()
}

#[test]
fn the_feet_are_the_followers_feet_in_the_leader_frame() {
    let (follower, leader) = (dancer(0.3, 1.5), dancer(1.1, -2.0));
    let sigma = 8.0;
    let raw = DuetFollower::encode(&follower, &leader, sigma).unwrap();
    let d = DuetFollower::DIMS;
    // A normaliser with non-trivial statistics, so de-normalising is tested too.
    let mean: Vec<f64> = (0..d).map(|i| 0.01 * i as f64).collect();
    let std: Vec<f64> = (0..d).map(|i| 0.5 + 0.01 * i as f64).collect();
    let x: Vec<f32> = raw
        .chunks_exact(d)
        .flat_map(|row| {
            row.iter()
                .enumerate()
                .map(|(i, &v)| ((f64::from(v) - mean[i]) / std[i]) as f32)
                .collect::<Vec<_>>()
        })
        .collect();
    let feet = FollowerFeet::new(&mean, &std).unwrap();
    let dev = device::inference();
    let got = feet
        .positions(Tensor::<3>::from_data(TensorData::new(x, [1, T, d]), &dev))
        .into_data()
        .try_to_vec::<f32>()
        .unwrap();
    let world = follower.joints_world().unwrap();
    let frames = leader_frames(&leader, sigma);
    let mut worst = 0f64;
    for f in 0..T {
        let inv = Mat3::from_axis_rotation(1, frames[f]).transpose();
        let pl = &leader.trans[f * 3..f * 3 + 3];
        for (k, &j) in FOOT_JOINTS.iter().enumerate() {
            let w = &world[(f * 24 + j) * 3..(f * 24 + j) * 3 + 3];
            let want = inv.mul_vec([
                f64::from(w[0] - pl[0]),
                f64::from(w[1]),
                f64::from(w[2] - pl[2]),
            ]);
            for a in 0..3 {
                let g = f64::from(got[(f * 4 + k) * 3 + a]);
                worst = worst.max((g - want[a]).abs());
            }
        }
    }
    assert!(worst < 1e-4, "feet differ from the CPU's by {worst} m");
}

#[test]
fn the_loss_is_zero_for_a_perfect_reconstruction_and_grows_with_foot_error() {
    let d = DuetFollower::DIMS;
    let feet = FollowerFeet::new(&vec![0.0; d], &vec![1.0; d]).unwrap();
    let dev = device::inference();
    let raw = DuetFollower::encode(&dancer(0.3, 1.5), &dancer(1.1, -2.0), 8.0).unwrap();
    let x = Tensor::<3>::from_data(TensorData::new(raw.clone(), [1, T, d]), &dev);
    let same = feet
        .velocity_loss(x.clone(), x.clone(), 30.0)
        .into_scalar::<f32>();
    assert!(same.abs() < 1e-6, "{same}");
    // A root that jitters by 1 cm every other frame: 0.3 m/s of velocity error per axis.
    let mut jitter = raw.clone();
    for (f, row) in jitter.chunks_exact_mut(d).enumerate() {
        row[DuetFollower::ROOT_POS.start] += if f % 2 == 0 { 0.005 } else { -0.005 };
    }
    let y = Tensor::<3>::from_data(TensorData::new(jitter, [1, T, d]), &dev);
    let l = feet.velocity_loss(y, x, 30.0).into_scalar::<f32>();
    // One of three axes moves by 0.3 m/s on every frame step: mean 0.1.
    assert!((l - 0.1).abs() < 1e-3, "{l}");
}

/// Counts parameters with and without a gradient, by module path prefix.
struct GradCount<'a> {
    grads: &'a dancegen_nn::burn::optim::GradientsParams,
    with: usize,
    without: usize,
}

impl ModuleVisitor for GradCount<'_> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        if self.grads.get::<D>(param.id).is_some() {
            self.with += 1;
        } else {
            self.without += 1;
        }
    }
}

#[test]
fn decoder_only_training_sends_no_gradient_to_the_encoders() {
    let cfg = HfsqAutoencoderConfig {
        width: 16,
        depth: 1,
        foot_velocity_weight: 1.0,
        ..Default::default()
    };
    let dev = device::training();
    dev.seed(3);
    let ae = cfg.init(&dev);
    let d = DuetFollower::DIMS;
    let raw = DuetFollower::encode(&dancer(0.3, 1.5), &dancer(1.1, -2.0), 8.0).unwrap();
    let x = Tensor::<3>::from_data(TensorData::new(raw[..32 * d].to_vec(), [1, 32, d]), &dev);
    let feet = FollowerFeet::new(&vec![0.0; d], &vec![1.0; d]).unwrap();
    let copy = cfg.init(&device::inference());
    for frozen in [false, true] {
        let opts = LossOptions {
            feet: Some(feet.clone()),
            frozen_latent: frozen.then(|| copy.clone()),
            ..LossOptions::default()
        };
        let (_, l) = ae.loss_with(x.clone(), &cfg, &opts);
        assert!(l.foot_velocity.is_some());
        let grads = dancegen_nn::burn::optim::GradientsParams::from_grads(l.total.backward(), &ae);
        for s in &ae.streams {
            let mut enc = GradCount {
                grads: &grads,
                with: 0,
                without: 0,
            };
            s.encoder.visit(&mut enc);
            let mut dec = GradCount {
                grads: &grads,
                with: 0,
                without: 0,
            };
            s.decoder.visit(&mut dec);
            assert!(dec.with > 0 && dec.without == 0, "decoder: {}", dec.with);
            if frozen {
                assert_eq!(enc.with, 0, "frozen encoder got {} gradients", enc.with);
            } else {
                assert!(enc.with > 0, "encoder got no gradient");
            }
        }
    }
}
