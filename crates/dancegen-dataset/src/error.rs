use std::path::PathBuf;

/// Everything that can go wrong while building a data set. Every variant about a file names it.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// A motion file that could not be read or converted (the inner error names the file).
    #[error(transparent)]
    Motion(#[from] dancegen_formats::dispatch::FormatError),
    /// A song that could not be decoded or analysed (the inner error names the file).
    #[error(transparent)]
    Music(#[from] dancegen_music::MusicError),
    /// An output file that could not be written (the inner error names the file).
    #[error(transparent)]
    Write(#[from] dancegen_io::atomic::WriteError),
    /// A file or directory whose content is not what the layout expects.
    #[error("{path}: {reason}")]
    Input { path: PathBuf, reason: String },
    /// Options that do not make a data set (no motion, every song held out, ...).
    #[error("{0}")]
    Options(String),
}

impl DatasetError {
    pub(crate) fn input(path: impl Into<PathBuf>, reason: impl std::fmt::Display) -> Self {
        DatasetError::Input {
            path: path.into(),
            reason: reason.to_string(),
        }
    }
}
