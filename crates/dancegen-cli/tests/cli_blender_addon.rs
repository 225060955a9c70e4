//! The Blender add-on (`integrations/blender/dancegen_blender`), in Debian's Blender headless:
//! installed from the zip `integrations/blender/build_zip.py` makes, its Dance operator run on
//! a real song with this build's `dancegen`, and what came into the scene checked against the
//! dance's own `.npy`: one armature with its action, at the scene's 24 fps, the frame range,
//! the song in the sequencer in sync, and every joint within 1e-4 m at each whole second. Then
//! the dance on a character (the three.js robot, selected as an armature: its own armature
//! dances, the copy `--character` made is baked onto it and removed), and a song that is not
//! audio, reported in words.
//!
//! Blender runs `tests/blender/addon_check.py`. Needs `blender` as `cli_blender.rs` does.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{blender, shared};
use serde_json::Value;

const TOLERANCE_M: f64 = 1e-4;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The add-on's zip, made by its script.
fn addon_zip(dir: &Path) -> PathBuf {
    let zip = dir.join("dancegen_blender.zip");
    let out = Command::new("python3")
        .arg(repo().join("integrations/blender/build_zip.py"))
        .arg(&zip)
        .output()
        .expect("run python3");
    assert!(
        out.status.success() && zip.is_file(),
        "build_zip.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    zip
}

/// Runs `addon_check.py` for `case`; its report.
fn run(blender: &Path, dir: &Path, case: &str, song: &Path, character: Option<&Path>) -> Value {
    let zip = addon_zip(dir);
    let out_dir = dir.join(format!("{case}-files"));
    let report = dir.join(format!("{case}.json"));
    let mut cmd = Command::new(blender);
    cmd.args([
        "-b",
        "--factory-startup",
        "-noaudio",
        "--python-exit-code",
        "1",
    ])
    .arg("--python")
    .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/addon_check.py"))
    .arg("--")
    .arg(&zip)
    .arg(env!("CARGO_BIN_EXE_dancegen"))
    .arg(&out_dir)
    .arg(&report)
    .arg(case)
    .arg(song);
    if let Some(c) = character {
        cmd.arg(c);
    }
    // The add-on installs into this folder, not the user's; the binary it runs finds this
    // checkout's models, never a user's installed ones (as `common::dancegen`).
    let out = cmd
        .env("BLENDER_USER_SCRIPTS", dir.join("blender-scripts"))
        .env("BLENDER_USER_CONFIG", dir.join("blender-config"))
        .env_remove("DANCEGEN_MODEL_DIR")
        .env(
            "XDG_DATA_HOME",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-installed-models"),
        )
        .output()
        .expect("run blender");
    assert!(
        out.status.success() && report.is_file(),
        "blender ({case}):\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap()
}

fn song() -> PathBuf {
    shared().join("data/music/sectoid/feelings.ogg")
}

#[test]
fn the_addon_brings_a_dance_in_with_its_song() {
    let Some(blender) = blender() else { return };
    let dir = tempfile::tempdir().unwrap();
    let r = run(&blender, dir.path(), "solo", &song(), None);
    assert_eq!(r["error"], Value::Null, "{r}");
    assert_eq!(r["fps"], 24.0, "the scene's rate is kept: {r}");
    let armatures = r["armatures"].as_array().unwrap();
    assert_eq!(armatures.len(), 1, "one armature per dancer: {r}");
    let a = &armatures[0];
    // 4 s (start 2, end 6) at the scene's 24 fps, from frame 1.
    assert_eq!(a["action_first"], 1.0, "{a}");
    let last = a["action_last"].as_f64().unwrap();
    let npy = dancegen_io::read_npy(&Path::new(r["last_dir"].as_str().unwrap()).join("dance.npy"))
        .unwrap();
    assert_eq!(&npy.shape[1..], [24, 3]);
    let frames = npy.shape[0];
    assert_eq!(frames, 120, "4 s at 30 fps");
    let want_last = 1.0 + (frames - 1) as f64 * 24.0 / 30.0;
    assert!(
        (last - want_last).abs() < 1e-3,
        "last key {last}, want {want_last}"
    );
    assert_eq!(
        (r["frame_start"].as_u64(), r["frame_end"].as_u64()),
        (Some(1), Some(want_last.ceil() as u64)),
        "the scene's frame range: {r}"
    );
    // The song from its second 2 at frame 1.
    let sounds = r["sounds"].as_array().unwrap();
    assert_eq!(sounds.len(), 1, "{r}");
    let s = &sounds[0];
    assert_eq!(
        Path::new(s["path"].as_str().unwrap())
            .canonicalize()
            .unwrap(),
        song().canonicalize().unwrap()
    );
    assert_eq!(s["frame_final_start"].as_f64(), Some(1.0), "{s}");
    assert_eq!(s["frame_start"].as_f64(), Some(1.0 - 48.0), "{s}");
    // Every joint where the .npy has it, at each whole second (Blender is Z-up).
    let names = dancegen_motion::Skeleton::smpl24().names().to_vec();
    let heads = a["heads"].as_object().unwrap();
    assert_eq!(heads.len(), 4, "seconds 0-3: {}", heads.len());
    let mut worst: f64 = 0.0;
    for (t, bones) in heads {
        let f = t.parse::<usize>().unwrap() * 30;
        let bones: HashMap<&String, &Value> = bones.as_object().unwrap().iter().collect();
        for (j, name) in names.iter().enumerate() {
            let head = bones.get(name).unwrap_or_else(|| panic!("no bone {name}"));
            let p = |k: usize| npy.data[(f * 24 + j) * 3 + k];
            for (k, w) in [p(0), -p(2), p(1)].iter().enumerate() {
                worst = worst.max((head[k].as_f64().unwrap() - w).abs());
            }
        }
    }
    eprintln!("add-on solo: worst joint error {worst:.2e} m over 4 seconds");
    assert!(worst <= TOLERANCE_M, "joint error {worst:.2e} m");
}

#[test]
fn the_addon_dances_on_the_selected_armature_and_says_what_went_wrong() {
    let Some(blender) = blender() else { return };
    let dir = tempfile::tempdir().unwrap();
    let robot = shared().join("data/holistic/three-js-robot-expressive/RobotExpressive.glb");
    let r = run(&blender, dir.path(), "character", &song(), Some(&robot));
    assert_eq!(r["error"], Value::Null, "{r}");
    let armatures = r["armatures"].as_array().unwrap();
    assert_eq!(armatures.len(), 1, "{r}");
    let a = &armatures[0];
    let bones: Vec<&str> = a["bones"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b.as_str().unwrap())
        .collect();
    for bone in ["Head", "Hips", "UpperArm.L", "LowerLeg.R"] {
        assert!(bones.contains(&bone), "the robot's bone {bone}: {bones:?}");
    }
    assert_eq!(a["action_first"], 1.0, "{a}");
    assert_eq!(a["action"], "dancegen dance", "{a}");
    // The user's own robot dances: the scene holds what it held, and the dancing copy
    // dancegen made is gone.
    assert_eq!(r["objects_after"], r["objects_before"], "{r}");
    // The robot moves: its head at 0 s and 3 s (measured 1.06 m apart; a robot left in its
    // rest pose, the action not applied, would not move at all).
    let head = |t: &str| a["heads"][t]["Head"].as_array().unwrap().clone();
    let moved = (0..3)
        .map(|k| (head("0")[k].as_f64().unwrap() - head("3")[k].as_f64().unwrap()).powi(2))
        .sum::<f64>()
        .sqrt();
    eprintln!("add-on character: the robot's head moved {moved:.3} m from 0 s to 3 s");
    assert!(moved > 0.1, "the robot's head moved {moved} m");

    let notes = dir.path().join("notes.mp3");
    std::fs::write(&notes, "not a song\n").unwrap();
    let r = run(&blender, dir.path(), "bad_song", &notes, None);
    let e = r["error"]
        .as_str()
        .unwrap_or_else(|| panic!("no error: {r}"));
    assert!(e.contains("notes.mp3"), "names the file: {e}");
    assert_eq!(r["armatures"], serde_json::json!([]), "{r}");
    assert!(
        r["last_error"].as_str().unwrap().contains("notes.mp3"),
        "{r}"
    );
}
