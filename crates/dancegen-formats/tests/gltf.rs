//! glTF 2.0 binary export: container structure, consistency of the node hierarchy with
//! forward kinematics, a real AIST++ motion, and the Khronos glTF-Validator.
//!
//! The validator test installs the npm package `gltf-validator` into
//! `$CARGO_TARGET_TMPDIR/gltf-validator` on first use (node and npm must be on the PATH and the
//! npm registry reachable; otherwise the test fails and says so).

#![allow(clippy::needless_range_loop)] // x/y/z loops read clearer with indices

mod common;

use common::gltf_validator::validate;
use dancegen_formats::aistpp::load_motion;
use dancegen_formats::gltf::{GlbInputError, GlbOptions, GltfError, glb_bytes, write_glb};
use dancegen_formats::scene_input::SceneInputError;
use dancegen_motion::fk::fk_axis_angle_f32;
use dancegen_motion::rotation::axis_angle_to_quat;
use dancegen_motion::skeleton::Skeleton;
use serde_json::Value;

/// SMPL rest pelvis for AIST++ (shared/data/README.md): AIST++ world pelvis in metres is
/// `PELVIS_REST + smpl_trans / smpl_scaling`, because `Skeleton::smpl24()` has a zero root
/// offset and FK puts joint 0 at the translation.
const PELVIS_REST: [f32; 3] = [-0.0021, -0.2444, 0.0282];
const AISTPP_SEQ: &str = "gBR_sBM_cAll_d04_mBR2_ch08";

/// A parsed `.glb`: its JSON document and BIN chunk.
struct Glb {
    doc: Value,
    bin: Vec<u8>,
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// Parses a GLB and checks the container: header, chunk types, lengths and padding.
fn parse_glb(bytes: &[u8]) -> Glb {
    assert!(bytes.len() >= 28, "GLB too short");
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(bytes, 4), 2, "GLB version");
    assert_eq!(u32_at(bytes, 8) as usize, bytes.len(), "header length");
    let json_len = u32_at(bytes, 12) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    assert_eq!(json_len % 4, 0, "JSON chunk length not 4-aligned");
    let json = &bytes[20..20 + json_len];
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bytes, bin_at) as usize;
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    assert_eq!(bin_len % 4, 0, "BIN chunk length not 4-aligned");
    assert_eq!(
        bin_at + 8 + bin_len,
        bytes.len(),
        "BIN chunk must end the file"
    );
    let bin = bytes[bin_at + 8..].to_vec();
    let text = std::str::from_utf8(json).expect("JSON chunk is UTF-8");
    let trimmed = text.trim_end_matches(' ');
    assert!(
        text.len() - trimmed.len() < 4,
        "JSON padded with spaces only"
    );
    let doc: Value = serde_json::from_str(trimmed).expect("JSON chunk parses");
    let blen = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
    assert!(
        blen <= bin.len() && bin.len() - blen < 4,
        "buffer byteLength vs BIN chunk"
    );
    assert!(bin[blen..].iter().all(|&b| b == 0), "BIN padded with zeros");
    Glb { doc, bin }
}

fn comp_size(ct: u64) -> usize {
    match ct {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => panic!("component type {ct}"),
    }
}

fn type_width(t: &str) -> usize {
    match t {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        "MAT4" => 16,
        _ => panic!("accessor type {t}"),
    }
}

impl Glb {
    fn accessor_bytes(&self, i: usize) -> (&[u8], &Value) {
        let a = &self.doc["accessors"][i];
        let v = &self.doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = a["count"].as_u64().unwrap() as usize
            * comp_size(a["componentType"].as_u64().unwrap())
            * type_width(a["type"].as_str().unwrap());
        (&self.bin[start..start + len], a)
    }

