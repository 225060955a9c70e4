//! Measurements of the holistic model's networks on held-out data (issue 19,
//! `docs/holistic-eval.md`), printed as one JSON object:
//!
//! - `mmr MODEL_DIR DATASET_DIR`: the bundle's MMR on the held-out clips
//!   (`DATASET_DIR/held_out/{motion,holistic,music}`): music retrieval by motion over
//!   non-overlapping 128-frame windows (R@1, R@3 against chance, Euclidean like the metric code)
//!   and the MMR-Matching Score (Eq. 8 over 1-s segments, and the released code's variant with one
//!   music latent per clip) of the real held-out dances;
//! - `mmr-gen MODEL_DIR DATASET_DIR GEN_DIR`: the MMR-Matching Score (both variants) of
//!   generated dances, `GEN_DIR/<held-out clip>.json` as `dancegen generate -o X.json` writes them
//!   (SMPL-H rotations, pelvis path, face), against the clip's music features — the measure the
//!   training-time MMR loss is meant to lower;
//! - `recon DATASET_DIR VQ_RUN...`: each part autoencoder run's reconstruction of the held-out
//!   clips, per part: root-relative body joint error (real motion), finger joint error relative to
//!   the wrist (synthetic fingers), both from the `ric` positions (heading-canonical), and ARKit
//!   weight error (synthetic face), and the mean jerk of the pelvis-relative body joints of the
//!   real clips and of their reconstruction.
//!
//! - `roundtrip DATASET_DIR VQ OUT_DIR`: the held-out and the training clips' bodies as SMPL
//!   `.npz` (AMASS-style, as `dancegen generate` writes it), read back from the holistic vector in two
//!   ways: `OUT_DIR/{held_out,train}/real/` through the representation alone and
//!   `OUT_DIR/{held_out,train}/recon/` through the part autoencoder `VQ` (a `soulnet_vq` run or
//!   a holistic bundle), both then put on the tracked floor as generation does (without its foot
//!   lock), so `dancegen eval --metrics physical` tells what the autoencoder alone does to the
//!   feet, the jitter and the tempo.
//!
//! ```text
//!     cargo run --release -p dancegen-train --example holistic_probe -- mmr models/soulnet-small target/datasets/holistic
//!     cargo run --release -p dancegen-train --example holistic_probe -- recon target/datasets/holistic target/runs/soulnet_small_vq ...
//!     cargo run --release -p dancegen-train --example holistic_probe -- roundtrip target/datasets/holistic models/soulnet-small target/holistic-roundtrip
//! ```

use std::path::{Path, PathBuf};

use dancegen_metrics::mmr::{
    MatchingVariant, SequenceLatents, chance_recall, matching_score, recall_at, retrieval_ranks,
};
use dancegen_motion::face::ARKIT_COUNT;
use dancegen_motion::repr::holistic::split::{BODY_DIMS, BODY_HAND_DIMS};
use dancegen_nn::burn::tensor::{Device, Tensor, TensorData};
use dancegen_nn::device;
use dancegen_nn::part_autoencoder::PartAutoencoder;
use dancegen_nn::retrieval::SequenceEncoder;
use dancegen_nn::weights::{self, Layout};
use dancegen_soulnet::bundle::HolisticModel;
use dancegen_soulnet::layout::{MUSIC_DIMS, TOTAL_DIMS};
use dancegen_train::data::{Clip, Normalizer, load_clips, motion_files};
use dancegen_train::tasks::soulnet::{KIND, VqTable};
use dancegen_train::{TrainConfig, files};

/// Retrieval window (the MMR's training window, one generator window).
const WINDOW: usize = 128;
/// Eq. 8's segment: one second.
const SEGMENT: usize = 30;

fn held_out(dataset: &Path) -> Result<Vec<Clip>, String> {
    clips_in(&dataset.join("held_out"))
}

