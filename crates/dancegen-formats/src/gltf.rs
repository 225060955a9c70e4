//! glTF 2.0 binary (`.glb`) export of animated skeletons with a simple skinned body.
//!
//! The file holds one node per joint (named after the joint, same order, so node `j` is joint
//! `j`), a `skin` over those nodes, one animation and a skinned mesh made of one tapered capsule
//! per bone, so the figure is visible in Blender, three.js, Unity (glTFast / UniGLTF) and the
//! Khronos validator.
//!
//! Several dancers ([`write_glb_multi`]) go into one scene so a duet imports as a unit: dancer
//! `d` (0-based, as `--dancer`) owns nodes `d·(J+1) ..` — its `J` joint nodes named
//! `dancer{d}/<joint>`, then its mesh node `dancer{d}` — plus skin `d`, mesh `d` and material
//! `d` (colours: [`EXTRA_DANCER_COLORS`]); the body geometry, inverse bind matrices and key times
//! are shared, and the single animation animates everyone so they stay in sync. With one dancer
//! the names stay unprefixed (mesh node `body`), exactly as [`write_glb`] writes them.
//!
//! # Conventions
//! glTF is Y-up, right-handed, metres — the same frame as [`dancegen_motion::conventions`], so positions
//! and rotations are written unchanged. Only the quaternion layout differs: glTF stores
//! `(x, y, z, w)`, dancegen's [`Quat`] is `(w, x, y, z)`; the writer reorders.
//!
//! - Node `j`'s rest translation is `skeleton.offsets()[j]`; the root node's rest translation is
//!   `offsets()[0]` (the rest pelvis, zero for [`dancegen_motion::Skeleton::smpl24`]). Rest rotations are
//!   identity, so each joint's rest world transform is a pure translation to its rest position
//!   (`offsets()[0]` plus the cumulative offsets) and the inverse bind matrices are the
//!   negated translations.
//! - The animation has one rotation channel per joint (the local axis-angle rotation, as a unit
//!   quaternion made hemisphere-continuous over time so that component-wise interpolation in
//!   Blender agrees with slerp) and one translation channel on the root node, whose values are
//!   `root_translation` — the **pelvis world position** of [`dancegen_motion::conventions`]. The animated
//!   translation *replaces* the rest translation, so in every frame joint 0 is exactly at
//!   `root_translation[t]` and every other joint where [`dancegen_motion::forward_kinematics`] puts it.
//!   Callers holding AIST++ `smpl_trans` must convert it first: pelvis world =
//!   `pelvis_rest + smpl_trans / smpl_scaling` (shared data README).
//! - Key times are `frame / fps` seconds, LINEAR interpolation.
//! - Mesh vertices are in the rest pose (bind pose) and each capsule is weighted 100% to the
//!   bone's parent joint (the joint whose rotation moves the bone).

use crate::capsule_mesh::{CapsuleShape, build_capsule_mesh};
use crate::glb_container::assemble_glb;
pub use crate::scene_input::DancerAnimation;
use crate::scene_input::{SceneInputError, check_scene};
use dancegen_motion::rotation::Quat;
use dancegen_motion::skeleton::Skeleton;
use dancegen_motion::vec3::add;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Appearance of the exported figure.
#[derive(Debug, Clone, PartialEq)]
pub struct GlbOptions {
    /// Capsule radius at the parent end of each bone, metres (capped at 35% of the bone length).
    pub bone_radius: f32,
    /// Radius at the child end relative to the parent end (1 = cylinder).
    pub taper: f32,
    /// Sides of each capsule (at least 3).
    pub sides: usize,
    /// Linear RGBA base colour of the material.
    pub base_color: [f32; 4],
    /// Name of the animation (Blender shows it as the action name).
    pub animation_name: String,
}

impl Default for GlbOptions {
    fn default() -> Self {
        GlbOptions {
            bone_radius: 0.045,
            taper: 0.7,
            sides: 8,
            base_color: [0.8, 0.45, 0.2, 1.0],
            animation_name: "dance".to_string(),
        }
    }
}

