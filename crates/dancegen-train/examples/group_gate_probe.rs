//! Diagnostic (issue 43): the learned skip gates `g_k(t)` of a group bundle with `prediction =
//! "x0_skip"`, one per smoothing width `σ_k` of x_t (`crate::prediction::SkipGate`), for the
//! root rotation's six 6D channels and, for comparison, the first spine joint's and the left
//! knee's. A gate mix whose weights are all ≥ 0 smooths its input; one with weights of opposite
//! signs can sharpen it and overshoot where the input changes fast (docs/group-collapse.md §20,
//! §21). Printed per noise level: each channel's gates in `skip_smoothing` order and their sum.
//!
//!     cargo run --release -p dancegen-train --example group_gate_probe -- MODEL_DIR

use dancegen_nn::device;
use dancegen_nn::edge151::{DIMS, rot6d};
use dancegen_tcdiffpp::bundle::GroupModel;

/// Noise levels of EDGE's 1000-step schedule, high to low.
const LEVELS: [usize; 7] = [999, 750, 500, 250, 100, 10, 0];
/// Joints shown: root, spine 1 (SMPL 3), left knee (SMPL 4).
const JOINTS: [(&str, usize); 3] = [("root", 0), ("spine1", 3), ("l_knee", 4)];

fn main() {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: group_gate_probe MODEL_DIR");
        std::process::exit(2);
    };
    let dev = device::inference();
    let model = match GroupModel::load(std::path::Path::new(&dir), &dev) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("group_gate_probe: {e}");
            std::process::exit(1);
        }
    };
    let Some(gate) = model.net.skip_gate.as_ref() else {
        eprintln!(
            "group_gate_probe: {dir}: the model has no learned skip (prediction = \"x0_skip\")"
        );
        std::process::exit(1);
    };
    let sigmas = &model.config.model.denoiser.skip_smoothing;
    println!("smoothing widths (frames): {sigmas:?}");
    for t in LEVELS {
        let features = model.net.time.forward(&[t as f32], &dev);
        let g = gate
            .gate
            .forward(features)
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .expect("gates convert to f32");
        println!("t = {t}");
        for (name, j) in JOINTS {
            for k in 0..6 {
                let c = rot6d(j, k);
                let each: Vec<f32> = (0..sigmas.len()).map(|i| g[i * DIMS + c]).collect();
                let shown: Vec<String> = each.iter().map(|v| format!("{v:+.3}")).collect();
                println!(
                    "  {name} 6D {k}: {}  sum {:+.3}",
                    shown.join(" "),
                    each.iter().sum::<f32>()
                );
            }
        }
    }
}
