//! Music–motion retrieval (MMR) measures of SoulNet (`../shared/reference/anchors.md` A.11,
//! `holistic.md` §1.5): the MMR-Matching Score of the paper's Eq. 8 with the released code's
//! variant next to it, the clip-level matching distance, and retrieval recall.
//!
//! Inputs are embeddings an MMR model produced (this crate has no models): per sequence, one
//! motion embedding per non-overlapping 1-s segment and the music's embeddings.
//!
//! **Eq. 8** ([`MatchingVariant::Paper`]): for a sequence of `S ≥ 2` segments with motion
//! latents `z_t` and music latents `m_t` (each `d` values),
//! `MS = sqrt(μ · mean_t ‖z_t − m_t‖² + λ · Σ_{t≥2} ‖Δz_t − Δm_t‖)`, μ = 0.7, λ = 0.3, averaged
//! over sequences; sequences with fewer than 2 segments are skipped (the released
//! `calculate_mmr_matching_score`, `xjli360/SoulDance-Official:utils/mmr_mertric.py`, given
//! per-segment music).
//!
//! **Released code** ([`MatchingVariant::ReleasedCode`]): the evaluation feeds the function one
//! `(1, d)` music vector per clip, so `m_segments` becomes `(S, 1, d)` and numpy broadcasts
//! `z − m` to `(S, S, d)`. Worked through, its first term is `(S / d) · mean_t ‖z_t − m‖²` and its
//! second `(S − 1) · Σ_k sqrt(Σ_t Δz_{t,k}²)` (Δm = 0). We reproduce that arithmetic so published
//! numbers can be compared; [`MatchingVariant::Paper`] is the measure the paper describes.

/// Eq. 8's weights (the paper: "we set μ = 0.7, λ = 0.3").
pub const MU: f64 = 0.7;
pub const LAMBDA: f64 = 0.3;

/// Which MMR-Matching Score.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatchingVariant {
    /// Eq. 8 with one music latent per segment.
    Paper,
    /// The released evaluation: one music latent per clip, numpy's broadcasting kept.
    ReleasedCode,
}

/// One sequence's latents: `motion` `S × d` (one per 1-s segment) and `music`, `S × d` for
/// [`MatchingVariant::Paper`] or one `d` vector (the clip's) for
/// [`MatchingVariant::ReleasedCode`].
#[derive(Debug, Clone, Copy)]
pub struct SequenceLatents<'a> {
    pub motion: &'a [Vec<f32>],
    pub music: &'a [Vec<f32>],
}

fn sq(a: &[f32], b: &[f32]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
        .sum()
}

