//! The AIST++ and FineDance layouts on real motion (the shared AIST++ sequences) and short real
//! music excerpts written as WAV.

mod common;

use std::path::Path;

use dancegen_dataset::{BuildOptions, Manifest, Pairing, PairingKind, build};
use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, convert_motion, load_motion_file};
use dancegen_motion::repr::finedance::FineDance315;

const D04: &str = "gBR_sBM_cAll_d04_mBR2_ch08";
const D06: &str = "gBR_sBM_cAll_d06_mBR2_ch06";
const JS: &str = "gJS_sFM_cAll_d02_mJS4_ch09";

fn layout_opts(root: &Path, out: &Path, pairing: Pairing) -> BuildOptions {
    let mut o = BuildOptions::pseudo(out, Vec::new(), Vec::new());
    o.pairing = pairing;
    o.root = Some(root.to_path_buf());
    o
}

#[test]
fn aistpp_layout_pairs_by_music_id_with_splits() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("aist");
    std::fs::create_dir_all(root.join("motions")).unwrap();
    std::fs::create_dir_all(root.join("wav")).unwrap();
    std::fs::create_dir_all(root.join("splits")).unwrap();
    for s in [D04, D06, JS] {
        std::fs::copy(
            common::aistpp_motions().join(format!("{s}.pkl")),
            root.join("motions").join(format!("{s}.pkl")),
        )
        .unwrap();
    }
    // mBR2 longer than the break sequences (9.6 s at 30 fps); mJS4 shorter than the jazz one
    // (32 s), so the clip is cut to the music.
    common::write_wav_excerpt(
        &common::song("metal_madness.ogg"),
        12.0,
        &root.join("wav/mBR2.wav"),
    );
    common::write_wav_excerpt(
        &common::song("feelings.ogg"),
        20.0,
        &root.join("wav/mJS4.wav"),
    );
    std::fs::write(root.join("splits/crossmodal_test.txt"), format!("{JS}\n")).unwrap();
    std::fs::write(root.join("splits/crossmodal_train.txt"), format!("{D04}\n")).unwrap();
    std::fs::write(root.join("ignore_list.txt"), format!("{D06}\n")).unwrap();

    let out = dir.path().join("set");
    let m = build(&layout_opts(&root, &out, Pairing::Aistpp), &())
        .expect("build")
        .manifest;
    assert_eq!(m, Manifest::read(&out.join("manifest.json")).unwrap());
    let names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, vec![D04, JS], "the ignored sequence is skipped");
    assert_eq!(m.genres, vec!["break", "street_jazz"]);
    assert_eq!(m.held_out, vec![JS.to_string()]);
    let br = &m.clips[0];
    let js = &m.clips[1];
    assert_eq!(br.frames, 288, "576 frames at 60 fps, every 2nd");
    assert!(br.source_song.ends_with("mBR2.wav"));
    assert_eq!(br.motion, format!("motion/{D04}.npz"));
    // 20 s of music at 30 fps: 1 + floor(20 * 15360 / 512) frames.
    assert_eq!(js.frames, 601);
    assert!(js.source_song.ends_with("mJS4.wav"));
    assert_eq!(js.music, format!("held_out/music/{JS}.npy"));
    for c in &m.clips {
        assert_eq!(c.pairing, PairingKind::Original);
        assert!(c.warp.is_none());
        assert_eq!(c.song_start_s, 0.0);
        let music = dancegen_io::read_npy(&out.join(&c.music)).unwrap();
        assert_eq!(music.shape, vec![c.frames, 35]);
    }
    // The motion is the EDGE 60 -> 30 fps stride of the source.
    let LoadedMotion::Smpl(src) =
        load_motion_file(&common::aistpp_motions().join(format!("{D04}.pkl"))).unwrap()
    else {
        panic!("AIST++ pickle is SMPL")
    };
    let LoadedMotion::Smpl(got) = load_motion_file(&out.join(&br.motion)).unwrap() else {
        panic!("npz is SMPL")
    };
    let want = src.resample_stride(2);
    assert_eq!(got.frames(), want.frames());
    let max_dt = root_difference(&got.trans, &want.trans);
    assert!(max_dt < 1e-5, "root position differs by {max_dt} m");
}

#[test]
fn finedance_layout_reads_315_npy_and_labels() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("fd");
    for d in ["motion", "music_wav", "label_json"] {
        std::fs::create_dir_all(root.join(d)).unwrap();
    }
    // A (T, 315) FineDance motion made from a real AIST++ sequence at 30 fps.
    let src = common::aistpp_motions().join(format!("{D04}.pkl"));
    let opts = ConvertOptions {
        fps: Some(30.0),
        ..Default::default()
    };
    let LoadedMotion::Smpl(m30) =
        convert_motion(&src, load_motion_file(&src).unwrap(), &opts).unwrap()
    else {
        panic!("SMPL")
    };
    let data = FineDance315::encode(&m30).unwrap();
    for (id, label) in [("001", "Popping"), ("063", "Wei")] {
        dancegen_io::write_npy_f32(
            &root.join(format!("motion/{id}.npy")),
            &[m30.frames(), 315],
            &data,
        )
        .unwrap();
        std::fs::write(
            root.join(format!("label_json/{id}.json")),
            format!(r#"{{"style1": "Modern", "style2": "{label}"}}"#),
        )
        .unwrap();
    }
    common::write_wav_excerpt(
        &common::song("metal_madness.ogg"),
        12.0,
        &root.join("music_wav/001.wav"),
    );
    std::fs::copy(
        root.join("music_wav/001.wav"),
        root.join("music_wav/063.wav"),
    )
    .unwrap();

    let out = dir.path().join("set");
    let m = build(&layout_opts(&root, &out, Pairing::FineDance), &())
        .expect("build")
        .manifest;
    assert_eq!(m.genres, vec!["popping", "uighur"]);
    assert_eq!(
        m.held_out,
        vec!["063".to_string()],
        "063 is in the FineDance test split"
    );
    assert_eq!(m.clips.len(), 2);
    for c in &m.clips {
        assert_eq!(c.frames, 288);
        let LoadedMotion::Smpl(got) = load_motion_file(&out.join(&c.motion)).unwrap() else {
            panic!("npz is SMPL")
        };
        // 6D encoding round trip: the root trajectory is stored verbatim (up to the floor).
        assert!(root_difference(&got.trans, &m30.trans) < 1e-5);
        let music = dancegen_io::read_npy(&out.join(&c.music)).unwrap();
        assert_eq!(music.shape, vec![288, 35]);
    }
}

/// Largest difference between two root paths `(T, 3)` after removing one constant height
/// offset: the builder puts every clip on the floor (`GroundMode::SupportFeet`), which moves the
/// whole path vertically and nothing else.
fn root_difference(got: &[f32], want: &[f32]) -> f32 {
    assert_eq!(got.len(), want.len());
    let dy = got[1] - want[1];
    got.chunks(3)
        .zip(want.chunks(3))
        .map(|(g, w)| {
            (g[0] - w[0])
                .abs()
                .max((g[1] - w[1] - dy).abs())
                .max((g[2] - w[2]).abs())
        })
        .fold(0.0f32, f32::max)
}
