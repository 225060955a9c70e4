//! What the editing tests (`edits.rs`, `edits_duet.rs`) share: the shared data folder, one
//! generator over the shipped models, world joints, and the real pose spread they compare
//! new parts with.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use dancegen_generate::Generator;
use dancegen_generate::ModelLocator;
use dancegen_generate::models::{Origin, SearchDir};
use dancegen_motion::repr::SmplMotion;

/// Real dancers' pose spread: the held-out real solo tracks at their true rates, 15.8 cm
/// (docs/group-eval.md, "Motion energy", `bash tools/group_eval.sh`). The issue asks a new part
/// to differ from the old one by at least half of it.
pub const REAL_POSE_SPREAD_M: f64 = 0.158;

pub fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// One generator over the shipped models, so each model loads once per test binary.
pub fn generator() -> &'static Generator {
    static G: OnceLock<Generator> = OnceLock::new();
    G.get_or_init(|| {
        Generator::new(ModelLocator::new(vec![SearchDir {
            dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models"),
            origin: Origin::Explicit,
        }]))
    })
}

/// World joints `(T, 24, 3)` as f64, for the metrics.
pub fn joints(m: &SmplMotion) -> Vec<f64> {
    m.joints_world()
        .unwrap()
        .into_iter()
        .map(f64::from)
        .collect()
}

/// The join bounds on `q` (an edit's figures, `what` naming it for messages): a
/// boundary-jerk ratio under 1.5 at the joins, and no root step at a join more than 5 cm beyond
/// the dance's own largest.
#[allow(dead_code)]
pub fn assert_joins(q: &dancegen_metrics::edit::EditQuality, what: &str) {
    let ratio = q.join_jerk_ratio.expect("joins inside the dance");
    assert!(
        ratio < 1.5,
        "{what}: boundary jerk ratio {ratio:.2} at the joins"
    );
    assert!(
        q.join_root_step_m <= q.other_root_step_m + 0.05,
        "{what}: root step {:.3} m at a join against {:.3} m elsewhere",
        q.join_root_step_m,
        q.other_root_step_m
    );
}
