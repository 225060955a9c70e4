//! Mamba layer (`dancegen_nn::ssm`) with the sequential and the chunked selective scan:
//! forward (inference device) and forward + backward (autodiff device), batch 2, 150 and 512
//! frames, d_model 64 and 128 (TCDiff++ sizes otherwise: d_state 16, d_conv 4, expand 2).
//! Why: the per-step loop's backward is O(T²) in Burn (`../shared/reference/rust-ml-stack.md`
//! §1), which is what the chunked scan exists to fix; this measures by how much.
//!
//! With `SSM_BENCH_PYTHON=/path/to/python` the same shapes are then timed in PyTorch
//! (`tools/parity/ssm.py --bench`, both scans) in the same run and the ratios printed.
//!
//! ```text
//! SSM_BENCH_PYTHON=/tmp/torchvenv/bin/python cargo bench -p dancegen-nn --bench ssm_scan
//! ```
//! `SSM_BENCH_ROUNDS` (default 3) sets the timed rounds per forward+backward measurement, five
//! times as many for the forward (median reported, after one warm-up).

use std::collections::BTreeMap;
use std::process::Command;
use std::time::Instant;

use dancegen_nn::burn::tensor::{Device, Distribution, Tensor};
use dancegen_nn::device;
use dancegen_nn::ssm::{Mamba, MambaConfig, Scan};

const BATCH: usize = 2;
const D_MODELS: [usize; 2] = [64, 128];
const FRAMES: [usize; 2] = [150, 512];

/// Forward rounds per forward+backward round.
const FORWARD_ROUNDS: usize = 5;

type Key = (usize, usize, &'static str, &'static str);

fn median_ms(rounds: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm-up
    let mut t: Vec<f64> = (0..rounds)
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn sync(y: Tensor<3>) {
    // Reading one value forces the (lazy) computation to finish.
    let _ = y.sum().into_scalar::<f32>();
}

fn bench_rust(rounds: usize) -> BTreeMap<Key, f64> {
    let mut out = BTreeMap::new();
    for d in D_MODELS {
        let infer: Device = device::inference();
        let train: Device = device::training();
        let m_inf: Mamba = MambaConfig::new(d).init(&infer);
        let m_tr: Mamba = MambaConfig::new(d).init(&train);
        for t in FRAMES {
            let x_inf = Tensor::<3>::random([BATCH, t, d], Distribution::Normal(0.0, 1.0), &infer);
            let x_tr = Tensor::<3>::random([BATCH, t, d], Distribution::Normal(0.0, 1.0), &train);
            for (scan, name) in [(Scan::Sequential, "sequential"), (Scan::Chunked, "chunked")] {
                // The forward is cheap and noisy on a shared machine: more rounds.
                let fwd = median_ms(FORWARD_ROUNDS * rounds, || {
                    sync(m_inf.forward_with(x_inf.clone(), scan))
                });
                let fb = median_ms(rounds, || {
                    let x = x_tr.clone().require_grad();
                    let loss = m_tr.forward_with(x.clone(), scan).square().mean();
                    let grads = loss.backward();
                    let _ = x.grad(&grads).unwrap().sum().into_scalar::<f32>();
                });
                println!(
                    "burn    d_model {d:3} T {t:3} {name:10}  forward {fwd:9.1} ms  \
                     forward+backward {fb:9.1} ms"
                );
                out.insert((d, t, name, "forward"), fwd);
                out.insert((d, t, name, "forward_backward"), fb);
            }
        }
    }
    out
}

fn bench_pytorch(python: &str, rounds: usize) -> BTreeMap<Key, f64> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tools/parity/ssm.py");
    let out = Command::new(python)
        .args([script, "--bench", "--rounds", &rounds.to_string()])
        .args(["--forward-rounds", &(FORWARD_ROUNDS * rounds).to_string()])
        .output()
        .unwrap_or_else(|e| panic!("{python} {script}: {e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut res = BTreeMap::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let (Some(d), Some(t), Some(scan), Some(what), Some(ms)) = (
            field(line, "d_model"),
            field(line, "frames"),
            field(line, "scan"),
            field(line, "what"),
            field(line, "median_ms"),
        ) else {
            continue;
        };
        let scan = if scan == "sequential" {
            "sequential"
        } else {
            "chunked"
        };
        let what = if what == "forward" {
            "forward"
        } else {
            "forward_backward"
        };
        println!("pytorch d_model {d:>3} T {t:>3} {scan:10}  {what:16} {ms:>9} ms");
        res.insert(
            (d.parse().unwrap(), t.parse().unwrap(), scan, what),
            ms.parse().unwrap(),
        );
    }
    res
}

/// The value of `"key": value` in one flat JSON line (the bench script's output).
fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let rest = &line[line.find(&format!("\"{key}\": "))? + key.len() + 4..];
    let end = rest.find([',', '}']).unwrap_or(rest.len());
    Some(rest[..end].trim().trim_matches('"'))
}

fn main() {
    let rounds = std::env::var("SSM_BENCH_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(3);
    let rust = bench_rust(rounds);
    println!();
    for d in D_MODELS {
        for t in FRAMES {
            for what in ["forward", "forward_backward"] {
                let s = rust[&(d, t, "sequential", what)];
                let c = rust[&(d, t, "chunked", what)];
                println!(
                    "burn chunked speed-up d_model {d:3} T {t:3} {what:16} {:6.1}x",
                    s / c
                );
            }
        }
    }
    let Ok(python) = std::env::var("SSM_BENCH_PYTHON") else {
        println!("\n(set SSM_BENCH_PYTHON to time PyTorch on the same shapes)");
        return;
    };
    println!();
    let torch = bench_pytorch(&python, rounds);
    println!("\nburn time / pytorch time (same scan, same shapes):");
    for (k, &ms) in &rust {
        if let Some(&p) = torch.get(k) {
            let (d, t, scan, what) = k;
            println!(
                "d_model {d:3} T {t:3} {scan:10} {what:16} burn {ms:9.1} ms  pytorch {p:9.1} ms  \
                 ratio {:5.2}",
                ms / p
            );
        }
    }
    // The layer as each framework would run it: Burn's chunked scan vs PyTorch's reference scan
    // (what TCDiff++ runs on CPU without the CUDA kernels).
    println!("\nburn chunked / pytorch sequential reference:");
    for d in D_MODELS {
        for t in FRAMES {
            for what in ["forward", "forward_backward"] {
                if let Some(&p) = torch.get(&(d, t, "sequential", what)) {
                    let ms = rust[&(d, t, "chunked", what)];
                    println!(
                        "d_model {d:3} T {t:3} {what:16} burn {ms:9.1} ms  pytorch {p:9.1} ms  \
                         ratio {:5.2}",
                        ms / p
                    );
                }
            }
        }
    }
}
