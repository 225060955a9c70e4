//! Constant-Q / variable-Q transform magnitude: `librosa.cqt` / `librosa.vqt` (librosa 0.11).
//!
//! Why it matters: `chroma_cens` (the 12 chroma columns of the 35-dim dance feature) and
//! `chroma_cqt` fold this transform, so its per-bin scale and its multirate structure have to be
//! librosa's, not merely "a CQT".
//!
//! What is reproduced (all from `librosa/core/constantq.py` and `filters.py`):
//! - frequencies `fmin * 2^(tuning/bpo) * 2^o * 2^(k/bpo)`, relative bandwidth `alpha` from the
//!   local log-frequency spacing (`filters._relative_bandwidth`), `Q = filter_scale / alpha`,
//!   filter lengths `Q * sr / (f + gamma / alpha)`, cutoff check against Nyquist;
//! - `__early_downsample`: `min(max(0, ceil(log2(nyq / cutoff)) - 2), max(0, twos(hop) - n_oct + 1))`
//!   halvings in one `soxr_hq` call with `scale=True` (none at 15360/30720 Hz with 7 octaves);
//! - octave by octave from the top, `__vqt_filter_fft`: `filters.wavelet` (complex exponential
//!   over `arange(floor(-len/2), floor(len/2))`, periodic Hann of that many samples, L1 norm,
//!   `pad_center` to `2^ceil(log2(max len))`), times `len / n_fft`, FFT, non-negative
//!   frequencies, `sparsify_rows(quantile=sparsity)` in float32 (drop the smallest entries that
//!   together hold less than `sparsity` of the row's L1 mass), times `sqrt(sr / sr_octave)`;
//! - response `fft_basis @ stft(y_oct, n_fft, hop_oct, window='ones', center, zero pad)`;
//! - then `y_oct = resample(y_oct, 2, 1, soxr_hq, scale=True)` and `hop //= 2` while the hop is even;
//! - stacking trimmed to the shortest octave, and with `scale=True` every bin divided by
//!   `sqrt(Q * sr / f)` (lengths at the full — after early downsampling — rate).
//!
//! The two real scale factors are folded into the sparse basis (|a·z| = a·|z| for a > 0), which
//! only changes float32 rounding. The basis is built in float64 (librosa: complex64 FFT) and
//! rounded to float32 once. Measured against librosa: ~3e-7 of the peak on the fixtures and on
//! ad-hoc checks of early downsampling (44.1 kHz), odd hops and the VQT (`gamma=None`).
//!
//! Performance: the basis is a CSR matrix of ~3000 complex entries (252 bins); every octave
//! has the same frame count, so frames are processed in parallel chunks, each chunk running the
//! real FFT of every octave and writing its rows of the output directly. The octave signals
//! (sequential libsoxr calls) do not depend on the tuning and can be prepared while it is
//! estimated ([`MultirateLayout::prepare`]); plans are cached ([`CqtPlan::cached`]).

use std::borrow::Cow;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

use rayon::prelude::*;
use realfft::num_complex::{Complex, Complex32};
use rustfft::FftPlanner;

use crate::error::{MusicError, Result};
use crate::resample::resample_hq;
use crate::stft::{FrameMatrix, Stft, n_frames};

/// Equivalent noise bandwidth of the Hann window (librosa's `WINDOW_BANDWIDTHS['hann']`).
const HANN_BANDWIDTH: f64 = 1.50018310546875;

/// `librosa.note_to_hz('C1')` = `440 * 2^((24 - 69) / 12)` ≈ 32.703 Hz.
pub fn c1_hz() -> f64 {
    440.0 * 2.0f64.powf((24.0 - 69.0) / 12.0)
}

