//! Group: 2–5 dancers from one song (TCDiff++, `dancegen_tcdiffpp`), free or following a
//! choreographer's formation (`FORMATION.json`, `dancegen_refine::formation::keyframes`).
//!
//! The model samples every dancer at once ([`dancegen_tcdiffpp::sampler::generate`]: LGDS or
//! the parallel long-form sampler, formation paths injected as clean roots). Then, per dancer,
//! the solo system's planted-feet pass (`dancegen_lodgepp::planted_feet`: leg IK always; the
//! root lock only for a dancer no formation constrains, since it would move the root off its
//! requested path), one shared floor, and the couple separation extended to the group
//! ([`group_separation_offsets`]). `--unison` gives every dancer the body motion of the
//! leftmost one (post-processing, not part of TCDiff++), each on its own path.

use std::path::Path;

use dancegen_lodgepp::planted_feet::{clean_planted_feet, pin_planted_feet};
use dancegen_motion::repr::motion::POSE_DIMS;
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::progress::DENOISING;
use dancegen_refine::couple_separation::{SeparationConfig, group_separation_offsets};
use dancegen_refine::formation::{StagePos, order_left_to_right};
use dancegen_tcdiffpp::bundle::GroupModel;
pub use dancegen_tcdiffpp::config::LongSampler;
use dancegen_tcdiffpp::layout::{GROUP_DIMS, N_MAX, N_MIN};
use dancegen_tcdiffpp::sampler::{GroupRequest, GroupSampleOptions, RootXy, generate};

use crate::edit;
use crate::error::GenerateError;
use crate::formation_file::{ANY_SONG_SECONDS, FormationFile};
use crate::song::{FPS, Span};
use crate::system::CommonOptions;
use crate::system::{Dance, DanceInput, DanceSystem, Dancer, GroupReport, Role};
use crate::systems::solo::keep_feet_above_floor;

/// Dancer counts the group model serves (front ends check them before a job starts).
pub const MIN_DANCERS: usize = N_MIN;
pub const MAX_DANCERS: usize = N_MAX;

/// Shortest music a group dance is made for (one half window of the model, 2.5 s).
pub const MIN_GROUP_SECONDS: f64 = 2.5;

/// Group options beyond [`CommonOptions`].
#[derive(Clone, Debug)]
pub struct GroupOptions {
    pub dancers: usize,
    pub formation: Option<FormationFile>,
    /// Every dancer dances the leftmost dancer's moves.
    pub unison: bool,
    /// `None`: the model's default.
    pub sampler: Option<LongSampler>,
    /// Move dancers out of each other's bodies.
    pub separation: bool,
    /// Planted-feet pass (leg IK, and the root lock for free dancers).
    pub foot_lock: bool,
}

impl GroupOptions {
    pub fn new(dancers: usize) -> Self {
        GroupOptions {
            dancers,
            formation: None,
            unison: false,
            sampler: None,
            separation: true,
            foot_lock: true,
        }
    }

    /// Reads `path` as a formation file (checked later against the song).
    pub fn with_formation_file(mut self, path: &Path) -> Result<Self, GenerateError> {
        self.formation = Some(FormationFile::read(path, "the formation")?);
        Ok(self)
    }
}

pub struct Group;

