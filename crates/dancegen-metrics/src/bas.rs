//! Beat Align Score (BAS): the four incompatible reference variants (anchors A.4, pitfall P6).
//!
//! | [`Variant`] | reference | motion beats | score |
//! |---|---|---|---|
//! | `Bailando` | `lisiyao21/Bailando:utils/beat_align_score.py` (`calc_db`, `BA`) | local minima (`argrelextrema(less)`, order 1) of the mean joint speed, smoothed by `gaussian_filter(σ = 5)` | mean over **music** beats of `exp(−d²/18)` |
//! | `Lodge` | `li-ronghui/LODGE:metric/beat_align_score.py` (`calc_ba_score` loop body) | as Bailando, after subtracting frame 0's root (`calc_ba_score`) | as Bailando |
//! | `Fact` | `google-research/mint:tools/calculate_beat_scores.py` (`motion_peak_onehot`, `alignment_score(.., sigma=3)`) | strict local minima (`argrelextrema(less, order=10)`) of the float32 sum of joint speeds | mean over **motion** beats of `exp(−d²/(2·3²))`, float32 |
//! | `Gcd` | `aioz-ai/GCD:eval/calculate_beat_scores.py` (`order=5`, `sigma=2.12`) | as Fact with order 5 | as Fact with σ = 2.12, float32 |
//!
//! `d` is the distance in frames to the nearest beat of the other kind. All frame parameters are
//! hard-coded in the references (no fps argument): Bailando is run at 60 and 30 fps with the same
//! σ = 5 frames / σ² = 9 frames²; LODGE at 30 fps; mint at 60 fps; GCD at 30 fps
//! ([`Variant::native_fps`]).
//!
//! Music beats are frame indices. Which part of the music beat list a reference uses for a clip
//! of `T` frames is [`clip_music_beats`]: Bailando cuts to `T − 1` (`get_mb(key, length)` with
//! `length = len(kinetic_vel)`), mint/GCD to `T` (`audio_beats[:T]`), LODGE uses the **whole
//! song** (its `librosa.load(...)[:length]` slices the `(audio, sr)` tuple).
//!
//! Degenerate cases ([`beat_align_score`] returns `None` where the reference raises):
//! - Bailando/LODGE, no motion beats: `np.min` of an empty array raises `ValueError` → `None`
//!   (the reference's `calc_ba_score` would crash; the fixtures drop such a clip from the mean).
//! - Bailando/LODGE, no music beats: `ba / len(music_beats)` is `0 / 0` on Python ints →
//!   `ZeroDivisionError` → `None`.
//! - Fact/GCD, no motion beats: the reference returns `0.0` → `Some(0.0)`.
//! - Fact/GCD, motion beats but no music beats: `np.argmin` of an empty array raises → `None`.
//!
//! Numerics: Bailando/LODGE are float64 throughout; the port follows numpy's summation order
//! (pairwise sums over joints, scipy's symmetric `correlate1d` loop, reflect boundary) so that
//! beat lists are identical. Fact/GCD compute velocities, norms, the envelope and the score in
//! float32 like the reference (`np.zeros_like(.., dtype=float32)`, float32 `exp`, Python `sum`
//! of float32 scalars); the returned score is that float32 value widened to f64.

use crate::{FRAME_LEN, FeatureError, NUM_JOINTS, frame_count, zero_start};

/// Which reference implementation to reproduce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Variant {
    /// `lisiyao21/Bailando:utils/beat_align_score.py` (also used by EDGE-era papers, Duolando).
    Bailando,
    /// `li-ronghui/LODGE:metric/beat_align_score.py`: Bailando's math plus frame-0 root
    /// subtraction; music beats of the whole song.
    Lodge,
    /// FACT / AIST++ "BeatAlign": `google-research/mint:tools/calculate_beat_scores.py`.
    Fact,
    /// GDance "MMC": `aioz-ai/GCD:eval/calculate_beat_scores.py`.
    Gcd,
}

impl Variant {
    /// All variants.
    pub const ALL: [Variant; 4] = [
        Variant::Bailando,
        Variant::Lodge,
        Variant::Fact,
        Variant::Gcd,
    ];