    fn f32s(&self, i: usize) -> Vec<f32> {
        let (b, a) = self.accessor_bytes(i);
        assert_eq!(a["componentType"], 5126);
        b.chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    fn uints(&self, i: usize) -> Vec<u32> {
        let (b, a) = self.accessor_bytes(i);
        match a["componentType"].as_u64().unwrap() {
            5121 => b.iter().map(|&x| x as u32).collect(),
            5123 => b
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]) as u32)
                .collect(),
            5125 => b
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                .collect(),
            ct => panic!("component type {ct}"),
        }
    }

    fn arr(&self, key: &str) -> &Vec<Value> {
        self.doc[key].as_array().unwrap()
    }

    /// Finds the sampler output accessor animating `node`'s `path`.
    fn channel_output(&self, node: usize, path: &str) -> (usize, usize) {
        let anim = &self.doc["animations"][0];
        let ch = anim["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["node"] == node && c["target"]["path"] == path)
            .unwrap_or_else(|| panic!("no {path} channel on node {node}"));
        let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
        (
            s["input"].as_u64().unwrap() as usize,
            s["output"].as_u64().unwrap() as usize,
        )
    }

    /// Joint world positions at key `frame`, by evaluating the node hierarchy as a glTF viewer
    /// does: `world = parent_world · T(translation) · R(rotation)`, animated values replacing the
    /// node's own TRS.
    fn joint_world_positions(&self, joints: usize, frame: usize) -> Vec<[f64; 3]> {
        let nodes = self.arr("nodes");
        let mut parent = vec![None; nodes.len()];
        for (i, n) in nodes.iter().enumerate() {
            for c in n["children"].as_array().into_iter().flatten() {
                parent[c.as_u64().unwrap() as usize] = Some(i);
            }
        }
        let mut world: Vec<([f64; 3], [f64; 4])> = Vec::new(); // (translation, quat xyzw)
        for (j, node) in nodes.iter().enumerate().take(joints) {
            let mut t: Vec<f64> = node["translation"]
                .as_array()
                .map(|a| a.iter().map(|v| v.as_f64().unwrap()).collect())
                .unwrap_or(vec![0.0; 3]);
            if j == 0 {
                let (_, out) = self.channel_output(0, "translation");
                let v = self.f32s(out);
                t = v[frame * 3..frame * 3 + 3]
                    .iter()
                    .map(|&x| x as f64)
                    .collect();
            }
            let (_, out) = self.channel_output(j, "rotation");
            let q = self.f32s(out);
            let q = [0, 1, 2, 3].map(|k| q[frame * 4 + k] as f64);
            let t = [t[0], t[1], t[2]];
            world.push(match parent[j] {
                None => (t, q),
                Some(p) => {
                    let (pt, pq) = world[p];
                    let r = rotate(pq, t);
                    ([pt[0] + r[0], pt[1] + r[1], pt[2] + r[2]], qmul(pq, q))
                }
            });
        }
        world.into_iter().map(|(t, _)| t).collect()
    }
}

/// Hamilton product of `(x, y, z, w)` quaternions.
fn qmul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let p = qmul(
        qmul(q, [v[0], v[1], v[2], 0.0]),
        [-q[0], -q[1], -q[2], q[3]],
    );
    [p[0], p[1], p[2]]
}

/// A smooth synthetic motion: every joint swings about a different axis, the root walks.
fn synthetic_motion(frames: usize, joints: usize) -> (Vec<f32>, Vec<f32>) {
    let mut rot = Vec::with_capacity(frames * joints * 3);
    let mut trans = Vec::with_capacity(frames * 3);
    for f in 0..frames {
        let t = f as f32 / 30.0;
        for j in 0..joints {
            let a = 0.6 * (2.0 * t + j as f32).sin();
            rot.extend([
                a * (j as f32 * 0.7).cos(),
                a * 0.5,
                a * (j as f32 * 1.3).sin(),
            ]);
        }
        trans.extend([0.3 * t, 0.9 + 0.05 * (6.0 * t).sin(), -0.2 * t]);
    }
    // Turn the root a full circle so quaternion hemisphere handling is exercised.
    for f in 0..frames {
        let ang = std::f32::consts::TAU * 1.5 * f as f32 / frames as f32;
        rot[f * joints * 3..f * joints * 3 + 3].copy_from_slice(&[0.0, ang % 6.2, 0.0]);
    }
    (rot, trans)
}

