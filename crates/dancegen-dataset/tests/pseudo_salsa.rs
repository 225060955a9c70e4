//! Beat-warp pseudo-pairing on real data: a CMU salsa take and a Sectoid song.

mod common;

use dancegen_dataset::warp::MAX_TEMPO_CHANGE;
use dancegen_dataset::{BuildOptions, DatasetError, Manifest, PairingKind, build, summary_table};
use dancegen_formats::dispatch::{LoadedMotion, load_motion_file};

/// Both partners of CMU salsa take `take` (`60_<take>`, `61_<take>`) with `songs`, the `61`
/// partner held out.
fn couple_take(out: &std::path::Path, take: &str, songs: &[&str]) -> BuildOptions {
    let mut opts = BuildOptions::pseudo(
        out,
        vec![
            common::salsa(&format!("60_{take}_scaled.bvh")),
            common::salsa(&format!("61_{take}_scaled.bvh")),
        ],
        songs.iter().map(|s| common::song(s)).collect(),
    );
    opts.hold_out = vec![format!("61_{take}_scaled")];
    opts
}

#[test]
fn salsa_take_is_warped_onto_metal_madness() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    // The partner is held out; with no held-out song it is paired with any song.
    let opts = couple_take(&out, "01", &["metal_madness.ogg"]);
    let t0 = std::time::Instant::now();
    let report = build(&opts, &()).expect("build");
    println!("built in {:.1} s", t0.elapsed().as_secs_f64());
    print!("{}", summary_table(&report.manifest));

    let m = Manifest::read(&out.join("manifest.json")).expect("manifest parses");
    assert_eq!(m, report.manifest);
    assert_eq!(m.version, 1);
    assert_eq!(m.fps, 30);
    assert_eq!(m.genres, vec!["salsa".to_string()]);
    assert_eq!(
        m.clips.len(),
        2,
        "18 s takes fit in a 144 s song: one clip each"
    );
    assert_eq!(m.held_out, vec!["61_01_scaled".to_string()]);
    let (lo, hi) = (
        1.0 / (1.0 + MAX_TEMPO_CHANGE),
        1.0 / (1.0 - MAX_TEMPO_CHANGE),
    );
    for c in &m.clips {
        assert_eq!(c.pairing, PairingKind::PseudoBeatWarp);
        let held = c.name == "61_01_scaled";
        assert_eq!(
            c.motion.starts_with("held_out/motion/"),
            held,
            "{}",
            c.motion
        );
        assert_eq!(c.music.starts_with("held_out/music/"), held, "{}", c.music);
        // Music rows == motion frames, and both files agree with the manifest.
        let music = dancegen_io::read_npy(&out.join(&c.music)).unwrap();
        assert_eq!(music.shape, vec![c.frames, 35]);
        let LoadedMotion::Smpl(motion) = load_motion_file(&out.join(&c.motion)).unwrap() else {
            panic!("{}: not an SMPL motion", c.motion);
        };
        assert_eq!(motion.frames(), c.frames);
        assert_eq!(motion.fps, 30.0);
        assert!((c.song_end_s - c.song_start_s - c.frames as f64 / 30.0).abs() < 1e-9);
        assert!(c.song_start_s >= 0.0 && c.song_end_s <= 144.5);
        // A 15 % tempo limit means playback speed 1/rate in [0.85, 1.15].
        let w = c.warp.as_ref().expect("warp report");
        assert!(w.min_rate >= lo - 1e-9 && w.max_rate <= hi + 1e-9, "{w:?}");
        assert!(1.0 / w.max_rate >= 0.85 - 1e-9 && 1.0 / w.min_rate <= 1.15 + 1e-9);
        assert!(
            w.matched_beats * 2 > w.motion_beats,
            "most kinematic beats matched: {w:?}"
        );
        let (before, after) = (w.bas_before.unwrap(), w.bas_after.unwrap());
        assert!(
            after > before + 0.03 && after > 1.15 * before,
            "BAS {before:.3} -> {after:.3}"
        );
        // The song's beat column inside the clip is the whole-song tracker's.
        let beats = (0..c.frames)
            .filter(|&r| music.data[r * 35 + 34] == 1.0)
            .count();
        assert!(beats as f64 > 0.8 * c.frames as f64 / 30.0 * 150.0 / 60.0);
    }
}

#[test]
fn training_motion_without_a_training_song_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut opts = BuildOptions::pseudo(
        dir.path().join("set"),
        vec![common::salsa("60_01_scaled.bvh")],
        vec![common::song("metal_madness.ogg")],
    );
    opts.hold_out = vec!["metal_madness".into()];
    let e = build(&opts, &()).unwrap_err();
    assert!(matches!(e, DatasetError::Options(_)), "{e}");
    assert!(e.to_string().contains("held out"), "{e}");
    // A hold-out name that matches nothing is refused (a typo would leak test data).
    opts.hold_out = vec!["metal_madnes".into()];
    let e = build(&opts, &()).unwrap_err();
    assert!(e.to_string().contains("metal_madnes"), "{e}");
    assert!(!dir.path().join("set/manifest.json").exists());
}

#[test]
fn held_out_song_pairs_only_with_held_out_motions() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let mut opts = couple_take(
        &out,
        "10",
        &["metal_madness.ogg", "escape_from_chaosland.ogg"],
    );
    opts.hold_out.push("escape_from_chaosland".into());
    let m = build(&opts, &()).expect("build").manifest;
    print!("{}", summary_table(&m));
    assert_eq!(m.clips.len(), 2);
    for c in &m.clips {
        let held = c.name.starts_with("61_10");
        assert_eq!(
            c.source_song.ends_with("escape_from_chaosland.ogg"),
            held,
            "{c:?}"
        );
        assert_eq!(c.motion.starts_with("held_out/"), held);
        assert_eq!(m.held_out.contains(&c.name), held);
        assert!(out.join(&c.motion).is_file() && out.join(&c.music).is_file());
    }
}

