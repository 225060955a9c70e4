use std::path::PathBuf;

/// Everything that can go wrong while reading or analysing music.
///
/// Every variant that concerns a file carries its path, so a user with a folder of songs knows
/// which one to fix.
#[derive(Debug, thiserror::Error)]
pub enum MusicError {
    #[error("{path}: cannot open: {err}")]
    Open { path: PathBuf, err: std::io::Error },
    #[error("{path}: file is empty (0 bytes)")]
    EmptyFile { path: PathBuf },
    #[error("{path}: not a recognised audio file (unknown or corrupt container header): {reason}")]
    UnknownFormat { path: PathBuf, reason: String },
    #[error("{path}: no decodable audio track")]
    NoAudioTrack { path: PathBuf },
    #[error("{path}: unsupported codec: {reason}")]
    UnsupportedCodec { path: PathBuf, reason: String },
    #[error("{path}: audio stream is corrupt or truncated: {reason}")]
    Corrupt { path: PathBuf, reason: String },
    #[error("{path}: file is truncated: {reason}")]
    Truncated { path: PathBuf, reason: String },
    #[error("{path}: contains no audio samples")]
    NoSamples { path: PathBuf },
    #[error("{path}: invalid sample rate {rate} Hz")]
    BadSampleRate { path: PathBuf, rate: u32 },
    #[error("resampler (libsoxr) failed: {0}")]
    Resample(String),
    #[error("invalid analysis parameter: {0}")]
    InvalidParameter(String),
}

pub type Result<T> = std::result::Result<T, MusicError>;
