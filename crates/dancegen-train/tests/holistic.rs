//! The holistic part autoencoder (`[model] kind = "soulnet_vq"`) trains on a real AIST++ body
//! with hands and a face from `[data] holistic`; bad hands/face files are named in the error.

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
        let task = SoulnetVqTask::from_config(&c).unwrap();
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
        SoulnetVqTask::from_config(&config(&dir.path().join("x"), &hol, "vq"))
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
        SoulnetVqTask::from_config(&c)
            .unwrap_err()
            .contains("holistic")
    );
}
