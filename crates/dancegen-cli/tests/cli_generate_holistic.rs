//! The `generate --system holistic` contract with the bundled SoulNet model
//! (`models/soulnet-small`): `.npy` = world joints (T, 52, 3) in SMPL-H order, `.json` with
//! `"face": {names, weights}`, Live Link Face `.csv`, `.bvh` with SMPL-X finger names, `.glb`
//! with finger bones and 52 ARKit morph targets; a song longer than one window; clear errors.

mod common;

use common::*;

fn song() -> String {
    shared()
        .join("data/music/sectoid/feelings.ogg")
        .to_str()
        .unwrap()
        .to_string()
}

#[test]
fn a_holistic_dance_has_fingers_and_a_face_in_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    // 12 s = 360 frames: three generator windows (128 frames each) joined by inpainting.
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--system",
        "holistic",
        "--start",
        "20",
        "--end",
        "32",
        "--seed",
        "2",
        "-o",
        &out("d.npy"),
        "-o",
        &out("d.json"),
        "-o",
        &out("face.csv"),
        "-o",
        &out("d.bvh"),
        "-o",
        &out("d.glb"),
    ]);
    ok(&o);
    let a = dancegen_io::read_npy(&dir.path().join("d.npy")).unwrap();
    assert_eq!(a.shape, vec![360, 52, 3]);
    assert!(a.data.iter().all(|v| v.is_finite()));
    // Fingers move relative to the wrist (not frozen): the left index tip (24) to the left
    // wrist (20) distance changes over the dance.
    let dist = |f: usize, j: usize, w: usize| {
        (0..3)
            .map(|k| (a.data[(f * 52 + j) * 3 + k] - a.data[(f * 52 + w) * 3 + k]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let d: Vec<f64> = (0..360).map(|f| dist(f, 24, 20)).collect();
    let spread =
        d.iter().cloned().fold(f64::MIN, f64::max) - d.iter().cloned().fold(f64::MAX, f64::min);
    // Frozen fingers give 0 (up to float noise); the shipped model's held-out dances spread it
    // by 2.8-7.2 cm (target/holistic-eval/gen, seeds 0-1), so 2 mm leaves a wide margin.
    assert!(spread > 0.002, "finger-to-wrist distance spread {spread} m");
    // Feet on or above the floor.
    for f in 0..360 {
        let low = [7, 8, 10, 11]
            .map(|j| a.data[(f * 52 + j) * 3 + 1])
            .into_iter()
            .fold(f64::MAX, f64::min);
        assert!(low > -1e-4, "frame {f}: foot at {low}");
    }

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("d.json")).unwrap()).unwrap();
    let names = json["face"]["names"].as_array().unwrap();
    assert_eq!(names.len(), 52);
    assert_eq!(names[0], "eyeBlinkLeft");
    let weights = json["face"]["weights"].as_array().unwrap();
    assert_eq!(weights.len(), 360);
    let all: Vec<f64> = weights
        .iter()
        .flat_map(|w| w.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()))
        .collect();
    assert_eq!(all.len(), 360 * 52);
    assert!(all.iter().all(|v| (0.0..=1.0).contains(v)));
    // The face moves: some weight varies over the dance.
    let std_max = (0..52)
        .map(|k| {
            let col: Vec<f64> = (0..360).map(|f| all[f * 52 + k]).collect();
            let m = col.iter().sum::<f64>() / 360.0;
            (col.iter().map(|v| (v - m).powi(2)).sum::<f64>() / 360.0).sqrt()
        })
        .fold(0.0, f64::max);
    // A constant face gives 0; the shipped model's most-moving weight has std 0.054 on a
    // held-out clip (seed 0), the synthetic data's mean 0.031.
    assert!(std_max > 0.01, "face weights nearly constant ({std_max})");

    let csv =
        dancegen_formats::livelink_csv::read_file(&dir.path().join("face.csv"), 30.0).unwrap();
    assert_eq!(csv.frames(), 360);
    let bvh = std::fs::read_to_string(dir.path().join("d.bvh")).unwrap();
    assert!(bvh.contains("left_index1") && bvh.contains("right_thumb3"));
    let glb = std::fs::read(dir.path().join("d.glb")).unwrap();
    assert!(
        glb.windows(13).any(|w| w == b"\"targetNames\""),
        "no morph target names"
    );
}

#[test]
fn holistic_errors_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.npy");
    let out = out.to_str().unwrap();
    // `generate --system holistic` up to `end` seconds into `out`, with `extra` flags.
    let holistic = |end: &str, extra: &[&str]| {
        let song = song();
        let mut args = vec![
            "-q", "generate", &song, "--system", "holistic", "--end", end,
        ];
        args.extend(extra);
        args.extend(["-o", out]);
        dancegen(&args)
    };
    // Too short.
    let o = holistic("1", &[]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("at least 2 s"), "{}", stderr(&o));
    // A FLAME mapping of the wrong shape names the file and the shape.
    let bad = dir.path().join("mapping.npy");
    dancegen_io::write_npy_f32(&bad, &[52, 100], &vec![0.0; 5200]).unwrap();
    let o = holistic("4", &["--flame-mapping", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("mapping.npy") && e.contains("103"), "{e}");
    // A model directory that is not a holistic model.
    let o = holistic("4", &["--model", dir.path().to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("model.toml"), "{}", stderr(&o));
    assert!(!std::path::Path::new(out).exists());
}

#[test]
fn swapping_holistic_networks_names_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("model");
    let out = out.to_str().unwrap();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/soulnet-small");
    // --holistic-model needs the run to swap in, and does not mix with the three-run form.
    let o = dancegen(&["-q", "bundle", "--holistic-model", model, "-o", out]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--holistic-vq"), "{}", stderr(&o));
    let o = dancegen(&[
        "-q",
        "bundle",
        "--holistic-vq",
        model,
        "--holistic-mmr",
        model,
        "--holistic-generator",
        model,
        "--holistic-model",
        model,
        "-o",
        out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--holistic-model"), "{}", stderr(&o));
    // A folder that is not a finished soulnet_vq run is named.
    let not_run = dir.path().join("not-a-run");
    std::fs::create_dir_all(&not_run).unwrap();
    let o = dancegen(&[
        "-q",
        "bundle",
        "--holistic-vq",
        not_run.to_str().unwrap(),
        "--holistic-model",
        model,
        "-o",
        out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not-a-run"), "{}", stderr(&o));
    // The same for a generator run; and a generator run alone says what goes with it.
    let o = dancegen(&[
        "-q",
        "bundle",
        "--holistic-generator",
        not_run.to_str().unwrap(),
        "--holistic-model",
        model,
        "-o",
        out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not-a-run"), "{}", stderr(&o));
    let o = dancegen(&[
        "-q",
        "bundle",
        "--holistic-generator",
        not_run.to_str().unwrap(),
        "-o",
        out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--holistic-model"), "{}", stderr(&o));
    assert!(!std::path::Path::new(out).exists(), "nothing written");
}
