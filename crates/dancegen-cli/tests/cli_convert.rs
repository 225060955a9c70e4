//! The `convert` command contract: `.npy` output = world joints (T, J, 3), metres, Y-up for SMPL
//! inputs; the BVH's own joints in its units without `--to`; retargeted SMPL 24 with it.

mod common;

use common::*;

const AIST: &str = "data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl";

#[test]
fn aistpp_to_npy_is_metres_y_up_with_pelvis_rest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("j.npy");
    let src = shared().join(AIST);
    ok(&dancegen(&[
        "-q",
        "convert",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]));
    let a = dancegen_io::read_npy(&out).unwrap();
    assert_eq!(a.shape, vec![576, 24, 3]);
    assert_eq!(a.dtype, "<f4");
    // Pelvis = smpl_trans / smpl_scaling + rest pelvis (shared/data/README.md).
    let m = dancegen_formats::aistpp::load_motion(&src).unwrap();
    let rest = [-0.0021f64, -0.2444, 0.0282];
    for f in [0usize, 300, 575] {
        for (ax, r) in rest.iter().enumerate() {
            let want = m.trans[f * 3 + ax] as f64 / m.scaling as f64 + r;
            let got = a.data[f * 72 + ax];
            assert!(
                (got - want).abs() < 1e-4,
                "frame {f} axis {ax}: {got} vs {want}"
            );
        }
    }
    // Rotations and offsets are checked against the AIST++ keypoints in
    // dancegen-formats/tests/aistpp_fk.rs; here the contract's translation convention.
    // --fps 30 halves the frames (stride as the references do).
    let out30 = dir.path().join("j30.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        src.to_str().unwrap(),
        "--fps",
        "30",
        "-o",
        out30.to_str().unwrap(),
    ]));
    assert_eq!(
        dancegen_io::read_npy(&out30).unwrap().shape,
        vec![288, 24, 3]
    );
}

#[test]
fn bvh_to_npy_keeps_file_joints_and_units_or_retargets() {
    let dir = tempfile::tempdir().unwrap();
    let src = shared().join("data/cmu-salsa/60_01_scaled.bvh");
    let raw = dir.path().join("raw.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        src.to_str().unwrap(),
        "-o",
        raw.to_str().unwrap(),
    ]));
    let bvh = dancegen_formats::bvh::read_bvh(&src, &Default::default()).unwrap();
    let a = dancegen_io::read_npy(&raw).unwrap();
    assert_eq!(a.shape, vec![bvh.frames, bvh.joints.len(), 3]);
    let smpl = dir.path().join("smpl.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        src.to_str().unwrap(),
        "--to",
        "smpl24",
        "--fps",
        "30",
        "-o",
        smpl.to_str().unwrap(),
    ]));
    let s = dancegen_io::read_npy(&smpl).unwrap();
    assert_eq!(s.shape[1..], [24, 3]);
    assert_eq!(s.shape[0], bvh.frames.div_ceil(4));
}

#[test]
fn every_output_format_writes_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let src = shared().join(AIST);
    for ext in ["bvh", "glb", "npz", "json"] {
        let out = dir.path().join(format!("m.{ext}"));
        ok(&dancegen(&[
            "-q",
            "convert",
            src.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]));
        assert!(std::fs::metadata(&out).unwrap().len() > 1000, "{ext}");
    }
    // BVH and NPZ come back to the same joints.
    let direct = dir.path().join("direct.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        src.to_str().unwrap(),
        "-o",
        direct.to_str().unwrap(),
    ]));
    let want = dancegen_io::read_npy(&direct).unwrap().data;
    let back = dir.path().join("back.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        dir.path().join("m.npz").to_str().unwrap(),
        "-o",
        back.to_str().unwrap(),
    ]));
    let got = dancegen_io::read_npy(&back).unwrap().data;
    let err = got
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-5, "npz round trip {err}");
    // An SMPL-skeleton BVH comes back to SMPL by joint names with --to smpl24.
    let from_bvh = dir.path().join("from_bvh.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        dir.path().join("m.bvh").to_str().unwrap(),
        "--to",
        "smpl24",
        "-o",
        from_bvh.to_str().unwrap(),
    ]));
    let got = dancegen_io::read_npy(&from_bvh).unwrap().data;
    let err = got
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-5, "BVH round trip {err}");
}

