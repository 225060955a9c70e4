//! Dynamic-programming beat tracker (Ellis 2007), exactly as librosa 0.11 `beat.beat_track`
//! with a precomputed onset envelope, plus the start-BPM conventions of the dance pipelines.
//!
//! The steps, each mirroring librosa's numba kernel including its floating-point types:
//! 1. tempo from [`crate::tempo::tempo`] (unless given);
//! 2. frames per beat `fpb = round(fps·60/bpm)`, numpy rounding (half to even);
//! 3. onsets divided by their float32 `std(ddof=1)` (numpy pairwise summation);
//! 4. local score: "same" convolution with a Gaussian of width `fpb/32` (float64);
//! 5. DP over predecessors `i − round(fpb/2)` … `i − 2·fpb` with penalty
//!    `tightness·(ln(i − loc) − ln fpb)²`;
//! 6. last beat: last local maximum of the cumulative score with at least half the median
//!    cumulative score of all local maxima; backtrack;
//! 7. trim leading/trailing frames whose local score is at most half the RMS of the smoothed
//!    beat-local-score sequence.

use crate::tempo;
pub use crate::tempo::{DEFAULT_START_BPM, FALLBACK_SR, tempo_fallback_from_env22050};

/// librosa's default `tightness`, used by every dance pipeline.
pub const DEFAULT_TIGHTNESS: f64 = 100.0;

/// `librosa.beat.beat_track(onset_envelope=env, sr=sr, hop_length=hop, start_bpm, tightness,
/// trim)`: returns `(tempo in BPM, beat frames in ascending order)`.
///
/// An envelope without any non-zero value gives `(0.0, [])`, as in librosa. A non-finite
/// envelope also gives `(0.0, [])` (librosa raises).
///
/// # Panics
/// If `start_bpm <= 0` or `tightness <= 0` (librosa raises `ParameterError`).
pub fn beat_track(
    env: &[f32],
    sr: f64,
    hop: usize,
    start_bpm: f64,
    tightness: f64,
    trim: bool,
) -> (f64, Vec<usize>) {
    assert!(start_bpm > 0.0, "start_bpm must be strictly positive");
    if !env.iter().any(|&v| v != 0.0) || !env.iter().all(|v| v.is_finite()) {
        return (0.0, Vec::new());
    }
    let bpm = tempo::tempo(env, sr, hop, start_bpm);
    (bpm, beats_for_bpm(env, sr, hop, bpm, tightness, trim))
}

/// The tracker alone with a given tempo (`beat_track(..., bpm=bpm)`): beat frames.
/// An envelope without any non-zero value (or with a non-finite value) has no beats.
///
/// # Panics
/// If `bpm <= 0` or `tightness <= 0` (librosa raises `ParameterError`).
pub fn beats_for_bpm(
    env: &[f32],
    sr: f64,
    hop: usize,
    bpm: f64,
    tightness: f64,
    trim: bool,
) -> Vec<usize> {
    assert!(bpm > 0.0, "bpm must be strictly positive");
    assert!(tightness > 0.0, "tightness must be strictly positive");
    if !env.iter().any(|&v| v != 0.0) || !env.iter().all(|v| v.is_finite()) {
        return Vec::new();
    }
    let frame_rate = sr / hop as f64;
    // At least one frame per beat (librosa would divide by zero for absurd tempi).
    let fpb = (frame_rate * 60.0 / bpm).round_ties_even().max(1.0);
    let onsets = normalize_onsets(env);
    let ls = local_score(&onsets, fpb);
    // The numba kernel takes `tightness` as float32.
    let (backlink, cum) = track_dp(&ls, fpb, tightness as f32 as f64);
    let mut beats = vec![false; env.len()];
    let mut n = last_beat(&cum) as isize;
    while n >= 0 {
        beats[n as usize] = true;
        n = backlink[n as usize] as isize;
    }
    trim_beats(&ls, &mut beats, trim);
    beats
        .iter()
        .enumerate()
        .filter_map(|(i, &b)| b.then_some(i))
        .collect()
}

/// Start BPM encoded in an AIST++ music id (`mBR0` … `mJB5`, `mHO0` … `mHO5`): genres BR, PO,
/// LO, MH, LH, WA, KR, JS, JB → `80 + 10·d`; HO → `110 + 5·d` (mint/EDGE `_get_tempo`).
///
/// `name` may be the id, a file name (`mBR2.wav`) or a path / sequence name containing it
/// (`gBR_sBM_cAll_d04_mBR0_ch01`); the id must be delimited by non-alphanumeric characters or
/// the ends of the string. The first id found wins. `None` if there is none.
///
/// Note: EDGE itself takes `name.split('_')[4]` of a sliced AIST++ sequence name, so a bare
/// `mBR0.wav` there would fall back to [`tempo_fallback_from_env22050`].
pub fn start_bpm_from_aist_name(name: &str) -> Option<f64> {
    const TEN: [&str; 9] = ["BR", "PO", "LO", "MH", "LH", "WA", "KR", "JS", "JB"];
    let b = name.as_bytes();
    for i in 0..b.len().saturating_sub(3) {
        if b[i] != b'm' || (i > 0 && b[i - 1].is_ascii_alphanumeric()) {
            continue;
        }
        let (genre, digit) = (&b[i + 1..i + 3], b[i + 3]);
        if !digit.is_ascii_digit() || b.get(i + 4).is_some_and(|c| c.is_ascii_alphanumeric()) {
            continue;
        }
        let d = (digit - b'0') as f64;
        if genre == b"HO" {
            return Some(110.0 + 5.0 * d);
        }
        if TEN.iter().any(|g| g.as_bytes() == genre) {
            return Some(80.0 + 10.0 * d);
        }
    }
    None
}

