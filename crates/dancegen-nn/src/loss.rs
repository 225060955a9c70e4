//! Training losses shared by the systems.
//!
//! - [`reconstruction`] (L1 / L2 / smooth-L1), [`velocity`], [`acceleration`] on `[B, T, C]`
//!   sequences (EDGE/Lodge `L_simple`, `L_vel`; T2M-GPT/MoMask velocity loss).
//! - [`rot6d_to_matrix`] + [`forward_kinematics`]: a differentiable FK for the FK-position losses
//!   (EDGE `L_FK`, Lodge's root-relative variant), using the skeleton constants of
//!   `dancegen-motion` (one source of truth for offsets and parents).
//! - [`foot_contact`]: EDGE's foot loss, velocity of the foot joints on frames where the model's
//!   own predicted contact exceeds 0.95.
//! - [`leg_crossing`]: ours, a hinge on shins that touch or swap sides (the crossed shins the
//!   physical metrics count, `dancegen_metrics::physical::shins_crossed`).
//! - [`commitment`]: VQ commitment `‖z_e − sg(z_q)‖²`.
//! - [`info_nce`]: symmetric InfoNCE over a batch of paired embeddings (SoulNet's music–motion
//!   retrieval); [`info_nce_filtered`] leaves near-duplicate negatives out (TMR's filtering).
//! - [`hinge_discriminator`] / [`hinge_generator`]: hinge GAN (Lodge's genre discriminator).

use burn::tensor::activation::{log_softmax, relu};
use burn::tensor::{Device, Int, Tensor, TensorData};

/// Element-wise distance of [`reconstruction`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Distance {
    L1,
    L2,
    /// Huber with δ = 1 (PyTorch `smooth_l1_loss`).
    SmoothL1,
}

fn distance<const D: usize>(a: Tensor<D>, b: Tensor<D>, kind: Distance) -> Tensor<1> {
    let d = a - b;
    match kind {
        Distance::L1 => d.abs().mean(),
        Distance::L2 => d.powf_scalar(2.0).mean(),
        Distance::SmoothL1 => {
            let abs = d.abs();
            let small = abs.clone().lower_elem(1.0);
            let quad = abs.clone().powf_scalar(2.0) * 0.5;
            let lin = abs - 0.5;
            lin.mask_where(small, quad).mean()
        }
    }
}

/// Mean distance between prediction and target.
pub fn reconstruction<const D: usize>(
    pred: Tensor<D>,
    target: Tensor<D>,
    kind: Distance,
) -> Tensor<1> {
    distance(pred, target, kind)
}

fn diff(x: Tensor<3>) -> Tensor<3> {
    let t = x.dims()[1];
    x.clone().narrow(1, 1, t - 1) - x.narrow(1, 0, t - 1)
}

/// Distance between the first differences in time of `[B, T, C]` sequences.
pub fn velocity(pred: Tensor<3>, target: Tensor<3>, kind: Distance) -> Tensor<1> {
    distance(diff(pred), diff(target), kind)
}

/// Distance between the second differences in time.
pub fn acceleration(pred: Tensor<3>, target: Tensor<3>, kind: Distance) -> Tensor<1> {
    distance(diff(diff(pred)), diff(diff(target)), kind)
}

/// pytorch3d `rotation_6d_to_matrix`: `[..., 6]` (the first two **rows**) → `[..., 3, 3]` by
/// Gram–Schmidt, rows `b1, b2, b1 × b2`. Input `[N, 6]`, output `[N, 3, 3]`.
pub fn rot6d_to_matrix(d6: Tensor<2>) -> Tensor<3> {
    let n = d6.dims()[0];
    let a1 = d6.clone().narrow(1, 0, 3);
    let a2 = d6.narrow(1, 3, 3);
    let normalize = |v: Tensor<2>| {
        let norm = v
            .clone()
            .powf_scalar(2.0)
            .sum_dim(1)
            .sqrt()
            .clamp_min(1e-12);
        v / norm
    };
    let b1 = normalize(a1);
    let proj = (b1.clone() * a2.clone()).sum_dim(1);
    let b2 = normalize(a2 - b1.clone() * proj);
    let b3 = cross(b1.clone(), b2.clone());
    Tensor::stack::<3>(vec![b1, b2, b3], 1).reshape([n, 3, 3])
}