impl DanceSystem for Group {
    const NAME: &'static str = "group";
    const MODEL_KIND: &'static str = dancegen_tcdiffpp::bundle::KIND;
    const DEFAULT_MODEL: &'static str = "tcdiffpp-small";
    const PARTS: &'static [(&'static str, f64)] = &[(DENOISING, 1.0)];
    const EDITS: &'static [&'static str] = &[
        edit::REGENERATE,
        edit::EXTEND,
        edit::CONTINUE,
        edit::KEEP_JOINTS,
        edit::KEYFRAME,
        edit::PATH,
    ];

    type Model = GroupModel;
    type Options = GroupOptions;

    fn load(dir: &Path, device: &Device) -> Result<GroupModel, GenerateError> {
        GroupModel::load(dir, device).map_err(|e| GenerateError::ModelLoad {
            system: "group",
            dir: dir.to_path_buf(),
            source: Box::new(e),
        })
    }

    fn check(
        _model: &GroupModel,
        common: &CommonOptions,
        group: &GroupOptions,
    ) -> Result<(), GenerateError> {
        if !(N_MIN..=N_MAX).contains(&group.dancers) {
            return Err(GenerateError::Invalid(format!(
                "--dancers {}: the group model dances {N_MIN} to {N_MAX} dancers",
                group.dancers
            )));
        }
        if common.genre.is_some() {
            return Err(GenerateError::Invalid(
                "--genre applies to solo dances; the group model has no genre control".into(),
            ));
        }
        if common.steps == Some(0) {
            return Err(GenerateError::Invalid("--steps must be at least 1".into()));
        }
        if let Some(w) = common.guidance
            && !(w.is_finite() && w >= 0.0)
        {
            return Err(GenerateError::Invalid(format!(
                "--guidance {w}: use a non-negative number (1 = no guidance, 2 = the default)"
            )));
        }
        // Everything but the times against the song's length (checked once it is known).
        if let Some(f) = &group.formation {
            f.parse(group.dancers, ANY_SONG_SECONDS)?;
        }
        Ok(())
    }

    fn dance(
        model: &GroupModel,
        input: DanceInput<'_, GroupOptions>,
    ) -> Result<Dance, GenerateError> {
        // A group's paths are its formation: `--path` is one (the same format).
        if let Some(path) = &input.common.edit.path {
            if input.options.formation.is_some() {
                return Err(GenerateError::Invalid(format!(
                    "--path {} and --formation both give the group's paths; give one",
                    path.label
                )));
            }
            let mut common = input.common.clone();
            common.edit.path = None;
            let options = GroupOptions {
                formation: Some(path.clone()),
                ..input.options.clone()
            };
            return Self::dance(
                model,
                DanceInput {
                    common: &common,
                    options: &options,
                    ..input
                },
            );
        }
        if !input.common.edit.is_empty() {
            return super::group_edit::edit(model, &input);
        }
        let (common, opts, song) = (input.common, input.options, input.song);
        let n = opts.dancers;
        let span = song.span(common.start, common.end)?;
        if span.seconds() < MIN_GROUP_SECONDS {
            return Err(GenerateError::Invalid(format!(
                "{}: {:.2} s of music to dance to; a group dance needs at least \
                 {MIN_GROUP_SECONDS} s",
                song.label,
                span.seconds()
            )));
        }
        let frames = span.end_frame - span.first_frame;
        let fps = f64::from(FPS);
        let (requested, control) = requested_paths(opts, n, &span, song.seconds(), frames)?;
        let partial = requested
            .as_ref()
            .is_some_and(|r| r.iter().any(|track| track.iter().any(Option::is_none)));
        let sample = sample_options(model, common, opts, partial);
        let req = GroupRequest {
            music: song.music(&span),
            frames,
            dancers: n,
            control: control.as_deref(),
            known: None,
        };
        let t0 = std::time::Instant::now();
        let raw = generate(
            &model.net,
            &model.schedule,
            model.config.model.window(),
            &req,
            &sample,
            input.device,
            input.hook,
        )?;
        let sample_s = t0.elapsed().as_secs_f64();
        if raw.iter().any(|v| !v.is_finite()) {
            return Err(GenerateError::Generation(
                "the model produced non-finite values (please report this with the song and seed)"
                    .into(),
            ));
        }
        let t1 = std::time::Instant::now();
        let d = Edge151::DIMS;
        let mut dancers: Vec<SmplMotion> = Vec::with_capacity(n);
        for s in 0..n {
            let mut own: Vec<f32> = raw
                .chunks_exact(GROUP_DIMS)
                .flat_map(|f| f[s * d..(s + 1) * d].iter().copied())
                .collect();
            if opts.foot_lock {
                let constrained = requested
                    .as_ref()
                    .is_some_and(|r| r[s].iter().any(Option::is_some));
                if constrained {
                    pin_planted_feet(&mut own);
                } else {
                    clean_planted_feet(&mut own);
                }
            }
            dancers
                .push(Edge151::decode(&own).map_err(|e| GenerateError::Generation(e.to_string()))?);
        }
        let mut notes = Vec::new();
        if opts.unison {
            let lead = order_left_to_right(&stage_positions(&dancers, 0)?)[0];
            let poses = dancers[lead].poses.clone();
            for m in dancers.iter_mut() {
                let len = m.frames() * POSE_DIMS;
                m.poses.copy_from_slice(&poses[..len]);
            }
            notes.push(format!("unison: every dancer dances dancer {lead}'s moves"));
        }
        put_on_one_floor(&mut dancers)?;
        if opts.separation {
            let largest = separate(&mut dancers, None)?;
            notes.push(format!(
                "dancers kept apart by moving them up to {:.0} mm",
                largest * 1000.0
            ));
        }
        let post_s = t1.elapsed().as_secs_f64();
        let report = stage_report(&dancers, requested.clone(), frames, &mut notes)?;
        Ok(Dance {
            dancers: dancers
                .into_iter()
                .map(|motion| Dancer {
                    role: Role::Member,
                    motion,
                })
                .collect(),
            span,
            summary: format!(
                "{n} dancers, {frames} frames ({:.1} s at {FPS} fps), seed {}, {:?} sampling, \
                 {} steps, guidance {}{}",
                frames as f64 / fps,
                common.seed,
                sample.sampler,
                sample.steps,
                sample.guidance,
                if requested.is_some() {
                    ", formation given"
                } else {
                    ""
                },
            ),
            timing_breakdown: format!("sampling {sample_s:.2} s, post-processing {post_s:.2} s; "),
            notes,
            group: Some(report),
            holistic: None,
        })
    }
}

