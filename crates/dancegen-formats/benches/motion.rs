//! Throughput benchmarks for dancegen-formats' readers and dancegen-motion's FK (no criterion; `harness = false`).
//!
//! Run: `cargo bench -p dancegen-formats --bench motion`
//!
//! Environment overrides: `DANCEGEN_BENCH_DATA` (default `/work/shared/data`),
//! `DANCEGEN_BENCH_REPS` (default 5). Each case prints the median (and min/max) of the
//! repetitions. Cases whose input files are missing are skipped with a note.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use dancegen_formats::aistpp::load_motion;
use dancegen_formats::bvh::{BvhReadOptions, BvhWriteOptions, parse_bvh_bytes, write_bvh};
use dancegen_formats::pickle;
use dancegen_motion::fk::{LocalRotations, forward_kinematics};
use dancegen_motion::skeleton::Skeleton;

/// One hour at 30 fps.
const FK_FRAMES: usize = 108_000;
const SMPL_JOINTS: usize = 24;

fn data_root() -> PathBuf {
    std::env::var_os("DANCEGEN_BENCH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/work/shared/data"))
}

fn reps() -> usize {
    std::env::var("DANCEGEN_BENCH_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|&n| n > 0)
        .unwrap_or(5)
}

/// Runs `f` once as warm-up, then `reps` times; returns sorted durations.
fn measure<R>(reps: usize, mut f: impl FnMut() -> R) -> Vec<Duration> {
    black_box(f());
    let mut times: Vec<Duration> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed()
        })
        .collect();
    times.sort();
    times
}

fn median(t: &[Duration]) -> f64 {
    let n = t.len();
    if n % 2 == 1 {
        t[n / 2].as_secs_f64()
    } else {
        (t[n / 2 - 1].as_secs_f64() + t[n / 2].as_secs_f64()) / 2.0
    }
}

/// Prints one result line: median time plus throughputs computed from the median.
fn report(name: &str, times: &[Duration], units: &[(&str, f64)]) {
    let med = median(times);
    let mut line = format!(
        "{name:<44} median {:>9.2} ms  (min {:.2}, max {:.2}, n={})",
        med * 1e3,
        times[0].as_secs_f64() * 1e3,
        times[times.len() - 1].as_secs_f64() * 1e3,
        times.len()
    );
    for (unit, amount) in units {
        line.push_str(&format!("  {:>12.3e} {unit}", amount / med));
    }
    println!("{line}");
}

/// Deterministic small perturbation in [-amp, amp] (splitmix64-based; no rand dependency).
fn noise(seed: u64, amp: f32) -> f32 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    ((z >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * amp
}

/// 108,000 frames of SMPL poses/translation made by repeating the real AIST++ clip, with a
/// per-repetition perturbation (±0.05 rad per pose value, ±1 cm on the root) so that no two
/// repetitions are bit-identical.
fn fk_input(root: &Path) -> Option<(Vec<f32>, Vec<f32>, usize)> {
    let path = root.join("aistpp/motions/gJS_sFM_cAll_d02_mJS4_ch09.pkl");
    let m = match load_motion(&path) {
        Ok(m) => m,
        Err(e) => {
            println!("skipping FK benchmark: {e}");
            return None;
        }
    };
    let src_frames = m.frames();
    let trans_m = m.trans_metres();
    let mut poses = Vec::with_capacity(FK_FRAMES * SMPL_JOINTS * 3);
    let mut trans = Vec::with_capacity(FK_FRAMES * 3);
    for f in 0..FK_FRAMES {
        let s = f % src_frames;
        let rep = (f / src_frames) as u64;
        let p = &m.poses[s * 72..(s + 1) * 72];
        poses.extend(
            p.iter()
                .enumerate()
                .map(|(i, &v)| v + noise(rep * 72 + i as u64, 0.05)),
        );
        let t = &trans_m[s * 3..(s + 1) * 3];
        trans.extend(
            t.iter()
                .enumerate()
                .map(|(i, &v)| v + noise(1 << 40 | (rep * 3 + i as u64), 0.01)),
        );
    }
    Some((poses, trans, src_frames))
}

fn bench_fk(root: &Path, reps: usize) {
    println!(
        "\n== Forward kinematics: SMPL-24, {FK_FRAMES} frames (1 h @ 30 fps), f32 axis-angle =="
    );
    let Some((poses, trans, src_frames)) = fk_input(root) else {
        return;
    };
    println!("(source clip: {src_frames} frames, repeated and perturbed)");
    let skel = Skeleton::smpl24();
    let frames = FK_FRAMES as f64;
    let joints = (FK_FRAMES * SMPL_JOINTS) as f64;
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        for world in [false, true] {
            let times = pool.install(|| {
                measure(reps, || {
                    forward_kinematics(&skel, LocalRotations::AxisAngle(&poses), &trans, world)
                        .expect("fk")
                })
            });
            let name = format!(
                "fk {} threads={threads}",
                if world {
                    "positions+world_rot"
                } else {
                    "positions"
                }
            );
            report(&name, &times, &[("frames/s", frames), ("joints/s", joints)]);
        }
    }
}

