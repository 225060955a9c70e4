//! Arbitrary bytes as a song → `dancegen_music::decode::MonoDecoder` (symphonia behind our
//! wrapper: WAV, Ogg Vorbis, MP3, FLAC). The first byte picks the format hint (the upload's
//! file extension), the rest is the file. `Ok`/`Err`, never a panic or a hang; decoding stops
//! after 4 M samples (a few minutes of audio) so that one input stays fast.
#![no_main]

use std::path::PathBuf;
use std::sync::Arc;

use dancegen_music::decode::{AudioSource, MonoDecoder};
use libfuzzer_sys::fuzz_target;

const EXTENSIONS: [&str; 5] = ["wav", "ogg", "mp3", "flac", "bin"];
const MAX_SAMPLES: usize = 4 << 20;

fuzz_target!(|data: &[u8]| {
    let Some((&hint, file)) = data.split_first() else {
        return;
    };
    let ext = EXTENSIONS[hint as usize % EXTENSIONS.len()];
    let source = AudioSource::Bytes {
        name: PathBuf::from(format!("upload.{ext}")),
        bytes: Arc::from(file),
    };
    let Ok(mut decoder) = MonoDecoder::open_source(&source) else {
        return;
    };
    assert!(decoder.sample_rate() > 0, "an opened song has a sample rate");
    let mut block = Vec::new();
    let mut total = 0;
    while total < MAX_SAMPLES {
        match decoder.next_block(&mut block) {
            Ok(true) => {
                assert!(block.iter().all(|v| v.is_finite()), "decoded samples are finite");
                total += block.len();
            }
            Ok(false) | Err(_) => break,
        }
    }
});
