//! Group pairing (`--pairing group`): 2–5 dancers composed from real motion into formations,
//! beat-warped onto a song (group.md §4). **A composition, not recorded group dance**: no group
//! data set can be had here, so every sample is made by this seeded generator, and every sample
//! carries its labels (start and end order, shapes, transitions, timing, trajectories).
//!
//! - **Units** ([`Source`]): each take of `--motion`, and its left–right mirror image. Two files
//!   sharing a CMU couple key (`60_01` and `61_01`, see [`crate::duet`]) or a two-dancer group
//!   file are a **couple unit**, which keeps the partners' real relative placement; each partner
//!   is also a solo unit. A sample has N ∈ 2..=5 dancers (sample `i` has `2 + i mod 4`) and at most two
//!   couples.
//! - **Formation** ([`plan`]): a template (line, column, V, …, cluster) with spacing 0.9–1.8 m
//!   (1.8–2.6 m between members when a couple is one of them), jitter and ±30° yaw; at 8-beat
//!   phrase boundaries of the song, transitions of 2–4 beats (stretched up to 8 so no path is
//!   faster than 2 m/s) on minimum-jerk paths: a morph to a
//!   new template with Hungarian slot assignment, or a swap of two neighbours with a lateral
//!   offset or an upstage pass.
//! - **Timing**: unison (one segment for every solo member, ±2 frames of jitter, each member
//!   mirrored with probability 0.3), canon (one segment, member k starting k·{1,2,4} beats
//!   later) or contrast (a segment per member).
//! - **Segments** are *retrieved*, not slid: among [`CANDIDATES`] random segments per member, the
//!   one whose own low-pass travel best matches its planned path (group.md §4.6). The root is
//!   then the planned path plus the source's sway ([`place`]); solo dancers face the audience
//!   ±15°.
//! - **Music**: each segment is beat-warped onto the song span with both ends fixed
//!   ([`crate::warp::match_beats_in_span`], ±15 % speed), a couple by one warp.
//! - **Rejected** ([`check`]): non-partner roots closer than 0.45 m, non-partner capsule bodies
//!   intersecting on any frame, a body under the floor on more than 2 % of the frames, or a placement that adds more than 0.10
//!   to a dancer's foot-skating ratio. Each sample is tried [`ATTEMPTS`] times.
//! - **Held out**: samples built only from held-out takes (`--hold-out`), held-out songs and
//!   held-out shapes (`--hold-out-shape`) go to `held_out/`; training samples use none of them.
//!
//! Layout: `OUT/[held_out/]group/<clip>/dancer_<k>.npz` (AMASS npz, each member on its own
//! floor at y = 0, a couple on one shared floor), `OUT/[held_out/]music/<clip>.npy` (T, 35),
//! `OUT/[held_out/]trajectories/<clip>.npy` (N, T, 2) float32 root `[x, z]` (pelvis joint), and
//! the manifest's `group` labels ([`crate::manifest::GroupLabels`]).

mod check;
mod place;
mod plan;

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, NpzStyle, save_motion_file};
use dancegen_metrics::FRAME_LEN;
use dancegen_motion::repr::motion::{GroundMode, SmplMotion};
use dancegen_motion::rng::SplitMix64;
use dancegen_music::features::EDGE35_DIM;
use dancegen_refine::formation::shapes::Shape;
use dancegen_refine::formation::{StagePos, order_left_to_right};
use rayon::prelude::*;

use crate::FPS;
use crate::beats::{bas_bailando, kinematic_beats};
use crate::duet::{couple_key, slice};
use crate::error::DatasetError;
use crate::genre;
use crate::inputs::{analyse_songs, check_hold_out, expand_motion_inputs};
use crate::manifest::{ClipEntry, GroupLabels, PairingKind, WarpReport};
pub use crate::options::GroupOptions;
use crate::options::{BuildOptions, Progress};
use crate::song::{Song, stem};
use crate::units::{MotionUnit, load_units, world_joints};
use crate::warp::{match_beats_in_span, warp_motion};
use check::{Reject, check_scene, skating};
use place::{couple_yaw, low_pass, place_couple, place_solo, root_xz, solo_yaw, travel_mismatch};
use plan::{Plan, plan_formation, spacing_range, uniform};

