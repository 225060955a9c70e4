//! TCDiff / TCDiff++'s 438-dim music features (`shared/reference/anchors.md` B.2).
//!
//! Reference: `Da1yuqin/TCDiff:data/data_preprocess/dataset_utils.py::wav_processing` (commit
//! e4f5880) drives a `FeatureExtractor` from `_preprocess_wav.py`, a file that is not in the
//! public snapshot we could read; its method names and signatures are those of
//! `lisiyao21/Bailando:extractor.py` (commit 9997e75), which is taken as its content. In
//! librosa 0.11 keyword form, per audio file:
//!
//! | step | call | columns |
//! |---|---|---|
//! | load | `y = librosa.load(path, sr=30720)` (60 fps × hop 512) | |
//! | mel dB | `power_to_db(melspectrogram(y=y, sr=sr), ref=np.max)` (n_fft 2048, 128 mels, top_db 80) | |
//! | MFCC | `mfcc(S=mel_db)` (20, DCT-II ortho) | 0–19 |
//! | ΔMFCC | `delta(mfcc, width=3)` (Savitzky-Golay, order 1, 'interp' edges) | 20–39 |
//! | HPSS | `y_h, y_p = effects.hpss(y)` (kernel 31, power 2, margin 1) | |
//! | chroma | `chroma_cqt(y=y_h, sr=sr, n_octaves=7)` (TCDiff: 7 if SR == 30720 else 5) | 40–51 |
//! | onset | `env = onset_strength(y=y_p, sr=sr, aggregate=np.median)` | 52 |
//! | beats | `_, beats = beat_track(onset_envelope=env, sr=sr)` (start_bpm 120, tightness 100, trim) → one-hot | 53 |
//! | tempogram | `tempogram(onset_envelope=env, sr=sr)` (win_length 384, Hann, inf-norm) | 54–437 |
//!
//! concatenated in that order along the feature axis and transposed to frames × 438 (the repo
//! saves float64 and feeds `torch.float32`; here float32). Every block has `1 + len/512` frames.
//!
//! Deviations of the published code that this port does not reproduce (documented, deliberate):
//! * TCDiff's `wav_processing` reshapes the envelope to `(1, T)` *before* the tempogram and
//!   beat calls. Run that way under librosa 0.11, `tempogram` returns `(1, 384, T)` (the
//!   concatenation then fails) and `beat_track` raises (`sparse=True` needs a 1-D input); the
//!   pinned librosa 0.9.2 has multichannel tempograms too (not run here: UNVERIFIED). So the
//!   released features cannot have come from that exact line (the function returns early when
//!   a precomputed `.npy` exists). Bailando and the other copies of this extractor
//!   (`load_music` in the Bailando-derived repos) reshape only *after* those calls and pass
//!   the 1-D envelope, which is what is implemented.
//! * TCDiff pins librosa 0.9.2 (resampy resampling by default); the crate contract is librosa
//!   0.11 (`soxr_hq`), which changes the loaded signal, not the pipeline.

use crate::HOP;
use crate::beat;
use crate::chroma;
use crate::delta::delta;
use crate::error::{MusicError, Result};
use crate::hpss::{HpssParams, hpss};
use crate::mel::{self, N_FFT};
use crate::mfcc::mfcc_from_mel_db;
use crate::onset::{PeakPick, peak_pick};
use crate::stft::FrameMatrix;
use crate::tempo::{self, TEMPOGRAM_WIN_LENGTH};

/// Width of the TCDiff feature vector: 20 + 20 + 12 + 1 + 1 + 384.
pub const TCDIFF438_DIM: usize = 438;
/// TCDiff's sample rate: 60 fps × hop 512.
pub const TCDIFF_SR: u32 = 30720;
/// TCDiff's frame rate.
pub const TCDIFF_FPS: u32 = 60;
/// First column of each block.
pub const MFCC_COL: usize = 0;
pub const DELTA_COL: usize = 20;
pub const CHROMA_COL: usize = 40;
pub const ONSET_COL: usize = 52;
pub const BEAT_COL: usize = 53;
pub const TEMPOGRAM_COL: usize = 54;
/// `librosa.feature.delta(mfcc, width=3)`.
pub const DELTA_WIDTH: usize = 3;
/// `beat_track` defaults TCDiff relies on.
pub const BEAT_START_BPM: f64 = 120.0;
pub const BEAT_TIGHTNESS: f64 = 100.0;
/// Bailando's `peak_pick(onset_env, 3, 3, 3, 5, 0.5, 10)` (computed by the extractor next to
/// the beats and discarded by TCDiff; see [`Tcdiff438Parts::onset_peaks`]).
pub const BAILANDO_PEAKS: PeakPick = PeakPick {
    pre_max: 3,
    post_max: 3,
    pre_avg: 3,
    post_avg: 5,
    delta: 0.5,
    wait: 10,
};

