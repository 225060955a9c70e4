//! Golden tests: PFC, foot-skating ratio and MPJPE against the reference outputs in
//! `shared/fixtures/metrics/outputs/{pfc,foot_skating,mpjpe}/` (README §4.4, §4.5, §4.7).
//!
//! - PFC (`Stanford-TML/EDGE:eval/eval_pfc.py`) on the Z-up 30-fps clips, one clip per set and the
//!   three sets; float64 reference, relative tolerance 1e-6; the frozen clip must give `None` /
//!   `NaN` as the reference does.
//! - Foot skating (`li-ronghui/LODGE:metric/foot_skating.py`): the reference's SMPL-X FK needs
//!   non-shipped rest joints, so we feed the fixture intermediates (grounded LODGE-FK positions
//!   of joints 7, 8, 10, 11) and require the exact float32 ratios and contact counts. We also
//!   check the position-space pipeline (grounding included) against
//!   `foot_skating_on_edge_positions_NOTREFERENCE.json` — our fixture author's own re-implementation,
//!   not a reference value.
//! - MPJPE (`xjli360/SoulDance-Official:utils/metrics.py::calculate_mpjpe`): per-pose arrays and
//!   means, float64 reference, relative tolerance 1e-6.

mod common;

use common::metrics_fixtures;
use std::path::Path;

use dancegen_metrics::foot_skating::{
    FootSkating, foot_skating_from_grounded_feet, foot_skating_ratio, mean_foot_skating,
};
use dancegen_metrics::mpjpe::{mpjpe_mean, mpjpe_per_pose};
use dancegen_metrics::pfc::{pfc_clip_score, pfc_from_clip_scores};
use serde_json::Value;

const REL_TOL: f64 = 1e-6;