    /// Frame rate the reference was written for (Bailando: AIST++ 60 fps; it is also applied
    /// unchanged to 30-fps data by later papers). Informative only: nothing is rescaled.
    pub fn native_fps(self) -> u32 {
        match self {
            Variant::Bailando | Variant::Fact => 60,
            Variant::Lodge | Variant::Gcd => 30,
        }
    }

    /// Short lower-case name, as in the fixture file names (`bas_{name}.json`).
    pub fn name(self) -> &'static str {
        match self {
            Variant::Bailando => "bailando",
            Variant::Lodge => "lodge",
            Variant::Fact => "fact",
            Variant::Gcd => "gcd",
        }
    }
}

/// Gaussian σ (frames) of Bailando/LODGE `calc_db`'s `gaussian_filter(kinetic_vel, 5)`.
pub const BAILANDO_SMOOTH_SIGMA: f64 = 5.0;

/// Motion beats (frame indices, ascending) of a `(T, 24, 3)` joint array as `variant` computes
/// them (see the module docs).
///
/// Index conventions follow the references: Bailando/LODGE index the `T − 1` velocity samples
/// (`s_t` between frames `t` and `t + 1`); Fact/GCD index the `T` envelope samples (`e_0 = 0`).
///
/// # Panics
/// If the slice is not whole `(24, 3)` frames; see [`try_motion_beats`].
pub fn motion_beats(joints: &[f64], variant: Variant) -> Vec<usize> {
    match try_motion_beats(joints, variant) {
        Ok(b) => b,
        Err(e) => panic!("motion_beats: {e}"),
    }
}

/// [`motion_beats`] returning an error instead of panicking. Fewer than 2 frames give no beats.
pub fn try_motion_beats(joints: &[f64], variant: Variant) -> Result<Vec<usize>, FeatureError> {
    let frames = frame_count(joints)?;
    Ok(match variant {
        Variant::Bailando => {
            let s = gaussian_filter1d(&mean_joint_speed(joints, frames), BAILANDO_SMOOTH_SIGMA);
            argrelmin(&s, 1)
        }
        Variant::Lodge => {
            let z = zero_start(joints);
            let s = gaussian_filter1d(&mean_joint_speed(&z, frames), BAILANDO_SMOOTH_SIGMA);
            argrelmin(&s, 1)
        }
        Variant::Fact => argrelmin(&speed_envelope_f32(joints, frames), 10),
        Variant::Gcd => argrelmin(&speed_envelope_f32(joints, frames), 5),
    })
}

/// The part of a song's music-beat list (ascending frame indices) that `variant` uses for a clip
/// of `frames` frames: Bailando `< T − 1`, Fact/GCD `< T`, LODGE all (whole-song bug).
pub fn clip_music_beats(music_beats: &[usize], frames: usize, variant: Variant) -> Vec<usize> {
    let limit = match variant {
        Variant::Bailando => frames.saturating_sub(1),
        Variant::Lodge => usize::MAX,
        Variant::Fact | Variant::Gcd => frames,
    };
    music_beats.iter().copied().filter(|&b| b < limit).collect()
}

/// Beat align score of `variant` from music and motion beat indices (frames). Pass the music
/// beats already cut as the reference does ([`clip_music_beats`]). `None` where the reference
/// raises (see the module docs).
pub fn beat_align_score(
    music_beats: &[usize],
    motion_beats: &[usize],
    variant: Variant,
) -> Option<f64> {
    match variant {
        Variant::Bailando | Variant::Lodge => bailando_ba(music_beats, motion_beats),
        Variant::Fact => alignment_score_f32(music_beats, motion_beats, 9.0),
        // `sigma**2` is a Python float, cast to float32 by the float32 division (NEP 50).
        Variant::Gcd => alignment_score_f32(music_beats, motion_beats, (2.12f64 * 2.12f64) as f32),
    }
}

