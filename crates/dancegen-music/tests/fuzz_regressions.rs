//! Inputs the `fuzz/` targets found, each kept as a test so the bug stays fixed.

use std::path::Path;
use std::sync::Arc;

use dancegen_music::decode::{AudioSource, MonoDecoder, decode_mono};

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/fuzz")
        .join(name)
}

/// `audio` target, 2026-12-07: a 92-byte WAV whose `fmt ` chunk declares 35,329 channels made
/// symphonia-format-riff 0.6.1 overflow a 16-bit multiply and panic (dev and test builds). It
/// must be refused as the file's error, from a file and from an upload's bytes alike.
#[test]
fn wav_with_an_absurd_channel_count_is_an_error_naming_the_file() {
    let path = fixture("audio_riff_fmt_multiply_overflow.wav");
    let err = decode_mono(&path).unwrap_err().to_string();
    assert!(
        err.contains("audio_riff_fmt_multiply_overflow.wav"),
        "{err}"
    );
    assert!(err.contains("35329 channels"), "{err}");

    let bytes: Arc<[u8]> = std::fs::read(&path).unwrap().into();
    let upload = AudioSource::Bytes {
        name: "upload.wav".into(),
        bytes,
    };
    let err = MonoDecoder::open_source(&upload).err().unwrap().to_string();
    assert!(
        err.starts_with("upload.wav:") && err.contains("35329 channels"),
        "{err}"
    );
}
