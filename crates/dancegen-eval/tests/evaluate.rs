//! The library call behind `dancegen eval`: clips on disk in, the report out as the CLI's
//! `--json` object; a bad request is an error naming the flag.

use std::path::Path;

use dancegen_eval::{EvalOptions, evaluate};

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
        pred,
        gt,
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
        pred: vec![clip(dir.path(), "a.npy", 0.0)],
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
