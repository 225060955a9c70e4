//! A holistic edit: `--edit DANCE --regenerate A-B` / `--extend` and `--continue-from MOTION`
//! with `--system holistic`, by SoulNet's own inpainting, in tokens.
//!
//! What is kept becomes tokens: the kept frames (body, and the fingers and face where the given
//! dance has them, as a holistic `.npz` dancegen wrote does) are encoded by the part
//! autoencoder, and each part's token whose frames are all kept is given to the masked
//! transformer of every window that covers it (`dancegen_soulnet::pipeline::known_tokens`,
//! `generate_known`); windows with nothing to make are not sampled. A given body without
//! fingers or face (a BVH, an SMPL `.npz`) keeps its body, and its fingers and face are made
//! to go with it.
//!
//! The decoded dance starts in its own frame of reference (SoulNet's representation is
//! heading-invariant), so each new part is first turned and moved about the vertical onto the
//! kept frame before it (after it, for a part at the start). Then the body joins the kept
//! frames as the solo system's new parts do (`dancegen_lodgepp::inpaint::join_made_runs`, the
//! foot lock on the new parts), the fingers and face cross-fade from the kept frames over
//! [`PART_BLEND_FRAMES`], and every kept value is spliced back exactly.
//!
//! Kept joints (`--keep-joints`), keyframes and a path are known on some joints or the root of
//! a frame only. SoulNet's tokens stand for a whole part over 4 frames, and a joint or a single
//! frame has no token of its own, so those frames are made by the masked transformer as new
//! ones and the partly known values are applied to the decoded body (a deviation from the
//! solo and group systems, whose samplers take them as cues): the new part is turned and moved
//! about the vertical onto the first keyed root orientation and floor position where no kept
//! frame anchors it, then [`join_made_runs`] eases it into the known joints and root height
//! (the difference at each known frame added around it, fading out over
//! `dancegen_lodgepp::inpaint::EASE_FRAMES`; replacement on every frame of kept joints), moves
//! its root onto the known floor positions (a path), and locks its planted feet without moving
//! a known root. The fingers and face are SoulNet's, made with its own body.

use dancegen_lodgepp::inpaint::{FootLock, KnownFrames, join_made_runs};
use dancegen_lodgepp::planted_feet::PlantedRule;
use dancegen_motion::face::ARKIT_COUNT;
use dancegen_motion::face::FaceWeights;
use dancegen_motion::repr::holistic::Holistic623;
use dancegen_motion::repr::holistic::split::to_split;
use dancegen_motion::repr::motion::POSE_DIMS;
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_motion::rotation::Quat;
use dancegen_motion::skeleton::Skeleton;
use dancegen_soulnet::bundle::HolisticModel;
use dancegen_soulnet::layout::TOTAL_DIMS;
use dancegen_soulnet::pipeline::{self, GenerateOptions, generate_known, known_tokens};

use super::holistic_options::{HolisticOptions, MIN_SONG_SECONDS};
use super::solo::{floor_made_frames, lift_made_frames_above_floor};
use crate::edit::{CONTINUE_SECONDS, GivenMotion, KnownParts};
use crate::error::GenerateError;
use crate::song::FPS;
use crate::system::{Dance, DanceInput, Dancer, HolisticParts, Role};

/// SMPL-H rotation values per frame (52 joints).
const H_DIMS: usize = 156;
/// SMPL 24 body values shared with SMPL-H (joints 0–21).
const BODY_VALUES: usize = 66;
/// Frames over which a new part's fingers and face fade in from the kept frame next to it.
pub const PART_BLEND_FRAMES: usize = 8;

