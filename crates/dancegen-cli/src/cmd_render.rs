//! `dancegen render`: a shaded capsule-figure preview of one or more motions.
//!
//! `.png` draws one frame (the middle one, or `--frame N` at the output frame rate); `.gif`
//! loops the whole clip at ≤ 15 fps by default; `.mp4` pipes the frames to `ffmpeg` and muxes
//! `--audio`.

use std::io::Write;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use dancegen_formats::dispatch::{LoadOptions, load_motion_file_with};
use dancegen_render::{RenderOptions, Scene, tracks_from_motion, write};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cli::RenderArgs;
use crate::progress::spinner;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Png,
    Gif,
    Mp4,
}

/// GIF frame rate when `--fps` is not given (keeps files small; delays are in 1/100 s).
const GIF_MAX_FPS: f32 = 15.0;

pub fn run(args: &RenderArgs, quiet: bool) -> Result<()> {
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let kind = match ext.as_str() {
        "png" => Kind::Png,
        "gif" => Kind::Gif,
        "mp4" => Kind::Mp4,
        other => bail!(
            "{}: unknown preview format '.{other}' (use .png, .gif or .mp4)",
            args.output.display()
        ),
    };
    if let Some(fps) = args.fps
        && !(fps.is_finite() && fps > 0.0 && fps <= 240.0)
    {
        bail!("--fps {fps}: use a frame rate in (0, 240]");
    }
    if args.audio.is_some() && kind != Kind::Mp4 {
        tracing::warn!("--audio is only used for .mp4 output; ignoring it");
    }
    if kind == Kind::Mp4 && !write::ffmpeg_available() {
        bail!(dancegen_render::RenderError::FfmpegMissing);
    }

    let pb = spinner("loading motion", quiet);
    let mut tracks = Vec::new();
    for path in &args.motions {
        let read = LoadOptions {
            source_fps: args.source_fps,
            ..LoadOptions::default()
        };
        let m = load_motion_file_with(path, &read)?;
        tracks.extend(tracks_from_motion(path, &m)?);
    }
    let motion_fps = tracks.first().map_or(30.0, |t| t.fps);
    let fps = args.fps.unwrap_or(match kind {
        Kind::Gif => motion_fps.min(GIF_MAX_FPS),
        _ => motion_fps,
    });
    let mut opts = RenderOptions::new(args.width, args.height);
    if args.draft {
        opts.supersample = 1;
        opts.shadows = false;
    }
    let scene = Scene::new(&tracks, &opts)?;
    pb.finish_and_clear();

    let start = Instant::now();
    let n = match kind {
        Kind::Png => {
            let total = scene.frame_count(fps);
            let k = args.frame.unwrap_or(total / 2);
            if k >= total {
                bail!("--frame {k}: the clip has {total} frames at {fps} fps");
            }
            let img = scene.render_at(k as f32 / fps);
            write::write_png(&args.output, &img)?;
            1
        }
        Kind::Gif | Kind::Mp4 => {
            let stream = scene.stream(fps);
            let bar = progress(stream.total() as u64, quiet);
            let frames = stream.inspect(|_| bar.inc(1));
            let n = if kind == Kind::Gif {
                write::write_gif(&args.output, frames, fps)?
            } else {
                write::write_mp4(
                    &args.output,
                    frames,
                    args.width,
                    args.height,
                    fps,
                    args.audio.as_deref().map(write::AudioClip::whole),
                )
                .with_context(|| format!("writing {}", args.output.display()))?
            };
            bar.finish_and_clear();
            n
        }
    };
    let secs = start.elapsed().as_secs_f64();
    if !quiet {
        writeln!(
            std::io::stdout().lock(),
            "{} dancer(s), {n} frame(s) at {fps} fps, {}x{} -> {} ({:.1} frames/s)",
            tracks.len(),
            args.width,
            args.height,
            args.output.display(),
            n as f64 / secs.max(1e-9)
        )?;
    }
    Ok(())
}

fn progress(total: u64, quiet: bool) -> ProgressBar {
    let pb = ProgressBar::new(total);
    if quiet {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    pb.set_style(
        ProgressStyle::with_template("rendering {bar:30} {pos}/{len} frames [{elapsed}<{eta}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}
