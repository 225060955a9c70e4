//! Tuning, CQT, chroma_cqt, chroma_cens and chroma_stft against librosa 0.11.
//!
//! `_stages` cases feed the exact 2 s input `y.npy` (no decoding or resampling), so they test the
//! port itself; the full `ref/` clips go through `load` (decode + soxr) first, as the dance
//! pipelines do. Every comparison prints its measured error.

mod common;

use common::*;
use dancegen_music::chroma::{
    cens_from_chroma, chroma_cens, chroma_cens_with_tuning, chroma_from_cqt, chroma_stft,
    chroma_stft_with_tuning,
};
use dancegen_music::cqt::{CqtParams, CqtPlan, cqt_magnitude};
use dancegen_music::stft::Stft;
use dancegen_music::tuning::{estimate_tuning, piptrack_spectrogram};
use dancegen_music::{FrameMatrix, HOP, load};

/// A librosa `(features, frames)` array → frame-major.
fn ref_matrix(path: &std::path::Path) -> FrameMatrix {
    let (data, shape) = read_npy(path);
    let (f, t) = (shape[0], shape[1]);
    let mut m = FrameMatrix::zeros(t, f);
    for i in 0..f {
        for j in 0..t {
            m.data[j * f + i] = data[i * t + j] as f32;
        }
    }
    m
}

/// `tuning_bins_per_octave_36` from `meta.json` (compared bit for bit; the workspace builds
/// serde_json with `float_roundtrip`, so the parse is correctly rounded).
fn meta_tuning(dir: &std::path::Path) -> f64 {
    read_meta(dir)["tuning_bins_per_octave_36"]
        .as_f64()
        .unwrap()
}

/// Sorted absolute differences (for percentiles).
fn abs_diffs(a: &FrameMatrix, b: &FrameMatrix) -> Vec<f32> {
    assert_eq!((a.rows, a.cols), (b.rows, b.cols), "shape mismatch");
    let mut d: Vec<f32> = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| (x - y).abs())
        .collect();
    d.sort_by(f32::total_cmp);
    d
}

fn percentile(sorted: &[f32], p: f64) -> f32 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

/// Frames where any chroma differs by more than `tol`.
fn frames_over(a: &FrameMatrix, b: &FrameMatrix, tol: f32) -> usize {
    (0..a.rows)
        .filter(|&t| {
            a.row(t)
                .iter()
                .zip(b.row(t))
                .any(|(x, y)| (x - y).abs() > tol)
        })
        .count()
}