/// The holistic clips of a data set folder with `motion/`, `holistic/` and `music/`.
fn clips_in(dir: &Path) -> Result<Vec<Clip>, String> {
    let h = std::path::absolute(dir).map_err(|e| e.to_string())?;
    let text = format!(
        "[run]\ndir = \"/tmp/unused\"\nsteps = 1\n[data]\npaths = [\"{m}\"]\nholistic = \"{hol}\"\n\
         representation = \"holistic\"\nwindow = 64\nstride = 64\nbatch_size = 1\n[data.music]\ndir = \"{mu}\"\ndims = {MUSIC_DIMS}\n\
         [model]\nkind = \"{KIND}\"\n[optimizer]\nkind = \"adamw\"\nlr = 1e-3\n",
        m = h.join("motion").display(),
        hol = h.join("holistic").display(),
        mu = h.join("music").display(),
    );
    let c = TrainConfig::parse(&text, Path::new("/")).map_err(|e| e.to_string())?;
    let mut clips = Vec::new();
    for f in motion_files(&c.data.paths).map_err(|e| e.to_string())? {
        clips.extend(load_clips(&f, &c.data).map_err(|e| e.to_string())?);
    }
    if clips.is_empty() {
        return Err(format!("{}: no clips", h.display()));
    }
    Ok(clips)
}

fn embed(enc: &SequenceEncoder, rows: &[f32], dims: usize, dev: &Device) -> Vec<f32> {
    let t = rows.len() / dims;
    let x = Tensor::<3>::from_data(TensorData::new(rows.to_vec(), [1, t, dims]), dev);
    enc.forward(x, None)
        .into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .unwrap()
}

fn mmr(model_dir: &Path, dataset: &Path) -> Result<serde_json::Value, String> {
    let dev = device::inference();
    let model = HolisticModel::load(model_dir, &dev).map_err(|e| e.to_string())?;
    let clips = held_out(dataset)?;
    let (mut zm, mut za) = (Vec::new(), Vec::new());
    // Per clip: motion and music latents of its 1-s segments, and the whole clip's music.
    let mut seqs: Vec<[Vec<Vec<f32>>; 3]> = Vec::new();
    for c in &clips {
        let mut motion = c.motion.clone();
        model.norm.transform(&mut motion);
        let music = c.music.as_ref().ok_or("held-out clip without music")?;
        let frames = c.frames.min(music.len() / MUSIC_DIMS);
        for s in (0..frames.saturating_sub(WINDOW - 1)).step_by(WINDOW) {
            let m = &motion[s * TOTAL_DIMS..(s + WINDOW) * TOTAL_DIMS];
            let a = &music[s * MUSIC_DIMS..(s + WINDOW) * MUSIC_DIMS];
            zm.push(embed(&model.mmr.motion, m, TOTAL_DIMS, &dev));
            za.push(embed(&model.mmr.music, a, MUSIC_DIMS, &dev));
        }
        seqs.push(sequence_latents(&model, &motion, music, frames, &dev));
    }
    let ranks = retrieval_ranks(&zm, &za);
    Ok(serde_json::json!({
        "clips": clips.len(),
        "windows": zm.len(),
        "window_frames": WINDOW,
        "r1": recall_at(&ranks, 1),
        "r3": recall_at(&ranks, 3),
        "chance_r1": chance_recall(zm.len(), 1),
        "chance_r3": chance_recall(zm.len(), 3),
        "matching_score_eq8": matching_scores(&seqs, MatchingVariant::Paper),
        "matching_score_released_code": matching_scores(&seqs, MatchingVariant::ReleasedCode),
    }))
}

/// The matching score over clips' `[segment motion, segment music, whole-clip music]` latents
/// ([`sequence_latents`]): Eq. 8 pairs each motion segment with its music segment, the released
/// code's variant with the whole clip's music.
fn matching_scores(seqs: &[[Vec<Vec<f32>>; 3]], variant: MatchingVariant) -> f64 {
    let pairs: Vec<SequenceLatents> = seqs
        .iter()
        .map(|[m, a, w]| SequenceLatents {
            motion: m,
            music: match variant {
                MatchingVariant::Paper => a,
                MatchingVariant::ReleasedCode => w,
            },
        })
        .collect();
    matching_score(&pairs, variant)
}