fn files_with_ext(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == ext))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn bench_bvh(root: &Path, reps: usize) {
    let dir = root.join("cmu-salsa");
    let files: Vec<Vec<u8>> = files_with_ext(&dir, "bvh")
        .iter()
        .map(|p| std::fs::read(p).expect("read bvh"))
        .collect();
    println!("\n== BVH: {} files from {} ==", files.len(), dir.display());
    if files.is_empty() {
        println!("skipping: no .bvh files");
        return;
    }
    let opts = BvhReadOptions::default();
    let bytes: usize = files.iter().map(Vec::len).sum();
    let parsed: Vec<_> = files
        .iter()
        .map(|b| parse_bvh_bytes(b, &opts).expect("parse bvh"))
        .collect();
    let frames: usize = parsed.iter().map(|b| b.frames).sum();
    let values: usize = parsed.iter().map(|b| b.data.len()).sum();
    println!(
        "({:.1} MB, {frames} frames, {values} channel values)",
        bytes as f64 / 1e6
    );
    let times = measure(reps, || {
        files
            .iter()
            .map(|b| parse_bvh_bytes(b, &opts).expect("parse").frames)
            .sum::<usize>()
    });
    report(
        "bvh parse (all files, 1 thread)",
        &times,
        &[("MB/s", bytes as f64 / 1e6), ("frames/s", frames as f64)],
    );
    for (label, wopts) in [
        (
            "bvh write precision=6 (default)",
            BvhWriteOptions::default(),
        ),
        (
            "bvh write precision=None (lossless)",
            BvhWriteOptions { precision: None },
        ),
    ] {
        let out_bytes: usize = parsed
            .iter()
            .map(|b| write_bvh(b, &wopts).expect("write").len())
            .sum();
        let times = measure(reps, || {
            parsed
                .iter()
                .map(|b| write_bvh(b, &wopts).expect("write").len())
                .sum::<usize>()
        });
        report(
            label,
            &times,
            &[
                ("MB/s out", out_bytes as f64 / 1e6),
                ("frames/s", frames as f64),
            ],
        );
    }
}

fn bench_pickle(root: &Path, reps: usize) {
    println!("\n== Pickle (AIST++) ==");
    for sub in ["aistpp/motions", "aistpp/keypoints3d"] {
        let files: Vec<Vec<u8>> = files_with_ext(&root.join(sub), "pkl")
            .iter()
            .map(|p| std::fs::read(p).expect("read pkl"))
            .collect();
        if files.is_empty() {
            println!("skipping {sub}: no .pkl files");
            continue;
        }
        let bytes: usize = files.iter().map(Vec::len).sum();
        // Small inputs: repeat the whole set so one repetition takes a measurable time.
        let inner = (50_000_000 / bytes.max(1)).clamp(1, 200);
        let times = measure(reps, || {
            let mut n = 0usize;
            for _ in 0..inner {
                for b in &files {
                    n += matches!(
                        pickle::parse(b).expect("parse pkl"),
                        pickle::PickleValue::Dict(_)
                    ) as usize;
                }
            }
            n
        });
        report(
            &format!("pickle parse {sub} ({} files x{inner})", files.len()),
            &times,
            &[
                ("MB/s", (bytes * inner) as f64 / 1e6),
                ("files/s", (files.len() * inner) as f64),
            ],
        );
    }
}

fn main() {
    // `cargo bench` passes `--bench`; a filter argument selects sections (fk, bvh, pickle).
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let run = |s: &str| filter.is_empty() || filter.iter().any(|f| s.contains(f.as_str()));
    let root = data_root();
    let reps = reps();
    println!(
        "dancegen-formats benchmarks: data {}, {reps} repetitions (median reported), {} CPUs",
        root.display(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    if run("fk") {
        bench_fk(&root, reps);
    }
    if run("bvh") {
        bench_bvh(&root, reps);
    }
    if run("pickle") {
        bench_pickle(&root, reps);
    }
}
