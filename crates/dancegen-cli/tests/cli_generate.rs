//! The `generate` contract with the bundled Lodge++ model: output files and their layout
//! (`.npy` = world joints (T, 24, 3), metres, Y-up, 30 fps), the length rules, and clear errors.

mod common;

use common::*;

fn song() -> String {
    shared()
        .join("data/music/sectoid/feelings.ogg")
        .to_str()
        .unwrap()
        .to_string()
}

/// `(T, 24, 3)` joints of a generated `.npy`.
fn joints(path: &std::path::Path) -> (usize, Vec<f64>) {
    let a = dancegen_io::read_npy(path).unwrap();
    assert_eq!(a.shape.len(), 3, "{:?}", a.shape);
    assert_eq!(&a.shape[1..], &[24, 3]);
    (a.shape[0], a.data)
}

#[test]
fn generates_every_format_for_a_song_segment() {
    let dir = tempfile::tempdir().unwrap();
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "20",
        "--end",
        "30",
        "--seed",
        "3",
        "--steps",
        "20",
        "-o",
        &out("d.npy"),
        "-o",
        &out("d.glb"),
        "-o",
        &out("d.bvh"),
        "-o",
        &out("d.npz"),
        "-o",
        &out("d.json"),
    ]);
    ok(&o);
    let (t, j) = joints(&dir.path().join("d.npy"));
    assert_eq!(t, 300, "10 s at 30 fps");
    assert!(j.iter().all(|v| v.is_finite()));
    for f in 0..t {
        let y = |k: usize| j[(f * 24 + k) * 3 + 1];
        // Feet never below the floor; the pelvis above it.
        let low = [7, 8, 10, 11]
            .map(y)
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        assert!(low > -1e-4, "frame {f}: foot at {low}");
        assert!(y(0) > 0.3, "frame {f}: pelvis at {}", y(0));
        // Stays on stage: within a 6 m square around the origin.
        assert!(j[f * 72].abs() < 3.0 && j[f * 72 + 2].abs() < 3.0);
    }
    // Standing on the floor, not hovering: the lowest foot is near 0 in most frames.
    let mut lows: Vec<f64> = (0..t)
        .map(|f| {
            [7, 8, 10, 11]
                .map(|k| j[(f * 24 + k) * 3 + 1])
                .into_iter()
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    lows.sort_by(f64::total_cmp);
    assert!(lows[t / 2] < 0.08, "median lowest foot {}", lows[t / 2]);
    for f in ["d.glb", "d.bvh", "d.npz", "d.json"] {
        let m = std::fs::metadata(dir.path().join(f)).unwrap();
        assert!(m.len() > 1000, "{f}");
    }
    // The npz and the npy describe the same dance.
    let back = dir.path().join("back.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        &out("d.npz"),
        "-o",
        back.to_str().unwrap(),
    ]));
    let (t2, j2) = joints(&back);
    assert_eq!(t2, t);
    let err = j
        .iter()
        .zip(&j2)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-3, "npz vs npy joints differ by {err}");
}

#[test]
fn same_seed_same_dance_other_seed_other_dance() {
    let dir = tempfile::tempdir().unwrap();
    let run = |seed: &str, name: &str| {
        let p = dir.path().join(name);
        ok(&dancegen(&[
            "-q",
            "generate",
            &song(),
            "--start",
            "60",
            "--end",
            "64.5",
            "--steps",
            "10",
            "--seed",
            seed,
            "-o",
            p.to_str().unwrap(),
        ]));
        joints(&p).1
    };
    let a = run("1", "a.npy");
    let b = run("1", "b.npy");
    let c = run("2", "c.npy");
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_eq!(a.len(), 135 * 72);
}

#[test]
fn unknown_genre_lists_the_choices() {
    let o = dancegen(&["-q", "generate", &song(), "--end", "3", "--genre", "polka"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("polka") && e.contains("salsa"), "{e}");
}

#[test]
fn short_songs_and_bad_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.npy");
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "10",
        "--end",
        "11.5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("at least 2"), "{}", stderr(&o));
    let bad = dir.path().join("not_audio.mp3");
    std::fs::write(&bad, b"this is not audio").unwrap();
    let o = dancegen(&[
        "-q",
        "generate",
        bad.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not_audio.mp3"), "{}", stderr(&o));
    assert!(!out.exists(), "no output on failure");
}

#[test]
fn missing_model_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--end",
        "3",
        "--model",
        dir.path().to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("model.toml") && e.contains("missing"), "{e}");
}
