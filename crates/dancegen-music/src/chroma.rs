//! Chroma features: `librosa.feature.chroma_cens`, `chroma_cqt` and `chroma_stft` (librosa 0.11).
//!
//! Why it matters: columns 21–32 of the 35-dim dance-conditioning feature (EDGE, FACT, Lodge,
//! FineDance, TCDiff) are `chroma_cens(y, sr, hop_length=512, n_chroma=12)`; TCDiff's 438-dim set
//! also uses `chroma_cqt`. `chroma_stft` is here because the fixtures pin it too.
//!
//! What has to match (see also `tuning.rs` and `cqt.rs`):
//! - tuning estimated on `y` (`estimate_tuning(bins_per_octave=36)`) and applied to the CQT's
//!   `fmin` only; `cq_to_chroma` gets the *untuned* C1, so C..B map to CQT bins
//!   `3c-1, 3c, 3c+1 (mod 36)` of every octave, no roll;
//! - `chroma_cqt(norm=None)` = that 0/1 folding of `|CQT|` (252 bins → 12);
//! - CENS: per-frame L1 normalisation (frames with norm < float32 tiny untouched), quantisation
//!   `Σ 0.25·[x > t]`, t ∈ {0.4, 0.2, 0.1, 0.05} compared in float32 (numpy casts the Python
//!   float to the array's float32), temporal smoothing with a symmetric 43-point Hann
//!   (`win_len_smooth + 2`, zero end points) normalised to sum 1, zero-padded like
//!   `scipy.ndimage.convolve(mode='constant')`, then L2 normalisation (silent frames stay 0);
//! - `chroma_stft`: power STFT (n_fft 2048, Hann, centred zero pad), tuning estimated on that
//!   power spectrogram with 12 bins per octave, `filters.chroma` (Gaussian bumps, per-column L2,
//!   octave weighting around C5 ± 2 octaves, rolled to start at C), per-frame max normalisation.
//!
//! All outputs are frame-major `frames × n_chroma` float32 with `1 + len(y) / hop` frames.

use rayon::prelude::*;

use crate::cqt::{CqtParams, CqtPlan, MultirateLayout, c1_hz};
use crate::error::{MusicError, Result};
use crate::stft::{FrameMatrix, Stft};
use crate::tuning::{estimate_tuning, estimate_tuning_from_spectrogram};

/// `librosa.hz_to_midi(f)` = `12 * (log2(f) - log2(440)) + 69`.
fn hz_to_midi(f: f64) -> f64 {
    12.0 * (f.log2() - 440.0f64.log2()) + 69.0
}

/// `librosa.filters.cq_to_chroma(n_input, bins_per_octave, n_chroma, fmin, base_c=True)` with no
/// window: a 0/1 matrix, stored as the chroma index of every CQT bin.
#[derive(Clone, Debug, PartialEq)]
pub struct CqToChroma {
    pub n_chroma: usize,
    /// `map[j]` = the chroma bin CQT bin `j` is added to.
    pub map: Vec<usize>,
}

impl CqToChroma {
    pub fn new(n_input: usize, bins_per_octave: usize, n_chroma: usize, fmin: f64) -> Result<Self> {
        if n_chroma == 0 || bins_per_octave == 0 || !bins_per_octave.is_multiple_of(n_chroma) {
            return Err(MusicError::InvalidParameter(format!(
                "incompatible CQ merge: bins_per_octave {bins_per_octave} must be a multiple \
                 of n_chroma {n_chroma}"
            )));
        }
        let n_merge = bins_per_octave / n_chroma;
        // np.roll(eye-repeat, -(n_merge // 2), axis=1): column jj takes old column jj + r.
        let r = n_merge / 2;
        let midi_0 = hz_to_midi(fmin).rem_euclid(12.0);
        // base_c=True: roll = midi_0, scaled to n_chroma, numpy round (half to even).
        let roll = (midi_0 * (n_chroma as f64 / 12.0)).round_ties_even() as i64;
        let map = (0..n_input)
            .map(|j| {
                let jj = j % bins_per_octave;
                let row = ((jj + r) % bins_per_octave) / n_merge;
                (row as i64 + roll).rem_euclid(n_chroma as i64) as usize
            })
            .collect();
        Ok(Self { n_chroma, map })
    }

