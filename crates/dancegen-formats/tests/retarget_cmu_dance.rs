//! Retargeting the CMU dance BVHs (shared/data/cmu-dance) of the two other naming conventions
//! to SMPL 24 at 30 fps: cgspeed (modern 05_02, whirl 55_01; 120 fps, frame 0 a reference
//! T-pose) and Unity humanoid (break 85_03, and 85_04 whose rest pose is a crouch).
//!
//! Asserted, with the reasons for each bound:
//! - Frame counts: cgspeed drops frame 0 and keeps source frames 1, 5, 9, …, i.e.
//!   `ceil((frames − 1) / 4)`; Unity (30 fps) keeps every frame. Retargeting the same file with
//!   frame 0 cut off by hand gives bit-identical output, so exactly the T-pose frame went and
//!   the rule does not fire on a dance frame.
//! - Mean bone direction error (SMPL FK bone vs the source bone it is aligned to) < 0.01°:
//!   zero by construction up to the f32 poses (~1e-5°); a wrong alignment or rotation order
//!   gives degrees to tens of degrees.
//! - Joint positions: every leg joint (hips, knees, ankles, toes) within 6 cm on average
//!   (measured 2.8–5.1 cm: hip width and shin length mismatches), and the motion's mean error
//!   within 2 cm of the rest-pose (proportions-only) error. The upper body of the cgspeed
//!   skeletons is short for their legs (shoulders ≈ 17 cm below SMPL's once the legs match), so
//!   their all-joint mean is ≈ 9.5 cm; bound 12 cm (Unity: ≈ 4.5 cm, bound 7 cm).
//! - Height after SMPL FK: SMPL keeps its own bones (rest head-to-ankle 1.514 m), so the
//!   standing height can only be ≤ 1.52 m; the tallest frames (90th percentile of head minus
//!   the lower ankle) must be 1.35–1.53 m, i.e. the dancer is upright and the head is above
//!   the feet, at some point of every take (upside-down or lying retargets fail).
//! - Feet on the floor: the lowest of ankles and toes, 10th percentile over frames, within
//!   −5…+8 cm of y = 0 (the source floor; measured 0.0–3.6 cm; the SMPL toe joint sits a few cm
//!   above the sole). Normalising the cgspeed files by head height instead of leg length would
//!   float them ≈ 14 cm.
//! - Left is left: in ≥ 99 % of (frame, joint) pairs each SMPL left hip/knee/ankle/shoulder/
//!   elbow/wrist is nearer the source's `Left*` joint than its `Right*` one (a breakdance leg
//!   crossing gives 1 miss in 4404).
//! - Facing: the SMPL pelvis forward (hip axis × pelvis up) within 1° of the source's, per
//!   frame (measured 0.0°): a mirrored or reversed root fails by 180°.
//! - Units and NaN: all poses and translations finite.

mod common;

use std::path::{Path, PathBuf};

use dancegen_formats::bvh::{Bvh, BvhReadOptions, parse_bvh, read_bvh};
use dancegen_formats::bvh_motion::{BvhMotionError, bvh_world_positions, smpl_fk_f64};
use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, convert_motion};
use dancegen_formats::retarget::{
    CGSPEED, UNITY_HUMANOID, detect_convention, has_reference_tpose, retarget_report,
    retarget_to_smpl,
};
use dancegen_motion::vec3::{cross, dot, norm, sub};

fn dance(rel: &str) -> PathBuf {
    common::shared_dir().join("data/cmu-dance").join(rel)
}

fn read(path: &Path) -> Bvh {
    read_bvh(path, &BvhReadOptions::default()).unwrap()
}

/// `q`-quantile (nearest rank) of `v`.
fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
    (dot(a, b) / (norm(a) * norm(b)))
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

fn mid(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]))
}

/// SMPL joint, source left name, source right name (prefix added by the caller).
const SIDES: [(usize, &str, &str); 6] = [
    (1, "LeftUpLeg", "RightUpLeg"),
    (4, "LeftLeg", "RightLeg"),
    (7, "LeftFoot", "RightFoot"),
    (16, "LeftArm", "RightArm"),
    (18, "LeftForeArm", "RightForeArm"),
    (20, "LeftHand", "RightHand"),
];

/// Leg joints whose per-joint mean error is bounded.
const LEG_JOINTS: [&str; 8] = [
    "lhip", "rhip", "lknee", "rknee", "lankle", "rankle", "ltoes", "rtoes",
];

