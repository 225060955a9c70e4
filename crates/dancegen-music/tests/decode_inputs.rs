//! Decoding: every channel layout and rate a user may have, and every kind of bad file gets a
//! clear error that names the file (never a panic).

mod common;

use std::path::{Path, PathBuf};

use common::*;
use dancegen_music::{MusicError, load};

/// Writes a PCM16 WAV with `channels` interleaved channels.
fn write_wav(path: &Path, rate: u32, channels: u16, frames: &[Vec<f32>]) {
    let n = frames.len();
    let data_len = (n * channels as usize * 2) as u32;
    let mut b = Vec::new();
    b.extend_from_slice(b"RIFF");
    b.extend_from_slice(&(36 + data_len).to_le_bytes());
    b.extend_from_slice(b"WAVEfmt ");
    b.extend_from_slice(&16u32.to_le_bytes());
    b.extend_from_slice(&1u16.to_le_bytes());
    b.extend_from_slice(&channels.to_le_bytes());
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(rate * channels as u32 * 2).to_le_bytes());
    b.extend_from_slice(&(channels * 2).to_le_bytes());
    b.extend_from_slice(&16u16.to_le_bytes());
    b.extend_from_slice(b"data");
    b.extend_from_slice(&data_len.to_le_bytes());
    for f in frames {
        for &s in f {
            b.extend_from_slice(&((s * 32767.0).round() as i16).to_le_bytes());
        }
    }
    std::fs::write(path, b).unwrap();
}

fn sine(rate: u32, secs: f32, hz: f32, channels: usize) -> Vec<Vec<f32>> {
    let n = (rate as f32 * secs) as usize;
    (0..n)
        .map(|i| {
            let v = 0.5 * (2.0 * std::f32::consts::PI * hz * i as f32 / rate as f32).sin();
            vec![v; channels]
        })
        .collect()
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn channel_layouts_and_rates_load() {
    let dir = tmp();
    for (name, rate, ch) in [
        ("mono_8k.wav", 8000u32, 1u16),
        ("stereo_44k.wav", 44100, 2),
        ("surround51_48k.wav", 48000, 6),
        ("stereo_192k.wav", 192_000, 2),
    ] {
        let p = dir.path().join(name);
        write_wav(&p, rate, ch, &sine(rate, 2.0, 440.0, ch as usize));
        let a = load(&p, 15360).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(a.native_rate, rate, "{name}");
        assert_eq!(
            a.samples.len(),
            (2.0f64 * 15360.0).ceil() as usize,
            "{name}"
        );
        // All channels carry the same sine, so the mono mix keeps amplitude 0.5 (±resampler ripple).
        let peak = a.samples[1000..29000]
            .iter()
            .fold(0f32, |m, v| m.max(v.abs()));
        assert!((peak - 0.5).abs() < 0.01, "{name}: peak {peak}");
    }
}

#[test]
fn channel_mean_is_the_mono_mix() {
    let dir = tmp();
    let p = dir.path().join("lr.wav");
    // Left +0.5, right -0.25 constant: mean 0.125 (librosa averages channels).
    let frames: Vec<Vec<f32>> = (0..15360).map(|_| vec![0.5, -0.25]).collect();
    write_wav(&p, 15360, 2, &frames);
    let a = load(&p, 15360).unwrap();
    let want =
        ((0.5f32 * 32767.0).round() / 32768.0 + (-0.25f32 * 32767.0).round() / 32768.0) / 2.0;
    assert!(a.samples.iter().all(|&v| (v - want).abs() < 1e-7));
}

fn expect_error(path: &Path, what: &str) -> MusicError {
    let e = load(path, 15360).expect_err(what);
    let msg = e.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "{what}: message does not name the file: {msg}"
    );
    println!("{what}: {msg}");
    e
}

#[test]
fn bad_inputs_are_clear_errors() {
    let dir = tmp();
    let missing = dir.path().join("no_such_song.mp3");
    assert!(matches!(
        expect_error(&missing, "missing"),
        MusicError::Open { .. }
    ));

    let empty = dir.path().join("empty.wav");
    std::fs::write(&empty, b"").unwrap();
    assert!(matches!(
        expect_error(&empty, "zero-length"),
        MusicError::EmptyFile { .. }
    ));

    let garbage = dir.path().join("garbage.ogg");
    let noise: Vec<u8> = (0..5000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    std::fs::write(&garbage, &noise).unwrap();
    expect_error(&garbage, "corrupt header");

    let bad_header = dir.path().join("bad_header.wav");
    let mut b = b"RIFF\x24\x00\x00\x00WAVEfmt ".to_vec();
    b.extend_from_slice(&noise[..200]);
    std::fs::write(&bad_header, &b).unwrap();
    expect_error(&bad_header, "corrupt WAV header");

    // A WAV whose format tag names a codec we do not decode (0x2000 = AC-3).
    let odd = dir.path().join("ac3_in_wav.wav");
    let mut b = Vec::new();
    b.extend_from_slice(b"RIFF");
    b.extend_from_slice(&(36u32 + 400).to_le_bytes());
    b.extend_from_slice(b"WAVEfmt ");
    b.extend_from_slice(&16u32.to_le_bytes());
    b.extend_from_slice(&0x2000u16.to_le_bytes());
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&48000u32.to_le_bytes());
    b.extend_from_slice(&(48000u32 * 4).to_le_bytes());
    b.extend_from_slice(&4u16.to_le_bytes());
    b.extend_from_slice(&16u16.to_le_bytes());
    b.extend_from_slice(b"data");
    b.extend_from_slice(&400u32.to_le_bytes());
    b.extend_from_slice(&[0u8; 400]);
    std::fs::write(&odd, &b).unwrap();
    assert!(matches!(
        expect_error(&odd, "unknown codec"),
        MusicError::UnsupportedCodec { .. }
    ));
}

fn truncated_copy(src: &Path, dir: &Path, keep: f64) -> PathBuf {
    let bytes = std::fs::read(src).unwrap();
    let n = (bytes.len() as f64 * keep) as usize;
    let dst = dir.join(format!(
        "truncated_{}",
        src.file_name().unwrap().to_string_lossy()
    ));
    std::fs::write(&dst, &bytes[..n]).unwrap();
    dst
}

#[test]
fn truncated_files_are_reported() {
    let dir = tmp();
    let clips = music_fixtures().join("clips");
    for name in [
        "real_freezingpoint.mp3",
        "real_freezingpoint.ogg",
        "real_freezingpoint.wav",
    ] {
        let t = truncated_copy(&clips.join(name), dir.path(), 0.47);
        let e = expect_error(&t, &format!("truncated {name}"));
        assert!(
            matches!(e, MusicError::Truncated { .. }),
            "{name}: expected a truncation error, got {e}"
        );
    }
}

#[test]
fn silence_gives_no_samples_error_only_when_empty() {
    // Digital silence is valid audio (features of silence are defined: tempo 0, no beats).
    let a = load(&music_fixtures().join("clips/silence.wav"), 15360).unwrap();
    assert!(a.samples.iter().all(|&v| v == 0.0));
}
