//! Motion that is not one body is refused by every command that reads motion (`convert`,
//! `eval`, `render`, `generate --leader` and `--edit`), with the file, the frame and the joint
//! named, and no output written: a joint 1e30 m away, and joints of two bodies in one file.

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// A real take's world joints `(600, 24, 3)`, metres, Y-up (AIST++ through EDGE's FK).
fn real_joints() -> (Vec<usize>, Vec<f32>) {
    let a = dancegen_io::read_npy(&shared().join("fixtures/metrics/inputs/real/R3_yup_30fps.npy"))
        .unwrap();
    (a.shape, a.data.iter().map(|&v| v as f32).collect())
}

/// The real take with its left wrist (joint 20) 1e30 m up in frame 40.
fn far_wrist(dir: &Path) -> PathBuf {
    let (shape, mut p) = real_joints();
    p[(40 * 24 + 20) * 3 + 1] = 1e30;
    let path = dir.join("far.npy");
    dancegen_io::write_npy_f32(&path, &shape, &p).unwrap();
    path
}

/// The real take with the upper body of every other frame 2 m to the side: two bodies.
fn two_bodies(dir: &Path) -> PathBuf {
    let (shape, mut p) = real_joints();
    for f in (0..shape[0]).step_by(2) {
        for j in [12, 15, 16, 17, 18, 19, 20, 21, 22, 23] {
            p[(f * 24 + j) * 3] += 2.0;
        }
    }
    let path = dir.join("two_bodies.npy");
    dancegen_io::write_npy_f32(&path, &shape, &p).unwrap();
    path
}

fn refused(args: &[&str], out: &Path) -> String {
    let o = dancegen(args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!out.exists(), "a refused input leaves no output");
    stderr(&o)
}

#[test]
fn convert_render_and_eval_refuse_motion_that_is_not_one_body() {
    let dir = tempfile::tempdir().unwrap();
    let far = far_wrist(dir.path());
    let two = two_bodies(dir.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();

    let out = dir.path().join("out.npy");
    let e = refused(&["convert", &s(&far), "-o", &s(&out)], &out);
    assert!(
        e.contains("far.npy: frame 40, joint 20 (lwrist): is 1.0000e30 m from the origin"),
        "{e}"
    );
    let e = refused(&["convert", &s(&two), "-o", &s(&out)], &out);
    assert!(
        e.contains("two_bodies.npy: frame 0, joint 12 (neck)") && e.contains("not one body"),
        "{e}"
    );

    let png = dir.path().join("frame.png");
    let e = refused(&["render", &s(&far), "-o", &s(&png)], &png);
    assert!(e.contains("far.npy: frame 40, joint 20"), "{e}");

    // eval reads `.npy` joints itself, and checks them the same way.
    let pred = dir.path().join("pred");
    std::fs::create_dir(&pred).unwrap();
    std::fs::copy(&two, pred.join("two_bodies.npy")).unwrap();
    let json = dir.path().join("eval.json");
    let e = refused(
        &[
            "eval",
            "--pred",
            &s(&pred),
            "--fps",
            "30",
            "--json",
            &s(&json),
        ],
        &json,
    );
    assert!(
        e.contains("two_bodies.npy") && e.contains("frame 0, joint 12 (neck)"),
        "{e}"
    );

    // The same take unchanged is read.
    let (shape, p) = real_joints();
    let fine = dir.path().join("fine.npy");
    dancegen_io::write_npy_f32(&fine, &shape, &p).unwrap();
    ok(&dancegen(&["-q", "convert", &s(&fine), "-o", &s(&out)]));
}

#[test]
fn generate_refuses_a_leader_or_an_edit_that_is_not_one_body() {
    let dir = tempfile::tempdir().unwrap();
    let far = far_wrist(dir.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let song = s(&shared().join("data/music/sectoid/metal_madness.ogg"));
    let out = dir.path().join("dance.npy");

    let e = refused(
        &["generate", &song, "--leader", &s(&far), "-o", &s(&out)],
        &out,
    );
    assert!(e.contains("far.npy: frame 40, joint 20 (lwrist)"), "{e}");

    let e = refused(
        &[
            "generate",
            &song,
            "--edit",
            &s(&far),
            "--regenerate",
            "1-2",
            "-o",
            &s(&out),
        ],
        &out,
    );
    assert!(e.contains("far.npy: frame 40, joint 20 (lwrist)"), "{e}");
}
