//! The HFSQ autoencoder alone on a real couple: encode the follower, decode it, write world
//! joints — to see how much of a generated follower's error the autoencoder already makes.
//!
//!     cargo run --release -p dancegen-reactdance --example ae_roundtrip -- MODEL_DIR FOLLOWER.npz LEADER.npz OUT.npy [LEVELS] [KEEP]
//!
//! `KEEP`: streams (`upper`, `lower`, `root`, comma-separated) written back from the input
//! instead of the reconstruction, to see which stream's reconstruction makes an error.

use dancegen_formats::dispatch::{LoadedMotion, load_motion_file};
use dancegen_motion::repr::{DuetFollower, SmplMotion};
use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::device;
use dancegen_reactdance::bundle::DuetModel;

fn smpl(path: &str) -> SmplMotion {
    match load_motion_file(std::path::Path::new(path)).expect("motion file") {
        LoadedMotion::Smpl(m) => m,
        other => panic!("{path}: {} is not SMPL motion", other.kind()),
    }
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    assert!(
        a.len() >= 5,
        "usage: MODEL_DIR FOLLOWER LEADER OUT.npy [LEVELS]"
    );
    let dev = device::inference();
    let model = DuetModel::load(std::path::Path::new(&a[1]), &dev).expect("model");
    let (f, l) = (smpl(&a[2]), smpl(&a[3]));
    let sigma = model.config.heading_sigma;
    let t = f.frames().min(l.frames()) / 4 * 4;
    let cut = |m: &SmplMotion| SmplMotion {
        fps: m.fps,
        poses: m.poses[..t * 72].to_vec(),
        trans: m.trans[..t * 3].to_vec(),
    };
    let (f, l) = (cut(&f), cut(&l));
    let d = DuetFollower::DIMS;
    let (mean, std) = (&model.norm.mean[..d], &model.norm.std[..d]);
    let mut x = DuetFollower::encode(&f, &l, sigma).expect("encode");
    for row in x.chunks_exact_mut(d) {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ((f64::from(*v) - mean[j]) / std[j]) as f32;
        }
    }
    let input = x.clone();
    let x = Tensor::<3>::from_data(TensorData::new(x, [1, t, d]), &dev);
    let levels = a
        .get(5)
        .and_then(|v| v.parse().ok())
        .unwrap_or(model.config.autoencoder.num_levels);
    let z = model.autoencoder.encode(x);
    let y = model.autoencoder.decode_levels(z, levels);
    let mut y = y
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .unwrap();
    let keep = a.get(6).map_or("", String::as_str);
    let kept: Vec<std::ops::Range<usize>> = keep
        .split(',')
        .filter(|k| !k.is_empty())
        .map(|k| match k {
            "upper" => DuetFollower::STREAMS[0].clone(),
            "lower" => DuetFollower::STREAMS[1].clone(),
            "root" => DuetFollower::STREAMS[2].clone(),
            other => panic!("KEEP: unknown stream {other} (upper, lower, root)"),
        })
        .collect();
    for (row, orig) in y.chunks_exact_mut(d).zip(input.chunks_exact(d)) {
        for r in &kept {
            row[r.clone()].copy_from_slice(&orig[r.clone()]);
        }
        for (j, v) in row.iter_mut().enumerate() {
            *v = (f64::from(*v) * std[j] + mean[j]) as f32;
        }
    }
    let out = DuetFollower::decode(&y, &l, sigma).expect("decode");
    let joints = out.joints_world().expect("fk");
    dancegen_io::write_npy_f32(std::path::Path::new(&a[4]), &[t, 24, 3], &joints).unwrap();
}
