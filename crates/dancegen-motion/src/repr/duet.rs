//! The duet representation of dancegen's reactive system (ReactDance, arXiv 2505.05589): the
//! follower's motion **relative to the leader**, split into the paper's three streams, and the
//! leader's own features that condition the model.
//!
//! ReactDance's code is unreleased (anchors D.5): the paper names the three streams (upper
//! body, lower body, "relative root distance to the leader") but not their contents. These
//! layouts are our choice, stated here once.
//!
//! Follower, [`DuetFollower::DIMS`] = 151 per frame, 30 fps, Y-up, metres:
//!
//! | dims | stream | content |
//! |---|---|---|
//! | 0..90 | upper | 6D (first two rows, as pytorch3d) of the local rotations of [`UPPER_JOINTS`] |
//! | 90..138 | lower | 6D of the local rotations of [`LOWER_JOINTS`] |
//! | 138..142 | lower | foot contacts of the follower (EDGE's rule: 1 where the joint moves < 1 cm in the next frame), SMPL joints 7, 8, 10, 11 |
//! | 142..145 | root | follower pelvis `(x, z)` minus the leader's, turned into the leader frame; follower pelvis height `y` (world) |
//! | 145..151 | root | 6D of the follower's root orientation in the leader frame |
//!
//! The **leader frame** of a frame is the rotation about +Y by the leader's heading
//! (`atan2(f_x, f_z)` with `f = R·(0, 0, 1)` for the pelvis rotation `R`; SMPL faces +Z),
//! unwrapped over the sequence and smoothed by a Gaussian of `sigma` frames ([`leader_frames`];
//! `sigma = 0`: the heading of each frame). Decoding uses the same frames, so the follower comes
//! back into the leader's world frame exactly and the pair stays a couple whatever the leader
//! does. Why smooth: a salsa leader turns at ~4 rad/s on average; in a frame that turns with the
//! leader every centimetre of error in the follower's relative position becomes world motion at
//! that rate (the first model, `sigma = 0`, moved its followers' pelvis at 2–4 m/s where real
//! followers move at 0.8–1.3 m/s). The smoothed frame keeps the representation independent of
//! where the couple stands and which way it faces, while spins stay in the features.
//!
//! Leader, [`DuetLeader::DIMS`] = 220 per frame, translation- and heading-invariant (in the
//! leader frame, which its own instantaneous heading deviates from):
//!
//! | dims | content |
//! |---|---|
//! | 0 | pelvis height `y` |
//! | 1..3 | pelvis velocity `(x, z)` in the leader frame, m/s (forward difference, last frame repeated) |
//! | 3 | heading rate, rad/s (wrapped, unsmoothed) |
//! | 4..10 | 6D of the pelvis orientation in the leader frame |
//! | 10..148 | 6D of the local rotations of joints 1..23 |
//! | 148..220 | the 24 joints' world positions minus the pelvis, in the leader frame |

use std::ops::Range;

use super::motion::{EDGE_CONTACT_VELOCITY, POSE_DIMS, SMPL_JOINTS, contacts_velocity};
use super::{ReprError, SmplMotion, check_fps, frames_of};
use crate::conventions::CANONICAL_FPS;
use crate::rot6d_track::decode_6d_track;
use crate::rotation::{Mat3, wrap_angle};
use crate::smoothing::{Ends, gaussian_smooth_truncated};

/// Spine, neck, head, collars, shoulders, elbows, wrists, hands (SMPL 24 indices).
pub const UPPER_JOINTS: [usize; 15] = [3, 6, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23];
/// Hips, knees, ankles, feet.
pub const LOWER_JOINTS: [usize; 8] = [1, 2, 4, 5, 7, 8, 10, 11];

/// The follower layout; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct DuetFollower;

impl DuetFollower {
    pub const DIMS: usize = 151;
    /// The three streams of the HFSQ autoencoder, in order.
    pub const STREAMS: [Range<usize>; 3] = [0..90, 90..142, 142..151];
    pub const UPPER: Range<usize> = 0..90;
    pub const LOWER_ROT: Range<usize> = 90..138;
    pub const CONTACTS: Range<usize> = 138..142;
    /// Relative pelvis position `(x_rel, y, z_rel)`.
    pub const ROOT_POS: Range<usize> = 142..145;
    pub const ROOT_ROT: Range<usize> = 145..151;
}

