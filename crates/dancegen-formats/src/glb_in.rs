//! Reading back the dances `.glb` files that dancegen writes ([`crate::gltf`]): each skin is a
//! dancer whose joint nodes carry one of the rigs' SMPL 24 bone names ([`crate::rig::Rig::joint_names`],
//! `dancer{d}/` prefixed in a scene of several), animated by one rotation channel per joint
//! and a translation channel (the pelvis world position) on the root, with key times
//! `frame / fps`. So `render`, `convert`, `eval`, `--leader`, `--edit` and `--continue-from` read
//! what `generate` writes. A holistic dance's skeleton has no SMPL hand joints (its fingers
//! hang from the wrists): those two stay at rest. Any other glTF is refused with the reason.
//!
//! Every index and length in the file is checked against what is there before it is used.

use std::path::Path;

use dancegen_motion::repr::motion::{POSE_DIMS, SMPL_JOINTS, SmplMotion};
use dancegen_motion::rotation::Quat;
use serde_json::Value;

use crate::glb_container::split_glb;
use crate::rig::smpl_joints_by_name;

/// Most key frames read (an hour at 120 fps), so a length field cannot ask for gigabytes.
const MAX_KEYS: usize = 120 * 3600;

/// The dancers of a `.glb` dancegen wrote, in skin order.
pub fn read_dance_glb(path: &Path) -> Result<Vec<SmplMotion>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    if !bytes.starts_with(b"glTF") {
        return Err("not a binary glTF (.glb) file".into());
    }
    let (json, bin) = split_glb(&bytes).map_err(|e| e.to_string())?;
    let json: Value =
        serde_json::from_slice(json).map_err(|e| format!("the glTF JSON does not parse: {e}"))?;
    let bin = bin.unwrap_or(&[]);
    let doc = Doc { json: &json, bin };
    let skins = doc.array("skins");
    if skins.is_empty() {
        return Err("the file has no skeleton (no skin): not a dance dancegen wrote".into());
    }
    let anim = doc
        .array("animations")
        .first()
        .ok_or("the file has no animation")?;
    // Node -> (sampler's input accessor, output accessor) per animated path.
    let mut rotation = std::collections::HashMap::new();
    let mut translation = std::collections::HashMap::new();
    let samplers = anim
        .get("samplers")
        .and_then(Value::as_array)
        .ok_or("animation without samplers")?;
    for ch in anim
        .get("channels")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
    {
        let sampler = index(ch.get("sampler")).and_then(|i| samplers.get(i));
        let target = ch.get("target");
        let node = target.and_then(|t| index(t.get("node")));
        let kind = target.and_then(|t| t.get("path")).and_then(Value::as_str);
        let (Some(s), Some(node), Some(kind)) = (sampler, node, kind) else {
            return Err("an animation channel without its sampler or target".into());
        };
        let io = (index(s.get("input")), index(s.get("output")));
        let (Some(input), Some(output)) = io else {
            return Err("an animation sampler without input or output".into());
        };
        match kind {
            "rotation" => rotation.insert(node, (input, output)),
            "translation" => translation.insert(node, (input, output)),
            _ => None,
        };
    }
    let nodes = doc.array("nodes");
    let mut dancers = Vec::with_capacity(skins.len());
    for (d, skin) in skins.iter().enumerate() {
        let joints: Vec<usize> = skin
            .get("joints")
            .and_then(Value::as_array)
            .ok_or_else(|| format!("skin {d} has no joints"))?
            .iter()
            .map(|j| index(Some(j)).filter(|&j| j < nodes.len()))
            .collect::<Option<_>>()
            .ok_or_else(|| format!("skin {d} names a node that is not in the file"))?;
        let name_of = |n: usize| {
            let name = nodes[n].get("name").and_then(Value::as_str).unwrap_or("");
            name.rsplit_once('/')
                .map_or(name, |(_, tail)| tail)
                .to_string()
        };
        let names: Vec<String> = joints.iter().map(|&n| name_of(n)).collect();
        // SMPL joint k -> node index, in the first rig whose every body joint is there.
        let smpl_nodes: Vec<Option<usize>> = smpl_joints_by_name(&names, d)?
            .into_iter()
            .map(|i| i.map(|i| joints[i]))
            .collect();
        let root = smpl_nodes[0].expect("the pelvis is required");
        let &(times_at, trans_at) = translation
            .get(&root)
            .ok_or_else(|| format!("dancer {d}'s root has no translation animation"))?;
        let times = doc.floats(times_at, 1)?;
        if times.is_empty() {
            return Err(format!("dancer {d}'s animation has no keys"));
        }
        let frames = times.len();
        let fps = if frames > 1 {
            (frames - 1) as f64 / f64::from(times[frames - 1] - times[0])
        } else {
            30.0
        };
        if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
            return Err(format!("dancer {d}'s key times give {fps} frames a second"));
        }
        let trans = doc.floats(trans_at, 3)?;
        if trans.len() != frames * 3 {
            return Err(format!(
                "dancer {d}'s root has {} keys, not {frames}",
                trans.len() / 3
            ));
        }
        let mut poses = vec![0f32; frames * POSE_DIMS];
        for (k, node) in smpl_nodes.iter().enumerate().take(SMPL_JOINTS) {
            let Some(node) = node else { continue };
            let Some(&(_, rot_at)) = rotation.get(node) else {
                continue; // not animated: at rest
            };
            let q = doc.floats(rot_at, 4)?;
            if q.len() != frames * 4 {
                return Err(format!(
                    "dancer {d}, joint {k}: {} rotation keys, not {frames}",
                    q.len() / 4
                ));
            }
            for f in 0..frames {
                let [x, y, z, w] = [0, 1, 2, 3].map(|i| f64::from(q[f * 4 + i]));
                let aa = Quat::new(w, x, y, z).normalize().to_axis_angle();
                for a in 0..3 {
                    poses[f * POSE_DIMS + k * 3 + a] = aa[a] as f32;
                }
            }
        }
        let m = SmplMotion::new(fps.round() as f32, poses, trans)
            .map_err(|e| format!("dancer {d}: {e}"))?;
        dancers.push(m);
    }
    Ok(dancers)
}

