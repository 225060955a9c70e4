//! Attention masks `[queries, keys]`, `true` = blocked (Burn's convention).
//!
//! - [`AttnMask::Causal`]: GPT-style; a frame sees itself and the past.
//! - [`AttnMask::BlockDiagonal`]: ReactDance's Blocked Local Context: frames attend only inside
//!   their non-overlapping block of `block` frames, so blocks are denoised in parallel without
//!   leaking into each other (paper, "Periodic Causal Mask restricts attention to non-overlapping
//!   blocks of size T").
//! - [`AttnMask::PeriodicBlockCausal`]: the same blocks, causal inside each block (the mask
//!   restarts every `block` frames); the literal reading of "periodic causal". ReactDance's code
//!   is unreleased, so both readings are offered.

use burn::tensor::{Bool, Device, Tensor, TensorData};

/// Which (query, key) pairs may not attend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum AttnMask {
    /// Every query sees every key.
    Full,
    /// Query `i` sees keys `j ≤ i` (plus `offset` cached keys before the queries).
    Causal,
    /// Query `i` sees keys `j` with `i / block == j / block`.
    BlockDiagonal { block: usize },
    /// Block-diagonal and causal inside each block.
    PeriodicBlockCausal { block: usize },
}

impl AttnMask {
    /// Whether query `i` may not attend to key `j`. With a KV cache, queries are the last
    /// `queries` of `keys` positions: query `i` is at absolute position `keys − queries + i`.
    pub fn blocked(&self, i: usize, j: usize) -> bool {
        match *self {
            AttnMask::Full => false,
            AttnMask::Causal => j > i,
            AttnMask::BlockDiagonal { block } => i / block.max(1) != j / block.max(1),
            AttnMask::PeriodicBlockCausal { block } => {
                let b = block.max(1);
                i / b != j / b || j > i
            }
        }
    }

    /// The mask as a `[queries, keys]` tensor, or `None` for [`AttnMask::Full`]. Queries sit at
    /// absolute positions `keys − queries ..` (the cached-decoding layout).
    pub fn tensor(&self, queries: usize, keys: usize, device: &Device) -> Option<Tensor<2, Bool>> {
        if *self == AttnMask::Full {
            return None;
        }
        let offset = keys.saturating_sub(queries);
        let data: Vec<bool> = (0..queries)
            .flat_map(|i| (0..keys).map(move |j| (i, j)))
            .map(|(i, j)| self.blocked(i + offset, j))
            .collect();
        Some(Tensor::from_bool(
            TensorData::new(data, [queries, keys]),
            device,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(m: AttnMask, n: usize) -> Vec<String> {
        (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| if m.blocked(i, j) { '.' } else { 'x' })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn patterns() {
        assert_eq!(pattern(AttnMask::Causal, 3), ["x..", "xx.", "xxx"]);
        assert_eq!(
            pattern(AttnMask::BlockDiagonal { block: 2 }, 4),
            ["xx..", "xx..", "..xx", "..xx"]
        );
        assert_eq!(
            pattern(AttnMask::PeriodicBlockCausal { block: 2 }, 4),
            ["x...", "xx..", "..x.", "..xx"]
        );
        assert!(pattern(AttnMask::Full, 3).iter().all(|r| r == "xxx"));
    }

    #[test]
    fn every_row_keeps_a_key() {
        // A fully blocked row would give NaN after the softmax.
        for m in [
            AttnMask::Causal,
            AttnMask::BlockDiagonal { block: 3 },
            AttnMask::PeriodicBlockCausal { block: 3 },
        ] {
            for i in 0..10 {
                assert!((0..10).any(|j| !m.blocked(i, j)), "{m:?} row {i}");
            }
        }
    }
}
