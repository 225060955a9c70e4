//! Beat alignment of a generated dance (post-processing, not part of any of the four papers):
//! the dance is time-warped so that its kinematic beats land on the song's beats (solo) or on
//! the leader's (duet: a partner's accents echo the leader's), with the same
//! monotone piecewise-linear map and the same ±15 % limit on the local playback speed that pair
//! real motion with songs in the training set (`dancegen_refine::beat_warp`). The dance keeps
//! its length: its first and last frames stay where they are.
//!
//! Why: a model trained on beat-warped motion still places its velocity minima only roughly on
//! the beat (solo BAS 0.24 against 0.46 for the real held-out motion, docs/solo-eval.md), and
//! a dancer who is a few frames late on every accent looks off the music. The kinematic beats
//! are the ones Bailando's BAS measures (Gaussian σ = 5 frames on the mean joint speed,
//! `dancegen_metrics::bas`), so what is moved is what a viewer and the metric both see; for a
//! duet both partners' beats are Duolando's (`dancegen_metrics::duet::duet_motion_beats`, the
//! speed over the 55 SMPL-X joints, hands weighted), the beats its Beat Echo Degree compares.

use dancegen_metrics::FeatureError;
use dancegen_metrics::bas::{Variant, beat_align_score, try_motion_beats};
use dancegen_metrics::duet::duet_motion_beats;
use dancegen_motion::repr::SmplMotion;
use dancegen_motion::repr::motion::POSE_DIMS as POSE;
use dancegen_refine::beat_warp::{TimeMap, WarpParams, match_beats_in_span, warp_motion};

/// Alignment passes at most. The first moves the kinematic beats onto the target beats; the
/// warp itself then shifts some of them (the playback speed changes at each anchor, which moves
/// the minima of the smoothed speed, and can merge two of them), so each pass finds the beats
/// of the warped dance again. A pass is kept only while it raises the alignment score (see
/// [`BeatAlignment::score`]) and its map, composed with the earlier ones, stays inside the
/// speed limit; a dance no warp improves comes back unchanged. On `feelings.ogg` 20–36 s (seed
/// 0, the shipped solo model) one unchecked pass met 8 music beats instead of 5 but lost 3 of
/// the dance's 16 beats, and its score fell from 0.36 to 0.34.
pub const MAX_PASSES: usize = 3;

/// A target beat counts as met when a kinematic beat of the dance lies within this many frames
/// of it (a warp places beats at fractional times; the metric's beats are whole frames).
pub const MET_WITHIN_FRAMES: usize = 1;

/// What the alignment did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BeatAlignment {
    /// Kinematic beats of the dance before alignment.
    pub motion_beats: usize,
    /// Beats to meet (the song's, or the leader's) inside the dance.
    pub target_beats: usize,
    /// Target beats met ([`MET_WITHIN_FRAMES`]) by a kinematic beat of the dance before
    /// alignment.
    pub met_before: usize,
    /// Target beats met by a kinematic beat of the aligned dance (its beats found again).
    pub matched: usize,
    /// [`Self::score`] of the dance before alignment.
    pub score_before: f64,
    /// Bailando's beat-align score of the aligned dance's kinematic beats against the target
    /// beats inside it (Gaussian tolerance σ = 3 frames, `dancegen_metrics::bas`): how close
    /// each target beat is to a motion beat, averaged over the target beats.
    pub score: f64,
    /// Passes whose warp was kept (0: the dance is returned unchanged).
    pub passes: usize,
    /// Largest local change of playback speed, as a fraction (0.15 = 15 % faster or slower).
    pub max_tempo_change: f64,
}

impl BeatAlignment {
    /// One line for the run's notes; `target` names the beats met ("music", "leader").
    pub fn note(&self, target: &str) -> String {
        format!(
            "beat alignment: {} of {} {target} beats met by a motion beat ({} before), \
             alignment score {:.2} ({:.2} before; playback speed within ±{:.0} %)",
            self.matched,
            self.target_beats,
            self.met_before,
            self.score,
            self.score_before,
            100.0 * self.max_tempo_change
        )
    }
}

/// World joints `(T, 24, 3)` of `m` as f64.
fn joints_f64(m: &SmplMotion) -> Result<Vec<f64>, String> {
    Ok(m.joints_world()
        .map_err(|e| format!("beat alignment: forward kinematics failed: {e}"))?
        .into_iter()
        .map(f64::from)
        .collect())
}

