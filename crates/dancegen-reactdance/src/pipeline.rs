//! Leader + music → follower: the whole reactive pipeline.
//!
//! 1. The leader's features ([`DuetLeader`]) and the music (EDGE-35 at 30 fps), padded to a
//!    whole number of latent tokens by repeating the last frame, grouped per token.
//! 2. The latent sampled by BLC (or the autoregressive ablation) with LDCFG ([`crate::blc`]).
//! 3. The whole latent decoded at once by the HFSQ decoder, cut to the leader's length,
//!    de-normalised, and put into the leader's world frame ([`DuetFollower::decode`]).
//! 4. Unless turned off, the follower is moved out of the leader's body where the two
//!    interpenetrate, by a smooth horizontal offset of its root
//!    ([`dancegen_refine::couple_separation`]; hands may touch). Not in the paper: the model
//!    places the follower from a learned relative position, and at partner distance its
//!    centimetre errors put trunks through each other (docs/duet-eval.md measures both).
//!
//! **Editing** ([`KnownFollower`]): the frames of the follower an edit keeps are encoded by the
//! HFSQ encoder, and the tokens they alone decide are hard cues to the latent sampler
//! ([`crate::blc::LatentCue`]); the rest of the latent is generated to go with them. The
//! caller joins the decoded follower to the kept frames and keeps them exactly.
//!
//! Heights are relative to the leader's floor (where its planted feet rest,
//! [`planted_floor_height`], as the training couples were grounded): the model was trained on
//! couples standing on y = 0, and a leader recorded with another floor height gets a follower on
//! its own floor.

use std::time::Instant;

use dancegen_motion::repr::motion::{GroundMode, planted_floor_height};
use dancegen_motion::repr::{DuetFollower, DuetLeader, SmplMotion};
use dancegen_nn::burn::tensor::{Device, Tensor, TensorData};
use dancegen_nn::diffusion::{BetaSchedule, Schedule};
use dancegen_nn::progress::{Cancelled, NoHook, StepHook};
use dancegen_refine::couple_separation::{SeparationConfig, separation_offsets};

use crate::blc::{LatentCue, LatentSampling, sample_latent_cued_hooked};
use crate::bundle::DuetModel;
use crate::config::MUSIC_DIMS;
use crate::denoiser::DuetCond;

/// A generated follower.
pub struct Generated {
    pub follower: SmplMotion,
    /// The model's foot contacts `[T, 4]` (SMPL joints 7, 8, 10, 11, as
    /// [`DuetFollower::CONTACTS`]; nominally 0 or 1), frame for frame with `follower`.
    pub contacts: Vec<f32>,
    /// Seconds spent sampling the latent and decoding it.
    pub sample_s: f64,
    pub decode_s: f64,
    /// Joint rotations (over joints and frames) whose generated 6D rows had lost their length
    /// and were bridged between their neighbours (`dancegen_motion::rot6d_track`).
    pub rotations_bridged: usize,
    /// Largest horizontal offset (metres) the separation gave the follower; 0 without it.
    pub separation_max_m: f64,
    /// Seconds spent on the separation.
    pub separate_s: f64,
}

/// `rows` frames of `width` values padded to `frames` by repeating the last frame.
fn pad_frames(data: &[f32], width: usize, frames: usize) -> Vec<f32> {
    let mut v = data.to_vec();
    let last = data[data.len() - width..].to_vec();
    while v.len() < frames * width {
        v.extend_from_slice(&last);
    }
    v
}

/// Generates the follower of `leader` (30 fps) on `music` (`(T, 35)` EDGE features at 30 fps,
/// at least as many frames as the leader; extra frames are ignored). `separation: None` leaves
/// the follower where the model put it.
pub fn generate_follower(
    model: &DuetModel,
    leader: &SmplMotion,
    music: &[f32],
    sampling: &LatentSampling,
    separation: Option<&SeparationConfig>,
    device: &Device,
) -> Result<Generated, String> {
    generate_follower_hooked(model, leader, music, sampling, separation, device, &NoHook)
        .map_err(|e| e.to_string())
}

/// Why [`generate_follower_hooked`] stopped.
#[derive(Debug, thiserror::Error)]
pub enum FollowerError {
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
    #[error("{0}")]
    Invalid(String),
}

impl From<String> for FollowerError {
    fn from(s: String) -> Self {
        FollowerError::Invalid(s)
    }
}

