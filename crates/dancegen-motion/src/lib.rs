//! Motion for dance generation: skeletons, rotations, forward kinematics, the research
//! representations and the file formats animators and researchers use.
//!
//! This crate has no deep-learning dependencies. Conventions (axes, units, frame rates, the 6D
//! rotation layout) are stated once, in [`conventions`]; importers and exporters convert at the
//! edge.
pub mod aistpp;
pub mod beat_warp;
pub mod bvh;
pub mod bvh_motion;
pub mod capsule_body;
pub(crate) mod capsule_mesh;
pub mod character;
pub mod conventions;
pub mod couple_separation;
pub mod face;
pub mod fbx;
pub mod fk;
pub mod foot_ik;
pub mod foot_lock;
pub mod formation;
pub mod formats;
pub(crate) mod glb_container;
pub mod gltf;
pub mod pickle;
pub mod repr;
pub mod retarget;
pub mod rig;
pub mod rigid_fit;
pub mod rng;
pub mod rot6d_track;
pub mod rotation;
pub mod scene_input;
pub mod skeleton;
pub mod smoothing;
pub mod smpl_npz;
pub mod vec3;

pub use fk::{FkError, FkOutput, LocalRotations, forward_kinematics};
pub use rotation::{Mat3, Quat};
pub use skeleton::{Skeleton, SkeletonError};
