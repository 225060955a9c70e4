//! Real-data checks of BVH forward kinematics and the SMPL ↔ BVH conversion.
//!
//! (i) Every CMU salsa file (all frames) survives `write_bvh` (default precision, 6
//! decimals) → `parse_bvh` with world joint positions (including end sites) unchanged to
//! 1e-4 m. The files are in scaled units; they are converted to metres by height
//! normalisation: metres per unit = SMPL rest head-to-ankle height / the file's rest
//! head-to-ankle height (≈ 1.514 m / 1.10 ≈ 1.38).
//! (ii) The AIST++ motions survive SMPL → BVH text → SMPL with SMPL FK joints unchanged to 1e-4 m.
//! (iii) BVH FK of the BVH written from SMPL equals SMPL FK of the poses (joint by joint, by name).

mod common;

use dancegen_formats::aistpp::load_motion;
use dancegen_formats::bvh::{Bvh, BvhReadOptions, BvhWriteOptions, parse_bvh, read_bvh, write_bvh};
use dancegen_formats::bvh_motion::{
    bvh_to_smpl, bvh_world_positions, bvh_world_positions_with_end_sites, smpl_fk_f64, smpl_to_bvh,
};
use dancegen_motion::skeleton::{SMPL24_NAMES, Skeleton};
use std::path::PathBuf;

fn salsa_files() -> Vec<PathBuf> {
    let dir = common::shared_dir().join("data/cmu-salsa");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("salsa dir")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "bvh"))
        .collect();
    v.sort();
    v
}

fn truncate(mut b: Bvh, frames: usize) -> Bvh {
    let n = b.num_channels();
    b.frames = b.frames.min(frames);
    b.data.truncate(b.frames * n);
    b
}

/// Head height minus ankle height in the rest pose (zero channels), via BVH FK.
fn rest_head_to_ankle(b: &Bvh, head: &str, ankle: &str) -> f64 {
    let mut rest = b.clone();
    rest.frames = 1;
    rest.data = vec![0.0; b.num_channels()];
    let (_, nj, p) = bvh_world_positions(&rest, 1.0).unwrap();
    assert_eq!(nj, b.joints.len());
    let h = b.joint_index(head).unwrap();
    let a = b.joint_index(ankle).unwrap();
    p[h * 3 + 1] - p[a * 3 + 1]
}

fn smpl_head_to_ankle() -> f64 {
    let p = Skeleton::smpl24().rest_positions();
    p[15][1] - p[7][1]
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn salsa_write_read_round_trip_positions() {
    let files = salsa_files();
    assert_eq!(files.len(), 26);
    let smpl_h = smpl_head_to_ankle();
    assert!((smpl_h - 1.514).abs() < 0.01, "{smpl_h}");
    let mut worst_m: f64 = 0.0;
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let b = read_bvh(f, &BvhReadOptions::default()).unwrap();
        let h = rest_head_to_ankle(&b, "head", "lFoot");
        assert!((1.0..1.2).contains(&h), "{name}: head-to-ankle {h}");
        let metres_per_unit = smpl_h / h;
        let text = write_bvh(&b, &BvhWriteOptions::default()).unwrap();
        let b2 = parse_bvh(&text, &BvhReadOptions::default()).unwrap();
        assert_eq!(b2.frames, b.frames);
        let (f1, n1, p1) = bvh_world_positions_with_end_sites(&b, metres_per_unit).unwrap();
        let (f2, n2, p2) = bvh_world_positions_with_end_sites(&b2, metres_per_unit).unwrap();
        assert_eq!((f1, n1), (f2, n2));
        assert_eq!(n1, 43 + 14);
        let err = max_abs_diff(&p1, &p2);
        worst_m = worst_m.max(err);
        assert!(err < 1e-4, "{name}: max joint error {err} m");
        // Sanity: the motion really moves (root travels, joints are not all at the origin).
        let spread = max_abs_diff(&p1[..n1 * 3], &p1[(f1 - 1) * n1 * 3..]);
        assert!(spread > 0.01, "{name}: no motion?");
    }
    println!("salsa write/read round trip: worst joint error {worst_m:.3e} m over 26 files");
}

