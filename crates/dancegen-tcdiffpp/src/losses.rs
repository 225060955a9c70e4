//! The training objective (paper §4.3, Eq. 12–18) with formation-control injection.
//!
//! `L = λ_sim L_simple + λ_vel L_vel + λ_FK L_FK + λ_con L_con + λ_D L_D`, all over the active
//! slots only:
//! - `L_simple`: x̂0 against x0 (L2, EDGE `p_losses`);
//! - `L_vel`: frame differences of x̂0 against x0's (EDGE: every channel; the released
//!   TCDiff++ keeps only the rotations, group.md §1 row 8);
//! - `L_FK`: world joints of both (EDGE FK on the absolute root, as TCDiff++ does);
//! - `L_con`: foot-joint velocity where the network's own contact label is above 0.95 (EDGE
//!   `foot_loss`);
//! - `L_D`, Eq. 16–17: for every pair of dancers, the change of their relative root position
//!   `(p_i − p_j) − (p̂_i − p̂_j)`, squared, summed over pairs, divided by `C − 1`, averaged
//!   over frames. The released `dis_loss` (×100) is a per-dancer temporal Δroot error instead,
//!   not pairwise (group.md §1 row 8); we implement the paper's, and the released one as its
//!   own term `λ_rootvel L_rootvel` (`[model.loss] root_velocity`, 0 by default);
//! - ours, 0 by default: `λ_leg L_leg`, [`leg_crossing`] on x̂0's joints (`[model.loss]
//!   leg_crossing`).
//!
//! Cued frames (ours, [`TrainingConfig::cued_frames`], off by default): some windows get a
//! prefix or their ends clean in x_t, as the window-by-window sampler and edits give them.
//!
//! Formation control (issue #17, group.md §1 row 12 "Proposal"): with probability
//! `1 − control_drop` a window trains controlled — each active dancer, with probability
//! [`CONTROL_DANCER_PROB`], has its clean root x/y written into `x_t` (and the control flag
//! set) on the whole window or, half of the time, on one random span of at least half of it;
//! otherwise nothing is injected. One model thus learns free dances, fully controlled ones and
//! partly controlled ones (dancers or times left free in a FORMATION.json).

use dancegen_nn::burn;
use dancegen_nn::diffusion::Schedule;
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_nn::edge151::{CONTACTS, DIMS, FEET, ROOT_HORIZONTAL, displacement, joints};
use dancegen_nn::loss::{FkSkeleton, leg_crossing};

use burn::tensor::{Device, Tensor, TensorData};

use crate::config::{LossWeights, TrainingConfig};
use crate::denoiser::{GroupCond, GroupDenoiser};
use crate::layout::{GROUP_DIMS, N_MAX, channel, from_tokens, to_tokens};

/// EDGE's contact threshold on the predicted label (`foot_loss`: `model_contact > 0.95`).
pub const CONTACT_THRESHOLD: f64 = 0.95;
/// Share of the active dancers of a controlled window whose root path is given (our choice).
pub const CONTROL_DANCER_PROB: f64 = 0.8;

/// One batch of group windows.
#[derive(Clone, Debug)]
pub struct GroupBatch {
    /// Normalised windows `[B, T, N_MAX·151]` (slots sorted, roots centroid-relative, empty
    /// slots zero).
    pub x0: Tensor<3>,
    /// `[B, T, 35]`.
    pub music: Tensor<3>,
    pub dancers: Vec<usize>,
    /// Swap codes `[B, N_MAX²]`.
    pub swap: Tensor<2>,
}