/// Moves `follower` horizontally out of `leader`'s body (the couple separation,
/// [`dancegen_refine::couple_separation`]); returns the largest offset, metres. Both dancers in
/// the same world frame.
pub fn separate_follower(
    follower: &mut SmplMotion,
    leader: &SmplMotion,
    config: &SeparationConfig,
) -> Result<f64, String> {
    let joints = |m: &SmplMotion| -> Result<Vec<f64>, String> {
        let j = m.joints_world().map_err(|e| e.to_string())?;
        Ok(j.into_iter().map(f64::from).collect())
    };
    let offsets = separation_offsets(&joints(follower)?, &joints(leader)?, config);
    let mut largest = 0.0f64;
    for (p, [dx, dz]) in follower.trans.chunks_exact_mut(3).zip(offsets) {
        p[0] += dx as f32;
        p[2] += dz as f32;
        largest = largest.max(dx.hypot(dz));
    }
    Ok(largest)
}

/// [`generate_follower`], telling `hook` after every denoising step and stopping with
/// [`FollowerError::Cancelled`] when it answers `Break`.
pub fn generate_follower_hooked(
    model: &DuetModel,
    leader: &SmplMotion,
    music: &[f32],
    sampling: &LatentSampling,
    separation: Option<&SeparationConfig>,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Generated, FollowerError> {
    generate_follower_known(
        model, leader, music, sampling, separation, None, device, hook,
    )
}

/// What an edit keeps of the follower: `motion` (the leader's length, in the leader's world
/// frame; any values on frames not kept) and, per frame, whether it is `kept`.
pub struct KnownFollower<'a> {
    pub motion: &'a SmplMotion,
    pub kept: &'a [bool],
}

/// [`generate_follower_hooked`] for an edit: the latent tokens that only `known`'s kept
/// frames decide are imposed (module documentation). The result is the model's whole
/// follower; the caller joins it to the kept frames.
#[allow(clippy::too_many_arguments)]
pub fn generate_follower_known(
    model: &DuetModel,
    leader: &SmplMotion,
    music: &[f32],
    sampling: &LatentSampling,
    separation: Option<&SeparationConfig>,
    known: Option<&KnownFollower<'_>>,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Generated, FollowerError> {
    let t = leader.frames();
    if t == 0 {
        return Err(FollowerError::Invalid("the leader has no frames".into()));
    }
    if music.len() < t * MUSIC_DIMS {
        return Err(FollowerError::Invalid(format!(
            "{} music frames for a {t}-frame leader",
            music.len() / MUSIC_DIMS
        )));
    }
    let ae = &model.config.autoencoder;
    let f = ae.frames_per_token();
    let k = t.div_ceil(f);
    let frames = k * f;
    // The floor the training couples were put on (`SmplMotion::put_feet_on_floor`: where the
    // planted feet rest), so the model sees the leader as it saw the real ones. The 10th
    // percentile used before sits 0.6-3.1 cm under the resting feet of the real salsa leaders,
    // which lifted every leader by that much and sank its follower by as much.
    let leader_joints = leader.joints_world().map_err(|e| e.to_string())?;
    let floor = planted_floor_height(&leader_joints, leader.fps)
        .unwrap_or_else(|| SmplMotion::ground_height(&leader_joints, GroundMode::SupportFeet));
    let mut grounded = leader.clone();
    for p in grounded.trans.chunks_exact_mut(3) {
        p[1] -= floor;
    }
    let leader = &grounded;
    let sigma = model.config.heading_sigma;
    let mut lead = DuetLeader::encode(leader, sigma).map_err(|e| e.to_string())?;
    let (lm, ls) = (
        &model.norm.mean[DuetFollower::DIMS..],
        &model.norm.std[DuetFollower::DIMS..],
    );
    for row in lead.chunks_exact_mut(DuetLeader::DIMS) {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ((f64::from(*v) - lm[j]) / ls[j]) as f32;
        }
    }
    let lead = pad_frames(&lead, DuetLeader::DIMS, frames);
    let mus = pad_frames(&music[..t * MUSIC_DIMS], MUSIC_DIMS, frames);
    let cond = DuetCond {
        leader: Tensor::from_data(TensorData::new(lead, [1, k, f * DuetLeader::DIMS]), device),
        music: Tensor::from_data(TensorData::new(mus, [1, k, f * MUSIC_DIMS]), device),
    };
    let schedule = Schedule::new(BetaSchedule::Cosine, model.config.denoiser.timesteps);
    let t0 = Instant::now();
    let cue = match known {
        Some(k) => Some(latent_cue(model, leader, floor, k, frames, device)?),
        None => None,
    };
    let latent = sample_latent_cued_hooked(
        &model.denoiser,
        &schedule,
        &cond,
        ae.latent_dim(),
        ae.num_levels,
        sampling,
        cue.as_ref(),
        device,
        hook,
    )?;
    let sample_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let decoded = model.autoencoder.decode(latent).narrow(1, 0, t);
    let mut data = decoded
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .map_err(|e| format!("decoded latent: {e:?}"))?;
    let (fm, fs) = (
        &model.norm.mean[..DuetFollower::DIMS],
        &model.norm.std[..DuetFollower::DIMS],
    );
    for row in data.chunks_exact_mut(DuetFollower::DIMS) {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (f64::from(*v) * fs[j] + fm[j]) as f32;
        }
    }
    let contacts: Vec<f32> = data
        .chunks_exact(DuetFollower::DIMS)
        .flat_map(|row| row[DuetFollower::CONTACTS].iter().copied())
        .collect();
    let (mut follower, rotations_bridged) =
        DuetFollower::decode_counted(&data, leader, sigma).map_err(|e| e.to_string())?;
    if rotations_bridged > 0 {
        tracing::info!(
            rotations = rotations_bridged,
            "bridged generated joint rotations whose 6D rows had shrunk below {} (a turn \
             passed through the origin)",
            dancegen_motion::rot6d_track::MIN_ROW_LENGTH
        );
    }
    if follower
        .trans
        .iter()
        .chain(&follower.poses)
        .any(|v| !v.is_finite())
    {
        return Err(FollowerError::Invalid(
            "the model produced non-finite values".into(),
        ));
    }
    let decode_s = t1.elapsed().as_secs_f64();
    let mut separation_max_m = 0.0f64;
    let t2 = Instant::now();
    if let Some(config) = separation {
        separation_max_m = separate_follower(&mut follower, leader, config)?;
    }
    for p in follower.trans.chunks_exact_mut(3) {
        p[1] += floor;
    }
    Ok(Generated {
        follower,
        contacts,
        sample_s,
        decode_s,
        rotations_bridged,
        separation_max_m,
        separate_s: t2.elapsed().as_secs_f64(),
    })
}

