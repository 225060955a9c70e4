//! The `eval --metrics genre` contract on real motion: CMU salsa, breakdance and modern takes
//! (`shared/data`) converted to SMPL 24 at 30 fps and labelled by a small manifest in the
//! `dancegen dataset build` layout; real clips evaluated as `--pred` with their own genre are
//! assigned it; the JSON keys; the input errors.

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::*;

/// `(stem, genre, BVH under shared/data)` of the real clips.
const CLIPS: [(&str, &str, &str); 8] = [
    ("60_01_scaled", "salsa", "cmu-salsa/60_01_scaled.bvh"),
    ("60_02_scaled", "salsa", "cmu-salsa/60_02_scaled.bvh"),
    ("60_03_scaled", "salsa", "cmu-salsa/60_03_scaled.bvh"),
    ("85_03_neo30", "break", "cmu-dance/break/85_03_neo30.bvh"),
    ("85_04_neo30", "break", "cmu-dance/break/85_04_neo30.bvh"),
    ("05_02", "modern", "cmu-dance/modern/05_02.bvh"),
    ("05_03", "modern", "cmu-dance/modern/05_03.bvh"),
    ("05_04", "modern", "cmu-dance/modern/05_04.bvh"),
];

/// A converted set: `gt/` with one joints `.npy` per clip and `manifest.json` labelling them.
struct Set {
    _dir: tempfile::TempDir,
    gt: PathBuf,
    manifest: PathBuf,
}

/// Converts the clips once per test run (the tests share them; nothing is written under
/// `shared/`).
fn set() -> &'static Set {
    static SET: OnceLock<Set> = OnceLock::new();
    SET.get_or_init(|| {
        let dir = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).unwrap();
        let gt = dir.path().join("gt");
        std::fs::create_dir_all(&gt).unwrap();
        let mut entries = Vec::new();
        for (stem, genre, bvh) in CLIPS {
            let out = gt.join(format!("{stem}.npy"));
            ok(&dancegen(&[
                "convert",
                s(&shared().join("data").join(bvh)),
                "--to",
                "smpl24",
                "--fps",
                "30",
                "-o",
                s(&out),
            ]));
            entries.push(manifest_entry(stem, genre));
        }
        let manifest = dir.path().join("manifest.json");
        let m = serde_json::json!({
            "version": 1,
            "fps": 30,
            "genres": ["break", "modern", "salsa"],
            "clips": entries,
            "held_out": [],
        });
        std::fs::write(&manifest, serde_json::to_string_pretty(&m).unwrap()).unwrap();
        Set {
            _dir: dir,
            gt,
            manifest,
        }
    })
}

