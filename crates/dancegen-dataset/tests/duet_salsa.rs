//! Duet pairing on real couples: CMU salsa takes with a Sectoid song, mirrored as couples.

mod common;

use dancegen_dataset::{BuildOptions, ClipEntry, Pairing, build, summary_table};
use dancegen_formats::dispatch::{LoadedMotion, load_motion_file};
use dancegen_motion::repr::motion::SmplMotion;

/// `mirror` with duet pairing adds each training couple's mirror image as a couple: both
/// partners reflected in one world frame, so the follower stays on the mirrored side of its
/// leader; the held-out couple is not mirrored.
#[test]
fn mirror_adds_mirrored_training_couples_only() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let mut opts = BuildOptions::pseudo(
        &out,
        [
            "60_01_scaled",
            "61_01_scaled",
            "60_02_scaled",
            "61_02_scaled",
        ]
        .iter()
        .map(|s| common::salsa(&format!("{s}.bvh")))
        .collect(),
        vec![common::song("metal_madness.ogg")],
    );
    opts.pairing = Pairing::Duet;
    opts.hold_out = vec!["60_02_scaled".into()];
    opts.mirror = true;
    let m = build(&opts, &()).expect("build").manifest;
    print!("{}", summary_table(&m));
    let mut names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
    names.sort_unstable();
    assert_eq!(
        names,
        [
            "60_01_scaled",
            "60_01_scaled_mirror",
            "60_02_scaled",
            "61_01_scaled",
            "61_01_scaled_mirror",
            "61_02_scaled"
        ],
        "both roles of the training couple and of its mirror; the held-out couple once"
    );
    let clip = |n: &str| m.clips.iter().find(|c| c.name == n).unwrap();
    for n in ["60_02_scaled", "61_02_scaled"] {
        assert!(clip(n).motion.starts_with("held_out/"), "{n}");
    }
    let load = |rel: &str| match load_motion_file(&out.join(rel)) {
        Ok(LoadedMotion::Smpl(s)) => s,
        _ => panic!("{rel}: not an SMPL motion"),
    };
    // The follower's mean x offset from its leader; the mirror image negates it. The two
    // couples are warped separately (same beats, so nearly the same warp): compared on average.
    let offset = |c: &ClipEntry| {
        let (f, l) = (
            load(&c.motion),
            load(c.leader.as_deref().expect("a leader")),
        );
        let n = f.frames().min(l.frames());
        let x = |s: &SmplMotion, i: usize| s.trans[i * 3] as f64;
        (0..n).map(|i| x(&f, i) - x(&l, i)).sum::<f64>() / n as f64
    };
    let (orig, mirr) = (
        offset(clip("60_01_scaled")),
        offset(clip("60_01_scaled_mirror")),
    );
    println!("follower x minus leader x: couple {orig:.3} m, mirror {mirr:.3} m");
    assert!(orig.abs() > 0.05, "the couple's mean x offset is {orig} m");
    assert!(
        (orig + mirr).abs() < 0.15 * orig.abs(),
        "mean x offset {orig} vs mirrored {mirr}"
    );
}
