//! The holistic system end to end at toy size: the three runs (`soulnet_vq`, `soulnet_mmr`,
//! `soulnet_magm`) train on a real AIST++ body with hands, face and music, `dancegen bundle`'s
//! assembler joins them, and the loaded model dances to music longer than one window (so the
//! windows are joined by inpainting). Training quality is not tested here (a few steps); shapes,
//! files, the join and the errors are.

mod common;

use std::path::Path;

use dancegen_io::NpyData;
use dancegen_nn::device;
use dancegen_nn::progress::NoHook;
use dancegen_nn::weights::{self, Layout};
use dancegen_soulnet::bundle::HolisticModel;
use dancegen_soulnet::pipeline::{GenerateOptions, generate};
use dancegen_train::data::Normalizer;
use dancegen_train::task::TrainTask;
use dancegen_train::tasks::soulnet::{
    Replacements, SoulnetMagmTask, assemble_holistic_bundle, replace_in_holistic_model,
};
use dancegen_train::{RunOptions, TrainConfig};

/// AIST++ sequence frames at 30 fps.
const FRAMES: usize = 288;

fn write_inputs(dir: &Path) {
    let stem = common::aist_motion().file_stem().unwrap().to_owned();
    let hol = dir.join("holistic");
    let music = dir.join("music");
    std::fs::create_dir_all(&hol).unwrap();
    std::fs::create_dir_all(&music).unwrap();
    let hands: Vec<f32> = (0..FRAMES * 90)
        .map(|i| 0.3 * ((i as f32) * 0.01).sin())
        .collect();
    let face: Vec<f32> = (0..FRAMES * 52)
        .map(|i| 0.5 + 0.4 * ((i as f32) * 0.03).sin())
        .collect();
    dancegen_io::write_npz(
        &hol.join(&stem).with_extension("npz"),
        &[
            ("hands", &[FRAMES, 30, 3], NpyData::F32(&hands)),
            ("face", &[FRAMES, 52], NpyData::F32(&face)),
        ],
    )
    .unwrap();
    let feats: Vec<f32> = (0..FRAMES * 35)
        .map(|i| ((i % 35) as f32 * 0.1 + (i / 35) as f32 * 0.05).sin())
        .collect();
    dancegen_io::write_npy_f32(
        &music.join(&stem).with_extension("npy"),
        &[FRAMES, 35],
        &feats,
    )
    .unwrap();
}

fn config(dir: &Path, run: &str, window: usize, model: &str) -> (TrainConfig, std::path::PathBuf) {
    let text = format!(
        r#"
[run]
dir = "{run}"
seed = 3
steps = 3
checkpoint_every = 3
log_every = 1

[data]
paths = ["{motion}"]
holistic = "holistic"
representation = "holistic"
window = {window}
stride = 16
batch_size = 4
normalizer = "mean_std"

[data.music]
dir = "music"
dims = 35

{model}

[optimizer]
kind = "adamw"
lr = 1e-3
"#,
        motion = common::aist_motion().display(),
    );
    let c = TrainConfig::parse(&text, dir).unwrap();
    let path = dir.join(format!("{run}.toml"));
    (c, path)
}

fn train(dir: &Path, run: &str, window: usize, model: &str) {
    let (c, path) = config(dir, run, window, model);
    let opts = RunOptions {
        quiet: true,
        stop_at: None,
    };
    dancegen_train::tasks::train_config(&c, &path, &opts).unwrap_or_else(|e| panic!("{run}: {e}"));
}

