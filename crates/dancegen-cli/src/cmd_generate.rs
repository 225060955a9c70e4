//! `dancegen generate`: a solo dance for a song with the Lodge++ model (the bundled default
//! model unless `--model` names another).
//!
//! Song → EDGE-35 features and beats at 30 fps (the whole song, then `--start/--end`) →
//! `dancegen_lodgepp` → EDGE-151 frames → SMPL motion (Y-up, metres, 30 fps) standing on the
//! floor → every `-o` file by its extension.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use dancegen_lodgepp::bundle::SoloModel;
use dancegen_lodgepp::pipeline::{GenerateOptions, Sampler};
use dancegen_motion::formats::{ConvertOptions, LoadedMotion, save_motion_file};
use dancegen_motion::repr::motion::GroundMode;
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_music::decode::AudioSource;
use dancegen_music::features::{ExtractOptions, FeatureSet, extract};
use dancegen_render::{RenderOptions, Scene, tracks_from_motion, write};

use crate::cli::{GenerateArgs, SamplerArg};
use crate::demo::song_or_demo;
use crate::progress::spinner;

/// The model shipped in the repository (`models/lodgepp-small`).
pub fn default_model_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/lodgepp-small")
}

/// Shortest song the model accepts (one PDDM window needs material to dance to).
const MIN_SONG_SECONDS: f64 = 2.0;
/// Motion frame rate (EDGE / Lodge++ / ReactDance).
pub(crate) const FPS: u32 = 30;
/// Preview size.
const PREVIEW_WIDTH: u32 = 640;
const PREVIEW_HEIGHT: u32 = 480;
/// GIF preview frame rate.
const GIF_FPS: f32 = 15.0;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Out {
    Motion,
    Gif,
    Mp4,
}

pub(crate) fn kind_of(p: &Path) -> Result<Out> {
    let ext = p
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    Ok(match ext.as_str() {
        "glb" | "bvh" | "npz" | "npy" | "json" => Out::Motion,
        "gif" => Out::Gif,
        "mp4" => Out::Mp4,
        other => bail!(
            "{}: unknown output format '.{other}' (use .glb, .bvh, .npz, .npy, .json, .gif or .mp4)",
            p.display()
        ),
    })
}

pub fn run(args: &GenerateArgs, quiet: bool) -> Result<()> {
    if args.leader.is_some() {
        return crate::cmd_generate_duet::run(args, quiet);
    }
    let outputs: Vec<PathBuf> = if args.output.is_empty() {
        vec![PathBuf::from("dance.glb")]
    } else {
        args.output.clone()
    };
    let kinds: Vec<Out> = outputs.iter().map(|p| kind_of(p)).collect::<Result<_>>()?;
    if kinds.contains(&Out::Mp4) && !write::ffmpeg_available() {
        bail!(dancegen_render::RenderError::FfmpegMissing);
    }
    if let Some(w) = args.guidance
        && !(w.is_finite() && w >= 0.0)
    {
        bail!("--guidance {w}: use a non-negative number (1 = no guidance, 2 = Lodge's default)");
    }
    if args.steps == Some(0) {
        bail!("--steps must be at least 1");
    }
    let started = Instant::now();
    let device = dancegen_nn_device();
    let model_dir = args.model.clone().unwrap_or_else(default_model_dir);
    let pb = spinner("loading the model", quiet);
    let model = SoloModel::load(&model_dir, &device).with_context(|| {
        format!(
            "loading the Lodge++ model in {} (give another with --model DIR)",
            model_dir.display()
        )
    })?;
    let genre_name = args
        .genre
        .clone()
        .unwrap_or_else(|| model.config.default_genre.clone());
    let genre = model.genre_index(&genre_name).map_err(anyhow::Error::msg)?;
    pb.finish_and_clear();

    let (source, label, feats) = analyse_song(args.song.as_ref(), quiet)?;
    let total = feats.features.rows;
    // librosa-style framing has a frame at both ends (1 + samples / hop rows): a song of
    // d seconds has d · 30 frame intervals, and the dance gets that many frames.
    let song_seconds = total.saturating_sub(1) as f64 / f64::from(FPS);
    let start = args.start.unwrap_or(0.0);
    let end = args.end.unwrap_or(song_seconds).min(song_seconds);
    if !(start.is_finite() && end.is_finite() && start >= 0.0 && start < end) {
        bail!(
            "--start {start} / --end {end}: need 0 ≤ start < end ≤ the song's {song_seconds:.2} s"
        );
    }
    if end - start < MIN_SONG_SECONDS {
        bail!(
            "{label}: {:.2} s of music to dance to; the model needs at least {MIN_SONG_SECONDS} s",
            end - start
        );
    }
    let (f0, f1) = (
        (start * f64::from(FPS)).round() as usize,
        ((end * f64::from(FPS)).round() as usize).min(total),
    );
    let cols = feats.features.cols;
    let music = feats.features.data[f0 * cols..f1 * cols].to_vec();
    let beats: Vec<usize> = feats
        .beat_frames
        .iter()
        .filter(|&&b| b >= f0 && b < f1)
        .map(|&b| b - f0)
        .collect();

    let mut opts = GenerateOptions::defaults(&model, genre, args.seed);
    if let Some(s) = args.steps {
        opts.steps = s;
    }
    if let Some(w) = args.guidance {
        opts.guidance = w;
    }
    opts.sampler = match args.sampler.unwrap_or(SamplerArg::Lodgepp) {
        SamplerArg::Lodgepp => Sampler::Lodgepp,
        SamplerArg::Edge => Sampler::Edge,
        SamplerArg::Autoregressive => Sampler::Autoregressive,
        SamplerArg::Blc => bail!("--sampler blc is the duet sampler (use it with --leader)"),
    };
    opts.refine = !args.no_foot_refine;
    if args.no_penetration_guidance {
        opts.penetration = None;
    }
    if args.no_foot_lock {
        opts.foot_lock = false;
    }
    let pb = spinner(
        &format!("dancing {:.1} s of {label} ({genre_name})", end - start),
        quiet,
    );
    let t_gen = Instant::now();
    let grad_device = device.clone().autodiff();
    let dance = model.generate(&music, &beats, &opts, &device, &grad_device);
    let gen_secs = t_gen.elapsed().as_secs_f64();
    pb.finish_and_clear();
    tracing::info!(
        horizontal_m = dance.seam_correction.horizontal,
        height_m = dance.seam_correction.height,
        "largest root corrections where generated frames meet the shared boundary frames"
    );
    let motion = to_smpl(&dance.frames)?;

    for (path, kind) in outputs.iter().zip(&kinds) {
        match kind {
            Out::Motion => save_motion_file(
                path,
                &LoadedMotion::Smpl(motion.clone()),
                &ConvertOptions::default(),
            )?,
            Out::Gif | Out::Mp4 => {
                let audio = if *kind == Out::Mp4 {
                    Some(song_segment_wav(&source, start, end)?)
                } else {
                    None
                };
                preview_motion(
                    path,
                    LoadedMotion::Smpl(motion.clone()),
                    *kind,
                    audio.as_ref().map(|t| t.path()),
                )?;
            }
        }
    }
    if !quiet {
        let mut out = std::io::stdout().lock();
        writeln!(
            out,
            "{label}: {} frames ({:.1} s at {FPS} fps), genre {genre_name}, seed {}, {} windows, \
             {} key motions; generated in {gen_secs:.2} s ({:.2} s in total)",
            dance.n_frames,
            dance.n_frames as f64 / f64::from(FPS),
            args.seed,
            dance.windows,
            dance.key_motions,
            started.elapsed().as_secs_f64()
        )?;
        for p in &outputs {
            writeln!(out, "  -> {}", p.display())?;
        }
    }
    Ok(())
}