/// numpy's float32 pairwise summation (`np.add.reduce` on a contiguous float32 array): blocks
/// of at most 128 summed with 8 interleaved accumulators, larger ranges split in halves
/// (rounded down to a multiple of 8).
fn pairwise_sum_f32(x: &[f32]) -> f32 {
    let n = x.len();
    if n < 8 {
        let mut res = 0f32;
        for &v in x {
            res += v;
        }
        res
    } else if n <= 128 {
        let mut r = [0f32; 8];
        r.copy_from_slice(&x[..8]);
        let mut i = 8;
        while i < n - n % 8 {
            for (j, rj) in r.iter_mut().enumerate() {
                *rj += x[i + j];
            }
            i += 8;
        }
        let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for &v in &x[i..] {
            res += v;
        }
        res
    } else {
        let mut n2 = n / 2;
        n2 -= n2 % 8;
        pairwise_sum_f32(&x[..n2]) + pairwise_sum_f32(&x[n2..])
    }
}

/// `onsets / (onsets.std(ddof=1) + tiny)` in float32, as numpy computes it.
fn normalize_onsets(env: &[f32]) -> Vec<f32> {
    let n = env.len();
    let mean = pairwise_sum_f32(env) / n as f32;
    let sq: Vec<f32> = env
        .iter()
        .map(|&v| {
            let d = v - mean;
            d * d
        })
        .collect();
    // ddof = 1; numpy clamps the divisor at 0 (→ inf/NaN for a single frame).
    let var = pairwise_sum_f32(&sq) / n.saturating_sub(1) as f32;
    let norm = var.sqrt() + f32::MIN_POSITIVE;
    env.iter().map(|&v| v / norm).collect()
}

/// `__beat_local_score` (static tempo): `ls[i] = Σ_k w[k]·o[i + fpb − k]` over
/// `k ∈ [max(0, i + fpb − N + 1), min(i + fpb, K))`, `w[k] = exp(−½((k − fpb)·32/fpb)²)`,
/// `K = 2·fpb + 1`, accumulated in float64 in that order.
fn local_score(onsets: &[f32], fpb: f64) -> Vec<f64> {
    let n = onsets.len();
    let half = fpb as usize;
    let k_len = 2 * half + 1;
    let window: Vec<f64> = (0..k_len)
        .map(|k| {
            let z = (-fpb + k as f64) * 32.0 / fpb;
            (-0.5 * (z * z)).exp()
        })
        .collect();
    (0..n)
        .map(|i| {
            let lo = (i + half + 1).saturating_sub(n);
            let hi = (i + half).min(k_len);
            let mut acc = 0f64;
            for (k, &w) in window.iter().enumerate().take(hi).skip(lo) {
                acc += w * onsets[i + half - k] as f64;
            }
            acc
        })
        .collect()
}

/// `__beat_track_dp`: backlinks (−1 = none) and cumulative scores.
fn track_dp(ls: &[f64], fpb: f64, tightness: f64) -> (Vec<i32>, Vec<f64>) {
    let n = ls.len();
    let mut backlink = vec![-1i32; n];
    let mut cum = vec![0f64; n];
    if n == 0 {
        return (backlink, cum);
    }
    let score_thresh = 0.01 * ls.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let near = (fpb / 2.0).round_ties_even() as usize;
    let far = 2 * fpb as usize;
    // penalty[d] for a predecessor d frames back, computed exactly as the kernel does.
    let log_fpb = fpb.ln();
    let penalty: Vec<f64> = (0..=far)
        .map(|d| {
            let z = (d as f64).ln() - log_fpb;
            tightness * (z * z)
        })
        .collect();
    cum[0] = ls[0];
    let mut first_beat = true;
    for i in 0..n {
        let mut best_score = f64::NEG_INFINITY;
        let mut beat_location = -1i64;
        // loc = i − near, i − near − 1, …, i − far, stopping before 0.
        if i >= near {
            let candidates = penalty.iter().enumerate().take(far.min(i) + 1).skip(near);
            for (d, &pen) in candidates {
                let loc = i - d;
                let score = cum[loc] - pen;
                if score > best_score {
                    best_score = score;
                    beat_location = loc as i64;
                }
            }
        }
        cum[i] = if beat_location >= 0 {
            ls[i] + best_score
        } else {
            ls[i]
        };
        if first_beat && ls[i] < score_thresh {
            backlink[i] = -1;
        } else {
            backlink[i] = beat_location as i32;
            first_beat = false;
        }
    }
    (backlink, cum)
}

