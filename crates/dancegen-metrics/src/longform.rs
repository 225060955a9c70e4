//! Long-form quality metrics of our own (no published reference; definitions are ours).
//!
//! Inputs are flat `(T, 24, 3)` joint positions (any consistent unit) at `fps` frames per second.
//!
//! - [`motion_freezing`]: share of 1-second windows in which the dancer is (nearly) still.
//! - [`boundary_jerk_ratio`]: how much jerkier the motion is around given window boundaries
//!   (e.g. where a long-form generator stitches windows) than elsewhere.

use crate::{FRAME_LEN, FeatureError, NUM_JOINTS, frame_count};

/// Threshold of [`motion_freezing`], as a share of the sequence's median speed.
pub const FREEZE_SPEED_FRACTION: f64 = 0.05;

/// Half-width (frames) of the band around a boundary in [`boundary_jerk_ratio`].
pub const BOUNDARY_BAND: usize = 2;

/// Per-step mean joint speed: `s_t = fps · mean_j ‖P[t+1, j] − P[t, j]‖`, `t ∈ [0, T−1)`.
pub fn mean_joint_speeds(joints: &[f64], fps: f64) -> Result<Vec<f64>, FeatureError> {
    let frames = frame_count(joints)?;
    Ok((0..frames.saturating_sub(1))
        .map(|t| {
            let a = &joints[t * FRAME_LEN..(t + 1) * FRAME_LEN];
            let b = &joints[(t + 1) * FRAME_LEN..(t + 2) * FRAME_LEN];
            let sum: f64 = a
                .chunks_exact(3)
                .zip(b.chunks_exact(3))
                .map(|(p, q)| norm3(q[0] - p[0], q[1] - p[1], q[2] - p[2]))
                .sum();
            fps * sum / NUM_JOINTS as f64
        })
        .collect())
}

/// Motion freezing: the share of non-overlapping 1-second windows whose mean joint speed is
/// under [`FREEZE_SPEED_FRACTION`] (5 %) of the sequence's median per-frame mean joint speed.
///
/// Definition:
/// - speeds `s_t` as in [`mean_joint_speeds`] (`T − 1` values, one per frame step);
/// - `median` = median of all `s_t` (mean of the two middle values for an even count);
/// - the speed series is cut into consecutive windows of `w = max(1, round(fps))` steps starting
///   at step 0; an incomplete trailing window is dropped;
/// - a window is frozen if its mean speed is `< 0.05 · median`, or exactly 0 (so that a sequence
///   that is still more than half of the time, whose median is 0, still counts its still windows);
/// - result = frozen windows / complete windows.
///
/// `Ok(None)` when there is no complete window (fewer than `w + 1` frames).
///
/// # Panics
/// If `fps` is not finite and positive.
pub fn motion_freezing(joints: &[f64], fps: f64) -> Result<Option<f64>, FeatureError> {
    assert!(fps.is_finite() && fps > 0.0, "fps must be positive");
    let speeds = mean_joint_speeds(joints, fps)?;
    let w = (fps.round() as usize).max(1);
    let windows = speeds.len() / w;
    if windows == 0 {
        return Ok(None);
    }
    let threshold = FREEZE_SPEED_FRACTION * median(&speeds);
    let frozen = speeds
        .chunks_exact(w)
        .filter(|win| {
            let mean = win.iter().sum::<f64>() / w as f64;
            mean < threshold || mean == 0.0
        })
        .count();
    Ok(Some(frozen as f64 / windows as f64))
}

/// Per-sample jerk magnitude: `j_t = fps³ · mean_j ‖P[t+3] − 3P[t+2] + 3P[t+1] − P[t]‖`,
/// `t ∈ [0, T−3)` (third finite difference, averaged over joints).
pub fn mean_joint_jerk(joints: &[f64], fps: f64) -> Result<Vec<f64>, FeatureError> {
    let frames = frame_count(joints)?;
    let scale = fps * fps * fps;
    Ok((0..frames.saturating_sub(3))
        .map(|t| {
            let p = |k: usize, i: usize| joints[(t + k) * FRAME_LEN + i];
            let sum: f64 = (0..NUM_JOINTS)
                .map(|j| {
                    let d = |c: usize| {
                        let i = j * 3 + c;
                        p(3, i) - 3.0 * p(2, i) + 3.0 * p(1, i) - p(0, i)
                    };
                    norm3(d(0), d(1), d(2))
                })
                .sum();
            scale * sum / NUM_JOINTS as f64
        })
        .collect())
}

/// Boundary jerk ratio: mean jerk magnitude in a ±2-frame band around the given window
/// boundaries divided by the mean jerk magnitude elsewhere.
///
/// Definition:
/// - jerk samples `j_t` as in [`mean_joint_jerk`]; sample `t` uses frames `t..=t+3` (centre
///   `t + 1.5`);
/// - a boundary `b` is the first frame of a new window, i.e. it sits between frames `b − 1` and
///   `b` (position `b − 0.5`); sample `t` is in its band when
///   `|(t + 1.5) − (b − 0.5)| ≤` [`BOUNDARY_BAND`], i.e. `b − 4 ≤ t ≤ b`. This covers the three
///   samples whose stencil straddles the boundary plus one on each side;
/// - bands of all boundaries are united (a sample counts once); boundaries outside the
///   sequence only contribute the samples that exist;
/// - ratio = mean of in-band samples / mean of the other samples.
///
/// `Ok(None)` when undefined: fewer than 4 frames, no in-band or no out-of-band sample, or an
/// out-of-band mean of 0 (motion with zero jerk away from the boundaries).
///
/// A ratio ≈ 1 means the boundaries are as smooth as the rest; a discontinuity (pose jump)
/// at a boundary gives a ratio ≫ 1.
pub fn boundary_jerk_ratio(
    joints: &[f64],
    fps: f64,
    boundaries: &[usize],
) -> Result<Option<f64>, FeatureError> {
    let jerk = mean_joint_jerk(joints, fps)?;
    let n = jerk.len();
    let mut in_band = vec![false; n];
    for &b in boundaries {
        let lo = b.saturating_sub(2 * BOUNDARY_BAND);
        let hi = b.min(n.saturating_sub(1));
        if n == 0 || lo > hi {
            continue;
        }
        for flag in &mut in_band[lo..=hi] {
            *flag = true;
        }
    }
    let (mut band_sum, mut band_n, mut rest_sum, mut rest_n) = (0.0, 0usize, 0.0, 0usize);
    for (&j, &inside) in jerk.iter().zip(&in_band) {
        if inside {
            band_sum += j;
            band_n += 1;
        } else {
            rest_sum += j;
            rest_n += 1;
        }
    }
    if band_n == 0 || rest_n == 0 || rest_sum == 0.0 {
        return Ok(None);
    }
    Ok(Some(
        (band_sum / band_n as f64) / (rest_sum / rest_n as f64),
    ))
}

fn norm3(x: f64, y: f64, z: f64) -> f64 {
    (x * x + y * y + z * z).sqrt()
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