/// Bailando `BA`: `Σ_b exp(−min_m (m − b)² / 2 / 9) / len(music_beats)`.
fn bailando_ba(music_beats: &[usize], motion_beats: &[usize]) -> Option<f64> {
    if music_beats.is_empty() || motion_beats.is_empty() {
        return None;
    }
    let mut ba = 0.0f64;
    for &b in music_beats {
        let min_sq = motion_beats
            .iter()
            .map(|&m| {
                let d = m as i64 - b as i64;
                d * d
            })
            .min()?;
        ba += (-(min_sq as f64) / 2.0 / 9.0).exp();
    }
    Some(ba / music_beats.len() as f64)
}

/// mint/GCD `alignment_score` in float32: mean over motion beats of `exp(−d²/2/σ²)`.
fn alignment_score_f32(
    music_beats: &[usize],
    motion_beats: &[usize],
    sigma_sq: f32,
) -> Option<f64> {
    if motion_beats.is_empty() {
        return Some(0.0);
    }
    let mut total = 0.0f32;
    for &m in motion_beats {
        let d = music_beats
            .iter()
            .map(|&b| (b as i64 - m as i64).unsigned_abs())
            .min()? as f32;
        let x = -(d * d) / 2.0 / sigma_sq;
        total += (x as f64).exp() as f32;
    }
    Some(f64::from(total / motion_beats.len() as f32))
}

/// Bailando `calc_db`'s `kinetic_vel` before smoothing: per step `t ∈ [0, T−1)`, the mean over
/// joints of `‖P[t+1, j] − P[t, j]‖` (float64, numpy's summation order).
pub fn mean_joint_speed(joints: &[f64], frames: usize) -> Vec<f64> {
    (0..frames.saturating_sub(1))
        .map(|t| pairwise_sum(&joint_step_speeds(joints, t)) / NUM_JOINTS as f64)
        .collect()
}

/// `‖P[t+1, j] − P[t, j]‖` for every joint (float64), the per-step speeds the motion-beat
/// extractors of Bailando and Duolando average.
pub fn joint_step_speeds(joints: &[f64], t: usize) -> [f64; NUM_JOINTS] {
    let mut norms = [0.0f64; NUM_JOINTS];
    for (j, n) in norms.iter_mut().enumerate() {
        let a = t * FRAME_LEN + j * 3;
        let b = a + FRAME_LEN;
        let mut s = 0.0;
        for c in 0..3 {
            let d = joints[b + c] - joints[a + c];
            s += d * d;
        }
        *n = s.sqrt();
    }
    norms
}

/// mint/GCD `motion_peak_onehot` envelope: `e_0 = 0`, `e_t = Σ_j ‖P[t, j] − P[t−1, j]‖` with the
/// differences cast to float32 and the norms and the sum in float32 (numpy's order).
pub fn speed_envelope_f32(joints: &[f64], frames: usize) -> Vec<f32> {
    let mut env = vec![0.0f32; frames];
    for (t, e) in env.iter_mut().enumerate().skip(1) {
        let mut norms = [0.0f32; NUM_JOINTS];
        for (j, n) in norms.iter_mut().enumerate() {
            let b = t * FRAME_LEN + j * 3;
            let a = b - FRAME_LEN;
            let mut s = 0.0f32;
            for c in 0..3 {
                let d = (joints[b + c] - joints[a + c]) as f32;
                s += d * d;
            }
            *n = s.sqrt();
        }
        *e = pairwise_sum(&norms);
    }
    env
}

/// numpy's `add.reduce` over a contiguous axis: identity 0 plus numpy's pairwise sum
/// (8 accumulators for blocks up to 128, recursive halving above).
fn pairwise_sum<T: Copy + Default + std::ops::Add<Output = T>>(a: &[T]) -> T {
    T::default() + pairwise_inner(a)
}

fn pairwise_inner<T: Copy + Default + std::ops::Add<Output = T>>(a: &[T]) -> T {
    let n = a.len();
    if n < 8 {
        let mut res = T::default();
        for &x in a {
            res = res + x;
        }
        res
    } else if n <= 128 {
        let mut r = [T::default(); 8];
        r.copy_from_slice(&a[..8]);
        let whole = n - n % 8;
        for chunk in a[8..whole].chunks_exact(8) {
            for (acc, &x) in r.iter_mut().zip(chunk) {
                *acc = *acc + x;
            }
        }
        let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for &x in &a[whole..] {
            res = res + x;
        }
        res
    } else {
        let mut n2 = n / 2;
        n2 -= n2 % 8;
        pairwise_inner(&a[..n2]) + pairwise_inner(&a[n2..])
    }
}