/// Named loss terms; `total` is the weighted sum.
pub struct GroupLosses {
    pub total: Tensor<1>,
    pub parts: Vec<(&'static str, Tensor<1>)>,
}

/// 1 on the channels of active slots, `[B, 1, N_MAX·151]`.
pub fn channel_mask(dancers: &[usize], device: &Device) -> Tensor<3> {
    let b = dancers.len();
    let mut m = Vec::with_capacity(b * GROUP_DIMS);
    for &n in dancers {
        m.extend((0..GROUP_DIMS).map(|c| f32::from(u8::from(c / DIMS < n))));
    }
    Tensor::from_data(TensorData::new(m, [b, 1, GROUP_DIMS]), device)
}

/// The released code's `dis_loss`: the frame-to-frame change of every slot's root x/y in
/// `pred` against `x0`'s (`[B, T, N_MAX·151]`, inactive slots zero in both), squared and
/// averaged over the `active` dancers' root channels and the frame pairs.
pub fn root_velocity(pred: Tensor<3>, x0: Tensor<3>, active: usize) -> Tensor<1> {
    let [_, t, _] = pred.dims();
    let device = pred.device();
    let m: Vec<f32> = (0..GROUP_DIMS)
        .map(|c| f32::from(u8::from(ROOT_HORIZONTAL.contains(&(c % DIMS)))))
        .collect();
    let mask = Tensor::<3>::from_data(TensorData::new(m, [1, 1, GROUP_DIMS]), &device);
    let vel = |x: Tensor<3>| x.clone().narrow(1, 1, t - 1) - x.narrow(1, 0, t - 1);
    ((vel(pred) - vel(x0)) * mask).powf_scalar(2.0).sum()
        / (active * ROOT_HORIZONTAL.len() * (t - 1)) as f64
}

/// `min(1 + SNR_t, cap)` per window ([`LossWeights::simple_snr_cap`]), `SNR = ᾱ / (1 − ᾱ)`.
pub fn snr_weights(schedule: &Schedule, steps: &[usize], cap: f64) -> Vec<f32> {
    steps
        .iter()
        .map(|&t| {
            let a = schedule.alphas_cumprod[t];
            (1.0 / (1.0 - a).max(f64::MIN_POSITIVE)).min(cap) as f32
        })
        .collect()
}

/// Which (frame, slot) roots a training window gets clean: `[B·T·N_MAX]` flags.
fn draw_control(dancers: &[usize], t: usize, drop: f64, rng: &mut SeededNoise) -> Vec<f32> {
    let mut c = vec![0f32; dancers.len() * t * N_MAX];
    for (b, &n) in dancers.iter().enumerate() {
        if rng.uniform() < drop {
            continue;
        }
        for s in 0..n {
            if rng.uniform() >= CONTROL_DANCER_PROB {
                continue;
            }
            let span = if rng.uniform() < 0.5 || t < 2 {
                0..t
            } else {
                let len = t.div_ceil(2) + rng.below(t / 2 + 1).min(t - t.div_ceil(2));
                let start = rng.below(t - len + 1);
                start..start + len
            };
            for f in span {
                c[(b * t + f) * N_MAX + s] = 1.0;
            }
        }
    }
    c
}

/// Per window and frame (`[B, T]`, flat), 1 where the frame is given clean in x_t
/// ([`TrainingConfig::cued_frames`]): with probability `share` a window gets, with equal odds,
/// its first half (an LGDS prefix), its first `k` frames, its last `k` frames, or both (an
/// edit's kept frames around a regenerated range), `k` uniform in `T/10..=T/2`.
pub fn draw_cued_frames(b: usize, t: usize, share: f64, rng: &mut SeededNoise) -> Vec<f32> {
    let mut c = vec![0f32; b * t];
    if t < 4 {
        return c;
    }
    for w in 0..b {
        if rng.uniform() >= share {
            continue;
        }
        let lo = (t / 10).max(1);
        let k = lo + rng.below(t / 2 - lo + 1);
        let (head, tail) = match rng.below(4) {
            0 => (t / 2, 0),
            1 => (k, 0),
            2 => (0, k),
            _ => (k.min(t / 3), k.min(t / 3)),
        };
        for f in (0..head).chain(t - tail..t) {
            c[w * t + f] = 1.0;
        }
    }
    c
}

/// The control flags as `[B, T, N_MAX]` and as a channel mask over the root x/y of
/// `[B, T, N_MAX·151]`.
pub fn control_tensors(
    flags: &[f32],
    b: usize,
    t: usize,
    device: &Device,
) -> (Tensor<3>, Tensor<3>) {
    let mut cm = vec![0f32; b * t * GROUP_DIMS];
    for (i, &f) in flags.iter().enumerate() {
        if f > 0.0 {
            let (bt, s) = (i / N_MAX, i % N_MAX);
            for &ch in &ROOT_HORIZONTAL {
                cm[bt * GROUP_DIMS + channel(s, ch)] = 1.0;
            }
        }
    }
    (
        Tensor::from_data(TensorData::new(flags.to_vec(), [b, t, N_MAX]), device),
        Tensor::from_data(TensorData::new(cm, [b, t, GROUP_DIMS]), device),
    )
}

/// One training batch; `seed` draws timesteps, noise, music dropout and control.
pub fn group_loss(
    net: &GroupDenoiser,
    schedule: &Schedule,
    batch: &GroupBatch,
    weights: &LossWeights,
    training: &TrainingConfig,
    seed: u64,
) -> GroupLosses {
    let [b, t, _] = batch.x0.dims();
    let device = batch.x0.device();
    let mut rng = SeededNoise::new(seed);
    let chmask = channel_mask(&batch.dancers, &device);
    let x0 = batch.x0.clone() * chmask.clone();

    let flags = draw_control(&batch.dancers, t, training.control_drop, &mut rng);
    let (control, cmask) = control_tensors(&flags, b, t, &device);
    let steps: Vec<usize> = (0..b).map(|_| rng.below(schedule.timesteps())).collect();
    let keep: Vec<bool> = (0..b)
        .map(|_| rng.uniform() >= training.cond_drop)
        .collect();
    let noise = rng.tensor([b, t, GROUP_DIMS], &device);
    let x_t = schedule.q_sample(x0.clone(), &steps, noise) * chmask.clone();
    let cmask = if training.cued_frames > 0.0 {
        let cued = draw_cued_frames(b, t, training.cued_frames, &mut rng);
        let cued = Tensor::<3>::from_data(TensorData::new(cued, [b, t, 1]), &device);
        (cmask + cued).clamp(0.0, 1.0) * chmask.clone()
    } else {
        cmask
    };
    let x_t = x0.clone() * cmask.clone() + x_t * (cmask.neg() + 1.0);
    let cond = GroupCond {
        music: batch.music.clone(),
        dancers: batch.dancers.clone(),
        swap: batch.swap.clone(),
        control,
    };
    let tf: Vec<f32> = steps.iter().map(|&s| s as f32).collect();
    let pred = net.forward(x_t, &tf, &cond, &keep) * chmask.clone();

    // Normalisers of the masked means: active values per frame.
    let active: usize = batch.dancers.iter().sum();
    let per_frame = (active * DIMS) as f64;
    let sq = (pred.clone() - x0.clone()).powf_scalar(2.0);
    let simple = if weights.simple_snr_cap > 0.0 {
        let w = snr_weights(schedule, &steps, weights.simple_snr_cap);
        let w = Tensor::<3>::from_data(TensorData::new(w, [b, 1, 1]), &device);
        (sq.sum_dim(2).sum_dim(1) * w).sum() / (per_frame * t as f64)
    } else {
        sq.sum() / (per_frame * t as f64)
    };
    let vel = |x: Tensor<3>| x.clone().narrow(1, 1, t - 1) - x.narrow(1, 0, t - 1);
    let velocity =
        (vel(pred.clone()) - vel(x0.clone())).powf_scalar(2.0).sum() / (per_frame * (t - 1) as f64);
    let root_velocity = root_velocity(pred.clone(), x0.clone(), active);

    let skel = FkSkeleton::smpl24();
    // Empty slots get the rest pose before FK: a zero 6D vector has no direction, and the
    // gradient of its normalisation is infinite (∞ · 0 mask = NaN in every weight).
    let slot_mask = crate::layout::token_mask(&batch.dancers, t, &device);
    let rest = rest_pose(&device);
    let valid =
        |raw: Tensor<3>| raw * slot_mask.clone() + rest.clone() * (slot_mask.clone().neg() + 1.0);
    let raw_pred = valid(net.denorm.apply(to_tokens(pred.clone())));
    let raw_gt = valid(net.denorm.apply(to_tokens(x0.clone())));
    let jp = joints(raw_pred.clone(), &skel); // [B, T·N, 24, 3]
    let jg = joints(raw_gt.clone(), &skel);
    let tok_mask = slot_mask.unsqueeze_dim::<4>(3);
    let joint_count = (active * t * 24 * 3) as f64;
    let fk = ((jp.clone() - jg) * tok_mask.clone())
        .powf_scalar(2.0)
        .sum()
        / joint_count;

    let [bt, k, _, _] = jp.dims();
    let crossing = (leg_crossing(jp.clone()).reshape([bt, k, 1, 1]) * tok_mask.clone()).sum()
        / (active * t) as f64;

    // Foot velocity where the network predicts contact (per dancer, along frames).
    let per_dancer = |j: Tensor<4>| j.reshape([b, t, N_MAX * 24, 3]);
    let foot_v = displacement(per_dancer(jp)).reshape([b, t * N_MAX, 24, 3]);
    let feet = Tensor::cat(
        FEET.iter()
            .map(|&f| foot_v.clone().narrow(2, f, 1))
            .collect(),
        2,
    ); // [B, T·N, 4, 3]
    let static_feet = raw_pred
        .clone()
        .narrow(2, CONTACTS.start, CONTACTS.len())
        .detach()
        .greater_elem(CONTACT_THRESHOLD)
        .float()
        .unsqueeze_dim::<4>(3);
    let contact =
        (feet * static_feet * tok_mask).powf_scalar(2.0).sum() / (active * t * 4 * 3) as f64;

    let distance = distance_consistency(from_tokens(raw_pred), from_tokens(raw_gt), &batch.dancers);

    let total = simple.clone() * weights.simple
        + velocity.clone() * weights.velocity
        + fk.clone() * weights.fk
        + contact.clone() * weights.contact
        + distance.clone() * weights.distance
        + root_velocity.clone() * weights.root_velocity
        + crossing.clone() * weights.leg_crossing;
    GroupLosses {
        total,
        parts: vec![
            ("simple", simple),
            ("velocity", velocity),
            ("fk", fk),
            ("contact", contact),
            ("distance", distance),
            ("root_velocity", root_velocity),
            ("leg_crossing", crossing),
        ],
    }
}

/// One EDGE-151 frame at the origin in the rest pose (identity 6D per joint), `[1, 1, 151]`.
fn rest_pose(device: &Device) -> Tensor<3> {
    let mut v = vec![0f32; DIMS];
    for j in 0..24 {
        v[dancegen_nn::edge151::rot6d(j, 0)] = 1.0;
        v[dancegen_nn::edge151::rot6d(j, 4)] = 1.0;
    }
    Tensor::<1>::from_data(TensorData::new(v, [DIMS]), device).reshape([1, 1, DIMS])
}

/// Eq. 16–17 on raw windows `[B, T, N_MAX·151]` (roots in metres): per element, the sum over
/// active pairs `i < j` of `‖(p_i − p_j) − (p̂_i − p̂_j)‖²` divided by `C − 1`, averaged over
/// frames and elements.
pub fn distance_consistency(pred: Tensor<3>, gt: Tensor<3>, dancers: &[usize]) -> Tensor<1> {
    let [b, t, _] = pred.dims();
    let device = pred.device();
    let root = |x: &Tensor<3>, s: usize| x.clone().narrow(2, channel(s, ROOT_HORIZONTAL[0]), 2);
    let mut total: Option<Tensor<1>> = None;
    for i in 0..N_MAX {
        for j in i + 1..N_MAX {
            let w: Vec<f32> = dancers
                .iter()
                .map(|&n| if j < n { 1.0 / (n - 1) as f32 } else { 0.0 })
                .collect();
            if w.iter().all(|&v| v == 0.0) {
                continue;
            }
            let w = Tensor::<1>::from_data(TensorData::new(w, [b]), &device).reshape([b, 1, 1]);
            let d = (root(&gt, i) - root(&gt, j)) - (root(&pred, i) - root(&pred, j));
            let term = (d.powf_scalar(2.0) * w).sum() / (b * t) as f64;
            total = Some(match total {
                Some(acc) => acc + term,
                None => term,
            });
        }
    }
    total.unwrap_or_else(|| Tensor::zeros([1], &device))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cued_frames_are_a_prefix_or_the_ends_of_some_windows() {
        let (b, t) = (400, 150);
        let mut rng = SeededNoise::new(5);
        let c = draw_cued_frames(b, t, 0.5, &mut rng);
        let mut cued_windows = 0;
        for w in 0..b {
            let row = &c[w * t..(w + 1) * t];
            let head = row.iter().take_while(|&&v| v > 0.0).count();
            let tail = row.iter().rev().take_while(|&&v| v > 0.0).count();
            let total = row.iter().filter(|&&v| v > 0.0).count();
            assert!(
                head + tail >= total && head <= t / 2 && tail <= t / 2,
                "window {w}"
            );
            cued_windows += usize::from(total > 0);
        }
        assert!((150..250).contains(&cued_windows), "{cued_windows} of {b}");
        assert!(
            draw_cued_frames(3, t, 0.0, &mut rng)
                .iter()
                .all(|&v| v == 0.0)
        );
    }

    #[test]
    fn snr_weights_are_one_at_pure_noise_and_capped_near_the_data() {
        let s = Schedule::edge();
        let w = snr_weights(&s, &[999, 500, 0], 6.0);
        assert!((w[0] - 1.0).abs() < 1e-3, "{w:?}");
        // Half way through the cosine schedule ᾱ ≈ 0.5: 1 + SNR ≈ 2.
        assert!(w[1] > 1.5 && w[1] < 2.5, "{w:?}");
        assert_eq!(w[2], 6.0);
    }
}