    /// Dense `(n_chroma, n_input)` matrix, librosa's layout.
    pub fn dense(&self) -> Vec<Vec<f32>> {
        let mut m = vec![vec![0.0f32; self.map.len()]; self.n_chroma];
        for (j, &c) in self.map.iter().enumerate() {
            m[c][j] = 1.0;
        }
        m
    }

    /// `cq_to_chr @ C` for one frame (`out` has `n_chroma` values; sums in float64).
    pub fn apply(&self, cqt_row: &[f32], out: &mut [f32], scratch: &mut Vec<f64>) {
        scratch.clear();
        scratch.resize(self.n_chroma, 0.0);
        for (&c, &v) in self.map.iter().zip(cqt_row) {
            scratch[c] += v as f64;
        }
        for (o, &v) in out.iter_mut().zip(scratch.iter()) {
            *o = v as f32;
        }
    }

    /// Folds a frame-major CQT magnitude (`frames × n_input`) into `frames × n_chroma`.
    pub fn fold(&self, cqt: &FrameMatrix) -> FrameMatrix {
        assert_eq!(cqt.cols, self.map.len(), "CQT bins vs cq_to_chroma inputs");
        let mut out = FrameMatrix::zeros(cqt.rows, self.n_chroma);
        if self.n_chroma == 0 {
            return out;
        }
        out.data
            .par_chunks_mut(self.n_chroma)
            .enumerate()
            .for_each_init(Vec::new, |scratch, (t, row)| {
                self.apply(cqt.row(t), row, scratch)
            });
        out
    }
}

/// `librosa.util.normalize(S, norm=norm, axis=-2)` on every frame of a float32 matrix, in place.
///
/// `norm` is a positive `p` or `f64::INFINITY` (max norm). Frames whose norm is below the
/// float32 `tiny` are left as they are (`fill=None`). Norms are computed in float64.
pub fn normalize_frames(m: &mut FrameMatrix, norm: f64) {
    assert!(norm > 0.0, "norm must be positive or infinite");
    if m.cols == 0 {
        return;
    }
    let tiny = f32::MIN_POSITIVE as f64;
    m.data.par_chunks_mut(m.cols).for_each(|row| {
        let length = if norm == f64::INFINITY {
            row.iter().map(|v| v.abs() as f64).fold(0.0, f64::max)
        } else if norm == 1.0 {
            row.iter().map(|v| v.abs() as f64).sum::<f64>()
        } else if norm == 2.0 {
            row.iter()
                .map(|&v| (v as f64) * (v as f64))
                .sum::<f64>()
                .sqrt()
        } else {
            row.iter()
                .map(|v| (v.abs() as f64).powf(norm))
                .sum::<f64>()
                .powf(1.0 / norm)
        };
        let length = if length < tiny { 1.0 } else { length };
        for v in row.iter_mut() {
            *v = (*v as f64 / length) as f32;
        }
    });
}

/// Options of `librosa.feature.chroma_cqt` (the `cqt_mode='full'`, no-window path).
#[derive(Clone, Debug, PartialEq)]
pub struct ChromaCqtParams {
    pub n_chroma: usize,
    pub n_octaves: usize,
    pub bins_per_octave: usize,
    /// Untuned lowest CQT frequency; `None` = C1 (also what `cq_to_chroma` is told).
    pub fmin: Option<f64>,
    /// `None` = `estimate_tuning(y, sr, bins_per_octave)`.
    pub tuning: Option<f64>,
    /// `None`, a positive p, or `f64::INFINITY` (librosa's default for `chroma_cqt`).
    pub norm: Option<f64>,
}

impl Default for ChromaCqtParams {
    fn default() -> Self {
        Self {
            n_chroma: 12,
            n_octaves: 7,
            bins_per_octave: 36,
            fmin: None,
            tuning: None,
            norm: Some(f64::INFINITY),
        }
    }
}

/// `librosa.feature.chroma_cqt(y=y, sr=sr, hop_length=hop, tuning=tuning, norm=norm)`: 12
/// chroma from a 7-octave, 36-bins-per-octave CQT from C1. `tuning = None` estimates it; `norm`
/// is `None`, a positive p, or `Some(f64::INFINITY)` (librosa's default).
pub fn chroma_cqt(
    y: &[f32],
    sr: f64,
    hop: usize,
    tuning: Option<f64>,
    norm: Option<f64>,
) -> Result<FrameMatrix> {
    chroma_cqt_with(
        y,
        sr,
        hop,
        &ChromaCqtParams {
            tuning,
            norm,
            ..ChromaCqtParams::default()
        },
    )
}

