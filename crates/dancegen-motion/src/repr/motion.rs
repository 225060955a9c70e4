//! The canonical in-memory motion: SMPL 24 local axis-angle + pelvis world position.
//!
//! Layout (row-major, `f32`):
//! - `poses`: `(T, 24, 3)` Rodrigues vectors (radians), **local** (parent-relative) rotations in
//!   SMPL 24 order (anchors.md C.4); the root's rotation is its world orientation.
//! - `trans`: `(T, 3)` **pelvis (joint 0) world position**, metres, Y-up
//!   ([`crate::conventions`]); FK puts joint 0 exactly there.
//! - `fps`: stored with the motion, never assumed.
//!
//! Operations follow the references: 60 → 30 fps by striding (EDGE, anchors.md C.2),
//! left/right mirroring by joint permutation + axis-angle (x, −y, −z) + translation x negation
//! (LODGE `SMPL_JOINTS_FLIP_PERM`, C.3), EDGE velocity contacts (C.2) and LODGE height contacts
//! (C.3), LODGE's frame-0 toe grounding (A.6 / C.3).

use super::{ReprError, frames_of};
use crate::fk::fk_axis_angle_f32;
use crate::rotation::Quat;
use crate::skeleton::{SMPL24_MIRROR, Skeleton};
use crate::smoothing::{Ends, gaussian_smooth};

/// Number of SMPL joints in [`SmplMotion`].
pub const SMPL_JOINTS: usize = 24;
/// Values per frame of `poses`.
pub const POSE_DIMS: usize = SMPL_JOINTS * 3;
/// Foot joints in contact-label order: left ankle 7, right ankle 8, left toe 10, right toe 11
/// (EDGE `dance_dataset.py`, LODGE `preprocess.py`; anchors.md C.2, C.3).
pub const FOOT_JOINTS: [usize; 4] = [7, 8, 10, 11];
/// EDGE's velocity-contact threshold: per-frame displacement norm in metres (C.2).
pub const EDGE_CONTACT_VELOCITY: f32 = 0.01;
/// LODGE's height-contact thresholds (metres above the ground, C.3): ankle, toe.
pub const LODGE_CONTACT_HEIGHT: (f32, f32) = (0.12, 0.05);

/// SMPL rest pelvis of AIST++ in metres: AIST++ world joints are
/// `FK(poses) + pelvis_rest + smpl_trans / smpl_scaling` (shared/data/README.md).
pub const AISTPP_PELVIS_REST: [f32; 3] = [-0.0021, -0.2444, 0.0282];

/// How [`SmplMotion::put_on_ground_with`] picks the height that becomes y = 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GroundMode {
    /// Lowest of the foot joints 7, 8, 10, 11 over **all frames** (default of
    /// [`SmplMotion::put_on_ground`]): no foot ever goes below the floor.
    #[default]
    ClipMinFeet,
    /// LODGE / FineDance (anchors.md A.6, C.3): frame-0 toe heights (joints 10, 11); their mean
    /// if they differ by less than 2 cm, else their minimum.
    FirstFrameToes,
    /// The [`SUPPORT_PERCENTILE`]th percentile over frames of the lowest foot joint: the height
    /// the supporting foot stands at, robust to the few frames where retargeting or capture
    /// noise drops a foot far below the floor (CMU salsa retargeted to SMPL has its per-frame
    /// lowest foot ~10 cm above the clip minimum in half the frames).
    SupportFeet,
}

/// Percentile of [`GroundMode::SupportFeet`].
pub const SUPPORT_PERCENTILE: f32 = 10.0;

/// A foot joint moving slower than this (m/s, 3D) is planted, for [`planted_floor_height`]. In
/// the real takes at their true rates (salsa, CMU 05 and 85, 30 fps) the slower foot joint's
/// speed has its lower quartile at 0.04-0.15 m/s (resting feet: capture noise, pivots) and its
/// upper quartile at 0.8-2.7 m/s (stepping feet).
pub const PLANTED_SPEED_MS: f32 = 0.25;

