//! Several dancers in one `.glb`: layout (per-dancer joints, skins, meshes, materials and
//! channels), each dancer's hierarchy against forward kinematics, input errors, the
//! single-dancer output staying as before, `save_motion_file` on a group, and the Khronos
//! glTF-Validator (`tests/common/gltf_validator.rs`).

mod common;

use common::gltf_validator::validate;
use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, save_motion_file};
use dancegen_formats::gltf::{
    DancerAnimation, EXTRA_DANCER_COLORS, GlbInputError, GlbOptions, glb_bytes, glb_bytes_multi,
    write_glb_multi,
};
use dancegen_formats::scene_input::SceneInputError;
use dancegen_motion::fk::fk_axis_angle_f32;
use dancegen_motion::repr::SmplMotion;
use dancegen_motion::skeleton::Skeleton;
use serde_json::{Value, json};

/// JSON document and BIN chunk of a GLB, after checking the container header.
fn parse_glb(bytes: &[u8]) -> (Value, Vec<u8>) {
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(4), 2);
    assert_eq!(u32_at(8), bytes.len());
    let json_len = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let bin_at = 20 + json_len;
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    assert_eq!(bin_at + 8 + u32_at(bin_at), bytes.len());
    let doc = serde_json::from_slice(&bytes[20..bin_at]).unwrap();
    (doc, bytes[bin_at + 8..].to_vec())
}

fn f32s(doc: &Value, bin: &[u8], acc: usize) -> Vec<f32> {
    let a = &doc["accessors"][acc];
    assert_eq!(a["componentType"], 5126);
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let start =
        v["byteOffset"].as_u64().unwrap() as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let width = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        "VEC4" => 4,
        "MAT4" => 16,
        t => panic!("{t}"),
    };
    let n = a["count"].as_u64().unwrap() as usize * width;
    bin[start..start + 4 * n]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

/// A distinct smooth motion per `seed`.
fn motion(frames: usize, joints: usize, seed: f32) -> (Vec<f32>, Vec<f32>) {
    let mut rot = Vec::with_capacity(frames * joints * 3);
    let mut trans = Vec::with_capacity(frames * 3);
    for f in 0..frames {
        let t = f as f32 / 30.0;
        for j in 0..joints {
            let a = 0.5 * (2.0 * t + j as f32 + seed).sin();
            rot.extend([
                a * (j as f32 * 0.7 + seed).cos(),
                0.4 * a,
                a * (j as f32).sin(),
            ]);
        }
        trans.extend([seed + 0.3 * t, 0.9, -0.2 * t * seed]);
    }
    (rot, trans)
}

fn dancer<'a>(m: &'a (Vec<f32>, Vec<f32>)) -> DancerAnimation<'a> {
    DancerAnimation {
        local_rotations_axis_angle: &m.0,
        root_translation: &m.1,
    }
}

