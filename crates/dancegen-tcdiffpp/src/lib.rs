//! dancegen's group dance system, after TCDiff++ (Dai et al., `shared/papers/tcdiffpp.md`;
//! `shared/reference/group.md` lists where the released code departs from the paper and which
//! choice we take).
//!
//! One diffusion model makes 2 to [`layout::N_MAX`] dancers at once:
//! - [`layout`]: a group window is `[B, T, N_MAX · 151]` (EDGE-151 per dancer slot, slots sorted
//!   left to right as the audience sees them at frame 0); the network reads it as frame-major
//!   tokens (token `k` = frame `k / N_MAX`, slot `k % N_MAX`, as the released `p_losses`);
//!   empty slots are masked.
//! - [`denoiser`]: the Group Dance Decoder (input projection + dancer positioning embedding,
//!   [`fusion`] projection, FiLM transformer or [`cross_mamba`] sequence decoder layers,
//!   [`swap`] mode as FiLM input and memory token) followed by the [`footwork`] adaptor;
//!   optionally (ours) the root integrated from per-frame steps, [`root_path`], and the
//!   heading from per-frame turns, [`heading_path`].
//! - [`losses`]: EDGE's terms plus the pairwise distance-consistency loss (paper Eq. 16–17).
//! - [`sampler`]: long group diffusion sampling (LGDS, keeping window 0) and the parallel
//!   EDGE-style long-form sampler, both with formation control by clean root injection.
//!
//! Shared pieces (FiLM decoder layer, Mamba, DDIM sampler with cues, EDGE-151 kinematics,
//! long-form stitching) come from `dancegen-nn`.

pub mod bundle;
pub mod config;
pub mod cross_mamba;
pub mod denoiser;
pub mod footwork;
pub mod fusion;
pub mod heading_path;
pub mod known;
pub mod layout;
pub mod losses;
pub mod prediction;
pub mod root_path;
pub mod sampler;
pub mod swap;
pub mod window;
