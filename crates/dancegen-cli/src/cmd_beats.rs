//! `dancegen beats`: tempo and beat times, optionally plotted.

use std::io::Write;

use anyhow::Result;
use dancegen_music::features::{ExtractOptions, FeatureSet, extract_with_signal};
use serde_json::json;

use crate::cli::BeatsArgs;
use crate::progress::spinner;

pub fn run(args: &BeatsArgs, quiet: bool) -> Result<()> {
    if let Some(p) = &args.plot {
        crate::plot::check_png_path(p)?;
    }
    let source = dancegen_generate::song::audio_source(&dancegen_generate::Song::file_or_demo(
        args.audio.as_deref(),
    ));
    let label = source.label().display().to_string();
    let pb = spinner(&format!("tracking beats in {label}"), quiet);
    let opts = ExtractOptions {
        fps: args.fps,
        set: FeatureSet::Edge35,
        start_bpm: args.start_bpm,
    };
    let (f, y) = extract_with_signal(&source, &opts)?;
    pb.finish_and_clear();
    if let Some(p) = &args.plot {
        crate::plot::beats_png(p, &label, &y, &f)?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        let v = json!({
            "tempo_bpm": f.tempo_bpm,
            "beat_times": f.beat_times(),
            "onset_times": f.onset_times(),
            "beat_frames": f.beat_frames,
            "fps": f.fps,
        });
        writeln!(out, "{v}")?;
    } else {
        writeln!(out, "{label}")?;
        writeln!(out, "tempo: {:.2} BPM", f.tempo_bpm)?;
        writeln!(out, "beats: {}", f.beat_frames.len())?;
        let times: Vec<String> = f.beat_times().iter().map(|t| format!("{t:.3}")).collect();
        writeln!(out, "beat times (s): {}", times.join(" "))?;
        if let Some(p) = &args.plot {
            writeln!(out, "plot: {}", p.display())?;
        }
    }
    Ok(())
}
