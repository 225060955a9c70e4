//! Single-dancer metrics. A group scene counts each dancer as a solo sequence (the TCDiff
//! protocol, anchors A.9): one sample per dancer in FID/Div, and a clip's per-clip value is the
//! mean over its dancers where defined.

use anyhow::{Context, Result, bail};
use dancegen_metrics::KineticVariant;
use dancegen_metrics::bas::{self, Variant};
use dancegen_metrics::foot_skating_duration::SkatingDuration;
use dancegen_metrics::protocol::{Prepared, Protocol};

use super::input::Clip;
use crate::EvalOptions;

/// Kinetic (`k`) or geometric (`g`) features of every dancer of every clip, stored as float32
/// as the references do.
pub fn features(set: &[Clip], kind: &str, protocol: &Protocol) -> Result<Vec<Vec<f64>>> {
    let mut out = Vec::new();
    for c in set {
        for d in &c.dancers {
            let f: Vec<f64> = if kind == "k" {
                let k = dancegen_metrics::try_kinetic_features(
                    &d.joints,
                    d.frame_time,
                    KineticVariant::Reference,
                )
                .with_context(|| format!("{}", c.path.display()))?;
                k[..protocol.kinetic_dims()].to_vec()
            } else {
                dancegen_metrics::try_manual_features(&d.joints)
                    .with_context(|| format!("{}", c.path.display()))?
                    .to_vec()
            };
            out.push(f.into_iter().map(|v| v as f32 as f64).collect());
        }
    }
    Ok(out)
}

/// Mean over the dancers where `f` is defined; `None` if it is defined for none.
pub fn over_dancers(
    c: &Clip,
    mut f: impl FnMut(&Prepared) -> Result<Option<f64>>,
) -> Result<Option<f64>> {
    let mut vals = Vec::new();
    for d in &c.dancers {
        if let Some(v) = f(d)? {
            vals.push(v);
        }
    }
    Ok(super::mean(&vals))
}

/// A per-clip metric that needs nothing but the dancer's own motion; `window` is the frames
/// between the boundaries of `boundary_jerk`.
pub fn clip_metric(m: &str, p: &Prepared, window: usize) -> Result<Option<f64>> {
    Ok(match m {
        "pfc" => {
            // EDGE's PFC is Z-up: (x, y, z) → (x, −z, y).
            let mut z = p.joints.clone();
            for v in z.chunks_exact_mut(3) {
                let (y, zz) = (v[1], v[2]);
                v[1] = -zz;
                v[2] = y;
            }
            dancegen_metrics::pfc::pfc_clip_score(&z, 24)
        }
        "fsr" => {
            let r = dancegen_metrics::foot_skating::foot_skating_ratio(&p.joints, 24).ratio();
            r.is_finite().then_some(r)
        }
        "penetration" => dancegen_metrics::penetration::capsule_penetration_ratio(
            &p.joints,
            dancegen_metrics::penetration::DEFAULT_SAMPLES_PER_SEGMENT,
        )?,
        "freeze" => dancegen_metrics::longform::motion_freezing(&p.joints, p.fps)?,
        "inverted" => dancegen_metrics::posture::inverted_share(&p.joints)?,
        "boundary_jerk" => {
            let b: Vec<usize> = (1..)
                .map(|i| i * window)
                .take_while(|&b| b < p.frames)
                .collect();
            if b.is_empty() {
                None
            } else {
                dancegen_metrics::longform::boundary_jerk_ratio(&p.joints, p.fps, &b)?
            }
        }
        other => unreachable!("per-clip metric {other}"),
    })
}

/// Duolando foot-skating duration of a clip, pooled over its dancers.
pub fn skating_duration(c: &Clip) -> Result<SkatingDuration> {
    let mut total = SkatingDuration::default();
    for d in &c.dancers {
        let one = dancegen_metrics::foot_skating_duration(&d.joints)
            .with_context(|| format!("{}: fsd", c.path.display()))?;
        total.skating += one.skating;
        total.steps += one.steps;
    }
    Ok(total)
}

