//! The training objectives of the three Lodge++ networks, on normalised EDGE-151 windows. The
//! training loop itself (data, optimiser, EMA, checkpoints) is `dancegen-train`'s.

use dancegen_nn::autoencoder::MotionAutoencoder;
use dancegen_nn::burn;
use dancegen_nn::diffusion::Conditioning;
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_nn::diffusion::pddm::ResidualShift;
use dancegen_nn::loss::{FkSkeleton, hinge_discriminator, hinge_generator};

use burn::module::Module;
use burn::nn::loss::CrossEntropyLossConfig;
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::choreo_gpt::ChoreoGpt;
use crate::config::{BOUNDARY_FRAMES, PddmLossWeights, PddmTable, PrimitiveDropout};
use crate::denoiser::{PddmCond, PddmDenoiser};
use crate::discriminator::GenreDiscriminator;
use crate::kinematics::{displacement, feet, joints};
use crate::layout::{self, CONTACTS, DIMS, ROOT_HORIZONTAL};
use crate::primitives::{PrimitiveMode, training_primitives};

/// The 42 coarse-dance channels of `[B, T, 151]`.
pub fn main_joints(x: Tensor<3>) -> Tensor<3> {
    let idx: Vec<i64> = layout::main_channels()
        .into_iter()
        .map(|c| c as i64)
        .collect();
    let n = idx.len();
    let device = x.device();
    x.select(
        2,
        Tensor::<1, Int>::from_data(TensorData::new(idx, [n]), &device),
    )
}

/// VQ token ids `[B, T/4]` of windows `[B, T, 151]`, from a frozen VQ-VAE on `device` (a plain,
/// non-autodiff device, so the EMA codebook is not updated).
pub fn tokens(vqvae: &MotionAutoencoder, x: Tensor<3>, device: &Device) -> Tensor<2, Int> {
    let x = Tensor::<3>::from_data(main_joints(x).into_data(), device);
    let idx = vqvae.encode(x);
    let [b, t, _] = idx.dims();
    idx.reshape([b, t])
}

/// GPT cross-entropy and top-1 accuracy of one batch (tokens from [`tokens`]).
pub fn gpt_loss(
    gpt: &ChoreoGpt,
    tokens: Tensor<2, Int>,
    music: Tensor<3>,
    genre: &[usize],
) -> (Tensor<1>, Tensor<1>) {
    let [b, t] = tokens.dims();
    let device = music.device();
    let tokens = Tensor::<2, Int>::from_data(tokens.into_data(), &device);
    let g: Vec<i64> = genre.iter().map(|&g| g as i64).collect();
    let g = Tensor::<1, Int>::from_data(TensorData::new(g, [b]), &device);
    let logits = gpt.forward(tokens.clone(), music, g);
    let v = logits.dims()[2];
    let flat = logits.reshape([b * t, v]);
    let target = tokens.reshape([b * t]);
    let ce = CrossEntropyLossConfig::new()
        .init(&device)
        .forward(flat.clone(), target.clone());
    let acc = flat.argmax(1).reshape([b * t]).equal(target).float().mean();
    (ce, acc)
}

/// The PDDM generator plus its discriminator, trained together (one optimiser; the
/// discriminator's loss sees the generator's output detached, and the generator's adversarial
/// term goes through a frozen copy of the discriminator).
#[derive(Module, Debug)]
pub struct PddmTrainModel {
    pub denoiser: PddmDenoiser,
    pub discriminator: Option<GenreDiscriminator>,
}

/// Built here, beside the model it builds, so that the config does not depend on training.
impl PddmTable {
    /// The model with identity statistics (a checkpoint or bundle supplies the real ones).
    pub fn init(&self, mean: &[f64], std: &[f64], device: &Device) -> PddmTrainModel {
        let g = self.genres.len();
        PddmTrainModel {
            denoiser: self.pddm.init(g, mean, std, &self.shift.schedule(), device),
            discriminator: self
                .use_discriminator
                .then(|| self.discriminator.init(g, device)),
        }
    }
}