/// Parameters of `librosa.vqt` (window `hann`, L1 filter norm and `pad_mode='constant'` fixed).
#[derive(Clone, Debug, PartialEq)]
pub struct CqtParams {
    /// Lowest frequency before tuning, Hz (librosa: `fmin=None` → C1).
    pub fmin: f64,
    pub n_bins: usize,
    pub bins_per_octave: usize,
    /// Tuning deviation in fractions of a bin; `fmin` is multiplied by `2^(tuning / bpo)`.
    pub tuning: f64,
    pub filter_scale: f64,
    /// Bandwidth offset in Hz: 0 for the CQT; `None` is librosa's ERB-like default for the VQT.
    pub gamma: Option<f64>,
    pub sparsity: f64,
    /// Divide each bin by `sqrt(filter length)` (librosa's `scale=True`).
    pub scale: bool,
}

impl Default for CqtParams {
    /// `librosa.cqt` defaults: C1, 84 bins, 12 per octave, no tuning, sparsity 0.01, scaled.
    fn default() -> Self {
        Self {
            fmin: c1_hz(),
            n_bins: 84,
            bins_per_octave: 12,
            tuning: 0.0,
            filter_scale: 1.0,
            gamma: Some(0.0),
            sparsity: 0.01,
            scale: true,
        }
    }
}

impl CqtParams {
    /// The CQT inside `chroma_cqt` / `chroma_cens`: C1, 7 octaves × 36 bins, given tuning.
    pub fn chroma(tuning: f64) -> Self {
        Self {
            n_bins: 7 * 36,
            bins_per_octave: 36,
            tuning,
            ..Self::default()
        }
    }

    /// Centre frequencies of the bins (`interval_frequencies(..., intervals='equal')` times the
    /// tuned `fmin`), ascending.
    pub fn frequencies(&self) -> Vec<f64> {
        let bpo = self.bins_per_octave as f64;
        let fmin = self.fmin * 2.0f64.powf(self.tuning / bpo);
        let ratios: Vec<f64> = (0..self.bins_per_octave)
            .map(|k| 2.0f64.powf(k as f64 / bpo))
            .collect();
        let mut all: Vec<f64> = (0..self.n_bins)
            .map(|i| {
                let (o, k) = (i / self.bins_per_octave, i % self.bins_per_octave);
                2.0f64.powi(o as i32) * ratios[k]
            })
            .collect();
        all.sort_by(f64::total_cmp);
        all.into_iter().map(|r| r * fmin).collect()
    }
}

/// `filters._relative_bandwidth(freqs)`.
fn relative_bandwidth(freqs: &[f64]) -> Vec<f64> {
    let n = freqs.len();
    let logf: Vec<f64> = freqs.iter().map(|f| f.log2()).collect();
    let mut bpo = vec![0.0; n];
    bpo[0] = 1.0 / (logf[1] - logf[0]);
    bpo[n - 1] = 1.0 / (logf[n - 1] - logf[n - 2]);
    for i in 1..n - 1 {
        bpo[i] = 2.0 / (logf[i + 1] - logf[i - 1]);
    }
    bpo.iter()
        .map(|&b| {
            let r = 2.0f64.powf(2.0 / b);
            (r - 1.0) / (r + 1.0)
        })
        .collect()
}

/// The `gamma` array of `wavelet_lengths` (scalar `gamma`, or `alpha * 24.7 / 0.108` for None).
fn gamma_of(gamma: Option<f64>, alpha: f64) -> f64 {
    gamma.unwrap_or(alpha * 24.7 / 0.108)
}

/// `filters.wavelet_lengths`: lengths `Q * sr / (f + gamma / alpha)` and the highest cutoff.
fn wavelet_lengths(
    freqs: &[f64],
    alpha: &[f64],
    sr: f64,
    filter_scale: f64,
    gamma: Option<f64>,
) -> (Vec<f64>, f64) {
    let mut cutoff = f64::NEG_INFINITY;
    let lengths = freqs
        .iter()
        .zip(alpha)
        .map(|(&f, &a)| {
            let q = filter_scale / a;
            let g = gamma_of(gamma, a);
            cutoff = cutoff.max(f * (1.0 + 0.5 * HANN_BANDWIDTH / q) + 0.5 * g);
            q * sr / (f + g / a)
        })
        .collect();
    (lengths, cutoff)
}