/// The sampling of a request: the model's defaults, the flags' overrides.
pub(super) fn sample_options(
    model: &GroupModel,
    common: &CommonOptions,
    opts: &GroupOptions,
    partial: bool,
) -> GroupSampleOptions {
    let sampling = &model.config.model.sampling;
    GroupSampleOptions {
        steps: common.steps.unwrap_or(sampling.steps),
        eta: sampling.eta,
        spacing: sampling.spacing,
        guidance: common.guidance.unwrap_or(sampling.guidance),
        sampler: opts.sampler.unwrap_or(if partial {
            // The parallel sampler drops control in windows whose first frame does not give
            // every dancer (it cannot place them; `dancegen_tcdiffpp::sampler`), so a
            // formation with free dancers is sampled window by window.
            LongSampler::Lgds
        } else {
            sampling.sampler
        }),
        prefix: sampling.prefix,
        seed: common.seed,
    }
}

/// Requested stage paths of the danced frames, `[dancer][frame]`, and the same as the
/// model's control (Z-up root x/y, `[frame · N_MAX + dancer]`), from `--formation`.
#[allow(clippy::type_complexity)]
pub(super) fn requested_paths(
    opts: &GroupOptions,
    n: usize,
    span: &Span,
    song_seconds: f64,
    frames: usize,
) -> Result<
    (
        Option<Vec<Vec<Option<StagePos>>>>,
        Option<Vec<Option<RootXy>>>,
    ),
    GenerateError,
> {
    let formation = match &opts.formation {
        Some(f) => Some(f.parse(n, song_seconds)?),
        None => None,
    };
    let requested: Option<Vec<Vec<Option<StagePos>>>> = formation.as_ref().map(|f| {
        f.sample(f64::from(FPS), span.end_frame)
            .into_iter()
            .map(|track| track[span.first_frame..].to_vec())
            .collect()
    });
    if let Some(r) = &requested
        && r.iter().all(|track| track.iter().all(Option::is_none))
    {
        tracing::warn!("the formation constrains no frame of the danced span");
    }
    // Stage [x, z] (Y-up) → the model's Z-up root (x, −z).
    let control = requested.as_ref().map(|r| {
        let mut c = vec![None; frames * N_MAX];
        for (d, track) in r.iter().enumerate() {
            for (f, p) in track.iter().enumerate().take(frames) {
                c[f * N_MAX + d] = p.map(|[x, z]| [x as f32, -z as f32]);
            }
        }
        c
    });
    Ok((requested, control))
}

