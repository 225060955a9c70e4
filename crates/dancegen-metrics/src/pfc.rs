//! PFC — Physical Foot Contact score (EDGE).
//!
//! Reference: `Stanford-TML/EDGE:eval/eval_pfc.py::calc_physical_score` (constants `up_dir = 2`,
//! `DT = 1/30`, foot joints `[7, 10, 8, 11]`, final factor `10000`).
//!
//! Input: global joint positions `(T, J, 3)` (flat, C order), SMPL joint order, **Z-up**
//! (EDGE's frame — unlike the Y-up kinetic/manual features), 30 fps, metres; `J ≥ 12`.
//!
//! Per clip, with `p₀` the root (joint 0):
//! 1. root velocity `v_t = (p₀[t+1] − p₀[t]) / DT` (T−1 rows), acceleration
//!    `a_t = (v[t+1] − v[t]) / DT` (T−2 rows);
//! 2. the up (z) component of `a_t` is clamped to `≥ 0`, then `â_t = ‖a_t‖ / max_s ‖a_s‖`;
//! 3. horizontal (x, y) foot displacement per frame `d_{t,f} = ‖f[t+2] − f[t+1]‖_xy`
//!    (**not** divided by `DT`) for the left ankle (7), left toe (10), right ankle (8), right toe (11);
//! 4. clip score `mean_t( min(d_lankle, d_ltoe) · min(d_rankle, d_rtoe) · â_t )`
//!    ([`pfc_clip_score`]);
//! 5. PFC = mean of the clip scores × 10000 ([`pfc_from_clip_scores`]).
//!
//! Degenerate cases (reference behaviour → this port):
//! - a clip whose root never accelerates (e.g. a frozen clip): `max ‖a‖ = 0`, the reference
//!   divides 0/0 and its clip score and the set mean are `NaN` → [`pfc_clip_score`] returns
//!   `None` and [`pfc_from_clip_scores`] returns `NaN` if any clip is `None`;
//! - fewer than 3 frames: the reference raises (`max` of an empty array) → `None`;
//! - an empty set: `np.mean([])` is `NaN` → `NaN`.
//! - More than 1000 files: the reference samples 1000 at random (and crashes: `random` is not
//!   imported); this port takes whatever clip scores it is given.

/// Frame time of the reference (`DT = 1/30`).
pub const PFC_DT: f64 = 1.0 / 30.0;

/// Index of the up axis in the reference's Z-up frame (`up_dir = 2`).
pub const PFC_UP_DIR: usize = 2;

/// Factor applied to the mean clip score (`np.mean(scores) * 10000`).
pub const PFC_SCALE: f64 = 10000.0;

/// Foot joints in the reference order: left ankle, left toe, right ankle, right toe.
pub const PFC_FOOT_JOINTS: [usize; 4] = [7, 10, 8, 11];

/// Horizontal axes (all but [`PFC_UP_DIR`]).
const FLAT_DIRS: [usize; 2] = [0, 1];

/// Position of joint `j` at frame `t`.
#[inline]
fn p(joints: &[f64], num_joints: usize, t: usize, j: usize) -> [f64; 3] {
    let o = (t * num_joints + j) * 3;
    [joints[o], joints[o + 1], joints[o + 2]]
}

/// The unscaled per-clip PFC score of a Z-up `(T, J, 3)` joint array (see the module docs).
///
/// Returns `None` where the reference yields `NaN` or raises: fewer than 3 frames, or a root
/// acceleration that is zero (or non-finite) over the whole clip.
///
/// # Panics
/// If `num_joints < 12` or `joints.len()` is not a multiple of `num_joints * 3`.
pub fn pfc_clip_score(joints: &[f64], num_joints: usize) -> Option<f64> {
    assert!(
        num_joints >= 12,
        "PFC needs at least 12 joints, got {num_joints}"
    );
    assert!(
        joints.len().is_multiple_of(num_joints * 3),
        "joint array of {} values is not a whole number of {num_joints}x3 frames",
        joints.len()
    );
    let frames = joints.len() / (num_joints * 3);
    if frames < 3 {
        return None;
    }
    let n = frames - 2;

    // Root velocity (T−1) and acceleration (T−2), as the reference orders the operations.
    let vel: Vec<[f64; 3]> = (0..frames - 1)
        .map(|t| {
            let (a, b) = (p(joints, num_joints, t, 0), p(joints, num_joints, t + 1, 0));
            [
                (b[0] - a[0]) / PFC_DT,
                (b[1] - a[1]) / PFC_DT,
                (b[2] - a[2]) / PFC_DT,
            ]
        })
        .collect();
    let mut acc: Vec<f64> = (0..n)
        .map(|t| {
            let mut a = [0.0; 3];
            for c in 0..3 {
                a[c] = (vel[t + 1][c] - vel[t][c]) / PFC_DT;
            }
            a[PFC_UP_DIR] = a[PFC_UP_DIR].max(0.0);
            (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
        })
        .collect();
    let scaling = acc.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !(scaling.is_finite() && scaling > 0.0) {
        return None;
    }
    for a in &mut acc {
        *a /= scaling;
    }

    let foot_speed = |t: usize, j: usize| -> f64 {
        let (a, b) = (
            p(joints, num_joints, t + 1, j),
            p(joints, num_joints, t + 2, j),
        );
        let d0 = b[FLAT_DIRS[0]] - a[FLAT_DIRS[0]];
        let d1 = b[FLAT_DIRS[1]] - a[FLAT_DIRS[1]];
        (d0 * d0 + d1 * d1).sqrt()
    };
    let [la, lt, ra, rt] = PFC_FOOT_JOINTS;
    let sum: f64 = (0..n)
        .map(|t| {
            let left = foot_speed(t, la).min(foot_speed(t, lt));
            let right = foot_speed(t, ra).min(foot_speed(t, rt));
            left * right * acc[t]
        })
        .sum();
    Some(sum / n as f64)
}

/// PFC of a set of clips: mean of the clip scores × [`PFC_SCALE`], as the reference prints it.
///
/// `NaN` if any clip score is `None` (the reference's `NaN` propagates through `np.mean`) or the
/// set is empty.
pub fn pfc_from_clip_scores(scores: &[Option<f64>]) -> f64 {
    if scores.is_empty() {
        return f64::NAN;
    }
    let mut sum = 0.0;
    for s in scores {
        match s {
            Some(v) => sum += v,
            None => return f64::NAN,
        }
    }
    sum / scores.len() as f64 * PFC_SCALE
}