/// Structural checks shared by the tests; returns the parsed file.
fn check_structure(bytes: &[u8], sk: &Skeleton, rot: &[f32], trans: &[f32], fps: f32) -> Glb {
    let joints = sk.len();
    let frames = trans.len() / 3;
    let g = parse_glb(bytes);
    let doc = &g.doc;
    assert_eq!(doc["asset"]["version"], "2.0");
    assert_eq!(doc["asset"]["generator"], "dancegen");
    let blen = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;

    // Buffer views: aligned, inside the buffer, targets as required.
    for v in g.arr("bufferViews") {
        let off = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = v["byteLength"].as_u64().unwrap() as usize;
        assert_eq!(off % 4, 0, "bufferView offset not aligned: {v}");
        assert!(off + len <= blen, "bufferView beyond buffer: {v}");
        assert!(v.get("byteStride").is_none());
    }
    // Accessors inside their views, aligned to their component size.
    for (i, a) in g.arr("accessors").iter().enumerate() {
        let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let off = a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let cs = comp_size(a["componentType"].as_u64().unwrap());
        let len =
            a["count"].as_u64().unwrap() as usize * cs * type_width(a["type"].as_str().unwrap());
        assert_eq!(off % cs, 0, "accessor {i} misaligned");
        assert!(
            off + len <= v["byteLength"].as_u64().unwrap() as usize,
            "accessor {i} overruns its view"
        );
    }

    // Nodes, skin, scene.
    let nodes = g.arr("nodes");
    assert_eq!(nodes.len(), joints + 1);
    for (j, n) in nodes.iter().take(joints).enumerate() {
        assert_eq!(n["name"], sk.names()[j].as_str());
        let t: Vec<f64> = n["translation"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for k in 0..3 {
            assert!(
                (t[k] - sk.offsets()[j][k]).abs() < 1e-6,
                "node {j} rest translation"
            );
        }
    }
    let body = &nodes[joints];
    assert_eq!(body["mesh"], 0);
    assert_eq!(body["skin"], 0);
    assert!(body.get("translation").is_none() && body.get("children").is_none());
    assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0, joints]));
    let skin = &doc["skins"][0];
    assert_eq!(skin["joints"].as_array().unwrap().len(), joints);
    let ibm_acc = skin["inverseBindMatrices"].as_u64().unwrap() as usize;
    assert_eq!(doc["accessors"][ibm_acc]["type"], "MAT4");
    let ibm = g.f32s(ibm_acc);
    let mut rest = sk.rest_positions();
    for p in &mut rest {
        for k in 0..3 {
            p[k] += sk.offsets()[0][k];
        }
    }
    for j in 0..joints {
        let m = &ibm[j * 16..j * 16 + 16];
        for k in 0..3 {
            assert!(
                (m[12 + k] as f64 + rest[j][k]).abs() < 1e-6,
                "IBM {j} translation (column-major)"
            );
            assert_eq!(m[k * 5], 1.0);
        }
    }

    // Mesh primitive.
    let prim = &doc["meshes"][0]["primitives"][0];
    let attr = &prim["attributes"];
    let pos_acc = &doc["accessors"][attr["POSITION"].as_u64().unwrap() as usize];
    assert!(
        pos_acc["min"].is_array() && pos_acc["max"].is_array(),
        "POSITION needs min/max"
    );
    let vcount = pos_acc["count"].as_u64().unwrap() as usize;
    for key in ["POSITION", "NORMAL", "JOINTS_0", "WEIGHTS_0"] {
        let a = &doc["accessors"][attr[key].as_u64().unwrap() as usize];
        assert_eq!(a["count"].as_u64().unwrap() as usize, vcount, "{key} count");
        let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        assert_eq!(v["target"], 34962, "{key} view target");
    }
    let idx_acc = prim["indices"].as_u64().unwrap() as usize;
    let iv =
        &doc["bufferViews"][doc["accessors"][idx_acc]["bufferView"].as_u64().unwrap() as usize];
    assert_eq!(iv["target"], 34963);
    let indices = g.uints(idx_acc);
    assert_eq!(indices.len() % 3, 0);
    assert!(indices.iter().all(|&i| (i as usize) < vcount));
    let positions = g.f32s(attr["POSITION"].as_u64().unwrap() as usize);
    for k in 0..3 {
        let lo = positions
            .iter()
            .skip(k)
            .step_by(3)
            .copied()
            .fold(f32::INFINITY, f32::min);
        let hi = positions
            .iter()
            .skip(k)
            .step_by(3)
            .copied()
            .fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(pos_acc["min"][k].as_f64().unwrap() as f32, lo);
        assert_eq!(pos_acc["max"][k].as_f64().unwrap() as f32, hi);
    }
    let weights = g.f32s(attr["WEIGHTS_0"].as_u64().unwrap() as usize);
    for w in weights.chunks_exact(4) {
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }
    let vjoints = g.uints(attr["JOINTS_0"].as_u64().unwrap() as usize);
    assert!(vjoints.iter().all(|&j| (j as usize) < joints));
    let mat = &doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"];
    assert_eq!(mat.as_array().unwrap().len(), 4);

    // Animation: one rotation channel per joint plus the root translation.
    let anim = &doc["animations"][0];
    assert_eq!(anim["channels"].as_array().unwrap().len(), joints + 1);
    for s in anim["samplers"].as_array().unwrap() {
        assert_eq!(s["interpolation"], "LINEAR");
        let input = &doc["accessors"][s["input"].as_u64().unwrap() as usize];
        assert!(
            input["min"].is_array() && input["max"].is_array(),
            "input needs min/max"
        );
        assert!(
            doc["bufferViews"][input["bufferView"].as_u64().unwrap() as usize]
                .get("target")
                .is_none()
        );
    }
    let (time_acc, trans_acc) = g.channel_output(0, "translation");
    let times = g.f32s(time_acc);
    assert_eq!(times.len(), frames);
    for (f, t) in times.iter().enumerate() {
        assert!((*t as f64 - f as f64 / fps as f64).abs() < 1e-5);
    }
    assert_eq!(
        doc["accessors"][time_acc]["max"][0].as_f64().unwrap() as f32,
        times[frames - 1]
    );
    assert_eq!(
        g.f32s(trans_acc),
        trans,
        "root translation track = pelvis world position"
    );
    // Rotations are the local axis-angle rotations as (x, y, z, w), up to sign.
    let wxyz = axis_angle_to_quat(rot);
    for j in 0..joints {
        let (_, out) = g.channel_output(j, "rotation");
        let q = g.f32s(out);
        assert_eq!(q.len(), frames * 4);
        for f in 0..frames {
            let e = &wxyz[(f * joints + j) * 4..][..4];
            let got = &q[f * 4..f * 4 + 4];
            let dot = got[3] * e[0] + got[0] * e[1] + got[1] * e[2] + got[2] * e[3];
            assert!(
                (dot.abs() - 1.0).abs() < 1e-5,
                "joint {j} frame {f}: {got:?} vs wxyz {e:?}"
            );
            if f > 0 {
                let p = &q[f * 4 - 4..f * 4];
                let d: f32 = (0..4).map(|k| p[k] * got[k]).sum();
                assert!(d >= 0.0, "joint {j} frame {f}: quaternion sign flip");
            }
        }
    }
    g
}

