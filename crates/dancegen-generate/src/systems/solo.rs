//! Solo: one dancer for a song (Lodge++, `dancegen_lodgepp`).
//!
//! Song span → EDGE-35 features and beats → Lodge++ → EDGE-151 frames → SMPL motion (Y-up,
//! metres, 30 fps) standing on the floor.

use std::path::Path;

use dancegen_lodgepp::bundle::SoloModel;
use dancegen_lodgepp::choreo_gpt::CHOREOGRAPHY;
use dancegen_lodgepp::inpaint::KnownFrames;
use dancegen_lodgepp::pipeline::{GenerateOptions, Sampler};
use dancegen_motion::repr::motion::FOOT_JOINTS;
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::progress::DENOISING;

use crate::beat_align::align_to_beats;
use crate::edit;
use crate::error::GenerateError;
use crate::song::FPS;
use crate::system::CommonOptions;
use crate::system::{Dance, DanceInput, DanceSystem, Dancer, Role};

/// Shortest music the model dances to (one PDDM window needs material).
pub const MIN_SONG_SECONDS: f64 = 2.0;

/// The Lodge++ long-form sampler.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SoloSampler {
    /// The full system: choreography network, primitives, parallel windows.
    #[default]
    Lodgepp,
    /// EDGE's half-overlapping windows (ablation).
    Edge,
    /// Window after window (ablation).
    Autoregressive,
}

/// Solo options beyond [`CommonOptions`]; the defaults are the shipped system.
#[derive(Clone, Debug)]
pub struct SoloOptions {
    pub sampler: SoloSampler,
    pub foot_refine: bool,
    pub penetration_guidance: bool,
    /// Planted feet stay put (root lock + leg IK; post-processing, not part of Lodge++).
    pub foot_lock: bool,
    /// The dance's kinematic beats are moved onto the song's beats by a time warp
    /// ([`crate::beat_align`]; post-processing, not part of Lodge++).
    pub beat_align: bool,
}

impl Default for SoloOptions {
    fn default() -> Self {
        SoloOptions {
            sampler: SoloSampler::Lodgepp,
            foot_refine: true,
            penetration_guidance: true,
            foot_lock: true,
            beat_align: true,
        }
    }
}

pub struct Solo;

impl DanceSystem for Solo {
    const NAME: &'static str = "solo";
    const MODEL_KIND: &'static str = dancegen_lodgepp::bundle::KIND;
    const DEFAULT_MODEL: &'static str = "lodgepp-small";
    // Measured on the demo song: the GPT's tokens take about a tenth of the generation.
    const PARTS: &'static [(&'static str, f64)] = &[(CHOREOGRAPHY, 0.1), (DENOISING, 0.9)];
    const EDITS: &'static [&'static str] = &edit::OPERATIONS;
    const MIN_SECONDS: f64 = MIN_SONG_SECONDS;
    const SECONDS_PER_DANCED_SECOND: f64 = 0.3;

    type Model = SoloModel;
    type Options = SoloOptions;

    fn load(dir: &Path, device: &Device) -> Result<SoloModel, GenerateError> {
        SoloModel::load(dir, device).map_err(|e| GenerateError::ModelLoad {
            system: "Lodge++",
            dir: dir.to_path_buf(),
            source: Box::new(e),
        })
    }

    fn check(
        model: &SoloModel,
        common: &CommonOptions,
        _: &SoloOptions,
    ) -> Result<(), GenerateError> {
        common.check_sampling("2 = Lodge's default")?;
        genre(model, common).map(|_| ())
    }

    fn dance(
        model: &SoloModel,
        input: DanceInput<'_, SoloOptions>,
    ) -> Result<Dance, GenerateError> {
        let (genre_index, genre_name) = genre(model, input.common)?;
        let song = input.song;
        if !input.common.edit.is_empty() {
            return edit(model, &input, genre_index, &genre_name);
        }
        let span = song.span(input.common.start, input.common.end)?;
        if span.seconds() < MIN_SONG_SECONDS {
            return Err(GenerateError::Invalid(format!(
                "{}: {:.2} s of music to dance to; the model needs at least {MIN_SONG_SECONDS} s",
                song.label,
                span.seconds()
            )));
        }
        let music = song.music(&span);
        let beats = song.beat_frames(&span);
        let opts = generate_options(model, genre_index, input.common, input.options);
        let grad_device = input.device.clone().autodiff();
        let dance =
            model.generate_hooked(music, &beats, &opts, input.device, &grad_device, input.hook)?;
        tracing::info!(
            horizontal_m = dance.seam_correction.horizontal,
            height_m = dance.seam_correction.height,
            "largest root corrections where generated frames meet the shared boundary frames"
        );
        let mut motion = to_smpl(&dance.frames)?;
        let mut notes = Vec::new();
        if dance.rotations_bridged > 0 {
            notes.push(format!(
                "{} joint rotations bridged where the model's 6D output shrank towards zero \
                 (decoding, not part of Lodge++)",
                dance.rotations_bridged
            ));
        }
        if input.options.beat_align {
            let (aligned, a) =
                align_to_beats(&motion, &beats).map_err(GenerateError::Generation)?;
            motion = aligned;
            keep_feet_above_floor(&mut motion).map_err(GenerateError::Generation)?;
            tracing::info!(
                matched = a.matched,
                met_before = a.met_before,
                passes = a.passes,
                motion_beats = a.motion_beats,
                music_beats = a.target_beats,
                max_tempo_change = a.max_tempo_change,
                "beat alignment"
            );
            notes.push(a.note("music"));
        }
        Ok(Dance {
            dancers: vec![Dancer {
                role: Role::Solo,
                motion,
            }],
            span,
            summary: format!(
                "{} frames ({:.1} s at {FPS} fps), genre {genre_name}, seed {}, {} windows, \
                 {} key motions{}",
                dance.n_frames,
                dance.n_frames as f64 / f64::from(FPS),
                input.common.seed,
                dance.windows,
                dance.key_motions,
                match dance.root_flips_repaired {
                    0 => String::new(),
                    n => format!(", {n} root-flip frames repaired"),
                },
            ),
            timing_breakdown: String::new(),
            notes,
            group: None,
            holistic: None,
        })
    }
}

