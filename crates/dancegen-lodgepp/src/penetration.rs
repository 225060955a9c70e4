//! Penetration guidance (paper §3.4.5, eq. 23–24) on a capsule body.
//!
//! The paper evaluates COAP's signed distance between SMPL-X hand vertices and the body mesh
//! and shifts the denoised motion along the gradient of
//! `G = 1/|p_h| Σ_q σ(f(q)) · 1[f(q) > 0]`. Neither the SMPL-X mesh nor COAP is available here,
//! so the body is `dancegen_motion::capsule_body` (capsules around the SMPL bones, radii from
//! anthropometric means) and `f(q)` is the penetration depth of a point `q` sampled on the axis
//! of a forearm or hand capsule into a non-neighbouring capsule: `r_src + r_tgt − dist(q,
//! segment_tgt)` (positive inside). The gradient reaches only the arm joints' rotations
//! (collars, shoulders, elbows, wrists, hands): the guidance moves arms, not the trunk.

use dancegen_motion::capsule_body::{CAPSULES, penetration_pairs, point_segment_distance_sq};
use dancegen_nn::burn;
use dancegen_nn::loss::FkSkeleton;

use burn::tensor::activation::sigmoid;
use burn::tensor::{Device, Tensor, TensorData};

use crate::kinematics::{Denormalize, joints, joints_host};
use crate::layout::{DIMS, rot6d};

/// Points sampled on each source capsule's axis: as many as the evaluation's penetration ratio
/// measures (`dancegen_metrics::penetration::DEFAULT_SAMPLES_PER_SEGMENT`), so no point it
/// counts lies between the points the guidance pushes.
pub const SAMPLES_PER_CAPSULE: usize = 8;
/// Width of the sigmoid of eq. 23 (metres of penetration depth).
pub const DEPTH_SCALE: f64 = 0.01;
/// SMPL joints whose rotations the guidance may change: collars 13/14, shoulders 16/17, elbows
/// 18/19, wrists 20/21, hands 22/23.
pub const ARM_JOINTS: [usize; 10] = [13, 14, 16, 17, 18, 19, 20, 21, 22, 23];

/// The sampled (point, target capsule) pairs as linear maps of the joints: point `m` is
/// `P[m] · J`, target segment `A[m] · J → B[m] · J`, combined radius `r[m]`.
#[derive(Clone, Debug)]
pub struct CapsulePairs {
    pub point: Vec<f32>,
    pub seg_a: Vec<f32>,
    pub seg_b: Vec<f32>,
    pub radius: Vec<f32>,
}

impl CapsulePairs {
    pub fn new() -> Self {
        let mut s = Self {
            point: Vec::new(),
            seg_a: Vec::new(),
            seg_b: Vec::new(),
            radius: Vec::new(),
        };
        let row = |a: usize, b: usize, t: f64| {
            let mut r = vec![0f32; 24];
            r[a] += (1.0 - t) as f32;
            r[b] += t as f32;
            r
        };
        for (src, tgt) in penetration_pairs() {
            let c = &CAPSULES[src];
            let g = &CAPSULES[tgt];
            for k in 0..SAMPLES_PER_CAPSULE {
                let t = c.start + (c.end - c.start) * (k as f64 + 0.5) / SAMPLES_PER_CAPSULE as f64;
                s.point.extend(row(c.joint_a, c.joint_b, t));
                s.seg_a.extend(row(g.joint_a, g.joint_b, g.start));
                s.seg_b.extend(row(g.joint_a, g.joint_b, g.end));
                s.radius.push((c.radius_m + g.radius_m) as f32);
            }
        }
        s
    }

    pub fn len(&self) -> usize {
        self.radius.len()
    }

    pub fn is_empty(&self) -> bool {
        self.radius.is_empty()
    }

    /// Whether any sampled point of the frame's joints `[24, 3]` (flat) is inside its target
    /// capsule: [`CapsulePairs::depths`] > 0 for some pair, computed on the host.
    pub fn any_inside(&self, joints: &[f32]) -> bool {
        let at = |v: &[f32], m: usize| {
            let mut p = [0f64; 3];
            for (k, &w) in v[m * 24..(m + 1) * 24].iter().enumerate() {
                if w != 0.0 {
                    for (a, pa) in p.iter_mut().enumerate() {
                        *pa += f64::from(w * joints[3 * k + a]);
                    }
                }
            }
            p
        };
        (0..self.len()).any(|m| {
            let d2 = point_segment_distance_sq(
                at(&self.point, m),
                at(&self.seg_a, m),
                at(&self.seg_b, m),
            );
            d2.sqrt() < f64::from(self.radius[m])
        })
    }

