//! A job's folder, `DATA_DIR/jobs/<id>/`: the uploaded song (and leader) and every output.
//!
//! Names from a URL are only ever looked up among the folder's own files: anything that could
//! leave the folder (separators, `..`, hidden names, links) is "not found".

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// `jobs/` under the data dir.
pub fn jobs_dir(data_dir: &Path) -> PathBuf {
    data_dir.join("jobs")
}

/// Whether `id` looks like one of ours (so it can be joined to a path safely).
pub fn valid_id(id: &str) -> bool {
    !id.is_empty() && id.len() <= 64 && id.bytes().all(|b| b.is_ascii_alphanumeric())
}

/// Bytes of the regular files under `dir`, at any depth (links are not followed; unreadable
/// entries count as 0): what `--max-disk-gb` measures.
pub fn dir_bytes(dir: &Path) -> u64 {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => dir_bytes(&e.path()),
            Ok(t) if t.is_file() => e.metadata().map_or(0, |m| m.len()),
            _ => 0,
        })
        .sum()
}

/// Whether `name` names a file directly inside a folder, and a visible one.
pub fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 128
        && !name.starts_with('.')
        && !name.contains(['/', '\\', '\0', ':'])
}

/// The regular file `name` of the job folder `dir`, if it is one (links are refused).
pub fn resolve(dir: &Path, name: &str) -> Option<PathBuf> {
    if !valid_name(name) {
        return None;
    }
    let path = dir.join(name);
    let meta = std::fs::symlink_metadata(&path).ok()?;
    meta.file_type().is_file().then_some(path)
}

/// The visible regular files of `dir` (staging folders and temporary files are hidden).
pub fn list(dir: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut names: Vec<String> = entries
        .flatten()
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| valid_name(n))
        .collect();
    names.sort();
    names
}

/// URL of file `name` of job `id`.
pub fn url(id: &str, name: &str) -> String {
    format!("/api/jobs/{id}/files/{name}")
}

/// Every file of job `id` as name → URL.
pub fn urls(id: &str, dir: &Path) -> BTreeMap<String, String> {
    list(dir)
        .into_iter()
        .map(|n| {
            let u = url(id, &n);
            (n, u)
        })
        .collect()
}

/// Removes what a killed job may have left in its folder: the generation library's hidden
/// staging folders and temporary files (outputs are renamed into place only when complete).
pub fn clean_staging(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        if name.to_string_lossy().starts_with(".dancegen-") {
            let p = e.path();
            let _ = if p.is_dir() {
                std::fs::remove_dir_all(&p)
            } else {
                std::fs::remove_file(&p)
            };
        }
    }
}

/// A safe file extension from an uploaded file name (lowercase ASCII letters and digits, at
/// most 5), used as the decoder's format hint.
pub fn extension_of(upload_name: &str) -> Option<String> {
    let ext = Path::new(upload_name).extension()?.to_str()?;
    let ext = ext.to_ascii_lowercase();
    (!ext.is_empty() && ext.len() <= 5 && ext.bytes().all(|b| b.is_ascii_alphanumeric()))
        .then_some(ext)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_leave_the_folder_are_not_found() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("dance.glb"), b"x").unwrap();
        std::fs::create_dir(dir.path().join(".dancegen-x")).unwrap();
        assert!(resolve(dir.path(), "dance.glb").is_some());
        for bad in [
            "../dance.glb",
            "..",
            ".",
            "",
            "a/b",
            "a\\b",
            ".dancegen-x",
            "/etc/passwd",
        ] {
            assert!(resolve(dir.path(), bad).is_none(), "{bad}");
        }
        assert_eq!(list(dir.path()), vec!["dance.glb".to_string()]);
        clean_staging(dir.path());
        assert!(!dir.path().join(".dancegen-x").exists());
        assert!(!valid_id("../x") && valid_id("a1B2"));
        assert_eq!(extension_of("My Song.MP3").as_deref(), Some("mp3"));
        assert_eq!(extension_of("song.o/g"), None);
    }
}
