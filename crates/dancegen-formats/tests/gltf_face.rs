//! A `.glb` with fingers and a face: SMPL-H 52 bones and a head whose 52 ARKit morph targets
//! play a `weights` animation, checked by structure and by the Khronos glTF-Validator.

mod common;

use common::gltf_validator::validate;
use dancegen_formats::gltf::{
    DancerAnimation, FaceAnimation, GlbInputError, GlbOptions, glb_bytes_with_face,
    write_glb_with_face,
};
use dancegen_motion::face::{ARKIT_COUNT, ARKIT_NAMES, FaceWeights};
use dancegen_motion::skeleton::Skeleton;
use serde_json::Value;

/// SMPL-H head joint.
const HEAD: usize = 15;

fn motion(frames: usize) -> (Vec<f32>, Vec<f32>, FaceWeights) {
    let j = 52;
    let mut rot = vec![0.0f32; frames * j * 3];
    for f in 0..frames {
        let s = (f as f32 * 0.2).sin();
        rot[(f * j + 16) * 3 + 2] = -1.2 + 0.3 * s; // left shoulder down
        rot[(f * j + 17) * 3 + 2] = 1.2 - 0.3 * s;
        for k in 22..52 {
            // Finger curl about z, mirrored for the right hand.
            let side = if k < 37 { -1.0 } else { 1.0 };
            rot[(f * j + k) * 3 + 2] = side * (0.4 + 0.4 * (f as f32 * 0.3 + k as f32).sin());
        }
    }
    let trans: Vec<f32> = (0..frames)
        .flat_map(|f| [0.01 * f as f32, 0.9, 0.0])
        .collect();
    let w = (0..frames * ARKIT_COUNT)
        .map(|i| 0.5 + 0.5 * ((i / ARKIT_COUNT) as f32 * 0.3 + (i % ARKIT_COUNT) as f32).sin())
        .collect();
    (rot, trans, FaceWeights::new(w, 30.0).unwrap())
}

