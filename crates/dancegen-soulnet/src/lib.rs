//! dancegen's holistic system, after SoulNet (`shared/papers/soulnet.md`; what its released code
//! really does: `shared/reference/holistic.md`): body, fingers and face in one dance.
//!
//! - [`layout`]: the split vector `[body 263 | hands 360 | face 52]` and its decoding;
//! - [`config`]: the three networks' tables and the sampling defaults;
//! - the part autoencoder (HRVQ-VAE, `dancegen_nn::part_autoencoder`) turns a window into
//!   body → hands → face residual tokens;
//! - the music–motion retrieval model (`dancegen_nn::retrieval`) embeds a window's music;
//! - [`generator`]: masked + residual transformers over the part tokens, conditioned on that
//!   embedding and on the music of each token's frames;
//! - [`pipeline`]: music of any length → tokens window by window (inpainting the overlap) →
//!   holistic frames; [`bundle`]: the model on disk;
//! - [`body_feet`]: the feet's velocities from the rows, for the autoencoder's foot loss.
//!
//! The hands and faces of the shipped model are synthetic (`docs/holistic-data.md`).

pub mod body_feet;
pub mod bundle;
pub mod config;
pub mod generator;
pub mod layout;
pub mod pipeline;
