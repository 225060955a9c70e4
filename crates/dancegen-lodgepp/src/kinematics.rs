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
/// frames `[B, T, 151]`.
pub fn joints(raw: Tensor<3>, skeleton: &FkSkeleton) -> Tensor<4> {
    let [b, t, _] = raw.dims();
    let j = skeleton.parents.len();
    let rot = raw
        .clone()
        .narrow(2, ROT6D_START, 6 * j)
        .reshape([b * t * j, 6]);
    let mats = rot6d_to_matrix(rot).reshape([b * t, j, 3, 3]);
    let root = raw.narrow(2, 4, 3).reshape([b * t, 3]);
    forward_kinematics(mats, root, skeleton).reshape([b, t, j, 3])
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