fn cross(a: Tensor<2>, b: Tensor<2>) -> Tensor<2> {
    let c = |t: &Tensor<2>, i: usize| t.clone().narrow(1, i, 1);
    Tensor::cat(
        vec![
            c(&a, 1) * c(&b, 2) - c(&a, 2) * c(&b, 1),
            c(&a, 2) * c(&b, 0) - c(&a, 0) * c(&b, 2),
            c(&a, 0) * c(&b, 1) - c(&a, 1) * c(&b, 0),
        ],
        1,
    )
}

/// A skeleton as FK needs it: parent of each joint (topological order, root first) and
/// parent-relative rest offsets in metres.
#[derive(Clone, Debug)]
pub struct FkSkeleton {
    pub parents: Vec<Option<usize>>,
    pub offsets: Vec<[f64; 3]>,
}

impl FkSkeleton {
    /// The SMPL 24-joint body of `dancegen-motion` (EDGE's offsets, anchors C.4).
    pub fn smpl24() -> Self {
        let s = dancegen_motion::skeleton::Skeleton::smpl24();
        FkSkeleton {
            parents: s.parents().to_vec(),
            offsets: s.offsets().to_vec(),
        }
    }
}

/// World joint positions `[N, J, 3]` from local rotation matrices `[N, J, 3, 3]` (column-vector
/// convention, parent-relative) and root positions `[N, 3]`.
pub fn forward_kinematics(
    rotations: Tensor<4>,
    root: Tensor<2>,
    skeleton: &FkSkeleton,
) -> Tensor<3> {
    let [n, j, _, _] = rotations.dims();
    assert_eq!(j, skeleton.parents.len(), "FK: joint count");
    let device = rotations.device();
    let mut world_rot: Vec<Tensor<3>> = Vec::with_capacity(j);
    let mut world_pos: Vec<Tensor<2>> = Vec::with_capacity(j);
    for k in 0..j {
        let local = rotations.clone().narrow(1, k, 1).reshape([n, 3, 3]);
        match skeleton.parents[k] {
            None => {
                world_rot.push(local);
                world_pos.push(root.clone());
            }
            Some(p) => {
                let o = skeleton.offsets[k];
                let off = Tensor::<1>::from_data(
                    TensorData::new(vec![o[0] as f32, o[1] as f32, o[2] as f32], [3]),
                    &device,
                )
                .reshape([1, 3, 1]);
                let moved = small_matmul(world_rot[p].clone(), off.expand([n, 3, 1]));
                world_pos.push(world_pos[p].clone() + moved.reshape([n, 3]));
                world_rot.push(small_matmul(world_rot[p].clone(), local));
            }
        }
    }
    Tensor::stack::<3>(world_pos, 1)
}

/// `a @ b` for batches of tiny matrices `[N, I, K] × [N, K, J]` as broadcast multiply + sum:
/// a batched GEMM pays a kernel call per 3×3 product, which made FK of a few thousand frames
/// (and its backward) take seconds.
fn small_matmul(a: Tensor<3>, b: Tensor<3>) -> Tensor<3> {
    let [n, i, k] = a.dims();
    let j = b.dims()[2];
    (a.reshape([n, i, k, 1]) * b.reshape([n, 1, k, j]))
        .sum_dim(2)
        .reshape([n, i, j])
}

/// EDGE's foot loss: the squared velocity of foot joints `[B, T, F, 3]` on frames where the
/// predicted contact `[B, T, F]` is above `threshold` (0.95 in EDGE), averaged over all entries.
pub fn foot_contact(feet: Tensor<4>, contact: Tensor<3>, threshold: f64) -> Tensor<1> {
    let [b, t, f, _] = feet.dims();
    let vel = feet.clone().narrow(1, 1, t - 1) - feet.narrow(1, 0, t - 1);
    let on = contact
        .narrow(1, 0, t - 1)
        .greater_elem(threshold)
        .float()
        .reshape([b, t - 1, f, 1]);
    (vel * on).powf_scalar(2.0).mean()
}

