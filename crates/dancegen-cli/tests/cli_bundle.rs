//! The whole solo model workflow through the CLI on tiny networks: `dataset build` → `train`
//! (VQ-VAE, GPT, PDDM) → `bundle` → `generate --model`. Checks what `bundle` promises: half
//! precision network weights, no training-only discriminator, and a model `generate` can use.

mod common;

use std::path::Path;

use common::*;

/// `(name, dtype)` of every tensor in a safetensors file (its JSON header).
fn tensor_dtypes(path: &Path) -> Vec<(String, String)> {
    let bytes = std::fs::read(path).unwrap();
    let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).unwrap();
    header
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, _)| k.as_str() != "__metadata__")
        .map(|(k, v)| (k.clone(), v["dtype"].as_str().unwrap().to_string()))
        .collect()
}

const RUN: &str = r#"
[run]
dir = "{dir}"
seed = 3
steps = 2
checkpoint_every = 2
log_every = 1
keep_checkpoints = 1
"#;

const TRAINING: &str = r#"
[optimizer]
kind = "adamw"
lr = 1e-3
weight_decay = 0.0

[schedule]
warmup_steps = 1
decay = "cosine"

[ema]
decay = 0.9
start = 1
"#;

#[test]
fn dataset_train_bundle_generate_with_tiny_networks() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let set = t.join("set");
    let song = shared().join("data/music/sectoid/metal_madness.ogg");
    let take = shared().join("data/cmu-salsa/60_01_scaled.bvh");
    ok(&dancegen(&[
        "dataset",
        "build",
        "-q",
        "--motion",
        take.to_str().unwrap(),
        "--music",
        song.to_str().unwrap(),
        "--genre",
        "salsa",
        "-o",
        set.to_str().unwrap(),
    ]));
    let run = |name: &str| t.join("runs").join(name);
    let data = |window: usize| {
        format!(
            "[data]\npaths = [\"{m}\"]\nmanifest = \"{s}/manifest.json\"\nrepresentation = \
             \"edge151\"\nfps = 30\nwindow = {window}\nstride = 16\nbatch_size = 2\nnormalizer = \
             \"mean_std\"\n\n[data.music]\ndir = \"{s}/music\"\ndims = 35\n",
            m = set.join("motion").display(),
            s = set.display(),
        )
    };
    let vq_model = r#"
[model]
kind = "lodgepp_vqvae"
recon = "l1"
velocity_weight = 0.2
commit_weight = 0.02

[model.codec]
input_dim = 42
output_dim = 42
width = 16
depth = 1
down_t = 2
stride_t = 2
dilation_growth_rate = 3
code_dim = 8

[model.quantizer]
kind = "vq"
nb_code = 16
code_dim = 8
mu = 0.99
"#;
    let gpt_model = format!(
        r#"
[model]
kind = "lodgepp_gpt"
vqvae = "{vq}"

[model.gpt]
d_model = 16
n_layers = 1
n_heads = 2
music_d = 12
music_layers = 1
music_heads = 2
window_tokens = 16
overlap_tokens = 4
dropout = 0.0
"#,
        vq = run("vq").display()
    );
    let pddm_model = r#"
[model]
kind = "lodgepp_pddm"
use_discriminator = true

[model.pddm]
d_model = 16
n_layers = 1
n_heads = 2
d_ff = 32
music_layers = 1
dropout = 0.0
foot_refine = true
window = 32

[model.discriminator]
d_model = 16
depth = 1
n_heads = 2
d_ff = 32
"#;
    // The VQ-VAE's data set needs no music; the window only sets the training crops.
    let vq_data = data(64).split("\n[data.music]").next().unwrap().replace(
        &format!("manifest = \"{}/manifest.json\"\n", set.display()),
        "",
    );
    for (name, data, model) in [
        ("vq", vq_data, vq_model.to_string()),
        ("gpt", data(64), gpt_model),
        ("pddm", data(32), pddm_model.to_string()),
    ] {
        let cfg = t.join(format!("{name}.toml"));
        let text =
            RUN.replace("{dir}", &run(name).display().to_string()) + &data + &model + TRAINING;
        std::fs::write(&cfg, text).unwrap();
        ok(&dancegen(&["train", "-q", cfg.to_str().unwrap()]));
    }
    let model = t.join("model");
    ok(&dancegen(&[
        "bundle",
        "-q",
        "--vqvae",
        run("vq").to_str().unwrap(),
        "--gpt",
        run("gpt").to_str().unwrap(),
        "--pddm",
        run("pddm").to_str().unwrap(),
        "-o",
        model.to_str().unwrap(),
    ]));

    // Half precision for the layers, f32 for the normaliser inside the PDDM; no
    // discriminator; the run's own file had one and was all f32.
    let shipped = tensor_dtypes(&model.join("pddm.safetensors"));
    let trained = tensor_dtypes(&run("pddm").join("model.safetensors"));
    assert!(trained.iter().any(|(k, _)| k.starts_with("discriminator")));
    assert!(trained.iter().all(|(_, d)| d == "F32"));
    assert!(
        shipped.iter().all(|(k, _)| !k.starts_with("discriminator")),
        "discriminator shipped"
    );
    let dtype = |key: &str| {
        shipped
            .iter()
            .find(|(k, _)| k.contains(key))
            .map(|(_, d)| d.clone())
            .unwrap_or_else(|| panic!("no tensor named like {key}: {shipped:?}"))
    };
    assert_eq!(dtype("denorm.scale"), "F32");
    assert!(
        shipped.iter().filter(|(_, d)| d == "F16").count() * 2 > shipped.len(),
        "most tensors in f16: {shipped:?}"
    );
    for f in ["vqvae.safetensors", "gpt.safetensors"] {
        assert!(
            tensor_dtypes(&model.join(f))
                .iter()
                .any(|(_, d)| d == "F16"),
            "{f}"
        );
    }

    // The bundle dances: 6 s of the song, full length, finite.
    let out = t.join("dance.npy");
    ok(&dancegen(&[
        "generate",
        "-q",
        song.to_str().unwrap(),
        "--end",
        "6",
        "--model",
        model.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]));
    let a = dancegen_io::read_npy(&out).unwrap();
    assert_eq!(a.shape, vec![180, 24, 3]);
    assert!(a.data.iter().all(|v| v.is_finite()));
}
