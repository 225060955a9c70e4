//! EDGE's final stitching of long-form windows (`render_sample`, mode "long"; anchors D.1).
//!
//! The sampler generates `N` windows of `W` frames with stride `W/2` (see
//! [`super::sampler::overwrite_first_halves`]); the stitched sequence has `W + (N − 1)·W/2`
//! frames. Over each overlap of `h = W/2` frames the weight is `linspace(0, 1, h)`:
//! linear channels (root position, contacts) are cross-faded `(1 − w)·prev + w·next`, and each
//! 6D-rotation group is slerped through quaternions (EDGE converts to axis-angle and slerps
//! quaternions). Outside the overlaps the windows' own values are kept.
//!
//! The 6D layout is pytorch3d's "first two rows" of the rotation matrix, as
//! [`crate::loss::rot6d_to_matrix`]; the slerped rotation is written back as its first two
//! rows. The rotation math is the motion crate's (`Mat3::from_6d`, `Quat::slerp`, shortest arc
//! with a normalised-lerp fallback). Runs on the host in f64: stitching is a once-per-dance post-process with branches
//! (shortest-path sign, near-parallel fallback) that tensor ops express badly.

use std::ops::Range;

use burn::tensor::{Tensor, TensorData};
use dancegen_motion::rotation::{Mat3, Quat};

/// How channels are blended across an overlap. Channels in no `rot6d` group are cross-faded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChannelLayout {
    /// Ranges of 6D rotations, each a multiple of 6 channels (one joint per 6).
    pub rot6d: Vec<Range<usize>>,
}

impl ChannelLayout {
    /// EDGE's 151-dim layout (anchors C.2): 4 contacts, 3 root position, 24 × 6D rotations.
    pub fn edge151() -> Self {
        ChannelLayout {
            rot6d: std::iter::once(7..151).collect(),
        }
    }
}

/// Stitches windows `[N, W, C]` (stride `W/2`) into `[W + (N − 1)·W/2, C]`.
pub fn stitch(windows: Tensor<3>, layout: &ChannelLayout) -> Tensor<2> {
    let [n, w, c] = windows.dims();
    assert!(
        w.is_multiple_of(2),
        "long-form windows need an even length, got {w}"
    );
    for r in &layout.rot6d {
        assert!(
            r.end <= c && r.len().is_multiple_of(6),
            "6D group {r:?} must be a multiple of 6 channels within {c}"
        );
    }
    let device = windows.device();
    let src: Vec<f32> = windows
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .expect("f32 windows");
    let at = |i: usize, f: usize, ch: usize| f64::from(src[(i * w + f) * c + ch]);
    let h = w / 2;
    let len = w + (n - 1) * h;
    let mut out = vec![0f32; len * c];
    let is_rot = |ch: usize| layout.rot6d.iter().any(|r| r.contains(&ch));
    // Frames covered by one window only: the first half of window 0, the second half of the last.
    for f in 0..h {
        for ch in 0..c {
            out[f * c + ch] = at(0, f, ch) as f32;
            out[((n - 1) * h + h + f) * c + ch] = at(n - 1, h + f, ch) as f32;
        }
    }
    for i in 0..n - 1 {
        for j in 0..h {
            let wt = if h == 1 {
                0.0
            } else {
                j as f64 / (h - 1) as f64
            };
            let f_out = (i + 1) * h + j;
            for ch in (0..c).filter(|&ch| !is_rot(ch)) {
                let v = (1.0 - wt) * at(i, h + j, ch) + wt * at(i + 1, j, ch);
                out[f_out * c + ch] = v as f32;
            }
            for r in &layout.rot6d {
                for g in r.clone().step_by(6) {
                    let prev: [f64; 6] = std::array::from_fn(|k| at(i, h + j, g + k));
                    let next: [f64; 6] = std::array::from_fn(|k| at(i + 1, j, g + k));
                    let qa = Mat3::from_6d(&prev).to_quat();
                    let qb = Mat3::from_6d(&next).to_quat();
                    let d6 = Mat3::from_quat(Quat::slerp(qa, qb, wt)).to_6d();
                    for (k, v) in d6.into_iter().enumerate() {
                        out[f_out * c + g + k] = v as f32;
                    }
                }
            }
        }
    }
    Tensor::from_data(TensorData::new(out, [len, c]), &device)
}
