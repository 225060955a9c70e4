//! A group edit: `--edit GROUP --regenerate A-B` / `--extend`, `--continue-from GROUP`,
//! `--keep-joints SET --from MOTION`, `--keyframe POSE@T` with `--system group`.
//!
//! Each dancer's [`crate::edit::KnownParts`] ([`crate::edit::Edit::for_dancer`]) becomes one
//! slot of the model's known frames, which the LGDS sampler imposes window by window and skips
//! where nothing is to be made (`dancegen_tcdiffpp::known`). Then per dancer, as the solo
//! system does with its windows: each made run is joined to the kept frames around it and its
//! planted feet locked (`dancegen_lodgepp::inpaint::join_made_runs`; no root lock for a dancer
//! a formation places), the floor and the separation move only made frames (faded in from
//! the kept ones), and the known values are spliced back exactly. The frames made anew are
//! warped onto the beat as a plain group dance is, each run with the kept frames around it
//! fixed ([`crate::beat_align::align_made_runs_to_beats`]; `--no-beat-align`), after the floor
//! has moved them: the floor's per-frame root heights change the joint speeds whose minima are
//! the beats the warp places. Warped before it, a new part's beats moved again (feelings.ogg
//! 38-44 s, seeds 1-5: dancer 1's new parts BAS 0.241, 0.330 warped after the floor).
//! `--unison` is refused: it would replace the kept dancers' own moves.

use dancegen_lodgepp::inpaint::{FootLock, KnownFrames, join_made_runs};
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_tcdiffpp::bundle::GroupModel;
use dancegen_tcdiffpp::known::GroupKnown;
use dancegen_tcdiffpp::layout::GROUP_DIMS;
use dancegen_tcdiffpp::sampler::GroupRequest;

use super::group_options::{GroupOptions, MIN_GROUP_SECONDS};
use super::group_stage::{requested_paths, sample_group, sample_options, separate, stage_report};
use super::solo::{fade_from_kept, floor_made_frames, lift_made_frames_above_floor};
use crate::beat_align::{BeatAlignment, align_made_runs_to_beats};
use crate::error::GenerateError;
use crate::song::FPS;
use crate::system::{Dance, DanceInput, Dancer, Role};