fn check_file(rel: &str, cgspeed: bool) {
    let path = dance(rel);
    let bvh = read(&path);
    let det = detect_convention(&bvh).unwrap();
    let want = if cgspeed { &CGSPEED } else { &UNITY_HUMANOID };
    assert_eq!(det.convention.name, want.name, "{rel}");
    let out = retarget_to_smpl(&bvh, 30.0).unwrap();
    let rep = retarget_report(&bvh, &out).unwrap();
    println!("{rel} ({}): {rep}", det.convention.name);

    // Frame counts and the reference frame.
    assert_eq!(out.fps, 30.0, "{rel}");
    if cgspeed {
        assert_eq!(out.stride, 4, "{rel}");
        assert_eq!(out.first_frame, 1, "{rel}");
        assert_eq!(out.frames, (bvh.frames - 1).div_ceil(4), "{rel}");
        // Cut frame 0 off by hand: the rule must not fire again, and the output must match.
        let nc = bvh.num_channels();
        let mut cut = bvh.clone();
        cut.frames -= 1;
        cut.data.drain(..nc);
        assert!(!has_reference_tpose(&cut, &det).unwrap(), "{rel}");
        let again = retarget_to_smpl(&cut, 30.0).unwrap();
        assert_eq!(again.first_frame, 0);
        assert_eq!(again.poses, out.poses, "{rel}");
        assert_eq!(again.trans, out.trans, "{rel}");
    } else {
        assert_eq!(out.stride, 1, "{rel}");
        assert_eq!(out.first_frame, 0, "{rel}");
        assert_eq!(out.frames, bvh.frames, "{rel}");
    }
    assert_eq!(out.poses.len(), out.frames * 72);
    assert_eq!(out.trans.len(), out.frames * 3);
    assert!(out.poses.iter().chain(&out.trans).all(|v| v.is_finite()));

    // Report bounds (module documentation).
    assert!(
        rep.mean_bone_angle_deg < 0.01,
        "{rel}: {}",
        rep.mean_bone_angle_deg
    );
    for (name, cm) in &rep.per_joint_error_cm {
        if LEG_JOINTS.contains(name) {
            assert!(*cm < 6.0, "{rel}: {name} {cm} cm");
        }
    }
    let mean_bound = if cgspeed { 12.0 } else { 7.0 };
    assert!(
        rep.mean_error_cm < mean_bound,
        "{rel}: {}",
        rep.mean_error_cm
    );
    assert!(
        rep.mean_error_cm < rep.rest_mean_error_cm + 2.0,
        "{rel}: {} vs rest {}",
        rep.mean_error_cm,
        rep.rest_mean_error_cm
    );

    // Geometry of the SMPL FK against the height-normalised source.
    let fk = smpl_fk_f64(&out.poses, &out.trans).unwrap();
    let smpl = |k: usize, j: usize| [0, 1, 2].map(|a| fk[(k * 24 + j) * 3 + a]);
    let (_, nj, src_pos) = bvh_world_positions(&bvh, out.metres_per_unit).unwrap();
    let src = |f: usize, name: &str| {
        let i = bvh.joint_index(&format!("{}{name}", det.prefix)).unwrap();
        [0, 1, 2].map(|a| src_pos[(f * nj + i) * 3 + a])
    };
    // The source joint that drives SMPL belly is rigid in the source root: pelvis "up".
    let belly = det.convention.map[3].rotation_from.unwrap();
    let (mut heights, mut lowest, mut facing_worst) = (Vec::new(), Vec::new(), 0.0f64);
    let (mut left_ok, mut left_n) = (0usize, 0usize);
    for k in 0..out.frames {
        let f = out.first_frame + k * out.stride;
        heights.push(smpl(k, 15)[1] - smpl(k, 7)[1].min(smpl(k, 8)[1]));
        lowest.push(
            [7, 8, 10, 11]
                .map(|j| smpl(k, j)[1])
                .into_iter()
                .fold(f64::INFINITY, f64::min),
        );
        for (j, l, r) in SIDES {
            let p = smpl(k, j);
            left_n += 1;
            left_ok += usize::from(norm(sub(p, src(f, l))) < norm(sub(p, src(f, r))));
        }
        let f_smpl = cross(
            sub(smpl(k, 1), smpl(k, 2)),
            sub(smpl(k, 3), mid(smpl(k, 1), smpl(k, 2))),
        );
        let (sl, sr) = (src(f, "LeftUpLeg"), src(f, "RightUpLeg"));
        let f_src = cross(sub(sl, sr), sub(src(f, belly), mid(sl, sr)));
        facing_worst = facing_worst.max(angle_deg(f_smpl, f_src));
    }
    let tall = quantile(heights, 0.9);
    let low = quantile(lowest, 0.1);
    println!(
        "{rel}: head-to-ankle p90 {tall:.3} m, lowest foot joint p10 {low:.3} m, left {left_ok}/{left_n}, facing worst {facing_worst:.3}°"
    );
    assert!((1.35..1.53).contains(&tall), "{rel}: {tall}");
    assert!((-0.05..0.08).contains(&low), "{rel}: {low}");
    assert!(
        left_ok as f64 >= 0.99 * left_n as f64,
        "{rel}: {left_ok}/{left_n}"
    );
    assert!(facing_worst < 1.0, "{rel}: {facing_worst}");
}

#[test]
fn cgspeed_modern() {
    check_file("modern/05_02.bvh", true);
}

#[test]
fn cgspeed_whirl() {
    check_file("whirl/55_01_cmu120.bvh", true);
}

