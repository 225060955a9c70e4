//! The face as animators' tools speak it: the 52 ARKit blendshape weights per frame, in [0, 1]
//! (issue 19; `../shared/reference/holistic.md` §5), and the files that carry them.
//!
//! - [`arkit`]: the 52 names, camelCase (ARKit, glTF `targetNames`, VRM "Perfect Sync") and
//!   PascalCase (Live Link Face), and a weights container that checks its shape and range.
//! - [`livelink_csv`]: Epic's Live Link Face CSV (`face.csv`), read and written.
//! - [`head_mesh`]: a stand-in head with the 52 blendshapes as morph targets, for `.glb`.
//! - [`flame`]: FLAME values to and from ARKit weights through a user-supplied 52 × 103 map.
pub mod arkit;
pub mod flame;
pub mod head_mesh;
pub mod livelink_csv;

pub use arkit::{ARKIT_COUNT, ARKIT_NAMES, FaceError, FaceWeights};
