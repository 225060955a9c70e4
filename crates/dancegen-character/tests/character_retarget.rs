//! `--character`: an SMPL 24 dance put on a user's humanoid glTF character.
//!
//! Every output is evaluated independently of the library: the written GLB is parsed here, the
//! `dance` animation sampled, and forward kinematics run over the node TRS (or `matrix`) with
//! this file's own affine maths; the character's joints are then compared with the dance's own
//! FK. Synthetic characters with SMPL's proportions (Mixamo, VRM 1.0, Blender, UE with a 0.01
//! armature, SMPL names; T-pose, A-pose, facing −Z) must reproduce the dance exactly; the real
//! RobotExpressive (cartoon proportions, IK feet, no hand bones) must point every limb bone along
//! the dance's and keep its hands and feet within a stated tolerance.
//!
//! The Khronos validator checks every output (installed by `common::gltf_validator`, as for
//! the crate's other glTF tests) and must report no error — also for the robot, whose own file
//! has 752 (skin weights not summing to 1, which the writer renormalises).
//!
//! `DANCEGEN_TEST_KEEP=DIR` keeps the robot's output (`robot_dance.glb`, `robot_tpose.glb`: the
//! robot in SMPL's rest pose) and the dance on dancegen's own figure (`smpl_dance.glb`) in
//! `DIR`, to look at them in a viewer.

#![allow(clippy::needless_range_loop)] // x/y/z loops read clearer with indices

#[path = "../../dancegen-formats/tests/common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};

use dancegen_character::{
    self as character, Character, CharacterError, Convention, RetargetedAnimation,
    SMPL_NODES_EXTRA, Site,
};
use dancegen_formats::aistpp::load_motion;
use dancegen_formats::gltf::DancerAnimation;
use dancegen_motion::rotation::{Mat3, Quat};
use dancegen_motion::skeleton::{SMPL24_NAMES, SMPL24_PARENTS, Skeleton};
use dancegen_motion::{LocalRotations, forward_kinematics};
use serde_json::{Value, json};

// ---------------------------------------------------------------------------------------------
// The dance: a real AIST++ break-dance take (spins, kicks, a travelling root).

struct Dance {
    fps: f32,
    poses: Vec<f32>,
    trans: Vec<f32>,
    frames: usize,
}

impl Dance {
    fn animation(&self) -> DancerAnimation<'_> {
        DancerAnimation {
            local_rotations_axis_angle: &self.poses,
            root_translation: &self.trans,
        }
    }

    /// World joint positions `(T, 24)`.
    fn positions(&self) -> Vec<[f64; 3]> {
        let rot: Vec<f64> = self.poses.iter().map(|&v| v as f64).collect();
        let tr: Vec<f64> = self.trans.iter().map(|&v| v as f64).collect();
        let fk = forward_kinematics(
            &Skeleton::smpl24(),
            LocalRotations::AxisAngle(&rot),
            &tr,
            false,
        )
        .unwrap();
        fk.positions
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect()
    }
}

/// 150 frames (5 s at 30 fps) from the middle of an AIST++ break take.
fn dance() -> Dance {
    let path = common::shared_dir().join("data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl");
    let m = load_motion(&path)
        .unwrap()
        .to_smpl_motion()
        .resample_stride(2);
    let frames = 150;
    assert!(m.frames() >= frames, "{} frames", m.frames());
    let start = (m.frames() - frames) / 2;
    Dance {
        fps: m.fps,
        poses: m.poses[start * 72..(start + frames) * 72].to_vec(),
        trans: m.trans[start * 3..(start + frames) * 3].to_vec(),
        frames,
    }
}

// ---------------------------------------------------------------------------------------------
// An independent GLB reader and evaluator.

#[derive(Clone, Copy, Debug)]
struct Aff {
    l: Mat3,
    t: [f64; 3],
}

impl Aff {
    fn mul(&self, o: &Aff) -> Aff {
        Aff {
            l: self.l.mul(&o.l),
            t: self.point(o.t),
        }
    }
    fn point(&self, p: [f64; 3]) -> [f64; 3] {
        let v = self.l.mul_vec(p);
        [v[0] + self.t[0], v[1] + self.t[1], v[2] + self.t[2]]
    }
    fn inverse(&self) -> Aff {
        let a = &self.l.0;
        let det = self.l.determinant();
        let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
            a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
        };
        let inv = Mat3([
            [c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2)],
            [-c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2)],
            [c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1)],
        ]);
        let inv = Mat3(inv.0.map(|r| r.map(|v| v / det)));
        let t = inv.mul_vec(self.t);
        Aff {
            l: inv,
            t: [-t[0], -t[1], -t[2]],
        }
    }
    fn trs(t: [f64; 3], q: Quat, s: [f64; 3]) -> Aff {
        let r = q.to_mat3().0;
        Aff {
            l: Mat3(std::array::from_fn(|i| {
                std::array::from_fn(|j| r[i][j] * s[j])
            })),
            t,
        }
    }
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

struct Glb {
    doc: Value,
    bin: Vec<u8>,
}

/// Parses a GLB and checks the container: header, two chunks, 4-byte padding, one buffer.
fn parse_glb(bytes: &[u8]) -> Glb {
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(bytes, 4), 2);
    assert_eq!(u32_at(bytes, 8) as usize, bytes.len());
    let jl = u32_at(bytes, 12) as usize;
    assert_eq!(u32_at(bytes, 16), 0x4E4F_534A);
    assert_eq!(jl % 4, 0);
    let doc: Value = serde_json::from_slice(&bytes[20..20 + jl]).unwrap();
    let b0 = 20 + jl;
    let bl = u32_at(bytes, b0) as usize;
    assert_eq!(u32_at(bytes, b0 + 4), 0x004E_4942);
    assert_eq!(bl % 4, 0);
    assert_eq!(b0 + 8 + bl, bytes.len());
    let buffers = doc["buffers"].as_array().unwrap();
    assert_eq!(buffers.len(), 1, "one GLB buffer");
    assert!(buffers[0].get("uri").is_none());
    assert!(buffers[0]["byteLength"].as_u64().unwrap() as usize <= bl);
    for v in doc["bufferViews"].as_array().unwrap() {
        assert_eq!(v["buffer"], 0);
        assert_eq!(
            v["byteOffset"].as_u64().unwrap_or(0) % 4,
            0,
            "4-byte aligned views"
        );
    }
    Glb {
        doc,
        bin: bytes[b0 + 8..b0 + 8 + bl].to_vec(),
    }
}

