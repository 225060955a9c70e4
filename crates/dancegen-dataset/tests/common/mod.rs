//! Locate `../shared` next to the project root; write short WAV files for layout tests.
#![allow(dead_code)]

use std::io::Write;
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

pub fn song(name: &str) -> PathBuf {
    shared_dir().join("data/music/sectoid").join(name)
}

pub fn salsa(name: &str) -> PathBuf {
    shared_dir().join("data/cmu-salsa").join(name)
}

pub fn aistpp_motions() -> PathBuf {
    shared_dir().join("data/aistpp/motions")
}

/// Writes the first `seconds` of a real song as a mono 16-bit PCM WAV at its native rate.
pub fn write_wav_excerpt(src: &Path, seconds: f64, out: &Path) {
    let audio = dancegen_music::load(src, 0).expect("decode the song");
    let sr = audio.sample_rate;
    let n = ((seconds * sr as f64) as usize).min(audio.samples.len());
    let mut bytes = Vec::with_capacity(44 + 2 * n);
    let data_len = (2 * n) as u32;
    bytes.extend_from_slice(b"RIFF");
    bytes.extend_from_slice(&(36 + data_len).to_le_bytes());
    bytes.extend_from_slice(b"WAVEfmt ");
    bytes.extend_from_slice(&16u32.to_le_bytes());
    bytes.extend_from_slice(&1u16.to_le_bytes()); // PCM
    bytes.extend_from_slice(&1u16.to_le_bytes()); // mono
    bytes.extend_from_slice(&sr.to_le_bytes());
    bytes.extend_from_slice(&(sr * 2).to_le_bytes());
    bytes.extend_from_slice(&2u16.to_le_bytes());
    bytes.extend_from_slice(&16u16.to_le_bytes());
    bytes.extend_from_slice(b"data");
    bytes.extend_from_slice(&data_len.to_le_bytes());
    for &x in &audio.samples[..n] {
        let v = (x.clamp(-1.0, 1.0) * 32767.0).round() as i16;
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::File::create(out)
        .and_then(|mut f| f.write_all(&bytes))
        .expect("write wav");
}
