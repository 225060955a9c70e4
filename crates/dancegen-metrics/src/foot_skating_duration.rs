//! Foot-skating duration (Duolando): the share of frames in which the pelvis travels while both
//! feet stay still relative to it — the body glides instead of stepping.
//!
//! Reference: `lisiyao21/Duolando:utils/metric_footskating_dur.py::detect_footskating_dur` and its
//! `__main__` (read at commit `059f3b9`; no golden fixture exists, so the tests pin the formula on
//! constructed motions). Per clip, with `P` pelvis (0), `L`/`R` ankles (7, 8):
//! 1. pelvis speed `‖Δ(P with its z component set to 0)‖` per frame step — the reference zeroes
//!    **z**, which on its Y-up data is a horizontal axis, so the "horizontal" speed is really the
//!    speed in the x–y (sideways–vertical) plane (quirk, reproduced);
//! 2. leg speeds `‖Δ(L − P)‖`, `‖Δ(R − P)‖` (z kept);
//! 3. over steps `i = 1 … T − 2` (the reference's loop starts at 1, so step 0 never counts, but
//!    the denominator is all `T − 1` steps): count steps with pelvis speed `> 0.03` and both leg
//!    speeds `< 0.01`. Thresholds are per frame step although the reference comments say m/s.
//!
//! The set value is **pooled** as the reference prints it: `100 · Σ count / Σ (T − 1)` over the
//! clips (a percentage), not a mean of per-clip ratios.

use crate::{FRAME_LEN, FeatureError, frame_count};

/// Pelvis joint.
pub const PELVIS: usize = 0;
/// Duolando `pelvis_threshold` (metres per frame step).
pub const PELVIS_THRESHOLD: f64 = 0.03;
/// Duolando `leg_velocity_threshold` (metres per frame step).
pub const LEG_THRESHOLD: f64 = 0.01;

/// Skating steps and steps of one clip.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SkatingDuration {
    /// Steps counted as skating.
    pub skating: usize,
    /// All frame steps (`T − 1`).
    pub steps: usize,
}

impl SkatingDuration {
    /// Percentage of skating steps; `None` without steps.
    pub fn percent(&self) -> Option<f64> {
        (self.steps > 0).then(|| 100.0 * self.skating as f64 / self.steps as f64)
    }
}

fn norm_of_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Foot-skating duration of a flat `(T, 24, 3)` Y-up clip in metres (see the module docs).
pub fn foot_skating_duration(joints: &[f64]) -> Result<SkatingDuration, FeatureError> {
    let frames = frame_count(joints)?;
    let pos = |t: usize, j: usize| {
        let o = t * FRAME_LEN + j * 3;
        [joints[o], joints[o + 1], joints[o + 2]]
    };
    let rel = |t: usize, j: usize| {
        let (a, p) = (pos(t, j), pos(t, PELVIS));
        [a[0] - p[0], a[1] - p[1], a[2] - p[2]]
    };
    let flat = |t: usize| {
        let p = pos(t, PELVIS);
        [p[0], p[1], 0.0]
    };
    let steps = frames.saturating_sub(1);
    let skating = (1..steps)
        .filter(|&i| {
            norm_of_diff(flat(i), flat(i + 1)) > PELVIS_THRESHOLD
                && norm_of_diff(
                    rel(i, crate::foot_skating::L_ANKLE),
                    rel(i + 1, crate::foot_skating::L_ANKLE),
                ) < LEG_THRESHOLD
                && norm_of_diff(
                    rel(i, crate::foot_skating::R_ANKLE),
                    rel(i + 1, crate::foot_skating::R_ANKLE),
                ) < LEG_THRESHOLD
        })
        .count();
    Ok(SkatingDuration { skating, steps })
}

/// The reference's set value: `100 · Σ skating / Σ steps`; `None` without steps.
pub fn pooled_percent(clips: &[SkatingDuration]) -> Option<f64> {
    let total = SkatingDuration {
        skating: clips.iter().map(|c| c.skating).sum(),
        steps: clips.iter().map(|c| c.steps).sum(),
    };
    total.percent()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `frames` frames of a rigid body whose 24 joints sit at fixed offsets from a root that
    /// moves by `step` per frame.
    fn gliding(frames: usize, step: [f64; 3]) -> Vec<f64> {
        let mut out = Vec::with_capacity(frames * FRAME_LEN);
        for t in 0..frames {
            for j in 0..24 {
                let off = [0.01 * j as f64, 0.05 * j as f64, -0.02 * j as f64];
                for c in 0..3 {
                    out.push(off[c] + step[c] * t as f64);
                }
            }
        }
        out
    }

    #[test]
    fn rigid_glide_along_x_skates_on_every_step_but_the_first() {
        let d = foot_skating_duration(&gliding(11, [0.05, 0.0, 0.0])).unwrap();
        assert_eq!(
            d,
            SkatingDuration {
                skating: 9,
                steps: 10
            }
        );
        assert_eq!(d.percent(), Some(90.0));
    }

    #[test]
    fn glide_along_z_is_invisible_as_in_the_reference() {
        // The reference zeroes the pelvis z before its speed: a pure z glide never counts.
        let d = foot_skating_duration(&gliding(11, [0.0, 0.0, 0.05])).unwrap();
        assert_eq!(d.skating, 0);
    }

    #[test]
    fn slow_glide_and_moving_feet_do_not_count() {
        assert_eq!(
            foot_skating_duration(&gliding(11, [0.02, 0.0, 0.0]))
                .unwrap()
                .skating,
            0
        );
        let mut j = gliding(11, [0.05, 0.0, 0.0]);
        // The left ankle swings relative to the pelvis on odd frames.
        for t in (1..11).step_by(2) {
            j[t * FRAME_LEN + crate::foot_skating::L_ANKLE * 3 + 1] += 0.05;
        }
        assert_eq!(foot_skating_duration(&j).unwrap().skating, 0);
    }

    #[test]
    fn pooled_over_clips_and_degenerate_inputs() {
        let a = SkatingDuration {
            skating: 9,
            steps: 10,
        };
        let b = SkatingDuration {
            skating: 0,
            steps: 30,
        };
        assert_eq!(pooled_percent(&[a, b]), Some(100.0 * 9.0 / 40.0));
        assert_eq!(pooled_percent(&[]), None);
        let one = foot_skating_duration(&gliding(1, [0.1, 0.0, 0.0])).unwrap();
        assert_eq!(
            one,
            SkatingDuration {
                skating: 0,
                steps: 0
            }
        );
        assert_eq!(one.percent(), None);
        assert!(foot_skating_duration(&[0.0; 5]).is_err());
    }
}