pub(super) fn edit(
    model: &HolisticModel,
    input: &DanceInput<'_, HolisticOptions>,
) -> Result<Dance, GenerateError> {
    let (common, song) = (input.common, input.song);
    let span = common.edit.span(song, common.start, common.end)?;
    if span.seconds() < MIN_SONG_SECONDS {
        return Err(GenerateError::Invalid(format!(
            "{}: {:.2} s of music to dance to; the model needs at least {MIN_SONG_SECONDS} s",
            song.label,
            span.seconds()
        )));
    }
    let known = common
        .edit
        .known(&span, song.seconds())?
        .expect("a non-empty edit knows something");
    let t = known.frames();
    // The fingers and face of every kept frame, where the given motion has them.
    let mut extras = given_extras(&common.edit, t);
    for (f, e) in extras.iter_mut().enumerate() {
        if !known.kept(f) {
            *e = None;
        }
    }
    let mut part_known: Vec<[bool; 3]> = (0..t)
        .map(|f| {
            let body = known.kept(f);
            let more = body && extras[f].is_some();
            [body, more, more]
        })
        .collect();
    let (poses, face) = holistic_values(&known, &extras);
    let rows = split_rows(&poses, &known.motion.trans, &face, &mut part_known)?;
    let tokens = known_tokens(model, &rows, &part_known, input.device);
    let mut opts = GenerateOptions::defaults(model, common.seed);
    if let Some(s) = common.steps {
        opts.sampling.steps = s;
    }
    if let Some(w) = common.guidance {
        opts.sampling.cond_scale = w;
    }
    let made = generate_known(
        model,
        song.music(&span),
        Some(&tokens),
        &opts,
        input.device,
        input.hook,
    )
    .map_err(|e| match e {
        pipeline::GenerateError::Cancelled(_) => GenerateError::Cancelled,
        pipeline::GenerateError::Invalid(r) => GenerateError::Generation(r),
    })?;
    let decoded = dancegen_soulnet::layout::decode(&made.rows, FPS as f32)
        .map_err(GenerateError::Generation)?;
    let gen_err = |e: &dyn std::fmt::Display| GenerateError::Generation(e.to_string());
    let mut hol = decoded.motion;
    let mut new_face = decoded.face[..t * ARKIT_COUNT].to_vec();
    let runs = made_runs(&part_known);
    for &(a, b) in &runs {
        align_run(&mut hol.poses, &mut hol.trans, &known, a, b);
    }
    // The body: joined and locked as a solo edit's new parts, the kept values exact.
    let body = SmplMotion {
        fps: FPS as f32,
        poses: (0..t)
            .flat_map(|f| {
                let mut row = hol.poses[f * H_DIMS..f * H_DIMS + BODY_VALUES].to_vec();
                row.resize(POSE_DIMS, 0.0);
                row
            })
            .collect(),
        trans: hol.trans.clone(),
    };
    let generated = Edge151::encode(&body).map_err(|e| gen_err(&e))?;
    let (values, mask) = known.edge151()?;
    let lock = input.options.foot_lock.then_some(FootLock {
        root: true,
        ik: model.config.sampling.foot_ik,
        rule: PlantedRule::Either,
        max_travel_m: f64::INFINITY,
    });
    let (joined, largest) = join_made_runs(&generated, &KnownFrames { values, mask }, lock);
    let mut body = Edge151::decode(&joined).map_err(|e| gen_err(&e))?;
    let made_height: Vec<bool> = known.root_height.iter().map(|&k| !k).collect();
    floor_made_frames(&mut body, &made_height)?;
    lift_made_frames_above_floor(&mut body, &made_height).map_err(GenerateError::Generation)?;
    known.splice(&mut body);
    // Fingers and face: kept where given, faded in from the kept frames next to new parts.
    for f in 0..t {
        hol.poses[f * H_DIMS..f * H_DIMS + BODY_VALUES]
            .copy_from_slice(&body.poses[f * POSE_DIMS..f * POSE_DIMS + BODY_VALUES]);
    }
    blend_parts(&mut hol.poses, &mut new_face, &extras, &runs, t);
    let face = FaceWeights::new(new_face, FPS as f32).map_err(|e| gen_err(&e))?;
    let new = known.frames_to_make();
    Ok(Dance {
        dancers: vec![Dancer {
            role: Role::Solo,
            motion: body.clone(),
        }],
        span,
        summary: format!(
            "{t} frames ({:.1} s at {FPS} fps) with fingers and face, {new} of them new ({:.1} \
             s), seed {}, {} window{} sampled of {}",
            t as f64 / f64::from(FPS),
            new as f64 / f64::from(FPS),
            common.seed,
            made.sampled,
            if made.sampled == 1 { "" } else { "s" },
            made.windows,
        ),
        timing_breakdown: String::new(),
        notes: vec![
            format!(
                "an edit: what was given is kept exactly, fingers and face too where the dance \
                 had them; the new frames join it (root moved by at most {largest:.2} m); the \
                 foot lock on the new frames only"
            ),
            "the fingers and face were learned from synthetic data (see the model card)".into(),
        ],
        group: None,
        holistic: Some(HolisticParts {
            poses: hol.poses,
            trans: body.trans,
            skeleton: Skeleton::smplh52_approx(),
            face,
            flame: None,
        }),
    })
}

