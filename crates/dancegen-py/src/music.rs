//! `dancegen.features` and `dancegen.beats`: the music analysis of `dancegen features` and
//! `dancegen beats`, from a path or from an array of samples.

use std::path::PathBuf;
use std::sync::Arc;

use dancegen_music::decode::AudioSource;
use dancegen_music::features::{ExtractOptions, FeatureSet, extract};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::fail;

/// The song: a path (str or os.PathLike), or a 1-D float array of mono samples with its
/// `sample_rate` (encoded as a 32-bit float WAV in memory and decoded as a file would be).
fn audio_source(audio: &Bound<'_, PyAny>, sample_rate: Option<u32>) -> PyResult<AudioSource> {
    if let Ok(path) = audio.extract::<PathBuf>() {
        if sample_rate.is_some() {
            return Err(fail("sample_rate is for an array of samples, not a file"));
        }
        return Ok(AudioSource::File(path));
    }
    let samples: PyReadonlyArray1<'_, f32> = audio.extract().map_err(|_| {
        fail("audio: give a path, or a 1-D float32 array of mono samples with sample_rate")
    })?;
    let rate = sample_rate.ok_or_else(|| fail("an array of samples needs its sample_rate"))?;
    if rate == 0 {
        return Err(fail("sample_rate must be positive"));
    }
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: rate,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    {
        let mut w = hound::WavWriter::new(&mut bytes, spec).map_err(fail)?;
        for &s in samples.as_slice().map_err(fail)? {
            w.write_sample(s).map_err(fail)?;
        }
        w.finalize().map_err(fail)?;
    }
    Ok(AudioSource::Bytes {
        name: PathBuf::from("samples.wav"),
        bytes: Arc::from(bytes.into_inner()),
    })
}

fn options(fps: u32, set: &str, start_bpm: Option<f64>) -> PyResult<ExtractOptions> {
    let set = match set {
        "edge35" => FeatureSet::Edge35,
        "tcdiff438" => FeatureSet::Tcdiff438,
        other => return Err(fail(format!("set '{other}': choose edge35 or tcdiff438"))),
    };
    if let Some(b) = start_bpm
        && !(b.is_finite() && b > 0.0)
    {
        return Err(fail(format!(
            "start_bpm must be a positive number, got {b}"
        )));
    }
    Ok(ExtractOptions {
        fps,
        set,
        start_bpm,
    })
}

/// Music features of `audio` at `fps` frames a second: `(T, D)` float32 (`set` "edge35": EDGE's
/// 35, "tcdiff438": TCDiff's 438), as `dancegen features` computes them.
#[pyfunction]
#[pyo3(signature = (audio, fps=30, set="edge35", start_bpm=None, sample_rate=None))]
pub fn features<'py>(
    py: Python<'py>,
    audio: &Bound<'py, PyAny>,
    fps: u32,
    set: &str,
    start_bpm: Option<f64>,
    sample_rate: Option<u32>,
) -> PyResult<Bound<'py, PyAny>> {
    let source = audio_source(audio, sample_rate)?;
    let opts = options(fps, set, start_bpm)?;
    let f = py.detach(|| extract(&source, &opts)).map_err(fail)?;
    let m = f.features;
    let arr = PyArray1::from_vec(py, m.data).reshape([m.rows, m.cols])?;
    Ok(arr.into_any())
}

/// Beats of `audio`: a dict with `beat_times` and `onset_times` (seconds), `beat_frames` and
/// `onset_frames` (at `fps`), and `tempo_bpm`, as `dancegen beats` finds them.
#[pyfunction]
#[pyo3(signature = (audio, fps=30, start_bpm=None, sample_rate=None))]
pub fn beats<'py>(
    py: Python<'py>,
    audio: &Bound<'py, PyAny>,
    fps: u32,
    start_bpm: Option<f64>,
    sample_rate: Option<u32>,
) -> PyResult<Bound<'py, PyDict>> {
    let source = audio_source(audio, sample_rate)?;
    let opts = options(fps, "edge35", start_bpm)?;
    let f = py.detach(|| extract(&source, &opts)).map_err(fail)?;
    let d = PyDict::new(py);
    d.set_item("tempo_bpm", f.tempo_bpm)?;
    d.set_item("beat_times", f.beat_times())?;
    d.set_item("beat_frames", f.beat_frames.clone())?;
    d.set_item("onset_frames", f.onset_frames.clone())?;
    let onset_times: Vec<f64> = f
        .onset_frames
        .iter()
        .map(|&x| x as f64 / fps as f64)
        .collect();
    d.set_item("onset_times", onset_times)?;
    Ok(d)
}
