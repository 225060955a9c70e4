//! The seeded generator lives in the motion crate (the data-set builders, which have no
//! deep-learning dependencies, draw from it too); re-exported under its old path.
pub use dancegen_motion::rng::SplitMix64;
