//! Median-filtering harmonic/percussive source separation, as librosa 0.11 does it.
//!
//! * [`hpss_masks`] is `librosa.decompose.hpss(S, kernel_size, power, margin, mask=True)` on a
//!   magnitude spectrogram: a median filter of `kernel_harm` frames along time gives the
//!   harmonic estimate, one of `kernel_perc` bins along frequency the percussive estimate (both
//!   `scipy.ndimage.median_filter(..., mode='reflect')`), and `librosa.util.softmask` turns them
//!   into Wiener-like masks.
//! * [`hpss`] is `librosa.effects.hpss(y)`: centred zero-padded Hann STFT → masks → the masked
//!   complex spectra `(|D|·mask)·phase(D)` → inverse STFT (overlap-add, divided by the window's
//!   sum of squares) trimmed to `len(y)`.
//!
//! The median filters are sliding sorted windows (O(k) per output value, no per-window sort), run
//! in parallel over rows; the spectrogram is never held in complex form (the synthesis pass
//! recomputes each frame's FFT), so peak memory is three `frames × bins` float32 matrices.

use rayon::prelude::*;
use realfft::RealFftPlanner;
use realfft::num_complex::Complex32;

use crate::error::{MusicError, Result};
use crate::stft::{FrameMatrix, Stft, hann_periodic, n_frames};

/// Parameters of `librosa.decompose.hpss` (librosa defaults via [`Default`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HpssParams {
    /// Median-filter length along time (frames) for the harmonic estimate.
    pub kernel_harm: usize,
    /// Median-filter length along frequency (bins) for the percussive estimate.
    pub kernel_perc: usize,
    /// Soft-mask exponent (`f32::INFINITY` gives librosa's hard mask).
    pub power: f32,
    pub margin_harm: f32,
    pub margin_perc: f32,
}

impl Default for HpssParams {
    /// `kernel_size=31, power=2.0, margin=1.0`.
    fn default() -> Self {
        Self {
            kernel_harm: 31,
            kernel_perc: 31,
            power: 2.0,
            margin_harm: 1.0,
            margin_perc: 1.0,
        }
    }
}

impl HpssParams {
    fn validate(&self) -> Result<()> {
        if self.kernel_harm == 0 || self.kernel_perc == 0 {
            return Err(MusicError::InvalidParameter(
                "HPSS kernel sizes must be positive".into(),
            ));
        }
        let margin_ok = |m: f32| m >= 1.0;
        if !margin_ok(self.margin_harm) || !margin_ok(self.margin_perc) {
            return Err(MusicError::InvalidParameter(format!(
                "HPSS margins must be >= 1 (got {}, {})",
                self.margin_harm, self.margin_perc
            )));
        }
        if self.power.is_nan() || self.power <= 0.0 {
            return Err(MusicError::InvalidParameter(format!(
                "HPSS soft-mask power must be > 0 (got {})",
                self.power
            )));
        }
        Ok(())
    }

    /// librosa's `split_zeros`: with both margins 1, bins where both estimates vanish are split
    /// half/half instead of being zeroed.
    fn split_zeros(&self) -> bool {
        self.margin_harm == 1.0 && self.margin_perc == 1.0
    }

    /// The (harmonic, percussive) mask values for one bin from its two median estimates.
    #[inline]
    fn masks(&self, harm: f32, perc: f32) -> (f32, f32) {
        let split = self.split_zeros();
        (
            softmask(harm, perc * self.margin_harm, self.power, split),
            softmask(perc, harm * self.margin_perc, self.power, split),
        )
    }
}

/// `librosa.util.softmask(x, x_ref, power, split_zeros)` for one element, in float32:
/// `z = max(x, x_ref)`; if `z` is below the smallest normal float the mask is 0.5 (split) or 0;
/// otherwise `(x/z)^p / ((x/z)^p + (x_ref/z)^p)`. An infinite power is the hard mask `x > x_ref`.
#[inline]
pub fn softmask(x: f32, x_ref: f32, power: f32, split_zeros: bool) -> f32 {
    if power.is_infinite() {
        return if x > x_ref { 1.0 } else { 0.0 };
    }
    let z = x.max(x_ref);
    if z < f32::MIN_POSITIVE {
        return if split_zeros { 0.5 } else { 0.0 };
    }
    let (a, b) = (x / z, x_ref / z);
    // numpy evaluates `** 2` as a plain square.
    let (ma, mb) = if power == 2.0 {
        (a * a, b * b)
    } else {
        (a.powf(power), b.powf(power))
    };
    ma / (ma + mb)
}

