//! The follower's four foot joints (SMPL 7, 8, 10, 11: ankles and feet) from its normalised
//! duet features, differentiably, for the autoencoder's foot velocity loss.
//!
//! Why: the feature losses weigh a hip's 6D error like a wrist's, but at the foot a hip error
//! is multiplied by the leg's length, and the root stream's error moves the whole body. Sent
//! through the first autoencoder alone, real followers slid at twice their real speed on
//! planted feet (`docs/solo-data-v2.md`, issue 41 part 5), though every feature loss had
//! flattened. The loss on the feet measures the error where the viewer sees it.
//!
//! The positions are in the **leader frame** of the duet representation
//! (`dancegen_motion::repr::duet`): the pelvis at `(x, y, z)` of the root stream, the pelvis
//! rotation its leader-frame 6D, the legs their local 6D, chained with the SMPL skeleton's
//! offsets. A real and a decoded follower of the same leader share that frame, so the
//! difference of their foot velocities there is their world difference, up to the frame's slow
//! turn (σ = 2 s) acting on the position error.

use dancegen_motion::repr::DuetFollower;
use dancegen_motion::repr::duet::LOWER_JOINTS;
use dancegen_motion::skeleton::Skeleton;
use dancegen_nn::burn;
use dancegen_nn::loss::{FkSkeleton, forward_kinematics, rot6d_to_matrix};

use burn::tensor::Tensor;
use dancegen_nn::denormalize::Denormalizer;

/// SMPL joints of the feet, in the order of the duet contact channels.
pub const FOOT_JOINTS: [usize; 4] = [7, 8, 10, 11];

/// The pelvis and the leg joints ([`LOWER_JOINTS`]) as an FK chain, and the follower
/// features' normaliser.
#[derive(Clone, Debug)]
pub struct FollowerFeet {
    skeleton: FkSkeleton,
    features: Denormalizer,
}

impl FollowerFeet {
    /// `mean` and `std` of the follower's [`DuetFollower::DIMS`] channels (the first channels of
    /// the duet training normaliser).
    pub fn new(mean: &[f64], std: &[f64]) -> Result<Self, String> {
        let features = Denormalizer::first(mean, std, DuetFollower::DIMS)?;
        let smpl = Skeleton::smpl24();
        let chain: Vec<usize> = std::iter::once(0).chain(LOWER_JOINTS).collect();
        let mut parents = Vec::with_capacity(chain.len());
        let mut offsets = Vec::with_capacity(chain.len());
        for &j in &chain {
            let parent = match smpl.parents()[j] {
                None => None,
                Some(p) => Some(chain.iter().position(|&c| c == p).ok_or_else(|| {
                    format!("SMPL joint {j}'s parent {p} is not in the leg chain")
                })?),
            };
            parents.push(parent);
            offsets.push(smpl.offsets()[j]);
        }
        Ok(Self {
            skeleton: FkSkeleton { parents, offsets },
            features,
        })
    }

    /// Normalised follower features `[B, T, 151]` → foot joints `[B, T, 4, 3]` in the leader
    /// frame, metres.
    pub fn positions(&self, x: Tensor<3>) -> Tensor<4> {
        let [b, t, _] = x.dims();
        let raw = self.features.apply(x);
        let n = b * t;
        let legs = LOWER_JOINTS.len();
        let lr = DuetFollower::LOWER_ROT;
        let rr = DuetFollower::ROOT_ROT;
        let rp = DuetFollower::ROOT_POS;
        let d6 = Tensor::cat(
            vec![
                raw.clone().narrow(2, rr.start, rr.len()),
                raw.clone().narrow(2, lr.start, lr.len()),
            ],
            2,
        )
        .reshape([n * (legs + 1), 6]);
        let mats = rot6d_to_matrix(d6).reshape([n, legs + 1, 3, 3]);
        let root = raw.narrow(2, rp.start, rp.len()).reshape([n, 3]);
        let joints = forward_kinematics(mats, root, &self.skeleton);
        let feet: Vec<Tensor<3>> = FOOT_JOINTS
            .iter()
            .map(|f| {
                let k = 1 + LOWER_JOINTS
                    .iter()
                    .position(|j| j == f)
                    .expect("feet are leg joints");
                joints.clone().narrow(1, k, 1)
            })
            .collect();
        Tensor::cat(feet, 1).reshape([b, t, FOOT_JOINTS.len(), 3])
    }

    /// Mean L1 distance (m/s at `fps`) between the foot velocities of `decoded` and `real`
    /// (normalised features `[B, T, 151]`); `real` is not differentiated.
    pub fn velocity_loss(&self, decoded: Tensor<3>, real: Tensor<3>, fps: f64) -> Tensor<1> {
        let vel = |p: Tensor<4>| {
            let t = p.dims()[1];
            p.clone().narrow(1, 1, t - 1) - p.narrow(1, 0, t - 1)
        };
        let a = vel(self.positions(decoded));
        let b = vel(self.positions(real.detach()));
        (a - b).abs().mean() * fps
    }
}
