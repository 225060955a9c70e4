//! Selective state-space layer (Mamba v1), TCDiff++ sequence decoder.
