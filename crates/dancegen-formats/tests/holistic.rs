//! SoulNet holistic 623 / 723 (anchors.md C.6) on the approximate SMPL-H 52 skeleton.

mod common;

use dancegen_formats::aistpp::load_motion;
use dancegen_motion::repr::holistic::{FACE_DIMS, JOINTS, LAYOUT, split};
use dancegen_motion::repr::{FineDance315, Holistic623, Holistic723, HumanMl263, SmplMotion};
use dancegen_motion::rotation::Mat3;
use dancegen_motion::skeleton::{SMPLH52_MIRROR, SMPLH52_NAMES, SMPLH52_PARENTS, Skeleton};

const SEQ: &str = "gJS_sFM_cAll_d02_mJS4_ch09";

fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Body from AIST++ (60 → 30 fps by stride 2), fingers with a deterministic curl animation.
/// Returns `(smpl body motion, poses (T, 52, 3), trans (T, 3))`.
fn synthetic() -> (SmplMotion, Vec<f32>, Vec<f32>) {
    let path = common::shared_dir()
        .join("data/aistpp/motions")
        .join(format!("{SEQ}.pkl"));
    let a = load_motion(&path).unwrap();
    let m = a.to_smpl_motion().resample_stride(2);
    assert_eq!(m.fps, 30.0);
    let t = m.frames();
    let mut poses = Vec::with_capacity(t * JOINTS * 3);
    for f in 0..t {
        poses.extend_from_slice(&m.poses[f * 72..f * 72 + 22 * 3]);
        for hand in 0..2 {
            // Left hand points along +X: curling toward the palm (−Y) is a negative rotation
            // about +Z; the mirror image (axis-angle (x, −y, −z)) gives +Z for the right hand.
            let side = if hand == 0 { -1.0f32 } else { 1.0 };
            for finger in 0..5 {
                for seg in 0..3 {
                    let phase = 0.7 * finger as f32 + 0.4 * seg as f32 + hand as f32;
                    let curl =
                        0.6 + 0.55 * (2.0 * std::f32::consts::PI * f as f32 / 45.0 + phase).sin();
                    let spread = if seg == 0 {
                        0.15 * (f as f32 / 20.0 + finger as f32).cos()
                    } else {
                        0.0
                    };
                    if finger == 4 {
                        // Thumb: opposition about a tilted axis.
                        poses.extend([0.3 * curl, side * -0.2 * curl, side * 0.5 * curl]);
                    } else {
                        poses.extend([0.0, side * spread, side * curl]);
                    }
                }
            }
        }
    }
    let trans = m.trans.clone();
    (m, poses, trans)
}

