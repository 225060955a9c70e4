//! The motion math of dancegen: skeletons, rotations, forward kinematics, the conventions, the
//! research representations, smoothing and the capsule body.
//!
//! This is the bottom layer of the motion crates. It reads and writes no file format (that is
//! `dancegen-formats`), fits no character (`dancegen-character`) and refines no dance
//! (`dancegen-refine`). Conventions (axes, units, frame rates, the 6D rotation layout) are
//! stated once, in [`conventions`]; importers and exporters convert at the edge.
pub mod body_bounds;
pub mod capsule_body;
pub mod conventions;
pub mod face;
pub mod fk;
pub mod repr;
pub mod rigid_fit;
pub mod rng;
pub mod rot6d_track;
pub mod rotation;
pub mod skeleton;
pub mod smoothing;
pub mod vec3;

pub use fk::{FkError, FkOutput, LocalRotations, forward_kinematics};
pub use rotation::{Mat3, Quat};
pub use skeleton::{Skeleton, SkeletonError};
