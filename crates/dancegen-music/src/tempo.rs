//! Autocorrelation tempogram and global tempo estimation (librosa 0.11
//! `feature.tempogram` / `feature.tempo`).
//!
//! The tempogram is returned frame-major (`[frame][lag]`), the transpose of librosa's
//! `(win_length, frames)`. Values are float64 in librosa; [`tempogram`] stores them as f32 (the
//! feature pipelines use f32), [`tempo`] works on the f64 values.
//!
//! Numerical notes: librosa autocorrelates with numpy's pocketfft and this module with realfft
//! (same zero-padded length `next_fast_len(2·win − 1)`), so tempogram values agree to a few ULP,
//! not bit for bit. The tempo is an argmax over a quantised BPM grid, `60·sr/(hop·lag)`, computed
//! with the same floating-point expression as librosa, so it is bit-identical.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex64;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};

use crate::stft::{FrameMatrix, hann_periodic};

/// librosa's default tempogram window (`win_length=384` frames), e.g. for TCDiff's features.
pub const TEMPOGRAM_WIN_LENGTH: usize = 384;

/// Sample rate of `librosa.load(path)` without `sr=` — the rate EDGE/Lodge estimate the
/// fallback start BPM at.
pub const FALLBACK_SR: u32 = 22050;

/// Start BPM of `librosa.feature.tempo` when none is given.
pub const DEFAULT_START_BPM: f64 = 120.0;

/// Parameters of [`tempo_with`] (librosa `feature.tempo` keyword arguments). Aggregation over
/// time is always `np.mean` (librosa's default, the only one the dance pipelines use).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TempoOptions {
    /// Centre of the log-normal tempo prior, BPM (> 0).
    pub start_bpm: f64,
    /// Width of the prior in octaves.
    pub std_bpm: f64,
    /// Autocorrelation window in seconds; `win_length = int(ac_size·sr) // hop` frames.
    pub ac_size: f64,
    /// Tempi at or above this are excluded (`None`: no limit).
    pub max_tempo: Option<f64>,
}

impl Default for TempoOptions {
    fn default() -> Self {
        Self {
            start_bpm: DEFAULT_START_BPM,
            std_bpm: 1.0,
            ac_size: 8.0,
            max_tempo: Some(320.0),
        }
    }
}

