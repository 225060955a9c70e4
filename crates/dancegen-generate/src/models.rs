//! Where models are found, listed and installed.
//!
//! A model is a folder holding `model.toml` (its `kind` says which system runs it) and its
//! weights. The binary does not embed models, so they can be updated and added on their own.
//! `--model DIR` names one model folder; otherwise the system's default model is looked up by
//! name in these folders of model folders, first match wins:
//!
//! 1. every folder in `DANCEGEN_MODEL_DIR` (a path list, `:`-separated on Unix);
//! 2. next to the binary: `<bin>/../share/dancegen/models` (a packaged install such as
//!    `/usr/bin` + `/usr/share`) and `<bin>/models` (an unpacked archive);
//! 3. the platform data folder (`$XDG_DATA_HOME/dancegen/models`, by default
//!    `~/.local/share/dancegen/models` on Linux), where `dancegen models install` copies them;
//! 4. the source tree's `models/`, only for a binary that runs from that tree's `target/`
//!    (or from the `CARGO_TARGET_DIR` it was built with), so `cargo run` works in a checkout
//!    and a copied or installed binary never silently depends on one.

use std::path::{Path, PathBuf};

/// Environment variable with extra folders of models, searched first.
pub const MODEL_DIR_ENV: &str = "DANCEGEN_MODEL_DIR";

/// The file that makes a folder a model.
pub const MODEL_TOML: &str = "model.toml";

/// Why a folder is on the search path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// From `DANCEGEN_MODEL_DIR`.
    EnvVar,
    /// Next to the running binary.
    BesideBinary,
    /// The platform data folder.
    DataDir,
    /// The source tree the binary was built from.
    SourceTree,
    /// Given by the caller.
    Explicit,
}

impl Origin {
    pub fn describe(self) -> &'static str {
        match self {
            Origin::EnvVar => MODEL_DIR_ENV,
            Origin::BesideBinary => "next to the binary",
            Origin::DataDir => "data folder",
            Origin::SourceTree => "source tree",
            Origin::Explicit => "given",
        }
    }
}

/// One folder of model folders.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SearchDir {
    pub dir: PathBuf,
    pub origin: Origin,
}

/// A model folder found on the search path.
#[derive(Clone, Debug)]
pub struct FoundModel {
    /// The folder's name (what `DEFAULT_MODEL` and `--model` refer to).
    pub name: String,
    /// `kind` from its `model.toml` (`lodgepp`, `reactdance`), if readable.
    pub kind: Option<String>,
    pub dir: PathBuf,
    pub origin: Origin,
    /// An earlier folder on the path has a model of the same name, which wins.
    pub shadowed: bool,
}

/// No model of that name anywhere on the search path.
#[derive(Debug, thiserror::Error)]
#[error("{}", self.message())]
pub struct ModelNotFound {
    pub name: String,
    pub system: String,
    pub looked_in: Vec<SearchDir>,
}

impl ModelNotFound {
    fn message(&self) -> String {
        let mut s = format!(
            "no '{}' model (the {} system's default) was found; looked in:",
            self.name, self.system
        );
        if self.looked_in.is_empty() {
            s.push_str("\n  (no folder: DANCEGEN_MODEL_DIR is unset and no data folder is known)");
        }
        for d in &self.looked_in {
            s.push_str(&format!(
                "\n  {} ({})",
                d.dir.join(&self.name).display(),
                d.origin.describe()
            ));
        }
        s.push_str(&format!(
            "\nfix: install the models with `dancegen models install --from CHECKOUT/models`, \
             or set {MODEL_DIR_ENV} to a folder that holds {}/, or give --model DIR",
            self.name
        ));
        s
    }
}

/// The ordered folders models are looked for in.
#[derive(Clone, Debug)]
pub struct ModelLocator {
    dirs: Vec<SearchDir>,
}

impl ModelLocator {
    /// The search path of this process (environment, binary location, data folder, source
    /// tree), in order.
    pub fn from_environment() -> Self {
        let mut dirs = Vec::new();
        if let Some(v) = std::env::var_os(MODEL_DIR_ENV) {
            dirs.extend(
                std::env::split_paths(&v)
                    .filter(|p| !p.as_os_str().is_empty())
                    .map(|dir| SearchDir {
                        dir,
                        origin: Origin::EnvVar,
                    }),
            );
        }
        let exe = std::env::current_exe()
            .ok()
            .and_then(|e| e.canonicalize().ok());
        if let Some(bin_dir) = exe.as_deref().and_then(Path::parent) {
            let prefix = bin_dir.parent().unwrap_or(bin_dir);
            for dir in [prefix.join("share/dancegen/models"), bin_dir.join("models")] {
                dirs.push(SearchDir {
                    dir,
                    origin: Origin::BesideBinary,
                });
            }
        }
        if let Some(dir) = data_models_dir() {
            dirs.push(SearchDir {
                dir,
                origin: Origin::DataDir,
            });
        }
        if let Some(dir) = exe.as_deref().and_then(source_tree_models_for) {
            dirs.push(SearchDir {
                dir,
                origin: Origin::SourceTree,
            });
        }
        ModelLocator { dirs }
    }