fn dancegen_nn_device() -> dancegen_lodgepp::Device {
    dancegen_lodgepp::inference_device()
}

/// The song (or the bundled demo), its label and its EDGE-35 features at 30 fps over the whole
/// song (both generators slice what they dance to from them).
pub(crate) fn analyse_song(
    song: Option<&PathBuf>,
    quiet: bool,
) -> Result<(AudioSource, String, dancegen_music::features::MusicFeatures)> {
    let source = song_or_demo(song);
    let label = source.label().display().to_string();
    let pb = spinner(&format!("analysing {label}"), quiet);
    let feats = extract(
        &source,
        &ExtractOptions {
            fps: FPS,
            set: FeatureSet::Edge35,
            start_bpm: None,
        },
    )?;
    pb.finish_and_clear();
    Ok((source, label, feats))
}

/// Raw EDGE-151 frames → SMPL motion standing on the floor: the supporting foot at y = 0 and
/// no frame with a foot below it.
fn to_smpl(frames: &[f32]) -> Result<SmplMotion> {
    if frames.iter().any(|v| !v.is_finite()) {
        bail!("the model produced non-finite values (please report this with the song and seed)");
    }
    let mut m = Edge151::decode(frames)?;
    m.put_on_ground_with(GroundMode::SupportFeet)?;
    let joints = m.joints_world()?;
    for (f, p) in m.trans.chunks_exact_mut(3).enumerate() {
        let low = dancegen_motion::repr::motion::FOOT_JOINTS
            .iter()
            .map(|&j| joints[(f * 24 + j) * 3 + 1])
            .fold(f32::INFINITY, f32::min);
        if low < 0.0 {
            p[1] -= low;
        }
    }
    Ok(m)
}

/// The song between `start` and `end` seconds as a temporary mono 16-bit WAV (for the MP4).
pub(crate) fn song_segment_wav(
    source: &AudioSource,
    start: f64,
    end: f64,
) -> Result<tempfile::NamedTempFile> {
    let audio = dancegen_music::load::load_many(source, &[0], |_| {})?
        .into_iter()
        .next()
        .context("decoding the song for the preview")?;
    let sr = audio.sample_rate;
    let a = ((start * f64::from(sr)) as usize).min(audio.samples.len());
    let b = ((end * f64::from(sr)) as usize).min(audio.samples.len());
    let tmp = tempfile::Builder::new().suffix(".wav").tempfile()?;
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: sr,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(tmp.path(), spec)?;
    for &s in &audio.samples[a..b] {
        w.write_sample((s.clamp(-1.0, 1.0) * 32767.0) as i16)?;
    }
    w.finalize()?;
    Ok(tmp)
}

pub(crate) fn preview_motion(
    path: &Path,
    loaded: LoadedMotion,
    kind: Out,
    audio: Option<&Path>,
) -> Result<()> {
    let tracks = tracks_from_motion(path, &loaded)?;
    let opts = RenderOptions::new(PREVIEW_WIDTH, PREVIEW_HEIGHT);
    let scene = Scene::new(&tracks, &opts)?;
    match kind {
        Out::Gif => {
            write::write_gif(path, scene.stream(GIF_FPS), GIF_FPS)?;
        }
        _ => {
            write::write_mp4(
                path,
                scene.stream(FPS as f32),
                PREVIEW_WIDTH,
                PREVIEW_HEIGHT,
                FPS as f32,
                audio,
            )?;
        }
    }
    Ok(())
}
