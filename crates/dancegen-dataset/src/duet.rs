//! Duet pairing (`--pairing duet`): couples of dancers recorded together, both time-warped by
//! **one** beat warp onto a song, so the partners stay in sync with each other and with the music.
//!
//! Which files form a couple:
//! - two files whose stems agree after the first `_`-separated token — CMU's
//!   `<subject>_<take>` naming, e.g. `60_01_scaled.bvh` and `61_01_scaled.bvh`;
//! - or one group file holding exactly two dancers.
//!
//! The warp is planned on the kinematic beats of the couple's first dancer (sorted file order)
//! and applied to both. Each couple gives **two** clips, one per role assignment: the clip
//! named after a dancer has that dancer as follower (`motion/<clip>.npz`) and the partner as
//! leader (`leader/<clip>.npz`). Both are grounded by one shared offset (the floor is shared).
//! Holding out either dancer's stem holds out the whole couple.
//!
//! With `--mirror`, every training couple is also paired as its left–right mirror image (couple
//! `<key>_mirror`, clips `<name>_mirror`): both partners go through the same world reflection
//! ([`SmplMotion::mirror`] reflects x), so their placement relative to each other is mirrored
//! with them and they stay a couple. Held-out couples are never mirrored.

use std::collections::{BTreeMap, BTreeSet};

use dancegen_metrics::FRAME_LEN;
use dancegen_motion::repr::motion::{POSE_DIMS, SmplMotion};
use rayon::prelude::*;

use crate::MIN_CLIP_FRAMES;
use crate::beats::bas_bailando;
use crate::clips::{create_dirs, gather_clips, write_couple_clip};
use crate::error::DatasetError;
use crate::genre;
use crate::inputs::{analyse_songs, check_hold_out, expand_motion_inputs};
use crate::manifest::{ClipEntry, WarpReport};
use crate::options::{BuildOptions, Progress};
use crate::song::stem;
use crate::song_plan::best_song;
use crate::units::{MotionUnit, load_units, mirrored_unit, world_joints};
use crate::warp::warp_motion;

/// Two dancers recorded together.
struct Couple {
    key: String,
    dancers: [MotionUnit; 2],
}

/// The couple key of a stem: everything after the first `_` (`60_01_scaled` → `01_scaled`).
pub(crate) fn couple_key(stem: &str) -> Option<&str> {
    stem.split_once('_')
        .map(|(_, rest)| rest)
        .filter(|r| !r.is_empty())
}

fn couples(opts: &BuildOptions) -> Result<Vec<Couple>, DatasetError> {
    let files = expand_motion_inputs(&opts.motions)?;
    let mut by_key: BTreeMap<String, Vec<MotionUnit>> = BTreeMap::new();
    let mut out = Vec::new();
    for path in &files {
        let s = stem(path);
        let genre = opts
            .genre
            .as_deref()
            .map(genre::normalize)
            .unwrap_or_else(|| genre::genre_from_name(&s));
        let units = load_units(path, &genre, &opts.source_fps)?;
        match units.len() {
            1 => {
                let key = couple_key(&s).ok_or_else(|| {
                    DatasetError::input(
                        path,
                        "a single-dancer file needs a `<dancer>_<take>` name to find its partner",
                    )
                })?;
                by_key.entry(key.to_string()).or_default().extend(units);
            }
            2 => {
                let [a, b]: [MotionUnit; 2] = units.try_into().expect("two dancers");
                out.push(Couple {
                    key: s,
                    dancers: [a, b],
                });
            }
            n => {
                return Err(DatasetError::input(
                    path,
                    format!("{n} dancers: a duet data set needs couples (two dancers)"),
                ));
            }
        }
    }
    for (key, units) in by_key {
        let n = units.len();
        match <[MotionUnit; 2]>::try_from(units) {
            Ok(dancers) => out.push(Couple { key, dancers }),
            Err(units) => {
                return Err(DatasetError::input(
                    &units[0].source,
                    format!(
                        "take `{key}` has {n} dancer file(s); a couple needs exactly two \
                         (`<dancer>_{key}` for two dancers)"
                    ),
                ));
            }
        }
    }
    Ok(out)
}

pub(crate) fn slice(m: &SmplMotion, r: std::ops::Range<usize>) -> SmplMotion {
    SmplMotion {
        fps: m.fps,
        poses: m.poses[r.start * POSE_DIMS..r.end * POSE_DIMS].to_vec(),
        trans: m.trans[r.start * 3..r.end * 3].to_vec(),
    }
}

