//! The `features` and `beats` command contracts external tools rely on.

mod common;

use common::*;

#[test]
fn features_npy_is_t_by_35_float32_c_order() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.npy");
    let clip = shared().join("fixtures/music/clips/click_120bpm.wav");
    let o = dancegen(&[
        "-q",
        "features",
        clip.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = dancegen_io::read_npy(&out).unwrap();
    assert_eq!(a.dtype, "<f4");
    assert_eq!(a.shape, vec![301, 35]);
    let raw = std::fs::read(&out).unwrap();
    let header = String::from_utf8_lossy(&raw[10..128]);
    assert!(header.contains("'fortran_order': False"), "{header}");
    // Compare with librosa's matrix for the same clip.
    let want =
        dancegen_io::read_npy(&shared().join("fixtures/music/ref/click_120bpm/fps30/feats35.npy"))
            .unwrap();
    let beats = |d: &[f64]| -> Vec<usize> {
        d.chunks_exact(35)
            .enumerate()
            .filter(|(_, r)| r[34] > 0.5)
            .map(|(i, _)| i)
            .collect()
    };
    assert_eq!(beats(&a.data), beats(&want.data));
}

#[test]
fn features_json_has_the_contract_keys() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.json");
    let clip = shared().join("fixtures/music/clips/click_120bpm.wav");
    let o = dancegen(&[
        "-q",
        "features",
        clip.to_str().unwrap(),
        "--fps",
        "60",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for key in ["fps", "tempo_bpm", "beat_times", "onset_times", "features"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["fps"], 60);
    assert_eq!(v["tempo_bpm"].as_f64().unwrap(), 120.0);
    let feats = v["features"].as_array().unwrap();
    assert_eq!(feats.len(), 601);
    assert_eq!(feats[0].as_array().unwrap().len(), 35);
    // Beat times are frame / fps seconds, in order.
    let times: Vec<f64> = v["beat_times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert_eq!(times.len(), 19);
    assert!(times.windows(2).all(|w| w[1] > w[0]));
    let frames: Vec<u64> = v["beat_frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_u64().unwrap())
        .collect();
    for (t, f) in times.iter().zip(&frames) {
        assert!((t - *f as f64 / 60.0).abs() < 1e-12);
    }
}

#[test]
fn no_song_uses_the_bundled_demo() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo.npy");
    let o = dancegen(&["features", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = dancegen_io::read_npy(&out).unwrap();
    // 45 s at 30 fps: 1 + 45·15360/512 frames.
    assert_eq!(a.shape, vec![1351, 35]);
}

#[test]
fn slices_and_tcdiff_shapes() {
    let dir = tempfile::tempdir().unwrap();
    let clip = shared().join("fixtures/music/clips/click_120bpm.wav");
    let out = dir.path().join("s.npy");
    let o = dancegen(&[
        "-q",
        "features",
        clip.to_str().unwrap(),
        "--slice5s",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // 10 s, 5 s windows every 2.5 s: 0, 2.5, 5.
    assert_eq!(dancegen_io::read_npy(&out).unwrap().shape, vec![3, 150, 35]);
    let out = dir.path().join("s.json");
    let o = dancegen(&[
        "-q",
        "features",
        clip.to_str().unwrap(),
        "--slice5s",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for key in [
        "fps",
        "tempo_bpm",
        "beat_times",
        "onset_times",
        "features",
        "slices",
    ] {
        assert!(v.get(key).is_some(), "slice JSON misses {key}");
    }
    assert_eq!(v["features"].as_array().unwrap().len(), 3);
    assert_eq!(v["features"][0].as_array().unwrap().len(), 150);
    let out = dir.path().join("t.npy");
    let o = dancegen(&[
        "-q",
        "features",
        clip.to_str().unwrap(),
        "--set",
        "tcdiff438",
        "--fps",
        "60",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(dancegen_io::read_npy(&out).unwrap().shape, vec![601, 438]);
    // The 438 set is only defined at 60 fps.
    let o = dancegen(&[
        "features",
        clip.to_str().unwrap(),
        "--set",
        "tcdiff438",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("60 fps"), "{}", stderr(&o));
}

#[test]
fn bad_input_fails_cleanly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.npy");
    let missing = dir.path().join("missing.mp3");
    let o = dancegen(&[
        "features",
        missing.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("missing.mp3") && err.contains("cannot open"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let garbage = dir.path().join("garbage.wav");
    std::fs::write(&garbage, vec![7u8; 3000]).unwrap();
    let o = dancegen(&[
        "features",
        garbage.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("garbage.wav"), "{}", stderr(&o));
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temp files left"
    );
    // Unsupported options are refused by the parser.
    let o = dancegen(&["features", "--fps", "45", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let o = dancegen(&["features", "-o", dir.path().join("x.csv").to_str().unwrap()]);
    assert!(
        stderr(&o).contains("unknown output format"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn beats_prints_tempo_and_plots_png() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("beats.png");
    let clip = shared().join("fixtures/music/clips/click_090bpm.wav");
    let o = dancegen(&[
        "beats",
        clip.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("tempo: 90.00 BPM"), "{text}");
    assert!(text.contains("beats: 15"), "{text}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let o = dancegen(&["beats", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["tempo_bpm"].as_f64().unwrap() > 0.0);
}

#[test]
fn help_and_version() {
    assert!(dancegen(&["--version"]).status.success());
    for sub in [
        &["--help"][..],
        &["features", "--help"],
        &["beats", "--help"],
    ] {
        let o = dancegen(sub);
        assert!(o.status.success());
        assert!(!o.stdout.is_empty());
    }
}
