//! Dance-evaluation features, ported from the public reference code the papers use.
//!
//! - [`kinetic`]: the 72 kinetic features behind FID_k / Div_k
//!   (`google/aistplusplus_api:aist_plusplus/features/kinetic.py`, origin
//!   `facebookresearch/fairmotion`), with the reference's acceleration precedence bug.
//! - [`fid`] / [`mod@diversity`]: FID and all-pairs diversity with GT-stat normalisation
//!   (`lisiyao21/Bailando:utils/metrics_new.py`).
//! - [`manual`]: the 32 geometric ("manual_new") features behind FID_g / Div_g
//!   (`google/aistplusplus_api:aist_plusplus/features/manual.py` ==
//!   `lisiyao21/Bailando:utils/features/manual_new.py`).
//!
//! - [`bas`]: beat alignment in the four published variants; [`pfc`], [`foot_skating`],
//!   [`foot_skating_duration`], [`mpjpe`]: physical plausibility and reconstruction;
//!   [`penetration`]: self-penetration of forearms/hands on a capsule body (our approximation
//!   of Lodge++'s mesh-based ratio);
//!   [`group`] (GMR, GMC, group MMC, TIF), [`duet`] (FID_cd, Div_cd, BED), [`longform`] (our
//!   freezing and boundary-jerk measures); [`edit`] (our figures of an edit's joins); [`protocol`]: the papers' clip preparation;
//!   [`genre`]: a nearest-centroid genre classifier on kinetic features (our genre-control check);
//!   [`posture`]: the share of upside-down frames (our check); [`physical`]: floor contact, foot
//!   sliding, jerk, spikes, crossed shins and kinematic tempo (our plausibility figures).
//!
//! Inputs are global joint positions, SMPL 24-joint order, **Y-up**, metres, flattened C order
//! `(T, 24, 3)`: value `joints[(t * 24 + j) * 3 + c]`. No files, no framework: plain slices in,
//! numbers out, so the functions can be called from any program.
//!
//! # Example
//!
//! FID_k and Div_k of a generated set against ground truth as Bailando computes them, and the
//! beat-align score of one clip:
//!
//! ```
//! use dancegen_metrics::bas::{Variant, beat_align_score, motion_beats};
//! use dancegen_metrics::fid::EPS_BAILANDO;
//! use dancegen_metrics::protocol::AISTPP_BAILANDO;
//! use dancegen_metrics::{KineticVariant, diversity, frechet_distance, kinetic_features,
//!     normalize_by_gt};
//!
//! // A toy clip: 240 frames at 60 fps of 24 joints swaying with phase `phase`.
//! fn clip(phase: f64) -> Vec<f64> {
//!     let mut j = Vec::with_capacity(240 * 72);
//!     for t in 0..240 {
//!         for k in 0..24 {
//!             let s = (t as f64 / 60.0 * 4.0 + phase + k as f64 * 0.1).sin();
//!             j.extend([0.1 * s, 1.0 + 0.02 * k as f64, 0.05 * s * s]);
//!         }
//!     }
//!     j
//! }
//! let gt: Vec<Vec<f64>> = (0..4).map(|i| clip(i as f64)).collect();
//! let pred: Vec<Vec<f64>> = (0..4).map(|i| clip(0.5 + 0.7 * i as f64)).collect();
//!
//! // Protocol: cut to 1200 frames, zero-start root, frame time 1/60 (Bailando on AIST++).
//! let features = |set: &[Vec<f64>]| -> Vec<Vec<f64>> {
//!     set.iter()
//!         .map(|j| {
//!             let p = AISTPP_BAILANDO.prepare(j, 24, 60.0).unwrap();
//!             kinetic_features(&p.joints, p.frame_time, KineticVariant::Reference).to_vec()
//!         })
//!         .collect()
//! };
//! let (g, p) = normalize_by_gt(&features(&gt), &features(&pred));
//! let fid_k = frechet_distance(&p, &g, EPS_BAILANDO);
//! let div_k = diversity(&p);
//! assert!(fid_k.is_finite() && fid_k >= 0.0 && div_k > 0.0);
//!
//! // Beat alignment: music beats (frame indices) against the clip's motion beats.
//! let music = [30, 60, 90, 120, 150, 180, 210];
//! let score = beat_align_score(&music, &motion_beats(&pred[0], Variant::Bailando),
//!     Variant::Bailando);
//! assert!(score.is_some_and(|s| (0.0..=1.0).contains(&s)));
//! ```

use std::path::Path;

pub mod bas;
pub mod diversity;
pub mod duet;
pub mod edit;
pub mod fid;
pub mod foot_skating;
pub mod foot_skating_duration;
pub mod genre;
pub mod group;
pub mod kinetic;
pub mod longform;
pub mod manual;
pub mod mmr;
pub mod mpjpe;
pub mod penetration;
pub mod pfc;
pub mod physical;
pub mod posture;
pub mod protocol;

pub use diversity::diversity;
pub use fid::{frechet_distance, normalize_by_gt};
pub use foot_skating_duration::foot_skating_duration;
pub use kinetic::{KineticVariant, kinetic_features, try_kinetic_features, zero_start};
pub use manual::{manual_feature_flags, manual_features, try_manual_features};

/// Number of SMPL joints the features expect.
pub const NUM_JOINTS: usize = 24;

/// Values per frame (`24 × 3`).
pub const FRAME_LEN: usize = NUM_JOINTS * 3;

/// Input that the feature extractors cannot process.
#[derive(Debug, thiserror::Error)]
pub enum FeatureError {
    /// The flat slice is not a whole number of `(24, 3)` frames.
    #[error("joint array of {len} values is not a whole number of 24x3 frames")]
    NotFrames { len: usize },
    /// Too few frames for the feature (the reference would divide by zero and return NaN).
    #[error("{what} needs at least {min} frames, got {frames}")]
    TooShort {
        what: &'static str,
        min: usize,
        frames: usize,
    },
    /// A frame rate that is not finite and positive.
    #[error("frame rate {fps} is not a positive number")]
    BadRate { fps: f64 },
    /// A `.npy` file that is not a `(T, 24, 3)` array.
    #[error("{path}: expected a (T, 24, 3) array, got shape {shape:?}")]
    BadShape { path: String, shape: Vec<usize> },
    /// The `.npy` file could not be read.
    #[error(transparent)]
    Read(#[from] dancegen_io::npy::ReadError),
}

/// Number of frames in a flat `(T, 24, 3)` slice, or an error if it is not whole frames.
pub fn frame_count(joints: &[f64]) -> Result<usize, FeatureError> {
    if !joints.len().is_multiple_of(FRAME_LEN) {
        return Err(FeatureError::NotFrames { len: joints.len() });
    }
    Ok(joints.len() / FRAME_LEN)
}

/// Reads a `(T, 24, 3)` `.npy` joint array (any numeric dtype) as flat f64, C order.
pub fn read_joints(path: &Path) -> Result<Vec<f64>, FeatureError> {
    let arr = dancegen_io::read_npy(path)?;
    if arr.shape.len() != 3 || arr.shape[1] != NUM_JOINTS || arr.shape[2] != 3 {
        return Err(FeatureError::BadShape {
            path: path.display().to_string(),
            shape: arr.shape,
        });
    }
    Ok(arr.data)
}
