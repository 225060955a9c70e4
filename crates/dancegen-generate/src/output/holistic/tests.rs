//! A synthetic holistic dance (a swaying body, curling fingers, a changing face) written to
//! every format through `write_all`, and each file read back.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use dancegen_formats::bvh::{BvhReadOptions, read_bvh};
use dancegen_formats::bvh_motion::bvh_world_positions;
use dancegen_formats::livelink_csv;
use dancegen_formats::rig::Rig;
use dancegen_formats::smpl_npz::{SmplNpzOptions, read_smpl_npz};
use dancegen_motion::face::{ARKIT_COUNT, ARKIT_NAMES, FaceWeights};
use dancegen_motion::repr::motion::SmplMotion;
use dancegen_motion::skeleton::{SMPLH52_NAMES, Skeleton};
use dancegen_music::FrameMatrix;
use dancegen_music::decode::AudioSource;
use dancegen_music::features::{MusicFeatures, StartBpm};
use serde_json::Value;

use super::{HEAD, bone_names};
use crate::error::GenerateError;
use crate::output::{plan, write_all};
use crate::progress::{CancelToken, Progress, Tracker, stage};
use crate::request::OutputRequest;
use crate::song::{AnalysedSong, Span};
use crate::system::{Dance, Dancer, HolisticParts, Role};

const T: usize = 40;
const J: usize = 52;

/// SMPL-H poses, pelvis, face of the synthetic dance.
fn parts() -> HolisticParts {
    let mut poses = vec![0.0f32; T * J * 3];
    for f in 0..T {
        let t = f as f32;
        let row = &mut poses[f * J * 3..(f + 1) * J * 3];
        row[1] = 0.4 * (0.1 * t).sin(); // the root turns about Y
        for j in 1..22 {
            let k = j as f32;
            row[j * 3] = 0.15 * (0.2 * t + k).sin();
            row[j * 3 + 1] = 0.1 * (0.3 * t + 2.0 * k).cos();
            row[j * 3 + 2] = 0.12 * (0.1 * t + 0.5 * k).sin();
        }
        for j in 22..J {
            // Finger curl about z (left hand down, right hand mirrored), changing over time.
            let side = if j < 37 { -1.0 } else { 1.0 };
            row[j * 3 + 2] = side * (0.5 + 0.45 * (0.25 * t + j as f32).sin());
        }
    }
    let trans = (0..T)
        .flat_map(|f| {
            let t = f as f32;
            [0.01 * t, 0.95 + 0.02 * (0.5 * t).sin(), -0.005 * t]
        })
        .collect();
    let weights = (0..T * ARKIT_COUNT)
        .map(|i| {
            let (f, k) = ((i / ARKIT_COUNT) as f32, (i % ARKIT_COUNT) as f32);
            (0.5 + 0.5 * (0.3 * f + 1.7 * k).sin()).clamp(0.0, 1.0)
        })
        .collect();
    HolisticParts {
        poses,
        trans,
        skeleton: Skeleton::smplh52_approx(),
        face: FaceWeights::new(weights, 30.0).expect("weights in [0, 1]"),
        flame: None,
    }
}

/// The SMPL 24 body of `parts`: joints 0–21 as SMPL-H's, the hands (22, 23) at rest.
fn body_of(parts: &HolisticParts) -> SmplMotion {
    let mut poses = vec![0.0f32; T * 72];
    for f in 0..T {
        poses[f * 72..f * 72 + 66].copy_from_slice(&parts.poses[f * J * 3..f * J * 3 + 66]);
    }
    SmplMotion::new(30.0, poses, parts.trans.clone()).unwrap()
}

fn dance(holistic: bool) -> Dance {
    let parts = parts();
    Dance {
        dancers: vec![Dancer {
            role: Role::Solo,
            motion: body_of(&parts),
        }],
        span: Span {
            start_s: 0.0,
            end_s: T as f64 / 30.0,
            first_frame: 0,
            end_frame: T,
        },
        summary: String::new(),
        timing_breakdown: String::new(),
        notes: Vec::new(),
        group: None,
        holistic: holistic.then_some(parts),
    }
}