/// The leader layout; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct DuetLeader;

impl DuetLeader {
    pub const DIMS: usize = 220;
}

/// Heading (yaw about +Y) of a pelvis rotation.
pub fn heading(root: &Mat3) -> f64 {
    let f = root.mul_vec([0.0, 0.0, 1.0]);
    f[0].atan2(f[2])
}

/// The leader frame's yaw angle of every frame: headings unwrapped, then a Gaussian of `sigma`
/// frames (ends held; `sigma ≤ 0` leaves them as they are).
pub fn leader_frames(leader: &SmplMotion, sigma: f64) -> Vec<f64> {
    let t = leader.frames();
    let mut h: Vec<f64> = (0..t).map(|f| heading(&rot(leader, f, 0))).collect();
    for f in 1..t {
        h[f] = h[f - 1] + wrap_angle(h[f] - h[f - 1]);
    }
    // Cut at 4σ (not the filter's default 3σ): the shipped model was trained on this frame.
    gaussian_smooth_truncated(&h, sigma, 4.0, Ends::Hold)
}

fn yaw(angle: f64) -> Mat3 {
    Mat3::from_axis_rotation(1, angle)
}

fn rot(m: &SmplMotion, f: usize, j: usize) -> Mat3 {
    Mat3::from_axis_angle(m.joint_aa(f, j).map(f64::from))
}

fn pelvis(m: &SmplMotion, f: usize) -> [f64; 3] {
    let p = &m.trans[f * 3..f * 3 + 3];
    [p[0], p[1], p[2]].map(f64::from)
}

fn push6(out: &mut Vec<f32>, r: &Mat3) {
    out.extend(r.to_6d().map(|v| v as f32));
}

fn check_pair(follower: &SmplMotion, leader: &SmplMotion) -> Result<usize, ReprError> {
    check_fps("DuetFollower", follower.fps, CANONICAL_FPS as f32)?;
    check_fps("DuetFollower (leader)", leader.fps, CANONICAL_FPS as f32)?;
    let t = follower.validate()?;
    let tl = leader.validate()?;
    if t != tl {
        return Err(ReprError::Invalid(format!(
            "follower has {t} frames, leader {tl}: a couple must have the same length"
        )));
    }
    Ok(t)
}

impl DuetFollower {
    /// `(T, 151)` of `follower` relative to `leader` (both 30 fps, same length) in leader frames
    /// smoothed by `sigma` frames.
    pub fn encode(
        follower: &SmplMotion,
        leader: &SmplMotion,
        sigma: f64,
    ) -> Result<Vec<f32>, ReprError> {
        let t = check_pair(follower, leader)?;
        let frames = leader_frames(leader, sigma);
        let contacts = contacts_velocity(&follower.joints_world()?, EDGE_CONTACT_VELOCITY);
        let mut out = Vec::with_capacity(t * Self::DIMS);
        for f in 0..t {
            for j in UPPER_JOINTS.into_iter().chain(LOWER_JOINTS) {
                push6(&mut out, &rot(follower, f, j));
            }
            out.extend_from_slice(&contacts[f * 4..f * 4 + 4]);
            let inv = yaw(frames[f]).transpose();
            let (pf, pl) = (pelvis(follower, f), pelvis(leader, f));
            let rel = inv.mul_vec([pf[0] - pl[0], 0.0, pf[2] - pl[2]]);
            out.extend([rel[0], pf[1], rel[2]].map(|v| v as f32));
            push6(&mut out, &inv.mul(&rot(follower, f, 0)));
        }
        Ok(out)
    }

    /// The follower back in `leader`'s world frame from `(T, 151)` (contacts are ignored);
    /// `sigma` as in [`Self::encode`].
    pub fn decode(data: &[f32], leader: &SmplMotion, sigma: f64) -> Result<SmplMotion, ReprError> {
        Self::decode_counted(data, leader, sigma).map(|(m, _)| m)
    }

