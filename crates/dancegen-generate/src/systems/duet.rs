//! Duet: the partner of a given leader (ReactDance, `dancegen_reactdance`).
//!
//! Leader (SMPL 24 at 30 fps) + the music from `start` for the leader's length → follower
//! of the same length in the leader's world frame, then (each unless turned off) its planted
//! feet locked, its beats time-warped onto the leader's, and moved out of the leader's body by
//! the couple separation. The dance is `[leader, follower]`.

use std::path::Path;

use dancegen_lodgepp::inpaint::{KnownFrames, join_made_runs};
use dancegen_lodgepp::planted_feet::{PlantedRule, lock_planted_feet_leashed};
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::progress::DENOISING;
use dancegen_reactdance::blc::{LatentSampling, LongForm};
use dancegen_reactdance::bundle::DuetModel;
use dancegen_reactdance::pipeline::{
    FollowerError, KnownFollower, generate_follower_hooked, generate_follower_known,
    separate_follower,
};
use dancegen_refine::couple_separation::SeparationConfig;

use crate::beat_align::align_follower_to_leader;
use crate::edit::{self, GivenMotion};
use crate::error::GenerateError;
use crate::song::{FPS, Span};
use crate::system::CommonOptions;
use crate::system::{Dance, DanceInput, DanceSystem, Dancer, Role};

/// Shortest leader the model accepts: one latent token.
pub const MIN_LEADER_FRAMES: usize = 8;

/// The latent's long-form sampler.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DuetSampler {
    /// Blocked Local Context: every block at once (ReactDance).
    #[default]
    Blc,
    /// Window by window (ablation).
    Autoregressive,
}

/// Duet options beyond [`CommonOptions`] (whose `guidance` is one weight for every level,
/// single-scale CFG with s = w − 1, and whose `genre` and `end` do not apply).
#[derive(Clone, Debug)]
pub struct DuetOptions {
    /// The leader, SMPL 24 at 30 fps ([`load_leader`]).
    pub leader: SmplMotion,
    /// How the leader is named in messages (its file).
    pub leader_label: String,
    pub sampler: DuetSampler,
    /// Guidance s of the coarse (base) HFSQ level.
    pub guidance_coarse: Option<f64>,
    /// Guidance s of the fine (residual) levels.
    pub guidance_fine: Option<f64>,
    /// Guidance s per level, coarse first (the last value repeats).
    pub guidance_levels: Vec<f64>,
    /// Move the follower out of the leader's body (hands may touch).
    pub separation: bool,
    /// Keep the follower's root from gliding over its planted feet, as the model's
    /// `[sampling]` says (root lock on a leash, no leg IK; post-processing, not part of
    /// ReactDance). `false` switches it off whatever the model says.
    pub foot_lock: bool,
    /// Time-warp the follower so its beats echo the leader's ([`crate::beat_align`];
    /// post-processing, not part of ReactDance).
    pub beat_align: bool,
}

impl DuetOptions {
    /// The shipped system's options for `leader`.
    pub fn new(leader: SmplMotion, leader_label: impl Into<String>) -> Self {
        DuetOptions {
            leader,
            leader_label: leader_label.into(),
            sampler: DuetSampler::Blc,
            guidance_coarse: None,
            guidance_fine: None,
            guidance_levels: Vec::new(),
            separation: true,
            foot_lock: true,
            beat_align: true,
        }
    }
}

/// The leader file as SMPL 24 at 30 fps, or an error naming the file. Any format `convert`
/// reads; a humanoid BVH is retargeted. A file with no usable rate is refused with `dancegen
/// convert --source-fps` as the way to give one (the web app takes no rate).
pub fn load_leader(path: &Path) -> Result<SmplMotion, GenerateError> {
    load_leader_with(
        path,
        None,
        "convert it first: dancegen convert FILE --source-fps N -o leader.npz",
    )
}

/// [`load_leader`] of a file sampled at `source_fps` whatever its header says (the CLI's
/// `--leader-fps`; `None`: the file's own rate).
pub fn load_leader_at(path: &Path, source_fps: Option<f64>) -> Result<SmplMotion, GenerateError> {
    load_leader_with(path, source_fps, "--leader-fps N")
}

fn load_leader_with(
    path: &Path,
    source_fps: Option<f64>,
    rate_hint: &'static str,
) -> Result<SmplMotion, GenerateError> {
    let invalid = |why: String| GenerateError::Invalid(format!("{}: {why}", path.display()));
    let m = GivenMotion::load(path, "the leader", source_fps, rate_hint)?.motion;
    if m.frames() < MIN_LEADER_FRAMES {
        return Err(invalid(format!(
            "{} frames at {FPS} fps; the leader needs at least {MIN_LEADER_FRAMES}",
            m.frames()
        )));
    }
    Ok(m)
}