/// Index into `0..n` of position `i` of scipy.ndimage's `'reflect'` extension
/// (`d c b a | a b c d | d c b a`, repeated with period `2n` for windows wider than the signal).
#[inline]
fn reflect_index(i: isize, n: usize) -> usize {
    let m = i.rem_euclid(2 * n as isize) as usize;
    if m < n { m } else { 2 * n - 1 - m }
}

/// Maps an f32 to a u32 whose unsigned order is `f32::total_cmp`'s order.
#[inline]
fn sort_key(v: f32) -> u32 {
    let b = v.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

#[inline]
fn from_sort_key(k: u32) -> f32 {
    f32::from_bits(if k & 0x8000_0000 != 0 {
        k & 0x7fff_ffff
    } else {
        !k
    })
}

/// `scipy.ndimage.median_filter(x, size, mode='reflect')` of one row, into `out`.
///
/// The window of output `i` is `x[i - size/2 .. i - size/2 + size]` (scipy's centring, also for
/// even sizes) and the result is its element of rank `size/2`, so it is one of the inputs,
/// bit for bit. `keys` and `window` are scratch space.
///
/// The window is kept sorted (as integer keys with the float order) and slid one sample at a
/// time: the outgoing value is found by binary search and the elements between it and the
/// incoming value's place are shifted by one, O(size) per output with a single `memmove`.
///
/// Matches scipy for every length except `x.len() == 2` with `size > 4` (scipy's 1-D rank filter
/// has a quirk there; it only concerns signals of under 1024 samples in the STFT use).
pub fn median_filter_reflect(
    x: &[f32],
    size: usize,
    out: &mut [f32],
    keys: &mut Vec<u32>,
    window: &mut Vec<u32>,
) {
    let n = x.len();
    assert_eq!(out.len(), n, "output length must equal input length");
    assert!(size > 0, "median filter size must be positive");
    if n == 0 {
        return;
    }
    let half = size / 2;
    // The reflect-extended row as keys: positions -half .. n - half + size - 1.
    keys.clear();
    keys.extend(
        (0..n + size - 1).map(|j| sort_key(x[reflect_index(j as isize - half as isize, n)])),
    );
    window.clear();
    window.extend_from_slice(&keys[..size]);
    window.sort_unstable();
    let rank = size / 2;
    out[0] = from_sort_key(window[rank]);
    for (i, o) in out.iter_mut().enumerate().skip(1) {
        let old = keys[i - 1];
        let new = keys[i - 1 + size];
        if new != old {
            let p = window.partition_point(|&k| k < old);
            debug_assert_eq!(window[p], old);
            let q = window.partition_point(|&k| k < new);
            if new > old {
                // p < q: close the gap at p, put `new` just before the first element >= new.
                window.copy_within(p + 1..q, p);
                window[q - 1] = new;
            } else {
                // q <= p: open a gap at q.
                window.copy_within(q..p, q + 1);
                window[q] = new;
            }
        }
        *o = from_sort_key(window[rank]);
    }
}

/// Median filter of every row of a row-major `rows × cols` buffer (in parallel).
fn median_filter_rows(data: &[f32], cols: usize, size: usize) -> Vec<f32> {
    let mut out = vec![0.0; data.len()];
    if cols == 0 {
        return out;
    }
    out.par_chunks_mut(cols)
        .zip(data.par_chunks(cols))
        .for_each_init(
            || (Vec::new(), Vec::new()),
            |(keys, win), (o, x)| median_filter_reflect(x, size, o, keys, win),
        );
    out
}

/// Row-major transpose of a `rows × cols` buffer (blocked for cache friendliness).
fn transpose(data: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    const B: usize = 32;
    let mut out = vec![0.0; data.len()];
    for r0 in (0..rows).step_by(B) {
        for c0 in (0..cols).step_by(B) {
            for r in r0..(r0 + B).min(rows) {
                for c in c0..(c0 + B).min(cols) {
                    out[c * rows + r] = data[r * cols + c];
                }
            }
        }
    }
    out
}

/// The two median-filtered estimates of a magnitude spectrogram (frames × bins):
/// `(harmonic = median along time, percussive = median along frequency)`.
pub fn median_estimates(mag: &FrameMatrix, p: &HpssParams) -> (FrameMatrix, FrameMatrix) {
    let (t, f) = (mag.rows, mag.cols);
    // Harmonic: filter each bin's time series; work bin-major so rows are contiguous.
    let by_bin = transpose(&mag.data, t, f);
    let harm_by_bin = median_filter_rows(&by_bin, t, p.kernel_harm);
    let harm = FrameMatrix {
        rows: t,
        cols: f,
        data: transpose(&harm_by_bin, f, t),
    };
    let perc = FrameMatrix {
        rows: t,
        cols: f,
        data: median_filter_rows(&mag.data, f, p.kernel_perc),
    };
    (harm, perc)
}

/// `librosa.decompose.hpss(S, mask=True)` for a magnitude spectrogram `mag` (frames × bins):
/// the (harmonic, percussive) soft masks, frames × bins.
pub fn hpss_masks(mag: &FrameMatrix, p: &HpssParams) -> Result<(FrameMatrix, FrameMatrix)> {
    p.validate()?;
    let (harm, perc) = median_estimates(mag, p);
    let mut mh = FrameMatrix::zeros(mag.rows, mag.cols);
    let mut mp = FrameMatrix::zeros(mag.rows, mag.cols);
    mh.data
        .par_iter_mut()
        .zip(mp.data.par_iter_mut())
        .zip(harm.data.par_iter().zip(perc.data.par_iter()))
        .for_each(|((oh, op), (&h, &q))| (*oh, *op) = p.masks(h, q));
    Ok((mh, mp))
}

/// `librosa.effects.hpss(y, n_fft=n_fft, hop_length=hop)` with Hann window, `center=True`,
/// zero padding: the harmonic and percussive signals, each `y.len()` samples.
pub fn hpss(y: &[f32], n_fft: usize, hop: usize, p: &HpssParams) -> Result<(Vec<f32>, Vec<f32>)> {
    p.validate()?;
    if n_fft == 0 || hop == 0 || !n_fft.is_multiple_of(2) {
        return Err(MusicError::InvalidParameter(format!(
            "HPSS needs an even n_fft and a positive hop (got {n_fft}, {hop})"
        )));
    }
    if y.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let stft = Stft::hann(n_fft, hop);
    let mag = stft.magnitude(y);
    let (harm, perc) = median_estimates(&mag, p);
    drop(mag);
    Ok(synthesize(&stft, y, &harm, &perc, p))
}

/// Inverse STFT of the two masked spectra. Frame `t` of the masked spectrum is rebuilt from a
/// fresh FFT of `y` (bit-identical to the analysis pass), so no complex spectrogram is stored.
fn synthesize(
    stft: &Stft,
    y: &[f32],
    harm: &FrameMatrix,
    perc: &FrameMatrix,
    p: &HpssParams,
) -> (Vec<f32>, Vec<f32>) {
    let n_fft = stft.n_fft();
    let hop = stft.hop();
    let half = n_fft / 2;
    let len = y.len();
    let t_total = n_frames(len, hop);
    let window: Vec<f32> = hann_periodic(n_fft).into_iter().map(|v| v as f32).collect();
    let ifft = RealFftPlanner::<f32>::new().plan_fft_inverse(n_fft);
    let scale = 1.0 / n_fft as f32;

    // Frames are processed in chunks; each chunk overlap-adds into its own buffer that starts at
    // padded sample `start * hop` (padded coordinates: signal sample s is at s + n_fft/2).
    const CHUNK: usize = 128;
    let n_chunks = t_total.div_ceil(CHUNK);
    let parts: Vec<(usize, Vec<f32>, Vec<f32>)> = (0..n_chunks)
        .into_par_iter()
        .map(|ci| {
            let start = ci * CHUNK;
            let end = (start + CHUNK).min(t_total);
            let buf_len = (end - start - 1) * hop + n_fft;
            let mut out_h = vec![0.0f32; buf_len];
            let mut out_p = vec![0.0f32; buf_len];
            let mut spec_h = ifft.make_input_vec();
            let mut spec_p = ifft.make_input_vec();
            let mut time = ifft.make_output_vec();
            let mut scratch = ifft.make_scratch_vec();
            stft.for_each_frame(y, start..end, |t, spec| {
                let (hrow, prow) = (harm.row(t), perc.row(t));
                for (k, c) in spec.iter().enumerate() {
                    let (mh, mp) = p.masks(hrow[k], prow[k]);
                    // librosa: S, phase = magphase(D); (S * mask) * phase.
                    let mag = crate::stft::magnitude_of(*c);
                    let phase = if mag == 0.0 {
                        Complex32::new(1.0, 0.0)
                    } else {
                        Complex32::new(c.re / mag, c.im / mag)
                    };
                    spec_h[k] = phase * (mag * mh);
                    spec_p[k] = phase * (mag * mp);
                }
                let off = (t - start) * hop;
                for (s, out) in [(&mut spec_h, &mut out_h), (&mut spec_p, &mut out_p)] {
                    // irfft ignores the imaginary parts of the DC and Nyquist bins.
                    s[0].im = 0.0;
                    s[half].im = 0.0;
                    ifft.process_with_scratch(s, &mut time, &mut scratch)
                        .expect("buffer sizes come from the plan");
                    for ((o, &v), &w) in out[off..off + n_fft].iter_mut().zip(&time).zip(&window) {
                        *o += v * scale * w;
                    }
                }
            });
            (start * hop, out_h, out_p)
        })
        .collect();

    // Sum the chunk buffers into the padded signals, then normalise by the window envelope.
    let padded_len = (t_total - 1) * hop + n_fft;
    let mut yh = vec![0.0f32; padded_len];
    let mut yp = vec![0.0f32; padded_len];
    for (off, bh, bp) in parts {
        for (o, v) in yh[off..off + bh.len()].iter_mut().zip(&bh) {
            *o += v;
        }
        for (o, v) in yp[off..off + bp.len()].iter_mut().zip(&bp) {
            *o += v;
        }
    }
    let env = window_sumsquare(&window, t_total, hop);
    let trim = |sig: Vec<f32>| -> Vec<f32> {
        (0..len)
            .map(|s| {
                let (v, e) = (sig[s + half], env[s + half]);
                if e > f32::MIN_POSITIVE { v / e } else { v }
            })
            .collect()
    };
    (trim(yh), trim(yp))
}

/// `librosa.filters.window_sumsquare`: the overlap-added squared window of `n_frames` frames.
fn window_sumsquare(window: &[f32], n_frames: usize, hop: usize) -> Vec<f32> {
    let n_fft = window.len();
    let mut env = vec![0.0f32; n_fft + hop * (n_frames - 1)];
    for t in 0..n_frames {
        for (e, &w) in env[t * hop..t * hop + n_fft].iter_mut().zip(window) {
            *e += w * w;
        }
    }
    env
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive_median(x: &[f32], size: usize) -> Vec<f32> {
        let n = x.len();
        let half = (size / 2) as isize;
        (0..n)
            .map(|i| {
                let mut w: Vec<f32> = (0..size as isize)
                    .map(|j| x[reflect_index(i as isize - half + j, n)])
                    .collect();
                w.sort_by(f32::total_cmp);
                w[size / 2]
            })
            .collect()
    }

    #[test]
    fn sliding_median_matches_naive_selection() {
        let mut state = 12345u32;
        let mut rnd = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            // Coarse values so that ties occur.
            ((state >> 24) % 17) as f32 * 0.25 - 1.0
        };
        let (mut keys, mut win) = (Vec::new(), Vec::new());
        for n in [1usize, 3, 5, 16, 40, 100] {
            let x: Vec<f32> = (0..n).map(|_| rnd()).collect();
            for size in [1usize, 3, 4, 7, 31] {
                let mut out = vec![0.0; n];
                median_filter_reflect(&x, size, &mut out, &mut keys, &mut win);
                assert_eq!(out, naive_median(&x, size), "n {n} size {size}");
            }
        }
    }

    #[test]
    fn softmask_edge_cases() {
        assert_eq!(softmask(0.0, 0.0, 2.0, true), 0.5);
        assert_eq!(softmask(0.0, 0.0, 2.0, false), 0.0);
        assert_eq!(softmask(3.0, 0.0, 2.0, true), 1.0);
        assert!((softmask(1.0, 2.0, 2.0, true) - 0.2).abs() < 1e-7);
        assert_eq!(softmask(2.0, 1.0, f32::INFINITY, true), 1.0);
    }

    #[test]
    fn harmonic_plus_percussive_reconstructs_the_signal() {
        // Masks sum to one, so H + P is the inverse STFT of the full STFT, i.e. y itself.
        let y: Vec<f32> = (0..20_000)
            .map(|i| {
                let t = i as f32 / 22050.0;
                (2.0 * std::f32::consts::PI * 440.0 * t).sin() * 0.5
                    + if i % 5000 < 20 { 0.8 } else { 0.0 }
            })
            .collect();
        let (h, p) = hpss(&y, 2048, 512, &HpssParams::default()).unwrap();
        assert_eq!(h.len(), y.len());
        let err = y
            .iter()
            .zip(h.iter().zip(&p))
            .map(|(&a, (&b, &c))| (a - b - c).abs())
            .fold(0.0f32, f32::max);
        assert!(err < 1e-5, "reconstruction error {err}");
    }
}