/// Bailando's kinematic beats of world joints (solo).
fn bailando_beats(joints: &[f64]) -> Result<Vec<usize>, FeatureError> {
    try_motion_beats(joints, Variant::Bailando)
}

/// `motion` warped so that its kinematic beats meet `beat_frames` (music beats, frames of
/// `motion`'s rate from its first frame); same frame count and rate. A dance too short for
/// beats, or without any, comes back unchanged.
pub fn align_to_beats(
    motion: &SmplMotion,
    beat_frames: &[usize],
) -> Result<(SmplMotion, BeatAlignment), String> {
    align_with(motion, beat_frames, bailando_beats)
}

/// `motion` with each run of frames where `made` is true (frames an edit made anew) warped
/// so that its kinematic beats meet `beat_frames` (frames of `motion`), as
/// [`align_to_beats`] warps a whole dance. Each run is warped together with the kept frame on
/// each side of it, whose places the warp fixes, so every frame outside the runs stays exactly
/// as it was and the run still meets its neighbours. Why: a plain dance is aligned whole,
/// and an edit's new part, left as sampled, was off the beat the rest of the dance keeps
/// (group edits, seeds 1-5: new parts' BAS 0.08-0.21 against 0.28-0.34 for the whole dance).
/// Returns the reports of the runs long enough to have beats.
pub fn align_made_runs_to_beats(
    motion: &SmplMotion,
    made: &[bool],
    beat_frames: &[usize],
) -> Result<(SmplMotion, Vec<BeatAlignment>), String> {
    let frames = motion.frames();
    if made.len() != frames {
        return Err(format!(
            "beat alignment: {} frames marked made for a dance of {frames}",
            made.len()
        ));
    }
    let mut out = motion.clone();
    let mut reports = Vec::new();
    let mut f = 0;
    while f < frames {
        if !made[f] {
            f += 1;
            continue;
        }
        let start = f;
        while f < frames && made[f] {
            f += 1;
        }
        // The run and one kept neighbour on each side (where there is one).
        let (a, b) = (start.saturating_sub(1), (f + 1).min(frames));
        let piece = SmplMotion {
            fps: motion.fps,
            poses: motion.poses[a * POSE..b * POSE].to_vec(),
            trans: motion.trans[a * 3..b * 3].to_vec(),
        };
        let beats: Vec<usize> = beat_frames
            .iter()
            .filter(|&&x| x >= a && x < b)
            .map(|&x| x - a)
            .collect();
        let (aligned, report) = align_to_beats(&piece, &beats)?;
        out.poses[a * POSE..b * POSE].copy_from_slice(&aligned.poses);
        out.trans[a * 3..b * 3].copy_from_slice(&aligned.trans);
        if report.target_beats > 0 {
            reports.push(report);
        }
    }
    Ok((out, reports))
}

/// A follower warped so that its beats echo the `leader`'s (both by Duolando's duet beats);
/// the follower keeps its frame count (the leader's).
pub fn align_follower_to_leader(
    follower: &SmplMotion,
    leader: &SmplMotion,
) -> Result<(SmplMotion, BeatAlignment), String> {
    let lead = duet_motion_beats(&joints_f64(leader)?).unwrap_or_default();
    align_with(follower, &lead, duet_motion_beats)
}