    /// [`Self::decode`], and the number of joint rotations (over joints and frames) whose 6D
    /// rows had lost their length and were bridged ([`crate::rot6d_track`]).
    pub fn decode_counted(
        data: &[f32],
        leader: &SmplMotion,
        sigma: f64,
    ) -> Result<(SmplMotion, usize), ReprError> {
        let t = frames_of("DuetFollower::decode", data, Self::DIMS)?;
        let tl = leader.validate()?;
        if t != tl {
            return Err(ReprError::Invalid(format!(
                "{t} follower frames for a {tl}-frame leader"
            )));
        }
        let frames = leader_frames(leader, sigma);
        let track = |k: usize| -> Vec<[f64; 6]> {
            data.chunks_exact(Self::DIMS)
                .map(|row| std::array::from_fn(|i| f64::from(row[k + i])))
                .collect()
        };
        let mut bridged = 0;
        let mut poses = vec![0f32; t * POSE_DIMS];
        for (k, j) in UPPER_JOINTS.into_iter().chain(LOWER_JOINTS).enumerate() {
            let (rot, n) = decode_6d_track(&track(6 * k));
            bridged += n;
            for (f, r) in rot.iter().enumerate() {
                poses[f * POSE_DIMS + 3 * j..f * POSE_DIMS + 3 * j + 3]
                    .copy_from_slice(&r.to_axis_angle().map(|v| v as f32));
            }
        }
        let (root_rot, n) = decode_6d_track(&track(Self::ROOT_ROT.start));
        bridged += n;
        let mut trans = Vec::with_capacity(t * 3);
        for (f, row) in data.chunks_exact(Self::DIMS).enumerate() {
            let h = yaw(frames[f]);
            let r = &row[Self::ROOT_POS];
            let off = h.mul_vec([f64::from(r[0]), 0.0, f64::from(r[2])]);
            let pl = pelvis(leader, f);
            trans.extend([pl[0] + off[0], f64::from(r[1]), pl[2] + off[2]].map(|v| v as f32));
            let root = h.mul(&root_rot[f]).to_axis_angle();
            poses[f * POSE_DIMS..f * POSE_DIMS + 3].copy_from_slice(&root.map(|v| v as f32));
        }
        Ok((
            SmplMotion::new(CANONICAL_FPS as f32, poses, trans)?,
            bridged,
        ))
    }
}

