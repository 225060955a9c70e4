//! Training sets for the dance models: motion clips paired with per-frame music features.
//!
//! Output layout (everything written atomically, the manifest last):
//!
//! ```text
//! OUT/motion/<clip>.npz        SMPL 24 motion, 30 fps, Y-up, metres (AMASS-style npz,
//!                              read back by dancegen_formats::dispatch::load_motion_file)
//! OUT/music/<clip>.npy         (T, 35) float32 EDGE-35 features at 30 fps, T = motion frames
//! OUT/leader/<clip>.npz        duet data sets only: the partner the clip's dancer follows
//! OUT/held_out/{motion,music,leader}/ the same for held-out clips (evaluation only)
//! OUT/manifest.json            see [`manifest::Manifest`]
//! ```
//!
//! Six ways to pair ([`Pairing`]):
//! - **pseudo** ([`Pairing::Pseudo`]): no data set here pairs dance with music, so each motion
//!   is time-warped onto the beats of a song ([`warp`]). This is a documented *pseudo*-pairing,
//!   not ground truth: the dancer never heard that song.
//! - **duet** ([`Pairing::Duet`]): couples recorded together, one warp for both partners,
//!   one clip per role assignment ([`duet`]).
//! - **dd100**: Duolando's duet data set under `--root` ([`dd100`]), its own pairing.
//! - **aistpp** / **finedance**: the data sets' own pairing ([`layouts`]).
//! - **group**: 2–5 dancers composed from real takes into formations, beat-warped onto songs
//!   ([`group`]; `OUT/group/<clip>/dancer_<k>.npz` and `OUT/trajectories/<clip>.npy`).
//!
//! Music features are computed once per song over the whole song (as the reference repos do)
//! and the clip's frames are sliced from that matrix, so a clip's beat/onset columns are the
//! whole-song tracker's decisions.
//!
//! This crate has no deep-learning dependencies.

mod beats;
mod build;
mod clips;
pub mod dd100;
pub mod duet;
pub mod error;
pub mod genre;
pub mod group;
pub mod holistic_synth;
mod inputs;
pub mod layouts;
pub mod manifest;
mod options;
mod pseudo;
mod rates;
mod song;
mod song_plan;
mod summary;
pub mod takes;
mod units;

/// Frame rate of every clip (motion and music), EDGE/Lodge's 30 fps.
pub const FPS: u32 = 30;

/// Clips shorter than this (1 s) are dropped: too short to train on.
pub const MIN_CLIP_FRAMES: usize = 30;

/// The beat warp lives in the refinement crate (the generation library aligns generated dances
/// with it too); re-exported under its old path.
pub use dancegen_refine::beat_warp as warp;

pub use beats::{bas_bailando, kinematic_beats};
pub use build::{BuildReport, build};
pub use error::DatasetError;
pub use manifest::{ClipEntry, GroupLabels, MANIFEST_VERSION, Manifest, PairingKind, WarpReport};
pub use options::{BuildOptions, Pairing, Progress};
pub use song::{Song, stem};
pub use summary::summary_table;