/// numpy's pairwise summation (`np.sum` along a contiguous float32 axis).
fn pairwise_sum_f32(a: &[f32]) -> f32 {
    let n = a.len();
    if n < 8 {
        let mut res = 0.0f32;
        for &v in a {
            res += v;
        }
        res
    } else if n <= 128 {
        let mut r = [0.0f32; 8];
        r.copy_from_slice(&a[..8]);
        let mut i = 8;
        while i < n - (n % 8) {
            for j in 0..8 {
                r[j] += a[i + j];
            }
            i += 8;
        }
        let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        while i < n {
            res += a[i];
            i += 1;
        }
        res
    } else {
        let mut n2 = n / 2;
        n2 -= n2 % 8;
        pairwise_sum_f32(&a[..n2]) + pairwise_sum_f32(&a[n2..])
    }
}

/// `util.sparsify_rows(row, quantile)` on one float32 complex row: the kept `(bin, value)`.
fn sparsify_row(row: &[Complex32], quantile: f64) -> Vec<(u32, Complex32)> {
    let mags: Vec<f32> = row.iter().map(|&c| crate::stft::magnitude_of(c)).collect();
    let norm = pairwise_sum_f32(&mags);
    let mut sorted = mags.clone();
    sorted.sort_by(f32::total_cmp);
    // argmin(cumsum(sorted / norm) < quantile): first index where the float32 cumsum reaches it.
    let q = quantile as f32;
    let mut cum = 0.0f32;
    let mut j = 0;
    for (i, &m) in sorted.iter().enumerate() {
        cum += m / norm;
        if cum >= q {
            j = i;
            break;
        }
    }
    let cut = sorted[j];
    mags.iter()
        .enumerate()
        .filter(|&(_, &m)| m >= cut)
        .map(|(i, _)| (i as u32, row[i]))
        .collect()
}

/// `Σ coefs[j] · spec[bins[j]]` in float32 with four independent accumulators (a ~13-term
/// dot product per filter is otherwise bound by the floating-point add latency).
#[inline]
fn sparse_dot(bins: &[u32], coefs: &[Complex32], spec: &[Complex32]) -> Complex32 {
    let mut acc = [Complex32::new(0.0, 0.0); 4];
    let mut bc = bins.chunks_exact(4);
    let mut cc = coefs.chunks_exact(4);
    for (b4, c4) in (&mut bc).zip(&mut cc) {
        for l in 0..4 {
            acc[l] += c4[l] * spec[b4[l] as usize];
        }
    }
    for (&b, &c) in bc.remainder().iter().zip(cc.remainder()) {
        acc[0] += c * spec[b as usize];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// One octave of the multirate transform: its STFT and its sparse filter basis.
struct Octave {
    stft: Stft,
    /// Which signal (index into the halving cascade) this octave reads.
    signal: usize,
    /// Output column of this octave's first (lowest) filter.
    first_col: usize,
    /// CSR: filter `k` owns entries `starts[k]..starts[k+1]`.
    starts: Vec<usize>,
    bins: Vec<u32>,
    coefs: Vec<Complex32>,
}

impl Octave {
    fn n_filters(&self) -> usize {
        self.starts.len() - 1
    }
}

/// The per-octave input signals of a multirate CQT ([`CqtPlan::prepare`]).
/// The multirate structure of a CQT: how the input is early-downsampled and how many times it
/// is halved. It does not depend on the filters' exact frequencies (except through the
/// Nyquist cutoff), so the octave signals can be computed before the tuning is known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MultirateLayout {
    /// Early downsampling factor applied to the input first (1 = none).
    pub early_factor: usize,
    /// `scale=False` compensation `sqrt(early_factor)` (1 otherwise).
    pub early_gain: f32,
    /// Number of `soxr_hq` halvings after the first octave signal.
    pub n_halvings: usize,
}

/// The per-octave input signals of a multirate CQT ([`MultirateLayout::prepare`]). Without
/// early downsampling the first one borrows the input.
pub struct OctaveSignals<'a> {
    layout: MultirateLayout,
    first: Cow<'a, [f32]>,
    halved: Vec<Vec<f32>>,
}

