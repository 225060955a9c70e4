//! Diversity (Div_k, Div_g; "Dist" in EDGE), Bailando protocol.
//!
//! Reference: `lisiyao21/Bailando:utils/metrics_new.py` (`calculate_avg_distance`): the mean
//! Euclidean distance over **all unordered pairs** of feature vectors,
//! `Σ_{i<j} ‖f_i − f_j‖ / (n(n−1)/2)`, computed on features already normalised with the GT
//! statistics ([`crate::fid::normalize_by_gt`]). GT diversity is the same on the GT features.
//!
//! Accumulation is float64 (as under numpy 1.x; numpy 2 keeps Bailando's float32 sum, a
//! difference of ~1e-7 relative on the fixtures).

/// Mean pairwise Euclidean distance over all unordered pairs. NaN for fewer than two vectors
/// (the reference divides 0 by 0).
///
/// # Panics
/// If the vectors have different lengths.
pub fn diversity(features: &[Vec<f64>]) -> f64 {
    let n = features.len();
    let mut sum = 0.0;
    for i in 0..n {
        for j in i + 1..n {
            assert_eq!(
                features[i].len(),
                features[j].len(),
                "feature vectors have different lengths"
            );
            let d2: f64 = features[i]
                .iter()
                .zip(&features[j])
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            sum += d2.sqrt();
        }
    }
    sum / ((n * n) as f64 - n as f64) * 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_points() {
        // Pairwise distances 5, 1, √26 (points (0,0), (3,4), (3,5)).
        let f = vec![vec![0.0, 0.0], vec![3.0, 4.0], vec![3.0, 5.0]];
        let want = (5.0 + 1.0 + 34f64.sqrt()) / 3.0;
        assert!((diversity(&f) - want).abs() < 1e-12);
    }

    #[test]
    fn single_vector_is_nan() {
        assert!(diversity(&[vec![1.0]]).is_nan());
    }
}