pub(super) fn edit(
    model: &GroupModel,
    input: &DanceInput<'_, GroupOptions>,
) -> Result<Dance, GenerateError> {
    let (common, opts, song) = (input.common, input.options, input.song);
    let n = opts.dancers;
    if opts.unison {
        return Err(GenerateError::Invalid(
            "--unison gives every dancer one dancer's moves, which would replace what the edit \
             keeps; leave it out"
                .into(),
        ));
    }
    let span = common.edit.span(song, common.start, common.end)?;
    if span.seconds() < MIN_GROUP_SECONDS {
        return Err(GenerateError::Invalid(format!(
            "{}: {:.2} s of music to dance to; a group dance needs at least {MIN_GROUP_SECONDS} s",
            song.label,
            span.seconds()
        )));
    }
    let frames = span.end_frame - span.first_frame;
    let d = Edge151::DIMS;
    let mut parts = Vec::with_capacity(n);
    let mut values = vec![0f32; frames * GROUP_DIMS];
    let mut mask = vec![0f32; frames * GROUP_DIMS];
    let mut own = Vec::with_capacity(n);
    for k in 0..n {
        let known = common
            .edit
            .for_dancer(k, n)?
            .known(&span, song.seconds())?
            .expect("a non-empty edit knows something");
        let (v, m) = known.edge151()?;
        for f in 0..frames {
            let at = f * GROUP_DIMS + k * d;
            values[at..at + d].copy_from_slice(&v[f * d..(f + 1) * d]);
            mask[at..at + d].copy_from_slice(&m[f * d..(f + 1) * d]);
        }
        own.push(KnownFrames { values: v, mask: m });
        parts.push(known);
    }
    let (requested, control) = requested_paths(opts, n, &span, song.seconds(), frames)?;
    if let Some(r) = &requested {
        for (k, track) in r.iter().enumerate() {
            if let Some(f) =
                (0..frames).find(|&f| track[f].is_some() && parts[k].root_horizontal[f])
            {
                return Err(GenerateError::Invalid(format!(
                    "--formation places dancer {k} at {:.2} s, where the edit keeps its \
                     position; a formation goes where the dance is made new",
                    (span.first_frame + f) as f64 / f64::from(FPS)
                )));
            }
        }
    }
    let sample = sample_options(model, common, opts, true);
    let req = GroupRequest {
        music: song.music(&span),
        frames,
        dancers: n,
        control: control.as_deref(),
        known: Some(GroupKnown {
            values: &values,
            mask: &mask,
        }),
    };
    let (raw, sample_s) = sample_group(model, &req, &sample, input)?;
    let t1 = std::time::Instant::now();
    let mut dancers: Vec<SmplMotion> = Vec::with_capacity(n);
    let mut moves: Vec<Vec<f32>> = Vec::with_capacity(n);
    let mut largest_join = 0f32;
    let beats = song.beat_frames(&span);
    let mut aligned_runs: Vec<BeatAlignment> = Vec::new();
    for (k, known) in own.iter().enumerate() {
        let generated: Vec<f32> = raw
            .chunks_exact(GROUP_DIMS)
            .flat_map(|f| f[k * d..(k + 1) * d].iter().copied())
            .collect();
        let placed = requested
            .as_ref()
            .is_some_and(|r| r[k].iter().any(Option::is_some));
        let lock = opts.foot_lock.then_some(FootLock {
            root: !placed,
            ik: model.config.model.sampling.foot_ik,
            rule: model.config.model.sampling.foot_lock_rule,
            max_travel_m: model.config.model.sampling.foot_ik_travel_bound(placed),
        });
        let (joined, largest) = join_made_runs(&generated, known, lock);
        largest_join = largest_join.max(largest);
        let mut m =
            Edge151::decode(&joined).map_err(|e| GenerateError::Generation(e.to_string()))?;
        let made: Vec<bool> = parts[k].root_height.iter().map(|&h| !h).collect();
        floor_made_frames(&mut m, &made)?;
        lift_made_frames_above_floor(&mut m, &made).map_err(GenerateError::Generation)?;
        if opts.beat_align {
            let untouched: Vec<bool> = (0..frames).map(|f| !parts[k].touched(f)).collect();
            let (aligned, reports) = align_made_runs_to_beats(&m, &untouched, &beats)
                .map_err(GenerateError::Generation)?;
            m = aligned;
            aligned_runs.extend(reports);
            lift_made_frames_above_floor(&mut m, &made).map_err(GenerateError::Generation)?;
        }
        let free: Vec<bool> = parts[k].root_horizontal.iter().map(|&h| !h).collect();
        moves.push(fade_from_kept(&free));
        dancers.push(m);
    }
    let mut notes = vec![format!(
        "an edit: what was given is kept exactly; the new frames join it (roots moved by at \
         most {largest_join:.2} m to meet the given paths); the foot lock on the new frames \
         only"
    )];
    if !aligned_runs.is_empty() {
        let warped = aligned_runs.iter().filter(|a| a.passes > 0).count();
        let mean = |f: fn(&BeatAlignment) -> f64| {
            aligned_runs.iter().map(f).sum::<f64>() / aligned_runs.len() as f64
        };
        notes.push(format!(
            "beat alignment of the new parts (the frames around them kept): {warped} of {} \
             runs warped, alignment score {:.2} ({:.2} before)",
            aligned_runs.len(),
            mean(|a| a.score),
            mean(|a| a.score_before),
        ));
    }
    if opts.separation {
        let largest = separate(&mut dancers, Some(&moves))?;
        notes.push(format!(
            "new frames kept apart by moving dancers up to {:.0} mm",
            largest * 1000.0
        ));
    }
    for (m, known) in dancers.iter_mut().zip(&parts) {
        known.splice(m);
    }
    let post_s = t1.elapsed().as_secs_f64();
    let report = stage_report(&dancers, requested, frames, &mut notes)?;
    let new = parts.iter().map(|p| p.frames_to_make()).max().unwrap_or(0);
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
            "{n} dancers, {frames} frames ({:.1} s at {FPS} fps), up to {new} of them new per \
             dancer ({:.1} s), seed {}, {} steps, guidance {}",
            frames as f64 / f64::from(FPS),
            new as f64 / f64::from(FPS),
            common.seed,
            sample.steps,
            sample.guidance,
        ),
        timing_breakdown: format!("sampling {sample_s:.2} s, post-processing {post_s:.2} s; "),
        notes,
        group: Some(report),
        holistic: None,
    })
}
