//! Locates `shared/fixtures/metrics` next to the project root.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub fn metrics_fixtures() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = root.join("../shared/fixtures/metrics");
    assert!(
        dir.is_dir(),
        "tests need ../shared/fixtures/metrics next to the project root (looked in {})",
        dir.display()
    );
    dir
}
