//! Writing the character with the dance: the user's own file as one GLB, its animations replaced
//! by a single animation `dance`.
//!
//! Everything else is the input's JSON unchanged — meshes, skins, materials, textures, morph
//! targets, cameras, extras and extensions (VRM's humanoid, spring bones, MToon) — except what
//! the GLB container and the new animation force:
//! - all buffers become the one GLB binary chunk: every bufferView's bytes are copied, each at
//!   a 4-byte aligned offset (so every accessor stays aligned to its component size), in view
//!   order;
//! - images given by URI (data URIs or files next to a `.gltf`) are embedded as bufferViews
//!   with their `mimeType`;
//! - an animated node given by `matrix` is rewritten as translation/rotation/scale (glTF forbids
//!   animating a `matrix` node);
//! - the old animations' accessors and bufferViews are dropped and the rest renumbered — but
//!   only when every extension in the file is one whose accessor and bufferView references we
//!   know ([`KNOWN_EXTENSIONS`]); with an unknown extension the old data stays (unused, which the
//!   validator reports as information), because renumbering could break a reference we cannot
//!   see.
//!
//! The animation has one LINEAR rotation channel per bone whose local rotation moves, a
//! translation channel on the hips and on detached (IK-style) bones, and key times
//! `frame / fps` as `f32`; its `extras` name the node each SMPL joint drives
//! ([`SMPL_NODES_EXTRA`]). The JSON is written by `serde_json` from the parsed document, so the
//! same inputs give the same bytes.

use std::collections::BTreeSet;
use std::path::Path;

use serde_json::{Map, Value, json};

use super::Character;
use super::error::CharacterError;
use super::gltf_in::array;
use super::retarget::RetargetedAnimation;
use dancegen_formats::glb_container::assemble_glb;

/// Name of the written animation (Blender shows it as the action name).
pub const ANIMATION_NAME: &str = "dance";

/// The animation's `extras` key listing, for each SMPL 24 joint in order, the node it drives
/// (`null` where the character has no bone for it): how a viewer finds the dancer's chest,
/// head and hands in a character whose bones it cannot know by name (the web viewer frames
/// and follows with them). Tools ignore `extras`.
pub const SMPL_NODES_EXTRA: &str = "dancegen_smpl_nodes";

/// Extensions that reference no accessor or bufferView, or whose references are renumbered
/// here (`KHR_draco_mesh_compression`, `EXT_mesh_gpu_instancing`). Any `KHR_materials_*`
/// extension is known too.
pub const KNOWN_EXTENSIONS: &[&str] = &[
    "KHR_animation_pointer",
    "KHR_draco_mesh_compression",
    "KHR_lights_punctual",
    "KHR_materials_variants",
    "KHR_mesh_quantization",
    "KHR_node_visibility",
    "KHR_texture_basisu",
    "KHR_texture_transform",
    "KHR_xmp",
    "KHR_xmp_json_ld",
    "EXT_mesh_gpu_instancing",
    "EXT_texture_avif",
    "EXT_texture_webp",
    "MSFT_lod",
    "MSFT_texture_dds",
    "VRM",
    "VRMC_materials_hdr_emissiveMultiplier",
    "VRMC_materials_mtoon",
    "VRMC_node_constraint",
    "VRMC_springBone",
    "VRMC_springBone_extended_collider",
    "VRMC_vrm",
    "VRMC_vrm_animation",
];

const FLOAT: u32 = 5126;

/// Writes the character with the dance to `path` as a GLB, atomically.
pub fn write_glb(
    path: impl AsRef<Path>,
    character: &Character,
    animation: &RetargetedAnimation,
) -> Result<(), CharacterError> {
    let bytes = glb_bytes(character, animation)?;
    dancegen_io::write_atomic(path.as_ref(), |w| w.write_all(&bytes))?;
    Ok(())
}

