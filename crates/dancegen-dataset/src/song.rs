//! A song analysed once: its EDGE-35 features and beats over the whole song.

use std::path::{Path, PathBuf};

use dancegen_music::FrameMatrix;
use dancegen_music::decode::AudioSource;
use dancegen_music::features::{EDGE35_DIM, ExtractOptions, FeatureSet, extract};

use crate::FPS;
use crate::error::DatasetError;

/// A song analysed once: its EDGE-35 features over the whole song and its beats.
#[derive(Clone, Debug)]
pub struct Song {
    /// File stem.
    pub name: String,
    pub path: PathBuf,
    /// `(frames, 35)` at [`FPS`].
    pub features: FrameMatrix,
    /// Beat frames of the librosa-exact tracker (the features' beat column).
    pub beat_frames: Vec<usize>,
    pub tempo_bpm: f64,
}

impl Song {
    /// EDGE-35 features at 30 fps of a whole song, exactly as `dancegen features` computes them.
    pub fn analyse(path: &Path) -> Result<Song, DatasetError> {
        let f = extract(
            &AudioSource::File(path.to_path_buf()),
            &ExtractOptions {
                fps: FPS,
                set: FeatureSet::Edge35,
                start_bpm: None,
            },
        )?;
        Ok(Song {
            name: stem(path),
            path: path.to_path_buf(),
            beat_frames: f.beat_frames,
            tempo_bpm: f.tempo_bpm,
            features: f.features,
        })
    }

    pub fn frames(&self) -> usize {
        self.features.rows
    }

    pub fn duration_s(&self) -> f64 {
        self.frames() as f64 / f64::from(FPS)
    }

    /// Beat times in seconds.
    pub fn beat_times(&self) -> Vec<f64> {
        self.beat_frames
            .iter()
            .map(|&b| b as f64 / f64::from(FPS))
            .collect()
    }

    /// Feature rows `start..start + n`, flattened.
    pub(crate) fn rows(&self, start: usize, n: usize) -> Vec<f32> {
        self.features.data[start * EDGE35_DIM..(start + n) * EDGE35_DIM].to_vec()
    }

    /// Beats in `start..start + n`, relative to `start`.
    pub(crate) fn beats_in(&self, start: usize, n: usize) -> Vec<usize> {
        self.beat_frames
            .iter()
            .filter(|&&b| b >= start && b < start + n)
            .map(|&b| b - start)
            .collect()
    }
}

/// File name without its extension.
pub fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
