//! Differentiable de-normalisation and forward kinematics of EDGE-151 frames
//! (`dancegen_motion::repr::Edge151`: contacts 4, Z-up root position 3, 24 × 6D), shared by
//! the systems that diffuse in that representation (Lodge++'s PDDM, TCDiff++): the auxiliary
//! losses (FK, velocity, foot contact), Lodge++'s Foot Refine Block and penetration guidance.
//!
//! **Window-relative horizontal root.** Both systems store the root's horizontal position
//! (Z-up x/y, [`ROOT_HORIZONTAL`]) relative to a reference point of the window (Lodge++: the
//! window's first frame; TCDiff++: the group's frame-0 centroid), so windows and dancers can
//! be placed afterwards. In normalised units that is `(x − x_ref) / std`: the normaliser's mean
//! is not added back for those two channels ([`Denormalize`]).

use std::ops::Range;

use dancegen_motion::fk::{self as host_fk, LocalRotations};
use dancegen_motion::repr::Edge151;
use dancegen_motion::rotation;
use dancegen_motion::skeleton::Skeleton;

use burn::module::{Module, Param};
use burn::tensor::{Device, Tensor, TensorData};

use crate::loss::{FkSkeleton, forward_kinematics, rot6d_to_matrix};

/// Values per frame.
pub const DIMS: usize = Edge151::DIMS;
/// Contact labels (left ankle, right ankle, left toe, right toe).
pub const CONTACTS: Range<usize> = Edge151::CONTACTS;
/// Z-up root x, y (horizontal); z is the height.
pub const ROOT_HORIZONTAL: [usize; 2] = [4, 5];
/// Z-up root height.
pub const ROOT_HEIGHT: usize = 6;
/// First 6D channel.
pub const ROT6D_START: usize = 7;
/// SMPL joints of the feet the contact labels describe (ankles 7/8, toes 10/11, in the
/// labels' order; EDGE `dataset/dance_dataset.py`).
pub const FEET: [usize; 4] = [7, 8, 10, 11];

/// Channel of the 6D value `k` of joint `j`.
pub fn rot6d(j: usize, k: usize) -> usize {
    ROT6D_START + 6 * j + k
}

/// Per-channel `raw = x · scale + shift` of the normaliser the model was trained with (the
/// shift of the window-relative root x/y is 0, see the module docs). Stored with the weights,
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

/// [`joints`] on the host: raw frames `[N, 151]` (flat) → world joints `[N, 24, 3]` (flat),
/// through the motion crate's FK (pytorch3d 6D → matrix, then the same chain).
pub fn joints_host(raw: &[f32], skeleton: &FkSkeleton) -> Vec<f32> {
    let j = skeleton.parents.len();
    let d6: Vec<f32> = raw
        .chunks_exact(DIMS)
        .flat_map(|f| f[ROT6D_START..ROT6D_START + 6 * j].iter().copied())
        .collect();
    let root: Vec<f32> = raw
        .chunks_exact(DIMS)
        .flat_map(|f| f[4..7].iter().copied())
        .collect();
    let mats = rotation::rot6d_to_matrix(&d6);
    host_fk::forward_kinematics(
        &host_skeleton(skeleton),
        LocalRotations::Matrix(&mats),
        &root,
        false,
    )
    .expect("one matrix per joint and frame")
    .positions
}

/// The motion crate's skeleton of `skeleton` (for the host-side FK and IK).
pub fn host_skeleton(skeleton: &FkSkeleton) -> Skeleton {
    let j = skeleton.parents.len();
    // FkSkeleton comes from a motion-crate skeleton (`FkSkeleton::smpl24`), so it is valid.
    Skeleton::new(
        (0..j).map(|k| format!("joint{k}")).collect(),
        skeleton.parents.clone(),
        skeleton.offsets.clone(),
    )
    .expect("FkSkeleton is a valid skeleton")
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
        let device = crate::device::inference();
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
        // The host path works in f64, the tensor path in f32: chains of 24 f32 3×3 products
        // on random (unnormalised) 6D inputs drift by a few 1e-6 per metre; 1e-4 leaves room.
        for (a, b) in host.iter().zip(&diff) {
            assert!((a - b).abs() < 1e-4 * (1.0 + b.abs()), "{a} vs {b}");
        }
    }
}
