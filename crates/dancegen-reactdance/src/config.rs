//! The model configuration (`model.toml` of a bundle, `[model]` of the training configs).
//!
//! ReactDance publishes no code and none of these values (anchors D.5: FSQ levels, block size,
//! guidance scales are UNVERIFIED); every default below is our choice, sized for a model that
//! trains on the CMU salsa couples in well under two hours on a 2-core CPU. `docs/duet-eval.md`
//! measures them.

use serde::{Deserialize, Serialize};

use dancegen_motion::repr::{DuetFollower, DuetLeader};
use dancegen_refine::foot_lock::PlantedRule;

/// Motion frames per latent token: the conv encoder halves the frame rate `down_t` times.
pub fn frames_per_token(down_t: usize) -> usize {
    1 << down_t
}

/// The HFSQ autoencoder: one conv encoder → HFSQ → conv decoder per follower stream.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HfsqAutoencoderConfig {
    /// Hidden channels of each stream's conv encoder / decoder.
    pub width: usize,
    /// Residual blocks per resolution.
    pub depth: usize,
    /// Halvings of the frame rate (2: 30 fps → 7.5 latent tokens per second).
    pub down_t: usize,
    /// HFSQ groups `G` per stream.
    pub groups: usize,
    /// FSQ levels of each group's dimensions (odd levels keep the grid symmetric about 0).
    pub levels: Vec<usize>,
    /// Residual levels `R` (level 1 = coarse, levels ≥ 2 = fine).
    pub num_levels: usize,
    /// Progressive masking: probability of zeroing the levels above a random level …
    pub residual_mask_prob: f64,
    /// … while adding Gaussian noise of this std to the base level.
    pub residual_noise_std: f64,
    /// Progressive masking: probability of zeroing one code dimension.
    pub code_mask_prob: f64,
    /// Kinematic L1 weights: features, velocity, acceleration.
    pub position_weight: f64,
    pub velocity_weight: f64,
    pub acceleration_weight: f64,
    /// Latent (commitment) loss weight.
    pub latent_weight: f64,
    /// Weight of the foot velocity loss (`crate::follower_feet`; m/s). Not in the paper:
    /// our addition, 0 (off) unless a configuration sets it.
    pub foot_velocity_weight: f64,
}

impl Default for HfsqAutoencoderConfig {
    fn default() -> Self {
        Self {
            width: 128,
            depth: 2,
            down_t: 2,
            groups: 2,
            levels: vec![7, 5, 5, 5],
            num_levels: 3,
            residual_mask_prob: 0.3,
            residual_noise_std: 0.05,
            code_mask_prob: 0.05,
            position_weight: 1.0,
            velocity_weight: 1.0,
            acceleration_weight: 0.5,
            latent_weight: 0.02,
            foot_velocity_weight: 0.0,
        }
    }
}

impl HfsqAutoencoderConfig {
    /// Latent channels of one stream (`G × levels.len()`).
    pub fn stream_dim(&self) -> usize {
        self.groups * self.levels.len()
    }

    /// Channels of one level over the three streams.
    pub fn level_dim(&self) -> usize {
        DuetFollower::STREAMS.len() * self.stream_dim()
    }

    /// Channels of the diffusion latent (`R` levels × 3 streams × stream dim), level-major.
    pub fn latent_dim(&self) -> usize {
        self.num_levels * self.level_dim()
    }

    pub fn frames_per_token(&self) -> usize {
        frames_per_token(self.down_t)
    }