#[test]
fn approximate_smplh52_skeleton() {
    let s = Skeleton::smplh52_approx();
    assert_eq!(s.len(), 52);
    assert_eq!(s.names(), SMPLH52_NAMES.map(String::from).as_slice());
    assert_eq!(s.parent_indices(), SMPLH52_PARENTS.to_vec());
    // Body = EDGE SMPL offsets.
    let smpl = Skeleton::smpl24();
    assert_eq!(&s.offsets()[..22], &smpl.offsets()[..22]);
    // Hands: exact mirrors (x negated).
    let off = s.offsets();
    for j in 22..52 {
        let (a, b) = (off[j], off[SMPLH52_MIRROR[j]]);
        assert!((a[0] + b[0]).abs() < 1e-9, "{j}");
        assert!(
            (a[1] - b[1]).abs() < 1e-9 && (a[2] - b[2]).abs() < 1e-9,
            "{j}"
        );
    }
    // Left hand points +X; finger segments in plausible ranges (metres).
    let rest = s.rest_positions();
    for (base, name) in [(22, "index"), (25, "middle"), (28, "pinky"), (31, "ring")] {
        assert!(SMPLH52_NAMES[base].starts_with(&format!("left_{name}")));
        let (knuckle, prox, mid) = (norm(off[base]), norm(off[base + 1]), norm(off[base + 2]));
        assert!((0.07..0.12).contains(&knuckle), "{name} {knuckle}");
        assert!((0.025..0.045).contains(&prox), "{name} {prox}");
        assert!((0.015..0.03).contains(&mid), "{name} {mid}");
        assert!(off[base][0] > 0.0 && off[base + 1][0] > 0.0 && off[base + 2][0] > 0.0);
        // Proximal : middle phalanx = 0.45 : 0.30.
        assert!((prox / mid - 1.5).abs() < 1e-9);
        // Finger tips (middle-phalanx end + distal 0.25) within a hand length of the wrist.
        let tip = rest[base + 2][0] + mid / 0.30 * 0.25 - rest[20][0];
        assert!((0.14..0.2).contains(&tip), "{name} {tip}");
    }
    // Middle finger: hand length ≈ 0.19 m.
    let hand = rest[27][0] + norm(off[27]) / 0.30 * 0.25 - rest[20][0];
    assert!((hand - 0.19).abs() < 1e-3, "{hand}");
    // Palm width (index to pinky knuckle) 5–9 cm; thumb forward (+Z) and down.
    let width = rest[22][2] - rest[28][2];
    assert!((0.05..0.09).contains(&width), "{width}");
    for (j, o) in off.iter().enumerate().take(37).skip(34) {
        assert!(o[2] > 0.0 && o[1] < 0.0, "{j}");
        assert!((0.02..0.06).contains(&norm(*o)), "{j}");
    }
    eprintln!(
        "smplh52_approx: hand length {hand:.4} m, palm width {width:.4} m, thumb tip z {:.4}",
        rest[36][2] - rest[20][2]
    );
}

#[test]
fn holistic623_round_trip() {
    let (m, poses, trans) = synthetic();
    let t = m.frames();
    let skel = Skeleton::smplh52_approx();
    assert_eq!(Holistic623::DIMS, 623);
    assert_eq!(LAYOUT.rot(), 4 + 153);
    assert_eq!(LAYOUT.vel(), 4 + 153 + 306);
    assert_eq!(LAYOUT.contacts(), 619);
    let parts = Holistic623::encode_with(&skel, &poses, &trans, 30.0).unwrap();
    assert_eq!(parts.data.len(), (t - 1) * 623);
    assert_eq!(
        Holistic623::encode(&poses, &trans, 30.0).unwrap(),
        parts.data
    );
    // recover_from_ric == canonical joints rotated by the initial heading.
    let dec = Holistic623::decode_joints(&parts.data).unwrap();
    let h0 = parts.heading[0];
    let want: Vec<f32> = parts.positions[..(t - 1) * JOINTS * 3]
        .chunks_exact(3)
        .flat_map(|p| h0.rotate([p[0], p[1], p[2]]).map(|v| v as f32))
        .collect();
    let err = max_abs_diff(&dec, &want);
    let hand_err = dec
        .chunks_exact(JOINTS * 3)
        .zip(want.chunks_exact(JOINTS * 3))
        .map(|(a, b)| max_abs_diff(&a[22 * 3..], &b[22 * 3..]))
        .fold(0.0, f32::max);
    // FK of the decoded motion reproduces the decoded joints.
    let sm = Holistic623::decode(&parts.data, 30.0).unwrap();
    assert_eq!(sm.frames(), t - 1);
    assert!(sm.face.is_none());
    let fk = sm.joints_world_with(&skel).unwrap();
    let ferr = max_abs_diff(&fk, &dec);
    // Decoded local rotations (joints 1–51) equal the input ones.
    let mut rerr = 0.0f64;
    for f in 0..t - 1 {
        for k in 1..JOINTS {
            let o = (f * JOINTS + k) * 3;
            let aa = |p: &[f32]| Mat3::from_axis_angle([p[o], p[o + 1], p[o + 2]].map(f64::from));
            let (a, b) = (aa(&poses), aa(&sm.poses));
            for (x, y) in a.0.iter().flatten().zip(b.0.iter().flatten()) {
                rerr = rerr.max((x - y).abs());
            }
        }
    }
    eprintln!(
        "{SEQ} ({t} frames @30): Holistic623 ric recovery err {err:.2e} m (hands {hand_err:.2e} m), \
         FK(decode) vs ric {ferr:.2e} m, local rotation matrix err {rerr:.2e}"
    );
    assert!(err < 1e-5, "{err}");
    assert!(ferr < 1e-5, "{ferr}");
    assert!(rerr < 1e-5, "{rerr}");
    // The fingers actually move in the ric block.
    let first = &parts.data[LAYOUT.ric() + 21 * 3..LAYOUT.rot()];
    let later = &parts.data[20 * 623 + LAYOUT.ric() + 21 * 3..20 * 623 + LAYOUT.rot()];
    assert!(max_abs_diff(first, later) > 1e-2);
    // Contacts are binary; the body part agrees with the 22-joint HumanML263 where it does not
    // depend on the floor (root velocities, body 6D, body local velocities).
    let body = HumanMl263::encode(&m).unwrap();
    let (mut root_err, mut rot_err, mut vel_err) = (0.0f32, 0.0f32, 0.0f32);
    for (h, b) in parts.data.chunks_exact(623).zip(body.chunks_exact(263)) {
        assert!(h[619..].iter().all(|&c| c == 0.0 || c == 1.0));
        root_err = root_err.max(max_abs_diff(&h[..3], &b[..3]));
        rot_err = rot_err.max(max_abs_diff(&h[157..157 + 126], &b[67..193]));
        vel_err = vel_err.max(max_abs_diff(&h[463..463 + 66], &b[193..259]));
    }
    eprintln!(
        "vs HumanML263: root vel {root_err:.2e}, body rot {rot_err:.2e}, body vel {vel_err:.2e}"
    );
    assert!(root_err < 1e-5 && rot_err < 1e-5 && vel_err < 1e-5);
}