/// Per frame of the edit, the given fingers and face `(156 rotations, 52 weights)` where a
/// kept frame's motion has them: the dance being edited frame for frame, or the last
/// [`CONTINUE_SECONDS`] of the motion continued.
fn given_extras(edit: &crate::edit::Edit, t: usize) -> Vec<Option<(Vec<f32>, Vec<f32>)>> {
    let mut out = vec![None; t];
    let take = |g: &GivenMotion, from: usize, to: std::ops::Range<usize>, out: &mut Vec<_>| {
        if let Some(h) = &g.holistic {
            for (i, f) in to.enumerate() {
                let s = from + i;
                out[f] = Some((
                    h.poses[s * H_DIMS..(s + 1) * H_DIMS].to_vec(),
                    h.face[s * ARKIT_COUNT..(s + 1) * ARKIT_COUNT].to_vec(),
                ));
            }
        }
    };
    if let Some(b) = &edit.base {
        take(b, 0, 0..b.motion.frames().min(t), &mut out);
    }
    if let Some(c) = &edit.continue_from {
        let keep = ((CONTINUE_SECONDS * f64::from(FPS)).round() as usize).min(t);
        let from = c.motion.frames().saturating_sub(keep);
        take(c, from, 0..keep, &mut out);
    }
    out
}

/// The SMPL-H rotations and face of the known frames: the body from `known`, the fingers and
/// face from `extras` (rest fingers and a neutral face where not given).
fn holistic_values(
    known: &KnownParts,
    extras: &[Option<(Vec<f32>, Vec<f32>)>],
) -> (Vec<f32>, Vec<f32>) {
    let t = known.frames();
    let mut poses = vec![0f32; t * H_DIMS];
    let mut face = vec![0f32; t * ARKIT_COUNT];
    for f in 0..t {
        if let Some((p, w)) = &extras[f] {
            poses[f * H_DIMS..(f + 1) * H_DIMS].copy_from_slice(p);
            face[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT].copy_from_slice(w);
        }
        poses[f * H_DIMS..f * H_DIMS + BODY_VALUES]
            .copy_from_slice(&known.motion.poses[f * POSE_DIMS..f * POSE_DIMS + BODY_VALUES]);
    }
    (poses, face)
}

/// SoulNet's split rows `(T, 675)` of the known frames: each stretch of frames with something
/// known is encoded on its own (the representation's velocities reach one frame ahead, so a
/// stretch's last frame repeats the row before it); rows of other frames are zero. A lone
/// kept frame has no velocity to encode: it is marked unknown to the tokens (its values are
/// still spliced back).
fn split_rows(
    poses: &[f32],
    trans: &[f32],
    face: &[f32],
    part_known: &mut [[bool; 3]],
) -> Result<Vec<f32>, GenerateError> {
    let t = part_known.len();
    let mut rows = vec![0f32; t * TOTAL_DIMS];
    let gen_err = |e: &dyn std::fmt::Display| GenerateError::Generation(e.to_string());
    let mut f = 0;
    while f < t {
        if !part_known[f][0] {
            f += 1;
            continue;
        }
        let a = f;
        while f < t && part_known[f][0] {
            f += 1;
        }
        if f - a < 2 {
            part_known[a] = [false; 3];
            continue;
        }
        let ric = Holistic623::encode(
            &poses[a * H_DIMS..f * H_DIMS],
            &trans[a * 3..f * 3],
            FPS as f32,
        )
        .map_err(|e| gen_err(&e))?;
        let d = Holistic623::DIMS;
        let mut with_face = Vec::with_capacity((f - a) * (d + ARKIT_COUNT));
        for i in 0..f - a {
            let r = i.min(f - a - 2);
            with_face.extend_from_slice(&ric[r * d..(r + 1) * d]);
            let g = a + i;
            with_face.extend_from_slice(&face[g * ARKIT_COUNT..(g + 1) * ARKIT_COUNT]);
        }
        let split = to_split(&with_face, ARKIT_COUNT).map_err(|e| gen_err(&e))?;
        rows[a * TOTAL_DIMS..f * TOTAL_DIMS].copy_from_slice(&split);
    }
    Ok(rows)
}

/// The maximal runs `[a, b)` of frames whose body is not kept.
fn made_runs(part_known: &[[bool; 3]]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut f = 0;
    while f < part_known.len() {
        if part_known[f][0] {
            f += 1;
            continue;
        }
        let a = f;
        while f < part_known.len() && !part_known[f][0] {
            f += 1;
        }
        runs.push((a, f));
    }
    runs
}

/// Heading of a root rotation: the angle about the vertical (Y) of its forward (+Z) axis.
fn heading(axis_angle: &[f32]) -> f64 {
    let q = Quat::from_axis_angle([0, 1, 2].map(|i| f64::from(axis_angle[i])));
    let v = q.rotate([0.0, 0.0, 1.0]);
    v[0].atan2(v[2])
}

