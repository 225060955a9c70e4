//! Locate `../shared` next to the project root.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub fn shared_dir() -> PathBuf {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    assert!(
        shared.is_dir(),
        "tests need ../shared next to the project root (looked in {})",
        shared.display()
    );
    shared
}
pub mod gltf_validator;