/// [`chroma_cqt`] with every option.
pub fn chroma_cqt_with(
    y: &[f32],
    sr: f64,
    hop: usize,
    params: &ChromaCqtParams,
) -> Result<FrameMatrix> {
    let bpo = params.bins_per_octave;
    match params.tuning {
        Some(t) => chroma_cqt_inner(y, sr, hop, params, || t),
        None => chroma_cqt_inner(y, sr, hop, params, || estimate_tuning(y, sr, bpo)),
    }
}

/// The CQT chroma with the tuning supplied by `estimate` (ignoring `params.tuning`).
///
/// The octave-halving cascade does not depend on the tuning (only the filters do), so the
/// signal is resampled while `estimate` runs and the tuned filters are built; it is redone only
/// if the tuned layout differs (a cutoff right at a power-of-two boundary).
fn chroma_cqt_inner(
    y: &[f32],
    sr: f64,
    hop: usize,
    params: &ChromaCqtParams,
    estimate: impl FnOnce() -> f64 + Send,
) -> Result<FrameMatrix> {
    let fmin = params.fmin.unwrap_or_else(c1_hz);
    let bpo = params.bins_per_octave;
    let fold = CqToChroma::new(params.n_octaves * bpo, bpo, params.n_chroma, fmin)?;
    let cqt_params = |tuning| CqtParams {
        fmin,
        n_bins: params.n_octaves * bpo,
        bins_per_octave: bpo,
        tuning,
        ..CqtParams::default()
    };
    let untuned = MultirateLayout::new(sr, hop, &cqt_params(0.0))?;
    let (signals, plan) = rayon::join(
        || untuned.prepare(y),
        || CqtPlan::cached(sr, hop, &cqt_params(estimate())),
    );
    let plan = plan?;
    let signals = match signals {
        Ok(s) if plan.accepts(&s) => s,
        _ => plan.prepare(y)?,
    };
    let c = plan.magnitude_prepared(&signals);
    let mut chroma = fold.fold(&c);
    if let Some(norm) = params.norm {
        normalize_frames(&mut chroma, norm);
    }
    Ok(chroma)
}

/// `librosa.feature.chroma_cqt(C=cqt, bins_per_octave=bpo, n_chroma, fmin, norm=None)` on a
/// frame-major CQT magnitude (no threshold, no normalisation).
pub fn chroma_from_cqt(
    cqt: &FrameMatrix,
    bins_per_octave: usize,
    n_chroma: usize,
    fmin: Option<f64>,
) -> Result<FrameMatrix> {
    let fold = CqToChroma::new(
        cqt.cols,
        bins_per_octave,
        n_chroma,
        fmin.unwrap_or_else(c1_hz),
    )?;
    Ok(fold.fold(cqt))
}

/// CENS quantisation steps and weights.
const QUANT_STEPS: [f32; 4] = [0.4, 0.2, 0.1, 0.05];
const QUANT_WEIGHT: f32 = 0.25;
/// `chroma_cens` default `win_len_smooth`.
pub const CENS_WIN_LEN_SMOOTH: usize = 41;

/// `scipy.signal.get_window('hann', n, fftbins=False)` / `sum`: symmetric Hann, unit sum.
fn smoothing_window(n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![1.0];
    }
    // general_cosine: 0.5 + 0.5 * cos(linspace(-pi, pi, n)).
    let fac = crate::tuning::linspace(-std::f64::consts::PI, std::f64::consts::PI, n);
    let w: Vec<f64> = fac.iter().map(|&x| 0.5 + 0.5 * x.cos()).collect();
    let s: f64 = w.iter().sum();
    w.into_iter().map(|v| v / s).collect()
}