fn json_chunk(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

#[test]
fn face_and_fingers_glb_structure_and_validator() {
    let sk = Skeleton::smplh52_approx();
    let frames = 40;
    let (rot, trans, face) = motion(frames);
    let dancer = DancerAnimation {
        local_rotations_axis_angle: &rot,
        root_translation: &trans,
    };
    let fa = FaceAnimation {
        weights: &face,
        head_joint: HEAD,
    };
    let bytes = glb_bytes_with_face(&sk, dancer, fa, 30.0, &GlbOptions::default()).unwrap();
    let doc = json_chunk(&bytes);
    // Finger bones are nodes of the skin.
    let names: Vec<&str> = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["name"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"left_index1") && names.contains(&"right_thumb3"),
        "{names:?}"
    );
    assert_eq!(doc["skins"][0]["joints"].as_array().unwrap().len(), 52);
    // The face: a child of the head, 52 named targets, a weights channel of 52 per key.
    let face_node = names.iter().position(|&n| n == "face").unwrap();
    let head_children = doc["nodes"][HEAD]["children"].as_array().unwrap();
    assert!(head_children.contains(&Value::from(face_node)));
    let mesh = &doc["meshes"][doc["nodes"][face_node]["mesh"].as_u64().unwrap() as usize];
    assert_eq!(
        mesh["primitives"][0]["targets"].as_array().unwrap().len(),
        52
    );
    let target_names: Vec<&str> = mesh["extras"]["targetNames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(target_names, ARKIT_NAMES);
    let anim = &doc["animations"][0];
    let ch = anim["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["path"] == "weights")
        .unwrap();
    assert_eq!(ch["target"]["node"], face_node);
    let out = anim["samplers"][ch["sampler"].as_u64().unwrap() as usize]["output"]
        .as_u64()
        .unwrap() as usize;
    assert_eq!(doc["accessors"][out]["count"], frames * 52);
    // Written to a file, the validator finds no errors.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("holistic.glb");
    write_glb_with_face(&path, &sk, dancer, fa, 30.0, &GlbOptions::default()).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    let report = validate(&path);
    eprintln!(
        "validator: {} warnings, {} infos",
        report["issues"]["numWarnings"], report["issues"]["numInfos"]
    );
    assert_eq!(report["issues"]["numErrors"], 0, "{report}");
    assert_eq!(report["info"]["animationCount"], 1);
    assert_eq!(report["info"]["hasMorphTargets"], true);
}

#[test]
fn a_face_of_the_wrong_length_or_joint_is_refused() {
    let sk = Skeleton::smplh52_approx();
    let (rot, trans, _) = motion(10);
    let (_, _, face) = motion(12);
    let dancer = DancerAnimation {
        local_rotations_axis_angle: &rot,
        root_translation: &trans,
    };
    let e = glb_bytes_with_face(
        &sk,
        dancer,
        FaceAnimation {
            weights: &face,
            head_joint: HEAD,
        },
        30.0,
        &GlbOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, GlbInputError::Face(_)) && e.to_string().contains("12 frames"),
        "{e}"
    );
    let (_, _, face) = motion(10);
    let e = glb_bytes_with_face(
        &sk,
        dancer,
        FaceAnimation {
            weights: &face,
            head_joint: 60,
        },
        30.0,
        &GlbOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("head joint 60"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.glb");
    assert!(
        write_glb_with_face(
            &path,
            &sk,
            dancer,
            FaceAnimation {
                weights: &face,
                head_joint: 60
            },
            30.0,
            &GlbOptions::default()
        )
        .is_err()
    );
    assert!(!path.exists(), "nothing written on error");
}

fn blender() -> Option<std::path::PathBuf> {
    let found = std::env::var_os("DANCEGEN_BLENDER")
        .map(std::path::PathBuf::from)
        .or_else(|| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|d| d.join("blender"))
                    .find(|p| p.is_file())
            })
        });
    if found.is_none() {
        assert!(
            std::env::var("DANCEGEN_REQUIRE_BLENDER").as_deref() != Ok("1"),
            "DANCEGEN_REQUIRE_BLENDER=1 but no blender on PATH"
        );
        eprintln!("skipped: no blender on PATH (tools/test.sh installs it)");
    }
    found
}

/// Blender imports the face as 52 shape keys named after ARKit, animated frame for frame with
/// the weights we wrote.
#[test]
fn blender_imports_the_face_as_arkit_shape_keys() {
    let Some(blender) = blender() else { return };
    let sk = Skeleton::smplh52_approx();
    let frames = 30;
    let (rot, trans, face) = motion(frames);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("face.glb");
    write_glb_with_face(
        &path,
        &sk,
        DancerAnimation {
            local_rotations_axis_angle: &rot,
            root_translation: &trans,
        },
        FaceAnimation {
            weights: &face,
            head_joint: HEAD,
        },
        30.0,
        &GlbOptions::default(),
    )
    .unwrap();
    let report = dir.path().join("face.json");
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/face_report.py");
    let out = std::process::Command::new(&blender)
        .args([
            "-b",
            "--factory-startup",
            "-noaudio",
            "--python-exit-code",
            "1",
            "--python",
        ])
        .arg(&script)
        .arg("--")
        .arg(&path)
        .arg(&report)
        .arg("0,7,29")
        .output()
        .expect("run blender");
    assert!(
        out.status.success() && report.exists(),
        "blender could not import the face:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    eprintln!(
        "blender: object {}, parent bone {}, {} animated keys",
        r["object"], r["parent_bone"], r["animated_keys"]
    );
    let names: Vec<&str> = r["shape_keys"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(names, ARKIT_NAMES, "shape keys named after ARKit, in order");
    assert_eq!(r["animated_keys"], 52);
    let mut worst = 0.0f64;
    for f in [0usize, 7, 29] {
        let got = r["values"][f.to_string()].as_array().unwrap();
        for (k, v) in got.iter().enumerate() {
            worst = worst.max((v.as_f64().unwrap() - face.frame(f)[k] as f64).abs());
        }
    }
    eprintln!("blender shape key values vs written weights: max error {worst:.1e}");
    assert!(worst < 1e-4, "{worst}");
}