/// A song that is never decoded (only `.mp4` reads it).
fn record() -> crate::record::DanceRecord {
    crate::record::DanceRecord {
        song: "silence.wav".into(),
        start_s: 0.0,
        end_s: 1.0,
        system: "holistic".into(),
        model: "soulnet-small".into(),
        seed: 0,
        dancers: 1,
        dancer: 0,
        fps: 30,
        version: "test".into(),
    }
}

fn song() -> AnalysedSong {
    AnalysedSong {
        source: AudioSource::Bytes {
            name: PathBuf::from("silence.wav"),
            bytes: Arc::from(Vec::new()),
        },
        label: "silence.wav".into(),
        features: MusicFeatures {
            fps: 30,
            start_bpm: StartBpm::Given(120.0),
            tempo_bpm: 120.0,
            beat_frames: Vec::new(),
            onset_frames: Vec::new(),
            features: FrameMatrix::zeros(0, 35),
        },
    }
}

/// Plans and writes `outputs` of `dance` as a job does.
fn write(dance: &Dance, outputs: Vec<OutputRequest>) -> Result<Vec<PathBuf>, GenerateError> {
    let planned = plan(&outputs, dance.holistic.is_some())?;
    let cancel = CancelToken::new();
    let cb = |_: &Progress| {};
    let tracker = Tracker::new(vec![(stage::WRITE_OUTPUTS, 1.0)], &cb, &cancel);
    write_all(&planned, dance, &song(), &record(), &tracker)
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The JSON chunk of a `.glb`.
fn glb_json(bytes: &[u8]) -> Value {
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(&bytes[16..20], b"JSON");
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

#[test]
fn finger_names_follow_smplh_order_and_the_face_rides_on_the_head() {
    let names = bone_names(Rig::Smpl);
    assert_eq!(names.len(), 52);
    assert_eq!(&names[..3], ["root", "lhip", "rhip"]);
    assert_eq!(names[21], "rwrist");
    for (i, finger) in ["index", "middle", "pinky", "ring", "thumb"]
        .iter()
        .enumerate()
    {
        for k in 1..=3 {
            assert_eq!(names[22 + i * 3 + k - 1], format!("left_{finger}{k}"));
            assert_eq!(names[37 + i * 3 + k - 1], format!("right_{finger}{k}"));
        }
    }
    assert_eq!(SMPLH52_NAMES[HEAD], "head");
    let mixamo = bone_names(Rig::Mixamo);
    assert_eq!(mixamo[0], "mixamorig:Hips");
    assert_eq!(mixamo[22], "left_index1");
}

#[test]
fn holistic_files_hold_body_fingers_and_face() {
    let dir = tempfile::tempdir().unwrap();
    let d = dance(true);
    let parts = d.holistic.as_ref().unwrap();
    let path = |ext: &str| dir.path().join(format!("dance.{ext}"));
    let exts = ["npy", "json", "csv", "bvh", "glb", "npz", "fbx"];
    let written = write(
        &d,
        exts.iter().map(|e| OutputRequest::new(path(e))).collect(),
    )
    .unwrap();
    assert_eq!(written.len(), exts.len());
    let mut want: Vec<String> = exts.iter().map(|e| format!("dance.{e}")).collect();
    want.sort();
    assert_eq!(entries(dir.path()), want, "the files and no staging folder");

    // .npy: (T, 52, 3); the body is the SMPL 24 body's FK; the fingers move.
    let npy = dancegen_io::read_npy(&path("npy")).unwrap();
    assert_eq!(npy.shape, vec![T, 52, 3]);
    assert_eq!(npy.dtype, "<f4");
    let body = d.dancers[0].motion.joints_world().unwrap();
    let mut worst = 0.0f64;
    for f in 0..T {
        for j in 0..22 {
            for a in 0..3 {
                let got = npy.data[(f * 52 + j) * 3 + a];
                worst = worst.max((got - f64::from(body[(f * 24 + j) * 3 + a])).abs());
            }
        }
    }
    assert!(
        worst < 1e-5,
        "body joints differ from SMPL 24 FK by {worst} m"
    );
    let at = |f: usize, j: usize| -> [f64; 3] {
        let o = (f * 52 + j) * 3;
        [npy.data[o], npy.data[o + 1], npy.data[o + 2]]
    };
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    // left_index3 (24) to the left wrist (20): changes only if the finger curls.
    let reach: Vec<f64> = (0..T).map(|f| dist(at(f, 24), at(f, 20))).collect();
    let span = reach.iter().cloned().fold(f64::MIN, f64::max)
        - reach.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 0.002, "the index finger does not curl: {span} m");

    // .json: 52 joints, the face with camelCase ARKit names and the weights given.
    let json: Value = serde_json::from_slice(&std::fs::read(path("json")).unwrap()).unwrap();
    let names = json["joint_names"].as_array().unwrap();
    assert_eq!(names.len(), 52);
    assert_eq!(names[22], "left_index1");
    assert_eq!(json["parents"].as_array().unwrap().len(), 52);
    assert_eq!(json["shape"], serde_json::json!([T, 52, 3]));
    let positions = json["positions"].as_array().unwrap();
    assert_eq!(positions.len(), T * 52 * 3);
    assert!(
        positions
            .iter()
            .zip(&npy.data)
            .all(|(a, &b)| a.as_f64().unwrap() as f32 == b as f32)
    );
    let face_names: Vec<&str> = json["face"]["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(face_names, ARKIT_NAMES);
    assert_eq!(face_names[0], "eyeBlinkLeft");
    assert!(
        face_names
            .iter()
            .all(|n| n.starts_with(|c: char| c.is_ascii_lowercase()))
    );
    let rows = json["face"]["weights"].as_array().unwrap();
    assert_eq!(rows.len(), T);
    for (f, row) in rows.iter().enumerate() {
        let row: Vec<f32> = row
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        assert_eq!(row, parts.face.frame(f), "frame {f}");
    }

    // .csv: Live Link Face, the same weights to its six decimals.
    let csv = livelink_csv::read_file(&path("csv"), 30.0).unwrap();
    assert_eq!(csv.frames(), T);
    let err = csv
        .as_slice()
        .iter()
        .zip(parts.face.as_slice())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(err <= 1e-6, "{err}");

    // .bvh: 52 joints, fingers by SMPL-X name, in the places the .npy has them.
    let bvh = read_bvh(path("bvh"), &BvhReadOptions::default()).unwrap();
    assert_eq!(bvh.joints.len(), 52);
    assert!(bvh.joint_index("left_index1").is_some() && bvh.joint_index("right_thumb3").is_some());
    assert!(bvh.joint_index("root").is_some() && bvh.joint_index("lwrist").is_some());
    let (frames, nj, pos) = bvh_world_positions(&bvh, 0.01).unwrap();
    assert_eq!((frames, nj), (T, 52));
    let mut worst = 0.0f64;
    for (j, name) in bone_names(Rig::Smpl).iter().enumerate() {
        let b = bvh.joint_index(name).unwrap();
        for f in 0..T {
            for a in 0..3 {
                let d = pos[(f * 52 + b) * 3 + a] - npy.data[(f * 52 + j) * 3 + a];
                worst = worst.max(d.abs());
            }
        }
    }
    assert!(worst < 1e-4, "BVH joints differ from the .npy by {worst} m");

    // .glb: 52 bones in the skin and 52 ARKit morph targets on the head.
    let doc = glb_json(&std::fs::read(path("glb")).unwrap());
    assert_eq!(doc["skins"][0]["joints"].as_array().unwrap().len(), 52);
    let targets: Vec<Vec<&str>> = doc["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|m| m["extras"]["targetNames"].as_array())
        .map(|n| n.iter().map(|v| v.as_str().unwrap()).collect())
        .collect();
    assert_eq!(targets, vec![ARKIT_NAMES.to_vec()]);
    let node_names: Vec<&str> = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n["name"].as_str())
        .collect();
    assert!(node_names.contains(&"left_index1") && node_names.contains(&"right_thumb3"));

    // .npz: AMASS SMPL-H, whose body reads back as the dance's.
    let members =
        dancegen_io::npz::read_npz_members(&path("npz"), &["poses", "trans", "mocap_framerate"])
            .unwrap();
    let shape = |k: &str| &members.iter().find(|(n, _)| n == k).unwrap().1.shape;
    assert_eq!(shape("poses"), &vec![T, 156]);
    assert_eq!(shape("trans"), &vec![T, 3]);
    let npz = read_smpl_npz(&path("npz"), &SmplNpzOptions::default()).unwrap();
    assert_eq!((npz.source_joints, npz.motion.fps), (52, 30.0));
    let back = npz.motion.joints_world().unwrap();
    let worst = back
        .iter()
        .zip(&body)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "npz body differs by {worst} m");

    // .fbx: the finger bones are in it.
    let fbx = std::fs::read(path("fbx")).unwrap();
    assert!(fbx.starts_with(b"Kaydara FBX Binary"));
    assert!(fbx.windows(12).any(|w| w == b"right_thumb3"));
}

#[test]
fn rig_names_the_body_and_keeps_the_finger_names() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.bvh");
    let mut r = OutputRequest::new(&out);
    r.rig = Rig::Mixamo;
    write(&dance(true), vec![r]).unwrap();
    let bvh = read_bvh(&out, &BvhReadOptions::default()).unwrap();
    assert_eq!(bvh.joints.len(), 52);
    assert_eq!(bvh.joints[0].name, "mixamorig:Hips");
    assert!(bvh.joint_index("mixamorig:LeftHand").is_some());
    assert!(bvh.joint_index("left_pinky2").is_some());
    assert!(bvh.joint_index("lwrist").is_none());
}