fn read_json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Reads a `.npy` array, checking its shape against `(_, dims...)`; returns (rows, data).
fn read_array(path: &Path, dims: &[usize]) -> (usize, Vec<f64>) {
    let arr = dancegen_io::read_npy(path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(&arr.shape[1..], dims, "{}", path.display());
    (arr.shape[0], arr.data)
}

/// A JSON number, or `NaN` for the string `"NaN"`.
fn number(v: &Value) -> f64 {
    match v {
        Value::String(s) if s == "NaN" => f64::NAN,
        _ => v.as_f64().unwrap_or_else(|| panic!("not a number: {v}")),
    }
}

fn rel_err(ours: f64, golden: f64) -> f64 {
    if ours == golden || (ours.is_nan() && golden.is_nan()) {
        0.0
    } else if golden == 0.0 || ours.is_nan() || golden.is_nan() {
        f64::INFINITY
    } else {
        (ours - golden).abs() / golden.abs()
    }
}

/// Exact equality, `NaN` equal to `NaN`.
fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

#[test]
fn pfc_matches_edge_reference() {
    let dir = metrics_fixtures();
    let golden = read_json(&dir.join("outputs/pfc/pfc_edge.json"));
    let mut scores = std::collections::HashMap::new();
    for (name, entry) in golden["per_clip"].as_object().unwrap() {
        let sub = if name.starts_with("gen") {
            "generated"
        } else {
            "real"
        };
        let path = dir.join(format!("inputs/{sub}/{name}_zup_30fps.npy"));
        let (frames, joints) = read_array(&path, &[24, 3]);
        assert_eq!(frames as u64, entry["T"].as_u64().unwrap(), "{name}: T");
        let score = pfc_clip_score(&joints, 24);
        let ours = pfc_from_clip_scores(&[score]);
        let want = number(&entry["value"]);
        let err = rel_err(ours, want);
        println!("PFC {name:<22} ours {ours:<22} reference {want:<22} rel {err:.2e}");
        assert!(err <= REL_TOL, "{name}: PFC {ours} vs {want}");
        assert_eq!(
            score.is_none(),
            want.is_nan(),
            "{name}: None iff reference NaN"
        );
        scores.insert(name.clone(), score);
    }
    for (set, entry) in golden["sets"].as_object().unwrap() {
        let clip_scores: Vec<Option<f64>> = entry["files"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| scores[f.as_str().unwrap()])
            .collect();
        let ours = pfc_from_clip_scores(&clip_scores);
        let want = number(&entry["value"]);
        let err = rel_err(ours, want);
        println!("PFC set {set:<20} ours {ours:<22} reference {want:<22} rel {err:.2e}");
        assert!(err <= REL_TOL, "set {set}: PFC {ours} vs {want}");
    }
    assert!(pfc_clip_score(&[0.0; 2 * 24 * 3], 24).is_none(), "T < 3");
    assert!(pfc_from_clip_scores(&[]).is_nan(), "empty set");
}

/// Parses `"left_static_num tensor(125)"` from the reference's captured prints.
fn printed_count(entry: &Value, key: &str) -> usize {
    let line = entry["printed"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .find(|l| l.starts_with(key))
        .unwrap_or_else(|| panic!("no {key} in {entry}"));
    let inner = line.split("tensor(").nth(1).unwrap().trim_end_matches(')');
    inner.parse().unwrap()
}

/// Places `(T, 4, 3)` feet `[7, 8, 10, 11]` into a `(T, 12, 3)` skeleton (other joints 0).
fn feet_to_skeleton(frames: usize, feet: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; frames * 12 * 3];
    for t in 0..frames {
        for (k, j) in [7, 8, 10, 11].into_iter().enumerate() {
            let (src, dst) = ((t * 4 + k) * 3, (t * 12 + j) * 3);
            out[dst..dst + 3].copy_from_slice(&feet[src..src + 3]);
        }
    }
    out
}

#[test]
fn foot_skating_matches_lodge_reference_on_grounded_feet() {
    let dir = metrics_fixtures();
    let golden = read_json(&dir.join("outputs/foot_skating/foot_skating_lodge.json"));
    let mut real = Vec::new();
    for (name, entry) in golden.as_object().unwrap() {
        if name.starts_with('_') {
            continue;
        }
        let path = dir.join(format!(
            "outputs/foot_skating/{name}_feet_grounded_lodgefk.npy"
        ));
        let (frames, feet) = read_array(&path, &[4, 3]);
        assert_eq!(frames as u64, entry["T"].as_u64().unwrap(), "{name}: T");
        let r = foot_skating_from_grounded_feet(&feet);
        let (wl, wr) = (number(&entry["left_ratio"]), number(&entry["right_ratio"]));
        println!(
            "foot skating {name:<18} left {}/{} = {} (ref {wl})  right {}/{} = {} (ref {wr})  ratio {}",
            r.left_sliding,
            r.left_contact,
            r.left_ratio,
            r.right_sliding,
            r.right_contact,
            r.right_ratio,
            r.ratio()
        );
        assert!(
            same(r.left_ratio, wl),
            "{name}: left {} vs {wl}",
            r.left_ratio
        );
        assert!(
            same(r.right_ratio, wr),
            "{name}: right {} vs {wr}",
            r.right_ratio
        );
        assert!(same(r.ratio(), number(&entry["ratio"])), "{name}: ratio");
        assert_eq!(
            r.left_contact,
            printed_count(entry, "left_static_num"),
            "{name}"
        );
        assert_eq!(
            r.right_contact,
            printed_count(entry, "right_static_num"),
            "{name}"
        );
        assert_eq!(r.left().is_none(), wl.is_nan(), "{name}: left None iff NaN");

        // Re-grounding already grounded positions must not change anything.
        let again = foot_skating_ratio(&feet_to_skeleton(frames, &feet), 12);
        assert!(
            same(again.left_ratio, wl) && same(again.right_ratio, wr),
            "{name}: regrounded"
        );

        if ["R1", "R2", "R3"].contains(&name.as_str()) {
            real.push(r);
        }
    }
    assert_eq!(real.len(), 3);
    let (l, r, ratio) = mean_foot_skating(&real);
    let want = &golden["_mean_real"];
    for (ours, key) in [(l, "left"), (r, "right"), (ratio, "ratio")] {
        let w = number(&want[key]);
        println!("foot skating mean real {key:<5} ours {ours} reference {w}");
        assert!(rel_err(ours, w) <= 1e-12, "mean {key}: {ours} vs {w}");
    }
}

#[test]
fn foot_skating_positions_match_notreference_reimplementation() {
    let dir = metrics_fixtures();
    let golden = read_json(
        &dir.join("outputs/foot_skating/foot_skating_on_edge_positions_NOTREFERENCE.json"),
    );
    for (name, entry) in golden.as_object().unwrap() {
        let sub = if name.starts_with("gen") {
            "generated"
        } else {
            "real"
        };
        let path = dir.join(format!("inputs/{sub}/{name}_yup_30fps.npy"));
        let (_, joints) = read_array(&path, &[24, 3]);
        let r: FootSkating = foot_skating_ratio(&joints, 24);
        let (wl, wr) = (number(&entry["left_ratio"]), number(&entry["right_ratio"]));
        println!(
            "foot skating (EDGE-FK, not reference) {name:<22} left {} ({wl}) right {} ({wr})",
            r.left_ratio, r.right_ratio
        );
        assert!(same(r.left_ratio, wl) && same(r.right_ratio, wr), "{name}");
        assert_eq!(
            r.left_contact as u64,
            entry["left_contact_frames"].as_u64().unwrap()
        );
        assert_eq!(
            r.right_contact as u64,
            entry["right_contact_frames"].as_u64().unwrap()
        );
    }
}

/// The first `keep` joints of each frame of a `(T, J, 3)` array.
fn first_joints(data: &[f64], num_joints: usize, keep: usize) -> Vec<f64> {
    data.chunks_exact(num_joints * 3)
        .flat_map(|f| f[..keep * 3].iter().copied())
        .collect()
}

#[test]
fn mpjpe_matches_souldance_reference() {
    let dir = metrics_fixtures();
    let golden = read_json(&dir.join("outputs/mpjpe/mpjpe_souldance.json"));
    for (key, entry) in golden.as_object().unwrap() {
        let pair = &entry["pair"];
        let (_, gt_all) = read_array(
            &dir.join("inputs")
                .join(pair["gt"]["file"].as_str().unwrap()),
            &[24, 3],
        );
        let (start, stop) = (
            pair["gt"]["start"].as_u64().unwrap() as usize,
            pair["gt"]["stop"].as_u64().unwrap() as usize,
        );
        let gt = &gt_all[start * 72..stop * 72];
        let (_, pred) = read_array(
            &dir.join("inputs")
                .join(pair["pred"]["file"].as_str().unwrap()),
            &[24, 3],
        );
        let joints = entry["joints"].as_u64().unwrap() as usize;
        let (gt, pred) = (
            first_joints(gt, 24, joints),
            first_joints(&pred, 24, joints),
        );

        let per_pose = mpjpe_per_pose(&gt, &pred, joints);
        let (poses, want) = read_array(
            &dir.join(format!("outputs/mpjpe/{key}_per_pose_f64.npy")),
            &[],
        );
        assert_eq!(per_pose.len(), poses, "{key}: poses");
        let worst = per_pose
            .iter()
            .zip(&want)
            .map(|(&a, &g)| rel_err(a, g))
            .fold(0.0, f64::max);
        let mean = mpjpe_mean(&gt, &pred, joints).unwrap();
        let want_mean = number(&entry["mean_f64"]);
        let err = rel_err(mean, want_mean);
        println!(
            "MPJPE {key:<24} mean {mean:<22} reference {want_mean:<22} rel {err:.2e}, per-pose max rel {worst:.2e}"
        );
        assert!(worst <= REL_TOL, "{key}: per-pose rel {worst}");
        assert!(err <= REL_TOL, "{key}: mean {mean} vs {want_mean}");
    }
    assert!(mpjpe_mean(&[], &[], 24).is_none());
}
