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
    // The beat counts behind BAS: a frozen clip has no motion beats, but its music has beats.
    assert_eq!(frozen["motion_beats"].as_u64(), Some(0));
    assert!(frozen["music_beats"].as_u64().unwrap() > 0);
    for c in clips.iter().filter(|c| c["bas"].is_number()) {
        assert!(c["motion_beats"].as_u64().unwrap() > 0, "{c}");
        assert_eq!(
            c["music_beats"], frozen["music_beats"],
            "same length, same beats: {c}"
        );
    }
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

    // Group and duet metrics on solo clips name what they need.
    for (m, need) in [("gmc", "group scenes"), ("bed", "duets"), ("gmr", "--gt")] {
        let o = dancegen(&["eval", "--pred", s(&src), "--fps", "60", "--metrics", m]);
        assert!(!o.status.success(), "{m}");
        assert!(stderr(&o).contains(need), "{m}: {}", stderr(&o));
    }

    // A follower without a leader of its stem.
    let lead = dir.path().join("leaders");
    std::fs::create_dir_all(&lead).unwrap();
    std::fs::copy(&src, lead.join("someone_else.npy")).unwrap();
    let o = dancegen(&[
        "eval",
        "--pred",
        s(&src),
        "--leader",
        s(&lead),
        "--fps",
        "60",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no --leader clip"), "{}", stderr(&o));

    // Unknown metric names fail before any file is read.
    let o = dancegen(&["eval", "--pred", "/nonexistent", "--metrics", "fid_x"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("unknown metric fid_x"),
        "{}",
        stderr(&o)
    );
}

/// Copies `inputs/scenes/<prefix>_scene{1..4}_yup_30fps.npy` to `dir/<prefix>/scene{i}.npy`.
fn scene_set(dir: &Path, prefix: &str) -> PathBuf {
    let to = dir.join(prefix);
    std::fs::create_dir_all(&to).unwrap();
    for i in 1..=4 {
        let from = shared().join(format!(
            "fixtures/metrics/inputs/scenes/{prefix}_scene{i}_yup_30fps.npy"
        ));
        std::fs::copy(from, to.join(format!("scene{i}.npy"))).unwrap();
    }
    to
}

fn golden_values() -> serde_json::Value {
    read_json(&shared().join("fixtures/metrics/golden_values.json"))
}

fn assert_rel(what: &str, got: f64, want: f64, tol: f64) {
    let rel = if got == want {
        0.0
    } else {
        (got - want).abs() / want.abs().max(1e-300)
    };
    println!("{what}: ours {got} golden {want} rel {rel:.2e}");
    assert!(
        rel <= tol,
        "{what}: ours {got} vs golden {want} (rel {rel:.2e})"
    );
}

#[test]
fn group_metrics_match_gcd_golden() {
    let dir = tempfile::tempdir().unwrap();
    let pred = scene_set(dir.path(), "gen");
    let gt = scene_set(dir.path(), "gt");
    let out = dir.path().join("group.json");
    ok(&dancegen(&[
        "eval",
        "--pred",
        s(&pred),
        "--gt",
        s(&gt),
        "--fps",
        "30",
        "--metrics",
        "gmr,gmc,tif,fid_k",
        "--json",
        s(&out),
    ]));
    let ours = read_json(&out);
    let g = &golden_values()["gcd"];
    assert_rel(
        "gmr",
        ours["gmr"].as_f64().unwrap(),
        g["GMR_k"].as_f64().unwrap(),
        1e-6,
    );
    assert_rel(
        "gmc",
        ours["gmc"].as_f64().unwrap(),
        g["gmc_mean_generated"].as_f64().unwrap(),
        1e-9,
    );
    let rows = ours["per_clip"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    for (i, row) in rows.iter().enumerate() {
        let want = g["GMC_per_scene"][format!("gen_scene{}", i + 1)]
            .as_f64()
            .unwrap();
        assert_rel(
            &format!("gmc scene{}", i + 1),
            row["gmc"].as_f64().unwrap(),
            want,
            1e-9,
        );
        let tif = row["tif"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&tif), "tif {tif}");
        assert!(row["dancers"].as_u64().unwrap() >= 2);
    }
    // fid_k counts every dancer as one solo sample (TCDiff): finite with 2-3 dancers per scene.
    assert!(ours["fid_k"].as_f64().is_some());
}

/// Copies the fixture duets to `dir/<prefix>_{f,l}/duet{i}.npy` (follower and leader share a
/// stem) and to `dir/<prefix>_pairs/duet{i}.npy` as (2, T, 24, 3) [leader, follower].
fn duet_set(dir: &Path, prefix: &str) -> (PathBuf, PathBuf, PathBuf) {
    let (f, l, pairs) = (
        dir.join(format!("{prefix}_f")),
        dir.join(format!("{prefix}_l")),
        dir.join(format!("{prefix}_pairs")),
    );
    for d in [&f, &l, &pairs] {
        std::fs::create_dir_all(d).unwrap();
    }
    for i in 1..=4 {
        let src = |role: &str| {
            shared().join(format!(
                "fixtures/metrics/inputs/duets/{prefix}_duet{i}_{role}_smpl24_yup_30fps.npy"
            ))
        };
        std::fs::copy(src("follower"), f.join(format!("duet{i}.npy"))).unwrap();
        std::fs::copy(src("leader"), l.join(format!("duet{i}.npy"))).unwrap();
        let fa = dancegen_io::read_npy(&src("follower")).unwrap();
        let la = dancegen_io::read_npy(&src("leader")).unwrap();
        assert_eq!(fa.shape, la.shape);
        let mut shape = vec![2];
        shape.extend(&fa.shape);
        let data: Vec<f32> = la.data.iter().chain(&fa.data).map(|&v| v as f32).collect();
        dancegen_io::write_npy_f32(&pairs.join(format!("duet{i}.npy")), &shape, &data).unwrap();
    }
    (f, l, pairs)
}

#[test]
fn duet_metrics_match_duolando_golden() {
    let dir = tempfile::tempdir().unwrap();
    let (gen_f, gen_l, gen_pairs) = duet_set(dir.path(), "gen");
    let (gt_f, gt_l, gt_pairs) = duet_set(dir.path(), "gt");
    let g = &golden_values()["duolando"];

    // Leaders as separate files, matched by stem (float64 inputs: the golden precision).
    let out = dir.path().join("duet.json");
    ok(&dancegen(&[
        "eval",
        "--pred",
        s(&gen_f),
        "--leader",
        s(&gen_l),
        "--gt",
        s(&gt_f),
        "--gt-leader",
        s(&gt_l),
        "--fps",
        "30",
        "--metrics",
        "fid_cd,div_cd,bed",
        "--json",
        s(&out),
    ]));
    let ours = read_json(&out);
    assert_rel(
        "fid_cd",
        ours["fid_cd"].as_f64().unwrap(),
        g["FID_cd"].as_f64().unwrap(),
        1e-6,
    );
    assert_rel(
        "div_cd",
        ours["div_cd"].as_f64().unwrap(),
        g["Div_cd"].as_f64().unwrap(),
        1e-6,
    );
    assert_rel(
        "div_cd_gt",
        ours["div_cd_gt"].as_f64().unwrap(),
        g["Div_cd_gt"].as_f64().unwrap(),
        1e-6,
    );
    assert_rel(
        "bed",
        ours["bed"].as_f64().unwrap(),
        g["BED_mean_generated"].as_f64().unwrap(),
        1e-9,
    );
    for (i, row) in ours["per_clip"].as_array().unwrap().iter().enumerate() {
        let want = g["BED_per_pair"][format!("gen_duet{}", i + 1)]
            .as_f64()
            .unwrap();
        assert_rel(
            &format!("bed duet{}", i + 1),
            row["bed"].as_f64().unwrap(),
            want,
            1e-9,
        );
    }

    // Two-dancer clips [leader, follower] give the same duet metrics (float32 storage here, so
    // a looser tolerance than the golden).
    let out2 = dir.path().join("pairs.json");
    ok(&dancegen(&[
        "eval",
        "--pred",
        s(&gen_pairs),
        "--gt",
        s(&gt_pairs),
        "--fps",
        "30",
        "--metrics",
        "fid_cd,div_cd,bed",
        "--json",
        s(&out2),
    ]));
    let pairs = read_json(&out2);
    for k in ["fid_cd", "div_cd", "bed"] {
        assert_rel(
            k,
            pairs[k].as_f64().unwrap(),
            ours[k].as_f64().unwrap(),
            1e-4,
        );
    }
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

#[test]
fn empty_group_array_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("empty_scene.npy");
    dancegen_io::write_npy_f32(&p, &[2, 0, 24, 3], &[]).unwrap();
    let o = dancegen(&["eval", "--pred", s(&p), "--fps", "30"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("empty_scene.npy") && e.contains("empty group array"),
        "{e}"
    );
}

#[test]
fn penetration_key_in_json() {
    let dir = tempfile::tempdir().unwrap();
    let (pred, _) = fixture_sets(dir.path());
    // Selected explicitly: the only metric, per clip and as the set mean.
    let out = dir.path().join("pen.json");
    let o = dancegen(&[
        "eval",
        "--pred",
        s(&pred),
        "--fps",
        "60",
        "--metrics",
        "penetration",
        "--json",
        s(&out),
    ]);
    ok(&o);
    let j = read_json(&out);
    let mean = j["penetration"].as_f64().expect("penetration missing");
    assert!((0.0..=100.0).contains(&mean), "{mean}");
    assert!(j.get("fid_k").is_none() && j.get("pfc").is_none(), "{j}");
    let clips = j["per_clip"].as_array().unwrap();
    let vals: Vec<f64> = clips
        .iter()
        .map(|c| c["penetration"].as_f64().unwrap())
        .collect();
    println!("penetration per clip {vals:?}, mean {mean}");
    assert!(vals.iter().all(|v| (0.0..=100.0).contains(v)));
    let m = vals.iter().sum::<f64>() / vals.len() as f64;
    assert!((m - mean).abs() < 1e-12);
    // Part of the default solo set.
    let out = dir.path().join("default.json");
    let o = dancegen(&["eval", "--pred", s(&pred), "--fps", "60", "--json", s(&out)]);
    ok(&o);
    let j = read_json(&out);
    assert_eq!(j["penetration"].as_f64(), Some(mean), "{j}");
}

#[test]
fn window_sets_the_boundaries_of_boundary_jerk() {
    // Smooth swaying joints with a 10 cm jump every 100 frames: jerky at 100-frame boundaries,
    // ordinary at the default 150-frame ones (except where they meet, at 300).
    let dir = tempfile::tempdir().unwrap();
    let (t, j) = (600usize, 24usize);
    let mut data = Vec::with_capacity(t * j * 3);
    for f in 0..t {
        let jump = 0.1 * (f / 100) as f32;
        for k in 0..j {
            let phase = f as f32 / 30.0 + k as f32;
            data.extend([
                0.2 * phase.sin() + jump,
                1.0 + 0.03 * k as f32,
                0.1 * (1.3 * phase).cos(),
            ]);
        }
    }
    let clip = dir.path().join("jumps.npy");
    dancegen_io::write_npy_f32(&clip, &[t, j, 3], &data).unwrap();
    let ratio = |window: Option<&str>| -> f64 {
        let out = dir.path().join("bj.json");
        let mut args = vec![
            "eval",
            "--pred",
            s(&clip),
            "--fps",
            "30",
            "--metrics",
            "boundary_jerk",
            "--json",
            s(&out),
        ];
        if let Some(w) = window {
            args.extend(["--window", w]);
        }
        ok(&dancegen(&args));
        read_json(&out)["boundary_jerk"].as_f64().unwrap()
    };
    let at_100 = ratio(Some("100"));
    let at_150 = ratio(None);
    assert!(at_100 > 5.0, "jumps at every 100-frame boundary: {at_100}");
    assert!(
        at_100 > 2.0 * at_150,
        "100: {at_100}, default 150: {at_150}"
    );
    let o = dancegen(&["eval", "--pred", s(&clip), "--fps", "30", "--window", "1"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--window"), "{}", stderr(&o));
}

#[test]
fn inverted_counts_upside_down_frames_of_a_real_clip() {
    let dir = tempfile::tempdir().unwrap();
    let (_, gt) = fixture_sets(dir.path());
    // The first real clip by name (read_dir's order is the file system's).
    let mut reals: Vec<_> = std::fs::read_dir(&gt)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    reals.sort();
    let real = reals.swap_remove(0);
    let a = dancegen_io::read_npy(&real).unwrap();
    let t = a.shape[0];
    // The same motion turned 180° about the x axis from frame t/2 on: (x, y, z) → (x, −y, −z)
    // around the pelvis height, so the second half stands on its head.
    let mut flipped: Vec<f32> = a.data.iter().map(|&v| v as f32).collect();
    for f in t / 2..t {
        for v in flipped[f * 72..(f + 1) * 72].chunks_exact_mut(3) {
            v[1] = 2.0 - v[1];
            v[2] = -v[2];
        }
    }
    let pred = dir.path().join("flip");
    std::fs::create_dir(&pred).unwrap();
    dancegen_io::write_npy_f32(&pred.join("half.npy"), &a.shape, &flipped).unwrap();
    std::fs::copy(&real, pred.join("real.npy")).unwrap();
    let out = dir.path().join("out.json");
    ok(&dancegen(&[
        "eval",
        "--pred",
        s(&pred),
        "--fps",
        "60",
        "--metrics",
        "inverted",
        "--json",
        s(&out),
    ]));
    let j = read_json(&out);
    let of = |name: &str| {
        j["per_clip"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["file"].as_str().unwrap().ends_with(name))
            .unwrap()["inverted"]
            .as_f64()
            .unwrap()
    };
    assert_eq!(of("real.npy"), 0.0, "a real clip is upright");
    let half = of("half.npy");
    let want = (t - t / 2) as f64 / t as f64;
    assert!((half - want).abs() < 1e-12, "{half} vs {want}");
    assert!((j["inverted"].as_f64().unwrap() - want / 2.0).abs() < 1e-12);
}
