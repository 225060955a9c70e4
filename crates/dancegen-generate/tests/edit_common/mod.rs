//! What the editing tests (`edits.rs`, `edits_duet.rs`) share: the shared data folder, one
//! generator over the shipped models, world joints, and the real pose spread they compare
//! new parts with.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use dancegen_generate::Generator;
use dancegen_generate::ModelLocator;
use dancegen_generate::models::{Origin, SearchDir};
use dancegen_motion::repr::SmplMotion;

/// Real dancers' pose spread: the held-out real solo tracks at their true rates, 15.8 cm
/// (docs/group-eval.md, "Motion energy", `bash tools/group_eval.sh`). The issue asks a new part
/// to differ from the old one by at least half of it.
pub const REAL_POSE_SPREAD_M: f64 = 0.158;

pub fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// One generator over the shipped models, so each model loads once per test binary.
pub fn generator() -> &'static Generator {
    static G: OnceLock<Generator> = OnceLock::new();
    G.get_or_init(|| {
        Generator::new(ModelLocator::new(vec![SearchDir {
            dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models"),
            origin: Origin::Explicit,
        }]))
    })
}

/// World joints `(T, 24, 3)` as f64, for the metrics.
pub fn joints(m: &SmplMotion) -> Vec<f64> {
    m.joints_world()
        .unwrap()
        .into_iter()
        .map(f64::from)
        .collect()
}

/// The join bounds on `q` (an edit's figures, `what` naming it for messages): a
/// boundary-jerk ratio under 1.5 at the joins, and no root step at a join more than 5 cm beyond
/// the dance's own largest.
#[allow(dead_code)]
pub fn assert_joins(q: &dancegen_metrics::edit::EditQuality, what: &str) {
    let ratio = q.join_jerk_ratio.expect("joins inside the dance");
    assert!(
        ratio < 1.5,
        "{what}: boundary jerk ratio {ratio:.2} at the joins"
    );
    assert!(
        q.join_root_step_m <= q.other_root_step_m + 0.05,
        "{what}: root step {:.3} m at a join against {:.3} m elsewhere",
        q.join_root_step_m,
        q.other_root_step_m
    );
}

/// The beats (frames from `start`, 30 fps) of the held-out song `feelings.ogg` between
/// `start` and `end` seconds, as the generator finds them.
#[allow(dead_code)]
pub fn feelings_beats(start: f64, end: f64) -> Vec<usize> {
    let song = dancegen_generate::song::AnalysedSong::analyse(&dancegen_generate::Song::File(
        shared().join("data/music/sectoid/feelings.ogg"),
    ))
    .unwrap();
    song.beat_frames(&song.span(Some(start), Some(end)).unwrap())
}

/// Bailando's beat-align score of world joints `j` (`(T, 24, 3)`) against music beats (frames).
#[allow(dead_code)]
pub fn bas(j: &[f64], beats: &[usize]) -> f64 {
    use dancegen_metrics::bas::{Variant, beat_align_score, clip_music_beats, motion_beats};
    let frames = j.len() / 72;
    let music = clip_music_beats(beats, frames, Variant::Bailando);
    beat_align_score(
        &music,
        &motion_beats(j, Variant::Bailando),
        Variant::Bailando,
    )
    .unwrap()
}

/// The BAS of the frames `range` of world joints `j` alone, against the beats inside it.
#[allow(dead_code)]
pub fn bas_of_range(j: &[f64], beats: &[usize], range: &std::ops::Range<usize>) -> f64 {
    let inside: Vec<usize> = beats
        .iter()
        .filter(|&&b| range.contains(&b))
        .map(|&b| b - range.start)
        .collect();
    bas(&j[range.start * 72..range.end * 72], &inside)
}

/// The beat bound on a regenerated range `made` of world joints `j`: its BAS (the
/// range alone, against the beats inside it) is at least the whole dance's − 0.05. Returns
/// both, for the report.
#[allow(dead_code)]
pub fn assert_on_the_beat(
    j: &[f64],
    beats: &[usize],
    made: &std::ops::Range<usize>,
    what: &str,
) -> (f64, f64) {
    let whole = bas(j, beats);
    let part = bas_of_range(j, beats, made);
    assert!(
        part >= whole - 0.05,
        "{what}: BAS {part:.3} in the new part, {whole:.3} overall"
    );
    (whole, part)
}

/// The beat bound on the mean over seeds: the new parts' BAS (`part`, one per seed)
/// at least the whole edited dances' (`whole`) − 0.05; `plain` (the same range of plain
/// dances of those seeds) is reported beside them. `Err` says by how much it is missed.
#[allow(dead_code)]
pub fn on_the_beat_over_seeds(
    part: &[f64],
    whole: &[f64],
    plain: &[f64],
    what: &str,
) -> Result<(), String> {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (p, w, q) = (mean(part), mean(whole), mean(plain));
    eprintln!(
        "{what}: BAS of the new parts {part:.3?} (mean {p:.3}), of the whole edited dances \
         mean {w:.3}, of the same range of plain dances {plain:.3?} (mean {q:.3})"
    );
    if p >= w - 0.05 {
        Ok(())
    } else {
        Err(format!(
            "{what}: mean BAS {p:.3} in the new parts, {w:.3} for the whole dances"
        ))
    }
}

/// Mean joint jerk (m/s³) of a motion's world joints at 30 fps.
#[allow(dead_code)]
pub fn mean_jerk(m: &SmplMotion) -> f64 {
    let v = dancegen_metrics::longform::mean_joint_jerk(&joints(m), 30.0).unwrap();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The path bounds on a dance `m` made along `want` (the path's floor position per
/// frame of the dance, `None` where it is free): followed within 0.1 m on average over more
/// than 400 frames, no root step over 0.25 m in a frame, and jerk at most 1.5 times the plain
/// dance's (`plain`). `what` names the dance in the report.
#[allow(dead_code)]
pub fn assert_path_followed(
    m: &SmplMotion,
    want: &[Option<[f64; 2]>],
    plain: &SmplMotion,
    what: &str,
) {
    let (mut sum, mut n) = (0.0, 0);
    for (f, p) in want.iter().enumerate() {
        if let Some([x, z]) = *p {
            sum += (f64::from(m.trans[f * 3]) - x).hypot(f64::from(m.trans[f * 3 + 2]) - z);
            n += 1;
        }
    }
    let mean = sum / n.max(1) as f64;
    let step = (1..m.frames())
        .map(|f| {
            let d = |c: usize| f64::from(m.trans[f * 3 + c] - m.trans[(f - 1) * 3 + c]);
            d(0).hypot(d(2))
        })
        .fold(0.0, f64::max);
    let (jerk_p, jerk_b) = (mean_jerk(m), mean_jerk(plain));
    eprintln!(
        "{what}: {n} frames, mean distance {mean:.4} m; largest root step {step:.3} m; jerk \
         {jerk_p:.0} against the plain dance's {jerk_b:.0}"
    );
    assert!(
        n > 400 && mean <= 0.1,
        "{what}: the path is missed by {mean:.3} m"
    );
    assert!(
        step <= 0.25,
        "{what}: a root step of {step:.3} m in a frame"
    );
    assert!(
        jerk_p <= 1.5 * jerk_b,
        "{what}: jerk {jerk_p:.0} against {jerk_b:.0}"
    );
}
