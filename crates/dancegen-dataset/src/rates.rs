//! The frame rate each input take is read at: given per input (`--source-fps INPUT=FPS`) or
//! the file's own, and which of the two it was.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::DatasetError;

/// Explicit capture rates of the inputs, `INPUT=FPS` entries.
///
/// `INPUT` is a `--motion` directory, a file, or a file name without extension; a file takes the
/// rate of the most specific entry that names it (its stem or path before a directory, the
/// deepest directory before a shallower one). `FPS` alone (no `INPUT=`) is every input's rate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SourceRates {
    entries: Vec<(Option<String>, f64)>,
}

impl SourceRates {
    /// Parses `INPUT=FPS` or `FPS`; the rate must be in `(0, 1000]`.
    pub fn parse_entry(s: &str) -> Result<(Option<String>, f64), String> {
        let (key, fps) = match s.rsplit_once('=') {
            Some((k, v)) if !k.trim().is_empty() => (Some(k.trim().to_string()), v),
            Some(_) => return Err(format!("{s:?}: give INPUT=FPS or FPS")),
            None => (None, s),
        };
        let fps: f64 = fps
            .trim()
            .parse()
            .map_err(|_| format!("{s:?}: {fps:?} is not a number of frames per second"))?;
        let fps = dancegen_formats::dispatch::check_source_fps(fps)?;
        Ok((key, fps))
    }

    pub fn new(entries: Vec<(Option<String>, f64)>) -> Self {
        SourceRates { entries }
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The given rate of `file`, if an entry names it.
    pub fn rate_for(&self, file: &Path) -> Option<f64> {
        let stem = crate::song::stem(file);
        let mut best: Option<(usize, f64)> = None;
        for (key, fps) in &self.entries {
            let rank = match key {
                None => Some(0),
                Some(k) if *k == stem || Path::new(k) == file => Some(usize::MAX),
                Some(k) if file.starts_with(k) => Some(1 + Path::new(k).components().count()),
                Some(_) => None,
            };
            if let Some(r) = rank
                && best.is_none_or(|(b, _)| r >= b)
            {
                best = Some((r, *fps));
            }
        }
        best.map(|(_, f)| f)
    }

    /// Fails on an entry that names none of `files`: a typo would silently leave a take at
    /// its header's rate.
    pub fn check_used(&self, files: &[PathBuf]) -> Result<(), DatasetError> {
        for (key, fps) in &self.entries {
            let Some(k) = key else { continue };
            let used = files
                .iter()
                .any(|f| crate::song::stem(f) == *k || f == Path::new(k) || f.starts_with(k));
            if !used {
                return Err(DatasetError::Options(format!(
                    "--source-fps {k}={fps}: {k} names no --motion input (give a --motion \
                     directory or file, or a file name without extension)"
                )));
            }
        }
        Ok(())
    }
}

/// Where a take's rate came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RateFrom {
    /// `--source-fps`.
    Given,
    /// The file's own header or rate field.
    Header,
}