/// SMPL-24 joints of the legs: left and right hip, knee, ankle.
const LEG_JOINTS: [[usize; 3]; 2] = [[1, 4, 7], [2, 5, 8]];

/// Centre-line distance under which [`leg_crossing`] pushes the shins apart, metres: a little
/// more than two shin radii (0.05 m, `dancegen_motion::capsule_body`), so shins are kept from
/// touching rather than only from sinking into each other, which the metric counts.
pub const SHIN_CLEARANCE_M: f64 = 0.08;

/// Ours, not a paper's: per pose, a penalty on crossed shins, `[B, T]` from world joints
/// `[B, T, 24, 3]` (Z-up, metres). Two hinges, on the two tests of the physical metrics' crossed
/// shins:
/// - shins too close: `Σ relu(SHIN_CLEARANCE_M − d)²` over the 9 pairs of points at the
///   knee, the middle and the ankle of each shin;
/// - legs swapped: along the horizontal hip axis (right hip → left hip), `relu(−knee gap) ·
///   relu(−ankle gap)`, non-zero only where both the knees and the ankles are on the wrong
///   side. An ankle alone crossing over is a dance step (a cross-body step) and costs nothing.
pub fn leg_crossing(joints: Tensor<4>) -> Tensor<2> {
    let [b, t, _, _] = joints.dims();
    let joint = |j: usize| joints.clone().narrow(2, j, 1).reshape([b, t, 3]);
    let [[lh, lk, la], [rh, rk, ra]] = LEG_JOINTS.map(|leg| leg.map(joint));
    let points = |knee: &Tensor<3>, ankle: &Tensor<3>| {
        [0.0, 0.5, 1.0].map(|a| knee.clone() * (1.0 - a) + ankle.clone() * a)
    };
    let (left, right) = (points(&lk, &la), points(&rk, &ra));
    let mut close = Tensor::<2>::zeros([b, t], &joints.device());
    for l in &left {
        for r in &right {
            let d = (l.clone() - r.clone())
                .powf_scalar(2.0)
                .sum_dim(2)
                .reshape([b, t]);
            let d = (d + 1e-10).sqrt();
            close = close + relu(d.neg() + SHIN_CLEARANCE_M).powf_scalar(2.0);
        }
    }
    let horizontal = |v: Tensor<3>| v.narrow(2, 0, 2);
    let axis = horizontal(lh - rh);
    let axis = axis.clone() / (axis.powf_scalar(2.0).sum_dim(2) + 1e-10).sqrt();
    let gap = |l: Tensor<3>, r: Tensor<3>| {
        (horizontal(l - r) * axis.clone())
            .sum_dim(2)
            .reshape([b, t])
    };
    let swapped = relu(gap(lk, rk).neg()) * relu(gap(la, ra).neg());
    close + swapped
}

/// VQ commitment loss `mean((z_e − sg(z_q))²)`.
pub fn commitment<const D: usize>(encoded: Tensor<D>, quantized: Tensor<D>) -> Tensor<1> {
    (encoded - quantized.detach()).powf_scalar(2.0).mean()
}

/// Cosine-similarity logits `[N, N]` of `a`, `b` `[N, d]`, divided by `temperature`.
fn cosine_logits(a: Tensor<2>, b: Tensor<2>, temperature: f64) -> Tensor<2> {
    let norm = |v: Tensor<2>| {
        let l = v
            .clone()
            .powf_scalar(2.0)
            .sum_dim(1)
            .sqrt()
            .clamp_min(1e-12);
        v / l
    };
    norm(a).matmul(norm(b).transpose()) / temperature
}

/// Cross-entropy of the diagonal of `[N, N]` logits, rows then columns, averaged.
fn symmetric_diagonal_ce(logits: Tensor<2>) -> Tensor<1> {
    let n = logits.dims()[0];
    let device: Device = logits.device();
    let diag = Tensor::<1, Int>::arange(0..n as i64, &device).reshape([n, 1]);
    let ce = |l: Tensor<2>| -> Tensor<1> { log_softmax(l, 1).gather(1, diag.clone()).mean().neg() };
    (ce(logits.clone()) + ce(logits.transpose())) / 2.0
}

