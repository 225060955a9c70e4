//! Tuning estimation: `librosa.pitch.piptrack` and `librosa.estimate_tuning` (librosa 0.11).
//!
//! Why it matters: `chroma_cens` (and `chroma_cqt` / `chroma_stft` with `tuning=None`) first
//! estimate the tuning deviation and shift the CQT's `fmin` (or the chroma filterbank) by it. The
//! estimate is a histogram edge (a multiple of 0.01 of a bin), so a port has to pick the same
//! bin; a one-bin difference moves every CQT filter by 1/3600 of an octave.
//!
//! What is matched exactly, step by step as librosa computes it:
//! - `|STFT|` with n_fft 2048, hop 512 (`n_fft / 4`), periodic Hann, centred zero padding;
//! - per frame, bins with `150 <= f < min(4000, sr/2)` (`f = i * (1 / (n_fft * (1 / sr)))`,
//!   numpy's `rfftfreq`) that are local maxima along frequency of `S * (S > 0.1 * max(S))`
//!   (`util.localmax`: first bin never, last bin if above its neighbour);
//! - parabolic interpolation and `np.gradient` with librosa's float32/float64 mix (numba kernel);
//! - keep peaks whose interpolated magnitude is `>=` the median of all picked magnitudes;
//! - `pitch_tuning`: residual `mod(bpo * log2(f / 27.5), 1)` in float32 folded to `[-0.5, 0.5)`,
//!   `np.histogram` with edges `linspace(-0.5, 0.5, 101)`, left edge of the fullest bin
//!   (first on ties), 0.0 if nothing was picked.
//!
//! Peaks are gathered per frame in parallel and never stored as dense `(bins, frames)` matrices.

use rayon::prelude::*;

use crate::stft::{FrameMatrix, Stft, n_frames};
use realfft::num_complex::Complex32;

/// `piptrack` defaults.
pub const PIPTRACK_FMIN: f64 = 150.0;
pub const PIPTRACK_FMAX: f64 = 4000.0;
pub const PIPTRACK_THRESHOLD: f32 = 0.1;
/// `estimate_tuning` analysis size (its `n_fft`; the hop is `n_fft / 4`).
pub const TUNING_N_FFT: usize = 2048;
/// `estimate_tuning` histogram resolution (fraction of a bin).
pub const TUNING_RESOLUTION: f64 = 0.01;

/// One spectral peak picked by [`piptrack_column`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PitchPeak {
    /// STFT frame.
    pub frame: usize,
    /// FFT bin of the local maximum.
    pub bin: usize,
    /// Interpolated frequency in Hz (float32, as librosa stores it).
    pub freq: f32,
    /// Interpolated magnitude `S + 0.5 * gradient * shift`.
    pub mag: f32,
}

/// `piptrack` on one spectrum column `s` (length `1 + n_fft/2`), appending its peaks to `out`.
///
/// `s` is whatever librosa's `S` is (a magnitude spectrum for `estimate_tuning(y=...)`, a power
/// spectrum inside `chroma_stft`). Reference: `ref_value = threshold * max(s)`.
#[allow(clippy::too_many_arguments)]
pub fn piptrack_column(
    s: &[f32],
    frame: usize,
    sr: f64,
    n_fft: usize,
    fmin: f64,
    fmax: f64,
    threshold: f32,
    out: &mut Vec<PitchPeak>,
) {
    let range = feasible_bins(s.len(), sr, n_fft, fmin, fmax);
    pick_peaks(s, max_f32(s), range, frame, sr, n_fft, threshold, out);
}

/// Bins `i` with `fmin <= f_i < min(fmax, sr/2)`, `f_i = i * (1 / (n_fft * (1 / sr)))` (numpy's
/// `rfftfreq`), as a range (the predicate is monotonic in `i`).
fn feasible_bins(n: usize, sr: f64, n_fft: usize, fmin: f64, fmax: f64) -> std::ops::Range<usize> {
    let fmin = fmin.max(0.0);
    let fmax = fmax.min(sr / 2.0);
    let val = 1.0 / (n_fft as f64 * (1.0 / sr));
    let first_at_least = |f: f64| {
        let mut i = ((f / val).floor().max(0.0) as usize)
            .saturating_sub(2)
            .min(n);
        while i < n && (i as f64 * val) < f {
            i += 1;
        }
        i
    };
    let lo = first_at_least(fmin);
    let hi = first_at_least(fmax).max(lo);
    lo..hi
}

