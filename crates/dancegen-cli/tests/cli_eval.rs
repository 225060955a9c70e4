//! The `eval` command contract: FID / Div against the Bailando golden values of
//! `shared/fixtures/metrics/outputs/fid_bailando_60fps` (that run is Bailando's protocol:
//! zero-start root, first 1200 frames, frame time 1/60 = `--protocol aistpp-bailando`), the
//! JSON layout, undefined clips as `null`, and clear input errors.

mod common;

use std::path::{Path, PathBuf};

use common::*;

/// Copies the 60 fps Y-up generated and real fixtures into `pred/` and `gt/` of `dir`.
fn fixture_sets(dir: &Path) -> (PathBuf, PathBuf) {
    let inputs = shared().join("fixtures/metrics/inputs");
    let mut out = Vec::new();
    for (src, dst) in [("generated", "pred"), ("real", "gt")] {
        let to = dir.join(dst);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(inputs.join(src)).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_str().unwrap().to_string();
            if name.ends_with("_yup_60fps.npy") {
                std::fs::copy(&p, to.join(name)).unwrap();
            }
        }
        out.push(to);
    }
    (out[0].clone(), out[1].clone())
}

fn read_json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn fid_and_div_match_bailando_golden() {
    let dir = tempfile::tempdir().unwrap();
    let (pred, gt) = fixture_sets(dir.path());
    let out = dir.path().join("out.json");
    let o = dancegen(&[
        "eval",
        "--pred",
        s(&pred),
        "--gt",
        s(&gt),
        "--protocol",
        "aistpp-bailando",
        "--fps",
        "60",
        "--metrics",
        "fid_k,fid_g,div_k,div_g",
        "--json",
        s(&out),
    ]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("fid_k"));
    let ours = read_json(&out);
    let golden =
        read_json(&shared().join("fixtures/metrics/outputs/fid_bailando_60fps/metrics.json"));
    for (key, gkey) in [
        ("fid_k", "fid_k"),
        ("fid_g", "fid_m"),
        ("div_k", "div_k"),
        ("div_g", "div_m"),
        ("div_k_gt", "div_k_gt"),
        ("div_g_gt", "div_m_gt"),
    ] {
        let want = golden[gkey]["real"].as_f64().unwrap();
        let got = ours[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} missing"));
        let rel = (got - want).abs() / want.abs();
        println!("{key}: ours {got} golden {want} rel {rel:.2e}");
        assert!(
            rel < 1e-6,
            "{key}: ours {got} vs golden {want} (rel {rel:.2e})"
        );
    }
    assert_eq!(ours["per_clip"].as_array().unwrap().len(), 8);
    assert_eq!(ours["protocol"], "aistpp-bailando");
}

#[test]
fn per_clip_nulls_for_frozen_clip_with_warning() {
    let dir = tempfile::tempdir().unwrap();
    let (pred, gt) = fixture_sets(dir.path());
    let out = dir.path().join("out.json");
    let beats =
        shared().join("fixtures/metrics/outputs/bas/music_beats_real_freezingpoint_fps60.npy");
    let o = dancegen(&[
        "eval",
        "--pred",
        s(&pred),
        "--gt",
        s(&gt),
        "--protocol",
        "aistpp-bailando",
        "--metrics",
        "fid_k,div_k,bas,pfc,fsr,freeze,boundary_jerk",
        "--beats",
        s(&beats),
        "--json",
        s(&out),
    ]);
    ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("gen05_R1_frozen_yup_60fps.npy: bas is undefined"),
        "{err}"
    );
    let j = read_json(&out);
    for key in [
        "fid_k",
        "div_k",
        "div_k_gt",
        "bas",
        "bas_gt",
        "pfc",
        "fsr",
        "freeze",
        "boundary_jerk",
        "per_clip",
    ] {
        assert!(j.get(key).is_some(), "{key} missing from {j}");
    }
    let clips = j["per_clip"].as_array().unwrap();
    let frozen = clips
        .iter()
        .find(|c| c["file"].as_str().unwrap().contains("gen05_R1_frozen"))
        .unwrap();
    assert!(frozen["bas"].is_null());
    // A frozen clip is frozen all the time.
    assert_eq!(frozen["freeze"].as_f64(), Some(1.0));
    // The set mean excludes the null: mean of the 7 defined clip scores.
    let defined: Vec<f64> = clips.iter().filter_map(|c| c["bas"].as_f64()).collect();
    assert_eq!(defined.len(), 7);
    let mean = defined.iter().sum::<f64>() / 7.0;
    assert!((j["bas"].as_f64().unwrap() - mean).abs() < 1e-12);
}

#[test]
fn bad_inputs_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = dancegen(&["eval", "--pred", s(&empty), "--fps", "60"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("empty") && stderr(&o).contains("no motion files"),
        "{}",
        stderr(&o)
    );

    let src = shared().join("fixtures/metrics/inputs/generated/gen01_R1_window_yup_60fps.npy");
    let mut a = dancegen_io::read_npy(&src).unwrap();
    a.data[5 * 72 + 10] = f64::NAN;
    let nan = dir.path().join("nan_clip.npy");
    let data: Vec<f32> = a.data.iter().map(|&v| v as f32).collect();
    dancegen_io::write_npy_f32(&nan, &a.shape, &data).unwrap();
    let o = dancegen(&["eval", "--pred", s(&nan), "--fps", "60"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("nan_clip.npy") && e.contains("frame 5"), "{e}");

    // Protocol frame rate is checked, not resampled.
    let o = dancegen(&[
        "eval",
        "--pred",
        s(&src),
        "--fps",
        "30",
        "--protocol",
        "aistpp-bailando",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("60 fps"), "{}", stderr(&o));

    // Group/duet metrics are not in eval yet.
    let o = dancegen(&["eval", "--pred", s(&src), "--metrics", "gmr"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not yet available"), "{}", stderr(&o));
}

#[test]
fn mpjpe_pairs_by_file_stem() {
    let dir = tempfile::tempdir().unwrap();
    let (pred, _) = fixture_sets(dir.path());
    let out = dir.path().join("out.json");
    // The same clips as prediction and GT: every pair has MPJPE 0.
    ok(&dancegen(&[
        "eval",
        "--pred",
        s(&pred),
        "--gt",
        s(&pred),
        "--fps",
        "60",
        "--metrics",
        "mpjpe",
        "--json",
        s(&out),
    ]));
    let j = read_json(&out);
    assert_eq!(j["mpjpe"].as_f64(), Some(0.0));
    assert_eq!(j["per_clip"].as_array().unwrap().len(), 8);
}
