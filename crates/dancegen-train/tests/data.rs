//! Windowed data sets and normalisers on real motion; the configuration's error messages.

mod common;

use std::path::Path;

use dancegen_train::config::{NormalizerKind, Representation};
use dancegen_train::data::{DataPosition, Normalizer, WindowDataset};
use dancegen_train::{TrainConfig, files};

fn parse(dir: &Path, edit: impl Fn(String) -> String) -> Result<TrainConfig, String> {
    TrainConfig::parse(&edit(common::tiny_config(dir, 10, 1)), dir)
}

#[test]
fn windows_cover_every_stride_and_the_order_is_a_seeded_permutation() {
    let tmp = tempfile::tempdir().unwrap();
    let mut c = parse(tmp.path(), |s| s).unwrap().data;
    let clips = WindowDataset::read_clips(&c).unwrap();
    // 576 frames at 60 fps → 288 at 30; LODGE 139 keeps every frame.
    assert_eq!(clips.len(), 1);
    assert_eq!(clips[0].frames, 288);
    assert_eq!(clips[0].motion.len(), 288 * 139);
    let norm = Normalizer::fit(NormalizerKind::MeanStd, &clips, 139).unwrap();

    // Dense sliding windows (ReactDance DSW): stride 1 → T − W + 1 windows.
    c.stride = 1;
    let d = WindowDataset::new(clips.clone(), &c, &norm, 5).unwrap();
    assert_eq!(d.windows.len(), 288 - 16 + 1);
    c.stride = 8;
    let d = WindowDataset::new(clips.clone(), &c, &norm, 5).unwrap();
    assert_eq!(d.windows.len(), (288 - 16) / 8 + 1);
    assert_eq!(d.windows[3], (0, 24));

    let p0 = d.permutation(0);
    let mut sorted = p0.clone();
    sorted.sort();
    assert_eq!(sorted, (0..d.windows.len()).collect::<Vec<_>>());
    assert_eq!(p0, d.permutation(0));
    assert_ne!(p0, d.permutation(1));
    let other = WindowDataset::new(clips.clone(), &c, &norm, 6).unwrap();
    assert_ne!(p0, other.permutation(0));

    // Batches walk the permutation and drop the last partial batch (35 windows, batch 4).
    let mut pos = DataPosition::default();
    let mut seen = Vec::new();
    for _ in 0..8 {
        let (idx, next) = d.batch_indices(pos);
        seen.extend(idx);
        pos = next;
    }
    assert_eq!(seen, p0[..32]);
    let (idx, next) = d.batch_indices(pos);
    assert_eq!(
        next,
        DataPosition {
            epoch: 1,
            cursor: 4
        }
    );
    assert_eq!(idx, d.permutation(1)[..4]);

    // A batch tensor holds the normalised window.
    let device = dancegen_nn::burn::tensor::Device::flex();
    let (b, _) = d.batch(DataPosition::default(), &device);
    assert_eq!(b.motion.dims(), [4, 16, 139]);
    assert!(b.music.is_none());
    let got = b.motion.into_data().try_to_vec::<f32>().unwrap();
    let (clip, start) = d.windows[p0[0]];
    assert_eq!(
        got[..139],
        d.clips[clip].motion[start * 139..(start + 1) * 139]
    );
}

#[test]
fn mean_std_normaliser_standardises_and_round_trips_through_json() {
    let tmp = tempfile::tempdir().unwrap();
    let c = parse(tmp.path(), |s| s).unwrap().data;
    let clips = WindowDataset::read_clips(&c).unwrap();
    let n = Normalizer::fit(NormalizerKind::MeanStd, &clips, 139).unwrap();
    let mut x = clips[0].motion.clone();
    n.transform(&mut x).unwrap();
    // Root x (dim 4) of a moving dancer: mean 0, std 1 after the transform.
    let col: Vec<f64> = x.chunks(139).map(|r| r[4] as f64).collect();
    let mean = col.iter().sum::<f64>() / col.len() as f64;
    let var = col.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / col.len() as f64;
    assert!(
        mean.abs() < 1e-5 && (var - 1.0).abs() < 1e-4,
        "{mean} {var}"
    );
    let mut back = x.clone();
    n.inverse(&mut back).unwrap();
    for (a, b) in back.iter().zip(&clips[0].motion) {
        assert!((a - b).abs() < 1e-4 * (1.0 + b.abs()));
    }
    let p = tmp.path().join(files::NORMALIZER);
    n.save(&p).unwrap();
    assert_eq!(Normalizer::load(&p).unwrap(), n);
    std::fs::write(&p, r#"{"kind":"mean_std","mean":[1,2],"std":[1]}"#).unwrap();
    let e = Normalizer::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("normalizer.json") && e.contains("different lengths"),
        "{e}"
    );

    // MinMax (EDGE) maps into [−1, 1].
    let mm = Normalizer::fit(NormalizerKind::MinMax, &clips, 139).unwrap();
    let mut y = clips[0].motion.clone();
    mm.transform(&mut y).unwrap();
    assert!(y.iter().all(|v| (-1.0..=1.0).contains(v)));
}

