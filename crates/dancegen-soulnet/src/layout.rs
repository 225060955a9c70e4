//! The holistic vector the networks see and what it decodes to.
//!
//! A frame is SoulNet's split vector `[body 263 | hands 360 | face 52]`
//! (`dancegen_motion::repr::holistic::split`; the face as the 52 ARKit weights), normalised by
//! the training set's mean and std. Music is the 35 EDGE/librosa features per 30-fps frame.
//! Decoding: the body and hands through the HumanML3D-style recovery of the 52 SMPL-H joints
//! (`Holistic623`), the face clamped to `[0, 1]`.

use dancegen_motion::face::ARKIT_COUNT;
use dancegen_motion::repr::holistic::Holistic623;
use dancegen_motion::repr::holistic::HolisticMotion;
use dancegen_motion::repr::holistic::split::{self, BODY_DIMS, BODY_HAND_DIMS, HAND_DIMS};

/// Music features per frame (EDGE's 35: envelope, 20 MFCC, 12 chroma, peak and beat one-hots).
pub const MUSIC_DIMS: usize = 35;
/// Values per frame of body, hands and face.
pub const PART_DIMS: [usize; 3] = [BODY_DIMS, HAND_DIMS, ARKIT_COUNT];
/// Values per frame.
pub const TOTAL_DIMS: usize = BODY_HAND_DIMS + ARKIT_COUNT;

/// A decoded holistic dance.
#[derive(Clone, Debug)]
pub struct HolisticDance {
    /// SMPL-H 52 rotations and root path (`Skeleton::smplh52_approx`).
    pub motion: HolisticMotion,
    /// `(T, 52)` ARKit weights in `[0, 1]`.
    pub face: Vec<f32>,
}

/// Un-normalised split rows `(T, 675)` → the dance.
pub fn decode(rows: &[f32], fps: f32) -> Result<HolisticDance, String> {
    if rows.is_empty() || !rows.len().is_multiple_of(TOTAL_DIMS) {
        return Err(format!(
            "{} values are not whole {TOTAL_DIMS}-value holistic frames",
            rows.len()
        ));
    }
    if rows.iter().any(|v| !v.is_finite()) {
        return Err(
            "the model produced non-finite values (please report this with the song and seed)"
                .into(),
        );
    }
    let t = rows.len() / TOTAL_DIMS;
    let mut body_hands = Vec::with_capacity(t * BODY_HAND_DIMS);
    let mut face = Vec::with_capacity(t * ARKIT_COUNT);
    for row in rows.chunks_exact(TOTAL_DIMS) {
        body_hands.extend_from_slice(&row[..BODY_HAND_DIMS]);
        face.extend(row[BODY_HAND_DIMS..].iter().map(|v| v.clamp(0.0, 1.0)));
    }
    let inter = split::from_split(&body_hands, 0).map_err(|e| e.to_string())?;
    let motion = Holistic623::decode(&inter, fps).map_err(|e| e.to_string())?;
    Ok(HolisticDance { motion, face })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_an_encoded_motion_and_clamps_the_face() {
        // A still pose with bent fingers, walking forward along z.
        let t = 12;
        let mut poses = vec![0f32; t * 52 * 3];
        let mut trans = vec![0f32; t * 3];
        for f in 0..t {
            poses[(f * 52 + 25) * 3 + 2] = 0.8;
            trans[f * 3 + 1] = 0.9;
            trans[f * 3 + 2] = 0.02 * f as f32;
        }
        let inter = Holistic623::encode(&poses, &trans, 30.0).unwrap();
        let body_hands = split::to_split(&inter, 0).unwrap();
        let mut rows = Vec::new();
        for row in body_hands.chunks_exact(BODY_HAND_DIMS) {
            rows.extend_from_slice(row);
            rows.extend((0..ARKIT_COUNT).map(|i| i as f32 / 26.0 - 0.5));
        }
        let d = decode(&rows, 30.0).unwrap();
        assert_eq!(d.motion.frames(), t - 1);
        assert!(d.face.iter().all(|v| (0.0..=1.0).contains(v)));
        assert_eq!(d.face[0], 0.0);
        assert_eq!(d.face[51], 1.0);
        let bend = d.motion.poses[(3 * 52 + 25) * 3 + 2];
        assert!((bend - 0.8).abs() < 1e-3, "{bend}");
        assert!(decode(&rows[..100], 30.0).is_err());
    }
}