/// A clip entry as `dancegen dataset build` writes it (music and warp fields are not read by
/// the genre check but make this a valid manifest).
fn manifest_entry(stem: &str, genre: &str) -> serde_json::Value {
    serde_json::json!({
        "name": stem,
        "motion": format!("motion/{stem}.npy"),
        "music": format!("music/{stem}.npy"),
        "genre": genre,
        "source_motion": format!("{stem}.bvh"),
        "source_song": "song.wav",
        "song_start_s": 0.0,
        "song_end_s": 10.0,
        "frames": 300,
        "pairing": "pseudo_beat_warp",
        "warp": null,
    })
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn read_json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// `eval --metrics genre` of `pred` stems against the whole real set, with `extra` flags.
fn eval_genre(pred: &[&str], want: &str, extra: &[&str]) -> std::process::Output {
    eval_genre_against(pred, &[s(&set().gt).to_string()], want, extra)
}

/// `eval --metrics genre` of `pred` stems against the `gt` files or folders, with `extra` flags.
fn eval_genre_against(
    pred: &[&str],
    gt: &[String],
    want: &str,
    extra: &[&str],
) -> std::process::Output {
    let set = set();
    let pred: Vec<String> = pred
        .iter()
        .map(|p| s(&set.gt.join(format!("{p}.npy"))).to_string())
        .collect();
    let mut args: Vec<&str> = vec!["eval", "--pred"];
    args.extend(pred.iter().map(String::as_str));
    args.push("--gt");
    args.extend(gt.iter().map(String::as_str));
    args.extend([
        "--gt-genres",
        s(&set.manifest),
        "--want-genre",
        want,
        "--metrics",
        "genre",
        "--fps",
        "30",
    ]);
    args.extend(extra);
    dancegen(&args)
}

#[test]
fn real_clips_are_assigned_their_own_genre() {
    let dir = tempfile::tempdir().unwrap();
    for (want, pred) in [
        (
            "salsa",
            &["60_01_scaled", "60_02_scaled", "60_03_scaled"][..],
        ),
        ("break", &["85_03_neo30", "85_04_neo30"][..]),
        ("modern", &["05_02", "05_03", "05_04"][..]),
    ] {
        let out = dir.path().join(format!("{want}.json"));
        let o = eval_genre(pred, want, &["--json", s(&out)]);
        ok(&o);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        println!("{text}");
        assert!(
            text.contains(&format!("genre.requested {want}\n")),
            "{text}"
        );
        assert!(text.contains("genre.share_requested 1.000000"), "{text}");
        let j = read_json(&out);
        let g = &j["genre"];
        assert_eq!(g["requested"], want, "{j}");
        // Clips of the training set, so nearest centroid should put each at its own genre.
        assert_eq!(g["share_requested"].as_f64(), Some(1.0), "{j}");
        assert_eq!(g["samples"].as_u64(), Some(pred.len() as u64), "{j}");
        assert_eq!(g["counts"][want].as_u64(), Some(pred.len() as u64), "{j}");
        assert_eq!(g["counts"].as_object().unwrap().len(), 1, "{j}");
        assert_eq!(
            g["classes"],
            serde_json::json!({"break": 2, "modern": 3, "salsa": 3})
        );
        assert!((g["chance_uniform"].as_f64().unwrap() - 1.0 / 3.0).abs() < 1e-12);
        assert!((g["chance_majority"].as_f64().unwrap() - 3.0 / 8.0).abs() < 1e-12);
        let loo = g["loo_accuracy_real"].as_f64().unwrap();
        // Eight clips: the accuracy is a multiple of 1/8.
        assert!((0.0..=1.0).contains(&loo) && (loo * 8.0 - (loo * 8.0).round()).abs() < 1e-9);
        // The --pred set is exactly that genre's real set: its own FID_k is zero (up to the
        // matrix square root's rounding), the other genres' are not.
        let fid = g["fid_k"].as_object().unwrap();
        assert_eq!(fid.len(), 3, "{j}");
        let own = fid[want].as_f64().unwrap();
        assert!(own.abs() < 1e-3, "fid_k.{want} = {own}");
        for (other, v) in fid.iter().filter(|(k, _)| *k != want) {
            let v = v.as_f64().unwrap();
            assert!(v > 1.0, "fid_k.{other} = {v} for {want} dances");
        }
        let rows = j["per_clip"].as_array().unwrap();
        assert_eq!(rows.len(), pred.len());
        assert!(rows.iter().all(|r| r["genre"] == want), "{j}");
        assert_eq!(j["protocol"], "none");
    }
}

#[test]
fn genre_features_follow_the_protocol() {
    // Under LODGE's FineDance protocol the kinetic features are 66-dimensional (22 joints), as
    // fid_k computes them; the check runs on them and the three salsa clips mix with the rest.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lodge.json");
    let o = eval_genre(
        &["60_01_scaled", "85_03_neo30", "05_02"],
        "salsa",
        &["--protocol", "finedance-lodge", "--json", s(&out)],
    );
    ok(&o);
    let j = read_json(&out);
    assert_eq!(j["protocol"], "finedance-lodge");
    let g = &j["genre"];
    let counts = g["counts"].as_object().unwrap();
    assert_eq!(counts.values().map(|v| v.as_u64().unwrap()).sum::<u64>(), 3);
    let share = g["share_requested"].as_f64().unwrap();
    let salsa = counts.get("salsa").and_then(|v| v.as_u64()).unwrap_or(0);
    assert!((share - salsa as f64 / 3.0).abs() < 1e-12, "{j}");
}

/// A genre with one real clip is one performance: `--genre-min-clips 2` leaves it out of the
/// classifier and reports it, and asking for it is then refused; the default keeps it.
#[test]
fn genres_with_one_real_clip_are_left_out_unless_asked() {
    let set = set();
    let gt: Vec<String> = CLIPS
        .iter()
        .filter(|(stem, _, _)| *stem != "85_04_neo30")
        .map(|(stem, _, _)| s(&set.gt.join(format!("{stem}.npy"))).to_string())
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let run = |want: &str, extra: &[&str], json: &Path| {
        let mut flags = vec!["--json", s(json)];
        flags.extend(extra);
        eval_genre_against(&["05_02"], &gt, want, &flags)
    };
    let out = dir.path().join("min2.json");
    ok(&run("modern", &["--genre-min-clips", "2"], &out));
    let g = &read_json(&out)["genre"];
    assert_eq!(g["classes"], serde_json::json!({"modern": 3, "salsa": 3}));
    assert_eq!(g["excluded"], serde_json::json!({"break": 1}));
    assert_eq!(g["min_clips"].as_u64(), Some(2));
    assert!((g["chance_uniform"].as_f64().unwrap() - 0.5).abs() < 1e-12);
    assert!(g["fid_k"].get("break").is_none(), "{g}");

    let o = run(
        "break",
        &["--genre-min-clips", "2"],
        &dir.path().join("break.json"),
    );
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("--want-genre break has 1 real --gt clip(s), fewer than --genre-min-clips 2"),
        "{e}"
    );

    let out = dir.path().join("default.json");
    ok(&run("modern", &[], &out));
    let g = &read_json(&out)["genre"];
    assert_eq!(
        g["classes"],
        serde_json::json!({"break": 1, "modern": 3, "salsa": 3})
    );
    assert_eq!(g["excluded"], serde_json::json!({}));
    assert_eq!(g["min_clips"].as_u64(), Some(1));

    let o = run(
        "modern",
        &["--genre-min-clips", "0"],
        &dir.path().join("zero.json"),
    );
    assert!(!o.status.success(), "--genre-min-clips 0 must be refused");
}