/// Builds a duet data set (see the module documentation).
pub(crate) fn build_duet(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<ClipEntry>, DatasetError> {
    if opts.motions.is_empty() {
        return Err(DatasetError::Options(
            "--pairing duet needs --motion FILES".into(),
        ));
    }
    if opts.music.is_empty() {
        return Err(DatasetError::Options(
            "--pairing duet needs --music SONGS".into(),
        ));
    }
    let mut couples = couples(opts)?;
    let mut known: BTreeSet<String> = opts.music.iter().map(|p| stem(p)).collect();
    for c in &couples {
        for d in &c.dancers {
            known.insert(d.stem.clone());
            known.insert(d.name.clone());
        }
    }
    check_hold_out(&opts.hold_out, &known)?;
    let held = |s: &str| opts.hold_out.iter().any(|h| h == s);
    if opts.mirror {
        let mirrored: Vec<Couple> = couples
            .iter()
            .filter(|c| !c.dancers.iter().any(|d| held(&d.stem) || held(&d.name)))
            .map(|c| Couple {
                key: format!("{}_mirror", c.key),
                dancers: [mirrored_unit(&c.dancers[0]), mirrored_unit(&c.dancers[1])],
            })
            .collect();
        couples.extend(mirrored);
    }
    let songs = analyse_songs(&opts.music, progress)?;
    let train_songs: Vec<usize> = (0..songs.len())
        .filter(|&i| !held(&songs[i].name))
        .collect();
    let held_songs: Vec<usize> = (0..songs.len()).filter(|&i| held(&songs[i].name)).collect();
    if train_songs.is_empty() {
        return Err(DatasetError::Options(
            "every song is held out: training couples need at least one song that is not".into(),
        ));
    }
    create_dirs(&opts.out)?;
    for d in ["leader", "held_out/leader"] {
        let p = opts.out.join(d);
        std::fs::create_dir_all(&p)
            .map_err(|e| DatasetError::input(&p, format!("cannot create directory: {e}")))?;
    }
    progress.stage("pairing couples", couples.len());
    let results: Vec<Result<Vec<ClipEntry>, DatasetError>> = couples
        .par_iter()
        .map(|c| {
            let r = pair_couple(c, &songs, &train_songs, &held_songs, opts, &held);
            progress.step(&c.key);
            r
        })
        .collect();
    gather_clips(results)
}

fn pair_couple(
    c: &Couple,
    songs: &[crate::song::Song],
    train_songs: &[usize],
    held_songs: &[usize],
    opts: &BuildOptions,
    held: &dyn Fn(&str) -> bool,
) -> Result<Vec<ClipEntry>, DatasetError> {
    let [a, b] = &c.dancers;
    let frames = a.motion.frames().min(b.motion.frames());
    if a.motion.frames() != b.motion.frames() {
        tracing::warn!(
            "couple {}: {} and {} frames, both cut to {frames}",
            c.key,
            a.motion.frames(),
            b.motion.frames()
        );
    }
    if frames < MIN_CLIP_FRAMES {
        tracing::warn!("couple {}: only {frames} frames at 30 fps, skipped", c.key);
        return Ok(Vec::new());
    }
    let couple_held = c.dancers.iter().any(|d| held(&d.stem) || held(&d.name));
    let candidates = if couple_held && !held_songs.is_empty() {
        held_songs
    } else {
        train_songs
    };
    let ma = slice(&a.motion, 0..frames);
    let mb = slice(&b.motion, 0..frames);
    let joints = world_joints(&ma, &a.source)?;
    let (si, plan) = best_song(&joints, frames, songs, candidates, opts, &c.key)
        .ok_or_else(|| DatasetError::Options(format!("couple {}: no song to pair with", c.key)))?;
    let song = &songs[si];
    let pieces = plan.len();
    let mut out = Vec::new();
    for (k, piece) in plan.into_iter().enumerate() {
        let r = piece.frames.clone();
        let (start, wa) = warp_motion(&slice(&ma, r.clone()), &piece.matched.map, song.frames());
        let (start_b, wb) = warp_motion(&slice(&mb, r.clone()), &piece.matched.map, song.frames());
        debug_assert_eq!(start, start_b);
        let len = wa.frames().min(wb.frames());
        if len < MIN_CLIP_FRAMES {
            tracing::warn!(
                "couple {}: only {len} frames fit in {}, skipped",
                c.key,
                song.name
            );
            continue;
        }
        let (wa, wb) = (slice(&wa, 0..len), slice(&wb, 0..len));
        let rates = piece.matched.map.rates();
        let bas_a = world_joints(&wa, &a.source)?;
        let report = WarpReport {
            min_rate: rates.iter().copied().fold(f64::INFINITY, f64::min),
            max_rate: rates.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            matched_beats: piece.matched.pairs.len(),
            motion_beats: piece.motion_beats,
            bas_before: None,
            bas_after: bas_bailando(&bas_a[..len * FRAME_LEN], &song.beats_in(start, len)),
        };
        let suffix = if pieces == 1 {
            String::new()
        } else {
            format!("_{k}")
        };
        for (follower, leader, unit) in [(&wa, &wb, a), (&wb, &wa, b)] {
            out.push(write_couple_clip(
                &opts.out,
                &format!("{}{suffix}", unit.name),
                unit,
                &song.path,
                start,
                follower,
                leader,
                song.rows(start, len),
                report.clone(),
                couple_held || held(&song.name),
            )?);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn couple_keys_drop_the_dancer_token() {
        assert_eq!(couple_key("60_01_scaled"), Some("01_scaled"));
        assert_eq!(couple_key("61_01_scaled"), Some("01_scaled"));
        assert_eq!(couple_key("solo"), None);
        assert_eq!(couple_key("a_"), None);
    }
}
