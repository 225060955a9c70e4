//! Differentiable de-normalisation and forward kinematics of EDGE-151 windows, shared by the
//! Foot Refine Block, the auxiliary losses and the penetration guidance.

use dancegen_nn::burn;
use dancegen_nn::loss::{FkSkeleton, forward_kinematics, rot6d_to_matrix};

use burn::module::{Module, Param};
use burn::tensor::{Device, Tensor, TensorData};

use crate::layout::{DIMS, FEET, ROOT_HORIZONTAL, ROT6D_START};

/// Per-channel `raw = x · scale + shift` of the normaliser the model was trained with (the
/// shift of the window-relative root x/y is 0, see [`crate::layout`]). Stored with the weights,
/// never trained.
#[derive(Module, Debug)]
pub struct Denormalize {
    pub scale: Param<Tensor<1>>,
    pub shift: Param<Tensor<1>>,
}

impl Denormalize {
    /// From a mean/std normaliser's statistics (`mean`, `std` of length 151).
    pub fn from_mean_std(mean: &[f64], std: &[f64], device: &Device) -> Self {
        assert_eq!(mean.len(), DIMS, "normaliser width");
        assert_eq!(std.len(), DIMS, "normaliser width");
        let shift: Vec<f32> = (0..DIMS)
            .map(|c| {
                if ROOT_HORIZONTAL.contains(&c) {
                    0.0
                } else {
                    mean[c] as f32
                }
            })
            .collect();
        let scale: Vec<f32> = std.iter().map(|&s| s as f32).collect();
        let t = |v: Vec<f32>| {
            Param::from_tensor(Tensor::<1>::from_data(TensorData::new(v, [DIMS]), device))
                .set_require_grad(false)
        };
        Self {
            scale: t(scale),
            shift: t(shift),
        }
    }

    /// Identity statistics (placeholders a checkpoint overwrites).
    pub fn identity(device: &Device) -> Self {
        Self::from_mean_std(&[0.0; DIMS], &[1.0; DIMS], device)
    }

    /// `[B, T, 151]` normalised → raw.
    pub fn apply(&self, x: Tensor<3>) -> Tensor<3> {
        let s = self.scale.val().reshape([1, 1, DIMS]);
        let m = self.shift.val().reshape([1, 1, DIMS]);
        x * s + m
    }

    /// Raw → normalised (the inverse of [`Denormalize::apply`]).
    pub fn invert(&self, raw: Tensor<3>) -> Tensor<3> {
        let s = self.scale.val().reshape([1, 1, DIMS]);
        let m = self.shift.val().reshape([1, 1, DIMS]);
        (raw - m) / s
    }

    /// The statistics on the host: `(scale, shift)`.
    pub fn host(&self) -> (Vec<f32>, Vec<f32>) {
        let v = |t: Tensor<1>| t.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
        (v(self.scale.val()), v(self.shift.val()))
    }
}

/// World joints `[B, T, 24, 3]` (Z-up, metres; horizontal root as stored) of raw EDGE-151
/// frames `[B, T, 151]`. Without autodiff (sampling) the FK runs on the host
/// ([`joints_host`]): two dozen chained 3×3 products per frame are ~100 tiny tensor operations
/// otherwise, which cost the Foot Refine Block about as much as a decoder layer per step.
pub fn joints(raw: Tensor<3>, skeleton: &FkSkeleton) -> Tensor<4> {
    let [b, t, _] = raw.dims();
    let j = skeleton.parents.len();
    if !raw.is_autodiff() {
        let device = raw.device();
        let host = raw
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .unwrap();
        let out = joints_host(&host, skeleton);
        return Tensor::<4>::from_data(TensorData::new(out, [b, t, j, 3]), &device);
    }
    let rot = raw
        .clone()
        .narrow(2, ROT6D_START, 6 * j)
        .reshape([b * t * j, 6]);
    let mats = rot6d_to_matrix(rot).reshape([b * t, j, 3, 3]);
    let root = raw.narrow(2, 4, 3).reshape([b * t, 3]);
    forward_kinematics(mats, root, skeleton).reshape([b, t, j, 3])
}