#[test]
fn a_csv_of_a_dance_without_a_face_fails_before_any_file() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("face.csv");
    // Planned for a system with a face, written for a dance without one.
    let outputs = vec![
        OutputRequest::new(dir.path().join("a.npy")),
        OutputRequest::new(&csv),
    ];
    let planned = plan(&outputs, true).unwrap();
    let cancel = CancelToken::new();
    let cb = |_: &Progress| {};
    let tracker = Tracker::new(vec![(stage::WRITE_OUTPUTS, 1.0)], &cb, &cancel);
    let e = write_all(&planned, &dance(false), &song(), &record(), &tracker).unwrap_err();
    let text = e.to_string();
    assert!(
        matches!(&e, GenerateError::Output { path, .. } if *path == csv),
        "{e:?}"
    );
    assert!(
        text.contains(&csv.display().to_string()) && text.contains("--system holistic"),
        "{text}"
    );
    assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
    // A system without a face is refused at planning.
    let e = plan(&outputs, false).err().unwrap().to_string();
    assert!(e.contains("face.csv") && e.contains("holistic"), "{e}");
}

#[test]
fn inconsistent_parts_name_the_file_and_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut d = dance(true);
    let out = dir.path().join("x.npy");
    if let Some(p) = d.holistic.as_mut() {
        p.face = FaceWeights::new(vec![0.5; (T - 1) * ARKIT_COUNT], 30.0).unwrap();
    }
    let e = write(&d, vec![OutputRequest::new(&out)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("x.npy") && e.contains("the face 39"), "{e}");
    assert!(entries(dir.path()).is_empty());
    let mut d = dance(true);
    if let Some(p) = d.holistic.as_mut() {
        p.poses[7 * 156 + 100] = f32::NAN;
    }
    let e = write(&d, vec![OutputRequest::new(&out)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("frame 7 joint 33"), "{e}");
    let mut d = dance(true);
    if let Some(p) = d.holistic.as_mut() {
        p.skeleton = Skeleton::smpl24();
    }
    let e = write(&d, vec![OutputRequest::new(&out)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("24 joints"), "{e}");
}