/// Share of frames with a planted lowest foot joint below which [`planted_floor_height`] has
/// too little to go on (a take that is mostly jumps, spins or floor work).
pub const MIN_PLANTED_SHARE: f32 = 0.1;

/// The floor a dancer stands on, from world joints `(T, 24, 3)` at `fps`: the median height of
/// the lowest foot joint (7, 8, 10, 11) over the frames in which that joint is planted (moves
/// slower than [`PLANTED_SPEED_MS`] to the next frame). A standing or stepping dancer's lowest
/// foot joint is its support foot, which rests on the floor, so its height when still is the
/// floor; the median ignores the few frames where capture or retargeting noise drops a foot
/// through the floor, and jumps (the lowest foot moving) do not count. `None` when fewer than
/// [`MIN_PLANTED_SHARE`] of the frames have a planted lowest foot joint.
///
/// Why not the clip minimum or a low percentile ([`GroundMode`]): both put the floor where the
/// feet are lowest, not where they rest. On the CMU salsa takes retargeted to SMPL at their
/// true 60 fps the planted median is 0.6-3.1 cm (median 1.7 cm) above the 10th percentile, so
/// grounding at the 10th percentile leaves the resting feet that far above the floor.
pub fn planted_floor_height(joints: &[f32], fps: f32) -> Option<f32> {
    let per_frame = planted_lowest_foot(joints, fps)?;
    let t = per_frame.len() + 1;
    let mut planted: Vec<f32> = per_frame.into_iter().flatten().collect();
    if (planted.len() as f32) < MIN_PLANTED_SHARE * t as f32 {
        return None;
    }
    planted.sort_by(f32::total_cmp);
    let n = planted.len();
    Some(if n % 2 == 1 {
        planted[n / 2]
    } else {
        0.5 * (planted[n / 2 - 1] + planted[n / 2])
    })
}

/// For frames `0..T − 1` of world joints `(T, 24, 3)` at `fps`: the height of the lowest foot
/// joint (7, 8, 10, 11) where it is planted (moves slower than [`PLANTED_SPEED_MS`] to the next
/// frame), `None` where it moves. `None` for fewer than 2 frames or an unusable rate. The one
/// definition of a planted frame behind [`planted_floor_height`] and [`planted_floor_track`].
fn planted_lowest_foot(joints: &[f32], fps: f32) -> Option<Vec<Option<f32>>> {
    let t = joints.len() / (SMPL_JOINTS * 3);
    if t < 2 || !(fps.is_finite() && fps > 0.0) {
        return None;
    }
    let at = |f: usize, j: usize| -> [f32; 3] {
        let i = (f * SMPL_JOINTS + j) * 3;
        [joints[i], joints[i + 1], joints[i + 2]]
    };
    let step = PLANTED_SPEED_MS / fps;
    Some(
        (0..t - 1)
            .map(|f| {
                let j = FOOT_JOINTS
                    .into_iter()
                    .min_by(|&a, &b| at(f, a)[1].total_cmp(&at(f, b)[1]))?;
                let (p, q) = (at(f, j), at(f + 1, j));
                let d =
                    ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt();
                (d < step).then_some(p[1])
            })
            .collect(),
    )
}

/// Gaussian σ (seconds) over which [`planted_floor_track`] lets the floor under a generated
/// dance change. Real captures stand on one floor; a generated long dance can raise or lower
/// its root against its legs from one stretch to the next (lodgepp-small on feelings.ogg
/// 60-90 s: the pelvis 0.73 m above the floor with the feet on it in one stretch, 1.08 m with
/// the feet 0.2 m up in another, the legs equally bent), and one floor for the whole clip then
/// leaves the feet hanging in most of it. Half a second is longer than a step's contact and
/// shorter than those stretches; jumps do not move it, as their frames have no planted foot.
pub const FLOOR_TRACK_SECONDS: f64 = 0.5;