/// One clip's MMR latents for the matching score: motion and music per 1-s segment, and the
/// whole clip's music (`motion` normalised, `frames` long).
fn sequence_latents(
    model: &HolisticModel,
    motion: &[f32],
    music: &[f32],
    frames: usize,
    dev: &Device,
) -> [Vec<Vec<f32>>; 3] {
    let (mut segm, mut sega) = (Vec::new(), Vec::new());
    for s in (0..frames.saturating_sub(SEGMENT - 1)).step_by(SEGMENT) {
        let m = &motion[s * TOTAL_DIMS..(s + SEGMENT) * TOTAL_DIMS];
        let a = &music[s * MUSIC_DIMS..(s + SEGMENT) * MUSIC_DIMS];
        segm.push(embed(&model.mmr.motion, m, TOTAL_DIMS, dev));
        sega.push(embed(&model.mmr.music, a, MUSIC_DIMS, dev));
    }
    let whole = vec![embed(
        &model.mmr.music,
        &music[..frames * MUSIC_DIMS],
        MUSIC_DIMS,
        dev,
    )];
    [segm, sega, whole]
}

/// The MMR-Matching Score of generated dances (see the module documentation).
fn mmr_gen(model_dir: &Path, dataset: &Path, gen_dir: &Path) -> Result<serde_json::Value, String> {
    use dancegen_motion::repr::holistic::{Holistic623, split};
    let dev = device::inference();
    let model = HolisticModel::load(model_dir, &dev).map_err(|e| e.to_string())?;
    let h = std::path::absolute(dataset.join("held_out")).map_err(|e| e.to_string())?;
    let flat = |v: &serde_json::Value, key: &str, path: &Path| -> Result<Vec<f32>, String> {
        fn walk(v: &serde_json::Value, out: &mut Vec<f32>) {
            match v {
                serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, out)),
                serde_json::Value::Number(n) => out.push(n.as_f64().unwrap_or(f64::NAN) as f32),
                _ => {}
            }
        }
        let mut out = Vec::new();
        walk(
            v.pointer(key)
                .ok_or_else(|| format!("{}: no {key}", path.display()))?,
            &mut out,
        );
        Ok(out)
    };
    let mut seqs: Vec<[Vec<Vec<f32>>; 3]> = Vec::new();
    let mut stems = Vec::new();
    for entry in std::fs::read_dir(h.join("music")).map_err(|e| e.to_string())? {
        let music_path = entry.map_err(|e| e.to_string())?.path();
        let stem = music_path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let json_path = gen_dir.join(format!("{stem}.json"));
        if !json_path.is_file() {
            continue;
        }
        let text = std::fs::read_to_string(&json_path).map_err(|e| e.to_string())?;
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        let poses = flat(&v, "/smplh_poses_axis_angle", &json_path)?;
        let trans = flat(&v, "/pelvis_trans", &json_path)?;
        let face = flat(&v, "/face/weights", &json_path)?;
        let inter = Holistic623::encode(&poses, &trans, 30.0).map_err(|e| e.to_string())?;
        let body_hands = split::to_split(&inter, 0).map_err(|e| e.to_string())?;
        let mut motion = Vec::new();
        for (f, row) in body_hands.chunks_exact(BODY_HAND_DIMS).enumerate() {
            motion.extend_from_slice(row);
            motion.extend_from_slice(&face[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT]);
        }
        model.norm.transform(&mut motion);
        let music = dancegen_io::read_npy(&music_path).map_err(|e| e.to_string())?;
        let music: Vec<f32> = music.data.iter().map(|&x| x as f32).collect();
        let frames = (motion.len() / TOTAL_DIMS).min(music.len() / MUSIC_DIMS);
        seqs.push(sequence_latents(&model, &motion, &music, frames, &dev));
        stems.push(stem);
    }
    if seqs.is_empty() {
        return Err(format!(
            "{}: no generated .json of a held-out clip",
            gen_dir.display()
        ));
    }
    stems.sort();
    Ok(serde_json::json!({
        "clips": stems,
        "matching_score_eq8": matching_scores(&seqs, MatchingVariant::Paper),
        "matching_score_released_code": matching_scores(&seqs, MatchingVariant::ReleasedCode),
    }))
}

