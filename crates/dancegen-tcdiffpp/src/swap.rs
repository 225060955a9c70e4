//! Swap mode S (paper §4.1): which left-to-right place each dancer ends in.
//!
//! Slots are the dancers' left-to-right order at frame 0 ([`crate::layout`]), so the start
//! order is the identity and S is the permutation to the end order, as a one-hot
//! `N_MAX × N_MAX` matrix (`S[s][r] = 1` when slot `s` ends `r`-th from the audience's left).
//! The released code feeds `2N` argsort indices of the *final* frame into an MLP, never passes
//! them, and would make the x-half the identity anyway (group.md §1 row 6); a one-hot
//! permutation carries the same information without pretending ranks are magnitudes.
//!
//! The embedding is the released MLP shape, `Linear → GELU → Linear → GELU`, used twice by the
//! denoiser: added to the FiLM vector and as one memory token.

use dancegen_nn::burn;

use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::activation::gelu;
use burn::tensor::{Device, Tensor};

use crate::layout::N_MAX;

/// Width of the flattened one-hot permutation.
pub const SWAP_DIMS: usize = N_MAX * N_MAX;

/// The one-hot swap code of `n` dancers whose stage x at the window's last frame is `end_x`
/// (slot order = start order). Empty slots' rows are zero.
pub fn swap_code(end_x: &[f32]) -> Vec<f32> {
    let n = end_x.len();
    assert!(n <= N_MAX, "at most {N_MAX} dancers");
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| end_x[a].total_cmp(&end_x[b]).then(a.cmp(&b)));
    let mut code = vec![0f32; SWAP_DIMS];
    for (rank, &slot) in order.iter().enumerate() {
        code[slot * N_MAX + rank] = 1.0;
    }
    code
}

/// The code of a group that keeps its order.
pub fn identity_code(n: usize) -> Vec<f32> {
    let mut code = vec![0f32; SWAP_DIMS];
    for s in 0..n.min(N_MAX) {
        code[s * N_MAX + s] = 1.0;
    }
    code
}

/// The end order (slots left to right) a code asks for.
pub fn end_order(code: &[f32], n: usize) -> Vec<usize> {
    let mut by_rank: Vec<(usize, usize)> = (0..n)
        .map(|s| {
            let row = &code[s * N_MAX..(s + 1) * N_MAX];
            let rank = (0..N_MAX)
                .max_by(|&a, &b| row[a].total_cmp(&row[b]))
                .unwrap_or(s);
            (rank, s)
        })
        .collect();
    by_rank.sort();
    by_rank.into_iter().map(|(_, s)| s).collect()
}

/// The swap-mode MLP.
#[derive(Module, Debug)]
pub struct SwapEmbedding {
    pub linear1: Linear,
    pub linear2: Linear,
}

impl SwapEmbedding {
    pub fn new(d: usize, device: &Device) -> Self {
        Self {
            linear1: LinearConfig::new(SWAP_DIMS, d).init(device),
            linear2: LinearConfig::new(d, d).init(device),
        }
    }

    /// Codes `[B, SWAP_DIMS]` → `[B, d]`.
    pub fn forward(&self, code: Tensor<2>) -> Tensor<2> {
        gelu(self.linear2.forward(gelu(self.linear1.forward(code))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_permutations() {
        // Slot 0 ends on the right, slots 1 and 2 move one place left.
        let code = swap_code(&[2.0, -1.0, 0.5]);
        assert_eq!(end_order(&code, 3), vec![1, 2, 0]);
        assert_eq!(code[2], 1.0);
        assert_eq!(code.iter().sum::<f32>(), 3.0);
        assert_eq!(swap_code(&[0.0, 1.0, 2.0, 3.0]), identity_code(4));
        assert_eq!(end_order(&identity_code(5), 5), vec![0, 1, 2, 3, 4]);
    }
}