/// The GLB file contents of [`write_glb`].
pub fn glb_bytes(
    character: &Character,
    animation: &RetargetedAnimation,
) -> Result<Vec<u8>, CharacterError> {
    let path = character.path();
    let fail = |reason: String| CharacterError::Retarget {
        path: path.to_path_buf(),
        reason,
    };
    let asset = character.asset();
    let tree = character.nodes();
    let times = check_animation(animation, tree.len()).map_err(fail)?;

    let mut doc = asset.json.clone();
    let extensions = extension_names(&doc);
    check_extensions(path, &extensions)?;
    let prune = extensions
        .iter()
        .all(|e| e.starts_with("KHR_materials_") || KNOWN_EXTENSIONS.contains(&e.as_str()));

    // Which accessors and views survive, and their new indices.
    let n_acc = array(&doc, "accessors").len();
    let n_views = array(&doc, "bufferViews").len();
    let acc_keep: Vec<bool> = if prune {
        used_accessors(&doc, n_acc)
    } else {
        vec![true; n_acc]
    };
    let acc_map = renumber(&acc_keep);
    let view_keep: Vec<bool> = if prune {
        used_views(&doc, &acc_keep, n_views)
    } else {
        vec![true; n_views]
    };
    let view_map = renumber(&view_keep);

    // The new binary chunk: surviving views, then embedded images, then the animation.
    let mut bin = Bin::default();
    let mut views: Vec<Value> = Vec::new();
    for (i, v) in array(&doc, "bufferViews").iter().enumerate() {
        if !view_keep[i] {
            continue;
        }
        let b = v.get("buffer").and_then(Value::as_u64).unwrap_or(0) as usize;
        let off = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let len = v.get("byteLength").and_then(Value::as_u64).unwrap_or(0) as usize;
        let bytes = asset
            .buffers
            .get(b)
            .and_then(|d| d.get(off..off.checked_add(len)?))
            .ok_or_else(|| fail(format!("bufferView {i} lies outside its buffer")))?;
        let mut nv = v.clone();
        let at = bin.push(bytes);
        nv["buffer"] = json!(0);
        nv["byteOffset"] = json!(at);
        views.push(nv);
    }
    // Surviving accessors with renumbered views.
    let mut accessors: Vec<Value> = Vec::new();
    for (i, a) in array(&doc, "accessors").iter().enumerate() {
        if !acc_keep[i] {
            continue;
        }
        let mut a = a.clone();
        for ptr in [
            "/bufferView",
            "/sparse/indices/bufferView",
            "/sparse/values/bufferView",
        ] {
            if let Some(v) = a.pointer_mut(ptr) {
                *v = remap(v, &view_map)
                    .ok_or_else(|| fail(format!("accessor {i}: bad bufferView")))?;
            }
        }
        accessors.push(a);
    }

    let Some(root) = doc.as_object_mut() else {
        return Err(fail("the glTF document is not a JSON object".into()));
    };
    root.remove("animations");
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = root.get_mut(key).and_then(Value::as_array_mut) {
            list.retain(|e| e.as_str() != Some("KHR_animation_pointer"));
            if list.is_empty() {
                root.remove(key);
            }
        }
    }

    // Animated nodes must use TRS.
    let animated: BTreeSet<usize> = animation
        .rotations
        .iter()
        .map(|c| c.node)
        .chain(animation.translations.iter().map(|c| c.node))
        .collect();
    if let Some(nodes) = root.get_mut("nodes").and_then(Value::as_array_mut) {
        for &k in &animated {
            if tree.has_matrix[k]
                && let Some(node) = nodes.get_mut(k).and_then(Value::as_object_mut)
            {
                let trs = tree.rest[k];
                let q = trs.rotation;
                node.remove("matrix");
                node.insert("translation".into(), json!(trs.translation));
                node.insert("rotation".into(), json!([q.x, q.y, q.z, q.w]));
                node.insert("scale".into(), json!(trs.scale));
            }
        }
    }

    if let Some(images) = root.get_mut("images").and_then(Value::as_array_mut) {
        for (i, img) in images.iter_mut().enumerate() {
            if let Some(v) = img.get_mut("bufferView") {
                *v = remap(v, &view_map)
                    .ok_or_else(|| fail(format!("image {i}: bad bufferView")))?;
            }
            if let (Some(embedded), Some(obj)) = (
                asset.images.get(i).and_then(Option::as_ref),
                img.as_object_mut(),
            ) {
                let at = bin.push(&embedded.data);
                views.push(
                    json!({"buffer": 0, "byteOffset": at, "byteLength": embedded.data.len()}),
                );
                obj.remove("uri");
                obj.insert("bufferView".into(), json!(views.len() - 1));
                obj.insert("mimeType".into(), json!(embedded.mime_type));
            }
        }
    }
    remap_accessor_refs(root, &acc_map, &view_map).map_err(fail)?;
    normalize_skin_weights(root.get("meshes"), &accessors, &views, &mut bin.data);

    // The dance.
    let frames = animation.frames;
    let time_view = bin.view(&mut views, &f32_bytes(&times));
    accessors.push(
        json!({"bufferView": time_view, "componentType": FLOAT, "count": frames,
        "type": "SCALAR", "min": [f64::from(times[0])], "max": [f64::from(times[frames - 1])]}),
    );
    let time_acc = accessors.len() - 1;
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    let mut add = |accessors: &mut Vec<Value>,
                   views: &mut Vec<Value>,
                   bin: &mut Bin,
                   node: usize,
                   path: &str,
                   data: Vec<f32>,
                   kind: &str| {
        let v = bin.view(views, &f32_bytes(&data));
        accessors.push(
            json!({"bufferView": v, "componentType": FLOAT, "count": frames,
            "type": kind}),
        );
        samplers.push(json!({"input": time_acc, "output": accessors.len() - 1,
            "interpolation": "LINEAR"}));
        channels.push(json!({"sampler": samplers.len() - 1,
            "target": {"node": node, "path": path}}));
    };
    for c in &animation.translations {
        let data = c.values.iter().flatten().copied().collect();
        add(
            &mut accessors,
            &mut views,
            &mut bin,
            c.node,
            "translation",
            data,
            "VEC3",
        );
    }
    for c in &animation.rotations {
        let data = c.values.iter().flatten().copied().collect();
        add(
            &mut accessors,
            &mut views,
            &mut bin,
            c.node,
            "rotation",
            data,
            "VEC4",
        );
    }

    root.insert("accessors".into(), Value::Array(accessors));
    root.insert("bufferViews".into(), Value::Array(views));
    let smpl_nodes: Vec<Option<usize>> =
        (0..24).map(|j| character.bone_map().node_for(j)).collect();
    root.insert(
        "animations".into(),
        json!([{
            "name": ANIMATION_NAME,
            "samplers": samplers,
            "channels": channels,
            "extras": {SMPL_NODES_EXTRA: smpl_nodes},
        }]),
    );
    bin.align();
    root.insert("buffers".into(), json!([{"byteLength": bin.data.len()}]));
    let json_bytes = serde_json::to_vec(&doc).map_err(|e| fail(e.to_string()))?;
    assemble_glb(json_bytes, bin.data).map_err(fail)
}