/// Segments drawn per member; the one whose travel best matches its path is kept.
pub const CANDIDATES: usize = 16;
/// Tries per sample before it is given up (each failure reason is counted in the log).
pub const ATTEMPTS: usize = 24;
/// Unison jitter (group.md §4.5: ±2 frames).
const UNISON_JITTER: usize = 2;
/// Beats per phrase: transitions start on every 8th beat of the song (group.md §4.4).
const PHRASE_BEATS: usize = 8;
/// Canon offsets in beats (group.md §4.5).
const CANON_BEATS: [usize; 3] = [1, 2, 4];
/// Chance that a unison member dances the mirror image.
const UNISON_MIRROR_CHANCE: f64 = 0.3;

/// One usable take (or its mirror image).
struct Source {
    unit: MotionUnit,
    /// Low-pass root path of the whole take.
    lp: Vec<StagePos>,
    held: bool,
    /// The source index of the same take mirrored (or unmirrored).
    mirror_of: usize,
    mirrored: bool,
}

impl Source {
    fn label(&self) -> String {
        if self.mirrored {
            format!("{}_mirror", self.unit.name)
        } else {
            self.unit.name.clone()
        }
    }
}

/// What a sample may draw from.
struct Pool {
    solos: Vec<usize>,
    couples: Vec<(usize, usize)>,
    songs: Vec<usize>,
    shapes: Vec<Shape>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Timing {
    Unison,
    Canon,
    Contrast,
}

impl Timing {
    fn name(self) -> &'static str {
        match self {
            Timing::Unison => "unison",
            Timing::Canon => "canon",
            Timing::Contrast => "contrast",
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Member {
    Solo,
    Couple,
}

/// A chosen segment: source (or couple's first source), first source frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Segment {
    source: usize,
    partner: Option<usize>,
    start: usize,
}

/// A composed, checked sample.
struct Scene {
    dancers: Vec<SmplMotion>,
    sources: Vec<String>,
    genres: Vec<String>,
    partners: Vec<[usize; 2]>,
    song: usize,
    song_start: usize,
    timing: Timing,
    plan: Plan,
    warp: WarpReport,
}

/// Source indices of a couple's two partners.
type CouplePair = (usize, usize);

/// One sample's outcome and the reasons of its rejected tries.
type SampleResult = (Result<Option<ClipEntry>, DatasetError>, Vec<Reject>);

fn load_sources(opts: &BuildOptions) -> Result<(Vec<Source>, Vec<CouplePair>), DatasetError> {
    let files = expand_motion_inputs(&opts.motions)?;
    let mut units: Vec<MotionUnit> = Vec::new();
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    let mut by_key: BTreeMap<(String, String), Vec<usize>> = BTreeMap::new();
    for path in &files {
        let s = stem(path);
        let g = opts
            .genre
            .as_deref()
            .map(genre::normalize)
            .unwrap_or_else(|| genre::genre_from_name(&s));
        let loaded = load_units(path, &g, &opts.source_fps)?;
        let first = units.len();
        let k = loaded.len();
        units.extend(loaded);
        if k == 2 {
            pairs.push((first, first + 1));
        } else if k == 1
            && let Some(key) = couple_key(&s)
        {
            let dir = path
                .parent()
                .map(|p| p.display().to_string())
                .unwrap_or_default();
            by_key
                .entry((dir, key.to_string()))
                .or_default()
                .push(first);
        }
    }
    for ids in by_key.values() {
        if let [a, b] = ids[..] {
            pairs.push((a, b));
        }
    }
    let held = |u: &MotionUnit| opts.hold_out.iter().any(|h| *h == u.stem || *h == u.name);
    let mut sources = Vec::with_capacity(units.len() * 2);
    for (i, u) in units.into_iter().enumerate() {
        let h = held(&u);
        let mirror = MotionUnit {
            motion: u.motion.mirror(),
            ..u.clone()
        };
        for (k, unit) in [u, mirror].into_iter().enumerate() {
            let lp = low_pass(&root_xz(&unit.motion));
            sources.push(Source {
                unit,
                lp,
                held: h,
                mirror_of: 2 * i + 1 - k,
                mirrored: k == 1,
            });
        }
    }
    // Couples, both unmirrored and mirrored together (one mirror plane for both partners).
    let couples = pairs
        .into_iter()
        .flat_map(|(a, b)| [(2 * a, 2 * b), (2 * a + 1, 2 * b + 1)])
        .collect();
    Ok((sources, couples))
}

/// Builds a group data set (see the module documentation).
pub(crate) fn build_group(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<ClipEntry>, DatasetError> {
    let g = &opts.group;
    if opts.motions.is_empty() || opts.music.is_empty() {
        return Err(DatasetError::Options(
            "--pairing group needs --motion FILES and --music SONGS".into(),
        ));
    }
    if !(g.clip_seconds.is_finite() && g.clip_seconds >= 5.0) {
        return Err(DatasetError::Options(format!(
            "--clip-seconds {}: a group sample needs at least 5 s (the model's window)",
            g.clip_seconds
        )));
    }
    let held_shapes: Vec<Shape> = g
        .hold_out_shapes
        .iter()
        .map(|s| s.parse::<Shape>())
        .collect::<Result<_, _>>()
        .map_err(|e| DatasetError::Options(format!("--hold-out-shape: {e}")))?;
    let (sources, couples) = load_sources(opts)?;
    let mut known: std::collections::BTreeSet<String> =
        opts.music.iter().map(|p| stem(p)).collect();
    for s in &sources {
        known.insert(s.unit.stem.clone());
        known.insert(s.unit.name.clone());
    }
    check_hold_out(&opts.hold_out, &known)?;
    let songs = analyse_songs(&opts.music, progress)?;
    let song_held = |s: &Song| opts.hold_out.contains(&s.name);
    let pool = |held: bool| -> Pool {
        let solos: Vec<usize> = (0..sources.len())
            .filter(|&i| sources[i].held == held)
            .collect();
        let cs: Vec<(usize, usize)> = couples
            .iter()
            .copied()
            .filter(|&(a, b)| sources[a].held == held && sources[b].held == held)
            .collect();
        let mut ss: Vec<usize> = (0..songs.len())
            .filter(|&i| song_held(&songs[i]) == held)
            .collect();
        if held && ss.is_empty() {
            ss = (0..songs.len()).collect();
        }
        let mut shapes: Vec<Shape> = Shape::ALL
            .into_iter()
            .filter(|s| held_shapes.contains(s) == held)
            .collect();
        if held && shapes.is_empty() {
            shapes = Shape::ALL.to_vec();
        }
        Pool {
            solos,
            couples: cs,
            songs: ss,
            shapes,
        }
    };
    let (train, held) = (pool(false), pool(true));
    if train.solos.is_empty() || train.songs.is_empty() || train.shapes.is_empty() {
        return Err(DatasetError::Options(
            "--pairing group: everything is held out; training samples need takes, songs and \
             shapes that are not"
                .into(),
        ));
    }
    let frames = (g.clip_seconds * f64::from(FPS)).round() as usize;
    let mut jobs: Vec<(usize, bool)> = (0..g.samples).map(|i| (i, false)).collect();
    if !held.solos.is_empty() {
        jobs.extend((0..g.held_out_samples).map(|i| (i, true)));
    } else if g.held_out_samples > 0 {
        tracing::warn!("--pairing group: no held-out take, so no held-out group samples");
    }
    for d in [
        "group",
        "trajectories",
        "held_out/group",
        "held_out/trajectories",
    ] {
        let p = opts.out.join(d);
        std::fs::create_dir_all(&p)
            .map_err(|e| DatasetError::input(&p, format!("cannot create directory: {e}")))?;
    }
    crate::clips::create_dirs(&opts.out)?;
    progress.stage("composing groups", jobs.len());
    let results: Vec<SampleResult> = jobs
        .par_iter()
        .map(|&(i, is_held)| {
            let p = if is_held { &held } else { &train };
            let mut rejects = Vec::new();
            let mut out = Ok(None);
            for attempt in 0..ATTEMPTS {
                let seed =
                    opts.seed ^ ((i as u64) << 20) ^ ((attempt as u64) << 8) ^ u64::from(is_held);
                let mut rng = SplitMix64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
                // Sample i has 2 + i mod 4 dancers, so every group size is equally common
                // (drawing N per try would favour the small groups, which pass more often).
                match compose(&mut rng, 2 + i % 4, &sources, p, &songs, frames) {
                    Ok(scene) => {
                        out = write_scene(&opts.out, &scene, &songs, i, is_held).map(Some);
                        break;
                    }
                    Err(r) => rejects.push(r),
                }
            }
            progress.step("sample");
            (out, rejects)
        })
        .collect();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let mut clips = Vec::new();
    let mut given_up = 0;
    for (r, rejects) in results {
        for x in rejects {
            *counts.entry(x.name()).or_default() += 1;
        }
        match r? {
            Some(c) => clips.push(c),
            None => given_up += 1,
        }
    }
    tracing::info!(
        "group composition: {} samples, {given_up} given up after {ATTEMPTS} tries; rejected \
         tries: {counts:?}",
        clips.len()
    );
    if clips.is_empty() {
        return Err(DatasetError::Options(format!(
            "--pairing group: no sample passed the checks (rejected tries: {counts:?})"
        )));
    }
    Ok(clips)
}

/// Median interval of the beats (frames), or 15 (120 BPM at 30 fps) without two beats.
fn beat_period(beats: &[usize]) -> f64 {
    let mut d: Vec<usize> = beats.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return 15.0;
    }
    d.sort_unstable();
    d[d.len() / 2] as f64
}

fn compose(
    rng: &mut SplitMix64,
    dancers_wanted: usize,
    sources: &[Source],
    pool: &Pool,
    songs: &[Song],
    frames: usize,
) -> Result<Scene, Reject> {
    let j = UNISON_JITTER;
    // Dancers and members.
    let mut n = dancers_wanted;
    let mut couples = 0;
    if !pool.couples.is_empty() {
        couples = rng.below((n / 2).min(2) + 1);
    }
    if pool.solos.is_empty() {
        couples = (n / 2).clamp(1, 2);
        n = 2 * couples;
    }
    let mut members: Vec<Member> = (0..couples)
        .map(|_| Member::Couple)
        .chain((0..n - 2 * couples).map(|_| Member::Solo))
        .collect();
    for i in (1..members.len()).rev() {
        members.swap(i, rng.below(i + 1));
    }
    let m = members.len();
    let solos = n - 2 * couples;
    // Song span, starting on a beat.
    let si = pool.songs[rng.below(pool.songs.len())];
    let song = &songs[si];
    let starts: Vec<usize> = song
        .beat_frames
        .iter()
        .copied()
        .filter(|&b| b >= j && b + frames + j <= song.frames())
        .collect();
    if starts.is_empty() {
        return Err(Reject::NoFit);
    }
    let song_start = starts[rng.below(starts.len())];
    let beat = beat_period(&song.beat_frames);
    let phrase_starts: Vec<usize> = song
        .beat_frames
        .iter()
        .enumerate()
        .filter(|&(k, &b)| k % PHRASE_BEATS == 0 && b > song_start && b < song_start + frames)
        .map(|(_, &b)| b - song_start)
        .collect();
    let spacing = spacing_range(couples > 0);
    let plan = plan_formation(
        rng,
        m,
        frames,
        &phrase_starts,
        beat,
        &pool.shapes,
        spacing,
        0.7 * spacing.0,
    )
    .ok_or(Reject::NoFit)?;
    let timing = if solos >= 2 {
        match rng.next_f64() {
            x if x < 0.3 => Timing::Unison,
            x if x < 0.5 => Timing::Canon,
            _ => Timing::Contrast,
        }
    } else {
        Timing::Contrast
    };
    // Facing jitter per member.
    let jitter: Vec<f64> = (0..m)
        .map(|_| uniform(rng, -place::FACING_JITTER_RAD, place::FACING_JITTER_RAD))
        .collect();
    let span = frames + 2 * j;
    let solo_members: Vec<usize> = (0..m)
        .filter(|&k| matches!(members[k], Member::Solo))
        .collect();
    let canon_shift = match timing {
        Timing::Canon => (CANON_BEATS[rng.below(CANON_BEATS.len())] as f64 * beat).round() as usize,
        _ => 0,
    };
    // Segment choice per member: (segment, first frame kept of its warped span).
    let mut chosen: Vec<Option<(Segment, usize)>> = vec![None; m];
    let cost_solo = |src: usize, start: usize, k: usize| -> f64 {
        let s = &sources[src];
        let seg = slice(&s.unit.motion, start + j..start + j + frames);
        let yaw = solo_yaw(&seg, jitter[k]);
        travel_mismatch(&plan.paths[k], &s.lp[start + j..start + j + frames], yaw)
    };
    if matches!(timing, Timing::Unison | Timing::Canon) {
        let extra = canon_shift * (solo_members.len() - 1);
        let need = span + extra;
        let fit: Vec<usize> = pool
            .solos
            .iter()
            .copied()
            .filter(|&s| sources[s].unit.motion.frames() >= need)
            .collect();
        if fit.is_empty() {
            return Err(Reject::NoFit);
        }
        let mut best: Option<(f64, usize, usize)> = None;
        for _ in 0..CANDIDATES {
            let src = fit[rng.below(fit.len())];
            let start = rng.below(sources[src].unit.motion.frames() - need + 1);
            let c: f64 = solo_members
                .iter()
                .enumerate()
                .map(|(r, &k)| cost_solo(src, start + r * canon_shift, k))
                .sum();
            if best.is_none_or(|b| c < b.0) {
                best = Some((c, src, start));
            }
        }
        let (_, src, start) = best.expect("candidates");
        for (r, &k) in solo_members.iter().enumerate() {
            let (source, jit) = if timing == Timing::Unison {
                let s = if rng.next_f64() < UNISON_MIRROR_CHANCE {
                    sources[src].mirror_of
                } else {
                    src
                };
                (s, rng.below(2 * j + 1))
            } else {
                (src, j)
            };
            chosen[k] = Some((
                Segment {
                    source,
                    partner: None,
                    start: start + r * canon_shift,
                },
                jit,
            ));
        }
    }
    for k in 0..m {
        if chosen[k].is_some() {
            continue;
        }
        let mut best: Option<(f64, Segment)> = None;
        for _ in 0..CANDIDATES {
            let seg = match members[k] {
                Member::Solo => {
                    let fit: Vec<usize> = pool
                        .solos
                        .iter()
                        .copied()
                        .filter(|&s| sources[s].unit.motion.frames() >= span)
                        .collect();
                    if fit.is_empty() {
                        return Err(Reject::NoFit);
                    }
                    let src = fit[rng.below(fit.len())];
                    let start = rng.below(sources[src].unit.motion.frames() - span + 1);
                    Segment {
                        source: src,
                        partner: None,
                        start,
                    }
                }
                Member::Couple => {
                    let (a, b) = pool.couples[rng.below(pool.couples.len())];
                    let len = sources[a]
                        .unit
                        .motion
                        .frames()
                        .min(sources[b].unit.motion.frames());
                    if len < span {
                        continue;
                    }
                    Segment {
                        source: a,
                        partner: Some(b),
                        start: rng.below(len - span + 1),
                    }
                }
            };
            let c = match seg.partner {
                None => cost_solo(seg.source, seg.start, k),
                Some(b) => {
                    let r = seg.start + j..seg.start + j + frames;
                    let (ma, mb) = (
                        slice(&sources[seg.source].unit.motion, r.clone()),
                        slice(&sources[b].unit.motion, r.clone()),
                    );
                    let yaw = couple_yaw(&ma, &mb, jitter[k]);
                    let mid: Vec<StagePos> = root_xz(&ma)
                        .iter()
                        .zip(root_xz(&mb))
                        .map(|(p, q)| [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0])
                        .collect();
                    travel_mismatch(&plan.paths[k], &low_pass(&mid), yaw)
                }
            };
            if best.as_ref().is_none_or(|b| c < b.0) {
                best = Some((c, seg));
            }
        }
        let (_, seg) = best.ok_or(Reject::NoFit)?;
        chosen[k] = Some((seg, j));
    }
    // Warp every distinct segment once onto the song span (ends fixed).
    let music_beats: Vec<f64> = song
        .beats_in(song_start - j, span)
        .iter()
        .map(|&b| b as f64 / f64::from(FPS))
        .collect();
    let len_s = span as f64 / f64::from(FPS);
    let mut warped: HashMap<Segment, (Vec<SmplMotion>, WarpReport)> = HashMap::new();
    let mut dancers = Vec::new();
    let mut labels = Vec::new();
    let mut genres = Vec::new();
    let mut partners = Vec::new();
    let mut warp_total = WarpReport {
        min_rate: f64::INFINITY,
        max_rate: f64::NEG_INFINITY,
        matched_beats: 0,
        motion_beats: 0,
        bas_before: None,
        bas_after: None,
    };
    let mut unplaced_skating = Vec::new();
    for k in 0..m {
        let (seg, jit) = chosen[k].expect("chosen");
        if let std::collections::hash_map::Entry::Vacant(slot) = warped.entry(seg) {
            let r = seg.start..seg.start + span;
            let a = slice(&sources[seg.source].unit.motion, r.clone());
            let ja =
                world_joints(&a, &sources[seg.source].unit.source).map_err(|_| Reject::NoFit)?;
            let mb: Vec<f64> = kinematic_beats(&ja)
                .iter()
                .map(|&b| b as f64 / f64::from(FPS))
                .collect();
            let matched = match_beats_in_span(
                &mb,
                &music_beats,
                len_s,
                &crate::warp::WarpParams::default(),
            );
            let mut parts = vec![a];
            if let Some(b) = seg.partner {
                parts.push(slice(&sources[b].unit.motion, r.clone()));
            }
            let mut out = Vec::new();
            for p in &parts {
                let (_, w) = warp_motion(p, &matched.map, span);
                if w.frames() < span - j {
                    return Err(Reject::NoFit);
                }
                out.push(w);
            }
            let rates = matched.map.rates();
            let report = WarpReport {
                min_rate: rates.iter().copied().fold(1.0, f64::min),
                max_rate: rates.iter().copied().fold(1.0, f64::max),
                matched_beats: matched.pairs.len().saturating_sub(2),
                motion_beats: mb.len(),
                bas_before: None,
                bas_after: None,
            };
            slot.insert((out, report));
        }
        let (parts, report) = &warped[&seg];
        warp_total.min_rate = warp_total.min_rate.min(report.min_rate);
        warp_total.max_rate = warp_total.max_rate.max(report.max_rate);
        warp_total.matched_beats += report.matched_beats;
        warp_total.motion_beats += report.motion_beats;
        let cut = |w: &SmplMotion| -> Option<SmplMotion> {
            (w.frames() >= jit + frames).then(|| slice(w, jit..jit + frames))
        };
        let path = &plan.paths[k];
        match seg.partner {
            None => {
                let w = cut(&parts[0]).ok_or(Reject::NoFit)?;
                unplaced_skating.push(skating(
                    &world_joints(&w, Path::new("")).map_err(|_| Reject::NoFit)?,
                ));
                let mut placed = place_solo(&w, path, solo_yaw(&w, jitter[k]));
                placed
                    .put_on_ground_with(GroundMode::SupportFeet)
                    .map_err(|_| Reject::NoFit)?;
                dancers.push(placed);
                labels.push(sources[seg.source].label());
                genres.push(sources[seg.source].unit.genre.clone());
            }
            Some(b) => {
                let wa = cut(&parts[0]).ok_or(Reject::NoFit)?;
                let wb = cut(&parts[1]).ok_or(Reject::NoFit)?;
                for w in [&wa, &wb] {
                    unplaced_skating.push(skating(
                        &world_joints(w, Path::new("")).map_err(|_| Reject::NoFit)?,
                    ));
                }
                let (mut pa, mut pb) =
                    place_couple(&wa, &wb, path, couple_yaw(&wa, &wb, jitter[k]));
                let mut both = pa.joints_world().map_err(|_| Reject::NoFit)?;
                both.extend(pb.joints_world().map_err(|_| Reject::NoFit)?);
                let floor = SmplMotion::ground_height(&both, GroundMode::SupportFeet);
                for mm in [&mut pa, &mut pb] {
                    for p in mm.trans.chunks_exact_mut(3) {
                        p[1] -= floor;
                    }
                }
                partners.push([dancers.len(), dancers.len() + 1]);
                dancers.push(pa);
                dancers.push(pb);
                labels.push(sources[seg.source].label());
                labels.push(sources[b].label());
                genres.push(sources[seg.source].unit.genre.clone());
                genres.push(sources[b].unit.genre.clone());
            }
        }
    }
    let joints: Vec<Vec<f64>> = dancers
        .iter()
        .map(|d| world_joints(d, Path::new("")).map_err(|_| Reject::NoFit))
        .collect::<Result<_, _>>()?;
    check_scene(&joints, &partners, &unplaced_skating)?;
    let bas: Vec<f64> = joints
        .iter()
        .filter_map(|jj| bas_bailando(jj, &song.beats_in(song_start, frames)))
        .collect();
    warp_total.bas_after = (!bas.is_empty()).then(|| bas.iter().sum::<f64>() / bas.len() as f64);
    Ok(Scene {
        dancers,
        sources: labels,
        genres,
        partners,
        song: si,
        song_start,
        timing,
        plan,
        warp: warp_total,
    })
}

fn write_scene(
    out: &Path,
    scene: &Scene,
    songs: &[Song],
    index: usize,
    held: bool,
) -> Result<ClipEntry, DatasetError> {
    let n = scene.dancers.len();
    let name = if held {
        format!("group_held_{index:03}_n{n}")
    } else {
        format!("group_{index:04}_n{n}")
    };
    let prefix = if held { "held_out/" } else { "" };
    let dir_rel = format!("{prefix}group/{name}");
    let dir = out.join(&dir_rel);
    std::fs::create_dir_all(&dir)
        .map_err(|e| DatasetError::input(&dir, format!("cannot create directory: {e}")))?;
    let opts = ConvertOptions {
        npz_style: NpzStyle::Amass,
        ..Default::default()
    };
    let frames = scene.dancers[0].frames();
    let mut traj = vec![0f32; n * frames * 2];
    for (k, d) in scene.dancers.iter().enumerate() {
        save_motion_file(
            &dir.join(format!("dancer_{k}.npz")),
            &LoadedMotion::Smpl(d.clone()),
            &opts,
        )?;
        let j = d
            .joints_world()
            .map_err(|e| DatasetError::input(&dir, format!("forward kinematics failed: {e}")))?;
        for t in 0..frames {
            traj[(k * frames + t) * 2] = j[t * FRAME_LEN];
            traj[(k * frames + t) * 2 + 1] = j[t * FRAME_LEN + 2];
        }
    }
    let traj_rel = format!("{prefix}trajectories/{name}.npy");
    dancegen_io::write_npy_f32(&out.join(&traj_rel), &[n, frames, 2], &traj)?;
    let song = &songs[scene.song];
    let music_rel = format!("{prefix}music/{name}.npy");
    dancegen_io::write_npy_f32(
        &out.join(&music_rel),
        &[frames, EDGE35_DIM],
        &song.rows(scene.song_start, frames),
    )?;
    let at = |t: usize| -> Vec<usize> {
        let p: Vec<StagePos> = (0..n)
            .map(|k| {
                let i = (k * frames + t) * 2;
                [f64::from(traj[i]), f64::from(traj[i + 1])]
            })
            .collect();
        order_left_to_right(&p)
    };
    let mut genre_count: BTreeMap<&str, usize> = BTreeMap::new();
    for g in &scene.genres {
        *genre_count.entry(g).or_default() += 1;
    }
    let genre = genre_count
        .iter()
        .max_by_key(|(_, c)| **c)
        .map(|(g, _)| g.to_string())
        .unwrap_or_default();
    let fps = f64::from(FPS);
    Ok(ClipEntry {
        name,
        motion: dir_rel,
        music: music_rel,
        genre,
        source_motion: scene.sources.join(","),
        source_song: song.path.display().to_string(),
        song_start_s: scene.song_start as f64 / fps,
        song_end_s: (scene.song_start + frames) as f64 / fps,
        frames,
        pairing: PairingKind::PseudoBeatWarp,
        warp: Some(scene.warp.clone()),
        leader: None,
        group: Some(GroupLabels {
            dancers: n,
            partners: scene.partners.clone(),
            start_order: at(0),
            end_order: at(frames - 1),
            shapes: scene
                .plan
                .shapes
                .iter()
                .map(|s| s.name().to_string())
                .collect(),
            transitions: scene
                .plan
                .transitions
                .iter()
                .map(|s| s.to_string())
                .collect(),
            timing: scene.timing.name().to_string(),
            trajectories: traj_rel,
            sources: scene.sources.clone(),
        }),
        holistic: None,
    })
}