/// The JSON document and the BIN chunk.
struct Doc<'a> {
    json: &'a Value,
    bin: &'a [u8],
}

fn index(v: Option<&Value>) -> Option<usize> {
    v.and_then(Value::as_u64)
        .and_then(|i| usize::try_from(i).ok())
}

impl Doc<'_> {
    fn array(&self, key: &str) -> &[Value] {
        self.json
            .get(key)
            .and_then(Value::as_array)
            .map(Vec::as_slice)
            .unwrap_or(&[])
    }

    /// Accessor `i`'s floats (`width` per element: SCALAR 1, VEC3 3, VEC4 4), from the BIN
    /// chunk, every offset and length checked.
    fn floats(&self, i: usize, width: usize) -> Result<Vec<f32>, String> {
        let acc = self
            .array("accessors")
            .get(i)
            .ok_or(format!("no accessor {i}"))?;
        let bad = |why: &str| format!("accessor {i}: {why}");
        if acc.get("componentType").and_then(Value::as_u64) != Some(5126) {
            return Err(bad("not 32-bit floats"));
        }
        let want = match width {
            1 => "SCALAR",
            3 => "VEC3",
            _ => "VEC4",
        };
        if acc.get("type").and_then(Value::as_str) != Some(want) {
            return Err(bad(&format!("not {want}")));
        }
        let count = index(acc.get("count")).ok_or_else(|| bad("no count"))?;
        if count > MAX_KEYS {
            return Err(bad(&format!("{count} keys, more than {MAX_KEYS}")));
        }
        let view = index(acc.get("bufferView"))
            .and_then(|v| self.array("bufferViews").get(v))
            .ok_or_else(|| bad("no buffer view"))?;
        if index(view.get("buffer")) != Some(0) {
            return Err(bad("its data is not in the file's binary chunk"));
        }
        let start =
            index(view.get("byteOffset")).unwrap_or(0) + index(acc.get("byteOffset")).unwrap_or(0);
        let stride = index(view.get("byteStride")).unwrap_or(width * 4);
        if stride < width * 4 {
            return Err(bad("a stride shorter than an element"));
        }
        let need = if count == 0 {
            0
        } else {
            (count - 1) * stride + width * 4
        };
        let end = start
            .checked_add(need)
            .ok_or_else(|| bad("offset overflows"))?;
        if end > self.bin.len() {
            return Err(bad("past the end of the binary chunk"));
        }
        let mut out = Vec::with_capacity(count * width);
        for e in 0..count {
            for c in 0..width {
                let o = start + e * stride + c * 4;
                let b = &self.bin[o..o + 4];
                let v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                if !v.is_finite() {
                    return Err(bad(&format!("element {e} is not finite")));
                }
                out.push(v);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gltf::{DancerAnimation, GlbOptions, glb_bytes_multi};
    use crate::rig::Rig;
    use dancegen_motion::rotation::Mat3;

    fn dancer(seed: f32, frames: usize) -> (Vec<f32>, Vec<f32>) {
        crate::test_dancers::turning_dancer(seed, frames, 0.9)
    }

    #[test]
    fn a_written_scene_reads_back_with_its_rotations_roots_and_rate() {
        let dir = tempfile::tempdir().unwrap();
        for rig in Rig::ALL {
            let (a, b) = (dancer(0.1, 12), dancer(2.0, 12));
            let scene = [
                DancerAnimation {
                    local_rotations_axis_angle: &a.0,
                    root_translation: &a.1,
                },
                DancerAnimation {
                    local_rotations_axis_angle: &b.0,
                    root_translation: &b.1,
                },
            ];
            let bytes =
                glb_bytes_multi(&rig.skeleton(), &scene, 30.0, &GlbOptions::default()).unwrap();
            let path = dir.path().join(format!("{}.glb", rig.name()));
            std::fs::write(&path, bytes).unwrap();
            let read = read_dance_glb(&path).unwrap();
            assert_eq!(read.len(), 2, "{rig:?}");
            for (m, (rot, trans)) in read.iter().zip([&a, &b]) {
                assert_eq!(m.fps, 30.0);
                assert_eq!(&m.trans, trans);
                for (got, want) in m.poses.chunks(3).zip(rot.chunks(3)) {
                    let g = Mat3::from_axis_angle([0, 1, 2].map(|a| f64::from(got[a])));
                    let w = Mat3::from_axis_angle([0, 1, 2].map(|a| f64::from(want[a])));
                    for r in 0..3 {
                        for c in 0..3 {
                            assert!((g.0[r][c] - w.0[r][c]).abs() < 1e-5, "{rig:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn broken_and_foreign_files_are_errors_not_panics() {
        let dir = tempfile::tempdir().unwrap();
        let (rot, trans) = dancer(0.3, 5);
        let one = [DancerAnimation {
            local_rotations_axis_angle: &rot,
            root_translation: &trans,
        }];
        let good =
            glb_bytes_multi(&Rig::Smpl.skeleton(), &one, 30.0, &GlbOptions::default()).unwrap();
        let path = dir.path().join("x.glb");
        // Every truncation of a good file is an error, never a panic.
        for cut in (0..good.len()).step_by(97) {
            std::fs::write(&path, &good[..cut]).unwrap();
            assert!(read_dance_glb(&path).is_err(), "cut at {cut}");
        }
        std::fs::write(&path, b"not a glb").unwrap();
        assert_eq!(
            read_dance_glb(&path).unwrap_err(),
            "not a binary glTF (.glb) file"
        );
        // A skeleton with other bone names.
        let mut renamed = good.clone();
        let at = renamed
            .windows(6)
            .position(|w| w == b"\"lhip\"")
            .expect("the left hip is named in the JSON");
        renamed[at..at + 6].copy_from_slice(b"\"lhiq\"");
        std::fs::write(&path, &renamed).unwrap();
        let e = read_dance_glb(&path).unwrap_err();
        assert!(e.contains("not an SMPL 24 skeleton"), "{e}");
    }
}
