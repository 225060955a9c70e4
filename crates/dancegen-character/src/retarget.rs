//! Putting an SMPL 24 dance on the character: world-rotation transfer with rest-pose alignment.
//!
//! # Rotations
//! SMPL's rest pose has identity world rotations, so SMPL joint `j`'s world rotation `G_s[j](t)`
//! (from [`dancegen_motion::forward_kinematics`]) is also how far it has turned from rest. Every mapped
//! character bone `k` follows its joint:
//!
//! `G_t[k](t) = F · G_s[j](t) · Fᵀ · C_k · W_k`
//!
//! - `W_k` is the bone's rest world rotation (the rotation-only chain of `scene.rs`);
//! - `C_k` turns the character's rest pose onto SMPL's (the "alignment" below), so at SMPL's rest
//!   pose every mapped bone points where SMPL's bone points — an A-pose character with a T-pose
//!   dance lifts its arms by exactly the difference;
//! - `F` is the facing correction (below); conjugating by it replays the dance's turns about the
//!   character's own axes.
//!
//! Local rotations are `W_parent(t)ᵀ · G_t[k](t)`; unmapped bones keep their rest local rotation
//! (twist bones, fingers, IK poles follow their parents).
//!
//! # Alignment
//! Bones are visited hips first, each limb and the spine from the body out. The hips' `C` takes
//! the character's hip axis (right thigh → left thigh) onto SMPL's and then its trunk direction
//! (hip centre → upper-arm centre) into SMPL's trunk plane. Every other bone starts from its
//! chain parent's `C` (so the parent's twist carries down the limb, like
//! [`dancegen_formats::retarget`]'s transported alignment) and adds the smallest rotation taking its rest
//! direction (towards the next mapped joint, see `bone_map.rs` aims), as already turned by the
//! parent's `C`, onto SMPL's rest direction between the corresponding joints. Feet are turned
//! only about the vertical: both rest poses stand on flat feet, whatever direction the foot
//! bone is drawn in (SMPL's ankle→toe joint vector points 26° down). Thighs, shins, upper arms
//! and forearms therefore point exactly along SMPL's in every frame.
//!
//! # Facing
//! The dance faces +Z with its left on +X ([`dancegen_motion::conventions`]). The character's left is
//! read from its thighs (left thigh − right thigh, horizontal); the yaw taking +X onto it,
//! rounded to a multiple of 90° (characters are authored facing an axis; rounding keeps a
//! slightly asymmetric rig from turning the whole dance by a few degrees), is `F`. A VRM 0.x
//! model faces −Z, so `F` is a half turn and the dance — turns and path — plays in the
//! character's own orientation.
//!
//! # Height and root
//! The height scale `s` is the character's leg length over SMPL's: hip→knee plus knee→ankle,
//! mean of both sides. Leg length, not head height, because it is what makes strides, jumps
//! and squats land where the feet are (the same choice as [`dancegen_formats::retarget`]'s cgspeed rule),
//! and bone lengths do not depend on the rest pose. A big-headed cartoon character keeps its
//! stride. The character's hip centre (mid-point of its thighs) follows SMPL's:
//!
//! `c_t(t) = F · [s·c_x(t), g_t + s·(c_y(t) − g_s), s·c_z(t)]`
//!
//! where `g_t` is the character's lower rest ankle height and `g_s` the dance's planted ankle
//! height, the 5th percentile over frames of the lower SMPL ankle ([`FLOOR_PERCENTILE`]), so
//! whatever floor height the dance's data set uses, a planted SMPL foot puts the character's
//! ankle at its own standing height: feet stay on the character's floor. The hips node is
//! placed so that the hip centre lands on `c_t(t)`, and its translation is expressed in its
//! parent's rest frame through the full affine inverse (any scale, rotation or `matrix` in the
//! armature chain).
//!
//! Detached (IK-style) feet and hands follow their limb: their world position is their rest
//! offset in the limb bone's frame, carried by the limb, converted to their parent's frame.

use super::Character;
use super::bone_map::{Aim, Site, site_position, smpl};
use super::error::CharacterError;
use super::transform::{Affine, Trs};
use dancegen_formats::gltf::DancerAnimation;
use dancegen_motion::fk::{LocalRotations, forward_kinematics};
use dancegen_motion::rotation::{Mat3, Quat};
use dancegen_motion::skeleton::{SMPL24_NAMES, Skeleton};
use dancegen_motion::vec3::{cross, lerp, norm, scale, sub};

/// Lower percentile of the per-frame lower ankle height taken as the dance's planted-foot
/// height: the minimum would follow a single frame where a foot dips through the floor, the
/// median would float a dancer who jumps half the time.
pub const FLOOR_PERCENTILE: f64 = 0.05;

