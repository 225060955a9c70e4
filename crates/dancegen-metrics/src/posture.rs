//! Posture checks of our own (no published reference; the definition is ours): is the dancer
//! the right way up?
//!
//! A generator can learn the joint rotations well enough for FID and BAS to look merely bad
//! while its root orientation is upside down: a body standing on its head, feet in the air.
//! The kinetic and geometric features do not name that failure, so it is measured directly.
//!
//! Inputs are flat `(T, 24, 3)` joint positions, SMPL order, **Y-up**, any consistent unit.

use crate::{FRAME_LEN, FeatureError, frame_count};

/// SMPL joints whose difference is the trunk direction: pelvis (0) → neck (12).
pub const TRUNK: (usize, usize) = (0, 12);

/// The share of frames in which the dancer is upside down: the trunk (pelvis → neck) points
/// below the horizontal plane, i.e. it is tilted more than 90° from vertical.
///
/// Real dance is upright nearly always. Of the training takes of the solo data set (measured on
/// `dancegen convert` output, 2026-12-02): CMU salsa 0.02 % of 10,618 frames, AIST++ 0 % of
/// 1,564, CMU modern 0.6 % of 4,192 (one floor move in take 05_06), CMU breakdance 7 % of 3,069
/// (head- and handstands).
///
/// `Ok(None)` for an empty sequence.
pub fn inverted_share(joints: &[f64]) -> Result<Option<f64>, FeatureError> {
    let frames = frame_count(joints)?;
    if frames == 0 {
        return Ok(None);
    }
    let (pelvis, neck) = TRUNK;
    let down = joints
        .chunks_exact(FRAME_LEN)
        .filter(|f| f[neck * 3 + 1] - f[pelvis * 3 + 1] < 0.0)
        .count();
    Ok(Some(down as f64 / frames as f64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::NUM_JOINTS;

    /// A frame with the neck `dy` above the pelvis (other joints at the pelvis).
    fn frame(dy: f64) -> Vec<f64> {
        let mut f = vec![0.0; FRAME_LEN];
        for j in 0..NUM_JOINTS {
            f[j * 3 + 1] = 0.9;
        }
        f[TRUNK.1 * 3 + 1] = 0.9 + dy;
        f
    }

    #[test]
    fn counts_the_frames_whose_neck_is_below_the_pelvis() {
        let mut j = Vec::new();
        for dy in [0.5, 0.4, -0.1, 0.3, -0.5, 0.0, 0.2, 0.5] {
            j.extend(frame(dy));
        }
        assert_eq!(inverted_share(&j).unwrap(), Some(2.0 / 8.0));
    }

    #[test]
    fn a_lying_body_is_not_inverted_and_empty_input_has_no_share() {
        assert_eq!(inverted_share(&frame(0.0)).unwrap(), Some(0.0));
        assert_eq!(inverted_share(&[]).unwrap(), None);
        assert!(inverted_share(&[0.0; 5]).is_err());
    }
}
