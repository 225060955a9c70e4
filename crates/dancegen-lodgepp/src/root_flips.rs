//! One- to three-frame flips of the root orientation in generated frames: what they are, and
//! their repair.
//!
//! A model trained on motion with spins and flips (pirouettes, break) sometimes outputs, for a
//! frame or two, a pelvis rotation 140–180° away from both neighbours, which then turns back
//! (docs/solo-data-v2.md, "Pops"). No dancer turns 90° in 1/30 s (that is 2700°/s; a fast
//! pirouette is about 720°/s, 24° per frame), so such a run is an artefact, and every joint
//! below the pelvis swings with it. The repair replaces the run's root rotation by the
//! spherical interpolation between the frames around it; nothing else is touched. It runs
//! before the foot lock, so the leg IK never follows a flip. The count is logged: the repair
//! hides a defect of the model, and a model that needs it often should be fixed.

use dancegen_motion::{Mat3, Quat};

use crate::layout::{DIMS, rot6d};

/// Smallest one-frame turn of the root counted as a flip, degrees (see the module docs).
pub const FLIP_DEGREES: f64 = 90.0;
/// Longest run of flipped frames repaired; a longer run is left alone (it may be a real,
/// if abrupt, change that the frames around it agree with).
pub const MAX_FLIP_RUN: usize = 3;

/// The root rotation of one raw frame.
fn root_rotation(frame: &[f32]) -> Mat3 {
    let d: [f64; 6] = std::array::from_fn(|k| f64::from(frame[rot6d(0, k)]));
    Mat3::from_6d(&d)
}

/// Angle between two rotations, degrees.
fn angle_deg(a: &Mat3, b: &Mat3) -> f64 {
    let r = a.transpose().mul(b);
    let tr = r.0[0][0] + r.0[1][1] + r.0[2][2];
    ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Repairs the flipped runs of raw EDGE-151 `frames` (`[T, 151]`) in place; returns how many
/// frames were repaired.
pub fn repair_root_flips(frames: &mut [f32]) -> usize {
    let t = frames.len() / DIMS;
    if t < 3 {
        return 0;
    }
    let rot: Vec<Mat3> = frames.chunks(DIMS).map(root_rotation).collect();
    let mut repaired = 0;
    let mut i = 1;
    while i + 1 < t {
        // A run starts where the root turns by a flip from the previous frame ...
        if angle_deg(&rot[i - 1], &rot[i]) < FLIP_DEGREES {
            i += 1;
            continue;
        }
        // ... and ends at the first frame after it that is close to the frame before the run.
        let before = i - 1;
        let after = (i + 1..t.min(i + 1 + MAX_FLIP_RUN))
            .find(|&k| angle_deg(&rot[before], &rot[k]) < FLIP_DEGREES);
        let Some(after) = after else {
            i += 1;
            continue;
        };
        let (qa, qb) = (rot[before].to_quat(), rot[after].to_quat());
        for k in i..after {
            let s = (k - before) as f64 / (after - before) as f64;
            let d = Mat3::from_quat(Quat::slerp(qa, qb, s)).to_6d();
            let f = &mut frames[k * DIMS..(k + 1) * DIMS];
            for (c, v) in d.iter().enumerate() {
                f[rot6d(0, c)] = *v as f32;
            }
            repaired += 1;
        }
        i = after + 1;
    }
    repaired
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames_turning(t: usize, deg_per_frame: f64) -> Vec<f32> {
        let mut f = vec![0f32; t * DIMS];
        for k in 0..t {
            let r = Mat3::from_axis_rotation(2, (deg_per_frame * k as f64).to_radians()).to_6d();
            for c in 0..6 {
                f[k * DIMS + rot6d(0, c)] = r[c] as f32;
            }
            f[k * DIMS + rot6d(5, 0)] = k as f32; // another joint: must stay
        }
        f
    }

    fn set_root(f: &mut [f32], k: usize, m: &Mat3) {
        for (c, v) in m.to_6d().iter().enumerate() {
            f[k * DIMS + rot6d(0, c)] = *v as f32;
        }
    }

    /// A pirouette (24°/frame) is not a flip; a one- and a two-frame 170° flip in it are
    /// repaired onto the spin; a lasting 150° change is kept.
    #[test]
    fn flips_are_repaired_and_spins_kept() {
        let mut f = frames_turning(60, 24.0);
        let spin = f.clone();
        assert_eq!(repair_root_flips(&mut f), 0);
        assert_eq!(f, spin);

        let flip = |k: usize| {
            root_rotation(&spin[k * DIMS..]).mul(&Mat3::from_axis_rotation(0, 170f64.to_radians()))
        };
        set_root(&mut f, 10, &flip(10));
        set_root(&mut f, 30, &flip(30));
        set_root(&mut f, 31, &flip(31));
        assert_eq!(repair_root_flips(&mut f), 3);
        for k in [10, 30, 31] {
            let got = root_rotation(&f[k * DIMS..]);
            let want = root_rotation(&spin[k * DIMS..]);
            assert!(angle_deg(&got, &want) < 0.1, "frame {k}");
        }
        for k in 0..60 {
            assert_eq!(f[k * DIMS + rot6d(5, 0)], k as f32);
        }

        let mut lasting = frames_turning(40, 0.0);
        for k in 20..40 {
            set_root(
                &mut lasting,
                k,
                &Mat3::from_axis_rotation(1, 150f64.to_radians()),
            );
        }
        let kept = lasting.clone();
        assert_eq!(repair_root_flips(&mut lasting), 0);
        assert_eq!(lasting, kept);
    }
}