fn align_with(
    motion: &SmplMotion,
    beat_frames: &[usize],
    beats_of: fn(&[f64]) -> Result<Vec<usize>, FeatureError>,
) -> Result<(SmplMotion, BeatAlignment), String> {
    let frames = motion.frames();
    let fps = f64::from(motion.fps);
    let unchanged = |target_beats| {
        (
            motion.clone(),
            BeatAlignment {
                target_beats,
                ..Default::default()
            },
        )
    };
    if frames < 3 || beat_frames.is_empty() {
        return Ok(unchanged(beat_frames.len()));
    }
    let Ok(kinematic) = beats_of(&joints_f64(motion)?) else {
        return Ok(unchanged(beat_frames.len()));
    };
    let last = frames - 1;
    let inside: Vec<usize> = beat_frames
        .iter()
        .copied()
        .filter(|&b| b > 0 && b < last)
        .collect();
    let met = |beats: &[usize]| {
        inside
            .iter()
            .filter(|&&b| beats.iter().any(|&m| m.abs_diff(b) <= MET_WITHIN_FRAMES))
            .count()
    };
    let to_s = |f: usize| f as f64 / fps;
    let target: Vec<f64> = beat_frames.iter().map(|&b| to_s(b)).collect();
    let len = to_s(last);
    let params = WarpParams::default();
    let score =
        |beats: &[usize]| beat_align_score(&inside, beats, Variant::Bailando).unwrap_or(0.0);
    let score_before = score(&kinematic);
    let mut best = (motion.clone(), TimeMap::shift(0.0), score_before, 0);
    let mut beats = kinematic.clone();
    for pass in 1..=MAX_PASSES {
        let beats_s: Vec<f64> = beats.iter().map(|&b| to_s(b)).collect();
        let step = match_beats_in_span(&beats_s, &target, len, &params);
        if step.pairs.is_empty() {
            break;
        }
        let map = best.1.then(&step.map);
        if !map.within(&params) {
            break;
        }
        // Always warp the original dance (one resampling, however many passes).
        let (start, warped) = warp_motion(motion, &map, frames);
        if start != 0 || warped.frames() != frames {
            // The map fixes both ends, so this is a defect, not bad input.
            return Err(format!(
                "beat alignment: the warp gave frames {start}..{} of {frames}",
                start + warped.frames()
            ));
        }
        let Ok(found) = beats_of(&joints_f64(&warped)?) else {
            break;
        };
        let s = score(&found);
        if s <= best.2 {
            break;
        }
        best = (warped, map, s, pass);
        beats = found;
    }
    let (aligned, map, score_after, passes) = best;
    let max_tempo_change = if passes == 0 {
        0.0
    } else {
        map.rates()
            .iter()
            .map(|r| (1.0 / r - 1.0).abs())
            .fold(0.0, f64::max)
    };
    Ok((
        aligned,
        BeatAlignment {
            motion_beats: kinematic.len(),
            target_beats: inside.len(),
            met_before: met(&kinematic),
            matched: met(&beats),
            score_before,
            score: score_after,
            passes,
            max_tempo_change,
        },
    ))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use dancegen_metrics::bas::{beat_align_score, clip_music_beats};

    /// 300 frames at 30 fps of a dancer bobbing (root height and both shoulders) every 15 frames
    /// (a 120 bpm beat), `lag` frames late.
    pub(crate) fn bob(lag: f64) -> SmplMotion {
        let frames = 300;
        let mut m = SmplMotion {
            fps: 30.0,
            poses: vec![0.0; frames * 72],
            trans: vec![0.0; frames * 3],
        };
        for f in 0..frames {
            let phase = std::f64::consts::TAU * (f as f64 - lag) / 15.0;
            m.trans[f * 3 + 1] = 0.9 + 0.05 * phase.cos() as f32;
            m.poses[f * 72 + 16 * 3 + 2] = 0.6 * phase.cos() as f32;
            m.poses[f * 72 + 17 * 3 + 2] = -0.6 * phase.cos() as f32;
        }
        m
    }

    /// A dancer bobbing (arms and root) at 2 Hz, a fifth of a beat late on a 120 bpm song: the
    /// alignment keeps the length and the end poses, and raises Bailando's BAS against the song.
    #[test]
    fn a_late_dancer_is_moved_onto_the_beat() {
        let m = bob(3.0);
        let frames = m.frames();
        let beats: Vec<usize> = (1..20).map(|k| k * 15).collect();
        let bas = |m: &SmplMotion| {
            let motion = try_motion_beats(&joints_f64(m).unwrap(), Variant::Bailando).unwrap();
            let music = clip_music_beats(&beats, m.frames(), Variant::Bailando);
            beat_align_score(&music, &motion, Variant::Bailando).unwrap()
        };
        let (aligned, report) = align_to_beats(&m, &beats).unwrap();
        assert_eq!(aligned.frames(), frames);
        assert_eq!(aligned.poses[..72], m.poses[..72]);
        assert_eq!(
            aligned.poses[(frames - 1) * 72..],
            m.poses[(frames - 1) * 72..]
        );
        assert!(report.matched > 5, "{report:?}");
        assert!(report.max_tempo_change <= 0.15 + 1e-9, "{report:?}");
        let (before, after) = (bas(&m), bas(&aligned));
        assert!(after > before + 0.1, "BAS {before} -> {after}");
    }

    /// Only the made run of a late dancer is warped: frames outside it (and the kept frame on
    /// each side, which the warp fixes) stay bit for bit, and the run's BAS rises.
    #[test]
    fn only_the_made_run_is_moved_onto_the_beat() {
        let m = bob(3.0);
        let frames = m.frames();
        let beats: Vec<usize> = (1..20).map(|k| k * 15).collect();
        let made: Vec<bool> = (0..frames).map(|f| (90..240).contains(&f)).collect();
        let (aligned, reports) = align_made_runs_to_beats(&m, &made, &beats).unwrap();
        assert_eq!(reports.len(), 1);
        assert!(reports[0].passes > 0, "{reports:?}");
        for f in (0..90).chain(240..frames) {
            assert_eq!(
                aligned.poses[f * 72..(f + 1) * 72],
                m.poses[f * 72..(f + 1) * 72]
            );
            assert_eq!(
                aligned.trans[f * 3..(f + 1) * 3],
                m.trans[f * 3..(f + 1) * 3]
            );
        }
        let bas_of_run = |m: &SmplMotion| {
            let motion: Vec<usize> = try_motion_beats(&joints_f64(m).unwrap(), Variant::Bailando)
                .unwrap()
                .into_iter()
                .filter(|b| (95..235).contains(b))
                .collect();
            let music: Vec<usize> = beats
                .iter()
                .copied()
                .filter(|b| (95..235).contains(b))
                .collect();
            beat_align_score(&music, &motion, Variant::Bailando).unwrap()
        };
        let (before, after) = (bas_of_run(&m), bas_of_run(&aligned));
        assert!(after > before + 0.1, "the run's BAS {before} -> {after}");
        let wrong = align_made_runs_to_beats(&m, &made[1..], &beats).unwrap_err();
        assert!(
            wrong.contains("299 frames marked made for a dance of 300"),
            "{wrong}"
        );
    }

    /// A follower doing the leader's bob a fifth of a beat late echoes it better after the
    /// alignment (Beat Echo Degree up), keeping its length.
    #[test]
    fn a_late_follower_echoes_the_leader() {
        let (leader, follower) = (bob(0.0), bob(3.0));
        let bed = |f: &SmplMotion| {
            dancegen_metrics::duet::beat_echo_degree(
                &joints_f64(f).unwrap(),
                &joints_f64(&leader).unwrap(),
            )
            .unwrap()
            .unwrap()
        };
        let (aligned, report) = align_follower_to_leader(&follower, &leader).unwrap();
        assert_eq!(aligned.frames(), follower.frames());
        assert!(report.matched > 5, "{report:?}");
        let (before, after) = (bed(&follower), bed(&aligned));
        assert!(after > before + 0.1, "BED {before} -> {after}");
    }

    /// The report counts the beats the aligned dance really has on the target (found again on
    /// its joints), and a late dancer's score rises.
    #[test]
    fn the_report_counts_the_beats_of_the_aligned_dance() {
        let beats: Vec<usize> = (1..20).map(|k| k * 15).collect();
        let met = |m: &SmplMotion| {
            let found = bailando_beats(&joints_f64(m).unwrap()).unwrap();
            beats
                .iter()
                .filter(|&&b| b < m.frames() - 1)
                .filter(|&&b| found.iter().any(|&f| f.abs_diff(b) <= MET_WITHIN_FRAMES))
                .count()
        };
        for lag in [0.0, 3.0, 5.0] {
            let m = bob(lag);
            let (aligned, report) = align_to_beats(&m, &beats).unwrap();
            assert_eq!(report.met_before, met(&m), "lag {lag}");
            assert_eq!(report.matched, met(&aligned), "lag {lag}");
            assert!(report.passes > 0, "lag {lag}: {report:?}");
            assert!(report.score > report.score_before, "lag {lag}: {report:?}");
        }
    }

    /// A dance whose beats are already the targets scores 1; no warp can raise that, so the
    /// alignment keeps no pass and returns the dance untouched.
    #[test]
    fn a_dance_already_on_the_beat_is_left_alone() {
        let m = bob(3.0);
        let own = bailando_beats(&joints_f64(&m).unwrap()).unwrap();
        assert!(own.len() > 5, "{own:?}");
        let (same, report) = align_to_beats(&m, &own).unwrap();
        assert_eq!(report.score_before, 1.0, "{report:?}");
        assert_eq!(report.passes, 0, "{report:?}");
        assert_eq!(report.max_tempo_change, 0.0);
        assert_eq!(same.poses, m.poses);
        assert_eq!(same.trans, m.trans);
    }

    #[test]
    fn no_beats_changes_nothing() {
        let m = SmplMotion {
            fps: 30.0,
            poses: vec![0.1; 40 * 72],
            trans: vec![0.0; 40 * 3],
        };
        let (same, report) = align_to_beats(&m, &[]).unwrap();
        assert_eq!(same.poses, m.poses);
        assert_eq!(report.matched, 0);
    }
}