/// SoulNet's split body part is HumanML3D's 263 of the 22 body joints: equal to our
/// [`HumanMl263`] of the body motion in every value but the floor-relative heights (root y and
/// the ric y's, which differ by one constant: the 52-joint floor includes the fingers).
#[test]
fn split_body_part_is_the_body_humanml263() {
    let (m, poses, trans) = synthetic();
    let inter = Holistic623::encode(&poses, &trans, 30.0).unwrap();
    let data = split::to_split(&inter, 0).unwrap();
    let body = HumanMl263::encode(&m).unwrap();
    let heights: Vec<usize> = std::iter::once(3)
        .chain((0..21).map(|j| 4 + 3 * j + 1))
        .collect();
    let (mut err, mut shift) = (0.0f32, None::<f32>);
    let mut shift_err = 0.0f32;
    for (row, b) in data.chunks_exact(623).zip(body.chunks_exact(263)) {
        let (part, hands, _) = split::parts(row);
        assert_eq!(hands.len(), 360);
        for k in 0..263 {
            if heights.contains(&k) {
                let d = part[k] - b[k];
                let s = *shift.get_or_insert(d);
                shift_err = shift_err.max((d - s).abs());
            } else {
                err = err.max((part[k] - b[k]).abs());
            }
        }
    }
    eprintln!("split body vs HumanML263: {err:.2e}; floor shift {shift:?} ± {shift_err:.2e}");
    assert!(err < 1e-5, "{err}");
    assert!(shift_err < 1e-5, "{shift_err}");
    assert_eq!(split::from_split(&data, 0).unwrap(), inter);
}