#[test]
fn bad_motion_inputs_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.npy");
    let bad = dir.path().join("broken.bvh");
    std::fs::write(&bad, "HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0\n").unwrap();
    let o = dancegen(&[
        "convert",
        bad.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("broken.bvh") && !e.contains("panicked"), "{e}");
    assert!(!out.exists());
    let o = dancegen(&["convert", "/nonexistent/m.pkl", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let o = dancegen(&[
        "convert",
        shared().join(AIST).to_str().unwrap(),
        "-o",
        dir.path().join("x.fbz").to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown output format"));
}

#[test]
fn rig_presets_rename_bones_and_unknown_rigs_are_listed() {
    let dir = tempfile::tempdir().unwrap();
    let aist = shared().join(AIST);
    let (bvh, glb, fbx, npy, npy_mixamo) = (
        dir.path().join("m.bvh"),
        dir.path().join("m.glb"),
        dir.path().join("m.fbx"),
        dir.path().join("smpl.npy"),
        dir.path().join("mixamo.npy"),
    );
    for out in [&bvh, &glb, &fbx, &npy_mixamo] {
        let o = dancegen(&[
            "convert",
            aist.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--rig",
            "mixamo",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = dancegen(&[
        "convert",
        aist.to_str().unwrap(),
        "-o",
        npy.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    // Bone names change in the scene formats; joints (and the research formats) do not.
    let text = std::fs::read_to_string(&bvh).unwrap();
    assert!(text.contains("ROOT mixamorig:Hips") && text.contains("JOINT mixamorig:LeftForeArm"));
    assert!(!text.contains("lelbow"));
    for f in [&glb, &fbx] {
        let bytes = std::fs::read(f).unwrap();
        let has = |s: &str| bytes.windows(s.len()).any(|w| w == s.as_bytes());
        assert!(
            has("mixamorig:RightToeBase") && !has("rtoes"),
            "{}",
            f.display()
        );
    }
    assert_eq!(
        std::fs::read(&npy).unwrap(),
        std::fs::read(&npy_mixamo).unwrap()
    );

    let o = dancegen(&[
        "convert",
        aist.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
        "--rig",
        "maya",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("unknown rig 'maya' (use smpl, mixamo, ue5 or vrm)"),
        "{e}"
    );
    // A BVH kept on its own skeleton has no SMPL joints to rename.
    let salsa = shared().join("data/cmu-salsa/61_13_scaled.bvh");
    let o = dancegen(&[
        "convert",
        salsa.to_str().unwrap(),
        "-o",
        glb.to_str().unwrap(),
        "--rig",
        "ue5",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("add --to smpl24"), "{e}");
}

/// What `generate` writes, `convert` and `render` read (issue 45): a group's `.glb` and `.fbx`
/// convert back to the joints of the group's `.npy` (every dancer, within float precision), one
/// dancer of the `.glb` with `--dancer`, and both render to a picture.
#[test]
fn our_own_glb_and_fbx_read_back_as_the_dance() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let song = shared().join("data/music/sectoid/feelings.ogg");
    ok(&dancegen(&[
        "-q",
        "generate",
        song.to_str().unwrap(),
        "--system",
        "group",
        "--dancers",
        "3",
        "--start",
        "30",
        "--end",
        "34",
        "-o",
        &p("g.glb"),
        "-o",
        &p("g.fbx"),
        "-o",
        &p("g.npy"),
    ]));
    ok(&dancegen(&[
        "-q",
        "convert",
        &p("g.glb"),
        "-o",
        &p("back.npy"),
    ]));
    let read = |name: &str| dancegen_io::read_npy(std::path::Path::new(&p(name))).unwrap();
    let (made, back) = (read("g.npy"), read("back.npy"));
    assert_eq!(made.shape, back.shape);
    assert_eq!(made.shape, vec![3, 120, 24, 3]);
    let worst = made
        .data
        .iter()
        .zip(&back.data)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-5,
        "the .glb's joints are {worst} m from the .npy's"
    );
    ok(&dancegen(&[
        "-q",
        "convert",
        &p("g.glb"),
        "--dancer",
        "2",
        "-o",
        &p("d2.npy"),
    ]));
    let one = read("d2.npy");
    assert_eq!(one.shape, vec![120, 24, 3]);
    assert_eq!(one.data[..], back.data[2 * 120 * 72..]);
    ok(&dancegen(&["-q", "render", &p("g.glb"), "-o", &p("g.png")]));
    assert!(std::fs::metadata(p("g.png")).unwrap().len() > 1000);
    // The .fbx: Euler degrees in f32 keys, so within 0.1 mm rather than the .glb's 1e-5 m.
    ok(&dancegen(&[
        "-q",
        "convert",
        &p("g.fbx"),
        "-o",
        &p("fbx.npy"),
    ]));
    let from_fbx = read("fbx.npy");
    assert_eq!(made.shape, from_fbx.shape);
    let worst = made
        .data
        .iter()
        .zip(&from_fbx.data)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-4,
        "the .fbx's joints are {worst} m from the .npy's"
    );
    ok(&dancegen(&["-q", "render", &p("g.fbx"), "-o", &p("f.png")]));
    assert!(std::fs::metadata(p("f.png")).unwrap().len() > 1000);
}