/// Root-relative joint positions `(T, 52, 3)` in the heading-canonical frame (HumanML3D's
/// `ric` channels of the split vector: body joints 1–21 at `[4, 67)`, the 30 finger joints at the
/// start of the hands part; the root's height subtracted) and the face weights of normalised
/// rows. Reading positions straight from `ric` keeps a drifting heading or root path (integrated
/// velocities) out of the pose error.
fn joints_and_face(rows: &[f32], norm: &Normalizer) -> Result<(Vec<f32>, Vec<f32>), String> {
    let mut r = rows.to_vec();
    norm.inverse(&mut r)?;
    let (mut j, mut face) = (Vec::new(), Vec::new());
    for row in r.chunks_exact(TOTAL_DIMS) {
        let root_y = row[3];
        j.extend_from_slice(&[0.0, 0.0, 0.0]);
        let ric = row[4..4 + 21 * 3]
            .iter()
            .chain(&row[BODY_DIMS..BODY_DIMS + 30 * 3]);
        for (k, v) in ric.enumerate() {
            j.push(if k % 3 == 1 { v - root_y } else { *v });
        }
        face.extend(row[BODY_HAND_DIMS..].iter().map(|v| v.clamp(0.0, 1.0)));
    }
    Ok((j, face))
}

fn recon(dataset: &Path, runs: &[PathBuf]) -> Result<serde_json::Value, String> {
    let dev = device::inference();
    let clips = held_out(dataset)?;
    let mut out = Vec::new();
    for run in runs {
        let table: VqTable = dancegen_train::tasks::bundle_files::finished_run_config(run, KIND)
            .map_err(|e| e.to_string())?;
        let vq = weights::load(
            table.autoencoder().init(&dev),
            &run.join(files::WEIGHTS),
            Layout::Burn,
        )
        .map_err(|e| e.to_string())?;
        let norm = Normalizer::load(&run.join(files::NORMALIZER)).map_err(|e| e.to_string())?;
        let (mut body, mut hands, mut face, mut n) = (0f64, 0f64, 0f64, 0usize);
        let (mut jerk_real, mut jerk_recon, mut jerk_n) = (0f64, 0f64, 0usize);
        for c in &clips {
            let t = c.frames / 4 * 4;
            let mut x = c.motion[..t * TOTAL_DIMS].to_vec();
            norm.transform(&mut x)?;
            let input =
                Tensor::<3>::from_data(TensorData::new(x.clone(), [1, t, TOTAL_DIMS]), &dev);
            let (rec, _) = vq.forward(input);
            let y: Vec<f32> = rec
                .into_data()
                .convert::<f32>()
                .try_to_vec::<f32>()
                .unwrap();
            let (jx, fx) = joints_and_face(&x, &norm)?;
            let (jy, fy) = joints_and_face(&y, &norm)?;
            jerk_real += body_jerk_sum(&jx, t);
            jerk_recon += body_jerk_sum(&jy, t);
            jerk_n += t.saturating_sub(3);
            for f in 0..t {
                let dist = |j: usize, rel: Option<usize>| {
                    let p = |v: &[f32], j: usize, k: usize| v[(f * 52 + j) * 3 + k];
                    (0..3)
                        .map(|k| {
                            let o = |v: &[f32]| rel.map_or(0.0, |w| p(v, w, k));
                            let a = p(&jx, j, k) - o(&jx);
                            let b = p(&jy, j, k) - o(&jy);
                            f64::from(a - b).powi(2)
                        })
                        .sum::<f64>()
                        .sqrt()
                };
                body += (1..22).map(|j| dist(j, None)).sum::<f64>() / 21.0;
                // Fingers relative to their wrist (left 20, right 21).
                hands += (22..52)
                    .map(|j| dist(j, Some(if j < 37 { 20 } else { 21 })))
                    .sum::<f64>()
                    / 30.0;
                face += (0..ARKIT_COUNT)
                    .map(|k| f64::from((fx[f * ARKIT_COUNT + k] - fy[f * ARKIT_COUNT + k]).abs()))
                    .sum::<f64>()
                    / ARKIT_COUNT as f64;
                n += 1;
            }
        }
        out.push(serde_json::json!({
            "run": run.display().to_string(),
            "quantizer": table.quantizer,
            "levels": table.levels(),
            "nb_code": table.nb_code,
            "frames": n,
            "body_mpjpe_mm": 1000.0 * body / n as f64,
            "finger_mpjpe_mm": 1000.0 * hands / n as f64,
            "face_l1": face / n as f64,
            "body_jerk_real": jerk_real / jerk_n.max(1) as f64,
            "body_jerk_recon": jerk_recon / jerk_n.max(1) as f64,
        }));
    }
    Ok(serde_json::Value::Array(out))
}

