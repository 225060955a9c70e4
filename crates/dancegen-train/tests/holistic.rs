//! The holistic part autoencoder (`[model] kind = "soulnet_vq"`) trains on a real AIST++ body
//! with hands and a face from `[data] holistic`; bad hands/face files are named in the error; its
//! decoder alone is fine-tuned from a finished run with the foot velocity loss.

mod common;

use std::path::Path;

use dancegen_io::NpyData;
use dancegen_train::tasks::soulnet::{QuantizerKind, SoulnetVqTask};
use dancegen_train::{RunOptions, TrainConfig, TrainTask};

/// AIST++ sequence frames at 30 fps.
const FRAMES: usize = 288;

fn write_holistic(dir: &Path, frames: usize) {
    let stem = common::aist_motion().file_stem().unwrap().to_owned();
    let hands: Vec<f32> = (0..frames * 90)
        .map(|i| 0.3 * ((i as f32) * 0.01).sin())
        .collect();
    let face: Vec<f32> = (0..frames * 52)
        .map(|i| 0.5 + 0.4 * ((i as f32) * 0.03).sin())
        .collect();
    dancegen_io::write_npz(
        &dir.join(stem).with_extension("npz"),
        &[
            ("hands", &[frames, 30, 3], NpyData::F32(&hands)),
            ("face", &[frames, 52], NpyData::F32(&face)),
        ],
    )
    .unwrap();
}

fn quiet() -> RunOptions {
    RunOptions {
        quiet: true,
        stop_at: None,
    }
}

fn config(run: &Path, holistic: &Path, quantizer: &str) -> TrainConfig {
    let text = format!(
        r#"
[run]
dir = "{run}"
seed = 3
steps = 4
checkpoint_every = 4
log_every = 2

[data]
paths = ["{motion}"]
holistic = "{holistic}"
representation = "holistic"
window = 32
stride = 8
batch_size = 4
normalizer = "mean_std"

[model]
kind = "soulnet_vq"
quantizer = "{quantizer}"
num_quantizers = 2
nb_code = 16
code_dim = 8
width = 16
depth = 1

[optimizer]
kind = "adamw"
lr = 1e-3
"#,
        run = run.display(),
        motion = common::aist_motion().display(),
        holistic = holistic.display(),
    );
    TrainConfig::parse(&text, run).unwrap()
}

#[test]
fn soulnet_vq_trains_for_every_quantizer_kind() {
    let dir = tempfile::tempdir().unwrap();
    let hol = dir.path().join("holistic");
    std::fs::create_dir_all(&hol).unwrap();
    write_holistic(&hol, FRAMES);
    for kind in ["hrvq", "rvq", "vq"] {
        let run = dir.path().join(kind);
        let c = config(&run, &hol, kind);
        let task = SoulnetVqTask::from_config(&c, &run.join("config.toml")).unwrap();
        assert_eq!(task.kind(), "soulnet_vq");
        let summary = dancegen_train::tasks::train_config(&c, &run.join("config.toml"), &quiet())
            .unwrap_or_else(|e| panic!("{kind}: {e}"));
        assert!(
            run.join("model.safetensors").is_file(),
            "{kind}: {summary:?}"
        );
        let log = std::fs::read_to_string(run.join("log.csv")).unwrap();
        assert!(
            log.lines().next().unwrap().contains("body,hands,face"),
            "{kind}: {log}"
        );
    }
    assert_eq!(
        SoulnetVqTask::from_config(&config(&dir.path().join("x"), &hol, "vq"), dir.path())
            .unwrap()
            .table
            .quantizer,
        QuantizerKind::Vq
    );
}