/// `__last_beat`: the last local maximum of `cum` (`cum[n] > cum[n−1]` and `cum[n] >= cum[n+1]`;
/// frame 0 never, the last frame if it exceeds its predecessor) whose value is at least half
/// the median over all local maxima; the last frame if there is none.
fn last_beat(cum: &[f64]) -> usize {
    let n = cum.len();
    if n < 2 {
        return n.saturating_sub(1);
    }
    let is_max = |i: usize| {
        if i == n - 1 {
            cum[i] > cum[i - 1]
        } else {
            i > 0 && cum[i] > cum[i - 1] && cum[i] >= cum[i + 1]
        }
    };
    let mut maxima: Vec<f64> = (0..n).filter(|&i| is_max(i)).map(|i| cum[i]).collect();
    if maxima.is_empty() {
        return n - 1;
    }
    maxima.sort_by(f64::total_cmp);
    let m = maxima.len();
    let median = if m % 2 == 1 {
        maxima[m / 2]
    } else {
        (maxima[m / 2 - 1] + maxima[m / 2]) / 2.0
    };
    let threshold = 0.5 * median;
    (0..n)
        .rev()
        .find(|&i| is_max(i) && cum[i] >= threshold)
        .unwrap_or(n - 1)
}

/// numba's `np.convolve(a, v)` (mode full): `_np_correlate_core` with the longer array first
/// and each output an in-order dot product.
fn convolve_full(a: &[f64], v: &[f64]) -> Vec<f64> {
    let (ap1, ap2): (&[f64], Vec<f64>) = if a.len() < v.len() {
        (v, a.iter().rev().copied().collect())
    } else {
        (a, v.iter().rev().copied().collect())
    };
    let (n1, n2) = (ap1.len(), ap2.len());
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).fold(0f64, |acc, (p, q)| acc + p * q);
    let mut out = Vec::with_capacity(n1 + n2 - 1);
    for i in 0..n2 - 1 {
        let k = i + 1;
        out.push(dot(&ap1[..k], &ap2[n2 - k..]));
    }
    for i in 0..=n1 - n2 {
        out.push(dot(&ap1[i..i + n2], &ap2));
    }
    for i in 0..n2 - 1 {
        let k = n2 - i - 1;
        out.push(dot(&ap1[n1 - k..], &ap2[..k]));
    }
    out
}

/// `__trim_beats`: threshold = ½·RMS of `convolve(ls[beats], hanning(5))[2 : N + 2]` (0 without
/// `trim`); then clear the flags of the leading and of the trailing frames whose local score is
/// at most the threshold.
fn trim_beats(ls: &[f64], beats: &mut [bool], trim: bool) {
    let n = ls.len();
    let threshold = if trim {
        let on_beats: Vec<f64> = ls
            .iter()
            .zip(beats.iter())
            .filter_map(|(&v, &b)| b.then_some(v))
            .collect();
        if on_beats.is_empty() {
            0.0
        } else {
            // np.hanning(5) in numba: 0.5 + 0.5·cos(π·n/4), n = −4, −2, 0, 2, 4 (exact values).
            let w = [0.0, 0.5, 1.0, 0.5, 0.0];
            let full = convolve_full(&on_beats, &w);
            let smooth = &full[2.min(full.len())..(n + 2).min(full.len())];
            let mut sum = 0f64;
            for &s in smooth {
                sum += s * s;
            }
            0.5 * (sum / smooth.len() as f64).powf(0.5)
        }
    } else {
        0.0
    };
    let mut i = 0;
    while i < n && ls[i] <= threshold {
        beats[i] = false;
        i += 1;
    }
    let mut i = n;
    while i > 0 && ls[i - 1] <= threshold {
        beats[i - 1] = false;
        i -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairwise_matches_numpy_structure() {
        // Small sums are plain loops; the result for integers is exact either way.
        let x: Vec<f32> = (0..1000).map(|i| i as f32).collect();
        assert_eq!(pairwise_sum_f32(&x), 499500.0);
    }

    #[test]
    fn convolve_matches_definition() {
        let a = [1.0, 2.0, 3.0];
        let v = [0.0, 0.5, 1.0, 0.5, 0.0];
        let expect = [0.0, 0.5, 2.0, 4.0, 4.0, 1.5, 0.0];
        assert_eq!(convolve_full(&a, &v), expect);
        assert_eq!(convolve_full(&v, &a), expect);
    }

    #[test]
    fn half_even_rounding_of_half_beat() {
        assert_eq!((13.0f64 / 2.0).round_ties_even(), 6.0);
        assert_eq!((15.0f64 / 2.0).round_ties_even(), 8.0);
        assert_eq!((17.0f64 / 2.0).round_ties_even(), 8.0);
    }

    #[test]
    fn silence_has_no_beats() {
        assert_eq!(
            beat_track(&vec![0.0; 300], 15360.0, 512, 120.0, 100.0, true),
            (0.0, vec![])
        );
    }
}
