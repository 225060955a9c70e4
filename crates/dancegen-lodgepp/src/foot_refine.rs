//! The Foot Refine Block (paper §3.4.4, D.2 `Refine_DanceDecoder`): forward kinematics of the
//! main decoder's x̂0 gives foot positions and velocities and soft foot-ground contact scores;
//! a FiLM decoder layer cross-attends from the decoder's hidden states to these per-frame foot
//! tokens and a zero-initialised projection adds the refinement to x̂0.
//!
//! Per-frame foot features (32): positions of the 4 foot joints (12), their velocities in m/s
//! (12), soft contact scores (4) and the predicted contact labels (4). Lodge's block has 48
//! (it counts the ankle score twice and assumes a floor at −1.2, D.2); ours uses floor 0, the
//! data's ground after `put_on_ground`.

use dancegen_nn::burn;
use dancegen_nn::loss::FkSkeleton;
use dancegen_nn::transformer::{DecoderContext, FilmDecoderLayer, FilmDecoderLayerConfig};

use burn::module::Module;
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::activation::sigmoid;
use burn::tensor::{Device, Tensor, TensorData};

use crate::kinematics::{Denormalize, displacement, feet, joints};
use crate::layout::CONTACTS;

/// Which channels the Foot Refine Block's refinement is added to at sampling time.
///
/// Lodge++ adds it to every channel (`All`). Training puts the FK joint, velocity, acceleration
/// and contact terms on the refined output only, so the block also learns to slow the arms and
/// the trunk (docs/solo-data-v2.md, round seven). `Legs` keeps the refinement on the channels
/// that place the feet ([`crate::layout::leg_channels`]) and leaves the rest of the body as the
/// main decoder predicted it. Not part of Lodge++.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FootRefineScope {
    #[default]
    All,
    Legs,
}

impl FootRefineScope {
    /// `[1, 1, 151]` weights of the refinement (1 where it applies), or `None` for all channels.
    pub fn mask(self, device: &Device) -> Option<Tensor<3>> {
        match self {
            FootRefineScope::All => None,
            FootRefineScope::Legs => {
                let mut m = vec![0f32; crate::layout::DIMS];
                for c in crate::layout::leg_channels() {
                    m[c] = 1.0;
                }
                Some(Tensor::from_data(
                    TensorData::new(m, [1, 1, crate::layout::DIMS]),
                    device,
                ))
            }
        }
    }
}

/// Features per frame.
pub const FOOT_FEATURES: usize = 32;
/// Contact height thresholds (m) of ankles and toes: LODGE's preprocessing labels (D.2/C.3:
/// ankle < 0.12, toe < 0.05).
pub const CONTACT_HEIGHT: [f32; 4] = [0.12, 0.12, 0.05, 0.05];
/// Contact speed threshold per frame (m): EDGE's 0.01 m (C.2).
pub const CONTACT_STEP: f32 = 0.01;
/// Softness of the sigmoids (m).
const HEIGHT_SOFTNESS: f32 = 0.02;
const STEP_SOFTNESS: f32 = 0.003;
/// Frames per second of the motion (velocities in m/s).
const FPS: f32 = 30.0;

/// See the module documentation.
#[derive(Module, Debug)]
pub struct FootRefine {
    pub features: Linear,
    pub layer: FilmDecoderLayer,
    pub output: Linear,
}

impl FootRefine {
    pub fn new(d: usize, n_heads: usize, d_ff: usize, dropout: f64, device: &Device) -> Self {
        FootRefine {
            features: LinearConfig::new(FOOT_FEATURES, d).init(device),
            layer: FilmDecoderLayerConfig::new(d, n_heads, d_ff)
                .with_dropout(dropout)
                .init(device),
            output: LinearConfig::new(d, crate::layout::DIMS)
                .with_initializer(Initializer::Zeros)
                .init(device),
        }
    }

    /// The refinement to add to `x0_main` `[B, T, 151]` (normalised), from the decoder's hidden
    /// states `h` `[B, T, d]` and FiLM vector `cond` `[B, d]`.
    pub fn forward(
        &self,
        h: Tensor<3>,
        x0_main: Tensor<3>,
        cond: Tensor<2>,
        denorm: &Denormalize,
        skeleton: &FkSkeleton,
    ) -> Tensor<3> {
        let tokens = self
            .features
            .forward(foot_features(denorm.apply(x0_main), skeleton));
        let none = Default::default();
        let ctx = DecoderContext {
            memory: tokens,
            cond: cond.unsqueeze_dim(1),
            self_masks: &none,
            cross_masks: &none,
            rotary: None,
        };
        self.output.forward(self.layer.forward(h, &ctx))
    }
}

/// `[B, T, 32]` foot features of raw frames `[B, T, 151]`.
pub fn foot_features(raw: Tensor<3>, skeleton: &FkSkeleton) -> Tensor<3> {
    let [b, t, _] = raw.dims();
    let device = raw.device();
    let f = feet(joints(raw.clone(), skeleton));
    let step = displacement(f.clone());
    let height = f.clone().narrow(3, 2, 1).reshape([b, t, 4]);
    let thr = Tensor::<1>::from_data(TensorData::new(CONTACT_HEIGHT.to_vec(), [4]), &device)
        .reshape([1, 1, 4]);
    let low = sigmoid((thr - height) / HEIGHT_SOFTNESS);
    let speed = step
        .clone()
        .powf_scalar(2.0)
        .sum_dim(3)
        .sqrt()
        .reshape([b, t, 4]);
    let still = sigmoid((speed.neg() + CONTACT_STEP) / STEP_SOFTNESS);
    let labels = raw.narrow(2, CONTACTS.start, CONTACTS.len());
    Tensor::cat(
        vec![
            f.reshape([b, t, 12]),
            step.reshape([b, t, 12]) * FPS,
            low * still,
            labels,
        ],
        2,
    )
}
