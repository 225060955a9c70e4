//! How well an edit (`generate --edit … --regenerate A-B`, `--continue-from`) keeps what it
//! must keep and joins what it makes (our figures, issue 44): the edited dance against the one
//! it edits, with the ranges of frames that were made new.
//!
//! | figure | meaning |
//! |---|---|
//! | `kept_max_m` | largest distance of any joint between the two dances over the kept frames |
//! | `join_jerk_ratio` | [`crate::longform::boundary_jerk_ratio`] with the joins as boundaries: ≈ 1 when a join is as smooth as the rest |
//! | `join_root_step_m` | largest horizontal root move between consecutive frames within [`JOIN_BAND`] frames of a join |
//! | `other_root_step_m` | the same away from the joins, the dance's own largest step |
//! | `join_foot_slide_m` | largest horizontal move between consecutive frames of a foot joint within [`crate::physical::CONTACT_HEIGHT_M`] of the floor in both, within [`JOIN_BAND`] frames of a join |
//! | `other_foot_slide_m` | the same away from the joins |
//! | `new_difference_m` | mean distance of the pelvis-relative joints between the two dances over the new frames: how new the new part is |
//!
//! A join is the first frame of a new range and the first kept frame after it (ranges at the
//! dance's ends have one). Joints are `(T, 24, 3)`, Y-up, metres, as everywhere in this crate.

use std::ops::Range;

use crate::physical::{CONTACT_HEIGHT_M, FOOT_JOINTS};
use crate::{FRAME_LEN, FeatureError, frame_count};

/// Frames on each side of a join that count as the join.
pub const JOIN_BAND: usize = 5;

/// See the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct EditQuality {
    pub kept_max_m: f64,
    pub join_jerk_ratio: Option<f64>,
    pub join_root_step_m: f64,
    pub other_root_step_m: f64,
    pub join_foot_slide_m: f64,
    pub other_foot_slide_m: f64,
    pub new_difference_m: f64,
}

/// Joint `k` of frame `f`.
fn at(j: &[f64], f: usize, k: usize) -> &[f64] {
    &j[f * FRAME_LEN + 3 * k..f * FRAME_LEN + 3 * k + 3]
}

/// The figures of `edited` against `original` (the same frame count) whose frames `made` were
/// made new.
pub fn edit_quality(
    original: &[f64],
    edited: &[f64],
    made: &[Range<usize>],
    fps: f64,
) -> Result<EditQuality, FeatureError> {
    let t = frame_count(original)?;
    let te = frame_count(edited)?;
    if te != t {
        return Err(FeatureError::TooShort {
            what: "an edit's comparison (one frame per frame of the original)",
            min: t,
            frames: te,
        });
    }
    let is_made = {
        let mut v = vec![false; t];
        for r in made {
            v[r.start.min(t)..r.end.min(t)].fill(true);
        }
        v
    };
    let joins: Vec<usize> = (1..t).filter(|&f| is_made[f] != is_made[f - 1]).collect();
    let near = |f: usize| {
        joins
            .iter()
            .any(|&b| f + JOIN_BAND >= b && f < b + JOIN_BAND)
    };
    let horizontal = |a: &[f64], b: &[f64]| ((a[0] - b[0]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();

    let mut kept_max = 0f64;
    let mut diff = (0f64, 0usize);
    for (f, &new) in is_made.iter().enumerate() {
        let (o, e) = (at(original, f, 0), at(edited, f, 0));
        for k in 0..24 {
            let (a, b) = (at(original, f, k), at(edited, f, k));
            if new {
                let d: f64 = (0..3)
                    .map(|c| ((a[c] - o[c]) - (b[c] - e[c])).powi(2))
                    .sum::<f64>()
                    .sqrt();
                diff = (diff.0 + d, diff.1 + 1);
            } else {
                let d: f64 = (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt();
                kept_max = kept_max.max(d);
            }
        }
    }
    let (mut join_step, mut other_step, mut join_slide, mut other_slide) = (0f64, 0f64, 0f64, 0f64);
    for f in 1..t {
        let step = horizontal(at(edited, f, 0), at(edited, f - 1, 0));
        let slide = FOOT_JOINTS
            .iter()
            .filter(|&&k| {
                at(edited, f, k)[1] < CONTACT_HEIGHT_M && at(edited, f - 1, k)[1] < CONTACT_HEIGHT_M
            })
            .map(|&k| horizontal(at(edited, f, k), at(edited, f - 1, k)))
            .fold(0f64, f64::max);
        if near(f) || near(f - 1) {
            join_step = join_step.max(step);
            join_slide = join_slide.max(slide);
        } else {
            other_step = other_step.max(step);
            other_slide = other_slide.max(slide);
        }
    }
    Ok(EditQuality {
        kept_max_m: kept_max,
        join_jerk_ratio: crate::longform::boundary_jerk_ratio(edited, fps, &joins)?,
        join_root_step_m: join_step,
        other_root_step_m: other_step,
        join_foot_slide_m: join_slide,
        other_foot_slide_m: other_slide,
        new_difference_m: if diff.1 == 0 {
            0.0
        } else {
            diff.0 / diff.1 as f64
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dancer walking along x at 1 cm a frame, arms swinging with `phase`.
    fn walk(t: usize, phase: f64) -> Vec<f64> {
        let mut j = Vec::with_capacity(t * FRAME_LEN);
        for f in 0..t {
            let x = 0.01 * f as f64;
            for k in 0..24 {
                let s = (f as f64 * 0.2 + phase + k as f64).sin() * 0.1;
                j.extend([x + s, 0.1 + 0.05 * k as f64, s]);
            }
        }
        j
    }

    #[test]
    fn an_untouched_dance_keeps_everything_and_a_jump_shows_at_its_join() {
        let a = walk(120, 0.0);
        let made = vec![Range { start: 40, end: 80 }];
        let q = edit_quality(&a, &a, &made, 30.0).unwrap();
        assert_eq!(q.kept_max_m, 0.0);
        assert_eq!(q.new_difference_m, 0.0);
        assert!(q.join_root_step_m < 0.05 && q.other_root_step_m < 0.05);

        // The new part from another phase and 0.5 m to the side: new, and a jump at its joins.
        let b = walk(120, 2.0);
        let mut e = a.clone();
        for f in 40..80 {
            for k in 0..24 {
                let i = f * FRAME_LEN + 3 * k;
                e[i] = b[i] + 0.5;
                e[i + 1] = b[i + 1];
                e[i + 2] = b[i + 2];
            }
        }
        let q = edit_quality(&a, &e, &made, 30.0).unwrap();
        assert_eq!(q.kept_max_m, 0.0);
        assert!(q.new_difference_m > 0.05, "{q:?}");
        assert!(
            q.join_root_step_m > 0.4 && q.other_root_step_m < 0.05,
            "{q:?}"
        );
        assert!(q.join_jerk_ratio.unwrap() > 10.0, "{q:?}");
        // A kept frame changed is seen.
        e[10 * FRAME_LEN + 1] += 0.01;
        let q = edit_quality(&a, &e, &made, 30.0).unwrap();
        assert!((q.kept_max_m - 0.01).abs() < 1e-12);
        assert!(edit_quality(&a, &e[..FRAME_LEN * 100], &made, 30.0).is_err());
    }
}