#[test]
fn bad_hands_or_face_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let hol = dir.path().join("holistic");
    std::fs::create_dir_all(&hol).unwrap();
    write_holistic(&hol, FRAMES - 10);
    let run = dir.path().join("run");
    let c = config(&run, &hol, "hrvq");
    let e = dancegen_train::tasks::train_config(&c, &run.join("config.toml"), &quiet())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(".npz") && e.contains("hands") && e.contains("shape"),
        "{e}"
    );
    // No [data] holistic: says what is missing.
    let mut c = config(&run, &hol, "hrvq");
    c.data.holistic = None;
    let e = dancegen_train::tasks::train_config(&c, &run.join("config.toml"), &quiet())
        .unwrap_err()
        .to_string();
    assert!(e.contains("[data] holistic"), "{e}");
    // The wrong representation for the task.
    let mut c = config(&run, &hol, "hrvq");
    c.data.representation = dancegen_train::config::Representation::Edge151;
    assert!(
        SoulnetVqTask::from_config(&c, &run.join("config.toml"))
            .unwrap_err()
            .contains("holistic")
    );
}

/// The tensors of a safetensors file whose names start with `prefix`, as raw bytes.
fn tensors(path: &Path, prefix: &str) -> Vec<(String, Vec<u8>)> {
    let bytes = std::fs::read(path).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let mut out: Vec<(String, Vec<u8>)> = st
        .tensors()
        .into_iter()
        .filter(|(n, _)| n.starts_with(prefix))
        .map(|(n, v)| (n, v.data().to_vec()))
        .collect();
    out.sort();
    assert!(!out.is_empty(), "no {prefix} tensors in {}", path.display());
    out
}

#[test]
fn a_decoder_fine_tune_keeps_the_tokens_and_learns_the_feet() {
    let dir = tempfile::tempdir().unwrap();
    let hol = dir.path().join("holistic");
    std::fs::create_dir_all(&hol).unwrap();
    write_holistic(&hol, FRAMES);
    let base = dir.path().join("base");
    let c = config(&base, &hol, "hrvq");
    dancegen_train::tasks::train_config(&c, &base.join("config.toml"), &quiet()).unwrap();

    let add = |c: &mut TrainConfig, extra: &str| {
        let t: toml::Table = toml::from_str(extra).unwrap();
        c.model.extend(t);
    };
    let tuned = dir.path().join("tuned");
    let mut c = config(&tuned, &hol, "hrvq");
    add(
        &mut c,
        &format!(
            "init_from = \"{}\"\ndecoders_only = true\nfoot_velocity_weight = 1.0\nacceleration_weight = 0.5",
            base.display()
        ),
    );
    dancegen_train::tasks::train_config(&c, &tuned.join("config.toml"), &quiet()).unwrap();
    let log = std::fs::read_to_string(tuned.join("log.csv")).unwrap();
    let header = log.lines().next().unwrap();
    assert!(
        header.contains("foot_velocity") && header.contains("acceleration"),
        "{header}"
    );
    // The encoders and the quantizer are the base run's, bit for bit; the decoder moved.
    let (a, b) = (
        base.join("model.safetensors"),
        tuned.join("model.safetensors"),
    );
    for part in ["encoders", "quantizer"] {
        assert_eq!(tensors(&a, part), tensors(&b, part), "{part}");
    }
    assert_ne!(tensors(&a, "decoder"), tensors(&b, "decoder"));

    // What cannot start: decoders_only alone, another architecture, a missing run.
    let mut c = config(&dir.path().join("x"), &hol, "hrvq");
    add(&mut c, "decoders_only = true");
    let e = SoulnetVqTask::from_config(&c, dir.path()).unwrap_err();
    assert!(e.contains("init_from"), "{e}");
    let mut c = config(&dir.path().join("x"), &hol, "rvq");
    add(&mut c, &format!("init_from = \"{}\"", base.display()));
    let e = dancegen_train::tasks::train_config(&c, &dir.path().join("x/config.toml"), &quiet())
        .unwrap_err()
        .to_string();
    assert!(e.contains("architecture") && e.contains("base"), "{e}");
    let mut c = config(&dir.path().join("x"), &hol, "hrvq");
    add(&mut c, "init_from = \"no-such-run\"\ndecoders_only = true");
    let e = SoulnetVqTask::from_config(&c, &dir.path().join("config.toml")).unwrap_err();
    assert!(e.contains("no-such-run"), "{e}");
}