/// Longest a dancer is off the floor: a jump 0.3 m high is in the air for 0.49 s
/// (`2·√(2h/g)`), and dance jumps are rarely higher. A generated dancer whose lowest foot keeps
/// moving for longer than this (it slides under a travelling root: a `--path`, a fast turn)
/// stands on that foot; it does not fly. Measured on a solo dance following a path of 2.5 m
/// in 6 s (feelings.ogg 0-20 s, seed 1): without this rule the feet hung 7-9 cm up for a
/// second and 13.5 % of the frames floated.
pub const MAX_FLIGHT_SECONDS: f64 = 0.5;

/// The floor under a dancer frame by frame, from world joints `(T, 24, 3)` at `fps`: the
/// height of the planted lowest foot joint (the frames [`planted_floor_height`] uses), and in
/// a stretch without one longer than [`MAX_FLIGHT_SECONDS`] the lowest foot joint's height
/// however it moves, averaged over a Gaussian window of [`FLOOR_TRACK_SECONDS`] around each
/// frame (a frame with no such sample within three σ takes the whole clip's planted median).
/// `None` when fewer than [`MIN_PLANTED_SHARE`] of the frames have a planted lowest foot
/// joint.
///
/// For generated dances, whose root height can drift against their legs. For real takes it
/// follows their one floor to within capture noise, so they are put on the floor with
/// [`SmplMotion::put_feet_on_floor`].
pub fn planted_floor_track(joints: &[f32], fps: f32) -> Option<Vec<f32>> {
    let whole = planted_floor_height(joints, fps)?;
    let per_frame = planted_lowest_foot(joints, fps)?;
    // (height, 1) where the lowest foot joint is planted, (0, 0) elsewhere; the last frame has
    // no next frame to tell.
    let mut height = vec![0.0f64; per_frame.len() + 1];
    let mut weight = vec![0.0f64; per_frame.len() + 1];
    for (f, h) in per_frame.iter().enumerate() {
        if let Some(h) = h {
            height[f] = f64::from(*h);
            weight[f] = 1.0;
        }
    }
    // No flight lasts longer: there the lowest foot is on the floor, sliding.
    let longest = (MAX_FLIGHT_SECONDS * f64::from(fps)).round() as usize;
    let lowest = |f: usize| {
        FOOT_JOINTS
            .iter()
            .map(|&j| joints[(f * SMPL_JOINTS + j) * 3 + 1])
            .fold(f32::INFINITY, f32::min)
    };
    let mut f = 0;
    while f < per_frame.len() {
        if per_frame[f].is_some() {
            f += 1;
            continue;
        }
        let start = f;
        while f < per_frame.len() && per_frame[f].is_none() {
            f += 1;
        }
        if f - start > longest {
            for g in start..f {
                height[g] = f64::from(lowest(g));
                weight[g] = 1.0;
            }
        }
    }
    let sigma = FLOOR_TRACK_SECONDS * f64::from(fps);
    let num = gaussian_smooth(&height, sigma, Ends::Renormalise);
    let den = gaussian_smooth(&weight, sigma, Ends::Renormalise);
    Some(
        num.iter()
            .zip(&den)
            .map(|(n, d)| if *d > 1e-3 { (n / d) as f32 } else { whole })
            .collect(),
    )
}

/// SMPL 24 motion, see the module documentation for the exact layout.
#[derive(Debug, Clone, PartialEq)]
pub struct SmplMotion {
    pub fps: f32,
    /// `(T, 24, 3)` local axis-angle.
    pub poses: Vec<f32>,
    /// `(T, 3)` pelvis world position, metres, Y-up.
    pub trans: Vec<f32>,
}

impl SmplMotion {
    /// Builds a motion, checking that `poses` is `(T, 72)` and `trans` is `(T, 3)`.
    pub fn new(fps: f32, poses: Vec<f32>, trans: Vec<f32>) -> Result<Self, ReprError> {
        let m = SmplMotion { fps, poses, trans };
        m.validate()?;
        Ok(m)
    }

