//! Geometric ("manual_new") features (→ FID_g, Div_g): 32 boolean predicates per frame,
//! averaged over frames `1 … T−1`.
//!
//! Reference: `google/aistplusplus_api:aist_plusplus/features/manual.py::extract_manual_features`
//! and `.../features/utils.py` (== `lisiyao21/Bailando:utils/features/manual_new.py`,
//! `li-ronghui/LODGE:metric/features/manual_new.py`; origin `facebookresearch/fairmotion`).
//! Do **not** use Bailando/LODGE's older `manual.py` (wrong joint-name order, wrong constants);
//! FACT's published FID_g came from a bugged fairmotion extractor (fairmotion issue #50).
//!
//! Reference behaviour reproduced here, oddities included:
//! - Velocities are one-frame differences divided by `time_per_frame = 1/120` **hard-coded**,
//!   whatever the data rate (so at 60 fps they are twice, at 30 fps four times the true speed
//!   relative to real 120-fps motion; thresholds are effectively shifted). No frame-time input.
//! - Scale constants come from hard-coded SMPL-ish rest coordinates: humerus length `hl`
//!   ≈ 0.25684, shoulder width `sw` ≈ 0.39085, hip width `hw` ≈ 0.11925 m.
//! - `move(j1, j2, j3, j4)`: j4 is unused (velocity of j3 relative to j1 along `j2 − j1`), so
//!   features 5 and 6 (`move(belly, chest, chest, r/lwrist)`) both measure the chest and are
//!   always equal.
//! - `nplane(j1, j2, j3, j4)` is the signed distance of j4 from the plane through **j3** with
//!   normal `j2 − j1` (so j1 is only a direction tail).
//! - `y_min` is the lowest y over **all 24** joints of the current frame; only joints 0–21 are
//!   otherwise used.
//! - `angle` uses `arccos` without clamping: a cosine rounding above 1, or a zero-length
//!   vector, gives NaN and the predicate is false. Ranges are open intervals.
//! - Feature 29 compares the trunk direction `root − neck` with `+y` in (70°, 110°), i.e. it
//!   fires when the body is roughly horizontal.
//! - The mean is taken in float32 (`np.array(features, dtype=np.float32).mean(axis=0)`); the
//!   returned values are exactly those float32 values (`count / (T−1)` rounded to f32).
//! - Joint order is SMPL: root 0, lhip 1, rhip 2, belly 3, lknee 4, rknee 5, spine 6, lankle 7,
//!   rankle 8, chest 9, ltoes 10, rtoes 11, neck 12, linshoulder 13, rinshoulder 14, head 15,
//!   lshoulder 16, rshoulder 17, lelbow 18, relbow 19, lwrist 20, rwrist 21, lhand 22, rhand 23.

use crate::{FRAME_LEN, FeatureError, NUM_JOINTS, frame_count};

type V3 = [f64; 3];

/// Number of manual features.
pub const NUM_MANUAL: usize = 32;

/// The reference's `time_per_frame = 1 / 120` (velocities are divided by it).
const TIME_PER_FRAME: f64 = 1.0 / 120.0;

const ROOT: usize = 0;
const LHIP: usize = 1;
const RHIP: usize = 2;
const BELLY: usize = 3;
const LKNEE: usize = 4;
const RKNEE: usize = 5;
const LANKLE: usize = 7;
const RANKLE: usize = 8;
const CHEST: usize = 9;
const LTOES: usize = 10;
const RTOES: usize = 11;
const NECK: usize = 12;
const LSHOULDER: usize = 16;
const RSHOULDER: usize = 17;
const LELBOW: usize = 18;
const RELBOW: usize = 19;
const LWRIST: usize = 20;
const RWRIST: usize = 21;

const ZERO: V3 = [0.0, 0.0, 0.0];
const Y_UNIT: V3 = [0.0, 1.0, 0.0];
const MINUS_Y_UNIT: V3 = [0.0, -1.0, 0.0];

#[inline]
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// `np.cross(a, b)`.
#[inline]
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Humerus length `hl`: ‖lshoulder − lelbow‖ of the reference's hard-coded rest coordinates.
pub fn humerus_length() -> f64 {
    norm(sub(
        [1.99113488e-01, 2.36807942e-01, -1.80702247e-02],
        [4.54445392e-01, 2.21158922e-01, -4.10167128e-02],
    ))
}