#[test]
fn bad_input_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.bvh");
    std::fs::write(&bad, "HIERARCHY\nROOT hip\n{").unwrap();
    let opts = BuildOptions::pseudo(
        dir.path().join("set"),
        vec![bad.clone()],
        vec![dir.path().join("missing.ogg")],
    );
    let e = build(&opts, &()).unwrap_err().to_string();
    assert!(e.contains("missing.ogg") || e.contains("broken.bvh"), "{e}");
}

/// `mirror` adds the left–right mirror image of every training take as its own clip, warped
/// onto the song like the take itself; the held-out take is not mirrored.
#[test]
fn mirror_adds_mirrored_training_takes_only() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let mut opts = couple_take(&out, "01", &["metal_madness.ogg"]);
    opts.mirror = true;
    let m = build(&opts, &()).expect("build").manifest;
    print!("{}", summary_table(&m));
    let names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        ["60_01_scaled", "60_01_scaled_mirror", "61_01_scaled"],
        "one mirrored clip, of the training take"
    );
    assert_eq!(m.held_out, vec!["61_01_scaled".to_string()]);
    let clip = |n: &str| m.clips.iter().find(|c| c.name == n).unwrap();
    let (orig, mirr) = (clip("60_01_scaled"), clip("60_01_scaled_mirror"));
    assert_eq!(mirr.genre, "salsa");
    assert!(!mirr.motion.starts_with("held_out/"));
    let load = |c: &dancegen_dataset::ClipEntry| match load_motion_file(&out.join(&c.motion)) {
        Ok(LoadedMotion::Smpl(s)) => s,
        _ => panic!("{}: not an SMPL motion", c.motion),
    };
    // The mirror image moves as much as the take: its kinematic beats are the take's, so the
    // warp matches about as many of them.
    let (wo, wm) = (orig.warp.as_ref().unwrap(), mirr.warp.as_ref().unwrap());
    assert!(
        (wo.motion_beats as i64 - wm.motion_beats as i64).abs() <= 2,
        "{wo:?} vs {wm:?}"
    );
    // Mirrored across x: where the take's root is right of its mean path, the mirror's is
    // left (the warps of the two differ a little, so compared on average).
    let (a, b) = (load(orig), load(mirr));
    let mean_x = |s: &dancegen_motion::repr::motion::SmplMotion| {
        s.trans.chunks_exact(3).map(|p| p[0] as f64).sum::<f64>() / s.frames() as f64
    };
    let (xa, xb) = (mean_x(&a), mean_x(&b));
    println!("mean root x: take {xa:.3} m, mirror {xb:.3} m");
    assert!(xa.abs() > 0.05, "the take's mean root x is {xa} m");
    assert!(
        (xa + xb).abs() < 0.1 * xa.abs(),
        "mean root x {xa} vs mirrored {xb}"
    );
}

/// `songs_per_motion` pairs a training take with its best songs, each warp its own clip named
/// after its song; the held-out take is paired once.
#[test]
fn songs_per_motion_pairs_training_takes_with_several_songs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let mut opts = couple_take(
        &out,
        "10",
        &["metal_madness.ogg", "escape_from_chaosland.ogg"],
    );
    opts.songs_per_motion = 2;
    let m = build(&opts, &()).expect("build").manifest;
    print!("{}", summary_table(&m));
    assert_eq!(
        m.clips.len(),
        3,
        "two pairings of the training take, one of the held-out take"
    );
    let first = m.clips.iter().find(|c| c.name == "60_10_scaled").unwrap();
    let other = m
        .clips
        .iter()
        .find(|c| c.name.starts_with("60_10_scaled__"))
        .expect("a second pairing");
    assert_ne!(first.source_song, other.source_song);
    let song_stem = std::path::Path::new(&other.source_song)
        .file_stem()
        .unwrap()
        .to_str()
        .unwrap();
    assert_eq!(other.name, format!("60_10_scaled__{song_stem}"));
    assert!(
        other.warp.as_ref().unwrap().matched_beats
            <= first.warp.as_ref().unwrap().matched_beats + 1,
        "the best song first (by matched beats per minute)"
    );
    assert_eq!(
        m.clips
            .iter()
            .filter(|c| c.name.starts_with("61_10"))
            .count(),
        1
    );
    // 0 songs per motion is refused.
    opts.songs_per_motion = 0;
    assert!(
        build(&opts, &())
            .unwrap_err()
            .to_string()
            .contains("at least 1")
    );
}

/// `merge_genres` relabels the clips and the manifest's genre list after pairing; the clips
/// themselves are those of the plain build.
#[test]
fn merge_genre_relabels_the_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let mut opts = couple_take(&out, "01", &["metal_madness.ogg"]);
    opts.merge_genres = vec![("salsa".into(), "latin".into())];
    let m = build(&opts, &()).expect("build").manifest;
    assert_eq!(m.genres, vec!["latin".to_string()]);
    assert!(m.clips.iter().all(|c| c.genre == "latin"), "{:?}", m.clips);
    assert_eq!(m.clips.len(), 2);

    opts.merge_genres = vec![
        ("salsa".into(), "latin".into()),
        ("latin".into(), "x".into()),
    ];
    let e = build(&opts, &()).unwrap_err().to_string();
    assert!(e.contains("both merged into and merged away"), "{e}");
}