/// Output accessor of the sampler animating `node`'s `path`.
fn channel_output(doc: &Value, node: usize, path: &str) -> usize {
    let anim = &doc["animations"][0];
    let ch = anim["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["node"] == node && c["target"]["path"] == path)
        .unwrap_or_else(|| panic!("no {path} channel on node {node}"));
    anim["samplers"][ch["sampler"].as_u64().unwrap() as usize]["output"]
        .as_u64()
        .unwrap() as usize
}

/// Joint world positions of the hierarchy rooted at node `root` at key `frame`, as a glTF viewer
/// evaluates it (children listed in the nodes, animated TRS replacing the rest TRS).
fn world_positions(doc: &Value, bin: &[u8], root: usize, frame: usize) -> Vec<(usize, [f64; 3])> {
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
    let nodes = doc["nodes"].as_array().unwrap();
    let mut out = Vec::new();
    let mut stack = vec![(root, [0.0; 3], [0.0, 0.0, 0.0, 1.0])];
    while let Some((n, pt, pq)) = stack.pop() {
        let local: Vec<f64> = if n == root {
            let v = f32s(doc, bin, channel_output(doc, n, "translation"));
            v[frame * 3..frame * 3 + 3]
                .iter()
                .map(|&x| x as f64)
                .collect()
        } else {
            nodes[n]["translation"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        };
        let q = f32s(doc, bin, channel_output(doc, n, "rotation"));
        let q = [0, 1, 2, 3].map(|k| q[frame * 4 + k] as f64);
        let r = qmul(
            qmul(pq, [local[0], local[1], local[2], 0.0]),
            [-pq[0], -pq[1], -pq[2], pq[3]],
        );
        let t = [pt[0] + r[0], pt[1] + r[1], pt[2] + r[2]];
        out.push((n, t));
        for c in nodes[n]["children"].as_array().into_iter().flatten() {
            stack.push((c.as_u64().unwrap() as usize, t, qmul(pq, q)));
        }
    }
    out.sort_by_key(|&(n, _)| n);
    out
}

#[test]
fn two_dancers_layout_and_fk() {
    let sk = Skeleton::smpl24();
    let j = sk.len();
    let frames = 20;
    let motions = [motion(frames, j, 0.0), motion(frames, j, 1.5)];
    let opts = GlbOptions::default();
    let bytes = glb_bytes_multi(
        &sk,
        &[dancer(&motions[0]), dancer(&motions[1])],
        30.0,
        &opts,
    )
    .unwrap();
    let (doc, bin) = parse_glb(&bytes);

    let nodes = doc["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 2 * j + 2);
    let joint_nodes: Vec<&Value> = nodes.iter().filter(|n| n.get("mesh").is_none()).collect();
    assert_eq!(joint_nodes.len(), 2 * j);
    assert_eq!(doc["skins"].as_array().unwrap().len(), 2);
    assert_eq!(doc["meshes"].as_array().unwrap().len(), 2);
    assert_eq!(doc["materials"].as_array().unwrap().len(), 2);
    assert_eq!(doc["animations"].as_array().unwrap().len(), 1);
    let channels = doc["animations"][0]["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 2 * (j + 1));
    assert_eq!(
        doc["animations"][0]["samplers"].as_array().unwrap().len(),
        2 * (j + 1)
    );
    assert_eq!(doc["scenes"][0]["nodes"], json!([0, j, j + 1, 2 * j + 1]));

    for d in 0..2 {
        let base = d * (j + 1);
        for (k, name) in sk.names().iter().enumerate() {
            assert_eq!(nodes[base + k]["name"], format!("dancer{d}/{name}"));
        }
        let body = &nodes[base + j];
        assert_eq!(body["name"], format!("dancer{d}"));
        assert_eq!(body["mesh"], d);
        assert_eq!(body["skin"], d);
        let skin = &doc["skins"][d];
        assert_eq!(skin["skeleton"], base);
        assert_eq!(skin["joints"], json!((base..base + j).collect::<Vec<_>>()));
        assert_eq!(doc["meshes"][d]["primitives"][0]["material"], d);
        // Every channel of this dancer targets its own nodes.
        let own = channels
            .iter()
            .filter(|c| {
                (base..base + j).contains(&(c["target"]["node"].as_u64().unwrap() as usize))
            })
            .count();
        assert_eq!(own, j + 1);
        assert_eq!(
            f32s(&doc, &bin, channel_output(&doc, base, "translation")),
            motions[d].1
        );
        // The hierarchy reproduces forward kinematics for this dancer.
        let fk = fk_axis_angle_f32(&sk, &motions[d].0, &motions[d].1).unwrap();
        for f in [0, frames / 2, frames - 1] {
            let world = world_positions(&doc, &bin, base, f);
            assert_eq!(world.len(), j);
            for (n, p) in world {
                let jj = n - base;
                for k in 0..3 {
                    let e = fk[(f * j + jj) * 3 + k] as f64;
                    assert!((p[k] - e).abs() < 1e-4, "dancer {d} joint {jj} frame {f}");
                }
            }
        }
    }
    // Geometry is shared, colours differ.
    let prims: Vec<&Value> = (0..2).map(|d| &doc["meshes"][d]["primitives"][0]).collect();
    assert_eq!(prims[0]["attributes"], prims[1]["attributes"]);
    assert_eq!(prims[0]["indices"], prims[1]["indices"]);
    let colour = |d: usize| doc["materials"][d]["pbrMetallicRoughness"]["baseColorFactor"].clone();
    assert_eq!(colour(0), json!(opts.base_color.map(f64::from)));
    assert_eq!(colour(1), json!(EXTRA_DANCER_COLORS[0].map(f64::from)));
    assert_ne!(colour(0), colour(1));
}

#[test]
fn colours_cycle_for_large_groups() {
    let sk = Skeleton::smpl24();
    let m = motion(2, sk.len(), 0.3);
    let n = EXTRA_DANCER_COLORS.len() + 2;
    let dancers = vec![dancer(&m); n];
    let (doc, _) =
        parse_glb(&glb_bytes_multi(&sk, &dancers, 30.0, &GlbOptions::default()).unwrap());
    let colour = |d: usize| doc["materials"][d]["pbrMetallicRoughness"]["baseColorFactor"].clone();
    assert_eq!(colour(n - 1), colour(1));
    assert_eq!(doc["skins"].as_array().unwrap().len(), n);
}

#[test]
fn input_errors() {
    let sk = Skeleton::smpl24();
    let o = GlbOptions::default();
    let a = motion(3, 24, 0.0);
    let b = motion(2, 24, 1.0);
    assert_eq!(
        glb_bytes_multi(&sk, &[dancer(&a), dancer(&b)], 30.0, &o),
        Err(GlbInputError::Scene(SceneInputError::FrameCountMismatch {
            dancer: 1,
            frames: 2,
            first: 3
        }))
    );
    let msg = SceneInputError::FrameCountMismatch {
        dancer: 1,
        frames: 2,
        first: 3,
    }
    .to_string();
    assert!(msg.contains('2') && msg.contains('3'), "{msg}");
    assert_eq!(
        glb_bytes_multi(&sk, &[], 30.0, &o),
        Err(GlbInputError::Scene(SceneInputError::NoDancers))
    );
    let bad = (a.0.clone(), vec![0.0; 6]);
    let e = glb_bytes_multi(&sk, &[dancer(&a), dancer(&bad)], 30.0, &o).unwrap_err();
    assert!(
        matches!(&e, GlbInputError::Scene(SceneInputError::Dancer { dancer: 1, reason })
            if matches!(**reason, SceneInputError::TranslationShape { .. })),
        "{e:?}"
    );
    assert!(e.to_string().starts_with("dancer 1: "), "{e}");
    // One dancer: errors are not wrapped, as from `glb_bytes`.
    assert!(matches!(
        glb_bytes_multi(&sk, &[dancer(&bad)], 30.0, &o),
        Err(GlbInputError::Scene(
            SceneInputError::TranslationShape { .. }
        ))
    ));
}

#[test]
fn single_dancer_output_unchanged() {
    let sk = Skeleton::smpl24();
    let m = motion(15, sk.len(), 0.7);
    let opts = GlbOptions {
        sides: 5,
        ..GlbOptions::default()
    };
    let one = glb_bytes(&sk, &m.0, &m.1, 30.0, &opts).unwrap();
    assert_eq!(
        one,
        glb_bytes_multi(&sk, &[dancer(&m)], 30.0, &opts).unwrap()
    );
    let (doc, _) = parse_glb(&one);
    for (k, name) in sk.names().iter().enumerate() {
        assert_eq!(doc["nodes"][k]["name"], name.as_str());
    }
    assert_eq!(doc["nodes"][sk.len()]["name"], "body");
    assert_eq!(doc["skins"][0]["name"], "skeleton");
    assert_eq!(doc["meshes"][0]["name"], "body");
    assert_eq!(doc["materials"][0]["name"], "body");
    assert_eq!(doc["scenes"][0]["nodes"], json!([0, sk.len()]));
}

#[test]
fn save_motion_file_writes_every_dancer() {
    let sk = Skeleton::smpl24();
    let (r0, t0) = motion(10, 24, 0.0);
    let (r1, t1) = motion(10, 24, 2.0);
    let g = vec![
        SmplMotion::new(30.0, r0, t0).unwrap(),
        SmplMotion::new(30.0, r1.clone(), t1.clone()).unwrap(),
    ];
    let group = LoadedMotion::Group(g.clone());
    let dir = tempfile::tempdir().unwrap();

    let all = dir.path().join("duet.glb");
    save_motion_file(&all, &group, &ConvertOptions::default()).unwrap();
    let expected = glb_bytes_multi(
        &sk,
        &[
            DancerAnimation {
                local_rotations_axis_angle: &g[0].poses,
                root_translation: &g[0].trans,
            },
            DancerAnimation {
                local_rotations_axis_angle: &g[1].poses,
                root_translation: &g[1].trans,
            },
        ],
        30.0,
        &GlbOptions::default(),
    )
    .unwrap();
    assert_eq!(std::fs::read(&all).unwrap(), expected);

    let picked = dir.path().join("follower.glb");
    let opts = ConvertOptions {
        dancer: Some(1),
        ..ConvertOptions::default()
    };
    save_motion_file(&picked, &group, &opts).unwrap();
    let expected = glb_bytes(&sk, &r1, &t1, 30.0, &GlbOptions::default()).unwrap();
    assert_eq!(std::fs::read(&picked).unwrap(), expected);

    let opts = ConvertOptions {
        dancer: Some(2),
        ..ConvertOptions::default()
    };
    let e = save_motion_file(&dir.path().join("x.glb"), &group, &opts).unwrap_err();
    assert!(
        e.reason.contains("--dancer 2") && e.reason.contains("2 dancers"),
        "{e}"
    );

    let mut slow = g.clone();
    slow[1].fps = 60.0;
    let e = save_motion_file(
        &dir.path().join("y.glb"),
        &LoadedMotion::Group(slow),
        &ConvertOptions::default(),
    )
    .unwrap_err();
    assert!(e.reason.contains("fps"), "{e}");

    // Single-person formats still need --dancer, and say which formats keep everyone.
    let e = save_motion_file(
        &dir.path().join("z.bvh"),
        &group,
        &ConvertOptions::default(),
    )
    .unwrap_err();
    assert!(
        e.reason.contains("--dancer") && e.reason.contains(".glb"),
        "{e}"
    );
}

#[test]
fn khronos_validator_accepts_duet() {
    let sk = Skeleton::smpl24();
    let motions = [motion(30, sk.len(), 0.0), motion(30, sk.len(), 1.0)];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("duet.glb");
    write_glb_multi(
        &path,
        &sk,
        &[dancer(&motions[0]), dancer(&motions[1])],
        30.0,
        &GlbOptions::default(),
    )
    .unwrap();
    let report = validate(&path);
    assert_eq!(report["issues"]["numErrors"], 0, "validation errors");
    assert_eq!(report["issues"]["numWarnings"], 0, "validation warnings");
    assert_eq!(report["info"]["animationCount"], 1);
    assert_eq!(report["info"]["hasSkins"], true);
}