#[test]
fn unity_break() {
    check_file("break/85_03_neo30.bvh", false);
}

#[test]
fn unity_break_crouched_rest_pose() {
    check_file("break/85_04_neo30.bvh", false);
}

/// Every cgspeed file starts with the reference T-pose; no Unity file does.
#[test]
fn reference_frame_rule_on_every_file() {
    for dir in ["modern", "whirl", "break"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dance(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "bvh"))
            .collect();
        files.sort();
        assert!(!files.is_empty());
        for p in files {
            let bvh = read(&p);
            let det = detect_convention(&bvh).unwrap();
            assert_eq!(
                has_reference_tpose(&bvh, &det).unwrap(),
                dir != "break",
                "{}",
                p.display()
            );
        }
    }
}

/// `convert --to smpl24` / `dataset build` go through `convert_motion`: dance frames only.
/// 05_19 has 861 frames, so keeping frame 0 would give ceil(861 / 4) = 216 frames, dropping it
/// ceil(860 / 4) = 215 (for 05_02 and 55_01 both counts are equal).
#[test]
fn convert_motion_drops_the_reference_frame() {
    let path = dance("modern/05_19.bvh");
    let bvh = read(&path);
    let n = bvh.frames;
    assert_eq!(n, 861);
    let nc = bvh.num_channels();
    let mut cut = bvh.clone();
    cut.frames -= 1;
    cut.data.drain(..nc);
    let direct = retarget_to_smpl(&cut, 30.0).unwrap();
    let opts = ConvertOptions {
        fps: Some(30.0),
        to_smpl24: true,
        ..ConvertOptions::default()
    };
    let LoadedMotion::Smpl(m) = convert_motion(&path, LoadedMotion::Bvh(bvh), &opts).unwrap()
    else {
        panic!("not SMPL");
    };
    assert_eq!(m.fps, 30.0);
    assert_eq!(m.frames(), 215);
    assert_eq!(m.poses, direct.poses);
    // convert_motion also puts the resting feet on y = 0: one vertical shift for every frame.
    let mut grounded =
        dancegen_motion::repr::SmplMotion::new(30.0, direct.poses, direct.trans).unwrap();
    grounded.put_feet_on_floor().unwrap();
    assert_eq!(m.trans, grounded.trans);
}

const UNKNOWN: &str = "HIERARCHY
ROOT pelvis
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT femur_l
  {
    OFFSET 1 -1 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 -4 0
    }
  }
}
MOTION
Frames: 1
Frame Time: 0.0333333
0 1 0 0 0 0 0 0 0
";

#[test]
fn unknown_naming_lists_found_and_missing_names() {
    let bvh = parse_bvh(UNKNOWN, &BvhReadOptions::default()).unwrap();
    let e = retarget_to_smpl(&bvh, 30.0).unwrap_err();
    let BvhMotionError::UnknownSkeleton { found, missing } = &e else {
        panic!("wrong error {e:?}");
    };
    assert_eq!(found, &["pelvis", "femur_l"]);
    assert_eq!(missing.len(), 3);
    assert!(missing[0].1.contains(&"lThigh".to_owned()));
    assert!(missing[1].1.contains(&"LowerBack".to_owned()));
    assert!(missing[2].1.contains(&"Spine2".to_owned()));
    let msg = e.to_string();
    for part in [
        "Poser/Daz lacks hip, lThigh",
        "cgspeed/MotionBuilder lacks Hips, LeftUpLeg",
        "Unity humanoid lacks",
        "joints found: pelvis, femur_l",
    ] {
        assert!(msg.contains(part), "{msg}");
    }
    // At the convert level the error names the file.
    let path = Path::new("some/dir/unknown.bvh");
    let opts = ConvertOptions {
        to_smpl24: true,
        ..ConvertOptions::default()
    };
    let e = convert_motion(path, LoadedMotion::Bvh(bvh), &opts).unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with("some/dir/unknown.bvh: "), "{msg}");
    assert!(msg.contains("Unity humanoid lacks"), "{msg}");
}

/// A name prefix in front of the root's `Hips` is carried to every name; a prefixed file whose
/// other names lack it is reported with the prefixed names it needs.
#[test]
fn prefix_comes_from_the_root() {
    let text = std::fs::read_to_string(dance("break/85_03_neo30.bvh")).unwrap();
    let renamed = text.replace("Neo_", "mixamorig:");
    let bvh = parse_bvh(&renamed, &BvhReadOptions::default()).unwrap();
    let det = detect_convention(&bvh).unwrap();
    assert_eq!(det.prefix, "mixamorig:");
    assert_eq!(det.convention.name, UNITY_HUMANOID.name);
    let broken = text.replace("Neo_Spine2", "Neo_Chest");
    let bvh = parse_bvh(&broken, &BvhReadOptions::default()).unwrap();
    let msg = detect_convention(&bvh).unwrap_err().to_string();
    assert!(msg.contains("Unity humanoid lacks Neo_Spine2"), "{msg}");
}
