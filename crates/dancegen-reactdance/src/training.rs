//! Training losses of the two stages, on windows of the `duet` training representation:
//! `[B, W, 151 + 220]` = normalised follower features then the leader's (see
//! `dancegen_motion::repr::duet`), with the music `[B, W, 35]`.
//!
//! Stage 2 (latent diffusion), per batch:
//! - target: the frozen autoencoder's latent of the follower window (unmasked);
//! - x0-prediction on the cosine schedule, `Σ_r λ_r · MSE(level r)`;
//! - **LDCFG training**: for every window and every level `r` independently, with probability
//!   `cond_drop` that level's prediction is made without the condition. Windows whose levels
//!   disagree run through the network twice (once with, once without), so each level's loss
//!   sees exactly the branch its draw asked for (≈ 1.5 forward passes per batch at p = 0.2);
//! - kinematic L1 of the decoded prediction (features and velocity), through the frozen
//!   decoder;
//! - relative orientation: L1 of the decoded root-orientation channels, which are the
//!   follower's orientation in the leader's heading frame;
//! - foot contact: on frames where the real follower's foot is planted, the velocity of the
//!   decoded lower-body and relative-root channels. The contact channels are normalised 0/1
//!   labels, so "planted" is the upper of the two values the batch holds for a channel;
//! - foot velocity (ours, off unless weighted): the decoded follower's world foot velocities
//!   against the real ones ([`crate::follower_feet`]).

use dancegen_motion::repr::{DuetFollower, DuetLeader};
use dancegen_nn::burn;
use dancegen_nn::diffusion::{Schedule, SeededNoise};
use dancegen_nn::rng::SplitMix64;

use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::autoencoder::HfsqAutoencoder;
use crate::config::{LatentLossWeights, frames_per_token};
use crate::denoiser::{DuetCond, LatentDenoiser, Layout};
use crate::follower_feet::FollowerFeet;

/// Channels per frame of the `duet` training representation.
pub const PAIR_DIMS: usize = DuetFollower::DIMS + DuetLeader::DIMS;

/// The follower part `[B, W, 151]` of a training window.
pub fn follower(motion: &Tensor<3>) -> Tensor<3> {
    motion.clone().narrow(2, 0, DuetFollower::DIMS)
}

/// The leader and music of windows, grouped per latent token.
pub fn cond_tokens(motion: &Tensor<3>, music: &Tensor<3>, f: usize) -> DuetCond {
    let [b, w, _] = motion.dims();
    let n = w / f;
    let leader = motion
        .clone()
        .narrow(2, DuetFollower::DIMS, DuetLeader::DIMS)
        .narrow(1, 0, n * f)
        .reshape([b, n, f * DuetLeader::DIMS]);
    let md = music.dims()[2];
    let music = music.clone().narrow(1, 0, n * f).reshape([b, n, f * md]);
    DuetCond { leader, music }
}

/// Named loss parts.
pub struct LdmLosses {
    pub total: Tensor<1>,
    pub parts: Vec<(&'static str, Tensor<1>)>,
}

fn rows(x: &Tensor<3>, idx: &[usize], device: &Device) -> Tensor<3> {
    let i: Vec<i64> = idx.iter().map(|&i| i as i64).collect();
    let n = i.len();
    x.clone().select(
        0,
        Tensor::<1, Int>::from_data(TensorData::new(i, [n]), device),
    )
}

/// Stage-2 loss (see the module documentation). `ae_target` runs on the inference device (no
/// masking, no graph), `ae_decode` on the training device with its parameters frozen.
#[allow(clippy::too_many_arguments)]
pub fn ldm_loss(
    net: &LatentDenoiser,
    ae_target: &HfsqAutoencoder,
    ae_decode: &HfsqAutoencoder,
    motion: Tensor<3>,
    music: Tensor<3>,
    schedule: &Schedule,
    weights: &LatentLossWeights,
    down_t: usize,
    seed: u64,
    feet: Option<&FollowerFeet>,
) -> LdmLosses {
    let device = motion.device();
    let f = frames_per_token(down_t);
    let [b, w, _] = motion.dims();
    let n = w / f;
    let x = follower(&motion).narrow(1, 0, n * f);
    let infer = dancegen_nn::device::inference();
    let z0 = ae_target
        .encode(x.clone().detach().to_device(&infer))
        .to_device(&device)
        .detach();
    let c_dim = z0.dims()[2];
    let levels = ae_target.num_levels;
    let level_dim = c_dim / levels;
    let cond = cond_tokens(&motion, &music, f);

    let mut rng = SplitMix64(seed);
    let big_t = schedule.timesteps();
    let t: Vec<usize> = (0..b).map(|_| rng.below(big_t)).collect();
    let noise = SeededNoise::new(rng.next_u64()).tensor([b, n, c_dim], &device);
    let x_t = schedule.q_sample(z0.clone(), &t, noise);
    let keep: Vec<Vec<bool>> = (0..b)
        .map(|_| {
            (0..levels)
                .map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 >= weights.cond_drop)
                .collect()
        })
        .collect();

