//! The stage of a group dance, shared by the plain group dance and its edit: the requested
//! formation paths, the sampling options of a request, the separation of the dancers and the
//! stage report (orders, paths, how well a formation was followed).

use dancegen_motion::repr::SmplMotion;
use dancegen_refine::couple_separation::{SeparationConfig, group_separation_offsets};
use dancegen_refine::formation::{StagePos, order_left_to_right};
use dancegen_tcdiffpp::bundle::GroupModel;
use dancegen_tcdiffpp::config::LongSampler;
use dancegen_tcdiffpp::layout::N_MAX;
use dancegen_tcdiffpp::sampler::{GroupRequest, GroupSampleOptions, RootXy, generate};

use super::group_options::GroupOptions;
use crate::error::GenerateError;
use crate::song::{FPS, Span};
use crate::system::{CommonOptions, DanceInput, GroupReport};

/// Samples `req` (raw frames `[frames, N_MAX·151]`, see `dancegen_tcdiffpp::sampler`) and the
/// seconds it took; a non-finite value is an error, not a dance.
pub(super) fn sample_group(
    model: &GroupModel,
    req: &GroupRequest,
    sample: &GroupSampleOptions,
    input: &DanceInput<'_, GroupOptions>,
) -> Result<(Vec<f32>, f64), GenerateError> {
    let t0 = std::time::Instant::now();
    let raw = generate(
        &model.net,
        &model.schedule,
        model.config.model.window(),
        req,
        sample,
        input.device,
        input.hook,
    )?;
    if raw.iter().any(|v| !v.is_finite()) {
        return Err(GenerateError::Generation(
            "the model produced non-finite values (please report this with the song and seed)"
                .into(),
        ));
    }
    Ok((raw, t0.elapsed().as_secs_f64()))
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
        solver: sampling.solver,
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

pub(super) fn world_joints(dancers: &[SmplMotion]) -> Result<Vec<Vec<f64>>, GenerateError> {
    dancers
        .iter()
        .map(|m| {
            m.joints_world()
                .map(|j| j.into_iter().map(f64::from).collect())
                .map_err(|e| GenerateError::Generation(e.to_string()))
        })
        .collect()
}

pub(super) fn stage_positions(
    dancers: &[SmplMotion],
    t: usize,
) -> Result<Vec<StagePos>, GenerateError> {
    Ok(world_joints(dancers)?
        .iter()
        .map(|j| [j[t * 72], j[t * 72 + 2]])
        .collect())
}