impl OctaveSignals<'_> {
    /// Signal `i` (0 = full or early-downsampled rate, then one halving each).
    fn get(&self, i: usize) -> &[f32] {
        if i == 0 {
            &self.first
        } else {
            &self.halved[i - 1]
        }
    }
}

impl MultirateLayout {
    /// The layout `librosa.vqt(y, sr=sr, hop_length=hop, ...)` uses with `params`
    /// (`__early_downsample_count`, then one halving per octave while the hop is even).
    pub fn new(sr: f64, hop: usize, params: &CqtParams) -> Result<Self> {
        Ok(Geometry::new(sr, hop, params)?.layout)
    }

    /// The octave signals: `y` early-downsampled (one `soxr_hq` call, `scale=True`), then halved
    /// `n_halvings` times with `resample(y, 2, 1, soxr_hq, scale=True)`.
    pub fn prepare<'a>(&self, y: &'a [f32]) -> Result<OctaveSignals<'a>> {
        if y.is_empty() {
            return Err(MusicError::InvalidParameter(
                "CQT of an empty signal".into(),
            ));
        }
        if y.len() < self.early_factor {
            return Err(MusicError::InvalidParameter(format!(
                "input signal of length {} is too short for this CQT",
                y.len()
            )));
        }
        let first: Cow<'a, [f32]> = if self.early_factor > 1 {
            let mut v = resample_hq(y, self.early_factor as f64, 1.0, true)?;
            if self.early_gain != 1.0 {
                for x in &mut v {
                    *x *= self.early_gain;
                }
            }
            Cow::Owned(v)
        } else {
            Cow::Borrowed(y)
        };
        let mut halved: Vec<Vec<f32>> = Vec::with_capacity(self.n_halvings);
        for i in 0..self.n_halvings {
            let prev: &[f32] = if i == 0 { &first } else { &halved[i - 1] };
            let next = resample_hq(prev, 2.0, 1.0, true)?;
            halved.push(next);
        }
        Ok(OctaveSignals {
            layout: *self,
            first,
            halved,
        })
    }
}

/// Frequencies, bandwidths and the multirate layout of a parameter set (validated).
struct Geometry {
    freqs: Vec<f64>,
    alpha: Vec<f64>,
    layout: MultirateLayout,
    /// Sample rate after early downsampling.
    sr: f64,
    /// Hop after early downsampling.
    hop: usize,
}