/// pytorch3d's 6D → rotation matrix (rows `b1, b2, b1 × b2`), as
/// [`dancegen_nn::loss::rot6d_to_matrix`] computes it.
fn rot6d_rows(d: &[f32]) -> [[f32; 3]; 3] {
    let unit = |v: [f32; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-12);
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let b1 = unit([d[0], d[1], d[2]]);
    let p = b1[0] * d[3] + b1[1] * d[4] + b1[2] * d[5];
    let b2 = unit([d[3] - b1[0] * p, d[4] - b1[1] * p, d[5] - b1[2] * p]);
    let b3 = [
        b1[1] * b2[2] - b1[2] * b2[1],
        b1[2] * b2[0] - b1[0] * b2[2],
        b1[0] * b2[1] - b1[1] * b2[0],
    ];
    [b1, b2, b3]
}

fn mat_mul(a: &[[f32; 3]; 3], b: &[[f32; 3]; 3]) -> [[f32; 3]; 3] {
    let mut m = [[0f32; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][k] + a[i][1] * b[1][k] + a[i][2] * b[2][k];
        }
    }
    m
}

/// [`joints`] on the host: raw frames `[N, 151]` (flat) → world joints `[N, 24, 3]` (flat).
pub fn joints_host(raw: &[f32], skeleton: &FkSkeleton) -> Vec<f32> {
    let j = skeleton.parents.len();
    let frames = raw.len() / DIMS;
    let mut out = vec![0f32; frames * j * 3];
    let mut rot = vec![[[0f32; 3]; 3]; j];
    for (f, frame) in raw.chunks_exact(DIMS).enumerate() {
        let pos = &mut out[f * j * 3..(f + 1) * j * 3];
        for k in 0..j {
            let c = ROT6D_START + 6 * k;
            let local = rot6d_rows(&frame[c..c + 6]);
            match skeleton.parents[k] {
                None => {
                    rot[k] = local;
                    pos[3 * k..3 * k + 3].copy_from_slice(&frame[4..7]);
                }
                Some(p) => {
                    let o = skeleton.offsets[k].map(|v| v as f32);
                    let r = rot[p];
                    for a in 0..3 {
                        pos[3 * k + a] =
                            pos[3 * p + a] + r[a][0] * o[0] + r[a][1] * o[1] + r[a][2] * o[2];
                    }
                    rot[k] = mat_mul(&r, &local);
                }
            }
        }
    }
    out
}

/// The four foot joints `[B, T, 4, 3]` of world joints `[B, T, 24, 3]`.
pub fn feet(joints: Tensor<4>) -> Tensor<4> {
    Tensor::cat(
        FEET.iter()
            .map(|&f| joints.clone().narrow(2, f, 1))
            .collect(),
        2,
    )
}

/// Per-frame displacement `[B, T, …]` with a zero first frame (so it keeps T frames).
pub fn displacement(x: Tensor<4>) -> Tensor<4> {
    let [b, t, j, c] = x.dims();
    let d = x.clone().narrow(1, 1, t - 1) - x.narrow(1, 0, t - 1);
    Tensor::cat(vec![Tensor::zeros([b, 1, j, c], &d.device()), d], 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Distribution;

    #[test]
    fn host_fk_matches_the_differentiable_one() {
        let device = dancegen_nn::device::inference();
        let grad = device.clone().autodiff();
        let skel = FkSkeleton::smpl24();
        let raw = Tensor::<3>::random([2, 5, DIMS], Distribution::Normal(0.0, 1.0), &device);
        let host = joints(raw.clone(), &skel)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        let tracked = Tensor::<3>::from_data(raw.into_data(), &grad);
        assert!(tracked.is_autodiff());
        let diff = joints(tracked, &skel)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        assert_eq!(host.len(), 2 * 5 * 24 * 3);
        for (a, b) in host.iter().zip(&diff) {
            assert!((a - b).abs() < 1e-4 * (1.0 + b.abs()), "{a} vs {b}");
        }
    }
}