/// An edit (`--edit … --regenerate`, `--continue-from`, `--keep-joints … --from`,
/// `--keyframe`, `--path`): the known frames, joints and root parts stay, the rest is
/// inpainted by the PDDM (`dancegen_lodgepp::inpaint`) without the choreography network, and
/// the known values are spliced back exactly. The beat warp is not applied (it moves frames
/// in time, and known ones must stay where they are); the foot lock runs on the made frames
/// only.
fn edit(
    model: &SoloModel,
    input: &DanceInput<'_, SoloOptions>,
    genre_index: usize,
    genre_name: &str,
) -> Result<Dance, GenerateError> {
    let common = input.common;
    let song = input.song;
    let span = common.edit.span(song, common.start, common.end)?;
    let frames = span.end_frame - span.first_frame;
    if span.seconds() < MIN_SONG_SECONDS {
        return Err(GenerateError::Invalid(format!(
            "{}: {:.2} s of music to dance to from --start; the model needs at least \
             {MIN_SONG_SECONDS} s",
            song.label,
            span.seconds()
        )));
    }
    let known = common
        .edit
        .known(&span, song.seconds())?
        .expect("a non-empty edit knows something");
    let (values, mask) = known.edge151()?;
    let opts = generate_options(model, genre_index, common, input.options);
    let grad_device = input.device.clone().autodiff();
    let done = model.inpaint_hooked(
        song.music(&span),
        &KnownFrames { values, mask },
        &opts,
        input.device,
        &grad_device,
        input.hook,
    )?;
    check_finite(&done.frames)?;
    let mut motion =
        Edge151::decode(&done.frames).map_err(|e| GenerateError::Generation(e.to_string()))?;
    // The floor moves only the root heights that are made; known ones are kept.
    let made: Vec<bool> = known.root_height.iter().map(|&k| !k).collect();
    floor_made_frames(&mut motion, &made)?;
    lift_made_frames_above_floor(&mut motion, &made).map_err(GenerateError::Generation)?;
    known.splice(&mut motion);
    let new = known.frames_to_make();
    Ok(Dance {
        dancers: vec![Dancer {
            role: Role::Solo,
            motion,
        }],
        span,
        summary: format!(
            "{frames} frames ({:.1} s at {FPS} fps), {new} of them new ({:.1} s) in {} windows, \
             genre {genre_name}, seed {}",
            frames as f64 / f64::from(FPS),
            new as f64 / f64::from(FPS),
            done.windows,
            common.seed,
        ),
        timing_breakdown: String::new(),
        notes: vec![format!(
            "an edit: what was given is kept exactly; the new frames join it (root moved by at \
             most {:.2} m to meet the given path); the foot lock on the new frames only, no \
             beat warp",
            done.largest_join_correction_m
        )],
        group: None,
        holistic: None,
    })
}

/// Frames over which an edit's floor correction fades in from a join.
pub const EDIT_FLOOR_BLEND_FRAMES: usize = 15;

/// The made frames of an edit stand on the floor as a whole generation does
/// ([`SmplMotion::put_feet_on_tracked_floor`]), with the correction faded in from each kept
/// frame, whose heights must not change ([`fade_from_kept`]).
pub(crate) fn floor_made_frames(m: &mut SmplMotion, made: &[bool]) -> Result<(), GenerateError> {
    let mut tracked = m.clone();
    tracked
        .put_feet_on_tracked_floor()
        .map_err(|e| GenerateError::Generation(e.to_string()))?;
    for (f, w) in fade_from_kept(made).into_iter().enumerate() {
        m.trans[f * 3 + 1] += w * (tracked.trans[f * 3 + 1] - m.trans[f * 3 + 1]);
    }
    Ok(())
}