/// Moves the dancers out of each other's bodies (the couple separation extended to the group,
/// [`group_separation_offsets`]); each dancer's move on each frame scaled by `weights`
/// (`[dancer][frame]`; an edit's kept frames do not move). Returns the largest move, metres.
pub(super) fn separate(
    dancers: &mut [SmplMotion],
    weights: Option<&[Vec<f32>]>,
) -> Result<f64, GenerateError> {
    let joints = world_joints(dancers)?;
    let offsets = group_separation_offsets(&joints, &SeparationConfig::group());
    let mut largest = 0f64;
    for (d, (m, off)) in dancers.iter_mut().zip(&offsets).enumerate() {
        for (f, (p, o)) in m.trans.chunks_exact_mut(3).zip(off).enumerate() {
            let w = weights.map_or(1.0, |w| f64::from(w[d][f]));
            let o = [o[0] * w, o[1] * w];
            p[0] += o[0] as f32;
            p[2] += o[1] as f32;
            largest = largest.max(o[0].hypot(o[1]));
        }
    }
    Ok(largest)
}

/// The stage record of a group dance: start and end order, every dancer's floor path, and
/// how well a requested formation was followed (also said in `notes`).
pub(super) fn stage_report(
    dancers: &[SmplMotion],
    requested: Option<Vec<Vec<Option<StagePos>>>>,
    frames: usize,
    notes: &mut Vec<String>,
) -> Result<GroupReport, GenerateError> {
    let trajectories: Vec<Vec<[f64; 2]>> = world_joints(dancers)?
        .iter()
        .map(|j| j.chunks_exact(72).map(|f| [f[0], f[2]]).collect())
        .collect();
    let at = |t: usize| -> Vec<usize> {
        order_left_to_right(&trajectories.iter().map(|tr| tr[t]).collect::<Vec<_>>())
    };
    let (mut err_sum, mut err_n) = (0.0, 0usize);
    let mut final_err: Option<f64> = None;
    if let Some(r) = &requested {
        // Final error: each constrained dancer's last constrained frame.
        let mut finals = Vec::new();
        for (tr, want) in trajectories.iter().zip(r) {
            let mut last = None;
            for (p, w) in tr.iter().zip(want) {
                if let Some(w) = w {
                    let e = (p[0] - w[0]).hypot(p[1] - w[1]);
                    err_sum += e;
                    err_n += 1;
                    last = Some(e);
                }
            }
            finals.extend(last);
        }
        if !finals.is_empty() {
            final_err = Some(finals.iter().sum::<f64>() / finals.len() as f64);
        }
    }
    let mean_err = (err_n > 0).then(|| err_sum / err_n as f64);
    if let Some(e) = mean_err {
        notes.push(format!(
            "formation followed within {:.0} mm on average ({:.0} mm at the end)",
            e * 1000.0,
            final_err.unwrap_or(0.0) * 1000.0
        ));
    }
    Ok(GroupReport {
        start_order: at(0),
        end_order: at(frames.saturating_sub(1)),
        trajectories,
        requested,
        trajectory_error_mean_m: mean_err,
        trajectory_error_final_m: final_err,
    })
}

fn world_joints(dancers: &[SmplMotion]) -> Result<Vec<Vec<f64>>, GenerateError> {
    dancers
        .iter()
        .map(|m| {
            m.joints_world()
                .map(|j| j.into_iter().map(f64::from).collect())
                .map_err(|e| GenerateError::Generation(e.to_string()))
        })
        .collect()
}

fn stage_positions(dancers: &[SmplMotion], t: usize) -> Result<Vec<StagePos>, GenerateError> {
    Ok(world_joints(dancers)?
        .iter()
        .map(|j| [j[t * 72], j[t * 72 + 2]])
        .collect())
}

/// Every dancer on the stage floor, y = 0, as the solo system puts its dancer
/// ([`SmplMotion::put_feet_on_tracked_floor`]): each dancer's root height is shifted frame by
/// frame so that the floor its planted feet stand on is y = 0, then no frame has a foot under
/// it. One shared constant floor for the group (what this did until the residual footwork
/// adaptor) left dancers whose root height drifts against their legs 15-20 cm in the air for
/// most of a 60 s dance (5 dancers, feelings.ogg 60-120 s, seed 3: 55-72 % of frames floating
/// for three of them).
fn put_on_one_floor(dancers: &mut [SmplMotion]) -> Result<(), GenerateError> {
    for m in dancers.iter_mut() {
        m.put_feet_on_tracked_floor()
            .map_err(|e| GenerateError::Generation(e.to_string()))?;
        keep_feet_above_floor(m).map_err(GenerateError::Generation)?;
    }
    Ok(())
}
