//! Group: 2–5 dancers from one song (TCDiff++, `dancegen_tcdiffpp`), free or following a
//! choreographer's formation (`FORMATION.json`, `dancegen_refine::formation::keyframes`).
//!
//! The model samples every dancer at once ([`dancegen_tcdiffpp::sampler::generate`]: LGDS or
//! the parallel long-form sampler, formation paths injected as clean roots). Then, per dancer,
//! the solo system's planted-feet pass (`dancegen_lodgepp::planted_feet`, with the bundle's
//! `sampling.foot_lock_rule`: leg IK unless `sampling.foot_ik` is off; the root lock only for a
//! dancer no formation constrains, since it would move the root off its requested path), one shared floor, and the couple separation extended to the group
//! ([`group_separation_offsets`]). Before the floor and the separation, each dancer is
//! time-warped so that its kinematic beats land on the song's, as the solo is
//! ([`crate::beat_align`]; `--no-beat-align`). `--unison` gives every dancer the body motion
//! of the leftmost one (post-processing, not part of TCDiff++), each on its own path.

use std::path::Path;

use dancegen_lodgepp::planted_feet::{
    lock_planted_feet_leashed, pin_planted_feet_stepping, pin_planted_feet_within,
};
use dancegen_motion::repr::motion::POSE_DIMS;
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::progress::DENOISING;
use dancegen_refine::formation::order_left_to_right;
use dancegen_tcdiffpp::bundle::GroupModel;
pub use dancegen_tcdiffpp::config::LongSampler;
use dancegen_tcdiffpp::layout::{GROUP_DIMS, N_MAX, N_MIN};
use dancegen_tcdiffpp::sampler::GroupRequest;

use crate::beat_align::{BeatAlignment, align_to_beats};
use crate::edit;
use crate::error::GenerateError;
use crate::formation_file::ANY_SONG_SECONDS;
use crate::song::FPS;
use crate::system::CommonOptions;
use crate::system::{Dance, DanceInput, DanceSystem, Dancer, Role};
use crate::systems::solo::keep_feet_above_floor;

pub use super::group_options::{GroupOptions, MAX_DANCERS, MIN_DANCERS, MIN_GROUP_SECONDS};
use super::group_stage::{
    requested_paths, sample_group, sample_options, separate, stage_positions, stage_report,
};

pub struct Group;

impl DanceSystem for Group {
    const NAME: &'static str = "group";
    const MODEL_KIND: &'static str = dancegen_tcdiffpp::bundle::KIND;
    const DEFAULT_MODEL: &'static str = "tcdiffpp-small";
    const PARTS: &'static [(&'static str, f64)] = &[(DENOISING, 1.0)];
    const EDITS: &'static [&'static str] = &edit::OPERATIONS;
    const MIN_SECONDS: f64 = super::group_options::MIN_GROUP_SECONDS;
    // 5 dancers × 60 s in 14 s (models/tcdiffpp-small/MODEL_CARD.md).
    const SECONDS_PER_DANCED_SECOND: f64 = 0.25;

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
        let (raw, sample_s) = sample_group(model, &req, &sample, &input)?;
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
                let sampling = &model.config.model.sampling;
                let rule = sampling.foot_lock_rule;
                if !constrained {
                    lock_planted_feet_leashed(&mut own, rule, sampling.foot_lock_leash_frames);
                }
                if sampling.foot_ik {
                    let travel = sampling.foot_ik_travel_bound(constrained);
                    match sampling.swing_on_path().filter(|_| constrained) {
                        Some((swing, lift)) => {
                            pin_planted_feet_stepping(&mut own, rule, travel, swing, lift);
                        }
                        None => {
                            pin_planted_feet_within(&mut own, rule, travel);
                        }
                    }
                }
            }
            dancers
                .push(Edge151::decode(&own).map_err(|e| GenerateError::Generation(e.to_string()))?);
        }
        let mut notes = Vec::new();
        if opts.beat_align {
            notes.push(align_dancers_to_beats(
                &mut dancers,
                &song.beat_frames(&span),
            )?);
        }
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

/// Each dancer warped in time so that its kinematic beats land on `beats` (frames of the
/// dance), the solo's alignment ([`align_to_beats`]: ±15 % playback speed, first and last
/// frames kept, so a formation's end places stay). Why: the network keeps the beat no better
/// than chance (on the held-out set, 60 of 120 dancers' BAS beat the same dancer's against
/// half-beat-shifted beats by 0.03; docs/group-collapse.md §23). Returns the run's note.
fn align_dancers_to_beats(
    dancers: &mut [SmplMotion],
    beats: &[usize],
) -> Result<String, GenerateError> {
    let mut done: Vec<BeatAlignment> = Vec::with_capacity(dancers.len());
    for m in dancers.iter_mut() {
        let (mut aligned, a) = align_to_beats(m, beats).map_err(GenerateError::Generation)?;
        keep_feet_above_floor(&mut aligned).map_err(GenerateError::Generation)?;
        *m = aligned;
        done.push(a);
    }
    let n = done.len().max(1) as f64;
    let mean = |f: fn(&BeatAlignment) -> f64| done.iter().map(f).sum::<f64>() / n;
    Ok(format!(
        "beat alignment, per dancer on average: {:.1} of {} music beats met by a motion beat \
         ({:.1} before), alignment score {:.2} ({:.2} before; playback speed within ±{:.0} %)",
        mean(|a| a.matched as f64),
        beats.len(),
        mean(|a| a.met_before as f64),
        mean(|a| a.score),
        mean(|a| a.score_before),
        100.0 * done.iter().map(|a| a.max_tempo_change).fold(0.0, f64::max),
    ))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::beat_align::tests::bob;

    /// Every dancer is aligned, each its own way, and keeps its length and its end poses (so a
    /// formation's start and end places).
    #[test]
    fn each_dancer_is_moved_onto_the_beat() {
        let beats: Vec<usize> = (1..20).map(|k| k * 15).collect();
        let given = vec![bob(3.0), bob(5.0), bob(0.0)];
        let mut dancers = given.clone();
        let note = align_dancers_to_beats(&mut dancers, &beats).unwrap();
        assert!(note.contains("of 19 music beats"), "{note}");
        for (k, (a, m)) in dancers.iter().zip(&given).enumerate() {
            let frames = m.frames();
            assert_eq!(a.frames(), frames, "dancer {k}");
            let last = (frames - 1) * 72;
            assert!(
                a.poses[..72] == m.poses[..72],
                "dancer {k}: first pose moved"
            );
            assert!(
                a.poses[last..] == m.poses[last..],
                "dancer {k}: last pose moved"
            );
        }
        // The two late dancers are warped, each its own way.
        assert!(dancers[0].poses != given[0].poses, "dancer 0 not aligned");
        assert!(dancers[1].poses != given[1].poses, "dancer 1 not aligned");
        assert!(
            dancers[0].poses != dancers[1].poses,
            "one warp for two lags"
        );
    }
}
