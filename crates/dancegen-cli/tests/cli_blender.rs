//! The real client: Blender, headless, imports the `.bvh`, `.glb` and `.fbx` that `generate`
//! writes for a solo dance and a duet, and with `--rig mixamo`; its bones stand where the
//! `.npy` says, frame for frame.
//!
//! Blender runs `tests/blender/import_report.py` (`blender -b --factory-startup`), which
//! reports the armatures, the frame rate, the action's frame range and every bone head in
//! world space at the first, middle and last frame. Blender is Z-up: our `(x, y, z)` (Y-up) is
//! its `(x, −z, y)`.
//!
//! Needs `blender` (Debian's `blender` + `python3-numpy`, or `DANCEGEN_BLENDER=/path`).
//! Without it the tests say so and pass, unless `DANCEGEN_REQUIRE_BLENDER=1`
//! (`tools/test.sh` sets it after installing Blender), where they fail.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{blender, dancegen, ok, shared};
use serde_json::Value;

/// Tolerances of the issue: BVH is text with 6 decimals in centimetres; GLB and FBX are
/// binary floats.
const BVH_TOLERANCE_M: f64 = 1e-4;
const BINARY_TOLERANCE_M: f64 = 1e-5;

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/blender/import_report.py")
}

/// Blender's report on `file`, at motion frames `frames`.
fn import(blender: &Path, file: &Path, frames: &[usize]) -> Value {
    let fmt = file.extension().unwrap().to_str().unwrap();
    let report = file.with_extension(format!("{fmt}.report.json"));
    let list: Vec<String> = frames.iter().map(usize::to_string).collect();
    let out = Command::new(blender)
        .args([
            "-b",
            "--factory-startup",
            "-noaudio",
            "--python-exit-code",
            "1",
        ])
        .arg("--python")
        .arg(script())
        .arg("--")
        .arg(fmt)
        .arg(file)
        .arg(&report)
        .arg(list.join(","))
        .output()
        .expect("run blender");
    assert!(
        out.status.success() && report.exists(),
        "blender could not import {}:\n{}\n{}",
        file.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap()
}

/// `(T, 24, 3)` joints of a `.npy`.
fn joints(path: &Path) -> (usize, Vec<f64>) {
    let a = dancegen_io::read_npy(path).unwrap();
    assert_eq!(&a.shape[1..], [24, 3], "{}", path.display());
    (a.shape[0], a.data)
}

/// Checks one imported file: `dancers` armature bone sets, 30 fps, T frames, and the bones
/// named `prefix + names[j]` at the `.npy`'s joint `j` in every reported frame.
fn check(
    report: &Value,
    what: &str,
    bones_expected: usize,
    prefix: &str,
    names: &[String],
    npy: &(usize, Vec<f64>),
    tolerance: f64,
) {
    let (frames, data) = npy;
    assert_eq!(report["fps"], 30.0, "{what}: scene frame rate");
    let armatures = report["armatures"].as_array().unwrap();
    let bones: usize = armatures
        .iter()
        .map(|a| a["bones"].as_array().unwrap().len())
        .sum();
    assert_eq!(bones, bones_expected, "{what}: bone count");
    let mut worst: f64 = 0.0;
    let mut seen = 0;
    for a in armatures {
        let span = a["action_last"].as_f64().unwrap() - a["action_first"].as_f64().unwrap();
        assert_eq!(
            span as usize + 1,
            *frames,
            "{what}: {} keys {span} frames apart, the dance has {frames}",
            a["name"]
        );
        for (f, heads) in a["frames"].as_object().unwrap() {
            let f: usize = f.parse().unwrap();
            let heads: HashMap<&String, &Value> = heads.as_object().unwrap().iter().collect();
            for (j, name) in names.iter().enumerate() {
                let Some(head) = heads.get(&format!("{prefix}{name}")) else {
                    continue;
                };
                seen += 1;
                let p = |k: usize| data[(f * 24 + j) * 3 + k];
                let want = [p(0), -p(2), p(1)];
                for (k, w) in want.iter().enumerate() {
                    worst = worst.max((head[k].as_f64().unwrap() - w).abs());
                }
            }
        }
    }
    assert_eq!(seen, 3 * 24, "{what}: the dancer's 24 bones at 3 frames");
    eprintln!("{what}: {bones} bones, {frames} frames, worst joint error {worst:.2e} m");
    assert!(
        worst <= tolerance,
        "{what}: joint error {worst:.2e} m > {tolerance:.0e}"
    );
}

fn smpl_names() -> Vec<String> {
    dancegen_motion::Skeleton::smpl24().names().to_vec()
}

fn frames_of(npy: &(usize, Vec<f64>)) -> [usize; 3] {
    [0, npy.0 / 2, npy.0 - 1]
}

fn song() -> String {
    shared()
        .join("data/music/sectoid/feelings.ogg")
        .display()
        .to_string()
}

fn generate(dir: &Path, stem: &str, extra: &[&str]) -> (usize, Vec<f64>) {
    let path = |ext: &str| dir.join(format!("{stem}.{ext}")).display().to_string();
    let mut args = vec!["generate".to_string(), song(), "-q".into()];
    for ext in ["glb", "bvh", "fbx", "npy"] {
        args.push("-o".into());
        args.push(path(ext));
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    ok(&dancegen(&args));
    joints(&dir.join(format!("{stem}.npy")))
}

#[test]
fn blender_imports_solo_and_duet_bvh_glb_fbx_where_the_npy_says() {
    let Some(blender) = blender() else { return };
    let dir = tempfile::tempdir().unwrap();
    let names = smpl_names();

    let solo = generate(dir.path(), "solo", &["--end", "8"]);
    let frames = frames_of(&solo);
    for (ext, tol) in [
        ("bvh", BVH_TOLERANCE_M),
        ("glb", BINARY_TOLERANCE_M),
        ("fbx", BINARY_TOLERANCE_M),
    ] {
        let r = import(&blender, &dir.path().join(format!("solo.{ext}")), &frames);
        check(&r, &format!("solo .{ext}"), 24, "", &names, &solo, tol);
    }

    // Duet: the .bvh holds the follower; .glb and .fbx hold the couple, the leader as
    // dancer 0 and the follower (the .npy) as dancer 1.
    let leader = shared().join("data/cmu-salsa/61_13_scaled.bvh");
    let duet = generate(dir.path(), "duet", &["--leader", leader.to_str().unwrap()]);
    let frames = frames_of(&duet);
    let r = import(&blender, &dir.path().join("duet.bvh"), &frames);
    check(&r, "duet .bvh", 24, "", &names, &duet, BVH_TOLERANCE_M);
    for ext in ["glb", "fbx"] {
        let r = import(&blender, &dir.path().join(format!("duet.{ext}")), &frames);
        check(
            &r,
            &format!("duet .{ext}"),
            48,
            "dancer1/",
            &names,
            &duet,
            BINARY_TOLERANCE_M,
        );
    }
}

#[test]
fn mixamo_rig_imports_with_mixamorig_names_where_the_smpl_rig_stands() {
    let Some(blender) = blender() else { return };
    let dir = tempfile::tempdir().unwrap();
    let smpl = generate(dir.path(), "smpl", &["--end", "6", "--seed", "4"]);
    let mixamo = generate(
        dir.path(),
        "mixamo",
        &["--end", "6", "--seed", "4", "--rig", "mixamo"],
    );
    assert_eq!(smpl, mixamo, "a rig renames bones; the joints do not move");
    let names = dancegen_formats::rig::Rig::Mixamo.joint_names();
    let frames = frames_of(&mixamo);
    for (ext, tol) in [
        ("bvh", BVH_TOLERANCE_M),
        ("glb", BINARY_TOLERANCE_M),
        ("fbx", BINARY_TOLERANCE_M),
    ] {
        let r = import(&blender, &dir.path().join(format!("mixamo.{ext}")), &frames);
        for a in r["armatures"].as_array().unwrap() {
            for b in a["bones"].as_array().unwrap() {
                assert!(
                    b.as_str().unwrap().starts_with("mixamorig:"),
                    ".{ext}: bone {b} is not a Mixamo bone"
                );
            }
        }
        check(&r, &format!("mixamo .{ext}"), 24, "", &names, &mixamo, tol);
    }
}

#[test]
fn blender_imports_a_character_dancing() {
    let Some(blender) = blender() else { return };
    let dir = tempfile::tempdir().unwrap();
    let robot = shared().join("data/holistic/three-js-robot-expressive/RobotExpressive.glb");
    let out = dir.path().join("robot.glb");
    let npy = dir.path().join("robot.npy");
    ok(&dancegen(&[
        "generate",
        &song(),
        "-q",
        "--end",
        "6",
        "--character",
        robot.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-o",
        npy.to_str().unwrap(),
    ]));
    let dance = joints(&npy);
    let frames = frames_of(&dance);
    let r = import(&blender, &out, &frames);
    assert_eq!(r["fps"], 30.0);
    assert!(
        !r["meshes"].as_array().unwrap().is_empty(),
        "the robot's meshes"
    );
    let arms = r["armatures"].as_array().unwrap();
    assert!(!arms.is_empty());
    for a in arms {
        let span = a["action_last"].as_f64().unwrap() - a["action_first"].as_f64().unwrap();
        assert_eq!(
            span as usize + 1,
            dance.0,
            "{}: the dance's frames",
            a["name"]
        );
        // The robot moves: its bones are elsewhere in the middle of the dance than at the start.
        let at = |f: usize| a["frames"][f.to_string()].as_object().unwrap().clone();
        let (first, middle) = (at(frames[0]), at(frames[1]));
        let moved = first
            .iter()
            .filter(|(name, p)| middle[*name] != **p)
            .count();
        assert!(
            moved > first.len() / 2,
            "{moved} of {} bones moved",
            first.len()
        );
    }
}