impl GlbOptions {
    /// The body's shape part of the options.
    pub(crate) fn capsule_shape(&self) -> CapsuleShape {
        CapsuleShape {
            bone_radius: self.bone_radius,
            taper: self.taper,
            sides: self.sides,
        }
    }
}

/// Why the inputs cannot be exported as glTF.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GlbInputError {
    /// What every scene format checks ([`crate::scene_input`]).
    #[error(transparent)]
    Scene(#[from] SceneInputError),
    #[error("too many frames ({frames}) at {fps} fps: key times are not strictly increasing")]
    TimesNotIncreasing { frames: usize, fps: f32 },
    /// Over GLB's 32-bit sizes.
    #[error("{0}")]
    TooLarge(String),
    /// A face track that does not fit the motion.
    #[error("face: {0}")]
    Face(String),
}

/// A `.glb` that could not be written; both variants name the path.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    #[error("{path}: cannot export glTF: {reason}")]
    Input {
        path: PathBuf,
        reason: GlbInputError,
    },
    #[error(transparent)]
    Write(#[from] dancegen_io::atomic::WriteError),
}

/// Writes the motion as a `.glb` file, atomically (see the module docs for the layout).
///
/// `local_rotations_axis_angle` is `T×J×3` (radians, parent-relative), `root_translation` is
/// `T×3` (metres, pelvis world position), `fps` the frame rate stored with the motion.
pub fn write_glb(
    path: impl AsRef<Path>,
    skeleton: &Skeleton,
    local_rotations_axis_angle: &[f32],
    root_translation: &[f32],
    fps: f32,
    opts: &GlbOptions,
) -> Result<(), GltfError> {
    write_glb_multi(
        path,
        skeleton,
        &[DancerAnimation {
            local_rotations_axis_angle,
            root_translation,
        }],
        fps,
        opts,
    )
}

/// The `.glb` file contents for [`write_glb`].
pub fn glb_bytes(
    skeleton: &Skeleton,
    local_rotations_axis_angle: &[f32],
    root_translation: &[f32],
    fps: f32,
    opts: &GlbOptions,
) -> Result<Vec<u8>, GlbInputError> {
    glb_bytes_multi(
        skeleton,
        &[DancerAnimation {
            local_rotations_axis_angle,
            root_translation,
        }],
        fps,
        opts,
    )
}

/// A face for a single dancer's `.glb`: ARKit weights played on a head mesh
/// ([`dancegen_motion::face::head_mesh`]) that rides on the skeleton's `head_joint`.
///
/// The head is its own node (`face`), a child of the head joint's node, with a mesh whose 52
/// morph targets are the ARKit blendshapes, named in `mesh.extras.targetNames` (the convention
/// three.js and Blender read), and one more animation channel, `path: "weights"`, with 52 values
/// per key. Blender imports the targets as shape keys named after ARKit.
#[derive(Debug, Clone, Copy)]
pub struct FaceAnimation<'a> {
    pub weights: &'a dancegen_motion::face::FaceWeights,
    pub head_joint: usize,
}

/// [`write_glb`] with a face (see [`FaceAnimation`]).
pub fn write_glb_with_face(
    path: impl AsRef<Path>,
    skeleton: &Skeleton,
    dancer: DancerAnimation<'_>,
    face: FaceAnimation<'_>,
    fps: f32,
    opts: &GlbOptions,
) -> Result<(), GltfError> {
    let path = path.as_ref();
    let bytes = glb_document(skeleton, &[dancer], Some(face), fps, opts).map_err(|reason| {
        GltfError::Input {
            path: path.to_path_buf(),
            reason,
        }
    })?;
    dancegen_io::write_atomic(path, |w| w.write_all(&bytes))?;
    Ok(())
}

