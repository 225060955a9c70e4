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
//! Inputs are global joint positions, SMPL 24-joint order, **Y-up**, metres, flattened C order
//! `(T, 24, 3)`: value `joints[(t * 24 + j) * 3 + c]`.

use std::path::Path;

pub mod bas;
pub mod diversity;
pub mod duet;
pub mod fid;
pub mod foot_skating;
pub mod group;
pub mod kinetic;
pub mod longform;
pub mod manual;
pub mod mpjpe;
pub mod pfc;
pub mod protocol;

pub use diversity::diversity;
pub use fid::{frechet_distance, normalize_by_gt};
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
    /// A `.npy` file that is not a `(T, 24, 3)` array.
    #[error("{path}: expected a (T, 24, 3) array, got shape {shape:?}")]
    BadShape { path: String, shape: Vec<usize> },
    /// The `.npy` file could not be read.
    #[error(transparent)]
    Read(#[from] dancegen_io::npy::ReadError),
}

/// Number of frames in a flat `(T, 24, 3)` slice, or an error if it is not whole frames.
pub fn frame_count(joints: &[f64]) -> Result<usize, FeatureError> {
    if joints.len() % FRAME_LEN != 0 {
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