    /// Checks the buffer shapes; returns the frame count.
    pub fn validate(&self) -> Result<usize, ReprError> {
        let t = frames_of("SmplMotion poses", &self.poses, POSE_DIMS)?;
        let tt = frames_of("SmplMotion trans", &self.trans, 3)?;
        if t != tt {
            return Err(ReprError::FrameMismatch {
                what: "SmplMotion",
                poses: t,
                trans: tt,
            });
        }
        if !self.fps.is_finite() || self.fps <= 0.0 {
            return Err(ReprError::Invalid(format!(
                "fps {} is not positive",
                self.fps
            )));
        }
        Ok(t)
    }

    /// Number of frames (`trans.len() / 3`).
    pub fn frames(&self) -> usize {
        self.trans.len() / 3
    }

    /// Axis-angle of joint `j` at frame `t`.
    pub fn joint_aa(&self, t: usize, j: usize) -> [f32; 3] {
        let o = t * POSE_DIMS + j * 3;
        [self.poses[o], self.poses[o + 1], self.poses[o + 2]]
    }

    /// World joint positions `(T, 24, 3)` via FK on the EDGE SMPL skeleton (C.4).
    pub fn joints_world(&self) -> Result<Vec<f32>, ReprError> {
        self.joints_world_with(&Skeleton::smpl24())
    }

    /// World joint positions `(T, J, 3)` on a caller-chosen 24-joint skeleton.
    pub fn joints_world_with(&self, skeleton: &Skeleton) -> Result<Vec<f32>, ReprError> {
        self.validate()?;
        Ok(fk_axis_angle_f32(skeleton, &self.poses, &self.trans)?)
    }

    /// Keeps every `k`-th frame starting at frame 0, `fps / k` (EDGE's 60 → 30 with `k = 2`).
    ///
    /// # Panics
    /// If `k == 0`.
    pub fn resample_stride(&self, k: usize) -> SmplMotion {
        assert!(k > 0, "resample_stride: k must be positive");
        let t = self.frames();
        let mut poses = Vec::with_capacity(t.div_ceil(k) * POSE_DIMS);
        let mut trans = Vec::with_capacity(t.div_ceil(k) * 3);
        for f in (0..t).step_by(k) {
            poses.extend_from_slice(&self.poses[f * POSE_DIMS..(f + 1) * POSE_DIMS]);
            trans.extend_from_slice(&self.trans[f * 3..(f + 1) * 3]);
        }
        SmplMotion {
            fps: self.fps / k as f32,
            poses,
            trans,
        }
    }

    /// Resamples to `target` fps over the same time span: output frame `i` is at time
    /// `i / target`; joint rotations are slerped (quaternion, shortest arc), the root position is
    /// interpolated linearly. Output frames that fall exactly on an input frame copy it bit for
    /// bit, so integer ratios equal [`SmplMotion::resample_stride`].
    ///
    /// # Panics
    /// If `target` is not positive.
    pub fn resample_fps(&self, target: f32) -> SmplMotion {
        assert!(target > 0.0, "resample_fps: target must be positive");
        let t = self.frames();
        if t == 0 {
            return SmplMotion {
                fps: target,
                poses: Vec::new(),
                trans: Vec::new(),
            };
        }
        let ratio = self.fps as f64 / target as f64;
        let n = ((t - 1) as f64 / ratio + 1e-9).floor() as usize + 1;
        let mut poses = Vec::with_capacity(n * POSE_DIMS);
        let mut trans = Vec::with_capacity(n * 3);
        for i in 0..n {
            let src = i as f64 * self.fps as f64 / target as f64;
            let i0 = (src + 1e-9).floor() as usize;
            let a = src - i0 as f64;
            if a.abs() < 1e-9 || i0 + 1 >= t {
                let i0 = i0.min(t - 1);
                poses.extend_from_slice(&self.poses[i0 * POSE_DIMS..(i0 + 1) * POSE_DIMS]);
                trans.extend_from_slice(&self.trans[i0 * 3..(i0 + 1) * 3]);
                continue;
            }
            for j in 0..SMPL_JOINTS {
                let q0 = Quat::from_axis_angle(self.joint_aa(i0, j).map(f64::from));
                let q1 = Quat::from_axis_angle(self.joint_aa(i0 + 1, j).map(f64::from));
                let aa = Quat::slerp(q0, q1, a).to_axis_angle();
                poses.extend(aa.map(|v| v as f32));
            }
            for c in 0..3 {
                let p0 = self.trans[i0 * 3 + c] as f64;
                let p1 = self.trans[(i0 + 1) * 3 + c] as f64;
                trans.push((p0 + (p1 - p0) * a) as f32);
            }
        }
        SmplMotion {
            fps: target,
            poses,
            trans,
        }
    }

