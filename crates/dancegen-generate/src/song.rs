//! The song, analysed once per job: EDGE-35 features and beats at 30 fps over the whole song
//! (every system slices what it dances to from them).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use dancegen_music::decode::AudioSource;
use dancegen_music::features::{ExtractOptions, FeatureSet, MusicFeatures, extract};

use crate::error::GenerateError;

/// Where the song comes from.
#[derive(Clone, Debug)]
pub enum Song {
    /// The bundled demo song (45 s of *Metal Madness*, compiled into the library).
    Demo,
    File(PathBuf),
    /// Bytes in memory (an upload); `name` is shown in messages and its extension is the
    /// format hint.
    Bytes {
        name: String,
        bytes: Arc<[u8]>,
    },
}

impl Song {
    /// The file, or the demo song when there is none (what every command does without a
    /// song argument).
    pub fn file_or_demo(path: Option<&std::path::Path>) -> Self {
        match path {
            Some(p) => Song::File(p.to_path_buf()),
            None => Song::Demo,
        }
    }
}

/// Motion and feature frame rate of every shipped system (EDGE / Lodge++ / ReactDance).
pub const FPS: u32 = 30;

/// 45 s of "Metal Madness" by Carlos Viola Iborra (Sectoid song pack, MIT-style licence; see
/// NOTICE), re-encoded as OGG/Vorbis q4.
const DEMO_SONG: &[u8] = include_bytes!("../../../assets/demo_metal_madness_45s.ogg");
const DEMO_NAME: &str = "demo_metal_madness_45s.ogg";

/// The audio source of a song (the demo song's bytes come from the binary).
pub fn audio_source(song: &Song) -> AudioSource {
    match song {
        Song::File(p) => AudioSource::File(p.clone()),
        Song::Bytes { name, bytes } => AudioSource::Bytes {
            name: PathBuf::from(name),
            bytes: bytes.clone(),
        },
        Song::Demo => {
            tracing::info!("no song given: using the bundled demo song ({DEMO_NAME})");
            AudioSource::Bytes {
                name: PathBuf::from(format!("<bundled demo> {DEMO_NAME}")),
                bytes: Arc::from(DEMO_SONG),
            }
        }
    }
}

/// A song and its features.
pub struct AnalysedSong {
    pub source: AudioSource,
    /// The path or name shown in messages.
    pub label: String,
    pub features: MusicFeatures,
}

/// Seconds `[start, end)` of a song, and the same span in feature frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    pub start_s: f64,
    pub end_s: f64,
    pub first_frame: usize,
    pub end_frame: usize,
}

impl Span {
    pub fn seconds(&self) -> f64 {
        self.end_s - self.start_s
    }
}

impl AnalysedSong {
    pub fn analyse(song: &Song) -> Result<Self, GenerateError> {
        let source = audio_source(song);
        let label = source.label().display().to_string();
        let features = extract(
            &source,
            &ExtractOptions {
                fps: FPS,
                set: FeatureSet::Edge35,
                start_bpm: None,
            },
        )?;
        Ok(AnalysedSong {
            source,
            label,
            features,
        })
    }

    /// Feature frames of the whole song.
    pub fn frames(&self) -> usize {
        self.features.features.rows
    }

    /// The song's length: librosa-style framing has a frame at both ends (1 + samples / hop
    /// rows), so a song of d seconds has d · 30 frame intervals.
    pub fn seconds(&self) -> f64 {
        self.frames().saturating_sub(1) as f64 / f64::from(FPS)
    }

    /// `[start, end)` (defaults: the whole song), checked, in seconds and frames.
    pub fn span(&self, start: Option<f64>, end: Option<f64>) -> Result<Span, GenerateError> {
        let song_seconds = self.seconds();
        let start_s = start.unwrap_or(0.0);
        let end_s = end.unwrap_or(song_seconds).min(song_seconds);
        if !(start_s.is_finite() && end_s.is_finite() && start_s >= 0.0 && start_s < end_s) {
            return Err(GenerateError::Invalid(format!(
                "--start {start_s} / --end {end_s}: need 0 ≤ start < end ≤ the song's \
                 {song_seconds:.2} s"
            )));
        }
        let fps = f64::from(FPS);
        Ok(Span {
            start_s,
            end_s,
            first_frame: (start_s * fps).round() as usize,
            end_frame: ((end_s * fps).round() as usize).min(self.frames()),
        })
    }

    /// The span of `frames` frames from `start` (an edited dance's own length), or an error
    /// saying how much of the song there is.
    pub fn span_of_frames(&self, start: Option<f64>, frames: usize) -> Result<Span, GenerateError> {
        let start_s = start.unwrap_or(0.0);
        let fps = f64::from(FPS);
        if !(start_s.is_finite() && start_s >= 0.0) {
            return Err(GenerateError::Invalid(format!(
                "--start {start_s}: need a time in seconds from 0"
            )));
        }
        let first_frame = (start_s * fps).round() as usize;
        let end_frame = first_frame + frames;
        if end_frame > self.frames() {
            return Err(GenerateError::Invalid(format!(
                "{}: {:.2} s of song from --start {start_s}, but the dance is {:.2} s long \
                 (give the song and --start it was made for)",
                self.label,
                self.frames().saturating_sub(first_frame) as f64 / fps,
                frames as f64 / fps
            )));
        }
        Ok(Span {
            start_s,
            end_s: start_s + frames as f64 / fps,
            first_frame,
            end_frame,
        })
    }

    /// The features of `span`, `[frames, dim]` row-major.
    pub fn music(&self, span: &Span) -> &[f32] {
        let cols = self.features.features.cols;
        &self.features.features.data[span.first_frame * cols..span.end_frame * cols]
    }

    /// Music beats inside `span`, as frames from its start.
    pub fn beat_frames(&self, span: &Span) -> Vec<usize> {
        self.features
            .beat_frames
            .iter()
            .filter(|&&b| b >= span.first_frame && b < span.end_frame)
            .map(|&b| b - span.first_frame)
            .collect()
    }
}

/// The song as a file ffmpeg can read for the MP4's sound track: the song's own file, or its
/// bytes (an upload, the demo song) in a temporary file with the same extension. ffmpeg decodes
/// it itself so the video keeps the song's channels; it used to get a mono WAV of our
/// analysis decode (librosa's down-mix), and a stereo song lost its stereo.
pub(crate) enum SongFile {
    Given(PathBuf),
    Temporary(tempfile::NamedTempFile),
}

impl SongFile {
    pub(crate) fn of(source: &AudioSource) -> Result<Self, GenerateError> {
        match source {
            AudioSource::File(p) => Ok(SongFile::Given(p.clone())),
            AudioSource::Bytes { name, bytes } => {
                let io = |e: &dyn std::fmt::Display| GenerateError::Output {
                    path: PathBuf::from("<temporary copy of the song for the video>"),
                    reason: e.to_string(),
                };
                let ext = name
                    .extension()
                    .and_then(|e| e.to_str())
                    .map(|e| format!(".{e}"))
                    .unwrap_or_default();
                let mut tmp = tempfile::Builder::new()
                    .prefix(".dancegen-song-")
                    .suffix(&ext)
                    .tempfile()
                    .map_err(|e| io(&e))?;
                std::io::Write::write_all(&mut tmp, bytes).map_err(|e| io(&e))?;
                Ok(SongFile::Temporary(tmp))
            }
        }
    }

    pub(crate) fn path(&self) -> &Path {
        match self {
            SongFile::Given(p) => p,
            SongFile::Temporary(t) => t.path(),
        }
    }
}
