//! Helpers shared by the CLI contract tests: run the built `dancegen` binary and find
//! `../shared` next to the project root.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `dancegen` binary under test with `args`.
pub fn dancegen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dancegen"))
        .args(args)
        .output()
        .expect("run dancegen")
}

/// `<project root>/../shared`.
pub fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts the command succeeded, showing its stderr otherwise.
pub fn ok(o: &Output) {
    assert!(o.status.success(), "{}", stderr(o));
}