/// The frames whose known values a new part `[a, b)` is turned and moved onto: the kept
/// frame next to it (before it, else after it) for both, or, for a part with no kept frame
/// next to it (a dance made whole around kept joints, keyframes or a path), the first frame
/// in it whose root orientation is known and the first whose floor position is.
fn run_anchors(known: &KnownParts, a: usize, b: usize) -> (Option<usize>, Option<usize>) {
    let t = known.frames();
    if a > 0 {
        return (Some(a - 1), Some(a - 1));
    }
    if b < t {
        return (Some(b), Some(b));
    }
    let heading = (a..b).find(|&f| known.joints[f] & 1 != 0);
    let floor = (a..b).find(|&f| known.root_horizontal[f]);
    (heading, floor)
}

/// Turns and moves the new frames `[a, b)` of the decoded dance about the vertical so that
/// their anchors ([`run_anchors`]) have the known dance's heading and floor position (the
/// turn is about the floor-position anchor, the run's first frame without one).
fn align_run(poses: &mut [f32], trans: &mut [f32], known: &KnownParts, a: usize, b: usize) {
    let (turn_at, move_at) = run_anchors(known, a, b);
    let kept = &known.motion;
    let turn = turn_at.map_or(0.0, |f| {
        heading(&kept.poses[f * POSE_DIMS..f * POSE_DIMS + 3])
            - heading(&poses[f * H_DIMS..f * H_DIMS + 3])
    });
    let pivot = move_at.unwrap_or(a);
    let yaw = Quat::from_axis_angle([0.0, turn, 0.0]);
    let from = [trans[pivot * 3], trans[pivot * 3 + 2]];
    let to = match move_at {
        Some(f) => [kept.trans[f * 3], kept.trans[f * 3 + 2]],
        None => from,
    };
    for f in a..b {
        let r = &mut poses[f * H_DIMS..f * H_DIMS + 3];
        let q = yaw * Quat::from_axis_angle([0, 1, 2].map(|i| f64::from(r[i])));
        let aa = q.to_axis_angle();
        for i in 0..3 {
            r[i] = aa[i] as f32;
        }
        let rel = [
            f64::from(trans[f * 3] - from[0]),
            0.0,
            f64::from(trans[f * 3 + 2] - from[1]),
        ];
        let v = yaw.rotate(rel);
        trans[f * 3] = to[0] + v[0] as f32;
        trans[f * 3 + 2] = to[1] + v[2] as f32;
    }
}

/// Fingers and face: the given values on kept frames, and on the first and last
/// [`PART_BLEND_FRAMES`] of each new part a fade (smoothstep; rotations by slerp) from the kept
/// frame next to it into the new values.
fn blend_parts(
    poses: &mut [f32],
    face: &mut [f32],
    extras: &[Option<(Vec<f32>, Vec<f32>)>],
    runs: &[(usize, usize)],
    t: usize,
) {
    for (f, e) in extras.iter().enumerate() {
        if let Some((p, w)) = e {
            poses[f * H_DIMS + BODY_VALUES..(f + 1) * H_DIMS].copy_from_slice(&p[BODY_VALUES..]);
            face[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT].copy_from_slice(w);
        }
    }
    let fade = |poses: &mut [f32], face: &mut [f32], f: usize, from: usize, w: f64| {
        let Some((p, fw)) = &extras[from] else {
            return;
        };
        for j in (BODY_VALUES..H_DIMS).step_by(3) {
            let q0 = Quat::from_axis_angle([0, 1, 2].map(|i| f64::from(p[j + i])));
            let at = f * H_DIMS + j;
            let q1 = Quat::from_axis_angle([0, 1, 2].map(|i| f64::from(poses[at + i])));
            let aa = Quat::slerp(q0, q1, w).to_axis_angle();
            for i in 0..3 {
                poses[at + i] = aa[i] as f32;
            }
        }
        for (v, &from) in face[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT]
            .iter_mut()
            .zip(fw)
        {
            *v = (f64::from(from) * (1.0 - w) + f64::from(*v) * w) as f32;
        }
    };
    let smooth = |u: f64| u * u * (3.0 - 2.0 * u);
    for &(a, b) in runs {
        let n = PART_BLEND_FRAMES.min((b - a) / 2);
        for k in 0..n {
            let w = smooth((k + 1) as f64 / (n + 1) as f64);
            if a > 0 {
                fade(poses, face, a + k, a - 1, w);
            }
            if b < t {
                fade(poses, face, b - 1 - k, b, w);
            }
        }
    }
}