    /// Penetration depths `[N, M]` (positive inside) of world joints `[N, 24, 3]`.
    pub fn depths(&self, j: Tensor<3>) -> Tensor<2> {
        let [n, _, _] = j.dims();
        let m = self.len();
        let device = j.device();
        let mat = |v: &[f32]| {
            Tensor::<2>::from_data(TensorData::new(v.to_vec(), [m, 24]), &device)
                .unsqueeze::<3>()
                .expand([n, m, 24])
        };
        let p = mat(&self.point).matmul(j.clone());
        let a = mat(&self.seg_a).matmul(j.clone());
        let b = mat(&self.seg_b).matmul(j);
        let ab = b - a.clone();
        let len2 = ab.clone().powf_scalar(2.0).sum_dim(2).clamp_min(1e-12);
        let s = ((p.clone() - a.clone()) * ab.clone())
            .sum_dim(2)
            .div(len2)
            .clamp(0.0, 1.0);
        let closest = a + ab * s;
        let dist = (p - closest)
            .powf_scalar(2.0)
            .sum_dim(2)
            .clamp_min(1e-12)
            .sqrt()
            .reshape([n, m]);
        let r = Tensor::<1>::from_data(TensorData::new(self.radius.clone(), [m]), &device)
            .reshape([1, m]);
        r - dist
    }
}

impl Default for CapsulePairs {
    fn default() -> Self {
        Self::new()
    }
}

/// Eq. 23 over a batch of windows: Σ σ(depth / scale) · 1[depth > 0] (a sum, so the step per
/// frame does not shrink with the batch).
pub fn penetration_energy(depth: Tensor<2>) -> Tensor<1> {
    let inside = depth.clone().greater_elem(0.0).float();
    (sigmoid(depth / DEPTH_SCALE) * inside).sum()
}

/// Settings of the guidance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PenetrationGuidance {
    /// `a_pene` of eq. 24, per unit of normalised motion.
    pub scale: f64,
    /// Gradient steps per denoising step.
    pub iterations: usize,
}

impl Default for PenetrationGuidance {
    fn default() -> Self {
        Self {
            scale: 0.02,
            iterations: 2,
        }
    }
}

/// 1 on the 6D channels of [`ARM_JOINTS`].
fn arm_channel_mask() -> Vec<f32> {
    let mut m = vec![0f32; DIMS];
    for &j in &ARM_JOINTS {
        for k in 0..6 {
            m[rot6d(j, k)] = 1.0;
        }
    }
    m
}

/// `x0` `[B, T, 151]` (normalised, on a plain device) moved down the gradient of the capsule
/// penetration energy, arm rotations only. The gradient is taken on `grad_device` (autodiff).
pub fn guide(
    x0: Tensor<3>,
    denorm: &Denormalize,
    pairs: &CapsulePairs,
    g: &PenetrationGuidance,
    grad_device: &Device,
) -> Tensor<3> {
    let [b, t, _] = x0.dims();
    let plain = x0.device();
    let (scale, shift) = denorm.host();
    let dn = Denormalize::from_mean_std(
        &shift.iter().map(|&v| f64::from(v)).collect::<Vec<_>>(),
        &scale.iter().map(|&v| f64::from(v)).collect::<Vec<_>>(),
        grad_device,
    );
    let skel = FkSkeleton::smpl24();
    let mask = arm_channel_mask();
    let mut x = x0.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
    for _ in 0..g.iterations {
        // Every frame's energy depends on that frame alone (FK and the capsule depths are per
        // frame), and its gradient is zero unless a point is inside a capsule (the indicator of
        // eq. 23). So only the penetrating frames go through autodiff, as a batch of one-frame
        // windows; most steps of most dances have none and cost one host FK.
        let raw: Vec<f32> = x
            .chunks_exact(DIMS)
            .flat_map(|f| {
                f.iter()
                    .zip(&scale)
                    .zip(&shift)
                    .map(|((v, s), m)| v * s + m)
            })
            .collect();
        let at = joints_host(&raw, &skel);
        let active: Vec<usize> = (0..b * t)
            .filter(|&f| pairs.any_inside(&at[f * 72..(f + 1) * 72]))
            .collect();
        if active.is_empty() {
            break;
        }
        let sub: Vec<f32> = active
            .iter()
            .flat_map(|&f| x[f * DIMS..(f + 1) * DIMS].iter().copied())
            .collect();
        let n = active.len();
        let xa =
            Tensor::<3>::from_data(TensorData::new(sub, [n, 1, DIMS]), grad_device).require_grad();
        let j = joints(dn.apply(xa.clone()), &skel).reshape([n, 24, 3]);
        let energy = penetration_energy(pairs.depths(j));
        let grads = energy.backward();
        let Some(gx) = xa.grad(&grads) else { break };
        let gx = gx.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
        for (k, &f) in active.iter().enumerate() {
            let row = &mut x[f * DIMS..(f + 1) * DIMS];
            let grad = &gx[k * DIMS..(k + 1) * DIMS];
            for ((v, d), m) in row.iter_mut().zip(grad).zip(&mask) {
                *v -= d * m * g.scale as f32;
            }
        }
    }
    Tensor::<3>::from_data(TensorData::new(x, [b, t, DIMS]), &plain)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_cover_every_source_sample() {
        let p = CapsulePairs::new();
        assert_eq!(p.len(), penetration_pairs().len() * SAMPLES_PER_CAPSULE);
        for row in p.point.chunks(24) {
            assert!((row.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }
}
