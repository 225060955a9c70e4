//! Research motion representations and the canonical in-memory motion they are made from.
//!
//! Everything goes through [`SmplMotion`] (SMPL 24 axis-angle + pelvis position, Y-up, metres,
//! fps stored). Each representation is a unit type with `encode(&SmplMotion)` and `decode(..)`
//! and documents its exact per-frame layout and the reference it follows
//! (`shared/reference/anchors.md` C.1–C.6, A.5/A.6):
//!
//! | type | dims | frame | reference |
//! |---|---|---|---|
//! | [`DuetFollower`] / [`DuetLeader`] | 3 streams (upper, lower + contacts, root relative to the leader) / leader features | Y-up, leader's heading frame | ReactDance (D.5, our layout) |
//! | [`Edge151`] | 4 contacts + 3 root + 24×6D | Z-up | EDGE (C.2) |
//! | [`Lodge139`] | 4 contacts + 3 root + 22×6D | Y-up, grounded | LODGE (C.3) |
//! | [`FineDance315`] / [`FineDance319`] | (4 +) 3 + 52×6D | Y-up | FineDance / LODGE (C.3) |
//! | [`GroupEdge151`] | N × (T, 151) | Z-up | TCDiff (C.5) |
//! | [`HumanMl263`] | 4 root + 21×3 ric + 21×6D (columns) + 22×3 vel + 4 contacts | Y-up, canonicalised | HumanML3D / SoulNet body (C.6) |
//! | [`Holistic623`] / [`Holistic723`] | the same for SMPL-H 52 (12·52 − 1) (+ 100 face) | Y-up, canonicalised | SoulNet holistic (C.6) |
//!
//! [`MinMaxNormalizer`] is EDGE's / LODGE's per-dimension MinMax(−1, 1) normaliser (C.2).

pub mod duet;
pub mod edge151;
pub mod finedance;
pub mod group;
pub mod holistic;
pub mod humanml263;
pub mod lodge139;
pub mod motion;
pub mod normalizer;

pub use duet::{DuetFollower, DuetLeader};
pub use edge151::Edge151;
pub use finedance::{FineDance315, FineDance319, FineDanceMotion};
pub use group::{GroupEdge151, GroupMotion};
pub use holistic::{Holistic623, Holistic723, HolisticMotion};
pub use humanml263::HumanMl263;
pub use lodge139::Lodge139;
pub use motion::{GroundMode, SmplMotion};
pub use normalizer::MinMaxNormalizer;

/// Errors of the representation encoders and decoders.
#[derive(Debug, thiserror::Error)]
pub enum ReprError {
    #[error("{what}: {got} values is not a whole number of {width}-value frames")]
    Shape {
        what: &'static str,
        got: usize,
        width: usize,
    },
    #[error("{what}: {poses} pose frames but {trans} translation frames")]
    FrameMismatch {
        what: &'static str,
        poses: usize,
        trans: usize,
    },
    #[error("{what} expects {expected} fps, got {got} (resample first)")]
    Fps {
        what: &'static str,
        expected: f32,
        got: f32,
    },
    #[error("{0}")]
    Invalid(String),
    /// A file whose stored frame rate is missing or not a positive number; its reader can be
    /// given the rate instead.
    #[error("{}: {why}", path.display())]
    NoRate {
        path: std::path::PathBuf,
        why: String,
    },
    #[error(transparent)]
    Fk(#[from] crate::fk::FkError),
    #[error(transparent)]
    Read(#[from] dancegen_io::npy::ReadError),
    #[error(transparent)]
    Write(#[from] dancegen_io::atomic::WriteError),
}

/// Checks `data.len()` is a multiple of `width` and returns the frame count.
pub fn frames_of(what: &'static str, data: &[f32], width: usize) -> Result<usize, ReprError> {
    if !data.len().is_multiple_of(width) {
        return Err(ReprError::Shape {
            what,
            got: data.len(),
            width,
        });
    }
    Ok(data.len() / width)
}

/// Errors unless `fps` is within 1e-3 of `expected`.
pub(crate) fn check_fps(what: &'static str, fps: f32, expected: f32) -> Result<(), ReprError> {
    if (fps - expected).abs() > 1e-3 {
        return Err(ReprError::Fps {
            what,
            expected,
            got: fps,
        });
    }
    Ok(())
}
