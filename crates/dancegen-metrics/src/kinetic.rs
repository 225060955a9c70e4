//! Kinetic features (→ FID_k, Div_k): 3 numbers per joint, 72 for the 24 SMPL joints.
//!
//! Reference: `google/aistplusplus_api:aist_plusplus/features/kinetic.py::extract_kinetic_features`
//! and `.../features/utils.py` (identical copies in `lisiyao21/Bailando:utils/features/`,
//! `li-ronghui/LODGE:metric/features/`; origin
//! `facebookresearch/fairmotion:fairmotion/tasks/clustering/features/kinetic.py`), with its
//! defaults `up_vec = "y"`, `sliding_window = 2`, `frame_time = 1/60`.
//!
//! Per joint `j`, in this order:
//! 1. horizontal average kinetic energy `Σ_{i=1}^{T-1} ‖(v_x, v_z)_i‖² / (T−1)`,
//! 2. vertical average kinetic energy `Σ_{i=1}^{T-1} v_{y,i}² / (T−1)`,
//! 3. "energy expenditure" `Σ_{i=1}^{T-1} a_i / (T−1)`,
//!
//! where `v_i` sums the one-step displacements `P[i+k] − P[i+k−1]` over `k ∈ [−2, 2]` with
//! valid indices and divides by `(count · frame_time)`, and `a_i` is the norm of the mean of the
//! windowed accelerations.
//!
//! Known bugs / pitfalls of the reference (reproduced by [`KineticVariant::Reference`]):
//! - **Acceleration precedence bug**: `v1 = P[i+k] − P[i+k−1] / frame_time` (only the second
//!   position is divided), so the energy expenditure is dominated by the absolute position
//!   (≈ −59·P at 1/60 s) and the kinetic vector depends on the global translation. Present in
//!   fairmotion, AIST++ API, Bailando, LODGE, Duolando; fixed only in
//!   `aioz-ai/GCD:eval/features/utils.py` ([`KineticVariant::AccelFixed`], not a reference for
//!   any published number). The two kinetic-energy terms are unaffected.
//! - `frame_time = 1/60` is hard-coded even for 30-fps data (LODGE/EDGE); reproduce, don't fix.
//! - fairmotion's original used root-relative positions; AIST++/Bailando use global positions;
//!   Bailando's `metrics_new.calc_and_save_feats` first subtracts the frame-0 root ([`zero_start`]).
//! - The reference returns float32 (`np.array(..., dtype=np.float32)`); this port returns the
//!   float64 values before that cast.

use crate::{FRAME_LEN, FeatureError, NUM_JOINTS, frame_count};

/// Default frame time of the reference (`1/60`, also used for 30-fps data by LODGE/EDGE).
pub const REFERENCE_FRAME_TIME: f64 = 1.0 / 60.0;

/// Sliding half-window of the reference (`sliding_window = 2`).
const SLIDING_WINDOW: isize = 2;

/// Which acceleration formula to use for the energy-expenditure term.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum KineticVariant {
    /// As the reference computes it: `v1 = P[t] − P[t−1] / dt` (precedence bug). Use this to
    /// match any published FID_k / Div_k.
    #[default]
    Reference,
    /// Corrected `v1 = (P[t] − P[t−1]) / dt` as in `aioz-ai/GCD`. Not a reference value.
    AccelFixed,
}

/// Subtracts frame 0's root (joint 0) position from every joint of every frame, as Bailando's
/// `utils/metrics_new.py::calc_and_save_feats` does (`joint3d - np.tile(joint3d[:1, :3], (1, 24))`)
/// before its kinetic/manual features ("zerostart" in the fixtures). Empty input is returned as is.
pub fn zero_start(joints: &[f64]) -> Vec<f64> {
    let mut out = joints.to_vec();
    if joints.len() < 3 {
        return out;
    }
    let root = [joints[0], joints[1], joints[2]];
    for (i, v) in out.iter_mut().enumerate() {
        *v -= root[i % 3];
    }
    out
}

/// Position of joint `j` at frame `t`.
#[inline]
fn p(joints: &[f64], t: usize, j: usize) -> [f64; 3] {
    let o = t * FRAME_LEN + j * 3;
    [joints[o], joints[o + 1], joints[o + 2]]
}

/// The 72 kinetic features of a `(T, 24, 3)` Y-up joint array (see the module docs).
///
/// # Panics
/// If the slice is not whole `(24, 3)` frames or holds fewer than 3 frames; see
/// [`try_kinetic_features`].
pub fn kinetic_features(joints: &[f64], frame_time: f64, variant: KineticVariant) -> [f64; 72] {
    match try_kinetic_features(joints, frame_time, variant) {
        Ok(f) => f,
        Err(e) => panic!("kinetic_features: {e}"),
    }
}