/// MPJPE of a clip against the GT clip of the same stem, dancer by dancer.
pub fn clip_mpjpe(c: &Clip, g: &Clip) -> Result<Option<f64>> {
    if c.dancers.len() != g.dancers.len() {
        tracing::warn!(
            "{}: {} dancers but its --gt clip {} has {}; no mpjpe",
            c.path.display(),
            c.dancers.len(),
            g.path.display(),
            g.dancers.len()
        );
        return Ok(None);
    }
    let n = c.frames().min(g.frames());
    if c.frames() != g.frames() {
        tracing::warn!(
            "{}: {} frames vs {} in the GT; mpjpe over the first {n}",
            c.path.display(),
            c.frames(),
            g.frames()
        );
    }
    let len = n * dancegen_metrics::FRAME_LEN;
    let mut vals = Vec::new();
    for (p, q) in c.dancers.iter().zip(&g.dancers) {
        if let Some(v) = dancegen_metrics::mpjpe::mpjpe_mean(&q.joints[..len], &p.joints[..len], 24)
        {
            vals.push(v);
        }
    }
    Ok(super::mean(&vals))
}

/// Beat align score of a clip (mean over its dancers; for a scene with `--bas-variant gcd`
/// this is GCD's group MMC up to its float32 accumulation).
pub fn clip_bas(c: &Clip, music: &[usize], variant: Variant) -> Result<Option<f64>> {
    over_dancers(c, |d| {
        let motion = bas::try_motion_beats(&d.joints, variant)
            .with_context(|| format!("{}", c.path.display()))?;
        let music = bas::clip_music_beats(music, d.frames, variant);
        Ok(bas::beat_align_score(&music, &motion, variant))
    })
}

/// Beats the BAS of a one-dancer clip compares: `(motion beats, music beats inside the clip)`.
/// They say why a score is low: too few motion beats, or beats in the wrong place. `None` for
/// a scene (one count per dancer would not fit a column).
pub fn clip_beat_counts(
    c: &Clip,
    music: &[usize],
    variant: Variant,
) -> Result<Option<(usize, usize)>> {
    let [d] = c.dancers.as_slice() else {
        return Ok(None);
    };
    let motion = bas::try_motion_beats(&d.joints, variant)
        .with_context(|| format!("{}", c.path.display()))?;
    Ok(Some((
        motion.len(),
        bas::clip_music_beats(music, d.frames, variant).len(),
    )))
}

/// Music-beat frame indices from `--beats` (`.npy` of indices, or a 35-dim feature file whose
/// last column is the beat flag) or `--music` (computed at the clips' frame rate).
pub fn music_beats(args: &EvalOptions, clips: &[Clip]) -> Result<Vec<usize>> {
    if let Some(frames) = &args.beat_frames {
        return Ok(frames.clone());
    }
    if let Some(path) = &args.beats {
        let a = dancegen_io::read_npy(path).with_context(|| format!("{}", path.display()))?;
        if let Some(v) = a.data.iter().find(|v| !v.is_finite()) {
            bail!("{}: beat file holds a non-finite value {v}", path.display());
        }
        return Ok(match a.shape.as_slice() {
            [_] => a
                .data
                .iter()
                .map(|&v| v.round().max(0.0) as usize)
                .collect(),
            [_, d] if *d > 0 => a
                .data
                .chunks(*d)
                .enumerate()
                .filter(|(_, row)| row[d - 1] > 0.0)
                .map(|(i, _)| i)
                .collect(),
            s => bail!(
                "{}: expected beat indices (N,) or features (T, D), got shape {s:?}",
                path.display()
            ),
        });
    }
    let Some(audio) = &args.music else {
        bail!("bas needs --beats or --music");
    };
    let fps = clips.first().map_or(30.0, Clip::fps);
    if clips.iter().any(|c| (c.fps() - fps).abs() > 1e-3) {
        bail!("--music needs all clips at one frame rate");
    }
    let fps_u = fps.round() as u32;
    if fps_u != 30 && fps_u != 60 {
        bail!("--music computes beats at 30 or 60 fps; the motion is at {fps} fps");
    }
    let opts = dancegen_music::features::ExtractOptions {
        fps: fps_u,
        ..Default::default()
    };
    let f = dancegen_music::features::extract(
        &dancegen_music::decode::AudioSource::File(audio.clone()),
        &opts,
    )?;
    Ok(f.beat_frames)
}