#[test]
fn stages_tuning_cqt_chroma() {
    for (key, fps, dir) in stage_cases() {
        let sr = (fps as usize * HOP) as f64;
        let y = read_npy_f32(&dir.join("y.npy"));
        let want_tuning = meta_tuning(&dir);

        // Tuning is a histogram edge: it has to be the same edge, bit for bit.
        let tuning = estimate_tuning(&y, sr, 36);
        println!("{key} fps{fps}: tuning {tuning} (librosa {want_tuning})");
        assert_eq!(tuning, want_tuning, "{key} fps{fps}: tuning");

        // CQT magnitude with librosa's tuning.
        let cqt = cqt_magnitude(&y, sr, HOP, &CqtParams::chroma(want_tuning)).unwrap();
        let want_cqt = ref_matrix(&dir.join("cqt_mag.npy"));
        assert_eq!((cqt.rows, cqt.cols), (want_cqt.rows, want_cqt.cols));
        let peak = want_cqt.data.iter().cloned().fold(0.0, f32::max);
        let d = abs_diffs(&cqt, &want_cqt);
        let max_err = d[d.len() - 1];
        // Per-bin relative error where the bin is above 1e-4 of the peak (below that, librosa's
        // own float32 basis/FFT rounding noise dominates).
        let max_rel = cqt
            .data
            .iter()
            .zip(&want_cqt.data)
            .filter(|&(_, &w)| w > peak * 1e-4)
            .map(|(&g, &w)| ((g - w) / w).abs())
            .fold(0.0, f32::max);
        println!(
            "  cqt: max |err| {max_err:.3e} = {:.3e} of peak {peak:.3e}; max rel err (bins > 1e-4 \
             peak) {max_rel:.3e}",
            max_err / peak
        );
        // Both sides are float32 sums of a float32-rounded basis (ours built in float64, librosa's
        // FFT in float32) and float32 FFTs of different algorithms: ~1e-6 of the peak.
        assert!(max_err <= peak * 2e-5, "{key} fps{fps}: cqt err {max_err}");
        assert!(max_rel < 1e-3, "{key} fps{fps}: cqt rel err {max_rel}");

        // Folding alone (on librosa's CQT), then on ours.
        let want_raw = ref_matrix(&dir.join("chroma_cqt_raw.npy"));
        let raw_ref = chroma_from_cqt(&want_cqt, 36, 12, None).unwrap();
        let raw_peak = want_raw.data.iter().cloned().fold(0.0, f32::max);
        let fold_err = max_abs_diff(&raw_ref.data, &want_raw.data);
        let raw = chroma_from_cqt(&cqt, 36, 12, None).unwrap();
        let raw_err = max_abs_diff(&raw.data, &want_raw.data);
        println!(
            "  chroma_cqt raw: fold-only err {fold_err:.3e}, full err {raw_err:.3e} (peak \
             {raw_peak:.3e})"
        );
        // Folding is a 0/1 sum of 21 float32 values: float32 summation-order rounding only.
        assert!(
            fold_err <= raw_peak * 1e-6,
            "{key} fps{fps}: fold err {fold_err}"
        );
        // Inherits the CQT's error budget.
        assert!(
            raw_err <= raw_peak * 2e-5,
            "{key} fps{fps}: raw chroma err {raw_err}"
        );

        // CENS from librosa's own raw chroma isolates the post-processing.
        let want_cens = ref_matrix(&dir.join("chroma_cens.npy"));
        let post_err = max_abs_diff(&cens_from_chroma(&want_raw, Some(41)).data, &want_cens.data);
        // Whole pipeline from y (tuning estimated).
        let cens = chroma_cens(&y, sr, HOP, 12).unwrap();
        let cens_err = max_abs_diff(&cens.data, &want_cens.data);
        println!(
            "  chroma_cens: post-processing err {post_err:.3e}, full pipeline err {cens_err:.3e}"
        );
        // Quantised values are identical unless a value sits within float32 rounding of a
        // threshold; what is left is float32 rounding of the smoothing/L2 steps (~1e-7).
        assert!(post_err < 1e-6, "{key} fps{fps}: cens post err {post_err}");
        // Issue target for chroma_cens.
        assert!(
            cens_err < 1e-3,
            "{key} fps{fps}: chroma_cens err {cens_err}"
        );

        let want_stft = ref_matrix(&dir.join("chroma_stft.npy"));
        let cstft = chroma_stft(&y, sr, HOP);
        let stft_err = max_abs_diff(&cstft.data, &want_stft.data);
        println!("  chroma_stft err {stft_err:.3e}");
        // Max-normalised (values <= 1); float32 power spectra from different FFTs agree to ~1e-6
        // relative, so with the same 12-bin tuning edge the error is ~1e-6.
        const STFT_TOL: f32 = 1e-4;
        if stft_err >= STFT_TOL {
            // The only tolerated cause: the tuning estimate (on the *power* spectrogram, 12 bins)
            // depends on float32 ulps because several picked magnitudes tie with the median
            // threshold (identical clicks give identical peaks), so a different subset passes
            // `mag >= median`. Require that tie, and that some histogram edge near ours
            // reproduces librosa, i.e. everything but the tuning edge matches.
            let ties = median_ties(&y, sr);
            let ours = tuning_edge_index(&y, sr);
            let best = (-5..=5)
                .map(|k| {
                    let t = -0.5 + (ours + k) as f64 * 0.01;
                    let e = max_abs_diff(
                        &chroma_stft_with_tuning(&y, sr, HOP, Some(t)).data,
                        &want_stft.data,
                    );
                    (e, t)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .unwrap();
            println!(
                "  chroma_stft: {ties} picked magnitudes tie with the median; with tuning {:.2} \
                 (ours {:.2}) err {:.3e}",
                best.1,
                -0.5 + ours as f64 * 0.01,
                best.0
            );
            assert!(
                ties >= 2,
                "{key} fps{fps}: chroma_stft err {stft_err} without a tie"
            );
            assert!(
                best.0 < STFT_TOL,
                "{key} fps{fps}: chroma_stft err {} at best tuning",
                best.0
            );
        }
    }
}

/// How many picked peak magnitudes of `chroma_stft`'s tuning estimate lie within float32 FFT
/// noise (1e-6 relative) of the median threshold.
fn median_ties(y: &[f32], sr: f64) -> usize {
    let power = Stft::hann(2048, HOP).power(y);
    let mut mags: Vec<f32> = piptrack_spectrogram(&power, sr)
        .iter()
        .map(|p| p.mag)
        .collect();
    if mags.is_empty() {
        return 0;
    }
    mags.sort_by(f32::total_cmp);
    let n = mags.len();
    let med = if n % 2 == 1 {
        mags[n / 2]
    } else {
        (mags[n / 2 - 1] + mags[n / 2]) / 2.0
    };
    mags.iter()
        .filter(|&&m| (m - med).abs() <= med * 1e-6)
        .count()
}

/// Our 12-bin `chroma_stft` tuning as a histogram edge index (edge = -0.5 + 0.01 * index).
fn tuning_edge_index(y: &[f32], sr: f64) -> i64 {
    let power = Stft::hann(2048, HOP).power(y);
    let t = dancegen_music::tuning::estimate_tuning_from_spectrogram(&power, sr, 12);
    ((t + 0.5) / 0.01).round() as i64
}

#[test]
fn full_clips_chroma_cens() {
    let mut failures = Vec::new();
    for (key, fps, dir) in ref_cases() {
        let sr = fps * HOP as u32;
        let audio = load(&clip_for_key(&key), sr).unwrap();
        let y = &audio.samples;
        let want_tuning = meta_tuning(&dir);
        let tuning = estimate_tuning(y, sr as f64, 36);
        let want = ref_matrix(&dir.join("chroma_cens.npy"));
        let got = chroma_cens(y, sr as f64, HOP, 12).unwrap();
        assert_eq!(
            (got.rows, got.cols),
            (want.rows, want.cols),
            "{key} fps{fps}"
        );
        let d = abs_diffs(&got, &want);
        let (max, p99) = (d[d.len() - 1], percentile(&d, 0.99));
        let n_bad = frames_over(&got, &want, 1e-3);
        // Same comparison with librosa's tuning, to separate a tuning-edge flip from the rest.
        let with_ref_tuning = if tuning != want_tuning {
            let g = chroma_cens_with_tuning(y, sr as f64, HOP, 12, Some(want_tuning)).unwrap();
            format!(
                ", with librosa's tuning max {:.3e}",
                max_abs_diff(&g.data, &want.data)
            )
        } else {
            String::new()
        };
        let want_stft = ref_matrix(&dir.join("chroma_stft.npy"));
        let stft_err = max_abs_diff(&chroma_stft(y, sr as f64, HOP).data, &want_stft.data);
        println!(
            "{key:26} fps{fps}: tuning {tuning:+.2} (librosa {want_tuning:+.2}); chroma_cens max \
             {max:.3e} p99 {p99:.3e}, {n_bad}/{} frames > 1e-3{with_ref_tuning}; chroma_stft max \
             {stft_err:.3e}",
            got.rows
        );
        // Issue target 1e-3 for every clip, decoded OGG/MP3 included. Those could in principle
        // need more: symphonia and libsndfile/libvorbis/mpg123 decode slightly different
        // samples, and the fixtures README (§5, §7) shows such input differences can push a
        // chroma value across a CENS quantisation threshold, moving the ±20 frames around it by
        // 0.02–0.1. Measured here: no flip at all (max error 0 on every clip), so no allowance.
        let ok = max < 1e-3;
        if !ok {
            failures.push(format!("{key} fps{fps}: max {max:.3e} p99 {p99:.3e}"));
        }
    }
    assert!(failures.is_empty(), "chroma_cens mismatches: {failures:#?}");
}

/// CPU time of this process (all threads) in ns, from `/proc/self/task/*/schedstat` (Linux);
/// 0 elsewhere. Wall time on a shared 2-core machine is noisy, CPU time much less so.
fn cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    tasks
        .filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("schedstat")).ok())
        .filter_map(|t| t.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// Timing of chroma_cens on 60 s at 15360 Hz (run with `--ignored --nocapture`; the test
/// profile is optimised). Prints the median/min wall time and the min CPU time of 9 runs, and
/// the parts.
#[test]
#[ignore]
fn time_chroma_cens_60s() {
    let audio = load(&music_fixtures().join("clips/bench_60s.ogg"), 15360).unwrap();
    let y = &audio.samples;
    let sr = 15360.0;
    let mut wall = Vec::new();
    let mut cpu = [u64::MAX; 5];
    let plan = CqtPlan::new(sr, HOP, &CqtParams::chroma(0.31)).unwrap();
    let signals = plan.prepare(y).unwrap();
    let t0 = std::time::Instant::now();
    let _ = chroma_cens(y, sr, HOP, 12).unwrap();
    let first = t0.elapsed().as_secs_f64() * 1e3;
    for _ in 0..9 {
        let c0 = cpu_ns();
        let t0 = std::time::Instant::now();
        std::hint::black_box(chroma_cens(y, sr, HOP, 12).unwrap());
        wall.push(t0.elapsed().as_secs_f64() * 1e3);
        cpu[0] = cpu[0].min(cpu_ns() - c0);
        let c0 = cpu_ns();
        std::hint::black_box(estimate_tuning(y, sr, 36));
        cpu[1] = cpu[1].min(cpu_ns() - c0);
        let c0 = cpu_ns();
        std::hint::black_box(plan.prepare(y).unwrap());
        cpu[2] = cpu[2].min(cpu_ns() - c0);
        let c0 = cpu_ns();
        std::hint::black_box(CqtPlan::new(sr, HOP, &CqtParams::chroma(0.31)).unwrap());
        cpu[3] = cpu[3].min(cpu_ns() - c0);
        let c0 = cpu_ns();
        std::hint::black_box(plan.magnitude_prepared(&signals));
        cpu[4] = cpu[4].min(cpu_ns() - c0);
    }
    wall.sort_by(f64::total_cmp);
    let ms = |ns: u64| ns as f64 / 1e6;
    println!(
        "chroma_cens 60 s @ 15360 Hz, {} threads: first call {first:.1} ms (builds the filter \
         plan); then (plan cached) wall median {:.1} ms (min {:.1}), CPU {:.1} ms; CPU of the \
         parts: tuning {:.1}, soxr octave cascade {:.1}, filter plan {:.1}, CQT {:.1}",
        rayon::current_num_threads(),
        wall[wall.len() / 2],
        wall[0],
        ms(cpu[0]),
        ms(cpu[1]),
        ms(cpu[2]),
        ms(cpu[3]),
        ms(cpu[4]),
    );
    // The 60 fps rate (SR 30720): twice the samples and frames, and n_fft 1024 per octave.
    let audio = load(&music_fixtures().join("clips/bench_60s.ogg"), 30720).unwrap();
    let _ = chroma_cens(&audio.samples, 30720.0, HOP, 12).unwrap();
    let mut wall = Vec::new();
    for _ in 0..5 {
        let t0 = std::time::Instant::now();
        std::hint::black_box(chroma_cens(&audio.samples, 30720.0, HOP, 12).unwrap());
        wall.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    wall.sort_by(f64::total_cmp);
    println!(
        "chroma_cens 60 s @ 30720 Hz: wall median {:.1} ms (plan cached)",
        wall[2]
    );
}