/// Guidance scale per HFSQ level: the model's, or one weight for all (`--guidance`), or the
/// given list, then the coarse and fine overrides.
fn level_scales(
    common: &CommonOptions,
    duet: &DuetOptions,
    defaults: &[f64],
    levels: usize,
) -> Result<Vec<f64>, GenerateError> {
    let pick = |v: &[f64], r: usize| v.get(r).or(v.last()).copied();
    let mut s: Vec<f64> = (0..levels)
        .map(|r| pick(defaults, r).unwrap_or(0.0))
        .collect();
    if let Some(w) = common.guidance {
        s = vec![w - 1.0; levels];
    }
    if !duet.guidance_levels.is_empty() {
        s = (0..levels)
            .map(|r| pick(&duet.guidance_levels, r).unwrap_or(0.0))
            .collect();
    }
    if let Some(c) = duet.guidance_coarse
        && let Some(first) = s.first_mut()
    {
        *first = c;
    }
    if let Some(f) = duet.guidance_fine {
        s.iter_mut().skip(1).for_each(|v| *v = f);
    }
    if let Some(bad) = s.iter().find(|v| !v.is_finite() || **v < -1.0) {
        return Err(GenerateError::Invalid(format!(
            "guidance scale {bad}: use s ≥ −1 (0 = conditional only, larger = stronger)"
        )));
    }
    Ok(s)
}

pub struct Duet;