#[test]
fn holistic723_face_pass_through() {
    let (_, poses, trans) = synthetic();
    let t = trans.len() / 3;
    assert_eq!(Holistic723::DIMS, 723);
    let face: Vec<f32> = (0..t * FACE_DIMS)
        .map(|i| ((i as f32) * 0.618_034).sin() * 1.5 + 1e-7 * i as f32)
        .collect();
    let enc = Holistic723::encode(&poses, &trans, Some(&face), 30.0).unwrap();
    assert_eq!(enc.len(), (t - 1) * 723);
    // Body/hands part equals the 623 encoding.
    let body = Holistic623::encode(&poses, &trans, 30.0).unwrap();
    let (b, fp) = Holistic723::split(&enc).unwrap();
    assert_eq!(b, body);
    assert_eq!(fp, face[..(t - 1) * FACE_DIMS]);
    let dec = Holistic723::decode(&enc, 30.0).unwrap();
    assert_eq!(dec.face.as_deref(), Some(&face[..(t - 1) * FACE_DIMS]));
    assert_eq!(
        Holistic723::decode_joints(&enc).unwrap(),
        Holistic623::decode_joints(&body).unwrap()
    );
    // No face → zeros.
    let enc0 = Holistic723::encode(&poses, &trans, None, 30.0).unwrap();
    let dec0 = Holistic723::decode(&enc0, 30.0).unwrap();
    assert!(dec0.face.unwrap().iter().all(|&v| v == 0.0));
    // Shape errors.
    assert!(Holistic723::encode(&poses, &trans, Some(&face[..FACE_DIMS]), 30.0).is_err());
    assert!(Holistic623::encode(&poses[..JOINTS * 3], &trans[..3], 30.0).is_err());
    assert!(Holistic623::encode(&poses, &trans[3..], 30.0).is_err());
    assert!(Holistic623::decode(&enc, 30.0).is_err());
    assert!(Holistic623::encode_with(&Skeleton::smpl24(), &poses, &trans, 30.0).is_err());
}

/// FineDance's 315 layout carries SMPL-H 52 with real fingers: a 52-joint motion written as a
/// FineDance `.npy` reads back with the same rotations, fingers included, and the same FK.
#[test]
fn finedance_315_reads_as_smplh52_with_fingers() {
    use dancegen_motion::repr::FineDanceMotion;
    let (_, poses, trans) = synthetic();
    let t = trans.len() / 3;
    let data = FineDance315::encode_smplh52(&poses, &trans).unwrap();
    assert_eq!(data.len(), t * 315);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("001.npy");
    dancegen_io::write_npy_f32(&path, &[t, 315], &data).unwrap();
    let fd = FineDanceMotion::from_npy(&path).unwrap();
    let m = fd.to_smplh52().unwrap();
    assert_eq!((m.frames(), m.poses.len()), (t, t * 52 * 3));
    assert_eq!(m.trans, trans);
    let mut rerr = 0.0f64;
    for (a, b) in m.poses.chunks_exact(3).zip(poses.chunks_exact(3)) {
        let (ra, rb) = (
            Mat3::from_axis_angle([a[0], a[1], a[2]].map(f64::from)),
            Mat3::from_axis_angle([b[0], b[1], b[2]].map(f64::from)),
        );
        for i in 0..3 {
            for k in 0..3 {
                rerr = rerr.max((ra.0[i][k] - rb.0[i][k]).abs());
            }
        }
    }
    let skel = Skeleton::smplh52_approx();
    let ferr = max_abs_diff(
        &m.joints_world_with(&skel).unwrap(),
        &dancegen_motion::repr::holistic::HolisticMotion {
            fps: 30.0,
            poses: poses.clone(),
            trans: trans.clone(),
            face: None,
        }
        .joints_world_with(&skel)
        .unwrap(),
    );
    eprintln!("FineDance 315 <-> SMPL-H 52: rotation {rerr:.1e}, FK {ferr:.1e} m");
    assert!(rerr < 1e-5 && ferr < 1e-5, "{rerr} {ferr}");
    // The fingers are really there (they curl), and the body agrees with the SMPL 24 reader.
    assert!(m.poses[22 * 3..52 * 3].iter().any(|v| v.abs() > 0.1));
    let body = fd.to_smpl24().unwrap();
    assert_eq!(&body.poses[..22 * 3], &m.poses[..22 * 3]);
    // Shape errors name the problem.
    assert!(FineDance315::encode_smplh52(&poses[..100], &trans).is_err());
    assert!(FineDance315::encode_smplh52(&poses, &trans[3..]).is_err());
}

