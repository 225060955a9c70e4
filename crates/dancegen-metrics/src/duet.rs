//! Duet metrics of Duolando (anchors A.10; the reference ReactDance follows):
//! FID_cd, Div_cd (cross-distance feature) and BED (Beat Echo Degree).
//!
//! Reference: `lisiyao21/Duolando:utils/metrics_duet.py` (`duet_feature`,
//! `calc_and_save_feats_duet`, `quantized_metrics`, `calc_db`, `BA`, `calc_duet_be_score`).
//!
//! - **Cross-distance feature** ([`cross_distance_feature`]): both dancers are cut to the shorter
//!   length `T`; for each frame the 10 × 10 Euclidean distances between the key joints
//!   [`DUET_KEY_JOINTS`] of the **follower** (row `i`) and the **leader** (column `j`), flattened
//!   row-major (`feature[i * 10 + j] = ‖F[t, k_i] − L[t, k_j]‖`), then averaged over time → 100-d.
//!   Absolute (global) positions are used; no root handling.
//! - **FID_cd / Div_cd** ([`duet_fid_div`]): the features are z-scored with the GT set's mean and
//!   population std ([`crate::fid::normalize_by_gt`]), then Fréchet distance
//!   ([`crate::fid::frechet_distance`], ε = 1e−5 fallback) and all-pairs diversity
//!   ([`crate::diversity()`]) exactly as Bailando (anchors A.3). The reference's FID is complex
//!   with a tiny imaginary part; we return the real part.
//! - **BED** ([`beat_echo_degree`]): Bailando's beat-align formula with the **leader's** motion
//!   beats in place of music beats and the follower's motion beats as motion beats:
//!   `mean_{b ∈ leader beats} exp(−min_{m ∈ follower beats} (m − b)² / 18)`. Motion beats are
//!   Bailando's `calc_db` on the dancer's own full length: mean joint speed, `gaussian_filter(σ = 5)`,
//!   `argrelextrema(less)` (order 1). The set score is the mean over pairs.
//!
//! Two more duet measures, **our definitions** for ReactDance's evaluation (its code is
//! unreleased): [`interpenetration_rate`] (IPR: share of frames in which the partners' capsule
//! bodies intersect, TIF's geometry on a couple) and [`contact_range_share`] (share of frames in
//! which they are within [`CONTACT_RANGE_M`] of touching).
//!
//! Joint layout: the reference works on SMPL-X 55-joint arrays. Our inputs are SMPL 24-joint
//! (`(T, 24, 3)`, flat C order); they are expanded to 55 joints with [`SMPLX55_FROM_SMPL24`]
//! (the fixtures' `manifest.json: smplx55_from_smpl24_index`: body joints 0–21 as is, jaw and
//! eyes = head 15, the 15 joints of each hand = SMPL hand 22 / 23). The key joints are all body
//! joints (identical in both layouts), but the BED speed is the mean over the **55** expanded
//! joints, so the head and hands weigh 3 × and 15 × — as the reference on such data.

use crate::bas::{Variant, argrelmin, beat_align_score, gaussian_filter1d, joint_step_speeds};
use crate::fid::{EPS_BAILANDO, frechet_distance, normalize_by_gt};
use crate::{FRAME_LEN, FeatureError, diversity, frame_count};

/// Duolando `SMPLX_FEAT_POINT`: pelvis, ankles, feet, head, shoulders, wrists.
pub const DUET_KEY_JOINTS: [usize; 10] = [0, 7, 8, 10, 11, 15, 16, 17, 20, 21];

/// Dimension of the cross-distance feature (`10 × 10`).
pub const CROSS_DISTANCE_DIM: usize = DUET_KEY_JOINTS.len() * DUET_KEY_JOINTS.len();

/// SMPL-24 joint index for each of the 55 SMPL-X joints (fixture mapping; see module docs).
pub const SMPLX55_FROM_SMPL24: [usize; 55] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, // body
    15, 15, 15, // jaw, eyes
    22, 22, 22, 22, 22, 22, 22, 22, 22, 22, 22, 22, 22, 22, 22, // left hand
    23, 23, 23, 23, 23, 23, 23, 23, 23, 23, 23, 23, 23, 23, 23, // right hand
];