impl DuetLeader {
    /// `(T, 220)` conditioning features of a 30-fps leader in leader frames smoothed by `sigma`
    /// frames.
    pub fn encode(leader: &SmplMotion, sigma: f64) -> Result<Vec<f32>, ReprError> {
        check_fps("DuetLeader::encode", leader.fps, CANONICAL_FPS as f32)?;
        let t = leader.validate()?;
        let joints = leader.joints_world()?;
        let fps = f64::from(leader.fps);
        let headings: Vec<f64> = (0..t).map(|f| heading(&rot(leader, f, 0))).collect();
        let frames = leader_frames(leader, sigma);
        let mut out = Vec::with_capacity(t * Self::DIMS);
        for (f, &frame) in frames.iter().enumerate() {
            let n = if f + 1 < t { f + 1 } else { f };
            let p = if n == f && f > 0 { f - 1 } else { f };
            let (a, b) = if n == f { (p, f) } else { (f, n) };
            let inv = yaw(frame).transpose();
            let (pa, pb) = (pelvis(leader, a), pelvis(leader, b));
            let v = inv.mul_vec([(pb[0] - pa[0]) * fps, 0.0, (pb[2] - pa[2]) * fps]);
            let dyaw = wrap_angle(headings[b] - headings[a]) * fps;
            let root = pelvis(leader, f);
            out.extend([root[1], v[0], v[2], dyaw].map(|x| x as f32));
            push6(&mut out, &inv.mul(&rot(leader, f, 0)));
            for j in 1..SMPL_JOINTS {
                push6(&mut out, &rot(leader, f, j));
            }
            for j in 0..SMPL_JOINTS {
                let o = (f * SMPL_JOINTS + j) * 3;
                let w = [joints[o], joints[o + 1], joints[o + 2]].map(f64::from);
                let rel = inv.mul_vec([w[0] - root[0], w[1] - root[1], w[2] - root[2]]);
                out.extend(rel.map(|x| x as f32));
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dancer(t: usize, phase: f32, x0: f32) -> SmplMotion {
        let mut poses = vec![0f32; t * POSE_DIMS];
        let mut trans = Vec::new();
        for f in 0..t {
            let s = f as f32 * 0.1 + phase;
            for j in 0..SMPL_JOINTS {
                let o = f * POSE_DIMS + 3 * j;
                poses[o] = 0.3 * (s + j as f32).sin();
                poses[o + 1] = 0.2 * (0.7 * s - j as f32).cos();
                poses[o + 2] = 0.1 * (1.3 * s).sin();
            }
            // A turning pelvis.
            poses[f * POSE_DIMS + 1] = 0.05 * f as f32 + phase;
            trans.extend([x0 + 0.01 * f as f32, 0.9 + 0.02 * s.sin(), 0.5 * s.cos()]);
        }
        SmplMotion::new(30.0, poses, trans).unwrap()
    }

    #[test]
    fn follower_round_trips_in_the_leaders_world_frame() {
        let leader = dancer(40, 0.0, 0.0);
        let follower = dancer(40, 1.0, 0.8);
        for sigma in [0.0, 10.0] {
            let enc = DuetFollower::encode(&follower, &leader, sigma).unwrap();
            assert_eq!(enc.len(), 40 * DuetFollower::DIMS);
            let dec = DuetFollower::decode(&enc, &leader, sigma).unwrap();
            let (a, b) = (
                follower.joints_world().unwrap(),
                dec.joints_world().unwrap(),
            );
            let worst = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0f32, f32::max);
            assert!(worst < 1e-4, "sigma {sigma}: joints differ by {worst} m");
        }
    }

    #[test]
    fn follower_features_ignore_where_the_couple_stands() {
        let leader = dancer(20, 0.0, 0.0);
        let follower = dancer(20, 1.0, 0.8);
        let moved = |m: &SmplMotion| {
            let mut m = m.clone();
            for p in m.trans.chunks_exact_mut(3) {
                p[0] += 3.0;
                p[2] -= 2.0;
            }
            m
        };
        let a = DuetFollower::encode(&follower, &leader, 5.0).unwrap();
        let b = DuetFollower::encode(&moved(&follower), &moved(&leader), 5.0).unwrap();
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0f32, f32::max);
        assert!(worst < 1e-4);
        let la = DuetLeader::encode(&leader, 5.0).unwrap();
        let lb = DuetLeader::encode(&moved(&leader), 5.0).unwrap();
        assert_eq!(la.len(), 20 * DuetLeader::DIMS);
        let worst = la
            .iter()
            .zip(&lb)
            .map(|(x, y)| (x - y).abs())
            .fold(0f32, f32::max);
        assert!(worst < 1e-3);
    }

    #[test]
    fn smoothed_leader_frames_follow_the_turn_without_the_wobble() {
        let mut leader = dancer(200, 0.0, 0.0);
        // Heading: a steady turn of 0.02 rad/frame plus a ±0.5 rad wobble every 8 frames.
        for f in 0..200 {
            let h = 0.02 * f as f32 + 0.5 * (f as f32 * std::f32::consts::TAU / 8.0).sin();
            leader.poses[f * POSE_DIMS..f * POSE_DIMS + 3].copy_from_slice(&[0.0, h, 0.0]);
        }
        let raw = leader_frames(&leader, 0.0);
        let smooth = leader_frames(&leader, 30.0);
        for f in 60..140 {
            assert!((raw[f] - 0.02 * f as f64).abs() <= 0.5 + 1e-6);
            assert!(
                (smooth[f] - 0.02 * f as f64).abs() < 0.02,
                "frame {f}: {}",
                smooth[f]
            );
        }
    }

    #[test]
    fn couples_of_different_lengths_are_an_error() {
        let e =
            DuetFollower::encode(&dancer(20, 0.0, 0.0), &dancer(21, 0.0, 0.0), 0.0).unwrap_err();
        assert!(e.to_string().contains("same length"), "{e}");
    }
}