/// Sum over frames of the mean jerk (m/s³ at 30 fps, third finite difference) of body joints
/// 1–21 relative to the pelvis, from the `ric` positions `[T, 52, 3]`: how jittery a
/// reconstruction is next to the real motion, apart from its error.
fn body_jerk_sum(joints: &[f32], t: usize) -> f64 {
    let p = |f: usize, j: usize, k: usize| f64::from(joints[(f * 52 + j) * 3 + k]);
    (0..t.saturating_sub(3))
        .map(|f| {
            (1..22)
                .map(|j| {
                    (0..3)
                        .map(|k| {
                            let d = |g: usize| p(g, j, k) - p(g, 0, k);
                            (d(f + 3) - 3.0 * d(f + 2) + 3.0 * d(f + 1) - d(f)).powi(2)
                        })
                        .sum::<f64>()
                        .sqrt()
                })
                .sum::<f64>()
                / 21.0
                * 27_000.0
        })
        .sum()
}

/// A part autoencoder and its normaliser: a `soulnet_vq` run or a holistic bundle.
fn load_vq(path: &Path, dev: &Device) -> Result<(PartAutoencoder, Normalizer), String> {
    use dancegen_soulnet::bundle::files as bundle_files;
    if path.join(bundle_files::VQ).is_file() {
        let m = HolisticModel::load(path, dev).map_err(|e| e.to_string())?;
        let norm =
            Normalizer::load(&path.join(bundle_files::NORMALIZER)).map_err(|e| e.to_string())?;
        return Ok((m.vq, norm));
    }
    let table: VqTable = dancegen_train::tasks::bundle_files::finished_run_config(path, KIND)
        .map_err(|e| e.to_string())?;
    let vq = weights::load(
        table.autoencoder().init(dev),
        &path.join(files::WEIGHTS),
        Layout::Burn,
    )
    .map_err(|e| e.to_string())?;
    let norm = Normalizer::load(&path.join(files::NORMALIZER)).map_err(|e| e.to_string())?;
    Ok((vq, norm))
}

