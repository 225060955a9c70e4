//! The bundled demo song, compiled into the binary so every command works out of the box.

use std::path::PathBuf;

use dancegen_music::decode::AudioSource;

/// 45 s of "Metal Madness" by Carlos Viola Iborra (Sectoid song pack, MIT-style licence; see
/// NOTICE), re-encoded as OGG/Vorbis q4.
const DEMO_SONG: &[u8] = include_bytes!("../../../assets/demo_metal_madness_45s.ogg");
const DEMO_NAME: &str = "demo_metal_madness_45s.ogg";

/// The song a command should read: the given file, or the demo song.
pub fn song_or_demo(path: Option<&PathBuf>) -> AudioSource {
    match path {
        Some(p) => AudioSource::File(p.clone()),
        None => {
            tracing::info!("no song given: using the bundled demo song ({DEMO_NAME})");
            AudioSource::Bytes {
                name: PathBuf::from(format!("<bundled demo> {DEMO_NAME}")),
                bytes: DEMO_SONG,
            }
        }
    }
}
