//! Onset strength (spectral flux on the mel dB spectrogram) and librosa's onset peak picking.

use crate::stft::FrameMatrix;

/// `librosa.onset.onset_strength(S=mel_db)` with the defaults the dance pipelines use:
/// lag 1, no frequency max-filter, mean over bands, centred (`n_fft/(2·hop)` extra frames of
/// delay), truncated to the spectrogram's frame count.
///
/// `mel_db` is `power_to_db(mel power)`, frames × mels.
pub fn onset_strength_from_mel_db(mel_db: &FrameMatrix, n_fft: usize, hop: usize) -> Vec<f32> {
    const LAG: usize = 1;
    let t = mel_db.rows;
    let pad = LAG + n_fft / (2 * hop);
    let mut env = vec![0f32; t];
    for i in LAG..t {
        let out = i - LAG + pad;
        if out >= t {
            break;
        }
        let (cur, prev) = (mel_db.row(i), mel_db.row(i - LAG));
        let sum: f64 = cur
            .iter()
            .zip(prev)
            .map(|(&a, &b)| (a - b).max(0.0) as f64)
            .sum();
        env[out] = (sum / mel_db.cols as f64) as f32;
    }
    env
}

/// Parameters of `librosa.util.peak_pick` in frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeakPick {
    pub pre_max: usize,
    pub post_max: usize,
    pub pre_avg: usize,
    pub post_avg: usize,
    pub delta: f32,
    pub wait: usize,
}

impl PeakPick {
    /// The defaults `onset_detect` derives from the frame rate: windows of 30 ms / 100 ms and a
    /// 30 ms wait, computed as Python's `seconds * sr // hop` (floor of a float division),
    /// `delta = 0.07`. At 30 fps that is pre_max 0, post_max 1, pre_avg 3, post_avg 4, wait 0.
    pub fn onset_defaults(sr: f64, hop: usize) -> Self {
        let frames = |sec: f64| (sec * sr / hop as f64).floor() as usize;
        Self {
            pre_max: frames(0.03),
            post_max: frames(0.0) + 1,
            pre_avg: frames(0.10),
            post_avg: frames(0.10) + 1,
            wait: frames(0.03),
            delta: 0.07,
        }
    }
}

/// `librosa.util.peak_pick` (0.10+ numba kernel): frame n is a peak when it is the maximum of
/// `x[n-pre_max .. n+post_max]`, at least `delta` above the mean of `x[n-pre_avg .. n+post_avg]`
/// (windows clipped at the edges), and more than `wait` frames after the previous peak.
pub fn peak_pick(x: &[f32], p: &PeakPick) -> Vec<usize> {
    let n = x.len();
    let mut peaks = Vec::new();
    if n == 0 {
        return peaks;
    }
    let window_max = |lo: usize, hi: usize| x[lo..hi].iter().copied().fold(f32::MIN, f32::max);
    let window_mean = |lo: usize, hi: usize| {
        let s: f64 = x[lo..hi].iter().map(|&v| v as f64).sum();
        (s / (hi - lo) as f64) as f32
    };
    // Frame 0 uses the one-sided windows [0, post_max) and [0, post_avg).
    let first_max = x[0] == window_max(0, p.post_max.min(n));
    let first_avg = x[0] >= window_mean(0, p.post_avg.min(n)) + p.delta;
    let mut last_peak: Option<usize> = None;
    if first_max && first_avg {
        peaks.push(0);
        last_peak = Some(0);
    }
    for (i, &xi) in x.iter().enumerate().skip(1) {
        if last_peak.is_some_and(|lp| i <= lp + p.wait) {
            continue;
        }
        let lo_m = i.saturating_sub(p.pre_max);
        let hi_m = (i + p.post_max).min(n);
        if xi != window_max(lo_m, hi_m) {
            continue;
        }
        let lo_a = i.saturating_sub(p.pre_avg);
        let hi_a = (i + p.post_avg).min(n);
        if xi >= window_mean(lo_a, hi_a) + p.delta {
            peaks.push(i);
            last_peak = Some(i);
        }
    }
    peaks
}

/// `librosa.onset.onset_detect(onset_envelope=env, sr, hop_length)`: min-max normalise the
/// envelope, then [`peak_pick`] with the frame-rate defaults. An all-zero envelope has no onsets.
pub fn onset_detect(env: &[f32], sr: f64, hop: usize) -> Vec<usize> {
    if env.is_empty() || !env.iter().all(|v| v.is_finite()) {
        return Vec::new();
    }
    let min = env.iter().copied().fold(f32::INFINITY, f32::min);
    let max = env.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let denom = max - min + f32::MIN_POSITIVE;
    let norm: Vec<f32> = env.iter().map(|&v| (v - min) / denom).collect();
    if !norm.iter().any(|&v| v != 0.0) {
        return Vec::new();
    }
    peak_pick(&norm, &PeakPick::onset_defaults(sr, hop))
}
