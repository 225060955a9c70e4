//! Golden test: kinetic and manual features against the reference outputs in
//! `shared/fixtures/metrics/outputs/features/` (README §4.1: `google/aistplusplus_api`
//! `extract_kinetic_features` / `extract_manual_features` with default arguments — kinetic
//! `frame_time = 1/60` and manual `1/120` also for the 30-fps files; `kinetic_zerostart` after
//! Bailando's frame-0 root subtraction; `kinetic_accelfixed_NOTREFERENCE` with the GCD fix).
//!
//! Tolerance: the golden files are the float32 cast of float64 reference results, so the only
//! expected difference is that cast (relative ≤ 2^-24 ≈ 6e-8); we require relative error ≤ 1e-6
//! (`|ours − golden| ≤ 1e-6·|golden|`, i.e. exact zero where the golden value is 0). Manual
//! features are counts of boolean predicates divided by `T − 1` in float32 and must match
//! exactly.

mod common;

use common::metrics_fixtures;
use std::path::Path;

use dancegen_metrics::kinetic::REFERENCE_FRAME_TIME;
use dancegen_metrics::{
    KineticVariant, kinetic_features, manual_features, read_joints, zero_start,
};

const REL_TOL: f64 = 1e-6;

fn read_golden(path: &Path) -> Vec<f64> {
    dancegen_io::read_npy(path)
        .unwrap_or_else(|e| panic!("{e}"))
        .data
}

/// Max relative error (`|a − g| / |g|`, infinite if `g = 0 ≠ a`) and its index.
fn max_rel(ours: &[f64], golden: &[f64]) -> (f64, usize) {
    assert_eq!(ours.len(), golden.len());
    let mut worst = (0.0, 0);
    for (i, (&a, &g)) in ours.iter().zip(golden).enumerate() {
        let e = if a == g {
            0.0
        } else if g == 0.0 {
            f64::INFINITY
        } else {
            (a - g).abs() / g.abs()
        };
        if e > worst.0 {
            worst = (e, i);
        }
    }
    worst
}

#[test]
fn features_match_reference_golden_files() {
    let dir = metrics_fixtures();
    let feat_dir = dir.join("outputs/features");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(feat_dir.join("_summary.json")).unwrap())
            .unwrap();
    let names: Vec<&String> = summary.as_object().unwrap().keys().collect();
    assert_eq!(names.len(), 22);

    let mut failures = Vec::new();
    let mut worst_by_kind = [0.0f64; 3];
    let mut f32_exact = [0usize; 3];
    for name in names {
        let input = ["real", "generated"]
            .iter()
            .map(|d| dir.join("inputs").join(d).join(format!("{name}.npy")))
            .find(|p| p.is_file())
            .unwrap_or_else(|| panic!("no input for {name}"));
        let joints = read_joints(&input).unwrap();
        let frames = joints.len() / 72;
        assert_eq!(
            summary[name.as_str()]["T"].as_u64(),
            Some(frames as u64),
            "{name}: frame count"
        );

        let kinds: [(&str, Vec<f64>); 3] = [
            (
                "kinetic",
                kinetic_features(&joints, REFERENCE_FRAME_TIME, KineticVariant::Reference).to_vec(),
            ),
            (
                "kinetic_zerostart",
                kinetic_features(
                    &zero_start(&joints),
                    REFERENCE_FRAME_TIME,
                    KineticVariant::Reference,
                )
                .to_vec(),
            ),
            (
                "kinetic_accelfixed_NOTREFERENCE",
                kinetic_features(&joints, REFERENCE_FRAME_TIME, KineticVariant::AccelFixed)
                    .to_vec(),
            ),
        ];
        let mut line = format!("{name:28}");
        for (k, (kind, ours)) in kinds.iter().enumerate() {
            let golden = read_golden(&feat_dir.join(format!("{name}.{kind}.npy")));
            let (err, at) = max_rel(ours, &golden);
            worst_by_kind[k] = worst_by_kind[k].max(err);
            // Informative: entries whose float32 cast is bit-identical to the golden value.
            f32_exact[k] += ours
                .iter()
                .zip(&golden)
                .filter(|&(&a, &g)| a as f32 == g as f32)
                .count();
            line += &format!(" {kind}: {err:.2e}@{at}");
            if err > REL_TOL {
                failures.push(format!(
                    "{name}.{kind}[{at}]: ours {} golden {} rel {err:.3e}",
                    ours[at], golden[at]
                ));
            }
        }

        let ours = manual_features(&joints);
        let golden = read_golden(&feat_dir.join(format!("{name}.manual.npy")));
        let mismatched: Vec<usize> = (0..32).filter(|&i| ours[i] != golden[i]).collect();
        let nonzero = ours.iter().filter(|&&v| v != 0.0).count() as u64;
        line += &format!(
            " manual: {} mismatched, {nonzero} nonzero",
            mismatched.len()
        );
        if summary[name.as_str()]["manual_nonzero"].as_u64() != Some(nonzero) {
            failures.push(format!("{name}.manual: nonzero count {nonzero}"));
        }
        for i in mismatched {
            failures.push(format!(
                "{name}.manual[{i}]: ours {} golden {} (count {} vs {})",
                ours[i],
                golden[i],
                ours[i] * (frames - 1) as f64,
                golden[i] * (frames - 1) as f64
            ));
        }
        println!("{line}");
    }
    println!(
        "max relative error: kinetic {:.3e}, kinetic_zerostart {:.3e}, accelfixed {:.3e}",
        worst_by_kind[0], worst_by_kind[1], worst_by_kind[2]
    );
    println!(
        "float32-identical entries of 22 x 72: kinetic {}, zerostart {}, accelfixed {}",
        f32_exact[0], f32_exact[1], f32_exact[2]
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
