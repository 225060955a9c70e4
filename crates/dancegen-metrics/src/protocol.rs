//! Evaluation protocols of the paper families (`shared/reference/anchors.md` A.3): how a
//! generated or ground-truth joint sequence is cut and normalised before the features.
//!
//! Each protocol is plain data ([`Protocol`]) plus [`Protocol::prepare`]. Nothing is resampled:
//! an input whose frame rate differs from the protocol's is an error.

use crate::{FRAME_LEN, NUM_JOINTS, kinetic::REFERENCE_FRAME_TIME, zero_start};

/// How the root trajectory is treated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RootHandling {
    /// Positions used as given.
    AsGiven,
    /// Frame-0 root subtracted from every joint (Bailando `calc_and_save_feats`).
    ZeroStart,
    /// Zero-start, then joints 1.. made relative to the current frame's root; the root keeps its
    /// trajectory (LODGE `metrics_finedance.py`).
    ZeroStartRootRelative,
}

/// One evaluation protocol.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    pub name: &'static str,
    /// Frame rate the protocol evaluates at; `None` = whatever the input has.
    pub fps: Option<f64>,
    /// Frames kept from the start (`None` = all).
    pub max_frames: Option<usize>,
    /// Fewest frames a clip must have.
    pub min_frames: usize,
    pub root: RootHandling,
    /// Joints the features use (kinetic vectors are truncated to `3 × joints_kept`).
    pub joints_kept: usize,
    /// Kinetic frame time; `None` = `1 / fps`.
    pub frame_time: Option<f64>,
}

/// Bailando on AIST++: 60 fps, first 1200 frames, zero-start root, frame time 1/60.
pub const AISTPP_BAILANDO: Protocol = Protocol {
    name: "aistpp-bailando",
    fps: Some(60.0),
    max_frames: Some(1200),
    min_frames: 3,
    root: RootHandling::ZeroStart,
    joints_kept: NUM_JOINTS,
    frame_time: Some(REFERENCE_FRAME_TIME),
};

/// LODGE on FineDance: 30 fps, first 1024 frames, zero-start + root-relative joints, 22 joints
/// (kinetic 66-d), frame time stays 1/60.
pub const FINEDANCE_LODGE: Protocol = Protocol {
    name: "finedance-lodge",
    fps: Some(30.0),
    max_frames: Some(1024),
    min_frames: 3,
    root: RootHandling::ZeroStartRootRelative,
    joints_kept: 22,
    frame_time: Some(REFERENCE_FRAME_TIME),
};

/// EDGE: 30 fps, 5-second (150-frame) clips, positions as given, frame time 1/60.
pub const EDGE_5S: Protocol = Protocol {
    name: "edge-5s",
    fps: Some(30.0),
    max_frames: Some(150),
    min_frames: 150,
    root: RootHandling::AsGiven,
    joints_kept: NUM_JOINTS,
    frame_time: Some(REFERENCE_FRAME_TIME),
};

/// No protocol: positions as given, frame time `1 / fps`.
pub const NONE: Protocol = Protocol {
    name: "none",
    fps: None,
    max_frames: None,
    min_frames: 3,
    root: RootHandling::AsGiven,
    joints_kept: NUM_JOINTS,
    frame_time: None,
};

/// All protocols, by name.
pub const ALL: [Protocol; 4] = [AISTPP_BAILANDO, FINEDANCE_LODGE, EDGE_5S, NONE];

/// A clip the protocol rejects.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProtocolError {
    #[error("expected (T, 24, 3) joints, got {joints} joints")]
    Joints { joints: usize },
    #[error("joint array of {len} values is not a whole number of 24x3 frames")]
    NotFrames { len: usize },
    #[error(
        "motion is at {input} fps but protocol {protocol} evaluates at {expected} fps; resample it first (e.g. `dancegen convert --fps {expected}`)"
    )]
    Fps {
        protocol: &'static str,
        input: f64,
        expected: f64,
    },
    #[error("protocol {protocol} needs at least {min} frames, got {frames}")]
    TooShort {
        protocol: &'static str,
        min: usize,
        frames: usize,
    },
    #[error("non-finite value (NaN or infinity) at frame {frame}")]
    NonFinite { frame: usize },
    #[error("invalid frame rate {0}")]
    BadFps(f64),
}