/// One sequence's score, or `None` with fewer than 2 segments (or mismatched shapes).
pub fn sequence_matching_score(s: &SequenceLatents, variant: MatchingVariant) -> Option<f64> {
    let n = s.motion.len();
    let d = s.motion.first()?.len();
    if n < 2 || d == 0 || s.motion.iter().any(|z| z.len() != d) {
        return None;
    }
    match variant {
        MatchingVariant::Paper => {
            if s.music.len() != n || s.music.iter().any(|m| m.len() != d) {
                return None;
            }
            let feature = (0..n).map(|t| sq(&s.motion[t], &s.music[t])).sum::<f64>() / n as f64;
            let dynamics: f64 = (1..n)
                .map(|t| {
                    (0..d)
                        .map(|k| {
                            let dz = s.motion[t][k] as f64 - s.motion[t - 1][k] as f64;
                            let dm = s.music[t][k] as f64 - s.music[t - 1][k] as f64;
                            (dz - dm).powi(2)
                        })
                        .sum::<f64>()
                        .sqrt()
                })
                .sum();
            Some((MU * feature + LAMBDA * dynamics).sqrt())
        }
        MatchingVariant::ReleasedCode => {
            let m = match s.music {
                [m] if m.len() == d => m,
                _ => return None,
            };
            let feature =
                n as f64 / d as f64 * (0..n).map(|t| sq(&s.motion[t], m)).sum::<f64>() / n as f64;
            let column_norms: f64 = (0..d)
                .map(|k| {
                    (1..n)
                        .map(|t| (s.motion[t][k] as f64 - s.motion[t - 1][k] as f64).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .sum();
            let dynamics = (n - 1) as f64 * column_norms;
            Some((MU * feature + LAMBDA * dynamics).sqrt())
        }
    }
}

/// The mean over sequences of [`sequence_matching_score`], skipping sequences without a score;
/// 0 when none has one (as the released code returns).
pub fn matching_score(seqs: &[SequenceLatents], variant: MatchingVariant) -> f64 {
    let v: Vec<f64> = seqs
        .iter()
        .filter_map(|s| sequence_matching_score(s, variant))
        .collect();
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The released training-time "MMR score": the mean Euclidean distance between each clip's
/// music and motion embeddings, divided by 100 (`cal_fid`'s `mmr_score_avg`).
pub fn clip_distance_score(motion: &[Vec<f32>], music: &[Vec<f32>]) -> f64 {
    let n = motion.len().min(music.len());
    if n == 0 {
        return 0.0;
    }
    (0..n)
        .map(|i| sq(&motion[i], &music[i]).sqrt())
        .sum::<f64>()
        / n as f64
        / 100.0
}

/// Retrieval of music by motion: for each motion embedding `i`, the rank (1-based) of its own
/// music `i` among all musics by Euclidean distance (ties count against it).
pub fn retrieval_ranks(motion: &[Vec<f32>], music: &[Vec<f32>]) -> Vec<usize> {
    let n = motion.len().min(music.len());
    (0..n)
        .map(|i| {
            let own = sq(&motion[i], &music[i]);
            1 + (0..n)
                .filter(|&j| j != i && sq(&motion[i], &music[j]) <= own)
                .count()
        })
        .collect()
}

/// Share of queries whose match ranks within `k` (R@k), from [`retrieval_ranks`].
pub fn recall_at(ranks: &[usize], k: usize) -> f64 {
    if ranks.is_empty() {
        return 0.0;
    }
    ranks.iter().filter(|&&r| r <= k).count() as f64 / ranks.len() as f64
}

/// R@k of a random ranking of `n` candidates: `k / n`.
pub fn chance_recall(n: usize, k: usize) -> f64 {
    if n == 0 {
        0.0
    } else {
        (k.min(n)) as f64 / n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: &[f32]) -> Vec<f32> {
        x.to_vec()
    }

    #[test]
    fn paper_eq8_by_hand() {
        // Two segments, d = 2. z = (1,0),(1,1); m = (0,0),(0,2).
        let z = [v(&[1.0, 0.0]), v(&[1.0, 1.0])];
        let m = [v(&[0.0, 0.0]), v(&[0.0, 2.0])];
        let s = SequenceLatents {
            motion: &z,
            music: &m,
        };
        // feature: mean(1, 1 + 1) = 1.5; dynamics: ‖(0,1) − (0,2)‖ = 1.
        let want = (0.7f64 * 1.5 + 0.3 * 1.0).sqrt();
        assert!(
            (sequence_matching_score(&s, MatchingVariant::Paper).unwrap() - want).abs() < 1e-12
        );
        // One segment: skipped; the mean over sequences ignores it.
        let one = SequenceLatents {
            motion: &z[..1],
            music: &m[..1],
        };
        assert_eq!(sequence_matching_score(&one, MatchingVariant::Paper), None);
        assert!((matching_score(&[s, one], MatchingVariant::Paper) - want).abs() < 1e-12);
        assert_eq!(matching_score(&[one], MatchingVariant::Paper), 0.0);
    }

    /// The released variant equals numpy's broadcast computed literally: `(S, S, d)` arrays.
    #[test]
    #[allow(clippy::needless_range_loop)] // index loops spell out numpy's axes
    fn released_variant_is_numpys_broadcast() {
        let z: Vec<Vec<f32>> = (0..5)
            .map(|t| {
                (0..4)
                    .map(|k| ((t * 7 + k * 3) as f32 * 0.37).sin())
                    .collect()
            })
            .collect();
        let m = [v(&[0.1, -0.2, 0.3, 0.05])];
        let (s_n, d) = (5usize, 4usize);
        // feature_dist = sum((z_seg - m_seg)**2, axis=1) with m_seg (S,1,d): [a,k] = Σ_b (z[b,k]-m[k])²
        let mut feat = 0.0f64;
        for _a in 0..s_n {
            for k in 0..d {
                feat += (0..s_n)
                    .map(|b| (z[b][k] as f64 - m[0][k] as f64).powi(2))
                    .sum::<f64>();
            }
        }
        feat /= (s_n * d) as f64; // np.mean over (S, d)
        // dynamics = sum(norm(delta_z - delta_m, axis=1)), shapes (S-1, S-1, d): [a,k] = ‖Δz[:,k]‖
        let mut dyn_ = 0.0f64;
        for _a in 0..s_n - 1 {
            for k in 0..d {
                dyn_ += (1..s_n)
                    .map(|b| (z[b][k] as f64 - z[b - 1][k] as f64).powi(2))
                    .sum::<f64>()
                    .sqrt();
            }
        }
        let want = (0.7 * feat + 0.3 * dyn_).sqrt();
        let s = SequenceLatents {
            motion: &z,
            music: &m,
        };
        let got = sequence_matching_score(&s, MatchingVariant::ReleasedCode).unwrap();
        assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        // Not Eq. 8 with the clip vector repeated per segment.
        let rep: Vec<Vec<f32>> = (0..5).map(|_| m[0].clone()).collect();
        let paper = sequence_matching_score(
            &SequenceLatents {
                motion: &z,
                music: &rep,
            },
            MatchingVariant::Paper,
        )
        .unwrap();
        assert!((paper - got).abs() > 0.1, "{paper} {got}");
        // Shape mismatches give no score.
        assert_eq!(
            sequence_matching_score(
                &SequenceLatents {
                    motion: &z,
                    music: &rep
                },
                MatchingVariant::ReleasedCode
            ),
            None
        );
    }

    #[test]
    fn retrieval_and_clip_distance() {
        let motion = [v(&[0.0, 0.0]), v(&[1.0, 0.0]), v(&[0.0, 1.0])];
        let music = [v(&[0.1, 0.0]), v(&[0.0, 1.1]), v(&[0.0, 0.95])];
        // Motion 1's own music (0,1.1) is farther than music 0 (0.1,0) and music 2.
        let ranks = retrieval_ranks(&motion, &music);
        assert_eq!(ranks, vec![1, 3, 1]);
        assert!((recall_at(&ranks, 1) - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(recall_at(&ranks, 3), 1.0);
        assert!((chance_recall(3, 1) - 1.0 / 3.0).abs() < 1e-12);
        let d = clip_distance_score(&motion, &music);
        let want = (0.1 + 2.21f64.sqrt() + 0.05) / 3.0 / 100.0;
        assert!((d - want).abs() < 1e-6, "{d} {want}");
    }
}
