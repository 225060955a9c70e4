//! Motion-level BVH: forward kinematics of a [`Bvh`] and conversion between SMPL motion
//! (axis-angle poses + pelvis translation) and BVH.
//!
//! # BVH forward kinematics
//! For every joint, local transform = translation(`offset` + position channels) ·
//! rotation(rotation channels composed in file order, degrees), e.g. `Zrotation Xrotation
//! Yrotation` gives `Rz·Rx·Ry` ([`Mat3::from_euler`]); world = parent world · local. Any
//! number of rotation channels in any order is accepted. Lengths are multiplied by `scale`.
//!
//! # SMPL ↔ BVH
//! [`smpl_to_bvh`] writes the SMPL 24 skeleton ([`Skeleton::smpl24`], EDGE joint names) in
//! **centimetres** (offsets × 100), which is what Blender's BVH importer and most DCC tools
//! expect for a human-sized rig. Joints are emitted in depth-first order (children in SMPL
//! index order), so the BVH joint order differs from the SMPL order; [`bvh_to_smpl`] maps back
//! by joint name.
//!
//! - Root channels: `Xposition Yposition Zposition Zrotation Xrotation Yrotation`; all other
//!   joints `Zrotation Xrotation Yrotation` ([`SMPL_BVH_EULER_ORDER`], the same `ZXY` order the
//!   CMU/Poser files use). Euler angles come from [`Mat3::to_euler`], which is exact at gimbal
//!   lock (middle angle ±90°: the last angle is set to 0 and the first absorbs the rotation).
//!   Each angle is then unwrapped by multiples of 360° to stay close to the previous frame, so
//!   curves in an animation editor do not jump by 360°; this does not change any rotation.
//! - **Root translation**: the root `OFFSET` is `0 0 0` and the root position channels are
//!   `trans × 100`, where `trans` is the **pelvis world position** in metres (the crate
//!   convention, [`dancegen_motion::conventions`]). This is *not* the `transl` parameter of the SMPL body
//!   model, which is offset from the pelvis by the body's rest pelvis position (for AIST++ the
//!   world pelvis is `(pelvis_rest + ...)·scaling + smpl_trans`); callers convert before.
//! - Leaf joints (head, toes, hands) get an `End Site` that continues the bone by half of its
//!   offset, so the leaf bones have a visible length in viewers; it does not affect the motion.

use crate::bvh::{Bvh, BvhError, BvhJoint, Channel};
use dancegen_motion::fk::{FkError, fk_axis_angle_f64};
use dancegen_motion::rotation::Mat3;
use dancegen_motion::skeleton::Skeleton;

/// Euler order of every SMPL joint in BVHs written by [`smpl_to_bvh`].
pub const SMPL_BVH_EULER_ORDER: &str = "ZXY";
/// Centimetres per metre: BVHs written by [`smpl_to_bvh`] are in centimetres.
pub const SMPL_BVH_UNITS_PER_METRE: f64 = 100.0;

/// Errors of the conversions in this module.
#[derive(Debug, thiserror::Error)]
pub enum BvhMotionError {
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error(transparent)]
    Fk(#[from] FkError),
    #[error("{what} has {got} values, expected a multiple of {per_frame} for {frames} frames")]
    Shape {
        what: &'static str,
        got: usize,
        per_frame: usize,
        frames: usize,
    },
    #[error("invalid frame rate {0}")]
    Fps(f64),
    #[error("BVH has no joint named {0:?}")]
    MissingJoint(String),
    #[error("BVH joint {joint:?} has parent {got:?}, expected {expected:?}")]
    WrongParent {
        joint: String,
        got: Option<String>,
        expected: Option<String>,
    },
    #[error("cannot infer the BVH length unit: mean bone length ratio to SMPL is {0}")]
    Units(f64),
    #[error("BVH hierarchy is not a valid skeleton: {0}")]
    Skeleton(#[from] dancegen_motion::skeleton::SkeletonError),
    /// No retargeting convention ([`crate::retarget::CONVENTIONS`]) finds all its joints.
    #[error(
        "BVH joint names match no known skeleton convention; {}; joints found: {}",
        missing_list(.missing),
        .found.join(", ")
    )]
    UnknownSkeleton {
        /// Every joint name of the file, in file order.
        found: Vec<String>,
        /// `(convention, the names it needs that the file lacks)` for every convention tried.
        missing: Vec<(&'static str, Vec<String>)>,
    },
    /// The rest pose cannot define a rest alignment (e.g. a zero-length bone).
    #[error("BVH rest pose: {0}")]
    RestPose(String),
}