/// Shoulder width `sw`: ‖lshoulder − rshoulder‖ of the hard-coded rest coordinates.
pub fn shoulder_width() -> f64 {
    norm(sub(
        [1.99113488e-01, 2.36807942e-01, -1.80702247e-02],
        [-1.91692337e-01, 2.36928746e-01, -1.23055102e-02],
    ))
}

/// Hip width `hw`: ‖lhip − rhip‖ of the hard-coded rest coordinates.
pub fn hip_width() -> f64 {
    norm(sub(
        [5.64076714e-02, -3.23069185e-01, 1.09197125e-02],
        [-6.24834076e-02, -3.31302464e-01, 1.50412619e-02],
    ))
}

/// One frame and its predecessor.
struct Frame<'a> {
    cur: &'a [f64],
    prev: &'a [f64],
}

impl Frame<'_> {
    fn at(&self, j: usize) -> V3 {
        [self.cur[3 * j], self.cur[3 * j + 1], self.cur[3 * j + 2]]
    }

    fn prev(&self, j: usize) -> V3 {
        [self.prev[3 * j], self.prev[3 * j + 1], self.prev[3 * j + 2]]
    }

    /// `y_min` pseudo-joint: `(0, min over all joints of y, 0)`.
    fn y_min(&self) -> V3 {
        let y = (0..NUM_JOINTS)
            .map(|j| self.cur[3 * j + 1])
            .fold(f64::INFINITY, f64::min);
        [0.0, y, 0.0]
    }

    /// `f_move(j1, j2, j3, _, θ)`: velocity of j3 relative to j1 along `j2 − j1` > θ.
    fn mv(&self, j1: usize, j2: usize, j3: usize, threshold: f64) -> bool {
        let velocity = sub(
            sub(self.at(j3), self.at(j1)),
            sub(self.prev(j3), self.prev(j1)),
        );
        let direction = sub(self.at(j2), self.at(j1));
        dot(velocity, direction) / norm(direction) / TIME_PER_FRAME > threshold
    }

    /// `f_nmove(j1, j2, j3, j4, θ)`: velocity of j4 relative to j1 along
    /// `(j3 − j1) × (j2 − j1)` > θ.
    fn nmove(&self, j1: usize, j2: usize, j3: usize, j4: usize, threshold: f64) -> bool {
        let velocity = sub(
            sub(self.at(j4), self.at(j1)),
            sub(self.prev(j4), self.prev(j1)),
        );
        let a1 = self.at(j1);
        let direction = cross(sub(self.at(j3), a1), sub(self.at(j2), a1));
        dot(velocity, direction) / norm(direction) / TIME_PER_FRAME > threshold
    }

    /// `f_plane(a, b, c, p, θ)`: signed distance of p from the plane through a, b, c with normal
    /// `(c − a) × (b − a)` > θ.
    fn plane(&self, a: V3, b: V3, c: V3, p: V3, threshold: f64) -> bool {
        let n = cross(sub(c, a), sub(b, a));
        dot(n, sub(p, a)) / norm(n) > threshold
    }

    /// `f_nplane(n1, n2, a, p, θ)`: signed distance of p from the plane through a with normal
    /// `n2 − n1` > θ.
    fn nplane(&self, n1: V3, n2: V3, a: V3, p: V3, threshold: f64) -> bool {
        let n = sub(n2, n1);
        dot(n, sub(p, a)) / norm(n) > threshold
    }

    /// `f_angle(j1, j2, k1, k2, (lo, hi))`: angle in degrees between `j2 − j1` and `k2 − k1`
    /// strictly inside `(lo, hi)`; NaN (zero vector, |cos| rounding above 1) is false.
    fn angle(&self, j1: V3, j2: V3, k1: V3, k2: V3, lo: f64, hi: f64) -> bool {
        let j = sub(j2, j1);
        let k = sub(k2, k1);
        let deg = (dot(j, k) / (norm(j) * norm(k))).acos().to_degrees();
        deg > lo && deg < hi
    }

    /// `f_fast(j, θ)`: ‖j − j_prev‖ / (1/120) > θ.
    fn fast(&self, j: usize, threshold: f64) -> bool {
        norm(sub(self.at(j), self.prev(j))) / TIME_PER_FRAME > threshold
    }

    /// The 32 predicates of one frame, in the reference order.
    fn flags(&self, hl: f64, sw: f64, hw: f64) -> [bool; NUM_MANUAL] {
        let p = |j| self.at(j);
        [
            // 1. right wrist moves forward (along the body normal), nmove(neck, rhip, lhip, rwrist, 1.8 hl)
            self.nmove(NECK, RHIP, LHIP, RWRIST, 1.8 * hl),
            // 2. left wrist moves forward, nmove(neck, lhip, rhip, lwrist, 1.8 hl)
            self.nmove(NECK, LHIP, RHIP, LWRIST, 1.8 * hl),
            // 3. right wrist above the neck, nplane(chest, neck, neck, rwrist, 0.2 hl)
            self.nplane(p(CHEST), p(NECK), p(NECK), p(RWRIST), 0.2 * hl),
            // 4. left wrist above the neck, nplane(chest, neck, neck, lwrist, 0.2 hl)
            self.nplane(p(CHEST), p(NECK), p(NECK), p(LWRIST), 0.2 * hl),
            // 5. "right wrist moves up", move(belly, chest, chest, rwrist, 1.8 hl): since j4 is
            // unused this is the chest's velocity relative to the belly, identical to feature 6
            self.mv(BELLY, CHEST, CHEST, 1.8 * hl),
            // 6. "left wrist moves up", move(belly, chest, chest, lwrist, 1.8 hl): same as feature 5
            self.mv(BELLY, CHEST, CHEST, 1.8 * hl),
            // 7. right elbow bent, angle(relbow, rshoulder, relbow, rwrist, (0, 110))
            self.angle(p(RELBOW), p(RSHOULDER), p(RELBOW), p(RWRIST), 0.0, 110.0),
            // 8. left elbow bent, angle(lelbow, lshoulder, lelbow, lwrist, (0, 110))
            self.angle(p(LELBOW), p(LSHOULDER), p(LELBOW), p(LWRIST), 0.0, 110.0),
            // 9. hands far apart, nplane(lshoulder, rshoulder, lwrist, rwrist, 2.5 sw)
            self.nplane(p(LSHOULDER), p(RSHOULDER), p(LWRIST), p(RWRIST), 2.5 * sw),
            // 10. wrists approach each other, move(lwrist, rwrist, rwrist, lwrist, 1.4 hl)
            self.mv(LWRIST, RWRIST, RWRIST, 1.4 * hl),
            // 11. move(rwrist, root, lwrist, root, 1.4 hl)
            self.mv(RWRIST, ROOT, LWRIST, 1.4 * hl),
            // 12. move(lwrist, root, rwrist, root, 1.4 hl)
            self.mv(LWRIST, ROOT, RWRIST, 1.4 * hl),
            // 13. right wrist fast, fast(rwrist, 2.5 hl)
            self.fast(RWRIST, 2.5 * hl),
            // 14. left wrist fast, fast(lwrist, 2.5 hl)
            self.fast(LWRIST, 2.5 * hl),
            // 15. right foot in front, plane(root, lhip, ltoes, rankle, 0.38 hl)
            self.plane(p(ROOT), p(LHIP), p(LTOES), p(RANKLE), 0.38 * hl),
            // 16. left foot in front, plane(root, rhip, rtoes, lankle, 0.38 hl)
            self.plane(p(ROOT), p(RHIP), p(RTOES), p(LANKLE), 0.38 * hl),
            // 17. right foot raised, nplane(zero, y_unit, y_min, rankle, 1.2 hl)
            self.nplane(ZERO, Y_UNIT, self.y_min(), p(RANKLE), 1.2 * hl),
            // 18. left foot raised, nplane(zero, y_unit, y_min, lankle, 1.2 hl)
            self.nplane(ZERO, Y_UNIT, self.y_min(), p(LANKLE), 1.2 * hl),
            // 19. feet apart, nplane(lhip, rhip, lankle, rankle, 2.1 hw)
            self.nplane(p(LHIP), p(RHIP), p(LANKLE), p(RANKLE), 2.1 * hw),
            // 20. right knee bent, angle(rknee, rhip, rknee, rankle, (0, 110))
            self.angle(p(RKNEE), p(RHIP), p(RKNEE), p(RANKLE), 0.0, 110.0),
            // 21. left knee bent, angle(lknee, lhip, lknee, lankle, (0, 110))
            self.angle(p(LKNEE), p(LHIP), p(LKNEE), p(LANKLE), 0.0, 110.0),
            // 22. right ankle fast, fast(rankle, 2.5 hl)
            self.fast(RANKLE, 2.5 * hl),
            // 23. left ankle fast, fast(lankle, 2.5 hl)
            self.fast(LANKLE, 2.5 * hl),
            // 24. right arm raised sideways, angle(neck, root, rshoulder, relbow, (25, 180))
            self.angle(p(NECK), p(ROOT), p(RSHOULDER), p(RELBOW), 25.0, 180.0),
            // 25. left arm raised sideways, angle(neck, root, lshoulder, lelbow, (25, 180))
            self.angle(p(NECK), p(ROOT), p(LSHOULDER), p(LELBOW), 25.0, 180.0),
            // 26. right leg raised, angle(neck, root, rhip, rknee, (50, 180))
            self.angle(p(NECK), p(ROOT), p(RHIP), p(RKNEE), 50.0, 180.0),
            // 27. left leg raised, angle(neck, root, lhip, lknee, (50, 180))
            self.angle(p(NECK), p(ROOT), p(LHIP), p(LKNEE), 50.0, 180.0),
            // 28. root behind the feet/neck plane, plane(rankle, neck, lankle, root, 0.5 hl)
            self.plane(p(RANKLE), p(NECK), p(LANKLE), p(ROOT), 0.5 * hl),
            // 29. trunk horizontal, angle(neck, root, zero, y_unit, (70, 110))
            self.angle(p(NECK), p(ROOT), ZERO, Y_UNIT, 70.0, 110.0),
            // 30. right hand low, nplane(zero, minus_y_unit, y_min, rwrist, −1.2 hl)
            self.nplane(ZERO, MINUS_Y_UNIT, self.y_min(), p(RWRIST), -1.2 * hl),
            // 31. left hand low, nplane(zero, minus_y_unit, y_min, lwrist, −1.2 hl)
            self.nplane(ZERO, MINUS_Y_UNIT, self.y_min(), p(LWRIST), -1.2 * hl),
            // 32. root fast, fast(root, 2.3 hl)
            self.fast(ROOT, 2.3 * hl),
        ]
    }
}