/// Maximum of a float32 slice (exact; eight lanes so it vectorises).
fn max_f32(s: &[f32]) -> f32 {
    let mut lanes = [f32::NEG_INFINITY; 8];
    let mut chunks = s.chunks_exact(8);
    for c in &mut chunks {
        for l in 0..8 {
            lanes[l] = lanes[l].max(c[l]);
        }
    }
    let mut m = chunks
        .remainder()
        .iter()
        .copied()
        .fold(f32::NEG_INFINITY, f32::max);
    for l in lanes {
        m = m.max(l);
    }
    m
}

/// The peak picking of `piptrack` on bins `range` of one column whose maximum is `colmax`.
/// Only `s[range.start - 1 .. range.end + 1]` is read.
#[allow(clippy::too_many_arguments)]
fn pick_peaks(
    s: &[f32],
    colmax: f32,
    range: std::ops::Range<usize>,
    frame: usize,
    sr: f64,
    n_fft: usize,
    threshold: f32,
    out: &mut Vec<PitchPeak>,
) {
    let n = s.len();
    // `threshold * np.max(S, axis=-2)`: the Python float is cast to float32 (NEP 50).
    let ref_value = threshold * colmax;
    let thr = |i: usize| if s[i] > ref_value { s[i] } else { 0.0 };
    // util.localmax never marks bin 0.
    for i in range.start.max(1)..range.end {
        // util.localmax on S * (S > ref): (x[0] > x[-1]) & (x[0] >= x[1]); last bin: x > x[-1].
        let x = thr(i);
        if x == 0.0 {
            continue;
        }
        let is_max = if i + 1 < n {
            x > thr(i - 1) && x >= thr(i + 1)
        } else {
            x > thr(i - 1)
        };
        if !is_max {
            continue;
        }
        // Parabolic interpolation (numba stencil on float32 input: `2 * x[0]` and `/ 2` promote
        // to float64) and np.gradient (float32); both are 0 / one-sided at the edges.
        let (shift, avg) = if i + 1 < n {
            let (xm, x0, xp) = (s[i - 1], s[i], s[i + 1]);
            let a = (xp + xm) as f64 - 2.0 * x0 as f64;
            let b = (xp - xm) as f64 / 2.0;
            let shift = if b.abs() >= a.abs() {
                0.0f32
            } else {
                (-b / a) as f32
            };
            (shift, (xp - xm) / 2.0)
        } else {
            (0.0f32, s[i] - s[i - 1])
        };
        let dskew = 0.5f32 * avg * shift;
        let freq = ((i as f64 + shift as f64) * sr / n_fft as f64) as f32;
        out.push(PitchPeak {
            frame,
            bin: i,
            freq,
            mag: s[i] + dskew,
        });
    }
}

/// `piptrack`'s per-frame peak picking on complex STFT frames, with the default range
/// (150–4000 Hz) and threshold 0.1, for callers that run the STFT themselves (the 35-dim
/// pipeline shares one STFT between the mel spectrogram and the tuning estimate).
#[derive(Clone, Debug)]
pub struct PitchTracker {
    sr: f64,
    n_fft: usize,
    n_bins: usize,
    range: std::ops::Range<usize>,
    /// Bins whose magnitude is needed: the range and one bin either side.
    m_lo: usize,
    m_hi: usize,
}

impl PitchTracker {
    pub fn new(sr: f64, n_fft: usize) -> Self {
        let n_bins = n_fft / 2 + 1;
        let range = feasible_bins(n_bins, sr, n_fft, PIPTRACK_FMIN, PIPTRACK_FMAX);
        let (m_lo, m_hi) = (range.start.saturating_sub(1), (range.end + 1).min(n_bins));
        Self {
            sr,
            n_fft,
            n_bins,
            range,
            m_lo,
            m_hi,
        }
    }