/// Named loss terms of one PDDM batch; `total` is the weighted sum.
pub struct PddmLosses {
    pub total: Tensor<1>,
    pub parts: Vec<(&'static str, Tensor<1>)>,
}

/// Subtracts every window's first-frame root x/y (normalised units) from all its frames.
pub fn root_relative(x: Tensor<3>) -> Tensor<3> {
    let [b, t, _] = x.dims();
    let mut parts = Vec::with_capacity(3);
    let lo = ROOT_HORIZONTAL[0];
    parts.push(x.clone().narrow(2, 0, lo));
    let root = x.clone().narrow(2, lo, 2);
    let first = root.clone().narrow(1, 0, 1).expand([b, t, 2]);
    parts.push(root - first);
    parts.push(x.narrow(2, lo + 2, DIMS - lo - 2));
    Tensor::cat(parts, 2)
}

/// The root's up axis per frame, `[B, T, 3]`: row 0 × row 1 of the raw (denormalised) root 6D,
/// i.e. the Z-up root matrix's row 2 when the rows are orthonormal.
///
/// Why it needs a term of its own: for an upright dancer facing heading θ, the stored rows are
/// `(cos θ, 0, sin θ)` and `(sin θ, 0, −cos θ)` (`Edge151`: first two rows of `Q·R_y(θ)`, Q the
/// +90°-about-X turn). Everything that does not depend on θ, the body's up `(0, 1, 0)`, lives in
/// row 2, which is not stored. On a data set whose takes face every way the mean of all six
/// root channels is near zero, which is what an x̂0 prediction tends to at high noise, and
/// Gram–Schmidt of a near-zero pair can land on either orientation: the v2–v5 solo PDDMs
/// committed to upside-down roots (docs/solo-data-v2.md).
pub fn root_up(raw: Tensor<3>) -> Tensor<3> {
    let a = |k: usize| raw.clone().narrow(2, layout::ROT6D_START + k, 1);
    let (a0, a1, a2, b0, b1, b2) = (a(0), a(1), a(2), a(3), a(4), a(5));
    Tensor::cat(
        vec![
            a1.clone() * b2.clone() - a2.clone() * b1.clone(),
            a2 * b0.clone() - a0.clone() * b2,
            a0 * b1 - a1 * b0,
        ],
        2,
    )
}

/// Mean squared error between the predicted and the true root up axis ([`root_up`]) of raw
/// frames `[B, T, 151]`. It is heading-free, so its target stays the same at every noise level.
/// Unnormalised on purpose: the prediction's rows are pulled to unit length and a right-handed
/// relation, with no division by a norm that can be near zero.
pub fn root_up_loss(pred_raw: Tensor<3>, truth_raw: Tensor<3>) -> Tensor<1> {
    (root_up(pred_raw) - root_up(truth_raw))
        .powf_scalar(2.0)
        .mean()
}

/// One PDDM training batch: windows `x` `[B, T, 151]` (normalised), `music` `[B, T, 35]`,
/// genres; `seed` draws the timesteps, noise, primitive modes and condition dropout.
/// `canonical_heading` turns every window into its own heading frame first (`crate::heading`).
#[allow(clippy::too_many_arguments)]
pub fn pddm_loss(
    model: &PddmTrainModel,
    canonical_heading: bool,
    x: Tensor<3>,
    music: Tensor<3>,
    genre: &[usize],
    shift: &ResidualShift,
    weights: &PddmLossWeights,
    dropout: &PrimitiveDropout,
    seed: u64,
) -> PddmLosses {
    let [b, t, _] = x.dims();
    let device = x.device();
    let mut rng = SeededNoise::new(seed);
    let mut d0 = root_relative(x);

    // Primitives and the boundary frames taken from the ground truth (paper §3.4.6).
    let mut host: Vec<f32> = d0
        .clone()
        .into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .unwrap();
    if canonical_heading {
        let (scale, shift) = model.denoiser.denorm.host();
        let stats = crate::heading::Stats {
            scale: &scale,
            shift: &shift,
        };
        crate::heading::canonicalise(&mut host, t, &stats);
        d0 = Tensor::<3>::from_data(TensorData::new(host.clone(), [b, t, DIMS]), &device);
    }
    let channels = layout::main_channels();
    let mut prim = Vec::with_capacity(b * t * DIMS);
    let mut mask = Vec::with_capacity(b * t);
    let mut boundary = vec![0f32; b * t * DIMS];
    for i in 0..b {
        let u = rng.uniform();
        let mode = if u < dropout.none {
            PrimitiveMode::None
        } else if u < dropout.none + dropout.boundaries_only {
            PrimitiveMode::BoundariesOnly
        } else {
            PrimitiveMode::Full
        };
        let w = &host[i * t * DIMS..(i + 1) * t * DIMS];
        let p = training_primitives(w, mode, &channels);
        if mode != PrimitiveMode::None {
            for f in (0..BOUNDARY_FRAMES).chain(t - BOUNDARY_FRAMES..t) {
                for c in 0..DIMS {
                    let tail_root = f >= BOUNDARY_FRAMES && ROOT_HORIZONTAL.contains(&c);
                    if !tail_root {
                        boundary[(i * t + f) * DIMS + c] = 1.0;
                    }
                }
            }
        }
        prim.extend(p.values);
        mask.extend(p.mask);
    }
    let dp = Tensor::<3>::from_data(TensorData::new(prim, [b, t, DIMS]), &device);
    let mask = Tensor::<3>::from_data(TensorData::new(mask, [b, t, 1]), &device);
    let keep_gt = Tensor::<3>::from_data(TensorData::new(boundary, [b, t, DIMS]), &device);

    let steps: Vec<usize> = (0..b).map(|_| 1 + rng.below(shift.steps())).collect();
    let d_t = shift.q_sample(
        d0.clone(),
        dp.clone(),
        &steps,
        rng.tensor([b, t, DIMS], &device),
    );
    let d_t = d0.clone() * keep_gt.clone() + d_t * (keep_gt.neg() + 1.0);
    let keep: Vec<bool> = (0..b).map(|_| rng.uniform() >= dropout.condition).collect();
    let cond = PddmCond {
        music: music.clone(),
        genre: genre.to_vec(),
        primitives: dp,
        mask,
        music_encoded: None,
    };
    let tf: Vec<f32> = steps.iter().map(|&s| (s - 1) as f32).collect();
    let out = model.denoiser.forward(
        d_t,
        &tf,
        Conditioning::Dropout {
            cond: &cond,
            keep: &keep,
        },
        true,
    );
    let mse = |a: Tensor<3>, b: Tensor<3>| (a - b).powf_scalar(2.0).mean();
    let recon = mse(out.refined.clone(), d0.clone());
    let recon_main = mse(out.main.clone(), d0.clone());

    let skel = FkSkeleton::smpl24();
    let denorm = &model.denoiser.denorm;
    let pred_raw = denorm.apply(out.refined.clone());
    let pred_raw_for_up = pred_raw.clone();
    let jp = joints(pred_raw.clone(), &skel);
    let truth_raw = denorm.apply(d0.clone());
    let jg = joints(truth_raw.clone(), &skel);
    let mse4 = |a: Tensor<4>, b: Tensor<4>| (a - b).powf_scalar(2.0).mean();
    let joint = mse4(jp.clone(), jg.clone());
    let vp = displacement(jp.clone());
    let vg = displacement(jg);
    let velocity = mse4(vp.clone(), vg.clone());
    let acceleration = mse4(displacement(vp), displacement(vg));
    // Eq. 20: foot velocity where the network itself predicts contact.
    let fv = displacement(feet(jp))
        .powf_scalar(2.0)
        .sum_dim(3)
        .reshape([b, t, 4]);
    let contact_pred = pred_raw
        .narrow(2, CONTACTS.start, CONTACTS.len())
        .clamp(0.0, 1.0);
    let contact = (fv * contact_pred).mean();

    let mut total = recon.clone()
        + recon_main.clone() * weights.main_output
        + joint.clone() * weights.joint
        + velocity.clone() * weights.velocity
        + acceleration.clone() * weights.acceleration
        + contact.clone() * weights.contact;
    let mut parts = vec![
        ("recon", recon),
        ("recon_main", recon_main),
        ("joint", joint),
        ("velocity", velocity),
        ("acceleration", acceleration),
        ("contact", contact),
    ];
    if weights.root_up > 0.0 {
        let up = root_up_loss(pred_raw_for_up, truth_raw);
        total = total + up.clone() * weights.root_up;
        parts.push(("root_up", up));
    }
    if let Some(disc) = &model.discriminator {
        let real = disc.forward(d0, music.clone(), genre);
        let fake = disc.forward(out.refined.clone().detach(), music.clone(), genre);
        let d_loss = hinge_discriminator(real, fake);
        let frozen = disc.clone().no_grad();
        let g_loss = hinge_generator(frozen.forward(out.refined, music, genre));
        total = total + d_loss.clone() * weights.discriminator + g_loss.clone() * weights.genre;
        parts.push(("disc", d_loss));
        parts.push(("genre", g_loss));
    }
    PddmLosses { total, parts }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::conventions::yup_to_zup_root_mat;
    use dancegen_motion::rotation::Mat3;

    /// Raw frames whose only non-zero channels are the root 6D of `rot` (a Y-up root rotation),
    /// stored as `Edge151` does.
    fn frames(rots: &[Mat3]) -> Tensor<3> {
        let mut v = vec![0f32; rots.len() * DIMS];
        for (f, r) in rots.iter().enumerate() {
            let six = yup_to_zup_root_mat(r).to_6d();
            for (k, x) in six.iter().enumerate() {
                v[f * DIMS + layout::ROT6D_START + k] = *x as f32;
            }
        }
        let device = dancegen_nn::device::inference();
        Tensor::<3>::from_data(TensorData::new(v, [1, rots.len(), DIMS]), &device)
    }

    fn host(x: Tensor<3>) -> Vec<f32> {
        x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn root_up_is_the_same_for_every_heading_and_flips_with_the_body() {
        // Eight headings evenly round the circle, so each stored channel's mean is 0 exactly
        // (up to rounding).
        let headings: Vec<f64> = (0..8)
            .map(|i| std::f64::consts::TAU * i as f64 / 8.0)
            .collect();
        let upright: Vec<Mat3> = headings
            .iter()
            .map(|&h| Mat3::from_axis_angle([0.0, h, 0.0]))
            .collect();
        // The stored 6D averages out over the headings: nothing in it says "up" by itself.
        let six = host(frames(&upright));
        for k in 0..6 {
            let mean: f32 = six
                .chunks(DIMS)
                .map(|f| f[layout::ROT6D_START + k])
                .sum::<f32>()
                / 8.0;
            assert!(mean.abs() < 1e-6, "channel {k} mean {mean}");
        }
        for up in host(root_up(frames(&upright))).chunks(3) {
            assert!(
                (up[0].abs() + (up[1] - 1.0).abs() + up[2].abs()) < 1e-5,
                "{up:?}"
            );
        }
        // Upside down (half a turn about the body's x axis after the heading): up is −Y.
        let inverted: Vec<Mat3> = upright
            .iter()
            .map(|r| r.mul(&Mat3::from_axis_angle([std::f64::consts::PI, 0.0, 0.0])))
            .collect();
        for up in host(root_up(frames(&inverted))).chunks(3) {
            assert!((up[1] + 1.0).abs() < 1e-5, "{up:?}");
        }
        // The loss: zero against itself, (0² + 2² + 0²) / 3 per frame against the flip.
        let scalar = |x: Tensor<1>| x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()[0];
        let same = scalar(root_up_loss(frames(&upright), frames(&upright)));
        let flip = scalar(root_up_loss(frames(&inverted), frames(&upright)));
        assert!(same.abs() < 1e-10, "{same}");
        assert!((flip - 4.0 / 3.0).abs() < 1e-4, "{flip}");
    }
}