/// Asserts that the evaluated node hierarchy reproduces forward kinematics on `frames`.
fn check_matches_fk(g: &Glb, sk: &Skeleton, rot: &[f32], trans: &[f32], frames: &[usize]) -> f64 {
    let joints = sk.len();
    let fk = fk_axis_angle_f32(sk, rot, trans).unwrap();
    let mut worst = 0f64;
    for &f in frames {
        let world = g.joint_world_positions(joints, f);
        for j in 0..joints {
            for k in 0..3 {
                let e = fk[(f * joints + j) * 3 + k] as f64;
                worst = worst.max((world[j][k] - e).abs());
            }
        }
    }
    assert!(worst < 1e-4, "glTF hierarchy vs FK: max error {worst} m");
    worst
}

#[test]
fn structure_and_hierarchy_match_fk() {
    let sk = Skeleton::smpl24();
    let (rot, trans) = synthetic_motion(90, sk.len());
    let bytes = glb_bytes(&sk, &rot, &trans, 30.0, &GlbOptions::default()).unwrap();
    let g = check_structure(&bytes, &sk, &rot, &trans, 30.0);
    check_matches_fk(&g, &sk, &rot, &trans, &[0, 1, 44, 89]);
}

#[test]
fn single_frame_pose_and_non_zero_root_offset() {
    // A skeleton whose root has a rest offset: the rest node translation is that offset, the
    // animated translation still puts the pelvis exactly at root_translation.
    let base = Skeleton::smpl24();
    let mut offsets = base.offsets().to_vec();
    offsets[0] = [0.0, 0.93, 0.02];
    let sk = Skeleton::new(base.names().to_vec(), base.parents().to_vec(), offsets).unwrap();
    let (rot, trans) = synthetic_motion(1, sk.len());
    let bytes = glb_bytes(&sk, &rot, &trans, 60.0, &GlbOptions::default()).unwrap();
    let g = check_structure(&bytes, &sk, &rot, &trans, 60.0);
    let world = g.joint_world_positions(sk.len(), 0);
    for k in 0..3 {
        assert!((world[0][k] - trans[k] as f64).abs() < 1e-6);
    }
    check_matches_fk(&g, &sk, &rot, &trans, &[0]);
}