#[test]
fn music_features_are_cut_with_the_motion_windows() {
    let tmp = tempfile::tempdir().unwrap();
    let music = tmp.path().join("music");
    std::fs::create_dir(&music).unwrap();
    // 250 frames of 3 features (shorter than the 288 motion frames): value = frame index.
    let feat: Vec<f32> = (0..250).flat_map(|t| [t as f32, 0.5, -1.0]).collect();
    let stem = common::aist_motion().file_stem().unwrap().to_owned();
    dancegen_io::write_npy_f32(&music.join(stem).with_extension("npy"), &[250, 3], &feat).unwrap();
    let c = parse(tmp.path(), |s| {
        s.replace(
            "normalizer = \"mean_std\"",
            &format!(
                "normalizer = \"none\"\nmusic = {{ dir = \"{}\", dims = 3 }}",
                music.display()
            ),
        )
    })
    .unwrap()
    .data;
    let clips = WindowDataset::read_clips(&c).unwrap();
    assert_eq!(clips[0].frames, 250);
    let n = Normalizer::fit(NormalizerKind::None, &clips, 139).unwrap();
    let d = WindowDataset::new(clips, &c, &n, 0).unwrap();
    let (b, _) = d.batch(
        DataPosition::default(),
        &dancegen_nn::burn::tensor::Device::flex(),
    );
    let m = b.music.unwrap();
    assert_eq!(m.dims(), [4, 16, 3]);
    let v = m.into_data().try_to_vec::<f32>().unwrap();
    let (_, start) = d.windows[d.permutation(0)[0]];
    assert_eq!(v[0], start as f32);
    assert_eq!(v[15 * 3], (start + 15) as f32);
}

#[test]
fn config_errors_name_the_problem() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    assert!(parse(d, |s| s).is_ok());
    let e = parse(d, |s| s.replace("warmup_steps", "warmup_step")).unwrap_err();
    assert!(e.contains("unknown field `warmup_step`"), "{e}");
    let e = parse(d, |s| s.replace("window = 16", "")).unwrap_err();
    assert!(e.contains("missing field `window`"), "{e}");
    let e = parse(d, |s| s.replace("gBR_sBM", "nope")).unwrap_err();
    assert!(
        e.contains("[data] paths") && e.contains("no such file"),
        "{e}"
    );
    let e = parse(d, |s| s.replace("kind = \"motion_autoencoder\"", "")).unwrap_err();
    assert!(e.contains("[model] needs `kind`"), "{e}");
    let e = parse(d, |s| {
        s.replace("lr = 2e-3", "lr = 2e-3\nbetas = [0.9, 0.99]")
    })
    .unwrap_err();
    assert!(e.contains("betas") && e.contains("3 values"), "{e}");
    let e = parse(d, |s| s.replace("\"lodge139\"", "\"smpl\"")).unwrap_err();
    assert!(e.contains("unknown variant `smpl`"), "{e}");

    // From a file: the error names it; relative paths resolve against its directory.
    let p = d.join("bad.toml");
    std::fs::write(
        &p,
        common::tiny_config(Path::new("run"), 10, 1).replace("[ema]", "[emma]"),
    )
    .unwrap();
    let e = TrainConfig::load(&p).unwrap_err().to_string();
    assert!(e.contains("bad.toml") && e.contains("emma"), "{e}");
    let ok = d.join("ok.toml");
    std::fs::write(&ok, common::tiny_config(Path::new("run"), 10, 1)).unwrap();
    let c = TrainConfig::load(&ok).unwrap();
    assert_eq!(c.run.dir, std::path::absolute(d).unwrap().join("run"));
    assert_eq!(c.data.representation, Representation::Lodge139);
    // The resolved copy parses back to the same configuration.
    assert_eq!(
        TrainConfig::parse(&c.to_toml(), Path::new("/elsewhere")).unwrap(),
        c
    );
}

#[test]
fn model_paths_resolve_against_the_config_file_and_survive_the_run_copy() {
    let tmp = tempfile::tempdir().unwrap();
    let c = parse(tmp.path(), |s| {
        s.replace("[model]\n", "[model]\nvqvae = \"runs/my_vqvae\"\n")
    })
    .unwrap();
    let want = tmp.path().join("runs/my_vqvae");
    assert_eq!(
        c.model.get("vqvae").and_then(|v| v.as_str()),
        Some(want.to_str().unwrap())
    );
    // The run's config copy, read from elsewhere (as `--resume` does), keeps the same path.
    let again = TrainConfig::parse(&c.to_toml(), Path::new("/elsewhere")).unwrap();
    assert_eq!(again.model.get("vqvae"), c.model.get("vqvae"));
}

#[test]
fn a_clip_missing_from_the_manifest_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = tmp.path().join("manifest.json");
    std::fs::write(
        &manifest,
        r#"{"genres": ["salsa"], "clips": [{"name": "other_clip", "genre": "salsa"}]}"#,
    )
    .unwrap();
    let c = parse(tmp.path(), |s| {
        s.replace(
            "[data]\n",
            &format!("[data]\nmanifest = {:?}\n", manifest.to_str().unwrap()),
        )
    })
    .unwrap();
    let e = WindowDataset::read_clips(&c.data).unwrap_err().to_string();
    assert!(e.contains("not listed in the manifest"), "{e}");
    assert!(e.contains(".pkl"), "names the motion file: {e}");
}
