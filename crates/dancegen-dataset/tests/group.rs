//! Group composition (`--pairing group`) on real data: two CMU salsa couples, an AIST++ clip
//! and an excerpt of a Sectoid song.

mod common;

use std::collections::BTreeSet;

use dancegen_dataset::group::GroupOptions;
use dancegen_dataset::{BuildOptions, DatasetError, Manifest, Pairing, build};
use dancegen_formats::dispatch::{LoadedMotion, load_motion_file};
use dancegen_refine::formation::order_left_to_right;

fn options(out: &std::path::Path, song: std::path::PathBuf) -> BuildOptions {
    let mut o = BuildOptions::pseudo(
        out,
        vec![
            common::salsa("60_01_scaled.bvh"),
            common::salsa("61_01_scaled.bvh"),
            common::salsa("60_02_scaled.bvh"),
            common::salsa("61_02_scaled.bvh"),
            common::aistpp_motions().join("gBR_sBM_cAll_d04_mBR2_ch08.pkl"),
        ],
        vec![song],
    );
    o.pairing = Pairing::Group;
    o.hold_out = vec!["60_02_scaled".into(), "61_02_scaled".into()];
    o.seed = 5;
    o.group = GroupOptions {
        samples: 8,
        held_out_samples: 4,
        clip_seconds: 6.0,
        hold_out_shapes: vec!["circle".into(), "diamond".into()],
    };
    o
}

fn root_xz(m: &LoadedMotion) -> Vec<[f64; 2]> {
    let LoadedMotion::Smpl(s) = m else {
        panic!("one dancer per file")
    };
    let j = s.joints_world().unwrap();
    j.chunks_exact(72)
        .map(|f| [f64::from(f[0]), f64::from(f[2])])
        .collect()
}

#[test]
fn composed_groups_are_labelled_apart_and_held_out_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let song = dir.path().join("song.wav");
    common::write_wav_excerpt(&common::song("metal_madness.ogg"), 40.0, &song);
    let out = dir.path().join("set");
    let report = build(&options(&out, song.clone()), &()).expect("build");
    let m = Manifest::read(&out.join("manifest.json")).unwrap();
    assert_eq!(m, report.manifest);
    assert!(m.clips.len() >= 6, "{} clips", m.clips.len());
    let mut sizes = BTreeSet::new();
    for c in &m.clips {
        let g = c.group.as_ref().expect("group labels");
        let held = c.motion.starts_with("held_out/");
        sizes.insert(g.dancers);
        assert!((2..=5).contains(&g.dancers));
        assert_eq!(c.frames, 180);
        // Held-out samples use held-out takes and shapes only; training ones never do.
        for s in &g.sources {
            assert_eq!(s.contains("_02_"), held, "{}: {s}", c.name);
        }
        for s in &g.shapes {
            assert_eq!(s == "circle" || s == "diamond", held, "{}: {s}", c.name);
        }
        let traj = dancegen_io::read_npy(&out.join(&g.trajectories)).unwrap();
        assert_eq!(traj.shape, vec![g.dancers, c.frames, 2]);
        let music = dancegen_io::read_npy(&out.join(&c.music)).unwrap();
        assert_eq!(music.shape, vec![c.frames, 35]);
        let roots: Vec<Vec<[f64; 2]>> = (0..g.dancers)
            .map(|k| {
                let p = out.join(&c.motion).join(format!("dancer_{k}.npz"));
                root_xz(&load_motion_file(&p).unwrap())
            })
            .collect();
        assert!(
            !out.join(&c.motion)
                .join(format!("dancer_{}.npz", g.dancers))
                .exists()
        );
        // Trajectories are the dancers' roots; the orders are read off them.
        for (k, r) in roots.iter().enumerate() {
            for (t, p) in r.iter().enumerate() {
                let i = (k * c.frames + t) * 2;
                assert!(
                    (traj.data[i] - p[0]).abs() < 1e-4 && (traj.data[i + 1] - p[1]).abs() < 1e-4
                );
            }
        }
        let at = |t: usize| order_left_to_right(&roots.iter().map(|r| r[t]).collect::<Vec<_>>());
        assert_eq!(g.start_order, at(0));
        assert_eq!(g.end_order, at(c.frames - 1));
        // Non-partners never come closer than 0.45 m; partners are a recorded couple.
        for a in 0..g.dancers {
            for b in a + 1..g.dancers {
                let partners = g.partners.contains(&[a, b]);
                if partners {
                    let key = |s: &str| s.split_once('_').unwrap().1.to_string();
                    assert_eq!(key(&g.sources[a]), key(&g.sources[b]));
                    continue;
                }
                for (t, (pa, pb)) in roots[a].iter().zip(&roots[b]).enumerate() {
                    let d = (pa[0] - pb[0]).hypot(pa[1] - pb[1]);
                    assert!(
                        d >= 0.45,
                        "{} frame {t}: dancers {a} and {b} {d:.3} m apart",
                        c.name
                    );
                }
            }
        }
        assert_eq!(g.shapes.len(), g.transitions.len() + 1);
    }
    assert!(sizes.len() >= 3, "group sizes {sizes:?}");
    assert!(m.clips.iter().any(|c| c.motion.starts_with("held_out/")));

    // Seeded: the same options give the same set.
    let again = dir.path().join("again");
    let mut o = options(&again, song);
    o.out = again.clone();
    let second = build(&o, &()).unwrap();
    let strip = |m: &Manifest| {
        m.clips
            .iter()
            .map(|c| (c.name.clone(), c.group.clone(), c.song_start_s))
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&second.manifest), strip(&m));
}

#[test]
fn bad_group_options_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = options(&dir.path().join("x"), common::song("metal_madness.ogg"));
    o.group.hold_out_shapes = vec!["hexagon".into()];
    let e = build(&o, &()).unwrap_err();
    assert!(matches!(e, DatasetError::Options(_)));
    assert!(e.to_string().contains("hexagon"), "{e}");
    o.group.hold_out_shapes.clear();
    o.group.clip_seconds = 2.0;
    let e = build(&o, &()).unwrap_err();
    assert!(e.to_string().contains("--clip-seconds"), "{e}");
}
