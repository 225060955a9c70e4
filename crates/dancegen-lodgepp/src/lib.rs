//! Lodge++ (Li et al., "Lodge++: High-quality and Long Dance Generation with Vivid Choreography
//! Patterns", `../shared/papers/lodgepp.md`): long solo dances from music and a genre, coarse to
//! fine.
//!
//! 1. **Global Choreography Network** ([`choreo_gpt`]): a VQ-VAE (`dancegen_nn::autoencoder`)
//!    over the 6D rotations of 7 main joints, 4× temporal downsampling, EMA codebook; a GPT
//!    generates the whole song's tokens window by window; the VQ decoder turns them into a
//!    coarse dance.
//! 2. **Dance primitives** ([`primitives`]): 8-frame key motions at the coarse dance's motion
//!    beats, moved onto the nearest music beats, and the 8 frames around every window boundary;
//!    full-body clips are retrieved from a library of real motion by the coarse joints (D.3).
//! 3. **PDDM** ([`denoiser`]): Lodge++'s residual-shifting diffusion
//!    (`dancegen_nn::diffusion::pddm`) denoises every 128-frame window in parallel from its
//!    primitives, with a Foot Refine Block ([`foot_refine`]); trained with joint, velocity,
//!    acceleration and contact losses and a multi-genre discriminator ([`discriminator`]).
//! 4. **Penetration guidance** ([`penetration`]): the SMPL-X mesh and COAP are not available, so
//!    hand and forearm points are pushed out of a capsule body (`dancegen_motion`'s capsules)
//!    by the gradient of its signed distance during denoising.
//!
//! 5. **Planted feet** ([`planted_feet`], not part of Lodge++): the root stops gliding with the
//!    support foot, and (when the bundle asks for it) leg IK pins planted ankles and toes
//!    (`--no-foot-lock` switches it off).
//! 6. **Decoding** ([`rotation_tracks`], [`seams`], [`root_flips`], not part of Lodge++): joint
//!    rotations whose 6D rows shrank are bridged, windows meet their cued frames, and one- to
//!    three-frame root flips are repaired.
//!
//! Motion is EDGE's 151-dim vector at 30 fps ([`layout`]).

pub mod bundle;
pub mod choreo_gpt;
pub mod config;
pub mod denoiser;
pub mod discriminator;
pub mod foot_refine;
pub mod heading;
pub mod inpaint;
pub mod kinematics;
pub mod layout;
pub mod library;
pub mod penetration;
pub mod pipeline;
pub mod planted_feet;
pub mod primitives;
pub mod root_flips;
pub mod rotation_tracks;
pub mod sampler;
pub mod seams;
pub mod training;

pub use dancegen_nn::burn::tensor::Device;

/// The device generation runs on (the flex CPU backend, or CUDA with dancegen-nn's `cuda`).
pub fn inference_device() -> Device {
    dancegen_nn::device::inference()
}