    /// The same network and latent (every field but the training-only loss weights and
    /// masking probabilities): weights of one load into the other, and a latent model trained on
    /// one reads the other's latent.
    pub fn same_architecture(&self, other: &Self) -> bool {
        self.width == other.width
            && self.depth == other.depth
            && self.down_t == other.down_t
            && self.groups == other.groups
            && self.levels == other.levels
            && self.num_levels == other.num_levels
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.levels.is_empty() || self.levels.iter().any(|&l| l < 2) {
            return Err("autoencoder.levels: every FSQ level count must be ≥ 2".into());
        }
        if self.groups == 0 || self.num_levels == 0 || self.width == 0 {
            return Err("autoencoder: groups, num_levels and width must be ≥ 1".into());
        }
        if self.down_t == 0 || self.down_t > 4 {
            return Err("autoencoder.down_t must be 1..=4".into());
        }
        if !(self.foot_velocity_weight.is_finite() && self.foot_velocity_weight >= 0.0) {
            return Err(format!(
                "autoencoder.foot_velocity_weight must be a number ≥ 0, not {}",
                self.foot_velocity_weight
            ));
        }
        Ok(())
    }
}

/// The latent diffusion transformer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DenoiserConfig {
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    /// Transformer encoder layers over the leader tokens before cross-attention.
    pub leader_layers: usize,
    pub dropout: f64,
    /// BLC block = training window, in latent tokens (60 tokens = 240 frames = 8 s).
    pub block_tokens: usize,
    /// Causal attention inside a block (the literal "periodic causal" reading); `false` lets a
    /// block's tokens see each other both ways (the block-diagonal reading).
    pub causal: bool,
    /// Diffusion steps of the cosine schedule in training.
    pub timesteps: usize,
    /// Also feed each encoded leader token to the decoder as a FiLM vector of the follower
    /// token at the same time (added to the music's), besides the paper's cross-attention.
    /// Ours, not ReactDance's: with the cross-attention alone the follower's timing is
    /// unrelated to the leader's (held-out Beat Echo Degree without the beat alignment 0.21,
    /// about what random beats score; docs/solo-data-v2.md, round ten). `false` is the paper's
    /// design and the default for bundles without the key.
    pub leader_film: bool,
}

impl Default for DenoiserConfig {
    fn default() -> Self {
        Self {
            d_model: 192,
            n_layers: 4,
            n_heads: 6,
            d_ff: 384,
            leader_layers: 1,
            dropout: 0.1,
            block_tokens: 60,
            causal: false,
            timesteps: 1000,
            leader_film: false,
        }
    }
}

impl DenoiserConfig {
    pub fn validate(&self) -> Result<(), String> {
        if self.d_model == 0 || !self.d_model.is_multiple_of(self.n_heads.max(1)) {
            return Err("denoiser.d_model must be a positive multiple of n_heads".into());
        }
        if !self.d_model.is_multiple_of(2) {
            return Err("denoiser.d_model must be even (phase-aligned encoding)".into());
        }
        if self.block_tokens < 2 {
            return Err("denoiser.block_tokens must be ≥ 2".into());
        }
        Ok(())
    }
}

/// Losses of the diffusion stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LatentLossWeights {
    /// `λ_r` per residual level (missing levels use the last value).
    pub levels: Vec<f64>,
    /// Kinematic L1 of the decoded prediction (features, velocity).
    pub kinematic: f64,
    /// Leader-follower relative orientation: the decoded root rotation in the leader's heading
    /// frame against the real one (rotation matrices, L1).
    pub relative_orientation: f64,
    /// Foot contact: velocity of the decoded feet (pelvis frame plus the relative root motion)
    /// on the real follower's contact frames.
    pub foot_contact: f64,
    /// Foot velocity (ours, not in the paper; 0 = off): L1 between the decoded and the real
    /// follower's world foot velocities in m/s (`crate::follower_feet`).
    pub foot_velocity: f64,
    /// Independent condition dropout per level (LDCFG training), paper: 0.2.
    pub cond_drop: f64,
}

impl Default for LatentLossWeights {
    fn default() -> Self {
        Self {
            levels: vec![1.0, 0.5, 0.25],
            kinematic: 0.5,
            relative_orientation: 0.5,
            foot_contact: 0.5,
            foot_velocity: 0.0,
            cond_drop: 0.2,
        }
    }
}

