//! `dancegen.evaluate` and the `dancegen.metrics` functions: `dancegen eval` on files,
//! folders or arrays, returning its `--json` object.

use std::path::PathBuf;

use dancegen_eval::{ClipArray, EvalOptions, Input};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::f64_values;
use crate::{fail, fail_chain};

/// One input: a path (str or os.PathLike), or a `(name, array)` pair.
fn input(item: &Bound<'_, PyAny>, flag: &str) -> PyResult<Input> {
    if let Ok(path) = item.extract::<PathBuf>() {
        return Ok(Input::Path(path));
    }
    if let Ok(pair) = item.cast::<PyTuple>()
        && pair.len() == 2
    {
        let name: String = pair.get_item(0)?.extract()?;
        let (shape, data) = f64_values(&pair.get_item(1)?, &format!("{flag} array {name}"))?;
        return Ok(Input::Array(ClipArray { name, shape, data }));
    }
    Err(fail(format!(
        "{flag}: give paths (files or folders) or arrays, got {}",
        item.get_type().name()?
    )))
}

fn inputs(items: &[Bound<'_, PyAny>], flag: &str) -> PyResult<Vec<Input>> {
    items.iter().map(|i| input(i, flag)).collect()
}

/// `dancegen eval --json` as text (the Python wrapper `dancegen.evaluate` parses it). Inputs
/// are paths or `(name, array)` pairs; `beats` a path or a list of beat frames.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn evaluate_json(
    py: Python<'_>,
    pred: Vec<Bound<'_, PyAny>>,
    gt: Vec<Bound<'_, PyAny>>,
    leader: Vec<Bound<'_, PyAny>>,
    gt_leader: Vec<Bound<'_, PyAny>>,
    protocol: &str,
    fps: Option<f64>,
    source_fps: Option<f64>,
    metrics: Option<String>,
    music: Option<PathBuf>,
    beats: Option<Bound<'_, PyAny>>,
    bas_variant: &str,
    window: u64,
    gt_genres: Option<PathBuf>,
    want_genre: Option<String>,
    genre_min_clips: u64,
) -> PyResult<String> {
    let (beats, beat_frames) = match beats {
        None => (None, None),
        Some(b) => match b.extract::<PathBuf>() {
            Ok(p) => (Some(p), None),
            Err(_) => (
                None,
                Some(b.extract::<Vec<usize>>().map_err(|_| {
                    fail("beats: give a .npy path or a list of beat frames (whole numbers ≥ 0)")
                })?),
            ),
        },
    };
    let opts = EvalOptions {
        pred: inputs(&pred, "pred")?,
        gt: inputs(&gt, "gt")?,
        leader: inputs(&leader, "leader")?,
        gt_leader: inputs(&gt_leader, "gt_leader")?,
        protocol: dancegen_eval::protocol_named(protocol).map_err(fail_chain)?,
        fps,
        source_fps,
        metrics,
        gt_genres,
        want_genre,
        genre_min_clips,
        bas_variant: dancegen_eval::bas_variant_named(bas_variant).map_err(fail_chain)?,
        beats,
        beat_frames,
        music,
        window,
    };
    let report = py
        .detach(|| dancegen_eval::evaluate(&opts))
        .map_err(fail_chain)?;
    Ok(report.to_json().to_string())
}
