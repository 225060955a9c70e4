//! The library call behind `dancegen eval`: clips on disk in, the report out as the CLI's
//! `--json` object; a bad request is an error naming the flag.

use std::path::Path;

use dancegen_eval::{ClipArray, EvalOptions, Input, evaluate};

/// A `(T, 24, 3)` joints `.npy` of a figure standing 1 m up and swaying with `phase`.
fn clip(dir: &Path, name: &str, phase: f32) -> std::path::PathBuf {
    let frames = 90;
    let mut data = Vec::with_capacity(frames * 72);
    for f in 0..frames {
        let t = f as f32 / 30.0;
        for j in 0..24 {
            let sway = 0.1 * (std::f32::consts::TAU * (t + phase) + j as f32 * 0.3).sin();
            data.extend([sway, 1.0 + 0.02 * j as f32, 0.05 * j as f32 * sway]);
        }
    }
    let path = dir.join(name);
    dancegen_io::npy::write_npy_f32(&path, &[frames, 24, 3], &data).unwrap();
    path
}

#[test]
fn evaluate_reports_the_cli_json_object() {
    let dir = tempfile::tempdir().unwrap();
    let pred = vec![
        clip(dir.path(), "a.npy", 0.0),
        clip(dir.path(), "b.npy", 0.3),
    ];
    let gt = vec![
        clip(dir.path(), "c.npy", 0.1),
        clip(dir.path(), "d.npy", 0.6),
    ];
    let opts = EvalOptions {
        pred: pred.into_iter().map(Input::Path).collect(),
        gt: gt.into_iter().map(Input::Path).collect(),
        fps: Some(30.0),
        metrics: Some("fid_k,div_k,pfc,physical".into()),
        ..EvalOptions::default()
    };
    let report = evaluate(&opts).unwrap();
    assert_eq!((report.pred_clips, report.gt_clips), (2, 2));
    let json = report.to_json();
    assert_eq!(json["protocol"], "none");
    for key in ["fid_k", "div_k", "div_k_gt", "pfc", "jerk"] {
        assert!(json.get(key).is_some(), "{key} missing: {json}");
    }
    let per_clip = json["per_clip"].as_array().unwrap();
    assert_eq!(per_clip.len(), 2);
    assert!(per_clip[0]["file"].as_str().unwrap().ends_with("a.npy"));
    assert_eq!(per_clip[0]["frames"], 90);
}

#[test]
fn a_metric_the_inputs_cannot_give_names_the_flag_it_needs() {
    let dir = tempfile::tempdir().unwrap();
    let opts = EvalOptions {
        pred: vec![Input::Path(clip(dir.path(), "a.npy", 0.0))],
        fps: Some(30.0),
        metrics: Some("fid_k".into()),
        ..EvalOptions::default()
    };
    let e = format!("{:#}", evaluate(&opts).unwrap_err());
    assert!(e.contains("fid_k") && e.contains("--gt"), "{e}");
    let opts = EvalOptions {
        metrics: Some("nonsense".into()),
        ..opts
    };
    let e = format!("{:#}", evaluate(&opts).unwrap_err());
    assert!(e.contains("unknown metric nonsense"), "{e}");
}

/// The clip of `path` as an array named `name`, as the Python package passes it.
fn array(path: &Path, name: &str) -> Input {
    let a = dancegen_io::read_npy(path).unwrap();
    Input::Array(ClipArray {
        name: name.into(),
        shape: a.shape,
        data: a.data,
    })
}

#[test]
fn arrays_in_memory_give_the_report_of_their_files() {
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<_> = [("a", 0.0), ("b", 0.3), ("c", 0.1), ("d", 0.6)]
        .into_iter()
        .map(|(n, phase)| clip(dir.path(), &format!("{n}.npy"), phase))
        .collect();
    let on_disk = EvalOptions {
        pred: files[..2].iter().cloned().map(Input::Path).collect(),
        gt: files[2..].iter().cloned().map(Input::Path).collect(),
        fps: Some(30.0),
        beat_frames: Some(vec![10, 25, 40, 55, 70]),
        ..EvalOptions::default()
    };
    let in_memory = EvalOptions {
        pred: vec![array(&files[0], "a"), array(&files[1], "b")],
        gt: vec![array(&files[2], "c"), array(&files[3], "d")],
        ..on_disk.clone()
    };
    let mut disk = evaluate(&on_disk).unwrap().to_json();
    let mut memory = evaluate(&in_memory).unwrap().to_json();
    assert!(disk.get("bas").is_some(), "beat frames give bas: {disk}");
    // Only the clip names differ: the file's path, the array's name.
    for (json, names) in [(&mut disk, ["a.npy", "b.npy"]), (&mut memory, ["a", "b"])] {
        for (clip, name) in json["per_clip"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .zip(names)
        {
            assert!(clip["file"].as_str().unwrap().ends_with(name), "{clip}");
            clip["file"] = serde_json::Value::Null;
        }
    }
    assert_eq!(disk, memory);
    // A wrong shape names the array.
    let bad = EvalOptions {
        pred: vec![Input::Array(ClipArray {
            name: "flat".into(),
            shape: vec![90, 72],
            data: vec![0.0; 90 * 72],
        })],
        ..on_disk
    };
    let e = format!("{:#}", evaluate(&bad).unwrap_err());
    assert!(e.contains("array flat") && e.contains("[90, 72]"), "{e}");
}
