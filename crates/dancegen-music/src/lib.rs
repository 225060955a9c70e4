//! Music analysis for dance generation.
//!
//! A Rust port of the librosa 0.11 pipeline the published dance models are conditioned on
//! (FACT/AIST++, EDGE, Lodge/Lodge++, FineDance, TCDiff, SoulNet "baseline" features): decoding,
//! libsoxr-HQ resampling, STFT, mel, MFCC, onset strength and peaks, tempo, beat tracking and
//! CQT-based chroma. Each stage is a public function so the dance models and the metrics reuse
//! exactly the same code. The numerical contract is "librosa 0.11.0 on the same input"; the
//! golden values live in `shared/fixtures/music/` and the tests say how close each stage is.
//!
//! Conventions: mono float32 signals; spectrograms and feature matrices are frame-major
//! ([`FrameMatrix`], `[frame][feature]`), i.e. the transpose of librosa's `(features, frames)`.
//! The frame rate is `sr / hop` with `hop = 512`, so 30 fps means SR 15360 and 60 fps SR 30720.
//!
//! This crate has no deep-learning dependencies.

pub mod beat;
pub mod chroma;
pub mod cqt;
pub mod decode;
pub mod delta;
pub mod edge_slices;
pub mod error;
pub mod features;
pub mod hpss;
pub mod load;
pub mod mel;
pub mod mfcc;
pub mod onset;
pub mod resample;
pub mod stft;
pub mod tcdiff;
pub mod tempo;
pub mod tuning;
pub mod wav_guard;

pub use error::{MusicError, Result};
pub use load::{Audio, load};
pub use stft::FrameMatrix;

/// Hop length of every dance-feature pipeline (samples per frame).
pub const HOP: usize = 512;