/// Makes every vertex's skin weights sum to 1, as glTF requires (2.0 spec §3.7.3.3; the
/// validator's `ACCESSOR_WEIGHTS_NON_NORMALIZED`). Some exporters leave sums like 0.98 —
/// RobotExpressive (FBX2glTF) has 752 such vertices — which engines renormalise when they load
/// them anyway, so rescaling here changes no pose and lets the output validate. Only float
/// `VEC4` weights without sparse storage are touched; normalised-integer weights, whose sums
/// are exact by construction, stay as they are. `meshes`, `accessors` and `views` are the
/// output's (renumbered), `bin` the output's binary chunk.
fn normalize_skin_weights(
    meshes: Option<&Value>,
    accessors: &[Value],
    views: &[Value],
    bin: &mut [u8],
) {
    /// A weight set's vertex `v`, component `c` lives at `base + v·stride + 4c`.
    struct Layout {
        base: usize,
        stride: usize,
        count: usize,
    }
    let bin_len = bin.len();
    let layout = |acc: usize| -> Option<Layout> {
        let a = accessors.get(acc)?;
        if a.get("componentType")?.as_u64()? != u64::from(FLOAT)
            || a.get("type")?.as_str()? != "VEC4"
            || a.get("sparse").is_some()
        {
            return None;
        }
        let view = views.get(index(a.get("bufferView")?)?)?;
        let count = a.get("count")?.as_u64()? as usize;
        let base = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize
            + a.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let stride = view.get("byteStride").and_then(Value::as_u64).unwrap_or(16) as usize;
        let end = base.checked_add(count.checked_sub(1)?.checked_mul(stride)?)? + 16;
        (stride >= 16 && end <= bin_len).then_some(Layout {
            base,
            stride,
            count,
        })
    };
    let primitives = meshes
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(|m| m.get("primitives")?.as_array())
        .flatten();
    for prim in primitives {
        let Some(attributes) = prim.get("attributes").and_then(Value::as_object) else {
            continue;
        };
        let sets: Option<Vec<Layout>> = (0..)
            .map_while(|k| attributes.get(&format!("WEIGHTS_{k}")))
            .map(|a| index(a).and_then(layout))
            .collect();
        let Some(sets) = sets.filter(|s| !s.is_empty()) else {
            continue;
        };
        let count = sets[0].count;
        if sets.iter().any(|l| l.count != count) {
            continue;
        }
        let at = |l: &Layout, v: usize, c: usize| l.base + v * l.stride + 4 * c;
        let read =
            |bin: &[u8], i: usize| f32::from_le_bytes([bin[i], bin[i + 1], bin[i + 2], bin[i + 3]]);
        for v in 0..count {
            let sum: f64 = sets
                .iter()
                .flat_map(|l| (0..4).map(move |c| (l, c)))
                .map(|(l, c)| f64::from(read(bin, at(l, v, c))))
                .sum();
            if !(sum.is_finite() && sum > 0.0) || (sum - 1.0).abs() < 1e-7 {
                continue;
            }
            for l in &sets {
                for c in 0..4 {
                    let i = at(l, v, c);
                    let w = (f64::from(read(bin, i)) / sum) as f32;
                    bin[i..i + 4].copy_from_slice(&w.to_le_bytes());
                }
            }
        }
    }
}