impl Glb {
    /// Float accessor data, tightly packed.
    fn floats(&self, accessor: usize) -> Vec<f32> {
        let a = &self.doc["accessors"][accessor];
        assert_eq!(a["componentType"], 5126);
        let n = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            t => panic!("unexpected accessor type {t}"),
        };
        let count = a["count"].as_u64().unwrap() as usize;
        let v = &self.doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        assert!(v.get("byteStride").is_none());
        let off = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        (0..count * n)
            .map(|i| f32::from_le_bytes(self.bin[off + 4 * i..off + 4 * i + 4].try_into().unwrap()))
            .collect()
    }

    fn dance(&self) -> &Value {
        let anims = self.doc["animations"].as_array().unwrap();
        assert_eq!(anims.len(), 1, "the old animations are replaced by one");
        assert_eq!(anims[0]["name"], "dance");
        &anims[0]
    }

    /// World transforms of every node at time `t` (`None`: the rest pose, no animation).
    fn pose(&self, t: Option<f64>) -> Vec<Aff> {
        let nodes = self.doc["nodes"].as_array().unwrap();
        let num = |v: &Value| v.as_f64().unwrap();
        let vec3 = |v: &Value, d: [f64; 3]| {
            v.as_array()
                .map_or(d, |a| [num(&a[0]), num(&a[1]), num(&a[2])])
        };
        let mut trs: Vec<([f64; 3], Quat, [f64; 3])> = nodes
            .iter()
            .map(|n| {
                let q = n["rotation"].as_array().map_or(Quat::IDENTITY, |a| {
                    Quat::new(num(&a[3]), num(&a[0]), num(&a[1]), num(&a[2]))
                });
                (
                    vec3(&n["translation"], [0.0; 3]),
                    q,
                    vec3(&n["scale"], [1.0; 3]),
                )
            })
            .collect();
        if let Some(t) = t {
            let anim = self.dance();
            for ch in anim["channels"].as_array().unwrap() {
                let k = ch["target"]["node"].as_u64().unwrap() as usize;
                assert!(
                    nodes[k].get("matrix").is_none(),
                    "an animated node must not use matrix"
                );
                let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
                assert_eq!(s["interpolation"], "LINEAR");
                let times = self.floats(s["input"].as_u64().unwrap() as usize);
                let vals = self.floats(s["output"].as_u64().unwrap() as usize);
                let i = times
                    .partition_point(|&x| (x as f64) <= t)
                    .clamp(1, times.len())
                    - 1;
                let j = (i + 1).min(times.len() - 1);
                let u = if j == i {
                    0.0
                } else {
                    ((t - times[i] as f64) / (times[j] - times[i]) as f64).clamp(0.0, 1.0)
                };
                let w = vals.len() / times.len();
                let at = |k: usize| -> Vec<f64> {
                    vals[k * w..k * w + w].iter().map(|&v| v as f64).collect()
                };
                let (a, b) = (at(i), at(j));
                let v: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + u * (y - x)).collect();
                match ch["target"]["path"].as_str().unwrap() {
                    "rotation" => {
                        trs[k].1 = Quat::new(v[3], v[0], v[1], v[2]).normalize();
                    }
                    "translation" => trs[k].0 = [v[0], v[1], v[2]],
                    p => panic!("unexpected channel path {p}"),
                }
            }
        }
        let mut parent = vec![None; nodes.len()];
        for (i, n) in nodes.iter().enumerate() {
            for c in n["children"].as_array().into_iter().flatten() {
                parent[c.as_u64().unwrap() as usize] = Some(i);
            }
        }
        let local: Vec<Aff> = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| match n["matrix"].as_array() {
                Some(m) => {
                    let m: Vec<f64> = m.iter().map(num).collect();
                    Aff {
                        l: Mat3(std::array::from_fn(|r| {
                            std::array::from_fn(|c| m[4 * c + r])
                        })),
                        t: [m[12], m[13], m[14]],
                    }
                }
                None => Aff::trs(trs[i].0, trs[i].1, trs[i].2),
            })
            .collect();
        let mut world: Vec<Option<Aff>> = vec![None; nodes.len()];
        fn resolve(k: usize, p: &[Option<usize>], l: &[Aff], w: &mut Vec<Option<Aff>>) -> Aff {
            if let Some(a) = w[k] {
                return a;
            }
            let a = match p[k] {
                Some(q) => resolve(q, p, l, w).mul(&l[k]),
                None => l[k],
            };
            w[k] = Some(a);
            a
        }
        (0..nodes.len())
            .map(|k| resolve(k, &parent, &local, &mut world))
            .collect()
    }
}

// ---------------------------------------------------------------------------------------------
// Comparing the character with the dance.

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}
fn mid(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        (a[0] + b[0]) / 2.0,
        (a[1] + b[1]) / 2.0,
        (a[2] + b[2]) / 2.0,
    ]
}
fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (norm(a) * norm(b));
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

/// What the evaluation measured.
#[derive(Debug, Default)]
struct Report {
    /// Per frame, per SMPL joint: |character − dance × scale| relative to the hip centres, in
    /// the character's units (`None` for joints without a site).
    frame_err: Vec<Vec<Option<f64>>>,
    /// Max over frames of `frame_err`, as a fraction of the character's height.
    joint_err: Vec<Option<f64>>,
    /// Wrists and ankles at frames 0, T/2, T−1, fraction of height.
    sampled_hand_foot: Vec<f64>,
    /// Max angle between character and dance limb bones (thighs, shins, upper arms, forearms).
    limb_angle_deg: f64,
    /// Max error of the hip centre against the documented root formula, fraction of height.
    hip_centre_err: f64,
}

const LIMBS: [(usize, usize); 8] = [
    (1, 4),
    (2, 5),
    (4, 7),
    (5, 8),
    (16, 18),
    (17, 19),
    (18, 20),
    (19, 21),
];

