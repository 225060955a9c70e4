//! The files motion comes in and goes out as: BVH, AIST++ and AIOZ-GDance pickles, SMPL /
//! SMPL-X `.npz`, glTF 2.0 / GLB, FBX, Live Link Face CSV, and the dispatch that picks one by
//! file name ([`dispatch`]).
//!
//! Each reader converts its file's conventions (axes, units, frame rate, skeleton) into the
//! canonical ones of `dancegen_motion::conventions` at the edge, and each writer converts back.
//! BVH skeletons other than SMPL's are retargeted onto SMPL 24 here ([`retarget`]), since that
//! fit reads the file's own joint names and rest pose. [`rig`] renames the SMPL 24 skeleton for
//! the tools that import our files (Mixamo, UE5, VRM bone names).
pub mod aistpp;
pub mod body_check;
pub mod bvh;
pub mod bvh_motion;
pub(crate) mod capsule_mesh;
pub mod dispatch;
pub mod fbx;
pub mod fbx_in;
pub mod glb_container;
pub mod glb_in;
pub mod gltf;
pub mod livelink_csv;
pub mod pickle;
pub mod retarget;
pub mod rig;
pub mod scene_input;
pub mod smpl_npz;
#[cfg(test)]
mod test_dancers;