/// The CENS post-processing of `chroma_cens` applied to a raw chroma (`chroma_cqt(norm=None)`,
/// frame-major): L1 normalise, quantise, smooth over `win_len_smooth + 2` frames (`None` = no
/// smoothing), L2 normalise.
pub fn cens_from_chroma(chroma: &FrameMatrix, win_len_smooth: Option<usize>) -> FrameMatrix {
    let (t, nc) = (chroma.rows, chroma.cols);
    let mut x = chroma.clone();
    normalize_frames(&mut x, 1.0);
    for v in &mut x.data {
        let mut q = 0.0f32;
        for s in QUANT_STEPS {
            if *v > s {
                q += QUANT_WEIGHT;
            }
        }
        *v = q;
    }
    let mut cens = match win_len_smooth {
        Some(w) if w > 0 => {
            let win = smoothing_window(w + 2);
            let half = (win.len() / 2) as isize;
            // scipy.ndimage.convolve with mode='constant' (cval 0), origin 0 (odd length);
            // the window is symmetric, so convolution = correlation with the reversed window.
            let wr: Vec<f64> = win.iter().rev().copied().collect();
            let mut out = FrameMatrix::zeros(t, nc);
            out.data
                .par_chunks_mut(nc)
                .enumerate()
                .for_each(|(ti, row)| {
                    for (c, o) in row.iter_mut().enumerate() {
                        let mut acc = 0.0f64;
                        for (k, &wk) in wr.iter().enumerate() {
                            let src = ti as isize + k as isize - half;
                            if wk != 0.0 && src >= 0 && (src as usize) < t {
                                acc += wk * x.data[src as usize * nc + c] as f64;
                            }
                        }
                        *o = acc as f32;
                    }
                });
            out
        }
        _ => x,
    };
    normalize_frames(&mut cens, 2.0);
    cens
}

/// `librosa.feature.chroma_cens(y=y, sr=sr, hop_length=hop, n_chroma=n_chroma)`: tuning
/// estimated, 7-octave 36-bins-per-octave CQT from C1, 41-frame smoothing, L2 norm.
pub fn chroma_cens(y: &[f32], sr: f64, hop: usize, n_chroma: usize) -> Result<FrameMatrix> {
    chroma_cens_with_tuning(y, sr, hop, n_chroma, None)
}

/// [`chroma_cens`] with a given tuning (`None` = estimated, as librosa's default).
pub fn chroma_cens_with_tuning(
    y: &[f32],
    sr: f64,
    hop: usize,
    n_chroma: usize,
    tuning: Option<f64>,
) -> Result<FrameMatrix> {
    let raw = chroma_cqt_with(
        y,
        sr,
        hop,
        &ChromaCqtParams {
            n_chroma,
            tuning,
            norm: None,
            ..ChromaCqtParams::default()
        },
    )?;
    Ok(cens_from_chroma(&raw, Some(CENS_WIN_LEN_SMOOTH)))
}

/// [`chroma_cens`] whose tuning comes from `estimate`, run while the CQT's octave cascade is
/// resampled. The 35-dim pipeline uses this to take the tuning from the STFT it computes for
/// the mel spectrogram anyway (`estimate_tuning` runs the very same 2048/512 Hann STFT).
pub fn chroma_cens_with_estimator(
    y: &[f32],
    sr: f64,
    hop: usize,
    n_chroma: usize,
    estimate: impl FnOnce() -> f64 + Send,
) -> Result<FrameMatrix> {
    let params = ChromaCqtParams {
        n_chroma,
        norm: None,
        ..ChromaCqtParams::default()
    };
    let raw = chroma_cqt_inner(y, sr, hop, &params, estimate)?;
    Ok(cens_from_chroma(&raw, Some(CENS_WIN_LEN_SMOOTH)))
}