/// A SoulDance-style `(T, 723)` split-layout `.npy` reads back as the motion it encodes, face
/// included; other widths are refused with the file's name.
#[test]
fn souldance_split_npy_reads_as_holistic_motion() {
    let (_, poses, trans) = synthetic();
    let t = trans.len() / 3;
    let face: Vec<f32> = (0..t * FACE_DIMS).map(|i| (i as f32 * 0.1).sin()).collect();
    let inter = Holistic723::encode(&poses, &trans, Some(&face), 30.0).unwrap();
    let data = split::to_split(&inter, FACE_DIMS).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("souldance.npy");
    dancegen_io::write_npy_f32(&path, &[t - 1, 723], &data).unwrap();
    let m = split::read_split_npy(&path, 30.0).unwrap();
    let want = Holistic723::decode(&inter, 30.0).unwrap();
    assert_eq!(m, want);
    assert_eq!(m.face.as_deref(), Some(&face[..(t - 1) * FACE_DIMS]));
    // Body + hands only.
    let (b, _) = Holistic723::split(&inter).unwrap();
    let p623 = dir.path().join("motionx.npy");
    dancegen_io::write_npy_f32(&p623, &[t - 1, 623], &split::to_split(&b, 0).unwrap()).unwrap();
    assert_eq!(split::read_split_npy(&p623, 30.0).unwrap().face, None);
    let bad = dir.path().join("bad.npy");
    dancegen_io::write_npy_f32(&bad, &[2, 263], &[0.0; 526]).unwrap();
    let e = split::read_split_npy(&bad, 30.0).unwrap_err().to_string();
    assert!(e.contains("bad.npy") && e.contains("[2, 263]"), "{e}");
}

/// A generated frame is not consistent data: a belly or hip joint a few centimetres off must
/// not turn the decoded body around. The root rotation is fitted on the whole body, so it moves
/// by a few degrees, as the joints did; a frame built from the hips and belly alone turned by
/// up to 3 rad on SoulNet's output (issue 41).
#[test]
fn holistic623_root_rotation_survives_a_displaced_belly() {
    let (_, poses, trans) = synthetic();
    let parts = Holistic623::encode(&poses, &trans, 30.0).unwrap();
    let clean = Holistic623::decode(&parts, 30.0).unwrap();
    let mut noisy = parts.clone();
    let dims = Holistic623::DIMS;
    let frames = noisy.len() / dims;
    // Joint 3 (belly, 10 cm above the pelvis) pushed 8 cm sideways and joint 1 (left hip) 4 cm
    // back, in every frame: the short vectors the root frame used to be built from.
    for f in 0..frames {
        let ric = f * dims + LAYOUT.ric();
        noisy[ric + 2 * 3] += 0.08;
        noisy[ric + 2] -= 0.04;
    }
    let moved = Holistic623::decode(&noisy, 30.0).unwrap();
    let mut worst = 0.0f64;
    for f in 0..frames {
        let aa = |p: &[f32]| {
            Mat3::from_axis_angle(
                [
                    p[f * JOINTS * 3],
                    p[f * JOINTS * 3 + 1],
                    p[f * JOINTS * 3 + 2],
                ]
                .map(f64::from),
            )
        };
        let d = aa(&clean.poses)
            .transpose()
            .mul(&aa(&moved.poses))
            .to_axis_angle();
        worst = worst.max(norm(d));
    }
    // Measured: 0.009 rad with the body fit, 0.644 rad with the hips-and-belly frame it
    // replaced. 0.25 rad (14°) is what a hand-placed 4 cm hip error alone turns a 12 cm hip
    // axis by (atan(4 / 12) = 0.32 rad) less a margin: a frame from those short vectors fails
    // it, a fit over the body passes with room.
    eprintln!("{SEQ}: root rotation moved by at most {worst:.3} rad");
    assert!(
        worst < 0.25,
        "the root turned by {worst:.3} rad for 8 cm of belly noise"
    );
}
