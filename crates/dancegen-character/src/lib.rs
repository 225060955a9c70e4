//! `--character`: putting a generated SMPL 24 dance on the user's own humanoid character.
//!
//! The user brings a rigged humanoid as glTF 2.0 — `.glb`, `.vrm` (VRM 0.x or 1.0, a GLB) or
//! `.gltf` with embedded or external buffers and textures — and gets back the same file, every
//! mesh, material, texture, morph target and extension intact, with its animations replaced by
//! one animation `dance`.
//!
//! ```no_run
//! use dancegen_character::{self as character, Character};
//! use dancegen_formats::gltf::DancerAnimation;
//! use dancegen_motion::Skeleton;
//! # fn main() -> Result<(), character::CharacterError> {
//! # let (poses, trans) = (vec![0.0f32; 72], vec![0.0f32; 3]);
//! let robot = Character::load("RobotExpressive.glb")?; // fails early on a non-humanoid
//! let dancer = DancerAnimation { local_rotations_axis_angle: &poses, root_translation: &trans };
//! let anim = character::retarget(&robot, &Skeleton::smpl24(), &[dancer], 30.0)?;
//! character::write_glb("robot_dance.glb", &robot, &anim)?;
//! # Ok(()) }
//! ```
//!
//! One file per job: `gltf_in.rs` reads the file, `scene.rs` holds the node hierarchy and its
//! rest pose, `names.rs` reads bone names, `bone_map.rs` matches SMPL joints to bones,
//! `retarget.rs` turns the dance into the character's node rotations and hips translation,
//! `glb_out.rs` writes the result. The choices (which bones are matched how, the rest-pose
//! alignment, the height scale, the facing correction, what happens to the old animations) are
//! documented where they are made.

mod bone_map;
mod error;
mod glb_out;
mod gltf_in;
mod names;
mod retarget;
mod scene;
mod transform;

use std::path::{Path, PathBuf};

pub use bone_map::{Aim, BoneMap, Convention, MappedBone, Site};
pub use error::CharacterError;
pub use glb_out::{ANIMATION_NAME, KNOWN_EXTENSIONS, SMPL_NODES_EXTRA, glb_bytes, write_glb};
pub use names::{NameTable, Part, Side, classify, smpl_official_name};
pub use retarget::{FLOOR_PERCENTILE, NodeChannel, RetargetedAnimation, retarget};
pub use scene::NodeTree;
pub use transform::{Affine, Trs};

use gltf_in::GltfAsset;

/// A humanoid character read from a glTF file, with its bones matched to SMPL 24.
#[derive(Debug, Clone)]
pub struct Character {
    path: PathBuf,
    asset: GltfAsset,
    tree: NodeTree,
    bone_map: BoneMap,
}

impl Character {
    /// Reads a `.glb`, `.vrm` or `.gltf` (external buffers and images next to it) and matches
    /// its bones. Errors name the file: not glTF, malformed, no skin, or which humanoid bones
    /// could not be found (with the character's bone names).
    pub fn load(path: impl AsRef<Path>) -> Result<Character, CharacterError> {
        let path = path.as_ref();
        let asset = gltf_in::read_gltf(path)?;
        Character::from_asset(path, asset)
    }

    /// Like [`Character::load`] from bytes already in memory; `path` names the file in errors
    /// and its folder resolves external URIs of a `.gltf`.
    pub fn from_bytes(path: impl AsRef<Path>, bytes: &[u8]) -> Result<Character, CharacterError> {
        let path = path.as_ref();
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let asset = gltf_in::parse_gltf(path, bytes, Some(&base))?;
        Character::from_asset(path, asset)
    }

    /// Like [`Character::from_bytes`], but reads nothing outside `bytes`: a buffer or image
    /// given as a file name is an error. For a file someone else sent (a server's upload),
    /// whose URIs could otherwise name any file on the server's disk (`../../etc/passwd`)
    /// and bring it into a download.
    pub fn from_self_contained_bytes(
        path: impl AsRef<Path>,
        bytes: &[u8],
    ) -> Result<Character, CharacterError> {
        let path = path.as_ref();
        let asset = gltf_in::parse_gltf(path, bytes, None)?;
        Character::from_asset(path, asset)
    }

    fn from_asset(path: &Path, asset: GltfAsset) -> Result<Character, CharacterError> {
        glb_out::check_extensions(path, &glb_out::extension_names(&asset.json))?;
        let tree = NodeTree::from_json(&asset.json).map_err(|reason| CharacterError::Invalid {
            path: path.to_path_buf(),
            reason,
        })?;
        let skinned = gltf_in::array(&asset.json, "nodes")
            .iter()
            .any(|n| n.get("skin").is_some() && n.get("mesh").is_some());
        if !skinned || !tree.is_joint.iter().any(|&j| j) {
            return Err(CharacterError::NoSkin {
                path: path.to_path_buf(),
            });
        }
        let bone_map = bone_map::match_bones(&asset.json, &tree).map_err(|missing| {
            CharacterError::MissingBones {
                path: path.to_path_buf(),
                missing,
                bones: (0..tree.len())
                    .filter(|&k| tree.is_joint[k])
                    .map(|k| tree.label(k))
                    .collect(),
            }
        })?;
        Ok(Character {
            path: path.to_path_buf(),
            asset,
            tree,
            bone_map,
        })
    }

    /// The file the character was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Which character bone each SMPL joint drives.
    pub fn bone_map(&self) -> &BoneMap {
        &self.bone_map
    }

    /// The node hierarchy and rest pose.
    pub fn nodes(&self) -> &NodeTree {
        &self.tree
    }

    /// The glTF JSON document as read.
    pub fn json(&self) -> &serde_json::Value {
        &self.asset.json
    }

    pub(crate) fn asset(&self) -> &GltfAsset {
        &self.asset
    }

    /// Rest world position of a site of the bone map.
    pub fn rest_site_position(&self, site: Site) -> Option<[f64; 3]> {
        bone_map::site_position(&self.tree, site)
    }

    /// Height of the skeleton at rest: the vertical extent of the skin joints and the bone-end
    /// nodes below them (world units of the file; the mesh may reach a little further).
    pub fn rest_height(&self) -> f64 {
        let t = &self.tree;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for k in (0..t.len()).filter(|&k| t.is_joint[k]) {
            for d in t.subtree(k) {
                if !t.has_content[d] {
                    let y = t.rest_position(d)[1];
                    lo = lo.min(y);
                    hi = hi.max(y);
                }
            }
        }
        if hi >= lo { hi - lo } else { 0.0 }
    }

    /// One line per driven bone, `smpl joint ← bone name (#node)`, for `--verbose` output and
    /// for users checking why a bone moves oddly.
    pub fn describe_bone_map(&self) -> String {
        let mut out = format!(
            "{:?} bone map of {}:\n",
            self.bone_map.convention,
            self.path.display()
        );
        for b in &self.bone_map.bones {
            let extra = if b.detached_from.is_some() {
                " (detached: follows its limb)"
            } else {
                ""
            };
            out.push_str(&format!(
                "  {:<12} ← {} (#{}){extra}\n",
                dancegen_motion::skeleton::SMPL24_NAMES[b.smpl],
                self.tree.label(b.node),
                b.node
            ));
        }
        out
    }
}
