//! Which song, and which stretch of a long take, a motion piece is warped onto: the plan the pseudo, duet and group pairings share.

use std::ops::Range;

use dancegen_metrics::FRAME_LEN;

use crate::beats::kinematic_beats;
use crate::options::BuildOptions;
use crate::song::Song;
use crate::warp::{BeatMatch, WarpParams, match_beats};
use crate::{FPS, MIN_CLIP_FRAMES};

/// Fraction of a song a motion piece may fill at the slowest allowed playback speed before
/// the motion is split into several clips (leaves room for the start offset).
const SONG_FILL: f64 = 0.9;

/// A motion piece and its matching against one song.
pub(crate) struct PiecePlan {
    pub(crate) frames: Range<usize>,
    pub(crate) motion_beats: usize,
    pub(crate) matched: BeatMatch,
}

/// Splits a motion of `frames` frames into pieces short enough for a song of `song_s` seconds
/// at the slowest playback speed the warp allows.
fn piece_ranges(frames: usize, song_s: f64, p: &WarpParams) -> Vec<Range<usize>> {
    let fps = f64::from(FPS);
    let capacity = (SONG_FILL * song_s / p.max_rate * fps).floor() as usize;
    if frames <= capacity || capacity < MIN_CLIP_FRAMES {
        return std::iter::once(0..frames).collect();
    }
    let k = frames.div_ceil(capacity);
    (0..k)
        .map(|i| i * frames / k..(i + 1) * frames / k)
        .collect()
}

pub(crate) fn plan_song(
    joints: &[f64],
    frames: usize,
    song: &Song,
    p: &WarpParams,
) -> Vec<PiecePlan> {
    let fps = f64::from(FPS);
    let music = song.beat_times();
    piece_ranges(frames, song.duration_s(), p)
        .into_iter()
        .map(|r| {
            let j = &joints[r.start * FRAME_LEN..r.end * FRAME_LEN];
            let beats: Vec<f64> = kinematic_beats(j).iter().map(|&b| b as f64 / fps).collect();
            let len = (r.len().saturating_sub(1)) as f64 / fps;
            let matched = match_beats(&beats, &music, len, song.duration_s(), p);
            PiecePlan {
                frames: r,
                motion_beats: beats.len(),
                matched,
            }
        })
        .collect()
}

/// The candidate song with the most matched beats per minute of motion, and its plan; exact ties
/// go to the first song in an order rotated by the seed. `None` without candidates.
pub(crate) fn best_song(
    joints: &[f64],
    frames: usize,
    songs: &[Song],
    candidates: &[usize],
    opts: &BuildOptions,
    name: &str,
) -> Option<(usize, Vec<PiecePlan>)> {
    ranked_songs(joints, frames, songs, candidates, opts, name)
        .into_iter()
        .next()
}

/// Every candidate song with its plan, best first: most matched beats per minute; exact ties
/// keep the order of the candidates rotated by `--seed`.
pub(crate) fn ranked_songs(
    joints: &[f64],
    frames: usize,
    songs: &[Song],
    candidates: &[usize],
    opts: &BuildOptions,
    name: &str,
) -> Vec<(usize, Vec<PiecePlan>)> {
    let minutes = frames as f64 / f64::from(FPS) / 60.0;
    let n = candidates.len();
    let mut ranked: Vec<(f64, usize, Vec<PiecePlan>)> = (0..n)
        .map(|k| {
            let si = candidates[(k + opts.seed as usize % n) % n];
            let plan = plan_song(joints, frames, &songs[si], &opts.warp);
            let matched: usize = plan.iter().map(|p| p.matched.pairs.len()).sum();
            let score = matched as f64 / minutes;
            tracing::debug!("{name} x {}: {score:.1} matched beats/min", songs[si].name);
            (score, si, plan)
        })
        .collect();
    // Stable: equal scores stay in the rotated order (the first one is what `best_song` took).
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
    ranked.into_iter().map(|(_, si, plan)| (si, plan)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_motions_are_split_to_fit_the_song() {
        let p = WarpParams::default();
        // 60 s song: at most 0.9 * 60 * 0.85 = 45.9 s of motion per piece (1377 frames).
        assert_eq!(piece_ranges(1377, 60.0, &p), vec![0..1377]);
        let r = piece_ranges(3000, 60.0, &p);
        assert_eq!(r.len(), 3);
        assert_eq!(r.first().unwrap().start, 0);
        assert_eq!(r.last().unwrap().end, 3000);
        for w in r.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        assert!(r.iter().all(|x| x.len() <= 1377));
    }
}