/// Per-frame predicates for frames `1 … T−1` (`T − 1` rows of 32 booleans).
pub fn manual_feature_flags(joints: &[f64]) -> Result<Vec<[bool; NUM_MANUAL]>, FeatureError> {
    let frames = frame_count(joints)?;
    let (hl, sw, hw) = (humerus_length(), shoulder_width(), hip_width());
    Ok((1..frames)
        .map(|t| {
            Frame {
                cur: &joints[t * FRAME_LEN..(t + 1) * FRAME_LEN],
                prev: &joints[(t - 1) * FRAME_LEN..t * FRAME_LEN],
            }
            .flags(hl, sw, hw)
        })
        .collect())
}

/// The 32 manual features of a `(T, 24, 3)` Y-up joint array: the fraction of frames
/// `1 … T−1` on which each predicate holds, as the reference's float32 mean.
///
/// # Panics
/// If the slice is not whole `(24, 3)` frames or holds fewer than 2 frames; see
/// [`try_manual_features`].
pub fn manual_features(joints: &[f64]) -> [f64; NUM_MANUAL] {
    match try_manual_features(joints) {
        Ok(f) => f,
        Err(e) => panic!("manual_features: {e}"),
    }
}

/// [`manual_features`] returning an error instead of panicking. Needs `T ≥ 2` (the reference
/// averages an empty list otherwise).
pub fn try_manual_features(joints: &[f64]) -> Result<[f64; NUM_MANUAL], FeatureError> {
    let flags = manual_feature_flags(joints)?;
    if flags.is_empty() {
        return Err(FeatureError::TooShort {
            what: "manual features",
            min: 2,
            frames: joints.len() / FRAME_LEN,
        });
    }
    let mut counts = [0u32; NUM_MANUAL];
    for row in &flags {
        for (c, &f) in counts.iter_mut().zip(row) {
            *c += u32::from(f);
        }
    }
    // float32 sum of 0/1 values is exact (< 2^24 frames); numpy then divides in float32.
    let n = flags.len() as f32;
    Ok(counts.map(|c| f64::from(c as f32 / n)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_match_reference() {
        assert!((humerus_length() - 0.25684).abs() < 1e-5);
        assert!((shoulder_width() - 0.39085).abs() < 1e-5);
        assert!((hip_width() - 0.11925).abs() < 1e-5);
    }

    #[test]
    fn rejects_short_input() {
        assert!(try_manual_features(&[0.0; FRAME_LEN]).is_err());
        assert!(try_manual_features(&[0.0; 7]).is_err());
    }
}
