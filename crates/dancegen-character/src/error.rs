//! Errors of `--character`: every one names the character file and says what is wrong with it
//! in words a user who only exported a model from Blender or VRoid can act on.

use std::path::PathBuf;

/// Why a character could not be loaded, retargeted or written.
#[derive(Debug, thiserror::Error)]
pub enum CharacterError {
    #[error("{path}: cannot read: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error(
        "{path}: not a glTF file ({reason}); --character takes a .glb, .vrm or .gltf (glTF 2.0)"
    )]
    NotGltf { path: PathBuf, reason: String },
    #[error("{path}: invalid glTF: {reason}")]
    Invalid { path: PathBuf, reason: String },
    #[error("{path}: not supported: {reason}")]
    Unsupported { path: PathBuf, reason: String },
    #[error("{path} has no skinned mesh: a humanoid character needs a skin (an armature)")]
    NoSkin { path: PathBuf },
    #[error(
        "{path}: cannot find these bones of a humanoid in the character: {}; the character's \
         bones are: {}",
        missing.join(", "),
        bones.join(", ")
    )]
    MissingBones {
        path: PathBuf,
        /// SMPL joints (with the part of the body they mean) no character bone was found for.
        missing: Vec<String>,
        /// Names of the character's skin joints, in node order (`#index` for unnamed ones).
        bones: Vec<String>,
    },
    #[error("{path}: cannot put the dance on the character: {reason}")]
    Retarget { path: PathBuf, reason: String },
    #[error(transparent)]
    Write(#[from] dancegen_io::atomic::WriteError),
}