#[test]
fn errors_name_the_path() {
    let sk = Skeleton::smpl24();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.glb");
    let err = write_glb(&path, &sk, &[], &[], 30.0, &GlbOptions::default()).unwrap_err();
    assert!(matches!(
        err,
        GltfError::Input {
            reason: GlbInputError::Scene(SceneInputError::NoFrames),
            ..
        }
    ));
    assert!(err.to_string().contains("empty.glb"), "{err}");
    assert!(!path.exists());
    let missing = dir.path().join("no/such/dir/x.glb");
    let rot = vec![0.0; 72];
    let err = write_glb(&missing, &sk, &rot, &[0.0; 3], 30.0, &GlbOptions::default()).unwrap_err();
    assert!(matches!(err, GltfError::Write(_)));
    assert!(err.to_string().contains("x.glb"), "{err}");
}

/// The AIST++ motion as (poses, pelvis world trajectory in metres, fps).
fn aistpp_motion() -> (Vec<f32>, Vec<f32>, f32) {
    let path = common::shared_dir().join(format!("data/aistpp/motions/{AISTPP_SEQ}.pkl"));
    let m = load_motion(&path).unwrap();
    let trans: Vec<f32> = m
        .trans_metres()
        .chunks_exact(3)
        .flat_map(|t| [0, 1, 2].map(|k| t[k] + PELVIS_REST[k]))
        .collect();
    (m.poses, trans, m.fps as f32)
}

#[test]
fn real_aistpp_motion() {
    let sk = Skeleton::smpl24();
    let (rot, trans, fps) = aistpp_motion();
    let frames = trans.len() / 3;
    assert_eq!(frames, 576);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("{AISTPP_SEQ}.glb"));
    write_glb(&path, &sk, &rot, &trans, fps, &GlbOptions::default()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    eprintln!(
        "{AISTPP_SEQ}: {frames} frames at {fps} fps -> {} bytes",
        bytes.len()
    );
    let g = check_structure(&bytes, &sk, &rot, &trans, fps);
    let worst = check_matches_fk(&g, &sk, &rot, &trans, &[0, 100, 287, 575]);
    eprintln!("max |glTF hierarchy - FK| = {worst:.2e} m");
    let dur = g.doc["accessors"][g.channel_output(0, "rotation").0]["max"][0]
        .as_f64()
        .unwrap();
    assert!((dur - 575.0 / 60.0).abs() < 1e-5, "duration {dur}");
    // The AIST++ pelvis trajectory is in metres above the floor: about 0.9 m at the start.
    let world = g.joint_world_positions(sk.len(), 0);
    assert!(
        world[0][1] > 0.7 && world[0][1] < 1.1,
        "pelvis height {}",
        world[0][1]
    );
}

#[test]
fn khronos_validator_accepts_output() {
    let sk = Skeleton::smpl24();
    let dir = tempfile::tempdir().unwrap();
    let (rot, trans) = synthetic_motion(30, sk.len());
    let synthetic = dir.path().join("synthetic.glb");
    write_glb(&synthetic, &sk, &rot, &trans, 30.0, &GlbOptions::default()).unwrap();
    let single = dir.path().join("single.glb");
    write_glb(
        &single,
        &sk,
        &rot[..72],
        &trans[..3],
        30.0,
        &GlbOptions::default(),
    )
    .unwrap();
    let (rot, trans, fps) = aistpp_motion();
    let real = dir.path().join(format!("{AISTPP_SEQ}.glb"));
    write_glb(&real, &sk, &rot, &trans, fps, &GlbOptions::default()).unwrap();
    for path in [&synthetic, &single, &real] {
        let report = validate(path);
        assert_eq!(
            report["issues"]["numErrors"],
            0,
            "{} has validation errors",
            path.display()
        );
        assert_eq!(report["info"]["animationCount"], 1);
        assert_eq!(report["info"]["hasSkins"], true);
    }
}