#[test]
fn salsa_bvh_fk_rest_pose_matches_offsets() {
    // Rest pose (all channels 0): world positions are the cumulative offsets.
    let f = &salsa_files()[0];
    let b = truncate(read_bvh(f, &BvhReadOptions::default()).unwrap(), 1);
    let mut rest = b.clone();
    rest.data.iter_mut().for_each(|v| *v = 0.0);
    let (_, _, p) = bvh_world_positions(&rest, 1.0).unwrap();
    for (i, j) in b.joints.iter().enumerate() {
        let mut want = j.offset;
        let mut k = j.parent;
        while let Some(pi) = k {
            for (w, o) in want.iter_mut().zip(b.joints[pi].offset) {
                *w += o;
            }
            k = b.joints[pi].parent;
        }
        for (a, w) in want.iter().enumerate() {
            assert!((p[i * 3 + a] - w).abs() < 1e-12, "{}", j.name);
        }
    }
}

const AISTPP: [&str; 3] = [
    "gBR_sBM_cAll_d04_mBR2_ch08",
    "gBR_sBM_cAll_d06_mBR2_ch06",
    "gJS_sFM_cAll_d02_mJS4_ch09",
];

#[test]
fn aistpp_smpl_bvh_smpl_round_trip() {
    let base = common::shared_dir().join("data/aistpp/motions");
    for seq in AISTPP {
        let m = load_motion(base.join(format!("{seq}.pkl"))).unwrap();
        let trans = m.trans_metres();
        let bvh = smpl_to_bvh(&m.poses, &trans, f64::from(m.fps)).unwrap();
        assert_eq!(bvh.frames, m.frames());
        assert_eq!(bvh.nominal_fps(), 60.0);
        assert_eq!(bvh.joints.len(), 24);
        assert_eq!(
            bvh.joints.iter().filter(|j| j.end_site.is_some()).count(),
            5
        );
        let text = write_bvh(&bvh, &BvhWriteOptions::default()).unwrap();
        let back = parse_bvh(&text, &BvhReadOptions::default()).unwrap();
        let (poses2, trans2) = bvh_to_smpl(&back).unwrap();
        assert_eq!(poses2.len(), m.poses.len());
        let a = smpl_fk_f64(&m.poses, &trans).unwrap();
        let b = smpl_fk_f64(&poses2, &trans2).unwrap();
        let err = max_abs_diff(&a, &b);
        println!(
            "{seq}: {} frames, SMPL→BVH text→SMPL max FK joint error {err:.3e} m",
            m.frames()
        );
        assert!(err < 1e-4, "{seq}: {err}");
    }
}

#[test]
fn aistpp_bvh_fk_equals_smpl_fk() {
    let base = common::shared_dir().join("data/aistpp/motions");
    for seq in AISTPP {
        let m = load_motion(base.join(format!("{seq}.pkl"))).unwrap();
        let trans = m.trans_metres();
        let smpl = smpl_fk_f64(&m.poses, &trans).unwrap();
        let bvh = smpl_to_bvh(&m.poses, &trans, 60.0).unwrap();
        let text = write_bvh(&bvh, &BvhWriteOptions::default()).unwrap();
        let parsed = parse_bvh(&text, &BvhReadOptions::default()).unwrap();
        for (what, b, tol) in [("in memory", &bvh, 1e-9), ("via text", &parsed, 1e-4)] {
            let (frames, nj, p) = bvh_world_positions(b, 0.01).unwrap();
            assert_eq!((frames, nj), (m.frames(), 24));
            let mut err: f64 = 0.0;
            for (sj, name) in SMPL24_NAMES.iter().enumerate() {
                let bj = b.joint_index(name).unwrap();
                for f in 0..frames {
                    for a in 0..3 {
                        let d = (p[(f * nj + bj) * 3 + a] - smpl[(f * 24 + sj) * 3 + a]).abs();
                        err = err.max(d);
                    }
                }
            }
            println!("{seq}: BVH FK vs SMPL FK ({what}) max error {err:.3e} m");
            assert!(err < tol, "{seq} {what}: {err}");
        }
    }
}