impl Geometry {
    fn new(sr: f64, hop: usize, params: &CqtParams) -> Result<Self> {
        let bpo = params.bins_per_octave;
        if params.n_bins < 2 || bpo == 0 || hop == 0 || sr <= 0.0 || params.fmin <= 0.0 {
            return Err(MusicError::InvalidParameter(format!(
                "CQT needs n_bins >= 2, bins_per_octave > 0, hop > 0, sr > 0, fmin > 0 \
                 (got n_bins {}, bpo {bpo}, hop {hop}, sr {sr}, fmin {})",
                params.n_bins, params.fmin
            )));
        }
        if !(0.0..1.0).contains(&params.sparsity) || params.filter_scale <= 0.0 {
            return Err(MusicError::InvalidParameter(format!(
                "CQT sparsity {} must be in [0, 1) and filter_scale {} positive",
                params.sparsity, params.filter_scale
            )));
        }
        let n_octaves = params.n_bins.div_ceil(bpo);
        let freqs = params.frequencies();
        let alpha = relative_bandwidth(&freqs);
        let (_, cutoff) = wavelet_lengths(&freqs, &alpha, sr, params.filter_scale, params.gamma);
        let nyquist = sr / 2.0;
        if cutoff > nyquist {
            return Err(MusicError::InvalidParameter(format!(
                "CQT basis with max frequency {:.1} Hz reaches {cutoff:.1} Hz, above the \
                 Nyquist frequency {nyquist} Hz; use fewer bins",
                freqs[freqs.len() - 1]
            )));
        }
        // __early_downsample_count
        let count1 = ((nyquist / cutoff).log2().ceil() as i64 - 1 - 1).max(0);
        let count2 = (hop.trailing_zeros() as i64 - n_octaves as i64 + 1).max(0);
        let count = count1.min(count2) as u32;
        let early_factor = 1usize << count;
        let early_gain = if count > 0 && !params.scale {
            (early_factor as f64).sqrt() as f32
        } else {
            1.0
        };
        let hop = hop / early_factor;
        // One halving after every octave but the last, while the hop stays even.
        let mut n_halvings = 0;
        let mut h = hop;
        for _ in 1..n_octaves {
            if !h.is_multiple_of(2) {
                break;
            }
            h /= 2;
            n_halvings += 1;
        }
        Ok(Self {
            freqs,
            alpha,
            layout: MultirateLayout {
                early_factor,
                early_gain,
                n_halvings,
            },
            sr: sr / early_factor as f64,
            hop,
        })
    }
}

/// One filter of `__vqt_filter_fft`: sparse FFT of the L1-normalised Hann-windowed complex
/// exponential, times `scale`.
fn filter_fft(
    f: f64,
    ilen: f64,
    my_sr: f64,
    n_fft: usize,
    scale: f64,
    sparsity: f64,
    fft: &dyn rustfft::Fft<f64>,
) -> Vec<(u32, Complex32)> {
    // filters.wavelet: arange(-ilen // 2, ilen // 2) * 2 * pi * freq / sr, periodic Hann of
    // that many samples (an integer, so __float_window adds nothing), L1 norm.
    let start = (-ilen / 2.0).floor();
    let stop = (ilen / 2.0).floor();
    let count = (stop - start).ceil() as usize;
    // Exact `cos`/`sin` every ANCHOR samples and unit rotations in between (drift ~1e-15,
    // far below the complex64 rounding that follows); the trig calls dominated planning.
    const ANCHOR: usize = 16;
    let dtheta = 2.0 * PI * f / my_sr;
    let rot = Complex::new(dtheta.cos(), dtheta.sin());
    let dwin = 2.0 * PI / count as f64;
    let wrot = Complex::new(dwin.cos(), dwin.sin());
    let (mut z, mut wz) = (Complex::new(1.0, 0.0), Complex::new(1.0, 0.0));
    let mut l1 = 0.0f64;
    let sig: Vec<Complex<f64>> = (0..count)
        .map(|j| {
            if j % ANCHOR == 0 {
                let ang = (start + j as f64) * 2.0 * PI * f / my_sr;
                z = Complex::new(ang.cos(), ang.sin());
                let wa = 2.0 * PI * j as f64 / count as f64;
                wz = Complex::new(wa.cos(), wa.sin());
            } else {
                z *= rot;
                wz *= wrot;
            }
            // Periodic Hann, 0.5 - 0.5 cos(2 pi j / count).
            let c = z * (0.5 - 0.5 * wz.re);
            l1 += (c.re * c.re + c.im * c.im).sqrt();
            c
        })
        .collect();
    let l1 = if l1 < f64::MIN_POSITIVE { 1.0 } else { l1 };
    // pad_center, rounded to complex64 (the `dtype` of filters.wavelet), then `*= len / n_fft`.
    let lpad = (n_fft - count) / 2;
    let rescale = ilen / n_fft as f64;
    let mut buf = vec![Complex::<f64>::new(0.0, 0.0); n_fft];
    for (j, c) in sig.iter().enumerate() {
        let c32 = Complex::new((c.re / l1) as f32, (c.im / l1) as f32);
        buf[lpad + j] = Complex::new(c32.re as f64, c32.im as f64) * rescale;
    }
    fft.process(&mut buf);
    let row: Vec<Complex32> = buf[..n_fft / 2 + 1]
        .iter()
        .map(|c| Complex32::new(c.re as f32, c.im as f32))
        .collect();
    sparsify_row(&row, sparsity)
        .into_iter()
        .map(|(b, c)| {
            let c = Complex32::new((c.re as f64 * scale) as f32, (c.im as f64 * scale) as f32);
            (b, c)
        })
        .collect()
}

