//! Golden test: Duolando duet metrics against `shared/fixtures/metrics/outputs/duolando/`
//! (README §4.8; `lisiyao21/Duolando:utils/metrics_duet.py`, anchors A.10).
//!
//! Inputs: `inputs/duets/<name>_{follower,leader}_smpl24_yup_30fps.npy`, expanded by the
//! reference glue to 55 SMPL-X joints (`manifest.json: smplx55_from_smpl24_index`, our
//! [`SMPLX55_FROM_SMPL24`]). Checks:
//! - the 100-d cross-distance feature of each pair vs `{gt,pred}/duet_features/<name>_00.npy`
//!   (float64 in the reference): relative 1e-12 per entry (measured max 1.2e-15);
//! - FID_cd, Div_cd, Div_cd(GT) vs `quantized_metrics` (real part): relative 1e-6 — computed from
//!   our features and from the stored features. Measured: Div exact to 4e-16; FID_cd 1.3e-7
//!   relative (8e-6 absolute) — the reference's Schur `sqrtm` trace on the rank ≤ 3 covariance
//!   product vs our exact `Σ√λ` (same effect as README §4.2; ours-vs-stored features, equal to
//!   1e-15, already move our FID by 7e-9 relative, so the term is ill-conditioned);
//! - per pair: follower and leader motion beats identical, BED relative 1e-12; the set means of
//!   BED relative 1e-12 (measured: per pair bit-identical, means 1.3e-16).

mod common;

use common::metrics_fixtures;
use std::path::Path;

use dancegen_metrics::duet::{
    SMPLX55_FROM_SMPL24, beat_echo_degree, cross_distance_feature, duet_fid_div, duet_motion_beats,
};
use dancegen_metrics::read_joints;

const REL_TOL: f64 = 1e-6;
const TIGHT: f64 = 1e-12;

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn rel(a: f64, g: f64) -> f64 {
    if a == g { 0.0 } else { (a - g).abs() / g.abs() }
}

const GT: [&str; 4] = ["gt_duet1", "gt_duet2", "gt_duet3", "gt_duet4"];
const GEN: [&str; 4] = ["gen_duet1", "gen_duet2", "gen_duet3", "gen_duet4"];

fn pair(name: &str) -> (Vec<f64>, Vec<f64>) {
    let dir = metrics_fixtures().join("inputs/duets");
    let f = read_joints(&dir.join(format!("{name}_follower_smpl24_yup_30fps.npy"))).unwrap();
    let l = read_joints(&dir.join(format!("{name}_leader_smpl24_yup_30fps.npy"))).unwrap();
    (f, l)
}

fn stored_feature(name: &str) -> Vec<f64> {
    let set = if name.starts_with("gt") { "gt" } else { "pred" };
    let path = metrics_fixtures().join(format!(
        "outputs/duolando/{set}/duet_features/{name}_00.npy"
    ));
    let arr = dancegen_io::read_npy(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(arr.shape, vec![100], "{}", path.display());
    arr.data
}

#[test]
fn manifest_mapping_matches() {
    let man = read_json(&metrics_fixtures().join("inputs/manifest.json"));
    let idx: Vec<usize> = man["smplx55_from_smpl24_index"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(idx, SMPLX55_FROM_SMPL24.to_vec());
}

#[test]
fn cross_distance_features_and_fid_div() {
    let golden = read_json(&metrics_fixtures().join("outputs/duolando/duolando_duet_metrics.json"));
    let q = &golden["quantized_metrics"];
    let mut worst = 0.0f64;
    let mut ours = |names: &[&str]| -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let mut mine = Vec::new();
        let mut stored = Vec::new();
        for n in names {
            let (f, l) = pair(n);
            let feat = cross_distance_feature(&f, &l).unwrap();
            let want = stored_feature(n);
            for (a, g) in feat.iter().zip(&want) {
                let e = rel(*a, *g);
                worst = worst.max(e);
                assert!(e <= TIGHT, "{n}: feature {a} vs {g}");
            }
            mine.push(feat);
            stored.push(want);
        }
        (mine, stored)
    };
    let (gt, gt_stored) = ours(&GT);
    let (pred, pred_stored) = ours(&GEN);
    println!("cross-distance feature: max relative error {worst:.3e}");
    for (label, g, p) in [("ours", &gt, &pred), ("stored", &gt_stored, &pred_stored)] {
        let s = duet_fid_div(g, p);
        for (what, v, key) in [
            ("FID_cd", s.fid_cd, "fid_k"),
            ("Div_cd", s.div_cd, "div"),
            ("Div_cd(GT)", s.div_cd_gt, "div_gt"),
        ] {
            let want = q[key]["real"].as_f64().unwrap();
            let e = rel(v, want);
            println!("{label} {what}: {v} vs {want} (rel {e:.3e})");
            assert!(e <= REL_TOL, "{label} {what}: {v} vs {want}");
        }
    }
}

#[test]
fn beat_echo_degree_per_pair_and_means() {
    let golden = read_json(&metrics_fixtures().join("outputs/duolando/duolando_duet_metrics.json"));
    let beats = |v: &serde_json::Value| -> Vec<usize> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_u64().unwrap() as usize)
            .collect()
    };
    for (names, key) in [(GT, "bed_mean_gt"), (GEN, "bed_mean_pred")] {
        let mut sum = 0.0;
        for n in names {
            let g = &golden["pairs"][n];
            let (f, l) = pair(n);
            assert_eq!(
                duet_motion_beats(&f).unwrap(),
                beats(&g["follower_beats"]),
                "{n}"
            );
            assert_eq!(
                duet_motion_beats(&l).unwrap(),
                beats(&g["leader_beats"]),
                "{n}"
            );
            let bed = beat_echo_degree(&f, &l).unwrap().unwrap();
            let want = g["bed"].as_f64().unwrap();
            println!("{n}: BED {bed} vs {want} (rel {:.3e})", rel(bed, want));
            assert!(rel(bed, want) <= TIGHT, "{n}: {bed} vs {want}");
            sum += bed;
        }
        let mean = sum / names.len() as f64;
        let want = golden[key].as_f64().unwrap();
        println!("{key}: {mean} vs {want} (rel {:.3e})", rel(mean, want));
        assert!(rel(mean, want) <= TIGHT, "{key}: {mean} vs {want}");
    }
}