/// The blocks of the 438-dim feature before concatenation (all frame-major).
#[derive(Clone, Debug)]
pub struct Tcdiff438Parts {
    pub mfcc: FrameMatrix,
    pub mfcc_delta: FrameMatrix,
    pub chroma: FrameMatrix,
    /// Median-aggregated onset strength of the percussive signal.
    pub onset_env: Vec<f32>,
    pub tempo_bpm: f64,
    pub beat_frames: Vec<usize>,
    pub tempogram: FrameMatrix,
}

impl Tcdiff438Parts {
    /// Bailando's onset peaks, `peak_pick(env, 3, 3, 3, 5, 0.5, 10)` on the raw percussive
    /// envelope: the extractor's second output, which the 438-dim vector leaves out.
    pub fn onset_peaks(&self) -> Vec<usize> {
        peak_pick(&self.onset_env, &BAILANDO_PEAKS)
    }

    /// Concatenates the blocks into frames × 438 in TCDiff's column order.
    pub fn assemble(&self) -> FrameMatrix {
        let t = self.onset_env.len();
        let mut out = FrameMatrix::zeros(t, TCDIFF438_DIM);
        for i in 0..t {
            let row = out.row_mut(i);
            row[MFCC_COL..DELTA_COL].copy_from_slice(self.mfcc.row(i));
            row[DELTA_COL..CHROMA_COL].copy_from_slice(self.mfcc_delta.row(i));
            row[CHROMA_COL..ONSET_COL].copy_from_slice(self.chroma.row(i));
            row[ONSET_COL] = self.onset_env[i];
            row[TEMPOGRAM_COL..].copy_from_slice(self.tempogram.row(i));
        }
        for &b in &self.beat_frames {
            out.row_mut(b)[BEAT_COL] = 1.0;
        }
        out
    }
}

/// `librosa.power_to_db(S, ref=np.max, amin=1e-10, top_db=80)` in place, in float32 as librosa
/// computes it: `10·log10(max(amin, S)) − 10·log10(max(amin, max S))`, then clamped from below
/// at (max − 80).
pub fn power_to_db_ref_max_in_place(s: &mut [f32]) {
    const AMIN: f32 = 1e-10;
    const TOP_DB: f32 = 80.0;
    let ref_value = s.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let ref_db = 10.0 * ref_value.max(AMIN).log10();
    let mut max = f32::NEG_INFINITY;
    for v in s.iter_mut() {
        *v = 10.0 * v.max(AMIN).log10() - ref_db;
        max = max.max(*v);
    }
    let floor = max - TOP_DB;
    for v in s.iter_mut() {
        *v = v.max(floor);
    }
}

/// `librosa.onset.onset_strength(S=mel_db, aggregate=np.median)` (lag 1, no max filter,
/// centred): per frame the median over bands of `max(0, S[t] − S[t−1])` (for an even number of
/// bands the mean of the two middle values, in float32 as numpy does), delayed by
/// `1 + n_fft/(2·hop)` frames (zeros in front) and truncated to the spectrogram's frame count.
///
/// `mel_db` is `power_to_db(mel power)` (ref 1, top_db 80), frames × bands.
pub fn onset_strength_median(mel_db: &FrameMatrix, n_fft: usize, hop: usize) -> Vec<f32> {
    const LAG: usize = 1;
    let t = mel_db.rows;
    let bands = mel_db.cols;
    let pad = LAG + n_fft / (2 * hop);
    let mut env = vec![0f32; t];
    if bands == 0 {
        return env;
    }
    let mut diff = vec![0f32; bands];
    for i in LAG..t {
        let out = i - LAG + pad;
        if out >= t {
            break;
        }
        for ((d, &a), &b) in diff.iter_mut().zip(mel_db.row(i)).zip(mel_db.row(i - LAG)) {
            *d = (a - b).max(0.0);
        }
        env[out] = median_in_place(&mut diff);
    }
    env
}

/// `np.median` of a float32 slice (reorders it).
fn median_in_place(x: &mut [f32]) -> f32 {
    let n = x.len();
    let mid = n / 2;
    let (_, &mut hi, _) = x.select_nth_unstable_by(mid, f32::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        let lo = x[..mid].iter().copied().fold(f32::NEG_INFINITY, f32::max);
        (lo + hi) / 2.0
    }
}

/// `librosa.onset.onset_strength(y=y, sr=sr, hop_length=hop, aggregate=np.median)`: mel power
/// (n_fft 2048, 128 Slaney mels) → `power_to_db` (ref 1, top_db 80) → [`onset_strength_median`].
pub fn onset_strength_median_from_signal(y: &[f32], sr: f64, hop: usize) -> Vec<f32> {
    let mut db = mel::mel_power(y, sr, hop);
    mel::power_to_db_in_place(&mut db.data, Some(80.0));
    onset_strength_median(&db, N_FFT, hop)
}

