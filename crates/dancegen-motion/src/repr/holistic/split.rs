//! SoulNet's split layout `[body 263 | hands 360 | face F]` of the holistic vector, and the exact
//! permutation to and from our interleaved [`super::Holistic623`] / [`super::Holistic723`]
//! layout (`../shared/reference/holistic.md` §1.1).
//!
//! SoulDance's models slice the stored vector as `[:263]` (body), `[263:623]` (hands) and
//! `[623:]` (face) (`models/vq/model.py`), and `data/m2m_dataset.py::motion_merge` rebuilds the
//! interleaved 623 from the first two. In the interleaved layout (per frame, joints 0–51 in
//! SMPL-H order, 22 body joints first) that is:
//!
//! | split dims | interleaved dims | content |
//! |---|---|---|
//! | body 0..67 | 0..67 | root (4) + ric of body joints 1–21 (63) |
//! | body 67..193 | 157..283 | 6D rotations of body joints 1–21 (126) |
//! | body 193..259 | 463..529 | local velocities of body joints 0–21 (66) |
//! | body 259..263 | 619..623 | foot contacts (4) |
//! | hands 0..90 | 67..157 | ric of the 30 finger joints |
//! | hands 90..270 | 283..463 | their 6D rotations |
//! | hands 270..360 | 529..619 | their local velocities |
//! | face 0..F | 623..623+F | passed through (F = 52 ARKit weights or 100 FLAME values) |
//!
//! The body part is exactly HumanML3D's 263 layout of the 22 body joints, so a body-only model
//! reads it as it is.

use std::ops::Range;

use super::{JOINTS, LAYOUT};
use crate::repr::ReprError;
use crate::repr::frames_of;
use crate::repr::humanml263::dims_for_joints;

/// Body joints (SMPL-H 0–21, the SMPL body without hands).
pub const BODY_JOINTS: usize = 22;
/// Values per frame of the body part: HumanML3D's 263.
pub const BODY_DIMS: usize = dims_for_joints(BODY_JOINTS);
/// Finger joints (SMPL-H 22–51: left hand, then right hand).
pub const FINGER_JOINTS: usize = JOINTS - BODY_JOINTS;
/// Values per frame of the hands part: 30 finger joints × (ric 3 + 6D 6 + velocity 3).
pub const HAND_DIMS: usize = FINGER_JOINTS * 12;
/// Body + hands, the interleaved [`super::Holistic623::DIMS`].
pub const BODY_HAND_DIMS: usize = BODY_DIMS + HAND_DIMS;

/// Interleaved ranges that make up the body part, in split order.
pub const BODY_SOURCE: [Range<usize>; 4] = [
    0..LAYOUT.ric() + 3 * (BODY_JOINTS - 1),
    LAYOUT.rot()..LAYOUT.rot() + 6 * (BODY_JOINTS - 1),
    LAYOUT.vel()..LAYOUT.vel() + 3 * BODY_JOINTS,
    LAYOUT.contacts()..LAYOUT.contacts() + 4,
];
/// Interleaved ranges that make up the hands part, in split order.
pub const HAND_SOURCE: [Range<usize>; 3] = [
    LAYOUT.ric() + 3 * (BODY_JOINTS - 1)..LAYOUT.rot(),
    LAYOUT.rot() + 6 * (BODY_JOINTS - 1)..LAYOUT.vel(),
    LAYOUT.vel() + 3 * BODY_JOINTS..LAYOUT.contacts(),
];

/// `perm[i]` = the interleaved index of split index `i`, for the 623 body + hand values (the
/// face follows unchanged).
pub fn permutation() -> Vec<usize> {
    BODY_SOURCE
        .iter()
        .chain(HAND_SOURCE.iter())
        .flat_map(|r| r.clone())
        .collect()
}

fn check(what: &'static str, data: &[f32], face_dims: usize) -> Result<usize, ReprError> {
    frames_of(what, data, BODY_HAND_DIMS + face_dims)
}

/// `(T, 623 + F)` interleaved → `(T, 263 + 360 + F)` split (SoulNet's model input).
pub fn to_split(data: &[f32], face_dims: usize) -> Result<Vec<f32>, ReprError> {
    check("holistic interleaved", data, face_dims)?;
    let perm = permutation();
    let mut out = Vec::with_capacity(data.len());
    for row in data.chunks_exact(BODY_HAND_DIMS + face_dims) {
        out.extend(perm.iter().map(|&k| row[k]));
        out.extend_from_slice(&row[BODY_HAND_DIMS..]);
    }
    Ok(out)
}

