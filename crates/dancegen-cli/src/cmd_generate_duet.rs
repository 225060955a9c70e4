//! `dancegen generate --leader LEADER`: the partner of a given leader (ReactDance; the bundled
//! models/reactdance-small unless `--model` names another).
//!
//! Leader file → SMPL 24 at 30 fps (BVH retargeted) → follower of the same length, in the
//! leader's world frame (`dancegen_reactdance::pipeline`) → every `-o` file: the couple
//! `[leader, follower]` where the format holds several dancers (.glb, .json, previews), the
//! follower alone in single-dancer formats (.bvh, .npz, and .npy = world joints (T, 24, 3)) or
//! with `--follower-only`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use dancegen_motion::couple_separation::SeparationConfig;
use dancegen_motion::formats::{
    ConvertOptions, LoadedMotion, convert_motion, load_motion_file, save_motion_file,
};
use dancegen_motion::repr::SmplMotion;
use dancegen_reactdance::blc::{LatentSampling, LongForm};
use dancegen_reactdance::bundle::DuetModel;
use dancegen_reactdance::pipeline::generate_follower;

use crate::cli::{GenerateArgs, SamplerArg};
use crate::cmd_generate::{FPS, Out, analyse_song, kind_of, preview_motion, song_segment_wav};
use crate::progress::spinner;

/// The duet model shipped in the repository (`models/reactdance-small`).
pub fn default_duet_model_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/reactdance-small")
}

/// Shortest leader the model accepts: one latent token.
const MIN_LEADER_FRAMES: usize = 8;

/// The leader file as SMPL 24 at 30 fps, or an error naming the file.
pub fn load_leader(path: &Path) -> Result<SmplMotion> {
    let loaded = load_motion_file(path)?;
    let opts = ConvertOptions {
        to_smpl24: true,
        fps: Some(FPS as f32),
        ..Default::default()
    };
    let m = match convert_motion(path, loaded, &opts).with_context(|| {
        format!(
            "{}: cannot use it as the leader (a humanoid skeleton retargets to SMPL 24)",
            path.display()
        )
    })? {
        LoadedMotion::Smpl(m) => m,
        LoadedMotion::Group(g) => bail!(
            "{}: {} dancers; the leader must be one dancer",
            path.display(),
            g.len()
        ),
        other => bail!(
            "{}: a {} has no joint rotations to lead with (give SMPL motion or a humanoid BVH)",
            path.display(),
            other.kind()
        ),
    };
    if m.poses.iter().chain(&m.trans).any(|v| !v.is_finite()) {
        bail!(
            "{}: the motion holds NaN or infinite values",
            path.display()
        );
    }
    if m.frames() < MIN_LEADER_FRAMES {
        bail!(
            "{}: {} frames at {FPS} fps; the leader needs at least {MIN_LEADER_FRAMES}",
            path.display(),
            m.frames()
        );
    }
    Ok(m)
}

fn level_scales(args: &GenerateArgs, defaults: &[f64], levels: usize) -> Result<Vec<f64>> {
    let mut s: Vec<f64> = (0..levels)
        .map(|r| defaults.get(r).or(defaults.last()).copied().unwrap_or(0.0))
        .collect();
    if let Some(w) = args.guidance {
        s = vec![w - 1.0; levels];
    }
    if !args.guidance_levels.is_empty() {
        s = (0..levels)
            .map(|r| {
                *args
                    .guidance_levels
                    .get(r)
                    .or(args.guidance_levels.last())
                    .expect("non-empty")
            })
            .collect();
    }
    if let Some(c) = args.guidance_coarse {
        s[0] = c;
    }
    if let Some(f) = args.guidance_fine {
        s.iter_mut().skip(1).for_each(|v| *v = f);
    }
    if let Some(bad) = s.iter().find(|v| !v.is_finite() || **v < -1.0) {
        bail!("guidance scale {bad}: use s ≥ −1 (0 = conditional only, larger = stronger)");
    }
    Ok(s)
}

