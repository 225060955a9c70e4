//! Generated joint rotations whose 6D rows shrank, bridged window by window before anything
//! else reads them (decoding, not part of Lodge++).
//!
//! The PDDM regresses 6D rotations. Where it is unsure between two poses far apart it can
//! move a joint's output along the straight line between them, through the origin; Gram–Schmidt
//! then turns the sign change into a jump of one frame. Measured on the bundled demo song (seed
//! 0, no beat alignment): the right shoulder's first row was 0.4–0.5 long over ten frames and
//! the decoded shoulder turned 127° in one of them, moving the hand 0.70 m; 199 of the dance's
//! 32,400 joint-frames had a row under half its length. `dancegen_motion::rot6d_track` bridges
//! each such run by the slerp between the well-defined frames around it, as the duet model's
//! decoding does. It runs per window, before the seams (`crate::seams`) and the root-flip
//! repair (`crate::root_flips`) read and rewrite the rotations, so they see proper rotations.

use dancegen_motion::rot6d_track::bridge_6d_track;

use crate::layout::{DIMS, rot6d};

/// Joints of the EDGE-151 layout (root first).
const JOINTS: usize = 24;

/// Bridges every joint's ill-defined 6D runs in each `n`-frame window of raw `[L·n, 151]`
/// frames (a trailing shorter window included); returns the number of joint-frames rewritten.
pub fn bridge_short_rows(frames: &mut [f32], n: usize) -> usize {
    assert!(n > 0, "window length must be positive");
    let mut bridged = 0;
    for window in frames.chunks_mut(n * DIMS) {
        let t = window.len() / DIMS;
        for j in 0..JOINTS {
            let c = rot6d(j, 0);
            let mut track: Vec<[f64; 6]> = (0..t)
                .map(|f| std::array::from_fn(|k| f64::from(window[f * DIMS + c + k])))
                .collect();
            let count = bridge_6d_track(&mut track);
            if count == 0 {
                continue;
            }
            bridged += count;
            for (f, d) in track.iter().enumerate() {
                for (k, v) in d.iter().enumerate() {
                    let old = &mut window[f * DIMS + c + k];
                    // Frames that were not bridged keep their exact value.
                    if f64::from(*old) != *v {
                        *old = *v as f32;
                    }
                }
            }
        }
    }
    bridged
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::rotation::Mat3;

    /// Two windows; in the second, joint 17 turns 160° about y along the straight 6D line, the
    /// rows shrinking in the middle. Only those frames change, and they turn evenly.
    #[test]
    fn a_shrinking_turn_is_bridged_in_its_window_only() {
        let n = 12;
        let mut frames = vec![0f32; 2 * n * DIMS];
        let id = Mat3::IDENTITY.to_6d();
        for f in 0..2 * n {
            for j in 0..JOINTS {
                for k in 0..6 {
                    frames[f * DIMS + rot6d(j, k)] = id[k] as f32;
                }
            }
        }
        let (a, b) = (
            Mat3::from_axis_rotation(1, 0.0).to_6d(),
            Mat3::from_axis_rotation(1, 160f64.to_radians()).to_6d(),
        );
        for f in 0..n {
            let s = f as f64 / (n - 1) as f64;
            for k in 0..6 {
                frames[(n + f) * DIMS + rot6d(17, k)] = (a[k] * (1.0 - s) + b[k] * s) as f32;
            }
        }
        let before = frames.clone();
        let bridged = bridge_short_rows(&mut frames, n);
        assert!(bridged > 0);
        let changed: Vec<usize> = (0..2 * n)
            .filter(|&f| (0..DIMS).any(|c| frames[f * DIMS + c] != before[f * DIMS + c]))
            .collect();
        assert_eq!(changed.len(), bridged);
        assert!(
            changed.iter().all(|&f| f > n && f < 2 * n - 1),
            "{changed:?}"
        );
        let yaw = |f: usize| {
            let d: [f64; 6] = std::array::from_fn(|k| f64::from(frames[f * DIMS + rot6d(17, k)]));
            let m = Mat3::from_6d(&d);
            m.0[0][2].atan2(m.0[0][0]).to_degrees().abs()
        };
        for f in n + 1..2 * n {
            let step = (yaw(f) - yaw(f - 1)).abs();
            assert!(step < 40.0, "frame {f}: turned {step}° in one frame");
        }
        assert_eq!(bridge_short_rows(&mut frames, n), 0);
    }
}
