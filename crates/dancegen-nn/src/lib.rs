//! Neural building blocks shared by dancegen's four dance systems (Lodge++, TCDiff++,
//! ReactDance, SoulNet), on Burn 0.22.
//!
//! One copy of each piece: an attention block, a sampler or a quantizer used by two systems
//! lives here once, configured, never duplicated.
//!
//! Conventions:
//! - Sequences are batch-first `[batch, frames, channels]`.
//! - Attention masks use Burn's convention: `true` = the query may **not** attend to the key.
//! - Parameter names follow the PyTorch reference modules (`tools/parity/*.py`), so a PyTorch
//!   state dict saved as safetensors loads with [`weights::load`] in [`weights::Layout::PyTorch`]
//!   (Linear weights transposed, LayerNorm `weight/bias` → `gamma/beta`).
//! - Models are built on [`device::inference`] or, to train, [`device::training`] (the autodiff
//!   decorator); see `../shared/reference/rust-ml-stack.md` for why that matters.

pub use burn;

pub mod attention;
pub mod autoencoder;
pub mod conv;
pub mod denormalize;
pub mod device;
pub mod diffusion;
pub mod edge151;
pub mod film;
pub mod gpt;
pub mod host_attention;
pub mod host_linear;
pub mod host_view;
pub mod loss;
pub mod mask;
pub mod masked;
pub mod mlp;
pub mod part_autoencoder;
pub mod pos_encoding;
pub mod progress;
pub mod quant;
pub mod residual_transformer;
pub mod retrieval;
pub mod rng;
pub mod ssm;
pub mod timestep;
pub mod transformer;
pub mod vector_math;
pub mod weights;