    /// Left/right mirror across the YZ plane (anchors.md C.3, LODGE): joint `j` takes joint
    /// `SMPL24_MIRROR[j]`'s rotation with axis-angle `(x, y, z) → (x, −y, −z)`; the root
    /// position's x is negated. On a left/right-symmetric skeleton the mirrored world joints are
    /// exactly the x-negated, swapped original joints; the SMPL offsets of C.4 are only
    /// approximately symmetric (a few millimetres).
    pub fn mirror(&self) -> SmplMotion {
        let t = self.frames();
        let mut poses = vec![0f32; self.poses.len()];
        for f in 0..t {
            for (j, &src) in SMPL24_MIRROR.iter().enumerate() {
                let s = self.joint_aa(f, src);
                let o = f * POSE_DIMS + j * 3;
                poses[o..o + 3].copy_from_slice(&[s[0], -s[1], -s[2]]);
            }
        }
        let trans = self
            .trans
            .chunks_exact(3)
            .flat_map(|p| [-p[0], p[1], p[2]])
            .collect();
        SmplMotion {
            fps: self.fps,
            poses,
            trans,
        }
    }

    /// Height (y) that [`GroundMode`] maps to the floor, from world joints `(T, 24, 3)`.
    pub fn ground_height(joints: &[f32], mode: GroundMode) -> f32 {
        let y = |f: usize, j: usize| joints[(f * SMPL_JOINTS + j) * 3 + 1];
        let t = joints.len() / (SMPL_JOINTS * 3);
        if t == 0 {
            return 0.0;
        }
        match mode {
            GroundMode::ClipMinFeet => (0..t)
                .flat_map(|f| FOOT_JOINTS.map(|j| y(f, j)))
                .fold(f32::INFINITY, f32::min),
            GroundMode::SupportFeet => {
                let mut lows: Vec<f32> = (0..t)
                    .map(|f| {
                        FOOT_JOINTS
                            .map(|j| y(f, j))
                            .into_iter()
                            .fold(f32::INFINITY, f32::min)
                    })
                    .collect();
                lows.sort_by(f32::total_cmp);
                let k = ((SUPPORT_PERCENTILE / 100.0) * (t - 1) as f32).round() as usize;
                lows[k.min(t - 1)]
            }
            GroundMode::FirstFrameToes => {
                let (l, r) = (y(0, 10), y(0, 11));
                if (l - r).abs() < 0.02 {
                    (l + r) / 2.0
                } else {
                    l.min(r)
                }
            }
        }
    }

    /// Shifts the root so the lowest foot joint (7, 8, 10, 11) over the whole clip is at y = 0
    /// ([`GroundMode::ClipMinFeet`]). Returns the height that was subtracted.
    pub fn put_on_ground(&mut self) -> Result<f32, ReprError> {
        self.put_on_ground_with(GroundMode::ClipMinFeet)
    }

    /// Shifts the root vertically so the height chosen by `mode` is y = 0. Returns the height
    /// that was subtracted from every root y.
    pub fn put_on_ground_with(&mut self, mode: GroundMode) -> Result<f32, ReprError> {
        let h = Self::ground_height(&self.joints_world()?, mode);
        for p in self.trans.chunks_exact_mut(3) {
            p[1] -= h;
        }
        Ok(h)
    }