    /// Exactly these folders.
    pub fn new(dirs: Vec<SearchDir>) -> Self {
        ModelLocator { dirs }
    }

    pub fn search_dirs(&self) -> &[SearchDir] {
        &self.dirs
    }

    /// The folder of the model called `name` (`system` is only for the error message).
    pub fn find(&self, name: &str, system: &str) -> Result<PathBuf, ModelNotFound> {
        self.dirs
            .iter()
            .map(|d| d.dir.join(name))
            .find(|m| m.join(MODEL_TOML).is_file())
            .ok_or_else(|| ModelNotFound {
                name: name.to_string(),
                system: system.to_string(),
                looked_in: self.dirs.clone(),
            })
    }

    /// Every model on the search path, in search order (later ones of the same name are
    /// marked shadowed).
    pub fn list(&self) -> Vec<FoundModel> {
        let mut out: Vec<FoundModel> = Vec::new();
        for d in &self.dirs {
            for dir in model_dirs_in(&d.dir) {
                let name = dir
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let shadowed = out.iter().any(|m| m.name == name);
                out.push(FoundModel {
                    kind: model_kind(&dir),
                    name,
                    dir,
                    origin: d.origin,
                    shadowed,
                });
            }
        }
        out
    }
}

/// `<platform data folder>/models` (`$XDG_DATA_HOME/dancegen/models` on Linux).
pub fn data_models_dir() -> Option<PathBuf> {
    directories::ProjectDirs::from("", "", "dancegen").map(|p| p.data_dir().join("models"))
}

/// The source tree's `models/` folder this library was compiled in.
fn source_tree_models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

/// The source tree's models, if `exe` runs from that tree's build output.
fn source_tree_models_for(exe: &Path) -> Option<PathBuf> {
    let models = source_tree_models().canonicalize().ok()?;
    let tree = models.parent()?;
    let mut targets = vec![tree.join("target")];
    // A build with CARGO_TARGET_DIR set (CI keeps it outside the checkout) records it here.
    if let Some(t) = option_env!("CARGO_TARGET_DIR") {
        let t = Path::new(t);
        targets.push(if t.is_absolute() {
            t.to_path_buf()
        } else {
            tree.join(t)
        });
    }
    targets
        .iter()
        .filter_map(|t| t.canonicalize().ok())
        .any(|t| exe.starts_with(&t))
        .then_some(models)
}

/// The `models/` folder of the checkout this library was built from, if it is still there:
/// the default of `dancegen models install --from` (so `cargo install --path
/// crates/dancegen-cli && dancegen models install` works from a checkout). Generation itself
/// only looks there for a binary running from that tree's build output.
pub fn checkout_models() -> Option<PathBuf> {
    let models = source_tree_models().canonicalize().ok()?;
    models.is_dir().then_some(models)
}

/// The model folders directly inside `dir` (sorted by name; none if `dir` is missing).
pub fn model_dirs_in(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join(MODEL_TOML).is_file())
        .collect();
    v.sort();
    v
}

/// `kind` from a model folder's `model.toml`.
pub fn model_kind(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join(MODEL_TOML)).ok()?;
    let table: toml::Table = toml::from_str(&text).ok()?;
    table.get("kind")?.as_str().map(str::to_string)
}

/// A model copied by [`install`].
#[derive(Clone, Debug)]
pub struct Installed {
    pub name: String,
    pub dir: PathBuf,
    /// It replaced a model of the same name.
    pub replaced: bool,
}

/// Why [`install`] failed (names the folder).
#[derive(Debug, thiserror::Error)]
#[error("{}: {reason}", path.display())]
pub struct InstallError {
    pub path: PathBuf,
    pub reason: String,
}

