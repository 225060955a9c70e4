//! The beat-warp pseudo-pairing of solo takes (`Pairing::Pseudo`).

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use dancegen_metrics::FRAME_LEN;
use dancegen_motion::repr::motion::{POSE_DIMS, SmplMotion};
use rayon::prelude::*;

use crate::beats::bas_bailando;
use crate::clips::{ClipData, create_dirs, gather_clips, write_clip};
use crate::error::DatasetError;
use crate::genre;
use crate::inputs::{analyse_songs, check_hold_out, expand_motion_inputs};
use crate::manifest::{ClipEntry, PairingKind, WarpReport};
use crate::options::{BuildOptions, Progress};
use crate::song::{Song, stem};
use crate::song_plan::{PiecePlan, ranked_songs};
use crate::units::{MotionUnit, load_units, mirrored_unit, world_joints};
use crate::warp::warp_motion;
use crate::{FPS, MIN_CLIP_FRAMES};

/// `Pairing::Pseudo`: every take, cut into pieces that fit a song, warped onto the beats of
/// the song whose beats it matches best (`song_plan::ranked_songs`); held-out takes and songs
/// go to `held_out/`.
pub(crate) fn build_pseudo(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<ClipEntry>, DatasetError> {
    if opts.motions.is_empty() {
        return Err(DatasetError::Options(
            "--pairing pseudo needs --motion FILES".into(),
        ));
    }
    if opts.music.is_empty() {
        return Err(DatasetError::Options(
            "--pairing pseudo needs --music SONGS".into(),
        ));
    }
    let motions = expand_motion_inputs(&opts.motions)?;
    let mut known = BTreeSet::new();
    let mut seen: HashMap<String, &Path> = HashMap::new();
    for p in motions.iter().chain(&opts.music) {
        let s = stem(p);
        if let Some(prev) = seen.insert(s.clone(), p) {
            return Err(DatasetError::input(
                p,
                format!(
                    "same file name as {} (clip and hold-out names come from file names)",
                    prev.display()
                ),
            ));
        }
        known.insert(s);
    }
    check_hold_out(&opts.hold_out, &known)?;
    let held = |s: &str| opts.hold_out.iter().any(|h| h == s);
    let any_train_motion = motions.iter().any(|m| !held(&stem(m)));
    if any_train_motion && opts.music.iter().all(|m| held(&stem(m))) {
        return Err(DatasetError::Options(
            "every song is held out: training motions need at least one song that is not".into(),
        ));
    }
    let songs = analyse_songs(&opts.music, progress)?;
    for s in &songs {
        tracing::info!(
            "{}: {:.1} s, tempo {:.1} BPM, {} beats",
            s.path.display(),
            s.duration_s(),
            s.tempo_bpm,
            s.beat_frames.len()
        );
    }
    let train_songs: Vec<usize> = (0..songs.len())
        .filter(|&i| !held(&songs[i].name))
        .collect();
    let held_songs: Vec<usize> = (0..songs.len()).filter(|&i| held(&songs[i].name)).collect();
    let any_held_motion = motions.iter().any(|m| held(&stem(m)));
    if !held_songs.is_empty() && !any_held_motion {
        tracing::warn!(
            "held-out songs are only paired with held-out motions, and no motion is held out: \
             {} unused",
            held_songs
                .iter()
                .map(|&i| songs[i].name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    create_dirs(&opts.out)?;
    progress.stage("pairing motions", motions.len());
    let results: Vec<Result<Vec<ClipEntry>, DatasetError>> = motions
        .par_iter()
        .map(|path| {
            let s = stem(path);
            let genre = opts
                .genre
                .as_deref()
                .map(genre::normalize)
                .unwrap_or_else(|| genre::genre_from_name(&s));
            let motion_held = held(&s);
            // Training motions never see a held-out song; held-out motions are paired with the
            // held-out songs when there are any (unseen motion on unseen music), else any song.
            let candidates = if motion_held && !held_songs.is_empty() {
                &held_songs
            } else {
                &train_songs
            };
            let mut entries = Vec::new();
            let mut units = load_units(path, &genre, &opts.source_fps)?;
            if opts.mirror && !motion_held {
                let mirrored: Vec<MotionUnit> = units.iter().map(mirrored_unit).collect();
                units.extend(mirrored);
            }
            for unit in units {
                for clip in pair_unit(&unit, &songs, candidates, opts, held)? {
                    entries.push(write_clip(&opts.out, &clip)?);
                }
            }
            progress.step(&s);
            Ok(entries)
        })
        .collect();
    let clips = gather_clips(results)?;
    let mut names = BTreeSet::new();
    for c in &clips {
        if !names.insert(c.name.as_str()) {
            return Err(DatasetError::Options(format!(
                "two clips are named {} (rename one of the inputs)",
                c.name
            )));
        }
    }
    Ok(clips)
}

/// Picks the song and produces the warped clips of one dancer.
fn pair_unit(
    unit: &MotionUnit,
    songs: &[Song],
    candidates: &[usize],
    opts: &BuildOptions,
    held: impl Fn(&str) -> bool,
) -> Result<Vec<ClipData>, DatasetError> {
    let m = &unit.motion;
    let frames = m.frames();
    if frames < MIN_CLIP_FRAMES {
        tracing::warn!(
            "{}: only {frames} frames at 30 fps, skipped",
            unit.source.display()
        );
        return Ok(Vec::new());
    }
    let joints = world_joints(m, &unit.source)?;
    let ranked = ranked_songs(&joints, frames, songs, candidates, opts, &unit.name);
    if ranked.is_empty() {
        return Err(DatasetError::Options(format!(
            "{}: no song to pair with",
            unit.source.display()
        )));
    }
    // A held-out take is measured once, against its best song.
    let keep = if held(&unit.stem) {
        1
    } else {
        opts.songs_per_motion.max(1)
    };
    let mut clips = Vec::new();
    for (rank, (si, plan)) in ranked.into_iter().take(keep).enumerate() {
        let song = &songs[si];
        // The best song keeps the plain name; further pairings name their song.
        let base = if rank == 0 {
            unit.name.clone()
        } else {
            format!("{}__{}", unit.name, song.name)
        };
        clips.extend(warp_plan(unit, &joints, song, plan, &base, &held)?);
    }
    Ok(clips)
}

/// The warped clips of `unit` on `song` by `plan` (one per piece), named `base` or
/// `base_<k>`.
fn warp_plan(
    unit: &MotionUnit,
    joints: &[f64],
    song: &Song,
    plan: Vec<PiecePlan>,
    base: &str,
    held: &impl Fn(&str) -> bool,
) -> Result<Vec<ClipData>, DatasetError> {
    let m = &unit.motion;
    let pieces = plan.len();
    let mut clips = Vec::new();
    for (k, piece) in plan.into_iter().enumerate() {
        let r = piece.frames.clone();
        let src = SmplMotion {
            fps: m.fps,
            poses: m.poses[r.start * POSE_DIMS..r.end * POSE_DIMS].to_vec(),
            trans: m.trans[r.start * 3..r.end * 3].to_vec(),
        };
        let (start, warped) = warp_motion(&src, &piece.matched.map, song.frames());
        let n = warped.frames();
        let name = if pieces == 1 {
            base.to_string()
        } else {
            format!("{base}_{k}")
        };
        if n < MIN_CLIP_FRAMES {
            tracing::warn!("{name}: only {n} frames fit in {}, skipped", song.name);
            continue;
        }
        let after = bas_bailando(
            &world_joints(&warped, &unit.source)?,
            &song.beats_in(start, n),
        );
        // The same piece unwarped, placed at the same song start.
        let fps = f64::from(FPS);
        let p0 = (piece.matched.map.inverse(start as f64 / fps) * fps)
            .round()
            .clamp(0.0, (r.len() - 1) as f64) as usize;
        let len = (r.len() - p0).min(song.frames() - start);
        let a = (r.start + p0) * FRAME_LEN;
        let before = bas_bailando(&joints[a..a + len * FRAME_LEN], &song.beats_in(start, len));
        let rates = piece.matched.map.rates();
        let report = WarpReport {
            min_rate: rates.iter().copied().fold(f64::INFINITY, f64::min),
            max_rate: rates.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            matched_beats: piece.matched.pairs.len(),
            motion_beats: piece.motion_beats,
            bas_before: before,
            bas_after: after,
        };
        clips.push(ClipData {
            name,
            genre: unit.genre.clone(),
            source_motion: unit.source.clone(),
            source_song: song.path.clone(),
            start_frame: start,
            music: song.rows(start, n),
            motion: warped,
            pairing: PairingKind::PseudoBeatWarp,
            warp: Some(report),
            held_out: held(&unit.stem) || held(&song.name),
        });
    }
    Ok(clips)
}