/// The `.glb` file contents for [`write_glb_with_face`].
pub fn glb_bytes_with_face(
    skeleton: &Skeleton,
    dancer: DancerAnimation<'_>,
    face: FaceAnimation<'_>,
    fps: f32,
    opts: &GlbOptions,
) -> Result<Vec<u8>, GlbInputError> {
    glb_document(skeleton, &[dancer], Some(face), fps, opts)
}

/// Base colours (linear RGBA) of dancers 1, 2, … — dancer 0 uses [`GlbOptions::base_color`] —
/// cycled for larger groups: blue, green, purple, red, teal, chosen to stand apart from the
/// default orange and from each other so partners are told apart at a glance.
pub const EXTRA_DANCER_COLORS: [[f32; 4]; 5] = [
    [0.10, 0.25, 0.80, 1.0],
    [0.15, 0.60, 0.20, 1.0],
    [0.50, 0.20, 0.70, 1.0],
    [0.75, 0.10, 0.10, 1.0],
    [0.10, 0.55, 0.55, 1.0],
];

/// Writes several dancers sharing one skeleton and timeline as one `.glb` scene, atomically,
/// so a duet or group arrives in Blender or Unity already in place.
pub fn write_glb_multi(
    path: impl AsRef<Path>,
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    opts: &GlbOptions,
) -> Result<(), GltfError> {
    let path = path.as_ref();
    let bytes =
        glb_bytes_multi(skeleton, dancers, fps, opts).map_err(|reason| GltfError::Input {
            path: path.to_path_buf(),
            reason,
        })?;
    dancegen_io::write_atomic(path, |w| w.write_all(&bytes))?;
    Ok(())
}

/// The `.glb` file contents for [`write_glb_multi`]. One dancer gives exactly the bytes of
/// [`glb_bytes`].
pub fn glb_bytes_multi(
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
    opts: &GlbOptions,
) -> Result<Vec<u8>, GlbInputError> {
    glb_document(skeleton, dancers, None, fps, opts)
}