/// Computes every block of the 438-dim feature of `y` (mono, at `sr`).
///
/// TCDiff always runs at [`TCDIFF_SR`]; other rates are accepted (chroma then uses 5 octaves,
/// as TCDiff's `octave=7 if SR == 15360 * 2 else 5` does).
pub fn tcdiff438_parts(y: &[f32], sr: f64) -> Result<Tcdiff438Parts> {
    if sr.is_nan() || sr <= 0.0 {
        return Err(MusicError::InvalidParameter(format!(
            "sample rate must be positive, got {sr}"
        )));
    }
    // The MFCC branch and the HPSS branch are independent: run them side by side.
    let (mfccs, hpss_branch) = rayon::join(
        || -> Result<(FrameMatrix, FrameMatrix)> {
            let mut db = mel::mel_power(y, sr, HOP);
            power_to_db_ref_max_in_place(&mut db.data);
            let mfcc = mfcc_from_mel_db(&db, 20);
            let d = delta(&mfcc, DELTA_WIDTH, 1)?;
            Ok((mfcc, d))
        },
        || -> Result<_> {
            let (y_h, y_p) = hpss(y, N_FFT, HOP, &HpssParams::default())?;
            let n_octaves = if sr == TCDIFF_SR as f64 { 7 } else { 5 };
            let (chroma, env) = rayon::join(
                || {
                    let params = chroma::ChromaCqtParams {
                        n_octaves,
                        ..chroma::ChromaCqtParams::default()
                    };
                    chroma::chroma_cqt_with(&y_h, sr, HOP, &params)
                },
                || onset_strength_median_from_signal(&y_p, sr, HOP),
            );
            let chroma = chroma?;
            let (tempogram, (tempo_bpm, beat_frames)) = rayon::join(
                || tempo::tempogram(&env, TEMPOGRAM_WIN_LENGTH),
                || beat::beat_track(&env, sr, HOP, BEAT_START_BPM, BEAT_TIGHTNESS, true),
            );
            Ok((chroma, env, tempogram, tempo_bpm, beat_frames))
        },
    );
    let (mfcc, mfcc_delta) = mfccs?;
    let (chroma, onset_env, tempogram, tempo_bpm, beat_frames) = hpss_branch?;
    let t = onset_env.len();
    for (name, rows) in [
        ("mfcc", mfcc.rows),
        ("delta", mfcc_delta.rows),
        ("chroma", chroma.rows),
        ("tempogram", tempogram.rows),
    ] {
        if rows != t {
            return Err(MusicError::InvalidParameter(format!(
                "internal frame-count mismatch: {name} has {rows} frames, onset envelope {t}"
            )));
        }
    }
    Ok(Tcdiff438Parts {
        mfcc,
        mfcc_delta,
        chroma,
        onset_env,
        tempo_bpm,
        beat_frames,
        tempogram,
    })
}

/// TCDiff's 438-dim features of `y` at `sr` (30720 for TCDiff): frames × 438 in the reference
/// column order (see the module docs).
///
/// Errors when the signal has fewer than 3 frames (`delta(width=3)` needs 3; ≥ 1024 samples).
pub fn tcdiff438(y: &[f32], sr: f64) -> Result<FrameMatrix> {
    Ok(tcdiff438_parts(y, sr)?.assemble())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_matches_numpy_conventions() {
        assert_eq!(median_in_place(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median_in_place(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median_in_place(&mut [0.0, 0.0, 5.0, 0.0]), 0.0);
    }

    #[test]
    fn ref_max_db_is_zero_at_the_peak_and_clamped() {
        let mut s = vec![1.0f32, 0.1, 1e-12, 0.0];
        power_to_db_ref_max_in_place(&mut s);
        assert_eq!(s[0], 0.0);
        assert!((s[1] + 10.0).abs() < 1e-5);
        assert_eq!(s[2], -80.0);
        assert_eq!(s[3], -80.0);
    }

    #[test]
    fn short_signals_error_or_work_without_panicking() {
        let sr = TCDIFF_SR as f64;
        for len in [0usize, 100, 1023] {
            assert!(tcdiff438(&vec![0.1; len], sr).is_err(), "len {len}");
        }
        for len in [1024usize, 5000] {
            let y: Vec<f32> = (0..len).map(|i| ((i * 7919) % 13) as f32 * 0.01).collect();
            let f = tcdiff438(&y, sr).unwrap();
            assert_eq!((f.rows, f.cols), (1 + len / 512, TCDIFF438_DIM));
            assert!(f.data.iter().all(|v| v.is_finite()));
        }
        let silence = tcdiff438(&vec![0.0; 30720], sr).unwrap();
        assert!(silence.data.iter().all(|v| v.is_finite()));
    }
}
