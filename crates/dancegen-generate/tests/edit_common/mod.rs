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
