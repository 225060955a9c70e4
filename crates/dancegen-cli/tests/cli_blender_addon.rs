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
//! The Dance button as a user presses it (modal: progress in the status bar, Esc cancels,
//! Blender's own timers keep running) needs Blender's window: `tests/blender/addon_modal_check.py`
//! under `xvfb-run`.

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

/// Runs `addon_check.py` for `case` in Blender's background mode; its report.
fn run(blender: &Path, dir: &Path, case: &str, song: &Path, character: Option<&Path>) -> Value {
    let mut cmd = Command::new(blender);
    cmd.arg("-b");
    run_script(cmd, "addon_check.py", dir, case, song, character)
}

/// Runs `addon_modal_check.py` for `case` in Blender with its window, on a virtual X display
/// (`xvfb-run`); its report. `None` (the test skips) without `xvfb-run`, unless
/// `DANCEGEN_REQUIRE_BLENDER=1`.
fn run_with_window(blender: &Path, dir: &Path, case: &str) -> Option<Value> {
    let found = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("xvfb-run").is_file()));
    if !found {
        assert!(
            std::env::var("DANCEGEN_REQUIRE_BLENDER").as_deref() != Ok("1"),
            "DANCEGEN_REQUIRE_BLENDER=1 but no xvfb-run on PATH (apt-get install xvfb xauth)"
        );
        eprintln!("skipped: no xvfb-run on PATH (tools/test.sh installs it)");
        return None;
    }
    let mut cmd = Command::new("xvfb-run");
    cmd.arg("-a").arg(blender).arg("--enable-event-simulate");
    Some(run_script(
        cmd,
        "addon_modal_check.py",
        dir,
        case,
        &shared().join("data/music/sectoid/feelings.ogg"),
        None,
    ))
}

/// Runs Blender (`cmd`, its mode chosen) with `tests/blender/SCRIPT` for `case`; its report.
fn run_script(
    mut cmd: Command,
    script: &str,
    dir: &Path,
    case: &str,
    song: &Path,
    character: Option<&Path>,
) -> Value {
    let zip = addon_zip(dir);
    let out_dir = dir.join(format!("{case}-files"));
    let report = dir.join(format!("{case}.json"));
    cmd.args(["--factory-startup", "-noaudio", "--python-exit-code", "1"])
        .arg("--python")
        .arg(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/blender")
                .join(script),
        )
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

#[test]
fn the_dance_button_works_in_the_background_shows_progress_and_esc_cancels() {
    let Some(blender) = blender() else { return };
    let dir = tempfile::tempdir().unwrap();
    let Some(r) = run_with_window(&blender, dir.path(), "finish") else {
        return;
    };
    assert_eq!(r["error"], Value::Null, "{r}");
    assert_eq!(r["invoke"], serde_json::json!(["RUNNING_MODAL"]), "{r}");
    // Blender's own 0.1 s timer kept firing while the binary worked: the UI was not blocked.
    let ticks = r["ticks_while_running"].as_u64().unwrap();
    assert!(ticks >= 5, "{ticks} ticks while the dance was made: {r}");
    // The status bar followed the binary's progress, in words, up to 100 %.
    let status = r["status"].as_array().unwrap();
    let fractions: Vec<f64> = status.iter().map(|s| s[0].as_f64().unwrap()).collect();
    assert!(status.len() >= 3, "{r}");
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]), "{fractions:?}");
    assert_eq!(fractions.last(), Some(&1.0), "{r}");
    assert!(
        status
            .iter()
            .all(|s| s[1].as_str().unwrap().starts_with("dancegen: "))
    );
    assert_eq!(r["armatures"].as_array().unwrap().len(), 1, "{r}");
    assert_eq!(r["binary_exit_code"], 0, "{r}");

    // Esc once the progress has started: the binary is stopped and nothing comes in.
    let r = run_with_window(&blender, dir.path(), "cancel").unwrap();
    assert_eq!(r["error"], Value::Null, "{r}");
    assert!(r["esc_at_fraction"].as_f64().unwrap() < 1.0, "{r}");
    assert_eq!(r["binary_running_at_end"], false, "{r}");
    assert_ne!(
        r["binary_exit_code"], 0,
        "the binary was stopped, not finished: {r}"
    );
    assert_eq!(r["armatures"], serde_json::json!([]), "{r}");
    assert_eq!(
        r["files"],
        serde_json::json!([]),
        "a cancelled dance leaves no file: {r}"
    );
}