/// Bit-exact cache key of a plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PlanKey([u64; 10]);

impl PlanKey {
    fn new(sr: f64, hop: usize, p: &CqtParams) -> Self {
        Self([
            sr.to_bits(),
            hop as u64,
            p.fmin.to_bits(),
            p.n_bins as u64,
            p.bins_per_octave as u64,
            p.tuning.to_bits(),
            p.filter_scale.to_bits(),
            p.gamma.map_or(u64::MAX, f64::to_bits),
            p.sparsity.to_bits(),
            p.scale as u64,
        ])
    }
}

/// A planned CQT/VQT for one sample rate, hop and parameter set (independent of the signal).
pub struct CqtPlan {
    n_bins: usize,
    layout: MultirateLayout,
    octaves: Vec<Octave>,
    hop: usize,
}

impl CqtPlan {
    /// Plans `librosa.vqt(y, sr=sr, hop_length=hop, ...)` with `params`. The filters are built
    /// in parallel.
    pub fn new(sr: f64, hop: usize, params: &CqtParams) -> Result<Self> {
        let g = Geometry::new(sr, hop, params)?;
        let (freqs, alpha, sr) = (&g.freqs, &g.alpha, g.sr);
        let n_octaves = params.n_bins.div_ceil(params.bins_per_octave);
        let n_filters = params.bins_per_octave.min(params.n_bins);
        // Final `V /= sqrt(lengths)` at the (early-downsampled) rate, folded per bin.
        let (full_lengths, _) =
            wavelet_lengths(freqs, alpha, sr, params.filter_scale, params.gamma);

        // Octave i reads signal min(i, n_halvings) at rate sr / 2^signal, hop / 2^signal.
        struct Spec {
            lo: usize,
            my_sr: f64,
            n_fft: usize,
            lengths: Vec<f64>,
        }
        let specs: Vec<Spec> = (0..n_octaves)
            .map(|i| {
                let signal = i.min(g.layout.n_halvings);
                let my_sr = sr / (1u64 << signal) as f64;
                let hi = params.n_bins - n_filters * i;
                let lo = params.n_bins.saturating_sub(n_filters * (i + 1));
                let (lengths, _) = wavelet_lengths(
                    &freqs[lo..hi],
                    &alpha[lo..hi],
                    my_sr,
                    params.filter_scale,
                    params.gamma,
                );
                let max_len = lengths.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let n_fft = 2.0f64.powf(max_len.log2().ceil()) as usize;
                Spec {
                    lo,
                    my_sr,
                    n_fft,
                    lengths,
                }
            })
            .collect();
        let mut planner = FftPlanner::<f64>::new();
        let ffts: Vec<_> = specs
            .iter()
            .map(|s| planner.plan_fft_forward(s.n_fft))
            .collect();
        // Every filter of every octave, in parallel.
        let jobs: Vec<(usize, usize)> = specs
            .iter()
            .enumerate()
            .flat_map(|(i, s)| (0..s.lengths.len()).map(move |k| (i, k)))
            .collect();
        let rows: Vec<Vec<(u32, Complex32)>> = jobs
            .par_iter()
            .map(|&(i, k)| {
                let s = &specs[i];
                let bin = s.lo + k;
                let gain = (sr / s.my_sr).sqrt();
                let scale = if params.scale {
                    gain / full_lengths[bin].sqrt()
                } else {
                    gain
                };
                filter_fft(
                    freqs[bin],
                    s.lengths[k],
                    s.my_sr,
                    s.n_fft,
                    scale,
                    params.sparsity,
                    ffts[i].as_ref(),
                )
            })
            .collect();
        let mut rows = rows.into_iter();
        let octaves = specs
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let signal = i.min(g.layout.n_halvings);
                let mut starts = vec![0usize];
                let mut bins = Vec::new();
                let mut coefs = Vec::new();
                for _ in 0..s.lengths.len() {
                    for (b, c) in rows.next().expect("one row per filter") {
                        bins.push(b);
                        coefs.push(c);
                    }
                    starts.push(bins.len());
                }
                Octave {
                    stft: Stft::rectangular(s.n_fft, g.hop >> signal),
                    signal,
                    first_col: s.lo,
                    starts,
                    bins,
                    coefs,
                }
            })
            .collect();
        Ok(Self {
            n_bins: params.n_bins,
            layout: g.layout,
            octaves,
            hop,
        })
    }

    /// [`CqtPlan::new`] through a small process-wide cache (most recently used 16 plans),
    /// like librosa's memoised filter bases. The tuning takes one of ~100 histogram values,
    /// so batch extraction (e.g. EDGE's 5 s slices) mostly reuses plans; building one costs
    /// about as much as the CQT of 10–20 s of audio.
    pub fn cached(sr: f64, hop: usize, params: &CqtParams) -> Result<Arc<CqtPlan>> {
        type Cache = Mutex<Vec<(PlanKey, Arc<CqtPlan>)>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        const CAPACITY: usize = 16;
        let key = PlanKey::new(sr, hop, params);
        let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
        {
            let mut c = cache.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(i) = c.iter().position(|(k, _)| *k == key) {
                let entry = c.remove(i);
                let plan = entry.1.clone();
                c.push(entry);
                return Ok(plan);
            }
        }
        // Built outside the lock (two threads may build the same plan; both are identical).
        let plan = Arc::new(CqtPlan::new(sr, hop, params)?);
        let mut c = cache.lock().unwrap_or_else(|e| e.into_inner());
        if !c.iter().any(|(k, _)| *k == key) {
            if c.len() >= CAPACITY {
                c.remove(0);
            }
            c.push((key, plan.clone()));
        }
        Ok(plan)
    }

    pub fn n_bins(&self) -> usize {
        self.n_bins
    }

    pub fn layout(&self) -> MultirateLayout {
        self.layout
    }

    /// Number of output frames for `len` input samples (`1 + len / hop`, trimmed to the
    /// shortest octave as `__trim_stack` does).
    pub fn n_frames(&self, len: usize) -> usize {
        let mut lens = vec![len.div_ceil(self.layout.early_factor)];
        for i in 0..self.layout.n_halvings {
            lens.push(lens[i].div_ceil(2));
        }
        self.octaves
            .iter()
            .map(|o| n_frames(lens[o.signal], o.stft.hop()))
            .min()
            .unwrap_or(0)
    }

    /// [`MultirateLayout::prepare`] for this plan.
    pub fn prepare<'a>(&self, y: &'a [f32]) -> Result<OctaveSignals<'a>> {
        self.layout.prepare(y)
    }

    /// Whether `signals` (prepared for the same `sr`/`hop`, possibly another tuning) are the
    /// ones this plan reads.
    pub fn accepts(&self, signals: &OctaveSignals) -> bool {
        signals.layout == self.layout && signals.halved.len() == self.layout.n_halvings
    }

    /// `np.abs(librosa.vqt(y, ...))`, frame-major (`frames × n_bins`, bins ascending).
    pub fn magnitude(&self, y: &[f32]) -> Result<FrameMatrix> {
        let signals = self.prepare(y)?;
        Ok(self.magnitude_prepared(&signals))
    }

    /// [`CqtPlan::magnitude`] from signals made by [`CqtPlan::prepare`].
    ///
    /// # Panics
    /// If `!self.accepts(signals)`.
    pub fn magnitude_prepared(&self, signals: &OctaveSignals) -> FrameMatrix {
        assert!(
            self.accepts(signals),
            "octave signals from an incompatible CQT plan"
        );
        let t = self
            .octaves
            .iter()
            .map(|o| n_frames(signals.get(o.signal).len(), o.stft.hop()))
            .min()
            .unwrap_or(0);
        let cols = self.n_bins;
        let mut out = FrameMatrix::zeros(t, cols);
        out.par_row_blocks(64, |frames, rows| {
            let start = frames.start;
            for oct in &self.octaves {
                let y_oct = signals.get(oct.signal);
                oct.stft.for_each_frame(y_oct, frames.clone(), |ti, spec| {
                    let row = &mut rows[(ti - start) * cols..(ti - start + 1) * cols];
                    let dst = &mut row[oct.first_col..oct.first_col + oct.n_filters()];
                    for (k, o) in dst.iter_mut().enumerate() {
                        let (a, b) = (oct.starts[k], oct.starts[k + 1]);
                        let acc = sparse_dot(&oct.bins[a..b], &oct.coefs[a..b], spec);
                        *o = crate::stft::magnitude_of(acc);
                    }
                });
            }
        });
        out
    }

    /// Hop of the output frames.
    pub fn hop(&self) -> usize {
        self.hop
    }

    /// Number of non-zero basis coefficients (all octaves).
    pub fn basis_nnz(&self) -> usize {
        self.octaves.iter().map(|o| o.coefs.len()).sum()
    }
}