impl DanceSystem for Duet {
    const NAME: &'static str = "duet";
    const MODEL_KIND: &'static str = dancegen_reactdance::bundle::KIND;
    const DEFAULT_MODEL: &'static str = "reactdance-small";
    const PARTS: &'static [(&'static str, f64)] = &[(DENOISING, 1.0)];
    const EDITS: &'static [&'static str] = &[edit::REGENERATE, edit::CONTINUE];
    const MIN_SECONDS: f64 = MIN_LEADER_FRAMES as f64 / FPS as f64;
    const SECONDS_PER_DANCED_SECOND: f64 = 0.3;

    type Model = DuetModel;
    type Options = DuetOptions;

    fn load(dir: &Path, device: &Device) -> Result<DuetModel, GenerateError> {
        DuetModel::load(dir, device).map_err(|e| GenerateError::ModelLoad {
            system: "duet",
            dir: dir.to_path_buf(),
            source: Box::new(e),
        })
    }

    fn check(
        model: &DuetModel,
        common: &CommonOptions,
        duet: &DuetOptions,
    ) -> Result<(), GenerateError> {
        if common.genre.is_some() {
            return Err(GenerateError::Invalid(
                "--genre applies to solo dances; the duet model follows the leader's style".into(),
            ));
        }
        if common.steps == Some(0) {
            return Err(GenerateError::Invalid("--steps must be at least 1".into()));
        }
        if common.end.is_some() {
            return Err(GenerateError::Invalid(
                "--end does not apply with --leader: the music is cut to the leader's length"
                    .into(),
            ));
        }
        if let Some(start) = common.start
            && !(start.is_finite() && start >= 0.0)
        {
            return Err(GenerateError::Invalid(format!(
                "--start {start}: give a time in seconds ≥ 0"
            )));
        }
        let levels = model.config.autoencoder.num_levels;
        level_scales(common, duet, &model.config.sampling.guidance, levels).map(|_| ())
    }

    fn dance(
        model: &DuetModel,
        input: DanceInput<'_, DuetOptions>,
    ) -> Result<Dance, GenerateError> {
        let (common, duet, song) = (input.common, input.options, input.song);
        let levels = model.config.autoencoder.num_levels;
        let guidance = level_scales(common, duet, &model.config.sampling.guidance, levels)?;
        let leader = &duet.leader;
        let start = common.start.unwrap_or(0.0);
        let fps = f64::from(FPS);
        let f0 = (start * fps).round() as usize;
        let t = leader.frames();
        let total = song.frames();
        if f0 + t > total {
            return Err(GenerateError::Invalid(format!(
                "{}: the song is shorter than the leader: {:.2} s of music from {start:.2} s, \
                 the leader {} lasts {:.2} s ({t} frames at {FPS} fps)",
                song.label,
                total.saturating_sub(f0) as f64 / fps,
                duet.leader_label,
                t as f64 / fps
            )));
        }
        let span = Span {
            start_s: start,
            end_s: start + t as f64 / fps,
            first_frame: f0,
            end_frame: f0 + t,
        };
        let long_form = match duet.sampler {
            DuetSampler::Blc => LongForm::Blc,
            DuetSampler::Autoregressive => LongForm::Autoregressive,
        };
        let sampling = LatentSampling {
            steps: common.steps.unwrap_or(model.config.sampling.steps),
            eta: model.config.sampling.eta,
            guidance: guidance.clone(),
            seed: common.seed,
            long_form,
        };
        let separation = duet.separation.then(SeparationConfig::default);
        if !common.edit.is_empty() {
            return edit_follower(model, &input, span, &sampling, separation.as_ref());
        }
        let foot_lock = (duet.foot_lock && model.config.sampling.foot_lock)
            .then_some(model.config.sampling.foot_lock_leash_frames);
        // Post-processing order: foot lock, beat alignment, separation (the separation runs
        // last so nothing moves the follower back into the leader).
        let separate_later = duet.beat_align || foot_lock.is_some();
        let out = generate_follower_hooked(
            model,
            leader,
            song.music(&span),
            &sampling,
            separation.as_ref().filter(|_| !separate_later),
            input.device,
            input.hook,
        )
        .map_err(follower_error)?;
        let mut follower = out.follower;
        let mut notes = Vec::new();
        if out.rotations_bridged > 0 {
            notes.push(format!(
                "{} joint rotations bridged where the model's 6D output shrank towards zero \
                 (decoding, not part of ReactDance)",
                out.rotations_bridged
            ));
        }
        let mut separation_max_m = out.separation_max_m;
        let mut separate_s = out.separate_s;
        if let Some(leash) = foot_lock {
            let rule = model.config.sampling.foot_lock_rule;
            lock_follower_feet(&mut follower, &out.contacts, rule, leash)?;
            notes.push(format!(
                "follower's root kept from gliding over planted feet ({rule:?} rule, on a \
                 {leash:.0}-frame leash; post-processing, not part of ReactDance)"
            ));
        }
        if duet.beat_align {
            let (aligned, a) =
                align_follower_to_leader(&follower, leader).map_err(GenerateError::Generation)?;
            follower = aligned;
            tracing::info!(
                matched = a.matched,
                met_before = a.met_before,
                passes = a.passes,
                follower_beats = a.motion_beats,
                leader_beats = a.target_beats,
                max_tempo_change = a.max_tempo_change,
                "beat alignment"
            );
            notes.push(a.note("leader"));
        }
        if separate_later && let Some(config) = &separation {
            let t0 = std::time::Instant::now();
            separation_max_m = separate_follower(&mut follower, leader, config)
                .map_err(GenerateError::Generation)?;
            separate_s = t0.elapsed().as_secs_f64();
        }
        notes.push(match separation {
            None => "no separation".to_string(),
            Some(_) => format!(
                "separated from the leader by up to {:.0} mm in {:.2} s",
                separation_max_m * 1000.0,
                separate_s
            ),
        });
        Ok(Dance {
            dancers: couple(leader, follower),
            span,
            summary: format!(
                "follower of {} ({t} frames, {:.1} s at {FPS} fps), seed {}, {long_form:?} \
                 sampling, guidance {guidance:?}",
                duet.leader_label,
                t as f64 / fps,
                common.seed,
            ),
            timing_breakdown: format!(
                "sampling {:.2} s, decoding {:.2} s; ",
                out.sample_s, out.decode_s
            ),
            notes,
            group: None,
            holistic: None,
        })
    }
}

/// The solo system's root lock on the follower, through EDGE-151 frames whose contact channel
/// is the model's own (`contacts`, `[T, 4]`), combined with nearness to the floor by `rule`,
/// on a leash of `leash_frames`: the follower's place comes from the model, beside the leader,
/// and an unleashed lock would carry it away by every glide it removes. No leg IK: pinning each
/// contact run's feet raised MPJPE by 40 mm on training and held-out couples alike
/// The dance's two dancers: the given leader, then the generated follower.
fn couple(leader: &SmplMotion, follower: SmplMotion) -> Vec<Dancer> {
    vec![
        Dancer {
            role: Role::Leader,
            motion: leader.clone(),
        },
        Dancer {
            role: Role::Follower,
            motion: follower,
        },
    ]
}