/// Raw holistic rows `(T, 675)` → the SMPL 24 body on the tracked floor, written as `.npz`.
fn write_body(rows: &[f32], path: &Path) -> Result<(), String> {
    let fps = 30.0;
    let d = dancegen_soulnet::layout::decode(rows, fps)?;
    let t = d.motion.frames();
    let mut poses = vec![0f32; t * 72];
    for f in 0..t {
        poses[f * 72..f * 72 + 66].copy_from_slice(&d.motion.poses[f * 156..f * 156 + 66]);
    }
    let mut body = dancegen_motion::repr::SmplMotion::new(fps, poses, d.motion.trans.clone())
        .map_err(|e| e.to_string())?;
    body.put_feet_on_tracked_floor()
        .map_err(|e| e.to_string())?;
    dancegen_formats::smpl_npz::write_smpl_npz(
        path,
        &body,
        &dancegen_formats::smpl_npz::SmplNpzOptions::default(),
    )
    .map_err(|e| e.to_string())
}

/// The denormalised rows beside a written body (`x.npz` -> `x.rows.npy`, `(T, TOTAL_DIMS)`), so
/// the decoded joint positions can be compared with the bodies posed by the 6D rotations.
fn write_rows(rows: &[f32], body: &Path) -> Result<(), String> {
    let path = body.with_extension("rows.npy");
    dancegen_io::write_npy_f32(&path, &[rows.len() / TOTAL_DIMS, TOTAL_DIMS], rows)
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn roundtrip(dataset: &Path, vq_path: &Path, out: &Path) -> Result<serde_json::Value, String> {
    let dev = device::inference();
    let (vq, norm) = load_vq(vq_path, &dev)?;
    let mut written = serde_json::Map::new();
    for (split, dir) in [
        ("held_out", dataset.join("held_out")),
        ("train", dataset.to_path_buf()),
    ] {
        let (real_dir, recon_dir) = (out.join(split).join("real"), out.join(split).join("recon"));
        for d in [&real_dir, &recon_dir] {
            std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
        }
        let clips = clips_in(&dir)?;
        for (i, c) in clips.iter().enumerate() {
            let stem = c
                .source
                .file_stem()
                .map_or_else(|| format!("clip{i}"), |s| s.to_string_lossy().into_owned());
            let name = format!("{stem}_{i}.npz");
            let t = c.frames / 4 * 4;
            let raw = &c.motion[..t * TOTAL_DIMS];
            write_body(raw, &real_dir.join(&name))?;
            write_rows(raw, &real_dir.join(&name))?;
            let mut x = raw.to_vec();
            norm.transform(&mut x)?;
            let input = Tensor::<3>::from_data(TensorData::new(x, [1, t, TOTAL_DIMS]), &dev);
            let (rec, _) = vq.forward(input);
            let mut y: Vec<f32> = rec
                .into_data()
                .convert::<f32>()
                .try_to_vec::<f32>()
                .map_err(|e| format!("{e:?}"))?;
            norm.inverse(&mut y)?;
            write_body(&y, &recon_dir.join(&name))?;
            write_rows(&y, &recon_dir.join(&name))?;
        }
        written.insert(split.into(), clips.len().into());
    }
    Ok(serde_json::json!({ "out": out.display().to_string(), "clips": written }))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("mmr") if args.len() == 3 => mmr(Path::new(&args[1]), Path::new(&args[2])),
        Some("mmr-gen") if args.len() == 4 => mmr_gen(
            Path::new(&args[1]),
            Path::new(&args[2]),
            Path::new(&args[3]),
        ),
        Some("recon") if args.len() >= 3 => recon(
            Path::new(&args[1]),
            &args[2..].iter().map(PathBuf::from).collect::<Vec<_>>(),
        ),
        Some("roundtrip") if args.len() == 4 => roundtrip(
            Path::new(&args[1]),
            Path::new(&args[2]),
            Path::new(&args[3]),
        ),
        _ => Err(
            "usage: holistic_probe mmr MODEL_DIR DATASET_DIR | mmr-gen MODEL_DIR DATASET_DIR GEN_DIR | recon DATASET_DIR VQ_RUN... | roundtrip DATASET_DIR VQ OUT_DIR".into(),
        ),
    };
    match result {
        Ok(v) => println!("{}", serde_json::to_string_pretty(&v).unwrap()),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
