//! Diffusion for the four dance systems: one sampler with pluggable conditioning.
//!
//! - [`schedule`]: the cosine / linear β schedules of EDGE (T = 1000) with every derived table in
//!   f64, `q_sample`, and the x0-prediction training loss with classifier-free condition dropout
//!   (anchors D.1: EDGE, Lodge, TCDiff++ all predict x0 with an L2 loss, dropout 0.25).
//! - [`sampler`]: DDPM ancestral sampling and EDGE's strided DDIM (eta), classifier-free guidance
//!   with one scale (EDGE) or per-channel-group scales (ReactDance LDCFG), a guidance-weight
//!   schedule (EDGE's long-form ramp), hard / soft inpainting cues (EDGE, Lodge) and EDGE's
//!   long-form window overwrite.
//! - [`pddm`]: Lodge++'s residual-shifting forward process and its reverse step (paper §3.4.1).
//! - [`longform`]: EDGE's final stitching of overlapping windows (linear cross-fade, quaternion
//!   slerp of 6D-rotation channels).
//! - [`noise`]: seeded Gaussian noise, so a sample is a function of its seed on every backend.
//!
//! A system plugs in by implementing [`Denoiser`] for its network, with its own condition type
//! (music tokens, leader motion, primitives + genre, …).

pub mod longform;
pub mod noise;
pub mod pddm;
pub mod sampler;
pub mod schedule;

use burn::tensor::{Int, Tensor};

pub use noise::SeededNoise;
pub use sampler::{
    ChannelScale, Cue, CueActivity, DpmPrevious, Guidance, Method, SampleOptions, Solver, Spacing,
    WeightSchedule, ddim_step, ddim_timesteps, ddim_timesteps_spaced, ddpm_step, dpmpp_2m_step,
    overwrite_first_halves, sample, sample_hooked, sample_with,
};
pub use schedule::{BetaSchedule, Schedule, x0_loss};

/// What the denoiser is conditioned on in one call.
///
/// Classifier-free guidance (Ho & Salimans 2022, as in EDGE's `guided_forward`) needs a
/// conditional and an unconditional prediction of the same network; training needs per-sample
/// condition dropout. The denoiser maps "no condition" to its own null embedding (EDGE learns
/// `null_cond_embed`), which is why the choice is passed down instead of a zeroed condition.
pub enum Conditioning<'a, C> {
    /// Every batch element sees the condition.
    Full(&'a C),
    /// No batch element sees it (the unconditional branch of guidance).
    Null,
    /// Classifier-free dropout in training: batch element `b` sees the condition iff `keep[b]`.
    Dropout { cond: &'a C, keep: &'a [bool] },
}

/// A network that predicts the clean sample x̂0 from a noisy `x_t` `[B, T, C]` and integer
/// timesteps `[B]` (0-based: 0 is the least noisy step). All four systems' diffusion models
/// are x0-predictors (anchors D.1–D.5), so the sampler needs nothing else.
pub trait Denoiser {
    /// The system's condition (music features, leader motion, primitives, …).
    type Cond;

    /// x̂0 `[B, T, C]`.
    fn predict_x0(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        cond: Conditioning<'_, Self::Cond>,
    ) -> Tensor<3>;

    /// Both branches of classifier-free guidance, `(conditional, unconditional)`. The default
    /// makes the two calls; a network that can stack the branches into one batch of `2B`
    /// overrides it, so each step is one pass over the weights with GEMMs twice as tall, which
    /// is what small batches (LGDS's single window) need.
    fn predict_x0_guided(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        cond: &Self::Cond,
    ) -> (Tensor<3>, Tensor<3>) {
        separate_guidance_branches(self, x_t, t, cond)
    }
}

/// [`Denoiser::predict_x0_guided`] as two calls, one per branch: the default, and the fallback
/// of an override that cannot stack the branches.
pub fn separate_guidance_branches<M: Denoiser + ?Sized>(
    model: &M,
    x_t: Tensor<3>,
    t: Tensor<1, Int>,
    cond: &M::Cond,
) -> (Tensor<3>, Tensor<3>) {
    let full = model.predict_x0(x_t.clone(), t.clone(), Conditioning::Full(cond));
    let null = model.predict_x0(x_t, t, Conditioning::Null);
    (full, null)
}