/// `librosa.filters.chroma(sr=sr, n_fft=n_fft, n_chroma=n_chroma, tuning=tuning)` (ctroct 5,
/// octwidth 2, column L2 norm, base C), dense `(n_chroma, 1 + n_fft/2)` float32.
pub fn chroma_filterbank(sr: f64, n_fft: usize, n_chroma: usize, tuning: f64) -> Vec<Vec<f32>> {
    let nc = n_chroma as f64;
    let (ctroct, octwidth) = (5.0, 2.0);
    // np.linspace(0, sr, n_fft, endpoint=False)[1:] -> hz_to_octs -> * n_chroma.
    let step = sr / n_fft as f64;
    let a440 = 440.0 * 2.0f64.powf(tuning / nc);
    let mut frqbins: Vec<f64> = (1..n_fft)
        .map(|i| nc * ((i as f64 * step) / (a440 / 16.0)).log2())
        .collect();
    frqbins.insert(0, frqbins[0] - 1.5 * nc);
    let mut binwidth: Vec<f64> = frqbins.windows(2).map(|w| (w[1] - w[0]).max(1.0)).collect();
    binwidth.push(1.0);
    let n_chroma2 = (nc / 2.0).round_ties_even();
    // wts[c][j], column-normalised.
    let mut wts = vec![vec![0.0f64; n_fft]; n_chroma];
    for j in 0..n_fft {
        for (c, row) in wts.iter_mut().enumerate() {
            let d = (frqbins[j] - c as f64 + n_chroma2 + 10.0 * nc).rem_euclid(nc) - n_chroma2;
            row[j] = (-0.5 * (2.0 * d / binwidth[j]).powi(2)).exp();
        }
        let mut ss = 0.0f64;
        for row in wts.iter() {
            ss += row[j] * row[j];
        }
        let len = ss.sqrt();
        let len = if len < f64::MIN_POSITIVE { 1.0 } else { len };
        let oct_w = (-0.5 * ((frqbins[j] / nc - ctroct) / octwidth).powi(2)).exp();
        for row in wts.iter_mut() {
            row[j] = row[j] / len * oct_w;
        }
    }
    // base_c: np.roll(wts, -3 * (n_chroma // 12), axis=0).
    let shift = 3 * (n_chroma / 12);
    let n_keep = 1 + n_fft / 2;
    (0..n_chroma)
        .map(|c| {
            wts[(c + shift) % n_chroma][..n_keep]
                .iter()
                .map(|&v| v as f32)
                .collect()
        })
        .collect()
}

/// `librosa.feature.chroma_stft(y=y, sr=sr, hop_length=hop)`: n_fft 2048, 12 chroma, tuning
/// estimated on the power spectrogram, max-normalised per frame.
pub fn chroma_stft(y: &[f32], sr: f64, hop: usize) -> FrameMatrix {
    chroma_stft_with_tuning(y, sr, hop, None)
}

/// [`chroma_stft`] with a given tuning (`None` = estimated on the power spectrogram).
pub fn chroma_stft_with_tuning(y: &[f32], sr: f64, hop: usize, tuning: Option<f64>) -> FrameMatrix {
    const N_FFT: usize = 2048;
    const N_CHROMA: usize = 12;
    let power = Stft::hann(N_FFT, hop).power(y);
    let tuning = tuning.unwrap_or_else(|| estimate_tuning_from_spectrogram(&power, sr, N_CHROMA));
    let fb = chroma_filterbank(sr, N_FFT, N_CHROMA, tuning);
    let mut out = FrameMatrix::zeros(power.rows, N_CHROMA);
    out.data
        .par_chunks_mut(N_CHROMA)
        .enumerate()
        .for_each(|(t, row)| {
            let s = power.row(t);
            for (o, w) in row.iter_mut().zip(&fb) {
                *o = w
                    .iter()
                    .zip(s)
                    .map(|(&a, &b)| a as f64 * b as f64)
                    .sum::<f64>() as f32;
            }
        });
    normalize_frames(&mut out, f64::INFINITY);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cq_to_chroma_folds_c_around_bin_zero() {
        let m = CqToChroma::new(252, 36, 12, c1_hz()).unwrap();
        assert_eq!(m.map[0], 0);
        assert_eq!(m.map[1], 0);
        assert_eq!(m.map[35], 0);
        assert_eq!(m.map[2], 1);
        assert_eq!(m.map[34], 11);
        assert_eq!(m.map[36 + 35], 0);
        assert!(CqToChroma::new(252, 36, 5, c1_hz()).is_err());
    }

    #[test]
    fn smoothing_window_is_symmetric_unit_sum() {
        let w = smoothing_window(43);
        assert_eq!(w.len(), 43);
        assert_eq!(w[0], 0.0);
        assert_eq!(w[42], 0.0);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((w[10] - w[32]).abs() < 1e-15);
    }

    #[test]
    fn silent_frames_stay_zero() {
        let y = vec![0.0f32; 15360];
        let c = chroma_cens(&y, 15360.0, 512, 12).unwrap();
        assert_eq!(c.rows, 31);
        assert!(c.data.iter().all(|&v| v == 0.0));
    }
}