/// How much of a correction a frame of an edit takes: 0 on kept frames (`made` false), rising
/// over [`EDIT_FLOOR_BLEND_FRAMES`] from the nearest kept frame to 1 (smootherstep: no step
/// of velocity or acceleration where the correction starts). 1 everywhere when nothing is
/// kept.
pub(crate) fn fade_from_kept(made: &[bool]) -> Vec<f32> {
    let t = made.len();
    // Distance to the nearest kept frame, forwards then backwards.
    let mut d = vec![usize::MAX; t];
    let mut last = None;
    for f in 0..t {
        if !made[f] {
            last = Some(f);
        }
        if let Some(k) = last {
            d[f] = f - k;
        }
    }
    last = None;
    for f in (0..t).rev() {
        if !made[f] {
            last = Some(f);
        }
        if let Some(k) = last {
            d[f] = d[f].min(k - f);
        }
    }
    d.into_iter()
        .map(|d| {
            let u = (d as f32 / EDIT_FLOOR_BLEND_FRAMES as f32).min(1.0);
            u * u * u * (u * (6.0 * u - 15.0) + 10.0)
        })
        .collect()
}

/// Lifts each frame of `made` whose lowest foot joint is below the floor (y = 0) onto it;
/// the others (kept frames of an edit) are not touched.
pub(crate) fn lift_made_frames_above_floor(
    m: &mut SmplMotion,
    made: &[bool],
) -> Result<(), String> {
    let joints = m.joints_world().map_err(|e| e.to_string())?;
    for (f, p) in m.trans.chunks_exact_mut(3).enumerate() {
        if !made[f] {
            continue;
        }
        let low = FOOT_JOINTS
            .iter()
            .map(|&j| joints[(f * 24 + j) * 3 + 1])
            .fold(f32::INFINITY, f32::min);
        if low < 0.0 {
            p[1] -= low;
        }
    }
    Ok(())
}

/// The requested genre (default: the model's) as the model's index and name.
fn genre(model: &SoloModel, common: &CommonOptions) -> Result<(usize, String), GenerateError> {
    let name = common
        .genre
        .clone()
        .unwrap_or_else(|| model.config.default_genre.clone());
    let index = model.genre_index(&name).map_err(GenerateError::Invalid)?;
    Ok((index, name))
}

fn generate_options(
    model: &SoloModel,
    genre: usize,
    common: &CommonOptions,
    solo: &SoloOptions,
) -> GenerateOptions {
    let mut opts = GenerateOptions::defaults(model, genre, common.seed);
    if let Some(s) = common.steps {
        opts.steps = s;
    }
    if let Some(w) = common.guidance {
        opts.guidance = w;
    }
    opts.sampler = match solo.sampler {
        SoloSampler::Lodgepp => Sampler::Lodgepp,
        SoloSampler::Edge => Sampler::Edge,
        SoloSampler::Autoregressive => Sampler::Autoregressive,
    };
    opts.refine = solo.foot_refine;
    if !solo.penetration_guidance {
        opts.penetration = None;
    }
    if !solo.foot_lock {
        opts.foot_lock = false;
    }
    opts
}

/// Raw EDGE-151 frames → SMPL motion standing on the floor: the planted feet at y = 0, frame
/// by frame ([`SmplMotion::put_feet_on_tracked_floor`]: a long generated dance's root height
/// drifts against its legs, and one floor for the whole dance left its feet 0.2 m up in most
/// of some), and no frame with a foot below it.
fn to_smpl(frames: &[f32]) -> Result<SmplMotion, GenerateError> {
    check_finite(frames)?;
    let motion_err = |e: &dyn std::fmt::Display| GenerateError::Generation(e.to_string());
    let mut m = Edge151::decode(frames).map_err(|e| motion_err(&e))?;
    m.put_feet_on_tracked_floor().map_err(|e| motion_err(&e))?;
    keep_feet_above_floor(&mut m).map_err(GenerateError::Generation)?;
    Ok(m)
}

/// A model output with a NaN or infinity is an error, not a dance.
fn check_finite(frames: &[f32]) -> Result<(), GenerateError> {
    if frames.iter().any(|v| !v.is_finite()) {
        return Err(GenerateError::Generation(
            "the model produced non-finite values (please report this with the song and seed)"
                .into(),
        ));
    }
    Ok(())
}

/// Lifts every frame whose lowest foot joint is below the floor (y = 0) onto it.
pub(crate) fn keep_feet_above_floor(m: &mut SmplMotion) -> Result<(), String> {
    let all = vec![true; m.frames()];
    lift_made_frames_above_floor(m, &all)
}