fn missing_list(missing: &[(&'static str, Vec<String>)]) -> String {
    missing
        .iter()
        .map(|(c, m)| format!("{c} lacks {}", m.join(", ")))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Per-frame world transforms of a BVH: rotations and positions for every joint.
struct BvhFrameFk {
    rot: Vec<Mat3>,
    pos: Vec<[f64; 3]>,
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Local rotation of `joint` from one frame row (`row` = whole frame): rotation channels
/// composed in file order (degrees).
fn local_rotation(bvh: &Bvh, joint: usize, row: &[f64], start: usize) -> Mat3 {
    let mut r = Mat3::IDENTITY;
    for (k, c) in bvh.joints[joint].channels.iter().enumerate() {
        if c.is_rotation() {
            let a = row.get(start + k).copied().unwrap_or(0.0).to_radians();
            r = r.mul(&Mat3::from_axis_rotation(c.axis(), a));
        }
    }
    r
}

/// Local translation of `joint` (unscaled): offset + position channels.
fn local_translation(bvh: &Bvh, joint: usize, row: &[f64], start: usize) -> [f64; 3] {
    let j = &bvh.joints[joint];
    let mut t = j.offset;
    for (k, c) in j.channels.iter().enumerate() {
        if c.is_position() {
            t[c.axis()] += row.get(start + k).copied().unwrap_or(0.0);
        }
    }
    t
}

/// Channel start of every joint.
fn channel_starts(bvh: &Bvh) -> Vec<usize> {
    let mut starts = Vec::with_capacity(bvh.joints.len());
    let mut acc = 0;
    for j in &bvh.joints {
        starts.push(acc);
        acc += j.channels.len();
    }
    starts
}

/// World transforms of one frame. `bvh` must be valid (parents before children).
fn frame_fk(bvh: &Bvh, starts: &[usize], row: &[f64], scale: f64, out: &mut BvhFrameFk) {
    for (i, j) in bvh.joints.iter().enumerate() {
        let r = local_rotation(bvh, i, row, starts[i]);
        let t = scaled(local_translation(bvh, i, row, starts[i]), scale);
        match j.parent {
            Some(p) => {
                let pr = out.rot[p];
                out.pos[i] = add(out.pos[p], pr.mul_vec(t));
                out.rot[i] = pr.mul(&r);
            }
            None => {
                out.pos[i] = t;
                out.rot[i] = r;
            }
        }
    }
}

/// World joint positions of every frame: `(frames, joints, positions)` with `positions`
/// `frames × joints × 3`, row-major, in file units × `scale`. End sites are not included; see
/// [`bvh_world_positions_with_end_sites`].
pub fn bvh_world_positions(
    bvh: &Bvh,
    scale: f64,
) -> Result<(usize, usize, Vec<f64>), BvhMotionError> {
    bvh_world_positions_ext(bvh, scale, false)
}

/// Like [`bvh_world_positions`], with one extra point per joint that has an `End Site`,
/// appended after all joints in joint order: `(frames, joints + end sites, positions)`.
pub fn bvh_world_positions_with_end_sites(
    bvh: &Bvh,
    scale: f64,
) -> Result<(usize, usize, Vec<f64>), BvhMotionError> {
    bvh_world_positions_ext(bvh, scale, true)
}

/// Runs BVH FK over every frame, calling `visit(frame, &transforms)`; the one frame loop that
/// positions and world transforms are both read from.
fn for_each_frame_fk(
    bvh: &Bvh,
    scale: f64,
    mut visit: impl FnMut(usize, &BvhFrameFk),
) -> Result<(), BvhMotionError> {
    bvh.validate()?;
    let nj = bvh.joints.len();
    let starts = channel_starts(bvh);
    let nc = bvh.num_channels();
    let mut fk = BvhFrameFk {
        rot: vec![Mat3::IDENTITY; nj],
        pos: vec![[0.0; 3]; nj],
    };
    for f in 0..bvh.frames {
        let row = &bvh.data[f * nc..(f + 1) * nc];
        frame_fk(bvh, &starts, row, scale, &mut fk);
        visit(f, &fk);
    }
    Ok(())
}

fn bvh_world_positions_ext(
    bvh: &Bvh,
    scale: f64,
    end_sites: bool,
) -> Result<(usize, usize, Vec<f64>), BvhMotionError> {
    let nj = bvh.joints.len();
    let ends: Vec<(usize, [f64; 3])> = if end_sites {
        bvh.joints
            .iter()
            .enumerate()
            .filter_map(|(i, j)| j.end_site.map(|e| (i, e)))
            .collect()
    } else {
        Vec::new()
    };
    let np = nj + ends.len();
    let mut out = vec![0.0; bvh.frames * np * 3];
    for_each_frame_fk(bvh, scale, |f, fk| {
        let dst = &mut out[f * np * 3..(f + 1) * np * 3];
        for (i, p) in fk.pos.iter().enumerate() {
            dst[i * 3..i * 3 + 3].copy_from_slice(p);
        }
        for (k, &(i, e)) in ends.iter().enumerate() {
            let p = add(fk.pos[i], fk.rot[i].mul_vec(scaled(e, scale)));
            dst[(nj + k) * 3..(nj + k) * 3 + 3].copy_from_slice(&p);
        }
    })?;
    Ok((bvh.frames, np, out))
}

/// World rotations and positions of every frame (`frames × joints`, frame-major), in file
/// units × `scale`, for retargeting.
pub fn bvh_world_transforms(
    bvh: &Bvh,
    scale: f64,
) -> Result<(Vec<Mat3>, Vec<[f64; 3]>), BvhMotionError> {
    let nj = bvh.joints.len();
    let mut rots = Vec::with_capacity(bvh.frames * nj);
    let mut poss = Vec::with_capacity(bvh.frames * nj);
    for_each_frame_fk(bvh, scale, |_, fk| {
        rots.extend_from_slice(&fk.rot);
        poss.extend_from_slice(&fk.pos);
    })?;
    Ok((rots, poss))
}

/// Depth-first order of a skeleton (children in index order), root first.
fn depth_first(skel: &Skeleton) -> Vec<usize> {
    let n = skel.len();
    let mut order = Vec::with_capacity(n);
    let mut stack: Vec<usize> = (0..n).filter(|&j| skel.parent(j).is_none()).rev().collect();
    while let Some(j) = stack.pop() {
        order.push(j);
        let kids: Vec<usize> = (0..n).filter(|&c| skel.parent(c) == Some(j)).collect();
        stack.extend(kids.into_iter().rev());
    }
    order
}

fn euler_channels(order: &str) -> [Channel; 3] {
    let ch = |c: u8| match c {
        b'X' => Channel::Xrotation,
        b'Y' => Channel::Yrotation,
        _ => Channel::Zrotation,
    };
    let b = order.as_bytes();
    [ch(b[0]), ch(b[1]), ch(b[2])]
}

/// Adds multiples of 360 to `a` so it is within 180 of `prev`.
fn unwrap_deg(a: f64, prev: f64) -> f64 {
    a - 360.0 * ((a - prev) / 360.0).round()
}

/// SMPL 24 motion → BVH in centimetres (see the module documentation for the layout).
///
/// `poses`: `T × 72` axis-angle (radians, SMPL joint order); `trans`: `T × 3` pelvis world
/// position in metres; `fps` > 0.
pub fn smpl_to_bvh(poses: &[f32], trans: &[f32], fps: f64) -> Result<Bvh, BvhMotionError> {
    skeleton_motion_to_bvh(&Skeleton::smpl24(), poses, trans, fps)
}

/// [`smpl_to_bvh`] for any skeleton with axis-angle local rotations (`T × 3J`), metres in,
/// centimetres out.
pub fn skeleton_motion_to_bvh(
    skel: &Skeleton,
    poses: &[f32],
    trans: &[f32],
    fps: f64,
) -> Result<Bvh, BvhMotionError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(BvhMotionError::Fps(fps));
    }
    let nj = skel.len();
    let frames = trans.len() / 3;
    if !trans.len().is_multiple_of(3) {
        return Err(BvhMotionError::Shape {
            what: "trans",
            got: trans.len(),
            per_frame: 3,
            frames,
        });
    }
    if poses.len() != frames * nj * 3 {
        return Err(BvhMotionError::Shape {
            what: "poses",
            got: poses.len(),
            per_frame: nj * 3,
            frames,
        });
    }
    let order = depth_first(skel);
    let mut new_index = vec![0usize; nj];
    for (k, &j) in order.iter().enumerate() {
        new_index[j] = k;
    }
    let has_children = skel.has_children();
    let rot_channels = euler_channels(SMPL_BVH_EULER_ORDER);
    let u = SMPL_BVH_UNITS_PER_METRE;
    let joints: Vec<BvhJoint> = order
        .iter()
        .map(|&j| {
            let parent = skel.parent(j);
            let mut channels = Vec::with_capacity(6);
            if parent.is_none() {
                channels.extend([Channel::Xposition, Channel::Yposition, Channel::Zposition]);
            }
            channels.extend(rot_channels);
            let off = skel.offsets()[j];
            BvhJoint {
                name: skel.names()[j].clone(),
                parent: parent.map(|p| new_index[p]),
                offset: if parent.is_none() {
                    [0.0; 3]
                } else {
                    scaled(off, u)
                },
                channels,
                end_site: (!has_children[j]).then(|| scaled(off, 0.5 * u)),
            }
        })
        .collect();
    let nc: usize = joints.iter().map(|j| j.channels.len()).sum();
    let mut data = Vec::with_capacity(frames * nc);
    let mut prev: Vec<[f64; 3]> = vec![[0.0; 3]; nj];
    for f in 0..frames {
        for &j in &order {
            if skel.parent(j).is_none() {
                for a in 0..3 {
                    data.push(f64::from(trans[f * 3 + a]) * u);
                }
            }
            let b = (f * nj + j) * 3;
            let aa = [
                f64::from(poses[b]),
                f64::from(poses[b + 1]),
                f64::from(poses[b + 2]),
            ];
            let e = Mat3::from_axis_angle(aa)
                .to_euler(SMPL_BVH_EULER_ORDER)
                .expect("valid order");
            for a in 0..3 {
                let mut d = e[a].to_degrees();
                if f > 0 {
                    d = unwrap_deg(d, prev[j][a]);
                }
                prev[j][a] = d;
                data.push(d);
            }
        }
    }
    Ok(Bvh {
        joints,
        frame_time: 1.0 / fps,
        frames,
        data,
    })
}

/// BVH with the SMPL 24 skeleton (joints found by their [`Skeleton::smpl24`] names, any file
/// order, any Euler orders) → `(poses T × 72 axis-angle, trans T × 3 pelvis world position in
/// metres)`. The length unit is inferred from the bone lengths (centimetres, as written by
/// [`smpl_to_bvh`], or metres); see [`bvh_to_smpl_with_units`] to state it.
///
/// The file's own offsets are otherwise ignored: SMPL FK uses the SMPL rest skeleton.
pub fn bvh_to_smpl(bvh: &Bvh) -> Result<(Vec<f32>, Vec<f32>), BvhMotionError> {
    bvh_to_skeleton_motion(bvh, &Skeleton::smpl24(), None)
}

/// [`bvh_to_smpl`] with an explicit length unit: BVH units per metre (100 for centimetres).
pub fn bvh_to_smpl_with_units(
    bvh: &Bvh,
    units_per_metre: f64,
) -> Result<(Vec<f32>, Vec<f32>), BvhMotionError> {
    bvh_to_skeleton_motion(bvh, &Skeleton::smpl24(), Some(units_per_metre))
}

/// Generic form of [`bvh_to_smpl`]: maps the joints of `skel` by name; each mapped joint's
/// BVH parent must be the joint named like its skeleton parent. `units_per_metre = None`
/// infers 1 or 100 from the ratio of bone lengths (BVH / skeleton).
pub fn bvh_to_skeleton_motion(
    bvh: &Bvh,
    skel: &Skeleton,
    units_per_metre: Option<f64>,
) -> Result<(Vec<f32>, Vec<f32>), BvhMotionError> {
    bvh.validate()?;
    let nj = skel.len();
    let mut map = Vec::with_capacity(nj);
    for name in skel.names() {
        map.push(
            bvh.joint_index(name)
                .ok_or_else(|| BvhMotionError::MissingJoint(name.clone()))?,
        );
    }
    for j in 0..nj {
        let got = bvh.joints[map[j]].parent;
        let expected = skel.parent(j).map(|p| map[p]);
        if got != expected {
            let name = |i: Option<usize>| i.map(|i| bvh.joints[i].name.clone());
            return Err(BvhMotionError::WrongParent {
                joint: skel.names()[j].clone(),
                got: name(got),
                expected: name(expected),
            });
        }
    }
    let upm = match units_per_metre {
        Some(u) => u,
        None => {
            let (mut sb, mut ss) = (0.0, 0.0);
            for (j, &bj) in map.iter().enumerate() {
                if skel.parent(j).is_some() {
                    sb += norm(bvh.joints[bj].offset);
                    ss += norm(skel.offsets()[j]);
                }
            }
            let ratio = if ss > 0.0 { sb / ss } else { f64::NAN };
            if (0.3..3.0).contains(&ratio) {
                1.0
            } else if (30.0..300.0).contains(&ratio) {
                100.0
            } else {
                return Err(BvhMotionError::Units(ratio));
            }
        }
    };
    if !(upm.is_finite() && upm > 0.0) {
        return Err(BvhMotionError::Units(upm));
    }
    let starts = channel_starts(bvh);
    let nc = bvh.num_channels();
    let root = map[skel.parents().iter().position(Option::is_none).unwrap_or(0)];
    let mut poses = Vec::with_capacity(bvh.frames * nj * 3);
    let mut trans = Vec::with_capacity(bvh.frames * 3);
    let empty: [f64; 0] = [];
    for f in 0..bvh.frames {
        let row = if nc == 0 {
            &empty[..]
        } else {
            &bvh.data[f * nc..(f + 1) * nc]
        };
        for &bj in &map {
            let aa = local_rotation(bvh, bj, row, starts[bj]).to_axis_angle();
            poses.extend(aa.iter().map(|&v| v as f32));
        }
        let t = local_translation(bvh, root, row, starts[root]);
        trans.extend(t.iter().map(|&v| (v / upm) as f32));
    }
    Ok((poses, trans))
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// SMPL FK in `f64` of `f32` poses / translation, a convenience for comparisons:
/// `T × 24 × 3` metres.
pub fn smpl_fk_f64(poses: &[f32], trans: &[f32]) -> Result<Vec<f64>, BvhMotionError> {
    let p: Vec<f64> = poses.iter().map(|&v| f64::from(v)).collect();
    let t: Vec<f64> = trans.iter().map(|&v| f64::from(v)).collect();
    Ok(fk_axis_angle_f64(&Skeleton::smpl24(), &p, &t)?)
}

/// Any BVH as a [`Skeleton`] plus axis-angle local rotations (`T × 3J`) and root translation
/// (`T × 3`), all lengths multiplied by `scale` — the form the glTF exporter takes.
///
/// End sites are dropped and position channels of non-root joints are ignored (a skeleton has
/// fixed bone lengths); the root translation is the root's offset plus its position channels.
pub fn bvh_skeleton_motion(
    bvh: &Bvh,
    scale: f64,
) -> Result<(Skeleton, Vec<f32>, Vec<f32>), BvhMotionError> {
    bvh.validate()?;
    let names: Vec<String> = bvh.joints.iter().map(|j| j.name.clone()).collect();
    let parents: Vec<Option<usize>> = bvh.joints.iter().map(|j| j.parent).collect();
    let offsets: Vec<[f64; 3]> = bvh.joints.iter().map(|j| scaled(j.offset, scale)).collect();
    let skel = Skeleton::new(names, parents, offsets)?;
    let starts = channel_starts(bvh);
    let nc = bvh.num_channels();
    let nj = bvh.joints.len();
    let mut poses = Vec::with_capacity(bvh.frames * nj * 3);
    let mut trans = Vec::with_capacity(bvh.frames * 3);
    for f in 0..bvh.frames {
        let row = &bvh.data[f * nc..(f + 1) * nc];
        for (j, &start) in starts.iter().enumerate() {
            let aa = local_rotation(bvh, j, row, start).to_axis_angle();
            poses.extend(aa.iter().map(|&v| v as f32));
        }
        let root = scaled(local_translation(bvh, 0, row, starts[0]), scale);
        trans.extend(root.iter().map(|&v| v as f32));
    }
    Ok((skel, poses, trans))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_first_smpl() {
        let order = depth_first(&Skeleton::smpl24());
        assert_eq!(order.len(), 24);
        assert_eq!(&order[..5], &[0, 1, 4, 7, 10]);
    }

    #[test]
    fn gimbal_lock_round_trip() {
        // X = 90° exactly: ZXY gimbal lock.
        let r = Mat3::from_euler("ZXY", [0.3, std::f64::consts::FRAC_PI_2, -0.7]).unwrap();
        let aa = r.to_axis_angle();
        let poses: Vec<f32> = (0..24).flat_map(|_| aa.iter().map(|&v| v as f32)).collect();
        let trans = [0.1f32, 0.9, -0.2];
        let bvh = smpl_to_bvh(&poses, &trans, 30.0).unwrap();
        let (p2, t2) = bvh_to_smpl(&bvh).unwrap();
        let a = smpl_fk_f64(&poses, &trans).unwrap();
        let b = smpl_fk_f64(&p2, &t2).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-6, "{x} {y}");
        }
    }
}