/// Bones whose local rotation never leaves its rest value by more than this (radians) get no
/// animation channel.
const STILL_ANGLE: f64 = 1e-6;

/// Per-node keyframe values, one per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeChannel<T> {
    pub node: usize,
    pub values: Vec<T>,
}

/// The dance as the character's own node animation.
#[derive(Debug, Clone, PartialEq)]
pub struct RetargetedAnimation {
    pub fps: f32,
    pub frames: usize,
    /// Local rotations, glTF order `(x, y, z, w)`, hemisphere-continuous over time (so that
    /// component-wise interpolation agrees with slerp), for every bone that moves.
    pub rotations: Vec<NodeChannel<[f32; 4]>>,
    /// Local translations of the hips and of detached (IK-style) bones.
    pub translations: Vec<NodeChannel<[f32; 3]>>,
    /// Character leg length / SMPL leg length.
    pub height_scale: f64,
    /// The facing correction `F`: degrees about +Y (0, 90, 180 or 270).
    pub facing_yaw_degrees: f64,
    /// The dance's planted-ankle height `g_s` (metres, in the dance's frame).
    pub source_floor: f64,
    /// The character's rest ankle height `g_t` (world units of the character).
    pub target_floor: f64,
}

/// The constant parts of the mapping, computed once from the two rest poses.
struct Plan {
    facing: Mat3,
    height_scale: f64,
    /// `C_k · W_k` per mapped bone.
    offsets: Vec<Mat3>,
    /// Hips: hip centre relative to the hips node, in the hips' rest rotation frame.
    hip_centre_in_hips: [f64; 3],
    /// Detached bones: rest position in the anchor's local (affine) frame.
    detached_local: Vec<Option<(usize, [f64; 3])>>,
    /// Nodes parents first, detached subtrees last.
    order: Vec<usize>,
    /// Bone index per node.
    bone_of: Vec<Option<usize>>,
    target_floor: f64,
}

