//! dancegen's reactive duet system, after ReactDance (Lin et al., ICLR 2026, arXiv 2505.05589;
//! `shared/papers/reactdance.md`, anchors D.5 — no public code, so the unpublished choices are
//! ours and are named where they are made).
//!
//! Given a leader's motion and the music, it generates the partner ("reactor", here the
//! follower):
//! - [`autoencoder`]: the HFSQ autoencoder over the follower's three streams (upper body, lower
//!   body, root relative to the leader; `dancegen_motion::repr::duet`), with progressive masking;
//! - [`follower_feet`]: the follower's feet from its features, for the autoencoder's foot loss;
//! - [`denoiser`]: the latent diffusion transformer, leader by cross-attention, music by FiLM;
//! - [`blc`]: Blocked Local Context sampling (all blocks in parallel, phase-aligned positions)
//!   with layer-wise decoupled guidance, and the autoregressive ablation;
//! - [`training`]: the losses of both stages (LDCFG's per-level condition dropout);
//! - [`pipeline`]: leader + music → follower; [`bundle`]: the model on disk.
//!
//! Shared pieces (conv codec, HFSQ, FiLM decoder layers, the DDIM sampler with per-channel
//! guidance, masks, phase-aligned encoding) come from `dancegen-nn`.

pub mod autoencoder;
pub mod blc;
pub mod bundle;
pub mod config;
pub mod denoiser;
pub mod follower_feet;
pub mod pipeline;
pub mod training;
