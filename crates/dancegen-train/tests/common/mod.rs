//! Shared by the training tests: a small motion-autoencoder config on real AIST++ motion.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A real AIST++ sequence (576 frames at 60 fps → 288 at 30), `../shared/data/aistpp`.
pub fn aist_motion() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl")
}

/// A complete config for a tiny VQ autoencoder: every feature of the loop is on (Adan, global
/// clipping, warm-up + cosine, EMA, a VQ with running-state codebook).
pub fn tiny_config(run_dir: &Path, steps: u64, seed: u64) -> String {
    format!(
        r#"
[run]
dir = "{dir}"
seed = {seed}
steps = {steps}
checkpoint_every = 4
log_every = 2
keep_checkpoints = 0

[data]
paths = ["{motion}"]
representation = "lodge139"
window = 16
stride = 8
batch_size = 4
normalizer = "mean_std"

[model]
kind = "motion_autoencoder"
recon = "l1"
velocity_weight = 0.5
commit_weight = 0.02

[model.codec]
input_dim = 139
output_dim = 139
width = 24
depth = 1
down_t = 1
stride_t = 2
dilation_growth_rate = 3
code_dim = 8
encoder_reverse_dilation = true

[model.quantizer]
kind = "vq"
nb_code = 16
code_dim = 8
mu = 0.99
reset_dead_codes = true
shuffle_reset = true

[optimizer]
kind = "adan"
lr = 2e-3
weight_decay = 0.02
grad_clip_norm = 1.0

[schedule]
warmup_steps = 3
decay = "cosine"

[ema]
decay = 0.9
"#,
        dir = run_dir.display(),
        motion = aist_motion().display(),
    )
}
