//! Why a generation job did not produce its dance.

use std::path::PathBuf;

use crate::models::ModelNotFound;

/// Everything a job can fail with; every variant names the file or option at fault.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// The job's [`crate::CancelToken`] was set; no output file was left behind.
    #[error("cancelled")]
    Cancelled,
    /// The request does not make sense (an option out of range, a flag for another system).
    #[error("{0}")]
    Invalid(String),
    #[error(transparent)]
    ModelNotFound(#[from] ModelNotFound),
    /// A model directory exists but does not load.
    #[error("loading the {system} model in {} (give another with --model DIR)", dir.display())]
    ModelLoad {
        system: &'static str,
        dir: PathBuf,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    #[error(transparent)]
    Music(#[from] dancegen_music::error::MusicError),
    #[error(transparent)]
    Motion(#[from] dancegen_formats::dispatch::FormatError),
    #[error(transparent)]
    Render(#[from] dancegen_render::RenderError),
    /// An output could not be written (names the output file, not the staging copy).
    #[error("{}: {reason}", path.display())]
    Output { path: PathBuf, reason: String },
    /// The system failed on valid input (please report with the song and seed).
    #[error("{0}")]
    Generation(String),
}

impl From<dancegen_nn::progress::Cancelled> for GenerateError {
    fn from(_: dancegen_nn::progress::Cancelled) -> Self {
        GenerateError::Cancelled
    }
}