    /// Appends the peaks of STFT frame `frame` (`spec`, `1 + n_fft/2` bins) to `out`.
    /// `mag` is scratch space.
    pub fn frame_peaks(
        &self,
        frame: usize,
        spec: &[Complex32],
        mag: &mut Vec<f32>,
        out: &mut Vec<PitchPeak>,
    ) {
        mag.resize(self.n_bins, 0.0);
        // |X| as numpy's complex64 abs (hypotf = float64 sqrt of the float64 sum of squares,
        // rounded once), without libm's slow hypot call. The column maximum comes from the
        // squared magnitudes (rounding is monotonic, so max then sqrt is exact).
        let mut max_sq = 0.0f64;
        for c in spec {
            let (re, im) = (c.re as f64, c.im as f64);
            max_sq = max_sq.max(re * re + im * im);
        }
        for (m, c) in mag[self.m_lo..self.m_hi]
            .iter_mut()
            .zip(&spec[self.m_lo..self.m_hi])
        {
            let (re, im) = (c.re as f64, c.im as f64);
            *m = (re * re + im * im).sqrt() as f32;
        }
        let colmax = max_sq.sqrt() as f32;
        pick_peaks(
            mag,
            colmax,
            self.range.clone(),
            frame,
            self.sr,
            self.n_fft,
            PIPTRACK_THRESHOLD,
            out,
        );
    }
}

/// `librosa.piptrack(y=y, sr=sr, n_fft=n_fft, hop_length=hop)` with the default range
/// (150–4000 Hz) and threshold 0.1, as a sparse list of peaks (frame-major, bins ascending).
pub fn piptrack(y: &[f32], sr: f64, n_fft: usize, hop: usize) -> Vec<PitchPeak> {
    let stft = Stft::hann(n_fft, hop);
    let tracker = PitchTracker::new(sr, n_fft);
    let t = n_frames(y.len(), hop);
    const CHUNK: usize = 128;
    let chunks: Vec<Vec<PitchPeak>> = (0..t.div_ceil(CHUNK))
        .into_par_iter()
        .map(|ci| {
            let frames = ci * CHUNK..((ci + 1) * CHUNK).min(t);
            let (mut peaks, mut mag) = (Vec::new(), Vec::new());
            stft.for_each_frame(y, frames, |ti, spec| {
                tracker.frame_peaks(ti, spec, &mut mag, &mut peaks)
            });
            peaks
        })
        .collect();
    chunks.concat()
}

/// `piptrack(S=s)` on a frame-major spectrogram (`n_fft` inferred as `2 * (bins - 1)`).
pub fn piptrack_spectrogram(s: &FrameMatrix, sr: f64) -> Vec<PitchPeak> {
    let n_fft = 2 * s.cols.saturating_sub(1);
    let chunks: Vec<Vec<PitchPeak>> = (0..s.rows)
        .into_par_iter()
        .fold(Vec::new, |mut acc, t| {
            piptrack_column(
                s.row(t),
                t,
                sr,
                n_fft,
                PIPTRACK_FMIN,
                PIPTRACK_FMAX,
                PIPTRACK_THRESHOLD,
                &mut acc,
            );
            acc
        })
        .collect();
    chunks.concat()
}

/// `librosa.estimate_tuning(y=y, sr=sr, bins_per_octave=bpo)` (n_fft 2048, resolution 0.01),
/// in fractions of a bin, in `[-0.5, 0.5)`.
pub fn estimate_tuning(y: &[f32], sr: f64, bins_per_octave: usize) -> f64 {
    let peaks = piptrack(y, sr, TUNING_N_FFT, TUNING_N_FFT / 4);
    tuning_from_peaks(&peaks, TUNING_RESOLUTION, bins_per_octave)
}

/// `librosa.estimate_tuning(S=s, sr=sr, bins_per_octave=bpo)` on a frame-major spectrogram.
pub fn estimate_tuning_from_spectrogram(s: &FrameMatrix, sr: f64, bins_per_octave: usize) -> f64 {
    let peaks = piptrack_spectrogram(s, sr);
    tuning_from_peaks(&peaks, TUNING_RESOLUTION, bins_per_octave)
}

/// The second half of `estimate_tuning`: median magnitude threshold, then [`pitch_tuning`].
pub fn tuning_from_peaks(peaks: &[PitchPeak], resolution: f64, bins_per_octave: usize) -> f64 {
    // `pitch > 0` mask (an interpolated pitch is always > 0 in the 150 Hz+ range, but keep the
    // test librosa makes).
    let mut mags: Vec<f32> = peaks
        .iter()
        .filter(|p| p.freq > 0.0)
        .map(|p| p.mag)
        .collect();
    let threshold = median_f32(&mut mags).unwrap_or(0.0);
    let freqs: Vec<f32> = peaks
        .iter()
        .filter(|p| p.freq > 0.0 && p.mag >= threshold)
        .map(|p| p.freq)
        .collect();
    pitch_tuning(&freqs, resolution, bins_per_octave)
}

