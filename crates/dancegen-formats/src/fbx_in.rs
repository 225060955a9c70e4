//! Reading back the dances `.fbx` files that dancegen writes ([`crate::fbx`]), through ufbx
//! (the C library engines' exporter test suites use, bundled by the `ufbx` crate), so `render`,
//! `convert`, `eval`, `--leader`, `--edit` and `--continue-from` read what `generate` writes.
//!
//! A dancer is a skin whose bones carry one of the rigs' SMPL 24 bone names
//! ([`crate::rig::Rig::joint_names`], `dancer{d}/` prefixed in a scene of several), skins in file order.
//! The file is read in dancegen's conventions whatever it declares: ufbx converts it to Y-up,
//! right-handed metres at the scene root. Each joint's SMPL rotation is its animated local
//! rotation (the writer's rest rotations are identity; a skin bound with rotated bones is
//! refused rather than misread), the root's composed with its parent's placement, and the
//! root's translation its animated world position. Frames are the animation's span at the
//! file's frame rate. A holistic dance's skeleton has no SMPL hand joints (its fingers hang
//! from the wrists): those two stay at rest.

use std::path::Path;

use dancegen_motion::repr::motion::{POSE_DIMS, SMPL_JOINTS, SmplMotion};
use dancegen_motion::rotation::{Mat3, Quat};

use crate::rig::smpl_joints_by_name;

/// Most frames read (an hour at 120 fps), so a time range cannot ask for gigabytes.
const MAX_FRAMES: usize = 120 * 3600;

/// How far from identity a bone's bind rotation may be (matrix entries) and still be the
/// writer's identity rest (its bind matrices are `f64` translations).
const REST_TOL: f64 = 1e-4;

/// The dancers of an `.fbx` dancegen wrote, in skin order.
pub fn read_dance_fbx(path: &Path) -> Result<Vec<SmplMotion>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let opts = ufbx::LoadOpts {
        target_axes: ufbx::CoordinateAxes::right_handed_y_up(),
        target_unit_meters: 1.0,
        space_conversion: ufbx::SpaceConversion::TransformRoot,
        ..Default::default()
    };
    let scene = ufbx::load_memory(&bytes, opts).map_err(|e| {
        format!(
            "not a readable FBX file: {}",
            e.description.as_ref() as &str
        )
    })?;
    if scene.skin_deformers.is_empty() {
        return Err("the file has no skeleton (no skin): not a dance dancegen wrote".into());
    }
    let stack = scene
        .anim_stacks
        .first()
        .ok_or("the file has no animation")?;
    let fps = scene.settings.frames_per_second;
    if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
        return Err(format!("the file's frame rate is {fps} frames a second"));
    }
    let span = (stack.time_end - stack.time_begin) * fps;
    if !(span.is_finite() && span >= 0.0 && span < MAX_FRAMES as f64) {
        return Err(format!(
            "the animation runs {:.1} s to {:.1} s: not a dance dancegen wrote",
            stack.time_begin, stack.time_end
        ));
    }
    let frames = span.round() as usize + 1;
    let mut dancers = Vec::with_capacity(scene.skin_deformers.len());
    for (d, skin) in scene.skin_deformers.iter().enumerate() {
        let bones: Vec<(&ufbx::Node, &ufbx::SkinCluster)> = skin
            .clusters
            .iter()
            .filter_map(|c| c.bone_node.as_ref().map(|n| (n.as_ref(), c.as_ref())))
            .collect();
        let tail = |n: &ufbx::Node| {
            let name: &str = n.element.name.as_ref();
            name.rsplit_once('/').map_or(name, |(_, t)| t).to_string()
        };
        let names: Vec<String> = bones.iter().map(|(n, _)| tail(n)).collect();
        let smpl = smpl_joints_by_name(&names, d)?;
        for (n, c) in &bones {
            let r = rotation(&c.bind_to_world);
            let off = (0..9)
                .map(|i| (r.0[i / 3][i % 3] - Mat3::IDENTITY.0[i / 3][i % 3]).abs())
                .fold(0.0, f64::max);
            if off > REST_TOL {
                return Err(format!(
                    "skin {d}'s bone {:?} is bound rotated: not a dance dancegen wrote (its \
                     rest rotations are identity)",
                    n.element.name.as_ref() as &str
                ));
            }
        }
        let root = bones[smpl[0].expect("the pelvis is required")].0;
        let placement = root
            .parent
            .as_ref()
            .map_or((Mat3::IDENTITY, [0.0; 3]), |p| {
                (rotation(&p.node_to_world), translation(&p.node_to_world))
            });
        let mut poses = vec![0f32; frames * POSE_DIMS];
        let mut trans = vec![0f32; frames * 3];
        for f in 0..frames {
            let time = stack.time_begin + f as f64 / fps;
            for (k, b) in smpl.iter().enumerate().take(SMPL_JOINTS) {
                let Some(b) = b else { continue };
                let local = ufbx::evaluate_transform(&stack.anim, bones[*b].0, time);
                let q = local.rotation;
                let mut r = Quat::new(q.w, q.x, q.y, q.z).normalize().to_mat3();
                if k == 0 {
                    r = placement.0 * r;
                    let t = local.translation;
                    let p = placement.0.mul_vec([t.x, t.y, t.z]);
                    for a in 0..3 {
                        trans[f * 3 + a] = (p[a] + placement.1[a]) as f32;
                    }
                }
                let aa = r.to_axis_angle();
                for a in 0..3 {
                    poses[f * POSE_DIMS + k * 3 + a] = aa[a] as f32;
                }
            }
        }
        let m = SmplMotion::new(fps.round() as f32, poses, trans)
            .map_err(|e| format!("dancer {d}: {e}"))?;
        dancers.push(m);
    }
    Ok(dancers)
}

