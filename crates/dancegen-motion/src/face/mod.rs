//! The face as animators' tools speak it: the 52 ARKit blendshape weights per frame, in [0, 1]
//! (issue 19; `../shared/reference/holistic.md` §5). The Live Link Face CSV that carries them is
//! read and written by `dancegen-formats` (`livelink_csv`).
//!
//! - [`arkit`]: the 52 names, camelCase (ARKit, glTF `targetNames`, VRM "Perfect Sync") and
//!   PascalCase (Live Link Face), and a weights container that checks its shape and range.
//! - [`head_mesh`]: a stand-in head with the 52 blendshapes as morph targets, for `.glb`.
//! - [`flame`]: FLAME values to and from ARKit weights through a user-supplied 52 × 103 map.
pub mod arkit;
pub mod flame;
pub mod head_mesh;

pub use arkit::{ARKIT_COUNT, ARKIT_NAMES, FaceError, FaceWeights};