/// The latent cue of an edit: the kept follower (grounded as the leader was, by `floor`)
/// encoded to the latent, and the tokens all of whose frames, and one token's worth on each
/// side (the codec's convolutions see their neighbours), are kept.
fn latent_cue(
    model: &DuetModel,
    leader: &SmplMotion,
    floor: f32,
    known: &KnownFollower<'_>,
    frames: usize,
    device: &Device,
) -> Result<LatentCue, FollowerError> {
    let t = leader.frames();
    if known.motion.frames() != t || known.kept.len() != t {
        return Err(FollowerError::Invalid(format!(
            "the kept follower has {} frames for a {t}-frame leader",
            known.motion.frames()
        )));
    }
    let mut follower = known.motion.clone();
    for p in follower.trans.chunks_exact_mut(3) {
        p[1] -= floor;
    }
    let mut data = DuetFollower::encode(&follower, leader, model.config.heading_sigma)
        .map_err(|e| e.to_string())?;
    let (fm, fs) = (
        &model.norm.mean[..DuetFollower::DIMS],
        &model.norm.std[..DuetFollower::DIMS],
    );
    for row in data.chunks_exact_mut(DuetFollower::DIMS) {
        for (j, v) in row.iter_mut().enumerate() {
            *v = ((f64::from(*v) - fm[j]) / fs[j]) as f32;
        }
    }
    let data = pad_frames(&data, DuetFollower::DIMS, frames);
    let x = Tensor::from_data(
        TensorData::new(data, [1, frames, DuetFollower::DIMS]),
        device,
    );
    let latent = model.autoencoder.encode(x);
    let [_, k, _] = latent.dims();
    let value = latent
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .map_err(|e| format!("encoded follower: {e:?}"))?;
    let f = model.config.autoencoder.frames_per_token();
    let kept = |g: usize| known.kept[g.min(t - 1)];
    let known_tokens = (0..k)
        .map(|i| {
            let lo = (i * f).saturating_sub(f);
            let hi = ((i + 2) * f).min(frames);
            (lo..hi).all(kept)
        })
        .collect();
    Ok(LatentCue {
        value,
        known: known_tokens,
    })
}
