//! `dancegen features` and `dancegen beats`: what the models hear of a song.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetArg {
    /// 35 dims: onset envelope, 20 MFCC, 12 chroma_cens, onset peak, beat (EDGE/Lodge/FACT).
    Edge35,
    /// 438 dims: TCDiff/TCDiff++ (MFCC + delta, chroma, onset, beat, tempogram), 60 fps only.
    Tcdiff438,
}

#[derive(Args, Debug)]
pub struct FeaturesArgs {
    /// Audio file (WAV, FLAC, OGG/Vorbis, MP3, ...). Default: the bundled demo song.
    pub audio: Option<PathBuf>,
    /// Feature frame rate: 30 (EDGE, Lodge, TCDiff; SR 15360) or 60 (FACT; SR 30720).
    #[arg(long, default_value_t = 30, value_parser = parse_fps)]
    pub fps: u32,
    /// Beat-tracker prior tempo. Default: from an AIST++ music name, else estimated at
    /// 22050 Hz as EDGE/Lodge do.
    #[arg(long, value_name = "BPM")]
    pub start_bpm: Option<f64>,
    /// Feature set.
    #[arg(long, value_enum, default_value_t = SetArg::Edge35)]
    pub set: SetArg,
    /// EDGE test-time slicing: 5 s windows (150 frames at 30 fps); `.npy` becomes (N, 150, 35).
    #[arg(long)]
    pub slice5s: bool,
    /// Stride between EDGE slices in seconds (EDGE test: 2.5, training: 0.5).
    #[arg(long, default_value_t = 2.5, requires = "slice5s")]
    pub slice_stride: f64,
    /// Output: `.npy` (float32, (T, D)) or `.json` ({fps, tempo_bpm, beat_times, onset_times, features}).
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct BeatsArgs {
    /// Audio file. Default: the bundled demo song.
    pub audio: Option<PathBuf>,
    /// Frame rate of the analysis (30 or 60).
    #[arg(long, default_value_t = 30, value_parser = parse_fps)]
    pub fps: u32,
    /// Beat-tracker prior tempo (default as for `features`).
    #[arg(long, value_name = "BPM")]
    pub start_bpm: Option<f64>,
    /// Write a PNG with the waveform, onset envelope, onsets and beats.
    #[arg(long, value_name = "PNG")]
    pub plot: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The two frame rates of the published pipelines (see `dancegen_music::features`).
fn parse_fps(s: &str) -> Result<u32, String> {
    match s {
        "30" => Ok(30),
        "60" => Ok(60),
        _ => Err(format!(
            "{s} is not supported: use 30 (EDGE, Lodge, TCDiff) or 60 (FACT)"
        )),
    }
}