#[test]
fn genre_input_errors_are_clear() {
    let set = set();
    let clip = set.gt.join("60_01_scaled.npy");
    let base = [
        "eval",
        "--pred",
        s(&clip),
        "--metrics",
        "genre",
        "--fps",
        "30",
    ];
    let run = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend(extra);
        dancegen(&a)
    };
    let fails_with = |o: std::process::Output, want: &str| {
        assert!(!o.status.success(), "expected failure mentioning {want}");
        let e = stderr(&o);
        assert!(e.contains(want), "expected {want:?} in: {e}");
    };
    let gt = s(&set.gt);
    let man = s(&set.manifest);
    fails_with(
        run(&["--gt-genres", man, "--want-genre", "salsa"]),
        "genre needs --gt (",
    );
    fails_with(
        run(&["--gt", gt, "--want-genre", "salsa"]),
        "genre needs --gt-genres",
    );
    fails_with(
        run(&["--gt", gt, "--gt-genres", man]),
        "genre needs --want-genre",
    );
    // An unknown genre lists the manifest's genres.
    fails_with(
        run(&["--gt", gt, "--gt-genres", man, "--want-genre", "tango"]),
        "--want-genre tango is not a genre of",
    );
    fails_with(
        run(&["--gt", gt, "--gt-genres", man, "--want-genre", "tango"]),
        "break, modern, salsa",
    );
    // A real clip the manifest does not label is named.
    let dir = tempfile::tempdir().unwrap();
    let extra = dir.path().join("not_in_manifest.npy");
    std::fs::copy(&clip, &extra).unwrap();
    fails_with(
        run(&[
            "--gt",
            gt,
            s(&extra),
            "--gt-genres",
            man,
            "--want-genre",
            "salsa",
        ]),
        "not_in_manifest.npy has no entry in",
    );
    // A file that is not a manifest.
    fails_with(
        run(&["--gt", gt, "--gt-genres", s(&clip), "--want-genre", "salsa"]),
        "--gt-genres",
    );
}