/// The rotation part of an affine matrix, scale removed column by column.
fn rotation(m: &ufbx::Matrix) -> Mat3 {
    let cols = [
        [m.m00, m.m10, m.m20],
        [m.m01, m.m11, m.m21],
        [m.m02, m.m12, m.m22],
    ];
    let unit = cols.map(|c| {
        let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt().max(1e-12);
        c.map(|v| v / n)
    });
    Mat3([0, 1, 2].map(|r| [0, 1, 2].map(|c| unit[c][r])))
}

fn translation(m: &ufbx::Matrix) -> [f64; 3] {
    [m.m03, m.m13, m.m23]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fbx::{FbxOptions, fbx_bytes};
    use crate::gltf::DancerAnimation;
    use crate::rig::Rig;

    /// Every joint through large angles (several times round for the root, which the
    /// writer's Euler curves must unwrap), travelling.
    fn dancer(seed: f32, frames: usize) -> (Vec<f32>, Vec<f32>) {
        crate::test_dancers::turning_dancer(seed, frames, 2.5)
    }

    fn rotation_error(got: &[f32], want: &[f32]) -> f64 {
        let m = |v: &[f32]| Mat3::from_axis_angle([0, 1, 2].map(|a| f64::from(v[a])));
        let (g, w) = (m(got), m(want));
        (0..9)
            .map(|i| (g.0[i / 3][i % 3] - w.0[i / 3][i % 3]).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_written_scene_reads_back_with_its_rotations_roots_and_rate() {
        let dir = tempfile::tempdir().unwrap();
        for (rig, fps) in Rig::ALL.into_iter().zip([30.0, 24.0, 60.0, 30.0]) {
            let (a, b) = (dancer(0.1, 40), dancer(2.0, 40));
            let scene = [
                DancerAnimation {
                    local_rotations_axis_angle: &a.0,
                    root_translation: &a.1,
                },
                DancerAnimation {
                    local_rotations_axis_angle: &b.0,
                    root_translation: &b.1,
                },
            ];
            let bytes = fbx_bytes(&rig.skeleton(), &scene, fps, &FbxOptions::default()).unwrap();
            let path = dir.path().join(format!("{}.fbx", rig.name()));
            std::fs::write(&path, bytes).unwrap();
            let read = read_dance_fbx(&path).unwrap();
            assert_eq!(read.len(), 2, "{rig:?}");
            for (m, (rot, trans)) in read.iter().zip([&a, &b]) {
                assert_eq!(m.fps, fps, "{rig:?}");
                assert_eq!(m.trans.len(), trans.len(), "{rig:?}");
                for (g, w) in m.trans.iter().zip(trans) {
                    assert!((g - w).abs() < 1e-5, "{rig:?}: root {g} for {w}");
                }
                for (k, (got, want)) in m.poses.chunks(3).zip(rot.chunks(3)).enumerate() {
                    let e = rotation_error(got, want);
                    assert!(e < 1e-4, "{rig:?}: frame {} joint {}: {e}", k / 24, k % 24);
                }
            }
        }
    }

    #[test]
    fn broken_and_foreign_files_are_errors_not_panics() {
        let dir = tempfile::tempdir().unwrap();
        let (rot, trans) = dancer(0.3, 5);
        let one = [DancerAnimation {
            local_rotations_axis_angle: &rot,
            root_translation: &trans,
        }];
        let good = fbx_bytes(&Rig::Smpl.skeleton(), &one, 30.0, &FbxOptions::default()).unwrap();
        let path = dir.path().join("x.fbx");
        // Every truncation of a good file is an error, never a panic.
        for cut in (0..good.len()).step_by(997) {
            std::fs::write(&path, &good[..cut]).unwrap();
            assert!(read_dance_fbx(&path).is_err(), "cut at {cut}");
        }
        std::fs::write(&path, b"not an fbx").unwrap();
        let e = read_dance_fbx(&path).unwrap_err();
        assert!(e.starts_with("not a readable FBX file"), "{e}");
        // A skeleton with other bone names (same length, so the file stays well formed): every
        // object named after the left hip (model, attribute, cluster) renamed.
        let mut renamed = good.clone();
        let mut count = 0;
        for at in 0..renamed.len() - 4 {
            if &renamed[at..at + 4] == b"lhip" {
                renamed[at..at + 4].copy_from_slice(b"lhiq");
                count += 1;
            }
        }
        assert!(count > 0, "the left hip is named in the file");
        std::fs::write(&path, &renamed).unwrap();
        let e = read_dance_fbx(&path).unwrap_err();
        assert!(e.contains("not an SMPL 24 skeleton"), "{e}");
    }
}
