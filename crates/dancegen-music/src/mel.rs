//! Slaney mel scale and filterbank (`librosa.filters.mel(htk=False, norm='slaney')`), the
//! mel power spectrogram, and `power_to_db`.

use crate::stft::{FrameMatrix, Stft, power_of};

/// Slaney mel scale: linear below 1 kHz (200/3 Hz per mel), logarithmic above with a step of
/// ln(6.4)/27 per mel (Slaney's Auditory Toolbox, librosa `hz_to_mel(htk=False)`).
const F_SP: f64 = 200.0 / 3.0;
const MIN_LOG_HZ: f64 = 1000.0;
const MIN_LOG_MEL: f64 = MIN_LOG_HZ / F_SP;

fn log_step() -> f64 {
    6.4f64.ln() / 27.0
}

pub fn hz_to_mel(f: f64) -> f64 {
    if f >= MIN_LOG_HZ {
        MIN_LOG_MEL + (f / MIN_LOG_HZ).ln() / log_step()
    } else {
        f / F_SP
    }
}

pub fn mel_to_hz(m: f64) -> f64 {
    if m >= MIN_LOG_MEL {
        MIN_LOG_HZ * (log_step() * (m - MIN_LOG_MEL)).exp()
    } else {
        F_SP * m
    }
}

/// A sparse mel filterbank: for each filter, its first FFT bin and its weights.
#[derive(Clone, Debug)]
pub struct MelFilterbank {
    pub n_fft: usize,
    filters: Vec<(usize, Vec<f32>)>,
}

impl MelFilterbank {
    /// `librosa.filters.mel(sr=sr, n_fft=n_fft, n_mels=n_mels, fmin=0, fmax=sr/2)` in float32.
    pub fn slaney(sr: f64, n_fft: usize, n_mels: usize) -> Self {
        Self::slaney_range(sr, n_fft, n_mels, 0.0, sr / 2.0)
    }

    pub fn slaney_range(sr: f64, n_fft: usize, n_mels: usize, fmin: f64, fmax: f64) -> Self {
        let n_bins = n_fft / 2 + 1;
        let fft_freqs: Vec<f64> = (0..n_bins)
            .map(|i| i as f64 * (sr / 2.0) / (n_bins - 1) as f64)
            .collect();
        let (mmin, mmax) = (hz_to_mel(fmin), hz_to_mel(fmax));
        let n_pts = n_mels + 2;
        let mel_f: Vec<f64> = (0..n_pts)
            .map(|i| mel_to_hz(mmin + (mmax - mmin) * i as f64 / (n_pts - 1) as f64))
            .collect();
        let filters = (0..n_mels)
            .map(|m| {
                let (f0, f1, f2) = (mel_f[m], mel_f[m + 1], mel_f[m + 2]);
                let enorm = 2.0 / (f2 - f0);
                let w: Vec<f32> = fft_freqs
                    .iter()
                    .map(|&f| {
                        let lower = (f - f0) / (f1 - f0);
                        let upper = (f2 - f) / (f2 - f1);
                        (lower.min(upper).max(0.0) * enorm) as f32
                    })
                    .collect();
                let first = w.iter().position(|&v| v != 0.0).unwrap_or(0);
                let last = w.iter().rposition(|&v| v != 0.0).map_or(0, |l| l + 1);
                let last = last.max(first);
                (first, w[first..last].to_vec())
            })
            .collect();
        Self { n_fft, filters }
    }

    pub fn n_mels(&self) -> usize {
        self.filters.len()
    }

    /// Dense `(n_mels, 1 + n_fft/2)` weights, librosa's layout (for tests and inspection).
    pub fn dense(&self) -> Vec<Vec<f32>> {
        let n_bins = self.n_fft / 2 + 1;
        self.filters
            .iter()
            .map(|(first, w)| {
                let mut row = vec![0.0; n_bins];
                row[*first..first + w.len()].copy_from_slice(w);
                row
            })
            .collect()
    }

    /// Applies the filterbank to one power spectrum.
    pub fn apply(&self, spectrum: &[f32], out: &mut [f32]) {
        for (o, (first, w)) in out.iter_mut().zip(&self.filters) {
            let s = &spectrum[*first..first + w.len()];
            *o = s
                .iter()
                .zip(w)
                .map(|(&a, &b)| a as f64 * b as f64)
                .sum::<f64>() as f32;
        }
    }
}

/// Analysis parameters shared by the mel-based features (librosa defaults).
pub const N_FFT: usize = 2048;
pub const N_MELS: usize = 128;

/// `librosa.feature.melspectrogram(y, sr, n_fft=2048, hop_length=hop, n_mels=128, power=2)`,
/// frames × mels.
pub fn mel_power(y: &[f32], sr: f64, hop: usize) -> FrameMatrix {
    let stft = Stft::hann(N_FFT, hop);
    let fb = MelFilterbank::slaney(sr, N_FFT, N_MELS);
    mel_power_with(&stft, &fb, y)
}

pub fn mel_power_with(stft: &Stft, fb: &MelFilterbank, y: &[f32]) -> FrameMatrix {
    stft.map_frames(y, fb.n_mels(), |spec, row, power| {
        power.clear();
        power.extend(spec.iter().map(|&c| power_of(c)));
        fb.apply(power, row);
    })
}

/// `librosa.power_to_db(S, ref=1.0, amin=1e-10, top_db=80)` in place: 10·log10(max(amin, S)),
/// then clamped from below at (global max − top_db). The clamp is over the whole matrix, so a
/// slice of a song can differ from the same frames of the full song.
pub fn power_to_db_in_place(s: &mut [f32], top_db: Option<f32>) {
    use rayon::prelude::*;
    const AMIN: f32 = 1e-10;
    const BLOCK: usize = 1 << 14;
    let max = s
        .par_chunks_mut(BLOCK)
        .map(|c| {
            let mut m = f32::NEG_INFINITY;
            for v in c.iter_mut() {
                *v = 10.0 * v.max(AMIN).log10();
                m = m.max(*v);
            }
            m
        })
        .reduce(|| f32::NEG_INFINITY, f32::max);
    if let Some(top) = top_db {
        let floor = max - top;
        s.par_chunks_mut(BLOCK).for_each(|c| {
            for v in c {
                *v = v.max(floor);
            }
        });
    }
}
