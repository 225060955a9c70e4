//! Quantizers: VQ with EMA codebook and dead-code reset, residual VQ, SoulNet hierarchical RVQ, FSQ, grouped hierarchical residual FSQ (ReactDance).