/// Duolando `duet_feature(follower, leader)`: the 100-d time-mean cross-distance feature (see the
/// module docs). Both inputs are flat `(T, 24, 3)`; the longer one is cut to the shorter length.
pub fn cross_distance_feature(follower: &[f64], leader: &[f64]) -> Result<Vec<f64>, FeatureError> {
    let frames = frame_count(follower)?.min(frame_count(leader)?);
    if frames == 0 {
        return Err(FeatureError::TooShort {
            what: "cross-distance feature",
            min: 1,
            frames,
        });
    }
    // numpy's axis-0 mean of a (T, 100) array: rows added in order, then divided by T.
    let mut feat = vec![0.0f64; CROSS_DISTANCE_DIM];
    for t in 0..frames {
        let base = t * FRAME_LEN;
        for (i, &ki) in DUET_KEY_JOINTS.iter().enumerate() {
            for (j, &kj) in DUET_KEY_JOINTS.iter().enumerate() {
                let mut s = 0.0;
                for c in 0..3 {
                    let d = follower[base + ki * 3 + c] - leader[base + kj * 3 + c];
                    s += d * d;
                }
                feat[i * DUET_KEY_JOINTS.len() + j] += s.sqrt();
            }
        }
    }
    for v in &mut feat {
        *v /= frames as f64;
    }
    Ok(feat)
}

/// FID_cd and Div_cd of a generated set against a GT set, plus the GT diversity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DuetScores {
    /// Fréchet distance between the normalised generated and GT features (real part).
    pub fid_cd: f64,
    /// All-pairs diversity of the normalised generated features.
    pub div_cd: f64,
    /// All-pairs diversity of the normalised GT features.
    pub div_cd_gt: f64,
}

/// Duolando `quantized_metrics` on cross-distance features ([`cross_distance_feature`]).
///
/// # Panics
/// If a set is empty or the feature dimensions differ.
pub fn duet_fid_div(gt: &[Vec<f64>], pred: &[Vec<f64>]) -> DuetScores {
    let (gt_n, pred_n) = normalize_by_gt(gt, pred);
    DuetScores {
        fid_cd: frechet_distance(&pred_n, &gt_n, EPS_BAILANDO),
        div_cd: diversity(&pred_n),
        div_cd_gt: diversity(&gt_n),
    }
}

/// Duolando `calc_db` on the 55-joint expansion of a flat `(T, 24, 3)` array: per step the mean
/// over the 55 joints of `‖P[t+1] − P[t]‖` (numpy's pairwise order), smoothed with
/// `gaussian_filter(σ = 5)`, strict local minima (order 1).
pub fn duet_motion_beats(joints: &[f64]) -> Result<Vec<usize>, FeatureError> {
    let frames = frame_count(joints)?;
    let speed: Vec<f64> = (0..frames.saturating_sub(1))
        .map(|t| {
            let per_joint = joint_step_speeds(joints, t);
            let expanded = SMPLX55_FROM_SMPL24.map(|j| per_joint[j]);
            numpy_sum(&expanded) / expanded.len() as f64
        })
        .collect();
    Ok(argrelmin(&gaussian_filter1d(&speed, 5.0), 1))
}

/// BED of one pair: Bailando `BA(leader beats, follower beats)` (see the module docs). `None`
/// where the reference raises or returns NaN: no follower beats (`np.min` of an empty array) or
/// no leader beats (division by zero).
pub fn beat_echo_degree(follower: &[f64], leader: &[f64]) -> Result<Option<f64>, FeatureError> {
    let fb = duet_motion_beats(follower)?;
    let lb = duet_motion_beats(leader)?;
    Ok(beat_align_score(&lb, &fb, Variant::Bailando))
}