/// Rejects what the writer cannot carry over: meshopt compression addresses raw buffers by
/// index and offset, which merging the buffers into one would silently break.
pub(crate) fn check_extensions(
    path: &Path,
    extensions: &BTreeSet<String>,
) -> Result<(), CharacterError> {
    if extensions.contains("EXT_meshopt_compression") {
        return Err(CharacterError::Unsupported {
            path: path.to_path_buf(),
            reason: "meshopt-compressed buffers (EXT_meshopt_compression); decompress the file \
                     first (e.g. `gltf-transform copy`, or `gltfpack -noq`)"
                .into(),
        });
    }
    Ok(())
}

/// Key times, after checking the animation against the character.
fn check_animation(a: &RetargetedAnimation, nodes: usize) -> Result<Vec<f32>, String> {
    if a.frames == 0 {
        return Err("the animation has no frames".into());
    }
    if !(a.fps.is_finite() && a.fps > 0.0) {
        return Err(format!("fps must be finite and positive, got {}", a.fps));
    }
    let times: Vec<f32> = (0..a.frames)
        .map(|f| (f as f64 / f64::from(a.fps)) as f32)
        .collect();
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(format!(
            "{} frames at {} fps: key times are not strictly increasing as f32",
            a.frames, a.fps
        ));
    }
    let rot = a.rotations.iter().map(|c| {
        (
            c.node,
            c.values.len(),
            c.values.iter().flatten().all(|v| v.is_finite()),
        )
    });
    let tr = a.translations.iter().map(|c| {
        (
            c.node,
            c.values.len(),
            c.values.iter().flatten().all(|v| v.is_finite()),
        )
    });
    for (node, len, finite) in rot.chain(tr) {
        if node >= nodes {
            return Err(format!(
                "animation targets node {node}, the character has {nodes}"
            ));
        }
        if len != a.frames {
            return Err(format!(
                "node {node} has {len} keys for {} frames",
                a.frames
            ));
        }
        if !finite {
            return Err(format!("node {node} has a key that is not finite"));
        }
    }
    Ok(times)
}

/// Every extension name used anywhere in the document (and declared in `extensionsUsed`).
pub(crate) fn extension_names(doc: &Value) -> BTreeSet<String> {
    let mut out: BTreeSet<String> = array(doc, "extensionsUsed")
        .iter()
        .filter_map(|e| e.as_str().map(str::to_string))
        .collect();
    let mut stack = vec![doc];
    while let Some(v) = stack.pop() {
        match v {
            Value::Object(m) => {
                for (k, child) in m {
                    if k == "extensions"
                        && let Some(e) = child.as_object()
                    {
                        out.extend(e.keys().cloned());
                    }
                    stack.push(child);
                }
            }
            Value::Array(a) => stack.extend(a.iter()),
            _ => {}
        }
    }
    out
}

fn index(v: &Value) -> Option<usize> {
    v.as_u64().map(|i| i as usize)
}

/// Accessors referenced by meshes, skins and GPU instancing (animations are being replaced).
fn used_accessors(doc: &Value, n: usize) -> Vec<bool> {
    let mut used = vec![false; n];
    let mut mark = |v: &Value| {
        if let Some(i) = index(v).filter(|&i| i < n) {
            used[i] = true;
        }
    };
    for mesh in array(doc, "meshes") {
        for prim in mesh
            .get("primitives")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            prim.get("attributes")
                .and_then(Value::as_object)
                .into_iter()
                .flat_map(|a| a.values())
                .for_each(&mut mark);
            prim.get("indices").into_iter().for_each(&mut mark);
            for t in prim
                .get("targets")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                t.as_object()
                    .into_iter()
                    .flat_map(|a| a.values())
                    .for_each(&mut mark);
            }
        }
    }
    for skin in array(doc, "skins") {
        skin.get("inverseBindMatrices")
            .into_iter()
            .for_each(&mut mark);
    }
    for node in array(doc, "nodes") {
        node.pointer("/extensions/EXT_mesh_gpu_instancing/attributes")
            .and_then(Value::as_object)
            .into_iter()
            .flat_map(|a| a.values())
            .for_each(&mut mark);
    }
    used
}

