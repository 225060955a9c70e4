//! The body's four foot joints (SMPL 7, 8, 10, 11: ankles and feet) moving from frame to frame,
//! differentiably, from normalised holistic rows: for the part autoencoder's foot velocity loss.
//!
//! Why: sent through the shipped part autoencoder alone, the real held-out dancers' planted feet
//! slid at 0.52 m/s against their own 0.21 (issue 41, `holistic_probe roundtrip`), though every
//! feature loss had flattened: the loss weighs each of the 675 values alike, and the few that
//! carry the root path and the feet are drowned by the hands and the face.
//!
//! The velocity is the one HumanML3D's recovery (`recover_from_ric`,
//! `dancegen_motion::repr::humanml263`) gives the joint between frames `t − 1` and `t`, written
//! in the heading frame of frame `t`:
//!
//! `v(t) = ric(t) − R_y(2·ω(t−1)) · ric(t−1) + (l_x(t−1), 0, l_z(t−1))`
//!
//! with `ω` the root's angular velocity channel (a half angle, as the recovery's quaternion
//! takes it), `l` its linear velocity channels and `ric` the joint's heading-relative position.
//! It needs no running sums, so any window gives it, and its length is the world speed.

use dancegen_motion::repr::holistic::split::BODY_DIMS;
use dancegen_nn::burn;

use burn::tensor::Tensor;
use dancegen_nn::denormalize::Denormalizer;

/// SMPL joints of the feet (left ankle, right ankle, left foot, right foot).
pub const FOOT_JOINTS: [usize; 4] = [7, 8, 10, 11];

/// The body rows' normaliser, to read the feet in metres.
#[derive(Clone, Debug)]
pub struct BodyFeet {
    body: Denormalizer,
}

impl BodyFeet {
    /// `mean` and `std` of the holistic normaliser (its first [`BODY_DIMS`] values are the
    /// body's).
    pub fn new(mean: &[f64], std: &[f64]) -> Result<Self, String> {
        Ok(Self {
            body: Denormalizer::first(mean, std, BODY_DIMS)?,
        })
    }

    /// Normalised rows `[B, T, D ≥ 263]` → the feet's velocities `[B, T − 1, 4, 3]`, metres per
    /// frame, each in its later frame's heading frame.
    pub fn velocities(&self, x: Tensor<3>) -> Tensor<4> {
        let [b, t, _] = x.dims();
        let raw = self.body.apply(x);
        let n = FOOT_JOINTS.len();
        let ric = Tensor::cat(
            FOOT_JOINTS
                .iter()
                .map(|&j| raw.clone().narrow(2, 4 + (j - 1) * 3, 3))
                .collect(),
            2,
        )
        .reshape([b, t, n, 3]);
        let cur = ric.clone().narrow(1, 1, t - 1);
        let prev = ric.narrow(1, 0, t - 1);
        let before = raw.narrow(1, 0, t - 1);
        let angle = before.clone().narrow(2, 0, 1).reshape([b, t - 1, 1]) * 2.0;
        let (c, s) = (angle.clone().cos(), angle.sin());
        let lin = |k: usize| before.clone().narrow(2, 1 + k, 1).reshape([b, t - 1, 1]);
        let axis = |p: &Tensor<4>, k: usize| p.clone().narrow(3, k, 1).reshape([b, t - 1, n]);
        let (px, py, pz) = (axis(&prev, 0), axis(&prev, 1), axis(&prev, 2));
        let turned_x = px.clone() * c.clone() + pz.clone() * s.clone();
        let turned_z = pz * c - px * s;
        let vx = axis(&cur, 0) - turned_x + lin(0);
        let vy = axis(&cur, 1) - py;
        let vz = axis(&cur, 2) - turned_z + lin(1);
        Tensor::stack::<4>(vec![vx, vy, vz], 3)
    }

