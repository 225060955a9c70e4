//! EDGE's 5-second slicing (`Stanford-TML/EDGE:data/slice.py` + `test.py`), reproduced so
//! features match what an EDGE-style model saw in training and at test time.
//!
//! EDGE loads the song at its native rate, cuts windows of `int(5·sr)` samples every
//! `int(stride·sr)` samples (only whole windows), writes each as a 16-bit PCM WAV, then runs the
//! 35-dim extractor on that file — including a fresh 22050 Hz start-BPM estimate per slice — and
//! keeps the first 150 frames. We do the same without touching the disk.

use rayon::prelude::*;

use crate::decode::AudioSource;
use crate::error::Result;
use crate::features::{
    EDGE_SLICE_SECONDS, LIBROSA_DEFAULT_SR, MusicFeatures, StartBpm, aist_start_bpm,
    edge35_from_signal, sample_rate_for_fps, tempo_at_22050,
};
use crate::load::load_many;
use crate::resample::resample_hq;

/// One slice's features plus where it starts in the song.
#[derive(Clone, Debug)]
pub struct EdgeSlice {
    pub start_seconds: f64,
    pub features: MusicFeatures,
}

/// The float → PCM16 → float round trip of `soundfile.write(..., subtype='PCM_16')` and
/// `librosa.load`: libsndfile 1.2 maps x to `floor(x·32768)` clamped to the int16 range
/// (measured with python-soundfile 0.14 / libsndfile 1.2.2), read back as `/32768`.
pub fn pcm16_round_trip(x: f32) -> f32 {
    let q = (x as f64 * 32768.0).floor().clamp(-32768.0, 32767.0);
    (q / 32768.0) as f32
}

/// Slice start positions (in native samples) for a signal of `len` samples.
pub fn slice_starts(len: usize, native_sr: u32, stride_seconds: f64) -> Vec<usize> {
    let window = (EDGE_SLICE_SECONDS * native_sr as f64) as usize;
    let step = ((stride_seconds * native_sr as f64) as usize).max(1);
    let mut starts = Vec::new();
    let mut s = 0usize;
    while window > 0 && s + window <= len {
        starts.push(s);
        s += step;
    }
    starts
}

/// 35-dim features of every 5 s slice of `path`, each `(150, 35)`.
///
/// `start_bpm`: the beat prior (EDGE: AIST++ name, else per-slice 22050 Hz estimate).
pub fn edge35_slices(
    source: &AudioSource,
    fps: u32,
    stride_seconds: f64,
    start_bpm: Option<f64>,
) -> Result<Vec<EdgeSlice>> {
    let sr = sample_rate_for_fps(fps)?;
    let native = load_many(source, &[0], |_| {})?.pop().expect("one output");
    let nsr = native.sample_rate;
    let window = (EDGE_SLICE_SECONDS * nsr as f64) as usize;
    let keep = (EDGE_SLICE_SECONDS * fps as f64) as usize;
    let aist = aist_start_bpm(source.label());
    slice_starts(native.samples.len(), nsr, stride_seconds)
        .into_par_iter()
        .map(|start| {
            let slice: Vec<f32> = native.samples[start..start + window]
                .iter()
                .map(|&x| pcm16_round_trip(x))
                .collect();
            let y = resample_hq(&slice, nsr as f64, sr as f64, false)?;
            let prior = match (start_bpm, aist) {
                (Some(b), _) => StartBpm::Given(b),
                (None, Some(b)) => StartBpm::AistName(b),
                (None, None) => {
                    let y22 = resample_hq(&slice, nsr as f64, LIBROSA_DEFAULT_SR as f64, false)?;
                    StartBpm::Estimated22050(tempo_at_22050(&y22))
                }
            };
            let mut f = edge35_from_signal(&y, fps, prior)?;
            f.features.rows = f.features.rows.min(keep);
            f.features.data.truncate(f.features.rows * f.features.cols);
            f.beat_frames.retain(|&b| b < keep);
            f.onset_frames.retain(|&o| o < keep);
            Ok(EdgeSlice {
                start_seconds: start as f64 / nsr as f64,
                features: f,
            })
        })
        .collect()
}