fn evaluate(ch: &Character, bytes: &[u8], d: &Dance, anim: &RetargetedAnimation) -> Report {
    let glb = parse_glb(bytes);
    let rest = glb.pose(None);
    let src = d.positions();
    let f = Mat3::from_axis_rotation(1, anim.facing_yaw_degrees.to_radians());
    let s = anim.height_scale;
    let height = ch.rest_height();
    let sites = ch.bone_map().sites;
    // Each site as a point fixed in a node's frame.
    let anchors: Vec<Option<(usize, [f64; 3])>> = sites
        .iter()
        .map(|site| {
            let site = (*site)?;
            let k = match site {
                Site::Node(k) | Site::EndOf(k) => k,
            };
            let p = ch.rest_site_position(site)?;
            Some((k, rest[k].inverse().point(p)))
        })
        .collect();
    let mut rep = Report {
        joint_err: vec![None; 24],
        ..Report::default()
    };
    let samples = [0, d.frames / 2, d.frames - 1];
    for t in 0..d.frames {
        let mut errs = vec![None; 24];
        let world = glb.pose(Some(t as f64 / d.fps as f64));
        let at = |j: usize| anchors[j].map(|(k, q)| world[k].point(q));
        let ps = |j: usize| src[t * 24 + j];
        let ct = mid(at(1).unwrap(), at(2).unwrap());
        let cs = mid(ps(1), ps(2));
        for j in 0..24 {
            let Some(pt) = at(j) else { continue };
            let want = f.mul_vec(sub(ps(j), cs)).map(|v| v * s);
            let e = norm(sub(sub(pt, ct), want)) / height;
            errs[j] = Some(e * height);
            let slot = rep.joint_err[j].get_or_insert(0.0);
            *slot = slot.max(e);
            if samples.contains(&t) && [7, 8, 20, 21].contains(&j) {
                rep.sampled_hand_foot.push(e);
            }
        }
        for (a, b) in LIMBS {
            let got = sub(at(b).unwrap(), at(a).unwrap());
            let want = f.mul_vec(sub(ps(b), ps(a)));
            rep.limb_angle_deg = rep.limb_angle_deg.max(angle_deg(got, want));
        }
        let want_c = f.mul_vec([
            s * cs[0],
            anim.target_floor + s * (cs[1] - anim.source_floor),
            s * cs[2],
        ]);
        rep.hip_centre_err = rep.hip_centre_err.max(norm(sub(ct, want_c)) / height);
        rep.frame_err.push(errs);
    }
    // The rest pose (no animation) is the input's.
    let input_rest_hips = ch.nodes().rest_position(ch.bone_map().hips());
    let out_rest_hips = rest[ch.bone_map().hips()].t;
    assert!(norm(sub(input_rest_hips, out_rest_hips)) < 1e-6 * height.max(1.0));
    rep
}

// ---------------------------------------------------------------------------------------------
// The Khronos validator (installed into the target directory by `common::gltf_validator`, as
// for every other glTF test of this crate).

/// The validator's report on `path`.
fn validate(path: &Path) -> Value {
    common::gltf_validator::validate(path)
}

