//! Golden test: GMR (+ Dist_k), GMC and group MMC against `aioz-ai/GCD` outputs in
//! `shared/fixtures/metrics/outputs/gcd/` (README §4.6). Scenes: `inputs/scenes/<s>_yup_30fps.npy`
//! `(N, 150, 24, 3)`. Tolerance: relative 1e-6 (group kinetic features compared after the
//! reference's float32 cast); measured values are printed with `--nocapture`.

mod common;

use common::metrics_fixtures;
use std::path::Path;

use dancegen_metrics::group::{gmc, gmc_pair, gmr, group_kinetic_features, group_mmc};

const REL_TOL: f64 = 1e-6;

fn rel(a: f64, g: f64) -> f64 {
    if a == g { 0.0 } else { (a - g).abs() / g.abs() }
}

fn load_scene(dir: &Path, name: &str) -> Vec<Vec<f64>> {
    let arr =
        dancegen_io::read_npy(&dir.join(format!("inputs/scenes/{name}_yup_30fps.npy"))).unwrap();
    assert_eq!(&arr.shape[2..], &[24, 3]);
    let per = arr.shape[1] * 72;
    arr.data.chunks(per).map(|c| c.to_vec()).collect()
}

const SCENES: [&str; 8] = [
    "gen_scene1",
    "gen_scene2",
    "gen_scene3",
    "gen_scene4",
    "gt_scene1",
    "gt_scene2",
    "gt_scene3",
    "gt_scene4",
];

#[test]
fn group_metrics_match_gcd() {
    let dir = metrics_fixtures();
    let gold: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("outputs/gcd/gcd_group_metrics.json")).unwrap(),
    )
    .unwrap();
    let beats: Vec<usize> =
        dancegen_io::read_npy(&dir.join("outputs/bas/music_beats_real_freezingpoint_fps30.npy"))
            .unwrap()
            .data
            .iter()
            .map(|&b| b as usize)
            .collect();
    let (mut gt_f, mut gen_f) = (Vec::new(), Vec::new());
    let mut worst = [0.0f64; 3];
    for name in SCENES {
        let scene = load_scene(&dir, name);
        let d: Vec<&[f64]> = scene.iter().map(|v| v.as_slice()).collect();
        let g = &gold["scenes"][name];

        let feat = group_kinetic_features(&d).unwrap();
        let golden =
            dancegen_io::read_npy(&dir.join(format!("outputs/gcd/{name}_group_kinetic.npy")))
                .unwrap()
                .data;
        let f32s: Vec<f64> = feat.iter().map(|&v| f64::from(v as f32)).collect();
        let exact = f32s.iter().zip(&golden).filter(|(a, b)| a == b).count();
        let kr = f32s
            .iter()
            .zip(&golden)
            .map(|(&a, &b)| rel(a, b))
            .fold(0.0, f64::max);
        worst[0] = worst[0].max(kr);

        let v = gmc(&d).unwrap().unwrap();
        let want = g["gmc"].as_f64().unwrap();
        let mut pairs = Vec::new();
        for n1 in 0..d.len() {
            for n2 in n1 + 1..d.len() {
                let (pv, pp) = gmc_pair(d[n1], d[n2]).unwrap().unwrap();
                pairs.push(format!("{pv} {pp}"));
            }
        }
        let golden_pairs: Vec<String> = g["gmc_pairs_printed"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect();
        for (ours, theirs) in pairs.iter().zip(&golden_pairs) {
            let (o, t): (Vec<&str>, Vec<&str>) =
                (ours.split(' ').collect(), theirs.split(' ').collect());
            assert_eq!(o[1], t[1], "{name}: matched-frame count {ours} vs {theirs}");
            let e = rel(o[0].parse().unwrap(), t[0].parse().unwrap());
            assert!(e <= REL_TOL, "{name}: pair {ours} vs {theirs}");
        }
        let ge = if want == 0.0 { v.abs() } else { rel(v, want) };
        worst[1] = worst[1].max(ge);

        let m = group_mmc(&d, &beats).unwrap().unwrap();
        let mw = g["mmc_gcd"].as_f64().unwrap();
        worst[2] = worst[2].max(rel(m, mw));
        println!(
            "{name}: N={} kinetic max rel {kr:.2e} ({exact}/72 f32-exact); GMC {v} (ref {want}, rel {ge:.2e}) pairs {pairs:?}; MMC {m} (ref {mw})",
            d.len()
        );
        assert!(kr <= REL_TOL, "{name}: group kinetic rel {kr}");
        assert!(ge <= REL_TOL, "{name}: GMC {v} vs {want}");
        assert!(rel(m, mw) <= REL_TOL, "{name}: MMC {m} vs {mw}");
        (if name.starts_with("gt") {
            &mut gt_f
        } else {
            &mut gen_f
        })
        .push(f32s);
    }
    let (fid, dist) = gmr(&gt_f, &gen_f);
    let (fw, dw) = (
        gold["gmr"]["GMR_k"].as_f64().unwrap(),
        gold["gmr"]["Dist_k_generated"].as_f64().unwrap(),
    );
    let (fs, _) = gmr(&gen_f, &gt_f);
    let fsw = gold["gmr_swapped_args_for_reference_only"]["value"]
        .as_f64()
        .unwrap();
    println!(
        "GMR {fid} (ref {fw}, rel {:.2e}); Dist_k {dist} (ref {dw}, rel {:.2e}); swapped {fs} (ref {fsw}, rel {:.2e}); worst kinetic/GMC/MMC {worst:?}",
        rel(fid, fw),
        rel(dist, dw),
        rel(fs, fsw)
    );
    assert!(rel(fid, fw) <= REL_TOL);
    assert!(rel(dist, dw) <= REL_TOL);
    assert!(rel(fs, fsw) <= REL_TOL);
}