impl LatentLossWeights {
    pub fn level(&self, r: usize) -> f64 {
        self.levels
            .get(r)
            .or(self.levels.last())
            .copied()
            .unwrap_or(1.0)
    }
}

/// Default leash of the follower's root lock (frames; [`SamplingDefaults::foot_lock_leash_frames`]).
/// Chosen on four training couples (`target/datasets/duet-val`, seeds 0-2, with the model's
/// contacts and [`PlantedRule::Both`]): 15 / 30 / 60 frames gave BED 0.423 / 0.458 / 0.424
/// and FID_cd 300 / 234 / 192 against 0.448 and 365 without the lock (docs/solo-data-v2.md,
/// round eight).
pub const FOLLOWER_LEASH_FRAMES: f64 = 30.0;

/// Sampling defaults a bundle ships with (the CLI overrides them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplingDefaults {
    /// DDIM steps.
    pub steps: usize,
    /// LDCFG `s_r` per level (`w_r = 1 + s_r`); missing levels use the last value.
    pub guidance: Vec<f64>,
    /// DDIM stochasticity (EDGE: 1; 0 = deterministic DDIM).
    pub eta: f64,
    /// Keep the follower's root from gliding over its planted feet (root lock on a leash;
    /// `dancegen_lodgepp::planted_feet`; post-processing, not part of ReactDance).
    pub foot_lock: bool,
    /// Time constant (frames) of the root lock's leash: a removed glide is given back over
    /// about this long, so the follower keeps the place the model gives it beside the leader.
    pub foot_lock_leash_frames: f64,
    /// When a follower's foot counts as planted: the model's contact channel and/or nearness
    /// to the floor ([`PlantedRule`]).
    pub foot_lock_rule: PlantedRule,
}

impl SamplingDefaults {
    /// Values the sampler and the post-processing cannot use, named by their `model.toml` key.
    pub fn validate(&self) -> Result<(), String> {
        let leash = self.foot_lock_leash_frames;
        if !(leash.is_finite() && leash > 0.0) {
            return Err(format!(
                "sampling.foot_lock_leash_frames must be a positive number of frames, not {leash}"
            ));
        }
        Ok(())
    }
}

impl Default for SamplingDefaults {
    fn default() -> Self {
        Self {
            // 10 DDIM steps keep a 2000-frame follower under 2 s end to end on 2 cores; on the
            // held-out couples 10 and 20 steps measured alike (docs/duet-eval.md, FID_k 378 vs
            // 386, IPR 31.8 vs 30.8 %).
            steps: 10,
            // Chosen on two training couples (60_05, 61_02; seed 0): the coarse scale sets how
            // close the follower dances. s_coarse 1.5 / 2 / 2.5 gave 25.6 / 20.4 / 15.9 %
            // interpenetration and 75 / 71 / 66 % contact range against the real followers'
            // 18.2 % and 75 %; higher scales also add jerk.
            guidance: vec![2.0, 0.5],
            eta: 1.0,
            foot_lock: true,
            foot_lock_leash_frames: FOLLOWER_LEASH_FRAMES,
            foot_lock_rule: PlantedRule::Both,
        }
    }
}

/// Leader and music channels per latent token.
pub fn leader_token_dim(frames_per_token: usize) -> usize {
    DuetLeader::DIMS * frames_per_token
}

/// EDGE-35 music features per frame.
pub const MUSIC_DIMS: usize = 35;

pub fn music_token_dim(frames_per_token: usize) -> usize {
    MUSIC_DIMS * frames_per_token
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_leash_that_is_not_a_positive_number_of_frames_is_refused_by_name() {
        assert!(SamplingDefaults::default().validate().is_ok());
        for bad in [0.0, -30.0, f64::NAN, f64::INFINITY] {
            let s = SamplingDefaults {
                foot_lock_leash_frames: bad,
                ..Default::default()
            };
            let e = s.validate().unwrap_err();
            assert!(e.contains("sampling.foot_lock_leash_frames"), "{e}");
        }
    }
}
