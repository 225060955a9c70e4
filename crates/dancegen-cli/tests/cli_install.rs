//! An installed `dancegen` finds its models without the source tree: the test binary is
//! copied into an empty folder outside the checkout, the models are installed the documented
//! way (`dancegen models install --from CHECKOUT/models` into the data folder), and a dance
//! is generated from another empty folder. Without the models the error lists every place
//! looked in and the fix, and writes nothing.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::*;

/// A copy of the binary under test in `root/bin`, run with a private data folder and no
/// `DANCEGEN_MODEL_DIR`, from `root/work`.
struct Installed {
    root: tempfile::TempDir,
}

impl Installed {
    fn new() -> Self {
        let root = tempfile::tempdir().unwrap();
        for d in ["bin", "work", "data", "home"] {
            std::fs::create_dir(root.path().join(d)).unwrap();
        }
        std::fs::copy(
            env!("CARGO_BIN_EXE_dancegen"),
            root.path().join("bin/dancegen"),
        )
        .unwrap();
        Installed { root }
    }

    fn path(&self, p: &str) -> PathBuf {
        self.root.path().join(p)
    }

    fn run(&self, args: &[&str]) -> Output {
        // The other tests of this binary start processes on other threads: a fork made while
        // `std::fs::copy` still held the copy open for writing keeps that descriptor until the
        // child execs, and until then exec'ing the copy fails with ETXTBSY ("text file busy").
        // That window is short, so a few bounded retries end it.
        let mut tries = 0;
        loop {
            let r = Command::new(self.path("bin/dancegen"))
                .args(args)
                .current_dir(self.path("work"))
                .env_remove("DANCEGEN_MODEL_DIR")
                .env("XDG_DATA_HOME", self.path("data"))
                .env("HOME", self.path("home"))
                .output();
            match r {
                Err(e) if e.kind() == std::io::ErrorKind::ExecutableFileBusy && tries < 50 => {
                    tries += 1;
                    std::thread::sleep(std::time::Duration::from_millis(20));
                }
                r => return r.expect("run the copied dancegen"),
            }
        }
    }
}

fn checkout_models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

#[test]
fn a_copied_binary_generates_with_models_installed_the_documented_way() {
    let inst = Installed::new();
    // Nothing yet: `models` says so.
    let o = inst.run(&["models"]);
    assert!(!o.status.success());
    let listing = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(listing.contains("none found"), "{listing}");

    let o = inst.run(&[
        "models",
        "install",
        "--from",
        checkout_models().to_str().unwrap(),
    ]);
    ok(&o);
    let said = String::from_utf8_lossy(&o.stdout).into_owned();
    let data_models = inst.path("data/dancegen/models");
    for name in ["lodgepp-small", "reactdance-small"] {
        assert!(said.contains(name), "{said}");
        assert!(data_models.join(name).join("model.toml").is_file());
    }
    let o = inst.run(&["models", "--json"]);
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let defaults = v["defaults"].as_array().unwrap();
    assert!(
        defaults.iter().all(|d| d["dir"]
            .as_str()
            .is_some_and(|s| s.starts_with(data_models.to_str().unwrap()))),
        "{v}"
    );

    // The demo song, 4 s, a few steps: the file lands in the working folder.
    let o = inst.run(&[
        "-q",
        "generate",
        "--end",
        "4",
        "--steps",
        "3",
        "-o",
        "dance.npy",
    ]);
    ok(&o);
    let a = dancegen_io::read_npy(&inst.path("work/dance.npy")).unwrap();
    assert_eq!(a.shape, vec![120, 24, 3]);
}

#[test]
fn without_models_the_error_lists_where_it_looked() {
    let inst = Installed::new();
    let o = inst.run(&["generate", "--end", "3", "-o", "x.npy"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("looked in"), "{e}");
    // Every folder of the search path: next to the binary (both layouts; the binary's path is
    // resolved) and the data folder.
    let real = inst.root.path().canonicalize().unwrap();
    for place in [
        real.join("share/dancegen/models/lodgepp-small"),
        real.join("bin/models/lodgepp-small"),
        inst.path("data/dancegen/models/lodgepp-small"),
    ] {
        let shown = place.display().to_string();
        assert!(e.contains(&shown), "{shown} missing from: {e}");
    }
    assert!(
        e.contains("DANCEGEN_MODEL_DIR") && e.contains("models install"),
        "{e}"
    );
    assert!(
        !e.contains("source tree"),
        "a copied binary must not use the checkout: {e}"
    );
    assert!(!inst.path("work/x.npy").exists());
    // Pointing DANCEGEN_MODEL_DIR at the checkout's models is the other documented fix.
    let o = Command::new(inst.path("bin/dancegen"))
        .args([
            "-q", "generate", "--end", "3", "--steps", "2", "-o", "x.npy",
        ])
        .current_dir(inst.path("work"))
        .env("DANCEGEN_MODEL_DIR", checkout_models())
        .env("XDG_DATA_HOME", inst.path("data"))
        .output()
        .unwrap();
    ok(&o);
    assert!(inst.path("work/x.npy").is_file());
}