/// numpy `add.reduce` over a contiguous axis of 55 values: 8 accumulators, then the remainder.
fn numpy_sum(a: &[f64; 55]) -> f64 {
    let mut r = [0.0f64; 8];
    r.copy_from_slice(&a[..8]);
    let whole = a.len() - a.len() % 8;
    for chunk in a[8..whole].chunks_exact(8) {
        for (acc, &x) in r.iter_mut().zip(chunk) {
            *acc += x;
        }
    }
    let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for &x in &a[whole..] {
        res += x;
    }
    res
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still(frames: usize, offset: [f64; 3]) -> Vec<f64> {
        let mut v = vec![0.0; frames * FRAME_LEN];
        for t in 0..frames {
            for j in 0..24 {
                for c in 0..3 {
                    v[t * FRAME_LEN + j * 3 + c] = offset[c] + j as f64 * 0.01 * (c + 1) as f64;
                }
            }
        }
        v
    }

    #[test]
    fn cross_distance_is_follower_rows_leader_columns() {
        let f = still(3, [0.0; 3]);
        let l = still(5, [1.0, 0.0, 0.0]);
        let feat = cross_distance_feature(&f, &l).unwrap();
        assert_eq!(feat.len(), 100);
        // i = pelvis of the follower, j = left ankle (7) of the leader.
        let d = |a: usize, b: usize| -> f64 {
            (0..3)
                .map(|c| {
                    let x = f[a * 3 + c] - l[b * 3 + c];
                    x * x
                })
                .sum::<f64>()
                .sqrt()
        };
        assert!((feat[1] - d(0, 7)).abs() < 1e-12);
        assert!((feat[10] - d(7, 0)).abs() < 1e-12);
        assert!((feat[1] - feat[10]).abs() > 1e-6);
    }

    #[test]
    fn empty_input_is_too_short() {
        assert!(cross_distance_feature(&[], &still(2, [0.0; 3])).is_err());
    }

    #[test]
    fn numpy_sum_matches_plain_sum_on_integers() {
        let a: [f64; 55] = std::array::from_fn(|i| i as f64);
        assert_eq!(numpy_sum(&a), (0..55).sum::<usize>() as f64);
    }
}

/// How close (metres, capsule surface to capsule surface) the partners must be to count as "in
/// contact range": a forearm's length, close enough to take a hand. Our choice.
pub const CONTACT_RANGE_M: f64 = 0.3;

/// Share of frames (in `[0, 1]`) in which the couple's capsule bodies intersect; `None` for an
/// empty clip.
pub fn interpenetration_rate(
    follower: &[f64],
    leader: &[f64],
) -> Result<Option<f64>, FeatureError> {
    crate::group::tif(&[follower, leader], &crate::group::CapsuleRadii::default())
}

/// Share of frames (in `[0, 1]`) in which the couple's smallest capsule gap is at most
/// [`CONTACT_RANGE_M`] (intersecting frames count as in range); `None` for an empty clip.
pub fn contact_range_share(follower: &[f64], leader: &[f64]) -> Result<Option<f64>, FeatureError> {
    let t = frame_count(follower)?.min(frame_count(leader)?);
    if t == 0 {
        return Ok(None);
    }
    let radii = crate::group::CapsuleRadii::default();
    let near = (0..t)
        .filter(|&f| crate::group::body_gap(follower, leader, f, &radii) <= CONTACT_RANGE_M)
        .count();
    Ok(Some(near as f64 / t as f64))
}

#[cfg(test)]
mod couple_tests {
    use super::*;

    /// A straight vertical stick figure at horizontal `x` (every joint on the line).
    fn stick(x: f64, frames: usize) -> Vec<f64> {
        let mut v = Vec::new();
        for _ in 0..frames {
            for j in 0..24 {
                v.extend([x, 0.05 * j as f64, 0.0]);
            }
        }
        v
    }

    #[test]
    fn far_partners_neither_touch_nor_intersect() {
        let (a, b) = (stick(0.0, 3), stick(3.0, 3));
        assert_eq!(interpenetration_rate(&a, &b).unwrap(), Some(0.0));
        assert_eq!(contact_range_share(&a, &b).unwrap(), Some(0.0));
    }

    #[test]
    fn overlapping_partners_intersect_and_are_in_range() {
        let (a, b) = (stick(0.0, 2), stick(0.05, 2));
        assert_eq!(interpenetration_rate(&a, &b).unwrap(), Some(1.0));
        assert_eq!(contact_range_share(&a, &b).unwrap(), Some(1.0));
        // 0.1 m torso radii on both: a 0.4 m axis distance leaves a 0.2 m gap, within range.
        let c = stick(0.4, 2);
        assert_eq!(interpenetration_rate(&a, &c).unwrap(), Some(0.0));
        assert_eq!(contact_range_share(&a, &c).unwrap(), Some(1.0));
    }
}