pub fn run(args: &GenerateArgs, quiet: bool) -> Result<()> {
    let leader_path = args.leader.as_ref().expect("called with --leader");
    let outputs: Vec<PathBuf> = if args.output.is_empty() {
        vec![PathBuf::from("couple.glb")]
    } else {
        args.output.clone()
    };
    let kinds: Vec<Out> = outputs.iter().map(|p| kind_of(p)).collect::<Result<_>>()?;
    if kinds.contains(&Out::Mp4) && !dancegen_render::write::ffmpeg_available() {
        bail!(dancegen_render::RenderError::FfmpegMissing);
    }
    if args.genre.is_some() {
        bail!("--genre applies to solo dances; the duet model follows the leader's style");
    }
    if args.steps == Some(0) {
        bail!("--steps must be at least 1");
    }
    let long_form = match args.sampler.unwrap_or(SamplerArg::Blc) {
        SamplerArg::Blc => LongForm::Blc,
        SamplerArg::Autoregressive => LongForm::Autoregressive,
        other => {
            bail!("--sampler {other:?} is a solo sampler; with --leader use blc or autoregressive")
        }
    };
    let started = Instant::now();
    let leader = load_leader(leader_path)?;
    let device = dancegen_lodgepp::inference_device();
    let model_dir = args.model.clone().unwrap_or_else(default_duet_model_dir);
    let pb = spinner("loading the duet model", quiet);
    let model = DuetModel::load(&model_dir, &device).with_context(|| {
        format!(
            "loading the duet model in {} (give another with --model DIR)",
            model_dir.display()
        )
    })?;
    pb.finish_and_clear();
    let levels = model.config.autoencoder.num_levels;
    let guidance = level_scales(args, &model.config.sampling.guidance, levels)?;

    let (source, label, feats) = analyse_song(args.song.as_ref(), quiet)?;
    let total = feats.features.rows;
    let start = args.start.unwrap_or(0.0);
    if !(start.is_finite() && start >= 0.0) {
        bail!("--start {start}: give a time in seconds ≥ 0");
    }
    if args.end.is_some() {
        bail!("--end does not apply with --leader: the music is cut to the leader's length");
    }
    let f0 = (start * f64::from(FPS)).round() as usize;
    let t = leader.frames();
    let fps = f64::from(FPS);
    if f0 + t > total {
        bail!(
            "{label}: the song is shorter than the leader: {:.2} s of music from {start:.2} s, \
             the leader {} lasts {:.2} s ({t} frames at {FPS} fps)",
            total.saturating_sub(f0) as f64 / fps,
            leader_path.display(),
            t as f64 / fps
        );
    }
    let cols = feats.features.cols;
    let music = &feats.features.data[f0 * cols..(f0 + t) * cols];
    let sampling = LatentSampling {
        steps: args.steps.unwrap_or(model.config.sampling.steps),
        eta: model.config.sampling.eta,
        guidance: guidance.clone(),
        seed: args.seed,
        long_form,
    };
    let pb = spinner(
        &format!(
            "dancing with {} ({:.1} s)",
            leader_path.display(),
            t as f64 / fps
        ),
        quiet,
    );
    let t_gen = Instant::now();
    let separation = (!args.no_separation).then(SeparationConfig::default);
    let out = generate_follower(
        &model,
        &leader,
        music,
        &sampling,
        separation.as_ref(),
        &device,
    )
    .map_err(anyhow::Error::msg)
    .context("generating the follower")?;
    let gen_secs = t_gen.elapsed().as_secs_f64();
    pb.finish_and_clear();

    let couple = LoadedMotion::Group(vec![leader.clone(), out.follower.clone()]);
    let follower = LoadedMotion::Smpl(out.follower.clone());
    for (path, kind) in outputs.iter().zip(&kinds) {
        let single_format = matches!(
            path.extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase)
                .as_deref(),
            Some("bvh" | "npz" | "npy")
        );
        let what = if args.follower_only || single_format {
            &follower
        } else {
            &couple
        };
        match kind {
            Out::Motion => save_motion_file(path, what, &ConvertOptions::default())?,
            Out::Gif | Out::Mp4 => {
                let what = if args.follower_only {
                    &follower
                } else {
                    &couple
                };
                let audio = if *kind == Out::Mp4 {
                    Some(song_segment_wav(&source, start, start + t as f64 / fps)?)
                } else {
                    None
                };
                preview_motion(path, what.clone(), *kind, audio.as_ref().map(|a| a.path()))?;
            }
        }
    }
    if !quiet {
        let mut o = std::io::stdout().lock();
        writeln!(
            o,
            "{label}: follower of {} ({t} frames, {:.1} s at {FPS} fps), seed {}, {:?} sampling, \
             guidance {:?}; generated in {gen_secs:.2} s (sampling {:.2} s, decoding {:.2} s; \
             {:.2} s in total); {}",
            leader_path.display(),
            t as f64 / fps,
            args.seed,
            long_form,
            guidance,
            out.sample_s,
            out.decode_s,
            started.elapsed().as_secs_f64(),
            match separation {
                None => "no separation".to_string(),
                Some(_) => format!(
                    "separated from the leader by up to {:.0} mm in {:.2} s",
                    out.separation_max_m * 1000.0,
                    out.separate_s
                ),
            }
        )?;
        for p in &outputs {
            writeln!(o, "  -> {}", p.display())?;
        }
    }
    Ok(())
}