/// Retargets one SMPL 24 dancer onto `character` (see the module docs).
///
/// `skeleton` must be an SMPL 24 skeleton ([`Skeleton::smpl24`], or SMPL 24 with other rest
/// offsets); `dancers` holds exactly one dancer laid out as for [`dancegen_formats::gltf::write_glb`].
pub fn retarget(
    character: &Character,
    skeleton: &Skeleton,
    dancers: &[DancerAnimation<'_>],
    fps: f32,
) -> Result<RetargetedAnimation, CharacterError> {
    let fail = |reason: String| CharacterError::Retarget {
        path: character.path().to_path_buf(),
        reason,
    };
    let dancer = match dancers {
        [d] => d,
        _ => {
            return Err(fail(format!(
                "--character takes one dancer, this dance has {}; a duet or group would need \
                 one copy of the character per dancer",
                dancers.len()
            )));
        }
    };
    if skeleton.names().iter().map(String::as_str).ne(SMPL24_NAMES) {
        return Err(fail(
            "the dance's skeleton is not SMPL 24 (only SMPL 24 dances can be retargeted)".into(),
        ));
    }
    let frames = check_motion(dancer, fps).map_err(fail)?;
    let plan = plan(character, skeleton).map_err(fail)?;

    let rot: Vec<f64> = dancer
        .local_rotations_axis_angle
        .iter()
        .map(|&v| f64::from(v))
        .collect();
    let trans: Vec<f64> = dancer
        .root_translation
        .iter()
        .map(|&v| f64::from(v))
        .collect();
    let fk = forward_kinematics(skeleton, LocalRotations::AxisAngle(&rot), &trans, true)
        .map_err(|e| fail(e.to_string()))?;
    let world_rot = fk.world_rotations.as_deref().unwrap_or(&[]);
    let pos = |f: usize, j: usize| -> [f64; 3] {
        let p = &fk.positions[(f * 24 + j) * 3..][..3];
        [p[0], p[1], p[2]]
    };
    let grot = |f: usize, j: usize| -> Mat3 {
        let m = &world_rot[(f * 24 + j) * 9..][..9];
        Mat3([[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]])
    };

    let mut lows: Vec<f64> = (0..frames)
        .map(|f| pos(f, smpl::ANKLE[0])[1].min(pos(f, smpl::ANKLE[1])[1]))
        .collect();
    lows.sort_by(f64::total_cmp);
    let source_floor = lows[((frames - 1) as f64 * FLOOR_PERCENTILE).floor() as usize];

    let tree = character.nodes();
    let bones = &character.bone_map().bones;
    let hips = bones[0].node;
    let ft = plan.facing.transpose();
    let mut rotations: Vec<Vec<Quat>> = vec![Vec::with_capacity(frames); bones.len()];
    let mut translations: Vec<(usize, Vec<[f64; 3]>)> = std::iter::once(hips)
        .chain(
            bones
                .iter()
                .filter(|b| b.detached_from.is_some())
                .map(|b| b.node),
        )
        .map(|n| (n, Vec::with_capacity(frames)))
        .collect();

    let n = tree.len();
    let mut local: Vec<Trs> = tree.rest.clone();
    let mut world = vec![Affine::IDENTITY; n];
    let mut frame = vec![Mat3::IDENTITY; n];
    let mut targets = vec![Mat3::IDENTITY; bones.len()];
    for f in 0..frames {
        for (b, bone) in bones.iter().enumerate() {
            let d = plan.facing.mul(&grot(f, bone.smpl)).mul(&ft);
            targets[b] = d.mul(&plan.offsets[b]);
        }
        let cs = lerp(pos(f, smpl::HIP[0]), pos(f, smpl::HIP[1]), 0.5);
        let s = plan.height_scale;
        let centre = plan.facing.mul_vec([
            s * cs[0],
            plan.target_floor + s * (cs[1] - source_floor),
            s * cs[2],
        ]);
        let hips_world = sub(centre, targets[0].mul_vec(plan.hip_centre_in_hips));

        for &k in &plan.order {
            let (pw, pf) = match tree.parents[k] {
                Some(p) => (world[p], frame[p]),
                None => (Affine::IDENTITY, Mat3::IDENTITY),
            };
            if let Some(b) = plan.bone_of[k] {
                frame[k] = targets[b];
                local[k].rotation = pf.transpose().mul(&targets[b]).to_quat();
                let wanted = if k == hips {
                    Some(hips_world)
                } else {
                    plan.detached_local[b].map(|(anchor, q)| world[anchor].point(q))
                };
                if let (Some(p), Some(inv)) = (wanted, pw.inverse()) {
                    local[k].translation = inv.point(p);
                }
            } else {
                frame[k] = pf.mul(&tree.rest[k].rotation.to_mat3());
            }
            world[k] = pw.mul(&local[k].to_affine());
        }
        for (b, bone) in bones.iter().enumerate() {
            rotations[b].push(local[bone.node].rotation);
        }
        for (node, values) in &mut translations {
            values.push(local[*node].translation);
        }
    }

    let mut rot_channels = Vec::new();
    for (b, bone) in bones.iter().enumerate() {
        if plan.bone_of[bone.node] != Some(b) {
            continue; // a node mapped twice keeps its first mapping
        }
        let rest = tree.rest[bone.node].rotation;
        let moves = rotations[b]
            .iter()
            .any(|q| 2.0 * q.dot(rest).abs().min(1.0).acos() > STILL_ANGLE);
        if bone.node != hips && !moves {
            continue;
        }
        rot_channels.push(NodeChannel {
            node: bone.node,
            values: continuous_xyzw(&rotations[b]),
        });
    }
    rot_channels.sort_by_key(|c| c.node);
    let mut trans_channels: Vec<NodeChannel<[f32; 3]>> = translations
        .into_iter()
        .map(|(node, v)| NodeChannel {
            node,
            values: v.iter().map(|p| p.map(|x| x as f32)).collect(),
        })
        .collect();
    trans_channels.sort_by_key(|c| c.node);
    trans_channels.dedup_by_key(|c| c.node);

    let yaw = plan.facing.0[0][2].atan2(plan.facing.0[0][0]).to_degrees();
    Ok(RetargetedAnimation {
        fps,
        frames,
        rotations: rot_channels,
        translations: trans_channels,
        height_scale: plan.height_scale,
        facing_yaw_degrees: yaw.rem_euclid(360.0).round(),
        source_floor,
        target_floor: plan.target_floor,
    })
}

/// Checks the dancer's arrays; returns the frame count.
fn check_motion(d: &DancerAnimation<'_>, fps: f32) -> Result<usize, String> {
    let rot = d.local_rotations_axis_angle;
    if rot.is_empty() || !rot.len().is_multiple_of(24 * 3) {
        return Err(format!(
            "the dance has {} rotation values, not a positive multiple of 24 joints × 3",
            rot.len()
        ));
    }
    let frames = rot.len() / 72;
    if d.root_translation.len() != frames * 3 {
        return Err(format!(
            "{frames} frames of rotations but {} root translation values (expected {})",
            d.root_translation.len(),
            frames * 3
        ));
    }
    if let Some(i) = rot
        .iter()
        .chain(d.root_translation)
        .position(|v| !v.is_finite())
    {
        return Err(format!("dance value {i} is not finite"));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(format!("fps must be finite and positive, got {fps}"));
    }
    let time = |f: usize| (f as f64 / f64::from(fps)) as f32;
    if (1..frames).any(|f| time(f) <= time(f - 1)) {
        return Err(format!(
            "{frames} frames at {fps} fps: key times are not strictly increasing as f32"
        ));
    }
    Ok(frames)
}

/// Facing, height scale and alignments from the two rest poses.
fn plan(character: &Character, skeleton: &Skeleton) -> Result<Plan, String> {
    let tree = character.nodes();
    let map = character.bone_map();
    let at = |j: usize| -> Result<[f64; 3], String> {
        map.sites[j]
            .and_then(|s| site_position(tree, s))
            .ok_or_else(|| format!("no position for SMPL joint {}", SMPL24_NAMES[j]))
    };
    let src = skeleton.rest_positions();

    // Facing: the yaw taking +X (the dance's left) onto the character's left, in quarter turns.
    let left = sub(at(smpl::HIP[0])?, at(smpl::HIP[1])?);
    if left[0].hypot(left[2]) < 1e-9 {
        return Err("the character's left and right thighs are at the same place".into());
    }
    let quarter = std::f64::consts::FRAC_PI_2;
    let yaw = ((-left[2]).atan2(left[0]) / quarter).round() * quarter;
    let facing = Mat3::from_axis_rotation(1, yaw);

    // Height scale from the legs.
    let leg = |p: &dyn Fn(usize) -> Result<[f64; 3], String>, s: usize| -> Result<f64, String> {
        let (h, k, a) = (p(smpl::HIP[s])?, p(smpl::KNEE[s])?, p(smpl::ANKLE[s])?);
        Ok(norm(sub(k, h)) + norm(sub(a, k)))
    };
    let src_at = |j: usize| Ok(src[j]);
    let target_leg = 0.5 * (leg(&at, 0)? + leg(&at, 1)?);
    let source_leg = 0.5 * (leg(&src_at, 0)? + leg(&src_at, 1)?);
    let height_scale = target_leg / source_leg;
    if !(height_scale.is_finite() && height_scale > 1e-9) {
        return Err(format!(
            "the character's legs have no length ({target_leg}), so its size is unknown"
        ));
    }

    // Alignments, chain parents first.
    let f_src = |a: usize, b: usize| facing.mul_vec(sub(src[b], src[a]));
    let mut aligns: Vec<Mat3> = Vec::with_capacity(map.bones.len());
    for bone in &map.bones {
        let parent = bone.chain_parent.map_or(Mat3::IDENTITY, |p| aligns[p]);
        let here = tree.rest_position(bone.node);
        let toward = |target: Site| site_position(tree, target).map(|p| sub(p, here));
        let c = match bone.aim {
            Aim::None => parent,
            Aim::Hips => {
                let up_t = sub(
                    lerp(at(smpl::SHOULDER[0])?, at(smpl::SHOULDER[1])?, 0.5),
                    lerp(at(smpl::HIP[0])?, at(smpl::HIP[1])?, 0.5),
                );
                let src_up = sub(
                    lerp(src[smpl::SHOULDER[0]], src[smpl::SHOULDER[1]], 0.5),
                    lerp(src[smpl::HIP[0]], src[smpl::HIP[1]], 0.5),
                );
                let tb = basis(left, up_t).ok_or("the character's trunk is degenerate")?;
                let sb = basis(f_src(smpl::HIP[1], smpl::HIP[0]), facing.mul_vec(src_up))
                    .ok_or("the dance skeleton's trunk is degenerate")?;
                sb.mul(&tb.transpose())
            }
            Aim::Full { target, source } => match toward(target) {
                Some(dt) => swing(parent, dt, f_src(bone.smpl, source), false),
                None => parent,
            },
            Aim::Heading { target, source } => match toward(target) {
                Some(dt) => swing(parent, dt, f_src(bone.smpl, source), true),
                None => parent,
            },
        };
        aligns.push(c);
    }
    let offsets: Vec<Mat3> = map
        .bones
        .iter()
        .zip(&aligns)
        .map(|(b, c)| c.mul(&tree.rest_frame[b.node]))
        .collect();

    let hips = map.bones[0].node;
    let centre = lerp(at(smpl::HIP[0])?, at(smpl::HIP[1])?, 0.5);
    let hip_centre_in_hips = tree.rest_frame[hips]
        .transpose()
        .mul_vec(sub(centre, tree.rest_position(hips)));

    let mut bone_of = vec![None; tree.len()];
    for (b, bone) in map.bones.iter().enumerate() {
        bone_of[bone.node].get_or_insert(b);
    }
    let mut detached_local = vec![None; map.bones.len()];
    let mut in_detached = vec![false; tree.len()];
    for (b, bone) in map.bones.iter().enumerate() {
        if let Some(anchor) = bone.detached_from {
            let inv = tree.rest_world[anchor]
                .inverse()
                .ok_or("a limb bone has zero scale")?;
            detached_local[b] = Some((anchor, inv.point(tree.rest_position(bone.node))));
            for k in tree.subtree(bone.node) {
                in_detached[k] = true;
            }
        }
    }
    let order: Vec<usize> = tree
        .order
        .iter()
        .copied()
        .filter(|&k| !in_detached[k])
        .chain(tree.order.iter().copied().filter(|&k| in_detached[k]))
        .collect();
    for b in map
        .bones
        .iter()
        .filter(|b| b.node == hips || b.detached_from.is_some())
    {
        if let Some(p) = tree.parents[b.node]
            && tree.rest_world[p].inverse().is_none()
        {
            return Err(format!(
                "the parent of bone {} has zero scale",
                tree.label(b.node)
            ));
        }
    }
    let target_floor = at(smpl::ANKLE[0])?[1].min(at(smpl::ANKLE[1])?[1]);
    Ok(Plan {
        facing,
        height_scale,
        offsets,
        hip_centre_in_hips,
        detached_local,
        order,
        bone_of,
        target_floor,
    })
}

/// `parent` followed by the smallest rotation taking `parent · target_dir` onto `source_dir`
/// (about the vertical only when `heading_only`).
fn swing(parent: Mat3, target_dir: [f64; 3], source_dir: [f64; 3], heading_only: bool) -> Mat3 {
    let mut from = parent.mul_vec(target_dir);
    let mut to = source_dir;
    if heading_only {
        from[1] = 0.0;
        to[1] = 0.0;
    }
    if norm(from) < 1e-9 || norm(to) < 1e-9 {
        return parent;
    }
    Mat3::between(from, to).mul(&parent)
}

/// Orthonormal frame (columns: left, up, forward) from a left axis and an up direction.
fn basis(left: [f64; 3], up: [f64; 3]) -> Option<Mat3> {
    let x = unit(left)?;
    let z = unit(cross(x, up))?;
    let y = cross(z, x);
    Some(Mat3([
        [x[0], y[0], z[0]],
        [x[1], y[1], z[1]],
        [x[2], y[2], z[2]],
    ]))
}

fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(v);
    (n > 1e-12).then(|| scale(v, 1.0 / n))
}