/// Views referenced by surviving accessors, images and Draco-compressed primitives.
fn used_views(doc: &Value, acc_keep: &[bool], n: usize) -> Vec<bool> {
    let mut used = vec![false; n];
    let mut mark = |v: Option<&Value>| {
        if let Some(i) = v.and_then(index).filter(|&i| i < n) {
            used[i] = true;
        }
    };
    for (i, a) in array(doc, "accessors").iter().enumerate() {
        if acc_keep[i] {
            mark(a.get("bufferView"));
            mark(a.pointer("/sparse/indices/bufferView"));
            mark(a.pointer("/sparse/values/bufferView"));
        }
    }
    for img in array(doc, "images") {
        mark(img.get("bufferView"));
    }
    for mesh in array(doc, "meshes") {
        for prim in mesh
            .get("primitives")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            mark(prim.pointer("/extensions/KHR_draco_mesh_compression/bufferView"));
        }
    }
    used
}

/// Old index → new index for the kept entries.
fn renumber(keep: &[bool]) -> Vec<Option<usize>> {
    let mut next = 0;
    keep.iter()
        .map(|&k| {
            k.then(|| {
                next += 1;
                next - 1
            })
        })
        .collect()
}

fn remap(v: &Value, map: &[Option<usize>]) -> Option<Value> {
    let i = index(v)?;
    map.get(i).copied().flatten().map(|j| json!(j))
}

/// Renumbers the accessor references of meshes, skins and GPU instancing, and Draco's views.
fn remap_accessor_refs(
    root: &mut Map<String, Value>,
    acc: &[Option<usize>],
    views: &[Option<usize>],
) -> Result<(), String> {
    let fix = |v: &mut Value, map: &[Option<usize>], what: &str| -> Result<(), String> {
        *v = remap(v, map).ok_or_else(|| format!("{what} refers to a missing accessor or view"))?;
        Ok(())
    };
    if let Some(meshes) = root.get_mut("meshes").and_then(Value::as_array_mut) {
        for (m, mesh) in meshes.iter_mut().enumerate() {
            let what = format!("mesh {m}");
            for prim in mesh
                .get_mut("primitives")
                .and_then(Value::as_array_mut)
                .into_iter()
                .flatten()
            {
                if let Some(attrs) = prim.get_mut("attributes").and_then(Value::as_object_mut) {
                    for v in attrs.values_mut() {
                        fix(v, acc, &what)?;
                    }
                }
                if let Some(v) = prim.get_mut("indices") {
                    fix(v, acc, &what)?;
                }
                for t in prim
                    .get_mut("targets")
                    .and_then(Value::as_array_mut)
                    .into_iter()
                    .flatten()
                {
                    for v in t.as_object_mut().into_iter().flat_map(|o| o.values_mut()) {
                        fix(v, acc, &what)?;
                    }
                }
                if let Some(v) =
                    prim.pointer_mut("/extensions/KHR_draco_mesh_compression/bufferView")
                {
                    fix(v, views, &what)?;
                }
            }
        }
    }
    if let Some(skins) = root.get_mut("skins").and_then(Value::as_array_mut) {
        for (s, skin) in skins.iter_mut().enumerate() {
            if let Some(v) = skin.get_mut("inverseBindMatrices") {
                fix(v, acc, &format!("skin {s}"))?;
            }
        }
    }
    if let Some(nodes) = root.get_mut("nodes").and_then(Value::as_array_mut) {
        for (k, node) in nodes.iter_mut().enumerate() {
            if let Some(attrs) = node
                .pointer_mut("/extensions/EXT_mesh_gpu_instancing/attributes")
                .and_then(Value::as_object_mut)
            {
                for v in attrs.values_mut() {
                    fix(v, acc, &format!("node {k}"))?;
                }
            }
        }
    }
    Ok(())
}

/// The binary chunk under construction.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
}

impl Bin {
    fn align(&mut self) {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
    }

    /// Appends bytes at a 4-byte aligned offset, which it returns.
    fn push(&mut self, bytes: &[u8]) -> usize {
        self.align();
        let at = self.data.len();
        self.data.extend_from_slice(bytes);
        at
    }

    /// Appends bytes as a new bufferView and returns its index.
    fn view(&mut self, views: &mut Vec<Value>, bytes: &[u8]) -> usize {
        let at = self.push(bytes);
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
        views.len() - 1
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}