#[test]
fn three_runs_make_a_model_that_dances_longer_than_one_window() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_inputs(dir);
    train(
        dir,
        "vq",
        32,
        "[model]\nkind = \"soulnet_vq\"\nnum_quantizers = 3\nnb_code = 16\ncode_dim = 8\nwidth = 16\ndepth = 1",
    );
    train(
        dir,
        "mmr",
        32,
        "[model]\nkind = \"soulnet_mmr\"\nd_model = 16\nn_layers = 1\nn_heads = 2\nd_ff = 32\nlatent_dim = 8",
    );
    // The generator's window must be window_tokens × 4 frames: say so when it is not.
    let gen_model = "[model]\nkind = \"soulnet_magm\"\nvq = \"vq\"\nmmr = \"mmr\"\n\n[model.generator]\nd_model = 16\nn_layers = 1\nn_heads = 2\nd_ff = 32\nresidual_layers = 1\nwindow_tokens = 8";
    let (c, path) = config(dir, "gen", 40, gen_model);
    let e = dancegen_train::tasks::train_config(
        &c,
        &path,
        &RunOptions {
            quiet: true,
            stop_at: None,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("window") && e.contains("32"), "{e}");
    train(dir, "gen", 32, gen_model);
    let log = std::fs::read_to_string(dir.join("gen/log.csv")).unwrap();
    assert!(
        log.lines()
            .next()
            .unwrap()
            .contains("masked_ce,residual_ce"),
        "{log}"
    );
    // With SoulNet's training-time MMR loss: logged, finite, positive.
    let with_mmr = gen_model.replace("mmr = \"mmr\"\n", "mmr = \"mmr\"\nmmr_loss_weight = 0.5\n");
    assert_ne!(with_mmr, gen_model);
    train(dir, "gen_mmr", 32, &with_mmr);
    let log = std::fs::read_to_string(dir.join("gen_mmr/log.csv")).unwrap();
    let head: Vec<&str> = log.lines().next().unwrap().split(',').collect();
    let col = head
        .iter()
        .position(|&h| h == "mmr")
        .expect("an mmr column");
    for line in log.lines().skip(1) {
        let v: f64 = line.split(',').nth(col).unwrap().parse().unwrap();
        assert!(v.is_finite() && v > 0.0, "{log}");
    }

    let out = dir.join("model");
    assemble_holistic_bundle(
        &dir.join("vq"),
        &dir.join("mmr"),
        &dir.join("gen"),
        &out,
        "toy",
    )
    .unwrap();
    let dev = device::inference();
    let model = HolisticModel::load(&out, &dev).unwrap();
    // 100 frames = 25 tokens per part: windows of 8 tokens overlapping by the default 8 → the
    // overlap is capped below the window, so several windows.
    let mut opts = GenerateOptions::defaults(&model, 7);
    opts.sampling.overlap_tokens = 2;
    opts.sampling.steps = 3;
    let music: Vec<f32> = (0..100 * 35).map(|i| (i as f32 * 0.013).cos()).collect();
    let made = generate(&model, &music, &opts, &dev, &NoHook).unwrap();
    assert_eq!(made.frames, 100);
    assert_eq!(made.rows.len(), 100 * 675);
    assert!(made.windows >= 4, "{} windows", made.windows);
    assert_eq!(made.joins.len(), made.windows - 1);
    let again = generate(&model, &music, &opts, &dev, &NoHook).unwrap();
    assert_eq!(made.rows, again.rows, "same seed, same dance");
    let d = dancegen_soulnet::layout::decode(&made.rows, 30.0).unwrap();
    assert_eq!(d.motion.poses.len(), 100 * 52 * 3);
    assert!(d.face.iter().all(|v| (0.0..=1.0).contains(v)));

    // The autoencoder's decoder fine-tuned alone on the feet, swapped into the model: the
    // MMR, the generator, the normaliser and the sampling stay; the tokens decode as before
    // apart from the decoder.
    let vq_model = "[model]\nkind = \"soulnet_vq\"\nnum_quantizers = 3\nnb_code = 16\ncode_dim = 8\nwidth = 16\ndepth = 1";
    train(
        dir,
        "vq_feet",
        32,
        &format!(
            "{vq_model}\ninit_from = \"vq\"\ndecoders_only = true\nfoot_velocity_weight = 1.0"
        ),
    );
    let swapped = dir.join("model_feet");
    let vq_feet = dir.join("vq_feet");
    let runs = Replacements {
        vq: Some(&vq_feet),
        generator: None,
    };
    replace_in_holistic_model(runs, &out, &swapped, "toy-feet").unwrap();
    for f in [
        "mmr.safetensors",
        "generator.safetensors",
        "normalizer.json",
    ] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(swapped.join(f)).unwrap(),
            "{f}"
        );
    }
    assert_ne!(
        std::fs::read(out.join("vq.safetensors")).unwrap(),
        std::fs::read(swapped.join("vq.safetensors")).unwrap()
    );
    let tuned = HolisticModel::load(&swapped, &dev).unwrap();
    assert_eq!(tuned.config.name, "toy-feet");
    assert_eq!(tuned.config.sampling, model.config.sampling);
    assert_eq!(tuned.config.vq.foot_velocity_weight, 1.0);
    let made_tuned = generate(&tuned, &music, &opts, &dev, &NoHook).unwrap();
    assert_eq!(made_tuned.frames, 100);
    // Another architecture is refused, naming the run.
    train(
        dir,
        "vq_wide",
        32,
        &vq_model.replace("width = 16", "width = 24"),
    );
    let vq_wide = dir.join("vq_wide");
    let runs = Replacements {
        vq: Some(&vq_wide),
        generator: None,
    };
    let e = replace_in_holistic_model(runs, &out, &dir.join("x"), "x")
        .unwrap_err()
        .to_string();
    assert!(e.contains("vq_wide") && e.contains("architecture"), "{e}");
    assert!(
        !dir.join("x").exists(),
        "nothing written for a refused swap"
    );

    // The generator trained further from the model itself (`vq`, `mmr` and `init_from` name
    // the model directory): it starts from the model's weights, and swapped in it keeps the
    // autoencoder, the MMR, the normaliser and the sampling.
    let more = gen_model.replace(
        "vq = \"vq\"\nmmr = \"mmr\"\n",
        "vq = \"model\"\nmmr = \"model\"\ninit_from = \"model\"\n",
    );
    assert_ne!(more, gen_model);
    let (c, path) = config(dir, "gen_more", 32, &more);
    let task = SoulnetMagmTask::from_config(&c, &path).unwrap();
    let start = task.init_with_data(
        &dev,
        &Normalizer::load(&out.join("normalizer.json")).unwrap(),
    );
    // The tensors as saved (the safetensors data block; the header's metadata order varies).
    let tensors = |g: &dancegen_soulnet::generator::PartGenerator, name: &str| {
        let p = dir.join(name);
        weights::save_as(g, &p, Layout::Burn, &[], weights::Storage::F16).unwrap();
        let b = std::fs::read(p).unwrap();
        let n = u64::from_le_bytes(b[..8].try_into().unwrap()) as usize;
        b[8 + n..].to_vec()
    };
    let first = tensors(&start, "start.safetensors");
    assert!(
        first == tensors(&model.generator, "shipped.safetensors"),
        "init_from starts from the model's generator"
    );
    assert!(first != tensors(&task.init(&dev), "scratch.safetensors"));
    train(dir, "gen_more", 32, &more);
    let regen = dir.join("model_gen");
    let gen_more = dir.join("gen_more");
    let runs = Replacements {
        vq: None,
        generator: Some(&gen_more),
    };
    replace_in_holistic_model(runs, &out, &regen, "toy-gen").unwrap();
    for f in ["vq.safetensors", "mmr.safetensors", "normalizer.json"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(regen.join(f)).unwrap(),
            "{f}"
        );
    }
    assert_ne!(
        std::fs::read(out.join("generator.safetensors")).unwrap(),
        std::fs::read(regen.join("generator.safetensors")).unwrap()
    );
    let again = HolisticModel::load(&regen, &dev).unwrap();
    assert_eq!(again.config.sampling, model.config.sampling);
    assert_eq!(
        generate(&again, &music, &opts, &dev, &NoHook)
            .unwrap()
            .frames,
        100
    );
    // A generator of another size is refused where the run starts, naming init_from.
    let (c, path) = config(
        dir,
        "gen_wide",
        32,
        &more.replace("d_model = 16", "d_model = 24"),
    );
    let e = SoulnetMagmTask::from_config(&c, &path).err().unwrap();
    assert!(e.contains("init_from") && e.contains("[generator]"), "{e}");
    // The runs' own generator goes into the fine-tuned model (same tokens); one trained on
    // another autoencoder is refused, naming its run.
    let runs = Replacements {
        vq: None,
        generator: Some(&dir.join("gen")),
    };
    replace_in_holistic_model(runs, &swapped, &dir.join("model_other"), "x").unwrap();
    train(
        dir,
        "gen_wide_vq",
        32,
        &gen_model.replace("vq = \"vq\"", "vq = \"vq_wide\""),
    );
    let e = replace_in_holistic_model(
        Replacements {
            vq: None,
            generator: Some(&dir.join("gen_wide_vq")),
        },
        &out,
        &dir.join("y"),
        "y",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("gen_wide_vq") && e.contains("another autoencoder"),
        "{e}"
    );
    assert!(
        !dir.join("y").exists(),
        "nothing written for a refused swap"
    );

    // A model directory missing a file names it.
    std::fs::remove_file(out.join("mmr.safetensors")).unwrap();
    let e = HolisticModel::load(&out, &dev).err().unwrap().to_string();
    assert!(e.contains("mmr.safetensors"), "{e}");
}