/// [`kinetic_features`] returning an error instead of panicking. Needs `T ≥ 3` (with fewer
/// frames the reference's acceleration window is empty and it returns NaN).
pub fn try_kinetic_features(
    joints: &[f64],
    frame_time: f64,
    variant: KineticVariant,
) -> Result<[f64; 72], FeatureError> {
    let frames = frame_count(joints)?;
    if frames < 3 {
        return Err(FeatureError::TooShort {
            what: "kinetic features",
            min: 3,
            frames,
        });
    }
    let mut out = [0.0; 3 * NUM_JOINTS];
    let denom = frames as f64 - 1.0;
    for j in 0..NUM_JOINTS {
        let (mut eh, mut ev, mut ee) = (0.0, 0.0, 0.0);
        for i in 1..frames {
            let (vh, vv) = average_velocity_hv(joints, frames, i, j, frame_time);
            eh += vh * vh;
            ev += vv * vv;
        }
        for i in 1..frames {
            ee += average_acceleration(joints, frames, i, j, frame_time, variant);
        }
        out[3 * j] = eh / denom;
        out[3 * j + 1] = ev / denom;
        out[3 * j + 2] = ee / denom;
    }
    Ok(out)
}

/// `calc_average_velocity_horizontal` / `_vertical` (up = y): norms of `(v_x, v_z)` and `v_y`.
fn average_velocity_hv(
    joints: &[f64],
    frames: usize,
    i: usize,
    j: usize,
    frame_time: f64,
) -> (f64, f64) {
    let mut sum = [0.0; 3];
    let mut count = 0usize;
    for k in -SLIDING_WINDOW..=SLIDING_WINDOW {
        let t = i as isize + k;
        if t - 1 < 0 || t >= frames as isize {
            continue;
        }
        let (a, b) = (p(joints, t as usize, j), p(joints, t as usize - 1, j));
        for c in 0..3 {
            sum[c] += a[c] - b[c];
        }
        count += 1;
    }
    let d = count as f64 * frame_time;
    let (hx, hz, vy) = (sum[0] / d, sum[2] / d, sum[1] / d);
    ((hx * hx + hz * hz).sqrt(), vy.abs())
}

/// `calc_average_acceleration`, with or without the precedence bug.
fn average_acceleration(
    joints: &[f64],
    frames: usize,
    i: usize,
    j: usize,
    dt: f64,
    variant: KineticVariant,
) -> f64 {
    let mut acc = [0.0; 3];
    let mut count = 0usize;
    for k in -SLIDING_WINDOW..=SLIDING_WINDOW {
        let t = i as isize + k;
        if t - 1 < 0 || t + 1 >= frames as isize {
            continue;
        }
        let t = t as usize;
        let (next, cur, prev) = (p(joints, t + 1, j), p(joints, t, j), p(joints, t - 1, j));
        for c in 0..3 {
            let v2 = (next[c] - cur[c]) / dt;
            let v1 = match variant {
                // The reference's `positions[i+j] - positions[i+j-1] / frame_time`.
                KineticVariant::Reference => cur[c] - prev[c] / dt,
                KineticVariant::AccelFixed => (cur[c] - prev[c]) / dt,
            };
            acc[c] += (v2 - v1) / dt;
        }
        count += 1;
    }
    let n = count as f64;
    let m = [acc[0] / n, acc[1] / n, acc[2] / n];
    (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still(frames: usize, offset: f64) -> Vec<f64> {
        (0..frames * FRAME_LEN)
            .map(|i| offset + (i % FRAME_LEN) as f64 * 0.01)
            .collect()
    }

    #[test]
    fn frozen_clip_has_zero_energy_and_bug_only_in_expenditure() {
        let j = still(10, 0.5);
        let r = kinetic_features(&j, REFERENCE_FRAME_TIME, KineticVariant::Reference);
        let f = kinetic_features(&j, REFERENCE_FRAME_TIME, KineticVariant::AccelFixed);
        for jt in 0..NUM_JOINTS {
            assert_eq!(r[3 * jt], 0.0);
            assert_eq!(r[3 * jt + 1], 0.0);
            assert_eq!(f[3 * jt + 2], 0.0);
            assert!(r[3 * jt + 2] > 0.0);
        }
    }

    #[test]
    fn zero_start_removes_frame0_root() {
        let j = still(4, 0.5);
        let z = zero_start(&j);
        assert_eq!(&z[0..3], &[0.0, 0.0, 0.0]);
        assert!((z[3] - (j[3] - j[0])).abs() < 1e-15);
        assert!((z[FRAME_LEN + 4] - (j[FRAME_LEN + 4] - j[1])).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_input() {
        assert!(try_kinetic_features(&[0.0; 5], 0.1, KineticVariant::Reference).is_err());
        assert!(
            try_kinetic_features(&[0.0; 2 * FRAME_LEN], 0.1, KineticVariant::Reference).is_err()
        );
    }
}
