//! `dancegen features`: per-frame music features to `.npy` or `.json`.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result, bail};
use dancegen_music::edge_slices::edge35_slices;
use dancegen_music::features::{ExtractOptions, FeatureSet, MusicFeatures, extract};
use serde_json::json;

use crate::cli::{FeaturesArgs, SetArg};
use crate::progress::spinner;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutFormat {
    Npy,
    Json,
}

pub fn out_format(path: &Path) -> Result<OutFormat> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("npy") => Ok(OutFormat::Npy),
        Some("json") => Ok(OutFormat::Json),
        _ => bail!(
            "{}: unknown output format (use a .npy or .json file name)",
            path.display()
        ),
    }
}

pub fn run(args: &FeaturesArgs, quiet: bool) -> Result<()> {
    let format = out_format(&args.output)?;
    let set = match args.set {
        SetArg::Edge35 => FeatureSet::Edge35,
        SetArg::Tcdiff438 => FeatureSet::Tcdiff438,
    };
    if let Some(b) = args.start_bpm
        && !(b.is_finite() && b > 0.0)
    {
        bail!("--start-bpm must be a positive number, got {b}");
    }
    if args.slice5s && set != FeatureSet::Edge35 {
        bail!("--slice5s is EDGE's slicing and applies to --set edge35 only");
    }
    if args.slice5s && !(args.slice_stride.is_finite() && args.slice_stride > 0.0) {
        bail!("--slice-stride must be positive, got {}", args.slice_stride);
    }
    let source = dancegen_generate::song::audio_source(&dancegen_generate::Song::file_or_demo(
        args.audio.as_deref(),
    ));
    let label = source.label().display().to_string();
    let pb = spinner(&format!("analysing {label}"), quiet);
    let started = std::time::Instant::now();
    if args.slice5s {
        let slices = edge35_slices(&source, args.fps, args.slice_stride, args.start_bpm)?;
        pb.finish_and_clear();
        tracing::info!(
            "{label}: {} slices of 5 s in {:.0} ms",
            slices.len(),
            started.elapsed().as_secs_f64() * 1e3
        );
        if slices.is_empty() {
            bail!("{label}: shorter than one 5 s EDGE slice");
        }
        let rows = slices[0].features.features.rows;
        let dim = slices[0].features.features.cols;
        match format {
            OutFormat::Npy => {
                let data: Vec<f32> = slices
                    .iter()
                    .flat_map(|s| s.features.features.data.iter().copied())
                    .collect();
                dancegen_io::write_npy_f32(&args.output, &[slices.len(), rows, dim], &data)?;
            }
            OutFormat::Json => {
                // The contract keys describe the whole song (as without slicing); each slice's
                // own tempo, beats and onsets are under `slices`.
                let song = extract(
                    &source,
                    &ExtractOptions {
                        fps: args.fps,
                        set,
                        start_bpm: args.start_bpm,
                    },
                )?;
                let value = json!({
                    "fps": args.fps,
                    "tempo_bpm": song.tempo_bpm,
                    "beat_times": song.beat_times(),
                    "onset_times": song.onset_times(),
                    "feature_set": "edge35",
                    "slice_seconds": 5.0,
                    "slice_stride_seconds": args.slice_stride,
                    "slice_start_times": slices.iter().map(|s| s.start_seconds).collect::<Vec<_>>(),
                    "slices": slices.iter().map(|s| features_json(&s.features)).collect::<Vec<_>>(),
                    "features": slices.iter().map(|s| rows_json(&s.features)).collect::<Vec<_>>(),
                });
                write_json(&args.output, &value)?;
            }
        }
        if !quiet {
            writeln!(
                std::io::stdout().lock(),
                "{label}: {} EDGE slices x {rows} frames x {dim} features -> {}",
                slices.len(),
                args.output.display()
            )?;
        }
        return Ok(());
    }
    let opts = ExtractOptions {
        fps: args.fps,
        set,
        start_bpm: args.start_bpm,
    };
    let f = extract(&source, &opts)?;
    pb.finish_and_clear();
    tracing::info!(
        "{label}: {} frames in {:.0} ms (start BPM {:?})",
        f.features.rows,
        started.elapsed().as_secs_f64() * 1e3,
        f.start_bpm
    );
    match format {
        OutFormat::Npy => dancegen_io::write_npy_f32(
            &args.output,
            &[f.features.rows, f.features.cols],
            &f.features.data,
        )?,
        OutFormat::Json => {
            let mut value = features_json(&f);
            value["feature_set"] = json!(match set {
                FeatureSet::Edge35 => "edge35",
                FeatureSet::Tcdiff438 => "tcdiff438",
            });
            value["features"] = rows_json(&f);
            write_json(&args.output, &value)?;
        }
    }
    if !quiet {
        writeln!(
            std::io::stdout().lock(),
            "{label}: {} frames x {} features at {} fps, tempo {:.2} BPM, {} beats -> {}",
            f.features.rows,
            f.features.cols,
            f.fps,
            f.tempo_bpm,
            f.beat_frames.len(),
            args.output.display()
        )?;
    }
    Ok(())
}

/// Everything but the matrix: the keys external tools rely on plus provenance.
fn features_json(f: &MusicFeatures) -> serde_json::Value {
    use dancegen_music::features::StartBpm;
    let (src, bpm) = match f.start_bpm {
        StartBpm::Given(b) => ("given", b),
        StartBpm::AistName(b) => ("aist_name", b),
        StartBpm::Estimated22050(b) => ("estimated_22050hz", b),
    };
    json!({
        "fps": f.fps,
        "tempo_bpm": f.tempo_bpm,
        "beat_times": f.beat_times(),
        "onset_times": f.onset_times(),
        "beat_frames": f.beat_frames,
        "onset_frames": f.onset_frames,
        "start_bpm": bpm,
        "start_bpm_source": src,
        "n_frames": f.features.rows,
        "dim": f.features.cols,
    })
}

fn rows_json(f: &MusicFeatures) -> serde_json::Value {
    let m = &f.features;
    serde_json::Value::Array(
        (0..m.rows)
            .map(|r| json!(m.row(r)))
            .collect::<Vec<serde_json::Value>>(),
    )
}

pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    dancegen_io::write_atomic(path, |w| {
        serde_json::to_writer(&mut *w, value).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .with_context(|| "writing JSON".to_string())
}
