//! Shared helpers for the golden tests: locate `shared/fixtures` (next to the project root) and
//! read `.npy` / `meta.json` files.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// `<project root>/../shared`, where the golden fixtures and real data live.
pub fn shared_dir() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let shared = root.join("../shared");
    assert!(
        shared.is_dir(),
        "tests need ../shared next to the project root (looked in {})",
        shared.display()
    );
    shared
}

pub fn music_fixtures() -> PathBuf {
    shared_dir().join("fixtures/music")
}

/// Reads a numpy array (any numeric dtype, C or Fortran order) as C-order f64 plus its shape.
pub fn read_npy(path: &Path) -> (Vec<f64>, Vec<usize>) {
    let a = dancegen_io::read_npy(path).unwrap_or_else(|e| panic!("{e}"));
    (a.data, a.shape)
}

pub fn read_npy_f32(path: &Path) -> Vec<f32> {
    read_npy(path).0.into_iter().map(|v| v as f32).collect()
}

pub fn read_npy_indices(path: &Path) -> Vec<usize> {
    read_npy(path).0.into_iter().map(|v| v as usize).collect()
}

pub fn read_meta(dir: &Path) -> serde_json::Value {
    let p = dir.join("meta.json");
    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
}

/// All `(key, fps_dir)` pairs of `ref/` (every clip, both frame rates).
pub fn ref_cases() -> Vec<(String, u32, PathBuf)> {
    let base = music_fixtures().join("ref");
    let mut out = Vec::new();
    let mut keys: Vec<_> = std::fs::read_dir(&base)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|k| !k.starts_with('_'))
        .collect();
    keys.sort();
    for k in keys {
        for fps in [30u32, 60] {
            let d = base.join(&k).join(format!("fps{fps}"));
            if d.is_dir() {
                out.push((k.clone(), fps, d));
            }
        }
    }
    out
}

/// The `_stages` cases: exact 2 s inputs with every intermediate.
pub fn stage_cases() -> Vec<(String, u32, PathBuf)> {
    let base = music_fixtures().join("ref/_stages");
    let mut out = Vec::new();
    for k in ["chords", "click_120bpm", "real_spunkyrace"] {
        for fps in [30u32, 60] {
            out.push((k.to_string(), fps, base.join(k).join(format!("fps{fps}"))));
        }
    }
    out
}

/// Maximum absolute difference between two equally long slices.
pub fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len(), "length mismatch");
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// Clip file for a `ref/` key (`real_freezingpoint_ogg` -> `clips/real_freezingpoint.ogg`).
pub fn clip_for_key(key: &str) -> PathBuf {
    let clips = music_fixtures().join("clips");
    for (suffix, ext) in [("_ogg", "ogg"), ("_mp3", "mp3")] {
        if let Some(stem) = key.strip_suffix(suffix) {
            return clips.join(format!("{stem}.{ext}"));
        }
    }
    clips.join(format!("{key}.wav"))
}