/// `(T, 263 + 360 + F)` split → `(T, 623 + F)` interleaved (`motion_merge`).
pub fn from_split(data: &[f32], face_dims: usize) -> Result<Vec<f32>, ReprError> {
    check("holistic split", data, face_dims)?;
    let perm = permutation();
    let mut out = Vec::with_capacity(data.len());
    for row in data.chunks_exact(BODY_HAND_DIMS + face_dims) {
        let start = out.len();
        out.resize(start + BODY_HAND_DIMS, 0.0);
        for (i, &k) in perm.iter().enumerate() {
            out[start + k] = row[i];
        }
        out.extend_from_slice(&row[BODY_HAND_DIMS..]);
    }
    Ok(out)
}

/// Reads a SoulDance / Motion-X-style holistic `.npy` in the split layout, `(T, 623)` (no
/// face) or `(T, 723)` (100 FLAME values), and decodes it on our approximate SMPL-H skeleton
/// ([`super::Holistic623::decode`]; the face passes through). For users who have such data: the
/// file names itself in every error.
pub fn read_split_npy(
    path: &std::path::Path,
    fps: f32,
) -> Result<super::HolisticMotion, ReprError> {
    let a = dancegen_io::read_npy(path)?;
    let bad = |why: String| ReprError::Invalid(format!("{}: {why}", path.display()));
    let face = match a.shape.as_slice() {
        [_, w] if *w == BODY_HAND_DIMS => 0,
        [_, w] if *w == BODY_HAND_DIMS + super::FACE_DIMS => super::FACE_DIMS,
        s => {
            return Err(bad(format!(
                "shape {s:?}: a holistic motion is (T, 623) or (T, 723) in SoulNet's split layout"
            )));
        }
    };
    let data: Vec<f32> = a.data.iter().map(|&v| v as f32).collect();
    let inter = from_split(&data, face)?;
    let m = if face == 0 {
        super::Holistic623::decode(&inter, fps)
    } else {
        super::Holistic723::decode(&inter, fps)
    };
    m.map_err(|e| bad(e.to_string()))
}

/// One split row's parts: `(body 263, hands 360, face F)`.
pub fn parts(row: &[f32]) -> (&[f32], &[f32], &[f32]) {
    let (body, rest) = row.split_at(BODY_DIMS);
    let (hands, face) = rest.split_at(HAND_DIMS.min(rest.len()));
    (body, hands, face)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_permutation_is_souldances_slices_and_a_bijection() {
        assert_eq!((BODY_DIMS, HAND_DIMS, FINGER_JOINTS), (263, 360, 30));
        // holistic.md §1.1, written out.
        assert_eq!(BODY_SOURCE, [0..67, 157..283, 463..529, 619..623]);
        assert_eq!(HAND_SOURCE, [67..157, 283..463, 529..619]);
        let mut p = permutation();
        assert_eq!(p.len(), 623);
        p.sort_unstable();
        assert!(p.iter().enumerate().all(|(i, &k)| i == k));
    }

    #[test]
    fn round_trip_with_face_and_shape_errors() {
        for face in [0usize, 52, 100] {
            let w = BODY_HAND_DIMS + face;
            let data: Vec<f32> = (0..3 * w).map(|i| i as f32 * 0.5 - 7.0).collect();
            let split = to_split(&data, face).unwrap();
            assert_eq!(from_split(&split, face).unwrap(), data);
            // The face is the tail of both layouts.
            assert_eq!(split[w - face..w], data[w - face..w]);
            let (b, h, f) = parts(&split[..w]);
            assert_eq!((b.len(), h.len(), f.len()), (263, 360, face));
            // Body's first 67 values are the interleaved first 67; hands start at ric of joint 22.
            assert_eq!(b[..67], data[..67]);
            assert_eq!(h[0], data[67]);
        }
        let e = to_split(&[0.0; 700], 52).unwrap_err().to_string();
        assert!(e.contains("holistic interleaved"), "{e}");
        assert!(from_split(&[0.0; 675], 100).is_err());
    }
}