/// `np.median` of a float32 array: the mean of the two middle values is taken in float32.
fn median_f32(v: &mut [f32]) -> Option<f32> {
    let n = v.len();
    if n == 0 {
        return None;
    }
    let cmp = |a: &f32, b: &f32| a.total_cmp(b);
    let (_, &mut hi, _) = v.select_nth_unstable_by(n / 2, cmp);
    if n % 2 == 1 {
        return Some(hi);
    }
    // The lower middle is the maximum of the lower partition.
    let lo = v[..n / 2].iter().copied().fold(f32::NEG_INFINITY, f32::max);
    Some((lo + hi) / 2.0)
}

/// `librosa.pitch_tuning(frequencies, resolution, bins_per_octave)`.
///
/// Arithmetic follows numpy on a float32 input: `f / 27.5`, `log2`, `* bpo` and `mod 1` in
/// float32; bin edges `linspace(-0.5, 0.5, ceil(1/resolution) + 1)` in float64.
pub fn pitch_tuning(frequencies: &[f32], resolution: f64, bins_per_octave: usize) -> f64 {
    let bpo = bins_per_octave as f32;
    let residuals: Vec<f32> = frequencies
        .iter()
        .filter(|&&f| f > 0.0)
        .map(|&f| {
            // hz_to_octs(f) = log2(f / (440 / 16)); float32 / python float stays float32.
            let octs = (f / 27.5f32).log2();
            let mut r = (bpo * octs).rem_euclid(1.0);
            if r >= 0.5 {
                r -= 1.0;
            }
            r
        })
        .collect();
    if residuals.is_empty() {
        return 0.0;
    }
    let edges = linspace(-0.5, 0.5, (1.0 / resolution).ceil() as usize + 1);
    let counts = histogram(&residuals, &edges);
    let mut best = 0;
    for (i, &c) in counts.iter().enumerate() {
        if c > counts[best] {
            best = i;
        }
    }
    edges[best]
}

/// `np.linspace(start, stop, num)` (endpoint included), bit-exact.
pub(crate) fn linspace(start: f64, stop: f64, num: usize) -> Vec<f64> {
    if num == 0 {
        return Vec::new();
    }
    if num == 1 {
        return vec![start];
    }
    let step = (stop - start) / (num - 1) as f64;
    let mut y: Vec<f64> = (0..num).map(|i| i as f64 * step + start).collect();
    y[num - 1] = stop;
    y
}

/// `np.histogram(values, edges)` counts: bin i is `[e_i, e_{i+1})`, the last bin is closed,
/// values outside `[e_0, e_last]` are dropped.
fn histogram(values: &[f32], edges: &[f64]) -> Vec<usize> {
    let nb = edges.len() - 1;
    let mut counts = vec![0usize; nb];
    let (first, last) = (edges[0], edges[nb]);
    let norm = nb as f64 / (last - first);
    for &v in values {
        let v = v as f64;
        if !(v >= first && v <= last) {
            continue;
        }
        let mut i = (((v - first) * norm) as usize).min(nb - 1);
        while i > 0 && v < edges[i] {
            i -= 1;
        }
        while i + 1 < nb && v >= edges[i + 1] {
            i += 1;
        }
        counts[i] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_match_numpy() {
        let e = linspace(-0.5, 0.5, 101);
        // np.linspace(-0.5, 0.5, 101)[51] == 0.010000000000000009
        assert_eq!(e[51], 0.010000000000000009);
        assert_eq!(e[100], 0.5);
    }

    #[test]
    fn empty_is_zero() {
        assert_eq!(pitch_tuning(&[], 0.01, 12), 0.0);
        assert_eq!(estimate_tuning(&[0.0; 4096], 22050.0, 36), 0.0);
    }

    #[test]
    fn a440_is_in_tune() {
        let sr = 22050.0;
        let y: Vec<f32> = (0..22050)
            .map(|i| (2.0 * std::f64::consts::PI * 440.0 * i as f64 / sr).sin() as f32)
            .collect();
        let t = estimate_tuning(&y, sr, 12);
        assert!(t.abs() <= 0.02, "tuning {t}");
    }

    #[test]
    fn median_even_odd() {
        assert_eq!(median_f32(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median_f32(&mut [4.0, 1.0, 2.0, 3.0]), Some(2.5));
    }
}