/// `np.abs(librosa.vqt(y, sr=sr, hop_length=hop, ...))` (`librosa.cqt` when `gamma = 0`),
/// frame-major.
pub fn cqt_magnitude(y: &[f32], sr: f64, hop: usize, params: &CqtParams) -> Result<FrameMatrix> {
    CqtPlan::new(sr, hop, params)?.magnitude(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn c1() {
        assert!((c1_hz() - 32.70319566257483).abs() < 1e-12);
    }

    #[test]
    fn pairwise_matches_sequential_for_small() {
        let v: Vec<f32> = (0..300).map(|i| (i as f32 * 0.37).sin().abs()).collect();
        let s = pairwise_sum_f32(&v);
        let exact: f64 = v.iter().map(|&x| x as f64).sum();
        assert!((s as f64 - exact).abs() < 1e-4);
    }

    #[test]
    fn no_early_downsampling_at_dance_rates() {
        for sr in [15360.0, 30720.0, 22050.0] {
            let p = CqtPlan::new(sr, 512, &CqtParams::chroma(0.0)).unwrap();
            assert_eq!(p.layout().early_factor, 1, "sr {sr}");
            assert_eq!(p.octaves.len(), 7);
        }
        let p = CqtPlan::new(44100.0, 512, &CqtParams::chroma(0.0)).unwrap();
        assert_eq!(p.layout().early_factor, 2);
        assert_eq!(p.layout().n_halvings, 6);
    }

    #[test]
    fn nyquist_is_checked() {
        assert!(CqtPlan::new(8000.0, 512, &CqtParams::chroma(0.0)).is_err());
    }

    #[test]
    fn sine_peaks_at_its_bin() {
        let sr = 15360.0;
        let f = 440.0;
        let y: Vec<f32> = (0..15360)
            .map(|i| (2.0 * PI * f * i as f64 / sr).sin() as f32)
            .collect();
        let c = cqt_magnitude(&y, sr, 512, &CqtParams::chroma(0.0)).unwrap();
        let row = c.row(15);
        let arg = (0..row.len())
            .max_by(|&a, &b| row[a].total_cmp(&row[b]))
            .unwrap();
        // A4 (MIDI 69) is 45 semitones above C1 (MIDI 24): bin 3 * 45 = 135.
        assert_eq!(arg, 135);
    }
}
