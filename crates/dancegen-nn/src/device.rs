//! Which device the models run on: Burn's pure-Rust `flex` CPU backend, or CUDA with the
//! `cuda` feature (for GPU users; not built in CI because its build script downloads LLVM).

use burn::tensor::Device;

/// The device for inference: CUDA device 0 with the `cuda` feature, else the flex CPU backend.
pub fn inference() -> Device {
    #[cfg(feature = "cuda")]
    {
        Device::cuda(0)
    }
    #[cfg(not(feature = "cuda"))]
    {
        Device::flex()
    }
}

/// The device to build trainable models on: [`inference`] with autodiff. A model built on a
/// plain device and moved here has no tracked parameters.
pub fn training() -> Device {
    inference().autodiff()
}