/// `(x, y, z, w)` quaternions with consecutive ones in the same hemisphere.
fn continuous_xyzw(q: &[Quat]) -> Vec<[f32; 4]> {
    let mut prev: Option<Quat> = None;
    q.iter()
        .map(|&q| {
            let mut q = q.normalize();
            if prev.is_some_and(|p| p.dot(q) < 0.0) {
                q = -q;
            }
            prev = Some(q);
            [q.x as f32, q.y as f32, q.z as f32, q.w as f32]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_aligns_left_and_up() {
        let t = basis([0.0, 0.0, -1.0], [0.0, 1.0, 0.2]).unwrap();
        let s = basis([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]).unwrap();
        let c = s.mul(&t.transpose());
        let l = c.mul_vec([0.0, 0.0, -1.0]);
        assert!((l[0] - 1.0).abs() < 1e-12 && l[1].abs() < 1e-12 && l[2].abs() < 1e-12);
        assert!((c.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn heading_swing_keeps_pitch() {
        let c = swing(Mat3::IDENTITY, [1.0, -0.5, 0.0], [0.0, -2.0, 1.0], true);
        let v = c.mul_vec([1.0, -0.5, 0.0]);
        assert!((v[1] + 0.5).abs() < 1e-12, "pitch kept");
        assert!(
            v[0].abs() < 1e-12 && (v[2] - 1.0).abs() < 1e-12,
            "heading turned"
        );
    }

    #[test]
    fn quaternions_stay_in_one_hemisphere() {
        let a = Quat::from_axis_angle([0.0, 3.0, 0.0]);
        let b = -Quat::from_axis_angle([0.0, 3.1, 0.0]);
        let out = continuous_xyzw(&[a, b]);
        let dot: f32 = (0..4).map(|i| out[0][i] * out[1][i]).sum();
        assert!(dot > 0.0);
    }
}