/// Why the follower could not be made, as the generator reports it.
fn follower_error(e: FollowerError) -> GenerateError {
    match e {
        FollowerError::Cancelled(_) => GenerateError::Cancelled,
        FollowerError::Invalid(why) => {
            GenerateError::Generation(format!("generating the follower: {why}"))
        }
    }
}

/// An edit of the follower (`--edit FOLLOWER --regenerate A-B`, `--continue-from`): the
/// latent tokens of the kept frames are hard cues to the sampler
/// ([`dancegen_reactdance::pipeline::generate_follower_known`]), the new frames are joined to
/// the kept ones as the solo system's are ([`join_made_runs`]) and the kept frames are the
/// input's exactly. The separation runs on the model's follower before the join; the foot
/// lock and the beat warp are not applied (both move kept frames).
fn edit_follower(
    model: &DuetModel,
    input: &DanceInput<'_, DuetOptions>,
    span: Span,
    sampling: &LatentSampling,
    separation: Option<&SeparationConfig>,
) -> Result<Dance, GenerateError> {
    let (common, duet, song) = (input.common, input.options, input.song);
    let leader = &duet.leader;
    let t = leader.frames();
    if let Some(b) = &common.edit.base
        && b.motion.frames() != t
    {
        return Err(GenerateError::Invalid(format!(
            "--edit {}: the follower has {} frames but the leader {} has {t}; give the \
             leader it was made with",
            b.label,
            b.motion.frames(),
            duet.leader_label
        )));
    }
    let known = common
        .edit
        .known(&span, song.seconds())?
        .expect("a non-empty edit knows something");
    let kept: Vec<bool> = (0..t).map(|f| known.kept(f)).collect();
    let out = generate_follower_known(
        model,
        leader,
        song.music(&span),
        sampling,
        separation,
        Some(&KnownFollower {
            motion: &known.motion,
            kept: &kept,
        }),
        input.device,
        input.hook,
    )
    .map_err(follower_error)?;
    let generated = Edge151::encode(&out.follower)
        .map_err(|e| GenerateError::Generation(format!("encoding the follower: {e}")))?;
    let (values, mask) = known.edge151()?;
    let (frames, largest) = join_made_runs(&generated, &KnownFrames { values, mask }, None);
    let mut follower =
        Edge151::decode(&frames).map_err(|e| GenerateError::Generation(e.to_string()))?;
    known.splice(&mut follower);
    let new = known.frames_to_make();
    let fps = f64::from(FPS);
    Ok(Dance {
        dancers: couple(leader, follower),
        span,
        summary: format!(
            "follower of {} ({t} frames, {:.1} s at {FPS} fps), {new} of them new ({:.1} s), \
             seed {}",
            duet.leader_label,
            t as f64 / fps,
            new as f64 / fps,
            common.seed,
        ),
        timing_breakdown: format!(
            "sampling {:.2} s, decoding {:.2} s; ",
            out.sample_s, out.decode_s
        ),
        notes: vec![format!(
            "an edit: the kept frames are the input's; the new ones join them (root moved by \
             at most {largest:.2} m to meet the kept path); no foot lock or beat warp{}",
            match separation {
                Some(_) => format!(
                    "; the model's follower separated from the leader by up to {:.0} mm",
                    out.separation_max_m * 1000.0
                ),
                None => String::new(),
            }
        )],
        group: None,
        holistic: None,
    })
}

/// (docs/solo-data-v2.md, round eight).
fn lock_follower_feet(
    follower: &mut SmplMotion,
    contacts: &[f32],
    rule: PlantedRule,
    leash_frames: f64,
) -> Result<(), GenerateError> {
    let gen_err = |e: &dyn std::fmt::Display| {
        GenerateError::Generation(format!("locking the follower's feet: {e}"))
    };
    let mut frames = Edge151::encode(follower).map_err(|e| gen_err(&e))?;
    let n = Edge151::CONTACTS.len();
    if contacts.len() != frames.len() / Edge151::DIMS * n {
        return Err(gen_err(&format!(
            "{} contact values for {} frames",
            contacts.len(),
            frames.len() / Edge151::DIMS
        )));
    }
    for (frame, c) in frames
        .chunks_exact_mut(Edge151::DIMS)
        .zip(contacts.chunks_exact(n))
    {
        frame[Edge151::CONTACTS].copy_from_slice(c);
    }
    lock_planted_feet_leashed(&mut frames, rule, Some(leash_frames));
    *follower = Edge151::decode(&frames).map_err(|e| gen_err(&e))?;
    Ok(())
}