/// Symmetric InfoNCE of paired embeddings `a`, `b` `[N, d]` (row `i` of each is a positive
/// pair): cross-entropy of the cosine-similarity logits `/ temperature` in both directions.
pub fn info_nce(a: Tensor<2>, b: Tensor<2>, temperature: f64) -> Tensor<1> {
    symmetric_diagonal_ce(cosine_logits(a, b, temperature))
}

/// [`info_nce`] with TMR's negative filtering (`InfoNCE_with_filtering`, which SoulNet's MMR
/// describes with threshold 0.8 but never enables — `holistic.md` §1.4): a negative `j` of
/// query `i` is left out of both softmaxes when `pair_similarity[i, j] > threshold` (`i ≠ j`),
/// so near-duplicate conditions (two cuts of the same song, say) are not pushed apart.
/// `pair_similarity` `[N, N]` is the similarity of the pairs' conditioning (e.g. cosine of the
/// music features); the diagonal is never filtered.
pub fn info_nce_filtered(
    a: Tensor<2>,
    b: Tensor<2>,
    temperature: f64,
    pair_similarity: Tensor<2>,
    threshold: f64,
) -> Tensor<1> {
    let n = a.dims()[0];
    let logits = cosine_logits(a, b, temperature);
    let eye = Tensor::<2>::eye(n, &logits.device()).bool();
    let drop = pair_similarity
        .greater_elem(threshold)
        .bool_and(eye.bool_not());
    // A large negative rather than −∞: exp underflows to 0 without NaN gradients.
    symmetric_diagonal_ce(logits.mask_fill(drop, -1e9))
}

/// Hinge loss of the discriminator: `mean(relu(1 − D(real))) + mean(relu(1 + D(fake)))`.
pub fn hinge_discriminator(real: Tensor<2>, fake: Tensor<2>) -> Tensor<1> {
    relu(real.neg() + 1.0).mean() + relu(fake + 1.0).mean()
}

/// Hinge loss of the generator: `−mean(D(fake))`.
pub fn hinge_generator(fake: Tensor<2>) -> Tensor<1> {
    fake.mean().neg()
}