    /// Shifts the root vertically so the floor the dancer stands on is y = 0: the planted
    /// feet's floor ([`planted_floor_height`]), or [`GroundMode::SupportFeet`] for a take with
    /// too few planted frames. Returns the height that was subtracted.
    pub fn put_feet_on_floor(&mut self) -> Result<f32, ReprError> {
        let joints = self.joints_world()?;
        let h = planted_floor_height(&joints, self.fps)
            .unwrap_or_else(|| Self::ground_height(&joints, GroundMode::SupportFeet));
        for p in self.trans.chunks_exact_mut(3) {
            p[1] -= h;
        }
        Ok(h)
    }

    /// Shifts the root vertically, frame by frame, so the floor the dancer's planted feet
    /// stand on ([`planted_floor_track`]) is y = 0: for generated dances, whose root height can
    /// drift against their legs. A motion with too few planted frames gets one shift,
    /// [`GroundMode::SupportFeet`]. Returns the largest and smallest shift subtracted.
    pub fn put_feet_on_tracked_floor(&mut self) -> Result<(f32, f32), ReprError> {
        let joints = self.joints_world()?;
        let track = planted_floor_track(&joints, self.fps).unwrap_or_else(|| {
            vec![Self::ground_height(&joints, GroundMode::SupportFeet); self.frames()]
        });
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (p, h) in self.trans.chunks_exact_mut(3).zip(&track) {
            p[1] -= h;
            lo = lo.min(*h);
            hi = hi.max(*h);
        }
        Ok((hi, lo))
    }

    /// EDGE velocity contacts `(T, 4)` in [`FOOT_JOINTS`] order (anchors.md C.2): 1 where the
    /// joint's per-frame 3D displacement `‖p[t+1] − p[t]‖ < threshold` (metres per frame, EDGE
    /// uses [`EDGE_CONTACT_VELOCITY`] at 30 fps), else 0. The last frame has velocity 0 and is
    /// therefore always 1, as in EDGE.
    pub fn foot_contacts_velocity(&self, threshold: f32) -> Result<Vec<f32>, ReprError> {
        let joints = self.joints_world()?;
        Ok(contacts_velocity(&joints, threshold))
    }

    /// LODGE height contacts `(T, 4)` in [`FOOT_JOINTS`] order (anchors.md C.3): ankle
    /// `y < ankle`, toe `y < toe` in the motion's current frame (ground the motion first; LODGE
    /// uses [`LODGE_CONTACT_HEIGHT`] after [`GroundMode::FirstFrameToes`]).
    pub fn foot_contacts_height(&self, ankle: f32, toe: f32) -> Result<Vec<f32>, ReprError> {
        let joints = self.joints_world()?;
        Ok(contacts_height(&joints, ankle, toe))
    }
}

/// [`SmplMotion::foot_contacts_velocity`] on precomputed joints `(T, 24, 3)`.
pub fn contacts_velocity(joints: &[f32], threshold: f32) -> Vec<f32> {
    let t = joints.len() / (SMPL_JOINTS * 3);
    let p = |f: usize, j: usize| {
        let o = (f * SMPL_JOINTS + j) * 3;
        [joints[o], joints[o + 1], joints[o + 2]]
    };
    let mut out = Vec::with_capacity(t * 4);
    for f in 0..t {
        for j in FOOT_JOINTS {
            let v = if f + 1 < t {
                let (a, b) = (p(f, j), p(f + 1, j));
                (0..3).map(|c| (b[c] - a[c]).powi(2)).sum::<f32>().sqrt()
            } else {
                0.0
            };
            out.push(if v < threshold { 1.0 } else { 0.0 });
        }
    }
    out
}

/// [`SmplMotion::foot_contacts_height`] on precomputed joints `(T, 24, 3)`.
pub fn contacts_height(joints: &[f32], ankle: f32, toe: f32) -> Vec<f32> {
    let t = joints.len() / (SMPL_JOINTS * 3);
    let mut out = Vec::with_capacity(t * 4);
    for f in 0..t {
        for (k, j) in FOOT_JOINTS.into_iter().enumerate() {
            let y = joints[(f * SMPL_JOINTS + j) * 3 + 1];
            let th = if k < 2 { ankle } else { toe };
            out.push(if y < th { 1.0 } else { 0.0 });
        }
    }
    out
}
