//! The Khronos glTF validator (npm `gltf-validator`, run by `tests/gltf_validate.mjs`), installed
//! once per test binary into the target directory.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

use serde_json::Value;

/// Pinned: the package only publishes 2.0.0-dev pre-releases, which `@2` does not match.
pub const VALIDATOR_PACKAGE: &str = "gltf-validator@2.0.0-dev.3.10";

/// Installs the validator once per test binary and returns its npm prefix.
pub fn validator_prefix() -> PathBuf {
    static LOCK: Mutex<()> = Mutex::new(());
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let prefix = Path::new(env!("CARGO_TARGET_TMPDIR")).join("gltf-validator");
    let installed = prefix.join("node_modules/gltf-validator/package.json");
    if !installed.is_file() {
        std::fs::create_dir_all(&prefix).unwrap();
        let out = Command::new("npm")
            .args(["install", "--no-audit", "--no-fund", "--prefix"])
            .arg(&prefix)
            .arg(VALIDATOR_PACKAGE)
            .output()
            .unwrap_or_else(|e| {
                panic!("the glTF validator test needs npm (Node.js) on the PATH: {e}")
            });
        assert!(
            out.status.success() && installed.is_file(),
            "`npm install {VALIDATOR_PACKAGE}` into {} failed (is the npm registry reachable?):\n{}",
            prefix.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    prefix
}

/// Runs the Khronos validator on `path`, prints the issue counts and messages and returns the
/// report.
pub fn validate(path: &Path) -> Value {
    let prefix = validator_prefix();
    // From the crate under test: `dancegen-formats` and `dancegen-character` share this helper.
    let script =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../dancegen-formats/tests/gltf_validate.mjs");
    let out = Command::new("node")
        .arg(&script)
        .arg(&prefix)
        .arg(path)
        .output()
        .unwrap_or_else(|e| panic!("the glTF validator test needs node on the PATH: {e}"));
    assert!(
        out.status.success(),
        "validator script failed on {}:\n{}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).expect("validator prints JSON");
    let issues = &report["issues"];
    eprintln!(
        "{}: validator {}: {} errors, {} warnings, {} infos, {} hints",
        path.display(),
        report["validatorVersion"],
        issues["numErrors"],
        issues["numWarnings"],
        issues["numInfos"],
        issues["numHints"]
    );
    for m in issues["messages"].as_array().into_iter().flatten() {
        eprintln!(
            "  [{}] {} {}: {}",
            m["severity"], m["code"], m["pointer"], m["message"]
        );
    }
    report
}