/// Cross-entropy of `logits` `[B, L, V]` against `targets` `[B, L]`, averaged over the positions
/// with `weight` `[B, L]` (1 = counted, 0 = ignored; e.g. only the masked tokens of a masked
/// transformer). Zero when no position counts.
pub fn masked_cross_entropy(
    logits: Tensor<3>,
    targets: Tensor<2, Int>,
    weight: Tensor<2>,
) -> Tensor<1> {
    let [b, l, _] = logits.dims();
    let picked = log_softmax(logits, 2)
        .gather(2, targets.reshape([b, l, 1]))
        .reshape([b, l]);
    let total = weight.clone().sum();
    (picked * weight).sum().neg() / total.clamp_min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device;

    fn t2(v: &[f32], n: usize, d: usize) -> Tensor<2> {
        Tensor::from_data(TensorData::new(v.to_vec(), [n, d]), &device::inference())
    }
    fn val(t: Tensor<1>) -> f32 {
        t.into_scalar::<f32>()
    }

    /// One pose `[1, 1, 24, 3]`: hips at x = ±0.1 m (left +), the given knees and ankles
    /// (left, right), every other joint at the origin.
    fn legs(knees: [[f32; 3]; 2], ankles: [[f32; 3]; 2]) -> Tensor<4> {
        let mut v = vec![0f32; 24 * 3];
        let mut put = |j: usize, p: [f32; 3]| v[j * 3..j * 3 + 3].copy_from_slice(&p);
        put(1, [0.1, 0.0, 0.9]);
        put(2, [-0.1, 0.0, 0.9]);
        put(4, knees[0]);
        put(5, knees[1]);
        put(7, ankles[0]);
        put(8, ankles[1]);
        Tensor::from_data(TensorData::new(v, [1, 1, 24, 3]), &device::inference())
    }

    fn crossing(j: Tensor<4>) -> f32 {
        leg_crossing(j).into_scalar::<f32>()
    }

    #[test]
    fn crossed_shins_cost_and_a_cross_body_step_does_not() {
        let apart = legs(
            [[0.1, 0.0, 0.5], [-0.1, 0.0, 0.5]],
            [[0.1, 0.0, 0.1], [-0.1, 0.0, 0.1]],
        );
        assert_eq!(crossing(apart), 0.0);
        // The left ankle steps across in front of the right one: knees on their sides.
        let cross_step = legs(
            [[0.1, 0.0, 0.5], [-0.1, 0.0, 0.5]],
            [[-0.12, 0.15, 0.1], [0.12, -0.15, 0.1]],
        );
        assert_eq!(crossing(cross_step), 0.0);
        // Knees and ankles both on the wrong side, shins 0.3 m apart front to back: only the
        // swap hinge, 0.1 · 0.1.
        let swapped = legs(
            [[-0.05, 0.15, 0.5], [0.05, -0.15, 0.5]],
            [[-0.05, 0.15, 0.1], [0.05, -0.15, 0.1]],
        );
        assert!((crossing(swapped) - 0.01).abs() < 1e-6);
        // Shins 2 cm apart side by side: each of the 3 matching pairs costs (0.08 − 0.02)².
        let touching = legs(
            [[0.01, 0.0, 0.5], [-0.01, 0.0, 0.5]],
            [[0.01, 0.0, 0.1], [-0.01, 0.0, 0.1]],
        );
        let want = 3.0 * (0.06f32).powi(2);
        assert!((crossing(touching) - want).abs() < 1e-5, "{want}");
    }

    #[test]
    fn filtering_drops_only_similar_negatives() {
        // Three pairs; pairs 0 and 1 share a near-identical condition.
        let a = t2(&[1.0, 0.0, 0.8, 0.6, 0.0, 1.0], 3, 2);
        let b = t2(&[0.9, 0.1, 0.7, 0.7, 0.1, 0.9], 3, 2);
        let sim = t2(&[1.0, 0.95, 0.1, 0.95, 1.0, 0.2, 0.1, 0.2, 1.0], 3, 3);
        let plain = val(info_nce(a.clone(), b.clone(), 0.1));
        // Nothing above the threshold: the plain loss.
        let none = val(info_nce_filtered(
            a.clone(),
            b.clone(),
            0.1,
            sim.clone(),
            0.99,
        ));
        assert!((plain - none).abs() < 1e-6, "{plain} {none}");
        // Pairs 0 and 1 no longer compete: lower loss, and by hand equal to dropping the two
        // cross terms from the softmaxes.
        let filt = val(info_nce_filtered(a, b, 0.1, sim, 0.8));
        assert!(filt < plain, "{filt} {plain}");
        let unit = |x: [f64; 2]| {
            let n = (x[0] * x[0] + x[1] * x[1]).sqrt();
            [x[0] / n, x[1] / n]
        };
        let av = [unit([1.0, 0.0]), unit([0.8, 0.6]), unit([0.0, 1.0])];
        let bv = [unit([0.9, 0.1]), unit([0.7, 0.7]), unit([0.1, 0.9])];
        let l = |i: usize, j: usize| (av[i][0] * bv[j][0] + av[i][1] * bv[j][1]) / 0.1;
        let keep = |i: usize, j: usize| i == j || !((i == 0 && j == 1) || (i == 1 && j == 0));
        let ce = |logit: &dyn Fn(usize, usize) -> f64| {
            (0..3)
                .map(|i| {
                    let z: f64 = (0..3)
                        .filter(|&j| keep(i, j))
                        .map(|j| logit(i, j).exp())
                        .sum();
                    -(logit(i, i) - z.ln())
                })
                .sum::<f64>()
                / 3.0
        };
        let want = (ce(&l) + ce(&|i, j| l(j, i))) / 2.0;
        assert!((filt as f64 - want).abs() < 1e-4, "{filt} vs {want}");
    }
}