/// A clip ready for the features: `(T, 24, 3)` Y-up joints.
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    pub joints: Vec<f64>,
    pub frames: usize,
    pub fps: f64,
    /// Kinetic frame time.
    pub frame_time: f64,
}

impl Protocol {
    /// The protocol called `name`.
    pub fn by_name(name: &str) -> Option<Protocol> {
        ALL.into_iter().find(|p| p.name == name)
    }

    /// Checks and normalises a `(T, 24, 3)` Y-up clip recorded at `fps`.
    pub fn prepare(
        &self,
        joints: &[f64],
        num_joints: usize,
        fps: f64,
    ) -> Result<Prepared, ProtocolError> {
        if num_joints != NUM_JOINTS {
            return Err(ProtocolError::Joints { joints: num_joints });
        }
        if !joints.len().is_multiple_of(FRAME_LEN) {
            return Err(ProtocolError::NotFrames { len: joints.len() });
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(ProtocolError::BadFps(fps));
        }
        if let Some(expected) = self.fps
            && (fps - expected).abs() > 1e-3
        {
            return Err(ProtocolError::Fps {
                protocol: self.name,
                input: fps,
                expected,
            });
        }
        let total = joints.len() / FRAME_LEN;
        if let Some(i) = joints.iter().position(|v| !v.is_finite()) {
            return Err(ProtocolError::NonFinite {
                frame: i / FRAME_LEN,
            });
        }
        if total < self.min_frames {
            return Err(ProtocolError::TooShort {
                protocol: self.name,
                min: self.min_frames,
                frames: total,
            });
        }
        let frames = self.max_frames.map_or(total, |m| total.min(m));
        let cut = &joints[..frames * FRAME_LEN];
        let out = match self.root {
            RootHandling::AsGiven => cut.to_vec(),
            RootHandling::ZeroStart => zero_start(cut),
            RootHandling::ZeroStartRootRelative => {
                let mut z = zero_start(cut);
                for frame in z.chunks_exact_mut(FRAME_LEN) {
                    let root = [frame[0], frame[1], frame[2]];
                    for (i, v) in frame.iter_mut().enumerate().skip(3) {
                        *v -= root[i % 3];
                    }
                }
                z
            }
        };
        Ok(Prepared {
            joints: out,
            frames,
            fps,
            frame_time: self.frame_time.unwrap_or(1.0 / fps),
        })
    }

    /// Truncates a 72-d kinetic vector to the protocol's joints (66-d for 22 joints).
    pub fn kinetic_dims(&self) -> usize {
        3 * self.joints_kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(frames: usize) -> Vec<f64> {
        (0..frames * FRAME_LEN).map(|i| i as f64 * 0.001).collect()
    }

    #[test]
    fn bailando_cuts_and_zero_starts() {
        let p = AISTPP_BAILANDO.prepare(&clip(1300), 24, 60.0).unwrap();
        assert_eq!(p.frames, 1200);
        assert_eq!(&p.joints[..3], &[0.0, 0.0, 0.0]);
        assert_eq!(p.frame_time, 1.0 / 60.0);
    }

    #[test]
    fn fps_mismatch_is_an_error() {
        let e = AISTPP_BAILANDO.prepare(&clip(10), 24, 30.0).unwrap_err();
        assert!(e.to_string().contains("30 fps"), "{e}");
    }

    #[test]
    fn lodge_root_relative_keeps_root_trajectory() {
        let c = clip(5);
        let p = FINEDANCE_LODGE.prepare(&c, 24, 30.0).unwrap();
        let f = 2 * FRAME_LEN;
        assert!((p.joints[f] - (c[f] - c[0])).abs() < 1e-12);
        assert!((p.joints[f + 3] - (c[f + 3] - c[f])).abs() < 1e-12);
        assert_eq!(FINEDANCE_LODGE.kinetic_dims(), 66);
    }

    #[test]
    fn short_and_nan_are_errors() {
        assert!(matches!(
            EDGE_5S.prepare(&clip(100), 24, 30.0),
            Err(ProtocolError::TooShort { .. })
        ));
        let mut c = clip(10);
        c[FRAME_LEN + 4] = f64::NAN;
        assert_eq!(
            NONE.prepare(&c, 24, 30.0),
            Err(ProtocolError::NonFinite { frame: 1 })
        );
    }
}