    // Rows of the doubled batch: each window with the condition if any level keeps it, and
    // without it if any level drops it.
    let mut idx = Vec::new();
    let mut row_keep = Vec::new();
    let (mut pos_cond, mut pos_null) = (vec![usize::MAX; b], vec![usize::MAX; b]);
    for (i, k) in keep.iter().enumerate() {
        if k.iter().any(|&k| k) {
            pos_cond[i] = idx.len();
            idx.push(i);
            row_keep.push(true);
        }
        if k.iter().any(|&k| !k) {
            pos_null[i] = idx.len();
            idx.push(i);
            row_keep.push(false);
        }
    }
    let t_cat: Vec<f32> = idx.iter().map(|&i| t[i] as f32).collect();
    let cond_cat = DuetCond {
        leader: rows(&cond.leader, &idx, &device),
        music: rows(&cond.music, &idx, &device),
    };
    let pred = net.forward(
        rows(&x_t, &idx, &device),
        &t_cat,
        &cond_cat,
        &row_keep,
        Layout::Batched,
    );
    let target = rows(&z0, &idx, &device);

    // Per-row, per-channel weights: λ_r where the row is the branch level r asked for.
    let mut wv = vec![0f32; idx.len() * c_dim];
    for (row, (&i, &rk)) in idx.iter().zip(&row_keep).enumerate() {
        for r in 0..levels {
            if keep[i][r] == rk {
                let lam = weights.level(r) as f32;
                wv[row * c_dim + r * level_dim..row * c_dim + (r + 1) * level_dim].fill(lam);
            }
        }
    }
    let wt = Tensor::<3>::from_data(TensorData::new(wv, [idx.len(), 1, c_dim]), &device);
    let diff = pred.clone() - target;
    let latent = (diff.clone() * diff * wt).sum() / ((b * n * c_dim) as f64);

    // The prediction each window's levels asked for, decoded.
    let pick = |pos: &[usize], other: &[usize]| -> Vec<usize> {
        pos.iter()
            .zip(other)
            .map(|(&p, &o)| if p == usize::MAX { o } else { p })
            .collect()
    };
    let kc = pick(&pos_cond, &pos_null);
    let kn = pick(&pos_null, &pos_cond);
    let mut mv = vec![0f32; b * c_dim];
    for (i, k) in keep.iter().enumerate() {
        for (r, &kr) in k.iter().enumerate() {
            if kr {
                mv[i * c_dim + r * level_dim..i * c_dim + (r + 1) * level_dim].fill(1.0);
            }
        }
    }
    let m = Tensor::<3>::from_data(TensorData::new(mv, [b, 1, c_dim]), &device);
    let eff = rows(&pred, &kc, &device) * m.clone() + rows(&pred, &kn, &device) * (m.neg() + 1.0);
    let decoded = ae_decode.decode(eff);
    let kinematic = dancegen_nn::loss::reconstruction(
        decoded.clone(),
        x.clone(),
        dancegen_nn::loss::Distance::L1,
    ) + dancegen_nn::loss::velocity(
        decoded.clone(),
        x.clone(),
        dancegen_nn::loss::Distance::L1,
    );
    let rr = DuetFollower::ROOT_ROT;
    let rel_orient = (decoded.clone().narrow(2, rr.start, rr.len())
        - x.clone().narrow(2, rr.start, rr.len()))
    .abs()
    .mean();
    let foot = foot_contact_loss(&decoded, &x);

    let mut total = latent.clone()
        + kinematic.clone() * weights.kinematic
        + rel_orient.clone() * weights.relative_orientation
        + foot.clone() * weights.foot_contact;
    let mut parts = vec![
        ("latent", latent),
        ("kinematic", kinematic),
        ("relative_orientation", rel_orient),
        ("foot_contact", foot),
    ];
    if let Some(feet) = feet.filter(|_| weights.foot_velocity > 0.0) {
        let fps = dancegen_motion::conventions::CANONICAL_FPS;
        let l = feet.velocity_loss(decoded, x, fps);
        total = total + l.clone() * weights.foot_velocity;
        parts.push(("foot_velocity", l));
    }
    LdmLosses { total, parts }
}

/// Velocity of the decoded lower-body rotations and relative root position on the real
/// follower's planted frames (see the module documentation).
fn foot_contact_loss(decoded: &Tensor<3>, real: &Tensor<3>) -> Tensor<1> {
    let c = DuetFollower::CONTACTS;
    let contacts = real.clone().narrow(2, c.start, c.len()).detach();
    let lo = contacts.clone().min_dim(1).min_dim(0);
    let hi = contacts.clone().max_dim(1).max_dim(0);
    let mid = (lo.clone() + hi.clone()) / 2.0;
    let spread = (hi - lo).greater_elem(1e-3).float();
    // 1 where a foot is planted (any of the four), per frame `[B, T, 1]`.
    let dims = contacts.dims();
    let planted = (contacts.greater(mid.expand(dims)).float() * spread).max_dim(2);
    let lr = DuetFollower::LOWER_ROT;
    let rp = DuetFollower::ROOT_POS;
    let legs = Tensor::cat(
        vec![
            decoded.clone().narrow(2, lr.start, lr.len()),
            decoded.clone().narrow(2, rp.start, rp.len()),
        ],
        2,
    );
    let t = legs.dims()[1];
    let vel = legs.clone().narrow(1, 1, t - 1) - legs.narrow(1, 0, t - 1);
    let w = planted.narrow(1, 0, t - 1);
    let denom = w.clone().sum() + 1.0;
    (vel.abs() * w).sum() / denom
}
