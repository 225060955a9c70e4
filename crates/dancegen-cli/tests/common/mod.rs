//! Helpers shared by the CLI contract tests: run the built `dancegen` binary and find
//! `../shared` next to the project root.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `dancegen` binary under test with `args`. Its models come from this checkout by
/// the source-tree rule (a binary in this tree's build output), never from a user's installed
/// models: `DANCEGEN_MODEL_DIR` is removed and the data folder points at an empty place.
pub fn dancegen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dancegen"))
        .args(args)
        .env_remove("DANCEGEN_MODEL_DIR")
        .env(
            "XDG_DATA_HOME",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-installed-models"),
        )
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

/// Blender (`DANCEGEN_BLENDER`, else `blender` on PATH), for the real-client tests. Without it
/// they say so and pass, unless `DANCEGEN_REQUIRE_BLENDER=1` (`tools/test.sh` sets it after
/// installing Blender), where they fail.
pub fn blender() -> Option<PathBuf> {
    let found = std::env::var_os("DANCEGEN_BLENDER")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|d| d.join("blender"))
                    .find(|p| p.is_file())
            })
        });
    if found.is_none() {
        assert!(
            std::env::var("DANCEGEN_REQUIRE_BLENDER").as_deref() != Ok("1"),
            "DANCEGEN_REQUIRE_BLENDER=1 but no blender on PATH (apt-get install blender \
             python3-numpy, or set DANCEGEN_BLENDER)"
        );
        eprintln!("skipped: no blender on PATH (tools/test.sh installs it)");
    }
    found
}