/// `(code, pointer)` of every error in a report.
fn errors(report: &Value) -> Vec<(String, String)> {
    report["issues"]["messages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|m| m["severity"] == 0)
        .map(|m| {
            (
                m["code"].as_str().unwrap_or("").to_string(),
                m["pointer"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect()
}

fn print_warnings(report: &Value) {
    for m in report["issues"]["messages"]
        .as_array()
        .into_iter()
        .flatten()
    {
        if m["severity"].as_u64().unwrap_or(9) <= 1 {
            eprintln!(
                "  [{}] {} {}: {}",
                m["severity"], m["code"], m["pointer"], m["message"]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Synthetic characters: SMPL's rest skeleton under other names, poses and armatures.

const MIXAMO: [&str; 24] = [
    "mixamorig:Hips",
    "mixamorig:LeftUpLeg",
    "mixamorig:RightUpLeg",
    "mixamorig:Spine",
    "mixamorig:LeftLeg",
    "mixamorig:RightLeg",
    "mixamorig:Spine1",
    "mixamorig:LeftFoot",
    "mixamorig:RightFoot",
    "mixamorig:Spine2",
    "mixamorig:LeftToeBase",
    "mixamorig:RightToeBase",
    "mixamorig:Neck",
    "mixamorig:LeftShoulder",
    "mixamorig:RightShoulder",
    "mixamorig:Head",
    "mixamorig:LeftArm",
    "mixamorig:RightArm",
    "mixamorig:LeftForeArm",
    "mixamorig:RightForeArm",
    "mixamorig:LeftHand",
    "mixamorig:RightHand",
    "mixamorig:LeftHandMiddle1",
    "mixamorig:RightHandMiddle1",
];

const BLENDER: [&str; 24] = [
    "Hips",
    "thigh.L",
    "thigh.R",
    "Spine",
    "shin.L",
    "shin.R",
    "Chest",
    "foot.L",
    "foot.R",
    "UpperChest",
    "toe.L",
    "toe.R",
    "Neck",
    "shoulder.L",
    "shoulder.R",
    "Head",
    "upper_arm.L",
    "upper_arm.R",
    "forearm.L",
    "forearm.R",
    "hand.L",
    "hand.R",
    "f_middle.01.L",
    "f_middle.01.R",
];

const UNREAL: [&str; 24] = [
    "pelvis",
    "thigh_l",
    "thigh_r",
    "spine_01",
    "calf_l",
    "calf_r",
    "spine_02",
    "foot_l",
    "foot_r",
    "spine_03",
    "ball_l",
    "ball_r",
    "neck_01",
    "clavicle_l",
    "clavicle_r",
    "head",
    "upperarm_l",
    "upperarm_r",
    "lowerarm_l",
    "lowerarm_r",
    "hand_l",
    "hand_r",
    "middle_01_l",
    "middle_01_r",
];

/// VRoid Studio's bone names (VRM without using its humanoid table).
const VROID: [&str; 24] = [
    "J_Bip_C_Hips",
    "J_Bip_L_UpperLeg",
    "J_Bip_R_UpperLeg",
    "J_Bip_C_Spine",
    "J_Bip_L_LowerLeg",
    "J_Bip_R_LowerLeg",
    "J_Bip_C_Chest",
    "J_Bip_L_Foot",
    "J_Bip_R_Foot",
    "J_Bip_C_UpperChest",
    "J_Bip_L_ToeBase",
    "J_Bip_R_ToeBase",
    "J_Bip_C_Neck",
    "J_Bip_L_Shoulder",
    "J_Bip_R_Shoulder",
    "J_Bip_C_Head",
    "J_Bip_L_UpperArm",
    "J_Bip_R_UpperArm",
    "J_Bip_L_LowerArm",
    "J_Bip_R_LowerArm",
    "J_Bip_L_Hand",
    "J_Bip_R_Hand",
    "J_Bip_L_Middle1",
    "J_Bip_R_Middle1",
];

/// VRM humanoid bone names in SMPL 24 order.
const VRM_BONES: [&str; 24] = [
    "hips",
    "leftUpperLeg",
    "rightUpperLeg",
    "spine",
    "leftLowerLeg",
    "rightLowerLeg",
    "chest",
    "leftFoot",
    "rightFoot",
    "upperChest",
    "leftToes",
    "rightToes",
    "neck",
    "leftShoulder",
    "rightShoulder",
    "head",
    "leftUpperArm",
    "rightUpperArm",
    "leftLowerArm",
    "rightLowerArm",
    "leftHand",
    "rightHand",
    "leftMiddleProximal",
    "rightMiddleProximal",
];

/// A synthetic rig: bone names, parents, world rest positions and local rest rotations, under
/// an armature node.
struct Rig {
    names: Vec<String>,
    parents: Vec<Option<usize>>,
    world: Vec<[f64; 3]>,
    local_rot: Vec<Quat>,
    armature_rot: Quat,
    armature_scale: f64,
    armature_matrix: bool,
    matrix_bones: Vec<usize>,
    extensions: Option<Value>,
}

impl Rig {
    /// SMPL's rest skeleton (pelvis 0.95 m above the floor) under `names`, plus a head-top end.
    fn smpl(names: &[&str; 24]) -> Rig {
        let sk = Skeleton::smpl24();
        let mut world: Vec<[f64; 3]> = sk
            .rest_positions()
            .iter()
            .map(|p| [p[0], p[1] + 0.95, p[2]])
            .collect();
        let mut parents: Vec<Option<usize>> = SMPL24_PARENTS
            .iter()
            .map(|&p| (p >= 0).then_some(p as usize))
            .collect();
        let mut names: Vec<String> = names.iter().map(|s| s.to_string()).collect();
        names.push("HeadTop_End".into());
        parents.push(Some(15));
        world.push([world[15][0], world[15][1] + 0.2, world[15][2]]);
        Rig {
            local_rot: vec![Quat::IDENTITY; names.len()],
            names,
            parents,
            world,
            armature_rot: Quat::IDENTITY,
            armature_scale: 1.0,
            armature_matrix: false,
            matrix_bones: Vec::new(),
            extensions: None,
        }
    }

    /// Arms 45° down (an A-pose), drawn with rotated upper-arm bones.
    fn a_pose(mut self) -> Rig {
        for (side, sign) in [(0usize, -1.0f64), (1, 1.0)] {
            let shoulder = 16 + side;
            let r = Quat::from_axis_angle([0.0, 0.0, sign * std::f64::consts::FRAC_PI_4]);
            self.local_rot[shoulder] = r;
            let base = self.world[shoulder];
            for j in [18 + side, 20 + side, 22 + side] {
                let v = r.rotate(sub(self.world[j], base));
                self.world[j] = [base[0] + v[0], base[1] + v[1], base[2] + v[2]];
            }
        }
        self
    }

    /// Facing −Z (VRM 0.x style): every position turned half a turn about Y.
    fn facing_back(mut self) -> Rig {
        for p in &mut self.world {
            *p = [-p[0], p[1], -p[2]];
        }
        self
    }

    /// FBX2glTF style: bones in Z-up centimetres under a `matrix` armature that turns −90° about
    /// X and scales by 0.01; the hips also given as a matrix.
    fn fbx_armature(mut self) -> Rig {
        self.armature_rot = Quat::from_axis_angle([-std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        self.armature_scale = 0.01;
        self.armature_matrix = true;
        self.matrix_bones = vec![0];
        self
    }

    fn world_frames(&self) -> Vec<Quat> {
        let mut f: Vec<Quat> = Vec::with_capacity(self.names.len());
        for j in 0..self.names.len() {
            let p = self.parents[j].map_or(self.armature_rot, |p| f[p]);
            f.push(p * self.local_rot[j]);
        }
        f
    }

    /// A valid skinned GLB: armature node 0, bones 1.., mesh node last, one old animation.
    fn glb(&self) -> Vec<u8> {
        let n = self.names.len();
        let frames = self.world_frames();
        let mut nodes: Vec<Value> = Vec::new();
        let arm = Aff::trs([0.0; 3], self.armature_rot, [self.armature_scale; 3]);
        let mut armature = json!({"name": "Armature", "children": [1]});
        if self.armature_matrix {
            let mut m = Vec::new();
            for c in 0..3 {
                for r in 0..3 {
                    m.push(arm.l.0[r][c]);
                }
                m.push(0.0);
            }
            m.extend([0.0, 0.0, 0.0, 1.0]);
            armature["matrix"] = json!(m);
        } else {
            let q = self.armature_rot;
            armature["rotation"] = json!([q.x, q.y, q.z, q.w]);
            let s = self.armature_scale;
            armature["scale"] = json!([s, s, s]);
        }
        nodes.push(armature);
        for j in 0..n {
            let (pf, pp) = match self.parents[j] {
                Some(p) => (frames[p], self.world[p]),
                None => (self.armature_rot, [0.0; 3]),
            };
            let t = pf
                .conjugate()
                .rotate(sub(self.world[j], pp))
                .map(|v| v / self.armature_scale);
            let q = self.local_rot[j];
            let mut node = json!({"name": self.names[j]});
            if self.matrix_bones.contains(&j) {
                let r = q.to_mat3().0;
                let mut m = Vec::new();
                for c in 0..3 {
                    for row in 0..3 {
                        m.push(r[row][c]);
                    }
                    m.push(0.0);
                }
                m.extend([t[0], t[1], t[2], 1.0]);
                node["matrix"] = json!(m);
            } else {
                node["translation"] = json!(t);
                node["rotation"] = json!([q.x, q.y, q.z, q.w]);
            }
            let kids: Vec<usize> = (0..n)
                .filter(|&c| self.parents[c] == Some(j))
                .map(|c| c + 1)
                .collect();
            if !kids.is_empty() {
                node["children"] = json!(kids);
            }
            nodes.push(node);
        }
        nodes.push(json!({"name": "Body", "mesh": 0, "skin": 0}));

        let mut bin: Vec<u8> = Vec::new();
        let mut push = |floats: &[f32], bytes: &[u8]| {
            let at = bin.len();
            bin.extend(floats.iter().flat_map(|f| f.to_le_bytes()));
            bin.extend(bytes);
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            (at, bin.len() - at)
        };
        let pos = push(&[0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.1, 0.0], &[]);
        let joints = push(&[], &[0; 12]);
        let weights = push(
            &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            &[],
        );
        let mut ibm = Vec::new();
        let inv_frames: Vec<Aff> = (0..n)
            .map(|j| {
                let w = Aff::trs(self.world[j], frames[j], [self.armature_scale; 3]);
                w.inverse()
            })
            .collect();
        for a in &inv_frames {
            for c in 0..3 {
                for r in 0..3 {
                    ibm.push(a.l.0[r][c] as f32);
                }
                ibm.push(0.0);
            }
            ibm.extend([a.t[0] as f32, a.t[1] as f32, a.t[2] as f32, 1.0]);
        }
        let ibm = push(&ibm, &[]);
        let times = push(&[0.0, 1.0], &[]);
        let q = self.local_rot[1];
        let rot = push(
            &[
                q.x as f32, q.y as f32, q.z as f32, q.w as f32, 0.0, 0.0, 0.0, 1.0,
            ],
            &[],
        );
        let view = |(o, l): (usize, usize)| json!({"buffer": 0, "byteOffset": o, "byteLength": l});
        let mut doc = json!({
            "asset": {"version": "2.0", "generator": "character_retarget test"},
            "scene": 0,
            "scenes": [{"nodes": [0, n + 1]}],
            "nodes": nodes,
            "meshes": [{"primitives": [{"attributes":
                {"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2}}]}],
            "skins": [{"joints": (1..=n).collect::<Vec<_>>(), "inverseBindMatrices": 3,
                "skeleton": 1}],
            "animations": [{"name": "old", "samplers": [{"input": 4, "output": 5}],
                "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]}],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [view(pos), view(joints), view(weights), view(ibm), view(times),
                view(rot)],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0.0, 0.0, 0.0], "max": [0.1, 0.1, 0.0]},
                {"bufferView": 1, "componentType": 5121, "count": 3, "type": "VEC4"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"},
                {"bufferView": 3, "componentType": 5126, "count": n, "type": "MAT4"},
                {"bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR",
                 "min": [0.0], "max": [1.0]},
                {"bufferView": 5, "componentType": 5126, "count": 2, "type": "VEC4"}
            ]
        });
        if let Some(ext) = &self.extensions {
            doc["extensions"] = ext.clone();
            doc["extensionsUsed"] = json!(ext.as_object().unwrap().keys().collect::<Vec<_>>());
        }
        glb_container(&serde_json::to_vec(&doc).unwrap(), &bin)
    }
}

fn glb_container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    for v in [0x4654_6C67u32, 2, total as u32, j.len() as u32, 0x4E4F_534A] {
        out.extend(v.to_le_bytes());
    }
    out.extend(&j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(&b);
    out
}

/// Loads `bytes` as `name` in a temporary folder, retargets the dance, writes and evaluates.
fn run(
    dir: &Path,
    name: &str,
    bytes: &[u8],
    d: &Dance,
) -> (Character, RetargetedAnimation, Report, PathBuf) {
    let input = dir.join(name);
    std::fs::write(&input, bytes).unwrap();
    let ch = Character::load(&input).unwrap_or_else(|e| panic!("{name}: {e}"));
    let anim = character::retarget(&ch, &Skeleton::smpl24(), &[d.animation()], d.fps).unwrap();
    let out = dir.join(format!("{name}.dance.glb"));
    character::write_glb(&out, &ch, &anim).unwrap();
    let written = std::fs::read(&out).unwrap();
    let rep = evaluate(&ch, &written, d, &anim);
    (ch, anim, rep, out)
}

/// Characters with SMPL's bone lengths reproduce the dance exactly, whatever their names, rest
/// pose, facing or armature: every joint (24 sites, relative to the hip centre) within 0.1 mm
/// — f32 keyframes along chains of up to 8 bones are good to ~1e-6 m, so 1e-4 only allows for
/// accumulated rounding.
#[test]
fn synthetic_characters_reproduce_the_dance() {
    let d = dance();
    let tmp = tempfile::tempdir().unwrap();
    let mut vrm_ext = serde_json::Map::new();
    for (j, b) in VRM_BONES.iter().enumerate() {
        vrm_ext.insert(b.to_string(), json!({"node": j + 1}));
    }
    let mut vrm = Rig::smpl(&std::array::from_fn(|j| {
        // Names that say nothing: only the humanoid table can map them.
        Box::leak(format!("bone_{j:02}").into_boxed_str()) as &str
    }));
    vrm.extensions = Some(json!({"VRMC_vrm": {"specVersion": "1.0",
        "meta": {"name": "test", "licenseUrl": "https://vrm.dev/licenses/1.0/",
                 "avatarPermission": "everyone", "authors": ["dancegen"]},
        "humanoid": {"humanBones": vrm_ext}}}));
    // VRM 0.x: a humanBones array, and the model faces −Z.
    let mut vrm0 = Rig::smpl(&std::array::from_fn(|j| {
        Box::leak(format!("node{j}").into_boxed_str()) as &str
    }))
    .facing_back();
    let bones: Vec<Value> = VRM_BONES
        .iter()
        .enumerate()
        .map(|(j, b)| json!({"bone": b, "node": j + 1, "useDefaultValues": true}))
        .collect();
    vrm0.extensions = Some(json!({"VRM": {"specVersion": "0.0",
        "humanoid": {"humanBones": bones}}}));
    let cases: Vec<(&str, Rig, Convention, f64)> = vec![
        ("vrm0.vrm", vrm0, Convention::Vrm0, 180.0),
        (
            "vroid_apose.glb",
            Rig::smpl(&VROID).a_pose(),
            Convention::BoneNames,
            0.0,
        ),
        (
            "mixamo_tpose.glb",
            Rig::smpl(&MIXAMO),
            Convention::BoneNames,
            0.0,
        ),
        (
            "mixamo_apose.glb",
            Rig::smpl(&MIXAMO).a_pose(),
            Convention::BoneNames,
            0.0,
        ),
        ("vrm1.vrm", vrm, Convention::Vrm1, 0.0),
        (
            "blender_back.glb",
            Rig::smpl(&BLENDER).facing_back(),
            Convention::BoneNames,
            180.0,
        ),
        (
            "unreal_fbx.glb",
            Rig::smpl(&UNREAL).fbx_armature(),
            Convention::BoneNames,
            0.0,
        ),
        (
            "smpl.glb",
            Rig::smpl(&SMPL24_NAMES).a_pose(),
            Convention::SmplNames,
            0.0,
        ),
    ];
    for (name, rig, convention, yaw) in cases {
        let (ch, anim, rep, out) = run(tmp.path(), name, &rig.glb(), &d);
        let m = ch.bone_map();
        assert_eq!(m.convention, convention, "{name}");
        for j in 0..22 {
            // Joint j is node j + 1 (node 0 is the armature); SMPL's lhand/rhand are the
            // middle fingers, which only aim the hands.
            assert_eq!(
                m.node_for(j),
                Some(j + 1),
                "{name}: SMPL joint {}",
                SMPL24_NAMES[j]
            );
        }
        assert_eq!(anim.facing_yaw_degrees, yaw, "{name}");
        assert!(
            (anim.height_scale - 1.0).abs() < 1e-9,
            "{name}: {}",
            anim.height_scale
        );
        let worst = rep
            .joint_err
            .iter()
            .flatten()
            .fold(0.0f64, |a, &b| a.max(b));
        let height = ch.rest_height();
        eprintln!(
            "{name}: worst joint {:.2e} m, limbs {:.2e}°, hip centre {:.2e} m",
            worst * height,
            rep.limb_angle_deg,
            rep.hip_centre_err * height
        );
        assert_eq!(
            rep.joint_err.iter().flatten().count(),
            24,
            "{name}: every joint has a site"
        );
        assert!(
            worst * height < 1e-4,
            "{name}: joint error {} m",
            worst * height
        );
        assert!(rep.limb_angle_deg < 0.01, "{name}: {}°", rep.limb_angle_deg);
        assert!(rep.hip_centre_err * height < 1e-4, "{name}");

        // The old animation and its data are gone; the mesh data is byte-identical.
        let glb = parse_glb(&std::fs::read(&out).unwrap());
        let channels = anim.rotations.len() + anim.translations.len();
        assert_eq!(
            glb.doc["accessors"].as_array().unwrap().len(),
            4 + 1 + channels,
            "{name}: mesh and skin accessors, key times, one per channel"
        );
        let input = parse_glb(&rig.glb());
        assert_eq!(
            &glb.bin[..216],
            &input.bin[..216],
            "{name}: mesh bytes kept"
        );
        {
            let report = validate(&out);
            print_warnings(&report);
            assert_eq!(errors(&report), vec![], "{name}: validator errors");
        }
    }
}

/// RobotExpressive (three.js, CC0): FBX2glTF output with a 100× armature, IK feet hanging from
/// the root bone, a `Hips` bone the legs do not hang from, palms instead of hand bones,
/// duplicated names and 14 animations.
#[test]
fn robot_expressive_dances() {
    let robot =
        common::shared_dir().join("data/holistic/three-js-robot-expressive/RobotExpressive.glb");
    let d = dance();
    let tmp = tempfile::tempdir().unwrap();
    let (ch, anim, rep, out) = run(
        tmp.path(),
        "RobotExpressive.glb",
        &std::fs::read(&robot).unwrap(),
        &d,
    );
    eprint!("{}", ch.describe_bone_map());
    // The animation names the node each SMPL joint drives, for viewers (the web app's frames
    // the robot's head and chest with it).
    let glb = parse_glb(&std::fs::read(&out).unwrap());
    let listed = glb.dance()["extras"][SMPL_NODES_EXTRA]
        .as_array()
        .expect("the SMPL nodes in the animation's extras")
        .iter()
        .map(Value::as_u64)
        .collect::<Vec<_>>();
    let want: Vec<Option<u64>> = (0..24)
        .map(|j| ch.bone_map().node_for(j).map(|k| k as u64))
        .collect();
    assert_eq!(listed, want);
    let name = |j: usize| glb.doc["nodes"][listed[j].unwrap() as usize]["name"].clone();
    assert_eq!((name(0), name(15)), ("Body".into(), "Head".into()));
    if let Some(keep) = std::env::var_os("DANCEGEN_TEST_KEEP") {
        // For looking at the result: the robot dancing and the dance on dancegen's own figure.
        let keep = Path::new(&keep);
        std::fs::copy(&out, keep.join("robot_dance.glb")).unwrap();
        let opts = dancegen_formats::gltf::GlbOptions::default();
        dancegen_formats::gltf::write_glb(
            keep.join("smpl_dance.glb"),
            &Skeleton::smpl24(),
            &d.poses,
            &d.trans,
            d.fps,
            &opts,
        )
        .unwrap();
        // SMPL's rest pose (a T-pose, feet planted) with the same hips path.
        let rest = vec![0.0f32; d.poses.len()];
        let t_pose = DancerAnimation {
            local_rotations_axis_angle: &rest,
            root_translation: &d.trans,
        };
        let a = character::retarget(&ch, &Skeleton::smpl24(), &[t_pose], d.fps).unwrap();
        character::write_glb(keep.join("robot_tpose.glb"), &ch, &a).unwrap();
    }
    let m = ch.bone_map();
    assert_eq!(m.convention, Convention::BoneNames);
    // Keyed by node index: `Body` (6) is the hips, `Hips` (8), `Abdomen`, `Torso` the spine.
    assert_eq!(m.hips(), 6);
    let want = [
        (3, 8),   // belly ← Hips
        (6, 9),   // spine ← Abdomen
        (9, 10),  // chest ← Torso
        (12, 11), // neck
        (15, 12), // head (the bone, not the mesh node 13 of the same name)
        (13, 15), // linshoulder ← Shoulder.L
        (16, 17), // lshoulder ← UpperArm.L
        (18, 19), // lelbow ← LowerArm.L
        (1, 55),  // lhip ← UpperLeg.L
        (4, 57),  // lknee ← LowerLeg.L
        (7, 3),   // lankle ← Foot.L, hanging from the root bone
        (17, 37),
        (19, 39),
        (2, 60),
        (5, 62),
        (8, 67),
    ];
    for (j, node) in want {
        assert_eq!(m.node_for(j), Some(node), "SMPL joint {}", SMPL24_NAMES[j]);
    }
    let foot = m.bones.iter().find(|b| b.node == 3).unwrap();
    assert_eq!(foot.detached_from, Some(57), "the IK foot follows the shin");
    assert_eq!(
        m.nodes_for(20),
        vec![20, 24, 27, 31],
        "the palms turn with the wrist"
    );
    assert_eq!(m.sites[20], Some(Site::EndOf(19)));
    assert_eq!(anim.facing_yaw_degrees, 0.0);

    let height = ch.rest_height();
    let hands_feet: Vec<f64> = [7, 8, 20, 21]
        .iter()
        .map(|&j| rep.joint_err[j].unwrap())
        .collect();
    let sampled_max = rep.sampled_hand_foot.iter().fold(0.0f64, |a, &b| a.max(b));
    eprintln!(
        "RobotExpressive: height {height:.3}, scale {:.3}, source floor {:.3} m, target floor \
         {:.3}; max over {} frames (fraction of height) lankle {:.3} rankle {:.3} lwrist {:.3} \
         rwrist {:.3}; at frames 0, T/2, T-1: {:?} (max {:.3}); limb bones {:.4}°; hip centre \
         {:.1e}",
        anim.height_scale,
        anim.source_floor,
        anim.target_floor,
        d.frames,
        hands_feet[0],
        hands_feet[1],
        hands_feet[2],
        hands_feet[3],
        rep.sampled_hand_foot
            .iter()
            .map(|e| (e * 1000.0).round() / 1000.0)
            .collect::<Vec<_>>(),
        sampled_max,
        rep.limb_angle_deg,
        rep.hip_centre_err,
    );
    // Bone directions are transferred exactly: only f32 keyframes separate them.
    assert!(
        rep.limb_angle_deg < 0.05,
        "limb bones off by {}°",
        rep.limb_angle_deg
    );
    assert!(rep.hip_centre_err < 1e-5);
    // Hands and feet cannot match: the robot does not have SMPL's proportions. With every
    // bone direction exact, a limb end's offset from the hip centre differs from the dance's
    // (scaled) by at most the summed length differences of the segments on the way (triangle
    // inequality): for a foot the hip half-width, thigh and shin; for a hand the shoulder's own
    // offset error plus the upper arm and forearm. That bound is checked in every frame — an
    // alignment or mapping bug (a bone turned the wrong way, sides swapped) breaks it.
    let sk = Skeleton::smpl24();
    let src = sk.rest_positions();
    let s = anim.height_scale;
    let tgt = |j: usize| ch.rest_site_position(m.sites[j].unwrap()).unwrap();
    let seg =
        |a: usize, b: usize| (norm(sub(tgt(b), tgt(a))) - s * norm(sub(src[b], src[a]))).abs();
    let half = (0.5 * norm(sub(tgt(1), tgt(2))) - 0.5 * s * norm(sub(src[1], src[2]))).abs();
    let tol = 1e-5 * height;
    let mut foot_bound = [0.0; 2];
    let mut hand_slack = f64::INFINITY;
    for side in 0..2 {
        foot_bound[side] = half + seg(1 + side, 4 + side) + seg(4 + side, 7 + side);
        let arm = seg(16 + side, 18 + side) + seg(18 + side, 20 + side);
        for (t, e) in rep.frame_err.iter().enumerate() {
            let foot = e[7 + side].unwrap();
            assert!(
                foot <= foot_bound[side] + tol,
                "frame {t}: foot {foot} > {}",
                foot_bound[side]
            );
            let (hand, shoulder) = (e[20 + side].unwrap(), e[16 + side].unwrap());
            assert!(
                hand <= shoulder + arm + tol,
                "frame {t}: hand {hand} > {shoulder} + {arm}"
            );
            hand_slack = hand_slack.min(shoulder + arm - hand);
        }
    }
    eprintln!(
        "RobotExpressive bounds: feet ≤ {:.3} / {:.3} of height (segment length differences), \
         hands ≤ shoulder error + {:.3} / {:.3}",
        foot_bound[0] / height,
        foot_bound[1] / height,
        (seg(16, 18) + seg(18, 20)) / height,
        (seg(17, 19) + seg(19, 21)) / height,
    );
    // And as plain numbers (measured on this dance, fractions of the robot's 4.08-unit
    // height): feet ≤ 0.16 — its hips are 1.27 wide, SMPL's scaled 0.22, which alone moves each
    // foot 0.13 sideways — and hands ≤ 0.44 — its forearm-plus-palm is 1.37 long against SMPL's
    // scaled 0.50. The limits leave ~25 % margin over those measurements.
    assert!(
        hands_feet[0].max(hands_feet[1]) < 0.2,
        "feet {hands_feet:?}"
    );
    assert!(
        hands_feet[2].max(hands_feet[3]) < 0.55,
        "hands {hands_feet:?}"
    );

    // Only the dance remains; the mesh, morph targets and materials are untouched.
    let glb = parse_glb(&std::fs::read(&out).unwrap());
    let input = parse_glb(&std::fs::read(&robot).unwrap());
    for key in ["meshes", "materials", "skins", "scenes"] {
        let (a, b) = (&glb.doc[key], &input.doc[key]);
        if key == "meshes" || key == "skins" {
            assert_eq!(a.as_array().unwrap().len(), b.as_array().unwrap().len());
        } else {
            assert_eq!(a, b, "{key}");
        }
    }
    assert_eq!(
        glb.doc["meshes"][2]["extras"]["targetNames"],
        json!(["Angry", "Surprised", "Sad"])
    );
    assert!(
        glb.bin.len() < input.bin.len(),
        "the 14 old animations' data is dropped"
    );

    {
        let report = validate(&out);
        // The input has 752 errors (ACCESSOR_WEIGHTS_NON_NORMALIZED: skin weights summing to
        // e.g. 0.98); the writer renormalises them, so the output has none.
        let before = validate(&robot);
        eprintln!(
            "validator: input {} errors, output {} errors",
            errors(&before).len(),
            errors(&report).len()
        );
        assert!(
            !errors(&before).is_empty(),
            "the fixture's known weight sums"
        );
        print_warnings(&report);
        assert_eq!(errors(&report), vec![], "the output validates");
    }
}

/// The same inputs give the same bytes.
#[test]
fn output_is_deterministic() {
    let d = dance();
    let ch = Character::from_bytes("mixamo.glb", &Rig::smpl(&MIXAMO).a_pose().glb()).unwrap();
    let a = character::retarget(&ch, &Skeleton::smpl24(), &[d.animation()], d.fps).unwrap();
    let b = character::retarget(&ch, &Skeleton::smpl24(), &[d.animation()], d.fps).unwrap();
    assert_eq!(
        character::glb_bytes(&ch, &a).unwrap(),
        character::glb_bytes(&ch, &b).unwrap()
    );
}

/// A `.gltf` with an external `.bin`, an external PNG and a data-URI image becomes one GLB with
/// both images embedded.
#[test]
fn gltf_with_external_files_becomes_one_glb() {
    let tmp = tempfile::tempdir().unwrap();
    let glb = parse_glb(&Rig::smpl(&MIXAMO).glb());
    let mut doc = glb.doc.clone();
    std::fs::write(tmp.path().join("body data.bin"), &glb.bin).unwrap();
    doc["buffers"][0]["uri"] = json!("body%20data.bin");
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, 2, 2);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[200u8; 16]).unwrap();
    }
    std::fs::write(tmp.path().join("skin.png"), &png_bytes).unwrap();
    use base64::Engine as _;
    let b64 = base64::engine::general_purpose::STANDARD.encode(&png_bytes);
    doc["images"] = json!([{"uri": "skin.png"}, {"uri": format!("data:image/png;base64,{b64}")}]);
    doc["textures"] = json!([{"source": 0}, {"source": 1}]);
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
        "emissiveTexture": {"index": 1}}]);
    // (Unused by the mesh, which has no texture coordinates: the validator would call binding
    // it an error.)
    let input = tmp.path().join("character.gltf");
    std::fs::write(&input, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();

    let d = dance();
    let ch = Character::load(&input).unwrap();
    let anim = character::retarget(&ch, &Skeleton::smpl24(), &[d.animation()], d.fps).unwrap();
    let out = tmp.path().join("out.glb");
    character::write_glb(&out, &ch, &anim).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let g = parse_glb(&bytes);
    for i in 0..2 {
        let img = &g.doc["images"][i];
        assert!(img.get("uri").is_none());
        assert_eq!(img["mimeType"], "image/png");
        let v = &g.doc["bufferViews"][img["bufferView"].as_u64().unwrap() as usize];
        let off = v["byteOffset"].as_u64().unwrap() as usize;
        assert_eq!(&g.bin[off..off + png_bytes.len()], &png_bytes[..]);
    }
    let rep = evaluate(&ch, &bytes, &d, &anim);
    let worst = rep
        .joint_err
        .iter()
        .flatten()
        .fold(0.0f64, |a, &b| a.max(b));
    assert!(worst * ch.rest_height() < 1e-4);
    {
        let report = validate(&out);
        print_warnings(&report);
        assert_eq!(errors(&report), vec![]);
    }
}

#[test]
fn bad_characters_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    // Not glTF at all.
    let song = tmp.path().join("song.glb");
    std::fs::write(&song, b"ID3\x03\x00 not a model").unwrap();
    let e = Character::load(&song).unwrap_err();
    assert!(matches!(e, CharacterError::NotGltf { .. }), "{e}");
    assert!(e.to_string().contains("song.glb: not a glTF file"), "{e}");
    // A missing file.
    let e = Character::load(tmp.path().join("nope.vrm")).unwrap_err();
    assert!(matches!(e, CharacterError::Read { .. }), "{e}");
    // A mesh without a skin.
    let statue = tmp.path().join("statue.gltf");
    std::fs::write(
        &statue,
        r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"name": "Statue", "mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]}]}"#,
    )
    .unwrap();
    let e = Character::load(&statue).unwrap_err();
    assert!(matches!(e, CharacterError::NoSkin { .. }), "{e}");
    assert_eq!(
        e.to_string(),
        format!(
            "{} has no skinned mesh: a humanoid character needs a skin (an armature)",
            statue.display()
        )
    );
    // A skinned character without a left arm below the shoulder, and no head (nor a neck whose
    // child could be taken for one).
    let mut rig = Rig::smpl(&MIXAMO);
    for j in [18, 20, 22, 15, 12] {
        rig.names[j] = format!("Bone{j}");
    }
    rig.names[24] = "Bone24".into();
    let e = Character::from_bytes("onearm.glb", &rig.glb()).unwrap_err();
    let CharacterError::MissingBones { missing, bones, .. } = &e else {
        panic!("{e}")
    };
    eprintln!("{e}");
    assert_eq!(
        missing,
        &vec![
            "lelbow (left forearm)".to_string(),
            "lwrist (left hand)".to_string(),
            "head (head)".to_string()
        ]
    );
    assert!(
        bones.contains(&"mixamorig:LeftArm".to_string()) && bones.contains(&"Bone18".to_string())
    );
    assert!(
        e.to_string()
            .starts_with("onearm.glb: cannot find these bones"),
        "{e}"
    );
    // Truncated and corrupted copies of a real character never panic.
    let good = Rig::smpl(&MIXAMO).glb();
    for cut in (0..good.len()).step_by(97) {
        let _ = Character::from_bytes("cut.glb", &good[..cut]);
    }
    let mut bad = good.clone();
    for i in (20..200).step_by(7) {
        bad[i] = b'#';
    }
    assert!(Character::from_bytes("bad.glb", &bad).is_err());
}

#[test]
fn wrong_dances_are_clear_errors() {
    let d = dance();
    let ch = Character::from_bytes("mixamo.glb", &Rig::smpl(&MIXAMO).glb()).unwrap();
    let sk = Skeleton::smpl24();
    let e = character::retarget(&ch, &sk, &[d.animation(), d.animation()], d.fps).unwrap_err();
    assert!(
        e.to_string().contains("--character takes one dancer"),
        "{e}"
    );
    let e = character::retarget(&ch, &sk, &[], d.fps).unwrap_err();
    assert!(e.to_string().contains("one dancer"), "{e}");
    let short = DancerAnimation {
        local_rotations_axis_angle: &d.poses[..71],
        root_translation: &d.trans[..3],
    };
    assert!(character::retarget(&ch, &sk, &[short], d.fps).is_err());
    assert!(character::retarget(&ch, &sk, &[d.animation()], 0.0).is_err());
    let other = Skeleton::smplh52_approx();
    assert!(character::retarget(&ch, &other, &[d.animation()], d.fps).is_err());
}

/// With an extension whose references are unknown, nothing is renumbered: the old animation's
/// accessors stay (unused), everything still validates. Meshopt compression is refused when the
/// character is loaded, before any dance is generated.
#[test]
fn unknown_extensions_keep_all_data() {
    let d = dance();
    let mut rig = Rig::smpl(&MIXAMO);
    rig.extensions = Some(json!({"EXT_future_thing": {"note": "refers to accessor 5"}}));
    let tmp = tempfile::tempdir().unwrap();
    let (_, anim, rep, out) = run(tmp.path(), "future.glb", &rig.glb(), &d);
    let worst = rep
        .joint_err
        .iter()
        .flatten()
        .fold(0.0f64, |a, &b| a.max(b));
    assert!(worst < 1e-4);
    let glb = parse_glb(&std::fs::read(&out).unwrap());
    let channels = anim.rotations.len() + anim.translations.len();
    assert_eq!(
        glb.doc["accessors"].as_array().unwrap().len(),
        6 + 1 + channels
    );
    assert_eq!(
        glb.doc["extensions"]["EXT_future_thing"]["note"],
        "refers to accessor 5"
    );
    {
        let report = validate(&out);
        assert_eq!(errors(&report), vec![]);
    }

    rig.extensions = Some(json!({"EXT_meshopt_compression": {}}));
    let e = Character::from_bytes("packed.glb", &rig.glb()).unwrap_err();
    assert!(matches!(e, CharacterError::Unsupported { .. }), "{e}");
    assert!(e.to_string().contains("EXT_meshopt_compression"), "{e}");
}

/// dancegen's own `.glb` figure (SMPL names, capsule mesh) is a character too, and dances its
/// own dance exactly.
#[test]
fn dancegen_figure_is_a_character() {
    let d = dance();
    let tmp = tempfile::tempdir().unwrap();
    let figure = tmp.path().join("figure.glb");
    let opts = dancegen_formats::gltf::GlbOptions::default();
    dancegen_formats::gltf::write_glb(
        &figure,
        &Skeleton::smpl24(),
        &d.poses[..72],
        &d.trans[..3],
        d.fps,
        &opts,
    )
    .unwrap();
    let (ch, anim, rep, _) = run(
        tmp.path(),
        "figure.glb",
        &std::fs::read(&figure).unwrap(),
        &d,
    );
    assert_eq!(ch.bone_map().convention, Convention::SmplNames);
    assert!((anim.height_scale - 1.0).abs() < 1e-9);
    let worst = rep
        .joint_err
        .iter()
        .flatten()
        .fold(0.0f64, |a, &b| a.max(b));
    assert!(worst * ch.rest_height() < 1e-4, "{worst}");
}