fn glb_document(
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    face: Option<FaceAnimation<'_>>,
    fps: f32,
    opts: &GlbOptions,
) -> Result<Vec<u8>, GlbInputError> {
    let joints = skeleton.len();
    let many = dancers.len() > 1;
    let frames = check_scene(
        joints,
        dancers,
        fps,
        &opts.capsule_shape(),
        &opts.base_color,
    )?;

    let times: Vec<f32> = (0..frames)
        .map(|f| (f as f64 / fps as f64) as f32)
        .collect();
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(GlbInputError::TimesNotIncreasing { frames, fps });
    }

    // Rest world positions (rest rotations are identity).
    let parents = skeleton.parents();
    let offsets = skeleton.offsets();
    let mut rest = Vec::with_capacity(joints);
    for j in 0..joints {
        rest.push(match parents[j] {
            None => offsets[j],
            Some(p) => add(rest[p], offsets[j]),
        });
    }
    let mesh = build_capsule_mesh(skeleton, &rest, opts.capsule_shape());

    let mut bin = BinBuilder::default();
    let mut accessors: Vec<Value> = Vec::new();
    let mut views: Vec<Value> = Vec::new();

    // Mesh attributes, shared by every dancer: skin joint indices are per skin, so one body
    // geometry serves all skins.
    let (pos_min, pos_max) = min_max3(&mesh.positions);
    let pos = bin.view(&mut views, &f32_bytes(&mesh.positions), Some(ARRAY_BUFFER));
    accessors.push(
        json!({"bufferView": pos, "componentType": FLOAT, "count": mesh.vertex_count(),
        "type": "VEC3", "min": pos_min, "max": pos_max}),
    );
    let pos_acc = accessors.len() - 1;
    let nrm = bin.view(&mut views, &f32_bytes(&mesh.normals), Some(ARRAY_BUFFER));
    accessors.push(
        json!({"bufferView": nrm, "componentType": FLOAT, "count": mesh.vertex_count(),
        "type": "VEC3"}),
    );
    let nrm_acc = accessors.len() - 1;
    let (joint_bytes, joint_type) = if joints <= 256 {
        (
            mesh.joints
                .iter()
                .flat_map(|&j| [j as u8, 0, 0, 0])
                .collect::<Vec<u8>>(),
            UNSIGNED_BYTE,
        )
    } else {
        (
            mesh.joints
                .iter()
                .flat_map(|&j| [j, 0, 0, 0])
                .flat_map(u16::to_le_bytes)
                .collect(),
            UNSIGNED_SHORT,
        )
    };
    let jv = bin.view(&mut views, &joint_bytes, Some(ARRAY_BUFFER));
    accessors.push(json!({"bufferView": jv, "componentType": joint_type,
        "count": mesh.vertex_count(), "type": "VEC4"}));
    let joints_acc = accessors.len() - 1;
    let weights: Vec<f32> = (0..mesh.vertex_count())
        .flat_map(|_| [1.0f32, 0.0, 0.0, 0.0])
        .collect();
    let wv = bin.view(&mut views, &f32_bytes(&weights), Some(ARRAY_BUFFER));
    accessors.push(json!({"bufferView": wv, "componentType": FLOAT,
        "count": mesh.vertex_count(), "type": "VEC4"}));
    let weights_acc = accessors.len() - 1;
    let (index_bytes, index_type) = if mesh.vertex_count() <= u16::MAX as usize {
        (
            mesh.indices
                .iter()
                .flat_map(|&i| (i as u16).to_le_bytes())
                .collect::<Vec<u8>>(),
            UNSIGNED_SHORT,
        )
    } else {
        (
            mesh.indices.iter().flat_map(|&i| i.to_le_bytes()).collect(),
            UNSIGNED_INT,
        )
    };
    let iv = bin.view(&mut views, &index_bytes, Some(ELEMENT_ARRAY_BUFFER));
    accessors.push(json!({"bufferView": iv, "componentType": index_type,
        "count": mesh.indices.len(), "type": "SCALAR"}));
    let index_acc = accessors.len() - 1;

    // Inverse bind matrices: column-major inverse of the rest world transform (shared, as
    // every dancer has the same rest pose).
    let ibm: Vec<f32> = rest
        .iter()
        .flat_map(|p| {
            let t = p.map(|v| -(v as f32));
            [
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, t[0], t[1], t[2], 1.0,
            ]
        })
        .collect();
    let ibmv = bin.view(&mut views, &f32_bytes(&ibm), None);
    accessors.push(
        json!({"bufferView": ibmv, "componentType": FLOAT, "count": joints,
        "type": "MAT4"}),
    );
    let ibm_acc = accessors.len() - 1;

    // Animation: one shared time accessor, then per dancer its rotations and translation.
    let tv = bin.view(&mut views, &f32_bytes(&times), None);
    accessors.push(
        json!({"bufferView": tv, "componentType": FLOAT, "count": frames,
        "type": "SCALAR", "min": [f64::from(times[0])], "max": [f64::from(times[frames - 1])]}),
    );
    let time_acc = accessors.len() - 1;
    let stride = joints + 1; // nodes (and samplers) per dancer
    let mut samplers = Vec::with_capacity(dancers.len() * stride);
    let mut channels = Vec::with_capacity(dancers.len() * stride);
    for (d, dancer) in dancers.iter().enumerate() {
        let rot = dancer.local_rotations_axis_angle;
        let base = d * stride;
        // Joint-major quaternions (x, y, z, w), one accessor per joint into a shared view.
        let mut quats = vec![0f32; joints * frames * 4];
        for j in 0..joints {
            let mut prev: Option<Quat> = None;
            for f in 0..frames {
                let a = &rot[(f * joints + j) * 3..][..3];
                let mut q =
                    Quat::from_axis_angle([a[0] as f64, a[1] as f64, a[2] as f64]).normalize();
                if let Some(p) = prev
                    && p.dot(q) < 0.0
                {
                    q = -q;
                }
                prev = Some(q);
                quats[(j * frames + f) * 4..][..4]
                    .copy_from_slice(&[q.x as f32, q.y as f32, q.z as f32, q.w as f32]);
            }
        }
        let qv = bin.view(&mut views, &f32_bytes(&quats), None);
        let first_rot_acc = accessors.len();
        for j in 0..joints {
            accessors.push(json!({"bufferView": qv, "byteOffset": j * frames * 16,
                "componentType": FLOAT, "count": frames, "type": "VEC4"}));
        }
        let trv = bin.view(&mut views, &f32_bytes(dancer.root_translation), None);
        accessors.push(
            json!({"bufferView": trv, "componentType": FLOAT, "count": frames,
            "type": "VEC3"}),
        );
        let trans_acc = accessors.len() - 1;
        for j in 0..joints {
            samplers.push(json!({"input": time_acc, "output": first_rot_acc + j,
                "interpolation": "LINEAR"}));
            channels.push(
                json!({"sampler": base + j, "target": {"node": base + j, "path": "rotation"}}),
            );
        }
        samplers.push(json!({"input": time_acc, "output": trans_acc, "interpolation": "LINEAR"}));
        channels.push(
            json!({"sampler": base + joints, "target": {"node": base, "path": "translation"}}),
        );
    }

    // Per dancer: joint nodes, then its mesh node (a scene root without a transform, as the
    // validator recommends for skinned meshes). Its own mesh entry exists only to carry its
    // own material.
    let label = |d: usize, what: &str| {
        if many {
            format!("dancer{d}/{what}")
        } else {
            what.to_string()
        }
    };
    let mut nodes: Vec<Value> = Vec::with_capacity(dancers.len() * stride);
    let mut scene_nodes = Vec::with_capacity(dancers.len() * 2);
    let mut skins = Vec::with_capacity(dancers.len());
    let mut meshes = Vec::with_capacity(dancers.len());
    let mut materials = Vec::with_capacity(dancers.len());
    for d in 0..dancers.len() {
        let base = d * stride;
        for (j, (name, offset)) in skeleton.names().iter().zip(offsets).enumerate() {
            let mut n = json!({"name": label(d, name),
                "translation": offset.map(|v| f64::from(v as f32))});
            let children: Vec<usize> = (j + 1..joints)
                .filter(|&c| parents[c] == Some(j))
                .map(|c| base + c)
                .collect();
            if !children.is_empty() {
                n["children"] = json!(children);
            }
            nodes.push(n);
        }
        let body = if many {
            format!("dancer{d}")
        } else {
            "body".to_string()
        };
        nodes.push(json!({"name": body, "mesh": d, "skin": d}));
        scene_nodes.extend([base, base + joints]);
        skins.push(json!({"name": label(d, "skeleton"),
            "joints": (base..base + joints).collect::<Vec<_>>(),
            "skeleton": base, "inverseBindMatrices": ibm_acc}));
        meshes.push(json!({"name": body, "primitives": [{
            "attributes": {"POSITION": pos_acc, "NORMAL": nrm_acc,
                "JOINTS_0": joints_acc, "WEIGHTS_0": weights_acc},
            "indices": index_acc, "material": d, "mode": 4}]}));
        let c = if d == 0 {
            opts.base_color
        } else {
            EXTRA_DANCER_COLORS[(d - 1) % EXTRA_DANCER_COLORS.len()]
        };
        materials.push(json!({"name": body, "pbrMetallicRoughness": {
            "baseColorFactor": c.map(f64::from), "metallicFactor": 0.0, "roughnessFactor": 0.8}}));
    }

    if let Some(face) = face {
        add_face(
            face,
            frames,
            time_acc,
            FaceParts {
                bin: &mut bin,
                views: &mut views,
                accessors: &mut accessors,
                nodes: &mut nodes,
                meshes: &mut meshes,
                materials: &mut materials,
                samplers: &mut samplers,
                channels: &mut channels,
            },
        )?;
    }

    let doc = json!({
        "asset": {"version": "2.0", "generator": "dancegen"},
        "scene": 0,
        "scenes": [{"name": "dancegen", "nodes": scene_nodes}],
        "nodes": nodes,
        "skins": skins,
        "meshes": meshes,
        "materials": materials,
        "animations": [{"name": opts.animation_name, "samplers": samplers, "channels": channels}],
        "buffers": [{"byteLength": bin.data.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    assemble_glb(
        serde_json::to_vec(&doc).expect("JSON of plain values"),
        bin.data,
    )
    .map_err(GlbInputError::TooLarge)
}

/// The document parts a face adds to.
struct FaceParts<'a> {
    bin: &'a mut BinBuilder,
    views: &'a mut Vec<Value>,
    accessors: &'a mut Vec<Value>,
    nodes: &'a mut Vec<Value>,
    meshes: &'a mut Vec<Value>,
    materials: &'a mut Vec<Value>,
    samplers: &'a mut Vec<Value>,
    channels: &'a mut Vec<Value>,
}

/// Adds the head mesh with its 52 morph targets as a child of the head joint's node, and its
/// `weights` channel (single dancer: node `j` is joint `j`).
fn add_face(
    face: FaceAnimation<'_>,
    frames: usize,
    time_acc: usize,
    p: FaceParts<'_>,
) -> Result<(), GlbInputError> {
    use dancegen_motion::face::{ARKIT_COUNT, ARKIT_NAMES, head_mesh::build_head_mesh};
    if face.weights.frames() != frames {
        return Err(GlbInputError::Face(format!(
            "{} frames of weights for {frames} frames of motion",
            face.weights.frames()
        )));
    }
    let head = face.head_joint;
    if head >= p.nodes.len() || p.nodes[head].get("mesh").is_some() {
        return Err(GlbInputError::Face(format!(
            "head joint {head} is not a joint"
        )));
    }
    let mesh = build_head_mesh();
    let count = mesh.positions.len() / 3;
    let (lo, hi) = min_max3(&mesh.positions);
    let pv = p
        .bin
        .view(p.views, &f32_bytes(&mesh.positions), Some(ARRAY_BUFFER));
    p.accessors.push(
        json!({"bufferView": pv, "componentType": FLOAT, "count": count,
        "type": "VEC3", "min": lo, "max": hi}),
    );
    let pos_acc = p.accessors.len() - 1;
    let nv = p
        .bin
        .view(p.views, &f32_bytes(&mesh.normals), Some(ARRAY_BUFFER));
    p.accessors.push(
        json!({"bufferView": nv, "componentType": FLOAT, "count": count,
        "type": "VEC3"}),
    );
    let nrm_acc = p.accessors.len() - 1;
    let cv = p
        .bin
        .view(p.views, &f32_bytes(&mesh.colors), Some(ARRAY_BUFFER));
    p.accessors.push(
        json!({"bufferView": cv, "componentType": FLOAT, "count": count,
        "type": "VEC3"}),
    );
    let color_acc = p.accessors.len() - 1;
    let idx: Vec<u8> = mesh
        .indices
        .iter()
        .flat_map(|&i| (i as u16).to_le_bytes())
        .collect();
    let iv = p.bin.view(p.views, &idx, Some(ELEMENT_ARRAY_BUFFER));
    p.accessors
        .push(json!({"bufferView": iv, "componentType": UNSIGNED_SHORT,
        "count": mesh.indices.len(), "type": "SCALAR"}));
    let index_acc = p.accessors.len() - 1;
    // Morph targets: one view and accessor per blendshape (vertex attributes sharing a view
    // would need a byteStride; POSITION targets need min and max).
    let mut targets = Vec::with_capacity(ARKIT_COUNT);
    for t in &mesh.targets {
        let (lo, hi) = min_max3(t);
        let tv = p.bin.view(p.views, &f32_bytes(t), Some(ARRAY_BUFFER));
        p.accessors.push(
            json!({"bufferView": tv, "componentType": FLOAT, "count": count,
            "type": "VEC3", "min": lo, "max": hi}),
        );
        targets.push(json!({"POSITION": p.accessors.len() - 1}));
    }
    // The skin and the painted eyes, brows and lips are the vertex colours (COLOR_0, which
    // glTF multiplies with the base colour).
    p.materials
        .push(json!({"name": "face", "pbrMetallicRoughness": {
        "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7}}));
    p.meshes.push(json!({"name": "face", "primitives": [{
        "attributes": {"POSITION": pos_acc, "NORMAL": nrm_acc, "COLOR_0": color_acc},
        "indices": index_acc,
        "material": p.materials.len() - 1, "mode": 4, "targets": targets}],
        "weights": vec![0.0; ARKIT_COUNT],
        "extras": {"targetNames": ARKIT_NAMES.to_vec()}}));
    p.nodes
        .push(json!({"name": "face", "mesh": p.meshes.len() - 1}));
    let face_node = p.nodes.len() - 1;
    let children = p.nodes[head]
        .as_object_mut()
        .expect("a node object")
        .entry("children")
        .or_insert_with(|| json!([]));
    children
        .as_array_mut()
        .expect("children array")
        .push(json!(face_node));
    let wv = p
        .bin
        .view(p.views, &f32_bytes(face.weights.as_slice()), None);
    p.accessors
        .push(json!({"bufferView": wv, "componentType": FLOAT,
        "count": frames * ARKIT_COUNT, "type": "SCALAR"}));
    p.samplers
        .push(json!({"input": time_acc, "output": p.accessors.len() - 1,
        "interpolation": "LINEAR"}));
    p.channels.push(json!({"sampler": p.samplers.len() - 1,
        "target": {"node": face_node, "path": "weights"}}));
    Ok(())
}

const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The binary buffer, each view starting at a multiple of 4.
#[derive(Default)]
struct BinBuilder {
    data: Vec<u8>,
}

impl BinBuilder {
    fn view(&mut self, views: &mut Vec<Value>, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.data.extend_from_slice(bytes);
        views.push(v);
        views.len() - 1
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn min_max3(v: &[f32]) -> (Vec<f64>, Vec<f64>) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in v.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (
        lo.iter().map(|&x| f64::from(x)).collect(),
        hi.iter().map(|&x| f64::from(x)).collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_inputs() {
        let sk = Skeleton::smpl24();
        let o = GlbOptions::default();
        assert_eq!(
            glb_bytes(&sk, &[], &[], 30.0, &o),
            Err(GlbInputError::Scene(SceneInputError::NoFrames))
        );
        let rot = vec![0.0f32; 24 * 3];
        assert!(matches!(
            glb_bytes(&sk, &rot[1..], &[0.0; 3], 30.0, &o),
            Err(GlbInputError::Scene(SceneInputError::RotationShape { .. }))
        ));
        assert!(matches!(
            glb_bytes(&sk, &rot, &[0.0; 6], 30.0, &o),
            Err(GlbInputError::Scene(
                SceneInputError::TranslationShape { .. }
            ))
        ));
        assert!(matches!(
            glb_bytes(&sk, &rot, &[0.0, f32::NAN, 0.0], 30.0, &o),
            Err(GlbInputError::Scene(SceneInputError::NonFinite {
                index: 1,
                ..
            }))
        ));
        assert_eq!(
            glb_bytes(&sk, &rot, &[0.0; 3], 0.0, &o),
            Err(GlbInputError::Scene(SceneInputError::BadFps(0.0)))
        );
        assert!(glb_bytes(&sk, &rot, &[0.0; 3], 30.0, &o).is_ok());
    }
}