/// `scipy.fft.next_fast_len(n, real=True)`: the smallest 5-smooth number `>= n`.
pub fn next_fast_len(n: usize) -> usize {
    if n <= 1 {
        return 1;
    }
    let mut m = n;
    loop {
        let mut r = m;
        for p in [2, 3, 5] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

/// `librosa.tempo_frequencies(n_bins, hop_length=hop, sr=sr)`: BPM of each autocorrelation lag,
/// `inf` for lag 0.
pub fn tempo_frequencies(n_bins: usize, sr: f64, hop: usize) -> Vec<f64> {
    (0..n_bins)
        .map(|k| {
            if k == 0 {
                f64::INFINITY
            } else {
                60.0 * sr / (hop as f64 * k as f64)
            }
        })
        .collect()
}

/// `librosa.time_to_frames(seconds, sr, hop)`: `int(seconds·sr) // hop` (truncation, then floor).
pub fn time_to_frames(seconds: f64, sr: f64, hop: usize) -> i64 {
    let samples = (seconds * sr) as i64;
    samples.div_euclid(hop as i64)
}

/// The envelope padded by `win/2` on both sides with numpy's `linear_ramp` to 0 (float32; the
/// ramp is computed in float64 as `i·(edge/width)` and rounded, as `np.linspace` does).
fn pad_linear_ramp(env: &[f32], win: usize) -> Vec<f32> {
    let pad = win / 2;
    let n = env.len();
    let mut out = vec![0f32; n + 2 * pad];
    if n == 0 {
        return out;
    }
    let ramp = |edge: f32, i: usize| (i as f64 * (edge as f64 / pad as f64)) as f32;
    for i in 0..pad {
        out[i] = ramp(env[0], i);
        // The right ramp is reversed: the value next to the signal is ramp[pad − 1].
        out[n + 2 * pad - 1 - i] = ramp(env[n - 1], i);
    }
    out[pad..pad + n].copy_from_slice(env);
    out
}

/// Per-frame autocorrelation with reusable FFT buffers.
struct Autocorr {
    win: usize,
    n_pad: usize,
    window: Vec<f64>,
    fwd: Arc<dyn RealToComplex<f64>>,
    inv: Arc<dyn ComplexToReal<f64>>,
}

struct AutocorrBufs {
    time: Vec<f64>,
    spec: Vec<Complex64>,
    scratch_fwd: Vec<Complex64>,
    scratch_inv: Vec<Complex64>,
}

impl Autocorr {
    fn new(win: usize) -> Self {
        let n_pad = next_fast_len(2 * win - 1);
        let mut planner = RealFftPlanner::<f64>::new();
        Self {
            win,
            n_pad,
            window: hann_periodic(win),
            fwd: planner.plan_fft_forward(n_pad),
            inv: planner.plan_fft_inverse(n_pad),
        }
    }

    fn bufs(&self) -> AutocorrBufs {
        AutocorrBufs {
            time: self.fwd.make_input_vec(),
            spec: self.fwd.make_output_vec(),
            scratch_fwd: self.fwd.make_scratch_vec(),
            scratch_inv: self.inv.make_scratch_vec(),
        }
    }

    /// Column `t` of the tempogram: autocorrelation of the windowed frame `padded[t..t+win]`
    /// (`irfft(|rfft(x, n_pad)|², n_pad)[:win]`), divided by its maximum absolute value unless
    /// that is below the smallest normal f64 (`util.normalize(norm=inf)`).
    fn column(&self, padded: &[f32], t: usize, b: &mut AutocorrBufs, out: &mut [f64]) {
        let frame = &padded[t..t + self.win];
        for (x, (&v, &w)) in b.time.iter_mut().zip(frame.iter().zip(&self.window)) {
            *x = v as f64 * w;
        }
        b.time[self.win..].fill(0.0);
        self.fwd
            .process_with_scratch(&mut b.time, &mut b.spec, &mut b.scratch_fwd)
            .expect("buffer sizes come from the plan");
        for c in b.spec.iter_mut() {
            *c = Complex64::new(c.re * c.re + c.im * c.im, 0.0);
        }
        self.inv
            .process_with_scratch(&mut b.spec, &mut b.time, &mut b.scratch_inv)
            .expect("power spectrum is real, so the inverse accepts it");
        let scale = 1.0 / self.n_pad as f64;
        let mut max = 0f64;
        for (o, &v) in out.iter_mut().zip(&b.time[..self.win]) {
            *o = v * scale;
            max = max.max(o.abs());
        }
        if max >= f64::MIN_POSITIVE {
            for o in out.iter_mut() {
                *o /= max;
            }
        }
    }
}

const FRAMES_PER_TASK: usize = 256;

/// Calls `f(first_frame, rows)` for consecutive blocks of tempogram columns in parallel;
/// `rows` is frame-major (`len = frames_in_block · win`).
fn tempogram_blocks<R: Send>(
    env: &[f32],
    win: usize,
    f: impl Fn(usize, &[f64]) -> R + Sync,
) -> Vec<R> {
    assert!(win >= 1, "win_length must be a positive integer");
    let n = env.len();
    let padded = pad_linear_ramp(env, win);
    let ac = Autocorr::new(win);
    (0..n.div_ceil(FRAMES_PER_TASK))
        .into_par_iter()
        .map(|blk| {
            let start = blk * FRAMES_PER_TASK;
            let end = (start + FRAMES_PER_TASK).min(n);
            let mut bufs = ac.bufs();
            let mut rows = vec![0f64; (end - start) * win];
            for (t, row) in (start..end).zip(rows.chunks_exact_mut(win)) {
                ac.column(&padded, t, &mut bufs, row);
            }
            f(start, &rows)
        })
        .collect()
}

/// `librosa.feature.tempogram(onset_envelope=env, win_length=win, center=True, window='hann',
/// norm=inf)` as float64, frame-major: `env.len()` rows of `win` lags. Row `t` is the
/// autocorrelation of the Hann-windowed envelope segment centred on frame `t` (the envelope
/// padded by `win/2` linear ramps to 0), normalised so its largest value (lag 0) is 1;
/// all-zero segments stay all-zero. `sr` and `hop` do not enter the computation.
pub fn tempogram_f64(env: &[f32], win: usize) -> Vec<f64> {
    tempogram_blocks(env, win, |_, rows| rows.to_vec()).concat()
}

/// [`tempogram_f64`] as an f32 [`FrameMatrix`] (frames × `win`). Use
/// [`TEMPOGRAM_WIN_LENGTH`] for librosa's default window.
pub fn tempogram(env: &[f32], win: usize) -> FrameMatrix {
    FrameMatrix {
        rows: env.len(),
        cols: win,
        data: tempogram_f64(env, win)
            .into_iter()
            .map(|v| v as f32)
            .collect(),
    }
}

/// Mean of the tempogram over time (`np.mean(tg, axis=-1)`), one value per lag, without
/// materialising the whole tempogram. An empty envelope gives all zeros.
pub fn mean_tempogram(env: &[f32], win: usize) -> Vec<f64> {
    let partial = tempogram_blocks(env, win, |_, rows| {
        let mut acc = vec![0f64; win];
        for row in rows.chunks_exact(win) {
            for (a, &v) in acc.iter_mut().zip(row) {
                *a += v;
            }
        }
        acc
    });
    let mut mean = vec![0f64; win];
    for p in &partial {
        for (m, &v) in mean.iter_mut().zip(p) {
            *m += v;
        }
    }
    if !env.is_empty() {
        for m in &mut mean {
            *m /= env.len() as f64;
        }
    }
    mean
}

/// The tempo choice of `librosa.feature.tempo` from an aggregated tempogram `tg` (one value per
/// lag, `tg.len() = win_length`): `argmax(log1p(1e6·tg) + logprior)` over the BPM grid
/// [`tempo_frequencies`], with `logprior = −½((log2 bpm − log2 start_bpm)/std_bpm)²` and every
/// lag before the first BPM below `max_tempo` excluded. The first maximum wins.
pub fn tempo_from_tempogram(tg: &[f64], sr: f64, hop: usize, opts: &TempoOptions) -> f64 {
    assert!(opts.start_bpm > 0.0, "start_bpm must be strictly positive");
    let bpms = tempo_frequencies(tg.len(), sr, hop);
    let log_start = opts.start_bpm.log2();
    let max_idx = match opts.max_tempo {
        // np.argmax of an all-false mask is 0: nothing is excluded.
        Some(max) => bpms.iter().position(|&b| b < max).unwrap_or(0),
        None => 0,
    };
    let mut best = 0usize;
    let mut best_score = f64::NAN;
    for (k, (&v, &bpm)) in tg.iter().zip(&bpms).enumerate() {
        let prior = if k < max_idx {
            f64::NEG_INFINITY
        } else {
            let z = (bpm.log2() - log_start) / opts.std_bpm;
            -0.5 * (z * z)
        };
        let score = (1e6 * v).ln_1p() + prior;
        // np.argmax: first maximum; NaN compares as the maximum.
        if k == 0 || score > best_score || (score.is_nan() && !best_score.is_nan()) {
            best = k;
            best_score = score;
        }
    }
    bpms.get(best).copied().unwrap_or(f64::INFINITY)
}

/// Autocorrelation window (frames) `feature.tempo` uses: `time_to_frames(ac_size, sr, hop)`,
/// e.g. 240 at 30 fps, 480 at 60 fps, 344 at 22050 Hz.
pub fn tempo_win_length(sr: f64, hop: usize, ac_size: f64) -> usize {
    let w = time_to_frames(ac_size, sr, hop);
    assert!(
        w >= 1,
        "win_length must be a positive integer (ac_size·sr < hop)"
    );
    w as usize
}

/// `librosa.feature.tempo(onset_envelope=env, sr=sr, hop_length=hop, start_bpm=start_bpm)`
/// with the other defaults (std_bpm 1, ac_size 8 s, max_tempo 320, mean aggregation).
///
/// As in librosa, an all-zero envelope has an all-zero tempogram, so the prior alone decides:
/// the grid tempo closest (in log2) to `start_bpm`, e.g. 117.45 at 22050 Hz for 120 — not 0
/// ([`crate::beat::beat_track`] is the one that returns 0 for silence).
pub fn tempo(env: &[f32], sr: f64, hop: usize, start_bpm: f64) -> f64 {
    tempo_with(
        env,
        sr,
        hop,
        &TempoOptions {
            start_bpm,
            ..TempoOptions::default()
        },
    )
}

/// [`tempo`] with every option.
pub fn tempo_with(env: &[f32], sr: f64, hop: usize, opts: &TempoOptions) -> f64 {
    let win = tempo_win_length(sr, hop, opts.ac_size);
    tempo_from_tempogram(&mean_tempogram(env, win), sr, hop, opts)
}

/// EDGE/Lodge start-BPM fallback for music without an AIST++ id:
/// `librosa.beat.tempo(y=librosa.load(path)[0])[0]`, i.e. [`tempo`] of the onset
/// envelope of the **22050 Hz** load (default `onset_strength`, hop 512) with start BPM 120.
///
/// Compute `env22050` with the crate's pipeline at [`FALLBACK_SR`]: `mel::mel_power(y, 22050,
/// 512)` → `mel::power_to_db_in_place(Some(80))` → `onset::onset_strength_from_mel_db(2048,
/// 512)`. A silent file gives 117.45 (the prior's peak), like librosa.
pub fn tempo_fallback_from_env22050(env22050: &[f32]) -> f64 {
    tempo(env22050, FALLBACK_SR as f64, crate::HOP, DEFAULT_START_BPM)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_len_is_5_smooth() {
        assert_eq!(next_fast_len(479), 480);
        assert_eq!(next_fast_len(687), 720);
        assert_eq!(next_fast_len(767), 768);
        assert_eq!(next_fast_len(959), 960);
    }

    #[test]
    fn window_lengths() {
        assert_eq!(tempo_win_length(15360.0, 512, 8.0), 240);
        assert_eq!(tempo_win_length(30720.0, 512, 8.0), 480);
        assert_eq!(tempo_win_length(22050.0, 512, 8.0), 344);
    }

    #[test]
    fn autocorr_matches_direct_sum() {
        let env: Vec<f32> = (0..50).map(|i| ((i * 7919) % 13) as f32 * 0.1).collect();
        let win = 16;
        let tg = tempogram_f64(&env, win);
        let padded = pad_linear_ramp(&env, win);
        let w = hann_periodic(win);
        for t in [0, 10, 49] {
            let x: Vec<f64> = (0..win).map(|i| padded[t + i] as f64 * w[i]).collect();
            let ac: Vec<f64> = (0..win)
                .map(|k| (0..win - k).map(|i| x[i] * x[i + k]).sum())
                .collect();
            let m = ac.iter().fold(0f64, |a, &v| a.max(v.abs()));
            for k in 0..win {
                assert!((tg[t * win + k] - ac[k] / m).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn silence_tempo_is_prior_peak() {
        let t = tempo(&vec![0.0; 500], 22050.0, 512, 120.0);
        assert_eq!(t, 60.0 * 22050.0 / (512.0 * 22.0)); // 117.45…
    }
}
