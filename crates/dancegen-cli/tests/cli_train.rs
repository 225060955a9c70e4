//! The `train` command contract: a config file starts a run directory with checkpoints, a log,
//! a loss curve and the final model; `--stop-at` interrupts, `--resume` continues; bad input
//! names the file and the problem.

mod common;

use std::path::Path;

use common::*;

/// A tiny FSQ autoencoder on one real AIST++ sequence, a few steps; the model keys left out
/// take the model's defaults.
fn tiny(run: &Path, steps: u64) -> String {
    let motion = shared().join("data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl");
    format!(
        r#"[run]
dir = "{run}"
seed = 1
steps = {steps}
checkpoint_every = 3
log_every = 1

[data]
paths = ["{motion}"]
representation = "lodge139"
window = 16
stride = 16
batch_size = 2

[model]
kind = "motion_autoencoder"

[model.codec]
input_dim = 139
output_dim = 139
width = 16
depth = 1
down_t = 1
code_dim = 3

[model.quantizer]
kind = "fsq"
levels = [5, 5, 5]

[optimizer]
kind = "adamw"
lr = 1e-3
grad_clip_norm = 1.0

[schedule]
warmup_steps = 2
decay = "linear"
"#,
        run = run.display(),
        motion = motion.display()
    )
}

#[test]
fn train_stop_and_resume_write_the_run_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let cfg = tmp.path().join("tiny.toml");
    std::fs::write(&cfg, tiny(&run, 5)).unwrap();

    let o = dancegen(&["train", cfg.to_str().unwrap(), "--stop-at", "3"]);
    ok(&o);
    let err = stderr(&o);
    // Plain log lines (stderr is not a terminal here, so the bar is hidden).
    assert!(
        err.contains("step 1/5 loss") && err.contains("steps/s"),
        "{err}"
    );
    assert!(err.contains("--resume"), "{err}");
    assert!(run.join("checkpoints/step_3/optimizer.bpk").is_file());
    assert!(!run.join("model.safetensors").exists());

    // A second start in the same directory is refused.
    let o = dancegen(&["train", cfg.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("already holds a run"), "{}", stderr(&o));

    let o = dancegen(&["-q", "train", "--resume", run.to_str().unwrap()]);
    ok(&o);
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    for f in [
        "config.toml",
        "model.safetensors",
        "model.toml",
        "normalizer.json",
        "log.csv",
        "loss.png",
    ] {
        assert!(run.join(f).is_file(), "{f}");
    }
    let log = std::fs::read_to_string(run.join("log.csv")).unwrap();
    let mut lines = log.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,loss,lr,grad_norm,steps_per_s,recon,velocity,commit"
    );
    assert_eq!(lines.count(), 5);
    let model = std::fs::read_to_string(run.join("model.toml")).unwrap();
    assert!(
        model.contains("kind = \"motion_autoencoder\"") && model.contains("[config"),
        "{model}"
    );
    let png = std::fs::read(run.join("loss.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn bad_configs_and_run_directories_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("bad.toml");
    let run = tmp.path().join("run");

    std::fs::write(
        &cfg,
        tiny(&run, 2).replace("motion_autoencoder", "transformer_gan"),
    )
    .unwrap();
    let o = dancegen(&["train", cfg.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("bad.toml")
            && e.contains("\"transformer_gan\"")
            && e.contains("known: motion_autoencoder"),
        "{e}"
    );

    std::fs::write(&cfg, tiny(&run, 2).replace("batch_size", "batchsize")).unwrap();
    let e = stderr(&dancegen(&["train", cfg.to_str().unwrap()]));
    assert!(e.contains("bad.toml") && e.contains("batchsize"), "{e}");

    std::fs::write(
        &cfg,
        tiny(&run, 2).replace("input_dim = 139", "input_dim = 151"),
    )
    .unwrap();
    let e = stderr(&dancegen(&["train", cfg.to_str().unwrap()]));
    assert!(e.contains("bad.toml") && e.contains("139 dims"), "{e}");

    let e = stderr(&dancegen(&[
        "train",
        "--resume",
        tmp.path().to_str().unwrap(),
    ]));
    assert!(e.contains("not a run directory"), "{e}");

    let o = dancegen(&["train"]);
    assert!(!o.status.success());
}