/// `scipy.ndimage.gaussian_filter1d(x, sigma)` with its defaults (`order = 0`, `mode = "reflect"`,
/// `truncate = 4.0`), following scipy's kernel normalisation and symmetric correlation loop.
pub fn gaussian_filter1d(x: &[f64], sigma: f64) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let radius = (4.0 * sigma + 0.5) as usize;
    // `_gaussian_kernel1d`: exp(-0.5 / sigma² · k²) / sum, k = -radius..=radius.
    let coef = -0.5 / (sigma * sigma);
    let phi: Vec<f64> = (-(radius as i64)..=radius as i64)
        .map(|k| (coef * (k * k) as f64).exp())
        .collect();
    let total = pairwise_sum(&phi);
    let w: Vec<f64> = phi.iter().map(|v| v / total).collect();
    // Reflect ("d c b a | a b c d | d c b a"), repeated for lines shorter than the radius.
    let period = 2 * n as i64;
    let at = |i: i64| -> f64 {
        let m = i.rem_euclid(period);
        x[if m >= n as i64 { period - 1 - m } else { m } as usize]
    };
    (0..n as i64)
        .map(|i| {
            let mut acc = at(i) * w[radius];
            for j in (1..=radius as i64).rev() {
                acc += (at(i - j) + at(i + j)) * w[radius - j as usize];
            }
            acc
        })
        .collect()
}

/// `scipy.signal.argrelextrema(x, np.less, order=order)` (default `mode = "clip"`): indices `i`
/// with `x[i] < x[clip(i ± k)]` for all `k ∈ 1..=order`. End points never qualify.
pub fn argrelmin<T: Copy + PartialOrd>(x: &[T], order: usize) -> Vec<usize> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    (0..n)
        .filter(|&i| {
            (1..=order).all(|k| {
                let plus = (i + k).min(n - 1);
                let minus = i.saturating_sub(k);
                x[i] < x[plus] && x[i] < x[minus]
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argrelmin_matches_scipy_semantics() {
        // Plateaus and end points are not minima; order widens the window.
        let x = [3.0, 1.0, 2.0, 2.0, 0.5, 0.5, 4.0, 1.0, 5.0];
        assert_eq!(argrelmin(&x, 1), vec![1, 7]);
        assert_eq!(argrelmin(&x, 2), vec![1]);
        assert!(argrelmin::<f64>(&[], 1).is_empty());
    }

    #[test]
    fn gaussian_filter_preserves_constants_and_mass() {
        let c = gaussian_filter1d(&[2.0; 7], 5.0);
        assert!(c.iter().all(|v| (v - 2.0).abs() < 1e-12));
        let mut impulse = vec![0.0; 101];
        impulse[50] = 1.0;
        let s: f64 = gaussian_filter1d(&impulse, 5.0).iter().sum();
        assert!((s - 1.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_scores() {
        for v in [Variant::Bailando, Variant::Lodge] {
            assert_eq!(beat_align_score(&[3], &[], v), None);
            assert_eq!(beat_align_score(&[], &[3], v), None);
            assert_eq!(beat_align_score(&[3], &[3], v), Some(1.0));
        }
        for v in [Variant::Fact, Variant::Gcd] {
            assert_eq!(beat_align_score(&[3], &[], v), Some(0.0));
            assert_eq!(beat_align_score(&[], &[], v), Some(0.0));
            assert_eq!(beat_align_score(&[], &[3], v), None);
            assert_eq!(beat_align_score(&[3], &[3], v), Some(1.0));
        }
    }

    #[test]
    fn clip_cuts() {
        let b = [0, 4, 5, 9];
        assert_eq!(clip_music_beats(&b, 5, Variant::Bailando), vec![0]);
        assert_eq!(clip_music_beats(&b, 5, Variant::Fact), vec![0, 4]);
        assert_eq!(clip_music_beats(&b, 5, Variant::Lodge), b.to_vec());
    }
}