/// Copies every model folder in `from` (or `from` itself if it is a model folder) into `to`.
///
/// Each model is copied into a hidden folder inside `to` and renamed into place, so an
/// interrupted install never leaves half a model under the real name; a model of the same
/// name is replaced only once the new copy is complete.
pub fn install(from: &Path, to: &Path) -> Result<Vec<Installed>, InstallError> {
    let fail = |path: &Path, reason: String| InstallError {
        path: path.to_path_buf(),
        reason,
    };
    let sources = if from.join(MODEL_TOML).is_file() {
        vec![from.to_path_buf()]
    } else {
        model_dirs_in(from)
    };
    if sources.is_empty() {
        return Err(fail(
            from,
            format!("no model folders here (a model folder holds {MODEL_TOML})"),
        ));
    }
    std::fs::create_dir_all(to).map_err(|e| fail(to, format!("cannot create it: {e}")))?;
    let mut done = Vec::new();
    for src in sources {
        let name = src
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| fail(&src, "not a folder name".into()))?;
        let staging = tempfile::Builder::new()
            .prefix(&format!(".{name}.installing-"))
            .tempdir_in(to)
            .map_err(|e| fail(to, e.to_string()))?;
        copy_tree(&src, staging.path())?;
        let dest = to.join(&name);
        let replaced = dest.exists();
        if replaced {
            // Move the old copy aside first: a rename onto a non-empty folder fails.
            let old = tempfile::Builder::new()
                .prefix(&format!(".{name}.old-"))
                .tempdir_in(to)
                .map_err(|e| fail(to, e.to_string()))?;
            let aside = old.path().join(&name);
            std::fs::rename(&dest, &aside).map_err(|e| fail(&dest, e.to_string()))?;
            std::fs::rename(staging.path(), &dest).map_err(|e| fail(&dest, e.to_string()))?;
            drop(old);
        } else {
            std::fs::rename(staging.path(), &dest).map_err(|e| fail(&dest, e.to_string()))?;
        }
        // `staging` was renamed away: dropping its guard finds nothing left to remove.
        drop(staging);
        done.push(Installed {
            name,
            dir: dest,
            replaced,
        });
    }
    Ok(done)
}

fn copy_tree(from: &Path, to: &Path) -> Result<(), InstallError> {
    let fail = |path: &Path, e: std::io::Error| InstallError {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    std::fs::create_dir_all(to).map_err(|e| fail(to, e))?;
    for entry in std::fs::read_dir(from).map_err(|e| fail(from, e))? {
        let entry = entry.map_err(|e| fail(from, e))?;
        let src = entry.path();
        let dst = to.join(entry.file_name());
        let ty = entry.file_type().map_err(|e| fail(&src, e))?;
        if ty.is_dir() {
            copy_tree(&src, &dst)?;
        } else {
            std::fs::copy(&src, &dst).map_err(|e| fail(&src, e))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fake_model(root: &Path, name: &str, kind: &str) -> PathBuf {
        let d = root.join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join(MODEL_TOML), format!("kind = \"{kind}\"\n")).unwrap();
        std::fs::write(d.join("w.safetensors"), b"weights").unwrap();
        d
    }

    #[test]
    fn first_folder_wins_and_later_ones_are_shadowed() {
        let a = tempfile::tempdir().unwrap();
        let b = tempfile::tempdir().unwrap();
        fake_model(a.path(), "m", "lodgepp");
        fake_model(b.path(), "m", "lodgepp");
        fake_model(b.path(), "n", "reactdance");
        let loc = ModelLocator::new(vec![
            SearchDir {
                dir: a.path().into(),
                origin: Origin::EnvVar,
            },
            SearchDir {
                dir: b.path().into(),
                origin: Origin::DataDir,
            },
        ]);
        assert_eq!(loc.find("m", "solo").unwrap(), a.path().join("m"));
        assert_eq!(loc.find("n", "duet").unwrap(), b.path().join("n"));
        let list = loc.list();
        assert_eq!(list.len(), 3);
        assert!(!list[0].shadowed && list[1].shadowed && !list[2].shadowed);
        assert_eq!(list[2].kind.as_deref(), Some("reactdance"));
        let e = loc.find("x", "solo").unwrap_err().to_string();
        assert!(e.contains(&a.path().join("x").display().to_string()), "{e}");
        assert!(
            e.contains(MODEL_DIR_ENV) && e.contains("data folder"),
            "{e}"
        );
    }

    #[test]
    fn install_copies_and_replaces_whole_models() {
        let src = tempfile::tempdir().unwrap();
        let dst = tempfile::tempdir().unwrap();
        fake_model(src.path(), "m", "lodgepp");
        std::fs::write(src.path().join("README.md"), b"not a model").unwrap();
        let to = dst.path().join("models");
        let first = install(src.path(), &to).unwrap();
        assert_eq!(first.len(), 1);
        assert!(!first[0].replaced);
        assert_eq!(
            std::fs::read(to.join("m/w.safetensors")).unwrap(),
            b"weights"
        );
        std::fs::write(src.path().join("m/w.safetensors"), b"newer").unwrap();
        let again = install(&src.path().join("m"), &to).unwrap();
        assert!(again[0].replaced);
        assert_eq!(std::fs::read(to.join("m/w.safetensors")).unwrap(), b"newer");
        // Nothing but the model is left in the destination (no staging folders).
        let names: Vec<_> = std::fs::read_dir(&to)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("m")]);
        assert!(install(dst.path().join("none").as_path(), &to).is_err());
    }
}