    /// Mean L1 distance (m/s at `fps`) between the foot velocities of `decoded` and `real`
    /// (normalised rows `[B, T, D]`); `real` is not differentiated.
    pub fn velocity_loss(&self, decoded: Tensor<3>, real: Tensor<3>, fps: f64) -> Tensor<1> {
        let a = self.velocities(decoded);
        let b = self.velocities(real.detach());
        (a - b).abs().mean() * fps
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::repr::holistic::split::to_split;
    use dancegen_motion::repr::{Holistic623, HumanMl263};
    use dancegen_nn::burn::tensor::TensorData;
    use dancegen_nn::device;

    /// A turning, travelling body with moving legs, in the split layout (real HumanML3D rows).
    fn rows() -> (Vec<f32>, usize) {
        let t = 40;
        let mut poses = vec![0f32; t * 52 * 3];
        let mut trans = vec![0f32; t * 3];
        for f in 0..t {
            let s = f as f32 / 30.0;
            poses[f * 156 + 1] = 1.3 * s; // the body turns about y
            poses[(f * 52 + 1) * 3] = 0.6 * (4.0 * s).sin(); // left hip swings
            poses[(f * 52 + 5) * 3] = 0.5 * (3.0 * s).sin().abs(); // right knee bends
            trans[f * 3] = 0.4 * s;
            trans[f * 3 + 1] = 0.9 + 0.03 * (5.0 * s).sin();
            trans[f * 3 + 2] = 0.2 * s * s;
        }
        let inter = Holistic623::encode(&poses, &trans, 30.0).unwrap();
        (to_split(&inter, 0).unwrap(), t - 1)
    }

    #[test]
    fn foot_velocities_are_those_of_the_recovered_joints() {
        let (body_hands, t) = rows();
        let d = body_hands.len() / t;
        // The recovery's world joints of the body part (HumanML3D's 263 of 22 joints).
        let body: Vec<f32> = body_hands
            .chunks_exact(d)
            .flat_map(|r| r[..BODY_DIMS].to_vec())
            .collect();
        let world = HumanMl263::decode_joints(&body).unwrap();
        let dev = device::inference();
        let feet = BodyFeet::new(&vec![0.0; d], &vec![1.0; d]).unwrap();
        let x = Tensor::<3>::from_data(TensorData::new(body_hands, [1, t, d]), &dev);
        let v: Vec<f32> = feet.velocities(x).into_data().try_to_vec::<f32>().unwrap();
        let mut largest = 0f32;
        for f in 1..t {
            for (k, &j) in FOOT_JOINTS.iter().enumerate() {
                let w = |g: usize, a: usize| world[(g * 22 + j) * 3 + a];
                let dw: Vec<f32> = (0..3).map(|a| w(f, a) - w(f - 1, a)).collect();
                let got = &v[((f - 1) * 4 + k) * 3..((f - 1) * 4 + k) * 3 + 3];
                let horizontal = |p: &[f32]| (p[0] * p[0] + p[2] * p[2]).sqrt();
                assert!((horizontal(&dw) - horizontal(got)).abs() < 1e-4, "{f} {j}");
                assert!((dw[1] - got[1]).abs() < 1e-5, "{f} {j}");
                largest = largest.max(horizontal(&dw));
            }
        }
        assert!(largest > 0.01, "the feet move ({largest} m per frame)");
    }

    #[test]
    fn the_loss_is_zero_on_itself_and_counts_metres_per_second() {
        let (body_hands, t) = rows();
        let d = body_hands.len() / t;
        let dev = device::inference();
        let feet = BodyFeet::new(&vec![0.0; d], &vec![1.0; d]).unwrap();
        let x = Tensor::<3>::from_data(TensorData::new(body_hands.clone(), [1, t, d]), &dev);
        let zero: f32 = feet.velocity_loss(x.clone(), x.clone(), 30.0).into_scalar();
        assert!(zero.abs() < 1e-6);
        // The left ankle raised 1 cm from the second frame on (up is the turn's axis, so
        // the later frames' velocities stay as they were): one jump of 1 cm between frames 0
        // and 1, of 12 values in T − 1 frames.
        let mut moved = body_hands;
        let ankle_y = 4 + 6 * 3 + 1;
        for f in 1..t {
            moved[f * d + ankle_y] += 0.01;
        }
        let y = Tensor::<3>::from_data(TensorData::new(moved, [1, t, d]), &dev);
        let l: f32 = feet.velocity_loss(y, x, 30.0).into_scalar();
        let expect = 0.01 * 30.0 / (12.0 * (t - 1) as f32);
        assert!((l - expect).abs() < 1e-5, "{l} vs {expect}");
        assert!(BodyFeet::new(&[0.0; 10], &[1.0; 10]).is_err());
    }
}
